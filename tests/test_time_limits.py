"""Time limits that bind on purpose (issue 23, item 2).

Each time-limit path of the certified designers runs with a limit that must
bind: a budget of 1 ns (spent before the first programme, whatever the
machine's speed) or a solver stub that reports HiGHS's time-out, as HiGHS
does, with the incumbent it had. Every test asserts the ``time_limit`` status,
a gap > 0, a proven bound on the right side of the true optimum (enumeration)
and a valid swarm. The small problems' optimality, asserted unconditionally
with limits far above need, is in tests/test_design_exact.py and
tests/test_design_stereo.py.
"""

from __future__ import annotations

import itertools
from types import SimpleNamespace

import numpy as np
import pytest

import ideas_hpc.design.exact as ex
import ideas_hpc.design.stereo as st
from design_oracle import subset_coverage
from ideas_hpc.design import CandidateBank, coverage_curve, failure_tolerant, min_swarm
from ideas_hpc.base.errors import InputError
from test_design_stereo import _bank as stereo_bank
from test_design_stereo import _best as stereo_best
from test_design_stereo import _truth as stereo_truth

BINDS = 1e-9   # s: spent before any integer programme starts
EPS = 0.02


def _toy(seed=1, k=16, v=100, p=0.3) -> CandidateBank:
    """Random masks on which the ring bound does not decide the design (N = 6, bound 3)."""
    rng = np.random.default_rng(seed)
    step = 2 * np.pi / k
    return CandidateBank(theta=step * np.arange(k), masks=rng.uniform(size=(k, v)) < p,
                         areas=rng.uniform(1, 3, v), step_rad=step, d_sep_m=1e4)


def _best_of_size(bank, n):
    """Highest coverage of any n candidates, by enumeration."""
    sets = np.array(list(itertools.combinations(range(bank.n_candidates), n)))
    return float(subset_coverage(bank.masks, bank.areas, sets).max())


def _fewest(bank, need):
    """Fewest candidates reaching ``need``, by enumeration."""
    for n in range(1, bank.n_candidates + 1):
        if _best_of_size(bank, n) >= need - 1e-12:
            return n
    raise AssertionError("unreachable")


def _timed_out(record):
    """A stub of ``solve`` that runs HiGHS and reports a time-out with its incumbent and a
    weak dual bound (1.5 spacecraft, the programme's LP bound at an early stop)."""
    real = ex.solve

    def stub(c, constraints, integrality, time_limit, lower=None):
        record.append(time_limit)
        res, dt = real(c, constraints, integrality, None, lower)
        return SimpleNamespace(x=res.x, status=1, message="Time limit reached",
                               mip_dual_bound=1.5), dt
    return stub


def test_coverage_curve_budget_spent_gives_time_limited_points():
    bank = _toy()
    reach = bank.reach
    curve = coverage_curve(bank, 5, time_limit=BINDS)
    assert curve.status[0] == "optimal"                 # N = 1 is an enumeration
    assert curve.coverage[0] == pytest.approx(_best_of_size(bank, 1), abs=1e-12)
    assert curve.status[1:] == ["time_limit"] * 4
    for i in range(1, 5):
        n = i + 1
        best = _best_of_size(bank, n)
        assert curve.gap[i] > 0.0 and curve.coverage[i] < best + 1e-12 <= curve.bound[i] + 2e-12
        assert curve.bound[i] <= reach + 1e-12
        assert curve.gap[i] == pytest.approx((curve.bound[i] - curve.coverage[i]) / curve.bound[i])
        sw = np.asarray(curve.swarms[i])
        assert 1 <= sw.size <= n and np.unique(sw).size == sw.size
        assert subset_coverage(bank.masks, bank.areas, sw[None, :])[0] == pytest.approx(
            curve.coverage[i], abs=1e-12)
    assert np.all(np.diff(curve.coverage) >= -1e-12)


