"""Genetic-algorithm swarm designers (SPEC section 7; paper eqs. 15-18), on pygad.

pygad runs the search; the fitness of a whole generation is one call to a
batch evaluator (pygad's ``fitness_batch_size`` = population size), which
evaluates every member in compiled code (see :mod:`ideas_hpc.design.ga.swarm_eval`).

NP design (eqs. 15-16): genes ``[N, theta_1 .. theta_Nmax]``, N an integer in
[1, N_max], theta in [0, 2 pi) (only the first N are used). Minimise N subject
to ``|A_obs - A_target| <= eps_tol``. pygad maximises, so the fitness is::

    feasible:    -N                              in [-N_max, -1]
    infeasible:  -(N_max + 1) - shortfall_pct    below every feasible design

which ranks every feasible swarm above every infeasible one and, among the
infeasible, rewards coverage. After each generation a repair step (memetic,
Lamarckian) tries to drop spacecraft from every feasible swarm: all
"one fewer" variants are scored in one batch call and the best feasible one
replaces the genome (its dropped angle moves behind N). A plain GA rarely
hits the narrow sets of angles that reach 100 % with the fewest spacecraft;
the repair lets it find them from larger feasible swarms. On an angle grid
the campaign also hands over the masks of every grid angle
(:class:`~ideas_hpc.design.ga.local_search.GridCover`): then 20 % of the initial population
are greedy swarms from random first angles, and the repair is a set-cover
local search (greedy completion, removal, 2-for-1 swaps), which reaches the
certified optimum on eros001708 for every seed tried
(tests/test_ga_optimum.py). ``A_target`` is 100 %, or the highest coverage
any swarm can reach when that is less (strict mode: some concavities are never
visible from a ring); the result says which.

FoV design (eqs. 17-18): genes ``P_i`` in [P_min, P_max] per spacecraft of a
given swarm; fitness = coverage in percent (maximised).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ideas_hpc.design.ga.settings import FovGASettings, GASearch, NadirGASettings
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.seeds import GA_SEEDING, search_rng, search_seed

TWO_PI = 2.0 * math.pi


@dataclass
class GAResult:
    """History and outcome of a GA run (store variables of SPEC section 9)."""

    best_fitness: np.ndarray          # (generation,)
    mean_fitness: np.ndarray          # (generation,)
    population: np.ndarray            # (individual, gene), final generation
    fitness: np.ndarray               # (individual,)
    coverage: np.ndarray              # (individual,) area fraction of the final population
    best_genome: np.ndarray           # (gene,)
    best_fitness_value: float
    best_coverage: float
    best_swarm_size: int
    evaluations: int                  # distinct designs scored (NP: repeats are memoised)
    target_coverage: float
    notes: list[str] = field(default_factory=list)


def _check_ga(population: int, generations: int) -> None:
    if int(population) < 2:
        raise InputError(f"must be >= 2, got {population}", field="population")
    if int(generations) < 1:
        raise InputError(f"must be >= 1, got {generations}", field="generations")


def nadir_fitness(cov: np.ndarray, n: np.ndarray, n_max: int, target: float,
                  eps_tol: float) -> np.ndarray:
    """Penalised NP fitness (module docstring); ``cov`` and ``target`` are fractions."""
    shortfall = np.maximum(0.0, target - cov)
    feasible = shortfall <= eps_tol + 1e-12
    return np.where(feasible, -n.astype(float), -(n_max + 1.0) - 100.0 * shortfall)


def reduce_swarms(genomes: np.ndarray, evaluate, target: float, eps_tol: float) -> np.ndarray:
    """Greedy repair: drop spacecraft from feasible NP genomes while they stay feasible.

    ``genomes`` (P, 1 + n_max); returns a repaired copy. Each round scores all
    one-fewer variants of every still-feasible genome in one ``evaluate`` call.
    """
    g = np.array(genomes, dtype=float, copy=True)
    cov, n = evaluate(g)
    live = np.where((target - cov <= eps_tol + 1e-12) & (n > 1))[0]
    while live.size:
        variants, owner = [], []
        for i in live:
            k = int(round(g[i, 0]))
            for j in range(k):
                v = g[i].copy()
                ang = np.delete(v[1:1 + k], j)
                v[1:k] = ang
                v[k] = g[i, 1 + j]  # the dropped angle waits behind N
                v[0] = k - 1
                variants.append(v)
                owner.append(i)
        variants = np.array(variants)
        owner = np.array(owner)
        vc, _ = evaluate(variants)
        ok = target - vc <= eps_tol + 1e-12
        nxt = []
        for i in live:
            sel = np.where((owner == i) & ok)[0]
            if sel.size:
                best = sel[np.argmax(vc[sel])]
                g[i] = variants[best]
                if int(round(g[i, 0])) > 1:
                    nxt.append(i)
        live = np.array(nxt, dtype=int)
    return g


def separate_angles(genomes: np.ndarray, min_sep: float, step: float) -> np.ndarray:
    """Repair NP genomes so that no two used angles are closer than ``min_sep`` (rad).

    Walking the used angles in increasing order, an angle too close to the
    last kept one moves forward to the first grid angle (``step``; 0 for
    continuous) at least ``min_sep`` beyond it; an angle that would then come
    too close to the first one (around the ring) is dropped (N decreases).
    Genomes that already respect the separation are returned unchanged.
    """
    if min_sep <= 0:
        return genomes
    g = np.array(genomes, dtype=float, copy=True)
    tol = 1e-9
    # which genomes break the separation, for the whole population at once
    n = np.rint(g[:, 0]).astype(np.int64)
    used = np.arange(g.shape[1] - 1)[None, :] < n[:, None]
    srt = np.sort(np.where(used, np.mod(g[:, 1:], TWO_PI), np.inf), axis=1)
    with np.errstate(invalid="ignore"):
        gaps = np.diff(srt, axis=1)                     # inf - inf = nan: never "too close"
    last = srt[np.arange(n.size), np.maximum(n - 1, 0)]
    wrap = np.where(n > 1, srt[:, 0] + TWO_PI - last, TWO_PI)
    bad = (gaps < min_sep - tol).any(axis=1) | (wrap < min_sep - tol)
    for i in np.flatnonzero(bad):
        k = int(n[i])
        ang = srt[i, :k]
        kept = [ang[0]]
        for a in ang[1:]:
            if a - kept[-1] < min_sep - tol:
                a = kept[-1] + min_sep
                if step > 0:
                    a = math.ceil(a / step - tol) * step
            if a + min_sep - tol <= kept[0] + TWO_PI and a < TWO_PI:
                kept.append(a)
        g[i, 0] = len(kept)  # the unused genes behind N keep their old values
        g[i, 1:1 + len(kept)] = kept
    return g


def swarm_keys(genomes: np.ndarray, angle_step: float) -> list[bytes]:
    """One hashable key per NP genome: its N and the sorted multiset of its used
    angles (grid indices when ``angle_step > 0``, else the angles mod 2 pi)."""
    g = np.asarray(genomes, dtype=float)
    n = np.rint(g[:, 0]).astype(np.int64)
    ang = np.mod(g[:, 1:], TWO_PI)
    if angle_step > 0:
        m = max(1, int(round(TWO_PI / angle_step)))
        ang = np.mod(np.rint(ang / angle_step), m)
    used = np.arange(ang.shape[1])[None, :] < n[:, None]
    srt = np.sort(np.where(used, ang, np.inf), axis=1)
    rows = np.concatenate([n[:, None].astype(float), srt], axis=1)
    return [r.tobytes() for r in rows]


def _run_pygad(*, num_genes, gene_type, gene_space, search: GASearch, batch_fitness, progress,
               repair=None, start=None):
    import pygad

    population, stall = search.population, search.stall_generations

    history_best: list[float] = []
    history_mean: list[float] = []
    state = {"stall": 0, "best": -np.inf}

    def fitness_func(ga, solutions, idx):
        return list(batch_fitness(np.atleast_2d(np.asarray(solutions, dtype=float))))

    def on_generation(ga):
        f = np.asarray(ga.last_generation_fitness, dtype=float)
        history_best.append(float(f.max()))
        history_mean.append(float(f.mean()))
        if progress is not None:
            progress(len(history_best), float(f.max()), float(f.mean()))
        if f.max() > state["best"] + 1e-12:
            state["best"] = float(f.max())
            state["stall"] = 0
        else:
            state["stall"] += 1
        if repair is not None:
            ga.population[:] = repair(np.asarray(ga.population, dtype=float))
            # parents of the next generation are chosen on the repaired genomes' fitness
            ga.last_generation_fitness = np.asarray(
                batch_fitness(np.asarray(ga.population, dtype=float)), dtype=float)
        if stall and state["stall"] >= stall:
            return "stop"
        return None

    def on_start(ga):
        if start is not None:
            ga.population[:] = start(np.asarray(ga.population, dtype=float))

    ga = pygad.GA(
        num_generations=int(search.generations),
        num_parents_mating=int(search.parents or max(2, population // 2)),
        fitness_func=fitness_func,
        fitness_batch_size=int(population),
        sol_per_pop=int(population),
        num_genes=num_genes,
        gene_type=gene_type,
        gene_space=gene_space,
        parent_selection_type="tournament",
        K_tournament=3,
        keep_elitism=int(search.elitism),
        crossover_type="uniform",
        mutation_type="random",
        mutation_probability=float(search.mutation_probability),
        mutation_by_replacement=True,
        on_generation=on_generation,
        on_start=on_start,
        random_seed=search_seed(search.seed),
        suppress_warnings=True,
    )
    ga.run()
    return ga, np.asarray(history_best), np.asarray(history_mean)


def run_nadir_ga(evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                 settings: NadirGASettings | None = None, *, progress=None, cover=None,
                 **keywords) -> GAResult:
    """NP swarm-size design.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(genomes (P, 1 + n_max)) -> (coverage (P,), n (P,))``, the
        batch evaluator (coverage as a fraction).
    settings : NadirGASettings
        The search (``angle_step_rad``: gene step of the angles, 0 continuous;
        ``target``: coverage fraction to reach, 1.0 or the reachable maximum;
        ``eps_tol``: allowed shortfall, fraction; ``min_separation_rad``: smallest
        angle between two spacecraft, see
        :func:`~ideas_hpc.flyby.swarm_geometry.min_separation_angle`). Genomes are
        repaired by :func:`separate_angles` before they are scored, and the
        repaired genome replaces the original (Lamarckian).
    **keywords
        The older keyword call (``n_max=..., population=..., angle_step=...,
        min_separation=...``), used when ``settings`` is None.
    cover : ideas_hpc.design.ga.local_search.GridCover, optional
        The masks of every grid angle. With it, the initial population gets
        ``seed_fraction`` greedy swarms from random first angles and every
        generation is improved by the set-cover local search of
        :mod:`ideas_hpc.design.ga.local_search` (completion, removal, 2-for-1 swaps);
        without it, by :func:`reduce_swarms`.
    """
    if settings is None:
        settings = NadirGASettings.from_keywords(**keywords)
    s = settings
    n_max, eps_tol, angle_step, target = s.n_max, s.eps_tol, s.angle_step_rad, s.target
    min_separation, seed, seed_fraction = s.min_separation_rad, s.search.seed, s.seed_fraction
    _check_ga(s.search.population, s.search.generations)
    if int(n_max) < 1:
        raise InputError(f"must be >= 1, got {n_max}", field="n_max")
    ang = {"low": 0.0, "high": TWO_PI}
    if angle_step > 0:
        ang["step"] = float(angle_step)
    gene_space = [{"low": 1, "high": int(n_max) + 1, "step": 1}] + [ang] * int(n_max)
    gene_type = [int] + [float] * int(n_max)
    count = {"n": 0}
    raw_evaluate = evaluate

    memo: dict = {}

    def evaluate(genomes):  # noqa: F811  (every genome is scored as its separated version)
        # A design is its multiset of grid angles: each distinct one is scored once
        # per run (a converged population repeats its swarms generation after generation).
        g = separate_angles(np.atleast_2d(genomes), min_separation, angle_step)
        keys = swarm_keys(g, angle_step)
        new = {}
        for i, k in enumerate(keys):
            if k not in memo and k not in new:
                new[k] = i
        if new:
            cov_new, n_new = raw_evaluate(g[list(new.values())])
            memo.update(zip(new, zip(np.asarray(cov_new, float).tolist(),
                                     np.asarray(n_new).tolist())))
            count["n"] += len(new)
        got = [memo[k] for k in keys]
        return (np.array([c for c, _ in got], dtype=float),
                np.array([m for _, m in got], dtype=np.int64))

    def batch(genomes):
        cov, n = evaluate(genomes)
        return nadir_fitness(cov, n, n_max, target, eps_tol)

    def repair(genomes):
        g = separate_angles(genomes, min_separation, angle_step)
        if cover is not None:
            return separate_angles(cover.improve(g), min_separation, angle_step)
        return reduce_swarms(g, evaluate, target, eps_tol)

    def start(genomes):
        if cover is None:
            return genomes
        rng = search_rng(seed, GA_SEEDING)
        return repair(cover.seed_population(genomes, seed_fraction, rng))

    ga, hb, hm = _run_pygad(num_genes=1 + int(n_max), gene_type=gene_type, gene_space=gene_space,
                            search=s.search, batch_fitness=batch, progress=progress,
                            repair=repair, start=start)
    pop = separate_angles(np.asarray(ga.population, dtype=float), min_separation, angle_step)
    cov, n = evaluate(pop)
    fit = nadir_fitness(cov, n, n_max, target, eps_tol)
    b = int(np.argmax(fit))
    return GAResult(best_fitness=hb, mean_fitness=hm, population=pop, fitness=fit, coverage=cov,
                    best_genome=pop[b].copy(), best_fitness_value=float(fit[b]),
                    best_coverage=float(cov[b]), best_swarm_size=int(n[b]),
                    evaluations=count["n"], target_coverage=float(target))


def run_fov_ga(evaluate: Callable[[np.ndarray], np.ndarray],
               settings: FovGASettings | None = None, *, progress=None,
               **keywords) -> GAResult:
    """FoV sweep-period design: maximise coverage over periods ``P_i`` (s).

    ``evaluate(genomes (P, N)) -> coverage (P,)`` as fractions. ``settings``
    (:class:`~ideas_hpc.design.ga.settings.FovGASettings`), or the older keyword
    call (``n_spacecraft=..., p_min=..., p_max=..., period_step=..., population=...``).
    """
    if settings is None:
        settings = FovGASettings.from_keywords(**keywords)
    n_spacecraft, p_min, p_max = settings.n_spacecraft, settings.p_min_s, settings.p_max_s
    period_step = settings.period_step_s
    _check_ga(settings.search.population, settings.search.generations)
    if not (p_min > 0 and p_max > p_min):
        raise InputError(f"P_min ({p_min / 60:g} min) must be below P_max ({p_max / 60:g} min)",
                         field="p_min")
    space = {"low": float(p_min), "high": float(p_max)}
    if period_step > 0:
        space["step"] = float(period_step)
    count = {"n": 0}

    def batch(genomes):
        count["n"] += len(genomes)
        return 100.0 * evaluate(genomes)

    ga, hb, hm = _run_pygad(num_genes=int(n_spacecraft), gene_type=float,
                            gene_space=[space] * int(n_spacecraft), search=settings.search,
                            batch_fitness=batch, progress=progress)
    pop = np.asarray(ga.population, dtype=float)
    cov = evaluate(pop)
    b = int(np.argmax(cov))
    return GAResult(best_fitness=hb, mean_fitness=hm, population=pop, fitness=100.0 * cov,
                    coverage=cov, best_genome=pop[b].copy(), best_fitness_value=100.0 * cov[b],
                    best_coverage=float(cov[b]), best_swarm_size=int(n_spacecraft),
                    evaluations=count["n"], target_coverage=1.0)
