"""Shipped campaigns fitted to a test's overrides: the keys those leave unread are dropped.

A campaign file may only set keys its run reads (issue 41, ``campaign/schema/reads.py``):
the shipped simulated flyby flown with ``--set attitude.mode="ideal"`` is refused for its
``[controller]`` table and its ``monte_carlo.attitude_start``, which an ideal attitude
ignores (a file key an override switches off is warned about instead). ``fitted(name,
overrides)`` writes a copy of ``campaigns/<name>`` without the lines of such keys (the
refusals and warnings name their lines) and returns its path; tests pass it with the
same overrides, so their stderr carries no such line. Copies live in one temporary folder per session.
"""

from __future__ import annotations

import atexit
import contextlib
import io
import re
import shutil
import tempfile
from pathlib import Path

from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.schema.campaign_tables import load

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
_HEADER = re.compile(r"^\s*\[")
_SWITCHED = re.compile(r"warning: FILE:(\d+): .*switched off by --set")
_DIR: list[Path] = []
_MADE: dict[tuple, Path] = {}


def _folder() -> Path:
    if not _DIR:
        _DIR.append(Path(tempfile.mkdtemp(prefix="ideas-hpc-campaigns-")))
        atexit.register(shutil.rmtree, _DIR[0], True)
    return _DIR[0]


def _drop(lines: list[str], line: int) -> list[str]:
    """``lines`` without 1-based ``line``, and the whole table when it is a header."""
    i = line - 1
    end = i + 1
    if _HEADER.match(lines[i]):
        while end < len(lines) and not _HEADER.match(lines[end]):
            end += 1
    return lines[:i] + lines[end:]


def fitted(name: str, overrides: list[str]) -> Path:
    """``campaigns/<name>`` without the keys that ``overrides`` leave unread (module docstring)."""
    key = (name, tuple(overrides))
    if key in _MADE:
        return _MADE[key]
    lines = (CAMPAIGNS / name).read_text().splitlines()
    out = _folder() / f"{len(_MADE)}-{name}"
    for _ in range(len(lines)):
        out.write_text("\n".join(lines) + "\n")
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err):
                load(out, overrides)
        except InputError as exc:
            if exc.file != str(out) or exc.line is None or "ignored" not in exc.message:
                raise
            lines = _drop(lines, exc.line)
            continue
        # a file key the overrides switch off is warned about (not refused): drop it too
        off = _SWITCHED.search(err.getvalue().replace(str(out), "FILE"))
        if off is None:
            break
        lines = _drop(lines, int(off.group(1)))
    _MADE[key] = out
    return out
