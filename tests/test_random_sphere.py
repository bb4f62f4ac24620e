"""The Gaussian random sphere against its theory (Muinonen et al. 1996; SPEC 7f).

Oracles: the closed form of the Gaussian law's Legendre coefficients,
``c_l = (2l + 1) exp(-a) i_l(a)``, ``a = 1 / ell^2`` (the Legendre expansion of
``exp(a x)``, Abramowitz & Stegun 10.2.36 / scipy's ``spherical_in``), scipy's complex
spherical harmonics, and Monte Carlo over many draws with the known truth: ``Var s = beta^2``,
``E exp(s - beta^2/2) = 1``, and the correlation ``(C(gamma) - c_0) / (1 - c_0)`` of the
degrees ``l >= 1``. Each statistic is a mean over independent draws (one number per
draw), so its standard error comes from the draws themselves.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import eval_legendre, spherical_in, sph_harm_y

from ideas_hpc.base import seeds
from ideas_hpc.body.random_sphere import (GaussianRandomSphere, ShapeFamily, choose_l_max,
                                          legendre_coefficients, radial_graph_problem,
                                          real_harmonics)
from ideas_hpc.body.target_prior import ellipsoid_nominal

DEG = math.pi / 180.0


def _closed_form_c(gamma_deg: float, l_max: int) -> np.ndarray:
    ell = 2.0 * math.sin(0.5 * gamma_deg * DEG)
    a = 1.0 / ell ** 2
    ls = np.arange(l_max + 1)
    return (2 * ls + 1) * math.exp(-a) * spherical_in(ls, a)


@pytest.mark.parametrize("gamma_deg", [15.0, 33.0, 60.0])
def test_gaussian_legendre_coefficients_match_the_closed_form(gamma_deg):
    fam = ShapeFamily(correlation_angle_rad=gamma_deg * DEG)
    c = legendre_coefficients(fam, 40)
    # round-off of the quadrature is absolute (~1e-14 of C(0) = 1), not relative
    np.testing.assert_allclose(c, _closed_form_c(gamma_deg, 40), rtol=1e-10, atol=2e-13)


@pytest.mark.parametrize("gamma_deg", [20.0, 33.0])
def test_legendre_series_reproduces_the_correlation_function(gamma_deg):
    fam = ShapeFamily(correlation_angle_rad=gamma_deg * DEG)
    c = legendre_coefficients(fam, 60)
    ell = 2.0 * math.sin(0.5 * gamma_deg * DEG)
    for g in np.radians([0.0, 5.0, 20.0, 33.0, 60.0, 90.0, 150.0, 180.0]):
        series = sum(c[l] * eval_legendre(l, math.cos(g)) for l in range(61))
        assert series == pytest.approx(math.exp(-2.0 * math.sin(g / 2) ** 2 / ell ** 2),
                                       abs=1e-12)


def test_l_max_rule_keeps_the_stated_variance():
    fam = ShapeFamily()                       # Gamma = 33 deg, variance_lost = 1e-6
    L = choose_l_max(fam)
    c = _closed_form_c(33.0, 80)
    lost = c[L + 1:].sum() / (1.0 - c[0])
    lost_one_less = c[L:].sum() / (1.0 - c[0])
    assert lost <= 1e-6 < lost_one_less       # the smallest such degree
    grs = GaussianRandomSphere(fam, np.eye(3))
    assert grs.variance_kept == pytest.approx(1.0 - lost, abs=1e-12)
    with pytest.raises(Exception, match="l_max"):
        choose_l_max(ShapeFamily(law="power", nu=2.0))   # 1/L tail: too slow for 1e-6 at 40


def test_real_harmonics_are_scipys_orthonormal_harmonics():
    rng = np.random.default_rng(5)
    u = rng.normal(size=(50, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    theta, phi = np.arccos(u[:, 2]), np.arctan2(u[:, 1], u[:, 0])
    y = real_harmonics(u, 12)
    for l in range(13):
        for m in range(-l, l + 1):
            z = sph_harm_y(l, abs(m), theta, phi)       # complex, Condon-Shortley phase
            want = (z.real if m == 0 else
                    math.sqrt(2) * (-1) ** m * (z.real if m > 0 else z.imag))
            np.testing.assert_allclose(y[:, l * l + l + m], want, atol=1e-12)


def _unit_sphere_draws(family: ShapeFamily, n: int, resolution: int = 3):
    nominal = ellipsoid_nominal((1.0, 1.0, 1.0), resolution)
    u = nominal.directions
    grs = GaussianRandomSphere(family, u)
    s = np.array([grs.log_radius(seeds.world_rng(11, k, seeds.WORLD_SHAPE)) for k in range(n)])
    return u, s


def _mean_and_se(per_draw: np.ndarray) -> tuple[float, float]:
    return float(per_draw.mean()), float(per_draw.std(ddof=1) / math.sqrt(per_draw.size))


@pytest.mark.parametrize("family", [ShapeFamily(), ShapeFamily(sigma=0.4, law="power", nu=4.0,
                                                               variance_lost=1e-4)],
                         ids=["gaussian", "power"])
def test_log_radius_variance_and_lognormal_mean(family):
    _, s = _unit_sphere_draws(family, 3000)
    var, se = _mean_and_se((s ** 2).mean(axis=1))           # E s = 0 is known
    assert abs(var - family.beta2) < 4.0 * se, (var, family.beta2, se)
    m, se_m = _mean_and_se(np.exp(s - 0.5 * family.beta2).mean(axis=1))
    assert abs(m - 1.0) < 4.0 * se_m, (m, se_m)
    mean_s, se_s = _mean_and_se(s.mean(axis=1))
    assert abs(mean_s) < 4.0 * se_s


def test_correlation_of_the_log_radius_at_angular_separations():
    fam = ShapeFamily()
    u, s = _unit_sphere_draws(fam, 3000)
    ell = fam.correlation_length
    a = 1.0 / ell ** 2
    c0 = (1.0 - math.exp(-2.0 * a)) / (2.0 * a)                 # e^-a i_0(a) = e^-a sinh(a)/a
    cos_sep = np.clip(u @ u.T, -1.0, 1.0)
    sep = np.arccos(cos_sep)
    iu = np.triu_indices(len(u), 1)
    for g_deg in (8.0, 20.0, 33.0, 60.0, 120.0):
        pick = np.abs(sep[iu] - g_deg * DEG) < 1.0 * DEG
        i, j = iu[0][pick], iu[1][pick]
        assert i.size > 50
        truth_each = (np.exp(-2.0 * np.sin(sep[i, j] / 2) ** 2 / ell ** 2) - c0) / (1.0 - c0)
        truth = float(truth_each.mean())
        emp, se = _mean_and_se((s[:, i] * s[:, j]).mean(axis=1) / fam.beta2)
        assert abs(emp - truth) < 4.0 * se + 2e-3, (g_deg, emp, truth, se)


def test_radial_graph_check_rejects_a_fold_and_accepts_a_perturbed_sphere():
    nominal = ellipsoid_nominal((1.0, 1.0, 1.0), 2)
    v, f = nominal.base_vertices, nominal.faces
    assert radial_graph_problem(v, f) is None
    bumpy = v * np.exp(0.5 * np.random.default_rng(1).standard_normal(len(v)))[:, None]
    assert radial_graph_problem(bumpy, f) is None
    folded = v.copy()
    folded[0] *= -0.3                        # one vertex pushed through the centre
    assert radial_graph_problem(folded, f) is not None
    assert radial_graph_problem(v, f[:, [0, 2, 1]]) is not None     # wound inward
    assert radial_graph_problem(v + np.array([2.0, 0, 0]), f) is not None   # centre outside
