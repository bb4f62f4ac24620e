"""The main job's whole scenario bank, built by this checkout and by a git revision.

Used by ``bench_scenarios.py --against REV`` (issue 31): the bank of
``campaigns/eros-design.toml`` (its 0.5 deg grid, 720 candidates; ``n`` scenarios)
built into a fresh store on ``workers`` local dask workers, preparation
(targeting, proofs) and reading back included, first by ``REV`` checked out into
a temporary worktree, then by this checkout, each in its own process importing
its own ``ideas_hpc`` with a warm Numba cache (a small bank is built first, untimed).
Both banks' rows are compared bit for bit.

This module is also the child process: ``python whole_bank.py TREE N WORKERS OUT``
builds the bank with the code at ``TREE`` and writes its rows to ``OUT`` (.npy),
printing ``wall <seconds>``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _child(tree: str, n: int, workers: int, out: str) -> None:
    from distributed import Client

    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.engine.cluster import local_cluster
    from ideas_hpc.montecarlo.scenarios import build_scenario_bank

    c = load(Path(tree) / "campaigns" / "eros-design.toml", [])
    setup, mc = setup_from_campaign(c), c.config.monte_carlo
    with local_cluster(workers) as cluster, Client(cluster) as client:
        for size in (4, n):     # the first, small bank loads every kernel: untimed
            with tempfile.TemporaryDirectory() as d:
                t = time.perf_counter()
                bank = build_scenario_bank(setup, np.radians(0.5), mc, seed=c.config.seed,
                                           n_scenarios=size, client=client,
                                           store=f"{d}/bank.zarr", progress=False)
                wall = time.perf_counter() - t
    np.save(out, bank.rows)
    print(f"wall {wall:.3f}", flush=True)


def build(tree: Path, n: int, workers: int, out: Path) -> float:
    """Seconds to build the bank with the code at ``tree`` (rows written to ``out``)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    # as the main job's process: bench_scenarios runs as one bank worker (one Numba
    # thread, the workers' malloc settings), the campaign's client does not
    for key in ("NUMBA_NUM_THREADS", "MALLOC_MMAP_MAX_", "MALLOC_ARENA_MAX",
                "MALLOC_TRIM_THRESHOLD_"):
        env.pop(key, None)
    res = subprocess.run([sys.executable, str(Path(__file__).resolve()), str(tree), str(n),
                          str(workers), str(out)], cwd=tree, env=env, capture_output=True,
                         text=True)
    walls = [ln for ln in res.stdout.splitlines() if ln.startswith("wall ")]
    if res.returncode != 0 or not walls:
        raise SystemExit(f"bank at {tree} failed:\n{res.stdout[-2000:]}\n{res.stderr[-3000:]}")
    return float(walls[-1].split()[1])


def against(rev: str, n: int, workers: int) -> None:
    """Print both banks' walls and the ratio (headline last)."""
    with tempfile.TemporaryDirectory() as d:
        tree = Path(d) / "rev"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(tree), rev], cwd=ROOT,
                       check=True)
        try:
            old = build(tree, n, workers, Path(d) / "old.npy")
            new = build(ROOT, n, workers, Path(d) / "new.npy")
            same = np.array_equal(np.load(Path(d) / "old.npy"), np.load(Path(d) / "new.npy"))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT)
    print(f"whole bank, {n} scenarios x 720 candidates on {workers} local workers "
          f"(preparation and read-back included): {rev} {old:.1f} s, this checkout "
          f"{new:.1f} s; rows {'identical' if same else 'DIFFERENT'}")
    if not same:
        raise SystemExit("the banks' rows differ")
    print(f"scenario bank: {old / new:.2f}x faster than {rev}'s bank")


if __name__ == "__main__":
    _child(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
