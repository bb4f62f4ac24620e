"""Sun direction in the body frame T from the body's heliocentric orbit (SPEC section 4).

Frames and conventions
----------------------
* ``N``: heliocentric inertial frame of the orbit elements, the ecliptic and
  equinox of the element set (J2000 ecliptic for paper Table 1). x toward the
  equinox, z toward the ecliptic north pole.
* The body moves on a two-body Kepler ellipse about the Sun:
  ``a, e, i, RAAN, argp`` fixed and true anomaly ``nu0`` at ``t0 = 0``; mean
  motion ``n = sqrt(MU_SUN / a^3)`` (the body's own mass is negligible).
* Pole ``p_N``: the orbit normal
  ``h = (sin i sin RAAN, -sin i cos RAAN, cos i)`` unless a pole is given;
  a given pole is ``(cos dec cos ra, cos dec sin ra, sin dec)`` *in frame N*
  (i.e. ``ra``/``dec`` are the pole's longitude and latitude in the frame of
  the orbit elements, see :class:`ideas_hpc.body.params.PhysicalParams`).
* Frame ``P`` (body equator at t0): ``z_P = p``, ``x_P = unit(z_N x p)``
  (the ascending node of the body equator on the N xy-plane, the IAU
  convention), ``y_P = z_P x x_P``; when the pole is along ``z_N`` the node is
  undefined and ``x_P = x_N``.
* Frame ``T`` turns about ``z_P`` by ``W(t) = W0 + omega t`` (``W0`` the prime
  meridian angle at t0, ``omega = 2 pi / P_spin``):
  ``[TN](t) = R3(W(t)) [PN]``.
* The Sun direction is taken from the body's centre (the spacecraft offset
  of ~1e5 m against ~2e11 m moves it by < 1e-6 rad).

All lengths m, times s, angles rad.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def kepler_E(M, e):
    """Eccentric anomaly from mean anomaly (Newton on ``E - e sin E = M``), rad."""
    E = M if e < 0.8 else np.pi
    for _ in range(50):
        f = E - e * np.sin(E) - M
        d = f / (1.0 - e * np.cos(E))
        E -= d
        if abs(d) < 1e-15:
            break
    return E


@njit(cache=True)
def body_position_N(t, elements, mu_sun):
    """Heliocentric position of the body in N at time ``t`` (s after t0), m.

    Parameters
    ----------
    t : float
        s after t0.
    elements : (6,) float64
        ``a (m), e, i, RAAN, argp, nu0`` (rad), osculating at t0.
    mu_sun : float
        m^3/s^2.
    """
    a, e, inc, raan, argp, nu0 = (elements[0], elements[1], elements[2],
                                  elements[3], elements[4], elements[5])
    n = np.sqrt(mu_sun / (a * a * a))
    E0 = 2.0 * np.arctan2(np.sqrt(1.0 - e) * np.sin(0.5 * nu0),
                          np.sqrt(1.0 + e) * np.cos(0.5 * nu0))
    M = E0 - e * np.sin(E0) + n * t
    E = kepler_E(M, e)
    nu = 2.0 * np.arctan2(np.sqrt(1.0 + e) * np.sin(0.5 * E),
                          np.sqrt(1.0 - e) * np.cos(0.5 * E))
    r = a * (1.0 - e * np.cos(E))
    u = argp + nu
    cO, sO = np.cos(raan), np.sin(raan)
    ci, si = np.cos(inc), np.sin(inc)
    cu, su = np.cos(u), np.sin(u)
    out = np.empty(3)
    out[0] = r * (cO * cu - sO * su * ci)
    out[1] = r * (sO * cu + cO * su * ci)
    out[2] = r * (su * si)
    return out


@njit(cache=True)
def dcm_PN(elements, pole):
    """Body-equator frame ``[PN]`` (rows ``x_P, y_P, z_P`` in N components).

    ``pole`` is ``(ra, dec, flag)``: ``flag > 0`` means use ``ra, dec`` (rad),
    otherwise the orbit normal.
    """
    inc, raan = elements[2], elements[3]
    p = np.empty(3)
    if pole[2] > 0.0:
        p[0] = np.cos(pole[1]) * np.cos(pole[0])
        p[1] = np.cos(pole[1]) * np.sin(pole[0])
        p[2] = np.sin(pole[1])
    else:
        p[0] = np.sin(inc) * np.sin(raan)
        p[1] = -np.sin(inc) * np.cos(raan)
        p[2] = np.cos(inc)
    x0 = -p[1]  # z_N x p
    x1 = p[0]
    nx = np.sqrt(x0 * x0 + x1 * x1)
    if nx < 1e-12:
        x0 = 1.0
        x1 = 0.0
    else:
        x0 /= nx
        x1 /= nx
    m = np.empty((3, 3))
    m[0, 0] = x0
    m[0, 1] = x1
    m[0, 2] = 0.0
    # y_P = p x x_P
    m[1, 0] = -p[2] * x1
    m[1, 1] = p[2] * x0
    m[1, 2] = p[0] * x1 - p[1] * x0
    m[2, 0] = p[0]
    m[2, 1] = p[1]
    m[2, 2] = p[2]
    return m


@njit(cache=True)
def sun_T(t, elements, pole, spin_rate, w0, mu_sun, out):
    """Unit vector body -> Sun in frame T at time t; returns the Sun distance (m).

    Parameters
    ----------
    t : float
        s after t0.
    elements : (6,) float64
        ``a, e, i, RAAN, argp, nu0`` (m, rad).
    pole : (3,) float64
        ``(ra, dec, flag)``, see :func:`dcm_PN`.
    spin_rate : float
        rad/s about +z_T.
    w0 : float
        Prime-meridian angle at t0, rad.
    mu_sun : float
        m^3/s^2.
    out : (3,) float64
        Output unit vector in T, overwritten.
    """
    rb = body_position_N(t, elements, mu_sun)
    d = np.sqrt(rb[0] ** 2 + rb[1] ** 2 + rb[2] ** 2)
    pn = dcm_PN(elements, pole)
    sp = np.empty(3)
    for i in range(3):
        sp[i] = -(pn[i, 0] * rb[0] + pn[i, 1] * rb[1] + pn[i, 2] * rb[2]) / d
    w = w0 + spin_rate * t
    c, sn = np.cos(w), np.sin(w)
    out[0] = c * sp[0] + sn * sp[1]
    out[1] = -sn * sp[0] + c * sp[1]
    out[2] = sp[2]
    return d


@njit(cache=True)
def sun_T_batch(times, elements, pole, spin_rate, w0, mu_sun, dirs, dist):
    """:func:`sun_T` over an array of times (``dirs (T, 3)``, ``dist (T,)`` outputs)."""
    for k in range(times.shape[0]):
        dist[k] = sun_T(times[k], elements, pole, spin_rate, w0, mu_sun, dirs[k])


#: Length of the derived-constant vector of :func:`ephemeris_precompute`.
N_EPH = 13


@njit(cache=True)
def ephemeris_precompute(elements, pole, spin_rate, w0, mu_sun):
    """Time-independent part of :func:`sun_T`, for the propagator's hot loop.

    Returns ``(N_EPH,)``: mean motion n (rad/s), mean anomaly at t0 (rad), e,
    a (m), b = a sqrt(1 - e^2) (m), spin rate (rad/s), W0 (rad), and the
    perifocal unit vectors P, Q (periapsis and 90 deg ahead) in the
    body-equator frame P (3 + 3 values). Then
    ``r_body = a (cos E - e) P + b sin E Q`` (Kepler), no angle conversions.
    """
    a, e, inc, raan, argp, nu0 = (elements[0], elements[1], elements[2],
                                  elements[3], elements[4], elements[5])
    out = np.empty(N_EPH)
    out[0] = np.sqrt(mu_sun / (a * a * a))
    E0 = 2.0 * np.arctan2(np.sqrt(1.0 - e) * np.sin(0.5 * nu0),
                          np.sqrt(1.0 + e) * np.cos(0.5 * nu0))
    out[1] = E0 - e * np.sin(E0)
    out[2] = e
    out[3] = a
    out[4] = a * np.sqrt(1.0 - e * e)
    out[5] = spin_rate
    out[6] = w0
    cO, sO = np.cos(raan), np.sin(raan)
    ci, si = np.cos(inc), np.sin(inc)
    cw, sw = np.cos(argp), np.sin(argp)
    pN = np.array([cO * cw - sO * sw * ci, sO * cw + cO * sw * ci, sw * si])
    qN = np.array([-cO * sw - sO * cw * ci, -sO * sw + cO * cw * ci, cw * si])
    pn = dcm_PN(elements, pole)
    for i in range(3):
        out[7 + i] = pn[i, 0] * pN[0] + pn[i, 1] * pN[1] + pn[i, 2] * pN[2]
        out[10 + i] = pn[i, 0] * qN[0] + pn[i, 1] * qN[1] + pn[i, 2] * qN[2]
    return out


@njit(cache=True)
def sun_T_fast(t, eph, out):
    """:func:`sun_T` from :func:`ephemeris_precompute` constants; returns the distance (m)."""
    e = eph[2]
    E = kepler_E(eph[1] + eph[0] * t, e)
    cE = np.cos(E)
    xp = eph[3] * (cE - e)
    yq = eph[4] * np.sin(E)
    s0 = -(xp * eph[7] + yq * eph[10])
    s1 = -(xp * eph[8] + yq * eph[11])
    s2 = -(xp * eph[9] + yq * eph[12])
    d = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    w = eph[6] + eph[5] * t
    c, sn = np.cos(w), np.sin(w)
    out[0] = (c * s0 + sn * s1) / d
    out[1] = (-sn * s0 + c * s1) / d
    out[2] = s2 / d
    return d
