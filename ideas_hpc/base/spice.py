"""spiceypy, the optional SPICE toolkit (``pip install ideas_hpc[spice]``), imported on use.

The core runs without it; a feature that needs it calls :func:`spiceypy` with the key
that asked for it, and a missing install is one error line naming that key.
"""

from __future__ import annotations

from ideas_hpc.base.errors import InputError


def spiceypy(field: str):
    """The ``spiceypy`` module, or an :class:`InputError` naming ``field`` when absent."""
    try:
        import spiceypy as sp
    except ImportError:
        raise InputError("needs spiceypy (SPICE): pip install 'ideas_hpc[spice]'",
                         field=field) from None
    return sp
