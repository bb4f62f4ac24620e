"""Held-out scoring (issue 41, item 4): the held-out mean is unbiased for a swarm chosen on
other scenarios, where the selection's own mean is not (the optimiser's curse), and the
agreement test holds its 95 % level on draws of a known truth."""

from __future__ import annotations

import numpy as np
import pytest

from ideas_hpc.design.holdout import HeldOut, agreement


def test_selection_is_biased_and_the_held_out_mean_is_not():
    """20 swarms of one true P = 0.9 (per-scenario Bernoulli draws); the best of 20 on 200
    selection scenarios sits well above 0.9 on average, its mean on 200 held-out scenarios
    does not (2000 replications)."""
    rng = np.random.default_rng(41)
    sel, held = [], []
    for _ in range(2000):
        draws = rng.random((20, 400)) < 0.9
        best = int(np.argmax(draws[:, :200].mean(axis=1)))
        sel.append(draws[best, :200].mean())
        held.append(draws[best, 200:].mean())
    se = 0.3 / np.sqrt(200 * 2000)
    assert np.mean(sel) - 0.9 > 0.02                      # the curse: about 1.9 sigma of one bank
    assert abs(np.mean(held) - 0.9) < 4 * se, np.mean(held)


def test_agreement_keeps_its_level_and_sees_a_shift():
    rng = np.random.default_rng(7)
    ok = [agreement(rng.random(300) < 0.9, rng.random(256) < 0.9)["agrees"]
          for _ in range(2000)]
    assert 0.93 < np.mean(ok) < 0.97, np.mean(ok)          # 95 % when they share the truth
    off = [agreement(rng.random(300) < 0.82, rng.random(256) < 0.92)["agrees"]
           for _ in range(500)]
    assert np.mean(off) < 0.2                                # a 0.1 shift is seen (3.5 se)
    same = agreement(np.full(10, 0.9), np.full(20, 0.9))
    assert same["agrees"] and same["inside"] and same["se"] < 1e-15
    assert not agreement(np.full(10, 0.9), np.full(20, 0.91))["agrees"]


def test_held_out_evaluator_is_the_exact_one():
    """The held-out P of a swarm is the exact failure-weighted P on those rows (brute force
    over the survivor subsets)."""
    rng = np.random.default_rng(3)
    rows = rng.random((5, 6, 30)) < 0.4
    w = rng.uniform(0.5, 1.5, 30)
    w /= w.sum()
    held = HeldOut.of_rows(rows, w, 0.7, 0.1)
    sw = np.array([0, 2, 5])
    want = []
    for s in range(5):
        tot = 0.0
        for mask in range(8):
            alive = [sw[i] for i in range(3) if mask >> i & 1]
            cov = w[rows[s, alive].any(axis=0)].sum() if alive else 0.0
            if cov >= 0.7 - 1e-12:
                tot += 0.9 ** len(alive) * 0.1 ** (3 - len(alive))
        want.append(tot)
    np.testing.assert_allclose(held.values(sw), want, rtol=0, atol=1e-14)
    assert HeldOut.of_rows(rows[:0], w, 0.7, 0.1) is None
    calls = []
    counted = HeldOut(lambda sw: calls.append(tuple(sw)) or np.ones(4), 4)
    assert counted.probability([5, 2]) == counted.probability([2, 5]) == 1.0
    assert calls == [(2, 5)]                                 # one flight per swarm


def test_prefetch_scores_many_swarms_in_one_batch():
    """Issue 43: the swarms the looks and the curve score are flown together (one set of
    held-out flights for the union of their members). The batch is called once with each
    unscored swarm once (sorted, duplicates and scored ones dropped), and every value is the
    exact one on those rows (the one-at-a-time evaluator of the same rows)."""
    rng = np.random.default_rng(5)
    rows = rng.random((7, 9, 40)) < 0.35
    w = rng.uniform(0.5, 1.5, 40)
    w /= w.sum()
    alone = HeldOut.of_rows(rows, w, 0.6, 0.1)
    batches = []

    def batch(swarms):
        batches.append([tuple(s) for s in swarms])
        union = np.unique(np.concatenate(swarms))
        part = HeldOut.of_rows(rows[:, union], w, 0.6, 0.1)
        return [part.values(np.searchsorted(union, s)) for s in swarms]

    held = HeldOut(lambda sw: alone.values(sw), 7, batch=batch)
    held.values([8, 1])                                     # scored before: not refetched
    held.prefetch([[3, 0, 7], [1, 8], [0, 3, 7], [2, 4, 5, 6]])
    assert batches == [[(0, 3, 7), (2, 4, 5, 6)]]
    for sw in ([7, 3, 0], [1, 8], [6, 5, 4, 2]):
        np.testing.assert_allclose(held.values(sw), alone.values(sw), rtol=0, atol=1e-14)
    held.prefetch([[0, 3, 7]])
    assert len(batches) == 1                                # nothing left to fly


def test_search_keys_keep_the_full_keys_argmax():
    """``Evaluator.scored``, the searches' order keys. Oracle: the full keys ``round(P, 12) + 1e-6 mean coverage`` from plain NumPy
    (survivor subsets enumerated, coverage summed); the argmax (first on ties) and the
    maximum must be the same, on plateaus (every P 0), on spread values and on swarms whose
    P differ by less than the coverage term."""
    from itertools import combinations

    from ideas_hpc.design.reliability_eval import Evaluator
    rng = np.random.default_rng(11)
    # p_f 1e-4: swarms that survive any one loss differ by ~1e-8, inside the tie band
    for need, density, q in ((0.99, 0.2, 0.1), (0.5, 0.3, 0.1), (0.3, 0.5, 0.1),
                             (0.0, 0.3, 0.1), (0.6, 0.45, 1e-4), (0.5, 0.4, 1e-4)):
        rows = rng.random((6, 10, 25)) < density
        w = rng.uniform(0.5, 1.5, 25)
        w /= w.sum()
        ev = Evaluator(rows, w, need, q)
        sw = np.array(list(combinations(range(10), 3)), dtype=np.int64)
        full = []
        for s in sw:
            p, cov = 0.0, 0.0
            for sc in range(6):
                cov += w[rows[sc, s].any(axis=0)].sum() / 6
                for mask in range(8):
                    alive = [s[i] for i in range(3) if mask >> i & 1]
                    c = w[rows[sc, alive].any(axis=0)].sum() if alive else 0.0
                    if c >= need - 1e-12:
                        p += (1 - q) ** len(alive) * q ** (3 - len(alive)) / 6
            full.append(round(p, 12) + 1e-6 * cov)
        full = np.array(full)
        key = ev.scored(sw)
        assert int(np.argmax(key)) == int(np.argmax(full))
        assert key.max() == pytest.approx(full.max(), abs=1e-12)
