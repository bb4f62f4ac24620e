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
2. Each task calls :func:`ideas_hpc.engine.chunk_write.write_chunk_region`: an xarray region write of its
   sample slice, then ``chunk_done[chunk_id] = True`` **last**. A kill between
   the two leaves the chunk not done; a resumed campaign redoes it, and since
   a chunk depends only on its sample indices and seeds the redo is identical.

Modules: :mod:`~ideas_hpc.engine.store_meta` (names, :class:`ChunkPlan`, config
hash, attrs), this module (creation and the resume check) and
:mod:`~ideas_hpc.engine.chunk_write` (region writes, ``done_mask``); import each name from
the module that defines it (the package :mod:`ideas_hpc.engine` gathers the public ones).

Seeds
-----
The seed scheme is :mod:`ideas_hpc.base.seeds` (``SeedSequence(s, spawn_key=(k,))``
per sample). The store keeps ``s`` in attrs and, per sample, the first four
words of that sequence's state (``sample_seed``, (sample, seed_word) uint32)
so any stored sample can be identified and re-run.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import time
import uuid
import warnings
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.engine.variables import describe
from ideas_hpc.engine.store_meta import (CHUNK_DIM, DONE_VAR, ENGINE_TAG, SAMPLE_DIM, SEED_VAR,
                                        ChunkPlan, _jsonable, config_diff, config_hash,
                                        config_json, store_attrs, without_later_defaults)
from ideas_hpc.base.seeds import seeds_for

_PARTIAL = ".partial-"


# --------------------------------------------------------------------------- creation

def _default_compressors():
    from zarr.codecs import ZstdCodec

    return (ZstdCodec(level=3),)


def _partial_dirs(path: Path) -> list[Path]:
    return sorted(path.parent.glob(f".{path.name}{_PARTIAL}*"))


def _remove_dead_partials(path: Path) -> None:
    """Delete hidden creation dirs left by killed processes on this host."""
    from ideas_hpc.engine.lock import _pid_alive

    host = socket.gethostname()
    for d in _partial_dirs(path):
        try:
            _, h, pid, _tok = d.name.rsplit("-", 3)
            if h == host and not _pid_alive(int(pid)):
                shutil.rmtree(d, ignore_errors=True)
        except ValueError:
            continue


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
        _check_compatible(path, config, plan, layout, int(campaign_seed))
        return False

    from ideas_hpc._version import code_version

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
    return describe(ds)


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


def config_problems(attrs: Mapping, config: Mapping, campaign_seed: int) -> list[str]:
    """How a store's attrs differ from a resolved config and seed (empty: compatible).

    When ``config`` has ``defaults`` and ``effective`` attributes (dotted key ->
    default, and -> the value a null key resolves to, as
    :func:`ideas_hpc.campaign.schema.campaign_tables.resolved_config` gives), keys the
    stored config lacks and whose value is their default, and null keys whose
    resolved value is the stored one, are not differences: the store was
    written by older code (:func:`without_later_defaults`).
    """
    problems = []
    if attrs.get("config_hash") != config_hash(config):
        old = attrs.get("config", {})
        old = json.loads(old) if isinstance(old, str) else old
        new = without_later_defaults(old, config, getattr(config, "defaults", None) or {},
                                     getattr(config, "effective", None))
        if config_json(new) != config_json(old):
            kinds = (old.get("kind"), config.get("kind")) if isinstance(old, Mapping) else ()
            if kinds and kinds[0] != kinds[1]:   # the one difference that explains the rest
                problems.append(f"a store of kind {kinds[0]!r}, this campaign is kind "
                                f"{kinds[1]!r}")
            problems += [p for p in config_diff(old, new) if not p.startswith("kind =")] \
                or ["config hash differs"]
    if int(attrs.get("campaign_seed", -1)) != int(campaign_seed):
        problems.append(f"campaign seed {attrs.get('campaign_seed')} in the store, "
                        f"{campaign_seed} now")
    return problems


def _check_compatible(path: Path, config: Mapping, plan: ChunkPlan,
                      layout: dict, campaign_seed: int) -> None:
    try:
        attrs = store_attrs(path)
    except InputError as exc:
        raise InputError(f"cannot resume {path}: {exc.message}", field="out") from exc
    problems = config_problems(attrs, config, campaign_seed)
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
    from ideas_hpc._version import warn_code_version

    warn_code_version(path, attrs)
