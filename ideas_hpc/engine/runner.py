"""Run a campaign's chunks as dask tasks that write their own store regions.

One task per chunk that is not yet done. The task computes the chunk
(``chunk_fn(chunk_id, start, stop) -> {name: array}``), writes its region of
the store and then its ``chunk_done`` flag, all on the worker: the client only
submits, counts completions (tqdm progress bar) and holds the store's lock.
dask retries a task that raises (``retries``) and reschedules tasks whose
worker died. A chunk depends only on its sample indices and the campaign seed,
so a retried, redone or resumed chunk writes identical values.

``chunk_fn`` must be picklable: a module-level function, or
:func:`functools.partial` of one with picklable arguments.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.engine.cluster import TASK_THREADS_ENV, connect
from ideas_hpc.engine.gate import gate_from_env, pass_gate
from ideas_hpc.engine.lock import StoreLock
from ideas_hpc.engine.chunk_write import done_mask, write_chunk_region
from ideas_hpc.engine.store import create_store
from ideas_hpc.engine.store_meta import ChunkPlan, store_plan
from ideas_hpc.base.progress import map_chunks

ChunkFn = Callable[[int, int, int], Mapping[str, np.ndarray]]


class CampaignError(RuntimeError):
    """Some chunks failed after their retries; the store stays resumable."""


@dataclass
class RunSummary:
    """What :func:`run_chunks` did."""

    store: str
    n_chunks: int
    chunks_run: int
    chunks_skipped: int
    samples_run: int
    wall_s: float
    compute_s: float = 0.0   # summed over tasks: time inside chunk_fn
    write_s: float = 0.0     # summed over tasks: region + flag writes
    n_workers: int = 0
    failed: list[int] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    @property
    def samples_per_s(self) -> float:
        return self.samples_run / self.wall_s if self.wall_s > 0 else float("nan")

    def __str__(self) -> str:
        return (f"{self.store}: {self.chunks_run} chunk{'' if self.chunks_run == 1 else 's'} "
                f"run, {self.chunks_skipped} skipped "
                f"(of {self.n_chunks}), {self.samples_run} sample{'' if self.samples_run == 1 else 's'} "
                f"in {self.wall_s:.2f} s ({self.samples_per_s:.1f} samples/s "
                + (f"on {self.n_workers} dask workers" if self.n_workers else "in this process")
                + f"; tasks spent "
                f"{self.compute_s:.2f} s computing, {self.write_s:.2f} s writing)")


def limit_task_threads() -> int | None:
    """Cap the calling thread's Numba parallel threads at ``IDEAS_HPC_TASK_THREADS``.

    Local workers must run each chunk on one thread (N workers fill N cores).
    ``NUMBA_NUM_THREADS`` cannot say so: a spawned dask worker re-imports the
    launching script (``__mp_main__``) before the nanny's ``env`` reaches
    ``os.environ``, and when that script imports this package, Numba has
    already sized its pool to every core. Each worker's ``prange`` kernels then
    ran on all cores: 2 workers on 2 cores ran 4 busy threads (measured: task
    thread 52 % of a core, the OpenMP helper 26 %), and setting the variable
    late makes Numba raise at its next compilation. The cap is set per thread
    (``numba.set_num_threads``), where the chunk runs.

    Returns the cap applied, or None when the variable is unset (then Numba's
    own ``NUMBA_NUM_THREADS``, read at import, applies; SLURM jobs export it
    before Python starts).
    """
    want = os.environ.get(TASK_THREADS_ENV, "").strip()
    if not want:
        return None
    if not want.isdigit() or int(want) < 1:
        raise InputError(f"must be a positive integer, got {want!r}", field=TASK_THREADS_ENV)
    import numba

    n = min(int(want), numba.config.NUMBA_NUM_THREADS)
    numba.set_num_threads(n)
    return n


def run_chunk(store_path: str, chunk_fn: ChunkFn, chunk_id: int, start: int,
               stop: int, gate: str | None = None) -> tuple[int, int, float, float]:
    """The task: compute one chunk, write its region, then its done flag.

    With a ``gate`` folder (see :mod:`~ideas_hpc.engine.gate`) the task first
    waits for a token there.
    """
    limit_task_threads()
    if gate is not None:
        pass_gate(gate, chunk_id)
    t0 = time.perf_counter()
    arrays = chunk_fn(chunk_id, start, stop)
    t1 = time.perf_counter()
    write_chunk_region(store_path, chunk_id, start, stop, arrays)
    return chunk_id, stop - start, t1 - t0, time.perf_counter() - t1


@dataclass(frozen=True)
class ClusterRequest:
    """Where the chunks run (:func:`ideas_hpc.engine.cluster.connect`): ``cluster``
    ("local" or "slurm"), ``workers``, a ``scheduler`` address, a ``slurm_config``."""

    cluster: str = "local"
    workers: int | None = None
    scheduler: str | None = None
    slurm_config: str | os.PathLike | None = None


def run_chunks(store_path: str | os.PathLike, chunk_fn: ChunkFn, plan: ChunkPlan | None = None,
               *, resume: bool = False, where: ClusterRequest | None = None,
               progress: bool = True, retries: int = 2, client=None,
               in_process: bool = False, **cluster_keywords) -> RunSummary:
    """Run every not-done chunk of a store, one dask task each.

    Parameters
    ----------
    store_path : path
        A store made by :func:`~ideas_hpc.engine.store.create_store`.
    chunk_fn : callable
        ``chunk_fn(chunk_id, start, stop) -> {variable: array}``, picklable,
        deterministic in ``(chunk_id, start, stop)``.
    plan : ChunkPlan, optional
        Must equal the store's plan (checked); default: the store's.
    resume : bool
        Skip chunks marked done. Without it, a store with done chunks is refused.
    where : ClusterRequest, optional
        ``workers``, ``scheduler``, ``cluster``, ``slurm_config`` (also accepted as
        keywords): see :func:`ideas_hpc.engine.cluster.connect`.
    progress : bool
        Show a tqdm bar over completed chunks (stderr).
    retries : int
        How many times dask re-runs a chunk task that raised.
    client : distributed.Client, optional
        Use this client instead of starting or connecting to a cluster.
    in_process : bool
        Without a client: run the chunk tasks one after the other in this
        process (same tasks, writes, retries and gate), no dask
        (:mod:`ideas_hpc.engine.job_cluster` decides when a job is that small).

    Returns
    -------
    RunSummary

    Raises
    ------
    CampaignError
        When chunks still fail after their retries (the others are written;
        rerun with ``resume=True``).
    """
    where = replace(where or ClusterRequest(), **cluster_keywords)
    workers, scheduler, cluster = where.workers, where.scheduler, where.cluster
    slurm_config = where.slurm_config
    path = Path(store_path)
    stored = store_plan(path)
    if plan is not None and (plan.n_samples, plan.chunk_size) != (stored.n_samples,
                                                                   stored.chunk_size):
        raise InputError(f"plan {plan} does not match the store's {stored}", field="plan")
    if not isinstance(retries, int) or retries < 0:
        raise InputError(f"must be an integer >= 0, got {retries!r}", field="retries")
    t0 = time.perf_counter()
    with StoreLock(path):
        done = done_mask(path)
        if done.any() and not resume:
            raise InputError(f"store {path} already has {int(done.sum())} finished chunks; "
                             "pass --resume to continue it", field="resume")
        todo = [c for c in stored.chunks() if not done[c[0]]]
        summary = RunSummary(store=str(path), n_chunks=stored.n_chunks, chunks_run=0,
                             chunks_skipped=stored.n_chunks - len(todo), samples_run=0, wall_s=0.0)
        if todo:
            if client is not None:
                _submit_all(client, path, chunk_fn, todo, summary, progress, retries)
            elif in_process:
                _submit_all(None, path, chunk_fn, todo, summary, progress, retries)
            else:
                logs = path.absolute().parent / f"{path.name}.slurm-logs"
                with connect(cluster=cluster, workers=workers, scheduler=scheduler,
                             slurm_config=slurm_config, log_directory=logs) as cl:
                    _submit_all(cl, path, chunk_fn, todo, summary, progress, retries)
    summary.wall_s = time.perf_counter() - t0
    if summary.failed:
        raise CampaignError(f"{len(summary.failed)} of {len(todo)} chunks failed after "
                            f"{retries} retries (chunks {summary.failed[:10]}): "
                            f"{summary.errors[0]}; the other chunks are written, rerun "
                            "with --resume to redo the failed ones")
    return summary


class _ChunkTask:
    """One store chunk ``(chunk_id, start, stop)`` -> :func:`run_chunk`'s tuple."""

    def __init__(self, path: str, chunk_fn: ChunkFn, gate: str | None):
        self.path, self.chunk_fn, self.gate = path, chunk_fn, gate

    def __call__(self, chunk) -> tuple[int, int, float, float]:
        cid, start, stop = chunk
        return run_chunk(self.path, self.chunk_fn, cid, start, stop, self.gate)


