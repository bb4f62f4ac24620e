"""Find data files (shape models, gravity fields) without ever shipping them.

Search order: an explicit directory, then every entry of ``IDEAS_HPC_DATA``
(``os.pathsep``-separated). Inside each root both ``root/NAME`` and
``root/eros/NAME`` are tried, so ``IDEAS_HPC_DATA=../shared/data`` works. When
nothing matches, the error lists every place that was looked at.
"""

from __future__ import annotations

import os
from pathlib import Path

from ideas_hpc.base.errors import DataNotFoundError

ENV_VAR = "IDEAS_HPC_DATA"
_SUBDIRS = ("", "eros")


def data_roots(explicit=None) -> list[Path]:
    """The data roots in search order (explicit first, then ``IDEAS_HPC_DATA``)."""
    roots: list[Path] = []
    if explicit is not None:
        roots.append(Path(explicit).expanduser())
    for entry in os.environ.get(ENV_VAR, "").split(os.pathsep):
        if entry.strip():
            roots.append(Path(entry.strip()).expanduser())
    return roots


def candidates(filename: str, explicit=None) -> list[Path]:
    """Every path :func:`find_data_file` tries for ``filename``, in order."""
    out = []
    for root in data_roots(explicit):
        for sub in _SUBDIRS:
            out.append(root / sub / filename if sub else root / filename)
    return out


def find_data_file(filename: str, explicit=None) -> Path:
    """Return the first existing ``filename`` on the data path, or raise.

    Raises
    ------
    DataNotFoundError
        Naming every candidate path, or saying that ``IDEAS_HPC_DATA`` is unset.
    """
    tried = candidates(filename, explicit)
    for p in tried:
        if p.is_file():
            return p
    if not tried:
        raise DataNotFoundError(
            f"data file {filename!r} not found: no data path given and {ENV_VAR} is not set "
            f"(set {ENV_VAR} to the folder that holds it, e.g. ../shared/data)",
            field="data_path")
    listing = ", ".join(str(p) for p in tried)
    raise DataNotFoundError(f"data file {filename!r} not found; looked in: {listing}",
                            field="data_path")


def have_data_file(filename: str, explicit=None) -> bool:
    """True when :func:`find_data_file` would succeed."""
    return any(p.is_file() for p in candidates(filename, explicit))
