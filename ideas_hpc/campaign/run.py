"""Run a campaign file of any kind and write its zarr store (SPEC sections 7-9).

The kind comes from the registry (:mod:`ideas_hpc.campaign.schema.kinds`). Every kind
writes through the engine: ``monte-carlo`` runs its chunks there; ``flyby`` and
the designs compute their result in one piece, which the engine writes as a
one-chunk store (:mod:`ideas_hpc.engine.single`): atomically, with the same
provenance attrs, and resumable (``--resume`` keeps a finished store with the
same resolved config).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from ideas_hpc.engine.lock import StoreLock
from ideas_hpc.engine.single import check_existing, write_complete
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import result
from ideas_hpc.base.progress import enabled as progress_enabled
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.campaign.schema.campaign_tables import SCHEMA, Campaign, load, resolved_config
from ideas_hpc.campaign.schema.model_fields import flyby_errors


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def run_file(path, *, out=None, overrides=None, workers=None, scheduler=None, resume=False,
             cluster="local", slurm_config=None, progress=True) -> Path:
    """Run any campaign file; returns the store path.

    Every :class:`~ideas_hpc.base.errors.InputError` leaves here with the campaign
    file and line of its field (when it names one), and no store is left.
    """
    c = load(path, overrides)
    try:
        with flyby_errors(), progress_enabled(progress):   # flyby-layer names -> file keys
            return _run(c, out=out, workers=workers, scheduler=scheduler, resume=resume,
                        cluster=cluster, slurm_config=slurm_config, progress=progress)
    except InputError as exc:
        if (exc.field or "").split(".")[0] not in SCHEMA:  # --out, --resume: no file line
            raise
        raise c.source.locate(exc) from None


def _check_execution(out: Path, workers, w_field: str, kind, scheduler) -> None:
    """Refuse a bad ``--workers`` or ``--out`` before anything is computed or written."""
    if workers is not None and scheduler is None and workers < 0:
        raise InputError(f"must be >= 0 (0: in this process), got {workers}", field=w_field)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out} is an existing file, not a store; choose another --out",
                         field="--out")
    parent = out.absolute().parent
    try:  # a probe file: root passes os.access checks where writes still fail (/proc)
        parent.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=parent, prefix=f".{out.name}.probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InputError(f"cannot write in {parent}: {exc.strerror}", field="--out") from None


def _run(c: Campaign, *, out, workers, scheduler, resume, cluster, slurm_config,
         progress) -> Path:
    out = Path(out) if out else Path(Path(c.source.path).stem + ".zarr")
    w_field = "--workers" if workers is not None else "run.workers"
    workers = workers if workers is not None else c.config.run.workers
    kind = KINDS[c.kind]
    _check_execution(out, workers, w_field, kind, scheduler)
    if c.config.description:   # e.g. the smoke run says it is not a design, first
        result(f"campaign: {c.config.description}")
    run = kind.runner(c.config.design.method)
    exec_kw = dict(workers=workers, scheduler=scheduler, cluster=cluster,
                   slurm_config=slurm_config)
    if kind.chunked:
        run(c, out, resume=resume, progress=progress, **exec_kw)
        return out
    config, seed = resolved_config(c), c.config.seed
    with StoreLock(out):
        if check_existing(out, config=config, campaign_seed=seed, resume=resume):
            _log(f"{out}: already complete for this config; nothing to do")
            return out
        ds = run(c, out, **exec_kw)
        # the engine writes the provenance (config, hash, seeds, code version)
        write_complete(out, ds, config=config, campaign_seed=seed)
    _log(f"wrote {out}")
    return out
