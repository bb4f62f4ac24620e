"""Proven bounds from the ring's geometry, and a swap search for swarms that meet them.

The candidates sit on a circle, and what one candidate sees changes slowly with
its angle: on eros001708 and eros022540 in strict mode most vertex groups are
seen by one arc of 120 or more consecutive grid angles, the rest by two arcs.
:func:`ring_bound` turns that into a proven upper bound on the coverage of N
grid candidates (for every N at once). A group whose candidates all lie in
one gap between consecutive swarm members is certainly missed, and that miss
is additive over gaps, so the least such miss is a shortest path over sorted
angles (:mod:`ideas_hpc.core.design.ring_gaps`).

``M[i, d]`` is the weight of the groups inside the open arc ``(i, i + d)``.
A group's candidate set lies in an arc exactly when the arc contains the
complement of one of the group's gaps (its candidate-free runs), itself an
arc. For N >= 2 the swarm's gaps are disjoint and two such complements of
one group always overlap, so no group is counted twice.

The bound is exact in practice on single-arc groups and loose on two-arc
ones. It decides a design when some swarm of the bound's size reaches the
target. :func:`swap_search` looks for one: best-improvement single swaps,
every swap of the swarm scored in one vectorised union (:meth:`CandidateBank.coverage`).
On eros022540 in strict mode the bound proves N >= 4 and the swap search
finds a 4-swarm covering 99.87 % against a need of 99.81 %. The integer
programme had stopped at its time limit with N = 6 there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ideas_hpc.core.design.ring_gaps import gap_matrix_of, ring_gap_bound, ring_gap_swarm
from ideas_hpc.design.bank import CandidateBank, Reduced
from ideas_hpc.mapping.requirement import meets

#: Largest grid on which the O(N K^3) bound is computed (0.25 deg).
MAX_GRID = 1440


def gap_matrix(cover: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """``M[i, d]`` (K, K + 1): weight of the groups inside the open arc ``(i, i + d)``.

    ``cover`` is (K, G) over the full grid (no merged candidates), every group
    seen by some candidate; ``weight`` (G,). Compiled in
    :func:`ideas_hpc.core.design.ring_gaps.gap_matrix_of`.
    """
    return gap_matrix_of(np.ascontiguousarray(cover, dtype=np.bool_),
                         np.ascontiguousarray(weight, dtype=np.float64))


@dataclass
class RingBound:
    """Upper bounds ``upper[n]`` (n = 0 .. computed) on the coverage of n grid candidates."""

    upper: np.ndarray
    tot: np.ndarray
    M: np.ndarray
    m: int
    reach: float

    def n_bound(self, need: float) -> int | None:
        """Fewest spacecraft the bound allows to reach ``need`` (None: beyond the sizes computed).

        A proven lower bound on the fewest covering grid candidates when: the rows are
        one ring's grid in grid order, one row per candidate (:func:`ring_bound_applies`;
        the designer keeps the trivial bound 1 elsewhere); the swarms bounded keep the
        separation ``m`` the bound was computed with; coverage is the union of the
        members' rows (a group inside a gap is missed); "reaches" is
        :func:`~ideas_hpc.mapping.requirement.meets`, the success-probability
        evaluator's comparison (the bound's float sums err far below its margin). The
        designer's ``U_m`` bound
        (:meth:`ideas_hpc.design.reliability.ReliabilityDesigner.cheap_ubar`, the
        fraction of scenarios whose ``n_bound <= m``) rests on exactly these.
        """
        ok = np.flatnonzero(meets(self.upper, need))
        return int(ok[0]) if ok.size else None

    def swarm(self, n: int) -> np.ndarray:
        """The n-swarm of least gap-missed weight (a start for :func:`swap_search`)."""
        s = int(np.argmin(self.tot[n]))
        idx, _ = ring_gap_swarm(self.M, int(n), int(self.m), s)
        return np.sort(idx)


def ring_bound_applies(bank: CandidateBank, red: Reduced) -> bool:
    """The bound needs one row per grid candidate in grid order, on grids up to :data:`MAX_GRID`."""
    k = bank.n_candidates
    return 2 <= k <= MAX_GRID and np.array_equal(red.rep, np.arange(k))


def ring_bound(bank: CandidateBank, red: Reduced, m: int, n_max: int,
               need: float | None = None, extra: int = 0) -> RingBound | None:
    """Proven coverage bounds of 1 .. n_max grid candidates (module docstring).

    ``red`` must hold one row per grid candidate, in grid order (no merging). With
    ``need`` the programme stops ``extra`` sizes after the first size the bound
    cannot exclude.
    Returns None on grids finer than :data:`MAX_GRID` (too slow to be worth it).
    """
    if not ring_bound_applies(bank, red):
        return None
    M = gap_matrix(red.cover, red.weight)
    reach = float(red.weight.sum())
    stop = -1.0 if need is None else reach - need + 1e-12
    tot = ring_gap_bound(M, int(n_max), int(m), float(stop), int(extra))
    upper = reach - tot.min(axis=1)
    upper[0] = 0.0
    computed = np.isfinite(tot.min(axis=1))
    computed[0] = True
    return RingBound(upper=np.where(computed, np.minimum(upper, reach), np.nan)[
        :int(np.flatnonzero(computed)[-1]) + 1], tot=tot, M=M, m=int(m), reach=reach)


def swap_search(bank: CandidateBank, start, m: int, *, need: float | None = None,
                max_rounds: int = 50) -> tuple[np.ndarray, float]:
    """Best-improvement single swaps of a fixed-size swarm, keeping grid distances > ``m``.

    Stops at a local optimum, after ``max_rounds``, or as soon as the coverage
    reaches ``need``. Returns (sorted indices, coverage).
    """
    k = bank.n_candidates
    sw = np.sort(np.asarray(start, dtype=np.int64))
    cur = float(bank.coverage([sw])[0])
    ring = np.arange(k)
    for _ in range(max_rounds):
        if need is not None and cur >= need:
            break
        trials = []
        for p in range(sw.size):
            rest = np.delete(sw, p)
            d = np.abs(ring[:, None] - rest[None, :]) if rest.size else np.zeros((k, 0))
            ok = (np.minimum(d, k - d) > m).all(axis=1) if rest.size else np.ones(k, bool)
            ok[sw] = False
            for c in np.flatnonzero(ok):
                trials.append(np.sort(np.r_[rest, c]))
        if not trials:
            break
        cov = bank.coverage(trials)
        i = int(np.argmax(cov))
        if cov[i] <= cur + 1e-15:
            break
        sw, cur = trials[i], float(cov[i])
    return sw, cur


def redundancy_polish(bank: CandidateBank, swarm, m: int, need: float,
                      max_rounds: int = 50) -> np.ndarray:
    """Among swarms of the same size that still reach ``need``, more area seen twice.

    Every optimal swarm has the same size, but not the same margin: a swarm
    whose members overlap keeps more of the body when one of them fails or
    points off. Best-improvement single swaps maximise the area seen by at
    least two members, keeping coverage >= ``need`` and grid distances > ``m``
    (each swap scored for all candidates at once from the other members'
    counts). Deterministic; returns sorted indices.
    """
    k = bank.n_candidates
    w = bank.areas / bank.areas.sum()
    masks = bank.masks.astype(np.float64)
    sw = np.sort(np.asarray(swarm, dtype=np.int64))
    ring = np.arange(k)

    def score(s):
        cnt = bank.masks[s].sum(axis=0)
        return float(w[cnt >= 2].sum())

    cur = score(sw)
    for _ in range(max_rounds):
        best = (cur + 1e-15, None)
        for p in range(sw.size):
            rest = np.delete(sw, p)
            cnt = bank.masks[rest].sum(axis=0)
            cov = w[cnt >= 1].sum() + masks @ (w * (cnt == 0))
            dbl = w[cnt >= 2].sum() + masks @ (w * (cnt == 1))
            d = np.abs(ring[:, None] - rest[None, :])
            ok = (np.minimum(d, k - d) > m).all(axis=1) & (cov >= need)
            ok[sw] = False
            if ok.any():
                c = int(np.flatnonzero(ok)[np.argmax(dbl[ok])])
                if dbl[c] > best[0]:
                    best = (float(dbl[c]), np.sort(np.r_[rest, c]))
        if best[1] is None:
            break
        cur, sw = best
    return sw
