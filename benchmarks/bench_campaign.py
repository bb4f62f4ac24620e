"""Benchmark: Monte Carlo campaign throughput on 1 and 2 local dask workers.

Workload: ``campaigns/eros-monte-carlo.toml`` (the paper's Fig. 21 swarm,
closed-loop attitude, all dispersions on), 256 samples in chunks of 8, each
chunk one task that flies its samples and writes its zarr region. Both runs
use the same store layout and code; each cluster is started and warmed up
(imports and the Numba cache loaded in every worker) before the clock starts,
so the ratio is the steady-state throughput a long campaign sees.

Reports samples per second for each, the per-chunk overhead (region write +
done flag, and scheduling: wall time not spent computing), and checks the
two stores are identical. A shared 2-core VM drifts by +-10 % between runs of
a few seconds, so the pair is measured ``--rounds`` times, alternating which
goes first; the headline is the ratio of the aggregate throughputs (all
samples over all wall time of each configuration). Last line
``campaign: <R>x throughput with 2 workers vs 1``.

Usage: ``python benchmarks/bench_campaign.py [--samples 256] [--chunk 8] [--rounds 5]``.
"""

from __future__ import annotations

import argparse
import functools
import os
import shutil
import tempfile
from pathlib import Path

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from ideas_hpc.campaign.montecarlo import _prepare, mc_chunk, mc_template  # noqa: E402
from ideas_hpc.campaign.schema.campaign_tables import resolved_config  # noqa: E402
from ideas_hpc.campaign.schema.campaign_tables import load  # noqa: E402
from ideas_hpc.engine.cluster import local_cluster  # noqa: E402
from ideas_hpc.engine.runner import run_campaign  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def _warm(client, fn):
    """Run one throw-away sample on every worker (imports, Numba cache)."""
    workers = list(client.scheduler_info()["workers"])
    futs = [client.submit(fn, 0, 0, 1, workers=[w], pure=False, allow_other_workers=False)
            for w in workers]
    client.gather(futs)


def run(n_workers: int, c, setup, nom, out: Path):
    from distributed import Client

    mc = c.config.monte_carlo
    fn = functools.partial(mc_chunk, setup=setup, nominal=nom.for_tasks(), mc=mc,
                           seed=c.config.seed)
    with local_cluster(n_workers) as cluster, Client(cluster) as client:
        _warm(client, fn)
        s = run_campaign(out, mc_template(setup, nom, mc.samples), fn,
                         config=resolved_config(c), campaign_seed=c.config.seed,
                         chunk_size=c.config.run.chunk_size,
                         client=client, progress=False)
    return s


def _report(n: int, s) -> None:
    per_chunk_write = s.write_s / max(1, s.chunks_run)
    sched = (s.wall_s * n - s.compute_s - s.write_s) / max(1, s.chunks_run)
    print(f"  {n} worker(s): {s.samples_run} samples in {s.wall_s:.2f} s = "
          f"{s.samples_per_s:.2f} samples/s; per chunk: {s.compute_s / s.chunks_run:.3f} s "
          f"compute, {per_chunk_write:.3f} s write + done flag, {max(sched, 0):.3f} s "
          "other (scheduling, transfer, start and tail idle)", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--chunk", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=5,
                    help="1-worker/2-worker campaign pairs, order alternating (shared VMs drift)")
    args = ap.parse_args()
    c = load(ROOT / "campaigns" / "eros-monte-carlo.toml",
             [f"monte_carlo.samples={args.samples}", f"run.chunk_size={args.chunk}"])
    setup, nom = _prepare(c)
    print(f"body: {setup.body.note}")
    print(f"workload: {args.samples} samples x {nom.theta.size} spacecraft, chunks of "
          f"{args.chunk}, {setup.tf_s - setup.t0_s:g} s flights, attitude {setup.attitude_mode}; "
          f"{args.rounds} rounds")
    tmp = Path(tempfile.mkdtemp(prefix="bench_campaign_"))
    try:
        runs: dict[int, list] = {1: [], 2: []}
        same = True
        for r in range(args.rounds):
            print(f"round {r + 1}:")
            for n in ((1, 2) if r % 2 == 0 else (2, 1)):
                out = tmp / f"r{r}w{n}.zarr"
                runs[n].append(run(n, c, setup, nom, out))
                _report(n, runs[n][-1])
            print(f"  ratio {runs[2][-1].samples_per_s / runs[1][-1].samples_per_s:.2f}")
            a, b = xr.open_zarr(tmp / f"r{r}w1.zarr"), xr.open_zarr(tmp / f"r{r}w2.zarr")
            same &= all(np.array_equal(a[v].values, b[v].values, equal_nan=a[v].dtype.kind == "f")
                        for v in ("coverage", "observed", "first_seen", "sigma_error"))
        print(f"stores from 1 and 2 workers identical: {same}")
        rate = {n: sum(s.samples_run for s in runs[n]) / sum(s.wall_s for s in runs[n])
                for n in (1, 2)}
        for n in (1, 2):
            print(f"{n} worker(s), all rounds: {rate[n]:.2f} samples/s")
        print(f"campaign: {rate[2] / rate[1]:.2f}x throughput with 2 workers vs 1")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
