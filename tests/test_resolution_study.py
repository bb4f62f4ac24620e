"""A requirement the mesh resolves (issue 29): the eps_tol warning's figures, and
``ideas-hpc resolution`` running one campaign on several shape models."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.body.bodies import load_body
from ideas_hpc.campaign.resolution_study import n_from_curve, resolution_study
from ideas_hpc.cli import main
from ideas_hpc.design.resolution import eps_tol_warning, mesh_resolution

ROOT = Path(__file__).resolve().parent.parent
NOMINAL = ROOT / "campaigns" / "eros-design-nominal.toml"
FAST = ["flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3", "dynamics.srp=false",
        "design.angle_step_deg=10", "design.verify_samples=0", "run.workers=0",
        "design.time_limit_s=60"]


def test_warning_names_eps_tol_and_the_vertex_figures():
    areas = np.r_[np.full(6, 2.0), np.full(4, 1.0)]       # fractions 1/8 and 1/16
    r = mesh_resolution(areas)
    assert r.median == pytest.approx(0.125) and r.smallest == pytest.approx(1 / 16)
    assert eps_tol_warning(areas, 0.13) is None             # coarser than the median
    msg = eps_tol_warning(areas, 0.1)
    assert "eps_tol" in msg and "0.1 %" not in msg          # 10 %, not 0.1 %
    assert "10 %" in msg and "12.500 %" in msg and "6.250 %" in msg
    assert "4 of 10 vertices" in msg


def test_eros001708_figures_match_the_mesh():
    """The figures the issue quotes for eros001708 (856 vertices), from the mesh itself."""
    body = load_body("eros001708")
    w = body.shape.vertex_areas / body.shape.vertex_areas.sum()
    msg = eps_tol_warning(body.shape.vertex_areas, 0.001)
    assert f"{100 * np.median(w):.3f} %" in msg and f"{100 * w.min():.3f} %" in msg
    assert f"{int((w < 0.001).sum())} of {w.size} vertices" in msg


def _curve(cov, status, target):
    n = np.arange(1, len(cov) + 1)
    return xr.Dataset({"coverage_vs_n": ("n_spacecraft", np.asarray(cov, float)),
                       "coverage_vs_n_status": ("n_spacecraft", np.asarray(status))},
                      coords={"n_spacecraft": n}), target


def test_n_from_curve():
    ds, t = _curve([0.5, 0.97, 0.995, 1.0], ["optimal"] * 4, 1.0)
    assert n_from_curve(ds, t, 0.001) == "4"
    assert n_from_curve(ds, t, 0.005) == "3"
    assert n_from_curve(ds, t, 0.05) == "2"
    ds, t = _curve([0.5, 0.97, 0.995, 1.0], ["optimal", "time_limit", "optimal", "optimal"], 1.0)
    assert n_from_curve(ds, t, 0.005) == "3*"               # N = 2 not proven short
    assert n_from_curve(ds, 1.5, 0.001) == "-"


def test_study_runs_each_shape_and_resumes(tmp_path, capsys):
    rows, path = resolution_study(NOMINAL, ["sphere", "ellipsoid"], overrides=FAST,
                                  out=tmp_path, progress=False, eps_list=(0.1, 5.0))
    assert [r["shape"] for r in rows] == ["sphere", "ellipsoid"]
    for r in rows:
        ds = xr.open_zarr(r["store"])
        assert ds.attrs["body"] == r["shape"] or r["shape"] in ds.attrs["body_note"]
        assert r["n"] == int(ds["best_swarm_size"])
        assert r["n_at_0.1pct"].rstrip("*") == str(r["n"])   # the run's own tolerance
        assert int(r["n_at_5pct"].rstrip("*")) <= r["n"]
    with open(path) as f:
        table = list(csv.DictReader(f))
    assert [t["shape"] for t in table] == ["sphere", "ellipsoid"]
    # the CLI: finished stores are kept (resumable), the table is printed
    args = ["resolution", str(NOMINAL), "--shapes", "sphere,ellipsoid", "--out", str(tmp_path),
            "--no-progress"] + [a for s in FAST for a in ("--set", s)]
    assert main(args) == 0
    out, err = capsys.readouterr()
    assert err.count("already complete") == 2
    assert "sphere" in out and "ellipsoid" in out and "resolution.csv" in out
    assert main(args + ["--set", 'body.name="sphere"']) == 2
