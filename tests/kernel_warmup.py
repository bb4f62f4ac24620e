"""Compile the test suite's Numba kernels before the tests, on every core (``.ci/run``).

On a fresh machine the suite compiles about 180 kernel signatures (``ideas_hpc.core``).
CI's two pytest sessions need mostly the same kernels, early, so each session pays for
almost all of them in its own wall time: one compiles a kernel while the other waits
on its lock (:mod:`ideas_hpc.base.compile_once`) with a core idle. Measured on
2026-12-07, fresh clone on the 2-core machine: the default session took 1700 s cold
against 1145 s with every kernel in the cache.

``compile`` reads the list of the suite's signatures (:data:`LIST`) and compiles each
one into the kernel cache (:mod:`ideas_hpc.base.kernel_cache`) in ``--jobs``
processes. Every process walks the whole list from its own starting point (process
``i`` of ``n`` at ``i/n`` of the list, wrapping round), skipping what the cache already
holds; the per-kernel lock makes a kernel compile once whichever process gets there
first. What the list lacks the tests compile as before: a stale list costs time,
never a result. ``record`` rewrites the list from the caches a run of the suite
filled; ``check`` says which signatures the caches hold that the list lacks (``.ci/run``
prints it after the tests).

A signature is stored as its Numba types, pickled (zlib, base64): the suite's kernels
take records and named tuples whose printed types cannot be parsed back. An entry
that no longer unpickles or names no kernel (another Numba, a renamed kernel) is
counted and skipped.
"""

from __future__ import annotations

import argparse
import base64
import importlib
import os
import pickle
import pkgutil
import subprocess
import sys
import time
import zlib
from pathlib import Path

#: The suite's kernel signatures: ``module qualname base64(zlib(pickle(signature)))``.
LIST = Path(__file__).with_name("kernel_signatures.txt")
PACKAGE = "ideas_hpc.core"


def cached_dispatchers(package: str = PACKAGE):
    """``(module, qualname, dispatcher)`` of every ``cache=True`` CPU kernel under ``package``."""
    from numba.core.registry import CPUDispatcher

    pkg = importlib.import_module(package)
    names = [package] + [m.name for m in pkgutil.walk_packages(pkg.__path__, package + ".")]
    seen = set()
    for name in names:
        if name.endswith("_cuda"):       # device kernels: numba.cuda, no CPU cache
            continue
        mod = importlib.import_module(name)
        for value in list(vars(mod).values()):
            if (isinstance(value, CPUDispatcher) and value.py_func.__module__ == name
                    and getattr(value, "_cache", None) is not None
                    and id(value) not in seen):
                seen.add(id(value))
                yield name, value.py_func.__qualname__, value


def cached_signatures(dispatcher) -> list:
    """The signatures ``dispatcher``'s on-disk cache holds (empty where it has no index)."""
    cache_file = getattr(dispatcher._cache, "_cache_file", None)
    if cache_file is None:
        return []
    return [key[0] for key in cache_file._load_index()]


def encode(sig) -> str:
    return base64.b64encode(zlib.compress(pickle.dumps(sig), 9)).decode("ascii")


def decode(text: str):
    return pickle.loads(zlib.decompress(base64.b64decode(text)))


def held(package: str = PACKAGE) -> list[tuple[str, str, str]]:
    """``(module, qualname, encoded signature)`` of everything the kernel caches hold, in
    the order the caches were written: a kernel's callees are written before it (compiling
    a caller compiles them first), so a walk in this order finds them in the cache."""
    out = []
    for module, qualname, disp in cached_dispatchers(package):
        cache_file = getattr(disp._cache, "_cache_file", None)
        if cache_file is None:
            continue
        for key, data_name in cache_file._load_index().items():
            try:
                written = os.stat(cache_file._data_path(data_name)).st_mtime_ns
            except OSError:
                continue
            out.append((written, module, qualname, encode(key[0])))
    return [row[1:] for row in sorted(out)]


