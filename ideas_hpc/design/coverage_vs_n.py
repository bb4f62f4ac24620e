"""The coverage-versus-N trade curve: the best coverage any N spacecraft reach.

For ``N = 1 .. N_max`` the max-coverage integer programme
(:func:`~ideas_hpc.design.exact.max_coverage`) gives the highest union
coverage ``C*(N)`` of N grid candidates and a swarm reaching it, each proven.
Two shortcuts keep the curve cheap, both exact:

* ``N = 1`` is an enumeration of the single candidates;
* ``C*(N) <= C_all`` (the union of every candidate) and ``C*`` is
  non-decreasing (the programme allows ``sum x <= N``, separation or not);
  once ``C*(N) = C_all`` the curve stays there, proven by that upper bound,
  and later N reuse that swarm.

Before each integer programme, the ring-gap bound
(:mod:`ideas_hpc.design.ring_bound`) gives a proven upper bound ``U(N)`` and
a swap search a swarm; when the swarm reaches ``U(N)`` the point is proven
without the programme, otherwise the programme's bound is capped by ``U(N)``.

``time_limit`` is the budget of the whole curve. Points the integer programme
cannot prove within what is left (large shape models) hold the best swarm
found, or the greedy swarm once the budget is spent, with ``status``
``time_limit`` and an upper bound (``C_all`` at worst), so the curve always
finishes and says how good each point is.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import steps
from ideas_hpc.design.bank import CandidateBank
from ideas_hpc.design.exact import greedy_swarm, max_coverage, prepare
from ideas_hpc.design.ring_bound import ring_bound, swap_search

REACH_TOL = 1e-12


@dataclass
class CoverageCurve:
    """``coverage[i]`` is the best coverage of ``n[i]`` spacecraft; ``swarms[i]`` grid indices."""

    n: np.ndarray
    coverage: np.ndarray
    bound: np.ndarray
    gap: np.ndarray
    status: list
    swarms: list
    solve_time: float

    def include(self, swarm: np.ndarray, coverage: float) -> None:
        """Take a swarm found elsewhere (the design itself) where it beats the curve.

        Points at its size and above that it beats get it, with their gaps to
        their (unchanged, still proven) bounds recomputed.
        """
        for i in range(self.n.size):
            if self.n[i] >= swarm.size and coverage > self.coverage[i]:
                self.coverage[i] = coverage
                self.swarms[i] = np.asarray(swarm)
                b = self.bound[i]
                self.gap[i] = max(0.0, (b - coverage) / b) if b > 0 else 0.0
                if self.gap[i] < 1e-9:
                    self.gap[i], self.status[i] = 0.0, "optimal"

    def angles(self, theta: np.ndarray) -> np.ndarray:
        """(len(n), max n) swarm angles, rad, NaN-padded."""
        out = np.full((self.n.size, int(self.n.max())), np.nan)
        for i, s in enumerate(self.swarms):
            out[i, :len(s)] = theta[s]
        return out


def coverage_curve(bank: CandidateBank, n_max: int, *, min_separation: float = 0.0,
                   time_limit: float | None = None) -> CoverageCurve:
    """Proven best coverage for every swarm size from 1 to ``n_max`` (module docstring)."""
    if np.ndim(bank.areas) != 1:     # one world's curve; worlds by scenario: the bank's P
        raise InputError("the coverage curve is of one world: vertex areas (V,), got shape "
                         f"{np.shape(bank.areas)}", field="areas")
    t0 = time.perf_counter()
    prepared = prepare(bank, min_separation)
    reach = bank.reach
    full = prepared[0] if np.array_equal(prepared[0].rep, np.arange(bank.n_candidates)) \
        else prepare(bank, min_separation, redundancy=True)[0]
    rb = ring_bound(bank, full, prepared[1], int(n_max), reach - REACH_TOL)
    single = bank.coverage([[k] for k in range(bank.n_candidates)])
    best = int(np.argmax(single))
    cov, bnd, gap, status, swarms = [float(single[best])], [float(single[best])], [0.0], \
        ["optimal"], [np.array([best])]
    for n in steps(range(2, int(n_max) + 1), "coverage vs N", unit="N"):
        if cov[-1] >= reach - REACH_TOL and status[-1] == "optimal":
            cov.append(cov[-1])
            bnd.append(reach)
            gap.append(0.0)
            status.append("optimal")
            swarms.append(swarms[-1])
            continue
        left = None if time_limit is None else time_limit - (time.perf_counter() - t0)
        if left is not None and left <= 0.0:
            idx, c = greedy_swarm(bank, prepared[1], n)
            c = float(bank.coverage([idx])[0])
            if c < cov[-1]:      # C* is non-decreasing: the previous swarm also fits
                idx, c = swarms[-1], cov[-1]
            ok = c >= reach - REACH_TOL
            cov.append(c)
            bnd.append(reach)
            gap.append(0.0 if ok else (reach - c) / reach)
            status.append("optimal" if ok else "time_limit")
            swarms.append(idx)
            continue
        upper = reach if rb is None or n >= rb.upper.size else float(rb.upper[n])
        sw, c = _swap_point(bank, rb, prepared[1], n, swarms[-1])
        if c >= upper - REACH_TOL:   # meets the ring bound: proven without a programme
            cov.append(c)
            bnd.append(upper)
            gap.append(0.0)
            status.append("optimal")
            swarms.append(sw)
            continue
        r = max_coverage(bank, n, time_limit=left, prepared=prepared)
        if c > r.coverage:
            r.coverage, r.indices = c, sw
        r.bound = min(r.bound, upper)
        r.gap = (r.bound - r.coverage) / r.bound if r.bound > 0 else 0.0
        if r.gap < 1e-9:
            r.status, r.gap, r.bound = "optimal", 0.0, r.coverage
        if r.coverage >= reach - REACH_TOL:  # the union bound proves it whatever HiGHS says
            r.status, r.gap, r.bound = "optimal", 0.0, reach
        elif r.coverage < cov[-1]:  # stopped early below the previous point, which also fits
            r.coverage, r.indices = cov[-1], swarms[-1]
            r.gap = (r.bound - r.coverage) / r.bound if r.bound > 0 else 0.0
        cov.append(r.coverage)
        bnd.append(r.bound)
        gap.append(r.gap)
        status.append(r.status)
        swarms.append(r.indices)
    return CoverageCurve(n=np.arange(1, int(n_max) + 1), coverage=np.array(cov),
                         bound=np.array(bnd), gap=np.array(gap), status=status, swarms=swarms,
                         solve_time=time.perf_counter() - t0)


def _swap_point(bank: CandidateBank, rb, m: int, n: int, prev: np.ndarray):
    """Best swap-search swarm of n, started from the greedy swarm and the ring bound's swarm."""
    starts = [greedy_swarm(bank, m, n)[0]]
    if rb is not None and n < rb.upper.size:
        starts.append(rb.swarm(n))
    best, best_c = None, -1.0
    for st in starts:
        if st.size != n or np.any(st < 0):
            continue
        sw, c = swap_search(bank, st, m)
        if c > best_c:
            best, best_c = sw, c
    return (prev, -1.0) if best is None else (best, best_c)
