"""SPICE kernels in a campaign (issue 32, SPEC section 7e): ``[body]`` and ``[flyby]`` keys.

``[body] shape`` (a mesh file: ``.bds``/``.dsk`` DSK type 2, ``.tab``, OBJ...) replaces the
mesh of the body that ``[body] name`` names and keeps its parameters.
``[body] kernels`` (paths: a meta-kernel or text/binary kernels) with
``[flyby] epoch_utc`` (UTC, converted to TDB seconds past J2000 with the leap-second
kernel among them) give, at that epoch:

* the heliocentric orbit of ``[body] spice_body`` (NAIF name or ID, default the body
  name) from the SPK, as osculating elements in ``ECLIPJ2000`` with the project's
  ``MU_SUN`` (frame N of :mod:`ideas_hpc.core.dynamics.ephemeris`), true anomaly at the
  epoch, so that flyby time 0 is the epoch (``flyby.epoch_s`` counts from it);
* the pole (RA/Dec in N), the prime-meridian angle ``W0`` (from the ascending node of
  the body equator on the ecliptic to +x of T) and the spin period from the angular
  velocity of ``[body] spice_frame`` (default ``IAU_<spice_body>``) from the PCK;
* with ``[flyby] spice_spacecraft`` (and ``geometry = "encounter"``), the closest approach
  of that spacecraft's SPK within a day of the epoch (sampled each minute, refined by
  Brent's method): its epoch, miss distance and the relative velocity there, in frame
  T, as ``v_inf`` (the body's gravity bends a fast pass by ~1e-8 rad, SPEC section 7c);
  the flyby then places its closest approach at that epoch.

The values are kept in :class:`SpiceValues` (``Campaign.extras["spice"]``), which the
resolved config records under ``models.spice``: a run can be repeated without the
kernels by writing them as ``[body.params]`` keys. Without ``kernels`` nothing changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ideas_hpc.base.fields import Field
from ideas_hpc.base.errors import InputError

SPICE_BODY = {
    "shape": Field("str", None, nullable=True, doc="mesh file replacing the named body's shape"),
    "kernels": Field("any", None, nullable=True, doc="SPICE kernels (list of paths)"),
    "spice_body": Field("str", None, nullable=True, doc="NAIF name or ID of the body"),
    "spice_frame": Field("str", None, nullable=True, doc="body-fixed frame (IAU_<body>)"),
}
SPICE_FLYBY = {
    "epoch_utc": Field("str", None, nullable=True, doc="flyby time 0 in UTC (needs body.kernels)"),
    "spice_spacecraft": Field("str", None, nullable=True,
                              doc="NAIF name/ID of a spacecraft whose SPK gives the encounter"),
}
#: Closest approach is searched this far either side of ``flyby.epoch_utc``, s.
CA_SEARCH_S = 86400.0


@dataclass(frozen=True)
class SpiceValues:
    """What the kernels gave (SI, rad; N = ECLIPJ2000), recorded in the resolved config."""

    epoch_utc: str
    epoch_et_s: float
    spice_body: str
    spice_frame: str
    orbit_a_m: float
    orbit_e: float
    orbit_i_rad: float
    orbit_raan_rad: float
    orbit_argp_rad: float
    orbit_nu_rad: float
    pole_ra_rad: float
    pole_dec_rad: float
    prime_meridian_rad: float
    spin_period_s: float
    ca_et_s: float | None = None
    miss_m: float | None = None
    v_inf_T_m_s: tuple | None = None

    def params_keys(self) -> dict:
        """The same values as ``[body.params]`` keys in the file's units."""
        from ideas_hpc.base.constants import AU

        d = math.degrees
        return {"a_au": self.orbit_a_m / AU, "e": self.orbit_e, "i_deg": d(self.orbit_i_rad),
                "raan_deg": d(self.orbit_raan_rad), "argp_deg": d(self.orbit_argp_rad),
                "nu_deg": d(self.orbit_nu_rad), "pole_ra_deg": d(self.pole_ra_rad),
                "pole_dec_deg": d(self.pole_dec_rad),
                "prime_meridian_deg": d(self.prime_meridian_rad),
                "spin_period_h": self.spin_period_s / 3600.0}


