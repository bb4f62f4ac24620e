"""A toy campaign that exercises the engine without any physics.

Each sample draws four numbers from its own generator
(:func:`~ideas_hpc.base.seeds.sample_rng`) and a compiled kernel turns them
into store-shaped results (per-vertex ``observed`` / ``first_seen`` /
``times_seen``, a ``coverage`` scalar and a ``sigma_error`` time series) by
iterating a chaotic logistic map ``work`` times per vertex. The chaos makes
the values sensitive to every bit of the inputs, so "identical arrays" between
runs really means identical computations; ``work`` sets the time a chunk takes.

A test fixture, not part of the package. Run it as a script for the
kill/resume tests and the SLURM checks (``tests/`` must be on ``PYTHONPATH``
so that dask workers can unpickle the chunk function; ``tests/conftest.py``
sets that for every process the tests start)::

    python tests/toy_campaign.py --out toy.zarr --n-samples 64 --chunk-size 4 \
        --workers 2 [--resume] [--scheduler ADDR | --cluster slurm]
"""

from __future__ import annotations

import argparse
import functools
import math
import os
import sys
from pathlib import Path

import numpy as np
from numba import njit, prange

from ideas_hpc.base.seeds import sample_rng

N_PARAMS = 4


@njit(cache=True, parallel=True)
def toy_kernel(params, vertex_area, n_time, work, observed, first_seen, times_seen,
               coverage, sigma_error):
    """Fill one chunk of toy results from per-sample parameters.

    Parameters
    ----------
    params : (n, 4) float64
        Uniform [0, 1) draws of each sample.
    vertex_area : (n_vertex,) float64
        Weights of the area-weighted ``coverage``, m^2.
    n_time, work : int
        Time steps of ``sigma_error``; logistic-map iterations per vertex.
    observed, first_seen, times_seen, coverage, sigma_error : output arrays
        ``(n, n_vertex)`` bool / float64 s / int32, ``(n,)`` float64,
        ``(n, n_time, 3)`` float64.
    """
    n = params.shape[0]
    nv = vertex_area.shape[0]
    total = 0.0
    for v in range(nv):
        total += vertex_area[v]
    for i in prange(n):
        p0 = params[i, 0]
        p1 = params[i, 1]
        r = 3.7 + 0.29 * params[i, 2]
        amp = params[i, 3]
        seen_area = 0.0
        for v in range(nv):
            x = 0.05 + 0.9 * ((p0 + v * p1 * 0.618033988749895) % 1.0)
            for _ in range(work):
                x = r * x * (1.0 - x)
            seen = x < 0.7
            observed[i, v] = seen
            times_seen[i, v] = np.int32(x * 10.0) if seen else 0
            first_seen[i, v] = x * 1000.0 if seen else np.nan
            if seen:
                seen_area += vertex_area[v]
        coverage[i] = seen_area / total
        for t in range(n_time):
            for a in range(3):
                sigma_error[i, t, a] = amp * math.exp(-t / (10.0 + 5.0 * p0)) * \
                    math.cos(0.1 * t * (a + 1) + 6.283185307179586 * p1)


def toy_areas(n_vertex: int) -> np.ndarray:
    """Deterministic positive per-vertex areas, m^2."""
    return 1.0 + 0.5 * np.sin(np.arange(n_vertex, dtype=np.float64))


def toy_template(n_samples: int, n_vertex: int = 64, n_time: int = 16):
    """xarray template of the toy store (SPEC section 9 names and dims)."""
    import dask.array as da
    import xarray as xr

    def lazy(shape, dtype):
        return da.zeros(shape, dtype=dtype, chunks=shape)

    ns, nv, nt = int(n_samples), int(n_vertex), int(n_time)
    return xr.Dataset(
        {
            "vertex_area": (("vertex",), toy_areas(nv), {"units": "m^2",
                                                         "description": "area per vertex"}),
            "coverage": (("sample",), lazy((ns,), np.float64),
                         {"units": "1", "description": "area-weighted observed fraction"}),
            "observed": (("sample", "vertex"), lazy((ns, nv), bool),
                         {"description": "vertex seen at least once"}),
            "first_seen": (("sample", "vertex"), lazy((ns, nv), np.float64),
                           {"units": "s", "description": "first time seen, NaN if never"}),
            "times_seen": (("sample", "vertex"), lazy((ns, nv), np.int32),
                           {"description": "number of images that saw the vertex"}),
            "sigma_error": (("sample", "time", "axis"), lazy((ns, nt, 3), np.float64),
                            {"units": "1", "description": "attitude error MRP"}),
        },
        coords={"sample": np.arange(ns), "vertex": np.arange(nv),
                "time": ("time", np.arange(nt, dtype=np.float64), {"units": "s"}),
                "axis": ["x", "y", "z"]},
    )


