"""Dask clusters for campaigns: local processes, an existing scheduler, or SLURM.

* ``local`` (default): a :class:`distributed.LocalCluster` of ``workers``
  processes with one thread each, every chunk task capped at one Numba
  thread so that N workers on N cores do not oversubscribe, and glibc's malloc
  tuned for the chunks' large temporaries (:data:`WORKER_MALLOC_ENV`).
* ``scheduler=ADDRESS``: connect to a running dask scheduler; the caller owns
  its workers.
* ``slurm``: :class:`dask_jobqueue.SLURMCluster`, scaled to ``workers`` jobs.
  Its settings live in ``dask.config`` under ``jobqueue.slurm``, as in
  dask-jobqueue: the package ships ``ideas_hpc/engine/jobqueue.yaml``
  (:data:`DEFAULT_SLURM_CONFIG`; ``slurm/jobqueue.yaml`` in a checkout links to
  it), registered as defaults by :func:`register_slurm_defaults`, so the
  user's dask config and ``DASK_JOBQUEUE__SLURM__*`` variables override any
  key. A campaign may name another file in the dask config format (YAML or
  TOML), whose ``jobqueue.slurm`` section is passed as keyword arguments.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import os
from pathlib import Path
from typing import Any, Iterator

from ideas_hpc.base.errors import InputError

#: Threads each chunk task may use, read in the task by
#: :func:`ideas_hpc.engine.runner.limit_task_threads`.
TASK_THREADS_ENV = "IDEAS_HPC_TASK_THREADS"

#: Set in each worker process once it runs (the nanny's ``env``), which is
#: after the worker has imported the launching script. ``NUMBA_NUM_THREADS``
#: must not be among them: Numba has read it by then and raises at its next
#: compilation if it changed once its pool runs; the task cap goes through
#: :data:`TASK_THREADS_ENV` instead.
WORKER_ENV = {TASK_THREADS_ENV: "1", "OMP_NUM_THREADS": "1",
              "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              # dask's statistical profiler samples every task thread's stack
              # every 10 ms; with long compiled calls that cost a second thread
              # ~50 % of a core per worker here (top -H), i.e. a 2-core run lost
              # a third of its throughput. Chunk timings are reported anyway.
              "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "False"}

#: Set before a worker process starts: glibc reads ``MALLOC_*`` once, at
#: process start. dask's default ``MALLOC_TRIM_THRESHOLD_=65536`` also freezes
#: glibc's mmap threshold at 128 kB, so every large temporary of a Monte Carlo
#: sample became a fresh mmap, page-faulted in and unmapped again: chunks ran
#: 20-30 % slower than in a plain process (0.33-0.38 s vs 0.27-0.29 s per
#: 8-sample chunk, measured alternately). A 32 MiB mmap threshold fixed the
#: samples, but a scenario of the success-probability bank allocates about
#: 570 MB in arrays of 52-155 MB (720 candidates' positions, velocities and
#: camera DCMs at 3001 images), above any mmap threshold glibc accepts: 127,000
#: page faults and 0.3-0.4 s of kernel time per scenario. So no allocation is
#: mmapped, every thread allocates from the one main heap (a worker thread's own
#: arena cannot hold such arrays and would fall back to mmap), and up to 1 GiB
#: may lie free at the heap's top before it is trimmed: the next scenario reuses
#: the same pages. One-thread bank scenarios went from 2.58 to 1.89 s (mean of
#: 5, two alternating rounds; 0 page faults and no kernel time), same rows.
WORKER_MALLOC_ENV = {"MALLOC_MMAP_MAX_": "0",
                     "MALLOC_ARENA_MAX": "1",
                     "MALLOC_TRIM_THRESHOLD_": str(2**30)}

#: Housekeeping intervals of the local scheduler, nannies and workers. The
#: defaults (event-loop health tick every 20 ms, memory monitor every 100 ms,
#: system monitor every 500 ms) are made for interactive dashboards; in a
#: campaign they cost the client process 8-9 % of a core and each worker ~2 %
#: (per-thread CPU from /proc over 6 s of a 2-worker run), taken from the
#: chunk tasks when workers fill the cores. Relaxed, the client uses 4 %.
QUIET_CLUSTER_CONFIG = {"distributed.admin.tick.interval": "1s",
                        "distributed.admin.system-monitor.interval": "2s",
                        "distributed.worker.memory.monitor-interval": "1s"}

#: Seconds each local worker process gets to exit when its cluster closes.
#: distributed's nanny waits 4 s (0.8 x its 5 s close timeout), then kills the
#: process and logs "Worker process still alive after 4.0 seconds, killing". A
#: worker that ran the prange (OpenMP) kernels takes about 1 s longer to exit
#: than one that did not, and on the loaded 2-core machine the main job's
#: workers took over 4 s: that WARNING was the last thing the job printed.
WORKER_EXIT_S = 60.0   # on a clean close only (connect: 5 s, dask's own, after an error)

#: The package's SLURM settings (package data), dask config format.
DEFAULT_SLURM_CONFIG = Path(__file__).resolve().with_name("jobqueue.yaml")

CLUSTER_KINDS = ("local", "slurm")


def default_workers() -> int:
    """Worker count when none is given: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def _check_workers(workers: int | None) -> int:
    if workers is None:
        return default_workers()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"must be a positive integer, got {workers!r}", field="workers")
    return workers


