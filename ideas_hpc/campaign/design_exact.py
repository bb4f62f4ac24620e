"""Kind ``design-nadir`` with ``design.method = "exact"`` (issue 13), and the GA's gap.

Orchestration only: the candidate bank (:mod:`ideas_hpc.design.bank`), the
proven fewest spacecraft (:func:`~ideas_hpc.design.exact.min_swarm`) or the
failure-tolerant design (:func:`~ideas_hpc.design.failures.failure_tolerant`),
the coverage-versus-N curve, the enumeration of every failure of the chosen
swarm, and the store variables ``design_method``, ``solver_status``,
``optimality_gap``, ``coverage_vs_n`` (dim ``n_spacecraft``) and
``worst_failure_coverage``.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from ideas_hpc.design.bank import grid_size, separation_steps
from ideas_hpc.design import build_bank, coverage_curve, worst_failure
from ideas_hpc.design.api import CoverSettings, minimize
from ideas_hpc.design.stereo import stereo_curve
from ideas_hpc.design.stereo import scorer as stereo_scorer
from ideas_hpc.engine.job_cluster import JobCluster, phase_client, visibility_tests
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import result
from ideas_hpc.design.candidates import candidate_masks
from ideas_hpc.design.resolution import eps_tol_warning
from ideas_hpc.flyby.flight import fly, target
from ideas_hpc.campaign.setup import requirement_from_campaign, setup_from_campaign
from ideas_hpc.flyby.reference_area import reference_areas
from ideas_hpc.campaign import precompile
from ideas_hpc.montecarlo.verify import verify_swarm
from ideas_hpc.campaign import datasets
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.campaign.vocabulary import requirement_line, verification_verdict
from ideas_hpc.campaign.schema.design_checks import designer_errors
from ideas_hpc.campaign.schema.design_table import verify_samples
from ideas_hpc.design.api.methods import method_of_designer

#: The stored method of a GA design (one vocabulary, :mod:`ideas_hpc.design.api.methods`).
GA_METHOD = method_of_designer("ga-nadir").name


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


@dataclass
class ExactDesign:
    """What run_design needs: the swarm, the variables to store, attrs and notes."""

    theta: np.ndarray
    data: xr.Dataset
    attrs: dict
    notes: list = field(default_factory=list)
    summary: str = ""
    bank: object = field(default=None, repr=False)     # the nominal candidate bank
    threshold: object = None    # the requirement's Threshold on that bank
    # (campaign, setup) the swarm was designed at when not the run's own: the
    # closest-approach distance design.ca_distances_km chose (campaign/design_distance.py)
    flown: tuple | None = field(default=None, repr=False)


def _threshold(bank, requirement, notes: list):
    """The requirement's :class:`~ideas_hpc.mapping.requirement.Threshold` on the bank: its
    target rule against the highest coverage all grid candidates reach together."""
    reach = bank.reach
    if reach <= 0.0:
        raise InputError("no grid candidate maps any vertex under the [coverage] options and "
                         "requirement: loosen them (or check flyby.epoch_s for the lighting)",
                         field="coverage")
    thr = requirement.threshold(reach)
    if thr.target == reach < 1.0:
        lim = requirement.limits
        what = "the [coverage] requirement" if lim.requirement else \
            f"{lim.mode} mode (strict options: {lim.strict})"
        notes.append(f"100 % is not reachable from this ring with {what}; the highest "
                     f"reachable coverage is {100 * reach:.3f} % (all {bank.n_candidates} grid "
                     f"angles), so the target is that and the threshold "
                     f"{100 * thr.need:.3f} % (target - eps_tol)")
    elif thr.target != 1.0:
        notes.append(f"target rule {requirement.rule!r}: target {100 * thr.target:.3f} %, "
                     f"threshold {100 * thr.need:.3f} % (the grid candidates reach "
                     f"{100 * reach:.3f} % together)")
    return thr


def failure_vars(bank, swarm_idx, k: int) -> dict:
    """``worst_failure_coverage`` and ``worst_failure`` (positions in the swarm) for k failures."""
    worst, failed, covs, _ = worst_failure(bank, swarm_idx, k)
    pos = np.searchsorted(np.sort(swarm_idx), failed).astype(np.int32)
    return {"worst_failure_coverage": ((), worst),
            "worst_failure": (("failed",), pos),
            "failure_cases": ((), np.int64(covs.size))}


def design_exact(c, setup, client) -> ExactDesign:
    """The certified NP design of a campaign (module docstring).

    ``client``: a :class:`distributed.Client`, None (this process) or the
    job's :class:`~ideas_hpc.engine.job_cluster.JobCluster`.
    """
    d = c.config.design
    requirement = requirement_from_campaign(c)
    k = d.failures_tolerated
    sep = c.config.swarm.min_separation_m
    n_grid = grid_size(d.grid_step_rad)
    # a separation no two grid points satisfy fails before any mask is computed
    with designer_errors(c):
        separation_steps(2 * math.pi / n_grid, setup.d_sep_m, sep, n_grid)
    stereo = setup.coverage.require_stereo      # grid size checked with the config
    t0 = time.perf_counter()
    if not stereo:  # the pair table is one pass in this process
        client = phase_client(client, functools.partial(candidate_masks, setup,
                                                        [(0.0, 0.0, 0)]))
    bank = build_bank(setup, d.grid_step_rad, client=client, chunk_size=d.chunk_size,
                      quality=stereo, pairs=stereo)
    if requirement.reference != "surface":   # issue 42: rows weighed by the reference area
        bank = dataclasses.replace(bank, areas=reference_areas(setup, requirement))
    scorer = stereo_scorer(bank) if stereo else bank
    t_masks = time.perf_counter() - t0
    _log(f"candidate {'rows' if setup.coverage.requirement else 'masks'}: {bank.n_candidates} "
         f"grid angles ({math.degrees(bank.step_rad):g} deg)"
         f"{' and their stereo pairs' if stereo else ''} in {t_masks:.1f} s")
    notes: list = []
    coarse = eps_tol_warning(bank.areas[bank.areas > 0], requirement.eps_tol)
    if coarse is not None:          # it still runs: a strict requirement may be meant
        _log(coarse)
    thr = _threshold(scorer, requirement, notes)
    # the problem (the bank, or its stereo scorer) and the settings pick the designer
    settings = CoverSettings(threshold=thr, n_max=d.n_max, min_separation_m=sep,
                             time_limit_s=d.time_limit_s, failures_tolerated=k)
    with designer_errors(c):
        res = minimize(scorer, settings)
    notes.extend(res.notes)
    t_design = time.perf_counter() - t0
    curve = (stereo_curve(scorer, d.n_max, min_separation=sep, time_limit=d.time_limit_s)
             if stereo else
             coverage_curve(bank, d.n_max, min_separation=sep, time_limit=d.time_limit_s))
    curve.include(res.indices, res.value)
    k_eval = k if k else 1
    data = {
        "design_method": ((), method_of_designer(res.designer).name),
        "solver_status": ((), res.status),
        "optimality_gap": ((), res.gap),
        "proven_bound": ((), res.bound),
        "solve_time": ((), res.timings_s["solve"]),
        "best_swarm_size": ((), np.int64(res.n)),
        "design_coverage": ((), res.value),
        "coverage_vs_n": (("n_spacecraft",), curve.coverage),
        "coverage_vs_n_gap": (("n_spacecraft",), curve.gap),
        "coverage_vs_n_status": (("n_spacecraft",), np.array(curve.status, dtype="U16")),
        "coverage_vs_n_swarm": (("n_spacecraft", "slot"), curve.angles(bank.theta)),
        **(failure_vars(scorer, res.indices, k_eval) if res.n > k_eval else {}),
    }
    ds = xr.Dataset(data, coords={"n_spacecraft": curve.n})
    if "worst_failure_coverage" in ds:  # the other units and names: store_schema
        ds["worst_failure_coverage"].attrs.update(
            units="1", long_name=f"lowest coverage after any {k_eval} failure(s)")
    attrs = {"design_method": method_of_designer(res.designer).name, "solver_status": res.status,
             "optimality_gap": float(res.gap), "target_coverage": float(thr.target),
             "threshold_coverage": float(thr.need),
             "design_masks_s": float(t_masks), "design_solve_s": float(t_design - t_masks),
             "coverage_curve_s": float(curve.solve_time), "failures_tolerated": int(k),
             "failures_evaluated": int(k_eval), "angle_step_rad": float(bank.step_rad),
             **({"eps_tol_warning": coarse} if coarse is not None else {})}
    summary = (f"exact design: N = {res.n} ({res.status}, gap {100 * res.gap:.1f} %, bound "
               f"{res.bound:g}), {requirement_line(thr.target, thr.need, res.value)}, "
               f"{'k = %d tolerant, ' % k if k else ''}masks {t_masks:.1f} s + solve "
               f"{t_design - t_masks:.1f} s; coverage-vs-N curve in {curve.solve_time:.1f} s")
    return ExactDesign(theta=res.swarm_rad, data=ds, attrs=attrs, notes=notes, summary=summary,
                       bank=bank, threshold=thr)


def ga_gap(c, setup, mask_bank, n_ga: int, threshold) -> tuple[xr.Dataset, list]:
    """The GA's gap to the certified optimum on the GA's own angle grid (masks reused), at
    the GA's ``threshold``."""
    d = c.config.design
    step = d.angle_step_rad
    if step <= 0:
        return xr.Dataset({"design_method": ((), GA_METHOD)}), [
            "continuous GA angles: no exact optimum to compare with"]
    bank = build_bank(setup, step, mask_bank=mask_bank, snap=False)
    try:
        with designer_errors():   # the note quotes the file's keys
            ex = minimize(bank, CoverSettings(
                threshold=threshold, n_max=d.n_max,
                min_separation_m=c.config.swarm.min_separation_m, time_limit_s=d.time_limit_s))
    except InputError as exc:
        return xr.Dataset({"design_method": ((), GA_METHOD)}), [f"no exact reference: {exc.message}"]
    if not ex.optimal:
        return xr.Dataset({"design_method": ((), GA_METHOD)}), [
            f"exact reference not proven in time (N = {ex.n}, gap {ex.gap:.2f})"]
    gap = (n_ga - ex.n) / n_ga
    ds = xr.Dataset({"design_method": ((), GA_METHOD), "solver_status": ((), GA_METHOD),
                     "optimality_gap": ((), gap), "proven_bound": ((), float(ex.n))})
    note = (f"the GA's N = {n_ga}; the certified optimum on the same {bank.n_candidates}-angle "
            f"grid is N = {ex.n} (gap {100 * gap:.1f} %)")
    return ds, [note]


