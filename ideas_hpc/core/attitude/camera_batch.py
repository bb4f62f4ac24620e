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

from ideas_hpc.core.attitude.batch import _dcm_BT
from ideas_hpc.core.attitude.compose import dot3_fma
from ideas_hpc.core.attitude.control import sliding_mode_into
from ideas_hpc.core.attitude.maneuvers import reference_into
from ideas_hpc.core.attitude.mrp import mrp_from_dcm
from ideas_hpc.core.attitude.rigid_body import rk4_step_into


@njit(cache=True, parallel=True, error_model="numpy")
def fly_cameras_into(mode, dcm_RT_all, spin_rate, periods, theta_max, gains, wheels, dt,
                     n_steps, img_every, initial, torque_table, dcm_CB, use, out, usable):
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
        bt = np.empty((1, 1, 1, 3, 3))
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
                _dcm_BT(x, spin_rate, t, bt, 0, 0, 0)
                rate = np.sqrt(x[3] * x[3] + x[4] * x[4] + x[5] * x[5])
                if misaligned:
                    for r in range(3):
                        for c in range(3):
                            out[i, n_img_done, r, c] = dot3_fma(
                                dcm_CB[i, r, 0], dcm_CB[i, r, 1], dcm_CB[i, r, 2],
                                bt[0, 0, 0, 0, c], bt[0, 0, 0, 1, c], bt[0, 0, 0, 2, c])
                else:
                    for r in range(3):
                        for c in range(3):
                            out[i, n_img_done, r, c] = bt[0, 0, 0, r, c]
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
                usable[i, n_img_done] = not (rate * exposure > smear_lim or angle > settle)
                n_img_done += 1
            if k < n_steps:
                rk4_step_into(x, u, L_ext, I_rw, J_s, dt, work, x)
                if err[0] * err[0] + err[1] * err[1] + err[2] * err[2] < int_limit * int_limit:
                    z[0] += err[0] * dt
                    z[1] += err[1] * dt
                    z[2] += err[2] * dt
