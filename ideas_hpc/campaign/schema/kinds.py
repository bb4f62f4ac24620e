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
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable


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
    #: ``((method, module, function), ...)``: the entry of each ``design.method``
    #: that is not ``module.function``.
    methods: tuple = ()
    #: The maneuver (``attitude.maneuver`` name) the kind always flies, whatever
    #: the file says; ``None``: the file's.
    maneuver: str | None = None

    def runner(self, method: str | None = None) -> Callable:
        """The run function, of ``design.method = method`` when the kind lists one."""
        module, function = self.module, self.function
        for m, mod, fn in self.methods:
            if m == method:
                module, function = mod, fn
        return getattr(importlib.import_module(module), function)


KINDS: dict[str, Kind] = {k.name: k for k in (
    Kind("flyby", "ideas_hpc.campaign.flyby_kind", "run_flyby", False,
         "one flyby of swarm.angles_rad"),
    Kind("design-nadir", "ideas_hpc.campaign.design_ga", "run_design", False,
         "fewest spacecraft for the coverage target (exact integer programme or GA)",
         methods=(("exact", "ideas_hpc.campaign.design_nadir", "run_design_exact"),)),
    Kind("design-fov", "ideas_hpc.campaign.design_ga", "run_design", False,
         "sweep periods of a swarm with half the field of view (GA)", maneuver="fov"),
    Kind("design-pareto", "ideas_hpc.campaign.design_pareto", "run_design_pareto", False,
         "non-dominated swarms for two or more objectives (NSGA-II), with the exact "
         "coverage-vs-N curve for (n, coverage)"),
    Kind("monte-carlo", "ideas_hpc.campaign.montecarlo", "run_monte_carlo", True,
         "dispersed flights of a designed swarm, chunked and resumable"),
)}
