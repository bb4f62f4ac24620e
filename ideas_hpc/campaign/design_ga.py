"""Kinds ``design-nadir`` and ``design-fov`` (SPEC section 7).

``design-nadir`` runs the certified exact designer by default
(:mod:`ideas_hpc.campaign.design_exact`) or the paper's GA
(``design.method = "ga"``, with its gap to the certified optimum); ``design-fov``
runs the sweep-period GA. Each ends with a full flyby of the chosen swarm.
"""

from __future__ import annotations

import functools
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr

from ideas_hpc.base.progress import result
from ideas_hpc.design.candidates import candidate_masks
from ideas_hpc.design.api import (CoverSettings, FovGAProblem, FovGASettings, GASearch,
                                  NadirGAProblem, NadirGASettings, minimize)
from ideas_hpc.design.bank import grid_size
from ideas_hpc.engine.job_cluster import JobCluster, visibility_tests
from ideas_hpc.base.errors import InputError, config_fields
from ideas_hpc.flyby.flight import fly
from ideas_hpc.design.ga.local_search import GridCover
from ideas_hpc.design.ga.swarm_eval import MaskBank, fov_keys, nadir_keys, snap_angle
from ideas_hpc.base.progress import bar as progress_bar
from ideas_hpc.flyby.swarm_geometry import min_separation_angle
from ideas_hpc.campaign import datasets
from ideas_hpc.engine.variables import with_attrs
from ideas_hpc.campaign.design_exact import GA_METHOD, checked_setup, ga_gap
from ideas_hpc.campaign.setup import requirement_from_campaign
from ideas_hpc.mapping.requirement import threshold_of
from ideas_hpc.campaign.schema.campaign_tables import Campaign
from ideas_hpc.campaign.schema.design_checks import DESIGNER_FIELDS
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.campaign.schema.model_fields import FLYBY_FIELDS
from ideas_hpc.campaign.vocabulary import requirement_line


#: The GA's parameter names -> the campaign file's keys (with every designer's and the
#: flyby layer's: the GA flies setups).
GA_FIELDS = {**FLYBY_FIELDS, **DESIGNER_FIELDS, "population": "design.population",
             "generations": "design.generations", "p_min": "design.p_min_min"}


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _progress_printer(total: int, label: str):
    bar = progress_bar(total, label, unit="gen")

    def cb(gen, best, mean):
        bar.update(1)
        bar.set_postfix(best=f"{best:.3f}", mean=f"{mean:.3f}")
        if gen >= total:
            bar.close()
    return cb


def _search(c: Campaign) -> GASearch:
    """The PyGAD search of the file's ``[design]`` table and seed."""
    d = c.config.design
    return GASearch(population=d.population, generations=d.generations, seed=c.config.seed,
                    parents=d.parents, elitism=d.elitism,
                    mutation_probability=d.mutation_probability,
                    stall_generations=d.stall_generations)


def _bank(setup, client, design) -> MaskBank:
    return MaskBank(functools.partial(candidate_masks, setup), setup.body.shape.n_vertices,
                    chunk_size=design.chunk_size, client=client)


def _fill_grid(bank: MaskBank, setup, step: float) -> tuple[float, np.ndarray]:
    """Masks of every grid angle; returns the reachable coverage (union of all) and
    the (grid angle, vertex) masks."""
    n = max(1, int(round(2 * np.pi / step)))
    keys = [(k * step, 0.0, k) for k in range(n)]
    t = time.perf_counter()
    bank.ensure(keys, desc="candidate masks")
    cov, _ = bank.union_coverage([keys], setup.body.shape.vertex_areas)
    _log(f"candidate masks: {n} grid angles in {time.perf_counter() - t:.1f} s; a ring of all "
         f"of them reaches {100 * cov[0]:.3f} % (area)")
    return float(cov[0]), bank.masks[bank.rows(keys)]


