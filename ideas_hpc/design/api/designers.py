"""The registered designers: thin adapters from (problem, settings) to each
designer's own function, and from its own record to :class:`DesignResult`.

The designers' internals are untouched; an adapter only unpacks the settings
and repacks the outcome.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ideas_hpc.design.api.result import DesignResult, Designer, register
from ideas_hpc.design.bank import CandidateBank
from ideas_hpc.design.exact import min_swarm
from ideas_hpc.design.failures import failure_tolerant
from ideas_hpc.design.ga.genetic import run_fov_ga, run_nadir_ga
from ideas_hpc.design.ga.settings import FovGASettings, NadirGASettings
from ideas_hpc.design.pareto.nsga2 import run_pareto
from ideas_hpc.design.reliability import min_swarm_reliable
from ideas_hpc.design.settings import CoverSettings, ReliableSettings
from ideas_hpc.design.stereo import StereoBank, min_swarm_stereo

_NONE = np.zeros(0, dtype=np.int64)


@dataclass(frozen=True)
class ScenarioProblem:
    """The scenario bank: ``rows`` (S, C, V) bool, ``areas`` (V,) m^2 shared or (S, V) per
    scenario (drawn worlds, issue 42: zero outside a world's reference area) and the
    candidates' angles ``theta_rad`` (C,)."""

    rows: np.ndarray
    areas: np.ndarray
    theta_rad: np.ndarray


@dataclass(frozen=True)
class NadirGAProblem:
    """The NP GA's problem: ``evaluate(genomes) -> (coverage, n)`` and, on a grid,
    the set-cover local search (:class:`~ideas_hpc.design.ga.local_search.GridCover`)."""

    evaluate: Callable
    cover: object = None


@dataclass(frozen=True)
class FovGAProblem:
    """The FoV GA's problem: ``evaluate(genomes) -> coverage`` over the periods of
    the swarm ``theta_rad``."""

    evaluate: Callable
    theta_rad: np.ndarray


@dataclass(frozen=True)
class ParetoSettings:
    """NSGA-II over the candidate bank (:func:`~ideas_hpc.design.pareto.nsga2.run_pareto`)."""

    objectives: tuple
    n_max: int
    population: int
    generations: int
    seed: int
    min_separation_m: float = 0.0
    parents: int | None = None
    mutation_probability: float = 0.1


def _from_exact(name: str, r) -> DesignResult:
    return DesignResult(designer=name, swarm_rad=np.asarray(r.theta), indices=r.indices,
                        n=int(r.n), status=r.status, bound=float(r.bound), gap=float(r.gap),
                        value=float(r.coverage), notes=tuple(r.notes),
                        timings_s={"solve": float(r.solve_time)}, detail=r)


def _cover(fn, name, tolerant=False):
    """``fn(problem[, k], threshold=..., ...)``; only a ``tolerant`` designer reads k (the
    stereo designer scores pairs of a whole swarm)."""
    def solve(problem, s: CoverSettings, progress):
        kw = dict(threshold=s.threshold, n_max=s.n_max,
                  min_separation=s.min_separation_m, time_limit=s.time_limit_s)
        if tolerant:
            return _from_exact(name, fn(problem, s.failures_tolerated, **kw))
        return _from_exact(name, fn(problem, **kw))
    return solve


def _reliable(problem: ScenarioProblem, s: ReliableSettings, progress) -> DesignResult:
    r = min_swarm_reliable(problem.rows, problem.areas, s)
    return DesignResult(designer="success-probability",
                        swarm_rad=np.asarray(problem.theta_rad)[r.indices], indices=r.indices,
                        n=int(r.n), status=r.status, bound=float(r.bound), gap=float(r.gap),
                        value=float(r.probability), notes=tuple(r.notes),
                        timings_s={"solve": float(r.solve_time)}, detail=r)


def _nadir_ga(problem: NadirGAProblem, s: NadirGASettings, progress) -> DesignResult:
    from ideas_hpc.design.ga.swarm_eval import snap_angle

    r = run_nadir_ga(problem.evaluate, s, progress=progress, cover=problem.cover)
    n = r.best_swarm_size
    swarm = np.sort(np.asarray([snap_angle(a, s.angle_step_rad)[0]
                                for a in r.best_genome[1:1 + n]]))
    return DesignResult(designer="ga-nadir", swarm_rad=swarm, indices=_NONE, n=int(n),
                        status="ga", bound=math.nan, gap=math.nan, value=float(r.best_coverage),
                        notes=tuple(r.notes), timings_s={}, detail=r)


def _fov_ga(problem: FovGAProblem, s: FovGASettings, progress) -> DesignResult:
    r = run_fov_ga(problem.evaluate, s, progress=progress)
    return DesignResult(designer="ga-fov", swarm_rad=np.asarray(problem.theta_rad),
                        indices=_NONE, n=int(r.best_swarm_size), status="ga", bound=math.nan,
                        gap=math.nan, value=float(r.best_coverage), notes=tuple(r.notes),
                        timings_s={}, detail=r)


def _pareto(problem: CandidateBank, s: ParetoSettings, progress) -> DesignResult:
    r = run_pareto(problem, s.objectives, n_max=s.n_max, population=s.population,
                   generations=s.generations, seed=s.seed, min_separation=s.min_separation_m,
                   parents=s.parents, mutation_probability=s.mutation_probability,
                   progress=progress)
    return DesignResult(designer="pareto", swarm_rad=np.zeros(0), indices=_NONE,
                        n=len(r.swarms), status="front", bound=math.nan, gap=math.nan,
                        value=math.nan, notes=tuple(r.notes), timings_s={"solve": r.wall_s},
                        detail=r)


register(Designer("exact", CoverSettings, CandidateBank, _cover(min_swarm, "exact"),
                  applies=lambda s: not s.failures_tolerated,
                  doc="fewest candidates covering the target (HiGHS set cover)"))
register(Designer("failure-tolerant", CoverSettings, CandidateBank,
                  _cover(failure_tolerant, "failure-tolerant", tolerant=True),
                  applies=lambda s: s.failures_tolerated > 0,
                  doc="fewest candidates keeping the target after any k failures"))
register(Designer("stereo", CoverSettings, StereoBank, _cover(min_swarm_stereo, "stereo"),
                  doc="fewest candidates mapping the target in stereo (pair model)"))
register(Designer("success-probability", ReliableSettings, ScenarioProblem, _reliable,
                  doc="fewest candidates with P_bank >= p on the scenario bank"))
register(Designer("ga-nadir", NadirGASettings, NadirGAProblem, _nadir_ga,
                  doc="the paper's NP swarm-size GA"))
register(Designer("ga-fov", FovGASettings, FovGAProblem, _fov_ga,
                  doc="the paper's FoV sweep-period GA"))
register(Designer("pareto", ParetoSettings, CandidateBank, _pareto,
                  doc="NSGA-II non-dominated swarms of several objectives"))
