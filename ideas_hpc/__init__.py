"""ideas_hpc: design spacecraft swarms that map a small body in one flyby.

Public entry points: :func:`load_body`, :func:`ideas_hpc.sizing.size_flyby`,
and the ``ideas-hpc`` command line (``size``, ``run``, ``report``).
"""

from __future__ import annotations

from ._version import __version__
from .bodies import Body, load_body
from .errors import InputError

__all__ = ["Body", "InputError", "__version__", "load_body"]
