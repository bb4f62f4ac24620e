"""Pole and rotation of the target prior (SPEC 7f) against exact laws and textbook frames.

Oracles: the Fisher law's mean cosine ``coth(kappa) - 1/kappa`` and its exact CDF of
``w = cos(angle)``, ``(exp(kappa w) - exp(-kappa)) / (2 sinh kappa)`` (Fisher, Proc. R.
Soc. A 217, 1953); a binomial test of the mirror share; the J2000 ecliptic pole at
RA 270 deg, Dec 90 deg - 23.4392911 deg and SPICE's ``J2000 -> ECLIPJ2000`` rotation; the
phase sigma written out by hand, ``2 pi dt sigma_P / P^2``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from ideas_hpc.base import seeds
from ideas_hpc.body.spin_prior import (DCM_N_EQ, PoleEstimate, RotationEstimate,
                                       ecliptic_from_equatorial, equatorial_from_ecliptic,
                                       sample_fisher, unit_from_angles)

DEG = math.pi / 180.0
EPS_DEG = 23.4392911


def test_textbook_points_of_the_ecliptic():
    lon, lat = ecliptic_from_equatorial(270.0 * DEG, (90.0 - EPS_DEG) * DEG)
    assert lat == pytest.approx(90.0 * DEG, abs=1e-7)          # north ecliptic pole
    lon, lat = ecliptic_from_equatorial(0.0, 0.0)
    assert (lon, lat) == pytest.approx((0.0, 0.0), abs=1e-15)    # the equinox
    ra, dec = equatorial_from_ecliptic(90.0 * DEG, 0.0)          # summer solstice point
    assert (ra, dec) == pytest.approx((90.0 * DEG, EPS_DEG * DEG), abs=1e-12)


def test_equatorial_to_ecliptic_is_spices_rotation():
    sp = pytest.importorskip("spiceypy")
    m = np.array(sp.pxform("J2000", "ECLIPJ2000", 0.0))
    np.testing.assert_allclose(DCM_N_EQ, m, atol=1e-12)


@pytest.mark.parametrize("kappa", [0.5, 1.0 / (30.0 * DEG) ** 2, 1.0 / (5.0 * DEG) ** 2, 1e5])
def test_fisher_sampler_mean_cosine_and_cdf(kappa):
    rng = np.random.default_rng(3)
    mu = unit_from_angles(40.0 * DEG, -25.0 * DEG)
    p = sample_fisher(rng, mu, kappa, 20000)
    assert np.allclose(np.linalg.norm(p, axis=1), 1.0)
    w = p @ mu
    truth = 1.0 / math.tanh(kappa) - 1.0 / kappa
    assert abs(w.mean() - truth) < 4.0 * w.std(ddof=1) / math.sqrt(w.size)
    # exact CDF (e^{k w} - e^{-k}) / (e^k - e^{-k}), divided through by e^k for range
    cdf = lambda x: (np.exp(-kappa * (1.0 - x)) * -np.expm1(-kappa * (1.0 + x))  # noqa: E731
                     / -math.expm1(-2.0 * kappa))
    assert stats.kstest(w, cdf).pvalue > 1e-3
    # the azimuth is uniform: the component across mu averages to zero
    e1 = np.cross(mu, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    across = p @ e1
    assert abs(across.mean()) < 4.0 * across.std(ddof=1) / math.sqrt(across.size) + 1e-12


def test_pole_sigma_is_the_per_axis_spread():
    sigma = 3.0 * DEG
    est = PoleEstimate(120.0 * DEG, 35.0 * DEG, sigma, 0.0)
    poles = np.array([est.draw(seeds.world_rng(2, k, seeds.WORLD_POLE))[0]
                      for k in range(6000)])
    mu = est.pole_N
    e1 = np.cross(mu, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(mu, e1)
    for e in (e1, e2):
        x = poles @ e
        # tangent components ~ N(0, sigma^2) to O(sigma^2); sd error of the sample sd ~ 1/sqrt(2n)
        assert abs(x.std() / sigma - 1.0) < 4.0 / math.sqrt(2 * x.size) + 0.01


def test_mirror_pole_share_and_geometry():
    p_mirror = 0.3
    est = PoleEstimate(11.35 * DEG, 17.22 * DEG, 2.0 * DEG, p_mirror)
    lon0, lat0 = ecliptic_from_equatorial(est.ra_rad, est.dec_rad)
    mirror = unit_from_angles(lon0 + math.pi, lat0)              # (lambda + 180, beta) in N
    n = 4000
    poles = np.array([est.draw(seeds.world_rng(4, k, seeds.WORLD_POLE))[0] for k in range(n)])
    near_mirror = (poles @ mirror) > (poles @ est.pole_N)      # the two are 158 deg apart
    assert np.all(np.maximum(poles @ mirror, poles @ est.pole_N) > math.cos(15.0 * DEG))
    assert stats.binomtest(int(near_mirror.sum()), n, p_mirror).pvalue > 1e-4
    exact = PoleEstimate(11.35 * DEG, 17.22 * DEG, 0.0, 1.0)
    p, mirrored = exact.draw(np.random.default_rng(0))
    assert mirrored
    np.testing.assert_allclose(p, mirror, atol=1e-14)
    ra, dec = equatorial_from_ecliptic(lon0 + math.pi, lat0)
    np.testing.assert_allclose(DCM_N_EQ.T @ p, unit_from_angles(ra, dec), atol=1e-14)


P_S = 5.270 * 3600.0


def _rotation(sigma_drift_rad, sigma_epoch_rad=0.0, **kw):
    dt = 60.0 * 86400.0
    sigma_p = sigma_drift_rad * P_S ** 2 / (2.0 * math.pi * dt)   # invert the hand formula
    return RotationEstimate(P_S, sigma_p, 0.7, sigma_epoch_rad, dt, **kw)


def test_phase_sigma_formula_and_draws():
    rot = _rotation(0.4, 0.3)
    hand = math.hypot(0.3, 2.0 * math.pi * rot.dt_epoch_to_tca_s * rot.sigma_period_s / P_S ** 2)
    assert rot.sigma_phase_rad == pytest.approx(hand, rel=1e-12)
    assert rot.sigma_phase_rad == pytest.approx(0.5, rel=1e-12)
    assert not rot.phase_uniform
    draws = np.array([rot.draw(seeds.world_rng(6, k, seeds.WORLD_ROTATION)) for k in range(20000)])
    dev = (draws[:, 1] - rot.phase_tca_nominal_rad + math.pi) % (2.0 * math.pi) - math.pi
    assert abs(dev.std() / 0.5 - 1.0) < 4.0 / math.sqrt(2 * dev.size) + 0.01
    periods = draws[:, 0]
    assert abs(periods.mean() - P_S) < 4.0 * rot.sigma_period_s / math.sqrt(periods.size)
    assert abs(periods.std() / rot.sigma_period_s - 1.0) < 4.0 / math.sqrt(2 * periods.size)


def test_phase_rule_uniform_above_pi():
    below = _rotation(3.0)                 # sigma_phi = 3.0 rad < pi: propagated
    assert not below.phase_uniform
    rng = seeds.world_rng(7, 0, seeds.WORLD_ROTATION)
    for _ in range(200):                   # no epoch error: the phase is the period's image
        period, phase = below.draw(rng)
        want = (0.7 + 2.0 * math.pi * below.dt_epoch_to_tca_s / period) % (2.0 * math.pi)
        assert phase == pytest.approx(want, abs=1e-9)
    above = _rotation(3.3)                 # sigma_phi = 3.3 rad > pi: uniform
    assert above.phase_uniform
    ph = np.array([above.draw(seeds.world_rng(8, k, seeds.WORLD_ROTATION))[1]
                   for k in range(5000)])
    assert stats.kstest(ph, stats.uniform(0.0, 2.0 * math.pi).cdf).pvalue > 1e-3
    # the threshold is the stated, configurable one
    assert _rotation(0.5, uniform_above_rad=0.4).phase_uniform
    assert not _rotation(0.5, uniform_above_rad=0.6).phase_uniform