def _submit_all(client, path: Path, chunk_fn: ChunkFn, todo, summary: RunSummary,
                progress: bool, retries: int) -> None:
    """The not-done chunks ``todo`` through :func:`ideas_hpc.base.progress.map_chunks`, on
    ``client``'s workers (``None``: in this process, in order), failures recorded."""
    if client is None:
        summary.n_workers = 0
    else:
        summary.n_workers = len(client.scheduler_info(n_workers=-1).get("workers", {})) \
            if _accepts_n_workers(client) else len(client.scheduler_info().get("workers", {}))
    gate = gate_from_env()  # read here, in the client: workers may not share its environment
    # the chunk function once per worker, not once per task (scatter): a scenario
    # bank's carries its row engine (about 12 MB), which every task would otherwise ship
    results = map_chunks(_ChunkTask(str(path), chunk_fn, gate), list(todo), client,
                         desc=path.name if progress else None, retries=retries,
                         scatter=True, errors="return", done=summary.chunks_skipped)
    for (cid, _start, _stop), res in zip(todo, results):
        if isinstance(res, BaseException):
            summary.failed.append(cid)
            summary.errors.append(f"chunk {cid}: {type(res).__name__}: {res}")
        else:
            _cid, n, t_c, t_w = res
            summary.chunks_run += 1
            summary.samples_run += n
            summary.compute_s += t_c
            summary.write_s += t_w
    summary.failed.sort()


def _accepts_n_workers(client) -> bool:
    import inspect

    try:
        return "n_workers" in inspect.signature(client.scheduler_info).parameters
    except (TypeError, ValueError):
        return False


def run_campaign(store_path: str | os.PathLike, template, chunk_fn: ChunkFn, *,
                 config: Mapping, campaign_seed: int, chunk_size: int,
                 attrs: Mapping | None = None, resume: bool = False, **run_kwargs: Any
                 ) -> RunSummary:
    """Create (or, with ``resume``, check) the store, then run its chunks.

    ``template``, ``config``, ``campaign_seed``, ``chunk_size``, ``attrs`` go to
    :func:`~ideas_hpc.engine.store.create_store`; ``run_kwargs`` (``workers``,
    ``scheduler``, ``cluster``, ``slurm_config``, ``progress``, ``retries``,
    ``client``) to :func:`run_chunks`.
    """
    Path(store_path).absolute().parent.mkdir(parents=True, exist_ok=True)
    with StoreLock(store_path):  # creation and run are one critical section
        create_store(store_path, template, config=config, campaign_seed=campaign_seed,
                     chunk_size=chunk_size, attrs=attrs, resume=resume)
        return run_chunks(store_path, chunk_fn, resume=resume, **run_kwargs)
