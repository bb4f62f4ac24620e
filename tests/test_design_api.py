"""One way to call a designer (issue 30): ``minimize(problem, settings)`` picks the
registered designer and returns one :class:`DesignResult`; oracles by enumeration."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pytest

from ideas_hpc.design import CandidateBank
from ideas_hpc.design.api import (DESIGNERS, CoverSettings, Designer, DesignResult,
                                  NadirGAProblem, NadirGASettings, designer_for, minimize)
from ideas_hpc.design.ga.genetic import run_nadir_ga


def _toy(seed=3, k=10, v=60, p=0.4):
    rng = np.random.default_rng(seed)
    step = 2 * np.pi / k
    return CandidateBank(theta=step * np.arange(k), masks=rng.uniform(size=(k, v)) < p,
                         areas=rng.uniform(1, 3, v), step_rad=step, d_sep_m=1e4)


def _all_sets(k, n_top):
    return [np.array(c) for n in range(1, n_top + 1) for c in itertools.combinations(range(k), n)]


def test_plain_settings_run_the_exact_designer_and_reach_the_enumerated_minimum():
    bank = _toy()
    need = bank.reach - 0.03
    sets = _all_sets(bank.n_candidates, 6)
    covs = bank.coverage(sets)
    n_true = min(len(s) for s, c in zip(sets, covs) if c >= need - 1e-12)
    res = minimize(bank, CoverSettings(target=bank.reach, eps_tol=0.03, n_max=6))
    assert isinstance(res, DesignResult) and res.designer == "exact"
    assert res.n == n_true and res.status == "optimal" and res.bound == n_true
    assert res.value == pytest.approx(float(bank.coverage([res.indices])[0]), abs=1e-12)
    np.testing.assert_allclose(res.swarm_rad, bank.theta[res.indices])
    assert res.timings_s["wall"] >= res.timings_s["solve"] >= 0.0


def test_failures_tolerated_pick_the_tolerant_designer_and_survive_every_failure():
    bank = _toy(seed=5, k=9, p=0.45)
    need = bank.reach - 0.05
    res = minimize(bank, CoverSettings(target=bank.reach, eps_tol=0.05, n_max=8,
                                       failures_tolerated=1))
    assert res.designer == "failure-tolerant"
    for lost in range(res.n):           # every single failure keeps the threshold
        alive = np.delete(res.indices, lost)
        assert bank.coverage([alive])[0] >= need - 1e-12
    # and no smaller swarm does (enumeration)
    for s in _all_sets(bank.n_candidates, res.n - 1):
        if s.size >= 2:
            worst = min(bank.coverage([np.delete(s, j)])[0] for j in range(s.size))
            assert worst < need - 1e-12


def test_unknown_settings_name_every_registered_designer():
    with pytest.raises(ValueError, match="no designer") as ei:
        designer_for(_toy(), object())
    for name in ("exact", "success-probability", "ga-nadir", "pareto"):
        assert name in str(ei.value)


def test_a_new_designer_is_one_register_call(monkeypatch):
    @dataclass(frozen=True)
    class FirstK:
        n: int

    def solve(bank, s, progress):
        idx = np.arange(s.n)
        return DesignResult("first-k", bank.theta[idx], idx, s.n, "heuristic", np.nan, np.nan,
                            float(bank.coverage([idx])[0]))

    monkeypatch.setitem(DESIGNERS, "first-k", Designer("first-k", FirstK, CandidateBank, solve))
    bank = _toy()
    res = minimize(bank, FirstK(3))
    assert res.designer == "first-k" and res.n == 3 and "wall" in res.timings_s
    assert res.value == pytest.approx(float(bank.coverage([np.arange(3)])[0]))


def test_ga_keyword_call_and_settings_call_agree():
    bank = _toy()

    def evaluate(genomes):
        n = np.rint(genomes[:, 0]).astype(int)
        idx = [np.unique(np.rint(g[1:1 + m] / bank.step_rad).astype(int) % 10)
               for g, m in zip(genomes, n)]
        return bank.coverage(idx), n

    kw = dict(n_max=4, population=6, generations=3, seed=7, eps_tol=0.05,
              angle_step=bank.step_rad, target=bank.reach)
    old = run_nadir_ga(evaluate, **kw)
    new = minimize(NadirGAProblem(evaluate), NadirGASettings.from_keywords(**kw))
    assert new.designer == "ga-nadir" and new.n == old.best_swarm_size
    np.testing.assert_array_equal(new.detail.best_genome, old.best_genome)
    np.testing.assert_array_equal(new.detail.best_fitness, old.best_fitness)
