"""Engine on real dask clusters: worker counts, retries, killed campaigns, killed workers.

Every distributed result is compared with the same toy campaign written
serially in this process without dask (``run_toy_serial``): arrays must be
bit-identical. One 2-worker LocalCluster is shared by the module (start-up
costs seconds); the worker-kill test runs last because it restarts a worker.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from gates import Gate, wait_until
from ideas_hpc.engine.gate import GATE_ENV
from ideas_hpc.engine.lock import lock_path
from ideas_hpc.engine.runner import CampaignError
from ideas_hpc.engine.chunk_write import done_mask
from ideas_hpc.base.errors import InputError
from toy_campaign import run_toy
from toy_stores import assert_same_as, serial_reference

# 24 chunks of ~0.05 s each: long enough to kill mid-run, short enough for CI.
TOY = dict(n_samples=96, chunk_size=4, n_vertex=64, n_time=16, work=60_000, seed=7)
N_CHUNKS = 24


def _warm():
    from toy_campaign import toy_chunk as f

    f(0, 0, 1, campaign_seed=0, n_vertex=2, n_time=1, work=1)  # load the Numba cache once
    return os.getpid()


@pytest.fixture(scope="module")
def cluster2():
    from distributed import Client

    from ideas_hpc.engine.cluster import local_cluster

    with local_cluster(2) as lc, Client(lc) as client:
        client.run(_warm)
        yield lc, client


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return serial_reference(tmp_path_factory, TOY)


def _worker_settings():
    import dask

    from ideas_hpc.engine.cluster import WORKER_MALLOC_ENV

    return ({k: os.environ.get(k) for k in (*WORKER_MALLOC_ENV, "IDEAS_HPC_TASK_THREADS")},
            {k: dask.config.get(k) for k in ("distributed.admin.tick.interval",
                                             "distributed.worker.memory.monitor-interval",
                                             "distributed.worker.profile.enabled")})


def test_local_workers_get_campaign_settings(cluster2):
    from ideas_hpc.engine.cluster import (QUIET_CLUSTER_CONFIG, TASK_THREADS_ENV, WORKER_ENV,
                                          WORKER_MALLOC_ENV)

    _, client = cluster2
    for env, cfg in client.run(_worker_settings).values():
        # dask's own default (MALLOC_TRIM_THRESHOLD_=65536) made chunks 20-30 % slower.
        assert env == {**WORKER_MALLOC_ENV, TASK_THREADS_ENV: WORKER_ENV[TASK_THREADS_ENV]}
        assert cfg["distributed.worker.profile.enabled"] is False
        for key in ("distributed.admin.tick.interval",
                    "distributed.worker.memory.monitor-interval"):
            assert cfg[key] == QUIET_CLUSTER_CONFIG[key]


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2,
                    reason="host: one CPU: Numba's pool has 1 thread anyway")
def test_local_worker_tasks_run_one_numba_thread(tmp_path):
    # A spawned worker re-imports the launching script before the nanny's env
    # arrives, so a script that imports Numba at the top sized every worker's
    # pool to all cores; the chunk task must still run single-threaded.
    script = tmp_path / "campaign_script.py"
    script.write_text(textwrap.dedent(f"""
        import numba  # before the cluster starts, like any user script
        import numpy as np

        from ideas_hpc.engine.runner import run_campaign
        from toy_campaign import toy_chunk, toy_config, toy_template


        def chunk(cid, start, stop):
            out = toy_chunk(cid, start, stop, campaign_seed=1, n_vertex=8, n_time=2, work=1)
            out["coverage"][:] = numba.get_num_threads()
            numba.njit(lambda x: x + 1)(cid)  # compiling after the pool started must work
            return out


        @numba.njit(parallel=True)
        def total(x):
            s = 0.0
            for i in numba.prange(x.size):
                s += x[i]
            return s


        if __name__ == "__main__":
            total(np.ones(10))  # the parent's thread pool is running
            run_campaign({str(tmp_path / "t.zarr")!r}, toy_template(4, 8, 2), chunk,
                         config=toy_config(4, 2, 8, 2, 1, 1), campaign_seed=1, chunk_size=2,
                         workers=1, progress=False)
            # Numba refuses a changed NUMBA_NUM_THREADS at the next compilation
            # once its pool runs: the cluster must not have set it in this process.
            numba.njit(lambda x: x + 1)(1)
            print("parent pool", numba.get_num_threads(), "of", numba.config.NUMBA_DEFAULT_NUM_THREADS)
    """))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}
    res = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         env=env, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    pool = res.stdout.split("parent pool")[1].split()
    assert pool[0] == pool[2] != "1"  # the client keeps every core
    coverage = xr.open_zarr(tmp_path / "t.zarr")["coverage"].values
    np.testing.assert_array_equal(coverage, 1.0)


def test_two_workers_match_serial(cluster2, reference, tmp_path):
    _, client = cluster2
    s = run_toy(tmp_path / "w2.zarr", client=client, progress=False, **TOY)
    assert (s.chunks_run, s.chunks_skipped, s.samples_run) == (N_CHUNKS, 0, 96)
    assert s.n_workers == 2
    assert_same_as(reference, tmp_path / "w2.zarr")
    assert not lock_path(tmp_path / "w2.zarr").exists()
    # Finished store, no --resume: refused; with --resume: nothing to do.
    with pytest.raises(InputError, match="already exists"):
        run_toy(tmp_path / "w2.zarr", client=client, progress=False, **TOY)
    s = run_toy(tmp_path / "w2.zarr", client=client, progress=False, resume=True, **TOY)
    assert (s.chunks_run, s.chunks_skipped) == (0, N_CHUNKS)


def test_one_worker_matches_two(reference, tmp_path, capsys):
    # Its own LocalCluster with one worker process, started by the engine.
    s = run_toy(tmp_path / "w1.zarr", workers=1, progress=True, **TOY)
    assert s.n_workers == 1 and s.chunks_run == N_CHUNKS
    assert_same_as(reference, tmp_path / "w1.zarr")
    err = capsys.readouterr().err
    assert f"{N_CHUNKS}/{N_CHUNKS}" in err  # the tqdm bar reached the end


def test_failed_tasks_retried_then_resumed(cluster2, reference, tmp_path):
    _, client = cluster2
    flags = tmp_path / "flags"
    flags.mkdir()
    # Chunks 2 and 5 raise once; dask retries them.
    s = run_toy(tmp_path / "retry.zarr", client=client, progress=False, retries=2,
                fail_once_dir=str(flags), fail_chunks=(2, 5), **TOY)
    assert s.chunks_run == N_CHUNKS and sorted(os.listdir(flags)) == ["failed-2", "failed-5"]
    assert_same_as(reference, tmp_path / "retry.zarr")
    # Without retries the failures surface, the rest is written, --resume finishes.
    flags2 = tmp_path / "flags2"
    flags2.mkdir()
    with pytest.raises(CampaignError, match=r"2 of 24 chunks failed.*chunks \[3, 9\]"):
        run_toy(tmp_path / "noretry.zarr", client=client, progress=False, retries=0,
                fail_once_dir=str(flags2), fail_chunks=(3, 9), **TOY)
    mask = done_mask(tmp_path / "noretry.zarr")
    assert list(np.flatnonzero(~mask)) == [3, 9]
    s = run_toy(tmp_path / "noretry.zarr", client=client, progress=False, retries=0, resume=True,
                fail_once_dir=str(flags2), fail_chunks=(3, 9), **TOY)
    assert (s.chunks_run, s.chunks_skipped) == (2, N_CHUNKS - 2)
    assert_same_as(reference, tmp_path / "noretry.zarr")


def test_chunk_written_but_not_marked_is_redone(cluster2, reference, tmp_path):
    # The state a kill between the region write and the done flag leaves behind,
    # made deterministic: chunk 2 holds garbage and is not marked done.
    from ideas_hpc.engine.store import create_store
    from toy_campaign import toy_config, toy_template

    _, client = cluster2
    out = tmp_path / "torn.zarr"
    kw = {k: TOY[k] for k in ("n_vertex", "n_time", "work")}
    create_store(out, toy_template(TOY["n_samples"], TOY["n_vertex"], TOY["n_time"]),
                 config=toy_config(TOY["n_samples"], TOY["chunk_size"], seed=TOY["seed"], **kw),
                 campaign_seed=TOY["seed"], chunk_size=TOY["chunk_size"],
                 attrs={"kind": "toy", "title": "engine test workload"})
    garbage = xr.Dataset({"coverage": ("sample", np.full(4, -1.0)),
                          "first_seen": (("sample", "vertex"), np.zeros((4, TOY["n_vertex"])))})
    garbage.to_zarr(out, region={"sample": slice(8, 12)}, consolidated=False)
    assert not done_mask(out).any()
    s = run_toy(out, client=client, progress=False, resume=True, **TOY)
    assert s.chunks_run == N_CHUNKS
    assert_same_as(reference, out)


TOY_SCRIPT = Path(__file__).resolve().parent / "toy_campaign.py"


def _toy_cmd(out: Path, extra: list[str], toy: dict) -> list[str]:
    return [sys.executable, str(TOY_SCRIPT), "--out", str(out), "--resume",
            "--no-progress", "--n-samples", str(toy["n_samples"]),
            "--chunk-size", str(toy["chunk_size"]), "--n-vertex", str(toy["n_vertex"]),
            "--n-time", str(toy["n_time"]), "--work", str(toy["work"]),
            "--seed", str(toy["seed"]), *extra]


def _n_done(out: Path) -> int:
    try:
        return int(done_mask(out).sum())
    except Exception:  # not created yet
        return -1


# Where a kill lands, each reached by waiting on the campaign's state:
#   "store":  the store exists (start-up: lock, store creation, cluster, submission);
#   "gate":   the tasks are submitted and wait at the gate, no new chunk runs;
#   "done":   k more chunks are marked done, the workers wait at the gate;
#   "inside": k chunks done and chunk k+1 claimed, i.e. computing or writing.
MOMENTS = ("store", "gate", "done", "inside")
# Tasks that were running when their client died still finish (dask cannot
# interrupt a thread); each kill can add up to this many chunks after it.
STALE = 2


def kill_and_resume(out: Path, extra: list[str], n_kills: int, rng: np.random.Generator,
                    log: list, workdir: Path, toy: dict = TOY) -> None:
    """SIGKILL the campaign process ``n_kills`` times at state-chosen moments, then finish it.

    Every run holds its chunk tasks at its own gate; the test hands out tokens,
    waits for the state it wants and kills there. The campaign cannot finish
    before a kill, whatever the machine's speed. ``log`` gets
    ``(moment, done before, done at the kill)`` per kill.
    """
    n_chunks = -(-toy["n_samples"] // toy["chunk_size"])
    for i in range(n_kills):
        before = max(_n_done(out), 0)
        room = n_chunks - before - 2 * STALE - 2  # chunks this kill may let through
        moment = "store" if i == 0 else str(rng.choice(MOMENTS[1:] if room >= 2 else ("gate",)))
        k = int(rng.integers(1, min(3, room - 1) + 1)) if moment in ("done", "inside") else 0
        gate = Gate(workdir / f"gate-{i}")
        err = workdir / f"run-{i}.err"
        with open(err, "w") as fh:
            proc = subprocess.Popen(_toy_cmd(out, extra, toy), stdout=fh, stderr=fh,
                                    env=dict(os.environ, **gate.env))
        try:
            if moment == "store":
                wait_until(lambda: _n_done(out) >= 0, "the store", proc, err)
            elif moment == "gate":
                wait_until(lambda: gate.waiting() >= 1, "a task at the gate", proc, err)
            else:
                gate.allow(k + (moment == "inside"))
                wait_until(lambda: _n_done(out) >= before + k, f"{k} more chunks done", proc, err)
                if moment == "inside":
                    wait_until(lambda: gate.claimed() == k + 1, "a chunk in progress", proc, err)
            assert proc.poll() is None, f"campaign ended before kill {i}: {err.read_text()[-2000:]}"
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            log.append((moment, before, _n_done(out)))
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            gate.open()  # tasks of the dead run still held on a shared cluster may go
    left = n_chunks - _n_done(out)
    final = subprocess.run(_toy_cmd(out, extra, toy), capture_output=True, text=True)
    assert final.returncode == 0, final.stderr[-2000:]
    assert left > 0 and f"{n_chunks} skipped" not in final.stdout  # the last run had work left


def _check_kills(log: list, n_kills: int, n_chunks: int) -> None:
    assert len(log) == n_kills, log
    for moment, before, at_kill in log:
        if moment in ("done", "inside"):  # these landed mid-run, by construction
            assert before < at_kill < n_chunks, log
    assert sum(m in ("done", "inside") for m, _, _ in log) >= 2, log


def test_sigkill_campaign_process_then_resume(cluster2, reference, tmp_path):
    lc, _ = cluster2
    out = tmp_path / "killed.zarr"
    log: list = []
    kill_and_resume(out, ["--scheduler", lc.scheduler_address], 5, np.random.default_rng(11),
                    log, tmp_path)
    print("kills (moment, chunks done before, at the kill):", log)
    _check_kills(log, 5, N_CHUNKS)
    assert_same_as(reference, out)
    assert not lock_path(out).exists()
    assert sorted(p.name for p in tmp_path.glob("*.zarr")) == ["killed.zarr"]  # no partial stores


@pytest.mark.slow
def test_sigkill_campaign_with_own_cluster_many_times(reference, tmp_path):
    # The killed process owns its LocalCluster: its workers die with it.
    # Five kills, not twelve (these were picked at random times once): the moments are now
    # chosen by state, and with this seed the five land on every moment (store, done,
    # inside, gate) plus a second kill at the gate with no chunk done since the last one
    # (a resume of a resume that did nothing), each followed by a resume; the seven more
    # kills of twelve only repeated these moments. Five kills leave TOY's 24 chunks room
    # enough (kill_and_resume), so the module's serial reference serves.
    out = tmp_path / "killed_own.zarr"
    log: list = []
    kill_and_resume(out, ["--workers", "2"], 5, np.random.default_rng(12), log, tmp_path)
    print("kills (moment, chunks done before, at the kill):", log)
    _check_kills(log, 5, N_CHUNKS)
    assert {m for m, _, _ in log} == set(MOMENTS), log  # every moment, own cluster
    moments = [m for m, _, _ in log]
    assert ("gate", "gate") in zip(moments, moments[1:]), log  # back to back, nothing done
    assert_same_as(reference, out)
    assert not lock_path(out).exists()


def _pid():
    return os.getpid()


def test_kill_worker_during_run(cluster2, reference, tmp_path, monkeypatch):
    lc, client = cluster2
    out = tmp_path / "wkill.zarr"
    gate = Gate(tmp_path / "gate")
    monkeypatch.setenv(GATE_ENV, str(gate.path))
    pids_before = set(client.run(_pid).values())
    result: dict = {}

    def campaign():
        try:
            result["summary"] = run_toy(out, client=client, progress=False, retries=2, **TOY)
        except BaseException as exc:  # reported by the assertion below
            result["error"] = exc

    th = threading.Thread(target=campaign)
    gate.allow(4)
    th.start()
    try:
        # 4 chunks done and both workers holding their next task at the gate.
        wait_until(lambda: _n_done(out) >= 4 and gate.waiting() >= 6 or not th.is_alive(),
                   "4 chunks done and 2 tasks at the gate")
        assert th.is_alive(), repr(result)
        assert _n_done(out) == 4  # nothing ran past the tokens
        victim = sorted(pids_before)[0]
        os.kill(victim, signal.SIGKILL)
    finally:
        gate.open()
        th.join()
    assert "error" not in result, repr(result.get("error"))
    assert result["summary"].chunks_run == N_CHUNKS
    assert_same_as(reference, out)
    client.wait_for_workers(2, timeout=120)
    pids_after = set(client.run(_pid).values())
    assert victim not in pids_after  # the worker really died and was replaced
