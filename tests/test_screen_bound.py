"""The screen over all scenarios (issue 29, proof at scale): its relaxation never
undercounts, its list is every swarm a brute force finds, and what it settles agrees
with the exhaustive optimum on small rings."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ideas_hpc.core.design.ring_screen import relaxed_probabilities, screen_swarms
from ideas_hpc.design.reliability import Evaluator, all_swarms, min_swarm_reliable
from ideas_hpc.design.screen_bound import screen_size
from ring_problems import (NoProgramme, exact_covers, mt_of, no_tolerance, relaxed_covers,
                           ring_rows)

P_F = 0.1
NEEDS = (0.9, 0.95)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("need", NEEDS)
def test_screen_lists_every_swarm_the_brute_force_counts(seed, need):
    rows, a = ring_rows(seed)
    w = a / a.sum()
    mt, slack = mt_of(rows, a, need)
    s_n, c_n = rows.shape[:2]
    for n in (2, 3):
        brute = {}
        for sw in itertools.combinations(range(c_n), n):
            relax = sum(relaxed_covers(rows[s], w, sw, need) for s in range(s_n))
            exact = sum(exact_covers(rows[s], w, sw, need) for s in range(s_n))
            assert relax >= exact, sw          # the relaxation never undercounts
            brute[sw] = relax
        for thr in (1, s_n // 2, s_n):
            want = {sw: c for sw, c in brute.items() if c >= thr}
            for step in (1, 5):     # any x0 order coprime with K lists the same swarms
                got, counts, complete = screen_swarms(mt, slack + 1e-9, n, 0, thr, 10_000,
                                                      10 ** 9, step)
                assert complete
                assert {tuple(map(int, g)): int(c) for g, c in zip(got, counts)} == want


@pytest.mark.parametrize("seed", range(4))
def test_relaxed_probability_never_below_the_exact_one(seed):
    rows, a = ring_rows(seed)
    need = 0.9
    mt, slack = mt_of(rows, a, need)
    ev = Evaluator(rows, a / a.sum(), need, P_F)
    sw = all_swarms(rows.shape[1], 4, 0)
    relaxed = relaxed_probabilities(mt, slack + 1e-9, sw, P_F)
    exact = ev(sw)
    assert np.all(relaxed >= exact - 1e-12)
    assert exact.max() > 0.0                   # the comparison is not all zeros


def test_screen_settles_what_the_exhaustive_search_says():
    """Oracle: every n-swarm scored exactly. A size the screen proves short has no swarm
    at p (and its bound is above the true best); a swarm it finds is at p."""
    proofs = finds = 0
    for seed in range(6):
        rows, a = ring_rows(seed)
        w = a / a.sum()
        for need in NEEDS:
            mt, slack = mt_of(rows, a, need)
            ev = Evaluator(rows, a / a.sum(), need, P_F)
            for n in (3, 4, 5):
                best = float(ev(all_swarms(rows.shape[1], n, 0)).max())
                u = [0.0] + [float(np.mean([any(exact_covers(rows[s], w, sw, need) for sw in
                                                itertools.combinations(range(rows.shape[1]), k))
                                            for s in range(rows.shape[0])]))
                             for k in range(1, n + 1)]
                for p in (0.5, 0.7, 0.8, 0.9):
                    out = screen_size(mt, slack, ev, n, p, P_F, u, 0)
                    if out.proven_short:
                        proofs += 1
                        assert best < p and out.upper >= best - 1e-12, (seed, need, n, p)
                    if out.swarm is not None:
                        finds += 1
                        assert float(ev([out.swarm])[0]) >= p - 1e-12
                    if best < p:
                        assert out.swarm is None
    assert proofs > 0 and finds > 0            # both branches are exercised


@pytest.mark.parametrize("seed", range(3))
def test_designer_with_the_screen_reaches_the_exhaustive_optimum(seed):
    """No enumeration and no scenario programme (enumerate_budget=0, ring bounds only, 12
    scenarios: above the tolerance bound's 8): when the designer says optimal, its N is
    the exhaustive fewest N with P_bank >= p."""
    rows, a = ring_rows(seed, s_n=12)
    need, p = 0.9, 0.8
    ev = Evaluator(rows, a / a.sum(), need, P_F)
    fewest = next(n for n in range(1, 9)
                  if float(ev(all_swarms(rows.shape[1], n, 0)).max()) >= p - 1e-12)
    r = min_swarm_reliable(rows, a, p=p, p_f=P_F, need=need, n_max=8, enumerate_budget=0,
                           bound_solver=NoProgramme(12), tolerance_solver=no_tolerance)
    assert r.probability >= p - 1e-12
    assert r.status == "optimal" and r.n == fewest
    # the level bound alone (U_m <= 1) leaves N - 1 open: the screen settled it
    assert any("by the screen over all scenarios" in note for note in r.notes)
