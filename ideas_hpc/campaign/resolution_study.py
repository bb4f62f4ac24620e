"""``ideas-hpc resolution``: one design campaign on a list of shape models (issue 29).

Each shape runs the campaign with ``body.name`` set to it, into its own store
``OUT/STEM-SHAPE.zarr`` (resumable: a finished store with the same config is
kept, so a cut-short study goes on where it stopped). The study prints one
table, N, coverage and (success-probability designs) P side by side, with the
mesh's vertex-area figures, and writes it as CSV (``OUT/resolution.csv``). A
requirement is resolved when N is the same on successively finer models
(SPEC 7d); ``docs/requirement.md`` has the study of the main job.
"""

from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.mapping.requirement import threshold_of

#: The four NASA PDS models of Eros, coarse to fine (plates).
EROS_MODELS = ("eros001708", "eros007790", "eros010152", "eros022540")


def _row(shape: str, store: Path, seconds: float, eps_list=()) -> dict:
    import xarray as xr

    from ideas_hpc.body.bodies import load_body
    from ideas_hpc.design.resolution import mesh_resolution

    ds = xr.open_zarr(store)
    a = ds.attrs
    mesh = mesh_resolution(load_body(shape).shape.vertex_areas)

    def scalar(name, default=np.nan):
        return float(ds[name].values) if name in ds else default

    return {"shape": shape, "vertices": mesh.n_vertices,
            "median_vertex_pct": 100 * mesh.median, "smallest_vertex_pct": 100 * mesh.smallest,
            "n": int(scalar("best_swarm_size")),
            "nominal_n": int(a.get("nominal_swarm_size", scalar("best_swarm_size"))),
            "coverage_pct": 100 * scalar("coverage"),
            "threshold_pct": 100 * float(a.get("threshold_coverage", np.nan)),
            "probability": scalar("reliability_probability"),
            "status": str(a.get("solver_status", "")),
            "gap_pct": 100 * float(a.get("optimality_gap", np.nan)),
            "seconds": seconds, "store": str(store),
            **{f"n_at_{e:g}pct": _n_at(ds, e / 100.0) for e in eps_list}}


def _n_at(ds, eps: float) -> str:
    """N at tolerance ``eps``: the run's own proven N at its own tolerance, else the curve's."""
    a = ds.attrs
    target = float(a.get("target_coverage", np.nan))
    own = target - float(a.get("threshold_coverage", np.nan))
    status = (str(ds["nominal_solver_status"].values) if "nominal_solver_status" in ds
              else a.get("solver_status"))         # success-probability stores: the nominal's
    nominal_proven = status == "optimal"
    if abs(own - eps) < 1e-9 and nominal_proven:
        return str(int(a.get("nominal_swarm_size", ds["best_swarm_size"].values)))
    return n_from_curve(ds, target, eps)


def n_from_curve(ds, target: float, eps: float) -> str:
    """Fewest N whose best coverage (the stored coverage-versus-N curve, proven per
    point when its status is ``optimal``) reaches ``target - eps``; ``"N*"`` when a
    smaller N is not proven short, ``"-"`` when no N of the curve reaches it."""
    if "coverage_vs_n" not in ds:
        return "-"
    n = np.asarray(ds["n_spacecraft"].values)
    cov = np.asarray(ds["coverage_vs_n"].values, dtype=float)
    status = np.array([str(x) for x in np.asarray(ds["coverage_vs_n_status"].values)])
    ok = np.flatnonzero(threshold_of(target, eps).meets(cov))
    if ok.size == 0:
        return "-"
    i = int(ok[0])
    proven = bool(np.all(status[:i] == "optimal"))
    return f"{int(n[i])}" + ("" if proven else "*")


def format_table(rows: list[dict]) -> str:
    """The study as a fixed-width text table (one line per shape)."""
    head = (f"{'shape':<12} {'vertices':>8} {'median w':>9} {'min w':>7} {'N':>3} "
            f"{'N nom':>5} {'coverage':>9} {'threshold':>9} {'P':>7} {'status':>10} "
            f"{'gap':>6} {'time':>7}")
    extra = [k for k in (rows[0] if rows else {}) if k.startswith("n_at_")]
    head += "".join(f" {'N@' + k[5:-3] + '%':>8}" for k in extra)
    out = [head, "-" * len(head)]
    for r in rows:
        p = "-" if not np.isfinite(r["probability"]) else f"{r['probability']:.4f}"
        out.append(f"{r['shape']:<12} {r['vertices']:>8d} {r['median_vertex_pct']:>8.3f}% "
                   f"{r['smallest_vertex_pct']:>6.3f}% {r['n']:>3d} {r['nominal_n']:>5d} "
                   f"{r['coverage_pct']:>8.3f}% {r['threshold_pct']:>8.3f}% {p:>7} "
                   f"{r['status']:>10} {r['gap_pct']:>5.1f}% {r['seconds']:>6.0f}s"
                   + "".join(f" {r[k]:>8}" for k in extra))
    ns = {r["n"] for r in rows}
    out.append("N is the same on every model: the requirement is resolved" if len(ns) == 1
               else f"N differs between models ({sorted(ns)}): the requirement follows the mesh")
    if extra:
        out.append("N@e%: fewest N whose proven best coverage (coverage-versus-N curve) "
                   "reaches target - e % (* : a smaller N is not proven short)")
    return "\n".join(out)


def resolution_study(campaign, shapes, *, overrides=None, out=None, workers=None,
                     progress=True, eps_list=()) -> tuple[list[dict], Path]:
    """Run ``campaign`` once per shape model; returns (rows, CSV path).

    ``eps_list`` (percent): also the N that other tolerances would give, read from each
    store's coverage-versus-N curve (no further run).
    """
    from ideas_hpc.campaign.run import run_file

    shapes = [s.strip() for s in shapes if s.strip()]
    if not shapes:
        raise InputError("give at least one shape model", field="--shapes")
    if any('body.name' in o.split("=")[0] for o in (overrides or [])):
        raise InputError("body.name is what the study varies: give the models with --shapes",
                         field="--set")
    stem = Path(campaign).stem
    out = Path(out) if out else Path(f"{stem}-resolution")
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for shape in shapes:
        store = out / f"{stem}-{shape}.zarr"
        print(f"resolution study: {shape} -> {store}", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        run_file(campaign, out=store, overrides=list(overrides or []) + [f'body.name="{shape}"'],
                 workers=workers, resume=True, progress=progress)
        rows.append(_row(shape, store, time.perf_counter() - t0, eps_list))
    path = out / "resolution.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return rows, path
