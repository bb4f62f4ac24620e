"""Compiled kernels shared by every checkout of the same sources: a content-addressed cache.

Numba writes a kernel's machine code beside its source (``__pycache__``), so every
clone, worktree or fresh checkout of ``ideas_hpc`` compiles all its kernels again
(about 80 CPU s for the main job, issue 43), although its sources are byte for byte
those another checkout on the same machine has compiled already. :func:`share` puts
the cache of the kernels under one package folder in a user folder named by the
digest of that folder's sources (and of the folders its kernels import):

``<root>/<digest>/<sub-folder of the source>/<Numba's own index and data files>``

- A second clone (a worktree, a re-clone, the other session of CI's two) with the
  same sources finds the kernels the first one compiled and loads them.
- Sources that differ by one byte anywhere under the digested folders use another
  folder: a kernel is never loaded against callees other than those it was
  compiled with, which Numba's per-file check alone does not ensure
  (:func:`ideas_hpc.base.compile_once.guard_sources`).
- The root is ``$IDEAS_HPC_KERNEL_CACHE``, else ``$XDG_CACHE_HOME/ideas_hpc/kernels``,
  else ``~/.cache/ideas_hpc/kernels``. ``IDEAS_HPC_KERNEL_CACHE=tree`` (or ``0``)
  keeps Numba's in-tree caches. ``NUMBA_CACHE_DIR``, when set, wins over both
  (Numba's own locator comes first), as do ``NUMBA_CACHE_LOCATOR_CLASSES``.
- Where the root cannot be written the kernel falls back to Numba's next locator
  (in the tree, as before).
- The :data:`KEEP` most recently used source versions are kept; older ones are
  removed when a new version's folder is made, and only when unused for a day, so a
  long run on older sources keeps its folder.

It does not help the very first run on a machine: that one compiles (README, "What
the first run costs").
"""

from __future__ import annotations

import hashlib
import os
import shutil
import time
from pathlib import Path

#: Environment variable naming the root folder (``tree`` or ``0``: Numba's in-tree caches).
ENV = "IDEAS_HPC_KERNEL_CACHE"
#: Source versions kept under the root (the most recently used).
KEEP = 6
#: A version folder unused for less than this is never removed (s).
MIN_IDLE_S = 86400.0

#: The locator class installed by :func:`share`, per package folder.
_INSTALLED: dict = {}


def cache_root() -> Path | None:
    """The root folder of shared kernel caches, or None (``IDEAS_HPC_KERNEL_CACHE=tree``)."""
    value = os.environ.get(ENV, "").strip()
    if value.lower() in ("tree", "0", "off"):
        return None
    if value:
        return Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "ideas_hpc" / "kernels"


def digest(folders) -> str:
    """The name of a source version's folder: blake2b of Numba's and Python's versions
    and of each folder's :func:`~ideas_hpc.base.compile_once.sources_digest` (its
    ``*.py`` files' relative paths and bytes)."""
    import sys

    import numba

    from ideas_hpc.base.compile_once import sources_digest

    h = hashlib.blake2b(digest_size=12)
    h.update(f"numba {numba.__version__} python {sys.version_info[:2]}\0".encode())
    for folder in folders:
        h.update(f"{Path(folder).name}\0{sources_digest(folder)}\0".encode())
    return h.hexdigest()


def prune(root: Path, keep: int = KEEP, min_idle_s: float = MIN_IDLE_S) -> list[Path]:
    """Remove version folders under ``root`` beyond the ``keep`` most recently used that
    have been unused for ``min_idle_s``; returns those removed."""
    try:
        versions = sorted((p for p in root.iterdir() if p.is_dir()),
                          key=lambda p: p.stat().st_mtime, reverse=True)
    except OSError:
        return []
    now, removed = time.time(), []
    for p in versions[keep:]:
        try:
            idle = now - p.stat().st_mtime
        except OSError:
            continue
        if idle >= min_idle_s:
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed


def share(package_dir, digested=()) -> Path | None:
    """Cache the kernels of the sources under ``package_dir`` in the user folder of their
    source version (module docstring); returns that folder, or None where the in-tree
    caches stay (``tree``, an unwritable root, a Numba without cache locators).

    ``digested``: further folders whose sources the kernels depend on (imports from
    outside ``package_dir``); their bytes are part of the version's name. Call before
    the package's kernels are defined: Numba picks a kernel's locator when it is
    decorated."""
    root = cache_root()
    if root is None:
        return None
    pkg = os.path.abspath(str(package_dir))
    if pkg in _INSTALLED:
        return _INSTALLED[pkg][1]
    try:
        from numba.core import caching
        mixin, base = caching._SourceFileBackedLocatorMixin, caching._CacheLocator
        classes = caching.CacheImpl._locator_classes
    except (ImportError, AttributeError):
        return None
    folder = root / digest([pkg, *map(str, digested)])
    try:
        fresh = not folder.exists()
        folder.mkdir(parents=True, exist_ok=True)
        os.utime(folder)                    # most recently used: kept by prune
    except OSError:
        return None
    if fresh:
        prune(root)

    class SourceVersionLocator(mixin, base):
        """Numba cache locator: ``<folder>/<source's sub-folder of the package>``."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            sub = os.path.relpath(os.path.dirname(os.path.abspath(py_file)), pkg)
            self._cache_path = os.path.normpath(os.path.join(str(folder), sub))

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            if not os.path.abspath(py_file).startswith(pkg + os.sep):
                return None
            return super().from_function(py_func, py_file)   # None where unwritable

    # after NUMBA_CACHE_DIR's locator (an explicit user choice), before the in-tree one
    at = 1 if classes and classes[0] is caching.UserProvidedCacheLocator else 0
    classes.insert(at, SourceVersionLocator)
    _INSTALLED[pkg] = (SourceVersionLocator, folder)
    return folder
