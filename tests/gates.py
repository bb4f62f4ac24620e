"""Test side of :mod:`ideas_hpc.engine.gate`: hand out chunk tokens, wait on campaign state.

Kill and race tests take their moment from what the campaign has done (chunks
marked done, tokens claimed, tasks waiting at the gate), never from a sleep,
so they behave the same on a fast or a slow, loaded machine.
"""

from __future__ import annotations

import subprocess
import time
import uuid
from pathlib import Path
from typing import Callable

from ideas_hpc.engine.gate import GATE_ENV, OPEN_FILE

# A hung campaign fails the test after this long instead of hanging CI; no
# assertion depends on it, however slow the machine.
SAFETY_LIMIT_S = 900.0


class Gate:
    """A gate folder for ``IDEAS_HPC_CHUNK_GATE``."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.path.mkdir(parents=True, exist_ok=True)

    @property
    def env(self) -> dict[str, str]:
        return {GATE_ENV: str(self.path)}

    def allow(self, n: int = 1) -> None:
        """Let ``n`` more chunk tasks through."""
        for _ in range(n):
            (self.path / f"token-{uuid.uuid4().hex}").touch()

    def open(self) -> None:
        """Let every task through."""
        (self.path / OPEN_FILE).touch()

    def claimed(self) -> int:
        return sum(1 for _ in self.path.glob("claimed-*"))

    def waiting(self) -> int:
        """Distinct chunks whose task has reached the gate."""
        return sum(1 for _ in self.path.glob("waiting-*"))


def wait_until(pred: Callable[[], bool], what: str, proc: subprocess.Popen | None = None,
               log: Path | None = None) -> None:
    """Poll ``pred`` until true; fail if ``proc`` exits first (with its log) or at the safety limit."""
    t_end = time.monotonic() + SAFETY_LIMIT_S
    while not pred():
        if proc is not None and proc.poll() is not None:
            tail = log.read_text()[-3000:] if log is not None and log.exists() else ""
            raise AssertionError(f"campaign exited ({proc.returncode}) while waiting for "
                                 f"{what}:\n{tail}")
        if time.monotonic() > t_end:
            raise AssertionError(f"gave up waiting for {what} after {SAFETY_LIMIT_S:.0f} s")
        time.sleep(0.02)
