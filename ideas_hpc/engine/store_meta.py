"""Store schema and metadata of engine stores: names, the chunk plan, the config hash
and the root attrs (SPEC sections 8-9). Creation is :mod:`ideas_hpc.engine.store`,
chunk writes :mod:`ideas_hpc.engine.chunk_write`."""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np

from ideas_hpc.base.errors import InputError

SAMPLE_DIM = "sample"
CHUNK_DIM = "chunk"
DONE_VAR = "chunk_done"
SEED_VAR = "sample_seed"
ENGINE_TAG = "ideas_hpc.engine/1"


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


def without_later_defaults(old: Mapping, new: Mapping, defaults: Mapping[str, Any],
                           effective: Mapping[str, Any] | None = None) -> dict:
    """``new`` (canonical JSON form) as a store's ``old`` config, written by older code, says it.

    A key is dropped when it is absent from ``old`` (a store written before the
    key existed) and its value in ``new`` equals ``defaults[key]`` (dotted key:
    its default, which by the project's rule is the old behaviour). A key whose
    default became null ("the code's own value") reads as ``old``'s value when
    that is the value the code uses now, ``effective[key]`` (floats to 1e-12).
    Any other difference stays, so a real change still differs. Tables left
    empty by the dropping are dropped too.
    """
    a = _flatten(json.loads(config_json(old)))
    canon = json.loads(config_json(new))
    flat_defaults = {k: config_json({"v": v}) for k, v in defaults.items()}
    effective = effective or {}

    def same(x: Any, y: Any) -> bool:
        if isinstance(x, float) or isinstance(y, float):
            return (isinstance(x, (int, float)) and isinstance(y, (int, float))
                    and abs(x - y) <= 1e-12 * max(abs(x), abs(y)))
        return x == y

    def prune(obj: Any, prefix: str) -> Any:
        if not isinstance(obj, dict) or not obj:
            return obj
        out = {}
        for k, v in obj.items():
            key = f"{prefix}.{k}" if prefix else k
            if isinstance(v, dict) and v:
                v = prune(v, key)
                if v == {} and key not in a and not any(x.startswith(key + ".") for x in a):
                    continue
            elif (key not in a and key in flat_defaults
                  and config_json({"v": v}) == flat_defaults[key]):
                continue
            elif v is None and key in a and key in effective and same(a[key], effective[key]):
                v = a[key]
            out[k] = v
        return out

    return prune(canon, "")


# --------------------------------------------------------------------------- metadata

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
