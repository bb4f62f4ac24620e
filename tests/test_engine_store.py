"""Engine store, seeds, chunk plan and lock: no dask cluster needed."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr

from ideas_hpc.engine import lock as lockmod
from ideas_hpc.engine.lock import StoreLock, StoreLockedError, lock_path
from ideas_hpc.engine.chunk_write import done_mask, write_chunk_region
from ideas_hpc.engine.store import create_store
from ideas_hpc.engine.store_meta import ChunkPlan, config_hash, store_attrs
from ideas_hpc.base.seeds import sample_rng, seeds_for
from toy_campaign import (run_toy_serial, toy_areas, toy_chunk, toy_config,
                                  toy_template)
from ideas_hpc.base.errors import InputError

SEED = 2024


def _make(path, n=10, cs=4, nv=8, nt=3, seed=SEED, **kw):
    return create_store(path, toy_template(n, nv, nt), config=toy_config(n, cs, nv, nt, 50, seed),
                        campaign_seed=seed, chunk_size=cs, **kw)


def _siblings(path: Path) -> list[str]:
    return sorted(p.name for p in path.parent.iterdir())


# ------------------------------------------------------------------ seeds and plan

def test_seeds_match_numpy_spawn():
    # Outside truth: SeedSequence(s).spawn(k + 1)[k] is the k-th child numpy documents.
    words = seeds_for(SEED, 7)
    assert words.shape == (7, 4) and words.dtype == np.uint32
    children = np.random.SeedSequence(SEED).spawn(7)
    for k, child in enumerate(children):
        np.testing.assert_array_equal(words[k], child.generate_state(4, np.uint32))
        a = sample_rng(SEED, k).random(5)
        b = np.random.default_rng(child).random(5)
        np.testing.assert_array_equal(a, b)
    assert len({tuple(w) for w in words}) == 7
    assert not np.array_equal(seeds_for(SEED + 1, 7), words)


@pytest.mark.parametrize("n,cs", [(10, 4), (8, 4), (1, 5), (7, 1)])
def test_chunk_plan_partitions_samples(n, cs):
    plan = ChunkPlan(n, cs)
    chunks = plan.chunks()
    assert plan.n_chunks == len(chunks) == int(np.ceil(n / cs))
    covered = np.concatenate([np.arange(a, b) for _, a, b in chunks])
    np.testing.assert_array_equal(covered, np.arange(n))  # each sample exactly once, in order
    assert [c for c, _, _ in chunks] == list(range(plan.n_chunks))
    assert all(0 < b - a <= cs for _, a, b in chunks)


@pytest.mark.parametrize("n,cs,field", [(0, 4, "n_samples"), (4, 0, "chunk_size")])
def test_chunk_plan_rejects_bad_sizes(n, cs, field):
    with pytest.raises(InputError) as ei:
        ChunkPlan(n, cs)
    assert ei.value.field == field


def test_config_hash_is_order_independent_and_sensitive():
    a = {"x": 1, "y": {"b": 2.0, "a": [1, 2]}}
    b = {"y": {"a": [1, 2], "b": 2.0}, "x": 1}
    assert config_hash(a) == config_hash(b)
    assert config_hash(a) != config_hash({**a, "x": 2})


# ------------------------------------------------------------------ store layout

def test_create_store_layout_attrs_and_compression(tmp_path):
    p = tmp_path / "s.zarr"
    assert _make(p, n=10, cs=4, nv=8, nt=3) is True
    ds = xr.open_zarr(p)
    assert ds.sizes["sample"] == 10 and ds.sizes["chunk"] == 3
    # Each chunk of samples is exactly one zarr chunk, whole along other dims.
    g = zarr.open_group(str(p), mode="r")
    assert g["first_seen"].chunks == (4, 8)
    assert g["sigma_error"].chunks == (4, 3, 3)
    assert g["coverage"].chunks == (4,)
    assert g["chunk_done"].chunks == (1,)
    # Per-vertex arrays compressed.
    assert any("Zstd" in type(c).__name__ for c in g["first_seen"].compressors)
    assert any("Zstd" in type(c).__name__ for c in g["observed"].compressors)
    # Nothing computed yet: no chunk of a sample variable on disk.
    assert g["first_seen"].nchunks_initialized == 0 and g["coverage"].nchunks_initialized == 0
    assert not ds.chunk_done.values.any()
    np.testing.assert_array_equal(ds.chunk_start.values, [0, 4, 8])
    np.testing.assert_array_equal(ds.chunk_stop.values, [4, 8, 10])
    # Sample-free variables written in full at creation.
    np.testing.assert_array_equal(ds.vertex_area.values, toy_areas(8))
    np.testing.assert_array_equal(ds.sample_seed.values, seeds_for(SEED, 10))
    assert list(ds.axis.values) == ["x", "y", "z"]
    assert np.isnan(ds.coverage.values).all()
    a = store_attrs(p)
    assert a["config"] == toy_config(10, 4, 8, 3, 50, SEED)
    assert json.loads(ds.attrs["config"]) == a["config"]
    assert a["config_hash"] == config_hash(toy_config(10, 4, 8, 3, 50, SEED))
    assert a["campaign_seed"] == SEED and a["n_chunks"] == 3
    from ideas_hpc._version import __version__
    assert a["code_version"].startswith(__version__)
    assert ds.first_seen.attrs["units"] == "s"


def test_region_write_then_done_flag(tmp_path):
    p = tmp_path / "s.zarr"
    _make(p, n=10, cs=4, nv=8, nt=3)
    arrays = toy_chunk(1, 4, 8, campaign_seed=SEED, n_vertex=8, n_time=3, work=50)
    write_chunk_region(p, 1, 4, 8, arrays)
    ds = xr.open_zarr(p)
    np.testing.assert_array_equal(done_mask(p), [False, True, False])
    np.testing.assert_array_equal(ds.first_seen.values[4:8], arrays["first_seen"])
    np.testing.assert_array_equal(ds.observed.values[4:8], arrays["observed"])
    assert np.isnan(ds.coverage.values[:4]).all() and np.isnan(ds.coverage.values[8:]).all()
    # The toy's coverage is the area-weighted observed fraction (independent NumPy check).
    w = toy_areas(8)
    np.testing.assert_allclose(ds.coverage.values[4:8], arrays["observed"] @ w / w.sum(),
                               rtol=1e-14)


class _Killed(Exception):
    """A kill of the worker between two writes, made deterministic."""


def test_fault_between_writes_never_leaves_a_done_chunk_without_data(tmp_path, monkeypatch):
    # A kill can land between any two of write_chunk_region's writes. Whatever it cuts, a
    # chunk marked done must hold its data: resume skips done chunks, so a done flag
    # written ahead of the data leaves a hole (NaN) that resume never fills.
    from ideas_hpc.engine import chunk_write
    from ideas_hpc.engine.store_meta import DONE_VAR
    from toy_stores import SAMPLE_VARS, assert_same_as

    toy = dict(n_samples=12, chunk_size=4, n_vertex=8, n_time=3, work=50, seed=SEED)
    run_toy_serial(tmp_path / "ref.zarr", **toy)
    ref = xr.load_dataset(tmp_path / "ref.zarr", engine="zarr")
    p = tmp_path / "s.zarr"
    _make(p, n=12, cs=4, nv=8, nt=3)
    plan = ChunkPlan(12, 4)
    real = chunk_write._write_chunk
    calls: list[list[str]] = []

    def chunk(cid):
        start, stop = plan.bounds(cid)
        return toy_chunk(cid, start, stop, campaign_seed=SEED, n_vertex=8, n_time=3, work=50)

    def killed_after(n_calls):
        def write(handles, arrays, chunk_id, sl):
            if len(calls) >= n_calls:
                raise _Killed
            calls.append(sorted(arrays))
            real(handles, arrays, chunk_id, sl)
        return write

    # the write order: every data variable first, the done flag alone and last
    monkeypatch.setattr(chunk_write, "_write_chunk", killed_after(99))
    write_chunk_region(p, 0, 0, 4, chunk(0))
    assert calls[-1] == [DONE_VAR]
    assert {n for c in calls[:-1] for n in c} == set(json.loads(store_attrs(p)["layout"]))
    n_writes = len(calls)
    # a kill after all writes but the last (chunk 1), and before the first (chunk 2)
    for cid, cut in ((1, n_writes - 1), (2, 0)):
        calls.clear()
        monkeypatch.setattr(chunk_write, "_write_chunk", killed_after(cut))
        with pytest.raises(_Killed):
            write_chunk_region(p, cid, *plan.bounds(cid), chunk(cid))
    monkeypatch.setattr(chunk_write, "_write_chunk", real)
    done = done_mask(p)
    ds = xr.load_dataset(p, engine="zarr")
    for cid in np.flatnonzero(done):
        sl = slice(*plan.bounds(cid))
        for name in SAMPLE_VARS:
            np.testing.assert_array_equal(ds[name].values[sl], ref[name].values[sl],
                                          err_msg=f"chunk {cid} done without its {name}")
    # resume: redo the chunks not marked done; the store equals the uninterrupted one
    for cid in np.flatnonzero(~done):
        write_chunk_region(p, int(cid), *plan.bounds(cid), chunk(cid))
    assert_same_as(ref, p)


def test_region_write_rejects_bad_chunks(tmp_path):
    p = tmp_path / "s.zarr"
    _make(p, n=10, cs=4, nv=8, nt=3)
    arrays = toy_chunk(0, 0, 4, campaign_seed=SEED, n_vertex=8, n_time=3, work=5)
    with pytest.raises(InputError, match="chunk 0 is samples"):
        write_chunk_region(p, 0, 0, 3, arrays)
    with pytest.raises(InputError, match="missing"):
        write_chunk_region(p, 0, 0, 4, {k: v for k, v in arrays.items() if k != "coverage"})
    with pytest.raises(InputError) as ei:
        write_chunk_region(p, 0, 0, 4, {**arrays, "coverage": np.zeros(5)})
    assert ei.value.field == "arrays.coverage"
    assert not done_mask(p).any()


def test_toy_kernel_matches_numpy_reimplementation():
    # Small `work` so that rounding differences cannot be amplified by the chaos.
    n_vertex, n_time, work, seed = 16, 5, 7, 99
    out = toy_chunk(0, 3, 6, campaign_seed=seed, n_vertex=n_vertex, n_time=n_time, work=work)
    for j, k in enumerate(range(3, 6)):
        p0, p1, p2, p3 = sample_rng(seed, k).random(4)
        v = np.arange(n_vertex)
        x = 0.05 + 0.9 * ((p0 + v * p1 * 0.618033988749895) % 1.0)
        r = 3.7 + 0.29 * p2
        for _ in range(work):
            x = r * x * (1.0 - x)
        seen = x < 0.7
        np.testing.assert_array_equal(out["observed"][j], seen)
        np.testing.assert_allclose(out["first_seen"][j], np.where(seen, x * 1000.0, np.nan),
                                   rtol=1e-12)
        t = np.arange(n_time)[:, None]
        a = np.arange(3)[None, :]
        sig = p3 * np.exp(-t / (10.0 + 5.0 * p0)) * np.cos(0.1 * t * (a + 1) + 2 * np.pi * p1)
        np.testing.assert_allclose(out["sigma_error"][j], sig, rtol=1e-12, atol=1e-15)


# ------------------------------------------------------------------ refusals, no partial store

def test_existing_path_without_resume_refused(tmp_path):
    p = tmp_path / "s.zarr"
    _make(p)
    before = (p / "zarr.json").read_bytes()
    with pytest.raises(InputError, match="already exists.*--resume") as ei:
        _make(p)
    assert str(p) in str(ei.value)
    assert (p / "zarr.json").read_bytes() == before
    # Any existing path, even a plain folder, is refused.
    q = tmp_path / "plain"
    q.mkdir()
    with pytest.raises(InputError, match="already exists"):
        _make(q)


def test_resume_accepts_same_config_refuses_other(tmp_path):
    p = tmp_path / "s.zarr"
    _make(p, n=10, cs=4)
    assert _make(p, n=10, cs=4, resume=True) is False
    with pytest.raises(InputError) as ei:
        create_store(p, toy_template(10, 8, 3), config=toy_config(10, 4, 8, 3, 51, SEED),
                     campaign_seed=SEED, chunk_size=4, resume=True)
    msg = str(ei.value)
    assert "incompatible" in msg and str(p) in msg and "toy.work" in msg
    assert "50" in msg and "51" in msg
    with pytest.raises(InputError, match="chunk size"):
        create_store(p, toy_template(10, 8, 3), config=toy_config(10, 4, 8, 3, 50, SEED),
                     campaign_seed=SEED, chunk_size=5, resume=True)
    with pytest.raises(InputError, match="campaign seed"):
        create_store(p, toy_template(10, 8, 3), config=toy_config(10, 4, 8, 3, 50, SEED),
                     campaign_seed=SEED + 1, chunk_size=4, resume=True)
    q = tmp_path / "notastore"
    q.mkdir()
    with pytest.raises(InputError, match="not a readable zarr store|not an ideas_hpc"):
        _make(q, resume=True)


def test_failed_creation_leaves_nothing(tmp_path, monkeypatch):
    p = tmp_path / "s.zarr"
    real = xr.Dataset.to_zarr

    def broken(self, store, *a, **kw):
        real(self, store, *a, **kw)  # metadata is on disk, then the failure
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(xr.Dataset, "to_zarr", broken)
    with pytest.raises(OSError, match="simulated"):
        _make(p)
    assert _siblings(p) == []
    monkeypatch.undo()
    # Bad template: nothing created either.
    bad = toy_template(10, 8, 3).transpose("vertex", "sample", ...)
    with pytest.raises(InputError, match="first dimension"):
        create_store(p, bad, config={}, campaign_seed=1, chunk_size=4)
    with pytest.raises(InputError, match="chunk_size"):
        create_store(p, toy_template(10, 8, 3), config={}, campaign_seed=1, chunk_size=0)
    assert _siblings(p) == []


def test_killed_creation_leftover_is_cleaned(tmp_path):
    p = tmp_path / "s.zarr"
    # A creation directory left by a dead process on this host.
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    left = tmp_path / f".s.zarr.partial-{socket.gethostname()}-{dead}-deadbeef"
    left.mkdir()
    _make(p)
    assert _siblings(p) == ["s.zarr"]


# ------------------------------------------------------------------ lock

def _hold_lock_in_subprocess(store: Path):
    code = ("import sys, time; from ideas_hpc.engine.lock import StoreLock\n"
            f"l = StoreLock({str(store)!r}).acquire(); print('locked', flush=True)\n"
            "sys.stdin.read()\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "locked"
    return proc


def test_lock_refuses_second_writer_and_releases(tmp_path):
    p = tmp_path / "s.zarr"
    _make(p)
    proc = _hold_lock_in_subprocess(p)
    try:
        with pytest.raises(StoreLockedError) as ei:
            StoreLock(p).acquire()
        msg = str(ei.value)
        assert f"pid {proc.pid}" in msg and socket.gethostname() in msg and str(p) in msg
        # A whole campaign is refused too, and the store is not touched.
        from ideas_hpc.engine.runner import run_chunks
        with pytest.raises(StoreLockedError):
            run_chunks(p, lambda *a: {}, resume=True, progress=False)
        assert not done_mask(p).any()
    finally:
        proc.stdin.close()
        proc.wait(timeout=30)
    # Released at exit of the holder (clean exit): we can take it.
    with StoreLock(p) as lk:
        assert lk.held and lock_path(p).exists()
    assert not lock_path(p).exists()


def test_stale_lock_taken_over_foreign_host_refused(tmp_path):
    p = tmp_path / "s.zarr"
    _make(p)
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    lp = lock_path(p)
    lp.write_text(json.dumps({"host": socket.gethostname(), "pid": proc.pid, "start": "1",
                              "time": "then"}))
    with StoreLock(p):  # dead pid on this host: stale
        rec = json.loads(lp.read_text())
        assert rec["pid"] == os.getpid()
    # Same live pid but a different start time: the pid was recycled -> stale.
    lp.write_text(json.dumps({"host": socket.gethostname(), "pid": os.getppid(),
                              "start": "-1", "time": "then"}))
    assert lockmod.lock_is_stale(json.loads(lp.read_text()))
    lp.write_text(json.dumps({"host": "elsewhere.example", "pid": 1, "time": "then"}))
    with pytest.raises(StoreLockedError, match="elsewhere.example"):
        StoreLock(p).acquire()
    lp.unlink()


def test_serial_reference_is_complete(tmp_path):
    p = tmp_path / "ref.zarr"
    run_toy_serial(p, n_samples=12, chunk_size=5, n_vertex=8, n_time=3, work=30, seed=SEED)
    ds = xr.open_zarr(p)
    assert done_mask(p).all()
    assert np.isfinite(ds.coverage.values).all()
    assert ((ds.coverage.values >= 0) & (ds.coverage.values <= 1)).all()
    np.testing.assert_array_equal(np.isnan(ds.first_seen.values), ~ds.observed.values)
