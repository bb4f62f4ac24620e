"""The report's body maps drawn in a second process while the report draws the rest.

A design store's report draws up to nine maps of the body
(:func:`~ideas_hpc.plots.coverage_map.render_coverage_map`: the body twice, face by face,
with matplotlib's 3-D Agg renderer, 0.7 s each on the 2-core machine): about half of
``ideas-hpc report``'s 16 s for the main job (2026-12-07). :class:`MapPool` with
``parallel`` hands each map to one child process as soon as the report knows it and
returns its path at once; the report draws its other figures meanwhile and
:meth:`MapPool.finish` waits for the maps (a map that failed raises its error there).
The PNGs are the same files: the same function draws them on the same arrays.

The child is spawned, not forked (zarr keeps an event-loop thread in this process, and
a forked child would inherit its locks), and starting it costs about 1.5 s of CPU: the
``ideas-hpc report`` command asks for it on a machine with a second CPU; the library's
default (``write_report(parallel=False)``), which tests call many times, draws in
process.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


class MapPool:
    """Draw maps here (``parallel=False`` or one CPU) or in one spawned child process."""

    def __init__(self, parallel: bool = False):
        self._pool = None
        self._jobs = []
        if parallel and (os.cpu_count() or 1) >= 2:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))

    @property
    def parallel(self) -> bool:
        """Whether maps are drawn in the child process."""
        return self._pool is not None

    def render(self, shape, values, path, **kw) -> Path:
        """:func:`~ideas_hpc.plots.coverage_map.render_coverage_map`, here or in the child;
        returns ``path`` (the file exists once :meth:`finish` has returned)."""
        from ideas_hpc.plots.coverage_map import render_coverage_map

        if self._pool is None:
            return render_coverage_map(shape, values, path, **kw)
        self._jobs.append(self._pool.submit(render_coverage_map, shape, np.asarray(values),
                                            path, **kw))
        return Path(path)

    def finish(self) -> None:
        """Wait for every map; the first map that failed raises its error here."""
        if self._pool is None:
            return
        try:
            for job in self._jobs:
                job.result()
        finally:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None

    def __enter__(self) -> "MapPool":
        return self

    def __exit__(self, *exc) -> None:
        if exc[0] is not None and self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None
            return
        self.finish()