def _kernel_list(value, base: Path | None) -> list[str]:
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, list) or not all(isinstance(k, str) for k in items) or not items:
        raise InputError("must be a path or a list of paths of SPICE kernels", field="body.kernels")
    out = []
    for k in items:
        p = Path(k).expanduser()
        if not p.is_absolute() and base is not None and not p.exists():
            p = base / p
        if not p.is_file():
            raise InputError(f"no such kernel file {k!r}", field="body.kernels")
        out.append(str(p))
    return out


def true_anomaly(mean_anomaly: float, e: float) -> float:
    """True anomaly (rad) of an ellipse from its mean anomaly: the eccentric anomaly from the
    project's one Kepler solver (:func:`ideas_hpc.core.dynamics.ephemeris.kepler_E`, the
    one the ephemeris propagates with), then the half-angle form."""
    from ideas_hpc.core.dynamics.ephemeris import kepler_E

    E = float(kepler_E(float(mean_anomaly), float(e)))
    return 2.0 * math.atan2(math.sqrt(1 + e) * math.sin(E / 2), math.sqrt(1 - e) * math.cos(E / 2))


def orientation_angles(dcm_TN) -> tuple[float, float, float]:
    """``(pole_ra, pole_dec, W0)`` (rad) of a body frame T given by ``[TN]`` (rows: T axes in N),
    in the convention of :mod:`ideas_hpc.core.dynamics.ephemeris`."""
    m = np.asarray(dcm_TN, dtype=np.float64)
    p, x_t = m[2], m[0]
    ra, dec = math.atan2(p[1], p[0]), math.asin(max(-1.0, min(1.0, p[2])))
    node = np.cross([0.0, 0.0, 1.0], p)
    n = float(np.linalg.norm(node))
    x_p = node / n if n > 1e-12 else np.array([1.0, 0.0, 0.0])
    w0 = math.atan2(float(np.cross(x_p, x_t) @ p), float(x_p @ x_t))
    return ra, dec, w0 % (2.0 * math.pi)


def resolve_spice(raw: dict, body_name: str, source: Path | None = None) -> dict:
    """``{"spice": SpiceValues}`` from ``body.kernels`` (paths relative to the campaign file
    ``source`` or here) at ``flyby.epoch_utc``; ``{}`` without kernels (nothing changes)."""
    values = _resolve(raw, body_name, Path(source).parent if source else None)
    return {"spice": values} if values is not None else {}


def _resolve(raw: dict, body_name: str, base: Path | None) -> SpiceValues | None:
    from ideas_hpc.base.constants import MU_SUN
    from ideas_hpc.base.spice import spiceypy

    body = raw.get("body") or {}
    flyby = raw.get("flyby") or {}
    if body.get("kernels") is None:
        if flyby.get("epoch_utc") is not None:
            raise InputError("needs body.kernels (a leap-second kernel at least)",
                             field="flyby.epoch_utc")
        return None
    utc = flyby.get("epoch_utc")
    if utc is None:
        raise InputError("is required with body.kernels (the epoch of the kernels' values)",
                         field="flyby.epoch_utc")
    sp = spiceypy("body.kernels")
    files = _kernel_list(body["kernels"], base)
    target = body.get("spice_body") or str(body_name)
    for f in files:
        sp.furnsh(f)
    try:
        try:
            et = sp.str2et(utc)
        except sp.utils.exceptions.SpiceyError as exc:
            raise InputError(f"cannot convert {utc!r} to TDB: {exc.short}",
                             field="flyby.epoch_utc") from None
        try:
            code = sp.bods2c(target)
        except sp.utils.exceptions.SpiceyError:
            raise InputError(f"{target!r} is not a NAIF body name or ID",
                             field="body.spice_body") from None
        frame = body.get("spice_frame") or f"IAU_{sp.bodc2n(code)}"
        try:
            state, _ = sp.spkezr(str(code), et, "ECLIPJ2000", "NONE", "SUN")
        except sp.utils.exceptions.SpiceyError as exc:
            raise InputError(f"no heliocentric state of {target!r} at {utc}: {exc.short}",
                             field="body.kernels") from None
        try:
            xf = sp.sxform("ECLIPJ2000", frame, et)
        except sp.utils.exceptions.SpiceyError as exc:
            raise InputError(f"no orientation of frame {frame!r} at {utc}: {exc.short}",
                             field="body.spice_frame") from None
        enc = _closest_approach(sp, flyby, code, frame, et) if flyby.get("spice_spacecraft") \
            else {}
    finally:
        for f in files:
            sp.unload(f)
    el = sp.oscelt(np.asarray(state), et, MU_SUN / 1e9)
    rp_km, e = float(el[0]), float(el[1])
    if not 0.0 <= e < 1.0:
        raise InputError(f"the SPK state of {target!r} is not on an ellipse about the Sun "
                         f"(e = {e:.4g})", field="body.kernels")
    dcm, omega = sp.xf2rav(xf)
    ra, dec, w0 = orientation_angles(dcm)
    rate = float(np.asarray(omega) @ np.asarray(dcm)[2])   # spin about +z of T, rad/s
    if not rate > 0.0:
        raise InputError(f"frame {frame!r} does not spin about its +z axis",
                         field="body.spice_frame")
    return SpiceValues(
        epoch_utc=utc, epoch_et_s=float(et), spice_body=target, spice_frame=frame,
        orbit_a_m=rp_km * 1e3 / (1.0 - e), orbit_e=e, orbit_i_rad=float(el[2]),
        orbit_raan_rad=float(el[3]), orbit_argp_rad=float(el[4]),
        orbit_nu_rad=true_anomaly(float(el[5]), e) % (2.0 * math.pi), pole_ra_rad=ra,
        pole_dec_rad=dec, prime_meridian_rad=w0, spin_period_s=2.0 * math.pi / rate, **enc)


