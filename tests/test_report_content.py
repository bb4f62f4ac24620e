"""The numbers of ``summary.txt`` against the store, for every store kind (issue 23 item 5).

Each test writes the report of a store (built-in ellipsoid, small settings) and
finds every number the summary states by the variable it belongs to
(``tests/report_numbers.py``: tolerant of wording, not of a wrong or a missing
number), recomputed here from the store's arrays with NumPy.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.report.write import write_report
from ideas_hpc.campaign.run import run_file
from report_numbers import printed, printed_int, sig
from test_campaign_mc import MC, SHORT

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
SMALL = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3"]


def _report(store, tmp_path) -> tuple[xr.Dataset, str]:
    return xr.open_zarr(store), write_report(store, tmp_path / "rep").read_text()


def _swarm(ds, text):
    ang = ds["swarm_angle"].values
    printed_int(text, r"swarm", ang.size)
    printed(text, r"swarm|angle", *ang, decimals=2)


def _ga(ds, text):
    printed_int(text, r"GA|generation", ds.sizes["generation"], ds.sizes["individual"],
                int(ds["best_swarm_size"]))
    printed(text, r"GA|generation", 100 * float(ds["best_coverage"]),
            100 * ds.attrs["target_coverage"], decimals=3)


def test_flyby_summary_numbers(tmp_path):
    ds, text = _report(run_file(CAMPAIGNS / "eros-flyby.toml", out=tmp_path / "f.zarr",
                                overrides=SMALL), tmp_path)
    _swarm(ds, text)
    printed(text, r"coverage", 100 * float(ds["coverage"]), 100 * float(ds["coverage_count"]),
            decimals=3)
    # targeting: the worst over spacecraft of the miss it ended with (last finite iterate)
    miss = ds["targeting_miss"].values
    final = [row[np.isfinite(row)][-1] for row in miss]
    printed(text, r"miss|targeting", 1e3 * max(final), decimals=3)
    for var, scale in (("sigma_error", 1.0), ("wheel_torque", 1.0),
                       ("wheel_speed", 60 / (2 * np.pi))):
        v = np.abs(ds[var].values) * scale
        printed(text, var, sig(float(v.max()), 4), sig(float(v[..., -1, :].max()), 3))


def test_monte_carlo_summary_numbers(tmp_path):
    # three spacecraft, one of them failed in every sample: coverages that differ
    out = run_file(MC, out=tmp_path / "mc.zarr", workers=1, progress=False,
                   overrides=SHORT + ["swarm.angles_rad=[0.2, 2.4, 4.0]"])
    ds, text = _report(out, tmp_path)
    cov = 100 * ds["coverage"].values
    assert np.isfinite(cov).all() and cov.size == 6
    srt = np.sort(cov)
    assert srt[1] - srt[0] > 0.01 and srt[-1] - srt[0] > 0.01   # the checks can tell them apart
    p5 = srt[0] + 0.05 * (cov.size - 1) * (srt[1] - srt[0])   # linear interpolation, 5 %
    printed(text, r"coverage", cov.mean(), cov.min(), p5, cov.max(), decimals=3)
    printed_int(text, r"coverage", cov.size)


@pytest.fixture(scope="module")
def exact_store(tmp_path_factory):
    """A certified design with one failure tolerated and a Monte Carlo verification."""
    sets = SMALL + ["design.angle_step_deg=5", "design.verify_samples=6",
                    "design.failures_tolerated=1", "monte_carlo.failure_probability=0.3",
                    "run.workers=0", "dynamics.srp=false"]
    return run_file(CAMPAIGNS / "eros-design-nominal.toml",
                    out=tmp_path_factory.mktemp("exact") / "d.zarr", overrides=sets)


def test_exact_design_summary_numbers(exact_store, tmp_path):
    ds, text = _report(exact_store, tmp_path)
    assert str(ds["design_method"].values) == "exact"
    _swarm(ds, text)
    n, bound = int(ds["best_swarm_size"]), float(ds["proven_bound"])
    printed_int(text, r"design|status", n, int(bound))
    printed(text, r"design|status", 100 * (n - bound) / n, decimals=1)
    # the trade curve: every point up to its maximum, with its N
    c = ds["coverage_vs_n"].values
    top = int(np.flatnonzero(c >= c.max())[0])
    for k in range(top + 1):
        printed(text, r"N spacecraft|coverage.vs|curve", 100 * c[k], decimals=3)
        printed_int(text, r"N spacecraft|coverage.vs|curve", int(ds["n_spacecraft"].values[k]))
    # worst failure: its coverage, recounted from the verification's failure-free swarm
    printed(text, r"worst|fail", 100 * float(ds["worst_failure_coverage"]), decimals=3)
    printed_int(text, r"worst|fail", *ds["worst_failure"].values.tolist())
    # verification: threshold, P counted here, samples, min, 5th percentile, median
    v = ds["verify_coverage"].values
    thr = ds.attrs["verify_threshold"]
    assert 0.0 < thr < 1.0
    key = r"verif|monte carlo"
    printed(text, key, 100 * thr, decimals=2)
    printed(text, key, 100 * np.mean(v >= thr), decimals=1)
    printed(text, key, 100 * v.min(), 100 * np.median(v), decimals=2)
    printed(text, key, 100 * np.percentile(v, 5), decimals=2)
    printed_int(text, key, v.size, int((ds["verify_n_failed"].values > 0).sum()))


def test_ga_design_summary_numbers(tmp_path):
    sets = SMALL + ["design.population=8", "design.generations=3", "design.n_max=6",
                    "design.angle_step_rad=0.1", "run.workers=0"]
    ds, text = _report(run_file(CAMPAIGNS / "eros-nadir-ga.toml", out=tmp_path / "g.zarr",
                                overrides=sets), tmp_path)
    assert str(ds["design_method"].values) == "ga"
    _swarm(ds, text)
    _ga(ds, text)
    printed(text, r"coverage", 100 * float(ds["coverage"].values.ravel()[0]), decimals=3)


def test_fov_design_summary_numbers(tmp_path):
    sets = SMALL + ["design.population=8", "design.generations=3", "run.workers=0",
                    "swarm.angles_rad=[0.2, 2.4, 4.0]", "design.p_max_min=2.0"]
    ds, text = _report(run_file(CAMPAIGNS / "eros-fov-ga.toml", out=tmp_path / "v.zarr",
                                overrides=sets), tmp_path)
    _swarm(ds, text)
    _ga(ds, text)
    printed(text, r"sweep|period", *(ds["sweep_period"].values / 60), decimals=1)


def test_pareto_summary_numbers(tmp_path):
    out = run_file(CAMPAIGNS / "eros-pareto.toml", out=tmp_path / "p.zarr", workers=0,
                   overrides=['body.name="ellipsoid"', "design.angle_step_deg=5.0"])
    ds, text = _report(out, tmp_path)
    n, cov, sw = ds["pareto_n"].values, ds["pareto_coverage"].values, ds["pareto_swarm"].values
    printed_int(text, r"pareto|front|non-dominated", n.size)
    for k, c, row in zip(n, cov, sw):     # one line per front point: N, coverage, angles
        ang = row[np.isfinite(row)]
        assert ang.size == k
        printed(text, r"angle", 100 * c, *ang, decimals=3)
        printed_int(text, r"angle", int(k))
    gap = np.abs(ds["pareto_gap_to_exact"].values).max()
    printed(text, r"gap|curve", sig(float(gap), 3))
