"""Benchmark: where a cold main job's compile time goes, kernel by kernel.

Workload: the main job (``campaigns/fast-flyby-design.toml``) made small, so that
compilation is most of it (``--set`` below: 20 scenarios at p = 0.5, 20 held out,
20 verification samples, no demonstration), run as the user runs it
(``ideas-hpc run`` in a fresh process, its workers and its precompile helper
included) on an empty ``NUMBA_CACHE_DIR``, so every kernel it uses is compiled.

Every process of the job (the client, the dask workers, the helper) loads a
``sitecustomize`` that registers a :mod:`numba.core.event` listener on
``numba:compile``: the event spans one compilation of one signature (after the
cache look-up missed, so loads from the cache are not counted). A kernel
compiled while another compiles (a callee reached during type inference) is
nested in it; its seconds count for the callee only (exclusive time), so the
table's total is the compile time of the job. Numba's own overloads
(``np.empty``'s implementation ...) compiled for a kernel count for the kernel. ``inline="always"`` callees are
not dispatcher compilations: Numba re-types and re-lowers their IR inside every
caller, so their cost is in the callers' seconds; the table lists them per
kernel (names the kernel's code reaches, directly or through a module alias).

Seconds are CPU seconds of the compiling thread (``time.thread_time``: Numba
compiles in the calling thread), so that other users' load on a shared machine
changes them little; wall seconds, which it does change (by up to 2x under load
3-5 on the 2-core VM), are in the last line with the machine load. The table: the
20 costliest kernels (exclusive CPU seconds summed over their signatures and
processes, signatures, processes that compiled one, inlined callees), then the
total. Last line ``compile: <total> s for <k> kernels (<n> signatures, <p>
processes; ..., <w> s wall; job wall <j> s)``.

Usage: ``python benchmarks/bench_compile.py [--campaign ...] [--set KEY=VALUE ...]
[--workers N] [--top 20] [--warm] [--keep DIR]``. ``--warm`` runs the job a second time
on the filled cache and prints its wall seconds (the cold / warm ratio of issue 43).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: The small main job (issue 43's compile measurements).
SMALL = ("design.scenarios=20", "design.holdout_scenarios=20", "design.verify_samples=20",
         "design.success_probability=0.5", "design.demonstrate=false")

#: Environment variable naming the folder the per-process records go to.
_ENV = "IDEAS_HPC_COMPILE_LOG"


def _inline_callees(py_func) -> list[str]:
    """Names of ``inline="always"`` dispatchers ``py_func``'s code reaches (globals and
    attributes of module globals; nested code objects included)."""
    import types
    from numba.core.dispatcher import Dispatcher

    names, stack = set(), [py_func.__code__]
    while stack:
        code = stack.pop()
        names.update(code.co_names)
        stack.extend(c for c in code.co_consts if isinstance(c, types.CodeType))
    g = py_func.__globals__
    found = set()
    for n in names:
        cands = [g.get(n)]
        if isinstance(g.get(n), types.ModuleType):
            cands = [getattr(g[n], m, None) for m in names]
        for c in cands:
            if isinstance(c, Dispatcher) and c.targetoptions.get("inline") == "always":
                found.add(c.py_func.__name__)
    return sorted(found)


def install_recorder(folder: str) -> None:
    """Record every ``numba:compile`` event of this process in ``folder/<pid>.jsonl``
    (one line per compilation, written at its end: a process stopped mid-job keeps
    what it finished)."""
    import threading
    from numba.core import event as ev

    path = os.path.join(folder, f"{os.getpid()}.jsonl")
    local = threading.local()

    class _Recorder(ev.Listener):
        def on_start(self, event):
            stack = getattr(local, "stack", None)
            if stack is None:
                stack = local.stack = []
            stack.append([time.perf_counter(), 0.0, time.thread_time(), 0.0])

        def on_end(self, event):
            t0, nested, c0, nested_cpu = local.stack.pop()
            dt = time.perf_counter() - t0
            dc = time.thread_time() - c0
            disp = event.data["dispatcher"]
            f = disp.py_func
            ours = f.__module__.startswith("ideas_hpc")
            if local.stack and not ours:
                return   # Numba's own overloads count for the kernel that needs them
            if local.stack:
                local.stack[-1][1] += dt
                local.stack[-1][3] += dc
            rec = {"kernel": f"{f.__module__}.{f.__qualname__}",
                   "sig": str(event.data["args"]), "incl": dt, "excl": dt - nested,
                   "cpu": dc - nested_cpu,
                   "inline": _inline_callees(f),
                   "parallel": bool(disp.targetoptions.get("parallel"))}
            with open(path, "a") as fh:
                fh.write(json.dumps(rec) + "\n")

    ev.register("numba:compile", _Recorder())


def read_records(folder: Path) -> list[dict]:
    recs = []
    for p in sorted(folder.glob("*.jsonl")):
        for ln in p.read_text().splitlines():
            if ln.strip():
                r = json.loads(ln)
                r["pid"] = p.stem
                recs.append(r)
    return recs


def table(recs: list[dict], top: int) -> list[str]:
    """The per-kernel lines, costliest first, and the total line."""
    by = collections.defaultdict(lambda: {"s": 0.0, "sigs": set(), "pids": set(), "inline": []})
    for r in recs:
        k = by[r["kernel"].replace("ideas_hpc.", "")]
        k["s"] += r["cpu"]
        k["sigs"].add(r["sig"])
        k["pids"].add(r["pid"])
        k["inline"] = r["inline"]
        k["parallel"] = r.get("parallel", False)
    rows = sorted(by.items(), key=lambda kv: -kv[1]["s"])
    out = [f"{'kernel':<58} {'s':>7} {'sigs':>4} {'proc':>4}  inline='always' callees"]
    for name, k in rows[:top]:
        par = " [parallel]" if k["parallel"] else ""
        out.append(f"{name + par:<58} {k['s']:7.2f} {len(k['sigs']):4d} {len(k['pids']):4d}  "
                   f"{', '.join(k['inline'])}")
    rest = sum(k["s"] for _, k in rows[top:])
    out.append(f"{'(' + str(max(0, len(rows) - top)) + ' more)':<58} {rest:7.2f}")
    return out


def run_job(campaign: Path, out: Path, cache: Path, log: Path, sets, workers) -> float:
    site = log.parent / "site"
    site.mkdir(exist_ok=True)
    (site / "sitecustomize.py").write_text(
        "import os, sys\n"
        f"sys.path.insert(0, {str(Path(__file__).resolve().parent)!r})\n"
        "import bench_compile\n"
        f"bench_compile.install_recorder(os.environ[{_ENV!r}])\n"
        "sys.path.pop(0)\n")
    from bench_startup import run_job as run_cli   # the same run as bench_startup's

    path = os.pathsep.join([str(site), str(ROOT), os.environ.get("PYTHONPATH", "")])
    wall, _ = run_cli(campaign, out, cache, sets, workers, helper=True,
                      env_extra={_ENV: str(log), "PYTHONPATH": path})
    return wall


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--campaign", default=str(ROOT / "campaigns" / "fast-flyby-design.toml"))
    ap.add_argument("--set", action="append", default=None, metavar="KEY=VALUE",
                    help="replaces the small main job's settings")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--top", type=int, default=20)
    ap.add_argument("--warm", action="store_true",
                    help="then run the job again on the filled cache (its wall seconds)")
    ap.add_argument("--keep", default=None,
                    help="keep the store, cache and records in this folder")
    a = ap.parse_args(argv)
    sets = list(SMALL) if a.set is None else a.set
    with tempfile.TemporaryDirectory(prefix="bench-compile-") as tmp:
        tmp = Path(a.keep) if a.keep else Path(tmp)
        (tmp / "cache").mkdir(parents=True)
        (tmp / "log").mkdir()
        wall = run_job(Path(a.campaign), tmp / "job.zarr", tmp / "cache", tmp / "log", sets,
                       a.workers)
        recs = read_records(tmp / "log")
        if a.warm:
            (tmp / "log_warm").mkdir()
            warm = run_job(Path(a.campaign), tmp / "warm.zarr", tmp / "cache", tmp / "log_warm",
                           sets, a.workers)
            n_warm = len(read_records(tmp / "log_warm"))
    print(f"workload: {Path(a.campaign).name} {' '.join(sets)} "
          f"(workers: {'job default' if a.workers is None else a.workers}); "
          f"machine load {os.getloadavg()[0]:.1f}")
    for ln in table(recs, a.top):
        print(ln)
    if a.warm:
        print(f"warm cache: job wall {warm:.1f} s ({n_warm} signatures compiled again); "
              f"cold / warm {wall / warm:.2f}")
    kernels = {r["kernel"] for r in recs}
    total = sum(r["cpu"] for r in recs)
    wall_total = sum(r["excl"] for r in recs)
    print(f"compile: {total:.1f} s for {len(kernels)} kernels ({len(recs)} signatures, "
          f"{len({r['pid'] for r in recs})} processes; CPU seconds of the compiling thread, "
          f"{wall_total:.1f} s wall; job wall {wall:.1f} s)")


if __name__ == "__main__":
    main()
