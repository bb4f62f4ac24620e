"""Package version, and the code version recorded in result stores."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

__version__ = "0.1.0"


def code_version() -> str:
    """``__version__`` plus the git commit when running from a checkout (``0.1.0+g1a2b3c4``)."""
    here = Path(__file__).resolve().parent.parent
    try:
        out = subprocess.run(["git", "-C", str(here), "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True, timeout=5)
        if out.returncode == 0 and out.stdout.strip():
            dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain",
                                    "--untracked-files=no"],
                                   capture_output=True, text=True, timeout=5).stdout.strip()
            return f"{__version__}+g{out.stdout.strip()}" + (".dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        pass
    return __version__


def warn_code_version(store, attrs) -> None:
    """One line on stderr when a store being resumed was written by other code.

    Not an error: the config hash guards what the numbers depend on in the
    input; whether a code change moves them is for the user to judge.
    """
    old, now = attrs.get("code_version"), code_version()
    if old != now:
        print(f"ideas-hpc: warning: {store} was written by code version {old}, resuming with "
              f"{now}", file=sys.stderr, flush=True)
