"""Benchmark: the main job from a cold and from a warm Numba cache, in the same run.

Workload: ``campaigns/eros-design-nominal.toml``, the main job as issue 19
measured it (the certified strict design on eros001708 with its 64-sample Monte
Carlo verification, masks included; the main job itself now adds a scenario
bank, ``--campaign campaigns/eros-design.toml``), run as the user runs it,
``ideas-hpc run`` in a fresh process, with the default execution (the job
decides in-process or cluster, :mod:`ideas_hpc.engine.job_cluster`).

1. cold: ``NUMBA_CACHE_DIR`` points at an empty temporary folder, so every
   kernel the job uses is compiled (pip install excluded);
2. warm: the same command again with that folder now filled.

Both runs must print the same summary lines (design, coverage, verification
P). Wall seconds are measured around the subprocess; on a shared machine they
include other users' load (say so when reporting). Last line
``startup: cold <C> s, warm <W> s (<R>x)``.

``--helper`` adds a third run, cold again on another empty cache with the
precompile helper off (``IDEAS_HPC_PRECOMPILE=0``; it is on by default on a cold
cache with a second CPU since issue 43, :mod:`ideas_hpc.campaign.precompile`), to
show what it saves or costs.

Usage: ``python benchmarks/bench_startup.py [--campaign campaigns/eros-design-nominal.toml]
[--set KEY=VALUE ...] [--workers N] [--helper]``.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: Summary lines compared between the cold and the warm run (timings removed).
_KEEP = ("exact design:", "Monte Carlo verification:", "Pareto front:", "GA:")


def _summary(printed: str) -> list[str]:
    lines = [ln for ln in printed.splitlines() if ln.startswith(_KEEP)]
    return [re.sub(r"(in|masks|solve|curve in) [0-9.]+ s", r"\1 _ s", ln) for ln in lines]


def run_job(campaign: Path, out: Path, cache: Path, sets, workers,
            helper: bool = False, env_extra: dict | None = None) -> tuple[float, str]:
    """Wall seconds and printed text of ``ideas-hpc run`` in a fresh process on the Numba
    cache ``cache`` (``env_extra``: more environment, e.g. ``bench_compile``'s recorder)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), MPLBACKEND="Agg", **(env_extra or {}))
    env.pop("IDEAS_HPC_PRECOMPILE", None)
    if not helper:
        env["IDEAS_HPC_PRECOMPILE"] = "0"
    cmd = [sys.executable, "-m", "ideas_hpc.cli", "run", str(campaign), "--out", str(out),
           "--no-progress"]
    for s in sets:
        cmd += ["--set", s]
    if workers is not None:
        cmd += ["--workers", str(workers)]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode:
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-3000:]}")
    return wall, p.stdout + "\n" + p.stderr   # results on stdout, logs on stderr


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--campaign", default=str(ROOT / "campaigns" / "eros-design-nominal.toml"))
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--helper", action="store_true",
                    help="also run cold without the precompile helper (another empty cache)")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench-startup-") as tmp:
        tmp = Path(tmp)
        cache = tmp / "numba-cache"
        cache.mkdir()
        cold, err_c = run_job(Path(a.campaign), tmp / "cold.zarr", cache, a.set, a.workers,
                              helper=True)
        n_files = sum(1 for _ in cache.rglob("*.nbi"))
        warm, err_w = run_job(Path(a.campaign), tmp / "warm.zarr", cache, a.set, a.workers,
                              helper=True)
        if a.helper:
            (tmp / "cache2").mkdir()
            cold1, _ = run_job(Path(a.campaign), tmp / "cold1.zarr", tmp / "cache2", a.set,
                               a.workers, helper=False)
    print(f"workload: {Path(a.campaign).name} {' '.join(a.set)} "
          f"(workers: {'job default' if a.workers is None else a.workers}); "
          f"machine load {os.getloadavg()[0]:.1f}")
    for ln in err_w.splitlines():
        if ln.startswith(_KEEP) or ln.startswith("candidate"):
            print(f"  {ln}")
    same = _summary(err_c) == _summary(err_w)
    print(f"cold cache: {cold:.1f} s ({n_files} cached kernels written); warm cache: "
          f"{warm:.1f} s; same summary: {same}")
    if a.helper:
        print(f"cold cache without the precompile helper (IDEAS_HPC_PRECOMPILE=0): {cold1:.1f} s "
              f"(the helper saves {cold1 - cold:.1f} s)")
    if not same:
        sys.exit("cold and warm runs disagree:\n" + "\n".join(_summary(err_c)) + "\n--\n"
                 + "\n".join(_summary(err_w)))
    print(f"startup: cold {cold:.1f} s, warm {warm:.1f} s ({cold / warm:.1f}x)")


if __name__ == "__main__":
    main()
