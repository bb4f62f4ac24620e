"""Brute-force oracles for the exact designer (vectorised numpy, no solver).

Coverage of a swarm ``S`` is ``1 - sum_v w_v prod_{j in S} (1 - M_jv)`` with
``w`` the area fractions: the uncovered area is what every member misses.
"""

from __future__ import annotations

import itertools

import numpy as np


def uncovered_weights(masks, areas):
    u = ~np.asarray(masks, dtype=bool)
    w = np.asarray(areas, dtype=np.float64) / np.sum(areas)
    return u, w


def pair_coverage(masks, areas) -> np.ndarray:
    """(K, K) coverage of every pair ``{a, b}`` (diagonal: singles), by one matrix product."""
    u, w = uncovered_weights(masks, areas)
    uf = u.astype(np.float64)
    return 1.0 - (uf * w) @ uf.T


def best_triple(masks, areas):
    """Highest coverage of any three distinct candidates and one triple reaching it."""
    u, w = uncovered_weights(masks, areas)
    uf = u.astype(np.float64)
    k = uf.shape[0]
    best, arg = -1.0, None
    for a in range(k - 2):
        rest = uf[a + 1:]
        miss = ((uf[a] * w) * rest) @ rest.T          # (b, c) uncovered area of {a, b, c}
        iu = np.triu_indices(rest.shape[0], 1)
        vals = 1.0 - miss[iu]
        i = int(np.argmax(vals))
        if vals[i] > best:
            best, arg = float(vals[i]), (a, a + 1 + iu[0][i], a + 1 + iu[1][i])
    return best, arg


def subset_coverage(masks, areas, subsets: np.ndarray, chunk: int = 20000) -> np.ndarray:
    """Coverage of each row of ``subsets`` (int array, (P, r))."""
    u, w = uncovered_weights(masks, areas)
    out = np.empty(subsets.shape[0])
    for s in range(0, subsets.shape[0], chunk):
        idx = subsets[s:s + chunk]
        out[s:s + chunk] = 1.0 - u[idx].all(axis=1) @ w
    return out


def min_tolerant_size(masks, areas, need: float, k: int, n_max: int):
    """Smallest n with an n-subset whose every (n - k)-subset covers ``need`` (and one such)."""
    kk = masks.shape[0]
    for n in range(k + 1, n_max + 1):
        combos = np.array(list(itertools.combinations(range(kk), n)), dtype=np.int64)
        ok = np.ones(combos.shape[0], dtype=bool)
        for keep in itertools.combinations(range(n), n - k):
            ok &= subset_coverage(masks, areas, combos[:, list(keep)]) >= need - 1e-12
            if not ok.any():
                break
        if ok.any():
            return n, combos[np.argmax(ok)]
    return None, None
