"""Navigation errors in a flight: the start state and the aim of body tracking (SPEC 7f).

A scenario's navigation draw (:mod:`ideas_hpc.flyby.navigation`) gives, in the encounter's
inertial frame N (= T at the predicted closest approach ``t_ca``, +z the spin pole), the
true target's offset ``delta`` from the predicted one at ``t_ca`` (common to the swarm)
and each member's own error ``m_i``. Member ``i`` is then at ``o_i = m_i - delta`` from
where it planned to be, relative to the true target
(:func:`~ideas_hpc.flyby.navigation.member_offsets_N`).

Start state
-----------
At 10 km/s the pass is a straight line (gravity bends it by ~1e-7 rad, SPEC 7c), so a
constant offset ``o_i`` in N at ``t_ca`` is the same offset at the start ``t0``, with the
same inertial velocity. In the rotating frame T, ``r_T = R3(phi) r_N`` and
``v_T = R3(phi) (v_N - w x r_N)`` with ``phi = w (t - t_ca)``
(:mod:`ideas_hpc.core.dynamics.encounter`), so the start state moves by::

    dr_T = R3(phi0) o_i,       dv_T = -R3(phi0) (w x o_i),      phi0 = w (t0 - t_ca).

The along-track part of ``delta`` (``|v| dt S``) makes the true closest approach ``dt``
late while the imaging window stays on the predicted clock.

Pointing
--------
Body tracking aims from where the member believes it is (its plan: the flown position
less ``o_i``) at the predicted target, so the camera points along ``-(r - o_i)`` instead of
``-r``: the ephemeris error becomes the bias of
:func:`~ideas_hpc.flyby.pass_rates.pointing_bias_rad` (``~ |o_perp| / rho``). Terminal
tracking locks on the measured centroid once the true range is within
:attr:`~ideas_hpc.flyby.navigation.NavigationPlan.detect_range_m` (and stays locked): the
camera then aims at the true centre, turned by the member's centroid error (a small
rotation about ``x_B`` and ``y_B``, drawn per member). Other maneuvers (nadir, sweeps)
fly their planned attitude in N, which does not depend on the target's position: their
error is the offset of the track alone.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.core.attitude.compose import compose_each


def member_offsets(pert, n: int) -> np.ndarray | None:
    """``o_i = m_i - delta`` (n, 3) m in N of a perturbation's navigation draws
    (``target_offset_N``, ``member_offset_N``), or None when it has none (or only zeros)."""
    t = getattr(pert, "target_offset_N", None)
    m = getattr(pert, "member_offset_N", None)
    c = getattr(pert, "centroid_prv", None)
    if t is None and m is None or not (np.any(t) or np.any(m) or np.any(c)):
        return None     # no navigation error: the nominal flight, bit for bit
    out = np.zeros((n, 3))
    if m is not None:
        out += np.asarray(m, dtype=np.float64).reshape(n, 3)
    if t is not None:
        out -= np.asarray(t, dtype=np.float64).reshape(1, 3)
    return out


def _r3(phi, v_N):
    """``R3(phi) v``: ``phi`` (T,), ``v`` (N, 3) -> (N, T, 3)."""
    c, s = np.cos(phi)[None, :], np.sin(phi)[None, :]
    x, y = v_N[:, None, 0], v_N[:, None, 1]
    z = np.broadcast_to(v_N[:, None, 2], (v_N.shape[0], phi.size))
    return np.stack([c * x + s * y, -s * x + c * y, z], axis=-1)


def offset_T(setup, off_N: np.ndarray, times_s) -> tuple[np.ndarray, np.ndarray]:
    """``(R3(phi) o, -R3(phi) (w x o))`` (N, T, 3): the offsets ``off_N`` (N, 3) m in N
    as positions (m) and velocities (m/s) in T at flyby times ``times_s`` (module
    docstring)."""
    w = float(setup.body.params.spin_rate)
    phi = w * (np.atleast_1d(np.asarray(times_s, dtype=np.float64)) - setup.encounter.t_ca_s)
    o = np.asarray(off_N, dtype=np.float64).reshape(-1, 3)
    w_x_o = np.cross(np.array([0.0, 0.0, w]), o)
    return _r3(phi, o), -_r3(phi, w_x_o)


def start_errors_T(setup, off_N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(dr_T, dv_T)`` (N, 3): the start-state change at ``setup.t0_s`` of the offsets
    ``off_N`` (module docstring)."""
    dr, dv = offset_T(setup, off_N, [setup.t0_s])
    return dr[:, 0], dv[:, 0]


def believed_track(setup, pos_T, vel_T, off_N):
    """The track (N, T, 3) a member believes it flies (its plan), from the flown one at
    the attitude steps: ``r - R3 o``, ``v + R3 (w x o)``, for the closed loop's body-tracking
    reference (the reference aims at the predicted target)."""
    t = setup.t0_s + setup.dt_s * np.arange(np.shape(pos_T)[1])
    dr, dv = offset_T(setup, off_N, t)
    return np.ascontiguousarray(pos_T - dr), np.ascontiguousarray(vel_T - dv)


def locked(setup, r_img_T) -> np.ndarray:
    """(N, n_img) bool: terminal tracking has locked on the centroid (the true range has been
    within ``setup.navigation.detect_range_m`` at this image or an earlier one)."""
    nav = setup.navigation
    rng_m = np.linalg.norm(np.asarray(r_img_T), axis=-1)
    if nav is None or nav.detect_range_m <= 0.0:
        return np.zeros(rng_m.shape, dtype=bool)
    return np.logical_or.accumulate(rng_m <= nav.detect_range_m, axis=1)


def aim_positions_T(setup, r_img_T, off_N) -> np.ndarray:
    """Where body tracking aims from, (N, n_img, 3) m in T: the believed positions
    ``r - R3 o`` (at the predicted target) before the lock, the flown ones (the measured
    centroid) after it."""
    r = np.asarray(r_img_T, dtype=np.float64)
    dr, _ = offset_T(setup, off_N, setup.image_times)
    lock = locked(setup, r)
    return np.ascontiguousarray(np.where(lock[..., None], r, r - dr))


def with_centroid_errors(setup, dcm_BT, r_img_T, centroid_dcm) -> np.ndarray:
    """``dcm_BT`` (N, n_img, 3, 3) turned by each member's centroid error ``centroid_dcm``
    (N, 3, 3) at the images where terminal tracking is locked."""
    lock = locked(setup, r_img_T)
    if centroid_dcm is None or not lock.any():
        return dcm_BT
    turned = compose_each(np.ascontiguousarray(centroid_dcm, dtype=np.float64),
                          np.ascontiguousarray(dcm_BT, dtype=np.float64))
    return np.where(lock[..., None, None], turned, dcm_BT)