def verification_vars(c, setup, theta, threshold: float, client) -> tuple[dict, dict, str]:
    """Monte Carlo verification of the chosen swarm (``design.verify_samples``).

    Flies the swarm through the campaign's ``[monte_carlo]`` dispersions with
    the campaign seed; returns store variables, attrs and a summary line.
    """
    m = verify_samples(c.config.design)
    if m == 0:
        return {}, {}, "Monte Carlo verification: off (design.verify_samples = 0)"
    kw = dict(mc=c.config.monte_carlo, seed=c.config.seed, threshold=threshold)
    client = phase_client(client, functools.partial(verify_swarm, setup, theta, None,
                                                    n_samples=1, **kw))
    v = verify_swarm(setup, theta, None, n_samples=m, client=client, **kw)
    data = {"verify_coverage": (("verify_sample",), v.coverage),
            "verify_n_failed": (("verify_sample",), v.n_failed)}
    required = getattr(c.config.design, "success_probability", None)
    verdict = verification_verdict(v.probability, m, threshold, required)
    attrs = {"verify_samples": int(m), "verify_threshold": float(threshold),
             "verify_probability": v.probability, "verify_wall_s": float(v.wall_s),
             "verify_passed": int(verdict.startswith("verification PASSED")),
             "verify_verdict": verdict}
    return data, attrs, v.summary()