def _closest_approach(sp, flyby: dict, body_code: int, frame: str, et0: float) -> dict:
    """Closest approach of ``flyby.spice_spacecraft`` to the body within a day of ``et0``."""
    from scipy.optimize import minimize_scalar

    name = flyby["spice_spacecraft"]
    if flyby.get("geometry") != "encounter":
        raise InputError('needs flyby.geometry = "encounter"', field="flyby.spice_spacecraft")
    given = [k for k in ("v_inf_km_s", "speed_km_s", "approach_dec_deg", "approach_ra_deg",
                         "phase_angle_deg") if flyby.get(k) is not None]
    if given:
        raise InputError(f"gives the approach already: drop flyby.{given[0]}",
                         field="flyby.spice_spacecraft")

    def dist(t):
        try:
            return float(np.linalg.norm(sp.spkpos(name, t, "J2000", "NONE", str(body_code))[0]))
        except sp.utils.exceptions.SpiceyError as exc:
            raise InputError(f"no state of {name!r} relative to the body at ET {t:.1f}: "
                             f"{exc.short}", field="flyby.spice_spacecraft") from None

    grid = et0 + np.arange(-CA_SEARCH_S, CA_SEARCH_S + 1.0, 60.0)
    d = np.array([dist(t) for t in grid])
    k = int(np.argmin(d))
    if k in (0, len(grid) - 1):
        raise InputError(f"{name!r} has no closest approach within a day of flyby.epoch_utc",
                         field="flyby.spice_spacecraft")
    # Offsets from the sampled minimum: Brent's relative tolerance sqrt(eps)|x| on raw ET
    # (~1e9 s) would stop 10 s away.
    best = minimize_scalar(lambda s: dist(grid[k] + s), bounds=(-60.0, 60.0), method="bounded",
                           options={"xatol": 1e-6})
    et_ca = float(grid[k] + best.x)
    state = np.asarray(sp.spkezr(name, et_ca, "J2000", "NONE", str(body_code))[0])
    v_T = np.asarray(sp.pxform("J2000", frame, et_ca)) @ state[3:] * 1e3
    return {"ca_et_s": et_ca, "miss_m": float(best.fun) * 1e3,
            "v_inf_T_m_s": tuple(float(x) for x in v_T)}


def apply_spice(params, values: SpiceValues | None):
    """``params`` (:class:`~ideas_hpc.body.params.PhysicalParams`) with the kernels' orbit,
    pole, prime meridian and spin; unchanged without kernels."""
    import dataclasses

    if values is None:
        return params
    return dataclasses.replace(
        params, orbit_a=values.orbit_a_m, orbit_e=values.orbit_e, orbit_i=values.orbit_i_rad,
        orbit_raan=values.orbit_raan_rad, orbit_argp=values.orbit_argp_rad,
        orbit_nu=values.orbit_nu_rad, pole_ra=values.pole_ra_rad, pole_dec=values.pole_dec_rad,
        prime_meridian=values.prime_meridian_rad, spin_period=values.spin_period_s)
