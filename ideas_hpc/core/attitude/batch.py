"""Batched closed-loop attitude simulation: S samples x N spacecraft in one call.

Each (sample, spacecraft) pair is independent; ``prange`` runs over the
flattened ``S * N`` index. Per step ``k`` (``t_k = k dt``):

1. reference at ``t_k`` (``core.maneuvers``),
2. sliding-mode torques from the state at ``t_k`` (``core.control``), held
   over ``[t_k, t_k + dt]``,
3. one RK4 step (``core.attitude.rk4_step_into``) with the MRP shadow switch,
4. ``z_{k+1} = z_k + ds_k dt`` (the controller's integral state, forward
   Euler as a sampled controller would do).

SPEC section 5; store variables of SPEC section 9.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.attitude.rigid_body import rk4_step_into
from ideas_hpc.core.attitude.control import sliding_mode_into
from ideas_hpc.core.attitude.mrp import mrp_from_dcm
from ideas_hpc.core.attitude.maneuvers import TRACK_MODE, reference_into


@njit(cache=True, error_model="numpy", inline="always")
def dcm_BT_s(s1, s2, s3, c, s):
    """``[B T] = [B N][T N]^T`` on scalars: ``sigma_BN = (s1, s2, s3)`` and
    ``[T N] = R3(w_s t)`` given by ``c, s = cos, sin(w_s t)``; returns its nine
    entries row by row. One formula for every closed loop that images
    (:func:`_dcm_BT`, ``camera_batch``), so they give the same bits."""
    ss = s1 * s1 + s2 * s2 + s3 * s3
    d = 1.0 / ((1.0 + ss) * (1.0 + ss))
    q = 1.0 - ss
    # [BN] (S&J 3.153, written out)
    b00 = (4.0 * (s1 * s1 - s2 * s2 - s3 * s3) + q * q) * d
    b01 = (8.0 * s1 * s2 + 4.0 * s3 * q) * d
    b02 = (8.0 * s1 * s3 - 4.0 * s2 * q) * d
    b10 = (8.0 * s2 * s1 - 4.0 * s3 * q) * d
    b11 = (4.0 * (-s1 * s1 + s2 * s2 - s3 * s3) + q * q) * d
    b12 = (8.0 * s2 * s3 + 4.0 * s1 * q) * d
    b20 = (8.0 * s3 * s1 + 4.0 * s2 * q) * d
    b21 = (8.0 * s3 * s2 - 4.0 * s1 * q) * d
    b22 = (4.0 * (-s1 * s1 - s2 * s2 + s3 * s3) + q * q) * d
    # [TN]^T = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    return (b00 * c + b01 * s, -b00 * s + b01 * c, b02,
            b10 * c + b11 * s, -b10 * s + b11 * c, b12,
            b20 * c + b21 * s, -b20 * s + b21 * c, b22)


@njit(cache=True, error_model="numpy")
def _dcm_BT(x, spin_rate, t, out, a, b, c_):
    """:func:`dcm_BT_s` of the state ``x`` at time ``t`` (s); writes ``out[a, b, c_]`` (3, 3).

    (Indices instead of a view: creating array views in the hot loop costs
    more than the whole step.)"""
    c = np.cos(spin_rate * t)
    s = np.sin(spin_rate * t)
    t00, t01, t02, t10, t11, t12, t20, t21, t22 = dcm_BT_s(x[0], x[1], x[2], c, s)
    out[a, b, c_, 0, 0] = t00
    out[a, b, c_, 0, 1] = t01
    out[a, b, c_, 0, 2] = t02
    out[a, b, c_, 1, 0] = t10
    out[a, b, c_, 1, 1] = t11
    out[a, b, c_, 1, 2] = t12
    out[a, b, c_, 2, 0] = t20
    out[a, b, c_, 2, 1] = t21
    out[a, b, c_, 2, 2] = t22


@njit(cache=True, error_model="numpy")
def closed_loop_step(t, x, z, ring, gains, wheels, L_ext, dt, ref, u, err, work):
    """One closed-loop step in place: reference, control, RK4, integral update.

    ``x`` (9,) and ``z`` (3,) are advanced from ``t`` to ``t + dt`` (s); ``u`` (3,)
    receives the held torques (N m) and ``err`` (6,) the errors ``[ds, dw]``
    at ``t``. ``ref`` (9,) and ``work`` (5, 9) are scratch. ``ring``
    (:class:`~ideas_hpc.core.attitude.records.Ring`) is the spacecraft's
    reference, ``L_ext`` (3,) the external torque (N m); other arguments as in
    :func:`simulate_batch`.
    """
    reference_into(ring.mode, t, ring.spin_rate, ring.sigma_RT, ring.dcm_RT, ring.theta_max,
                   ring.period_s, ref)
    sliding_mode_into(x, z, ref, gains, wheels, L_ext, u, err)
    rk4_step_into(x, u, L_ext, wheels.I_rw_kgm2, wheels.J_s_kgm2, dt, work, x)
    # conditional integration (anti-windup, see core.control): only near the goal
    int_limit = gains.int_limit
    if err[0] * err[0] + err[1] * err[1] + err[2] * err[2] < int_limit * int_limit:
        z[0] += err[0] * dt
        z[1] += err[1] * dt
        z[2] += err[2] * dt


@njit(cache=True, parallel=True, error_model="numpy")
def simulate_batch(mode, dcm_RT_all, spin_rate, periods, theta_max, gains, wheels,
                   dt, n_steps, every, initial, tables):
    """Closed-loop attitude of ``S x N`` spacecraft over ``n_steps`` steps of ``dt``.

    Parameters
    ----------
    mode : int
        0 Nadir Pointing, 1 FoV Sweeping, 2 body tracking from ``ref_table``
        (``core.maneuvers``).
    dcm_RT_all : (N, 3, 3) float64
        Ring frames ``[R_i T]`` (``core.frames.dcm_RT``).
    spin_rate : float
        Target spin rate, rad/s.
    periods : (N,) float64
        FoV sweep periods ``P_i``, s (unused for NP but must be > 0).
    theta_max : float
        FoV sweep amplitude, rad.
    gains : :class:`~ideas_hpc.core.attitude.records.ControlGains`
        Controller gains (``core.control``), ``phi`` already capped; the MRP
        error integral ``z`` only accumulates while ``|ds| < gains.int_limit``
        (conditional integration; ``inf`` integrates always, as SPEC writes it).
    wheels : :class:`~ideas_hpc.core.attitude.records.Wheels`
        Inertias (kg m^2), torque (N m) and wheel momentum (N m s) limits.
    dt : float
        Step, s.
    n_steps : int
        Number of steps; final time ``n_steps dt``.
    every : (int, int)
        ``(decimate, img_every)``: record every ``decimate``-th step (``k = 0,
        decimate, ...``); camera DCMs every ``img_every``-th (``k = 0,
        img_every, ...``).
    initial : :class:`~ideas_hpc.core.attitude.records.Initial`
        (S, N, 3) initial ``sigma_BN``, ``omega_BN_B`` (rad/s), wheel speeds (rad/s).
    tables : :class:`~ideas_hpc.core.attitude.records.StepTables`
        Per step: ``reference`` (N, n_steps + 1, 9), read by ``mode`` 2 (body
        tracking, ``core.maneuvers.track_reference_table``; other modes ignore
        it: pass ``(N, 0, 9)``), and ``torque_B_N_m`` (N, n_steps + 1, 3), the
        external torque ``L_ext`` in B (N m) held over each step (``(N, 0, 3)``:
        none). The controller does not know it (its feed-forward torque is zero).

    Returns
    -------
    sigma_error, omega_error : (S, N, T, 3) float64
        ``sigma_B/R`` and ``omega_B/R`` (rad/s, B components) at recorded times.
    wheel_speed : (S, N, T, 3) float64
        rad/s.
    wheel_torque : (S, N, T, 3) float64
        N m, the torque applied from each recorded time on.
    dcm_BT : (S, N, n_img, 3, 3) float64
        Camera DCM (body <- target frame) at image times.
    max_torque, max_momentum : (S, N) float64
        ``max |u_s|`` (N m) and ``max |J_s Omega|`` (N m s) over all steps.
    image_omega : (S, N, n_img, 3) float64
        ``omega_BN`` (B components, rad/s) at the image times: the camera's inertial
        rate (the camera is fixed in B); its norm is the smear test's rate (SPEC 7d)
        and it is the angular velocity ``ideas-hpc export`` writes into the CK.
    image_error : (S, N, n_img) float64
        Principal angle of ``sigma_B/R`` at the image times, rad
        (``4 atan |sigma_B/R|``), for the settle test.
    """
    sigma0, omega0, wheel0 = initial
    int_limit = gains.int_limit
    I_rw = wheels.I_rw_kgm2
    J_s = wheels.J_s_kgm2
    n_s = sigma0.shape[0]
    n_sc = sigma0.shape[1]
    decimate, img_every = every
    n_rec = n_steps // decimate + 1
    n_img = n_steps // img_every + 1
    sig_err = np.empty((n_s, n_sc, n_rec, 3))
    om_err = np.empty((n_s, n_sc, n_rec, 3))
    wheel = np.empty((n_s, n_sc, n_rec, 3))
    torque = np.empty((n_s, n_sc, n_rec, 3))
    dcm_BT = np.empty((n_s, n_sc, n_img, 3, 3))
    img_omega = np.empty((n_s, n_sc, n_img, 3))
    img_err = np.empty((n_s, n_sc, n_img))
    max_u = np.zeros((n_s, n_sc))
    max_h = np.zeros((n_s, n_sc))
    sigma_RT_all = np.empty((n_sc, 3))
    for i in range(n_sc):
        sigma_RT_all[i] = mrp_from_dcm(np.ascontiguousarray(dcm_RT_all[i]))
    ref_table = tables.reference
    torque_table = tables.torque_B_N_m
    disturbed = torque_table.shape[1] > 0
    # the controller is not told the disturbance: the sliding surface rejects it
    L_known = np.zeros(3)
    for job in prange(n_s * n_sc):
        smp = job // n_sc
        i = job % n_sc
        x = np.empty(9)
        z = np.zeros(3)
        ref = np.empty(9)
        u = np.empty(3)
        err = np.empty(6)
        work = np.empty((5, 9))
        L_ext = np.zeros(3)
        sigma_RT = sigma_RT_all[i]
        dcm_RT = dcm_RT_all[i]
        period = periods[i]
        for j in range(3):
            x[j] = sigma0[smp, i, j]
            x[3 + j] = omega0[smp, i, j]
            x[6 + j] = wheel0[smp, i, j]
        ss = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
        if ss > 1.0:
            for j in range(3):
                x[j] = -x[j] / ss
        mu = 0.0
        mh = 0.0
        # counters instead of k % n: integer division is a visible share of a step
        c_img = 0
        n_img_done = 0
        c_rec = 0
        r = 0
        for k in range(n_steps + 1):
            t = k * dt
            img = c_img == 0
            if img:
                _dcm_BT(x, spin_rate, t, dcm_BT, smp, i, n_img_done)
                for j in range(3):
                    img_omega[smp, i, n_img_done, j] = x[3 + j]
            c_img += 1
            if c_img == img_every:
                c_img = 0
            for j in range(3):
                h = abs(J_s[j] * x[6 + j])
                if h > mh:
                    mh = h
            rec = c_rec == 0
            if rec:
                for j in range(3):
                    wheel[smp, i, r, j] = x[6 + j]
            # closed_loop_step written out (at the final time only the errors
            # and the next torque are formed)
            if mode == TRACK_MODE:
                for j in range(9):
                    ref[j] = ref_table[i, k, j]
            else:
                reference_into(mode, t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)
            if disturbed:
                for j in range(3):
                    L_ext[j] = torque_table[i, k, j]
            sliding_mode_into(x, z, ref, gains, wheels, L_known, u, err)
            if img:
                img_err[smp, i, n_img_done] = 4.0 * np.arctan(
                    np.sqrt(err[0] * err[0] + err[1] * err[1] + err[2] * err[2]))
                n_img_done += 1
            if k < n_steps:
                rk4_step_into(x, u, L_ext, I_rw, J_s, dt, work, x)
                if err[0] * err[0] + err[1] * err[1] + err[2] * err[2] < int_limit * int_limit:
                    z[0] += err[0] * dt
                    z[1] += err[1] * dt
                    z[2] += err[2] * dt
            for j in range(3):
                a = abs(u[j])
                if a > mu:
                    mu = a
            if rec:
                for j in range(3):
                    sig_err[smp, i, r, j] = err[j]
                    om_err[smp, i, r, j] = err[3 + j]
                    torque[smp, i, r, j] = u[j]
                r += 1
            c_rec += 1
            if c_rec == decimate:
                c_rec = 0
        max_u[smp, i] = mu
        max_h[smp, i] = mh
    return sig_err, om_err, wheel, torque, dcm_BT, max_u, max_h, img_omega, img_err