def reference_coverage(w, cov) -> float:
    """A flight's mapped (or, without a requirement, observed) area as a fraction of the
    reference area of vertex weights ``w`` (:mod:`ideas_hpc.mapping.reference`); ``cov``
    its :class:`~ideas_hpc.mapping.coverage.CoverageResult`."""
    mapped = cov.observed if cov.quality is None else cov.quality.mapped
    return float(np.sum(w[np.asarray(mapped, dtype=bool)]) / np.sum(w))


def checked_setup(c, theta):
    """The kind's flyby setup (with the maneuver its registry entry flies), checked by
    targeting swarm ``theta`` once here: a targeting failure is the user's to fix, in
    one line, rather than a failed task on every worker."""
    setup = setup_from_campaign(c, maneuver=KINDS[c.kind].maneuver)
    # a design over a target prior's drawn worlds names the prior (datasets.flown_body)
    _log(f"body: {datasets.flown_body(c, setup).get('body_note', setup.body.note)}")
    target(setup, theta)
    return setup


def run_exact(c, setup, *, workers=None, scheduler=None, cluster="local",
              slurm_config=None, designer=None) -> xr.Dataset:
    """Kind ``design-nadir``, method ``exact``: certified design, its Monte Carlo
    verification, then a flyby of it (the store). ``designer`` replaces
    :func:`design_exact` (the success-probability design validates its own swarm)."""
    helper = precompile.start(setup, c)  # cold cache: later kernels compile alongside
    try:
        with designer_errors(c):
            return _run_exact(c, setup, workers, scheduler, cluster, slurm_config, designer)
    finally:
        if helper is not None:
            helper.close()


