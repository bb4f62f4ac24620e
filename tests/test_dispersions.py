"""The declared Monte Carlo dispersions: their distributions over many draws (moments and
Kolmogorov-Smirnov tests), reproducibility per sample, the stream layout pinned, the store layout."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from ideas_hpc.attitude import initial_conditions

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.montecarlo.dispersions import (DISPERSION_ORDER, DISPERSION_VARS, DISPERSIONS,
                                              draw_sample)
from test_campaign_mc import MC, SHORT, one_worker  # noqa: F401  (module fixture)

THETA = np.array([0.2, 1.7, 2.4])


@pytest.fixture(scope="module")
def campaign():
    c = load(MC, SHORT)
    return c, setup_from_campaign(c)


DRAWS = 3000


def _draws(mc, setup, seed=11, n=DRAWS):
    """Store values and perturbations of samples 0 .. n-1, stacked along a first axis."""
    vals, perts = zip(*(draw_sample(mc, seed, k, THETA, setup) for k in range(n)))
    return ({key: np.array([v[key] for v in vals]) for key in vals[0]},
            {key: [p[key] for p in perts] for key in perts[0]})


def _normal(x, sigma, name):
    """Zero-mean normal of standard deviation ``sigma``: mean, spread and a KS test."""
    x = np.asarray(x, dtype=np.float64).ravel()
    se = sigma / np.sqrt(x.size)
    assert abs(x.mean()) < 5 * se, name
    assert abs(x.std() - sigma) < 5 * sigma / np.sqrt(2 * x.size), name
    assert stats.kstest(x / sigma, "norm").pvalue > 1e-4, name


def test_dispersions_have_their_declared_distributions(campaign):
    # moments over many samples, of what the store records and of what the flyby
    # receives; distinct sigmas so that two dispersions swapped are seen
    c, setup = campaign
    mc = dataclasses.replace(c.config.monte_carlo, sigma_c20_pct=5.0, sigma_c22_pct=2.0,
                             sigma_gm_pct=0.5, sigma_position_m=100.0,
                             sigma_velocity_m_s=3e-3, sigma_misalignment_rad=2e-3)
    v, pert = _draws(mc, setup)
    p = setup.body.params
    over = {key: np.array([o[key] for o in pert["params_override"]])
            for key in ("c20", "c22", "mu", "reflectivity")}
    for name, nominal, pct in (("c20", p.c20, 5.0), ("c22", p.c22, 2.0), ("mu", p.mu, 0.5)):
        for x in (v[name], over[name]):
            _normal(x / nominal - 1.0, pct / 100.0, name)
    z = np.c_[v["c20"] / p.c20, v["c22"] / p.c22, v["mu"] / p.mu, v["reflectivity"]]
    r = np.corrcoef(z.T)[np.triu_indices(4, 1)]
    assert np.all(np.abs(r) < 5 / np.sqrt(DRAWS)), r        # drawn independently
    lo, hi = mc.reflectivity_min, mc.reflectivity_max
    for x in (v["reflectivity"], over["reflectivity"]):
        assert lo <= x.min() and x.max() <= hi
        assert stats.kstest((x - lo) / (hi - lo), "uniform").pvalue > 1e-4
    for key, sig in (("position_error", 100.0), ("velocity_error", 3e-3)):
        assert v[key].shape == (DRAWS, THETA.size, 3)
        _normal(v[key], sig, key)
        _normal(np.array(pert[key + "_T"]), sig, key + "_T")
    # misalignment: a PRV of angle sigma * N(0, 1) about a uniform random axis: its norm
    # is sigma |N(0, 1)|, its direction uniform (mean 0, covariance I / 3)
    for m in (v["misalignment_prv"], np.array(pert["misalignment_prv"])):
        m = m.reshape(-1, 3)
        norm = np.linalg.norm(m, axis=1)
        assert stats.kstest(norm / 2e-3, "halfnorm").pvalue > 1e-4
        u = m / norm[:, None]
        assert np.all(np.abs(u.mean(axis=0)) < 5 / np.sqrt(3 * len(u)))
        assert np.allclose(np.cov(u.T), np.eye(3) / 3, atol=5 * 0.3 / np.sqrt(len(u)))
    # attitude: the sample's own stream, the attitude package's initial conditions
    for k in (0, 17):
        s0, w0, W0 = initial_conditions(11, k, THETA.size)
        np.testing.assert_array_equal(v["sigma0"][k], s0)
        np.testing.assert_array_equal(v["omega0"][k], w0)
        np.testing.assert_array_equal(np.array(pert["ics"][k][2]), W0)


@pytest.mark.parametrize("k_fail,prob", [(1, 0.0), (0, 0.3), (2, 0.25)])
def test_failures_have_their_declared_law(campaign, k_fail, prob):
    # k certain failures on a uniform random subset, then each survivor fails with prob
    c, setup = campaign
    mc = dataclasses.replace(c.config.monte_carlo, failures_k=k_fail, failure_probability=prob)
    v, pert = _draws(mc, setup)
    act = v["active"]
    assert act.shape == (DRAWS, THETA.size) and act.dtype == bool
    np.testing.assert_array_equal(np.array(pert["active"]), act)
    np.testing.assert_array_equal(v["n_failed"], (~act).sum(axis=1))
    assert np.all(v["n_failed"] >= k_fail)
    n = THETA.size
    p_fail = k_fail / n + (1 - k_fail / n) * prob          # per spacecraft
    se = np.sqrt(p_fail * (1 - p_fail) / DRAWS)
    assert np.all(np.abs((~act).mean(axis=0) - p_fail) < 5 * se), (~act).mean(axis=0)
    extra = v["n_failed"] - k_fail                          # Binomial(n - k, prob)
    assert abs(extra.mean() - (n - k_fail) * prob) < 5 * np.sqrt((n - k_fail) * prob *
                                                                 (1 - prob) / DRAWS + 1e-30)


def _pattern_law(n, k, prob):
    """Exact probability of each failure pattern (bit i set: spacecraft i failed): k certain
    failures on a uniformly chosen k-subset, then each other spacecraft fails independently."""
    from itertools import combinations
    from math import comb

    law = np.zeros(2 ** n)
    for pat in range(2 ** n):
        failed = {i for i in range(n) if pat >> i & 1}
        for chosen in combinations(range(n), k):
            if set(chosen) <= failed:
                m = len(failed) - k
                law[pat] += prob ** m * (1 - prob) ** (n - k - m) / comb(n, k)
    return law


@pytest.mark.parametrize("k_fail,prob", [(0, 0.3), (1, 0.3)])
def test_failures_are_independent(campaign, k_fail, prob):
    # Marginals alone cannot tell independent failures from a common cause (one uniform for
    # the whole swarm): the joint rate of two spacecraft, the variance of n_failed and the
    # frequency of every failure pattern against exact enumeration can.
    c, setup = campaign
    mc = dataclasses.replace(c.config.monte_carlo, failures_k=k_fail, failure_probability=prob)
    draws = 6000
    v, _ = _draws(mc, setup, seed=23, n=draws)
    failed = ~v["active"]
    n = THETA.size
    law = _pattern_law(n, k_fail, prob)
    assert law.sum() == pytest.approx(1.0, abs=1e-12)
    # joint failure of spacecraft 0 and 1 (k = 0: p_f^2 = 0.09; common cause: p_f = 0.3)
    p01 = sum(law[pat] for pat in range(2 ** n) if pat & 0b11 == 0b11)
    se01 = np.sqrt(p01 * (1 - p01) / draws)
    assert abs((failed[:, 0] & failed[:, 1]).mean() - p01) < 5 * se01
    # Var n_failed: (n - k) p (1 - p) for independent failures
    var = (n - k_fail) * prob * (1 - prob)
    assert abs(v["n_failed"].var() - var) < 0.1 * var
    # every pattern's frequency against the exact law (chi-square, 7 d.o.f.)
    code = (failed * (1 << np.arange(n))).sum(axis=1)
    counts = np.bincount(code, minlength=2 ** n)
    keep = law > 0
    assert counts[~keep].sum() == 0
    assert stats.chisquare(counts[keep], law[keep] * draws).pvalue > 1e-3


def test_draws_are_reproducible_per_sample_and_pinned(campaign):
    # Sample k alone equals sample k drawn after others; other k and other seeds differ.
    # The pinned numbers guard the stream layout (DISPERSIONS is append-only: an entry
    # inserted or swapped earlier changes every existing campaign's samples).
    c, setup = campaign
    mc = c.config.monte_carlo
    a, _ = draw_sample(mc, 99, 5, THETA, setup)
    for k in range(5):
        draw_sample(mc, 99, k, THETA, setup)
    b, _ = draw_sample(mc, 99, 5, THETA, setup)
    other, _ = draw_sample(mc, 99, 6, THETA, setup)
    seed2, _ = draw_sample(mc, 100, 5, THETA, setup)
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
    for name in ("c20", "reflectivity", "position_error", "misalignment_prv", "sigma0"):
        assert not np.array_equal(a[name], other[name]) and not np.array_equal(a[name],
                                                                             seed2[name]), name
    assert a["c20"] == pytest.approx(-29152116.04692344, rel=1e-13)
    assert a["c22"] == pytest.approx(14603814.684986878, rel=1e-13)
    assert a["mu"] == pytest.approx(444312.5547105581, rel=1e-13)
    assert a["reflectivity"] == pytest.approx(0.6969016435658099, rel=1e-13)
    np.testing.assert_allclose(a["position_error"][0],
                               [38.399064165733016, 49.215105719295515, 77.37351289463867],
                               rtol=1e-13)
    np.testing.assert_allclose(a["misalignment_prv"][1], [-0.00080993157431505,
                                                          0.00092970695401297,
                                                          -0.00077788288838918], rtol=1e-12)
    np.testing.assert_array_equal(a["active"], [True, False, True])


def test_switching_a_dispersion_off_does_not_shift_the_others(campaign):
    c, setup = campaign
    mc = c.config.monte_carlo
    on, _ = draw_sample(mc, 7, 3, THETA, setup)
    off, _ = draw_sample(dataclasses.replace(mc, sigma_c20_pct=0.0, sigma_position_m=0.0), 7, 3,
                         THETA,
                         setup)
    assert off["c20"] == setup.body.params.c20 and not off["position_error"].any()
    for name in ("c22", "mu", "reflectivity", "velocity_error", "active", "misalignment_prv",
                 "sigma0"):
        np.testing.assert_array_equal(on[name], off[name], err_msg=name)


def test_declared_list_is_the_store_layout(one_worker):  # noqa: F811
    ds = xr.open_zarr(one_worker)
    assert tuple(ds.attrs["dispersion_order"]) == DISPERSION_ORDER
    assert len(set(DISPERSION_ORDER)) == len(DISPERSIONS)
    for var in DISPERSION_VARS:
        assert ds[var.name].dims == ("sample", *var.dims), var.name
        assert ds[var.name].dtype == np.dtype(var.dtype), var.name
        assert ds[var.name].attrs.get("units") == var.units, var.name
