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
