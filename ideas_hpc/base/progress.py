"""Progress bars of the long one-piece phases (issue 22): candidate masks, the
coverage-versus-N curve, the Monte Carlo verification; and where lines go: results
on stdout (:func:`result`), progress and logs on stderr (:func:`log`).

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


def result(msg: str) -> None:
    """A result line (a summary a user keeps): on stdout, so ``run > result.txt`` keeps it."""
    print(msg, flush=True)


def log(msg: str) -> None:
    """A progress or log line (body loaded, phase timings): on stderr, beside the bars."""
    print(msg, file=sys.stderr, flush=True)


def plural(n: int, word: str, many: str | None = None) -> str:
    """``1 sample``, ``2 samples``: the count and the word in the right number."""
    return f"{n} {word if n == 1 else (many or word + 's')}"


def bar(total: int, desc: str | None, unit: str = "chunk"):
    """A tqdm bar on stderr; none under ``enabled(False)``, without ``desc`` or for one step."""
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False,
                disable=not _STATE["on"] or desc is None or total <= 1)


def map_chunks(fn, chunks: list, client=None, *, desc: str | None, unit: str = "chunk",
               retries: int = 0, sizes: list | None = None, scatter: bool = False,
               errors: str = "raise", done: int = 0) -> list:
    """``[fn(c) for c in chunks]``, on the client's workers when given, with a bar.

    The one way every phase maps work over dask or in this process (the
    candidate rows, the GA's masks, the verification, the scenario bank, the
    engine's chunks). ``retries``: how many times a chunk that raised is run
    again (by dask, or here). ``sizes``: each chunk's count in ``unit`` for
    the bar (default 1 each); ``done``: units already done before (a resumed
    store). ``scatter``: ship ``fn`` to every worker once rather than with every
    task (a function that carries a large state, a scenario bank's row engine).
    ``errors="return"``: a chunk that still fails gives its exception in place
    of its result, and the others run on (``"raise"``: the first failure raises).
    Results come back in the order of ``chunks`` whatever the completion order.
    """
    if errors not in ("raise", "return"):
        raise ValueError(f"errors must be 'raise' or 'return', got {errors!r}")
    sizes = [1] * len(chunks) if sizes is None else list(sizes)
    with bar(done + sum(sizes), desc, unit) as b:
        b.update(done)
        if client is None:
            out = [_here(fn, c, retries, errors, b, n) for c, n in zip(chunks, sizes)]
            b.refresh()     # the final count is drawn whatever tqdm's refresh interval
            return out
        from distributed import as_completed

        if scatter:
            fn_f = client.scatter(fn, broadcast=True, hash=False)
            futures = client.map(_apply, chunks, fn=fn_f, pure=False, retries=retries)
        else:
            futures = client.map(fn, chunks, pure=False, retries=retries)
        index = {f.key: i for i, f in enumerate(futures)}
        out: list = [None] * len(futures)
        try:
            for f in as_completed(futures):
                i = index[f.key]
                if f.status == "finished":
                    out[i] = f.result()
                elif errors == "return":
                    out[i] = f.exception()
                else:
                    f.result()          # raises the task's error
                b.update(sizes[i])
        except BaseException:
            client.cancel(futures)
            raise
        b.refresh()         # the final count is drawn whatever tqdm's refresh interval
        return out


def _here(fn, chunk, retries, errors, b, n):
    for attempt in range(retries + 1):
        try:
            out = fn(chunk)
        except Exception as exc:  # noqa: BLE001 - retried, then raised or returned
            if attempt < retries:
                continue
            if errors == "raise":
                raise
            out = exc
        b.update(n)
        return out


def _apply(chunk, fn):
    return fn(chunk)


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
