"""Multi-objective swarm design over a candidate bank: NSGA-II (pygad) and its objectives.

Decision variables (the genome, integers)::

    [N, i_1, ..., i_Nmax]      N in 1..N_max,  i_j in 0..K-1 (grid indices of the bank)

The swarm is ``{i_1 .. i_N}``; the genes behind ``N`` wait for a later
mutation of ``N`` (as in the NP GA of :mod:`ideas_hpc.design.ga.genetic`). Every genome is
*repaired* before it is scored (Lamarckian: the repaired genome replaces it):
walking ``i_1 .. i_N`` in order, a member closer than
``swarm.min_separation_km`` to one already kept (circular grid distance
``<= m``, :func:`~ideas_hpc.design.bank.separation_steps`; ``m >= 0`` so a
repeated index counts too) moves to the nearest grid index that conflicts
with none, or is dropped (N decreases) when none is left. So every stored
swarm flies as designed; no penalty term distorts the objectives.

Objectives: :mod:`ideas_hpc.design.pareto.objectives` (``n``, ``coverage``,
``worst_failure_coverage``, ``stereo_coverage``, ``mean_resolution``), stored with
their natural sign and searched as ``sense * value`` (minimised).

NSGA-II survival (Deb et al. 2002): pygad keeps the best half of each
generation by non-dominated rank and crowding distance
(``parent_selection_type="nsga2"``, ``keep_elitism = P / 2``). Every scored
swarm also enters an archive whose non-dominated set (:func:`non_dominated`)
is the result, so a good swarm seen once is never lost. The first population
holds greedy swarms (largest new area first, :func:`~ideas_hpc.design.exact.
greedy_swarm`) of every size 1..N_max and greedy swarms from random first
angles. When ``coverage`` is an objective a memetic step follows (as the NP
GA's set-cover local search): the seeds, a random quarter of every generation
and the archive's front climb by 1-swap coverage ascent at fixed N
(:func:`swap_ascent`) and go back into the population; on eros001708 this
finds the proven coverage-versus-N curve (tests/test_pareto.py).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ideas_hpc.base.seeds import PARETO_SEARCH, search_rng, search_seed
from ideas_hpc.design.bank import CandidateBank, separation_steps
from ideas_hpc.design.exact import greedy_swarm
from ideas_hpc.design.pareto.objectives import OBJECTIVES, check_objectives, evaluate, minimised

__all__ = ["OBJECTIVES", "check_objectives", "evaluate", "minimised", "non_dominated",
           "repair", "swap_ascent", "run_pareto", "ParetoResult"]


def non_dominated(f: np.ndarray) -> np.ndarray:
    """Mask of the rows of ``f`` (P, M), minimised, that no other row dominates.

    ``a`` dominates ``b`` when ``a <= b`` in every objective and ``a < b`` in
    one. Equal rows do not dominate each other (both stay).
    """
    f = np.asarray(f, dtype=np.float64)
    le = (f[:, None, :] <= f[None, :, :]).all(axis=2)
    lt = (f[:, None, :] < f[None, :, :]).any(axis=2)
    return ~(le & lt).any(axis=0)


def repair(genomes: np.ndarray, k: int, m: int) -> np.ndarray:
    """Separated, distinct members for every genome (module docstring); returns a copy."""
    g = np.array(genomes, dtype=np.int64, copy=True)
    n_max = g.shape[1] - 1
    g[:, 0] = np.clip(g[:, 0], 1, n_max)
    g[:, 1:] = np.mod(g[:, 1:], k)
    for row in g:
        n = int(row[0])
        used = row[1:1 + n]
        if np.unique(used).size == n and (m == 0 or _separated(used, k, m)):
            continue
        free = np.ones(k, dtype=bool)
        kept: list[int] = []
        for i in used:
            if not free[i]:
                cand = np.flatnonzero(free)
                if cand.size == 0:
                    continue
                d = np.abs(cand - i)
                i = int(cand[np.argmin(np.minimum(d, k - d))])
            kept.append(int(i))
            free[(i + np.arange(-m, m + 1)) % k] = False
        rest = [x for x in row[1 + n:]]
        row[0] = len(kept)
        row[1:] = (kept + rest + list(used))[:n_max]
    return g


def _separated(s, k, m) -> bool:
    s = np.sort(np.asarray(s))
    if s.size < 2:
        return True
    gaps = np.diff(np.r_[s, s[0] + k])
    return bool(gaps.min() > m)


def members_of(genomes: np.ndarray) -> np.ndarray:
    """(P, n_max) member matrix, -1 behind each genome's N."""
    g = np.asarray(genomes, dtype=np.int64)
    on = np.arange(g.shape[1] - 1)[None, :] < g[:, :1]
    return np.where(on, g[:, 1:], -1)


