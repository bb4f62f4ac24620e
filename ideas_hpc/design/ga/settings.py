"""Frozen settings of the genetic designers (pymoo's algorithm object: the search's
knobs travel together, apart from the problem and the run).

:class:`GASearch` holds what every PyGAD run reads; :class:`NadirGASettings`
and :class:`FovGASettings` add what the NP and FoV designs read. Angles are in
rad and periods in s, as the field names say.
"""

from __future__ import annotations

from dataclasses import dataclass, fields


@dataclass(frozen=True)
class GASearch:
    """The PyGAD search: population size, generations, seed and the operators."""

    population: int
    generations: int
    seed: int
    parents: int | None = None
    elitism: int = 2
    mutation_probability: float = 0.1
    stall_generations: int = 0


def _split(cls, kw: dict, renames: dict):
    """``cls`` built from the old keyword names (``renames``: old -> field), the
    search's own keys pulled into a :class:`GASearch`."""
    kw = {renames.get(k, k): v for k, v in kw.items()}
    search_keys = {f.name for f in fields(GASearch)}
    search = GASearch(**{k: kw.pop(k) for k in list(kw) if k in search_keys})
    return cls(search=search, **kw)


@dataclass(frozen=True)
class NadirGASettings:
    """NP swarm-size GA (:func:`~ideas_hpc.design.ga.genetic.run_nadir_ga`).

    ``eps_tol`` and ``target`` are coverage fractions; ``angle_step_rad`` 0 means
    continuous angles; ``seed_fraction`` of the first population is seeded
    greedily when a grid cover is given.
    """

    search: GASearch
    n_max: int
    eps_tol: float
    angle_step_rad: float
    target: float = 1.0
    min_separation_rad: float = 0.0
    seed_fraction: float = 0.2

    @classmethod
    def from_keywords(cls, **kw) -> "NadirGASettings":
        """The settings of the keyword call ``run_nadir_ga(evaluate, n_max=..., ...)``."""
        return _split(cls, kw, {"angle_step": "angle_step_rad",
                                "min_separation": "min_separation_rad"})


@dataclass(frozen=True)
class FovGASettings:
    """FoV sweep-period GA (:func:`~ideas_hpc.design.ga.genetic.run_fov_ga`); periods in s."""

    search: GASearch
    n_spacecraft: int
    p_min_s: float
    p_max_s: float
    period_step_s: float = 0.0

    @classmethod
    def from_keywords(cls, **kw) -> "FovGASettings":
        """The settings of the keyword call ``run_fov_ga(evaluate, n_spacecraft=..., ...)``."""
        return _split(cls, kw, {"p_min": "p_min_s", "p_max": "p_max_s",
                                "period_step": "period_step_s"})
