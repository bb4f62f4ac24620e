"""Kernel writers of ``ideas-hpc export`` (SPEC section 7e): SPK 13, CK 3, SCLK, FK, PCK.

Frames: ``N`` is ``ECLIPJ2000`` (the frame of the body's orbit elements and pole,
:mod:`ideas_hpc.core.dynamics.ephemeris`); ``[TN](tau) = R3(W0 + omega tau) [PN]`` at
``tau`` seconds after the element epoch, whose TDB is ``et_elements``. The export writes

* a text PCK of the body-fixed frame T in IAU form (pole RA/Dec in J2000, prime
  meridian ``W = W0 + Wdot d`` in deg and deg/day from J2000), exact for the project's
  uniform spin about a fixed pole, and a frame kernel naming it ``IDEAS_<ID>_FIXED``;
* per spacecraft an SPK type 13 segment (Hermite, positions and velocities relative to
  the body centre in J2000, km and km/s);
* per spacecraft a camera frame ``IDEAS_SC<k>_CAMERA`` (CK class) and a CK type 3
  segment (quaternions J2000 -> camera at every image; angular velocities: the flown
  ones of a simulated attitude, else central differences of the image attitudes), with a type 1 SCLK kernel whose ticks are
  1e-5 s of TDB from the first image.

All writers need spiceypy (imported on use by the caller).
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.campaign.schema.spice_table import orientation_angles

TICK_S = 1e-5        #: SCLK tick, s of TDB
FRAME_BASE = 1_490_000   #: frame IDs of the exported frames (NAIF leaves 1,400,000+ to users)


def dcm_TN(params, tau_s):
    """``[TN]`` (rows: T axes in ECLIPJ2000) at ``tau_s`` s after the element epoch."""
    from ideas_hpc.dynamics.trajectory import body_dcm_TN

    tau = np.atleast_1d(np.asarray(tau_s, dtype=np.float64))
    return body_dcm_TN(params, params.prime_meridian + params.spin_rate * tau)


def pck_text(body_id: int, params, et_elements: float, dcm_NJ) -> str:
    """IAU-form text PCK of frame T (constant pole, uniform spin about it)."""
    tn = dcm_TN(params, 0.0)[0] @ dcm_NJ          # [T J2000] at the element epoch
    ra, dec, w = orientation_angles(tn)
    rate = math.degrees(params.spin_rate) * 86400.0   # deg/day
    w0 = (math.degrees(w) - rate * et_elements / 86400.0) % 360.0
    return ("\\begindata\n"
            f"BODY{body_id}_POLE_RA = ( {math.degrees(ra)!r} 0.0 0.0 )\n"
            f"BODY{body_id}_POLE_DEC = ( {math.degrees(dec)!r} 0.0 0.0 )\n"
            f"BODY{body_id}_PM = ( {w0!r} {rate!r} 0.0 )\n"
            "\\begintext\n")


def fk_text(body_id: int, body_frame: str, sc_ids, cam_frames) -> str:
    lines = ["\\begindata",
             f"FRAME_{body_frame} = {FRAME_BASE}",
             f"FRAME_{FRAME_BASE}_NAME = '{body_frame}'",
             f"FRAME_{FRAME_BASE}_CLASS = 2",
             f"FRAME_{FRAME_BASE}_CLASS_ID = {body_id}",
             f"FRAME_{FRAME_BASE}_CENTER = {body_id}",
             f"OBJECT_{body_id}_FRAME = '{body_frame}'"]
    for k, (sc, name) in enumerate(zip(sc_ids, cam_frames)):
        fid, inst = FRAME_BASE + 1 + k, sc * 1000
        lines += [f"FRAME_{name} = {fid}", f"FRAME_{fid}_NAME = '{name}'",
                  f"FRAME_{fid}_CLASS = 3", f"FRAME_{fid}_CLASS_ID = {inst}",
                  f"FRAME_{fid}_CENTER = {sc}", f"CK_{inst}_SCLK = {sc}", f"CK_{inst}_SPK = {sc}",
                  f"NAIF_BODY_NAME += 'IDEAS_SC{k}'", f"NAIF_BODY_CODE += {sc}"]
    return "\n".join(lines + ["\\begintext", ""])


def sclk_text(sc_ids, et0: float) -> str:
    """Type 1 SCLK per spacecraft: one partition, ticks of :data:`TICK_S` s of TDB from ``et0``."""
    lines = ["\\begindata", "SCLK_KERNEL_ID = ( @2000-01-01/00:00 )"]
    for sc in sc_ids:
        i = -sc
        lines += [f"SCLK_DATA_TYPE_{i} = ( 1 )", f"SCLK01_TIME_SYSTEM_{i} = ( 1 )",
                  f"SCLK01_N_FIELDS_{i} = ( 1 )", f"SCLK01_MODULI_{i} = ( 100000000000000 )",
                  f"SCLK01_OFFSETS_{i} = ( 0 )", f"SCLK01_OUTPUT_DELIM_{i} = ( 1 )",
                  f"SCLK_PARTITION_START_{i} = ( 0.0 )",
                  f"SCLK_PARTITION_END_{i} = ( 1.0E14 )",
                  f"SCLK01_COEFFICIENTS_{i} = ( 0.0 {et0!r} {TICK_S!r} )"]
    return "\n".join(lines + ["\\begintext", ""])


def write_spk(sp, path, body_id: int, sc_ids, et, r_J_m, v_J_m_s, degree: int = 7) -> None:
    """One SPK type 13 segment per spacecraft (``r_J_m``, ``v_J_m_s``: (N, T, 3))."""
    h = sp.spkopn(str(path), "ideas_hpc export", 0)
    try:
        for k, sc in enumerate(sc_ids):
            states = np.ascontiguousarray(np.concatenate([r_J_m[k], v_J_m_s[k]], axis=1) / 1e3)
            sp.spkw13(h, sc, body_id, "J2000", float(et[0]), float(et[-1]), f"IDEAS_SC{k}",
                      degree, len(et), states, np.ascontiguousarray(et))
    finally:
        sp.spkcls(h)


def rates_J(dcm_CJ, t_s) -> np.ndarray:
    """Angular velocity of C relative to J2000 in J2000 components (rad/s), central differences
    of the attitudes at times ``t_s`` (one-sided at the ends); zeros for a single image.
    ``t_s`` should be short times (flyby seconds), not TDB past J2000: at 8e8 s a TDB
    carries 1.2e-7 s of rounding, 3e-7 of a 0.4 s difference.

    The rotation between neighbours, ``[C(b) C(a)] = [C J](b) [C J](a)^T``, gives its angle
    as ``atan2(sin, cos)`` of its antisymmetric part and trace: exact for a rotation about a
    fixed axis at a constant rate (an ideal nadir camera), where an ``acos`` of the trace
    would lose half the digits of the small angle between images."""
    n = len(t_s)
    out = np.zeros((n, 3))
    if n < 2:
        return out
    for i in range(n):
        a, b = max(i - 1, 0), min(i + 1, n - 1)
        rel = dcm_CJ[b] @ dcm_CJ[a].T
        v = np.array([rel[1, 2] - rel[2, 1], rel[2, 0] - rel[0, 2], rel[0, 1] - rel[1, 0]])
        s2 = float(np.linalg.norm(v))                  # 2 sin(angle)
        if s2 == 0.0:
            continue
        ang = math.atan2(0.5 * s2, 0.5 * (np.trace(rel) - 1.0))
        # the axis in C(a) components, then in J2000
        out[i] = dcm_CJ[a].T @ (v / s2) * ang / (t_s[b] - t_s[a])
    return out


def write_ck(sp, path, sc_ids, et, dcm_CJ, omega_J) -> None:
    """One CK type 3 segment per spacecraft (``dcm_CJ``: (N, n_img, 3, 3), J2000 -> camera;
    ``omega_J`` (N, n_img, 3): the camera's angular velocity relative to J2000 in J2000
    components, rad/s, what CK type 3 stores: rates in the segment's reference frame)."""
    h = sp.ckopn(str(path), "ideas_hpc export", 0)
    try:
        for k, sc in enumerate(sc_ids):
            ticks = np.array([sp.sce2c(sc, float(t)) for t in et])
            quats = np.array([sp.m2q(np.ascontiguousarray(m)) for m in dcm_CJ[k]])
            av = np.ascontiguousarray(omega_J[k], dtype=np.float64)
            sp.ckw03(h, float(ticks[0]), float(ticks[-1]), sc * 1000, "J2000", True,
                     f"IDEAS_SC{k}_CAMERA", len(et), ticks, quats, av, 1, ticks[:1])
    finally:
        sp.ckcls(h)
