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

The closed loop (``attitude.mode = "simulated"``) flies the same aim as its reference
(:func:`terminal_reference`): the believed track's body-tracking reference before the lock,
then, from the first attitude step at which the true range is within the detection range,
a slew of :data:`LOCK_SLEW_S` that moves the aim point from the predicted target onto the
true centre (the measured centroid) and turns in the centroid error, after which the
reference is the flown track's, turned by that error. The wheels follow it within their
torque and momentum limits; where the line of sight's own rate and acceleration near
closest approach exceed them (:func:`~ideas_hpc.flyby.pass_rates.follow_check`) the
error grows past the settle limit and those images are lost (blinded), as the design sees.
Ideal attitude locks at once (perfect tracking has no transient).
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.core.attitude.compose import compose_each
from ideas_hpc.core.attitude.mrp import dcm_from_mrp, mrp_from_dcm, mrp_from_prv
from ideas_hpc.flyby.encounter import track_omega_BN_B, track_reference


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


def aim_rates_B(setup, r_img_T, v_img_T, off_N, centroid_dcm=None) -> np.ndarray:
    """(N, n_img, 3) rad/s: the inertial rate, B components, of ideal body tracking with
    navigation errors (:func:`aim_positions_T`, :func:`with_centroid_errors`) at the images,
    from the flown positions ``r_img_T`` (m) and velocities relative to T ``v_img_T`` (m/s):
    before the lock the believed track's (``r - R3 o``, ``v - dv``: the aim point moves
    with the spacecraft's plan), after it the flown track's turned by the centroid error
    ``[B' B] = centroid_dcm`` (constant: ``omega' = [B' B] omega``). Ideal attitude locks
    at once, so the lock's step is an instant between images, not a rate."""
    r = np.asarray(r_img_T, dtype=np.float64)
    v = np.asarray(v_img_T, dtype=np.float64)
    dr, dv = offset_T(setup, off_N, setup.image_times)
    lock = locked(setup, r)
    w = track_omega_BN_B(setup, np.where(lock[..., None], r, r - dr),
                         np.where(lock[..., None], v, v - dv))
    if centroid_dcm is None or not lock.any():
        return w
    turned = np.einsum("nab,nkb->nka", np.asarray(centroid_dcm, dtype=np.float64), w)
    return np.ascontiguousarray(np.where(lock[..., None], turned, w))


def with_centroid_errors(setup, dcm_BT, r_img_T, centroid_dcm) -> np.ndarray:
    """``dcm_BT`` (N, n_img, 3, 3) turned by each member's centroid error ``centroid_dcm``
    (N, 3, 3) at the images where terminal tracking is locked."""
    lock = locked(setup, r_img_T)
    if centroid_dcm is None or not lock.any():
        return dcm_BT
    turned = compose_each(np.ascontiguousarray(centroid_dcm, dtype=np.float64),
                          np.ascontiguousarray(dcm_BT, dtype=np.float64))
    return np.where(lock[..., None, None], turned, dcm_BT)


#: Duration (s) of the closed loop's slew from the prediction onto the measured centroid at
#: the lock. A step of the reference by the ephemeris bias (degrees) would wind up the
#: controller's integral during the transient (K_I = 0.01 1/s^2 then holds an error of
#: ~0.1 deg for a minute, measured), which a flight's attitude system avoids by commanding
#: a slew; 5 s of ``(1 - cos)`` profile asks ``theta_b pi^2 / (2 t_s^2)``, 1.5e-3 rad/s^2
#: (0.7 % of the paper's wheels' torque) for a 0.9 deg bias.
LOCK_SLEW_S = 5.0


