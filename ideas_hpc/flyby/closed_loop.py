"""The one-pass closed-loop flights: the cameras at the images only (issue 31).

Two compiled variants of the closed loop that :mod:`ideas_hpc.flyby.views` picks
by their declared capabilities (:data:`ideas_hpc.flyby.views.CLOSED_LOOPS`) when
a flight wants only the positions and the imaging cameras at the images (the
scenario bank, the validation flights, the designers' candidates). They fly the
same bits as the batched loop of :func:`ideas_hpc.attitude.simulate_attitude` for
a start on the reference (``tests/test_scenario_flight.py``), at a fraction of
the cost:

* what does not depend on a scenario's draws (ring frames, the reference at the
  first step, gains, wheels, disturbance-torque tables, spin tables) is
  prepared once per world (:class:`FlightStatics`, kept by
  :func:`ideas_hpc.flyby.world.cached_static` under the world's
  :attr:`~ideas_hpc.flyby.world.World.attitude_key`);
* the closed loop writes the misaligned camera DCMs and the usable flags at
  the images straight into a buffer kept across flights
  (:func:`ideas_hpc.core.attitude.camera_batch.fly_cameras_into`, the scalar
  loop) instead of three fresh ``N x n_img x 9`` arrays; Nadir Pointing without
  disturbance torques flies 64 spacecraft side by side
  (:func:`~ideas_hpc.core.attitude.camera_lanes.fly_cameras_lanes_into`, the
  lanes);
* the orbits write only the positions at the images, and the velocities there
  that the smear test reads (:func:`positions_into`);
* only the unusable images are then blinded, in place
  (:func:`ideas_hpc.flyby.usable.blind_into`).
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
from ideas_hpc.core.attitude.records import ControlGains, ImageViews, Initial, Wheels
from ideas_hpc.core.dynamics.frames import dcm_RT as _dcm_RT
from ideas_hpc.core.dynamics.propagate_positions import propagate_positions_into
from ideas_hpc.dynamics.trajectory import MAX_STEPS, propagate_swarm, sample_times
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.camera import misalignment_dcms
from ideas_hpc.flyby.usable import blind_into, scene_radius_m


@dataclass
class FlightStatics:
    """Everything of the closed loop that no scenario draw but the world changes (SI)."""

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
    vertices_T: np.ndarray     # (V, 3) m: blinding inside the bounding sphere
    scene_radius_m: float      # the footprint centre's sphere (flyby.usable.scene_radius_m)
    cs_img: np.ndarray         # (n_img, 2) cos, sin(w_s t) at the images


def flight_statics(setup, theta, periods=None) -> FlightStatics:
    """The scenario-independent part of :func:`ideas_hpc.attitude.simulate_attitude`'s
    preparation for the flyby's camera, of ``setup`` in its world (the spin, the
    bounding radius) for spacecraft ``theta`` (rad) and sweep ``periods`` (s)."""
    th = np.ascontiguousarray(theta, dtype=np.float64).ravel()
    man, p, tm = maneuver_args(setup.maneuver.name, th.size, periods, setup.theta_max_rad,
                               setup.p_min_s)
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
    return FlightStatics(
        code=int(man.code), rings=rings, spin=ws, periods=p, theta_max=tm,
        gains=ControlGains(k_p, k_i, eta, phi, float(g.int_limit)),
        wheels=Wheels(sc.inertia_rw, sc.J_s, float(sc.u_max_N_m), float(sc.h_max_N_m_s)),
        dt=dt, n_steps=int(n_steps), img_every=int(img_every),
        torques=pack_torques(tuple(setup.torques), th, n_steps, dt, ws),
        sigma_RN0=s_r, omega_RN0_R=w_r, use=limits,
        r_max_m=float(setup.body.shape.r_max), vertices_T=setup.body.shape.vertices_T,
        scene_radius_m=scene_radius_m(setup.body.shape),
        cs_img=spin_table(ws, dt, int(n_steps), int(img_every)))


def fly_cameras(statics: FlightStatics, start_BR, misalignment_prv, at_images, buffers: dict,
                lanes: bool):
    """Imaging camera DCMs (N, n_img, 3, 3) of a closed loop started ``start_BR`` =
    ``(sigma_B/R, omega_B/R, wheels)`` (N, 3) about its reference: misaligned by
    ``misalignment_prv`` (N, 3) rad or None, unusable images blinded. ``at_images`` =
    ``(r_img, v_img)``: positions (m) and velocities relative to T (m/s), (N, n_img, 3),
    in T, at the images (``v_img`` None: no smear test). Lives in ``buffers["dcm"]``
    (reused by the next call); ``lanes``: the 64-lane loop."""
    r_img, v_img = at_images
    n = statics.rings.shape[0]
    mis = (np.empty((0, 3, 3)) if misalignment_prv is None
           else np.ascontiguousarray(misalignment_dcms(misalignment_prv)))
    s0, w0, W0 = start_BR
    s0 = init_array(s0, "sigma0", n)
    w0 = init_array(w0, "omega0", n)
    W0 = init_array(W0, "wheel0", n)
    if not (s0.shape == w0.shape == W0.shape) or s0.shape[0] != 1:
        raise InputError("one sample of sigma0, omega0, wheel0 of the same shape",
                         field="ics_reference")
    s_abs, w_abs = absolute_start(statics.sigma_RN0, statics.omega_RN0_R, s0, w0)
    shape = (n, r_img.shape[1], 3, 3)
    if buffers.get("dcm") is None or buffers["dcm"].shape != shape:
        buffers["dcm"] = np.empty(shape)
        buffers["usable"] = np.empty(shape[:2], dtype=np.bool_)
    dcm, ok = buffers["dcm"], buffers["usable"]
    initial = Initial(np.ascontiguousarray(s_abs[0]), np.ascontiguousarray(w_abs[0]),
                      np.ascontiguousarray(W0[0]))
    no_v = np.empty((0, 0, 3))
    views = ImageViews(statics.img_every, statics.cs_img, mis, statics.use,
                       np.ascontiguousarray(r_img) if v_img is not None else no_v,
                       np.ascontiguousarray(v_img) if v_img is not None else no_v,
                       statics.scene_radius_m, dcm, ok)
    if lanes:
        fly_cameras_lanes_into(statics.rings, statics.spin, statics.gains, statics.wheels,
                               statics.dt, statics.n_steps, initial, views)
    else:
        fly_cameras_into(statics.code, statics.rings, statics.spin, statics.periods,
                         statics.theta_max, statics.gains, statics.wheels, statics.dt,
                         statics.n_steps, initial, statics.torques, views)
    blind_into(dcm, r_img, ok, statics.r_max_m, statics.vertices_T)
    return dcm


def image_times(setup) -> np.ndarray:
    """The orbit's samples at the images, s (``sample_times(...)[::image_every]``)."""
    t0, tf = float(setup.t0_s), float(setup.tf_s)
    return np.ascontiguousarray(sample_times(t0, tf, float(setup.dt_s))[::setup.image_every])