@functools.cache
def _local_cluster_class():
    """:class:`distributed.LocalCluster` whose close gives every worker process
    :data:`WORKER_EXIT_S` to exit before it is killed (imported on first use)."""
    from distributed import LocalCluster
    from distributed.core import Status

    class JobLocalCluster(LocalCluster):
        worker_exit_s = WORKER_EXIT_S

        async def _close(self):
            if self.status in (Status.running, Status.failed):
                await asyncio.gather(*(w.close(timeout=self.worker_exit_s)
                                       for w in list(self.workers.values())))
            await super()._close()

    return JobLocalCluster


def local_cluster(workers: int | None = None, **kwargs: Any):
    """A process-based :class:`distributed.LocalCluster`, one thread per worker.

    ``kwargs`` override the defaults (``dashboard_address=None``, quiet logs).
    """
    cls = _local_cluster_class()   # imports distributed (its config) outside config.set
    opts = dict(n_workers=_check_workers(workers), threads_per_worker=1, processes=True,
                env=dict(WORKER_ENV), dashboard_address=None, silence_logs=logging.WARNING)
    opts.update(kwargs)
    if opts["dashboard_address"] is None and "scheduler_kwargs" not in opts:
        # No dashboard, but the scheduler still serves HTTP (health checks) and
        # would try 8787 first, warning "Port 8787 is already in use" whenever
        # another cluster runs on the machine: a free port, on localhost.
        opts["scheduler_kwargs"] = {"dashboard": False, "dashboard_address": "127.0.0.1:0"}
    import dask

    # Worker processes inherit this environment at spawn. The nanny exports
    # its pre-spawn-environ into os.environ but lets a value already there win,
    # and any earlier plain LocalCluster in this process left dask's 65536
    # there; so the malloc settings are put in place here, for this and later
    # spawns (this process's own malloc was configured when it started).
    os.environ.update(WORKER_MALLOC_ENV)
    # Workers take the spawning process's dask config (env vars are applied
    # after dask is imported there), so the profiler switch must be set here.
    with dask.config.set({"distributed.worker.profile.enabled": False, **QUIET_CLUSTER_CONFIG}):
        return cls(**opts)


def _read_config_file(path: Path) -> dict:
    """A dask config file: YAML or JSON read by ``dask.config``, TOML by ``tomllib``."""
    import dask.config

    if not path.is_file():
        raise InputError("cannot read SLURM config: no such file", field="slurm_config",
                         file=str(path))
    try:
        if path.suffix == ".toml":
            import tomllib

            return tomllib.loads(path.read_text())
        return next(iter(dask.config.collect_yaml([str(path)])), None) or {}
    except OSError as exc:
        raise InputError(f"cannot read SLURM config: {exc.strerror}", field="slurm_config",
                         file=str(path)) from exc
    except Exception as exc:
        raise InputError(f"cannot parse SLURM config: {exc}", field="slurm_config",
                         file=str(path)) from exc


_DEFAULTS_REGISTERED = False


def register_slurm_defaults() -> None:
    """Add :data:`DEFAULT_SLURM_CONFIG` to ``dask.config``'s defaults (once per process).

    As dask-jobqueue does with its own file: values the user's dask config
    sets keep priority, values still at dask-jobqueue's defaults take ours.
    """
    global _DEFAULTS_REGISTERED
    if _DEFAULTS_REGISTERED:
        return
    import dask.config
    import dask_jobqueue  # noqa: F401  (its defaults first, ours over them)

    dask.config.update_defaults(_read_config_file(DEFAULT_SLURM_CONFIG))
    _DEFAULTS_REGISTERED = True


def load_slurm_config(path: str | os.PathLike | None = None) -> dict:
    """The ``jobqueue.slurm`` settings: of ``dask.config`` (with the package's
    defaults, :func:`register_slurm_defaults`) when ``path`` is None, else of
    the YAML or TOML dask-config file ``path``.

    Raises
    ------
    InputError
        When the file is missing, unparsable or has no ``jobqueue.slurm`` table.
    """
    if path is None:
        import dask.config

        register_slurm_defaults()
        return dict(dask.config.get("jobqueue.slurm"))
    path = Path(path)
    data = _read_config_file(path)
    try:
        section = data["jobqueue"]["slurm"]
    except (KeyError, TypeError):
        raise InputError("no 'jobqueue.slurm' section", field="slurm_config",
                         file=str(path)) from None
    if not isinstance(section, dict):
        raise InputError("'jobqueue.slurm' must be a table", field="slurm_config", file=str(path))
    return dict(section)


