"""Propagator accuracy contract (SPEC section 4) and the Sun ephemeris.

Truths: scipy ``solve_ivp(DOP853, rtol=1e-12, atol=1e-9)`` on an independent
NumPy right-hand side (degree-2 field by complex-step differentiation of the
SPEC U2 formula); central finite differences for the STM; the Jacobi integral
in the rotating frame (point mass, no SRP); Kepler's laws for the ephemeris.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ideas_hpc.body.bodies import load_body
from ideas_hpc.base.constants import AU, MU_SUN, P_SUN_1AU
from ideas_hpc.core.dynamics import propagate as P
from ideas_hpc.core.dynamics.forces import K_SRP
from ideas_hpc.core.dynamics.ephemeris import body_position_N
from ideas_hpc.dynamics.force_model import ForceModel, pack_force_model
from ideas_hpc.dynamics.force_terms import BOX_AREA
from ideas_hpc.dynamics.trajectory import sun_direction_T

BODY = load_body("eros-ellipsoid", resolution=1)
PAR = BODY.params
D_SEP = 155.901e3


def _u2(x, mu, c20, c22):
    r2 = x[0] ** 2 + x[1] ** 2 + x[2] ** 2
    r = np.sqrt(r2)
    cd2 = (x[0] ** 2 + x[1] ** 2) / r2
    c2l = (x[0] ** 2 - x[1] ** 2) / (x[0] ** 2 + x[1] ** 2)  # cos 2 lambda
    return mu / r ** 3 * (c20 * (1 - 1.5 * cd2) + 3 * c22 * cd2 * c2l)


def _grad_cs(x, mu, c20, c22):
    """grad U2 by complex-step differentiation (exact to rounding)."""
    g = np.zeros(3)
    h = 1e-20 * np.linalg.norm(x)
    for k in range(3):
        xc = x.astype(complex)
        xc[k] += 1j * h
        g[k] = _u2(xc, mu, c20, c22).imag / h
    return g


def scipy_rhs(params, srp_coef, degree2=True):
    """Independent NumPy RHS: rotating frame, point mass + degree 2, cannonball SRP."""
    w = params.spin_rate
    mu, c20, c22 = params.mu, params.c20, params.c22

    def f(t, y):
        r, v = y[:3], y[3:]
        a = -mu * r / np.linalg.norm(r) ** 3
        if degree2:
            a = a + _grad_cs(r, mu, c20, c22)
        if srp_coef:
            s = sun_direction_T(params, [t])[0]
            d = _sun_dist(params, t)
            a = a - srp_coef / d ** 2 * s
        acor = np.array([2 * w * v[1] + w * w * r[0], -2 * w * v[0] + w * w * r[1], 0.0])
        return np.concatenate([v, a + acor])
    return f


def _sun_dist(params, t):
    el = np.array([params.orbit_a, params.orbit_e, params.orbit_i, params.orbit_raan,
                   params.orbit_argp, params.orbit_nu])
    return np.linalg.norm(body_position_N(t, el, MU_SUN))


def _prop(pk, r0, v0, tf, stm=False, t_out=None, rtol=1e-12, atol=1e-9):
    t_out = np.empty(0) if t_out is None else np.ascontiguousarray(t_out, dtype=float)
    y_out = np.zeros((t_out.shape[0], 6))
    y, nfev, status = P.propagate(np.asarray(r0, float), np.asarray(v0, float), 0.0, tf, stm,
                                  rtol, atol, t_out, y_out, 100000, *pk.args())
    assert status == 0
    return y, y_out


R0 = np.array([D_SEP * math.cos(2.4), D_SEP * math.sin(2.4), -30e3])
V0 = np.array([4.0, -3.2, 100.0])


def test_propagator_vs_scipy_dop853_1mm():
    pk = pack_force_model(BODY, ForceModel(gravity="degree2", srp=True))
    srp = P_SUN_1AU * AU ** 2 * 1.6 * BOX_AREA / 4.0
    assert pk.ff[K_SRP] == pytest.approx(srp, rel=1e-14)
    t_eval = np.linspace(0.0, 600.0, 61)
    ref = solve_ivp(scipy_rhs(PAR, srp), (0.0, 600.0), np.concatenate([R0, V0]),
                    method="DOP853", rtol=1e-12, atol=1e-9, t_eval=t_eval)
    y, ys = _prop(pk, R0, V0, 600.0, t_out=t_eval)
    assert np.linalg.norm(y[:3] - ref.y[:3, -1]) <= 1e-3
    # sampled (dense output) too
    assert np.max(np.linalg.norm(ys[:, :3] - ref.y[:3].T, axis=1)) <= 1e-3
    assert np.max(np.linalg.norm(ys[:, 3:] - ref.y[3:].T, axis=1)) <= 1e-5
    # a closer, more curved arc (30-60 km), 600 s
    r0 = np.array([35e3, 5e3, 8e3])
    v0 = np.array([-2.0, 3.5, 0.5])
    ref = solve_ivp(scipy_rhs(PAR, srp), (0.0, 600.0), np.concatenate([r0, v0]),
                    method="DOP853", rtol=1e-12, atol=1e-9)
    y, _ = _prop(pk, r0, v0, 600.0)
    assert np.linalg.norm(y[:3] - ref.y[:3, -1]) <= 1e-3


def test_stm_vs_central_finite_differences():
    pk = pack_force_model(BODY, ForceModel(gravity="degree2", srp=True))
    for r0, v0 in ((R0, V0), (np.array([35e3, 5e3, 8e3]), np.array([-2.0, 3.5, 0.5]))):
        y, _ = _prop(pk, r0, v0, 600.0, stm=True, rtol=1e-13, atol=1e-12)
        phi = y[6:].reshape(6, 6)
        fd = np.zeros((6, 6))
        for k in range(6):
            h = 1e-2 if k < 3 else 1e-4
            dp = np.zeros(6)
            dp[k] = h
            yp, _ = _prop(pk, r0 + dp[:3], v0 + dp[3:], 600.0, rtol=1e-13, atol=1e-12)
            ym, _ = _prop(pk, r0 - dp[:3], v0 - dp[3:], 600.0, rtol=1e-13, atol=1e-12)
            fd[:, k] = (yp[:6] - ym[:6]) / (2 * h)
        prv, prv_fd = phi[:3, 3:], fd[:3, 3:]
        assert np.linalg.norm(prv - prv_fd) <= 1e-6 * np.linalg.norm(prv_fd)
        assert np.linalg.norm(phi - fd) <= 1e-5 * np.linalg.norm(fd)


def _jacobi(params, states):
    r, v = states[:, :3], states[:, 3:]
    w = params.spin_rate
    return (0.5 * np.sum(v * v, axis=1) - 0.5 * w * w * (r[:, 0] ** 2 + r[:, 1] ** 2)
            - params.mu / np.linalg.norm(r, axis=1))


@pytest.mark.parametrize("r0,v0", [(R0, V0), (np.array([30e3, 0.0, 5e3]),
                                              np.array([0.0, -3.0, 0.4]))])
def test_jacobi_integral_point_mass(r0, v0):
    pk = pack_force_model(BODY, ForceModel(gravity="point_mass", srp=False))
    t = np.arange(6001) * 0.1
    y, ys = _prop(pk, r0, v0, 600.0, t_out=t)
    j = _jacobi(PAR, ys)
    j_end = _jacobi(PAR, y[None, :6])[0]
    assert np.max(np.abs(j - j[0])) <= 1e-10 * abs(j[0])
    assert abs(j_end - j[0]) <= 1e-10 * abs(j[0])
    # the samples sit on the grid: first is the initial state
    assert np.array_equal(ys[0], np.concatenate([r0, v0]))


def test_ephemeris_kepler_and_frames():
    el = np.array([PAR.orbit_a, PAR.orbit_e, PAR.orbit_i, PAR.orbit_raan, PAR.orbit_argp,
                   PAR.orbit_nu])
    # true anomaly 0 at t0: perihelion
    assert np.linalg.norm(body_position_N(0.0, el, MU_SUN)) == pytest.approx(
        PAR.orbit_a * (1 - PAR.orbit_e), rel=1e-14)
    period = 2 * math.pi * math.sqrt(PAR.orbit_a ** 3 / MU_SUN)
    assert np.linalg.norm(body_position_N(0.5 * period, el, MU_SUN)) == pytest.approx(
        PAR.orbit_a * (1 + PAR.orbit_e), rel=1e-12)
    p1 = body_position_N(period, el, MU_SUN)
    assert np.allclose(p1, body_position_N(0.0, el, MU_SUN), rtol=0, atol=1e-6 * PAR.orbit_a)
    # pole = orbit normal: the Sun stays in the body equator (z_T = 0)
    t = np.linspace(0.0, 0.3 * period, 50)
    s = sun_direction_T(PAR, t)
    assert np.allclose(np.linalg.norm(s, axis=1), 1.0, atol=1e-14)
    assert np.max(np.abs(s[:, 2])) < 1e-12
    # over 600 s the Sun turns about +z_T at -(spin rate) (+ the slow orbital rate)
    s2 = sun_direction_T(PAR, [0.0, 600.0])
    ang = math.atan2(s2[1, 1], s2[1, 0]) - math.atan2(s2[0, 1], s2[0, 0])
    n_orb = math.sqrt(MU_SUN * PAR.orbit_a * (1 - PAR.orbit_e ** 2)) / (PAR.orbit_a * (1 - PAR.orbit_e)) ** 2
    assert ang == pytest.approx(-(PAR.spin_rate - n_orb) * 600.0, rel=1e-9)
    # a configured pole along the ecliptic north: Sun z_T = -sin(orbit latitude)
    import dataclasses
    p2 = dataclasses.replace(PAR, pole_ra=0.0, pole_dec=math.pi / 2)
    rb = body_position_N(1e6, el, MU_SUN)
    s3 = sun_direction_T(p2, [1e6])[0]
    assert s3[2] == pytest.approx(-rb[2] / np.linalg.norm(rb), abs=1e-14)


def test_fast_ephemeris_matches_reference_path():
    """The propagator's precomputed Sun direction equals the element-by-element one."""
    import dataclasses

    from ideas_hpc.core.dynamics.ephemeris import ephemeris_precompute, sun_T, sun_T_fast
    for par in (PAR, dataclasses.replace(PAR, pole_ra=0.4, pole_dec=1.1, prime_meridian=2.0)):
        el = np.array([par.orbit_a, par.orbit_e, par.orbit_i, par.orbit_raan, par.orbit_argp,
                       par.orbit_nu])
        pole = np.array([par.pole_ra or 0.0, par.pole_dec or 0.0,
                         1.0 if par.pole_ra is not None else 0.0])
        eph = ephemeris_precompute(el, pole, par.spin_rate, par.prime_meridian, MU_SUN)
        for t in (0.0, 300.0, 3.7e6, 2.0e7):
            a, b = np.zeros(3), np.zeros(3)
            d1 = sun_T(t, el, pole, par.spin_rate, par.prime_meridian, MU_SUN, a)
            d2 = sun_T_fast(t, eph, b)
            assert d2 == pytest.approx(d1, rel=1e-12)
            assert np.allclose(a, b, rtol=0, atol=1e-12)