def test_min_swarm_programme_timed_out_keeps_its_incumbent_and_bound(monkeypatch):
    bank = _toy()
    need = bank.reach - EPS
    n_true = _fewest(bank, need)
    calls: list = []
    monkeypatch.setattr(ex, "solve", _timed_out(calls))
    res = min_swarm(bank, target=bank.reach, eps_tol=EPS, time_limit=7.0)
    assert calls and all(t is not None and 0 < t <= 7.0 for t in calls)   # budget passed on
    assert res.status == "time_limit" and res.gap > 0.0
    assert 1 <= res.bound <= n_true <= res.n
    assert res.gap == pytest.approx((res.n - res.bound) / res.n)
    assert subset_coverage(bank.masks, bank.areas, res.indices[None, :])[0] >= need - 1e-12
    assert res.coverage == pytest.approx(
        subset_coverage(bank.masks, bank.areas, res.indices[None, :])[0], abs=1e-12)


def test_max_coverage_timed_out_without_incumbent_is_greedy_with_a_gap(monkeypatch):
    bank = _toy()
    best = _best_of_size(bank, 3)
    calls: list = []
    monkeypatch.setattr(ex, "solve", lambda *a, **k: (calls.append(a[3]), (SimpleNamespace(
        x=None, status=1, message="Time limit reached", mip_dual_bound=None), 1.0))[1])
    r = ex.max_coverage(bank, 3, time_limit=3.0)
    assert calls == [3.0]
    assert r.status == "time_limit" and r.gap > 0.0
    assert r.n <= 3 and r.coverage <= best + 1e-12 <= r.bound + 2e-12
    assert r.coverage == pytest.approx(
        subset_coverage(bank.masks, bank.areas, r.indices[None, :])[0], abs=1e-12)


def test_failure_tolerant_budget_spent_gives_a_tolerant_swarm_with_its_gap():
    bank = _toy()
    need = bank.reach - EPS
    exact = failure_tolerant(bank, 1, target=bank.reach, eps_tol=EPS, n_max=16, time_limit=600)
    assert exact.status == "optimal"
    res = failure_tolerant(bank, 1, target=bank.reach, eps_tol=EPS, n_max=16, time_limit=BINDS)
    assert res.status == "time_limit" and res.gap > 0.0
    assert res.bound <= exact.n <= res.n
    assert res.gap == pytest.approx((res.n - res.bound) / res.n)
    s = res.indices.tolist()
    for f in s:     # every single failure leaves the need (brute force)
        rest = np.array([[j for j in s if j != f]])
        assert subset_coverage(bank.masks, bank.areas, rest)[0] >= need - 1e-12
    assert res.worst_failure_coverage >= need - 1e-12


@pytest.mark.parametrize("incumbent", [False, True], ids=["no-incumbent", "incumbent"])
def test_stereo_designer_timed_out(monkeypatch, incumbent):
    sb = stereo_bank(0)
    need = sb.reach - EPS
    n_true = next(n for n in range(1, 15) if stereo_best(sb, n) >= need - 1e-12)
    calls: list = []
    real = st.solve

    def stub(c, constraints, integrality, time_limit, lower=None):
        calls.append(time_limit)
        res, dt = real(c, constraints, integrality, None, lower)
        return SimpleNamespace(x=res.x if incumbent else None, status=1,
                               message="Time limit reached", mip_dual_bound=1.5), dt

    monkeypatch.setattr(st, "solve", stub)
    res = st.min_swarm_stereo(sb, target=sb.reach, eps_tol=EPS, n_max=14, time_limit=4.0)
    assert calls == [4.0]
    assert res.status == "time_limit" and res.gap > 0.0
    assert 1 <= res.bound <= n_true <= res.n
    assert res.gap == pytest.approx((res.n - res.bound) / res.n)
    assert stereo_truth(sb, res.indices) >= need - 1e-12


def test_failure_tolerant_out_of_time_and_n_max_names_the_time_limit():
    # The greedy completion after a spent budget needs 11 spacecraft, one more than the
    # optimum 10 = n_max: an input error naming the time limit, not a traceback.
    bank = _toy()
    assert failure_tolerant(bank, 1, target=bank.reach, eps_tol=EPS, n_max=10,
                            time_limit=600).n == 10
    with pytest.raises(InputError, match="within the time limit") as ei:
        failure_tolerant(bank, 1, target=bank.reach, eps_tol=EPS, n_max=10, time_limit=BINDS)
    assert ei.value.field == "time_limit" and ei.value.message.endswith("`time_limit` or `n_max`")
