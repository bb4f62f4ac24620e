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
               retries: int = 0, sizes: list | None = None, scatter: bool = False) -> list:
    """``[fn(c) for c in chunks]``, on the client's workers when given, with a bar.

    The one way the one-piece phases map work over dask or in this process.
    ``sizes``: each chunk's count in ``unit`` for the bar (default 1 each);
    ``scatter``: ship ``fn`` to every worker once rather than with every task
    (a function that carries a large state, a scenario bank's row engine).
    Results come back in the order of ``chunks`` whatever the completion order.
    """
    sizes = [1] * len(chunks) if sizes is None else list(sizes)
    with bar(sum(sizes), desc, unit) as b:
        if client is None:
            out = []
            for c, n in zip(chunks, sizes):
                out.append(fn(c))
                b.update(n)
            return out
        from distributed import as_completed

        if scatter:
            fn_f = client.scatter(fn, broadcast=True, hash=False)
            futures = client.map(_apply, chunks, fn=fn_f, pure=False, retries=retries)
        else:
            futures = client.map(fn, chunks, pure=False, retries=retries)
        size = {f.key: n for f, n in zip(futures, sizes)}
        for f in as_completed(futures):
            b.update(size[f.key])
        return client.gather(futures)


def _apply(chunk, fn):
    return fn(chunk)


def steps(items, desc: str, unit: str = "step"):
    """Iterate ``items`` (a sized iterable) with a bar."""
    items = list(items)
    with bar(len(items), desc, unit) as b:
        for x in items:
            yield x
            b.update(1)
