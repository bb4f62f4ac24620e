"""Exact NP swarm design: the proven fewest spacecraft (weighted set cover, HiGHS).

With ``x_c`` in {0, 1} (candidate c flies) and ``y_g`` in [0, 1] (vertex
group g counted as covered), the NP design of paper eqs. 15-16 on the
candidate grid is the integer programme::

    minimise    sum_c x_c                                          (N)
    subject to  y_g <= sum_{c sees g} x_c           for every group g
                sum_g w_g y_g >= need = A_target - eps_tol        (area fractions,
                                                                  design/area.py)
                sum_{c in W} x_c <= 1               for every separation window W

``y`` need not be integer: ``y_g <= 1`` and ``y_g <= 0`` when no chosen
candidate sees ``g``, so any feasible ``y`` undercounts the true union and the
optimum over ``x`` is the optimum of the true problem. The max-coverage variant
(:func:`max_coverage`) maximises ``sum w y`` with ``sum x <= N``.

*Heavy groups* (:func:`heavy_groups`): the area a feasible swarm may leave
uncovered is at most the slack ``sum_g w_g - (A_target - eps_tol)``, so a
group heavier than the slack is covered by every feasible swarm, and its
``y_g`` is fixed to 1 (the row then reads ``sum_{c sees g} x_c >= 1``). This
removes no feasible swarm and tightens the LP relaxation, a set-cover row in
place of a partial one: on eros001708 in strict mode 646 of 809 groups are
heavy for a 0.1 % tolerance.

Before any integer programme, :func:`min_swarm` asks the ring-gap bound
(:mod:`ideas_hpc.design.ring_bound`) for the fewest spacecraft that can reach
the target, ``L``, and a swap search for a swarm of ``L`` that does. When it
finds one, that swarm is the proven optimum and no programme is solved (this
certifies eros022540 in strict mode, where HiGHS alone stops at its time
limit). Otherwise ``L`` enters the programme as the row ``sum x >= L``.

Solved by :func:`scipy.optimize.milp` (HiGHS branch and cut). The objective
of :func:`min_swarm` is an integer, so the proven lower bound is
``ceil(dual bound)`` and the gap ``(N - bound) / N`` is exact; ``status`` is
``"optimal"`` only when that gap is 0. A time limit returns the best swarm
found so far with its gap (status ``"time_limit"``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import sparse
from scipy.optimize import Bounds, LinearConstraint

from ideas_hpc.design.highs import run_milp

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import plural
from ideas_hpc.design.area import FEAS_TOL, area_constraint
from ideas_hpc.design.bank import CandidateBank, Reduced, conflict_windows, reduce_problem, separation_steps
from ideas_hpc.design.ring_bound import redundancy_polish, ring_bound, swap_search
from ideas_hpc.mapping.requirement import Threshold, as_threshold, meets

#: Relative gaps below this are float noise of the solver's bound (max coverage).
GAP_ZERO = 1e-9


@dataclass
class ExactResult:
    """Outcome of one exact design (store variables of issue 13).

    ``indices`` are grid indices of the chosen candidates, ``theta`` their
    angles (rad); ``bound`` the proven bound (lower bound on N for
    :func:`min_swarm`, upper bound on coverage for :func:`max_coverage`).
    """

    indices: np.ndarray
    theta: np.ndarray
    n: int
    coverage: float
    target: float
    status: str
    bound: float
    gap: float
    solve_time: float
    notes: list = field(default_factory=list)

    @property
    def optimal(self) -> bool:
        return self.status == "optimal"


def check_time_limit(time_limit) -> float | None:
    if time_limit is None:
        return None
    t = float(time_limit)
    if not (t > 0 and math.isfinite(t)):
        raise InputError(f"must be > 0 s, got {time_limit!r}", field="time_limit")
    return t


def _cover_rows(red: Reduced, n_x: int, extra_cols: int = 0):
    """Rows ``y_g - sum_{c sees g} x_c <= 0`` as a sparse block over (x, y, extra)."""
    g = red.n_groups
    cov = sparse.csr_matrix(red.cover.T.astype(np.float64))
    return sparse.hstack([-cov, sparse.identity(g, format="csr"),
                          sparse.csr_matrix((g, extra_cols))], format="csr")


def _separation_rows(red: Reduced, m: int, n_grid: int, n_cols: int):
    win = conflict_windows(n_grid, m)
    if win.size == 0 or win.shape[1] < 2:
        return None
    rows = np.repeat(np.arange(win.shape[0]), win.shape[1])
    a = sparse.csr_matrix((np.ones(win.size), (rows, win.ravel())), shape=(win.shape[0], n_cols))
    return LinearConstraint(a, -np.inf, 1.0)


def prepare(bank: CandidateBank, min_separation: float, *, redundancy: bool = False):
    """Reduced data and the separation width ``m`` (grid steps) for a bank."""
    m = separation_steps(bank.step_rad, bank.d_sep_m, min_separation, bank.n_candidates)
    red = reduce_problem(bank.masks, bank.areas, merge_candidates=(m == 0 and not redundancy))
    return red, m


def heavy_groups(red: Reduced, need: float) -> np.ndarray:
    """(G,) bool: groups heavier than the uncovered area a swarm reaching ``need`` may leave.

    Every swarm of coverage >= ``need`` covers them (module docstring). The
    slack is the true one, ``sum w - need``, larger than the programme's
    (which asks ``need + FEAS_TOL``), so the fixing is valid for both.
    """
    slack = float(red.weight.sum()) - need
    return red.weight > slack + 1e-12


def solve(c, constraints, integrality, time_limit, lower=None):
    """HiGHS through scipy, variables in [lower, 1] (default [0, 1]); returns (result, seconds)."""
    t = time.perf_counter()
    res = run_milp(c, constraints=constraints, integrality=integrality,
                   bounds=Bounds(0.0 if lower is None else lower, 1.0), time_limit=time_limit)
    return res, time.perf_counter() - t


def _chosen(red: Reduced, x: np.ndarray) -> np.ndarray:
    return np.sort(red.rep[np.flatnonzero(x[:red.rep.size] > 0.5)])


def n_max_too_small(n_max: int, what: str, top) -> InputError:
    """The programme proved no swarm of at most ``n_max`` works: say so, with the best
    ``n_max`` reach (``top``, a max-coverage result); the time limit is named only for
    that best value when it is not proven (it is not the cause of the failure)."""
    best = f"{100 * top.coverage:.3f} %" + ("" if top.status == "optimal" else
                                          " (best found, not proven within "
                                          "`time_limit`)")
    return InputError(f"N_max too small: no swarm of at most {n_max} spacecraft {what} "
                      f"(proven); the best with {n_max} is {best}; raise `n_max`",
                      field="n_max")


def min_swarm(bank: CandidateBank, *, target: float | None = None, eps_tol: float | None = None,
              n_max: int | None = None, min_separation: float = 0.0,
              time_limit: float | None = None, threshold: Threshold | None = None) -> ExactResult:
    """The fewest grid candidates whose union covers ``threshold.need`` (fractions), or
    ``target - eps_tol`` (the older keywords).

    Raises
    ------
    InputError
        ``eps_tol`` when the target cannot be reached by any swarm
        (the message gives the highest reachable coverage), ``n_max`` when it
        needs more than ``n_max`` spacecraft and ``min_separation`` when only
        the separation stands in the way (the campaign maps these names to its
        file keys, :data:`ideas_hpc.campaign.schema.design_checks.DESIGNER_FIELDS`).
    """
    time_limit = check_time_limit(time_limit)
    thr = as_threshold(threshold, target, eps_tol)
    red, m = prepare(bank, min_separation)
    target, need = thr.target, thr.need
    reach = bank.reach
    if need > reach + FEAS_TOL:
        raise InputError(f"target {100 * target:.3f} % (minus eps_tol) is not reachable: the "
                         f"highest coverage any swarm on this grid reaches is {100 * reach:.4f} %",
                         field="eps_tol")
    low, found, above, t_ring = _by_ring(bank, red, min_separation, m, need, n_max)
    if found is not None:
        out = _ring_result(bank, found, target, t_ring)
    else:
        nc, g = red.rep.size, red.n_groups
        cons = [LinearConstraint(_cover_rows(red, nc), -np.inf, 0.0),
                area_constraint(thr, red.weight, nc, nc + g)]
        sep = _separation_rows(red, m, bank.n_candidates, nc + g)
        if sep is not None:
            cons.append(sep)
        top = (np.inf if n_max is None else int(n_max)) if above is None else above.size - 1
        cons.append(LinearConstraint(np.r_[np.ones(nc), np.zeros(g)][None, :], low or 0, top))
        c = np.r_[np.ones(nc), np.zeros(g)]
        lower = np.r_[np.zeros(nc), heavy_groups(red, need).astype(np.float64)]
        left = None if time_limit is None else max(1e-3, time_limit - t_ring)
        res, dt = solve(c, cons, np.r_[np.ones(nc), np.zeros(g)], left, lower)
        if m > 0 and res.x is None and res.status == 2 and above is None:
            out = None
        else:
            out = _min_result(bank, red, res, dt + t_ring, thr, n_max, m, low, above)
    if m == 0:
        return out
    # Does the separation cost spacecraft? Solve without it (merged columns: fast).
    free = min_swarm(bank, threshold=thr, n_max=n_max, time_limit=time_limit)
    sep_km = min_separation / 1e3
    if out is None:
        raise InputError(f"no swarm{'' if n_max is None else f' of at most {n_max}'} with "
                         f"spacecraft at least {sep_km:g} km apart "
                         f"reaches {100 * need:.3f} %; without the separation {free.n} "
                         "spacecraft do, with some closer than that", field="min_separation")
    out.solve_time += free.solve_time
    if free.n < out.n:
        out.notes.append(f"the separation of {sep_km:g} km costs spacecraft: {free.n} would do "
                         f"with some closer than {sep_km:g} km, {out.n} are needed with it")
    return out


def _by_ring(bank, red, min_separation, m, need, n_max):
    """Ring-gap bound and swap searches: ``(low, found, above, seconds)``.

    ``low``: proven lower bound on N (None without a bound); ``found``: a swarm
    of ``low`` reaching ``need`` (then optimal); ``above``: otherwise the
    smallest swarm of ``low + 1 .. low + 2`` the swap search finds reaching it.
    """
    t = time.perf_counter()
    grid_order = red.rep.size == bank.n_candidates and np.array_equal(
        red.rep, np.arange(bank.n_candidates))
    full = red if grid_order else prepare(bank, min_separation, redundancy=True)[0]
    top = int(n_max) if n_max is not None else 64
    rb = ring_bound(bank, full, m, top, need, extra=2)      # and the two sizes above
    low = None if rb is None else rb.n_bound(need)
    if low is None:
        return None, None, None, time.perf_counter() - t
    for n in range(low, min(top, low + 2, rb.upper.size - 1) + 1):
        for start in (rb.swarm(n), greedy_swarm(bank, m, n)[0]):
            if start.size != n or np.any(start < 0):
                continue
            sw, cov = swap_search(bank, start, m, need=need)
            if cov >= need:
                sw = redundancy_polish(bank, sw, m, need)
                return (low, sw, None, time.perf_counter() - t) if n == low else \
                    (low, None, sw, time.perf_counter() - t)
    return low, None, None, time.perf_counter() - t


def _ring_result(bank, idx, target, dt) -> ExactResult:
    return ExactResult(indices=idx, theta=bank.theta[idx], n=idx.size,
                       coverage=float(bank.coverage([idx])[0]), target=target, status="optimal",
                       bound=float(idx.size), gap=0.0, solve_time=dt,
                       notes=[f"proven by the ring-gap bound (no {plural(idx.size - 1, 'grid candidate')} "
                              f"can reach the threshold) and a swap search that found "
                              f"{idx.size} that do; no integer programme needed"])


def _min_result(bank, red, res, dt, thr, n_max, m, low=None, above=None) -> ExactResult:
    """The design from HiGHS's outcome for the threshold ``thr``; ``above`` is a swarm
    found before it (the programme then looked only for smaller ones)."""
    target, need = thr.target, thr.need
    notes = []
    bound = getattr(res, "mip_dual_bound", None)
    bound = math.ceil(bound - 1e-6) if bound is not None and np.isfinite(bound) else 1
    bound = max(bound, low or 1)
    if res.x is None and above is not None:
        found = f"a swap search found {above.size} spacecraft reaching the threshold"
        if res.status == 2:     # nothing smaller exists: above is optimal
            bound = above.size
            notes.append(f"{found}; the integer programme proves no smaller swarm does "
                         f"(ring-gap bound {low})")
        else:
            notes.append(f"{found}; the integer programme found nothing smaller within "
                         f"design.time_limit_s (proven lower bound {bound})")
        idx = above
        res_status = 0 if res.status == 2 else 1
    elif res.x is None:
        if res.status == 2:
            what = (f"with spacecraft at least {m + 1} grid steps apart "
                    if m else "")
            top = max_coverage(bank, n_max, prepared=(red, m))
            raise n_max_too_small(n_max, f"{what}reaches {100 * need:.3f} %", top)
        idx = greedy_cover(bank, need, m, n_max)
        if idx is None:
            raise InputError(f"no swarm found within the time limit ({res.message}); raise "
                             "`time_limit`", field="time_limit")
        notes.append(f"the integer programme found no swarm within design.time_limit_s; "
                     f"greedy cover of {idx.size} spacecraft, proven lower bound {bound}")
        res_status = 1
    else:
        idx = _chosen(red, res.x)
        res_status = res.status
        if res_status == 1:  # stopped early: keep the greedy cover if it is smaller
            g = greedy_cover(bank, need, m, n_max)
            if g is not None and g.size < idx.size:
                notes.append(f"the integer programme stopped at its time limit with "
                             f"{idx.size} spacecraft; a greedy cover needs {g.size}")
                idx = g
    n = idx.size
    bound = min(max(bound, 1), n)
    gap = (n - bound) / n
    status = "optimal" if gap == 0 else ("time_limit" if res_status == 1 else "feasible")
    cov = float(bank.coverage([idx])[0])
    if cov < need - FEAS_TOL:  # the solver's tolerances never hide a shortfall
        raise RuntimeError(f"exact design covers {cov!r} < {need!r}")
    return ExactResult(indices=idx, theta=bank.theta[idx], n=n, coverage=cov, target=target,
                       status=status, bound=float(bound), gap=float(gap), solve_time=dt,
                       notes=notes)


def greedy_cover(bank: CandidateBank, need: float, m: int, n_max: int | None):
    """Greedy set cover: add the candidate that covers the most new area, keeping
    every pair more than ``m`` grid steps apart, until ``need`` is reached.

    The fallback when the integer programme has no incumbent at its time limit
    (a feasible design; its gap to the proven bound is reported). Returns grid
    indices, or None when it cannot reach ``need``.
    """
    idx, covered = greedy_swarm(bank, m, n_max, need)
    return idx if meets(covered, need) else None


def greedy_swarm(bank: CandidateBank, m: int, n_max: int | None,
                 need: float = math.inf) -> tuple[np.ndarray, float]:
    """Up to ``n_max`` candidates picked by largest new area (pairs more than ``m``
    grid steps apart), stopping early once ``need`` is covered.
    Returns ``(sorted grid indices, covered area fraction)``."""
    w = bank.areas / bank.areas.sum()
    left = np.ones(bank.masks.shape[1], dtype=bool)
    allowed = np.ones(bank.n_candidates, dtype=bool)
    chosen: list[int] = []
    covered = 0.0
    while not meets(covered, need) and (n_max is None or len(chosen) < n_max):
        gain = (bank.masks & left) @ w
        gain[~allowed] = -1.0
        j = int(np.argmax(gain))
        if gain[j] <= 0.0:
            break
        chosen.append(j)
        covered += gain[j]
        left &= ~bank.masks[j]
        d = np.abs(np.arange(bank.n_candidates) - j)
        allowed &= np.minimum(d, bank.n_candidates - d) > m
    return np.sort(np.array(chosen, dtype=np.int64)), covered


def max_coverage(bank: CandidateBank, n: int, *, min_separation: float = 0.0,
                 time_limit: float | None = None, prepared=None) -> ExactResult:
    """The highest union coverage any ``n`` grid candidates reach, with one swarm reaching it."""
    time_limit = check_time_limit(time_limit)
    red, m = prepared if prepared is not None else prepare(bank, min_separation)
    nc, g = red.rep.size, red.n_groups
    cons = [LinearConstraint(_cover_rows(red, nc), -np.inf, 0.0),
            LinearConstraint(np.r_[np.ones(nc), np.zeros(g)][None, :], 0, int(n))]
    sep = _separation_rows(red, m, bank.n_candidates, nc + g)
    if sep is not None:
        cons.append(sep)
    res, dt = solve(np.r_[np.zeros(nc), -red.weight], cons,
                    np.r_[np.ones(nc), np.zeros(g)], time_limit)
    if res.x is None and res.status != 1:
        raise RuntimeError(f"HiGHS found no swarm of {n}: {res.message}")
    # no incumbent at the time limit (large shape models): the greedy swarm, with its gap
    idx = _chosen(red, res.x) if res.x is not None else greedy_swarm(bank, m, n)[0]
    cov = float(bank.coverage([idx])[0])
    return coverage_result(bank.theta, idx, cov, res, dt,
                           cov if res.x is not None else max(cov, bank.reach))


def coverage_result(theta, idx, cov: float, res, dt: float, fallback: float) -> ExactResult:
    """A max-coverage outcome: the swarm ``idx`` of coverage ``cov`` and HiGHS's proven
    upper bound (``fallback`` when it gives none), its gap and status."""
    bound = getattr(res, "mip_dual_bound", None)
    bound = fallback if bound is None or not np.isfinite(bound) else max(cov, -float(bound))
    gap = (bound - cov) / bound if bound > 0 else 0.0
    if gap < GAP_ZERO:
        gap, bound = 0.0, cov
    status = "optimal" if gap == 0.0 else ("time_limit" if res.status == 1 else "feasible")
    return ExactResult(indices=idx, theta=theta[idx], n=idx.size, coverage=cov, target=cov,
                       status=status, bound=float(bound), gap=float(gap), solve_time=dt)
