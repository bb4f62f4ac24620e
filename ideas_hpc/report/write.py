"""``ideas-hpc report STORE``: the paper's figures that apply, and a text summary."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from ideas_hpc.design.api.methods import method_of
from ideas_hpc.attitude.maneuvers import store_figure
from ideas_hpc.base.errors import InputError
from ideas_hpc.plots import figures
from ideas_hpc.base.units import DEG, KM
from ideas_hpc.report.reliability import (reliability_figures, reliability_lines,
                                                   swarm_label)
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.report.map_pool import MapPool
from ideas_hpc.report.requirement import coverage_meaning
from ideas_hpc.campaign.vocabulary import requirement_line, verification_verdict



def _shape(ds):
    from ideas_hpc.body.shape import build_shape

    return build_shape(ds["vertex_position"].values, ds["face_vertices"].values.astype(np.int64),
                       name=str(ds.attrs.get("shape_model", "body")), source="store")


def _summary(ds, figs) -> str:
    a = ds.attrs
    lines = [f"ideas_hpc report: kind {a.get('kind')}, code {a.get('code_version')}",
             f"body: {a.get('body_note', a.get('body'))}"]
    if "d_sep_m" in a:
        lines.append(f"ring radius d_sep {a['d_sep_m'] / KM:.3f} km, half angle "
                     f"{a['half_angle_rad'] / DEG:.4f} deg, far field {a['far_m'] / KM:.3f} km, "
                     f"maneuver {a.get('maneuver')}, attitude {a.get('attitude_mode')}, "
                     f"coverage mode {a.get('coverage_mode')}")
    if a.get("geometry") == "encounter":
        lines.append(f"encounter: {a['speed_m_s'] / KM:g} km/s, approach declination "
                     f"{a['approach_dec_rad'] / DEG:.1f} deg, right ascension "
                     f"{a['approach_ra_rad'] / DEG:.1f} deg, phase angle "
                     f"{a['phase_angle_rad'] / DEG:.1f} deg, closest approach at t = "
                     f"{a['t_ca_s']:g} s")
    if "pointing_feasible" in ds:
        lines.append(f"pointing: peak rate {float(ds['pointing_rate'].max()) / DEG:.3g} deg/s, "
                     f"torque {float(ds['pointing_torque'].max()) * 1e3:.3g} mN m, momentum "
                     f"{float(ds['pointing_momentum'].max()) * 1e3:.3g} mN m s; "
                     + ("the wheels can follow" if bool(ds["pointing_feasible"].all()) else
                        "WARNING: the wheels cannot follow for spacecraft "
                        f"{np.where(~ds['pointing_feasible'].values)[0].tolist()}"))
    if "swarm_angle" in ds and "sample" not in ds["swarm_angle"].dims:
        ang = " ".join(f"{x:.2f}" for x in ds["swarm_angle"].values)
        lines.append(f"swarm: N = {ds.sizes['spacecraft']}, angles (rad) {ang}")
        if "sweep_period" in ds:
            lines.append("sweep periods (min): "
                         + " ".join(f"{p / 60:.1f}" for p in ds["sweep_period"].values))
    if "best_fitness" in ds:
        lines.append(f"GA: {ds.sizes['generation']} generations, population "
                     f"{ds.sizes['individual']}, {a.get('ga_evaluations')} designs evaluated in "
                     f"{a.get('ga_wall_s', float('nan')):.1f} s; best swarm size "
                     f"{int(ds['best_swarm_size'])}, " + _requirement(ds))
        for note in json.loads(a.get("notes", "[]")):
            lines.append(f"note: {note}")
    if "coverage" in ds or "design_method" in ds:
        lines.append(coverage_meaning(ds))
    if "design_method" in ds:
        lines.extend(_design_lines(ds))
    if "pareto_n" in ds:
        lines.extend(_pareto_lines(ds))
    flown = (f" of the flown N = {int(ds['best_swarm_size'])} swarm"
             if "design_method" in ds and "best_swarm_size" in ds else "")
    if "coverage" in ds:
        cov = np.atleast_1d(ds["coverage"].values) * 100
        cnt = np.atleast_1d(ds["coverage_count"].values) * 100
        if cov.size == 1:
            lines.append(f"coverage{flown}: {cov[0]:.3f} % of the area, {cnt[0]:.3f} % of the "
                         "vertices")
        else:
            ok = np.isfinite(cov)
            lines.append(f"coverage over {ok.sum()} sample{'' if ok.sum() == 1 else 's'}: mean {cov[ok].mean():.3f} %, min "
                         f"{cov[ok].min():.3f} %, 5th percentile {np.percentile(cov[ok], 5):.3f} %,"
                         f" max {cov[ok].max():.3f} %")
        if "best_coverage_of_reference" in ds:
            lines.append(f"coverage{flown} of the reference area: "
                         f"{100 * float(ds['best_coverage_of_reference']):.3f} %")
        if "mapped" in ds and "coverage_seen" in ds:
            seen = np.atleast_1d(ds["coverage_seen"].values) * 100
            lines.append(f"coverage counts vertices meeting the [coverage] requirement; "
                         f"seen (no requirement): mean {np.nanmean(seen):.3f} % of the area")
    if "targeting_miss" in ds:
        m = ds["targeting_miss"].values
        last = np.nanmin(np.where(np.isfinite(m), m, np.inf), axis=-1)
        lines.append(f"targeting{flown}: worst final miss {np.max(last) * 1e3:.3f} mm "
                     f"(tolerance {a.get('targeting_tolerance_m', float('nan')) * 1e3:.0f} mm)")
    for var, unit, scale in (("sigma_error", "", 1.0), ("wheel_torque", "N m", 1.0),
                             ("wheel_speed", "rpm", figures.RPM)):
        if var in ds:
            v = np.abs(ds[var].values) * scale
            lines.append(f"{var}: max |.| {np.nanmax(v):.4g} {unit}; at the end "
                         f"{np.nanmax(v[..., -1, :]):.3g} {unit}")
    lines.append("figures: " + ", ".join(p.name for p in figs))
    return "\n".join(lines) + "\n"


def _requirement(ds) -> str:
    """target, threshold and reached, as in the run's own summary (vocabulary.py)."""
    a = ds.attrs
    target = float(a.get("target_coverage", 1.0))
    if "threshold_coverage" not in a and "verify_threshold" not in a:
        return f"target {100 * target:.3f} %, reached {100 * float(ds['best_coverage']):.3f} %"
    thr = float(a.get("threshold_coverage", a.get("verify_threshold")))
    return requirement_line(target, thr, float(ds["best_coverage"]))


