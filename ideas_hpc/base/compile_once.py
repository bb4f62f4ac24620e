"""Compile each cached kernel once across processes: a file lock per kernel cache.

Numba's on-disk cache (``cache=True``) is read when a process first needs a
signature and written once it has compiled it, with nothing between the two:
two dask workers that reach the same kernel on a cold cache both miss, both
compile and both write. A job's workers start their first chunks together, so
on a fresh clone every kernel of a distributed phase was compiled once per
worker (issue 43: the scenario bank's kernels on both workers of the main job,
py-spy showing both in ``Dispatcher.compile`` on the same kernel).

:func:`install` wraps :meth:`numba.core.dispatcher.Dispatcher.compile` (the one
path from a first call, or an explicit signature, to the cache and the
compiler) so that a process holds an exclusive ``flock`` on
``<kernel's cache index>.lock`` from its cache look-up to its cache write. A
second process that needs the same kernel meanwhile waits on the lock and
then finds the first one's entry in the cache: it loads instead of compiling
(``Dispatcher.stats.cache_hits``). Kernels with different cache files still
compile side by side. Nothing changes in what is compiled or how: only who
compiles it.

Order: the in-process compiler lock first, then the file lock, so threads of
one process never hold file locks in opposite orders; across processes a
kernel's lock is taken before its callees' (compiling a caller compiles its
callees), and calls form no cycle, so no two processes wait on each other. A
lock this process already holds (a kernel compiled again for another
signature while it compiles) is not taken twice. Where a lock cannot be
opened (a read-only cache folder, a file system without ``flock``) the kernel
compiles as before.
"""

from __future__ import annotations

import contextlib
import os

#: Lock files this process holds: path -> [fd, depth] (guarded by numba's compiler lock).
_HELD: dict = {}
#: The unwrapped ``Dispatcher.compile`` (None until :func:`install`).
_ORIGINAL = None


def lock_path(dispatcher) -> str | None:
    """The lock file of ``dispatcher``'s on-disk cache, or None (no ``cache=True``)."""
    index = getattr(getattr(getattr(dispatcher, "_cache", None), "_cache_file", None),
                    "_index_path", None)
    return None if index is None else index + ".lock"


def _acquire(path: str):
    import fcntl

    held = _HELD.get(path)
    if held is not None:
        held[1] += 1
        return
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError:
        fd = None
    if fd is not None:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:
            os.close(fd)
            fd = None
    _HELD[path] = [fd, 1]


def _release(path: str) -> None:
    held = _HELD[path]
    held[1] -= 1
    if held[1] == 0:
        del _HELD[path]
        if held[0] is not None:
            os.close(held[0])   # closing the descriptor drops its flock


@contextlib.contextmanager
def holding(dispatcher):
    """Hold ``dispatcher``'s cache lock (no-op without ``cache=True``): what a compile does."""
    from numba.core.compiler_lock import global_compiler_lock

    path = lock_path(dispatcher)
    if path is None:
        yield
        return
    with global_compiler_lock:
        _acquire(path)
        try:
            yield
        finally:
            _release(path)


def _compile(self, sig):
    with holding(self):
        return _ORIGINAL(self, sig)


def install() -> None:
    """Wrap ``Dispatcher.compile`` with the per-kernel file lock (module docstring); once."""
    global _ORIGINAL
    from numba.core.dispatcher import Dispatcher

    if _ORIGINAL is not None or getattr(Dispatcher.compile, "_compile_once", False):
        return
    _ORIGINAL = Dispatcher.compile
    _compile._compile_once = True
    Dispatcher.compile = _compile


#: The stamp of the kernel sources the caches under a package folder were compiled from.
STAMP = "ideas_hpc_kernel_sources.stamp"


def sources_digest(folder) -> str:
    """blake2b of every ``*.py`` under ``folder`` (relative path and bytes, sorted)."""
    import hashlib
    from pathlib import Path

    h = hashlib.blake2b(digest_size=16)
    root = Path(folder)
    for f in sorted(root.rglob("*.py")):
        h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()


def guard_sources(folder) -> int:
    """Drop the on-disk kernel caches under ``folder`` when its sources changed since they
    were written; returns the number of cache files removed.

    Numba checks a cached kernel against its *own* file only (its index holds that file's
    modification time): a kernel that inlines or calls kernels of another file keeps its
    cached machine code when only that other file changes (a ``git pull``, a branch
    switch), and runs the old callee: wrong numbers, or a segfault (seen 2026-11-29:
    ``core/design/reliability.py``'s ``swarm_probabilities`` crashed in a tree whose
    callees had moved on). The whole folder's sources are stamped instead: when the
    stamp in ``folder/__pycache__`` differs from the sources, every ``*.nbi`` / ``*.nbc``
    under ``folder`` is removed (under a file lock, so concurrent processes of one tree
    remove once) and the stamp rewritten; kernels then compile once more, as on a fresh
    clone. Nothing happens when the stamp matches, or with ``NUMBA_CACHE_DIR`` set (the
    caches then live elsewhere, keyed by that setting's user), or where the folder cannot
    be written (Numba then caches nothing there either)."""
    from pathlib import Path

    if os.environ.get("NUMBA_CACHE_DIR"):
        return 0
    cache = Path(folder) / "__pycache__"
    stamp = cache / STAMP
    digest = sources_digest(folder)
    try:
        if stamp.read_text() == digest:
            return 0
    except OSError:
        pass
    removed = 0
    try:
        cache.mkdir(exist_ok=True)
        lock = str(cache / (STAMP + ".lock"))
        _acquire(lock)
    except OSError:
        return 0
    try:
        try:
            current = stamp.read_text()
        except OSError:
            current = None
        if current != digest:        # not already done by another process meanwhile
            for pattern in ("*.nbi", "*.nbc"):
                for f in Path(folder).rglob(pattern):
                    with contextlib.suppress(OSError):
                        f.unlink()
                        removed += 1
            with contextlib.suppress(OSError):
                tmp = stamp.with_suffix(f".{os.getpid()}.tmp")
                tmp.write_text(digest)
                os.replace(tmp, stamp)
    finally:
        _release(lock)
    return removed


def loaded_kernels(prefix: str = "ideas_hpc.core") -> dict:
    """``{module.kernel: [signature, ...]}`` of every Numba kernel in the modules under
    ``prefix`` that this process has compiled or loaded from the cache (what a warm-up
    covered, what a worker ran)."""
    import sys

    from numba.core.registry import CPUDispatcher

    out = {}
    for name, mod in list(sys.modules.items()):
        if mod is None or not (name == prefix or name.startswith(prefix + ".")):
            continue
        for f in list(vars(mod).values()):
            if isinstance(f, CPUDispatcher) and f.overloads:
                out[f"{f.py_func.__module__}.{f.py_func.__qualname__}"] = sorted(
                    str(s) for s in f.overloads)
    return out
