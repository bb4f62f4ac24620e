"""Chunked, resumable campaign execution on dask into zarr (SPEC section 8).

Campaign kinds plug in a template and a chunk function::

    from ideas_hpc.engine import run_campaign
    summary = run_campaign("mc.zarr", template, functools.partial(my_chunk, ...),
                           config=resolved_config, campaign_seed=seed, chunk_size=8,
                           resume=args.resume, workers=args.workers,
                           scheduler=args.scheduler, cluster="local")

* :mod:`~ideas_hpc.engine.store`: store creation and the resume check.
* :mod:`~ideas_hpc.engine.store_meta`: names, chunk plan, config hash, attrs.
* :mod:`~ideas_hpc.engine.chunk_write`: region writes, ``done_mask``.
* The per-sample seed helpers are those of :mod:`ideas_hpc.base.seeds`, gathered here too.
* :mod:`~ideas_hpc.engine.lock`: one writer per store.
* :mod:`~ideas_hpc.engine.cluster`: LocalCluster, existing scheduler, SLURMCluster
  (settings in ``dask.config``, defaults shipped as ``engine/jobqueue.yaml``).
* :mod:`~ideas_hpc.engine.runner`: one dask task per chunk, retries, progress.
* :mod:`~ideas_hpc.engine.gate`: hold chunk tasks until released (``IDEAS_HPC_CHUNK_GATE``).
"""

from __future__ import annotations

from ideas_hpc.engine.cluster import connect, load_slurm_config, local_cluster, slurm_cluster
from ideas_hpc.engine.lock import StoreLock, StoreLockedError
from ideas_hpc.engine.runner import CampaignError, RunSummary, run_campaign, run_chunks
from ideas_hpc.engine.chunk_write import done_mask, write_chunk_region
from ideas_hpc.engine.store import create_store
from ideas_hpc.engine.store_meta import (CHUNK_DIM, DONE_VAR, SAMPLE_DIM, SEED_VAR, ChunkPlan,
                                        config_hash, is_store, store_attrs, store_plan)
from ideas_hpc.base.seeds import sample_rng, sample_seed_sequence, seeds_for

__all__ = [
    "CHUNK_DIM", "DONE_VAR", "SAMPLE_DIM", "SEED_VAR", "CampaignError", "ChunkPlan",
    "RunSummary", "StoreLock", "StoreLockedError", "config_hash", "connect", "create_store",
    "done_mask", "is_store", "load_slurm_config", "local_cluster", "run_campaign", "run_chunks",
    "sample_rng", "sample_seed_sequence", "seeds_for", "slurm_cluster", "store_attrs",
    "store_plan", "write_chunk_region",
]
