"""Failure-tolerant design: the fewest spacecraft that survive any k failures.

A swarm ``S`` tolerates ``k`` failures when every ``S \\ F`` with ``F`` a
k-subset of ``S`` still covers ``A_target - eps_tol``. Counting only vertices
seen ``k + 1`` times is sufficient but not necessary (two failures rarely
remove the same vertices), so this module solves the exact problem.

Exact formulation, one *scenario* per candidate k-set ``F`` (grid indices)::

    y^F_g <= sum_{c sees g, c not in F} x_c           for groups g seen by F
    sum_{g unseen by F} w_g y_g + sum_{g seen by F} w_g y^F_g
        >= (A_target - eps_tol) * (sum_{j in F} x_j - (k - 1))

When all of ``F`` fly, the right side is the target and the left side
undercounts the union of ``S \\ F``; otherwise the right side is <= 0 and the
row is void. With every k-set of candidates this is exactly the problem, but
there are ``C(K, k)`` of them, so they are generated lazily: solve with the
scenarios known so far (a relaxation, hence a proven lower bound on N),
enumerate every failure of the optimum, add the violated ones (and their
shifts by a few grid steps, which the next optimum tends to try), repeat. The
first optimum that survives all its failures is the proven optimum.
"""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
from scipy import sparse
from scipy.optimize import LinearConstraint

from ..errors import InputError
from .bank import CandidateBank
from .exact import FEAS_TOL, ExactResult, _separation_rows, check_time_limit, prepare, solve

#: Grid shifts of each violated failure set added with it (valid rows, fewer rounds).
SHIFTS = (-2, -1, 1, 2)


def worst_failure(bank: CandidateBank, swarm, k: int):
    """Enumerate every k-subset failure of ``swarm`` (grid indices).

    Returns ``(worst coverage, failed grid indices of the worst case, coverages of all
    subsets (C(N, k),), the subsets (C(N, k), k) as grid indices)``.
    """
    s = np.asarray(swarm, dtype=np.int64)
    if k <= 0:
        cov = float(bank.coverage([s])[0])
        return cov, np.zeros(0, dtype=np.int64), np.array([cov]), np.zeros((1, 0), np.int64)
    if k >= s.size:
        return 0.0, s.copy(), np.array([0.0]), s[None, :].copy()
    fails = np.array(list(itertools.combinations(range(s.size), k)), dtype=np.int64)
    keep = np.ones((fails.shape[0], s.size), dtype=bool)
    np.put_along_axis(keep, fails, False, axis=1)
    rest = s[np.nonzero(keep)[1].reshape(fails.shape[0], s.size - k)]
    cov = bank.coverage(list(rest))
    i = int(np.argmin(cov))
    return float(cov[i]), s[fails[i]], cov, s[fails]


def failure_tolerant(bank: CandidateBank, k: int, *, target: float, eps_tol: float,
                     n_max: int, min_separation: float = 0.0,
                     time_limit: float | None = None) -> ExactResult:
    """Fewest spacecraft keeping ``target - eps_tol`` after any ``k`` failures (module docstring)."""
    time_limit = check_time_limit(time_limit)
    if k < 0:
        raise InputError(f"must be >= 0, got {k}", field="design.failures_tolerated")
    if k >= n_max:
        raise InputError(f"{k} failures need more than design.n_max = {n_max} spacecraft",
                         field="design.failures_tolerated")
    t0 = time.perf_counter()
    deadline = None if time_limit is None else t0 + time_limit
    red, m = prepare(bank, min_separation, redundancy=True)
    need = target - eps_tol
    nc, g = red.rep.size, red.n_groups
    scen: list[tuple] = []
    seen_f: set = set()
    rounds, bound, best = 0, k + 1, None
    status = "optimal"
    while True:
        rounds += 1
        left = None if deadline is None else deadline - time.perf_counter()
        if left is not None and left <= 0:
            status = "time_limit"
            break
        c, cons, integ = _master(red, scen, k, need, n_max, m, bank.n_candidates)
        res, _ = solve(c, cons, integ, left)
        if res.x is None:
            if res.status == 2:
                raise InputError(f"no swarm of at most {n_max} spacecraft keeps "
                                 f"{100 * need:.3f} % after any {k} failures",
                                 field="design.failures_tolerated")
            status = "time_limit"
            break
        s = np.sort(red.rep[np.flatnonzero(res.x[:nc] > 0.5)])
        lb = getattr(res, "mip_dual_bound", None)
        if res.status == 0:
            bound = max(bound, s.size)
        elif lb is not None and np.isfinite(lb):
            bound = max(bound, math.ceil(lb - 1e-6))
        worst, _, covs, subsets = worst_failure(bank, s, k)
        bad = subsets[covs < need - 1e-12]
        if bad.size == 0:
            best = s
            status = "optimal" if res.status == 0 else "time_limit"
            break
        for f in bad:
            for d in (0,) + SHIFTS:
                key = tuple(sorted(((f + d) % bank.n_candidates).tolist()))
                if key not in seen_f and len(set(key)) == k:
                    seen_f.add(key)
                    scen.append(key)
        last = s
    if best is None:  # out of time: a feasible swarm by greedy augmentation of the last try
        best = _greedy_complete(bank, last if rounds > 1 else np.zeros(0, np.int64), k, need,
                                n_max)
    n = best.size
    bound = min(bound, n)
    gap = (n - bound) / n
    if gap > 0 and status == "optimal":
        status = "feasible"
    worst, failed, _, _ = worst_failure(bank, best, k)
    cov = float(bank.coverage([best])[0])
    r = ExactResult(indices=best, theta=bank.theta[best], n=n, coverage=cov, target=target,
                    status=status if gap == 0 else (status if status != "optimal" else "feasible"),
                    bound=float(bound), gap=float(gap), solve_time=time.perf_counter() - t0,
                    notes=[f"{rounds} rounds of failure scenarios, {len(scen)} scenarios"])
    r.worst_failure_coverage = worst
    r.worst_failure = failed
    return r


