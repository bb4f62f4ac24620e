"""Progress bars of the long one-piece phases (issue 22): candidate masks, the
coverage-versus-N curve, the Monte Carlo verification.

The bars are tqdm's, on stderr, like the GA's and the engine's; ``ideas-hpc
run --no-progress`` turns them off for the whole run (:func:`enabled`).
Results come back in submission order, so progress never changes numbers.
"""

from __future__ import annotations

import sys
from contextlib import contextmanager

_STATE = {"on": True}


@contextmanager
def enabled(on: bool):
    """Show (or hide) the bars inside this block."""
    old = _STATE["on"]
    _STATE["on"] = bool(on)
    try:
        yield
    finally:
        _STATE["on"] = old


def on() -> bool:
    """Whether bars are shown (``run --no-progress`` turns them off)."""
    return _STATE["on"]


def bar(total: int, desc: str | None, unit: str = "chunk"):
    """A tqdm bar on stderr; none under ``enabled(False)``, without ``desc`` or for one step."""
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False,
                disable=not _STATE["on"] or desc is None or total <= 1)


def map_chunks(fn, chunks: list, client=None, *, desc: str | None, unit: str = "chunk",
               retries: int = 0) -> list:
    """``[fn(c) for c in chunks]``, on the client's workers when given, with a bar."""
    with bar(len(chunks), desc, unit) as b:
        if client is None:
            out = []
            for c in chunks:
                out.append(fn(c))
                b.update(1)
            return out
        from distributed import as_completed

        futures = client.map(fn, chunks, pure=False, retries=retries)
        for _ in as_completed(futures):
            b.update(1)
        return client.gather(futures)


def steps(items, desc: str, unit: str = "step"):
    """Iterate ``items`` (a sized iterable) with a bar."""
    items = list(items)
    with bar(len(items), desc, unit) as b:
        for x in items:
            yield x
            b.update(1)


def note(msg: str) -> None:
    """One line on stderr before a long step that has no bar (none under ``enabled(False)``)."""
    if _STATE["on"]:
        print(msg, file=sys.stderr, flush=True)
