"""Results computed in one piece (a flyby, a design) as one-chunk engine stores.

Every campaign kind writes through the engine, so every store has the same
provenance (resolved config and its hash, code version, campaign seed and
``sample_seed``, ``chunk_done``) and the same create/resume rules. A kind that
computes its whole result at once gives the engine a finished dataset: the
store gets a ``sample`` dimension of length 1 (one plan sample, one chunk) and
its variables keep their own dimensions.

Order of a one-piece run: :func:`check_existing` before the work (refuse an
existing store early, skip a finished one), then :func:`write_complete`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.engine.lock import StoreLock
from ideas_hpc.engine.chunk_write import done_mask, write_chunk_region
from ideas_hpc.engine.store import config_problems, create_store
from ideas_hpc.engine.store_meta import store_attrs
from ideas_hpc.engine.store_meta import SAMPLE_DIM


def check_existing(path: str | os.PathLike, *, config: Mapping, campaign_seed: int,
                   resume: bool) -> bool:
    """Before computing: may ``path`` be written? Returns True when it is already finished.

    Raises
    ------
    InputError
        ``path`` exists without ``resume``; it is not a readable store; it was
        written by another resolved config (the differing fields named) or seed.
    """
    path = Path(path)
    if not (path.exists() or path.is_symlink()):
        return False
    if not resume:
        raise InputError(f"store {path} already exists; use --resume to continue or keep it, "
                         "or choose another --out", field="--out")
    try:
        attrs = store_attrs(path)
    except InputError as exc:
        raise InputError(f"{path} exists but is not a readable store ({exc.message})",
                         field="--out") from None
    problems = config_problems(attrs, config, campaign_seed)
    if problems:
        raise InputError(f"store {path} was written by an incompatible config ("
                         + "; ".join(problems) + ")", field="--resume")
    from ideas_hpc._version import warn_code_version

    warn_code_version(path, attrs)
    return bool(done_mask(path).all())


def write_complete(path: str | os.PathLike, ds, *, config: Mapping, campaign_seed: int,
                   attrs: Mapping | None = None) -> None:
    """Write a finished dataset as a one-chunk engine store (atomic: all or nothing).

    A store left by a run killed between its creation and its done flag is
    finished here (same config, so the same numbers).
    """
    template = ds if SAMPLE_DIM in ds.dims else ds.assign_coords({SAMPLE_DIM: np.arange(1)})
    n = int(template.sizes[SAMPLE_DIM])
    sample_vars = {k: np.asarray(v.values) for k, v in template.data_vars.items()
                   if SAMPLE_DIM in v.dims}
    with StoreLock(path):
        create_store(path, template, config=config, campaign_seed=campaign_seed, chunk_size=n,
                     attrs=attrs, resume=True)
        if not done_mask(path).all():
            write_chunk_region(path, 0, 0, n, sample_vars)
