"""Kind ``design-pareto`` (issue 14 item 5): the non-dominated swarms for several objectives.

Orchestration only: the candidate bank (:func:`~ideas_hpc.design.build_bank`,
the masks of every grid angle), NSGA-II over it
(:func:`~ideas_hpc.design.pareto.nsga2.run_pareto`, objectives from
``design.objectives``), and the store variables with dim ``pareto`` (one row
per non-dominated swarm, ordered by the objectives in the order given):

* ``pareto_n`` (swarm size), ``pareto_coverage`` and ``pareto_<objective>``
  for every chosen objective, natural sign and units;
* ``pareto_swarm`` (pareto, slot): the swarm angles, rad, NaN-padded.

For the two objectives (``n``, ``coverage``) the proven coverage-versus-N
curve (:func:`~ideas_hpc.design.coverage_curve`) is stored beside the front
under the names the exact designer uses (``coverage_vs_n``, dim
``n_spacecraft``), with ``pareto_gap_to_exact`` = ``C*(N) - C(front point)``
per front point (0 where the front reaches the proven optimum).

Keys read: ``design.objectives``, ``angle_step_deg``, ``n_max``, ``population``,
``generations``, ``parents``, ``mutation_probability``, ``time_limit_s`` (the
exact curve), ``chunk_size`` and ``swarm.min_separation_km``. NSGA-II keeps
the best half of each generation, so ``design.elitism`` and the NP GA's
``eps_tol_pct`` / ``stall_generations`` do not apply. No flyby is stored: a
front has no single swarm to fly (run a ``flyby`` of a chosen ``pareto_swarm``
row).
"""

from __future__ import annotations

import json
import math
import sys
import time

import numpy as np
import xarray as xr

from ideas_hpc.base.progress import result
from ideas_hpc.design.stereo import check_grid
from ideas_hpc.design import build_bank, coverage_curve
from ideas_hpc.design.bank import grid_size, separation_steps
from ideas_hpc.design.pareto.objectives import OBJECTIVES, bank_needs, check_objectives, evaluate
from ideas_hpc.design.api import ParetoSettings, minimize
from ideas_hpc.engine.job_cluster import JobCluster, visibility_tests
from ideas_hpc.flyby.flight import target
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.campaign import datasets
from ideas_hpc.campaign.schema.design_checks import STEP_KEY, designer_errors

#: A front point matches the exact curve when their coverages differ by at most this.
MATCH_TOL = 1e-12


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _progress(total: int):
    from ideas_hpc.base.progress import bar as progress_bar

    bar = progress_bar(total, "NSGA-II", unit="gen")

    def cb(gen, front):
        bar.update(1)
        bar.set_postfix(front=front)
        if gen >= total:
            bar.close()
    return cb


def _stored_names(names) -> tuple:
    """The chosen objectives, plus ``n`` and ``coverage`` (always stored)."""
    return tuple(dict.fromkeys(("n", "coverage") + tuple(names)))


def pareto_dataset(bank, res, n_max: int) -> xr.Dataset:
    """The front as store variables (module docstring)."""
    stored = _stored_names(res.objectives)
    members = np.full((len(res.swarms), max(1, n_max)), -1, dtype=np.int64)
    for i, s in enumerate(res.swarms):
        members[i, :s.size] = s
    vals = evaluate(bank, stored, members) if len(res.swarms) else np.zeros((0, len(stored)))
    data = {}
    for j, name in enumerate(stored):
        o = OBJECTIVES[name]
        v = vals[:, j].astype(np.int64) if name == "n" else vals[:, j]
        data[f"pareto_{name}"] = (("pareto",), v, {"units": o.units, "long_name": o.long_name})
    data["pareto_swarm"] = (("pareto", "slot"), res.angles(bank.theta, n_max),
                            {"units": "rad", "long_name": "swarm angles of the front point "
                             "(NaN beyond its N)"})
    return xr.Dataset(data, coords={"pareto": np.arange(len(res.swarms)),
                                    "slot": np.arange(max(1, n_max))})


