"""The closed loop of a scenario bank's flight, written straight into the cameras (issue 31).

:func:`fly_cameras_into` flies the same closed loop as
:func:`ideas_hpc.core.attitude.batch.simulate_batch` for one sample of ``N``
spacecraft (the same operations in the same order, so the same bits), but keeps
only what the bank's rows read: at every image it forms the camera DCM
``[C T] = [C B][B T]`` (the misalignment composed as
:func:`ideas_hpc.core.attitude.compose.compose_each` does) and the usable-image
test (:func:`ideas_hpc.flyby.usable.usable_images`), in one pass over the images
into a buffer the caller reuses. The flyby pipeline instead writes ``[B T]``,
then a composed copy, then a blinded copy: three passes over ``N x n_img x 9``
doubles (155 MB for 720 candidates over 600 s) per scenario.

The blinding itself (the unusable images' cameras turned away from the body)
is left to the caller on the few images it applies to.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.attitude.compose import dot3_fma
from ideas_hpc.core.attitude.control import sliding_mode_into
from ideas_hpc.core.attitude.maneuvers import reference_into
from ideas_hpc.core.attitude.mrp import mrp_add_s, mrp_from_dcm, mrp_rotate_s, mrp_sub_s
from ideas_hpc.core.attitude.rigid_body import _eom_s, rk4_step_into, wheel_limit_s


@njit(cache=True, error_model="numpy")
def spin_table(spin_rate, dt, n_steps, img_every):
    """(n_img, 2) ``cos, sin(w_s t)`` at the images ``t = k dt``, ``k = 0, img_every, ...``
    (``[T N]`` of :func:`~ideas_hpc.core.attitude.batch._dcm_BT`, the same operations, so
    the same bits), alike for every spacecraft.

    (A table of the Nadir Pointing reference's ``tan(w_s t / 4)`` at every step
    was tried and dropped: the loop ran 20 % slower reading it than computing it.)"""
    cs = np.empty((n_steps // img_every + 1, 2))
    for k in range(0, n_steps + 1, img_every):
        t = k * dt
        cs[k // img_every, 0] = np.cos(spin_rate * t)
        cs[k // img_every, 1] = np.sin(spin_rate * t)
    return cs


@njit(cache=True, error_model="numpy")
def _dcm_CT_into(s1, s2, s3, c, s, dcm_CB, i, misaligned, out, n):
    """``out[i, n] = [C B][B N][T N]^T`` with ``sigma_BN = (s1, s2, s3)`` and
    ``cos, sin(w_s t) = c, s`` (the formulas of
    :func:`~ideas_hpc.core.attitude.batch._dcm_BT`, then
    :func:`~ideas_hpc.core.attitude.compose.compose_each`'s products)."""
    ss = s1 * s1 + s2 * s2 + s3 * s3
    d = 1.0 / ((1.0 + ss) * (1.0 + ss))
    q = 1.0 - ss
    b00 = (4.0 * (s1 * s1 - s2 * s2 - s3 * s3) + q * q) * d
    b01 = (8.0 * s1 * s2 + 4.0 * s3 * q) * d
    b02 = (8.0 * s1 * s3 - 4.0 * s2 * q) * d
    b10 = (8.0 * s2 * s1 - 4.0 * s3 * q) * d
    b11 = (4.0 * (-s1 * s1 + s2 * s2 - s3 * s3) + q * q) * d
    b12 = (8.0 * s2 * s3 + 4.0 * s1 * q) * d
    b20 = (8.0 * s3 * s1 + 4.0 * s2 * q) * d
    b21 = (8.0 * s3 * s2 - 4.0 * s1 * q) * d
    b22 = (4.0 * (-s1 * s1 - s2 * s2 + s3 * s3) + q * q) * d
    t00 = b00 * c + b01 * s
    t01 = -b00 * s + b01 * c
    t02 = b02
    t10 = b10 * c + b11 * s
    t11 = -b10 * s + b11 * c
    t12 = b12
    t20 = b20 * c + b21 * s
    t21 = -b20 * s + b21 * c
    t22 = b22
    if not misaligned:
        out[i, n, 0, 0] = t00
        out[i, n, 0, 1] = t01
        out[i, n, 0, 2] = t02
        out[i, n, 1, 0] = t10
        out[i, n, 1, 1] = t11
        out[i, n, 1, 2] = t12
        out[i, n, 2, 0] = t20
        out[i, n, 2, 1] = t21
        out[i, n, 2, 2] = t22
        return
    for r in range(3):
        m0 = dcm_CB[i, r, 0]
        m1 = dcm_CB[i, r, 1]
        m2 = dcm_CB[i, r, 2]
        out[i, n, r, 0] = dot3_fma(m0, m1, m2, t00, t10, t20)
        out[i, n, r, 1] = dot3_fma(m0, m1, m2, t01, t11, t21)
        out[i, n, r, 2] = dot3_fma(m0, m1, m2, t02, t12, t22)


@njit(cache=True, parallel=True, error_model="numpy")
def fly_cameras_into(mode, dcm_RT_all, spin_rate, periods, theta_max, gains, wheels, dt,
                     n_steps, img_every, initial, torque_table, dcm_CB, use, out, usable,
                     cs_img):
    """Camera DCMs and usable flags at the images of ``N`` closed-loop spacecraft.

    Parameters
    ----------
    mode, dcm_RT_all, spin_rate, periods, theta_max, gains, wheels, dt, n_steps
        As :func:`~ideas_hpc.core.attitude.batch.simulate_batch` (not body tracking:
        ``mode`` 0 or 1).
    img_every : int
        Image every ``img_every``-th step (``k = 0, img_every, ...``).
    initial : :class:`~ideas_hpc.core.attitude.records.Initial`
        (N, 3) absolute ``sigma_BN``, ``omega_BN_B`` (rad/s), wheel speeds (rad/s).
    torque_table : (N, n_steps + 1, 3) float64
        External torque in B, N m, held over each step; ``(N, 0, 3)``: none.
    dcm_CB : (N, 3, 3) float64
        Camera misalignments ``[C B]``; ``(0, 3, 3)``: none (``[C T] = [B T]``).
    use : (3,) float64
        ``(exposure s, smear limit rad = pixels x IFOV, settle limit rad)``; an
        image is usable unless ``rate * exposure > smear limit`` or ``error > settle``.
    out : (N, n_img, 3, 3) float64
        Receives ``[C T]`` at every image.
    usable : (N, n_img) bool
        Receives the usable-image flags.
    cs_img : (n_img, 2) float64
        :func:`spin_table` of ``spin_rate``, ``dt``, ``n_steps``, ``img_every``.
    """
    sigma0, omega0, wheel0 = initial
    int_limit = gains.int_limit
    I_rw = wheels.I_rw_kgm2
    J_s = wheels.J_s_kgm2
    n_sc = sigma0.shape[0]
    disturbed = torque_table.shape[1] > 0
    misaligned = dcm_CB.shape[0] > 0
    exposure = use[0]
    smear_lim = use[1]
    settle = use[2]
    sigma_RT_all = np.empty((n_sc, 3))
    for i in range(n_sc):
        sigma_RT_all[i] = mrp_from_dcm(np.ascontiguousarray(dcm_RT_all[i]))
    L_known = np.zeros(3)
    for i in prange(n_sc):
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
            x[j] = sigma0[i, j]
            x[3 + j] = omega0[i, j]
            x[6 + j] = wheel0[i, j]
        ss = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
        if ss > 1.0:
            for j in range(3):
                x[j] = -x[j] / ss
        c_img = 0
        n_img_done = 0
        for k in range(n_steps + 1):
            t = k * dt
            img = c_img == 0
            rate = 0.0
            if img:
                _dcm_CT_into(x[0], x[1], x[2], cs_img[n_img_done, 0], cs_img[n_img_done, 1],
                             dcm_CB, i, misaligned, out, n_img_done)
                rate = np.sqrt(x[3] * x[3] + x[4] * x[4] + x[5] * x[5])
            c_img += 1
            if c_img == img_every:
                c_img = 0
            reference_into(mode, t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)
            if disturbed:
                for j in range(3):
                    L_ext[j] = torque_table[i, k, j]
            sliding_mode_into(x, z, ref, gains, wheels, L_known, u, err)
            if img:
                angle = 4.0 * np.arctan(
                    np.sqrt(err[0] * err[0] + err[1] * err[1] + err[2] * err[2]))
                usable[i, n_img_done] = not ((rate * exposure > smear_lim) | (angle > settle))
                n_img_done += 1
            if k < n_steps:
                rk4_step_into(x, u, L_ext, I_rw, J_s, dt, work, x)
                if err[0] * err[0] + err[1] * err[1] + err[2] * err[2] < int_limit * int_limit:
                    z[0] += err[0] * dt
                    z[1] += err[1] * dt
                    z[2] += err[2] * dt


#: Spacecraft flown side by side in :func:`fly_cameras_lanes_into`. One spacecraft's
#: step is a long chain of dependent operations; a loop over independent lanes lets
#: the CPU overlap them (the compiled loop is scalar, not SIMD: no packed
#: arithmetic in its assembly). Measured on the main job's 720 candidates: 64 and
#: 128 lanes 2-3x faster than one at a time, 4 to 32 lanes 1.2-1.6x.
LANES = 64


@njit(cache=True, parallel=True, error_model="numpy")
def fly_cameras_lanes_into(dcm_RT_all, spin_rate, gains, wheels, dt, n_steps, img_every,
                           initial, dcm_CB, use, out, usable, cs_img):
    """:func:`fly_cameras_into` for Nadir Pointing without disturbance torques, flying
    :data:`LANES` spacecraft side by side: every step is a loop over them, with the
    reference, :func:`~ideas_hpc.core.attitude.control.sliding_mode_into` and
    :func:`~ideas_hpc.core.attitude.rigid_body.rk4_step_into` written out on scalars
    (their operations, in their order: the same bits), independent from lane to lane
    so that the CPU overlaps them (:data:`LANES`).
    Arguments as :func:`fly_cameras_into` (no mode, periods, amplitude or torque table).
    """
    sigma0, omega0, wheel0 = initial
    k_p = gains.k_p
    k_i = gains.k_i
    eta = gains.eta
    phi = gains.phi
    int_limit = gains.int_limit
    I_rw = wheels.I_rw_kgm2
    J_s = wheels.J_s_kgm2
    u_max = wheels.u_max_Nm
    h_max = wheels.h_max_Nms
    n = sigma0.shape[0]
    misaligned = dcm_CB.shape[0] > 0
    exposure = use[0]
    smear_lim = use[1]
    settle = use[2]
    B = LANES
    for blk in prange((n + B - 1) // B):
        i0 = blk * B
        m = min(B, n - i0)
        X = np.zeros((9, B))        # [sigma_BN, omega_BN_B, wheel speeds] per lane
        Z = np.zeros((3, B))        # the MRP error integral
        U = np.zeros((3, B))        # held wheel torques
        D = np.zeros((3, B))        # sigma_B/R at the step
        SR = np.zeros((3, B))       # sigma_RT
        OR = np.zeros((3, B))       # omega_RN_R
        RATE = np.zeros(B)
        for lane in range(m):
            i = i0 + lane
            s = mrp_from_dcm(np.ascontiguousarray(dcm_RT_all[i]))
            for j in range(3):
                SR[j, lane] = s[j]
                OR[j, lane] = dcm_RT_all[i, j, 2] * spin_rate
                X[j, lane] = sigma0[i, j]
                X[3 + j, lane] = omega0[i, j]
                X[6 + j, lane] = wheel0[i, j]
            ss = X[0, lane] * X[0, lane] + X[1, lane] * X[1, lane] + X[2, lane] * X[2, lane]
            if ss > 1.0:
                for j in range(3):
                    X[j, lane] = -X[j, lane] / ss
        c_img = 0
        n_img_done = 0
        h = 0.5 * dt
        kk = dt / 6.0
        for k in range(n_steps + 1):
            t = k * dt
            img = c_img == 0
            if img:
                c = cs_img[n_img_done, 0]
                sn = cs_img[n_img_done, 1]
                for lane in range(m):
                    _dcm_CT_into(X[0, lane], X[1, lane], X[2, lane], c, sn, dcm_CB, i0 + lane,
                                 misaligned, out, n_img_done)
                    RATE[lane] = np.sqrt(X[3, lane] * X[3, lane] + X[4, lane] * X[4, lane]
                                         + X[5, lane] * X[5, lane])
            c_img += 1
            if c_img == img_every:
                c_img = 0
            # nadir_reference_into: sigma_TN = tan(w_s t / 4) z, alike for every lane
            tz = np.tan(0.25 * spin_rate * t)
            for lane in range(m):
                rr1, rr2, rr3 = mrp_add_s(0.0, 0.0, tz, SR[0, lane], SR[1, lane], SR[2, lane])
                s1 = X[0, lane]
                s2 = X[1, lane]
                s3 = X[2, lane]
                w1 = X[3, lane]
                w2 = X[4, lane]
                w3 = X[5, lane]
                # sliding_mode_into (NP: no reference acceleration, no known torque)
                d1, d2, d3 = mrp_sub_s(s1, s2, s3, rr1, rr2, rr3)
                r1, r2, r3 = mrp_rotate_s(d1, d2, d3, OR[0, lane], OR[1, lane], OR[2, lane])
                e1 = w1 - r1
                e2 = w2 - r2
                e3 = w3 - r3
                dd = d1 * d1 + d2 * d2 + d3 * d3
                de = d1 * e1 + d2 * e2 + d3 * e3
                q = 1.0 - dd
                sd1 = 0.25 * (q * e1 + 2.0 * (d2 * e3 - d3 * e2) + 2.0 * de * d1)
                sd2 = 0.25 * (q * e2 + 2.0 * (d3 * e1 - d1 * e3) + 2.0 * de * d2)
                sd3 = 0.25 * (q * e3 + 2.0 * (d1 * e2 - d2 * e1) + 2.0 * de * d3)
                sv1 = e1 + k_p[0] * d1 + k_i[0] * Z[0, lane]
                sv2 = e2 + k_p[1] * d2 + k_i[1] * Z[1, lane]
                sv3 = e3 + k_p[2] * d3 + k_i[2] * Z[2, lane]
                p1 = min(1.0, max(-1.0, phi[0] * sv1))
                p2 = min(1.0, max(-1.0, phi[1] * sv2))
                p3 = min(1.0, max(-1.0, phi[2] * sv3))
                dwd1 = -k_p[0] * sd1 - k_i[0] * d1 - eta[0] * p1
                dwd2 = -k_p[1] * sd2 - k_i[1] * d2 - eta[1] * p2
                dwd3 = -k_p[2] * sd3 - k_i[2] * d3 - eta[2] * p3
                wd1 = dwd1 + 0.0 - (w2 * r3 - w3 * r2)
                wd2 = dwd2 + 0.0 - (w3 * r1 - w1 * r3)
                wd3 = dwd3 + 0.0 - (w1 * r2 - w2 * r1)
                h1 = I_rw[0] * w1 + J_s[0] * (X[6, lane] + w1)
                h2 = I_rw[1] * w2 + J_s[1] * (X[7, lane] + w2)
                h3 = I_rw[2] * w3 + J_s[2] * (X[8, lane] + w3)
                U[0, lane] = wheel_limit_s(-I_rw[0] * wd1 - (w2 * h3 - w3 * h2) + 0.0,
                                           X[6, lane], J_s[0], u_max, h_max)
                U[1, lane] = wheel_limit_s(-I_rw[1] * wd2 - (w3 * h1 - w1 * h3) + 0.0,
                                           X[7, lane], J_s[1], u_max, h_max)
                U[2, lane] = wheel_limit_s(-I_rw[2] * wd3 - (w1 * h2 - w2 * h1) + 0.0,
                                           X[8, lane], J_s[2], u_max, h_max)
                D[0, lane] = d1
                D[1, lane] = d2
                D[2, lane] = d3
            if img:
                for lane in range(m):
                    angle = 4.0 * np.arctan(np.sqrt(D[0, lane] * D[0, lane]
                                                    + D[1, lane] * D[1, lane]
                                                    + D[2, lane] * D[2, lane]))
                    usable[i0 + lane, n_img_done] = not ((RATE[lane] * exposure > smear_lim)
                                                         | (angle > settle))
                n_img_done += 1
            if k < n_steps:
                _rk4_lanes(X, U, D, Z, m, I_rw, J_s, dt, h, kk, int_limit)


@njit(cache=True, error_model="numpy")
def _rk4_lanes(X, U, D, Z, m, I_rw, J_s, dt, h, kk, int_limit):
    """:func:`~ideas_hpc.core.attitude.rigid_body.rk4_step_into` (no external torque) and
    the conditional integral update of every lane, in place."""
    I1 = I_rw[0]
    I2 = I_rw[1]
    I3 = I_rw[2]
    J1 = J_s[0]
    J2 = J_s[1]
    J3 = J_s[2]
    iI = (1.0 / I1, 1.0 / I2, 1.0 / I3)
    iJ = (1.0 / J1, 1.0 / J2, 1.0 / J3)
    I_ = (I1, I2, I3)
    J_ = (J1, J2, J3)
    L_ = (0.0, 0.0, 0.0)
    for lane in range(m):
        x0 = X[0, lane]
        x1 = X[1, lane]
        x2 = X[2, lane]
        x3 = X[3, lane]
        x4 = X[4, lane]
        x5 = X[5, lane]
        x6 = X[6, lane]
        x7 = X[7, lane]
        x8 = X[8, lane]
        u_ = (U[0, lane], U[1, lane], U[2, lane])
        a0, a1, a2, a3, a4, a5, a6, a7, a8 = _eom_s(
            (x0, x1, x2, x3, x4, x5, x6, x7, x8), u_, L_, iI, I_, J_, iJ)
        b0, b1, b2, b3, b4, b5, b6, b7, b8 = _eom_s(
            (x0 + h * a0, x1 + h * a1, x2 + h * a2, x3 + h * a3, x4 + h * a4, x5 + h * a5,
             x6 + h * a6, x7 + h * a7, x8 + h * a8), u_, L_, iI, I_, J_, iJ)
        c0, c1, c2, c3, c4, c5, c6, c7, c8 = _eom_s(
            (x0 + h * b0, x1 + h * b1, x2 + h * b2, x3 + h * b3, x4 + h * b4, x5 + h * b5,
             x6 + h * b6, x7 + h * b7, x8 + h * b8), u_, L_, iI, I_, J_, iJ)
        e0, e1, e2, e3, e4, e5, e6, e7, e8 = _eom_s(
            (x0 + dt * c0, x1 + dt * c1, x2 + dt * c2, x3 + dt * c3, x4 + dt * c4,
             x5 + dt * c5, x6 + dt * c6, x7 + dt * c7, x8 + dt * c8), u_, L_, iI, I_, J_, iJ)
        s0 = x0 + kk * (a0 + 2.0 * b0 + 2.0 * c0 + e0)
        s1 = x1 + kk * (a1 + 2.0 * b1 + 2.0 * c1 + e1)
        s2 = x2 + kk * (a2 + 2.0 * b2 + 2.0 * c2 + e2)
        X[3, lane] = x3 + kk * (a3 + 2.0 * b3 + 2.0 * c3 + e3)
        X[4, lane] = x4 + kk * (a4 + 2.0 * b4 + 2.0 * c4 + e4)
        X[5, lane] = x5 + kk * (a5 + 2.0 * b5 + 2.0 * c5 + e5)
        X[6, lane] = x6 + kk * (a6 + 2.0 * b6 + 2.0 * c6 + e6)
        X[7, lane] = x7 + kk * (a7 + 2.0 * b7 + 2.0 * c7 + e7)
        X[8, lane] = x8 + kk * (a8 + 2.0 * b8 + 2.0 * c8 + e8)
        ss = s0 * s0 + s1 * s1 + s2 * s2
        if ss > 1.0:
            s0 = -s0 / ss
            s1 = -s1 / ss
            s2 = -s2 / ss
        X[0, lane] = s0
        X[1, lane] = s1
        X[2, lane] = s2
        dsq = D[0, lane] * D[0, lane] + D[1, lane] * D[1, lane] + D[2, lane] * D[2, lane]
        if dsq < int_limit * int_limit:
            Z[0, lane] += D[0, lane] * dt
            Z[1, lane] += D[1, lane] * dt
            Z[2, lane] += D[2, lane] * dt
