"""Compare the stores this checkout writes with the ones a given git revision writes.

A refactor must not change numbers. This script checks out ``REV`` into a
temporary worktree, runs the same campaigns with both codes (each in its own
process, importing its own ``ideas_hpc``) and compares every data variable:
bit for bit, or the largest relative difference when not identical.

    python benchmarks/compare_revision.py REV [--cases flyby-paper flyby-strict mc16]
           [--keep DIR] [--tol 1e-9]

Cases: ``flyby-paper`` (``campaigns/eros-flyby.toml``), ``flyby-strict`` (the
same with exact culling, occlusion and a 5 deg elevation mask), ``mc16``
(a 16-sample ``campaigns/eros-monte-carlo.toml`` on one worker), and the designs
``design-exact``, ``design-ga``, ``design-pareto`` (their campaign files with
small verification / population / generation counts). Exit status 1
when any variable differs by more than ``--tol`` (relative), or a variable is
missing on one side; variables only the new code writes are listed, not failed.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
STRICT = ['coverage.mode="exact"', "coverage.occlusion=true", "coverage.min_elevation_deg=5.0"]
CASES = {
    "flyby-paper": ("campaigns/eros-flyby.toml", []),
    "flyby-strict": ("campaigns/eros-flyby.toml", STRICT),
    "mc16": ("campaigns/eros-monte-carlo.toml", ["monte_carlo.samples=16", "run.workers=1"]),
    # designs, with only their sizes made small (keys every revision accepts)
    # the exact nominal design (eros-design.toml is the success-probability job, whose
    # requirement needs at least 100 scenarios and validation samples: too long here)
    "design-exact": ("campaigns/eros-design-nominal.toml", ["design.verify_samples=4",
                                                            "run.workers=0"]),
    "design-ga": ("campaigns/eros-nadir-ga.toml", ["design.population=8", "design.generations=3",
                                                   "run.workers=0"]),
    "design-pareto": ("campaigns/eros-pareto.toml", ["design.population=8",
                                                     "design.generations=3", "run.workers=0"]),
    # the stereo pair formulation (a few minutes per revision)
    "design-stereo": ("campaigns/eros-stereo-design.toml", ["design.verify_samples=4",
                                                            "run.workers=0"]),
}


def _run(tree: Path, case: str, out: Path) -> None:
    campaign, sets = CASES[case]
    cmd = [sys.executable, "-m", "ideas_hpc.cli", "run", str(tree / campaign), "--out", str(out),
           "--no-progress"]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, PYTHONPATH=str(tree))
    res = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"{case} failed in {tree}:\n{res.stderr[-3000:]}")


def _rel_diff(a: np.ndarray, b: np.ndarray) -> float:
    if a.dtype.kind not in "fc":
        return 0.0 if np.array_equal(a, b) else float("inf")
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    if not np.array_equal(nan_a, nan_b):
        return float("inf")
    a, b = a[~nan_a], b[~nan_b]
    if a.size == 0:
        return 0.0
    scale = max(float(np.max(np.abs(a))), 1e-300)
    return float(np.max(np.abs(a - b))) / scale


#: Wall-clock measurements stored as variables: they differ run to run.
WALL_CLOCK = ("solve_time",)


def compare(old: Path, new: Path, tol: float) -> list[str]:
    """Lines describing each variable; a line starting with 'FAIL' is a failure."""
    import xarray as xr

    a, b = xr.open_zarr(old), xr.open_zarr(new)
    lines = []
    for name in sorted(set(a.variables) | set(b.variables)):
        if name in WALL_CLOCK:
            lines.append(f"skip {name}: wall clock")
            continue
        if name not in b.variables:
            lines.append(f"FAIL {name}: missing in the new store")
            continue
        if name not in a.variables:
            lines.append(f"new  {name}: only in the new store")
            continue
        x, y = a[name].values, b[name].values
        if x.shape != y.shape:
            lines.append(f"FAIL {name}: shape {x.shape} -> {y.shape}")
        elif x.dtype.kind in "fc" and np.array_equal(x, y, equal_nan=True):
            lines.append(f"same {name}")
        elif x.dtype.kind not in "fc" and np.array_equal(x, y):
            lines.append(f"same {name}")
        else:
            d = _rel_diff(x, y)
            lines.append(f"{'FAIL' if d > tol else 'ok  '} {name}: max relative difference {d:.3e}")
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("rev", help="git revision to compare with (e.g. HEAD~3, a commit)")
    p.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    p.add_argument("--keep", default=None, help="keep the stores in this folder")
    p.add_argument("--tol", type=float, default=1e-9)
    a = p.parse_args(argv)
    work = Path(a.keep or tempfile.mkdtemp(prefix="compare-rev-"))
    work.mkdir(parents=True, exist_ok=True)
    old_tree = work / "old-tree"
    if old_tree.exists():
        subprocess.run(["git", "worktree", "remove", "--force", str(old_tree)], cwd=ROOT)
    subprocess.run(["git", "worktree", "add", "--detach", "-q", str(old_tree), a.rev],
                   cwd=ROOT, check=True)
    failed = False
    try:
        for case in a.cases:
            old, new = work / f"{case}-old.zarr", work / f"{case}-new.zarr"
            for path in (old, new):
                shutil.rmtree(path, ignore_errors=True)
            _run(old_tree, case, old)
            _run(ROOT, case, new)
            print(f"== {case}")
            for line in compare(old, new, a.tol):
                print("  " + line)
                failed |= line.startswith("FAIL")
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(old_tree)], cwd=ROOT)
        if a.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    print("compare_revision: " + ("DIFFERENT" if failed else "same numbers") + f" as {a.rev}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