def swap_ascent(bank: CandidateBank, swarm, m: int, max_moves: int = 50) -> np.ndarray:
    """1-swap coverage ascent at fixed N: replace the member whose best replacement
    (the candidate adding the most area to the others, separated from them)
    gains the most; stop when no swap raises the coverage. Returns sorted indices."""
    w = np.asarray(bank.areas, dtype=np.float64) / float(np.sum(bank.areas))
    mk = np.asarray(bank.masks, dtype=bool)
    mf = mk.astype(np.float32)
    k = mk.shape[0]
    s = [int(i) for i in swarm]
    cur = float(w @ mk[s].any(axis=0))
    for _ in range(max_moves):
        cnt = mk[s].sum(axis=0)
        best = (cur + 1e-13, None, None)
        for pos, i in enumerate(s):
            others = s[:pos] + s[pos + 1:]
            left = (cnt - mk[i]) == 0
            gain = (w.astype(np.float32) * left) @ mf.T
            ok = np.ones(k, dtype=bool)
            for j in others:
                ok[(j + np.arange(-m, m + 1)) % k] = False
            ok[i] = False
            if not ok.any():
                continue
            c = int(np.argmax(np.where(ok, gain, -1.0)))
            new = float(w @ (~left | mk[c]))     # exact, float64
            if new > best[0]:
                best = (new, pos, c)
        if best[1] is None:
            break
        cur, s[best[1]] = best[0], best[2]
    return np.sort(np.array(s, dtype=np.int64))


@dataclass
class ParetoResult:
    """The non-dominated swarms: ``values[i]`` (natural units) of ``swarms[i]`` (grid indices)."""

    objectives: tuple
    values: np.ndarray
    swarms: list
    generations: int
    evaluations: int
    wall_s: float
    notes: list = field(default_factory=list)

    @property
    def n(self) -> np.ndarray:
        return np.array([s.size for s in self.swarms], dtype=np.int64)

    def angles(self, theta: np.ndarray, n_max: int) -> np.ndarray:
        """(front, n_max) swarm angles, rad, NaN-padded."""
        out = np.full((len(self.swarms), max(1, n_max)), np.nan)
        for i, s in enumerate(self.swarms):
            out[i, :s.size] = theta[s]
        return out


class _Archive:
    """Every swarm scored once (memo on its sorted members) and the running front."""

    def __init__(self, bank, names):
        self.bank, self.names = bank, names
        self.memo: dict[bytes, np.ndarray] = {}
        self.front_keys: list[bytes] = []
        self.swarm: dict[bytes, np.ndarray] = {}

    def score(self, members: np.ndarray) -> np.ndarray:
        srt = np.sort(np.where(members < 0, np.iinfo(np.int64).max, members), axis=1)
        keys = [r.tobytes() for r in srt]
        new = {}
        for i, key in enumerate(keys):
            if key not in self.memo and key not in new:
                new[key] = i
        if new:
            rows = members[list(new.values())]
            vals = evaluate(self.bank, self.names, rows)
            for key, r, v in zip(new, rows, vals):
                self.memo[key] = v
                self.swarm[key] = np.sort(r[r >= 0])
            self._update(list(new))
        return np.array([self.memo[key] for key in keys])

    def _update(self, new_keys):
        keys = self.front_keys + new_keys
        f = minimised(self.names, np.array([self.memo[k] for k in keys]))
        # one swarm per objective vector (the first found), then the non-dominated ones
        _, first = np.unique(f, axis=0, return_index=True)
        first = np.sort(first)
        keep = first[non_dominated(f[first])]
        self.front_keys = [keys[i] for i in keep]


