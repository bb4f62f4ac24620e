"""Chunk writes into an engine store (step 2 of :mod:`ideas_hpc.engine.store`):
each task writes its sample slice, then sets ``chunk_done[chunk_id]`` last."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Mapping

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.engine.store_meta import DONE_VAR, ChunkPlan, store_attrs


# One entry per worker process: the store last written, keyed by its path and
# the mtime of its root metadata, so a store recreated at the same path is
# read afresh. Chunk writes never touch metadata, so the cached zarr array
# handles stay valid for the whole campaign.
_LAYOUT_CACHE: dict[tuple[str, int], dict] = {}


def _layout(path: Path) -> dict:
    key = (str(path.resolve()), (path / "zarr.json").stat().st_mtime_ns)
    got = _LAYOUT_CACHE.get(key)
    if got is None:
        attrs = store_attrs(path)
        got = {"layout": json.loads(attrs["layout"]),
               "plan": ChunkPlan(int(attrs["n_samples"]), int(attrs["chunk_size"])),
               "handles": None}
        _LAYOUT_CACHE.clear()
        _LAYOUT_CACHE[key] = got
    return got


def write_chunk_region(path: str | os.PathLike, chunk_id: int, start: int, stop: int,
                       arrays: Mapping[str, np.ndarray]) -> None:
    """Write one chunk's samples, then mark it done (last).

    Parameters
    ----------
    path : path
        An engine store.
    chunk_id, start, stop : int
        The chunk and its sample slice ``[start, stop)``; must match the store's plan.
    arrays : mapping name -> ndarray
        Every sample variable of the store, each of shape
        ``(stop - start, *other dims)``, castable to the stored dtype.
    """
    path = Path(path)
    lay = _layout(path)
    plan: ChunkPlan = lay["plan"]
    if plan.bounds(int(chunk_id)) != (int(start), int(stop)):
        raise InputError(f"chunk {chunk_id} is samples {plan.bounds(int(chunk_id))} in {path}, "
                         f"got [{start}, {stop})", field="chunk_id")
    missing = set(lay["layout"]) - set(arrays)
    extra = set(arrays) - set(lay["layout"])
    if missing or extra:
        raise InputError(f"chunk arrays must be exactly the store's sample variables; "
                         f"missing {sorted(missing)}, unknown {sorted(extra)}", field="arrays")
    out = {}
    n = int(stop) - int(start)
    for name, spec in lay["layout"].items():
        arr = np.asarray(arrays[name])
        want = (n, *spec["shape"][1:])
        if arr.shape != want:
            raise InputError(f"shape {arr.shape}, expected {want}", field=f"arrays.{name}")
        out[name] = arr.astype(spec["dtype"], copy=False)
    # The store's sample variables carry no CF encoding (no scale/offset, no
    # time units), so the stored values are the arrays themselves and the
    # write skips xarray; nothing touches the shared metadata.
    handles = lay["handles"]
    if handles is None:
        handles = lay["handles"] = _open_handles(str(path), [*lay["layout"], DONE_VAR],
                                                 plan.chunk_size)
    chunk_id = int(chunk_id)
    _write_chunk(handles, out, chunk_id, slice(int(start), int(stop)))
    _write_chunk(handles, {DONE_VAR: np.ones(1, dtype=bool)}, chunk_id,
                 slice(chunk_id, chunk_id + 1))  # last: the chunk is complete


def _open_handles(path: str, names: list[str], chunk_size: int) -> dict:
    """``{name: (AsyncArray, whole-chunk writer or None)}``, once per worker and store.

    Opening the group parses the consolidated metadata of every array (~4 ms
    of CPU), so the handles are kept with the cached layout.
    """
    import asyncio

    import zarr.api.asynchronous as za
    from zarr.core.sync import sync

    from ideas_hpc.engine.chunk_files import whole_chunk_writer

    async def run():
        group = await za.open_group(store=path, mode="r+")
        return await asyncio.gather(*(group.getitem(n) for n in names))

    return {n: (a, whole_chunk_writer(a, 1 if n == DONE_VAR else chunk_size))
            for n, a in zip(names, sync(run()))}


def _write_chunk(handles: dict, arrays: dict, chunk_id: int, sl: slice) -> None:
    """Write chunk ``chunk_id`` of each array: its own chunk file when
    :func:`~ideas_hpc.engine.chunk_files.whole_chunk_writer` supports the
    array (~0.5 ms each), otherwise zarr's async ``setitem`` on slice ``sl``,
    issued together (zarr spends a few ms of fixed cost per call). Returns
    when every write has completed.
    """
    import asyncio

    from zarr.core.sync import sync

    rest = {}
    for name, arr in arrays.items():
        write = handles[name][1]
        if write is not None:
            write(chunk_id, arr)
        else:
            rest[name] = arr
    if rest:
        async def run():
            await asyncio.gather(*(handles[n][0].setitem(sl, a) for n, a in rest.items()))

        sync(run())


def done_mask(path: str | os.PathLike) -> np.ndarray:
    """``chunk_done`` of a store as a bool array; an unreadable flag counts as not done."""
    import zarr

    path = Path(path)
    arr = zarr.open_array(str(path / DONE_VAR), mode="r")
    try:
        return np.asarray(arr[:], dtype=bool)
    except Exception:  # a flag file torn by a kill: read one by one
        out = np.zeros(arr.shape[0], dtype=bool)
        for i in range(arr.shape[0]):
            try:
                out[i] = bool(arr[i])
            except Exception:
                out[i] = False
        return out