def _stereo_ga(c: Campaign, setup, client):
    """The NP GA scoring stereo from two spacecraft with the pair model
    (:class:`~ideas_hpc.design.stereo.StereoBank` on the GA's own angle grid)."""
    from ideas_hpc.design import build_bank
    from ideas_hpc.design.stereo import scorer

    d = c.config.design
    step = d.angle_step_rad
    t = time.perf_counter()
    bank = build_bank(setup, step, client=client, chunk_size=d.chunk_size, snap=False,
                      quality=True, pairs=True)
    sb = scorer(bank)
    thr = requirement_from_campaign(c).threshold(sb.reach)
    _log(f"candidate rows and stereo pairs: {bank.n_candidates} grid angles in "
         f"{time.perf_counter() - t:.1f} s; all of them map {100 * sb.reach:.3f} % in stereo")

    def evaluate(genomes):
        idx = [np.unique([snap_angle(a, step)[1] for a in g[1:1 + int(round(g[0]))]])
               for g in genomes]
        return sb.coverage(idx), np.rint(genomes[:, 0]).astype(int)

    settings = NadirGASettings(
        search=_search(c), n_max=d.n_max, eps_tol=thr.eps_tol, angle_step_rad=step,
        target=thr.target,
        min_separation_rad=min_separation_angle(c.config.swarm.min_separation_m, setup.d_sep_m))
    out = minimize(NadirGAProblem(evaluate), settings,
                   progress=_progress_printer(d.generations, "NP GA (stereo)"))
    res, n = out.detail, out.n
    res.notes.append("GA scoring stereo from own tracks and from pairs of spacecraft (the "
                     "exact designer's pair model); no set-cover local search")
    try:
        ex = minimize(sb, CoverSettings(threshold=thr, n_max=d.n_max,
                                        min_separation_m=c.config.swarm.min_separation_m,
                                        time_limit_s=d.time_limit_s))
        gap = (n - ex.bound) / n
        res.gap_data = xr.Dataset({"design_method": ((), GA_METHOD), "solver_status": ((), GA_METHOD),
                                   "optimality_gap": ((), gap),
                                   "proven_bound": ((), float(ex.bound))})
        res.notes.append(f"the GA's N = {n}; the exact stereo designer on the same grid: N = "
                         f"{ex.n} ({ex.status}, proven lower bound {ex.bound:g}); gap to the "
                         f"bound {100 * gap:.1f} %")
    except InputError as exc:
        res.gap_data = xr.Dataset({"design_method": ((), GA_METHOD)})
        res.notes.append(f"no exact reference: {exc.message}")
    return res, out.swarm_rad, None


def design_nadir(c: Campaign, setup, client):
    """NP swarm-size GA (SPEC section 7). Returns (GAResult, angles, None)."""

    if setup.coverage.require_stereo:
        return _stereo_ga(c, setup, client)
    d = c.config.design
    requirement = requirement_from_campaign(c)
    bank = _bank(setup, client, d)
    step = d.angle_step_rad
    thr = requirement.threshold()      # continuous angles: no reach known
    notes = []
    masks = None
    if step > 0:
        reach, masks = _fill_grid(bank, setup, step)
        thr = requirement.threshold(reach)
        if thr.target == reach < 1.0:
            notes.append(f"100 % is not reachable from this ring in {setup.coverage.mode} mode "
                         f"(strict options: {setup.coverage.strict}); the highest reachable "
                         f"coverage is {100 * reach:.3f} % (all {int(round(2 * np.pi / step))} "
                         "grid angles), and the GA minimises N to reach that instead")
    areas = setup.body.shape.vertex_areas

    def evaluate(genomes):
        keys = [nadir_keys(g, step) for g in genomes]
        cov, _ = bank.union_coverage(keys, areas)
        return cov, np.rint(genomes[:, 0]).astype(int)

    min_sep = min_separation_angle(c.config.swarm.min_separation_m, setup.d_sep_m)
    cover = None if masks is None else GridCover(
        masks, areas, step, n_max=d.n_max, threshold=thr,
        min_sep_steps=math.ceil(min_sep / step - 1e-9) if min_sep > 0 else 0)
    settings = NadirGASettings(search=_search(c), n_max=d.n_max, eps_tol=thr.eps_tol,
                               angle_step_rad=step, target=thr.target,
                               min_separation_rad=min_sep)
    out = minimize(NadirGAProblem(evaluate, cover), settings,
                   progress=_progress_printer(d.generations, "NP GA"))
    res = out.detail
    if cover is not None:
        notes.append(f"GA with set-cover local search on the {cover.k} grid-angle masks "
                     "(greedy seeding of 20 % of the first population; completion, removal "
                     "and 2-for-1 swaps after each generation)")
    res.notes.extend(notes)
    res.gap_data, gap_notes = ga_gap(c, setup, bank, out.n, thr)
    res.notes.extend(gap_notes)
    return res, out.swarm_rad, None


