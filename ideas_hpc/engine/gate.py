"""Hold every chunk task at a gate until somebody lets it through.

Set ``IDEAS_HPC_CHUNK_GATE=DIR`` before starting a campaign and each chunk
task, on whatever worker it runs, waits before computing until it can claim a
token in ``DIR``: a file named ``token-*`` that it renames to
``claimed-<chunk>-<uuid>`` (a rename is atomic, so exactly one task gets each
token). A file named ``open`` in ``DIR`` lets every task through. A task that
reaches the gate leaves ``waiting-<chunk>`` there.

This makes the progress of a campaign a function of state that an outside
process controls, not of how fast the machine is: the kill-and-resume tests
hand out tokens one by one and kill the campaign at a known point (``k`` chunks
done, the next one claimed and computing), and an operator can pause a long
campaign on a shared machine by pointing the variable at an empty folder.
"""

from __future__ import annotations

import os
import time
import uuid
from pathlib import Path

GATE_ENV = "IDEAS_HPC_CHUNK_GATE"
OPEN_FILE = "open"
# Safety net only: a gate nobody serves fails the task (dask reports it) instead
# of holding a worker forever. No outcome waits on this clock.
MAX_WAIT_S = 3600.0


def gate_from_env() -> str | None:
    """The gate folder named by ``IDEAS_HPC_CHUNK_GATE``, or None when unset."""
    value = os.environ.get(GATE_ENV, "").strip()
    return str(Path(value).absolute()) if value else None


def pass_gate(gate_dir: str, chunk_id: int, poll_s: float = 0.01) -> str:
    """Block until a token in ``gate_dir`` is claimed for ``chunk_id`` or the gate is open.

    Returns the name of the claimed file, or ``"open"``.
    """
    gate = Path(gate_dir)
    (gate / f"waiting-{chunk_id}").touch()  # lets the gate keeper see the task arrived
    t_end = time.monotonic() + MAX_WAIT_S
    while True:
        if (gate / OPEN_FILE).exists():
            return OPEN_FILE
        for token in sorted(gate.glob("token-*")):
            claimed = gate / f"claimed-{chunk_id}-{uuid.uuid4().hex[:8]}"
            try:
                os.rename(token, claimed)
            except FileNotFoundError:  # another task took it first
                continue
            return claimed.name
        if time.monotonic() > t_end:
            raise RuntimeError(f"chunk {chunk_id}: gate {gate} ({GATE_ENV}) gave no token "
                               f"in {MAX_WAIT_S:.0f} s")
        time.sleep(poll_s)
