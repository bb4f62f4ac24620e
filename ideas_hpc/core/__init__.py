"""Compiled kernels: pure ``@njit(cache=True)`` functions on float64 arrays, SI units.

Nothing in this sub-package converts units, reads files or holds state; the
boundary layer (``ideas_hpc.*`` outside ``core``) validates and converts first.
"""

from ideas_hpc.base import compile_once as _compile_once

# every process (the client, each dask worker) compiles a cached kernel only where no
# other process is compiling it: it waits and loads (ideas_hpc.base.compile_once)
_compile_once.install()
