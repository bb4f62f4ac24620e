"""A scenario's perturbed flight for the bank's rows, in one pass (issue 31).

What :func:`ideas_hpc.flyby.flight.open_loop_views` returns for a closed-loop
flight started on its reference (``monte_carlo.attitude_start = "reference"``):
the positions at the images and the imaging cameras (misaligned, unusable images
blinded), the same bits, at a fraction of the cost:

* what does not depend on the scenario's draws (ring frames, the reference at
  the first step, gains, wheels, disturbance-torque tables) is prepared once per
  engine (:class:`FlightStatics`), not once per scenario;
* the closed loop writes the misaligned camera DCMs and the usable flags at
  the images straight into a buffer kept across scenarios
  (:func:`ideas_hpc.core.attitude.camera_batch.fly_cameras_into`) instead of
  three fresh ``N x n_img x 9`` arrays (attitude, misaligned, blinded); Nadir
  Pointing without disturbance torques (the main job) flies 64 spacecraft side by
  side, one loop over them per step in packed (SIMD) arithmetic
  (:func:`~ideas_hpc.core.attitude.camera_lanes.fly_cameras_lanes_into`);
* the orbits write only the positions at the images
  (:func:`ideas_hpc.core.dynamics.propagate_positions.propagate_positions_into`);
* only the unusable images are then blinded, in place, by the formula of
  :func:`ideas_hpc.flyby.usable.blind` on the same gathered rows.

Flights this does not cover (ideal attitude, body tracking, an encounter, an
absolute or acquisition start) return None: the caller flies the pipeline.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ideas_hpc.attitude.checks import init_array, steps
from ideas_hpc.attitude.gains import gains_from_config
from ideas_hpc.attitude.maneuvers import maneuver_args
from ideas_hpc.attitude.spacecraft import default_spacecraft, validate_spacecraft
from ideas_hpc.attitude.start import absolute_start, reference_state0
from ideas_hpc.attitude.torque_terms import pack_torques
from ideas_hpc.core.attitude.camera_batch import fly_cameras_into, spin_table
from ideas_hpc.core.attitude.camera_lanes import fly_cameras_lanes_into
from ideas_hpc.core.attitude.maneuvers import NP_MODE
from ideas_hpc.core.dynamics.propagate_positions import propagate_positions_into
from ideas_hpc.core.attitude.records import ControlGains, ImageViews, Initial, Wheels
from ideas_hpc.core.dynamics.frames import dcm_RT as _dcm_RT
from ideas_hpc.dynamics.force_model import pack_force_model
from ideas_hpc.dynamics.trajectory import MAX_STEPS, propagate_swarm, sample_times
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.camera import misalignment_dcms
from ideas_hpc.flyby.usable import blind_into


@dataclass
class FlightStatics:
    """Everything of the closed loop that no scenario draw changes (SI)."""

    code: int
    rings: np.ndarray          # (N, 3, 3) [R_i T]
    spin: float                # rad/s
    periods: np.ndarray        # (N,) s
    theta_max: float           # rad
    gains: ControlGains
    wheels: Wheels
    dt: float                  # s
    n_steps: int
    img_every: int
    torques: np.ndarray        # (N, n_steps + 1, 3) N m or (N, 0, 3)
    sigma_RN0: np.ndarray      # (N, 3) the reference at the first step
    omega_RN0_R: np.ndarray    # (N, 3) rad/s
    use: np.ndarray            # (3,) exposure s, smear limit rad, settle rad
    r_max_m: float
    cs_img: np.ndarray         # (n_img, 2) cos, sin(w_s t) at the images
    t_img: np.ndarray          # (n_img,) s, the orbit's samples at the images


def covers(setup, pert) -> bool:
    """Does the one-pass flight apply to ``setup`` flown with ``pert``?"""
    # a flight asked for on another device goes through simulate_attitude's kernel
    return (getattr(setup, "device", "cpu") == "cpu"
            and setup.attitude_mode == "simulated" and setup.encounter is None
            and not setup.maneuver.tracks_body and pert.ics_reference is not None
            and not pert.acquisition_s)


def flight_statics(setup, theta) -> FlightStatics:
    """The scenario-independent part of :func:`ideas_hpc.attitude.simulate_attitude`'s
    preparation for the flyby's camera (:func:`ideas_hpc.flyby.camera.camera_dcms`)."""
    th = np.ascontiguousarray(theta, dtype=np.float64).ravel()
    kw_mode = setup.maneuver.name
    man, p, tm = maneuver_args(kw_mode, th.size, None, setup.theta_max_rad, setup.p_min_s)
    sc = validate_spacecraft(setup.spacecraft or default_spacecraft())
    g = gains_from_config(man.gains if setup.gains is None else setup.gains)
    ws = float(setup.body.params.spin_rate)
    dt = float(setup.dt_s)
    n_steps = steps(setup.tf_s - setup.t0_s, dt, "t_f")
    img_every = steps(setup.image_dt_s, dt, "image_dt")
    k_p, k_i, eta, phi = g.arrays(dt)
    rings = np.ascontiguousarray(np.array([_dcm_RT(float(t), np.eye(3)) for t in th])
                                 .reshape(-1, 3, 3))
    s_r, w_r = reference_state0(man.code, rings, ws, p, tm, np.empty((th.size, 0, 9)))
    use = getattr(setup, "imaging", None)
    # no usable-image test: every image counts (no rate or angle exceeds inf)
    limits = (np.array([0.0, np.inf, np.inf]) if use is None else
              np.array([use.exposure_s, use.smear_pixels * use.ifov_rad, use.settle_rad]))
    cs = spin_table(ws, dt, int(n_steps), int(img_every))
    t_img = image_times(setup)
    return FlightStatics(
        code=int(man.code), rings=rings, spin=ws, periods=p, theta_max=tm,
        gains=ControlGains(k_p, k_i, eta, phi, float(g.int_limit)),
        wheels=Wheels(sc.inertia_rw, sc.J_s, float(sc.u_max_N_m), float(sc.h_max_N_m_s)),
        dt=dt, n_steps=int(n_steps), img_every=int(img_every),
        torques=pack_torques(tuple(setup.torques), th, n_steps, dt, ws),
        sigma_RN0=s_r, omega_RN0_R=w_r,
        use=limits,
        r_max_m=float(setup.body.shape.r_max), cs_img=cs, t_img=t_img)


