"""The campaign kinds: one registry, read by the schema and by the runner.

Each kind names the module and function that run it. A one-piece kind's
function returns the finished ``xarray.Dataset`` and
:func:`ideas_hpc.campaign.run.run_file` writes it through the engine as a
one-chunk store (:mod:`ideas_hpc.engine.single`); a chunked kind plans its
chunks and runs them on the engine itself (:func:`ideas_hpc.engine.run_campaign`).
Functions are imported when the kind runs, so the registry costs nothing and
has no import cycle. A new kind is a module with its run function and one
entry here (plus its keys in :mod:`ideas_hpc.campaign.schema.campaign_tables` if it has any).
A kind whose ``design.method`` picks a different entry lists it in ``methods``
(method -> module and function), so this table alone says which function runs.

Each entry also lists the keys of its own that its run reads (``reads``; a
``methods`` entry lists those of its function): the ``[design]`` and
``[monte_carlo]`` keys, ``run.workers``, ``run.chunk_size``. A key that some kind
lists is refused, with one line naming it, in a file whose kind does not list it
(:mod:`ideas_hpc.campaign.schema.reads`, which also holds the conditions on other
settings: ``attitude.mode``, ``flyby.geometry``, ``design.success_probability``...).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable


#: Where a kind's flown swarm comes from (:attr:`Kind.swarm`).
SWARM_SOURCES = ("file", "file-angles", "designed")

#: In :attr:`Kind.reads`: every ``[monte_carlo]`` key a dispersion declares (read live,
#: :func:`ideas_hpc.montecarlo.dispersions.dispersion_keys`).
DISPERSION_KEYS = "monte_carlo.<dispersions>"
#: The angle grid: the key and its deprecated alias (``design_checks``).
ANGLE_STEP = ("design.angle_step_deg", "design.angle_step_rad")
#: The PyGAD search of the GAs (:class:`ideas_hpc.design.api.GASearch`).
GA_SEARCH = ("design.population", "design.generations", "design.parents", "design.elitism",
             "design.mutation_probability", "design.stall_generations")
#: What every fewest-spacecraft designer of design-nadir reads (bank, N, requirement, cluster).
COVER = ("design.method", "design.n_max", "design.eps_tol_pct", "design.target_rule",
         "design.time_limit_s", "design.chunk_size", "run.workers", *ANGLE_STEP)


@dataclass(frozen=True)
class Kind:
    """A campaign kind.

    ``run(c, out, *, workers, scheduler, cluster, slurm_config, progress, resume)``
    returns an ``xarray.Dataset`` (``chunked=False``) or writes the store
    itself through the engine (``chunked=True``).
    """

    name: str
    module: str
    function: str
    chunked: bool
    doc: str
    #: ``((method, module, function, reads), ...)``: the entry of each ``design.method``
    #: that is not ``module.function``, with the keys of its own that it reads.
    methods: tuple = ()
    #: The maneuver (``attitude.maneuver`` name) the kind always flies, whatever
    #: the file says; ``None``: the file's.
    maneuver: str | None = None
    # --- capabilities: what the schema, the scans and the report read, so that
    # no kind name is compared outside this module
    #: Where the flown swarm comes from: ``"file"`` (``swarm.angles_rad`` and,
    #: for a sweeping maneuver, ``swarm.sweep_periods_min``), ``"file-angles"``
    #: (the angles from the file or a nadir design store, the periods designed)
    #: or ``"designed"`` (the kind designs the angles).
    swarm: str = "file"
    #: Scores stereo pairs (``coverage.require_stereo``).
    stereo: bool = False
    #: Designs for ``design.success_probability`` (the scenario bank).
    success_probability: bool = False
    #: ``design.method`` values that take continuous angles (``angle_step_deg = 0``).
    continuous_methods: tuple = ()
    #: Its store's ``swarm_angle`` is one nadir-pointing design, readable as
    #: ``design.nadir_store``.
    nadir_swarm_store: bool = False
    #: Its store holds dispersed samples (dimension ``sample``).
    samples: bool = False
    #: Its store holds one flown swarm (``swarm_angle``, with ``sweep_period`` when it
    #: sweeps; the chosen swarm of a design, the nominal design of dispersed samples),
    #: which ``ideas-hpc export`` writes as SPICE kernels.
    one_swarm: bool = True
    #: The keys of its own that ``module.function`` reads (dotted; :data:`DISPERSION_KEYS`
    #: for every dispersion's): a key some kind lists is refused where the kind that
    #: runs does not list it (:mod:`ideas_hpc.campaign.schema.reads`).
    reads: tuple = ()

    def __post_init__(self):
        if self.swarm not in SWARM_SOURCES:
            raise ValueError(f"kind {self.name!r}: swarm must be one of {SWARM_SOURCES}")

    @property
    def designs(self) -> bool:
        """The kind designs something (angles or periods) rather than flying a given swarm."""
        return self.swarm != "file"

    def runner(self, method: str | None = None) -> Callable:
        """The run function, of ``design.method = method`` when the kind lists one."""
        module, function = self.module, self.function
        for m, mod, fn, *_ in self.methods:
            if m == method:
                module, function = mod, fn
        return getattr(importlib.import_module(module), function)

    def reads_of(self, method: str | None = None) -> tuple:
        """The keys of its own that the entry of ``design.method = method`` reads."""
        for m, _, _, *reads in self.methods:
            if m == method:
                return tuple(reads[0]) if reads else ()
        return tuple(self.reads)

    def entries(self) -> tuple:
        """``((method or None, reads), ...)``: every entry that can run, ``None`` for the
        kind's own (``module.function``: every method not listed in ``methods``)."""
        return ((None, tuple(self.reads)),
                *((m, tuple(r[0]) if r else ()) for m, _, _, *r in self.methods))


