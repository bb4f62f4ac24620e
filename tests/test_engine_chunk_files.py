"""Whole-chunk writer against zarr's own writes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import zarr

from ideas_hpc.engine.chunk_files import whole_chunk_writer

ROWS = 4  # chunk rows
N = 10    # 3 chunks, the last one short


def _pair(root: Path, name: str, dtype, tail: tuple, **kw):
    """The same array twice: one written by zarr, one by the whole-chunk writer."""
    mk = dict(shape=(N, *tail), chunks=(ROWS, *tail), dtype=dtype, **kw)
    return (zarr.create_array(str(root / f"{name}_zarr"), **mk),
            zarr.create_array(str(root / f"{name}_direct"), **mk))


def _chunk_files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and p.name != "zarr.json"}


@pytest.mark.parametrize("dtype, tail, data", [
    (np.float64, (3, 2), lambda rng, s: rng.normal(size=s)),
    (np.float64, (5,), lambda rng, s: np.where(rng.random(s) < 0.3, np.nan, rng.random(s))),
    (np.bool_, (7,), lambda rng, s: rng.random(s) < 0.5),
    (np.int32, (6,), lambda rng, s: rng.integers(-1000, 1000, s).astype(np.int32)),
])
def test_bytes_and_values_match_zarr(tmp_path, dtype, tail, data):
    rng = np.random.default_rng(7)
    values = np.asarray(data(rng, (N, *tail)), dtype=dtype)
    ref, direct = _pair(tmp_path, "a", dtype, tail)
    write = whole_chunk_writer(direct, ROWS)
    assert write is not None
    for i in range(3):
        sl = slice(i * ROWS, min(N, (i + 1) * ROWS))
        ref[sl] = values[sl]
        write(i, values[sl])  # the last call is 2 rows: padded with the fill value
    np.testing.assert_array_equal(zarr.open_array(str(tmp_path / "a_direct"))[:], values)
    a, b = _chunk_files(tmp_path / "a_zarr"), _chunk_files(tmp_path / "a_direct")
    assert len(a) == 3 and a == b


def test_rewrite_replaces_chunk_and_leaves_no_temporaries(tmp_path):
    _, direct = _pair(tmp_path, "r", np.float64, (2,))
    write = whole_chunk_writer(direct, ROWS)
    write(1, np.ones((ROWS, 2)))
    write(1, np.full((ROWS, 2), 2.0))  # a redone chunk (resume, retry) overwrites
    got = zarr.open_array(str(tmp_path / "r_direct"))[:]
    np.testing.assert_array_equal(got[ROWS:2 * ROWS], 2.0)
    assert not [p for p in (tmp_path / "r_direct").rglob("*.partial")]


def test_unsupported_layouts_fall_back(tmp_path):
    sharded = zarr.create_array(str(tmp_path / "s"), shape=(N, 3), chunks=(2, 3),
                                shards=(ROWS, 3), dtype="f8")
    assert whole_chunk_writer(sharded, ROWS) is None
    split = zarr.create_array(str(tmp_path / "p"), shape=(N, 6), chunks=(ROWS, 3), dtype="f8")
    assert whole_chunk_writer(split, ROWS) is None  # a task would write two chunks
    memory = zarr.create_array(zarr.storage.MemoryStore(), shape=(N, 3), chunks=(ROWS, 3),
                               dtype="f8")
    assert whole_chunk_writer(memory, ROWS) is None
    v2 = zarr.create_array(str(tmp_path / "v2"), shape=(N, 3), chunks=(ROWS, 3), dtype="f8",
                           zarr_format=2)
    assert whole_chunk_writer(v2, ROWS) is None
