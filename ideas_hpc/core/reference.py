"""Attitude reference generators: Nadir Pointing and FoV Sweeping (SPEC section 5).

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

The MRP arithmetic below is an allocation-free scalar transcription of
``core.mrp.mrp_add`` / ``mrp_sub`` / ``dcm_from_mrp`` (same formulas, same
shadow-set rules; tests check them against ``core.mrp`` to 1e-15). The hot
loop calls them millions of times, and the array forms allocate.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .mrp import mrp_from_dcm

NP_MODE = 0
FOV_MODE = 1


@njit(cache=True, error_model="numpy")
def _switch(a, b, c):
    ss = a * a + b * b + c * c
    if ss > 1.0:
        return -a / ss, -b / ss, -c / ss
    return a, b, c


@njit(cache=True, error_model="numpy")
def mrp_add_s(a1, a2, a3, b1, b2, b3):
    """Scalar ``core.mrp.mrp_add``: ``sigma1 = sigma_BN``, ``sigma2 = sigma_FB`` -> ``sigma_FN``
    (S&J 3.160), short set returned as a 3-tuple."""
    s1s = a1 * a1 + a2 * a2 + a3 * a3
    s2s = b1 * b1 + b2 * b2 + b3 * b3
    den = 1.0 + s1s * s2s - 2.0 * (a1 * b1 + a2 * b2 + a3 * b3)
    if abs(den) < 0.1:
        a1 = -a1 / s1s
        a2 = -a2 / s1s
        a3 = -a3 / s1s
        s1s = 1.0 / s1s
        den = 1.0 + s1s * s2s - 2.0 * (a1 * b1 + a2 * b2 + a3 * b3)
    # num = (1 - |s1|^2) s2 + (1 - |s2|^2) s1 - 2 s2 x s1
    c1 = b2 * a3 - b3 * a2
    c2 = b3 * a1 - b1 * a3
    c3 = b1 * a2 - b2 * a1
    p = 1.0 - s1s
    q = 1.0 - s2s
    return _switch((p * b1 + q * a1 - 2.0 * c1) / den,
                   (p * b2 + q * a2 - 2.0 * c2) / den,
                   (p * b3 + q * a3 - 2.0 * c3) / den)


@njit(cache=True, error_model="numpy")
def mrp_sub_s(a1, a2, a3, r1, r2, r3):
    """Scalar ``core.mrp.mrp_sub``: ``sigma_BN``, ``sigma_RN`` -> ``sigma_BR`` (S&J 3.161)."""
    srs = r1 * r1 + r2 * r2 + r3 * r3
    sbs = a1 * a1 + a2 * a2 + a3 * a3
    den = 1.0 + srs * sbs + 2.0 * (r1 * a1 + r2 * a2 + r3 * a3)
    if abs(den) < 0.1:
        r1 = -r1 / srs
        r2 = -r2 / srs
        r3 = -r3 / srs
        srs = 1.0 / srs
        den = 1.0 + srs * sbs + 2.0 * (r1 * a1 + r2 * a2 + r3 * a3)
    # num = (1 - |sR|^2) sB - (1 - |sB|^2) sR + 2 sB x sR
    c1 = a2 * r3 - a3 * r2
    c2 = a3 * r1 - a1 * r3
    c3 = a1 * r2 - a2 * r1
    p = 1.0 - srs
    q = 1.0 - sbs
    return _switch((p * a1 - q * r1 + 2.0 * c1) / den,
                   (p * a2 - q * r2 + 2.0 * c2) / den,
                   (p * a3 - q * r3 + 2.0 * c3) / den)


@njit(cache=True, error_model="numpy")
def mrp_rotate_s(s1, s2, s3, v1, v2, v3):
    """``dcm_from_mrp(sigma) @ v`` without forming the matrix (S&J 3.153)::

        C v = v + (8 s x (s x v) - 4 (1 - s^2) s x v) / (1 + s^2)^2
    """
    ss = s1 * s1 + s2 * s2 + s3 * s3
    a1 = s2 * v3 - s3 * v2
    a2 = s3 * v1 - s1 * v3
    a3 = s1 * v2 - s2 * v1
    b1 = s2 * a3 - s3 * a2
    b2 = s3 * a1 - s1 * a3
    b3 = s1 * a2 - s2 * a1
    d = 1.0 / ((1.0 + ss) * (1.0 + ss))
    k = 4.0 * (1.0 - ss)
    return (v1 + (8.0 * b1 - k * a1) * d,
            v2 + (8.0 * b2 - k * a2) * d,
            v3 + (8.0 * b3 - k * a3) * d)


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
    """Dispatch: ``mode`` 0 = Nadir Pointing, 1 = FoV Sweeping."""
    if mode == FOV_MODE:
        fov_reference_into(t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)
    else:
        nadir_reference_into(t, spin_rate, sigma_RT, dcm_RT, ref)


@njit(cache=True, error_model="numpy")
def reference(mode, t, spin_rate, dcm_RT, theta_max, period):
    """Allocating form: returns ``(sigma_RN, omega_RN_R, omegadot_RN_R)`` (see module doc)."""
    ref = np.empty(9)
    sigma_RT = mrp_from_dcm(np.ascontiguousarray(dcm_RT))
    reference_into(mode, t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)
    return ref[0:3].copy(), ref[3:6].copy(), ref[6:9].copy()


@njit(cache=True, error_model="numpy")
def reference_dcm_BT(mode, dcm_RT_all, theta_max, periods, times):
    """Camera DCM ``[B T]`` under perfect tracking (``B`` = reference frame).

    ``[B T] = [R T]`` for Nadir Pointing (constant: R is fixed in T) and
    ``[B T] = R1(theta_ref(t)) [R T]`` for FoV Sweeping.

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
            if mode == FOV_MODE:
                th = theta_max * np.sin(2.0 * np.pi * times[k] / periods[i])
                c = np.cos(th)
                s = np.sin(th)
                for j in range(3):
                    out[i, k, 0, j] = dcm_RT_all[i, 0, j]
                    out[i, k, 1, j] = c * dcm_RT_all[i, 1, j] + s * dcm_RT_all[i, 2, j]
                    out[i, k, 2, j] = -s * dcm_RT_all[i, 1, j] + c * dcm_RT_all[i, 2, j]
            else:
                out[i, k] = dcm_RT_all[i]
    return out
