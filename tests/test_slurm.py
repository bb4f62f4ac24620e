"""SLURM through dask-jobqueue.

* ``job_script()`` of the configured SLURMCluster, checked without any SLURM
  controller (runs by default).
* ``@pytest.mark.slurm``: real jobs against a running slurmctld (CI starts a
  one-node cluster with ``slurm/ci_local_slurm.sh start``); skipped when
  ``sinfo`` is absent or no node is idle.
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.engine.cluster import (DEFAULT_SLURM_CONFIG, WORKER_MALLOC_ENV, load_slurm_config,
                                      slurm_cluster)
from gates import wait_until
from toy_campaign import run_toy
from ideas_hpc.base.errors import InputError
from toy_stores import assert_same_as, serial_reference

REPO = Path(__file__).resolve().parent.parent
TOY = dict(n_samples=24, chunk_size=4, n_vertex=32, n_time=8, work=20_000, seed=3)


def test_job_script_from_repo_config():
    # shipped in the package; the checkout's slurm/jobqueue.yaml is the same file
    assert DEFAULT_SLURM_CONFIG == REPO / "ideas_hpc" / "engine" / "jobqueue.yaml"
    assert (REPO / "slurm" / "jobqueue.yaml").resolve() == DEFAULT_SLURM_CONFIG.resolve()
    cfg = load_slurm_config()
    assert cfg["interface"] == "lo" and cfg["cores"] == 1
    with slurm_cluster() as cluster:
        script = cluster.job_script()
        addr = cluster.scheduler_address
    lines = script.splitlines()
    assert lines[0].startswith("#!")
    sbatch = [ln for ln in lines if ln.startswith("#SBATCH")]
    for want in ("#SBATCH -J ideas-worker", "#SBATCH --cpus-per-task=1", "#SBATCH --mem=2G",
                 "#SBATCH -t 01:00:00", "#SBATCH --export=ALL"):
        assert want in sbatch, (want, sbatch)
    assert "export NUMBA_NUM_THREADS=1" in lines
    for key, value in WORKER_MALLOC_ENV.items():  # as local workers get them
        assert f"export {key}={value}" in lines
    worker = [ln for ln in lines if "distributed.cli.dask_worker" in ln]
    assert len(worker) == 1
    cmd = worker[0].split()
    assert cmd[0] == sys.executable and cmd[1:3] == ["-m", "distributed.cli.dask_worker"]
    assert addr in cmd and addr.startswith("tcp://127.0.0.1:")  # scheduler bound to lo
    assert cmd[cmd.index("--interface") + 1] == "lo"
    assert cmd[cmd.index("--nthreads") + 1] == "1"
    # The prologue comes before the worker starts.
    assert lines.index("export NUMBA_NUM_THREADS=1") < lines.index(worker[0])


def test_job_script_from_toml_with_queue_and_account(tmp_path):
    cfg = tmp_path / "site.toml"
    cfg.write_text(
        '[jobqueue.slurm]\ncores = 4\nprocesses = 2\nmemory = "8GiB"\nqueue = "short"\n'
        'account = "proj42"\nwalltime = "00:10:00"\ninterface = "lo"\n'
        'job-extra-directives = ["--constraint=skylake"]\n'
        'scheduler-options = { interface = "lo" }\n')
    with slurm_cluster(cfg, walltime="00:20:00") as cluster:
        script = cluster.job_script()
    for want in ("#SBATCH -p short", "#SBATCH -A proj42", "#SBATCH --cpus-per-task=4",
                 "#SBATCH --mem=8G", "#SBATCH -t 00:20:00", "#SBATCH --constraint=skylake"):
        assert want in script, (want, script)
    worker = next(ln for ln in script.splitlines() if "dask_worker" in ln)
    assert "--nworkers 2" in worker and "--nthreads 2" in worker


def test_slurm_config_errors(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("jobqueue:\n  slurm:\n    cores: 1\n    memory: 1GiB\n    coers: 2\n")
    with pytest.raises(InputError) as ei:
        slurm_cluster(bad)
    assert ei.value.field == "jobqueue.slurm.coers" and ei.value.file == str(bad)
    empty = tmp_path / "empty.yaml"
    empty.write_text("jobqueue:\n  pbs: {}\n")
    with pytest.raises(InputError, match="jobqueue.slurm"):
        load_slurm_config(empty)
    with pytest.raises(InputError, match="cannot read"):
        load_slurm_config(tmp_path / "missing.yaml")


# ------------------------------------------------------------------ real SLURM

@functools.lru_cache(maxsize=1)
def _slurm_unreachable() -> str | None:
    """None when the controller answers with an idle node, else why it does not."""
    if shutil.which("sinfo") is None:
        return "sinfo is not on PATH"
    try:
        out = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True,
                             timeout=20)
    except subprocess.TimeoutExpired:
        return "sinfo did not answer within 20 s (controller hung?)"
    except (OSError, subprocess.SubprocessError) as exc:
        return f"sinfo failed: {exc}"
    if out.returncode != 0:
        return f"sinfo exited with {out.returncode}: {out.stderr.strip()[:200]}"
    if not any(s.strip() in ("idle", "mixed") for s in out.stdout.split()):
        return f"no idle node (sinfo says {out.stdout.split()!r})"
    return None


def require_slurm() -> None:
    """Skip when no SLURM controller answers, with the reason; in CI (``CI=true``, as
    ``.ci/run`` sets it) fail instead, so that a hung or missing controller is not green."""
    why = _slurm_unreachable()
    if why is None:
        return
    if os.environ.get("CI", "").strip().lower() in ("true", "1", "yes"):
        pytest.fail(f"CI needs the SLURM controller: {why}", pytrace=False)
    pytest.skip(f"no SLURM controller with an idle node: {why} "
                "(start one with slurm/ci_local_slurm.sh start)")


@pytest.fixture
def slurm_controller():
    require_slurm()


needs_slurm = pytest.mark.usefixtures("slurm_controller")


def test_unreachable_controller_fails_in_ci_and_skips_outside(monkeypatch):
    def hang(cmd, **kw):
        raise subprocess.TimeoutExpired(cmd, kw.get("timeout"))

    def outcome():   # caught here: a skip must not end this test as skipped
        try:
            require_slurm()
        except pytest.fail.Exception as exc:
            return "fail", str(exc)
        except pytest.skip.Exception as exc:
            return "skip", str(exc)
        return "run", ""

    monkeypatch.setattr(shutil, "which", lambda name: "/usr/bin/" + name)
    monkeypatch.setattr(subprocess, "run", hang)
    _slurm_unreachable.cache_clear()
    try:
        monkeypatch.setenv("CI", "true")
        got = outcome()
        assert got[0] == "fail" and "did not answer within 20 s" in got[1], got
        monkeypatch.delenv("CI")
        got = outcome()
        assert got[0] == "skip" and "did not answer within 20 s" in got[1], got
        monkeypatch.setattr(shutil, "which", lambda name: None)
        _slurm_unreachable.cache_clear()
        monkeypatch.setenv("CI", "true")
        got = outcome()
        assert got[0] == "fail" and "not on PATH" in got[1], got
    finally:
        _slurm_unreachable.cache_clear()


@pytest.fixture(scope="module")
def toy_reference(tmp_path_factory):
    return serial_reference(tmp_path_factory, TOY, "slurm_ref")


def _our_jobs(name: str) -> list[str]:
    out = subprocess.run(["squeue", "-h", "-n", name, "-o", "%i"], capture_output=True,
                         text=True, timeout=20)
    return out.stdout.split()


@pytest.mark.slurm
@needs_slurm
def test_toy_campaign_through_slurmcluster(toy_reference, tmp_path):
    out = tmp_path / "slurm.zarr"
    t0 = time.perf_counter()
    s = run_toy(out, cluster="slurm", workers=2, progress=False, **TOY)
    wall = time.perf_counter() - t0
    print(f"SLURM toy campaign: {s}; {wall:.1f} s including job start")
    assert s.chunks_run == 6 and s.n_workers >= 1
    assert_same_as(toy_reference, out)
    logs = tmp_path / "slurm.zarr.slurm-logs"
    assert any(logs.glob("ideas-worker-*.err"))  # jobs really ran under SLURM
    # Closing the cluster cancelled the worker jobs.
    wait_until(lambda: not _our_jobs("ideas-worker"), "the worker jobs to leave the queue")


@pytest.mark.slurm
@needs_slurm
def test_sbatch_script_runs_a_campaign(toy_reference, tmp_path):
    # slurm/run_campaign.sbatch as a user would submit it, with the toy as the command.
    out = tmp_path / "batch.zarr"
    env = dict(os.environ, IDEAS_HPC_REPO=str(REPO), IDEAS_HPC_WORKERS="1",
               IDEAS_HPC_RUN=f"{sys.executable} {REPO / 'tests' / 'toy_campaign.py'}")
    args = ["--no-progress"] + [f"--{k.replace('_', '-')}={v}" for k, v in TOY.items()]
    sub = subprocess.run(["sbatch", "--parsable", f"--output={tmp_path}/batch-%j.out",
                          str(REPO / "slurm" / "run_campaign.sbatch"), "toy", str(out), *args],
                         capture_output=True, text=True, env=env, cwd=tmp_path, timeout=30)
    assert sub.returncode == 0, sub.stderr
    job = sub.stdout.strip().split(";")[0]
    wait_until(lambda: not subprocess.run(["squeue", "-h", "-j", job], capture_output=True,
                                          text=True).stdout.strip(), f"batch job {job} to end")
    log = (tmp_path / f"batch-{job}.out").read_text()
    assert "6 chunks run" in log, log[-3000:]
    assert_same_as(toy_reference, out)


@pytest.mark.slurm
@needs_slurm
def test_monte_carlo_campaign_through_slurm(tmp_path):
    """The real Monte Carlo campaign on SLURM worker jobs equals the local run."""
    from ideas_hpc.campaign.run import run_file

    mc = REPO / "campaigns" / "eros-monte-carlo.toml"
    sets = ["body.name=\"ellipsoid\"", "flyby.tf_s=60", "flyby.z_start_km=-3",
            "flyby.z_stop_km=3", "attitude.decimate=10", "monte_carlo.samples=4",
            "run.chunk_size=2"]
    local = run_file(mc, out=tmp_path / "local.zarr", overrides=sets, workers=1, progress=False)
    slurm = run_file(mc, out=tmp_path / "slurm.zarr", overrides=sets, workers=2,
                     cluster="slurm", slurm_config=REPO / "slurm" / "jobqueue.yaml",
                     progress=False)
    a, b = xr.open_zarr(local), xr.open_zarr(slurm)
    assert bool(b["chunk_done"].all())
    for name in ("coverage", "observed", "first_seen", "sigma_error", "c20"):
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    assert any((tmp_path / "slurm.zarr.slurm-logs").glob("ideas-worker-*.err"))


@pytest.mark.slurm
@needs_slurm
def test_world_bank_through_slurm_equals_local_and_resumes(tmp_path):
    """A bank of drawn worlds (issue 43 item 4): every scenario its own Eros-class world,
    flown by SLURM worker jobs, equals the serial bank row for row; a store missing one
    chunk is resumed on SLURM, flying that chunk only."""
    import zarr

    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.engine.store_meta import DONE_VAR
    from ideas_hpc.engine.cluster import connect
    from ideas_hpc.montecarlo.scenarios import build_scenario_bank

    c = load(REPO / "campaigns" / "eros-class-flyby.toml")
    setup, mc = setup_from_campaign(c), c.config.monte_carlo
    kw = dict(seed=7, n_scenarios=4, progress=False, chunk_size=1)
    step = np.deg2rad(30.0)
    serial = build_scenario_bank(setup, step, mc, **kw)
    store = tmp_path / "worlds.zarr"
    with connect(cluster="slurm", workers=2, slurm_config=REPO / "slurm" / "jobqueue.yaml",
                 log_directory=tmp_path / "logs") as client:
        first = build_scenario_bank(setup, step, mc, client=client, store=str(store), **kw)
        assert first.attrs["chunks_run"] == 4
        np.testing.assert_array_equal(first.rows, serial.rows)
        np.testing.assert_array_equal(first.areas, serial.areas)
        # as a killed run leaves it: chunk 2's flag down and its rows lost
        zarr.open_array(str(store / DONE_VAR), mode="r+")[2] = False
        rows = zarr.open_group(str(store), mode="r+")["rows"]
        rows[2] = np.zeros(rows.shape[1:], dtype=bool)
        again = build_scenario_bank(setup, step, mc, client=client, store=str(store), **kw)
    assert again.attrs["chunks_run"] == 1
    np.testing.assert_array_equal(again.rows, serial.rows)
    assert any((tmp_path / "logs").glob("ideas-worker-*.err"))   # jobs really ran under SLURM
