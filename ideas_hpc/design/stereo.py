"""Exact swarm design with stereo from two spacecraft (issue 14 item 4).

A swarm maps vertex ``v`` in stereo when one member's own track gives a
stereo pair (``own[a, v]``, :mod:`ideas_hpc.core.mapping.quality_masks`) or one pair
of members does (``pairs[ab, v]``, :mod:`ideas_hpc.core.mapping.stereo_pairs`); the
test suite checks this model against the quality pass of every subset. That
is not a union of per-spacecraft rows, so the set cover gets a variable per
pair. With ``x_a`` in {0, 1} (candidate a flies), ``z_ab`` in [0, 1] (both
fly) and ``y_g`` in [0, 1] (group g counted as mapped)::

    minimise    sum_a x_a
    subject to  z_ab <= x_a,  z_ab <= x_b                      for every useful pair
                y_g <= sum_{a: own sees g} x_a + sum_{ab sees g} z_ab
                sum_g w_g y_g >= need = A_target - eps_tol     (design/area.py)
                separation windows and swarm size as in :mod:`ideas_hpc.design.exact`

For integer ``x`` the largest feasible ``z_ab`` is ``x_a x_b``, so this is
exactly the stereo problem on the candidate grid (not a relaxation): its
optimum is the proven fewest spacecraft, with HiGHS's bound and gap as for
the plain design. Vertex groups merge identical (own, pair) columns and pairs
that map nothing are dropped. There are ``K (K - 1) / 2`` pairs, so the grid
is limited to :data:`MAX_CANDIDATES` candidates (2 deg or coarser).
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import sparse
from scipy.optimize import LinearConstraint

from ideas_hpc.core.mapping.stereo_pairs import pair_index
from ideas_hpc.core.design.union import population_coverage
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import steps
from ideas_hpc.design.bank import (CandidateBank, conflict_windows, reduce_problem,
                   separation_steps)
from ideas_hpc.design.area import FEAS_TOL, area_constraint
from ideas_hpc.design.exact import (ExactResult, check_time_limit, coverage_result, heavy_groups,
                    n_max_too_small, solve)
from ideas_hpc.design.ring_bound import swap_search
from ideas_hpc.mapping.requirement import Threshold, as_threshold

#: Largest candidate grid of the pair formulation (K (K - 1) / 2 pair rows).
MAX_CANDIDATES = 180
TWO_PI = 2.0 * math.pi


def check_grid(n_candidates: int, field: str = "angle_step_deg") -> None:
    """At most :data:`MAX_CANDIDATES` grid angles (``field`` names the step; the campaign
    passes its file key)."""
    if n_candidates > MAX_CANDIDATES:
        least = (f"{360.0 / MAX_CANDIDATES:g}" if field.endswith("_deg")
                 else f"{TWO_PI / MAX_CANDIDATES:.4f}")
        raise InputError(f"stereo from two spacecraft needs a pair variable per candidate pair; "
                         f"{n_candidates} grid angles are too many (at most {MAX_CANDIDATES}): "
                         f"use {field} >= {least} with `require_stereo`", field=field)


@dataclass
class StereoBank:
    """Own-track rows ``bank.masks`` (K, V) and pair rows ``pairs`` (K (K-1)/2, V)."""

    bank: CandidateBank
    pairs: np.ndarray

    def swarm_rows(self, swarm) -> np.ndarray:
        """Row indices (own rows 0..K-1, pair rows K + pair_index) a swarm maps with."""
        s = sorted(int(i) for i in swarm)
        k = self.bank.n_candidates
        return np.array(s + [k + pair_index(a, b, k) for a, b in itertools.combinations(s, 2)],
                        dtype=np.int64)

    @functools.cached_property
    def rows(self) -> np.ndarray:
        """Own-track rows then pair rows, (K + K (K - 1) / 2, V): stacked once, scored often."""
        return np.ascontiguousarray(np.vstack([self.bank.masks, self.pairs]))

    def coverage(self, swarms) -> np.ndarray:
        """Stereo-mapped area fraction of each swarm (grid indices)."""
        members = [self.swarm_rows(s) for s in swarms]
        width = max(1, max(m.size for m in members))
        mem = np.full((len(members), width), -1, dtype=np.int64)
        for i, m in enumerate(members):
            mem[i, :m.size] = m
        a = np.ascontiguousarray(self.bank.areas, dtype=np.float64)
        return population_coverage(self.rows, mem, a, float(a.sum()))[0]

    @property
    def n_candidates(self) -> int:
        return self.bank.n_candidates

    @property
    def reach(self) -> float:
        return float(self.coverage([np.arange(self.bank.n_candidates)])[0])


def scorer(bank: CandidateBank) -> StereoBank:
    """Stereo coverage with pairs of spacecraft for a bank built with ``pairs=True``: a
    :class:`StereoBank` over its own-track stereo rows, built once per bank.

    With ``require_stereo`` the own-track stereo rows are the bank's mapped rows (a
    stereo pair is made of usable observations).
    """
    if bank.stereo is None or bank.pairs is None:
        raise InputError("stereo from two spacecraft needs the candidates' stereo rows and "
                         "pair table (build_bank(..., pairs=True))", field="coverage")
    if "stereo" not in bank.derived:
        bank.derived["stereo"] = StereoBank(replace(bank, masks=bank.stereo, pairs=None,
                                                    derived={}), bank.pairs)
    return bank.derived["stereo"]


def _model(sb: StereoBank, m: int):
    """Reduced cover data: (cover (R, G) over own + useful pair rows, weight, pair ends, R_own)."""
    k = sb.bank.n_candidates
    red = reduce_problem(sb.rows, sb.bank.areas, merge_candidates=False)
    useful = red.cover[k:].any(axis=1)
    ends = np.array(list(itertools.combinations(range(k), 2)), dtype=np.int64).reshape(-1, 2)
    if m:   # pairs closer than the separation never fly together
        d = np.abs(ends[:, 0] - ends[:, 1])
        useful &= np.minimum(d, k - d) > m
    cover = np.vstack([red.cover[:k], red.cover[k:][useful]])
    return cover, red, ends[useful]


def _constraints(sb: StereoBank, cover, red, ends, m: int, card):
    k = sb.bank.n_candidates
    p = ends.shape[0]
    g = red.n_groups
    n_var = k + p + g
    cov_t = sparse.csr_matrix(cover.T.astype(np.float64))                 # (G, k + p)
    rows = [sparse.hstack([-cov_t, sparse.identity(g)], format="csr")]
    lo, hi = [np.full(g, -np.inf)], [np.zeros(g)]
    if p:
        r = np.repeat(np.arange(2 * p), 2)
        c = np.c_[ends.ravel(), k + np.repeat(np.arange(p), 2)].ravel()
        v = np.tile([-1.0, 1.0], 2 * p)
        rows.append(sparse.csr_matrix((v, (r, c)), shape=(2 * p, n_var)))
        lo.append(np.full(2 * p, -np.inf))
        hi.append(np.zeros(2 * p))
    # a group mapped through pairs needs two chosen endpoints of its pairs (or an own
    # track): 2 y_g <= 2 sum_own x + sum_endpoints x, implied for integer x, tighter in LP
    ends_of = np.zeros((g, k))
    for j, (a, b) in enumerate(ends):
        hit = cover[k + j]
        ends_of[hit, a] = 1.0
        ends_of[hit, b] = 1.0
    rows.append(sparse.hstack([sparse.csr_matrix(-(ends_of + 2.0 * cover[:k].T)),
                               sparse.csr_matrix((g, p)), 2.0 * sparse.identity(g)],
                              format="csr"))
    lo.append(np.full(g, -np.inf))
    hi.append(np.zeros(g))
    ones = np.zeros(n_var)
    ones[:k] = 1.0
    rows.append(sparse.csr_matrix(ones[None, :]))
    lo.append([card[0]])
    hi.append([card[1]])
    cons = [LinearConstraint(sparse.vstack(rows, format="csr"), np.concatenate(lo),
                             np.concatenate(hi))]
    win = conflict_windows(k, m)
    if win.size and win.shape[1] > 1:
        r = np.repeat(np.arange(win.shape[0]), win.shape[1])
        cons.append(LinearConstraint(sparse.csr_matrix((np.ones(win.size), (r, win.ravel())),
                                                       shape=(win.shape[0], n_var)), -np.inf, 1))
    integ = np.r_[np.ones(k), np.zeros(p + g)]
    return cons, integ, n_var


def greedy_stereo(sb: StereoBank, m: int, n_max: int, need: float = math.inf):
    """Greedy swarm on stereo coverage (pairs count), members more than ``m`` steps apart.

    Returns the swarms of 2, 3, ... members (grid indices) and their coverages.
    """
    k = sb.bank.n_candidates
    ring = np.arange(k)
    # start from the best pair: one spacecraft alone rarely maps anything in stereo
    ends = np.array(list(itertools.combinations(range(k), 2)), dtype=np.int64).reshape(-1, 2)
    d = np.abs(ends[:, 0] - ends[:, 1])
    ends = ends[np.minimum(d, k - d) > m]
    if n_max < 2 or ends.size == 0:
        single = sb.coverage([[i] for i in range(k)])
        return [np.array([int(np.argmax(single))])], [float(single.max())]
    cov = sb.coverage(list(ends))
    chosen: list[int] = [int(i) for i in ends[int(np.argmax(cov))]]
    out, covs = [np.sort(np.array(chosen, dtype=np.int64))], [float(cov.max())]
    while len(chosen) < n_max and covs[-1] < need:
        ok = np.ones(k, dtype=bool)
        for c in chosen:
            d = np.abs(ring - c)
            ok &= np.minimum(d, k - d) > m
        cand = np.flatnonzero(ok)
        if cand.size == 0:
            break
        cov = sb.coverage([chosen + [int(c)] for c in cand])
        chosen.append(int(cand[int(np.argmax(cov))]))
        out.append(np.sort(np.array(chosen, dtype=np.int64)))
        covs.append(float(cov.max()))
    return out, covs


def _heuristic(sb: StereoBank, need: float, m: int, n_max: int):
    """Smallest swarm found by greedy additions then swap searches at smaller sizes."""
    swarms, covs = greedy_stereo(sb, m, n_max, need)
    if not covs or covs[-1] < need:
        return None
    best = swarms[-1]
    sizes = {sw.size: sw for sw in swarms}
    for n in range(best.size - 1, 1, -1):
        sw, c = swap_search(sb, sizes.get(n, best[:n]), m, need=need)
        if c < need:
            break
        best = sw
    return best


def min_swarm_stereo(sb: StereoBank, *, target: float | None = None,
                     eps_tol: float | None = None, n_max: int, min_separation: float = 0.0,
                     time_limit=None, threshold: Threshold | None = None) -> ExactResult:
    """The fewest grid candidates whose stereo-mapped area reaches ``threshold.need`` (or
    ``target - eps_tol``)."""
    time_limit = check_time_limit(time_limit)
    thr = as_threshold(threshold, target, eps_tol)
    bank = sb.bank
    check_grid(bank.n_candidates)
    m = separation_steps(bank.step_rad, bank.d_sep_m, min_separation, bank.n_candidates)
    need = thr.need
    cover, red, ends = _model(sb, m)
    k, p, g = bank.n_candidates, ends.shape[0], red.n_groups
    heur = _heuristic(sb, need, m, int(n_max))
    top = int(n_max) if heur is None else heur.size - 1
    note = (f"stereo from own tracks and from {p} candidate pairs ({g} vertex groups), one "
            "variable per pair (exact); " + ("no heuristic swarm" if heur is None else
                                             f"greedy + swap search: {heur.size}"))
    if top < 1:   # one spacecraft: nothing smaller to look for
        return _stereo_result(sb, heur, thr, heur.size, 0.0, "optimal", [note])
    cons, integ, n_var = _constraints(sb, cover, red, ends, m, (1, top))
    cons.append(area_constraint(thr, red.weight, k + p, n_var))
    c = np.zeros(n_var)
    c[:k] = 1.0
    lower = np.zeros(n_var)
    lower[k + p:] = heavy_groups(red, need)
    res, dt = solve(c, cons, integ, time_limit, lower)
    if res.x is not None:       # smaller than the heuristic swarm
        idx = np.sort(np.flatnonzero(res.x[:k] > 0.5))
        bound = getattr(res, "mip_dual_bound", None)
        bound = math.ceil(bound - 1e-6) if bound is not None and np.isfinite(bound) else 1
        status = "optimal" if bound >= idx.size else "time_limit"
        return _stereo_result(sb, idx, thr, min(bound, idx.size), dt, status, [note])
    if res.status == 2:         # no swarm below the heuristic's: it is optimal
        if heur is None:
            best = max_coverage_stereo(sb, int(n_max), min_separation=min_separation,
                                       time_limit=time_limit)
            raise n_max_too_small(n_max, f"maps {100 * need:.3f} % in stereo", best)
        return _stereo_result(sb, heur, thr, heur.size, dt, "optimal",
                              [note + "; the integer programme proves nothing smaller works"])
    if heur is None:
        raise InputError(f"no stereo design found within the time limit ({res.message}); "
                         "raise `time_limit`", field="time_limit")
    bound = getattr(res, "mip_dual_bound", None)
    bound = math.ceil(bound - 1e-6) if bound is not None and np.isfinite(bound) else 1
    return _stereo_result(sb, heur, thr, min(max(bound, 1), heur.size), dt,
                          "time_limit", [note + f"; the integer programme reached its time "
                                         f"limit with proven lower bound {bound}"])


def _stereo_result(sb, idx, thr, bound, dt, status, notes) -> ExactResult:
    cov = float(sb.coverage([idx])[0])
    if cov < thr.need - FEAS_TOL:
        raise RuntimeError(f"stereo design maps {cov!r} < {thr.need!r}")
    gap = (idx.size - bound) / idx.size
    return ExactResult(indices=idx, theta=sb.bank.theta[idx], n=idx.size, coverage=cov,
                       target=thr.target, status="optimal" if gap == 0 else status,
                       bound=float(bound), gap=float(gap), solve_time=dt, notes=notes)


def max_coverage_stereo(sb: StereoBank, n: int, *, min_separation: float = 0.0,
                        time_limit=None) -> ExactResult:
    """The highest stereo-mapped area any ``n`` grid candidates reach, with a swarm reaching it."""
    time_limit = check_time_limit(time_limit)
    bank = sb.bank
    check_grid(bank.n_candidates)
    m = separation_steps(bank.step_rad, bank.d_sep_m, min_separation, bank.n_candidates)
    cover, red, ends = _model(sb, m)
    k, p = bank.n_candidates, ends.shape[0]
    cons, integ, n_var = _constraints(sb, cover, red, ends, m, (0, int(n)))
    c = np.zeros(n_var)
    c[k + p:] = -red.weight
    res, dt = solve(c, cons, integ, time_limit)
    swarms, _ = greedy_stereo(sb, m, int(n))
    idx, cov = swap_search(sb, swarms[-1], m) if swarms else (np.zeros(0, np.int64), 0.0)
    if res.x is not None:
        i2 = np.sort(np.flatnonzero(res.x[:k] > 0.5))
        c2 = float(sb.coverage([i2])[0])
        if c2 > cov:
            idx, cov = i2, c2
    return coverage_result(bank.theta, idx, cov, res, dt, sb.reach)


def stereo_curve(sb: StereoBank, n_max: int, *, min_separation: float = 0.0,
                 time_limit=None):
    """Coverage-versus-N with stereo: a :class:`~ideas_hpc.design.coverage_vs_n.CoverageCurve`."""
    import time

    from ideas_hpc.design.coverage_vs_n import CoverageCurve

    t0 = time.perf_counter()
    out = []
    for n in steps(range(1, int(n_max) + 1), "coverage vs N (stereo)", unit="N"):
        left = None if time_limit is None else max(1e-3, time_limit - (time.perf_counter() - t0))
        r = max_coverage_stereo(sb, n, min_separation=min_separation, time_limit=left)
        if out and r.coverage < out[-1].coverage:      # non-decreasing: the last one fits
            r.coverage, r.indices = out[-1].coverage, out[-1].indices
        out.append(r)
        if r.optimal and r.coverage >= sb.reach - 1e-12:
            for _ in range(n + 1, int(n_max) + 1):
                out.append(r)
            break
    return CoverageCurve(n=np.arange(1, int(n_max) + 1), coverage=np.array([r.coverage for r in out]),
                         bound=np.array([r.bound for r in out]),
                         gap=np.array([r.gap for r in out]), status=[r.status for r in out],
                         swarms=[r.indices for r in out], solve_time=time.perf_counter() - t0)