def _slurm_kwarg_names() -> set[str]:
    import inspect

    from dask_jobqueue.core import Job, JobQueueCluster
    from dask_jobqueue.slurm import SLURMJob

    names: set[str] = set()
    for fn in (SLURMJob.__init__, Job.__init__, JobQueueCluster.__init__):
        names |= set(inspect.signature(fn).parameters)
    return names - {"self", "scheduler", "config_name", "n_workers", "job_cls", "loop",
                    "asynchronous", "base_class_kwargs", "job_kwargs", "name"}


def slurm_kwargs(section: dict, source: str | None = None) -> dict:
    """SLURMCluster keyword arguments from a ``jobqueue.slurm`` config mapping.

    Dask-config spelling (``job-extra-directives``) becomes the keyword
    (``job_extra_directives``); ``name`` is the job name; null values are
    dropped so dask-jobqueue's defaults apply. Unknown keys are refused.
    """
    allowed = _slurm_kwarg_names()
    out = {}
    for key, value in section.items():
        kw = str(key).replace("-", "_")
        if kw == "name":
            kw = "job_name"
        if kw not in allowed:
            raise InputError(f"unknown SLURMCluster option (known: {', '.join(sorted(allowed))})",
                             field=f"jobqueue.slurm.{key}", file=source)
        if value is not None:
            out[kw] = value
    return out


def slurm_cluster(config_path: str | os.PathLike | None = None, **overrides: Any):
    """A :class:`dask_jobqueue.SLURMCluster`, ``overrides`` laid over its settings.

    Without ``config_path`` dask-jobqueue reads ``jobqueue.slurm`` from
    ``dask.config`` (the package's defaults, :func:`register_slurm_defaults`,
    under the user's dask config). With one, that file's ``jobqueue.slurm``
    section (:func:`load_slurm_config`) becomes keyword arguments
    (:func:`slurm_kwargs`). No job is submitted until the cluster is scaled,
    so ``job_script()`` works without a SLURM controller.
    """
    from dask_jobqueue import SLURMCluster

    if config_path is None:
        register_slurm_defaults()
        return SLURMCluster(**overrides)
    path = Path(config_path)
    kwargs = slurm_kwargs(load_slurm_config(path), str(path))
    kwargs.update(overrides)
    return SLURMCluster(**kwargs)


@contextlib.contextmanager
def connect(*, cluster: str = "local", workers: int | None = None, scheduler: str | None = None,
            slurm_config: str | os.PathLike | None = None, worker_timeout: float = 300.0,
            log_directory: str | os.PathLike | None = None, **cluster_kwargs: Any) -> Iterator:
    """Yield a :class:`distributed.Client` on the requested cluster; close what it started.

    Parameters
    ----------
    cluster : {'local', 'slurm'}
        Kind of cluster to start when ``scheduler`` is None.
    workers : int, optional
        Local worker processes, or SLURM jobs. Default: the usable CPUs (local),
        1 job (SLURM).
    scheduler : str, optional
        Address of an existing dask scheduler (``tcp://host:8786``); nothing is started.
    slurm_config : path, optional
        jobqueue config file for ``cluster='slurm'`` (default: ``dask.config``,
        with the package's ``jobqueue.yaml`` as defaults).
    worker_timeout : float
        Seconds to wait for the first SLURM worker before giving up.
    log_directory : path, optional
        Where SLURM writes the worker jobs' output when the config sets no
        ``log-directory`` (otherwise SLURM writes ``slurm-JOBID.out`` in the
        current directory).
    """
    from distributed import Client

    if cluster not in CLUSTER_KINDS:
        raise InputError(f"must be one of {CLUSTER_KINDS}, got {cluster!r}", field="cluster")
    if scheduler is not None:
        if not isinstance(scheduler, str) or not scheduler:
            raise InputError(f"must be a scheduler address, got {scheduler!r}", field="scheduler")
        try:
            client = Client(scheduler, timeout="30s")
        except OSError as exc:
            raise InputError(f"cannot connect to dask scheduler {scheduler}: {exc}",
                             field="scheduler") from exc
        try:
            yield client
        finally:
            client.close()
        return
    if cluster == "local":
        with local_cluster(workers, **cluster_kwargs) as lc:
            try:
                with Client(lc) as client:
                    yield client
            except BaseException:
                # a failed or interrupted job does not wait for its running tasks:
                # a worker's close waits for them, and a chunk can run a minute
                lc.worker_exit_s = 5.0
                raise
        return
    n_jobs = _check_workers(workers) if workers is not None else 1
    if log_directory is not None and not load_slurm_config(slurm_config).get("log-directory"):
        Path(log_directory).mkdir(parents=True, exist_ok=True)
        cluster_kwargs.setdefault("log_directory", str(log_directory))
    with slurm_cluster(slurm_config, **cluster_kwargs) as sc:
        sc.scale(jobs=n_jobs)
        with Client(sc) as client:
            try:
                client.wait_for_workers(1, timeout=worker_timeout)
            except TimeoutError as exc:
                raise RuntimeError(
                    f"no SLURM worker started within {worker_timeout:g} s; check `squeue` and "
                    f"the job logs (log-directory in {slurm_config or 'dask.config jobqueue.slurm'})"
                ) from exc
            yield client
