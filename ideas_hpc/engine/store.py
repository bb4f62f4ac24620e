"""Chunked, resumable zarr stores laid out for xarray (SPEC sections 8-9).

A campaign store is written in two steps:

1. :func:`create_store` writes the xarray *template* with ``compute=False``:
   every data variable that has the ``sample`` dimension is only declared
   (metadata, chunked ``chunk_size`` samples along ``sample`` and whole along
   every other dimension, so each chunk of samples is exactly one zarr chunk
   and is written by exactly one task); everything else (coordinates,
   per-vertex areas, the per-sample seeds) is written in full. It also writes
   ``chunk_done`` (dim ``chunk``, one zarr chunk per campaign chunk, all False)
   and the attrs: resolved config (JSON), its hash, code version, campaign
   seed, sample count and chunk size. Creation goes to a hidden sibling
   directory that is renamed into place at the end, so a failure (or a kill)
   never leaves a partial store at ``path``.
2. Each task calls :func:`write_chunk_region`: an xarray region write of its
   sample slice, then ``chunk_done[chunk_id] = True`` **last**. A kill between
   the two leaves the chunk not done; a resumed campaign redoes it, and since
   a chunk depends only on its sample indices and seeds the redo is identical.

Seeds
-----
Sample ``k`` of a campaign with seed ``s`` draws from
``np.random.default_rng(np.random.SeedSequence(s, spawn_key=(k,)))``
(:func:`sample_rng`), the same stream as ``SeedSequence(s).spawn(k + 1)[k]``,
so a sample re-runs alone and results do not depend on chunking or on the
worker count. The store keeps ``s`` in attrs and, per sample, the first four
words of that sequence's state (``sample_seed``, (sample, seed_word) uint32)
so any stored sample can be identified and re-run.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import socket
import time
import uuid
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np

from ..errors import InputError

SAMPLE_DIM = "sample"
CHUNK_DIM = "chunk"
DONE_VAR = "chunk_done"
SEED_VAR = "sample_seed"
SEED_WORDS = 4
ENGINE_TAG = "ideas_hpc.engine/1"
_PARTIAL = ".partial-"


# --------------------------------------------------------------------------- seeds

def sample_seed_sequence(campaign_seed: int, k: int) -> np.random.SeedSequence:
    """The :class:`numpy.random.SeedSequence` of sample ``k`` (``spawn_key=(k,)``)."""
    return np.random.SeedSequence(int(campaign_seed), spawn_key=(int(k),))


def sample_rng(campaign_seed: int, k: int) -> np.random.Generator:
    """Random generator of sample ``k``: ``default_rng(SeedSequence(campaign_seed, spawn_key=(k,)))``."""
    return np.random.default_rng(sample_seed_sequence(campaign_seed, k))


def seeds_for(campaign_seed: int, n_samples: int) -> np.ndarray:
    """Per-sample seed words, ``(n_samples, 4)`` uint32.

    Row ``k`` is ``SeedSequence(campaign_seed, spawn_key=(k,)).generate_state(4)``;
    it identifies the stream :func:`sample_rng` gives for sample ``k``.
    """
    if int(n_samples) < 0:
        raise InputError(f"must be >= 0, got {n_samples}", field="n_samples")
    out = np.empty((int(n_samples), SEED_WORDS), dtype=np.uint32)
    for k in range(int(n_samples)):
        out[k] = sample_seed_sequence(campaign_seed, k).generate_state(SEED_WORDS, np.uint32)
    return out


# --------------------------------------------------------------------------- chunk plan

@dataclass(frozen=True)
class ChunkPlan:
    """Split ``n_samples`` samples into chunks of ``chunk_size`` (the last may be shorter)."""

    n_samples: int
    chunk_size: int

    def __post_init__(self):
        if int(self.n_samples) < 1:
            raise InputError(f"must be >= 1, got {self.n_samples}", field="n_samples")
        if int(self.chunk_size) < 1:
            raise InputError(f"must be >= 1, got {self.chunk_size}", field="chunk_size")

    @property
    def n_chunks(self) -> int:
        return -(-int(self.n_samples) // int(self.chunk_size))

    def bounds(self, chunk_id: int) -> tuple[int, int]:
        """``(start, stop)`` sample indices of chunk ``chunk_id``."""
        if not 0 <= chunk_id < self.n_chunks:
            raise InputError(f"chunk {chunk_id} outside 0..{self.n_chunks - 1}", field="chunk_id")
        start = chunk_id * self.chunk_size
        return start, min(start + self.chunk_size, self.n_samples)

    def chunks(self) -> list[tuple[int, int, int]]:
        """All chunks as ``(chunk_id, start, stop)``."""
        return [(c, *self.bounds(c)) for c in range(self.n_chunks)]

    def __iter__(self) -> Iterator[tuple[int, int, int]]:
        return iter(self.chunks())

    def __len__(self) -> int:
        return self.n_chunks


# --------------------------------------------------------------------------- config hash

def _jsonable(obj: Any) -> Any:
    if isinstance(obj, Mapping):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    if obj is None or isinstance(obj, (bool, int, float, str)):
        return obj
    return str(obj)


def config_json(config: Mapping) -> str:
    """Canonical JSON of a resolved config (sorted keys), as stored in attrs."""
    return json.dumps(_jsonable(config), sort_keys=True, separators=(",", ":"), allow_nan=True)


def config_hash(config: Mapping) -> str:
    """``sha256:<hex>`` of :func:`config_json`."""
    return "sha256:" + hashlib.sha256(config_json(config).encode()).hexdigest()


def _flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(obj, Mapping):
        out: dict[str, Any] = {}
        for k, v in obj.items():
            out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
        return out or {prefix: {}}
    return {prefix: obj}


def config_diff(old: Mapping, new: Mapping, limit: int = 6) -> list[str]:
    """Human-readable differences between two configs (dotted keys)."""
    a, b = _flatten(_jsonable(old)), _flatten(_jsonable(new))
    out = []
    for key in sorted(set(a) | set(b)):
        if key not in b:
            out.append(f"{key} = {a[key]!r} in the store, absent now")
        elif key not in a:
            out.append(f"{key} absent in the store, {b[key]!r} now")
        elif a[key] != b[key]:
            out.append(f"{key} = {a[key]!r} in the store, {b[key]!r} now")
    if len(out) > limit:
        out = out[:limit] + [f"... and {len(out) - limit} more"]
    return out


# --------------------------------------------------------------------------- creation

def _default_compressors():
    from zarr.codecs import ZstdCodec

    return (ZstdCodec(level=3),)


def _partial_dirs(path: Path) -> list[Path]:
    return sorted(path.parent.glob(f".{path.name}{_PARTIAL}*"))


def _remove_dead_partials(path: Path) -> None:
    """Delete hidden creation dirs left by killed processes on this host."""
    from .lock import _pid_alive

    host = socket.gethostname()
    for d in _partial_dirs(path):
        try:
            _, h, pid, _tok = d.name.rsplit("-", 3)
            if h == host and not _pid_alive(int(pid)):
                shutil.rmtree(d, ignore_errors=True)
        except ValueError:
            continue


def is_store(path: str | os.PathLike) -> bool:
    """True when ``path`` is a store written by this engine."""
    try:
        return _read_attrs(Path(path)).get("engine") == ENGINE_TAG
    except (OSError, ValueError, KeyError):
        return False


def _read_attrs(path: Path) -> dict:
    meta = json.loads((path / "zarr.json").read_text())
    return dict(meta.get("attributes", {}))


def store_attrs(path: str | os.PathLike) -> dict:
    """Attrs of an engine store, with ``config`` decoded from JSON."""
    path = Path(path)
    try:
        attrs = _read_attrs(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"{path} is not a readable zarr store ({exc})", field="store") from exc
    if attrs.get("engine") != ENGINE_TAG:
        raise InputError(f"{path} is not an ideas_hpc campaign store", field="store")
    attrs["config"] = json.loads(attrs["config"])
    return attrs


def store_plan(path: str | os.PathLike) -> ChunkPlan:
    """The :class:`ChunkPlan` a store was created with."""
    a = store_attrs(path)
    return ChunkPlan(int(a["n_samples"]), int(a["chunk_size"]))


def _layout_of_template(template, chunk_size: int) -> dict:
    return {name: {"dims": list(v.dims), "shape": [int(s) for s in v.shape],
                   "dtype": str(np.dtype(v.dtype))}
            for name, v in template.data_vars.items() if SAMPLE_DIM in v.dims}


def create_store(path: str | os.PathLike, template, *, config: Mapping, campaign_seed: int,
                 chunk_size: int, attrs: Mapping | None = None, resume: bool = False,
                 compressors=None, encoding: Mapping | None = None) -> bool:
    """Create a campaign store from an xarray template, or check one for resuming.

    Parameters
    ----------
    path : path
        Store directory (``.zarr``). Must not exist unless ``resume``.
    template : xarray.Dataset
        The result layout. It must have the ``sample`` dimension; every data
        variable with ``sample`` must have it first. Those variables are only
        declared (their template values are ignored; unwritten chunks read as
        the fill value: NaN for floats, 0/False otherwise). Everything else
        (coordinates and sample-free variables) is written now. Put units and
        descriptions in each variable's attrs.
    config : mapping
        The resolved campaign config (JSON-able). Stored as JSON in attrs
        ``config`` and hashed into ``config_hash``; a resume with a different
        hash is refused.
    campaign_seed : int
        Stored in attrs; ``sample_seed`` (sample, seed_word) is added.
    chunk_size : int
        Samples per chunk (one dask task and one zarr chunk each).
    attrs : mapping, optional
        Extra global attrs (campaign kind, title...). JSON-able values.
    resume : bool
        When ``path`` exists: check it is compatible and return False.
        When it does not exist: create it as usual.
    compressors : tuple of zarr codecs, optional
        Default ``(ZstdCodec(level=3),)`` for every array except ``chunk_done``.
    encoding : mapping, optional
        Per-variable xarray encoding merged over the engine's.

    Returns
    -------
    bool
        True if the store was created, False if an existing one is resumed.

    Raises
    ------
    InputError
        Bad template or chunk size; ``path`` exists without ``resume``; under
        ``resume``, the store was written by a different config or layout.
    """
    import xarray as xr

    path = Path(path)
    if not isinstance(template, xr.Dataset):
        raise InputError("template must be an xarray.Dataset", field="template")
    if SAMPLE_DIM not in template.dims:
        raise InputError(f"template has no '{SAMPLE_DIM}' dimension", field="template")
    n_samples = int(template.sizes[SAMPLE_DIM])
    plan = ChunkPlan(n_samples, int(chunk_size))
    for reserved in (DONE_VAR, SEED_VAR, CHUNK_DIM):
        if reserved in template.variables:
            raise InputError(f"'{reserved}' is reserved by the engine", field=f"template.{reserved}")
    for name, v in template.data_vars.items():
        if SAMPLE_DIM in v.dims and v.dims[0] != SAMPLE_DIM:
            raise InputError(f"'{SAMPLE_DIM}' must be the first dimension, got {v.dims}",
                             field=f"template.{name}")
    chash = config_hash(config)
    layout = _layout_of_template(template, plan.chunk_size)

    if path.exists() or path.is_symlink():
        if not resume:
            raise InputError(f"store {path} already exists; pass --resume to continue it, "
                             "or choose another --out", field="out")
        _check_compatible(path, chash, config, plan, layout, int(campaign_seed))
        return False

    from .._version import code_version

    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_dead_partials(path)
    tmp = path.with_name(f".{path.name}{_PARTIAL}{socket.gethostname()}-{os.getpid()}-"
                         f"{uuid.uuid4().hex[:8]}")
    try:
        ds = _build_dataset(template, plan, int(campaign_seed))
        ds.attrs.update(_jsonable(dict(attrs or {})))
        ds.attrs.update({
            "engine": ENGINE_TAG,
            "config": config_json(config),
            "config_hash": chash,
            "code_version": code_version(),
            "campaign_seed": int(campaign_seed),
            "seed_scheme": "numpy SeedSequence(campaign_seed, spawn_key=(sample,)); "
                           "sample_seed = its generate_state(4, uint32)",
            "n_samples": n_samples,
            "chunk_size": plan.chunk_size,
            "n_chunks": plan.n_chunks,
            "layout": json.dumps(layout, sort_keys=True),
            "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        })
        enc = _encoding(ds, plan, compressors)
        for name, e in (encoding or {}).items():
            enc.setdefault(name, {}).update(e)
        with warnings.catch_warnings():
            # Consolidated metadata is a zarr-python extension for format 3; we
            # want it so that plain xarray.open_zarr(STORE) opens fast and quietly.
            warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
            ds.to_zarr(tmp, mode="w-", compute=False, encoding=enc, consolidated=True)
        try:
            os.rename(tmp, path)
        except OSError as exc:
            raise InputError(f"store {path} appeared while it was being created ({exc})",
                             field="out") from exc
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return True


def _build_dataset(template, plan: ChunkPlan, campaign_seed: int):
    import dask.array as da
    import xarray as xr

    ds = template.copy(deep=False)
    for name, v in template.variables.items():
        if v.dtype.kind == "U":
            # Fixed-width unicode has no zarr v3 spec yet (zarr warns); object
            # strings are stored as the specified variable-length string type.
            ds[name] = v.astype(object)
    for name, v in template.data_vars.items():
        if SAMPLE_DIM not in v.dims:
            continue
        chunks = tuple(plan.chunk_size if d == SAMPLE_DIM else -1 for d in v.dims)
        dtype = np.dtype(v.dtype)
        # Lazy placeholders: to_zarr(compute=False) declares them, nothing is computed.
        lazy = da.zeros(v.shape, dtype=dtype, chunks=chunks)
        ds[name] = xr.Variable(v.dims, lazy, attrs=v.attrs)
    ds[SEED_VAR] = xr.Variable(
        (SAMPLE_DIM, "seed_word"), seeds_for(campaign_seed, plan.n_samples),
        attrs={"description": "first 4 words of SeedSequence(campaign_seed, spawn_key=(sample,))"})
    ch = np.array(plan.chunks(), dtype=np.int64).reshape(-1, 3)
    ds[DONE_VAR] = xr.Variable((CHUNK_DIM,), np.zeros(plan.n_chunks, dtype=bool), attrs={
        "description": "True once every sample of the chunk is written (written last)"})
    ds = ds.assign_coords(chunk_start=((CHUNK_DIM,), ch[:, 1]), chunk_stop=((CHUNK_DIM,), ch[:, 2]))
    return ds


def _encoding(ds, plan: ChunkPlan, compressors) -> dict:
    comp = tuple(compressors) if compressors is not None else _default_compressors()
    enc: dict[str, dict] = {}
    for name, v in ds.variables.items():
        if name == DONE_VAR:
            # One zarr chunk per campaign chunk: tasks never share a chunk file.
            enc[name] = {"chunks": (1,), "compressors": None}
            continue
        e: dict[str, Any] = {"compressors": comp}
        if SAMPLE_DIM in v.dims and name != SEED_VAR and name in ds.data_vars:
            e["chunks"] = tuple(plan.chunk_size if d == SAMPLE_DIM else int(s)
                                for d, s in zip(v.dims, v.shape))
        enc[name] = e
    return enc


def _check_compatible(path: Path, chash: str, config: Mapping, plan: ChunkPlan,
                      layout: dict, campaign_seed: int) -> None:
    try:
        attrs = store_attrs(path)
    except InputError as exc:
        raise InputError(f"cannot resume {path}: {exc.message}", field="out") from exc
    problems = []
    if attrs.get("config_hash") != chash:
        problems += config_diff(attrs["config"], config) or ["config hash differs"]
    if int(attrs.get("campaign_seed", -1)) != campaign_seed:
        problems.append(f"campaign seed {attrs.get('campaign_seed')} in the store, {campaign_seed} now")
    if int(attrs["n_samples"]) != plan.n_samples:
        problems.append(f"{attrs['n_samples']} samples in the store, {plan.n_samples} now")
    if int(attrs["chunk_size"]) != plan.chunk_size:
        problems.append(f"chunk size {attrs['chunk_size']} in the store, {plan.chunk_size} now")
    stored_layout = json.loads(attrs.get("layout", "{}"))
    if not problems and stored_layout != layout:
        for name in sorted(set(stored_layout) | set(layout)):
            if stored_layout.get(name) != layout.get(name):
                problems.append(f"variable {name}: {stored_layout.get(name)} in the store, "
                                f"{layout.get(name)} now")
    if problems:
        raise InputError(f"cannot resume store {path}: it was written by an incompatible "
                         "config: " + "; ".join(problems), field="out")
    from .._version import warn_code_version

    warn_code_version(path, attrs)


# --------------------------------------------------------------------------- chunk writes

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

    from .chunk_files import whole_chunk_writer

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
