"""One job, at most one cluster: started when it pays back, shared by the job's phases.

A job (one ``ideas-hpc run``) has phases that can spread over dask workers:
the candidate masks, the Monte Carlo verification, a Monte Carlo campaign's
chunks (and any later phase, such as a scenario bank: it calls
:meth:`JobCluster.client` like the others). :class:`JobCluster` decides once,
from the job's work size, whether a cluster pays back, starts it at the first
phase that asks for it, hands every later phase the same client and closes it
when the job ends.

The rule (:func:`runs_in_process`):

* ``workers=0``: in this process.
* an explicit worker count (``--workers N``, ``run.workers = N``), a
  scheduler address or ``--cluster slurm``: honoured, a cluster is used.
* otherwise (no count given, local cluster): in this process when the job's
  work is below :data:`IN_PROCESS_MAX_TESTS`, else a local cluster of
  :func:`~ideas_hpc.engine.cluster.default_workers` processes.

Work is counted in vertex-image visibility tests,
``flights x spacecraft x images x vertices`` (:func:`visibility_tests`), the
inner loop of every phase. In this process the kernels already run on every
core (``prange``); a local cluster adds 5-10 s of start and stop and pickling,
and pays back only where per-flight Python work dominates (many Monte Carlo
samples). Measured on eros001708 (2 cores): the design masks (720 candidates,
3.7e9 tests) took 2.8 s in process and 3.9-4.3 s on 2 workers plus 9 s of
cluster; 2048 Monte Carlo samples of 8 spacecraft (8.4e10 tests) run about
1.8x faster on 2 workers than in one process.

Workers load compiled kernels from the Numba cache: before the cluster
starts, the phase's ``warm`` callable runs once in this process (a one-flight
version of the phase), which compiles its kernels and fills the cache (the
workers would otherwise each compile them again).
"""

from __future__ import annotations

import contextlib
from typing import Callable

#: Below this many vertex-image tests (and without an explicit worker count)
#: a job runs in this process: about 15 s of kernel time on 2 cores.
IN_PROCESS_MAX_TESTS = 2e10


def visibility_tests(n_flights: int, n_spacecraft: int, n_images: int, n_vertices: int) -> float:
    """Work of ``n_flights`` flights of ``n_spacecraft`` each: vertex-image tests."""
    return float(n_flights) * float(n_spacecraft) * float(n_images) * float(n_vertices)


def runs_in_process(*, workers: int | None, scheduler: str | None, cluster: str,
                    work: float) -> bool:
    """True when a job of ``work`` tests runs without dask (module docstring: the rule)."""
    if scheduler is not None or cluster != "local":
        return False
    if workers is not None:
        return workers == 0
    return work < IN_PROCESS_MAX_TESTS


class JobCluster:
    """The job's one cluster, started on demand; a context manager that closes it.

    Parameters
    ----------
    workers, scheduler, cluster, slurm_config
        As in :func:`ideas_hpc.engine.cluster.connect`.
    work : float
        The job's vertex-image tests (:func:`visibility_tests`), summed over its phases.
    connect_kwargs
        More arguments for :func:`~ideas_hpc.engine.cluster.connect`.
    """

    def __init__(self, *, workers: int | None = None, scheduler: str | None = None,
                 cluster: str = "local", slurm_config=None, work: float = 0.0,
                 **connect_kwargs):
        self.in_process = runs_in_process(workers=workers, scheduler=scheduler,
                                          cluster=cluster, work=work)
        self._kw = dict(cluster=cluster, workers=workers, scheduler=scheduler,
                        slurm_config=slurm_config, **connect_kwargs)
        self._stack = contextlib.ExitStack()
        self._client = None
        self.started = 0   # clusters started (0 or 1)

    def client(self, warm: Callable[[], object] | None = None):
        """The shared :class:`distributed.Client`, or None to run in this process.

        ``warm`` (a one-flight version of the phase) runs here first, so the
        workers find the phase's kernels compiled in the Numba cache; once
        they are, it costs one flight.
        """
        if self.in_process:
            return None
        if warm is not None:
            warm()
        if self._client is None:
            from ideas_hpc.engine.cluster import connect

            self._client = self._stack.enter_context(connect(**self._kw))
            self.started += 1
        return self._client

    def close(self) -> None:
        self._client = None
        self._stack.close()

    def __enter__(self) -> "JobCluster":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def phase_client(job, warm: Callable[[], object] | None = None):
    """A phase's client: from a :class:`JobCluster` (started on demand, ``warm``
    first), or ``job`` itself when it is already a client or None."""
    return job.client(warm) if isinstance(job, JobCluster) else job