def _master(red, scen, k, need, n_max, m, n_grid):
    """Objective, constraints and integrality of the relaxation with scenarios ``scen``."""
    nc, g = red.rep.size, red.n_groups
    cov_t = sparse.csr_matrix(red.cover.T.astype(np.float64))   # (G, K)
    blocks_rows, rhs_hi, rhs_lo = [], [], []
    extra = [np.flatnonzero(red.cover[list(f)].any(axis=0)) for f in scen]
    n_var = nc + g + sum(e.size for e in extra)
    # nominal cover rows y_g <= sum x
    rows = [sparse.hstack([-cov_t, sparse.identity(g), sparse.csr_matrix((g, n_var - nc - g))])]
    lo = [np.full(g, -np.inf)]
    hi = [np.zeros(g)]
    # nominal coverage
    w0 = np.zeros(n_var)
    w0[nc:nc + g] = red.weight
    rows.append(sparse.csr_matrix(w0[None, :]))
    lo.append([need + FEAS_TOL])
    hi.append([np.inf])
    off = nc + g
    for f, gs in zip(scen, extra):
        e = gs.size
        sub = cov_t[gs].tolil()
        sub[:, list(f)] = 0.0
        rows.append(sparse.hstack([-sub.tocsr(), sparse.csr_matrix((e, off - nc)),
                                   sparse.identity(e), sparse.csr_matrix((e, n_var - off - e))]))
        lo.append(np.full(e, -np.inf))
        hi.append(np.zeros(e))
        w = np.zeros(n_var)
        w[nc:nc + g] = red.weight
        w[nc + gs] = 0.0
        w[off:off + e] = red.weight[gs]
        w[list(f)] = -(need + FEAS_TOL)
        rows.append(sparse.csr_matrix(w[None, :]))
        lo.append([-(need + FEAS_TOL) * (k - 1)])
        hi.append([np.inf])
        off += e
    card = np.zeros(n_var)
    card[:nc] = 1.0
    rows.append(sparse.csr_matrix(card[None, :]))
    lo.append([k + 1])
    hi.append([n_max])
    cons = [LinearConstraint(sparse.vstack(rows, format="csr"), np.concatenate(lo),
                             np.concatenate(hi))]
    sep = _separation_rows(red, m, n_grid, n_var)
    if sep is not None:
        cons.append(sep)
    c = np.zeros(n_var)
    c[:nc] = 1.0
    integ = np.zeros(n_var)
    integ[:nc] = 1
    return c, cons, integ


def _greedy_complete(bank, start, k, need, n_max):
    """Add the candidate that most raises the worst-case coverage until it meets ``need``."""
    s = [int(i) for i in start]
    while len(s) < n_max:
        if len(s) > k and worst_failure(bank, s, k)[0] >= need - 1e-12:
            break
        scores = [worst_failure(bank, s + [j], k)[0] if j not in s else -1.0
                  for j in range(bank.n_candidates)]
        s.append(int(np.argmax(scores)))
    return np.sort(np.array(s, dtype=np.int64))
