"""Spherical-harmonic gravity in the body-fixed frame T (SPEC section 4).

Returns, as every model of :mod:`ideas_hpc.core.dynamics.gravity`, the potential ``U``
(m^2/s^2), acceleration ``a = grad U`` (m/s^2) and gradient (1/s^2) at ``r_T`` (m).

Spherical harmonics to any degree (Montenbruck & Gill, *Satellite Orbits*,
2000, section 3.2, eqs. 3.29-3.33): unnormalised solid harmonics ``V_nm``,
``W_nm`` by the recursions of eqs. 3.29-3.31, ``U = GM/R sum(C V + S W)``.
A derivative of a solid harmonic is again a finite sum of solid harmonics one
degree higher (eq. 3.33), so first and second derivatives of ``U`` are the
same sum evaluated with *derivative coefficient tables* one and two degrees
higher. :func:`sh_derivative_tables` builds those tables once (per field),
:func:`sh_gravity` evaluates potential, acceleration and gradient from one
``V, W`` recursion to degree ``N + 2``. Unnormalised harmonics overflow near
degree 80; the boundary layer limits the degree.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def sh_unnormalise(cbar, sbar):
    """Unnormalised ``C_nm, S_nm`` from fully normalised ones (Kaula).

    ``C_nm = N_nm Cbar_nm``, ``N_nm = sqrt((2 - delta_m0)(2n + 1)(n - m)!/(n + m)!)``.
    Tables are lower-triangular ``(N+1, N+1)`` indexed ``[n, m]``.
    """
    nmax = cbar.shape[0] - 1
    c = np.zeros_like(cbar)
    s = np.zeros_like(sbar)
    for n in range(nmax + 1):
        for m in range(n + 1):
            # (n-m)!/(n+m)! as a running product keeps it finite for large n
            ratio = 1.0
            for k in range(n - m + 1, n + m + 1):
                ratio /= k
            f = np.sqrt((1.0 if m == 0 else 2.0) * (2 * n + 1) * ratio)
            c[n, m] = f * cbar[n, m]
            s[n, m] = f * sbar[n, m]
    return c, s


@njit(cache=True)
def _sh_derivative(c, s, axis):
    """Coefficients of ``R d/dx_axis`` of ``sum C V + S W`` (M&G eq. 3.33).

    Input tables are ``(N+1, N+1)``; the result is ``(N+2, N+2)``.
    """
    n1 = c.shape[0]
    cd = np.zeros((n1 + 1, n1 + 1))
    sd = np.zeros((n1 + 1, n1 + 1))
    for n in range(n1):
        for m in range(n + 1):
            cc = c[n, m]
            ss = s[n, m]
            if cc == 0.0 and ss == 0.0:
                continue
            k = (n - m + 2) * (n - m + 1)
            if axis == 2:
                cd[n + 1, m] -= (n - m + 1) * cc
                sd[n + 1, m] -= (n - m + 1) * ss
            elif axis == 0:
                if m == 0:
                    cd[n + 1, 1] -= cc
                else:
                    cd[n + 1, m + 1] -= 0.5 * cc
                    sd[n + 1, m + 1] -= 0.5 * ss
                    cd[n + 1, m - 1] += 0.5 * k * cc
                    sd[n + 1, m - 1] += 0.5 * k * ss
            else:
                if m == 0:
                    sd[n + 1, 1] -= cc
                else:
                    sd[n + 1, m + 1] -= 0.5 * cc
                    cd[n + 1, m + 1] += 0.5 * ss
                    sd[n + 1, m - 1] -= 0.5 * k * cc
                    cd[n + 1, m - 1] += 0.5 * k * ss
    for n in range(n1 + 1):
        sd[n, 0] = 0.0  # W_n0 = 0
    return cd, sd


@njit(cache=True)
def sh_derivative_tables(c, s):
    """Stack of unnormalised coefficient tables for U, grad U and the Hessian.

    Parameters
    ----------
    c, s : (N+1, N+1) float64
        Unnormalised ``C_nm``, ``S_nm`` (``C_00 = 1`` for the central term).

    Returns
    -------
    ctab, stab : (10, N+3, N+3) float64
        Index 0: the potential; 1-3: ``R d/dx, R d/dy, R d/dz``;
        4-9: ``R^2 d2/dxx, dxy, dxz, dyy, dyz, dzz``. Evaluate with
        :func:`sh_gravity`.
    """
    n = c.shape[0]
    ctab = np.zeros((10, n + 2, n + 2))
    stab = np.zeros((10, n + 2, n + 2))
    for i in range(n):
        for j in range(n):
            ctab[0, i, j] = c[i, j]
            stab[0, i, j] = s[i, j]
    first_a = np.array([0, 0, 0, 1, 1, 2])
    second_a = np.array([0, 1, 2, 1, 2, 2])
    for a in range(3):
        cd, sd = _sh_derivative(c, s, a)
        for i in range(n + 1):
            for j in range(n + 1):
                ctab[1 + a, i, j] = cd[i, j]
                stab[1 + a, i, j] = sd[i, j]
    for k in range(6):
        cd, sd = _sh_derivative(c, s, first_a[k])
        cdd, sdd = _sh_derivative(cd, sd, second_a[k])
        for i in range(n + 2):
            for j in range(n + 2):
                ctab[4 + k, i, j] = cdd[i, j]
                stab[4 + k, i, j] = sdd[i, j]
    return ctab, stab


@njit(cache=True)
def sh_vw(r_T, r_ref, nmax, v, w):
    """Solid harmonics ``V_nm, W_nm`` to degree ``nmax`` (M&G eqs. 3.29-3.31).

    ``v, w`` are ``(nmax+1, nmax+1)`` work arrays, overwritten.
    """
    x, y, z = r_T[0], r_T[1], r_T[2]
    r2 = x * x + y * y + z * z
    rr = r_ref / r2
    x0 = x * rr
    y0 = y * rr
    z0 = z * rr
    rho = r_ref * rr
    v[0, 0] = r_ref / np.sqrt(r2)
    w[0, 0] = 0.0
    for m in range(nmax + 1):
        if m > 0:
            v[m, m] = (2 * m - 1) * (x0 * v[m - 1, m - 1] - y0 * w[m - 1, m - 1])
            w[m, m] = (2 * m - 1) * (x0 * w[m - 1, m - 1] + y0 * v[m - 1, m - 1])
        if m < nmax:
            v[m + 1, m] = (2 * m + 1) * z0 * v[m, m]
            w[m + 1, m] = (2 * m + 1) * z0 * w[m, m]
        for n in range(m + 2, nmax + 1):
            a = (2 * n - 1) / (n - m)
            b = (n + m - 1) / (n - m)
            v[n, m] = a * z0 * v[n - 1, m] - b * rho * v[n - 2, m]
            w[n, m] = a * z0 * w[n - 1, m] - b * rho * w[n - 2, m]


@njit(cache=True)
def sh_gravity(r_T, gm, r_ref, ctab, stab, acc, grad, v, w):
    """Spherical-harmonic potential, acceleration and gradient.

    Parameters
    ----------
    r_T : (3,) float64
        Field point, m, frame T (outside the Brillouin sphere ``r > r_ref``
        for convergence).
    gm : float
        m^3/s^2 of the field (from the table's label).
    r_ref : float
        Reference radius, m.
    ctab, stab : (10, K, K) float64
        From :func:`sh_derivative_tables` (``K = N + 3``).
    acc, grad : (3,), (3, 3) float64
        Outputs, overwritten (central term included when ``C_00 = 1``).
    v, w : (K, K) float64
        Work arrays.

    Returns
    -------
    float
        U, m^2/s^2.
    """
    kk = ctab.shape[1]
    sh_vw(r_T, r_ref, kk - 1, v, w)
    out = np.zeros(10)
    for n in range(kk):
        for m in range(n + 1):
            vv = v[n, m]
            ww = w[n, m]
            for q in range(10):
                out[q] += ctab[q, n, m] * vv + stab[q, n, m] * ww
    f0 = gm / r_ref
    f1 = f0 / r_ref
    f2 = f1 / r_ref
    acc[0] = f1 * out[1]
    acc[1] = f1 * out[2]
    acc[2] = f1 * out[3]
    grad[0, 0] = f2 * out[4]
    grad[0, 1] = f2 * out[5]
    grad[0, 2] = f2 * out[6]
    grad[1, 1] = f2 * out[7]
    grad[1, 2] = f2 * out[8]
    grad[2, 2] = f2 * out[9]
    grad[1, 0] = grad[0, 1]
    grad[2, 0] = grad[0, 2]
    grad[2, 1] = grad[1, 2]
    return f0 * out[0]
