"""Whole-chunk writes of zarr v3 arrays on a local store, without the async pipeline.

A campaign task writes exactly one zarr chunk of every sample variable (the
store is chunked that way, :mod:`ideas_hpc.engine.store`). zarr's own
``setitem`` sends each of those writes through its event-loop thread and two
thread-pool hops (encode, then put): 22 variables cost ~45 ms of CPU per chunk
on the development VM, while encoding them with the arrays' own codecs and
writing the files takes ~11 ms (``benchmarks/bench_campaign.py`` reports the
per-chunk write). With two workers on two cores that CPU is taken from the
other worker's compute.

:func:`whole_chunk_writer` returns a writer only for the layout this module
understands (local filesystem store, zarr format 3, regular chunk grid with
the whole chunk being written, C order, one array-to-bytes codec followed by
bytes-to-bytes codecs that all encode synchronously); otherwise None, and the
caller uses zarr's ``setitem``. The bytes are the ones zarr writes for the
same data (``tests/test_engine_chunk_files.py`` compares them file for file),
and each file is replaced atomically as zarr does, so a kill leaves either
the old chunk or the new one.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path
from typing import Callable

import numpy as np

ChunkWriter = Callable[[int, np.ndarray], None]


def whole_chunk_writer(array, chunk_rows: int) -> ChunkWriter | None:
    """A ``write(chunk_index, data)`` for one zarr array, or None when unsupported.

    Parameters
    ----------
    array : zarr.AsyncArray or zarr.Array
        An array chunked ``(chunk_rows, *shape[1:])``.
    chunk_rows : int
        Rows (samples) per chunk along the first axis.

    Returns
    -------
    callable or None
        ``write(i, data)`` stores ``data`` (rows ``i*chunk_rows`` onwards, at
        most ``chunk_rows`` of them, the other axes whole) as chunk ``i``;
        a short last chunk is padded with the fill value, as zarr stores it.
    """
    try:
        from zarr.abc.codec import ArrayBytesCodec, BytesBytesCodec, SupportsSyncCodec
        from zarr.core.buffer import default_buffer_prototype
        from zarr.core.chunk_grids import RegularChunkGrid
        from zarr.core.metadata.v3 import ArrayV3Metadata
        from zarr.storage import LocalStore
    except ImportError:  # pragma: no cover - a zarr without these internals
        return None
    a = getattr(array, "_async_array", array)
    md = a.metadata
    store = a.store_path.store
    shape = tuple(md.shape)
    if not (isinstance(store, LocalStore) and isinstance(md, ArrayV3Metadata)
            and isinstance(md.chunk_grid, RegularChunkGrid)
            and tuple(md.chunk_grid.chunk_shape) == (chunk_rows, *shape[1:])
            and a.config.order == "C" and len(md.codecs) >= 1
            and isinstance(md.codecs[0], ArrayBytesCodec)
            and all(isinstance(c, BytesBytesCodec) for c in md.codecs[1:])
            and all(isinstance(c, SupportsSyncCodec) for c in md.codecs)):
        return None
    proto = default_buffer_prototype()
    codecs = tuple(md.codecs)
    chunk_shape = (chunk_rows, *shape[1:])
    dtype = md.dtype.to_native_dtype()
    fill = md.fill_value
    root = Path(store.root) / a.store_path.path

    def write(i: int, data: np.ndarray) -> None:
        coords = (int(i),) + (0,) * (len(shape) - 1)
        data = np.asarray(data, dtype=dtype)
        if data.shape != chunk_shape:
            full = np.full(chunk_shape, fill, dtype=dtype)
            full[: data.shape[0]] = data
            data = full
        spec = md.get_chunk_spec(coords, a.config, proto)
        buf = proto.nd_buffer.from_numpy_array(np.ascontiguousarray(data))
        for codec in codecs:
            buf = codec._encode_sync(buf, spec)
        target = root / md.encode_chunk_key(coords)
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name(f"{target.name}.{uuid.uuid4().hex}.partial")
        try:
            with open(tmp, "wb") as f:
                f.write(buf.as_buffer_like())
            os.replace(tmp, target)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    return write
