"""Flyby trajectories: Sun direction and batched Newton targeting (SPEC section 4).

Boundary layer and orchestration for :mod:`ideas_hpc.core.dynamics.ephemeris` and
:mod:`ideas_hpc.core.dynamics.targeting`: it validates inputs (errors name the field),
packs the force model once (:func:`ideas_hpc.dynamics.force_model.pack_force_model`) and
calls one compiled kernel for the whole swarm.

Time convention: ``t`` (s) counts from the epoch of the heliocentric elements
and of the prime-meridian angle (``t = 0``), so ``t0 = 0`` in the paper's
flyby.

The force model lives in three modules: the settings objects of the terms
(:mod:`ideas_hpc.dynamics.force_terms`), the record and its factory
(:mod:`ideas_hpc.dynamics.forces`) and the ``[dynamics]`` table
(:mod:`ideas_hpc.dynamics.force_model`); import its names from there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ideas_hpc.base.constants import MU_SUN
from ideas_hpc.core.dynamics.ephemeris import dcm_PN, sun_T_batch
from ideas_hpc.core.dynamics.targeting import propagate_batch, target_batch
from ideas_hpc.base.errors import InputError
from ideas_hpc.dynamics.force_model import ForceModel, pack_force_model
from ideas_hpc.dynamics.forces import PackedForceModel, elements_and_pole
from ideas_hpc.body.params import PhysicalParams

MAX_STEPS = 100_000


# -------------------------------------------------------------- Sun


def sun_direction_T(params: PhysicalParams, times) -> np.ndarray:
    """Unit vectors body -> Sun in frame T at ``times`` (s after the element epoch).

    See :mod:`ideas_hpc.core.dynamics.ephemeris` for the frames (ecliptic inertial
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
    elements, pole = elements_and_pole(params)
    dirs = np.empty((t.shape[0], 3))
    dist = np.empty(t.shape[0])
    sun_T_batch(t, elements, pole, params.spin_rate, params.prime_meridian, MU_SUN, dirs, dist)
    return dirs, dist


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


@dataclass(frozen=True)
class TargetingSettings:
    """The Newton targeting's knobs: output step ``dt_sample_s``, miss tolerance
    ``tol_m``, at most ``max_iter`` updates; ``raise_on_failure``: raise rather
    than flag a spacecraft that did not converge."""

    dt_sample_s: float = 0.1
    tol_m: float = 0.01
    max_iter: int = 25
    raise_on_failure: bool = True


#: The older keywords of :func:`target_swarm` -> their :class:`TargetingSettings` field.
_TARGETING_KEYWORDS = {"dt_sample": "dt_sample_s", "tol": "tol_m", "max_iter": "max_iter",
                       "raise_on_failure": "raise_on_failure"}


def target_swarm(body, r0_T, r_target_T, t0, tf, *, force_model: ForceModel = ForceModel(),
                 settings: TargetingSettings | None = None, params_override=None,
                 packed: PackedForceModel | None = None, **keywords) -> TargetingResult:
    """Newton-target every spacecraft from ``r0_T`` (at t0) to ``r_target_T`` (at tf).

    One compiled call for the whole swarm (:func:`ideas_hpc.core.dynamics.targeting.target_batch`).
    ``settings`` (:class:`TargetingSettings`) holds ``dt_sample``, ``tol``,
    ``max_iter`` and ``raise_on_failure`` below; the same keywords override it.

    Parameters
    ----------
    body : ideas_hpc.body.bodies.Body
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
    unknown = set(keywords) - set(_TARGETING_KEYWORDS)
    if unknown:
        raise TypeError(f"target_swarm() got an unexpected keyword argument {unknown.pop()!r}")
    s = replace(settings or TargetingSettings(),
                **{_TARGETING_KEYWORDS[k]: v for k, v in keywords.items()})
    dt_sample, tol, max_iter = s.dt_sample_s, s.tol_m, s.max_iter
    raise_on_failure = s.raise_on_failure
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
                    packed: PackedForceModel | None = None, views: bool = False):
    """Fly every spacecraft from given initial states, without targeting.

    Monte Carlo use: the designed ``v0`` (from :func:`target_swarm` on the
    nominal model) flown from a dispersed start through a perturbed field.

    Returns
    -------
    times : (T,) s
    position_T, velocity_T : (N, T, 3)
        m and m/s, frame T; contiguous copies, or with ``views=True`` strided
        views of the integrator's ``(N, T, 6)`` states (no copy: a Monte Carlo
        sample reads only the image positions and the arrival points).

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
    if views:
        return times, states[:, :, :3], states[:, :, 3:]
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


def body_dcm_TN(params: PhysicalParams, w_rad, pole_lon_lat=None) -> np.ndarray:
    """``[T N] = R3(W) [P N]`` (rows: the body-fixed axes in N) at rotation angle(s) ``w_rad``
    (rad, scalar -> (3, 3), array (n,) -> (n, 3, 3)) about the pole ``(lambda, beta)`` in N
    (rad; default ``params``' own pole, or its orbit normal: SPEC section 4). Used by the
    SPICE export and by the drawn worlds' placement."""
    elements, pole = elements_and_pole(params)
    if pole_lon_lat is not None:
        pole = np.array([pole_lon_lat[0], pole_lon_lat[1], 1.0])
    w = np.asarray(w_rad, dtype=np.float64)
    c, s = np.cos(w), np.sin(w)
    r3 = np.zeros(w.shape + (3, 3))
    r3[..., 0, 0], r3[..., 0, 1], r3[..., 1, 0], r3[..., 1, 1], r3[..., 2, 2] = c, s, -s, c, 1.0
    return r3 @ dcm_PN(elements, pole)
