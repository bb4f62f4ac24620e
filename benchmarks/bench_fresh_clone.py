"""Benchmark: from ``git clone`` to the HTML report, a first and a second clone (issue 43).

Issue 43's target: a fresh clone reaches its HTML report in at most the warm main job
x 1.3 + the install. The path is the README's quick start as a user types it, each
step timed around its subprocess (wall seconds):

1. **first clone**: ``git clone`` of this repository's HEAD into a temporary folder,
   ``python3 -m venv .venv && .venv/bin/pip install -q -e .``, ``ideas-hpc run
   campaigns/fast-flyby-design.toml``, ``ideas-hpc report --html``, with an empty
   shared kernel cache (``IDEAS_HPC_KERNEL_CACHE`` pointing at a new folder): every
   kernel compiles, as on a machine that never ran ``ideas_hpc``;
2. **second clone**: the same in another folder with the same kernel cache: the
   kernels the first clone compiled are loaded (:mod:`ideas_hpc.base.kernel_cache`);
3. **warm**: the main job again in the second clone.

Both clones' first result lines must be the warm run's (the answer does not depend on
what was compiled). ``IDEAS_HPC_DATA`` is unset: the main job needs no data. Last
lines: the target for each clone, then the headline
``fresh_clone: second clone <S> s to report, <R>x faster than the first clone (<F> s)``.

Usage: ``python benchmarks/bench_fresh_clone.py [--keep DIR]``. Run it on a quiet
machine: wall seconds include other users' load (the machine load is printed).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = "campaigns/fast-flyby-design.toml"


def _timed(cmd, cwd, env, log: Path) -> float:
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        rc = subprocess.run(cmd, cwd=cwd, env=env, stdout=fh, stderr=subprocess.STDOUT).returncode
    if rc:
        sys.exit(f"{' '.join(map(str, cmd))} failed ({rc}); see {log}")
    return time.perf_counter() - t0


def _answer(log: Path) -> str:
    """The first result line (N, P-hat, bound)."""
    lines = [s for s in log.read_text().splitlines() if s.startswith("success-probability design")]
    return lines[0] if lines else "(no result line)"


def clone_to_report(root: Path, name: str, env: dict, warm: bool = False) -> dict:
    """Clone, install, run, report (and a warm run with ``warm``) under ``root/name``."""
    t = {}
    where = root / name
    t0 = time.perf_counter()
    subprocess.run(["git", "clone", "-q", str(ROOT), str(where)], check=True)
    _timed([sys.executable, "-m", "venv", ".venv"], where, env, root / f"{name}-venv.log")
    _timed([".venv/bin/pip", "install", "-q", "-e", "."], where, env, root / f"{name}-pip.log")
    t["install"] = time.perf_counter() - t0          # clone + venv + pip, as a user waits
    run = [".venv/bin/ideas-hpc", "run", CAMPAIGN, "--out", "job.zarr", "--no-progress"]
    t["run"] = _timed(run, where, env, root / f"{name}-run.log")
    t["report"] = _timed([".venv/bin/ideas-hpc", "report", "job.zarr", "--html"], where, env,
                         root / f"{name}-report.log")
    t["answer"] = _answer(root / f"{name}-run.log")
    if warm:
        run[4] = "job2.zarr"
        t["warm"] = _timed(run, where, env, root / f"{name}-warm.log")
        t["warm_answer"] = _answer(root / f"{name}-warm.log")
    return t


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", help="work in this folder and keep it (logs, stores)")
    a = ap.parse_args(argv)
    root = Path(a.keep or tempfile.mkdtemp(prefix="bench-fresh-clone-"))
    root.mkdir(parents=True, exist_ok=True)
    env = {k: v for k, v in os.environ.items()
           if k not in ("IDEAS_HPC_DATA", "NUMBA_CACHE_DIR", "PYTHONPATH", "VIRTUAL_ENV")}
    env.update(IDEAS_HPC_KERNEL_CACHE=str(root / "kernels"), MPLBACKEND="Agg")
    load = os.getloadavg()[0]
    first = clone_to_report(root, "first", env)
    second = clone_to_report(root, "second", env, warm=True)
    warm = second["warm"]
    print(f"machine load {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end; "
          f"commit {subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=ROOT, capture_output=True, text=True).stdout.strip()}")
    print(f"{'':14s}{'clone+install':>14s}{'first run':>11s}{'report':>8s}{'to report':>11s}"
          f"{'target':>8s}")
    for name, t in (("first clone", first), ("second clone", second)):
        total = t["install"] + t["run"] + t["report"]
        target = warm * 1.3 + t["install"]
        t["total"] = total
        print(f"{name:14s}{t['install']:13.1f}s{t['run']:10.1f}s{t['report']:7.1f}s"
              f"{total:10.1f}s{target:7.1f}s  {'met' if total <= target else 'not met'}")
    print(f"warm main job: {warm:.1f} s (target = warm x 1.3 + that clone's install)")
    same = first["answer"] == second["answer"] == second["warm_answer"]
    print(f"answers {'identical' if same else 'DIFFER'}: {second['warm_answer'][:110]}")
    if not same:
        sys.exit("the first clone, the second clone and the warm run answered differently")
    print(f"fresh_clone: second clone {second['total']:.1f} s to report, "
          f"{first['total'] / second['total']:.2f}x faster than the first clone "
          f"({first['total']:.1f} s)")


if __name__ == "__main__":
    main()
