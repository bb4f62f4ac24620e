"""Ring problems and brute-force oracles for the screen of the success-probability designer
(tests/test_screen_bound.py, tests/test_screen_sizes.py).

``relaxed_covers`` is the reference semantics of the ring-gap relaxation, straight from
the rows (no gap matrix): a vertex is surely missed when every candidate that sees it
lies strictly inside one gap of the swarm (a single member's one gap is the whole ring
but itself).
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.design.bank import reduce_problem
from ideas_hpc.design.ring_bound import gap_matrix
from ideas_hpc.design.screen_bound import clip_gap_matrix, stack_gap_matrices


def ring_rows(seed, s_n=6, c_n=14, v_n=24, two_arc=0.25, widths=(4, 8)):
    """Rows on a ring: each vertex seen by an arc of candidates, some by two arcs (where the
    relaxation is loose); arcs jitter from scenario to scenario. Arcs of ``widths`` close
    to ``c_n`` let single candidates cover in some scenarios."""
    rng = np.random.default_rng(seed)
    rows = np.zeros((s_n, c_n, v_n), dtype=bool)
    for v in range(v_n):
        lo0, wid0 = (c_n * v) // v_n, int(rng.integers(*widths))
        second = rng.random() < two_arc
        for s in range(s_n):
            lo = lo0 + int(rng.integers(-1, 2))
            rows[s, np.arange(lo, lo + wid0 + int(rng.integers(-1, 2))) % c_n, v] = True
            if second:
                rows[s, np.arange(lo + c_n // 2, lo + c_n // 2 + 2) % c_n, v] = True
    return rows, rng.uniform(0.5, 1.5, v_n)


def relaxed_covers(rows_s, w, swarm, need):
    """Brute force of the ring-gap relaxation, straight from the rows: a vertex is surely
    missed when every candidate that sees it lies strictly inside one gap of the swarm."""
    c_n = rows_s.shape[0]
    sw = sorted(swarm)
    missed = 0.0
    for v in range(rows_s.shape[1]):
        seers = set(np.flatnonzero(rows_s[:, v]))
        if not seers:
            continue
        for a, b in zip(sw, sw[1:] + [sw[0] + c_n]):
            inside = {c % c_n for c in range(a + 1, b)}
            if seers <= inside:
                missed += w[v]
                break
    reach = w[rows_s.any(axis=0)].sum()
    return reach - missed >= need - 1e-12


def exact_covers(rows_s, w, swarm, need):
    return w[rows_s[list(swarm)].any(axis=0)].sum() >= need - 1e-12


def mt_of(rows, w, need):
    """The screen's ``Mt`` and the scenarios' slacks (``reach - need``) for rows."""
    clipped, slack = [], []
    for s in range(rows.shape[0]):
        red = reduce_problem(rows[s], w, merge_candidates=False)
        reach = float(red.weight.sum())
        clipped.append(clip_gap_matrix(gap_matrix(red.cover, red.weight), reach - need))
        slack.append(reach - need)
    return stack_gap_matrices(clipped), np.asarray(slack)


class NoProgramme:
    """Stand-in for the scenario programme: ``U_m <= 1`` (no information), no swarm."""

    upper, status, swarm = np.inf, "skipped", None

    def __init__(self, s_n):
        self.s_n = s_n

    def __call__(self, m, seconds):
        out = NoProgramme(self.s_n)
        out.upper = float(self.s_n)
        return out


def no_tolerance(masks, w, need, k, seconds, step):
    """Stand-in for the k-tolerant programmes: the trivial lower bound ``k + 1``."""
    return k + 1