KINDS: dict[str, Kind] = {k.name: k for k in (
    Kind("flyby", "ideas_hpc.campaign.flyby_kind", "run_flyby", False,
         "one flyby of swarm.angles_rad",
         reads=("spacecraft",)),    # the wheel-limit check of its pointing, ideal or not
    Kind("design-nadir", "ideas_hpc.campaign.design_ga", "run_design", False,
         "fewest spacecraft for the coverage target (exact integer programme or GA)",
         methods=(("exact", "ideas_hpc.campaign.design_nadir", "run_design_exact",
                   COVER + ("design.failures_tolerated", "design.verify_samples",
                            "design.coverage_reference", DISPERSION_KEYS)),),
         swarm="designed", stereo=True, success_probability=True,
         continuous_methods=("ga",), nadir_swarm_store=True,
         reads=COVER + GA_SEARCH),     # the GA, with its gap to the exact optimum
    Kind("design-fov", "ideas_hpc.campaign.design_ga", "run_design", False,
         "sweep periods of a swarm with half the field of view (GA)", maneuver="fov",
         swarm="file-angles",
         reads=GA_SEARCH + ("design.p_max_min", "design.period_step_min", "design.nadir_store",
                            "design.chunk_size", "run.workers")),
    Kind("design-pareto", "ideas_hpc.campaign.design_pareto", "run_design_pareto", False,
         "non-dominated swarms for two or more objectives (NSGA-II), with the exact "
         "coverage-vs-N curve for (n, coverage)", swarm="designed", one_swarm=False,
         reads=("design.objectives", "design.n_max", "design.population", "design.generations",
                "design.parents", "design.mutation_probability", "design.time_limit_s",
                "design.chunk_size", "run.workers", *ANGLE_STEP)),
    Kind("monte-carlo", "ideas_hpc.campaign.montecarlo", "run_monte_carlo", True,
         "dispersed flights of a designed swarm, chunked and resumable", samples=True,
         # eps_tol_pct, target_rule: the result line's threshold
         reads=("monte_carlo.samples", DISPERSION_KEYS, "design.eps_tol_pct",
                "design.target_rule", "run.chunk_size", "run.workers")),
)}


def kind_of(name: str) -> Kind:
    """The registered kind ``name`` (a store's ``kind`` attr, a campaign's ``kind``)."""
    try:
        return KINDS[name]
    except KeyError:
        raise ValueError(f"unknown campaign kind {name!r}; one of "
                         f"{', '.join(KINDS)}") from None
