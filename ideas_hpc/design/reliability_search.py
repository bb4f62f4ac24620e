"""Local search of the success-probability designer (issue 20): moves and extensions of
swarms on the exact ``P_bank`` (``ev``: an :class:`ideas_hpc.design.reliability.Evaluator`,
passed in, so this module imports nothing of the designer's), and the exhaustive list of
separated swarms of a size."""

from __future__ import annotations

import itertools
import time

import numpy as np


def _dist_ok(c_n: int, rest: np.ndarray, m: int) -> np.ndarray:
    """(C,) bool: candidates more than ``m`` grid steps from every member of ``rest``."""
    ring = np.arange(c_n)
    if rest.size == 0:
        return np.ones(c_n, dtype=bool)
    d = np.abs(ring[:, None] - rest[None, :])
    return (np.minimum(d, c_n - d) > m).all(axis=1)


def improve(ev, start, m: int, *, radius: int = 6, rounds: int = 30,
            deadline: float | None = None):
    """Best-improvement single moves of each member within ``radius`` grid steps
    (keeping distances > ``m``), maximising the exact ``P_bank``; stops at ``deadline``
    (``time.perf_counter()``). Returns (swarm, P)."""
    c_n = ev.rows.shape[1]
    radius = c_n // 2 if c_n <= 96 else radius
    sw = np.sort(np.asarray(start, dtype=np.int64))
    cur = float(ev.scored([sw])[0])
    for _ in range(rounds):
        if deadline is not None and time.perf_counter() >= deadline:
            break
        trials = []
        for p in range(sw.size):
            rest = np.delete(sw, p)
            ok = _dist_ok(c_n, rest, m)
            ok[sw] = False
            near = (sw[p] + np.arange(-radius, radius + 1)) % c_n
            trials += [np.sort(np.r_[rest, c]) for c in near if ok[c]]
        if not trials:
            break
        vals = ev.scored(np.array(trials))
        i = int(np.argmax(vals))
        if vals[i] <= cur + 1e-13:
            break
        sw, cur = trials[i], float(vals[i])
    return sw, float(ev([sw])[0])


def extend(ev, sw, m: int):
    """The best one-member extension of ``sw`` (exact ``P_bank``), or None."""
    c_n = ev.rows.shape[1]
    sw = np.asarray(sw, dtype=np.int64)
    ok = _dist_ok(c_n, sw, m)
    ok[sw] = False
    cand = np.flatnonzero(ok)
    if cand.size == 0:
        return None
    trials = np.sort(np.c_[np.repeat(sw[None, :], cand.size, axis=0), cand], axis=1)
    vals = ev.scored(trials)
    return trials[int(np.argmax(vals))]


def all_swarms(c_n: int, n: int, m: int):
    """Every n-subset of the ring grid with circular distances > m, as (K, n) int64."""
    out = [c for c in itertools.combinations(range(c_n), n)
           if all(min(abs(a - b), c_n - abs(a - b)) > m
                  for a, b in itertools.combinations(c, 2))]
    return np.array(out, dtype=np.int64).reshape(-1, n)