def _design_lines(ds) -> list[str]:
    """The certified design's status, trade curve and worst failure (issue 13)."""
    a = ds.attrs
    method = str(ds["design_method"].values)
    out = []
    if "optimality_gap" in ds and "success_probability_required" not in ds:
        # (a success-probability store words its status apart: report_reliability)
        out.append(f"design: method {method}, status {str(ds['solver_status'].values)}, "
                   f"N = {int(ds['best_swarm_size'])}, proven lower bound "
                   f"{float(ds['proven_bound']):g}, optimality gap "
                   f"{100 * float(ds['optimality_gap']):.1f} %"
                   + (f"; {_requirement(ds)}" if method_of(method).proven else ""))
    if "coverage_vs_n" in ds:
        n, c = ds["n_spacecraft"].values, ds["coverage_vs_n"].values
        stop = int(np.argmax(c >= c[-1])) + 1       # the curve is flat after its maximum
        st = ds["coverage_vs_n_status"].values if "coverage_vs_n_status" in ds else \
            np.full(n.size, "optimal")
        gp = ds["coverage_vs_n_gap"].values if "coverage_vs_n_gap" in ds else np.zeros(n.size)
        pts = ", ".join(f"{int(k)}: {100 * v:.3f} %" + ("" if s == "optimal" else
                                                        f" (gap {100 * g:.2g} %)")
                        for k, v, s, g in zip(n[:stop], c[:stop], st[:stop], gp[:stop]))
        if stop < n.size:
            pts += f" (the same up to N = {int(n[-1])})"
        label = "proven" if all(s == "optimal" for s in st) else \
            "proven unless a gap to the proven bound is shown"
        out.append(f"best coverage for N spacecraft ({label}): {pts}")
    if "worst_failure_coverage" in ds:
        out.append(f"worst case after {a.get('failures_evaluated', 1)} failure(s) "
                   f"{swarm_label(ds)}: "
                   f"{100 * float(ds['worst_failure_coverage']):.3f} % (failed spacecraft "
                   f"{ds['worst_failure'].values.tolist()})")
    if "verify_coverage" in ds:
        from ideas_hpc.montecarlo.verify import verification_line   # the one wording

        c = ds["verify_coverage"].values
        out.append(verification_line(c, ds["verify_n_failed"].values,
                                     float(a["verify_threshold"]),
                                     float(a["verify_probability"]), who=swarm_label(ds)))
        out.append(a.get("verify_verdict") or verification_verdict(
            float(a["verify_probability"]), c.size, float(a["verify_threshold"])))
    out.extend(reliability_lines(ds))
    if method_of(method).proven:
        out.extend(f"note: {n}" for n in json.loads(a.get("notes", "[]")))
    return out


