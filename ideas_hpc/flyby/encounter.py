"""Real encounters: any approach direction and speed, the body turning underneath
(SPEC section 7c; issue 24). Boundary and orchestration for :mod:`ideas_hpc.core.dynamics.encounter`.

The paper's geometry (:mod:`ideas_hpc.flyby.flight`, ``flyby.geometry = "paper"``)
holds each spacecraft at fixed ``x, y`` in the rotating body frame. An
encounter instead flies ballistic trajectories: spacecraft ``i`` starts on the
straight track through its ring point (radius ``d_sep`` in the plane through the
body centre normal to ``v_inf``, swarm angle ``theta_i``) at flyby time ``t0``,
is Newton-targeted (the existing STM solver, :func:`ideas_hpc.dynamics.trajectory.target_swarm`)
to pass that ring point at closest approach ``t_ca`` under the full force model
(gravity, SRP) in the rotating frame T, and is then propagated to ``tf``.

The swarm and ring frames follow from ``v_inf`` (paper eqs. 7-14 with ``v_SC``
along the mean velocity; for a ring symmetric about the track the mean velocity
at closest approach is ``v_inf`` to first order in the bending, about 1e-7 rad
for Eros at 10 km/s): they are fixed in the inertial frame N (= T at ``t_ca``),
so the camera frames are the paper's maneuvers in N, turned into T by the
spin (:class:`ideas_hpc.flyby.geometry.EncounterGeometry`).

The start point lies on the straight track and the pass through the ring point
at ``t_ca`` is exact (to the targeting tolerance); with gravity the speed and
direction far from the body then equal ``v_inf`` to first order in
``mu / (d v_inf^2)`` (1e-8 for Eros at 10 km/s and 156 km).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.attitude import default_spacecraft, ideal_dcm_BT
from ideas_hpc.core.dynamics.encounter import (dcm_BT_from_BN, dcm_NS, pointing_demand, straight_tracks_T,
                             track_dcm_BN)
from ideas_hpc.core.attitude.maneuvers import track_rates, track_reference_table
from ideas_hpc.base.errors import InputError
from ideas_hpc.dynamics.trajectory import TargetingResult, propagate_swarm, target_swarm

DEFAULT_SPEED_M_S = 10e3
DEFAULT_WINDOW_M = 30e3


@dataclass(frozen=True)
class Encounter:
    """A ballistic encounter, SI: approach direction in T at closest approach, speed,
    flyby time of closest approach."""

    speed_m_s: float
    ra_rad: float
    dec_rad: float
    t_ca_s: float

    @property
    def dcm_NS(self) -> np.ndarray:
        """Swarm frame ``[N S]`` (columns in N = T at closest approach)."""
        return dcm_NS(self.ra_rad, self.dec_rad)

    @property
    def v_inf_T(self) -> np.ndarray:
        """Asymptotic relative velocity in T at closest approach, m/s."""
        return self.speed_m_s * self.dcm_NS[:, 2]


def approach_angles(v_inf_T_m_s=None, speed_m_s=None, ra_rad=None, dec_rad=None,
                    phase_angle_rad=None, sun_T_ca=None) -> tuple[float, float, float]:
    """``(speed m/s, ra rad, dec rad)`` of the approach, from plain SI inputs.

    Parameters
    ----------
    v_inf_T_m_s : (3,) array_like or None
        Asymptotic relative velocity in T, m/s; when given it fixes everything.
    speed_m_s : float or None
        ``|v_inf|``, m/s (default 10 km/s).
    ra_rad, dec_rad : float or None
        Approach right ascension and declination in T, rad (defaults 0 and pi/2).
    phase_angle_rad : float or None
        Sun-body-spacecraft angle on approach, rad; replaces ``ra_rad``.
    sun_T_ca : (3,) array_like
        Body -> Sun direction in T at closest approach (with ``phase_angle_rad``).

    ``phase_angle`` (between the Sun direction ``s`` and ``-v_inf``) fixes the
    right ascension for the given declination: ``-u . s = cos(alpha)`` with
    ``u = (cos d cos a, cos d sin a, sin d)`` gives ``cos d rho cos(a - psi) =
    -cos(alpha) - sin d s_z`` (``rho, psi``: the polar form of ``s_x, s_y``); of
    the two roots the one east of the Sun's meridian, ``a = psi + acos(...)``,
    is taken. Errors name these parameters (``v_inf_T_m_s``, ``phase_angle_rad``).
    """
    if v_inf_T_m_s is not None:
        v = np.asarray(v_inf_T_m_s, dtype=np.float64)
        speed = float(np.linalg.norm(v))
        if speed <= 0.0:
            raise InputError("must not be the zero vector", field="v_inf_T_m_s")
        return speed, math.atan2(v[1], v[0]), math.asin(max(-1.0, min(1.0, v[2] / speed)))
    speed = speed_m_s if speed_m_s is not None else DEFAULT_SPEED_M_S
    dec = dec_rad if dec_rad is not None else 0.5 * math.pi
    if phase_angle_rad is None:
        return speed, ra_rad or 0.0, dec
    s = np.asarray(sun_T_ca, dtype=np.float64)
    rho = math.hypot(s[0], s[1])
    rhs = -math.cos(phase_angle_rad) - math.sin(dec) * s[2]
    lim = math.cos(dec) * rho
    if abs(rhs) > lim * (1 + 1e-12) or lim == 0.0:
        lo = math.degrees(math.acos(min(1.0, -math.sin(dec) * s[2] + lim)))
        hi = math.degrees(math.acos(max(-1.0, -math.sin(dec) * s[2] - lim)))
        raise InputError(f"{math.degrees(phase_angle_rad):g} deg cannot be reached at "
                         f"declination {math.degrees(dec):g} deg with the Sun at this epoch "
                         f"(reachable: {lo:.1f} to {hi:.1f} deg)", field="phase_angle_rad")
    a = math.atan2(s[1], s[0]) + math.acos(max(-1.0, min(1.0, rhs / lim)))
    return speed, math.remainder(a, 2 * math.pi), dec


def approach_speed(v_inf_T_m_s=None, speed_m_s=None) -> float:
    """``|v_inf|`` (m/s): of ``v_inf_T_m_s`` when given, else ``speed_m_s`` or 10 km/s."""
    if v_inf_T_m_s is not None:
        return float(np.linalg.norm(v_inf_T_m_s))
    return speed_m_s if speed_m_s is not None else DEFAULT_SPEED_M_S


def window_s(speed_m_s: float, image_dt_s: float, before_s=None, after_s=None,
             before_m=None, after_m=None) -> tuple[float, float]:
    """``(before, after)`` closest approach, s, on the image grid (at least one image period).

    From ``before_s``/``after_s`` or, by default, ``before_m``/``after_m`` (m) at
    the approach speed ``speed_m_s`` (30 km each when neither is given).
    """
    out = []
    for t, d in ((before_s, before_m), (after_s, after_m)):
        if t is None:
            t = (d if d is not None else DEFAULT_WINDOW_M) / speed_m_s
        out.append(max(1, round(t / image_dt_s)) * image_dt_s)
    return out[0], out[1]


def phase_angle(enc: Encounter, sun_T_ca) -> float:
    """Sun-body-spacecraft angle on approach, rad: between the Sun and ``-v_inf``."""
    s = np.asarray(sun_T_ca, dtype=np.float64)
    u = enc.dcm_NS[:, 2]
    return math.acos(max(-1.0, min(1.0, float(-u @ s) / float(np.linalg.norm(s)))))


def tracks_T(setup, theta, times) -> np.ndarray:
    """Gravity-free straight tracks (N, T, 3) of the swarm ``theta`` in T, m."""
    enc = setup.encounter
    th = np.ascontiguousarray(np.asarray(theta, dtype=np.float64).ravel())
    t = np.ascontiguousarray(np.atleast_1d(np.asarray(times, dtype=np.float64)))
    return straight_tracks_T(th, np.ascontiguousarray(enc.dcm_NS), float(setup.d_sep_m),
                             enc.speed_m_s, enc.t_ca_s, setup.body.params.spin_rate, t)


def endpoints_encounter(setup, theta) -> tuple[np.ndarray, np.ndarray]:
    """Start points at ``t0`` and ring points at ``t_ca`` (N, 3), m, frame T."""
    r = tracks_T(setup, theta, [setup.t0_s, setup.encounter.t_ca_s])
    return np.ascontiguousarray(r[:, 0]), np.ascontiguousarray(r[:, 1])


def target_encounter(setup, theta, *, raise_on_failure: bool = True) -> TargetingResult:
    """Target every spacecraft to its ring point at ``t_ca``, then fly the whole window.

    Returns the :class:`~ideas_hpc.dynamics.trajectory.TargetingResult` of the arc
    ``t0 -> t_ca`` (``v0_T``, miss history) with the trajectory sampled every
    ``setup.dt_s`` over ``[t0_s, tf_s]``.
    """
    r0, r_ca = endpoints_encounter(setup, theta)
    t_ca = setup.encounter.t_ca_s
    try:
        arc = target_swarm(setup.body, r0, r_ca, setup.t0_s, t_ca, force_model=setup.force_model,
                           dt_sample=t_ca - setup.t0_s, tol=setup.tol_m, max_iter=setup.max_iter,
                           raise_on_failure=raise_on_failure)
    except InputError as exc:
        if exc.field == "r0_T":
            raise InputError(f"{exc.message}: the imaging window starts inside the body's "
                             "bounding sphere; start it further out (`before_m` or before_s) "
                             "with the ring outside R_max (`d_sep_m`)",
                             field="before_m") from None
        if exc.field == "r_target_T":
            raise InputError(f"{exc.message}: the ring passes inside the body's bounding "
                             f"sphere; increase `d_sep_m` (now {setup.d_sep_m / 1e3:.4g} km)",
                             field="d_sep_m") from None
        raise
    v0 = np.where(np.isfinite(arc.v0_T), arc.v0_T, 0.0)
    times, pos, vel = propagate_swarm(setup.body, r0, v0, setup.t0_s, setup.tf_s,
                                      force_model=setup.force_model, dt_sample=setup.dt_s)
    return TargetingResult(v0_T=arc.v0_T, miss=arc.miss, n_iter=arc.n_iter,
                           converged=arc.converged, times=times, position_T=pos,
                           velocity_T=vel, nfev=arc.nfev)


def track_dcms(setup, r_img_T) -> tuple[np.ndarray, np.ndarray]:
    """``([B T], [B N])`` (N, n_img, 3, 3) of the body-tracking camera (``attitude.maneuver =
    "track"``) along the flown positions ``r_img_T`` at the image times."""
    enc = setup.encounter
    t = np.ascontiguousarray(setup.image_times)
    w = setup.body.params.spin_rate
    bn = track_dcm_BN(np.ascontiguousarray(r_img_T, dtype=np.float64), t, enc.t_ca_s, w,
                      np.ascontiguousarray(enc.dcm_NS[:, 2]))
    return dcm_BT_from_BN(bn, w, t, enc.t_ca_s), bn


def track_reference(setup, r_T, v_T) -> np.ndarray:
    """Body-tracking reference (N, T, 9) in N at the attitude steps, from the flown track.

    ``r_T``, ``v_T`` (N, T, 3): positions (m) and velocities (m/s) in T at
    ``t0 + k dt``, ``k = 0 .. T - 1``; turned into N (``N = T`` at closest
    approach, ``v_N = [N T] v_T + w x r_N``) for
    :func:`ideas_hpc.core.attitude.maneuvers.track_reference_table`.
    """
    enc = setup.encounter
    r = np.asarray(r_T, dtype=np.float64)
    r_N, v_N = _state_N(setup, setup.t0_s + setup.dt_s * np.arange(r.shape[1]), r, v_T)
    return track_reference_table(r_N, v_N, np.ascontiguousarray(enc.dcm_NS[:, 2]),
                                 float(setup.dt_s))


def _state_N(setup, times_s, r_T, v_T) -> tuple[np.ndarray, np.ndarray]:
    """``(r_N, v_N)`` (N, T, 3) of positions ``r_T`` (m) and velocities relative to T
    ``v_T`` (m/s) at flyby times ``times_s`` (T,): ``N = T`` at closest approach,
    ``r_N = R3(phi)^T r_T``, ``v_N = R3(phi)^T v_T + w x r_N``, ``phi = w (t - t_ca)``."""
    w = setup.body.params.spin_rate
    r = np.asarray(r_T, dtype=np.float64)
    v = np.asarray(v_T, dtype=np.float64)
    phi = w * (np.asarray(times_s, dtype=np.float64) - setup.encounter.t_ca_s)
    c, s_ = np.cos(phi)[None, :], np.sin(phi)[None, :]
    r_N = np.stack([c * r[..., 0] - s_ * r[..., 1], s_ * r[..., 0] + c * r[..., 1], r[..., 2]],
                   axis=-1)
    v_N = np.stack([c * v[..., 0] - s_ * v[..., 1], s_ * v[..., 0] + c * v[..., 1], v[..., 2]],
                   axis=-1) + np.cross([0.0, 0.0, w], r_N)
    return np.ascontiguousarray(r_N), np.ascontiguousarray(v_N)


def track_omega_BN_B(setup, r_img_T, v_img_T) -> np.ndarray:
    """(N, n_img, 3) rad/s: the inertial rate, B components, of the body-tracking camera
    of :func:`track_dcms` at the image times, along positions ``r_img_T`` (m) with
    velocities relative to T ``v_img_T`` (m/s): the tracking frame's rate in the state
    (:func:`~ideas_hpc.core.attitude.maneuvers.track_rates`), exact, not differenced
    across images."""
    r_N, v_N = _state_N(setup, setup.image_times, r_img_T, v_img_T)
    return track_rates(r_N, v_N, np.ascontiguousarray(setup.encounter.dcm_NS[:, 2]))


def pointing_check(dcm_BN, dt: float, spacecraft) -> dict:
    """Peak rate, torque and momentum the pointing profile asks for, against the wheels.

    Returns a dict of (N,) arrays ``pointing_rate`` (rad/s), ``pointing_torque``
    (N m), ``pointing_momentum`` (N m s), ``pointing_feasible`` (bool: torque
    <= ``u_max_N_m`` and momentum <= ``h_max_N_m_s``) and the one-line ``summary``.
    """
    rate, tq, h = pointing_demand(np.ascontiguousarray(dcm_BN, dtype=np.float64), float(dt),
                                  np.ascontiguousarray(spacecraft.inertia_rw))
    ok = (tq <= spacecraft.u_max_N_m) & (h <= spacecraft.h_max_N_m_s)
    head = (f"pointing: peak rate {math.degrees(rate.max()):.3g} deg/s, torque "
            f"{tq.max() * 1e3:.3g} mN m (wheel limit {spacecraft.u_max_N_m * 1e3:g}), momentum "
            f"{h.max() * 1e3:.3g} mN m s (limit {spacecraft.h_max_N_m_s * 1e3:g})")
    if ok.all():
        summary = head + ": the wheels can follow"
    else:
        bad = np.where(~ok)[0].tolist()
        summary = (f"WARNING {head}: spacecraft {bad} cannot follow this pointing profile "
                   "(slower encounter, larger d_sep or stronger wheels)")
    return {"pointing_rate": rate, "pointing_torque": tq, "pointing_momentum": h,
            "pointing_feasible": ok, "summary": summary}


def pointing_profile(setup, theta, periods=None, r_img_T=None) -> dict:
    """:func:`pointing_check` of the swarm's reference attitude at the image times.

    The maneuver runs in the geometry's ring frames and is turned into N
    (paper: ``[B N] = [B T] R3(w t)``; encounter: already in N); body tracking:
    along the flown positions ``r_img_T``.
    """
    th = np.asarray(theta, dtype=np.float64).ravel()
    sc = setup.spacecraft or default_spacecraft()
    if setup.maneuver.tracks_body:
        return pointing_check(track_dcms(setup, r_img_T)[1], setup.image_dt_s, sc)
    img_t = setup.image_times - setup.t0_s
    kw = dict(mode=setup.maneuver.name, periods=periods, theta_max=setup.theta_max_rad, p_min=setup.p_min_s)
    geo = setup.geometry
    w, ts = geo.maneuver_frame(setup, setup.body.params.spin_rate)
    bn = geo.to_N(setup, ideal_dcm_BT(th, w, img_t, dcm_TS=ts, **kw), img_t)
    return pointing_check(bn, setup.image_dt_s, sc)


def encounter_attrs(setup) -> dict:
    """Store attrs of an encounter (SI): speed, approach angles, closest approach, phase."""
    enc = setup.encounter
    sun = setup.sun_T([enc.t_ca_s])[0]
    return {"geometry": "encounter", "speed_m_s": enc.speed_m_s, "approach_ra_rad": enc.ra_rad,
            "approach_dec_rad": enc.dec_rad, "t_ca_s": enc.t_ca_s,
            "phase_angle_rad": phase_angle(enc, sun), "v_inf_T_m_s": enc.v_inf_T.tolist(),
            **navigation_attrs(getattr(setup, "navigation", None))}


def navigation_attrs(plan) -> dict:
    """Store attrs of the navigation errors (SPEC 7f; 1-sigma, SI), or {} without them."""
    if plan is None:
        return {}
    e = plan.error
    return {"navigation_sigma_major_m": e.sigma_major_m, "navigation_sigma_minor_m":
            e.sigma_minor_m, "navigation_angle_rad": e.theta_rad,
            "navigation_sigma_tca_s": e.sigma_tca_s, "navigation_sigma_member_m": e.sigma_member_m,
            "navigation_update": e.update, "navigation_source": e.source,
            "navigation_detect_range_m": plan.detect_range_m,
            "navigation_centroid_sigma_rad": plan.centroid_sigma_rad}
