"""Compiled kernels: pure ``@njit(cache=True)`` functions on float64 arrays, SI units.

Nothing in this sub-package converts units, reads files or holds state; the
boundary layer (``ideas_hpc.*`` outside ``core``) validates and converts first.
"""
