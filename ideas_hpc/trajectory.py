"""Flyby trajectories: force model, Sun direction and batched Newton targeting (SPEC section 4).

Boundary layer and orchestration for :mod:`ideas_hpc.core.gravity`,
:mod:`ideas_hpc.core.ephemeris`, :mod:`ideas_hpc.core.propagate` and
:mod:`ideas_hpc.core.targeting`: it validates inputs (errors name the field),
packs the force model into arrays once, and calls one compiled kernel for
the whole swarm.

Time convention: ``t`` (s) counts from the epoch of the heliocentric elements
and of the prime-meridian angle (``t = 0``), so ``t0 = 0`` in the paper's
flyby.

Force-model options (TOML ``[dynamics]`` table, :func:`force_model_from_config`)::

    gravity      = "degree2"   # point_mass | degree2 | spherical_harmonics | polyhedron
    sh_degree    = 15          # spherical_harmonics: truncation degree
    sh_file      = "n15acoeff.tab"
    srp          = true
    reflectivity = 0.6         # C_r = 1 + reflectivity
    sc_mass      = 4.0         # kg
    sc_area      = 0.035       # m^2 (30x10x10 cm box: total area / 4)
    density      = 2670.0      # kg/m^3, polyhedron (default: body mass / shape volume)
    rtol         = 1e-12       # integrator tolerances (DOP853)
    atol         = 1e-9
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .constants import AU, G, MU_SUN, P_SUN_1AU
from .core import propagate as _prop
from .core.ephemeris import ephemeris_precompute, sun_T_batch
from .core.gravity import polyhedron_precompute, sh_derivative_tables, sh_unnormalise
from .core.targeting import propagate_batch, target_batch
from .errors import InputError
from .params import PhysicalParams

GRAVITY_MODELS = ("point_mass", "degree2", "spherical_harmonics", "polyhedron")
_MODEL_CODE = {"point_mass": _prop.MODEL_POINT_MASS, "degree2": _prop.MODEL_DEGREE2,
               "spherical_harmonics": _prop.MODEL_SH, "polyhedron": _prop.MODEL_POLYHEDRON}

#: 30 x 10 x 10 cm box (SPEC section 4): total surface area / 4, m^2.
BOX_AREA = (4 * 0.30 * 0.10 + 2 * 0.10 * 0.10) / 4.0
MAX_STEPS = 100_000


@dataclass(frozen=True)
class ForceModel:
    """Force model of the flyby dynamics (SPEC section 4). SI units.

    Attributes
    ----------
    gravity : {'point_mass', 'degree2', 'spherical_harmonics', 'polyhedron'}
        ``degree2`` is the point mass plus the C20/C22 field of the body
        parameters; ``spherical_harmonics`` uses ``sh_file`` (GM and reference
        radius from its label); ``polyhedron`` the body's shape at ``density``.
    sh_degree : int
        Truncation degree of the spherical harmonics.
    sh_file : str
        Table name on the data path or a path.
    srp : bool
        Cannonball solar radiation pressure.
    reflectivity : float
        ``C_r = 1 + reflectivity``.
    sc_mass : float
        kg.
    sc_area : float
        m^2.
    density : float or None
        kg/m^3 for the polyhedron; None means body mass / shape volume.
    rtol, atol : float
        DOP853 tolerances (the accuracy contract of SPEC section 4 is checked at
        1e-12 / 1e-9).
    """

    gravity: str = "degree2"
    sh_degree: int = 15
    sh_file: str = "n15acoeff.tab"
    srp: bool = True
    reflectivity: float = 0.6
    sc_mass: float = 4.0
    sc_area: float = BOX_AREA
    density: float | None = None
    rtol: float = 1e-12
    atol: float = 1e-9

    def __post_init__(self):
        _check_force_model(self, "")


def _check_force_model(fm: ForceModel, prefix: str) -> None:
    if fm.gravity not in GRAVITY_MODELS:
        raise InputError(f"must be one of {', '.join(GRAVITY_MODELS)}, got {fm.gravity!r}",
                         field=f"{prefix}gravity")
    if isinstance(fm.sh_degree, bool) or not isinstance(fm.sh_degree, (int, np.integer)) \
            or not 2 <= fm.sh_degree <= 60:
        raise InputError(f"must be an integer in [2, 60], got {fm.sh_degree!r}",
                         field=f"{prefix}sh_degree")
    if not isinstance(fm.sh_file, str) or not fm.sh_file:
        raise InputError("must be a file name or path", field=f"{prefix}sh_file")
    if not isinstance(fm.srp, (bool, np.bool_)):
        raise InputError(f"must be true or false, got {fm.srp!r}", field=f"{prefix}srp")
    checks = (("reflectivity", 0.0, 1.0, False), ("sc_mass", 0.0, math.inf, True),
              ("sc_area", 0.0, math.inf, True), ("rtol", 0.0, 1.0, True),
              ("atol", 0.0, math.inf, True))
    for name, lo, hi, lo_open in checks:
        v = getattr(fm, name)
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
                or not math.isfinite(v) or v < lo or (lo_open and v == lo) or v > hi:
            rng = f"{'>' if lo_open else '>='} {lo:g}" + ("" if hi == math.inf else f" and <= {hi:g}")
            raise InputError(f"must be a finite number {rng}, got {v!r}", field=f"{prefix}{name}")
    if fm.density is not None:
        v = fm.density
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise InputError(f"must be a finite number > 0, got {v!r}", field=f"{prefix}density")


_FM_FIELDS = {f.name for f in dataclasses.fields(ForceModel)}


def force_model_from_config(table: dict | None, prefix: str = "dynamics.") -> ForceModel:
    """Build a :class:`ForceModel` from a TOML table (keys as the attributes, SI units).

    Unknown keys and bad values raise :class:`InputError` naming ``<prefix><key>``.
    """
    table = dict(table or {})
    for k in table:
        if k not in _FM_FIELDS:
            raise InputError(f"unknown key {k!r}; allowed: {', '.join(sorted(_FM_FIELDS))}",
                             field=f"{prefix}{k}")
    kw = {}
    for k, v in table.items():
        if k in ("reflectivity", "sc_mass", "sc_area", "rtol", "atol", "density") \
                and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        kw[k] = v
    fm = ForceModel.__new__(ForceModel)
    for f in dataclasses.fields(ForceModel):
        object.__setattr__(fm, f.name, kw.get(f.name, f.default))
    _check_force_model(fm, prefix)
    return fm


# -------------------------------------------------------------- packing


class PackedForceModel(NamedTuple):
    """Arrays handed to the kernels (see :mod:`ideas_hpc.core.propagate`)."""

    model: int
    consts: np.ndarray
    sh_c: np.ndarray
    sh_s: np.ndarray
    pv: np.ndarray
    pf: np.ndarray
    pe: np.ndarray
    ped: np.ndarray
    pfd: np.ndarray

    def args(self):
        return (self.model, self.consts, self.sh_c, self.sh_s, self.pv, self.pf, self.pe,
                self.ped, self.pfd)


_EMPTY3 = np.zeros((1, 1, 1))
_POLY_CACHE: dict = {}
_SH_CACHE: dict = {}


def _poly_data(shape):
    key = id(shape.vertices_T)
    hit = _POLY_CACHE.get(key)
    if hit is None or hit[0] is not shape.vertices_T:
        v = np.ascontiguousarray(shape.vertices_T, dtype=np.float64)
        f = np.ascontiguousarray(shape.faces, dtype=np.int64)
        e, ed, fd = polyhedron_precompute(v, f)
        hit = (shape.vertices_T, v, f, e, ed, fd)
        _POLY_CACHE[key] = hit
    return hit[1:]


def _sh_field(fm: ForceModel):
    from .gravity_field import load_sh_field

    key = fm.sh_file
    if key not in _SH_CACHE:
        _SH_CACHE[key] = load_sh_field(fm.sh_file)
    fld = _SH_CACHE[key]
    if fm.sh_degree > fld.degree:
        raise InputError(f"sh_degree {fm.sh_degree} above the table's degree {fld.degree}",
                         field="dynamics.sh_degree")
    return fld.truncated(fm.sh_degree)


_OVERRIDE_KEYS = ("mu", "c20", "c22", "reflectivity")


def _apply_override(params: PhysicalParams, fm: ForceModel, override):
    """(params, reflectivity, changed-keys) after a Monte Carlo override."""
    if override is None:
        return params, fm.reflectivity, set()
    if isinstance(override, PhysicalParams):
        return override, fm.reflectivity, {"mu", "c20", "c22"}
    if not isinstance(override, dict):
        raise InputError("must be a dict or PhysicalParams", field="params_override")
    refl = fm.reflectivity
    rep = {}
    for k, v in override.items():
        if k not in _OVERRIDE_KEYS:
            raise InputError(f"unknown key {k!r}; allowed: {', '.join(_OVERRIDE_KEYS)}",
                             field=f"params_override.{k}")
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) \
                or not math.isfinite(v):
            raise InputError(f"must be a finite number, got {v!r}", field=f"params_override.{k}")
        if k == "mu" and v <= 0:
            raise InputError("must be > 0", field="params_override.mu")
        if k == "reflectivity":
            if not 0.0 <= v <= 1.0:
                raise InputError("must be in [0, 1]", field="params_override.reflectivity")
            refl = float(v)
        else:
            rep[k] = float(v)
    return dataclasses.replace(params, **rep), refl, set(rep)


def pack_force_model(body, force_model: ForceModel = ForceModel(),
                     params_override=None) -> PackedForceModel:
    """Pack a force model for the kernels.

    The expensive parts (polyhedron edge data, the spherical-harmonic table and
    its derivative tables) are cached per shape / file, so a Monte Carlo
    sample that perturbs ``mu``, ``c20``, ``c22`` or the reflectivity costs
    only the array packing (and, for spherical harmonics with perturbed
    C20/C22, one O(N^2) table rebuild).

    ``params_override``: dict with SI keys ``mu`` (m^3/s^2), ``c20``, ``c22``
    (m^2), ``reflectivity``, or a whole :class:`PhysicalParams`.
    """
    params = body.require_params()
    params, refl, changed = _apply_override(params, force_model, params_override)
    fm = force_model
    consts = np.zeros(_prop.N_CONSTS)
    consts[_prop.K_MU] = params.mu
    consts[_prop.K_C20] = params.c20
    consts[_prop.K_C22] = params.c22
    consts[_prop.K_SPIN] = params.spin_rate
    if fm.srp:
        consts[_prop.K_SRP] = P_SUN_1AU * AU * AU * (1.0 + refl) * fm.sc_area / fm.sc_mass
    consts[_prop.K_W0] = params.prime_meridian
    consts[_prop.K_MU_SUN] = MU_SUN
    consts[_prop.K_ELEM:_prop.K_ELEM + 6] = (params.orbit_a, params.orbit_e, params.orbit_i,
                                             params.orbit_raan, params.orbit_argp,
                                             params.orbit_nu)
    if params.pole_ra is not None and params.pole_dec is not None:
        consts[_prop.K_POLE:_prop.K_POLE + 3] = (params.pole_ra, params.pole_dec, 1.0)
    consts[_prop.K_EPH:] = ephemeris_precompute(
        consts[_prop.K_ELEM:_prop.K_ELEM + 6].copy(), consts[_prop.K_POLE:_prop.K_POLE + 3].copy(),
        params.spin_rate, params.prime_meridian, MU_SUN)
    e3 = _EMPTY3
    sh_c = sh_s = e3
    pv = np.zeros((1, 3))
    pf = np.zeros((1, 3), dtype=np.int64)
    pe = np.zeros((1, 2), dtype=np.int64)
    ped = pfd = e3
    if fm.gravity == "spherical_harmonics":
        fld = _sh_field(fm)
        nominal = body.require_params()
        gm = fld.gm * (params.mu / nominal.mu if "mu" in changed else 1.0)
        c, s = sh_unnormalise(fld.cbar, fld.sbar)
        if "c20" in changed:
            c[2, 0] = params.c20 / fld.r_ref ** 2
        if "c22" in changed:
            c[2, 2] = params.c22 / fld.r_ref ** 2
        sh_c, sh_s = sh_derivative_tables(c, s)
        consts[_prop.K_SH_GM] = gm
        consts[_prop.K_SH_RREF] = fld.r_ref
    elif fm.gravity == "polyhedron":
        pv, pf, pe, ped, pfd = _poly_data(body.shape)
        rho = fm.density if fm.density is not None else params.mu / (G * body.shape.volume)
        consts[_prop.K_GRHO] = G * rho
    return PackedForceModel(_MODEL_CODE[fm.gravity], consts, sh_c, sh_s, pv, pf, pe, ped, pfd)


# -------------------------------------------------------------- Sun


def sun_direction_T(params: PhysicalParams, times) -> np.ndarray:
    """Unit vectors body -> Sun in frame T at ``times`` (s after the element epoch).

    See :mod:`ideas_hpc.core.ephemeris` for the frames (ecliptic inertial
    frame N, pole = orbit normal unless ``pole_ra/pole_dec`` are set).

    Returns
    -------
    (T, 3) float64
    """
    return _sun(params, times)[0]


def sun_distance(params: PhysicalParams, times) -> np.ndarray:
    """Heliocentric distance of the body (m) at ``times`` (s after the element epoch)."""
    return _sun(params, times)[1]


def _sun(params: PhysicalParams, times):
    """(unit directions body -> Sun in T (T, 3), distances (T,) m) from the ephemeris kernel."""
    t = np.atleast_1d(np.asarray(times, dtype=np.float64))
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise InputError("must be a 1-D array of finite times (s)", field="times")
    t = np.ascontiguousarray(t)
    consts = pack_params_only(params)
    dirs = np.empty((t.shape[0], 3))
    dist = np.empty(t.shape[0])
    sun_T_batch(t, consts[_prop.K_ELEM:_prop.K_ELEM + 6].copy(),
                consts[_prop.K_POLE:_prop.K_POLE + 3].copy(), params.spin_rate,
                params.prime_meridian, MU_SUN, dirs, dist)
    return dirs, dist


def pack_params_only(params: PhysicalParams) -> np.ndarray:
    """``consts`` with the ephemeris part filled (helper for the Sun direction)."""
    consts = np.zeros(_prop.N_CONSTS)
    consts[_prop.K_ELEM:_prop.K_ELEM + 6] = (params.orbit_a, params.orbit_e, params.orbit_i,
                                             params.orbit_raan, params.orbit_argp,
                                             params.orbit_nu)
    if params.pole_ra is not None and params.pole_dec is not None:
        consts[_prop.K_POLE:_prop.K_POLE + 3] = (params.pole_ra, params.pole_dec, 1.0)
    return consts


# -------------------------------------------------------------- targeting


@dataclass
class TargetingResult:
    """Result of :func:`target_swarm` (frame T, SI).

    Attributes
    ----------
    v0_T : (N, 3) float64
        Initial velocities, m/s.
    miss : (N, max_iter + 1) float64
        ``|dr_k|`` per propagation k, m; NaN where not run (paper Fig. 23;
        store variable ``targeting_miss``).
    n_iter : (N,) int
        Newton updates made.
    converged : (N,) bool
    times : (T,) float64
        Sample times, s.
    position_T, velocity_T : (N, T, 3) float64
        Sampled final trajectories, m and m/s (paper Fig. 22; store
        variables ``position``, ``velocity``).
    nfev : (N,) int
        Right-hand-side evaluations (42-state) in the Newton loop.
    """

    v0_T: np.ndarray
    miss: np.ndarray
    n_iter: np.ndarray
    converged: np.ndarray
    times: np.ndarray
    position_T: np.ndarray
    velocity_T: np.ndarray
    nfev: np.ndarray | None = None

    @property
    def final_miss(self) -> np.ndarray:
        """Last miss per spacecraft, m."""
        idx = np.clip(self.n_iter, 0, self.miss.shape[1] - 1)
        return self.miss[np.arange(self.miss.shape[0]), idx]


class TargetingError(RuntimeError):
    """Some spacecraft did not converge; ``.failed`` lists them, ``.result`` has everything."""

    def __init__(self, message, failed, result):
        super().__init__(message)
        self.failed = failed
        self.result = result


def _states(name, x):
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("must be an (N, 3) array of numbers (m)", field=name) from None
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] == 0:
        raise InputError(f"must have shape (N, 3), got {np.shape(x)}", field=name)
    bad = np.where(~np.all(np.isfinite(a), axis=1))[0]
    if bad.size:
        raise InputError(f"non-finite state for spacecraft {bad.tolist()}", field=name)
    return np.ascontiguousarray(a)


def _scalar(name, v, *, positive=False):
    if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
            or not math.isfinite(v):
        raise InputError(f"must be a finite number, got {v!r}", field=name)
    if positive and v <= 0:
        raise InputError(f"must be > 0, got {v!r}", field=name)
    return float(v)


def _check_arc(other_name, r0_T, other, t0, tf, dt_sample):
    """Validate start states, a second (N, 3) array of the same shape, and the time span."""
    r0 = _states("r0_T", r0_T)
    b = _states(other_name, other)
    if b.shape != r0.shape:
        raise InputError(f"shape {b.shape} differs from r0_T {r0.shape}", field=other_name)
    t0 = _scalar("t0", t0)
    tf = _scalar("tf", tf)
    if tf <= t0:
        raise InputError(f"must be > t0 ({t0:g} s), got {tf:g} s", field="tf")
    return r0, b, t0, tf, _scalar("dt_sample", dt_sample, positive=True)


def sample_times(t0: float, tf: float, dt_sample: float) -> np.ndarray:
    """``t0, t0 + dt, ...`` up to tf (tf included when it is on the grid)."""
    n = int(math.floor((tf - t0) / dt_sample * (1.0 + 1e-12) + 1e-9)) + 1
    return t0 + dt_sample * np.arange(n, dtype=np.float64)


def target_swarm(body, r0_T, r_target_T, t0, tf, *, force_model: ForceModel = ForceModel(),
                 dt_sample: float = 0.1, tol: float = 0.01, max_iter: int = 25,
                 raise_on_failure: bool = True, params_override=None,
                 packed: PackedForceModel | None = None) -> TargetingResult:
    """Newton-target every spacecraft from ``r0_T`` (at t0) to ``r_target_T`` (at tf).

    One compiled call for the whole swarm (:func:`ideas_hpc.core.targeting.target_batch`).

    Parameters
    ----------
    body : ideas_hpc.bodies.Body
    r0_T, r_target_T : (N, 3) or (3,) array
        m, frame T.
    t0, tf : float
        s after the element epoch, ``tf > t0``.
    force_model : ForceModel
    dt_sample : float
        Output step, s (the attitude step, 0.1 s).
    tol : float
        Miss tolerance, m (1 cm).
    max_iter : int
        Newton updates at most (25).
    raise_on_failure : bool
        Raise :class:`TargetingError` naming the spacecraft that did not
        converge; otherwise they are flagged in ``converged``.
    params_override : dict or PhysicalParams, optional
        Monte Carlo perturbation (``mu``, ``c20``, ``c22``, ``reflectivity``; SI).
    packed : PackedForceModel, optional
        A pre-packed model (from :func:`pack_force_model`), to skip packing.

    Raises
    ------
    InputError
        Naming the field: ``tf`` <= ``t0``, non-finite ``r0_T``/``r_target_T``,
        a start inside the bounding sphere (``r0_T``), ``tol`` <= 0,
        negative ``max_iter``, ``dt_sample`` <= 0.
    TargetingError
        When ``raise_on_failure`` and a spacecraft did not converge.
    """
    if not isinstance(force_model, ForceModel):
        raise InputError("must be a ForceModel", field="force_model")
    r0, rt, t0, tf, dt_sample = _check_arc("r_target_T", r0_T, r_target_T, t0, tf, dt_sample)
    tol = _scalar("tol", tol, positive=True)
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)):
        raise InputError(f"must be an integer, got {max_iter!r}", field="max_iter")
    if max_iter < 0:
        raise InputError(f"must be >= 0, got {max_iter}", field="max_iter")
    r_max = body.shape.r_max
    for name, arr in (("r0_T", r0), ("r_target_T", rt)):
        inside = np.where(np.linalg.norm(arr, axis=1) <= r_max)[0]
        if inside.size:
            raise InputError(f"spacecraft {inside.tolist()} inside the body's bounding sphere "
                             f"(R_max = {r_max:.1f} m)", field=name)
    pk = packed if packed is not None else pack_force_model(body, force_model, params_override)
    times = sample_times(t0, tf, dt_sample)
    v0, miss, n_iter, conv, states, nfev = target_batch(
        r0, rt, t0, tf, tol, int(max_iter), force_model.rtol, force_model.atol, MAX_STEPS,
        times, *pk.args())
    res = TargetingResult(v0_T=v0, miss=miss, n_iter=n_iter, converged=conv, times=times,
                          position_T=np.ascontiguousarray(states[:, :, :3]),
                          velocity_T=np.ascontiguousarray(states[:, :, 3:]), nfev=nfev)
    if raise_on_failure and not np.all(conv):
        failed = np.where(~conv)[0].tolist()
        fm = res.final_miss
        detail = ", ".join(f"spacecraft {i}: miss {fm[i]:.3g} m after {n_iter[i]} iterations"
                           for i in failed)
        raise TargetingError(f"targeting did not converge to {tol:g} m for {detail}",
                             failed, res)
    return res


def propagate_swarm(body, r0_T, v0_T, t0, tf, *, force_model: ForceModel = ForceModel(),
                    dt_sample: float = 0.1, params_override=None,
                    packed: PackedForceModel | None = None):
    """Fly every spacecraft from given initial states, without targeting.

    Monte Carlo use: the designed ``v0`` (from :func:`target_swarm` on the
    nominal model) flown from a dispersed start through a perturbed field.

    Returns
    -------
    times : (T,) s
    position_T, velocity_T : (N, T, 3)
        m and m/s, frame T.

    Raises
    ------
    InputError
        As :func:`target_swarm` for the states and times.
    RuntimeError
        When the integrator fails for a spacecraft (step limit).
    """
    r0, v0, t0, tf, dt_sample = _check_arc("v0_T", r0_T, v0_T, t0, tf, dt_sample)
    pk = packed if packed is not None else pack_force_model(body, force_model, params_override)
    times = sample_times(t0, tf, dt_sample)
    states, status = propagate_batch(r0, v0, t0, tf, force_model.rtol, force_model.atol,
                                     MAX_STEPS, times, *pk.args())
    if np.any(status != 0):
        bad = np.where(status != 0)[0].tolist()
        raise RuntimeError(f"propagation failed for spacecraft {bad} (status {status[bad]})")
    return (times, np.ascontiguousarray(states[:, :, :3]),
            np.ascontiguousarray(states[:, :, 3:]))


def ring_states(body, angles, d_sep, z_start, z_stop):
    """Start and target positions of a ring swarm (SPEC section 3), m, frame T.

    ``r_i(t0) = [d cos th, d sin th, z_start]``, ``r_i(tf) = [.., .., z_stop]``;
    ``z_start`` may be an array (helical configuration).
    """
    th = np.asarray(angles, dtype=np.float64).ravel()
    zs = np.broadcast_to(np.asarray(z_start, dtype=np.float64), th.shape)
    ze = np.broadcast_to(np.asarray(z_stop, dtype=np.float64), th.shape)
    r0 = np.stack([d_sep * np.cos(th), d_sep * np.sin(th), zs], axis=1)
    rt = np.stack([d_sep * np.cos(th), d_sep * np.sin(th), ze], axis=1)
    return np.ascontiguousarray(r0), np.ascontiguousarray(rt)
