"""A bank of drawn worlds on a local or SLURM cluster, timed (issue 43, deliverable 4).

Builds the scenario bank of ``campaigns/eros-class-flyby.toml`` (every scenario its own
world of the built-in Eros-class prior, 10 km/s, Lutetia navigation, a visual map) for
``--worlds`` worlds on a grid of ``--step-deg`` ring candidates, into a resumable zarr
store (a killed run continues where it stopped: run the same command again), through
dask workers started on the chosen cluster (``--cluster local`` processes, or SLURM
worker jobs through dask-jobqueue with ``slurm/jobqueue.yaml``). Prints the wall time,
scenarios per second and the rows' digest (the same digest whatever the cluster and
worker count: ``tests/test_slurm.py`` checks rows equal to a serial build).

    python benchmarks/world_bank_run.py --worlds 1024 --step-deg 0.5 --workers 2
    python benchmarks/world_bank_run.py --worlds 4096 --step-deg 0.5 --workers 2 \\
        --cluster slurm --store /scratch/$USER/worlds.zarr

The last line is the headline: ``world bank: <S> worlds x <C> candidates in <T> s
(<R> worlds/s) on <W> <cluster> workers``.
"""

from __future__ import annotations

import argparse
import hashlib
import tempfile
import time
from pathlib import Path

import numpy as np

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.engine.cluster import connect
from ideas_hpc.montecarlo.scenarios import build_scenario_bank

ROOT = Path(__file__).resolve().parent.parent


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worlds", type=int, default=1024)
    ap.add_argument("--step-deg", type=float, default=0.5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cluster", choices=("local", "slurm"), default="local")
    ap.add_argument("--chunk-size", type=int, default=16)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--store", default=None,
                    help="zarr store (resumed when it exists); default: a fresh temporary one")
    a = ap.parse_args(argv)
    c = load(ROOT / "campaigns" / "eros-class-flyby.toml")
    setup, mc = setup_from_campaign(c), c.config.monte_carlo
    store = a.store or str(Path(tempfile.mkdtemp(prefix="worlds-")) / "worlds.zarr")
    kw = {}
    if a.cluster == "slurm":
        kw = dict(slurm_config=ROOT / "slurm" / "jobqueue.yaml",
                  log_directory=str(Path(store).with_suffix(".slurm-logs")))
    with connect(cluster=a.cluster, workers=a.workers, **kw) as client:
        client.wait_for_workers(a.workers, timeout=600)
        t0 = time.perf_counter()
        bank = build_scenario_bank(setup, np.deg2rad(a.step_deg), mc, seed=a.seed,
                                   n_scenarios=a.worlds, client=client, store=store,
                                   chunk_size=a.chunk_size, progress=True)
        wall = time.perf_counter() - t0
    digest = hashlib.sha256(np.packbits(bank.rows).tobytes()).hexdigest()[:16]
    s, n_c, n_v = bank.rows.shape
    print(f"store {store}: {bank.attrs.get('chunks_run', '?')} chunks flown; rows {s} x {n_c} x "
          f"{n_v}, sha256 {digest}")
    print(f"world bank: {s} worlds x {n_c} candidates in {wall:.1f} s ({s / wall:.2f} worlds/s) "
          f"on {a.workers} {a.cluster} workers")


if __name__ == "__main__":
    main()