def _run_exact(c, setup, workers, scheduler, cluster, slurm_config, designer) -> xr.Dataset:
    d = c.config.design
    n_img, n_v = setup.image_times.size, setup.body.shape.n_vertices
    n_grid = grid_size(d.grid_step_rad)
    work = (visibility_tests(n_grid, 1, n_img, n_v)
            + visibility_tests(verify_samples(d), d.n_max, n_img, n_v))
    if designer is not None:   # the scenario bank: every candidate in every scenario
        work += visibility_tests(getattr(d, "scenarios", 0) * n_grid, 1, n_img, n_v)
    # one cluster at most, for every phase (masks, scenarios, verification), when it pays back
    with JobCluster(workers=workers, scheduler=scheduler, cluster=cluster,
                    slurm_config=slurm_config, work=work) as client:
        res = (designer or design_exact)(c, setup, client)
        if res.flown is not None:   # the store flies and records the chosen distance
            c, setup = res.flown
        result(res.summary)
        for note in res.notes:
            result(f"note: {note}")
        threshold = res.attrs["threshold_coverage"]
        vdata, vattrs, vline = ({}, {}, None) if designer else \
            verification_vars(c, setup, res.theta, threshold, client)
    if vline:
        result(vline)
    if vattrs:
        result(vattrs["verify_verdict"])
    flight = fly(setup, res.theta)
    ds = datasets.flyby_dataset(setup, flight)
    ds = xr.merge([ds, res.data, xr.Dataset(vdata)], combine_attrs="override")
    ds["best_coverage"] = ((), flight.coverage.coverage)
    requirement = requirement_from_campaign(c)
    if requirement.reference != "surface":
        w = reference_areas(setup, requirement)
        ds["reference_area"] = (("vertex",), w)
        ds["best_coverage_of_reference"] = ((), reference_coverage(w, flight.coverage))
    ds.attrs.update(datasets.base_attrs(c, setup))
    ds.attrs.update(res.attrs)
    ds.attrs.update(vattrs)
    ds.attrs["notes"] = json.dumps(res.notes)
    return ds
