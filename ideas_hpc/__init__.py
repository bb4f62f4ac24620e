"""ideas_hpc: design spacecraft swarms that map a small body in one flyby.

Public entry points: :func:`load_body`, :func:`ideas_hpc.flyby.sizing.size_flyby`,
and the ``ideas-hpc`` command line (``size``, ``run``, ``report``).
"""

from __future__ import annotations

import os as _os

# Numba's OpenMP threads busy-wait by default; on a small shared machine two
# spinning threads slowed the parallel kernels ~5x (measured in
# benchmarks/bench_targeting.py). Must be set before numba loads its runtime.
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from ideas_hpc._version import __version__
from ideas_hpc.body.bodies import Body, load_body
from ideas_hpc.base.errors import InputError

__all__ = ["Body", "InputError", "__version__", "load_body"]
