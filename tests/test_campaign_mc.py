"""Monte Carlo campaigns through the engine: determinism, re-runs, kills, bad input."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from gates import Gate, wait_until
from ideas_hpc.campaign.montecarlo import run_sample
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.engine.chunk_write import done_mask
from ideas_hpc.base.errors import InputError

ROOT = Path(__file__).resolve().parent.parent
MC = ROOT / "campaigns" / "eros-monte-carlo.toml"
SHORT = ["body.name=\"ellipsoid\"", "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
         "attitude.decimate=10", "monte_carlo.samples=6", "run.chunk_size=2",
         "monte_carlo.failures_k=1", "monte_carlo.failure_probability=0.0"]
SAMPLE_VARS = ("coverage", "observed", "first_seen", "times_seen", "sigma_error",
               "wheel_torque", "c20", "reflectivity", "active", "position_error", "sigma0",
               "arrival_error", "misalignment_prv")


def _same(a, b, names=SAMPLE_VARS):
    for v in names:
        assert np.array_equal(a[v].values, b[v].values, equal_nan=a[v].dtype.kind == "f"), v


@pytest.fixture(scope="module")
def one_worker(tmp_path_factory):
    out = tmp_path_factory.mktemp("mc") / "w1.zarr"
    run_file(MC, out=out, overrides=SHORT, workers=1, progress=False)
    return out


def test_mc_store_layout_and_dispersions(one_worker):
    ds = xr.open_zarr(one_worker)
    assert ds.sizes["sample"] == 6 and bool(ds["chunk_done"].all())
    assert ds["observed"].dims == ("sample", "vertex")
    assert ds["sigma_error"].dims == ("sample", "spacecraft", "time", "axis")
    assert ds["coverage"].attrs["units"] == "1" and "config" in ds.attrs
    assert ds.attrs["campaign_seed"] == 2026 and "code_version" in ds.attrs
    # exactly one failure per sample, as configured
    assert np.all(ds["n_failed"].values == 1) and np.all((~ds["active"].values).sum(1) == 1)
    # dispersions differ between samples and stay in their ranges
    r = ds["reflectivity"].values
    assert np.all((r >= 0.4) & (r <= 0.8)) and np.unique(r).size == 6
    # coverage is consistent with the stored per-vertex mask and areas
    a = ds["vertex_area"].values
    cov = (ds["observed"].values * a).sum(1) / a.sum()
    assert np.allclose(cov, ds["coverage"].values, rtol=1e-12)


def test_mc_two_workers_identical(one_worker, tmp_path):
    out = tmp_path / "w2.zarr"
    run_file(MC, out=out, overrides=SHORT, workers=2, progress=False)
    _same(xr.open_zarr(one_worker), xr.open_zarr(out))


def test_mc_sample_reruns_alone(one_worker):
    ds = xr.open_zarr(one_worker)
    c = load(MC, SHORT)
    k = 3
    r = run_sample(c, k)
    for v in ("coverage", "observed", "first_seen", "sigma_error", "c22", "velocity_error"):
        assert np.array_equal(r[v][0], ds[v].values[k], equal_nan=True), v


def _n_done(out) -> int:
    try:
        return int(done_mask(out).sum())
    except Exception:  # not created yet
        return -1


def _run_cli(out, extra=(), **kw):
    cmd = [sys.executable, "-m", "ideas_hpc.cli", "run", str(MC), "--out", str(out),
           "--workers", "1", "--no-progress"]
    for s in SHORT:
        cmd += ["--set", s]
    return subprocess.Popen(cmd + list(extra), text=True, **kw)


def test_mc_killed_and_resumed_is_identical(one_worker, tmp_path):
    """SIGKILL the campaign process (and its workers) twice, resume: same arrays.

    The chunk tasks wait at a gate (IDEAS_HPC_CHUNK_GATE), so the kills land at
    known states whatever the machine's speed: once with one chunk done and the
    second one computing, once with the resumed run's task at the gate.
    """
    out = tmp_path / "killed.zarr"
    n_chunks = 3
    log = []
    for i, moment in enumerate(("inside", "gate")):
        gate = Gate(tmp_path / f"gate-{i}")
        err = tmp_path / f"run-{i}.err"
        with open(err, "w") as fh:
            p = _run_cli(out, ["--resume"] if out.exists() else [], start_new_session=True,
                         env=dict(os.environ, **gate.env), stdout=fh, stderr=fh)
        before = max(_n_done(out), 0)
        if moment == "inside":
            gate.allow(2)
            wait_until(lambda: _n_done(out) >= 1 and gate.claimed() == 2, "chunk 2 running", p, err)
        else:
            wait_until(lambda: gate.waiting() >= 1, "a task at the gate", p, err)
        assert p.poll() is None
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        log.append((moment, before, _n_done(out)))
    assert [a for _, _, a in log] and all(0 < a < n_chunks for _, _, a in log), log
    p = _run_cli(out, ["--resume"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _, err = p.communicate()
    assert p.returncode == 0, err
    _same(xr.open_zarr(one_worker), xr.open_zarr(out))


@pytest.mark.parametrize("sets,field", [
    (["monte_carlo.sampels=3"], "monte_carlo.sampels"),
    (["monte_carlo.samples=\"many\""], "monte_carlo.samples"),
    (["monte_carlo.samples=0"], "monte_carlo.samples"),
    (["monte_carlo.failure_probability=1.5"], "monte_carlo.failure_probability"),
    (["monte_carlo.failures_k=9"], "monte_carlo.failures_k"),
    (["monte_carlo.reflectivity_min=0.9"], "monte_carlo.reflectivity_max"),
])
def test_mc_bad_input_leaves_nothing(tmp_path, sets, field):
    out = tmp_path / "bad.zarr"
    with pytest.raises(InputError) as ei:
        run_file(MC, out=out, overrides=SHORT + sets, workers=1, progress=False)
    assert ei.value.field == field
    assert not out.exists() and not any(tmp_path.iterdir())


def test_mc_store_holds_the_resolved_config(one_worker):
    """The engine path records the same fully resolved config as the flyby path."""
    import json

    from ideas_hpc.campaign.schema.campaign_tables import resolved_config

    stored = json.loads(xr.open_zarr(one_worker).attrs["config"])
    assert stored == resolved_config(load(MC, SHORT))
    assert stored["monte_carlo"]["sigma_c20_pct"] == 5.0 and "models" in stored


def test_existing_store_and_incompatible_resume(one_worker):
    with pytest.raises(InputError, match="exists"):
        run_file(MC, out=one_worker, overrides=SHORT, workers=1, progress=False)
    with pytest.raises(InputError, match="monte_carlo.sigma_c20_pct"):
        run_file(MC, out=one_worker, overrides=SHORT + ["monte_carlo.sigma_c20_pct=9.0"],
                 workers=1, progress=False, resume=True)
    # a finished store resumes to a no-op
    before = xr.open_zarr(one_worker)["coverage"].values.copy()
    run_file(MC, out=one_worker, overrides=SHORT, workers=1, progress=False, resume=True)
    assert np.array_equal(before, xr.open_zarr(one_worker)["coverage"].values)


def test_mc_on_existing_scheduler(one_worker, tmp_path):
    """--scheduler ADDRESS: the campaign runs on a cluster somebody else started."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None) as cluster:
        out = run_file(MC, out=tmp_path / "sched.zarr", overrides=SHORT,
                       scheduler=cluster.scheduler_address, progress=False)
    _same(xr.open_zarr(one_worker), xr.open_zarr(out))


def test_mc_in_process_matches_one_worker(one_worker, tmp_path):
    # workers=0 (and any job below IN_PROCESS_MAX_TESTS without a count) runs the
    # chunk tasks in this process: same store as a dask worker writes
    out = tmp_path / "w0.zarr"
    run_file(MC, out=out, overrides=SHORT, workers=0, progress=False)
    _same(xr.open_zarr(one_worker), xr.open_zarr(out))
    assert done_mask(out).all()

