"""Compiled kernels: pure ``@njit(cache=True)`` functions on float64 arrays, SI units.

Nothing in this sub-package converts units, reads files or holds state; the
boundary layer (``ideas_hpc.*`` outside ``core``) validates and converts first.
"""

import os as _os

from ideas_hpc.base import compile_once as _compile_once
from ideas_hpc.base import kernel_cache as _kernel_cache

# every process (the client, each dask worker) compiles a cached kernel only where no
# other process is compiling it: it waits and loads (ideas_hpc.base.compile_once)
_compile_once.install()
# every checkout of the same sources shares one compiled copy of each kernel, in a user
# folder named by the digest of core/ and base/ (the only package folder core imports):
# a second clone loads what the first compiled, and other sources never load it
# (ideas_hpc.base.kernel_cache)
if _kernel_cache.share(__path__[0], digested=[_os.path.join(_os.path.dirname(__path__[0]),
                                                            "base")]) is None:
    # in-tree caches (IDEAS_HPC_KERNEL_CACHE=tree, an unwritable user folder): those
    # compiled from other sources (a pull, a branch switch) are dropped before any loads,
    # since Numba checks a cached kernel against its own file only (compile_once)
    _compile_once.guard_sources(__path__[0])