def toy_chunk(chunk_id: int, start: int, stop: int, *, campaign_seed: int, n_vertex: int,
              n_time: int, work: int, fail_once_dir: str | None = None,
              fail_chunks: tuple = ()) -> dict:
    """Chunk function of the toy campaign (use with :func:`functools.partial`).

    ``fail_chunks`` raise once each (a marker file in ``fail_once_dir``
    remembers the failure), to exercise dask's retries.
    """
    if fail_once_dir is not None and chunk_id in fail_chunks:
        marker = Path(fail_once_dir) / f"failed-{chunk_id}"
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            os.close(fd)
            raise RuntimeError(f"toy: planned failure of chunk {chunk_id}")
        except FileExistsError:
            pass
    n = stop - start
    params = np.empty((n, N_PARAMS))
    for j in range(n):  # 4 draws per sample; the kernel does the work
        params[j] = sample_rng(campaign_seed, start + j).random(N_PARAMS)
    observed = np.empty((n, n_vertex), dtype=np.bool_)
    first_seen = np.empty((n, n_vertex))
    times_seen = np.empty((n, n_vertex), dtype=np.int32)
    coverage = np.empty(n)
    sigma_error = np.empty((n, n_time, 3))
    toy_kernel(params, toy_areas(n_vertex), n_time, work, observed, first_seen, times_seen,
               coverage, sigma_error)
    return {"observed": observed, "first_seen": first_seen, "times_seen": times_seen,
            "coverage": coverage, "sigma_error": sigma_error}


def toy_config(n_samples: int, chunk_size: int, n_vertex: int, n_time: int, work: int,
               seed: int) -> dict:
    """The resolved config of a toy campaign (what the store's config hash covers)."""
    return {"kind": "toy", "seed": int(seed),
            "toy": {"n_samples": int(n_samples), "chunk_size": int(chunk_size),
                    "n_vertex": int(n_vertex), "n_time": int(n_time), "work": int(work)}}


def run_toy(out, *, n_samples: int = 64, chunk_size: int = 4, n_vertex: int = 64,
            n_time: int = 16, work: int = 200, seed: int = 12345, resume: bool = False,
            **run_kwargs):
    """Create/resume and run a toy campaign; returns the :class:`RunSummary`."""
    from ideas_hpc.engine.runner import run_campaign

    fn = functools.partial(toy_chunk, campaign_seed=seed, n_vertex=n_vertex, n_time=n_time,
                           work=work, **{k: run_kwargs.pop(k) for k in
                                         ("fail_once_dir", "fail_chunks") if k in run_kwargs})
    return run_campaign(out, toy_template(n_samples, n_vertex, n_time), fn,
                        config=toy_config(n_samples, chunk_size, n_vertex, n_time, work, seed),
                        campaign_seed=seed, chunk_size=chunk_size,
                        attrs={"kind": "toy", "title": "engine test workload"},
                        resume=resume, **run_kwargs)


def run_toy_serial(out, *, n_samples: int = 64, chunk_size: int = 4, n_vertex: int = 64,
                   n_time: int = 16, work: int = 200, seed: int = 12345) -> None:
    """The same toy campaign written chunk by chunk in this process, without dask.

    The reference the distributed, killed-and-resumed runs must reproduce.
    """
    from ideas_hpc.engine.chunk_write import write_chunk_region
    from ideas_hpc.engine.store import create_store
    from ideas_hpc.engine.store_meta import ChunkPlan

    create_store(out, toy_template(n_samples, n_vertex, n_time),
                 config=toy_config(n_samples, chunk_size, n_vertex, n_time, work, seed),
                 campaign_seed=seed, chunk_size=chunk_size,
                 attrs={"kind": "toy", "title": "engine test workload"})
    for cid, start, stop in ChunkPlan(n_samples, chunk_size):
        arrays = toy_chunk(cid, start, stop, campaign_seed=seed, n_vertex=n_vertex,
                           n_time=n_time, work=work)
        write_chunk_region(out, cid, start, stop, arrays)


def main(argv: list[str] | None = None) -> int:
    from ideas_hpc.base.errors import InputError

    p = argparse.ArgumentParser(prog="python tests/toy_campaign.py",
                                description="Run the engine's toy campaign into a zarr store.")
    p.add_argument("campaign", nargs="?", default="toy",
                   help="ignored (lets slurm/run_campaign.sbatch launch the toy like a campaign)")
    p.add_argument("--out", required=True)
    p.add_argument("--n-samples", type=int, default=64)
    p.add_argument("--chunk-size", type=int, default=4)
    p.add_argument("--n-vertex", type=int, default=64)
    p.add_argument("--n-time", type=int, default=16)
    p.add_argument("--work", type=int, default=200)
    p.add_argument("--seed", type=int, default=12345)
    p.add_argument("--resume", action="store_true")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--scheduler", default=None)
    p.add_argument("--cluster", choices=("local", "slurm"), default="local")
    p.add_argument("--slurm-config", default=None)
    p.add_argument("--retries", type=int, default=2)
    p.add_argument("--no-progress", action="store_true")
    a = p.parse_args(argv)
    try:
        s = run_toy(a.out, n_samples=a.n_samples, chunk_size=a.chunk_size, n_vertex=a.n_vertex,
                    n_time=a.n_time, work=a.work, seed=a.seed, resume=a.resume,
                    workers=a.workers, scheduler=a.scheduler, cluster=a.cluster,
                    slurm_config=a.slurm_config, retries=a.retries, progress=not a.no_progress)
    except InputError as exc:
        print(f"toy: error: {exc}", file=sys.stderr)
        return 2
    print(s)
    return 0


if __name__ == "__main__":  # pragma: no cover
    # Run the module's own copy, not ``__main__``'s: workers unpickle
    # ``toy_campaign.toy_chunk`` by name.
    import toy_campaign

    sys.exit(toy_campaign.main())
