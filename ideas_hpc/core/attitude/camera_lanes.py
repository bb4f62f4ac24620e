"""The closed loop of a scenario bank's flight for Nadir Pointing, many spacecraft
side by side in packed arithmetic (issue 31).

:func:`fly_cameras_lanes_into` is :func:`~ideas_hpc.core.attitude.camera_batch.fly_cameras_into`
for Nadir Pointing without disturbance torques, bit for bit, with the step of
:data:`LANES` spacecraft written as loops over lanes that LLVM vectorises.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.attitude.compose import dot3_fma
from ideas_hpc.core.attitude.lanes_control import (_CB, _CT, _D, _NROW, _OR, _R, _RARE, _RATE,
                                                   _SR, _U, _V, _X, _Z, LANES, _control_lanes)
from ideas_hpc.core.attitude.mrp import mrp_from_dcm
from ideas_hpc.core.attitude.rigid_body import _eom_s
from ideas_hpc.core.attitude.smear import camera_rate_xy_s, smear_rate_s

@njit(cache=True, parallel=True, error_model="numpy")
def fly_cameras_lanes_into(dcm_RT_all, spin_rate, gains, wheels, dt, n_steps, initial,
                           views):
    """:func:`fly_cameras_into` for Nadir Pointing without disturbance torques, flying
    :data:`LANES` spacecraft side by side: every step is a loop over them, with the
    reference, :func:`~ideas_hpc.core.attitude.control.sliding_mode_into` and
    :func:`~ideas_hpc.core.attitude.rigid_body.rk4_step_into` written out on scalars
    (their operations, in their order: the same bits), independent from lane to lane
    so that they compile to packed arithmetic (:data:`LANES`; a short last block pads
    its unused lanes with a zero state that is flown but never written out).
    Arguments as :func:`fly_cameras_into` (no mode, periods, amplitude or torque table).
    """
    sigma0, omega0, wheel0 = initial
    img_every, cs_img, dcm_CB, use, r_T, v_T, radius, out, usable = views
    n = sigma0.shape[0]
    smear_tested = v_T.shape[0] > 0
    misaligned = dcm_CB.shape[0] > 0
    exposure = use[0]
    smear_lim = use[1]
    settle = use[2]
    # 4 atan(x) > settle decided without the atan away from x* = tan(settle / 4): the
    # relative margin 1e-9 is 1e6 times the few ulp by which tan and atan round, so on
    # either side the computed test is sure (the atan is called only in between)
    x_lo = -1.0
    x_hi = np.inf
    if 0.0 < settle < np.pi:
        x_star = np.tan(0.25 * settle)
        x_lo = x_star * (1.0 - 1e-9)
        x_hi = x_star * (1.0 + 1e-9)
    B = LANES
    for blk in prange((n + B - 1) // B):
        i0 = blk * B
        m = min(B, n - i0)
        S = np.zeros(_NROW * B)
        RV = np.zeros(_CHUNK * 6 * B)
        for lane in range(m):
            i = i0 + lane
            s = mrp_from_dcm(np.ascontiguousarray(dcm_RT_all[i]))
            for j in range(3):
                S[(_SR + j) * B + lane] = s[j]
                S[(_OR + j) * B + lane] = dcm_RT_all[i, j, 2] * spin_rate
                S[(_X + j) * B + lane] = sigma0[i, j]
                S[(_X + 3 + j) * B + lane] = omega0[i, j]
                S[(_X + 6 + j) * B + lane] = wheel0[i, j]
            if misaligned:
                for j in range(9):
                    S[(_CB + j) * B + lane] = dcm_CB[i, j // 3, j % 3]
            ss = (S[_X * B + lane] * S[_X * B + lane]
                  + S[(_X + 1) * B + lane] * S[(_X + 1) * B + lane]
                  + S[(_X + 2) * B + lane] * S[(_X + 2) * B + lane])
            if ss > 1.0:
                for j in range(3):
                    S[(_X + j) * B + lane] = -S[(_X + j) * B + lane] / ss
        c_img = 0
        n_img_done = 0
        for k in range(n_steps + 1):
            t = k * dt
            img = c_img == 0
            if img:
                c = cs_img[n_img_done, 0]
                sn = cs_img[n_img_done, 1]
                _dcm_CT_lanes(S, c, sn, misaligned)
                if smear_tested:    # the rate before the step's torque, as fly_cameras_into
                    q = n_img_done % _CHUNK
                    if q == 0:
                        _load_chunk(RV, r_T, v_T, i0, m, n_img_done)
                    for j in range(6):
                        for lane in range(B):
                            S[(_R + j) * B + lane] = RV[(q * 6 + j) * B + lane]
                    _smear_lanes(S, misaligned, spin_rate, radius)
                for lane in range(m):
                    for j in range(9):
                        out[i0 + lane, n_img_done, j // 3, j % 3] = S[(_CT + j) * B + lane]
                    usable[i0 + lane, n_img_done] = S[_RATE * B + lane] * exposure > smear_lim
            c_img += 1
            if c_img == img_every:
                c_img = 0
            # nadir_reference_into: sigma_TN = tan(w_s t / 4) z, alike for every lane
            _control_lanes(S, np.tan(0.25 * spin_rate * t), gains, wheels)
            if img:
                for lane in range(m):
                    d1 = S[_D * B + lane]
                    d2 = S[(_D + 1) * B + lane]
                    d3 = S[(_D + 2) * B + lane]
                    x = np.sqrt(d1 * d1 + d2 * d2 + d3 * d3)
                    if x <= x_lo:
                        unsettled = False
                    elif x >= x_hi and x_hi < np.inf:
                        unsettled = True
                    else:
                        unsettled = 4.0 * np.arctan(x) > settle
                    usable[i0 + lane, n_img_done] = not (usable[i0 + lane, n_img_done]
                                                         | unsettled)
                n_img_done += 1
            if k < n_steps:
                _rk4_lanes(S, wheels.I_rw_kgm2, wheels.J_s_kgm2, dt, gains.int_limit)


#: Images whose positions and velocities :func:`_load_chunk` reads at a time: each
#: lane's run of them is contiguous, where reading them image by image touches 128
#: cache lines far apart per image (measured: the gather cost 0.04 s of a 720-candidate
#: scenario's 0.25 s loop image by image).
_CHUNK = 32


@njit(cache=True, error_model="numpy")
def _load_chunk(RV, r_T, v_T, i0, m, n0):
    """``RV[(q * 6 + j) * LANES + lane]``: ``r_T`` (``j`` < 3) and ``v_T`` (``j - 3``) of
    spacecraft ``i0 + lane`` (``lane < m``) at image ``n0 + q``, ``q < _CHUNK``."""
    B = LANES
    n_q = min(_CHUNK, r_T.shape[1] - n0)
    for lane in range(m):
        for q in range(n_q):
            for j in range(3):
                RV[(q * 6 + j) * B + lane] = r_T[i0 + lane, n0 + q, j]
                RV[(q * 6 + 3 + j) * B + lane] = v_T[i0 + lane, n0 + q, j]


@njit(cache=True, error_model="numpy")
def _smear_lanes(S, misaligned, spin_rate, radius):
    """The smear rate of every lane of ``S`` into its ``_RATE`` row, from its ``_X``
    (rate), ``_CB``, ``_CT``, ``_R`` and ``_V`` rows: the operands of
    :func:`~ideas_hpc.core.attitude.smear.image_smear_rate`, so the same bits, in a loop
    over lanes that vectorises (:func:`~ideas_hpc.core.attitude.smear.scene_inverse_range_s`
    has no branch)."""
    B = LANES
    for lane in range(B):
        wx, wy = camera_rate_xy_s(S[(_X + 3) * B + lane], S[(_X + 4) * B + lane],
                                  S[(_X + 5) * B + lane], S[_CB * B + lane],
                                  S[(_CB + 1) * B + lane], S[(_CB + 2) * B + lane],
                                  S[(_CB + 3) * B + lane], S[(_CB + 4) * B + lane],
                                  S[(_CB + 5) * B + lane], misaligned)
        ct = (S[_CT * B + lane], S[(_CT + 1) * B + lane], S[(_CT + 2) * B + lane],
              S[(_CT + 3) * B + lane], S[(_CT + 4) * B + lane], S[(_CT + 5) * B + lane],
              S[(_CT + 6) * B + lane], S[(_CT + 7) * B + lane], S[(_CT + 8) * B + lane])
        S[_RATE * B + lane] = smear_rate_s(
            wx, wy, ct, (S[_R * B + lane], S[(_R + 1) * B + lane], S[(_R + 2) * B + lane]),
            (S[_V * B + lane], S[(_V + 1) * B + lane], S[(_V + 2) * B + lane]), spin_rate,
            radius)


@njit(cache=True, error_model="numpy")
def _dcm_CT_lanes(S, c, s, misaligned):
    """``[C T] = [C B][B N][T N]^T`` of every lane of ``S`` into its ``_CT`` rows, with
    ``cos, sin(w_s t) = c, s``: the operations of
    :func:`~ideas_hpc.core.attitude.camera_batch._dcm_CT_into` (the same bits), in a
    loop over lanes that vectorises (``[C B]`` from the ``_CB`` rows when ``misaligned``)."""
    B = LANES
    for lane in range(B):
        s1 = S[_X * B + lane]
        s2 = S[(_X + 1) * B + lane]
        s3 = S[(_X + 2) * B + lane]
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
        t10 = b10 * c + b11 * s
        t11 = -b10 * s + b11 * c
        t20 = b20 * c + b21 * s
        t21 = -b20 * s + b21 * c
        if not misaligned:
            S[_CT * B + lane] = t00
            S[(_CT + 1) * B + lane] = t01
            S[(_CT + 2) * B + lane] = b02
            S[(_CT + 3) * B + lane] = t10
            S[(_CT + 4) * B + lane] = t11
            S[(_CT + 5) * B + lane] = b12
            S[(_CT + 6) * B + lane] = t20
            S[(_CT + 7) * B + lane] = t21
            S[(_CT + 8) * B + lane] = b22
            continue
        for r in range(3):
            m0 = S[(_CB + 3 * r) * B + lane]
            m1 = S[(_CB + 3 * r + 1) * B + lane]
            m2 = S[(_CB + 3 * r + 2) * B + lane]
            S[(_CT + 3 * r) * B + lane] = dot3_fma(m0, m1, m2, t00, t10, t20)
            S[(_CT + 3 * r + 1) * B + lane] = dot3_fma(m0, m1, m2, t01, t11, t21)
            S[(_CT + 3 * r + 2) * B + lane] = dot3_fma(m0, m1, m2, b02, b12, b22)


@njit(cache=True, error_model="numpy")
def _rk4_lanes(S, I_rw, J_s, dt, int_limit):
    """:func:`~ideas_hpc.core.attitude.rigid_body.rk4_step_into` (no external torque) and
    the conditional integral update of every lane of ``S``, in place."""
    B = LANES
    h = 0.5 * dt
    kk = dt / 6.0
    lim2 = int_limit * int_limit
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
    n_sw = 0
    for lane in range(B):
        x0 = S[_X * B + lane]
        x1 = S[(_X + 1) * B + lane]
        x2 = S[(_X + 2) * B + lane]
        x3 = S[(_X + 3) * B + lane]
        x4 = S[(_X + 4) * B + lane]
        x5 = S[(_X + 5) * B + lane]
        x6 = S[(_X + 6) * B + lane]
        x7 = S[(_X + 7) * B + lane]
        x8 = S[(_X + 8) * B + lane]
        u_ = (S[_U * B + lane], S[(_U + 1) * B + lane], S[(_U + 2) * B + lane])
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
        S[(_X + 3) * B + lane] = x3 + kk * (a3 + 2.0 * b3 + 2.0 * c3 + e3)
        S[(_X + 4) * B + lane] = x4 + kk * (a4 + 2.0 * b4 + 2.0 * c4 + e4)
        S[(_X + 5) * B + lane] = x5 + kk * (a5 + 2.0 * b5 + 2.0 * c5 + e5)
        S[(_X + 6) * B + lane] = x6 + kk * (a6 + 2.0 * b6 + 2.0 * c6 + e6)
        S[(_X + 7) * B + lane] = x7 + kk * (a7 + 2.0 * b7 + 2.0 * c7 + e7)
        S[(_X + 8) * B + lane] = x8 + kk * (a8 + 2.0 * b8 + 2.0 * c8 + e8)
        # the shadow-set switch is rare: flagged here and taken below, on the lanes
        # that need it (its three packed divisions on every lane cost more)
        ss = s0 * s0 + s1 * s1 + s2 * s2
        sw = ss > 1.0
        S[_X * B + lane] = s0
        S[(_X + 1) * B + lane] = s1
        S[(_X + 2) * B + lane] = s2
        S[_RARE * B + lane] = 1.0 if sw else 0.0
        n_sw += 1 if sw else 0
        # the integral's condition as a select (branch-free); z + 0 is never taken:
        # the untaken side keeps z itself
        d0 = S[_D * B + lane]
        d1 = S[(_D + 1) * B + lane]
        d2 = S[(_D + 2) * B + lane]
        ok = d0 * d0 + d1 * d1 + d2 * d2 < lim2
        z0 = S[_Z * B + lane]
        z1 = S[(_Z + 1) * B + lane]
        z2 = S[(_Z + 2) * B + lane]
        S[_Z * B + lane] = z0 + d0 * dt if ok else z0
        S[(_Z + 1) * B + lane] = z1 + d1 * dt if ok else z1
        S[(_Z + 2) * B + lane] = z2 + d2 * dt if ok else z2
    if n_sw > 0:
        for lane in range(B):
            if S[_RARE * B + lane] != 0.0:      # S&J 3.150, as rk4_step_into
                s0 = S[_X * B + lane]
                s1 = S[(_X + 1) * B + lane]
                s2 = S[(_X + 2) * B + lane]
                ss = s0 * s0 + s1 * s1 + s2 * s2
                S[_X * B + lane] = -s0 / ss
                S[(_X + 1) * B + lane] = -s1 / ss
                S[(_X + 2) * B + lane] = -s2 / ss