def positions_into(setup, world, r0, v0, out, v_out=None) -> np.ndarray:
    """``out`` (N, n_img, 3) m: the positions at the images (:func:`image_times`) of
    start states ``r0``, ``v0`` (N, 3) flown through ``world``, as
    ``propagate_swarm(...)[1][:, ::image_every]`` bit for bit, and the velocities
    relative to T (m/s) into ``v_out`` when given (``[2][:, ::image_every]``, the same
    bits); a failed integration flies ``propagate_swarm`` for its error."""
    r0 = np.ascontiguousarray(r0, dtype=np.float64)
    v0 = np.ascontiguousarray(v0, dtype=np.float64)
    fm = world.force_model
    pk = world.forces
    status = propagate_positions_into(r0, v0, float(setup.t0_s), float(setup.tf_s), fm.rtol,
                                      fm.atol, MAX_STEPS, image_times(setup), out,
                                      np.empty((0, 0, 3)) if v_out is None else v_out,
                                      *pk.args())
    if np.any(status != 0) or r0.shape != v0.shape or r0.ndim != 2 or r0.shape[1] != 3:
        propagate_swarm(world.body, r0, v0, setup.t0_s, setup.tf_s, force_model=fm,
                        dt_sample=setup.dt_s, packed=pk, views=True)
        raise RuntimeError("propagation failed")    # propagate_swarm raised already
    return out
