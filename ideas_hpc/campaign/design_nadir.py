"""Kind ``design-nadir``, method ``exact``: the registry's entry.

Without ``design.success_probability`` it runs the certified design for a
world where nothing goes wrong (:mod:`ideas_hpc.campaign.design_exact`); with
it, the success-probability design over the scenario bank
(:mod:`ideas_hpc.campaign.design_reliability`), which builds on the first.
Both end in :func:`~ideas_hpc.campaign.design_exact.run_exact` (one job
cluster, the verification or validation, the flyby of the chosen swarm).
"""

from __future__ import annotations

import functools

import numpy as np
import xarray as xr

from ideas_hpc.campaign.design_exact import checked_setup, run_exact
from ideas_hpc.campaign.design_distance import design_distances
from ideas_hpc.campaign.design_reliability import design_reliable, scenario_store_path


def run_design_exact(c, out, *, workers=None, scheduler=None, cluster="local",
                     slurm_config=None, **_) -> xr.Dataset:
    """Registry entry of kind ``design-nadir``, method ``exact`` (module docstring)."""
    setup = checked_setup(c, np.linspace(0.0, 2 * np.pi, 16, endpoint=False))
    designer = None
    if c.config.design.success_probability is not None:
        # design.ca_distances_km: the distance is a dimension of the design (its banks
        # choose it; design_distance.py); unset: the one distance, as before
        designer = functools.partial(
            design_reliable if c.config.design.ca_distances_m is None else design_distances,
            bank_store=scenario_store_path(out))
    return run_exact(c, setup, workers=workers, scheduler=scheduler, cluster=cluster,
                     slurm_config=slurm_config, designer=designer)