def _pareto_lines(ds) -> list[str]:
    """The non-dominated swarms of a design-pareto store, one line each."""
    a = ds.attrs
    names = json.loads(a.get("objectives", "[]"))
    out = [f"Pareto front ({', '.join(names)}): {ds.sizes['pareto']} non-dominated swarms, "
           f"{a.get('pareto_evaluations')} swarms scored in {a.get('pareto_wall_s', 0.0):.1f} s"]
    for i in range(ds.sizes["pareto"]):
        vals = []
        for name in names:
            v = float(ds[f"pareto_{name}"].values[i])
            unit = ds[f"pareto_{name}"].attrs.get("units", "")
            vals.append(f"{name} {int(v)}" if name == "n" else
                        f"{name} {100 * v:.3f} %" if unit == "1" else f"{name} {v:.4g} {unit}")
        ang = ds["pareto_swarm"].values[i]
        ang = " ".join(f"{x:.3f}" for x in ang[np.isfinite(ang)])
        out.append(f"  {', '.join(vals)}; angles (rad) {ang}")
    if "pareto_gap_to_exact" in ds:
        out.append(f"front against the proven coverage-vs-N curve: largest gap "
                   f"{a.get('pareto_max_gap_to_exact', float('nan')):.3g}; every proven point "
                   f"matched: {bool(a.get('pareto_matches_exact'))}")
    out.extend(f"note: {n}" for n in json.loads(a.get("notes", "[]")))
    return out


def _design_figures(ds, out: Path) -> list[Path]:
    from ideas_hpc.plots import design

    figs = []
    if "design_method" in ds and "swarm_angle" in ds and "d_sep_m" in ds.attrs:
        figs.append(design.ring_view(ds, out / "design_ring.png"))
    if "coverage_vs_n" in ds:
        figs.append(design.coverage_vs_n(ds, out / "design_coverage_vs_n.png"))
    if "pareto_n" in ds:
        figs.append(design.pareto_front(ds, out / "design_pareto_front.png"))
    if "verify_coverage" in ds:
        figs.append(design.verification(ds, out / "design_verification.png"))
    figs.extend(reliability_figures(ds, out))
    return figs


def _quality_maps(ds, shape, out, render_coverage_map):
    """Maps of the quality variables (issue 14) and area histograms. Monte Carlo:
    the per-vertex probability of the booleans and the median of the others
    (``render_coverage_map``: :meth:`~ideas_hpc.report.map_pool.MapPool.render`)."""
    from ideas_hpc.plots import figures

    mc = ds["best_resolution"].ndim == 2
    deg = 180.0 / np.pi
    figs = []
    for name, label, scale in (("best_resolution", "best resolution, m", 1.0),
                               ("emission_at_best", "emission at best, deg", deg),
                               ("incidence_at_best", "incidence at best, deg", deg),
                               ("n_spacecraft_seen", "spacecraft that saw the vertex", 1.0)):
        x = ds[name].values.astype(float) * scale
        if mc:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)   # never-seen vertices
                x = np.nanmedian(np.where(np.isfinite(x), x, np.nan), axis=0)
            label = "median " + label
        figs.append(render_coverage_map(shape, x, out / f"quality_{name}.png", kind="value",
                                        label=label, title=name))
    for name in ("stereo", "mapped", "lit"):
        x = ds[name].values
        if mc:
            figs.append(render_coverage_map(shape, x.mean(axis=0), out / f"quality_{name}.png",
                                            kind="fraction",
                                            title=f"probability of {name} per vertex"))
        else:
            figs.append(render_coverage_map(shape, x, out / f"quality_{name}.png",
                                            kind="observed", title=name))
    figs.append(figures.quality_histograms(ds, out / "quality_histograms.png"))
    return figs


def _ranges(ids) -> str:
    """``[0, 1, 2, 5]`` -> ``"0-2, 5"``."""
    parts, start = [], None
    for i, k in enumerate(ids):
        if start is None:
            start = k
        if i + 1 == len(ids) or ids[i + 1] != k + 1:
            parts.append(f"{start}" if start == k else f"{start}-{k}")
            start = None
    return ", ".join(parts)


def _check_complete(ds, store: Path) -> None:
    """Refuse a store with unfinished chunks (their samples read as NaN)."""
    if "chunk_done" not in ds:
        return
    missing = np.flatnonzero(~ds["chunk_done"].values.astype(bool)).tolist()
    if missing:
        raise InputError(f"incomplete store: chunk(s) {_ranges(missing)} of "
                         f"{ds.sizes['chunk']} not done; finish it with 'ideas-hpc run "
                         "CAMPAIGN --out STORE --resume'", file=store)