def run_pareto(bank: CandidateBank, objectives, *, n_max: int, population: int,
               generations: int, seed: int, min_separation: float = 0.0,
               parents: int | None = None, mutation_probability: float = 0.1,
               progress=None) -> ParetoResult:
    """NSGA-II over the bank (module docstring); returns the archive's non-dominated set."""
    import pygad

    names = check_objectives(objectives)
    for x in names:       # a missing optional quality array fails before the search
        OBJECTIVES[x].evaluate(bank, np.zeros((1, 1), dtype=np.int64))
    k = bank.n_candidates
    n_max = int(min(n_max, k))
    m = separation_steps(bank.step_rad, bank.d_sep_m, min_separation, k)
    t0 = time.perf_counter()
    arch = _Archive(bank, names)
    rng = search_rng(seed, PARETO_SEARCH)
    ascent = "coverage" in names

    def fitness_func(ga, solutions, idx):
        g = repair(np.atleast_2d(solutions), k, m)
        return list(-minimised(names, arch.score(members_of(g))))

    def seeds(pop):
        rows = [greedy_swarm(bank, m, n)[0] for n in range(1, n_max + 1)]
        while len(rows) < pop // 2:       # greedy completions of random first angles
            first = int(rng.integers(k))
            n = int(rng.integers(1, n_max + 1))
            rows.append(_greedy_from(bank, first, m, n))
        return rows

    def write(pop, rows, at):
        for r, s in zip(at, rows):
            if s.size:
                pop[r, 0] = s.size
                pop[r, 1:1 + s.size] = s

    done: dict[bytes, np.ndarray] = {}     # swarm -> its swap-ascent optimum

    def ascend(swarms):
        out = []
        for sw in swarms:
            key = np.sort(sw).tobytes()
            if key not in done:
                done[key] = swap_ascent(bank, sw, m)
            out.append(done[key])
        arch.score(_pad(out, n_max))
        return out

    def on_start(ga):
        pop = np.asarray(ga.population, dtype=np.int64)
        rows = seeds(pop.shape[0])[:pop.shape[0]]
        if ascent:
            rows = ascend(rows)
        write(pop, rows, range(len(rows)))
        ga.population[:] = repair(pop, k, m)

    def on_generation(ga):
        pop = repair(np.asarray(ga.population, dtype=np.int64), k, m)
        if ascent:
            # a quarter of the population climbs (Lamarckian), then the archive's front
            # climbs and replaces the tail of the population (offspring, not elites)
            pick = rng.choice(pop.shape[0], size=max(1, pop.shape[0] // 4), replace=False)
            mem = members_of(pop[pick])
            write(pop, ascend([r[r >= 0] for r in mem]), pick)
            better = ascend([arch.swarm[key] for key in arch.front_keys])
            tail = list(range(pop.shape[0] - 1, -1, -1))[:min(len(better), pop.shape[0] // 2)]
            write(pop, better, tail)
        ga.population[:] = pop
        ga.last_generation_fitness = np.array(fitness_func(ga, pop, None))
        if progress is not None:
            progress(ga.generations_completed, len(arch.front_keys))

    p = int(population)
    ga = pygad.GA(
        num_generations=int(generations),
        num_parents_mating=int(parents or max(2, p // 2)),
        fitness_func=fitness_func, fitness_batch_size=p, sol_per_pop=p,
        num_genes=1 + n_max, gene_type=int,
        gene_space=[range(1, n_max + 1)] + [range(k)] * n_max,
        parent_selection_type="nsga2", keep_elitism=max(1, p // 2),
        crossover_type="uniform", mutation_type="random",
        mutation_probability=float(mutation_probability), mutation_by_replacement=True,
        on_start=on_start, on_generation=on_generation,
        random_seed=search_seed(seed), suppress_warnings=True)
    ga.run()
    keys = arch.front_keys
    vals = np.array([arch.memo[x] for x in keys]).reshape(len(keys), len(names))
    order = np.lexsort(vals.T[::-1])
    notes = [f"NSGA-II (pygad), population {p}, {ga.generations_completed} generations; "
             f"{len(arch.memo)} distinct swarms scored; separation repair with "
             f"m = {m} grid steps" + ("; 1-swap coverage ascent on the front" if ascent else "")]
    return ParetoResult(objectives=names, values=vals[order], swarms=[arch.swarm[keys[i]]
                        for i in order], generations=int(ga.generations_completed),
                        evaluations=len(arch.memo), wall_s=time.perf_counter() - t0, notes=notes)


def _pad(swarms, n_max: int) -> np.ndarray:
    out = np.full((max(1, len(swarms)), n_max), -1, dtype=np.int64)
    for i, s in enumerate(swarms):
        out[i, :s.size] = s
    return out if swarms else out[:0]


def _greedy_from(bank, first: int, m: int, n: int) -> np.ndarray:
    """Greedy swarm of ``n`` that starts at grid index ``first``."""
    w = bank.areas / bank.areas.sum()
    k = bank.n_candidates
    left = ~bank.masks[first]
    chosen = [first]
    allowed = np.ones(k, dtype=bool)
    while True:
        d = np.abs(np.arange(k) - chosen[-1])
        allowed &= np.minimum(d, k - d) > m
        if len(chosen) >= n or not allowed.any():
            break
        gain = np.where(allowed, (bank.masks & left) @ w, -1.0)
        j = int(np.argmax(gain))
        chosen.append(j)
        left &= ~bank.masks[j]
    return np.sort(np.array(chosen, dtype=np.int64))