def fly_views(setup, statics: FlightStatics, r0_T, v0_T, pert, buffers: dict):
    """``(r_img_T (N, n_img, 3) m, imaging camera DCMs (N, n_img, 3, 3))`` of the
    perturbed flight, equal to :func:`~ideas_hpc.flyby.flight.open_loop_views`'
    first two results. The DCMs live in ``buffers`` (reused by the next call)."""
    p = pert
    r0 = r0_T if p.position_error_T is None else r0_T + p.position_error_T
    v0 = v0_T if p.velocity_error_T is None else v0_T + p.velocity_error_T
    n = statics.rings.shape[0]
    r_img = _positions(setup, statics, r0, v0, p.params_override, buffers)
    mis = (np.empty((0, 3, 3)) if p.misalignment_prv is None
           else np.ascontiguousarray(misalignment_dcms(p.misalignment_prv)))
    s0, w0, W0 = p.ics_reference
    s0 = init_array(s0, "sigma0", n)
    w0 = init_array(w0, "omega0", n)
    W0 = init_array(W0, "wheel0", n)
    if not (s0.shape == w0.shape == W0.shape) or s0.shape[0] != 1:
        raise InputError("one sample of sigma0, omega0, wheel0 of the same shape",
                         field="ics_reference")
    s_abs, w_abs = absolute_start(statics.sigma_RN0, statics.omega_RN0_R, s0, w0)
    n_img = r_img.shape[1]
    shape = (n, n_img, 3, 3)
    if buffers.get("dcm") is None or buffers["dcm"].shape != shape:
        buffers["dcm"] = np.empty(shape)
        buffers["usable"] = np.empty((n, n_img), dtype=np.bool_)
    dcm, ok = buffers["dcm"], buffers["usable"]
    initial = Initial(np.ascontiguousarray(s_abs[0]), np.ascontiguousarray(w_abs[0]),
                      np.ascontiguousarray(W0[0]))
    views = ImageViews(statics.img_every, statics.cs_img, mis, statics.use, dcm, ok)
    if statics.code == NP_MODE and statics.torques.shape[1] == 0:
        fly_cameras_lanes_into(statics.rings, statics.spin, statics.gains, statics.wheels,
                               statics.dt, statics.n_steps, initial, views)
    else:
        fly_cameras_into(statics.code, statics.rings, statics.spin, statics.periods,
                         statics.theta_max, statics.gains, statics.wheels, statics.dt,
                         statics.n_steps, initial, statics.torques, views)
    blind_into(dcm, r_img, ok, statics.r_max_m)
    return r_img, dcm


def _positions(setup, statics, r0, v0, params_override, buffers):
    """Positions at the images (N, n_img, 3) m, into ``buffers["r"]``."""
    shape = (np.shape(r0)[0], statics.t_img.size, 3)
    if buffers.get("r") is None or buffers["r"].shape != shape:
        buffers["r"] = np.empty(shape)
    return positions_into(setup, statics.t_img, r0, v0, params_override, buffers["r"])


def image_times(setup) -> np.ndarray:
    """The orbit's samples at the images, s (``sample_times(...)[::image_every]``)."""
    t0, tf = float(setup.t0_s), float(setup.tf_s)
    return np.ascontiguousarray(sample_times(t0, tf, float(setup.dt_s))[::setup.image_every])


def positions_into(setup, t_img, r0, v0, params_override, out) -> np.ndarray:
    """``out`` (N, n_img, 3) m: the positions at the images ``t_img`` (:func:`image_times`),
    as ``propagate_swarm(...)[1][:, ::image_every]`` bit for bit; a failed integration
    flies ``propagate_swarm`` for its error."""
    r0 = np.ascontiguousarray(r0, dtype=np.float64)
    v0 = np.ascontiguousarray(v0, dtype=np.float64)
    fm = setup.force_model
    pk = pack_force_model(setup.body, fm, params_override)
    status = propagate_positions_into(r0, v0, float(setup.t0_s), float(setup.tf_s), fm.rtol,
                                      fm.atol, MAX_STEPS, t_img, out, *pk.args())
    if np.any(status != 0) or r0.shape != v0.shape or r0.ndim != 2 or r0.shape[1] != 3:
        propagate_swarm(setup.body, r0, v0, setup.t0_s, setup.tf_s, force_model=fm,
                        dt_sample=setup.dt_s, params_override=params_override, views=True)
        raise RuntimeError("propagation failed")    # propagate_swarm raised already
    return out