def exact_reference(bank, ds: xr.Dataset, n_max: int, sep: float, time_limit: float):
    """Coverage-versus-N curve and the front's gap to it; returns (dataset, attrs, note)."""
    curve = coverage_curve(bank, n_max, min_separation=sep, time_limit=time_limit)
    n = ds["pareto_n"].values
    exact = curve.coverage[n - 1]
    gap = exact - ds["pareto_coverage"].values
    proven = np.array([curve.status[k - 1] == "optimal" for k in n], dtype=bool)
    ok = np.abs(gap[proven]) <= MATCH_TOL
    ref = xr.Dataset({
        "coverage_vs_n": (("n_spacecraft",), curve.coverage,
                          {"units": "1", "long_name": "best coverage of N spacecraft (proven "
                           "per N)"}),
        "coverage_vs_n_gap": (("n_spacecraft",), curve.gap, {"units": "1"}),
        "coverage_vs_n_status": (("n_spacecraft",), np.array(curve.status, dtype="U16")),
        "coverage_vs_n_swarm": (("n_spacecraft", "slot"), curve.angles(bank.theta),
                                {"units": "rad"}),
        "pareto_gap_to_exact": (("pareto",), gap,
                                {"units": "1", "long_name": "proven best coverage at the "
                                 "point's N minus the point's coverage"}),
    }, coords={"n_spacecraft": curve.n})
    attrs = {"coverage_curve_s": float(curve.solve_time),
             "pareto_matches_exact": int(ok.all()),
             "pareto_max_gap_to_exact": float(np.max(np.abs(gap))) if gap.size else 0.0}
    note = (f"front against the exact coverage-vs-N curve: {int(ok.sum())} of {int(proven.sum())}"
            f" proven points matched within {MATCH_TOL:g} (largest gap "
            f"{attrs['pareto_max_gap_to_exact']:.3g})")
    return ref, attrs, note


def run_design_pareto(c, out, *, workers=None, scheduler=None, cluster="local",
                      slurm_config=None, **_) -> xr.Dataset:
    """Kind ``design-pareto``: bank, NSGA-II, the non-dominated set (module docstring)."""
    d = c.config.design
    sep = c.config.swarm.min_separation_m
    with designer_errors(c):
        names = check_objectives(d.objectives)
    setup = setup_from_campaign(c)
    _log(f"body: {setup.body.note}")
    target(setup, np.linspace(0.0, 2 * np.pi, 16, endpoint=False))
    n_grid = grid_size(d.grid_step_rad)
    needs = bank_needs(names)
    if "pairs" in needs:   # the pair table has one variable per candidate pair
        with designer_errors(c):
            check_grid(n_grid, STEP_KEY)
    # a separation no two grid points satisfy fails before any mask is computed
    with designer_errors(c):
        separation_steps(2 * math.pi / n_grid, setup.d_sep_m, sep, n_grid)
    t0 = time.perf_counter()
    work = visibility_tests(n_grid, 1, setup.image_times.size, setup.body.shape.n_vertices)
    with JobCluster(workers=workers, scheduler=scheduler, cluster=cluster,
                    slurm_config=slurm_config, work=work) as job:
        # stereo from two spacecraft needs the pair table (one pass, no cluster)
        bank = build_bank(setup, d.grid_step_rad,
                          client=None if "pairs" in needs else job.client(),
                          chunk_size=d.chunk_size, quality="quality" in needs,
                          pairs="pairs" in needs)
    t_masks = time.perf_counter() - t0
    _log(f"candidate masks: {bank.n_candidates} grid angles ({math.degrees(bank.step_rad):g} deg) "
         f"in {t_masks:.1f} s")
    with designer_errors(c):
        res = minimize(bank, ParetoSettings(
            objectives=names, n_max=d.n_max, population=d.population,
            generations=d.generations, seed=c.config.seed, min_separation_m=sep,
            parents=d.parents, mutation_probability=d.mutation_probability),
            progress=_progress(d.generations)).detail
    ds = pareto_dataset(bank, res, d.n_max)
    notes = list(res.notes)
    attrs = {"objectives": json.dumps(list(names)), "angle_step_rad": float(bank.step_rad),
             "design_masks_s": float(t_masks), "pareto_wall_s": float(res.wall_s),
             "pareto_evaluations": int(res.evaluations),
             "pareto_generations": int(res.generations)}
    if set(names) == {"n", "coverage"}:
        with designer_errors(c):
            ref, ref_attrs, note = exact_reference(bank, ds, d.n_max, sep, d.time_limit_s)
        ds = xr.merge([ds, ref], combine_attrs="override")
        attrs.update(ref_attrs)
        notes.append(note)
    result(f"Pareto front: {ds.sizes['pareto']} non-dominated swarms of "
         f"{', '.join(names)} in {res.wall_s:.1f} s ({res.evaluations} swarms scored)")
    for note in notes:
        result(f"note: {note}")
    ds.attrs.update(datasets.base_attrs(c, setup))
    ds.attrs.update(attrs)
    ds.attrs["notes"] = json.dumps(notes)
    return ds
