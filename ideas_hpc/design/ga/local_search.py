"""Set-cover local search for the NP GA (memetic operators on the mask bank).

When the GA's angles live on a grid (``design.angle_step_rad`` > 0) the
campaign already holds the mask of every grid angle (it needs their union for
the reachable target), so the NP problem is a weighted set cover over those
``K`` candidates: the swarm ``S`` covers ``A(S) = sum_v a_v [v seen by some
member]`` (paper eq. 26) and is feasible when ``A_target - A(S) <= eps_tol``
(eq. 16). Three operators act on every swarm of a population; each step is
one product of the unseen vertices' areas with the (vertex, candidate) mask
matrix, which scores all K candidates at once (the population's fitness
itself stays one batch call of :mod:`ideas_hpc.design.ga.swarm_eval`):

* **completion** -- an infeasible swarm gets, one at a time, the grid angle
  that sees the most still-unseen area (greedy set cover) until it is feasible;
* **removal** -- a member whose loss keeps the swarm feasible is dropped (the
  one whose loss costs the least area first);
* **2-for-1 swap** -- drop two members ``i, j`` and add the one grid angle
  ``c`` that sees the most of what ``S - {i, j}`` misses; accept when
  ``S - {i, j} + {c}`` is feasible (one spacecraft fewer).

They are a heuristic local search (Lamarckian: the improved swarm replaces
the genome); they never consult the exact designer. ``seed_population``
builds greedy swarms from random first angles for part of the initial
population.
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.mapping.requirement import as_threshold

TWO_PI = 2.0 * math.pi


class GridCover:
    """Masks of the GA's grid angles and the operators above.

    Parameters
    ----------
    masks : (K, V) bool
        Vertex seen by grid angle ``k step`` (rad).
    areas : (V,) float
        Vertex areas (any unit; normalised here to fractions).
    step : float
        Grid step, rad.
    target, eps_tol : float
        Coverage fraction to reach and allowed shortfall (fractions); or
    threshold : ideas_hpc.mapping.requirement.Threshold
        The threshold they make (a swarm is feasible when it meets it).
    n_max : int
        Largest swarm.
    min_sep_steps : int
        Smallest separation between two members, in grid steps (0: none).
    """

    def __init__(self, masks, areas, step, target=None, eps_tol=None, n_max=None,
                 min_sep_steps=0, *, threshold=None):
        a = np.asarray(areas, dtype=np.float64)
        self.w = a / a.sum()
        self.m = np.ascontiguousarray(np.asarray(masks, dtype=np.float64))
        self.k = self.m.shape[0]
        # float32 copy for the gains: a gain only ranks candidates; feasibility is
        # rechecked in float64
        self.m32 = np.ascontiguousarray(self.m, dtype=np.float32)
        self.w32 = self.w.astype(np.float32)
        self.step = float(step)
        # feasible: A(S) >= need, the least coverage that meets the threshold
        self.need = as_threshold(threshold, target, eps_tol).floor
        self.n_max = int(n_max)
        self.sep = int(min_sep_steps)
        self._memo: dict[frozenset, list[int]] = {}  # set -> its local optimum

    # ---- genome <-> index sets -------------------------------------------------
    def to_sets(self, genomes: np.ndarray) -> list[list[int]]:
        out = []
        for g in genomes:
            n = int(round(g[0]))
            idx = np.rint(np.mod(g[1:1 + n], TWO_PI) / self.step).astype(np.int64) % self.k
            out.append(list(dict.fromkeys(idx.tolist())))  # unique, order kept
        return out

    def write(self, genomes: np.ndarray, sets: list[list[int]]) -> np.ndarray:
        """Genomes holding ``sets`` (unused genes behind N keep their values)."""
        g = np.array(genomes, dtype=float, copy=True)
        for i, s in enumerate(sets):
            s = sorted(s)
            g[i, 0] = len(s)
            g[i, 1:1 + len(s)] = np.asarray(s, dtype=float) * self.step
        return g

    # ---- helpers ----------------------------------------------------------------
    def _counts(self, s) -> np.ndarray:
        return self.m[list(s)].sum(axis=0) if s else np.zeros(self.m.shape[1])

    def _allowed(self, kept) -> np.ndarray:
        """Candidates at least ``sep`` grid steps from every kept member."""
        ok = np.ones(self.k, dtype=bool)
        if self.sep > 0:
            for j in kept:
                d = np.abs(np.arange(self.k) - j)
                ok &= np.minimum(d, self.k - d) >= self.sep
        return ok

    def _gain(self, cnt: np.ndarray) -> np.ndarray:
        """Unseen area each candidate would add to sets with vertex counts ``cnt``
        ((V,) or (sets, V)); one BLAS product for all K candidates."""
        return ((self.w32 * (cnt == 0)) @ self.m32.T).astype(np.float64)

    def coverage(self, s) -> float:
        return float(self.w @ (self._counts(s) > 0))

    # ---- operators ---------------------------------------------------------------
    def complete(self, sets: list[list[int]]) -> list[list[int]]:
        """Greedy completion of every infeasible set (all sets advance together)."""
        sets = [list(s) for s in sets]
        todo = [i for i, s in enumerate(sets)
                if len(s) < self.n_max and self.coverage(s) < self.need]
        while todo:
            nxt = []
            for i in todo:
                g = np.where(self._allowed(sets[i]), self._gain(self._counts(sets[i])), -1.0)
                c = int(np.argmax(g))
                if g[c] <= 0:  # nothing left to see from an allowed angle
                    continue
                sets[i].append(c)
                if len(sets[i]) < self.n_max and self.coverage(sets[i]) < self.need:
                    nxt.append(i)
            todo = nxt
        return sets

    def remove(self, s: list[int]) -> list[int]:
        """Drop redundant members of a feasible set, cheapest loss first."""
        s = list(s)
        while len(s) > 1:
            cnt = self._counts(s)
            only = self.w * (cnt == 1)
            loss = self.m[s] @ only  # area seen by member j alone
            cov = float(self.w @ (cnt > 0))
            j = int(np.argmin(loss))
            if cov - loss[j] < self.need:
                return s
            s.pop(j)
        return s

    def swap(self, s: list[int]) -> list[int] | None:
        """One 2-for-1 swap that keeps the set feasible, or None."""
        n = len(s)
        if n < 2:
            return None
        pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
        rest = [[s[q] for q in range(n) if q not in p] for p in pairs]
        pi, pj = np.array(pairs).T
        cnts = self._counts(s)[None, :] - self.m[np.asarray(s)[pi]] - self.m[np.asarray(s)[pj]]
        seens = (cnts > 0) @ self.w
        gains = self._gain(cnts)  # (pairs, K)
        best, best_cov = None, -1.0
        for kept, seen, gain in zip(rest, seens, gains):
            g = np.where(self._allowed(kept), gain, -1.0) if self.sep > 0 else gain
            c = int(np.argmax(g))
            if seen + g[c] < self.need - 1e-5:  # float32 ranking: far short, skip
                continue
            cov = self.coverage(kept + [c])
            if cov >= self.need and cov > best_cov:
                best, best_cov = kept + [c], cov
        return best

    def improve(self, genomes: np.ndarray) -> np.ndarray:
        """Completion, removal and 2-for-1 swaps until none applies (Lamarckian).

        Swaps are tried only on swarms at most one spacecraft larger than the
        smallest feasible one (the others cannot become the best this
        generation; they still get completion and removal), and each swarm's
        local optimum is remembered, so repeated genomes cost nothing.
        """
        sets = self.complete(self.to_sets(genomes))
        ok = [self.coverage(s) >= self.need for s in sets]
        sets = [self.remove(s) if f else s for s, f in zip(sets, ok)]
        best = min((len(s) for s, f in zip(sets, ok) if f), default=0)
        out = []
        for s, f in zip(sets, ok):
            if f and len(s) <= best + 1:
                key = frozenset(s)
                if key not in self._memo:
                    t = s
                    while (u := self.swap(t)) is not None:
                        t = self.remove(u)
                    self._memo[key] = t
                s = self._memo[key]
            out.append(s)
        return self.write(genomes, out)

    def seed_population(self, genomes: np.ndarray, fraction: float,
                        rng: np.random.Generator) -> np.ndarray:
        """Replace the first ``fraction`` of ``genomes`` by greedy swarms from random starts."""
        m = int(round(fraction * len(genomes)))
        if m <= 0:
            return genomes
        starts = rng.choice(self.k, size=m, replace=m > self.k)
        g = np.array(genomes, dtype=float, copy=True)
        g[:m] = self.write(g[:m], self.complete([[int(c)] for c in starts]))
        return g
