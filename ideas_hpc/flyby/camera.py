"""Camera pointing of a flyby: the camera DCMs at the image times (SPEC section 5).

Ideal tracking of the maneuver's reference, the closed-loop reaction-wheel
attitude (:func:`ideas_hpc.attitude.simulate_attitude`), body tracking on
encounters, and the fixed camera misalignment ``[C B]`` of a Monte Carlo
sample; the usable-image test of both (the closed loop's rates, perfect tracking's
reference rate, :func:`ideal_usable`). ``setup`` is a
:class:`ideas_hpc.flyby.flight.FlybySetup`.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.attitude import (ideal_dcm_BT, ideal_omega_BN_B, initial_conditions,
                                simulate_attitude)
from ideas_hpc.attitude.modes import undrawn_start
from ideas_hpc.attitude.run_settings import InitialState, from_keywords
from ideas_hpc.core.attitude.compose import compose_each
from ideas_hpc.core.attitude.mrp import dcm_from_mrp, mrp_from_prv
from ideas_hpc.core.attitude.smear import smear_rates
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.encounter import track_dcms, track_omega_BN_B, track_reference
from ideas_hpc.flyby.nav_flight import aim_rates_B
from ideas_hpc.flyby.usable import blind, scene_radius_m, usable_images


def misalignment_dcms(prv) -> np.ndarray:
    """Fixed camera misalignments ``[C B]`` (N, 3, 3) from principal rotation vectors (N, 3), rad."""
    prv = np.asarray(prv, dtype=np.float64).reshape(-1, 3)
    return np.stack([dcm_from_mrp(mrp_from_prv(np.ascontiguousarray(v))) for v in prv])


def camera_dcms(setup, theta, periods=None, *, state0: InitialState | None = None,
                spin_rate=None, r_img_T=None, track_T=None, start="absolute",
                acquisition_s=0.0, **initial):
    """Camera DCMs at the image times, and the attitude result when simulated.

    ``state0``: the initial attitude state
    (:class:`~ideas_hpc.attitude.run_settings.InitialState`); the older keywords
    ``sigma0``, ``omega0``, ``wheel0`` fill it.
    ``start = "reference"``: ``sigma0``, ``omega0`` are errors about the reference
    of the geometry flown (encounter swarm frame, body tracking included);
    ``acquisition_s``: fly the loop that long before the window
    (:func:`ideas_hpc.attitude.simulate_attitude`).
    ``r_img_T`` (N, n_img, 3): the flown positions, for body tracking;
    ``track_T``: ``(position_T, velocity_T)`` (N, T, 3) at every attitude step,
    for body tracking with simulated attitude, or its reference table (N, T, 9) already
    built (:func:`ideas_hpc.flyby.nav_flight.terminal_reference`: navigation errors and
    terminal tracking).
    Returns ``(dcm_BT (N, n_img, 3, 3), AttitudeResult or None)``.
    """
    sigma0, omega0, wheel0 = from_keywords(None, None, None, None, state0, initial)[3].arrays()
    th = np.asarray(theta, dtype=np.float64)
    closed = setup.attitude.closed_loop
    if setup.maneuver.tracks_body and not closed:
        return track_dcms(setup, r_img_T)[0], None
    ws = setup.body.params.spin_rate if spin_rate is None else spin_rate
    duration = setup.tf_s - setup.t0_s
    img_t = setup.image_times - setup.t0_s
    kw = dict(mode=setup.maneuver.name, periods=periods, theta_max=setup.theta_max_rad, p_min=setup.p_min_s)
    sim_kw = dict(kw, start=start, acquisition_s=acquisition_s)
    if setup.maneuver.tracks_body:
        if track_T is None:
            raise InputError("body tracking with simulated attitude needs the flown positions "
                             "and velocities at every step", field="track_T")
        table = (track_T if isinstance(track_T, np.ndarray)
                 else track_reference(setup, *track_T))
        sim_kw = dict(sim_kw, ref_table=table)
    if sigma0 is None and closed:
        # no initial state given: the setup's own start (SPEC 7d), sample 0
        (sigma0, omega0, wheel0), word = undrawn_start(
            setup.attitude_start, th.size, lambda: initial_conditions(setup.seed, 0, th.size))
        if word == "reference":
            sim_kw = dict(sim_kw, start="reference")
    # the geometry's ring frames (with the body, or fixed in N) and its turn into T
    return setup.geometry.camera(
        setup, ws, lambda w, ts: ideal_dcm_BT(th, w, img_t, dcm_TS=ts, **kw),
        lambda w, ts: _simulate(setup, th, w, duration, sigma0, omega0, wheel0, ts, sim_kw))


def _simulate(setup, th, ws, duration, sigma0, omega0, wheel0, dcm_TS, kw):
    res = simulate_attitude(th, ws, duration, gains=setup.gains, spacecraft=setup.spacecraft,
                            dt=setup.dt_s, image_dt=setup.image_dt_s, sigma0=sigma0, omega0=omega0,
                            wheel0=wheel0, decimate=setup.decimate, dcm_TS=dcm_TS,
                            torques=setup.torques, device=getattr(setup, "device", "cpu"),
                            **kw)
    return np.ascontiguousarray(res.dcm_BT[0]), res


def camera_at_images(setup, th, periods, ics, misalignment, r_img, track_T=None, *,
                     start="absolute", acquisition_s=0.0):
    """Camera DCMs at the images (attitude, then the camera misalignment).
    ``start``, ``acquisition_s``: see :func:`camera_dcms`."""
    s0, w0, W0 = ics if ics is not None else (None, None, None)
    dcm, att = camera_dcms(setup, th, periods, state0=InitialState(s0, w0, W0), r_img_T=r_img,
                           track_T=track_T, start=start, acquisition_s=acquisition_s)
    return misaligned(dcm, misalignment), att


def smear_rates_of(setup, att, dcm_CB, dcm_CT, r_img, v_img) -> np.ndarray:
    """(N, n_img) rad/s: the footprint centre's image rate across the line of sight
    (:func:`image_smear_rates`) of the closed loop ``att`` (sample 0, its rates at the
    images ``image_omega``)."""
    return image_smear_rates(setup, att.image_omega[0], dcm_CB, dcm_CT, r_img, v_img)


def image_smear_rates(setup, omega_BN_B, dcm_CB, dcm_CT, r_img, v_img) -> np.ndarray:
    """(N, n_img) rad/s: the footprint centre's image rate across the line of sight
    (:func:`ideas_hpc.core.attitude.smear.smear_rates`, the one-pass loops' operands) of
    cameras ``dcm_CT`` (N, n_img, 3, 3) turning at ``omega_BN_B`` (N, n_img, 3; rad/s, B
    components), misaligned by ``dcm_CB`` (N, 3, 3) or None, along positions ``r_img``
    (m) and velocities relative to T ``v_img`` (m/s), (N, n_img, 3), in ``setup``'s world
    (its body's spin and :func:`~ideas_hpc.flyby.usable.scene_radius_m`): the closed
    loop's rates (:func:`smear_rates_of`) and perfect tracking's
    (:func:`ideal_omega_BN_B_at`) alike."""
    f8 = np.float64
    return smear_rates(np.ascontiguousarray(omega_BN_B, dtype=f8),
                       np.empty((0, 3, 3)) if dcm_CB is None
                       else np.ascontiguousarray(dcm_CB, dtype=f8),
                       np.ascontiguousarray(dcm_CT, dtype=f8),
                       np.ascontiguousarray(r_img, dtype=f8),
                       np.ascontiguousarray(v_img, dtype=f8),
                       float(setup.body.params.spin_rate), scene_radius_m(setup.body.shape))


def ideal_omega_BN_B_at(setup, theta, periods, r_img, v_img, navigation=(None, None)):
    """(N, n_img, 3) rad/s, B components: the inertial rate of perfect tracking's camera at
    the images, the reference's own analytic rate ``omega_RN`` (B = R): body tracking's
    along the flown positions ``r_img`` (m) and velocities relative to T ``v_img`` (m/s)
    (:func:`~ideas_hpc.flyby.encounter.track_omega_BN_B`; with ``navigation = (offsets
    (N, 3) m in N, centroid errors (N, 3) rad or None)`` the aim of
    :func:`~ideas_hpc.flyby.nav_flight.aim_rates_B`), else the maneuver's reference in the
    geometry's ring frames (:func:`ideas_hpc.attitude.ideal_omega_BN_B`: ``[R T] w_s z_T``
    for the paper's rings, which turn with the body; 0 for an encounter's Nadir Pointing,
    fixed in N; plus ``theta_ref' x_R`` for a sweep)."""
    if setup.maneuver.tracks_body:
        off, centroid = navigation
        if off is None:
            return track_omega_BN_B(setup, r_img, v_img)
        return aim_rates_B(setup, r_img, v_img, off,
                           None if centroid is None else misalignment_dcms(centroid))
    w, ts = setup.geometry.maneuver_frame(setup, setup.body.params.spin_rate)
    return ideal_omega_BN_B(theta, w, setup.image_times - setup.t0_s, mode=setup.maneuver.name,
                            periods=periods, theta_max=setup.theta_max_rad, dcm_TS=ts,
                            p_min=setup.p_min_s)


def ideal_usable(setup, omega_BN_B, dcm_CB, dcm_CT, r_img, v_img) -> np.ndarray:
    """(N, n_img) bool: perfect tracking's images that pass the usable-image test of
    ``setup.imaging``: the smear test of the closed loop, the same expression
    (:func:`image_smear_rates`, :func:`~ideas_hpc.flyby.usable.usable_images`), at the
    rates ``omega_BN_B`` of :func:`ideal_omega_BN_B_at`; the attitude error is zero, so
    no image is unsettled."""
    rate = image_smear_rates(setup, omega_BN_B, dcm_CB, dcm_CT, r_img, v_img)
    return usable_images(setup.imaging, rate, np.zeros(rate.shape))[0]


def _tested(setup, att):
    """``(use, smear rate (N, n_img))`` of a closed-loop flight the usable-image test
    applies to, else None (ideal attitude, tested in the flight itself by
    :func:`ideal_usable`, or no ``setup.imaging``)."""
    use = getattr(setup, "imaging", None)
    if use is None or att is None or att.image_error is None:
        return None
    if att.image_smear_rate is None:
        raise ValueError("the usable-image test needs the smear rate at the images: fly the "
                         "closed loop through ideas_hpc.flyby.views.flight_views")
    return use, att.image_smear_rate[0]


def usable_mask(setup, att) -> np.ndarray | None:
    """(N, n_img) bool: the images that pass the usable-image test (smear and settle,
    :mod:`ideas_hpc.flyby.usable`) of a closed loop ``att``, or None (ideal attitude, whose
    flight blinds its own unusable images, :func:`ideal_usable`, or no
    ``setup.imaging``)."""
    got = _tested(setup, att)
    if got is None:
        return None
    return usable_images(got[0], got[1], att.image_error[0])[0]


def imaging_dcms(setup, dcm, att, r_img):
    """The cameras the coverage sees: ``dcm`` with the unusable images blinded when
    ``setup.imaging`` is set and the attitude is simulated (:func:`usable_mask`); perfect
    tracking's are blinded by :func:`ideas_hpc.flyby.views.flight_views`
    (:func:`ideal_usable`)."""
    ok = usable_mask(setup, att)
    return dcm if ok is None else blind(dcm, r_img, ok, setup.body.shape.r_max,
                                         setup.body.shape.vertices_T)


def discarded_images(setup, att) -> tuple[np.ndarray, np.ndarray] | None:
    """``(smeared (N,), unsettled (N,))`` image counts of a simulated flight, or None when
    every image counts (ideal attitude or no ``setup.imaging``)."""
    got = _tested(setup, att)
    if got is None:
        return None
    _, smear, settle = usable_images(got[0], got[1], att.image_error[0])
    return smear, settle


def misaligned(dcm, misalignment):
    """Camera DCMs ``[C T] = [C B][B T]`` (N, n_img, 3, 3); ``misalignment`` ``[C B]`` (N, 3, 3) or None."""
    if misalignment is None:
        return dcm
    return compose_each(np.ascontiguousarray(misalignment, dtype=np.float64),
                        np.ascontiguousarray(dcm, dtype=np.float64))
