"""The statistics of the success-probability designer against exact answers:
the betting lower confidence bound (its 3/4 bet cap matters for data at the edges of
[0, 1]: a bet above 1 can stake more than the capital) against the exact
Clopper-Pearson bound and by its coverage over many simulated samples, and the
failure bound against exact enumeration of the failure sets."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest
from scipy import stats

from ideas_hpc.design.reliability_stats import (failure_upper_bound, hoeffding_lower_bound,
                                                lower_confidence_bound)


def _clopper_pearson_lower(k, n, confidence):
    return 0.0 if k == 0 else float(stats.beta.ppf(1.0 - confidence, k, n - k + 1))


@pytest.mark.parametrize("p,n", [(0.98, 256), (0.9, 256), (0.995, 512)])
def test_bound_on_bernoulli_data_is_near_the_exact_one(p, n):
    # All data at the edges (0 or 1): the exact Clopper-Pearson bound is the yardstick.
    rng = np.random.default_rng(7)
    x = (rng.uniform(size=n) < p).astype(float)
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # no log1p of a value <= -1
        lo = lower_confidence_bound(x, 0.95)
    cp = _clopper_pearson_lower(int(x.sum()), n, 0.95)
    assert np.isfinite(lo) and lo <= x.mean()
    # within 0.03 of the exact bound, and tighter than Hoeffding's
    assert lo >= cp - 0.03, (lo, cp)
    assert lo >= hoeffding_lower_bound(x, 0.95) - 1e-12


@pytest.mark.parametrize("p", [1.0, 0.0])
def test_bound_on_constant_edge_data(p):
    x = np.full(200, p)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lo = lower_confidence_bound(x, 0.95)
    if p == 1.0:    # exact: the lower bound for 200 successes in 200 is 0.05^(1/200)
        assert 0.05 ** (1 / 200) - 0.03 <= lo < 1.0
    else:
        assert lo == 0.0


def test_coverage_at_the_edges():
    # P(L <= p) >= 95 % over 400 samples of Bernoulli(0.97), 128 values each; a bound
    # with alpha swapped for the confidence, or unbounded bets, misses more often.
    rng = np.random.default_rng(3)
    p, reps = 0.97, 400
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lo = np.array([lower_confidence_bound((rng.uniform(size=128) < p).astype(float), 0.95)
                       for _ in range(reps)])
    miss = np.mean(lo > p)
    assert miss <= 0.05 + 3 * np.sqrt(0.05 * 0.95 / reps), miss


def test_failure_bound_against_enumeration():
    # sum over every failure set F of P(F) U_{n - |F|}, enumerated set by set
    n, p_f = 6, 0.13
    u = np.array([0.0, 0.1, 0.3, 0.55, 0.8, 0.9, 0.97])
    exact = 0.0
    for fails in itertools.product((0, 1), repeat=n):
        j = sum(fails)
        exact += p_f ** j * (1 - p_f) ** (n - j) * u[n - j]
    assert failure_upper_bound(n, u, p_f) == pytest.approx(exact, rel=1e-12)
    # U_m = m / n bounds the mean surviving fraction 1 - p_f exactly
    assert failure_upper_bound(n, np.arange(n + 1) / n, p_f) == pytest.approx(1 - p_f, rel=1e-12)
