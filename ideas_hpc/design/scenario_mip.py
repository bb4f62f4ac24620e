"""Scenario-indicator integer programme: the most scenarios an m-swarm reaches (issue 20).

Sample-average approximation with scenario indicators (Luedtke & Ahmed 2008,
"A sample approximation approach for optimization with probabilistic
constraints", SIAM J. Optim. 19(2)). With ``x_c`` in {0, 1} (candidate c
flies), ``z_s`` in {0, 1} (scenario s counted as reached with no failure) and
``y_{s,g}`` in [0, 1] (light vertex group g of scenario s counted covered)::

    maximise    sum_s z_s                                      (U_m = value / S)
    subject to  sum_c x_c <= m
                sum_{c sees g in s} x_c >= z_s       heavy groups g of scenario s
                y_{s,g} <= sum_{c sees g in s} x_c    light groups
                sum_{light g} w_g y_{s,g} >= (need - W_heavy,s) z_s
                sum_{c in W} x_c <= 1                 separation windows W

A group is *heavy* when its area exceeds the slack ``1 - need``: a swarm that
misses it cannot reach the threshold, so with ``z_s = 1`` it must be covered
(as :func:`ideas_hpc.design.exact.heavy_groups` argues). A heavy row is implied
by the row of any subset of its candidates in the same scenario, so only the
subset-minimal ones are kept (:func:`ideas_hpc.core.design.reliability.minimal_sets`).
A scenario with an unseen heavy group, or whose light groups cannot make up
the rest, is unreachable and its ``z_s`` is fixed to 0.

Each scenario's rows use its own vertex weights (``w`` (S, V), issue 42; a shared (V,)
is every scenario's): the groups, the heavy test and the area row of scenario s involve
only ``x``, ``z_s`` and ``y_{s,g}``, so the programme stays a relaxation of the bank's
counting with weights that differ by scenario.

``sum x <= m`` (not ``= m``) makes ``U_m`` nondecreasing in m. HiGHS's dual
bound is a proven upper bound on the optimum, so :meth:`ScenarioMIP.solve`
returns a proven ``Ubar_m >= U_m`` even at a time limit.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.optimize import Bounds, LinearConstraint

from ideas_hpc.base.vertex_weights import row
from ideas_hpc.core.design.reliability import minimal_sets
from ideas_hpc.design.bank import conflict_windows
from ideas_hpc.design.highs import run_milp


@dataclass
class BoundResult:
    """``U_m`` bound: ``upper`` scenarios at most (proven), ``reached`` by ``swarm``."""

    m: int
    upper: int
    reached: int
    swarm: np.ndarray | None
    status: str           # "optimal" or "time_limit"
    seconds: float


def _packed64(cover: np.ndarray) -> np.ndarray:
    """(G, C) bool -> (G, ceil(C / 64)) uint64 bit sets."""
    b = np.packbits(cover, axis=1)
    pad = (-b.shape[1]) % 8
    if pad:
        b = np.hstack([b, np.zeros((b.shape[0], pad), dtype=np.uint8)])
    return np.ascontiguousarray(b).view(np.uint64)


def scenario_groups(rows_s: np.ndarray, w: np.ndarray):
    """Vertex groups of one scenario: ``(cover (G, C) bool, weight (G,))`` by identical seers."""
    c_n = rows_s.shape[0]
    packed = np.packbits(np.ascontiguousarray(rows_s.T), axis=1)
    groups, inv = np.unique(packed, axis=0, return_inverse=True)
    weight = np.bincount(inv.ravel(), weights=w, minlength=groups.shape[0])
    cover = np.unpackbits(groups, axis=1, count=c_n).astype(bool)
    return cover, weight


class ScenarioMIP:
    """The programme of the module docstring for one bank, solved for any ``m``."""

    def __init__(self, rows: np.ndarray, w: np.ndarray, need: float, sep_steps: int):
        s_n, c_n, _ = rows.shape
        self.s_n, self.c_n = s_n, c_n
        slack = 1.0 - need
        coo_r, coo_c, coo_v = [], [], []
        lo_rows: list[float] = []
        n_row = 0
        light_cols = 0
        z_ub = np.ones(s_n)
        light_w: list[np.ndarray] = []
        for s in range(s_n):
            cover, weight = scenario_groups(rows[s], row(w, s))   # that scenario's weights
            empty = ~cover.any(axis=1)
            heavy = weight > slack + 1e-12
            if np.any(heavy & empty):
                z_ub[s] = 0.0
                continue
            light = ~heavy & ~empty
            rest = need - float(weight[heavy].sum())
            if rest > 1e-12 and float(weight[light].sum()) < rest - 1e-12:
                z_ub[s] = 0.0
                continue
            hc = cover[heavy]
            if hc.shape[0]:
                order = np.argsort(hc.sum(axis=1), kind="stable")
                hc = hc[order][minimal_sets(_packed64(hc[order]))]
                r, c = np.nonzero(hc)
                coo_r += [n_row + r, n_row + np.arange(hc.shape[0])]
                coo_c += [c, np.full(hc.shape[0], c_n + s)]
                coo_v += [-np.ones(r.size), np.ones(hc.shape[0])]
                lo_rows += [-np.inf] * hc.shape[0]
                n_row += hc.shape[0]
            if rest > 1e-12:
                lc, lw = cover[light], weight[light]
                r, c = np.nonzero(lc)
                ycol = c_n + s_n + light_cols + np.arange(lc.shape[0])
                coo_r += [n_row + r, n_row + np.arange(lc.shape[0])]
                coo_c += [c, ycol]
                coo_v += [-np.ones(r.size), np.ones(lc.shape[0])]
                lo_rows += [-np.inf] * lc.shape[0]
                n_row += lc.shape[0]
                # rest z_s - sum w y <= 0
                coo_r += [np.full(lc.shape[0] + 1, n_row)]
                coo_c += [np.r_[c_n + s, ycol]]
                coo_v += [np.r_[rest, -lw]]
                lo_rows.append(-np.inf)
                n_row += 1
                light_cols += lc.shape[0]
                light_w.append(lw)
        n_var = c_n + s_n + light_cols
        self.n_var = n_var
        a = sparse.csr_matrix((np.concatenate(coo_v) if coo_v else np.zeros(0),
                               (np.concatenate(coo_r) if coo_r else np.zeros(0, int),
                                np.concatenate(coo_c) if coo_c else np.zeros(0, int))),
                              shape=(n_row, n_var))
        self.cover_rows = LinearConstraint(a, -np.inf, 0.0) if n_row else None
        win = conflict_windows(c_n, sep_steps)
        self.sep_rows = None
        if win.size and win.shape[1] >= 2:
            r = np.repeat(np.arange(win.shape[0]), win.shape[1])
            self.sep_rows = LinearConstraint(
                sparse.csr_matrix((np.ones(win.size), (r, win.ravel())),
                                  shape=(win.shape[0], n_var)), -np.inf, 1.0)
        self.upper = np.r_[np.ones(c_n), z_ub, np.ones(light_cols)]
        self.integrality = np.r_[np.ones(c_n + s_n), np.zeros(light_cols)]
        self.reachable = int(z_ub.sum())
        self.n_rows = n_row

    def solve(self, m: int, time_limit: float | None) -> BoundResult:
        """Most scenarios any swarm of at most ``m`` reaches with no failure (proven bound)."""
        t = time.perf_counter()
        if self.reachable == 0 or m <= 0:
            return BoundResult(m, 0, 0, None, "optimal", 0.0)
        card = LinearConstraint(np.r_[np.ones(self.c_n), np.zeros(self.n_var - self.c_n)][None, :],
                                0, m)
        cons = [c for c in (self.cover_rows, self.sep_rows) if c is not None] + [card]
        cost = np.r_[np.zeros(self.c_n), -np.ones(self.s_n), np.zeros(self.n_var - self.c_n - self.s_n)]
        res = run_milp(cost, constraints=cons, integrality=self.integrality,
                       bounds=Bounds(0.0, self.upper), time_limit=time_limit)
        dt = time.perf_counter() - t
        dual = getattr(res, "mip_dual_bound", None)
        upper = self.reachable
        if dual is not None and np.isfinite(dual):
            upper = min(upper, int(math.floor(-dual + 1e-6)))
        if res.x is None:
            return BoundResult(m, upper, 0, None, "time_limit" if res.status == 1 else "optimal",
                               dt)
        swarm = np.flatnonzero(res.x[:self.c_n] > 0.5).astype(np.int64)
        reached = int(round(-res.fun))
        upper = max(upper, reached)
        status = "optimal" if upper == reached else "time_limit"
        return BoundResult(m, upper, reached, swarm, status, dt)
