"""The closed loop of a scenario bank's flight, written straight into the cameras (issue 31).

:func:`fly_cameras_into` flies the same closed loop as
:func:`ideas_hpc.core.attitude.batch.simulate_batch` for one sample of ``N``
spacecraft (the same operations in the same order, so the same bits), but keeps
only what the bank's rows read: at every image it forms the camera DCM
``[C T] = [C B][B T]`` (the misalignment composed as
:func:`ideas_hpc.core.attitude.compose.compose_each` does) and the usable-image
test (:func:`ideas_hpc.flyby.usable.usable_images`, the smear rate of the footprint
centre by :func:`ideas_hpc.core.attitude.smear.image_smear_rate` from the state and
the camera at the image), in one pass over the images
into a buffer the caller reuses. The flyby pipeline instead writes ``[B T]``,
then a composed copy, then a blinded copy: three passes over ``N x n_img x 9``
doubles (155 MB for 720 candidates over 600 s) per scenario.

The blinding itself (the unusable images' cameras turned away from the body)
is left to the caller on the few images it applies to.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.attitude.batch import dcm_BT_s
from ideas_hpc.core.attitude.compose import dot3_fma
from ideas_hpc.core.attitude.control import sliding_mode_into
from ideas_hpc.core.attitude.maneuvers import reference_into
from ideas_hpc.core.attitude.mrp import mrp_from_dcm
from ideas_hpc.core.attitude.rigid_body import rk4_step_into
from ideas_hpc.core.attitude.smear import image_smear_rate


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
    ``cos, sin(w_s t) = c, s`` (:func:`~ideas_hpc.core.attitude.batch.dcm_BT_s`, then
    :func:`~ideas_hpc.core.attitude.compose.compose_each`'s products)."""
    t00, t01, t02, t10, t11, t12, t20, t21, t22 = dcm_BT_s(s1, s2, s3, c, s)
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
                     n_steps, initial, torque_table, views):
    """Camera DCMs and usable flags at the images of ``N`` closed-loop spacecraft.

    Parameters
    ----------
    mode, dcm_RT_all, spin_rate, periods, theta_max, gains, wheels, dt, n_steps
        As :func:`~ideas_hpc.core.attitude.batch.simulate_batch` (not body tracking:
        ``mode`` 0 or 1).
    initial : :class:`~ideas_hpc.core.attitude.records.Initial`
        (N, 3) absolute ``sigma_BN``, ``omega_BN_B`` (rad/s), wheel speeds (rad/s).
    torque_table : (N, n_steps + 1, 3) float64
        External torque in B, N m, held over each step; ``(N, 0, 3)``: none.
    views : :class:`~ideas_hpc.core.attitude.records.ImageViews`
        The image cadence, the spin table at the images (:func:`spin_table` of
        ``spin_rate``, ``dt``, ``n_steps``, ``img_every``), the misalignments, the
        usable-image limits, the positions and velocities at the images and the
        footprint sphere (the smear rate, :func:`~ideas_hpc.core.attitude.smear.smear_rate_s`
        with ``w_s = spin_rate``), and the arrays that receive ``[C T]`` and the flags.
    """
    sigma0, omega0, wheel0 = initial
    img_every, cs_img, dcm_CB, use, r_T, v_T, radius, out, usable = views
    int_limit = gains.int_limit
    I_rw = wheels.I_rw_kgm2
    J_s = wheels.J_s_kgm2
    n_sc = sigma0.shape[0]
    disturbed = torque_table.shape[1] > 0
    misaligned = dcm_CB.shape[0] > 0
    exposure = use[0]
    smear_lim = use[1]
    settle = use[2]
    smear_tested = v_T.shape[0] > 0
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
                if smear_tested:
                    rate = image_smear_rate(x[3], x[4], x[5], dcm_CB, out, r_T, v_T, i,
                                            n_img_done, spin_rate, radius)
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