def _fov_swarm(c: Campaign) -> np.ndarray:
    """The swarm to sweep: ``design.nadir_store`` (an NP design's best swarm) or ``swarm.angles_rad``."""
    src = c.config.design.nadir_store
    if src:
        try:
            ds = xr.open_zarr(src)
            theta = np.asarray(ds["swarm_angle"].values, dtype=float)
        except Exception as exc:
            raise c.error(f"cannot read the NP design store {src!r}: {exc}",
                          "design.nadir_store") from None
        if not getattr(KINDS.get(ds.attrs.get("kind")), "nadir_swarm_store", False):
            able = " or ".join(k.name for k in KINDS.values() if k.nadir_swarm_store)
            raise c.error(f"{src!r} is a {ds.attrs.get('kind')!r} store, not {able}",
                          "design.nadir_store")
        return theta
    return np.asarray(c.config.swarm.angles_rad, dtype=float)


def design_fov(c: Campaign, setup, client):
    """FoV sweep-period GA (SPEC section 7). Returns (GAResult, angles, periods)."""

    d = c.config.design
    theta = _fov_swarm(c)
    bank = _bank(setup, client, d)
    areas = setup.body.shape.vertex_areas
    step = d.period_step_s

    def evaluate(genomes):
        keys = [fov_keys(g, theta, d.p_min_s, step) for g in genomes]
        cov, _ = bank.union_coverage(keys, areas)
        return cov

    settings = FovGASettings(search=_search(c), n_spacecraft=theta.size, p_min_s=d.p_min_s,
                             p_max_s=d.p_max_s, period_step_s=step)
    res = minimize(FovGAProblem(evaluate, theta), settings,
                   progress=_progress_printer(d.generations, "FoV GA")).detail
    periods = np.array([k[1] for k in fov_keys(res.best_genome, theta, d.p_min_s, step)])
    return res, theta, periods


def run_design(c: Campaign, out: Path, *, workers=None, scheduler=None, cluster="local",
               slurm_config=None, **_) -> xr.Dataset:
    """Kinds ``design-nadir`` and ``design-fov``: GA, then a full flyby of the best swarm."""
    nadir = KINDS[c.kind].swarm == "designed"     # the GA designs angles, else periods
    setup = checked_setup(c, np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
                          if nadir else _fov_swarm(c))
    t = time.perf_counter()
    design = design_nadir if nadir else design_fov
    d = c.config.design
    # distinct candidate flights the GA can ask for: at most every grid angle
    # (nadir on a grid), at most every spacecraft of every individual
    n_flights = d.population * d.generations * d.n_max
    if nadir and d.angle_step_rad > 0:
        n_flights = min(n_flights, grid_size(d.angle_step_rad))
    work = visibility_tests(n_flights, 1, setup.image_times.size, setup.body.shape.n_vertices)
    with config_fields(GA_FIELDS), JobCluster(workers=workers, scheduler=scheduler,
                                              cluster=cluster, slurm_config=slurm_config,
                                              work=work) as job:
        res, theta, periods = design(c, setup, job.client())
    wall = time.perf_counter() - t
    threshold = threshold_of(res.target_coverage, c.config.design.eps_tol).need
    result(f"GA: {res.evaluations} designs evaluated in {wall:.1f} s; best: N = "
         f"{res.best_swarm_size}, " + (requirement_line(res.target_coverage, threshold,
                                                       res.best_coverage) if nadir else
                                       f"reached {100 * res.best_coverage:.3f} %"))
    for note in res.notes:
        result(f"note: {note}")
    if periods is not None and not nadir:
        result("sweep periods found (min): " + " ".join(f"{p / 60:.1f}" for p in periods))
    flight = fly(setup, theta, periods)
    ds = datasets.flyby_dataset(setup, flight)
    g = xr.Dataset({
        "best_fitness": (("generation",), res.best_fitness),
        "mean_fitness": (("generation",), res.mean_fitness),
        "population": (("individual", "gene"), res.population),
        "fitness": (("individual",), res.fitness),
        "population_coverage": (("individual",), res.coverage),
        "best_genome": (("gene",), res.best_genome),
        "best_swarm_size": ((), res.best_swarm_size),
        "best_coverage": ((), flight.coverage.coverage),
    }, coords={"generation": np.arange(1, res.best_fitness.size + 1)})
    ds = xr.merge([ds, with_attrs(g)], combine_attrs="override")
    if getattr(res, "gap_data", None) is not None:
        ds = xr.merge([ds, res.gap_data], combine_attrs="override")
    ds["best_fitness"].attrs["long_name"] = ("fitness (-N if feasible)" if nadir
                                            else "coverage, %")
    ds.attrs.update(datasets.base_attrs(c, setup))
    ds.attrs.update({"ga_evaluations": int(res.evaluations), "ga_wall_s": float(wall),
                     "target_coverage": float(res.target_coverage),
                     **({"threshold_coverage": float(threshold)} if nadir else {}),
                     "notes": json.dumps(res.notes)})
    return ds
