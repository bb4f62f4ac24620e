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
there are ``C(K, k)`` of them. For ``k = 1`` all ``K`` rows go in at once;
for ``k >= 2`` they are generated lazily: solve with the
scenarios known so far (a relaxation, hence a proven lower bound on N),
enumerate every failure of the optimum, add the violated ones (and their
shifts by a few grid steps, which the next optimum tends to try), repeat. The
first optimum that survives all its failures is the proven optimum.

A group heavier than the slack (:func:`~ideas_hpc.design.exact.heavy_groups`)
must be seen by at least ``k + 1`` members of a tolerant swarm: were it seen
by ``k`` or fewer, their failure would lose more than the slack. Its
``v^1 .. v^{k+1}`` are fixed to 1 (so ``sum_{c sees g} x_c >= k + 1``), which
removes no tolerant swarm and makes the k = 1 strict design on eros001708
about 4x faster to prove.
"""

from __future__ import annotations

import itertools
import time

import numpy as np
from scipy import sparse
from scipy.optimize import LinearConstraint

from ideas_hpc.base.errors import InputError
from ideas_hpc.design.area import FEAS_TOL, area_floor, area_row
from ideas_hpc.design.bank import CandidateBank
from ideas_hpc.design.exact import (ExactResult, _separation_rows, check_time_limit, heavy_groups,
                    min_swarm, prepare, solve)
from ideas_hpc.mapping.requirement import Threshold, as_threshold, meets

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


def failure_tolerant(bank: CandidateBank, k: int, *, target: float | None = None,
                     eps_tol: float | None = None, n_max: int, min_separation: float = 0.0,
                     time_limit: float | None = None,
                     threshold: Threshold | None = None) -> ExactResult:
    """Fewest spacecraft keeping ``threshold.need`` (or ``target - eps_tol``) after any ``k``
    failures (module docstring).

    Three steps: the proven lower bound ``N_0 + k`` (removing k spacecraft from a
    tolerant swarm leaves a plain design); for ``k >= 2`` a feasible swarm from
    the sufficient (k+1)-fold cover (:func:`_master` without scenarios,
    counting ``v^{k+1}``); then the scenario search over the sizes in between
    (for ``k = 1`` one programme with every single failure), within
    ``time_limit``. ``status`` is ``"optimal"`` only when the bounds meet.
    """
    time_limit = check_time_limit(time_limit)
    thr = as_threshold(threshold, target, eps_tol)
    if k < 0:
        raise InputError(f"must be >= 0, got {k}", field="k")
    if k >= n_max:
        raise InputError(f"{k} failures need more than `n_max` = {n_max} spacecraft",
                         field="k")
    t0 = time.perf_counter()
    deadline = None if time_limit is None else t0 + time_limit
    plain = min_swarm(bank, threshold=thr, n_max=n_max, min_separation=min_separation,
                      time_limit=time_limit)
    bound = plain.n + k if plain.optimal else int(plain.bound) + k
    red, m = prepare(bank, min_separation, redundancy=True)
    need = thr.need
    nc = red.rep.size
    lower = _heavy_lower(red, k, need, nc + (k + 1) * red.n_groups)
    best = None
    # For k = 1 the one programme with every single failure (below) finds and proves the
    # optimum; the (k+1)-fold cover first is worth its solve only when the plain optimum
    # is 2 (eros001708 paper mode: it meets the bound, 3.5 s in all against 6.7 s; strict
    # mode: 7 s for the fold against 6 s for the whole programme).
    if k == 1 and plain.n != 2:
        notes = [f"lower bound {bound} = plain optimum {plain.n} + {k} failure"]
    else:
        c, cons, integ = _master(red, [], k, thr, (k + 1, n_max), m, bank.n_candidates,
                                 fold=True)
        res, _ = solve(c, cons, integ, _left(deadline), lower)
        if res.x is not None:
            best = np.sort(red.rep[np.flatnonzero(res.x[:nc] > 0.5)])
        notes = [f"lower bound {bound} = plain optimum {plain.n} + {k} failures; the "
                 f"{k + 1}-fold cover gives " + (f"{best.size}" if best is not None
                                                 else "nothing")]
    if bound - k == 2 and (best is None or best.size > bound):
        found, done = pair_clique(bank, bound, need, m)
        if found is not None:
            best = found
        elif done:
            bound += 1
        notes.append(f"clique search over the pairs reaching the threshold: "
                     + ("found a swarm of the lower bound" if found is not None else
                        "none of the lower bound" if done else "stopped at its budget"))
    # k = 1: all K single failures at once are K dense rows, which HiGHS handles in one
    # solve (exact, no rounds); for k >= 2 the C(K, k) scenarios are generated lazily.
    scen: list[tuple] = [(j,) for j in range(bank.n_candidates)] if k == 1 else []
    seen_f: set = set(scen)
    rounds = 0
    while best is None or best.size > bound:
        left = _left(deadline)
        if left is not None and left <= 0:
            break
        rounds += 1
        top = n_max if best is None else best.size - 1
        c, cons, integ = _master(red, scen, k, thr, (bound, top), m, bank.n_candidates)
        res, _ = solve(c, cons, integ, left, lower)
        if res.status == 2:          # no swarm of bound..top survives: best is optimal
            if best is None:
                raise InputError(f"no swarm of at most {n_max} spacecraft keeps "
                                 f"{100 * need:.3f} % after any {k} failures",
                                 field="k")
            bound = best.size
            break
        if res.x is None:
            break
        s = np.sort(red.rep[np.flatnonzero(res.x[:nc] > 0.5)])
        if res.status == 0:
            bound = max(bound, s.size)   # optimum of a relaxation
        _, _, covs, subsets = worst_failure(bank, s, k)
        bad = subsets[~meets(covs, need)]
        if bad.size == 0:
            best = s
            break
        for f in bad:
            for d in (0,) + SHIFTS:
                key = tuple(sorted(((f + d) % bank.n_candidates).tolist()))
                if key not in seen_f and len(set(key)) == k:
                    seen_f.add(key)
                    scen.append(key)
    if best is None:  # out of time before any tolerant swarm: greedy completion of the plain one
        best = _greedy_complete(bank, plain.indices, k, need, n_max)
        notes.append("out of time: greedy completion of the plain optimum")
        if best is None:
            raise InputError(f"no {k}-failure-tolerant swarm of at most {n_max} found "
                             f"within the time limit (lower bound {bound} spacecraft); raise "
                             "`time_limit` or `n_max`", field="time_limit")
    if rounds and k == 1:
        notes.append(f"all {len(scen)} single failures in one integer programme")
    elif rounds:
        notes.append(f"{rounds} rounds of lazy failure scenarios ({len(scen)} scenarios)")
    n = best.size
    bound = min(bound, n)
    gap = (n - bound) / n
    status = "optimal" if gap == 0 else ("time_limit" if deadline is not None
                                         and time.perf_counter() >= deadline else "feasible")
    worst, failed, _, _ = worst_failure(bank, best, k)
    if worst < need - FEAS_TOL:
        raise RuntimeError(f"failure-tolerant swarm keeps only {worst!r} < {need!r}")
    r = ExactResult(indices=best, theta=bank.theta[best], n=n,
                    coverage=float(bank.coverage([best])[0]), target=thr.target, status=status,
                    bound=float(bound), gap=float(gap), solve_time=time.perf_counter() - t0,
                    notes=notes)
    r.worst_failure_coverage = worst
    r.worst_failure = failed
    return r


def pair_clique(bank: CandidateBank, size: int, need: float, m: int, budget: int = 200000):
    """A swarm of ``size`` whose every pair covers ``need``, by exhaustive clique search.

    When the plain optimum is 2 and ``size = 2 + k``, a swarm survives any k
    failures iff every pair of it reaches the target (the survivors' union
    contains a pair), so a tolerant swarm of the lower bound is a clique of
    ``size`` in the graph of target-reaching pairs (minus pairs closer than
    the separation). Returns ``(grid indices or None, search complete)``.
    """
    u = (~bank.masks).astype(np.float64)
    w = bank.areas / bank.areas.sum()
    adj = meets(1.0 - (u * w) @ u.T, need)
    n = adj.shape[0]
    np.fill_diagonal(adj, False)
    if m:
        d = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
        adj &= np.minimum(d, n - d) > m
    count = [0]

    def extend(chosen, cand):
        if len(chosen) == size:
            return list(chosen)
        for v in np.flatnonzero(cand):
            count[0] += 1
            if count[0] > budget:
                return None
            nxt = cand & adj[v]
            nxt[:v + 1] = False
            if np.count_nonzero(nxt) >= size - len(chosen) - 1:
                got = extend(chosen + [int(v)], nxt)
                if got is not None:
                    return got
        return None

    got = extend([], adj.any(axis=1))
    if got is None:
        return None, count[0] <= budget
    s = np.array(sorted(got), dtype=np.int64)
    return (s, True) if meets(worst_failure(bank, s, size - 2)[0], need) else (None, False)


def _heavy_lower(red, k, need, n_var):
    """Lower bounds of ``[x, v^1 .. v^{k+1}]``: 1 for every ``v^t`` of a heavy group."""
    lower = np.zeros(n_var)
    h = heavy_groups(red, need).astype(np.float64)
    nc, g = red.rep.size, red.n_groups
    for t in range(k + 1):
        lower[nc + t * g:nc + (t + 1) * g] = h
    return lower


def _left(deadline):
    return None if deadline is None else deadline - time.perf_counter()


def _master(red, scen, k, thr, card, m, n_grid, fold=False):
    """Objective, constraints and integrality of the relaxation with scenarios ``scen``.

    Variables ``[x (K), v^1 (G), ..., v^{k+1} (G)]``; ``v^t_g`` is 1 only if at least
    ``t`` chosen candidates see group g (``t v^t_g <= sum_{c sees g} x_c``, with
    ``v^t`` binary for ``t >= 2`` so that the bound is exact; ``v^1`` may stay
    continuous as in the plain design). After the failure of ``F`` (all flying), g
    stays seen iff ``count_S(g) >= |F seen-by g| + 1``, so the scenario row is
    ``sum_g w_g v_g^{1 + |F sees g|} >= need (sum_{j in F} x_j - (k - 1))``.
    ``fold=True`` asks instead ``sum_g w_g v_g^{k+1} >= need`` (sufficient only).
    ``need`` is the area floor of the threshold ``thr``
    (:func:`~ideas_hpc.design.area.area_floor`); ``card`` = (lowest, highest) swarm size.
    """
    nc, g = red.rep.size, red.n_groups
    n_var = nc + (k + 1) * g
    cov_t = sparse.csr_matrix(red.cover.T.astype(np.float64))   # (G, K)
    rows, lo, hi = [], [], []
    for t in range(1, k + 2):
        rows.append(sparse.hstack([-cov_t, sparse.csr_matrix((g, (t - 1) * g)),
                                   t * sparse.identity(g),
                                   sparse.csr_matrix((g, (k + 1 - t) * g))]).tocsr())
        lo.append(np.full(g, -np.inf))
        hi.append(np.zeros(g))
    floor = area_floor(thr)
    rows.append(sparse.csr_matrix(area_row(red.weight, nc + (k * g if fold else 0),
                                           n_var)[None, :]))
    lo.append([floor])
    hi.append([np.inf])
    cov_i = red.cover.astype(np.int64)
    for f in scen:
        hits = cov_i[list(f)].sum(axis=0)                        # |F sees g|, 0..k
        w = np.zeros(n_var)
        w[nc + hits * g + np.arange(g)] = red.weight
        w[list(f)] -= floor
        rows.append(sparse.csr_matrix(w[None, :]))
        lo.append([-floor * (k - 1)])
        hi.append([np.inf])
    ones = np.zeros(n_var)
    ones[:nc] = 1.0
    rows.append(sparse.csr_matrix(ones[None, :]))
    lo.append([card[0]])
    hi.append([card[1]])
    cons = [LinearConstraint(sparse.vstack(rows, format="csr"), np.concatenate(lo),
                             np.concatenate(hi))]
    sep = _separation_rows(red, m, n_grid, n_var)
    if sep is not None:
        cons.append(sep)
    c = np.zeros(n_var)
    c[:nc] = 1.0
    integ = np.ones(n_var)
    integ[nc:nc + g] = 0
    return c, cons, integ


def _greedy_complete(bank, start, k, need, n_max):
    """Add the candidate that most raises the worst-case coverage until it reaches ``need``."""
    s = [int(i) for i in start]
    while len(s) < n_max:
        if len(s) > k and meets(worst_failure(bank, s, k)[0], need):
            return np.sort(np.array(s, dtype=np.int64))
        scores = [worst_failure(bank, s + [j], k)[0] if j not in s else -1.0
                  for j in range(bank.n_candidates)]
        s.append(int(np.argmax(scores)))
    ok = len(s) > k and meets(worst_failure(bank, s, k)[0], need)
    return np.sort(np.array(s, dtype=np.int64)) if ok else None
