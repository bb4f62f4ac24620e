"""The one flight of a swarm through a world: positions and cameras at the images (issue 40).

Every flight goes through :func:`flight_views`: the flyby pipeline
(:func:`~ideas_hpc.flyby.flight.fly`, :func:`~ideas_hpc.flyby.flight.fly_open_loop`,
:func:`~ideas_hpc.flyby.flight.open_loop_views`), the Monte Carlo kind, the
scenario bank and its validation flights
(:class:`~ideas_hpc.montecarlo.scenario_rows.RowEngine`) and the designers'
candidates. It takes a :class:`~ideas_hpc.flyby.world.World` (the scenario's
target, Sun, encounter and force model) and the swarm's own draws (a
:class:`~ideas_hpc.flyby.flight.Perturbation`), and

1. flies the orbits through the world: the whole trajectory when it is wanted
   back or the camera follows it (body tracking), else only the positions at the
   images, and the velocities there when the closed loop's smear test reads them
   (:func:`ideas_hpc.flyby.closed_loop.positions_into`, the same bits); on an
   encounter, from a start moved by the scenario's navigation draws (``target_offset_N``,
   ``member_offset_N``; :mod:`ideas_hpc.flyby.nav_flight`), body tracking then aiming at
   the predicted target (and, with terminal tracking, at the measured centroid, in the
   ideal cameras and the closed loop's reference alike);
2. points the cameras: perfect tracking of the maneuver's reference (its
   cameras kept per world, :func:`~ideas_hpc.flyby.world.cached_static`), or the
   closed loop, flown by the first compiled variant of :data:`CLOSED_LOOPS`
   whose declared capabilities cover the flight (device, maneuver, geometry,
   start, torques, time series). Every variant flies the same bits
   (``tests/test_scenario_flight.py``, ``tests/test_bank_cuda.py`` for the
   device), so the choice decides speed only;
3. applies the camera misalignments and blinds the unusable images
   (:func:`ideas_hpc.flyby.camera.imaging_dcms`; the smear rate of the batched
   loop, :func:`ideas_hpc.flyby.camera.smear_rates_of`, is kept on its
   ``AttitudeResult`` as ``image_smear_rate``). Perfect tracking (``attitude.mode =
   "ideal"``) faces the same smear test at its reference's analytic rate where the
   geometry tests its images (an encounter,
   :func:`ideas_hpc.flyby.camera.ideal_usable`); on the paper's geometry it counts every
   image, as the paper's ideal mode did (:mod:`ideas_hpc.flyby.usable`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ideas_hpc.attitude import initial_conditions
from ideas_hpc.attitude.modes import undrawn_start
from ideas_hpc.core.attitude.maneuvers import FOV_MODE, NP_MODE
from ideas_hpc.dynamics.trajectory import propagate_swarm
from ideas_hpc.flyby import closed_loop as _loop
from ideas_hpc.flyby.camera import (camera_at_images, camera_dcms, ideal_omega_BN_B_at,
                                    ideal_usable, imaging_dcms, misaligned, misalignment_dcms,
                                    smear_rates_of)
from ideas_hpc.flyby.encounter import track_dcms
from ideas_hpc.flyby.nav_flight import (aim_positions_T, member_offsets, start_errors_T,
                                        terminal_reference, with_centroid_errors)
from ideas_hpc.flyby.usable import blind
from ideas_hpc.flyby.world import World, array_key, cached_static


@dataclass(frozen=True)
class FlightPlan:
    """What a flight returns and how it runs.

    ``series``: the attitude time series and the whole trajectory come back (the
    pipeline's outputs); False: only the positions and the imaging cameras at the
    images (the bank, the candidates), which the one-pass variants fly.
    ``buffers``: arrays reused across flights (``series`` False; one dict per thread).
    ``trajectory``: ``(position_T, velocity_T)`` (N, T, 3) already flown (a targeted
    flight), flown again by nobody.
    """

    series: bool = True
    buffers: dict | None = None
    trajectory: tuple | None = None


@dataclass
class Views:
    """A flight at its images (SI, frame T): ``r_img_T`` (N, n_img, 3); ``dcm_BT`` the
    cameras as flown (misaligned; None from a one-pass variant); ``imaging_BT`` what the
    coverage sees (unusable images blinded); ``attitude`` the closed loop's
    ``AttitudeResult`` (series only); ``position_T``, ``velocity_T`` (N, T, 3) the
    trajectory (series or body tracking, else None)."""

    r_img_T: np.ndarray
    dcm_BT: np.ndarray | None
    imaging_BT: np.ndarray
    attitude: object | None = None
    position_T: np.ndarray | None = None
    velocity_T: np.ndarray | None = None


@dataclass(frozen=True)
class Start:
    """Where a closed loop starts: ``state`` ``(sigma, omega, wheels)`` (N, 3), absolute
    or, with ``relative``, errors about the reference flown; ``acquisition_s`` flown from
    an absolute state before the window."""

    state: tuple
    relative: bool
    acquisition_s: float = 0.0


@dataclass(frozen=True)
class ClosedLoop:
    """One compiled variant of the closed loop, with what it can fly.

    ``fly(setup, world, key, theta, periods, start, misalignment_prv, at_images, trajectory,
    buffers) -> (dcm as flown or None, imaging dcm, AttitudeResult or None)``, with
    ``at_images = (r_img, v_img)`` the positions and velocities (N, n_img, 3) at the
    images (``v_img`` None when no smear test reads it).
    ``devices``: where it runs; ``series``: it returns the attitude time series;
    ``codes``: the maneuver codes it flies (None: every one, body tracking from its
    table included); ``any_geometry``: False for ring frames that turn with the body
    only (the paper's geometry); ``absolute``: it starts from an absolute state and
    flies an acquisition (else only relative to the reference); ``torques``: it flies
    disturbance-torque tables.
    """

    name: str
    fly: Callable
    devices: tuple = ("cpu",)
    series: bool = False
    codes: tuple | None = None
    any_geometry: bool = False
    absolute: bool = False
    torques: bool = False

    def covers(self, setup, start: Start, series: bool) -> bool:
        """Whether it can fly ``setup`` from ``start`` (``series``: the series wanted)."""
        return (setup.device in self.devices and (self.series or not series)
                and (self.codes is None or (setup.maneuver.code in self.codes
                                            and not setup.maneuver.tracks_body))
                and (self.any_geometry or setup.geometry.rings_turn_with_body)
                and (self.absolute or (start.relative and not start.acquisition_s))
                and (self.torques or not setup.torques))


def _statics(setup, world, key, theta, periods):
    return cached_static(("closed-loop", key, world.attitude_key, array_key(theta, periods)),
                         lambda: _loop.flight_statics(setup, theta, periods))


def _one_pass(lanes: bool):
    def fly(setup, world, key, theta, periods, start, mis, at_images, trajectory, buffers):
        statics = _statics(setup, world, key, theta, periods)
        dcm = _loop.fly_cameras(statics, start.state, mis, at_images,
                                {} if buffers is None else buffers, lanes)
        return None, dcm, None
    return fly


def _batch(setup, world, key, theta, periods, start, mis, at_images, trajectory, buffers):
    # the batched loop of simulate_attitude on the setup's device, time series and all
    r_img, v_img = at_images
    mis_CB = None if mis is None else misalignment_dcms(mis)
    dcm, att = camera_at_images(setup, theta, periods, start.state, mis_CB, r_img,
                                trajectory, start="reference" if start.relative else "absolute",
                                acquisition_s=start.acquisition_s)
    if v_img is not None:
        att.image_smear_rate = smear_rates_of(setup, att, mis_CB, dcm, r_img, v_img)[None]
    return dcm, imaging_dcms(setup, dcm, att, r_img), att


#: The closed loop's compiled variants, most specialised first; a flight takes the first
#: that covers it (:meth:`ClosedLoop.covers`). ``batch`` covers every flight.
CLOSED_LOOPS: list[ClosedLoop] = [
    ClosedLoop("lanes", _one_pass(True), codes=(NP_MODE,)),
    ClosedLoop("scalar", _one_pass(False), codes=(NP_MODE, FOV_MODE), torques=True),
    ClosedLoop("batch", _batch, devices=("cpu", "cuda"), series=True, any_geometry=True,
               absolute=True, torques=True),
]


def closed_loop_for(setup, start: Start, series: bool) -> ClosedLoop:
    """The variant of :data:`CLOSED_LOOPS` that flies ``setup`` from ``start``."""
    for v in CLOSED_LOOPS:
        if v.covers(setup, start, series):
            return v
    raise ValueError(f"no closed-loop variant flies maneuver {setup.maneuver.name!r} on "
                     f"{setup.device!r}")


def flight_start(setup, pert, n: int) -> Start:
    """The closed loop's start of a flight with the draws ``pert``: relative to the
    reference (``ics_reference``), absolute (``ics``, with its acquisition), or, with
    neither, the setup's own undrawn start (sample 0, :func:`undrawn_start`)."""
    if pert.ics_reference is not None:
        return Start(tuple(pert.ics_reference), True)
    if pert.ics is not None:
        return Start(tuple(pert.ics), False, float(pert.acquisition_s))
    state, word = undrawn_start(setup.attitude_start, n,
                                lambda: initial_conditions(setup.seed, 0, n))
    return Start(state, word == "reference")


def flight_views(setup, theta, periods, r0_T, v0_T, pert, *, world: World | None = None,
                 plan: FlightPlan = FlightPlan()) -> Views:
    """Fly spacecraft ``theta`` (rad; sweep ``periods`` s) from ``r0_T``, ``v0_T`` (N, 3)
    plus ``pert``'s state errors (or along ``plan.trajectory``) through ``world``
    (default: ``setup``'s with ``pert.params_override``), with ``pert``'s attitude start
    and misalignment (module docstring). Failures (``pert.active``) are not applied."""
    th = np.ascontiguousarray(theta, dtype=np.float64).ravel()
    if world is None:
        world = setup.world.perturbed(pert.params_override)
    flown = world.flown(setup)
    closed = flown.attitude.closed_loop
    tracks = flown.maneuver.tracks_body
    # the velocities at the images: only the smear test reads them (the closed loop's, and
    # perfect tracking's where the geometry tests its images)
    smear = getattr(flown, "imaging", None) is not None and (
        closed or flown.geometry.ideal_images_tested)
    pos = vel = v_img = None
    nav = member_offsets(pert, th.size) if flown.encounter is not None else None
    if plan.trajectory is not None:
        pos, vel = plan.trajectory
        r_img = np.ascontiguousarray(pos[:, ::setup.image_every])
    else:
        r0 = r0_T if pert.position_error_T is None else r0_T + pert.position_error_T
        v0 = v0_T if pert.velocity_error_T is None else v0_T + pert.velocity_error_T
        if nav is not None:     # the navigation draws move the start (nav_flight)
            dr, dv = start_errors_T(flown, nav)
            r0, v0 = r0 + dr, v0 + dv
        if plan.series or tracks:
            _, pos, vel = propagate_swarm(world.body, r0, v0, setup.t0_s, setup.tf_s,
                                          force_model=world.force_model, dt_sample=setup.dt_s,
                                          packed=world.forces, views=True)
            r_img = np.ascontiguousarray(pos[:, ::setup.image_every])
        else:
            r_img, v_img = _positions(flown, world, r0, v0, plan.buffers, smear)
    if smear and v_img is None:
        v_img = np.ascontiguousarray(vel[:, ::setup.image_every])
    mis = pert.misalignment_prv
    if not closed:
        ideal = _ideal(setup, world, flown, th, periods, r_img, (nav, pert.centroid_prv))
        mis_CB = None if mis is None else misalignment_dcms(mis)
        if mis is not None:
            dcm = misaligned(ideal, mis_CB)
        else:       # the pipeline's caller owns its arrays; the bank only reads them
            dcm = ideal.copy() if plan.series else ideal
        if not smear:
            return Views(r_img, dcm, dcm, None, pos, vel)
        omega = _ideal_rates(setup, world, flown, th, periods, r_img, v_img,
                             (nav, pert.centroid_prv))
        ok = ideal_usable(flown, omega, mis_CB, dcm, r_img, v_img)
        return Views(r_img, dcm, blind(dcm, r_img, ok, flown.body.shape.r_max,
                                              flown.body.shape.vertices_T), None, pos, vel)
    start = flight_start(flown, pert, th.size)
    loop = closed_loop_for(flown, start, plan.series)
    if loop.series and not plan.series:     # the time series is not kept: one sample a run
        flown = flown.with_(decimate=max(1, int(round((flown.tf_s - flown.t0_s) / flown.dt_s))))
    track = None if pos is None else (pos, vel)
    if track is not None and tracks and nav is not None:
        # the reference table: at the predicted target, then at the measured centroid
        track = terminal_reference(flown, pos, vel, nav, pert.centroid_prv)
    dcm, imaging, att = loop.fly(flown, world, setup.flight_key, th, periods, start, mis,
                                 (r_img, v_img), track, plan.buffers)
    return Views(r_img, dcm, imaging, att, pos, vel)


def _positions(flown, world, r0, v0, buffers, velocities: bool):
    """``(r, v)``: positions (N, n_img, 3) m at the images, into ``buffers["r"]`` when
    given, and with ``velocities`` the velocities relative to T (m/s) into
    ``buffers["v"]`` (else None)."""
    shape = (np.shape(r0)[0], _loop.image_times(flown).size, 3)
    names = ("r", "v") if velocities else ("r",)
    if buffers is None:
        outs = [np.empty(shape) for _ in names]
    else:
        for name in names:
            if buffers.get(name) is None or buffers[name].shape != shape:
                buffers[name] = np.empty(shape)
        outs = [buffers[name] for name in names]
    v_out = outs[1] if velocities else None
    return _loop.positions_into(flown, world, r0, v0, outs[0], v_out), v_out


def _ideal(setup, world, flown, th, periods, r_img, navigation=(None, None)):
    """Perfect tracking's cameras: along the flown positions (body tracking; with
    ``navigation = (offsets (N, 3) m in N, centroid errors (N, 3) rad)`` at the predicted
    target, then the measured centroid, :mod:`~ideas_hpc.flyby.nav_flight`), else the
    maneuver's reference, which no draw but the world changes (kept per world)."""
    if flown.maneuver.tracks_body:
        off, centroid = navigation
        if off is None:
            return track_dcms(flown, r_img)[0]
        dcm = track_dcms(flown, aim_positions_T(flown, r_img, off))[0]
        return with_centroid_errors(flown, dcm, r_img, None if centroid is None
                                    else misalignment_dcms(centroid))
    return cached_static(("ideal", setup.flight_key, world.attitude_key, array_key(th, periods)),
                         lambda: camera_dcms(flown, th, periods)[0])


def _ideal_rates(setup, world, flown, th, periods, r_img, v_img, navigation):
    """Perfect tracking's camera rates at the images (:func:`~ideas_hpc.flyby.camera.
    ideal_omega_BN_B_at`): body tracking's along the flight, else the maneuver's reference
    rate, which no draw but the world changes (kept per world, as its cameras)."""
    if flown.maneuver.tracks_body:
        return ideal_omega_BN_B_at(flown, th, periods, r_img, v_img, navigation)
    return cached_static(("ideal-rate", setup.flight_key, world.attitude_key,
                          array_key(th, periods)),
                         lambda: ideal_omega_BN_B_at(flown, th, periods, r_img, v_img))
