"""Attitude maneuvers: reference generators for Nadir Pointing and FoV Sweeping (SPEC section 5).

Frames (SPEC section 3):

* ``N`` inertial; ``T`` body-fixed frame of the target, spinning about
  ``z_N = z_T`` at the spin rate ``w_s`` (rad/s)::

      [TN](t) = R3(w_s t)       (rotation about z by w_s t; N = T at t = 0)

  The sky direction of the pole does not matter here: the spacecraft attitude
  is torque-free apart from its own wheels, so the whole problem may be solved
  in an inertial frame whose z axis is the pole.
* ``R_i``: ring frame, fixed in T (``[R_i T]`` from ``core.frames.dcm_RT``),
  so it co-rotates with the body: ``omega_RN = w_s z_T``, constant in N.
  SPEC section 5 asks to keep this rate (the paper drops it).
* ``F_i``: the FoV-sweep reference, a rotation about the ring x axis by
  ``theta_ref(t) = theta_max sin(2 pi t / P_i)`` on top of ``R_i``
  (paper eqs. 20-24).

Each generator writes ``ref`` (9,): ``[sigma_RN, omega_RN_R, omegadot_RN_R]``,
i.e. the reference MRP relative to N, its angular velocity relative to N in
reference-frame components (rad/s), and the *inertial* time derivative of that
angular velocity in reference-frame components (rad/s^2), the form the
tracking law of S&J section 8.3 needs.

FoV acceleration: ``omega_FN = theta' x_R + omega_RN``; since ``omega_RN`` is
constant in N and ``x_R`` turns with R,
``N d/dt omega_FN = theta'' x + omega_RN x (theta' x)``. The second term is the
transport term the paper's eq. 23 omits (it is ``w_s theta'`` ~ 1e-5 rad/s^2
for Eros, kept because it is right).

The MRP arithmetic uses the allocation-free scalar forms of
:mod:`ideas_hpc.core.attitude.mrp` (``mrp_add_s``): the hot loop calls them millions of
times.

Adding a maneuver: write its ``*_reference_into`` and ``*_camera_dcm_into``
kernels here, give it the next mode code and a branch in
:func:`reference_into` and :func:`camera_dcm_into`, and register it in
:mod:`ideas_hpc.attitude.maneuvers` (CONTRIBUTING.md, "A new attitude maneuver").
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.attitude.mrp import mrp_add_s, mrp_from_dcm

#: Mode codes of the maneuvers (the dispatch value of :func:`reference_into`).
NP_MODE = 0
FOV_MODE = 1
#: Body tracking: the reference is precomputed per step from the flown track
#: (:func:`track_reference_table`), read by ``core.attitude.batch.simulate_batch``.
TRACK_MODE = 2


@njit(cache=True, error_model="numpy")
def nadir_reference_into(t, spin_rate, sigma_RT, dcm_RT, ref):
    """Nadir Pointing reference: the ring frame ``R_i`` (SPEC section 5).

    Parameters
    ----------
    t : float
        Time since t0, s.
    spin_rate : float
        Target spin rate ``w_s`` about ``z_T = z_N``, rad/s.
    sigma_RT : (3,) float64
        MRP of ``[R_i T]`` (constant).
    dcm_RT : (3, 3) float64
        ``[R_i T]``.
    ref : (9,) float64
        Output ``[sigma_RN, omega_RN_R (rad/s), omegadot_RN_R (rad/s^2)]``;
        ``sigma_RN`` composes ``[R T][T N](t)``, ``omega_RN_R = [R T](0, 0, w_s)``
        and the inertial acceleration is zero.
    """
    # sigma_TN = tan(w_s t / 4) z   (S&J 3.139 for a rotation about z)
    tz = np.tan(0.25 * spin_rate * t)
    r1, r2, r3 = mrp_add_s(0.0, 0.0, tz, sigma_RT[0], sigma_RT[1], sigma_RT[2])
    ref[0] = r1
    ref[1] = r2
    ref[2] = r3
    ref[3] = dcm_RT[0, 2] * spin_rate
    ref[4] = dcm_RT[1, 2] * spin_rate
    ref[5] = dcm_RT[2, 2] * spin_rate
    ref[6] = 0.0
    ref[7] = 0.0
    ref[8] = 0.0


@njit(cache=True, error_model="numpy")
def fov_reference_into(t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref):
    """FoV Sweeping reference ``F_i`` (paper eqs. 20-24, SPEC section 5).

    ``theta_ref = theta_max sin(2 pi t / P)`` about the ring x axis on top of
    ``R_i``: ``sigma_FR = tan(theta_ref / 4) x`` (eq. 24),
    ``omega_FR = theta_ref' x`` (eq. 22), ``omega_FR' = theta_ref'' x`` (eq. 23),
    plus the ring-frame rate and the transport term (module docstring).

    Parameters
    ----------
    t, spin_rate, sigma_RT, dcm_RT
        As in :func:`nadir_reference_into`.
    theta_max : float
        Sweep amplitude, rad.
    period : float
        Sweep period ``P_i``, s (> 0).
    ref : (9,) float64
        Output ``[sigma_FN, omega_FN_F (rad/s), omegadot_FN_F (rad/s^2)]``.
    """
    wp = 2.0 * np.pi / period
    sn = np.sin(wp * t)
    cs = np.cos(wp * t)
    th = theta_max * sn
    thd = theta_max * wp * cs
    thdd = -theta_max * wp * wp * sn
    tz = np.tan(0.25 * spin_rate * t)
    r1, r2, r3 = mrp_add_s(0.0, 0.0, tz, sigma_RT[0], sigma_RT[1], sigma_RT[2])
    f1, f2, f3 = mrp_add_s(r1, r2, r3, np.tan(0.25 * th), 0.0, 0.0)
    ref[0] = f1
    ref[1] = f2
    ref[2] = f3
    # omega_RN in R, then in F = R1(theta) R
    o1 = dcm_RT[0, 2] * spin_rate
    o2 = dcm_RT[1, 2] * spin_rate
    o3 = dcm_RT[2, 2] * spin_rate
    c = np.cos(th)
    s = np.sin(th)
    of1 = o1
    of2 = c * o2 + s * o3
    of3 = -s * o2 + c * o3
    ref[3] = thd + of1
    ref[4] = of2
    ref[5] = of3
    # thetadd x + omega_RN x (thetad x);  (a x x) = (0, a3, -a2)
    ref[6] = thdd
    ref[7] = of3 * thd
    ref[8] = -of2 * thd


@njit(cache=True, error_model="numpy")
def reference_into(mode, t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref):
    """Dispatch: ``mode`` 0 = Nadir Pointing, 1 = FoV Sweeping.

    Any other code raises ``ValueError``: a maneuver without its branch here
    (or a tabulated one, ``TRACK_MODE``, whose reference is not a function of
    ``t``) must never fly another maneuver's reference.
    """
    if mode == NP_MODE:
        nadir_reference_into(t, spin_rate, sigma_RT, dcm_RT, ref)
    elif mode == FOV_MODE:
        fov_reference_into(t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)
    else:
        raise ValueError("reference_into: no reference kernel for this maneuver mode code")


@njit(cache=True, error_model="numpy")
def reference(mode, t, spin_rate, dcm_RT, theta_max, period):
    """Allocating form: returns ``(sigma_RN, omega_RN_R, omegadot_RN_R)`` (see module doc)."""
    ref = np.empty(9)
    sigma_RT = mrp_from_dcm(np.ascontiguousarray(dcm_RT))
    reference_into(mode, t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)
    return ref[0:3].copy(), ref[3:6].copy(), ref[6:9].copy()


@njit(cache=True, error_model="numpy")
def nadir_camera_dcm_into(t, dcm_RT, theta_max, period, out):
    """Nadir Pointing camera DCM under perfect tracking: ``[B T] = [R T]`` (R fixed in T)."""
    for a in range(3):
        for j in range(3):
            out[a, j] = dcm_RT[a, j]


@njit(cache=True, error_model="numpy")
def fov_camera_dcm_into(t, dcm_RT, theta_max, period, out):
    """FoV Sweeping camera DCM under perfect tracking: ``[B T] = R1(theta_ref(t)) [R T]``,
    ``theta_ref = theta_max sin(2 pi t / P)`` (paper eq. 20); angles in rad, times in s."""
    th = theta_max * np.sin(2.0 * np.pi * t / period)
    c = np.cos(th)
    s = np.sin(th)
    for j in range(3):
        out[0, j] = dcm_RT[0, j]
        out[1, j] = c * dcm_RT[1, j] + s * dcm_RT[2, j]
        out[2, j] = -s * dcm_RT[1, j] + c * dcm_RT[2, j]


@njit(cache=True, error_model="numpy")
def camera_dcm_into(mode, t, dcm_RT, theta_max, period, out):
    """Dispatch: camera DCM ``[B T]`` (3, 3) of maneuver ``mode`` at ``t`` (s) into ``out``.

    An unknown code raises ``ValueError`` (as :func:`reference_into`).
    """
    if mode == NP_MODE:
        nadir_camera_dcm_into(t, dcm_RT, theta_max, period, out)
    elif mode == FOV_MODE:
        fov_camera_dcm_into(t, dcm_RT, theta_max, period, out)
    else:
        raise ValueError("camera_dcm_into: no camera kernel for this maneuver mode code")


@njit(cache=True, error_model="numpy")
def reference_dcm_BT(mode, dcm_RT_all, theta_max, periods, times):
    """Camera DCM ``[B T]`` under perfect tracking (``B`` = reference frame).

    ``[B T] = [R T]`` for Nadir Pointing (constant: R is fixed in T) and
    ``[B T] = R1(theta_ref(t)) [R T]`` for FoV Sweeping (:func:`camera_dcm_into`).

    Parameters
    ----------
    mode : int
        0 NP, 1 FoV.
    dcm_RT_all : (N, 3, 3) float64
    theta_max : float
        rad.
    periods : (N,) float64
        s (ignored for NP).
    times : (n_img,) float64
        s.

    Returns
    -------
    (N, n_img, 3, 3) float64
    """
    n = dcm_RT_all.shape[0]
    m = times.shape[0]
    out = np.empty((n, m, 3, 3))
    for i in range(n):
        for k in range(m):
            camera_dcm_into(mode, times[k], dcm_RT_all[i], theta_max, periods[i], out[i, k])
    return out


@njit(cache=True, error_model="numpy")
def _track_frame(r, v, z_S, dcm, w):
    """Body-tracking frame ``[R N]`` (rows ``x, y, z`` in N) and its rate in R (rad/s).

    ``z = -r/|r|`` (boresight on the body centre), ``x = unit(z_S - (z_S . z) z)``,
    ``y = z x x`` (as ``core.dynamics.encounter.track_dcm_BN``). With
    ``z' = -(v - (rhat . v) rhat)/|r|``: ``w_x = -z' . y``, ``w_y = z' . x`` and
    ``w_z = x' . y = -(z_S . z)(z' . y)/|z_S - (z_S . z) z|``. ``r`` m, ``v`` m/s, frame N.
    """
    rn = np.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    z0, z1, z2 = -r[0] / rn, -r[1] / rn, -r[2] / rn
    rv = -(z0 * v[0] + z1 * v[1] + z2 * v[2])             # rhat . v
    zd0 = -(v[0] + rv * z0) / rn                          # rhat = -z
    zd1 = -(v[1] + rv * z1) / rn
    zd2 = -(v[2] + rv * z2) / rn
    d = z_S[0] * z0 + z_S[1] * z1 + z_S[2] * z2
    p0, p1, p2 = z_S[0] - d * z0, z_S[1] - d * z1, z_S[2] - d * z2
    pn = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    x0, x1, x2 = p0 / pn, p1 / pn, p2 / pn
    y0, y1, y2 = z1 * x2 - z2 * x1, z2 * x0 - z0 * x2, z0 * x1 - z1 * x0
    dcm[0, 0], dcm[0, 1], dcm[0, 2] = x0, x1, x2
    dcm[1, 0], dcm[1, 1], dcm[1, 2] = y0, y1, y2
    dcm[2, 0], dcm[2, 1], dcm[2, 2] = z0, z1, z2
    zy = zd0 * y0 + zd1 * y1 + zd2 * y2
    w[0] = -zy
    w[1] = zd0 * x0 + zd1 * x1 + zd2 * x2
    w[2] = -d * zy / pn


@njit(cache=True, error_model="numpy")
def track_reference_table(r_N, v_N, z_S, dt):
    """Body-tracking reference at every step, in the layout of :func:`reference_into`.

    Parameters
    ----------
    r_N, v_N : (N, T, 3) float64
        Positions (m) and velocities (m/s) relative to the body centre, inertial
        frame N, at the steps ``t_k = t0 + k dt``.
    z_S : (3,) float64
        Approach direction (unit), frame N.
    dt : float
        Step, s (T >= 3).

    Returns
    -------
    (N, T, 9) float64
        ``[sigma_RN, omega_RN_R (rad/s), omegadot_RN_R (rad/s^2)]`` per step; the
        rate from the position and velocity (:func:`_track_frame`), its inertial
        derivative by second-order differences of ``omega_RN`` in N.
    """
    n = r_N.shape[0]
    m = r_N.shape[1]
    out = np.empty((n, m, 9))
    dcm = np.empty((n, m, 3, 3))
    w_N = np.empty((n, m, 3))
    w = np.empty(3)
    for i in range(n):
        for k in range(m):
            _track_frame(r_N[i, k], v_N[i, k], z_S, dcm[i, k], w)
            sig = mrp_from_dcm(np.ascontiguousarray(dcm[i, k]))
            for a in range(3):
                out[i, k, a] = sig[a]
                out[i, k, 3 + a] = w[a]
                w_N[i, k, a] = dcm[i, k, 0, a] * w[0] + dcm[i, k, 1, a] * w[1] \
                    + dcm[i, k, 2, a] * w[2]
        for k in range(m):
            for a in range(3):
                if k == 0:
                    wd = (-3.0 * w_N[i, 0, a] + 4.0 * w_N[i, 1, a] - w_N[i, 2, a]) / (2.0 * dt)
                elif k == m - 1:
                    wd = (3.0 * w_N[i, k, a] - 4.0 * w_N[i, k - 1, a]
                          + w_N[i, k - 2, a]) / (2.0 * dt)
                else:
                    wd = (w_N[i, k + 1, a] - w_N[i, k - 1, a]) / (2.0 * dt)
                w[a] = wd
            for a in range(3):
                out[i, k, 6 + a] = dcm[i, k, a, 0] * w[0] + dcm[i, k, a, 1] * w[1] \
                    + dcm[i, k, a, 2] * w[2]
    return out


@njit(cache=True, error_model="numpy")
def reference_rates(mode, dcm_RT_all, spin_rate, theta_max, periods, times):
    """``omega_RN_R`` (rad/s) of maneuver ``mode`` (0 NP, 1 FoV) at ``times`` (s): the
    reference's own analytic rate (:func:`reference_into`), which perfect tracking's
    camera turns at (``B = R``). Arguments as :func:`reference_dcm_BT` plus the spin
    ``spin_rate`` (rad/s) of the ring frames about ``z_T``. Returns (N, n_img, 3)."""
    n = dcm_RT_all.shape[0]
    m = times.shape[0]
    out = np.empty((n, m, 3))
    ref = np.empty(9)
    for i in range(n):
        sigma_RT = mrp_from_dcm(np.ascontiguousarray(dcm_RT_all[i]))
        for k in range(m):
            reference_into(mode, times[k], spin_rate, sigma_RT, dcm_RT_all[i], theta_max,
                           periods[i], ref)
            out[i, k, 0] = ref[3]
            out[i, k, 1] = ref[4]
            out[i, k, 2] = ref[5]
    return out


@njit(cache=True, error_model="numpy")
def track_rates(r_N, v_N, z_S):
    """``omega_RN_R`` (rad/s) of the body-tracking frame (:func:`_track_frame`: boresight on
    the body centre, ``x`` toward the approach direction ``z_S``) at positions ``r_N`` (m)
    and velocities ``v_N`` (m/s), (N, T, 3) in N: exact in the state, no differences
    across steps. Returns (N, T, 3)."""
    n = r_N.shape[0]
    m = r_N.shape[1]
    out = np.empty((n, m, 3))
    dcm = np.empty((3, 3))
    w = np.empty(3)
    for i in range(n):
        for k in range(m):
            _track_frame(r_N[i, k], v_N[i, k], z_S, dcm, w)
            out[i, k, 0] = w[0]
            out[i, k, 1] = w[1]
            out[i, k, 2] = w[2]
    return out
