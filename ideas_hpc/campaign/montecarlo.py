"""Monte Carlo campaigns over initial attitudes and perturbations (SPEC section 8).

The campaign kind ``monte-carlo``: store layout, chunk task and run. The swarm's
trajectories are designed once on the nominal model (targeted ``v0``,
:func:`~ideas_hpc.montecarlo.sample.design_nominal`). Each sample then flies
that design open loop through its own world
(:func:`~ideas_hpc.montecarlo.sample.fly_sample`), perturbed by the declared
dispersions of :mod:`ideas_hpc.montecarlo.dispersions` (attitude, gravity,
reflectivity, initial state, failures, misalignment), whose module docstring
gives the seed streams and draw order. Every draw is stored, so a sample
re-runs alone: ``ideas_hpc.campaign.montecarlo.run_sample(campaign, k)``.

Work is split into chunks of samples (``run.chunk_size``); each chunk is one
dask task that flies its samples and writes its region of the store
(:mod:`ideas_hpc.engine`).
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import numpy as np
import xarray as xr

from ideas_hpc.engine.job_cluster import JobCluster, visibility_tests
from ideas_hpc.engine.runner import run_campaign
from ideas_hpc.base.progress import plural, result
from ideas_hpc.flyby.flight import FlybySetup, Perturbation
from ideas_hpc.campaign.setup import requirement_from_campaign, setup_from_campaign
from ideas_hpc.mapping.requirement import meets
from ideas_hpc.montecarlo.dispersions import dispersion_order, dispersion_vars, draw_sample
from ideas_hpc.montecarlo.sample import Nominal, design_nominal, fly_sample
from ideas_hpc.engine.variables import ATTITUDE_SERIES, DISCARDS, PER_SAMPLE, QUALITY, VARS, with_attrs
from ideas_hpc.campaign import datasets
from ideas_hpc.campaign.schema.campaign_tables import Campaign, resolved_config


def mc_chunk(chunk_id: int, start: int, stop: int, *, setup: FlybySetup, nominal: Nominal,
             mc, seed: int) -> dict:
    """Chunk task: fly samples ``start..stop-1`` and return their arrays (sample first)."""
    rows = []
    for k in range(start, stop):
        values, pert = draw_sample(mc, seed, k, nominal.theta, setup)
        r = fly_sample(setup, nominal, Perturbation(**pert))
        r.update(values)
        rows.append(r)
    return {name: np.stack([np.asarray(r[name]) for r in rows]) for name in rows[0]}


def _lazy(shape, dtype):
    import dask.array as da

    return da.zeros(shape, dtype=dtype, chunks=shape)


def mc_template(setup: FlybySetup, nom: Nominal, n_samples: int) -> xr.Dataset:
    """Store layout: per-sample variables (declared) and the nominal design (written)."""
    ns, n = int(n_samples), nom.theta.size
    nv = setup.body.shape.n_vertices
    dec = setup.decimate
    times = nom.times[::dec]
    nt = times.size
    simulated = setup.attitude.closed_loop
    s = ("sample",)
    sizes = {"spacecraft": n, "axis": 3, "wheel": 3, "vertex": nv, "time": nt}

    def per_sample(var):
        return (s + var.dims, _lazy((ns, *(sizes[d] for d in var.dims)), var.dtype),
                var.attrs())

    v = {name: per_sample(VARS[name]) for name in PER_SAMPLE}
    v.update({
        "swarm_angle": (("spacecraft",), nom.theta),
        "position": (("spacecraft", "time", "axis"), nom.position_T[:, ::dec]),
        "velocity": (("spacecraft", "time", "axis"), nom.velocity_T[:, ::dec]),
        "targeting_miss": (("spacecraft", "iteration"), nom.miss),
        **datasets.mesh_vars(setup.body.shape),
    })
    v.update({var.name: per_sample(var) for var in dispersion_vars()})
    if setup.coverage.wants_quality:
        v.update({name: per_sample(VARS[name]) for name in QUALITY})
    if nom.periods is not None:
        v["sweep_period"] = (("spacecraft",), nom.periods)
    if simulated:
        v.update({name: per_sample(VARS[name]) for name in ATTITUDE_SERIES})
        if setup.imaging is not None:
            v.update({name: per_sample(VARS[name]) for name in DISCARDS})
    ds = xr.Dataset(v, coords={"sample": np.arange(ns), "spacecraft": np.arange(n),
                               "time": ("time", times, {"units": "s"}),
                               "iteration": np.arange(nom.miss.shape[1]),
                               "axis": datasets.AXES, "wheel": datasets.WHEELS,
                               "vertex": np.arange(nv)})
    return with_attrs(ds)


def _prepare(c: Campaign):
    setup = setup_from_campaign(c)
    sw = c.config.swarm
    periods = setup.maneuver.swarm_periods(sw.sweep_periods_s)
    nom = design_nominal(setup, sw.angles_rad, periods)
    return setup, nom


def run_sample(c: Campaign, k: int) -> dict:
    """Re-run sample ``k`` of a campaign alone (same numbers as in the store)."""
    setup, nom = _prepare(c)
    return mc_chunk(k, k, k + 1, setup=setup, nominal=nom, mc=c.config.monte_carlo,
                    seed=c.config.seed)


def run_monte_carlo(c: Campaign, out, *, workers=None, scheduler=None, resume=False,
                    cluster="local", slurm_config=None, progress=True):
    """Kind ``monte-carlo``: chunked, resumable, on dask (SPEC section 8)."""
    setup, nom = _prepare(c)
    print(f"body: {setup.body.note}", file=sys.stderr, flush=True)
    mc = c.config.monte_carlo
    n = mc.samples
    template = mc_template(setup, nom, n)
    fn = functools.partial(mc_chunk, setup=setup, nominal=nom.for_tasks(), mc=mc,
                           seed=c.config.seed)
    attrs = datasets.base_attrs(c, setup)
    attrs["dispersion_order"] = list(dispersion_order())  # fixes the draw order
    work = visibility_tests(n, nom.theta.size, setup.image_times.size,
                            setup.body.shape.n_vertices)
    logs = Path(out).absolute().parent / f"{Path(out).name}.slurm-logs"
    with JobCluster(workers=workers, scheduler=scheduler, cluster=cluster,
                    slurm_config=slurm_config, work=work, log_directory=logs) as job:
        # sample 0 here first: the workers load its kernels from the Numba cache
        client = job.client(warm=functools.partial(fn, 0, 0, 1))
        summary = run_campaign(out, template, fn, config=resolved_config(c),
                               campaign_seed=c.config.seed,
                               chunk_size=c.config.run.chunk_size, attrs=attrs, resume=resume,
                               client=client, in_process=job.in_process, progress=progress)
    print(str(summary), file=sys.stderr, flush=True)
    with xr.open_zarr(out) as ds:
        coverage = np.asarray(ds["coverage"].values, dtype=float)
        n_failed = np.asarray(ds["n_failed"].values) if "n_failed" in ds else None
    # the swarm is given: no reach, so the rule's target for an unknown one (100 %)
    result(coverage_result(coverage, n_failed, requirement_from_campaign(c).threshold().need))
    return summary


def coverage_result(coverage, n_failed, threshold: float) -> str:
    """The result line of a Monte Carlo campaign: how often the swarm reaches the threshold
    (the paper's requirement, 100 % - ``design.eps_tol_pct``), the coverage percentiles and
    how many samples lost a spacecraft. Unfinished samples (NaN) are counted apart."""
    cov = np.asarray(coverage, dtype=float)
    ok = np.isfinite(cov)
    c = 100 * cov[ok]
    if not c.size:
        return "Monte Carlo result: no finished sample"
    line = (f"Monte Carlo result: P(coverage >= {100 * threshold:.2f} %) = "
            f"{100 * np.mean(meets(cov[ok], threshold)):.1f} % over "
            f"{plural(int(c.size), 'sample')} "
            f"(threshold: 100 % - design.eps_tol_pct); coverage min {c.min():.2f} %, "
            f"5th percentile {np.percentile(c, 5):.2f} %, median {np.median(c):.2f} %, "
            f"max {c.max():.2f} %")
    if n_failed is not None:
        nf = np.asarray(n_failed)[ok]
        line += f"; {plural(int((nf > 0).sum()), 'sample')} with a failed spacecraft"
    if (~ok).any():
        line += f"; {plural(int((~ok).sum()), 'sample')} not finished"
    return line