def lock_ramp(setup, lock: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(lam, lam', lam'')`` (N, T): the share of the way from the prediction to the
    centroid at the attitude steps, ``(1 - cos(pi tau / t_s)) / 2`` for ``tau`` from the
    first locked step (``lock`` (N, T) bool) to ``t_s = LOCK_SLEW_S``, 1 after, 0 before,
    and its first and second time derivatives (1/s, 1/s^2)."""
    dt = float(setup.dt_s)
    k0 = np.where(lock.any(axis=1), np.argmax(lock, axis=1), lock.shape[1])
    tau = (np.arange(lock.shape[1])[None, :] - k0[:, None]) * dt
    w = math.pi / LOCK_SLEW_S
    on = (tau >= 0.0) & (tau < LOCK_SLEW_S)
    lam = np.where(tau >= LOCK_SLEW_S, 1.0, np.where(on, 0.5 * (1.0 - np.cos(w * tau)), 0.0))
    return (lam, np.where(on, 0.5 * w * np.sin(w * tau), 0.0),
            np.where(on, 0.5 * w * w * np.cos(w * tau), 0.0))


def turned_reference(table: np.ndarray, prv: np.ndarray, ramp) -> np.ndarray:
    """A body-tracking reference table (N, T, 9) (``[sigma_RN, omega_RN_R, omegadot_RN_R]``)
    turned by the share ``lam`` of each member's centroid error ``prv`` (N, 3) rad (a
    rotation about a fixed axis: ``[R' R] = C(lam a)``, ``a = prv``), ``ramp = (lam, lam',
    lam'')`` (N, T) from :func:`lock_ramp`: ``[R' N] = C [R N]``,
    ``omega' = C omega + lam' a``, ``omegadot' = C omegadot + lam'' a + omega' x lam' a``
    (inertial derivative in R' components, S&J eq. 2.16 on ``omega_R'R = lam' a``)."""
    lam, lam1, lam2 = ramp
    out = np.array(table, dtype=np.float64, copy=True)
    a_all = np.asarray(prv, dtype=np.float64).reshape(-1, 3)
    for i, k in zip(*np.nonzero(lam > 0.0)):
        a = a_all[i]
        c = dcm_from_mrp(mrp_from_prv(np.ascontiguousarray(lam[i, k] * a)))
        rn = dcm_from_mrp(np.ascontiguousarray(table[i, k, 0:3]))
        out[i, k, 0:3] = mrp_from_dcm(np.ascontiguousarray(c @ rn))
        w = c @ table[i, k, 3:6] + lam1[i, k] * a
        out[i, k, 3:6] = w
        out[i, k, 6:9] = c @ table[i, k, 6:9] + lam2[i, k] * a + np.cross(w, lam1[i, k] * a)
    return out


def terminal_reference(setup, pos_T, vel_T, off_N, centroid_prv=None) -> np.ndarray:
    """The closed loop's body-tracking reference (N, T, 9) in N with navigation errors
    (module docstring): at the predicted target (the believed track,
    :func:`believed_track`) until terminal tracking locks (:func:`locked` at every attitude
    step of the flown ``pos_T``), then slewed over :data:`LOCK_SLEW_S` onto the measured
    centroid (the flown track ``pos_T``, ``vel_T``) turned by ``centroid_prv`` (N, 3) rad
    or None: the aim point moves from the prediction to the true centre,
    ``r - (1 - lam) R3 o`` with velocity ``v - (1 - lam) dv + lam' R3 o``, and the rates
    and accelerations are that moving aim's (:func:`lock_ramp`)."""
    lock = locked(setup, pos_T)
    if not lock.any():
        return track_reference(setup, *believed_track(setup, pos_T, vel_T, off_N))
    t = setup.t0_s + setup.dt_s * np.arange(np.shape(pos_T)[1])
    dr, dv = offset_T(setup, off_N, t)
    ramp = lock_ramp(setup, lock)
    lam, lam1 = ramp[0][..., None], ramp[1][..., None]
    table = track_reference(setup, np.ascontiguousarray(pos_T - (1.0 - lam) * dr),
                            np.ascontiguousarray(vel_T - (1.0 - lam) * dv + lam1 * dr))
    return table if centroid_prv is None else turned_reference(table, centroid_prv, ramp)
