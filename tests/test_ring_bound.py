"""Ring-gap bound (ideas_hpc.core.design.ring_gaps, ideas_hpc.design.ring_bound) against brute force.

The bound must (1) equal its own definition, the least weight of groups lying
inside one gap over every N-subset, computed by enumeration; (2) never exceed
the true missed weight of any subset (validity); (3) respect the separation;
(4) stay above the proven optimum of the integer programme on eros001708.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ideas_hpc.design import CandidateBank, max_coverage, min_swarm
from ideas_hpc.design.bank import reduce_problem
from ideas_hpc.design.ring_bound import gap_matrix, ring_bound, swap_search


def _circle_bank(seed: int, k: int = 18, v: int = 60) -> CandidateBank:
    """Vertices seen by one or two circular arcs of candidates (as on the real ring)."""
    rng = np.random.default_rng(seed)
    masks = np.zeros((k, v), dtype=bool)
    for j in range(v):
        for _ in range(1 + (rng.random() < 0.35)):
            a, ln = rng.integers(k), rng.integers(1, k // 2)
            masks[(a + np.arange(ln)) % k, j] = True
    areas = rng.uniform(0.5, 2.0, v)
    return CandidateBank(theta=np.arange(k) * 2 * np.pi / k, masks=masks, areas=areas,
                         step_rad=2 * np.pi / k, d_sep_m=1e5)


def _inside_one_gap(masks, subset, k):
    """(V,) bool: every candidate seeing the vertex lies strictly inside one gap of the subset."""
    p = np.sort(subset)
    gap_of = np.full(k, -1)                       # gap index of each grid angle, -1 on a member
    for i, a in enumerate(p):
        b = p[(i + 1) % p.size] + (k if i + 1 == p.size else 0)
        gap_of[np.arange(a + 1, b) % k] = i
    out = np.zeros(masks.shape[1], dtype=bool)
    for j in range(masks.shape[1]):
        g = gap_of[masks[:, j]]
        out[j] = g.size > 0 and (g >= 0).all() and (g == g[0]).all()
    return out


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("m", [0, 1, 2])
def test_bound_is_the_least_gap_miss_and_never_above_the_truth(seed, m):
    bank = _circle_bank(seed)
    k = bank.n_candidates
    red = reduce_problem(bank.masks, bank.areas, merge_candidates=False)
    rb = ring_bound(bank, red, m, 5)
    w = bank.areas / bank.areas.sum()
    seen = bank.masks.any(axis=0)
    for n in range(1, 6):
        best_gap, best_true = np.inf, -1.0
        for s in itertools.combinations(range(k), n):
            s = np.array(s)
            d = np.abs(s[:, None] - s[None, :])
            if m and (np.minimum(d, k - d)[np.triu_indices(n, 1)] <= m).any():
                continue
            gap_miss = w[_inside_one_gap(bank.masks, s, k) & seen].sum()
            true_cov = w[bank.masks[s].any(axis=0)].sum()
            assert gap_miss <= w[seen].sum() - true_cov + 1e-12     # validity, every subset
            best_gap = min(best_gap, gap_miss)
            best_true = max(best_true, true_cov)
        assert rb.upper[n] == pytest.approx(w[seen].sum() - best_gap, abs=1e-12)
        assert rb.upper[n] >= best_true - 1e-12
        sw = rb.swarm(n)
        dd = np.abs(sw[:, None] - sw[None, :])
        assert sw.size == n and (np.minimum(dd, k - dd)[np.triu_indices(n, 1)] > m).all()


def test_gap_matrix_counts_each_group_inside_an_arc():
    # one group seen by candidates {2, 3}, another by {0, 5} on a 6-circle
    cover = np.zeros((6, 2), dtype=bool)
    cover[[2, 3], 0] = True
    cover[[0, 5], 1] = True
    M = gap_matrix(cover, np.array([0.25, 0.5]))
    assert M[1, 3] == 0.25 and M[1, 2] == 0.0          # (1, 4) holds {2, 3}; (1, 3) does not
    assert M[4, 3] == 0.5 and M[4, 2] == 0.0           # (4, 7) = {5, 0}
    assert M[1, 6] == 0.75                             # all but 1: both groups inside
    assert M[2, 6] == 0.5                              # all but 2: {0, 5} inside, {2, 3} not
    assert (np.diff(M, axis=1) >= 0).all()


@pytest.mark.parametrize("seed", range(4))
def test_gap_matrix_equals_its_definition_by_brute_force(seed):
    # M[i, d] = weight of the groups whose candidates all lie in the open arc
    # (i, i + d), checked set by set; dyadic weights make every sum exact
    rng = np.random.default_rng(seed)
    k, g = 16, 40
    cover = np.zeros((k, g), dtype=bool)
    for j in range(g):
        for _ in range(1 + (rng.random() < 0.4)):
            a, ln = rng.integers(k), rng.integers(1, k)
            cover[(a + np.arange(ln)) % k, j] = True
    cover[:, 0] = True                                  # seen by all: never inside an arc
    w = rng.integers(1, 64, g) / 1024.0
    M = gap_matrix(cover, w)
    for i in range(k):
        for d in range(k + 1):
            arc = {(i + t) % k for t in range(1, d)}
            want = sum(w[j] for j in range(g)
                       if not cover[:, j].all() and set(np.flatnonzero(cover[:, j])) <= arc)
            assert M[i, d] == want, (i, d)


def test_swap_search_keeps_size_and_separation_and_never_gets_worse():
    bank = _circle_bank(7, k=24)
    start = np.array([0, 1, 2])
    sw, c = swap_search(bank, start, 2)
    d = np.abs(sw[:, None] - sw[None, :])
    assert sw.size == 3 and (np.minimum(d, 24 - d)[np.triu_indices(3, 1)] > 2).all()
    assert c >= bank.coverage([start])[0] and c == pytest.approx(bank.coverage([sw])[0])


@pytest.mark.parametrize("seed", range(8))
def test_min_swarm_with_the_ring_proof_matches_enumeration(seed):
    bank = _circle_bank(seed, k=20, v=80)
    need = bank.reach - 0.01
    res = min_swarm(bank, target=bank.reach, eps_tol=0.01, n_max=10)
    cov = {n: max(bank.coverage([list(s) for s in itertools.combinations(range(20), n)]))
           for n in range(1, res.n + 1)}
    assert res.status == "optimal" and cov[res.n] >= need - 1e-12
    assert res.n == 1 or cov[res.n - 1] < need


def test_bound_is_above_the_proven_optimum_on_eros(eros1708):
    from test_design_exact import eros_bank

    bank = eros_bank(True, 1.0)
    red = reduce_problem(bank.masks, bank.areas, merge_candidates=False)
    rb = ring_bound(bank, red, 0, 4)
    for n in range(1, 5):
        assert rb.upper[n] >= max_coverage(bank, n).coverage - 1e-12


def test_swarm_above_the_bound_is_proven_by_the_programme():
    """When the bound is loose, the swap search's larger swarm is kept and HiGHS only
    has to rule out the sizes below it; its infeasibility proves that swarm optimal."""
    from types import SimpleNamespace

    from ideas_hpc.design.exact import _min_result, prepare
    from ideas_hpc.mapping.requirement import threshold_of

    bank = _circle_bank(3, k=20, v=80)
    exact = min_swarm(bank, target=bank.reach, eps_tol=0.01, n_max=10)
    red, m = prepare(bank, 0.0)
    above = exact.indices
    infeasible = SimpleNamespace(x=None, status=2, message="infeasible", mip_dual_bound=None)
    r = _min_result(bank, red, infeasible, 0.1, threshold_of(bank.reach, 0.01), 10, m,
                    exact.n - 1, above)
    assert r.status == "optimal" and r.n == exact.n and r.gap == 0.0
    stopped = SimpleNamespace(x=None, status=1, message="time", mip_dual_bound=exact.n - 1.5)
    r = _min_result(bank, red, stopped, 0.1, threshold_of(bank.reach, 0.01), 10, m,
                    exact.n - 2, above)
    assert r.status == "time_limit" and r.bound == exact.n - 1 and r.n == exact.n


@pytest.mark.parametrize("seed", range(3))
def test_redundancy_polish_keeps_the_target_and_no_swap_adds_overlap(seed):
    from ideas_hpc.design.ring_bound import redundancy_polish

    bank = _circle_bank(seed, k=20, v=80)
    need = bank.reach - 0.05
    m = 1
    w = bank.areas / bank.areas.sum()
    twice = lambda s: w[bank.masks[list(s)].sum(axis=0) >= 2].sum()   # noqa: E731

    def separated(s):
        s = np.asarray(s)
        dd = np.abs(s[:, None] - s[None, :])
        return not (np.minimum(dd, 20 - dd)[np.triu_indices(s.size, 1)] <= m).any()

    # the start: the first smallest swarm with grid distances > m reaching need (brute force),
    # so the separation is held throughout, never dropped
    start = None
    for size in range(1, 11):
        combos = np.array(list(itertools.combinations(range(20), size)))
        ok = [c for c, cov in zip(combos, bank.masks[combos].any(axis=1) @ w)
              if cov >= need and separated(c)]
        if ok:
            start = ok[0]
            break
    assert start is not None
    out = redundancy_polish(bank, start, m, need)
    assert out.size == start.size and bank.coverage([out])[0] >= need - 1e-12
    assert separated(out)
    assert twice(out) >= twice(start) - 1e-15
    for p in range(out.size):                     # brute force: a local optimum
        for c in range(20):
            if c in out:
                continue
            s = np.sort(np.r_[np.delete(out, p), c])
            dd = np.abs(s[:, None] - s[None, :])
            if (np.minimum(dd, 20 - dd)[np.triu_indices(s.size, 1)] <= m).any():
                continue
            if bank.coverage([s])[0] >= need:
                assert twice(s) <= twice(out) + 1e-12


@pytest.mark.parametrize("seed", range(3))
def test_redundancy_polish_never_breaks_the_separation(seed):
    # Spread members and a loose target: overlap is gained by moving members together,
    # so every swap the polish wants runs into the separation (grid distances > m).
    from ideas_hpc.design.ring_bound import redundancy_polish

    bank = _circle_bank(seed, k=20, v=80)
    w = bank.areas / bank.areas.sum()
    twice = lambda s: w[bank.masks[list(s)].sum(axis=0) >= 2].sum()   # noqa: E731
    start, m = np.array([0, 5, 10, 15]), 1
    need = w[bank.masks[start].any(axis=0)].sum() - 0.3
    out = redundancy_polish(bank, start, m, need)
    assert twice(out) > twice(start)                 # the polish did move members
    assert out.size == start.size and w[bank.masks[out].any(axis=0)].sum() >= need - 1e-12
    d = np.abs(out[:, None] - out[None, :])
    assert (np.minimum(d, 20 - d)[np.triu_indices(out.size, 1)] > m).all(), out
