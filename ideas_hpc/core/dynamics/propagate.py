"""Compiled orbit + STM propagator in the rotating body frame T (SPEC section 4).

Equations of motion (paper eqs. 3-5, SPEC section 4), frame T spinning at
``omega = [0, 0, w]`` about +z::

    r'' = -2 omega x r' - omega x (omega x r) + a_grav(r) + a_srp(t)
    Phi' = A Phi,   A = [[0, I], [G - W W, -2 W]],   W = [omega x]

The 42-element state is ``[r (3), v (3), Phi (36, row-major)]``; a 6-element
state propagates the trajectory alone.

Force model: the record ``(fi, ff)`` of :mod:`ideas_hpc.core.dynamics.forces` (gravity
of any model plus cannonball SRP), built by the boundary layer
:func:`ideas_hpc.dynamics.forces.pack_forces`.

Integrator: Dormand-Prince 8(5,3) ("DOP853", Hairer, Norsett & Wanner,
*Solving ODEs I*, section II.10) with the same step control, error norm
(RMS of the 5th and 3rd order embedded estimates over all components,
``scale = atol + rtol max(|y_old|, |y_new|)``), initial step choice and 7th
order dense output as ``scipy.integrate.solve_ivp(method="DOP853")``, so the
two agree to the tolerance. Samples on the output grid come from the dense
output.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.dynamics.dop853_tableau import A as _A
from ideas_hpc.core.dynamics.dop853_tableau import B as _B
from ideas_hpc.core.dynamics.dop853_tableau import C as _C
from ideas_hpc.core.dynamics.dop853_tableau import D as _D
from ideas_hpc.core.dynamics.dop853_tableau import E3 as _E3
from ideas_hpc.core.dynamics.dop853_tableau import E5 as _E5
from ideas_hpc.core.dynamics.forces import K_SPIN, gravity_T, srp_T

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_STEP_TOO_SMALL = 2
STATUS_NONFINITE = 3

_SAFETY = 0.9
_MIN_FACTOR = 0.2
_MAX_FACTOR = 10.0
_ERR_EXP = -1.0 / 8.0
_N_STAGES = 12


@njit(cache=True)
def rhs(t, y, dy, fi, ff):
    """Right-hand side for a 6-state (trajectory) or 42-state (with STM).

    Parameters
    ----------
    t : float
        s after t0 (the Sun ephemeris and the spin angle are referred to t0 = 0).
    y, dy : (6,) or (42,) float64
        State ``[r (m), v (m/s), Phi (row-major)]`` in T, and its derivative (output).
    fi, ff
        Force record (:mod:`ideas_hpc.core.dynamics.forces`).
    """
    _rhs_w(t, y, dy, fi, ff, np.empty(3), np.empty((3, 3)), np.empty(3), np.empty((3, 3)),
           np.empty(3))


@njit(cache=True)
def _rhs_w(t, y, dy, fi, ff, acc, grad, a2, g2, asrp):
    """:func:`rhs` with caller-owned work arrays (no allocation in the hot loop)."""
    w = ff[K_SPIN]
    gravity_T(y[:3], fi, ff, acc, grad, a2, g2)
    srp_T(t, ff, asrp)
    x, yy = y[0], y[1]
    vx, vy, vz = y[3], y[4], y[5]
    dy[0] = vx
    dy[1] = vy
    dy[2] = vz
    # -2 w x v - w x (w x r), w = (0, 0, w)
    dy[3] = 2.0 * w * vy + w * w * x + acc[0] + asrp[0]
    dy[4] = -2.0 * w * vx + w * w * yy + acc[1] + asrp[1]
    dy[5] = acc[2] + asrp[2]
    if y.shape[0] == 42:
        # A21 = G - W W = G + diag(w^2, w^2, 0);  A22 = -2 W
        grad[0, 0] += w * w
        grad[1, 1] += w * w
        for j in range(6):
            p0 = y[6 + j]
            p1 = y[12 + j]
            p2 = y[18 + j]
            q0 = y[24 + j]
            q1 = y[30 + j]
            q2 = y[36 + j]
            dy[6 + j] = q0
            dy[12 + j] = q1
            dy[18 + j] = q2
            dy[24 + j] = grad[0, 0] * p0 + grad[0, 1] * p1 + grad[0, 2] * p2 + 2.0 * w * q1
            dy[30 + j] = grad[1, 0] * p0 + grad[1, 1] * p1 + grad[1, 2] * p2 - 2.0 * w * q0
            dy[36 + j] = grad[2, 0] * p0 + grad[2, 1] * p1 + grad[2, 2] * p2


@njit(cache=True)
def _rms(v, scale):
    s = 0.0
    for i in range(v.shape[0]):
        q = v[i] / scale[i]
        s += q * q
    return np.sqrt(s / v.shape[0])


@njit(cache=True)
def dop853(y0, t0, tf, rtol, atol, t_out, y_out, max_steps, fi, ff):
    """Integrate ``y' = rhs(t, y)`` from t0 to tf with DOP853 and step control.

    Parameters
    ----------
    y0 : (n,) float64
        Initial state (n = 6 or 42), SI, frame T.
    t0, tf : float
        s, ``tf > t0``.
    rtol, atol : float
        Tolerances, as scipy's ``solve_ivp``.
    t_out : (T,) float64
        Sorted sample times in ``[t0, tf]`` (may be empty).
    y_out : (T, m) float64
        Output: the first ``m <= 6`` state components at ``t_out`` from the
        7th-order dense output (the extra stages use the 6-state only).
    max_steps : int
        Give up (status 1) after this many steps.
    fi, ff
        Force record (:mod:`ideas_hpc.core.dynamics.forces`).

    Returns
    -------
    y : (n,) float64
        State at tf.
    nfev : int
        Right-hand-side evaluations (the extra dense-output stages, which use
        the 6-state, are counted too).
    status : int
        0 success, 1 too many steps, 2 step too small, 3 non-finite state.
    """
    n = y0.shape[0]
    K = np.empty((16, n))
    wa = np.empty(3)
    wg = np.empty((3, 3))
    wa2 = np.empty(3)
    wg2 = np.empty((3, 3))
    ws = np.empty(3)
    y = y0.copy()
    ynew = np.empty(n)
    ytmp = np.empty(n)
    scale = np.empty(n)
    e3 = np.empty(n)
    e5 = np.empty(n)
    t = t0
    nfev = 0
    f = np.empty(n)
    _rhs_w(t, y, f, fi, ff, wa, wg, wa2, wg2, ws)
    nfev += 1
    # initial step, Hairer et al. II.4 (as scipy select_initial_step)
    for i in range(n):
        scale[i] = atol + abs(y[i]) * rtol
    d0 = _rms(y, scale)
    d1 = _rms(f, scale)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, tf - t0)
    for i in range(n):
        ytmp[i] = y[i] + h0 * f[i]
    _rhs_w(t0 + h0, ytmp, K[1], fi, ff, wa, wg, wa2, wg2, ws)
    nfev += 1
    for i in range(n):
        e3[i] = K[1, i] - f[i]
    d2 = _rms(e3, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    h_abs = min(100.0 * h0, h1)

    n_out = t_out.shape[0]
    m_out = y_out.shape[1] if n_out > 0 else 0
    k_out = 0
    while k_out < n_out and t_out[k_out] < t0:
        k_out += 1
    nsteps = 0
    status = STATUS_OK
    Kd = np.empty((16, 6))
    yd = np.empty(6)
    fd = np.empty(6)
    F = np.empty((7, 6))
    while t < tf:
        if nsteps >= max_steps:
            status = STATUS_MAX_STEPS
            break
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs < min_step:
            h_abs = min_step
        rejected = False
        accepted = False
        while not accepted:
            if h_abs < min_step:
                status = STATUS_STEP_TOO_SMALL
                break
            t_new = t + h_abs
            if t_new > tf:
                t_new = tf
            h = t_new - t
            h_abs = abs(h)
            for i in range(n):
                K[0, i] = f[i]
            for s in range(1, _N_STAGES):
                for i in range(n):
                    acc = 0.0
                    for j in range(s):
                        acc += _A[s, j] * K[j, i]
                    ytmp[i] = y[i] + h * acc
                _rhs_w(t + _C[s] * h, ytmp, K[s], fi, ff, wa, wg, wa2, wg2, ws)
            nfev += _N_STAGES - 1
            for i in range(n):
                acc = 0.0
                for j in range(_N_STAGES):
                    acc += _B[j] * K[j, i]
                ynew[i] = y[i] + h * acc
            _rhs_w(t_new, ynew, K[_N_STAGES], fi, ff, wa, wg, wa2, wg2, ws)
            nfev += 1
            finite = True
            for i in range(n):
                scale[i] = atol + max(abs(y[i]), abs(ynew[i])) * rtol
                a3 = 0.0
                a5 = 0.0
                for j in range(_N_STAGES + 1):
                    a3 += _E3[j] * K[j, i]
                    a5 += _E5[j] * K[j, i]
                e3[i] = a3 / scale[i]
                e5[i] = a5 / scale[i]
                if not np.isfinite(ynew[i]):
                    finite = False
            if not finite:
                status = STATUS_NONFINITE
                break
            n5 = 0.0
            n3 = 0.0
            for i in range(n):
                n5 += e5[i] * e5[i]
                n3 += e3[i] * e3[i]
            if n5 == 0.0 and n3 == 0.0:
                err = 0.0
            else:
                err = h_abs * n5 / np.sqrt((n5 + 0.01 * n3) * n)
            if err < 1.0:
                if err == 0.0:
                    factor = _MAX_FACTOR
                else:
                    factor = min(_MAX_FACTOR, _SAFETY * err ** _ERR_EXP)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                accepted = True
            else:
                h_abs *= max(_MIN_FACTOR, _SAFETY * err ** _ERR_EXP)
                rejected = True
        if status != STATUS_OK:
            break
        # dense output on [t, t_new] for samples in the step (6-state only)
        if k_out < n_out and t_out[k_out] <= t_new:
            for s in range(_N_STAGES + 1):
                for i in range(6):
                    Kd[s, i] = K[s, i]
            for s in range(_N_STAGES + 1, 16):
                for i in range(6):
                    acc = 0.0
                    for j in range(s):
                        acc += _A[s, j] * Kd[j, i]
                    yd[i] = y[i] + h * acc
                _rhs_w(t + _C[s] * h, yd, fd, fi, ff, wa, wg, wa2, wg2, ws)
                for i in range(6):
                    Kd[s, i] = fd[i]
            nfev += 3
            for i in range(6):
                dlt = ynew[i] - y[i]
                F[0, i] = dlt
                F[1, i] = h * Kd[0, i] - dlt
                F[2, i] = 2.0 * dlt - h * (Kd[_N_STAGES, i] + Kd[0, i])
                for q in range(4):
                    acc = 0.0
                    for j in range(16):
                        acc += _D[q, j] * Kd[j, i]
                    F[3 + q, i] = h * acc
            while k_out < n_out and t_out[k_out] <= t_new:
                x = (t_out[k_out] - t) / h
                x1 = 1.0 - x
                for i in range(m_out):
                    val = F[6, i] * x + F[5, i]
                    val = val * x1 + F[4, i]
                    val = val * x + F[3, i]
                    val = val * x1 + F[2, i]
                    val = val * x + F[1, i]
                    val = val * x1 + F[0, i]
                    y_out[k_out, i] = val * x + y[i]
                k_out += 1
        for i in range(n):
            y[i] = ynew[i]
            f[i] = K[_N_STAGES, i]
        t = t_new
        nsteps += 1
    return y, nfev, status


@njit(cache=True)
def propagate(r0, v0, t0, tf, with_stm, rtol, atol, t_out, y_out, max_steps, fi, ff):
    """Propagate one spacecraft from ``(r0, v0)`` at t0 to tf (frame T, SI).

    ``with_stm`` adds ``Phi(t0) = I`` and returns the 42-state; samples of
    ``[r, v]`` at ``t_out`` go to ``y_out`` (``(T, 6)``). Returns
    ``(y_final, nfev, status)`` as :func:`dop853`.
    """
    n = 42 if with_stm else 6
    y0 = np.zeros(n)
    for i in range(3):
        y0[i] = r0[i]
        y0[3 + i] = v0[i]
    if with_stm:
        for i in range(6):
            y0[6 + 7 * i] = 1.0
    return dop853(y0, t0, tf, rtol, atol, t_out, y_out, max_steps, fi, ff)