def write_report(store, out=None, *, html: bool = False, parallel: bool = False) -> Path:
    """Write PNGs and ``summary.txt`` for a store (and ``report.html`` with ``html``,
    :mod:`~ideas_hpc.report.html`); returns the summary path. ``parallel``: draw the
    body maps in a second process meanwhile (:mod:`~ideas_hpc.report.map_pool`; the
    ``ideas-hpc report`` command's choice)."""
    with MapPool(parallel) as maps:
        return _write_report(store, out, html, maps)


def _write_report(store, out, html: bool, maps: MapPool) -> Path:
    store = Path(store)
    if not store.exists():
        raise InputError("no such store", field="STORE", file=store)
    try:
        ds = xr.open_zarr(store)
    except Exception as exc:
        raise InputError(f"not a readable zarr store: {exc}", file=store) from None
    _check_complete(ds, store)
    out = Path(out) if out else store.with_name(store.name.removesuffix(".zarr") + "-report")
    out.mkdir(parents=True, exist_ok=True)
    figs: list[Path] = []
    kind = ds.attrs.get("kind", "")
    if "best_fitness" in ds:
        # a GA that designs N (the paper's NP design, Figs. 19-20) or one of given N
        # (its FoV design, Figs. 30-31): the kind's declared swarm capability
        sizes = getattr(KINDS.get(kind), "swarm", "") == "designed"
        n = "19" if sizes else "30"
        figs.append(figures.ga_fitness(ds, out / f"fig{n}_ga_fitness.png",
                                       title=f"{kind}: best and mean fitness"))
        n = "20" if sizes else "31"
        figs.append(figures.population_histogram(ds, out / f"fig{n}_final_population.png",
                                                 sizes=sizes))
    figs.extend(_design_figures(ds, out))
    shape = _shape(ds) if "vertex_position" in ds else None
    if "position" in ds:
        figs.append(figures.trajectories(ds, out / "fig22_trajectories.png",
                                         vertices=shape.vertices_T if shape else None,
                                         faces=shape.faces if shape else None))
    if "targeting_miss" in ds:
        figs.append(figures.targeting_error(ds, out / "fig23_targeting_error.png"))
    if "camera_dcm_BT" in ds and shape is not None and "sample" not in ds["position"].dims:
        snap_t = ds["snapshot_time"].values
        j = len(snap_t) // 2
        k = int(np.argmin(np.abs(ds["time"].values - snap_t[j])))
        n = store_figure(ds.attrs.get("maneuver"), "pyramids", 24)
        figs.append(figures.fov_pyramids(out / f"fig{n}_fov_pyramids.png",
                                         ds["position"].values[:, k],
                                         ds["camera_dcm_BT"].values[:, j],
                                         float(ds.attrs["half_angle_rad"]), float(snap_t[j]),
                                         vertices=shape.vertices_T, faces=shape.faces,
                                         body=shape.name))
    render_coverage_map = maps.render
    if "observed" in ds and shape is not None:
        obs = ds["observed"].values
        fs = ds["first_seen"].values
        if obs.ndim == 2:  # Monte Carlo: fraction of samples that saw each vertex
            obs = np.nanmean(obs.astype(float), axis=0)
            figs.append(render_coverage_map(shape, obs, out / "fig25_coverage_map.png",
                                            kind="fraction",
                                            title="fraction of samples that saw each vertex"))
        else:
            figs.append(render_coverage_map(shape, obs, out / "fig25_coverage_map.png",
                                            kind="observed", title="coverage map"))
            figs.append(render_coverage_map(shape, fs, out / "fig25b_first_seen.png",
                                            kind="first_seen"))
    if "best_resolution" in ds and shape is not None:
        figs += _quality_maps(ds, shape, out, render_coverage_map)
    base = store_figure(ds.attrs.get("maneuver"), "attitude", 26)
    for i, (var, label, scale) in enumerate((("sigma_error", "MRP error", 1.0),
                                             ("omega_error", "rate error, rad/s", 1.0),
                                             ("wheel_speed", "wheel speed, rpm", figures.RPM),
                                             ("wheel_torque", "wheel torque, N m", 1.0))):
        if var in ds:
            figs.append(figures.attitude_series(ds, var, out / f"fig{base + i}_{var}.png",
                                                ylabel=label, scale=scale))
    if "coverage" in ds and "sample" in ds["coverage"].dims:
        figs.append(figures.mc_coverage(ds, out / "mc_coverage.png"))
    from ideas_hpc.report.study import study_figures, study_groups, study_lines

    groups = study_groups(store)
    extras = study_figures(store, ds, groups, out, shape=shape)
    figs.extend(extras)
    maps.finish()            # every PNG written before the summary and the page list them
    summary = out / "summary.txt"
    summary.write_text(_summary(ds, figs) + "".join(f"{line}\n" for line in study_lines(groups)))
    if html:
        from ideas_hpc.report.html import write_html

        write_html(ds, summary.read_text(), out / "report.html", images=extras)
    return summary