def same(rows) -> set:
    """Rows as comparable values (one signature pickles to other bytes in another process)."""
    return {(m, q, decode(s)) for m, q, s in rows}


def read_list(path: Path = LIST) -> list[tuple[str, str, str]]:
    rows = []
    for line in path.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            module, qualname, sig = line.split()
            rows.append((module, qualname, sig))
    return rows


def write_list(rows, path: Path = LIST) -> None:
    head = ("# The test suite's Numba kernel signatures, compiled ahead of the tests by\n"
            "# tests/kernel_warmup.py (module, qualname, base64(zlib(pickle(signature)))).\n"
            "# Rewrite after a full run with: python tests/kernel_warmup.py record\n")
    path.write_text(head + "".join(f"{m} {q} {s}\n" for m, q, s in rows))


def _kernel(module: str, qualname: str):
    obj = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def _busy(disp) -> bool:
    """Whether another process holds ``disp``'s compile lock right now."""
    import fcntl

    from ideas_hpc.base.compile_once import lock_path

    path = lock_path(disp)
    if path is None:
        return False
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)             # closing drops the lock taken just to look
    return False


def compile_rows(rows, start: int = 0) -> dict:
    """Compile every row not in the cache, in list order from ``start`` (wrapping round);
    a kernel another process is compiling is left for the end, when it is usually in
    the cache. Returns the counts ``compiled``, ``cached`` and ``skipped`` (unreadable)."""
    counts = {"compiled": 0, "cached": 0, "skipped": 0}
    n = len(rows)
    later = []
    for j in list(range(n)) + [None]:
        if j is None:                           # the deferred ones, now waiting if need be
            todo, wait = later, True
        else:
            todo, wait = [rows[(start + j) % n]], False
        for module, qualname, text in todo:
            try:
                disp, sig = _kernel(module, qualname), decode(text)
            except Exception:        # noqa: BLE001  (a stale row: time, never a result)
                counts["skipped"] += 1
                continue
            if sig in disp.overloads or sig in cached_signatures(disp):
                counts["cached"] += 1
                continue
            if not wait and _busy(disp):
                later.append((module, qualname, text))
                continue
            disp.compile(sig)        # loads instead when another process wrote it meanwhile
            counts["compiled"] += 1
    return counts


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("compile", help="compile the listed signatures into the kernel cache")
    c.add_argument("--jobs", type=int, default=2)
    c.add_argument("--start", type=int, default=None, help=argparse.SUPPRESS)
    sub.add_parser("record", help="rewrite the list from what the kernel caches hold")
    sub.add_parser("check", help="say which cached signatures the list lacks")
    a = p.parse_args(argv)
    if a.cmd == "record":
        rows = held()
        write_list(rows)
        print(f"kernel_warmup: {len(rows)} signatures written to {LIST.name}")
        return 0
    if a.cmd == "check":
        missing = same(held()) - same(read_list())
        names = sorted({f"{m}.{q}" for m, q, _ in missing})
        print(f"kernel_warmup: {len(missing)} signatures compiled by this run are not in "
              f"{LIST.name}" + (f": {', '.join(names)} (rewrite it with "
                                "`python tests/kernel_warmup.py record`)" if missing else ""))
        return 0
    rows = read_list()
    if a.start is not None:                      # one worker process
        t0 = time.perf_counter()
        counts = compile_rows(rows, a.start)
        print(f"kernel_warmup[{a.start}]: " + ", ".join(f"{v} {k}" for k, v in counts.items())
              + f" in {time.perf_counter() - t0:.1f} s", flush=True)
        return 0
    jobs = max(1, a.jobs)
    procs = [subprocess.Popen([sys.executable, __file__, "compile", "--start", str(i)])
             for i in range(jobs)]
    return max(proc.wait() for proc in procs)


if __name__ == "__main__":
    sys.exit(main())
