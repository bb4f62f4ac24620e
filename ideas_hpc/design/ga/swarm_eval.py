"""Batch evaluation of whole GA populations (pymoo style: one call per generation).

A swarm's coverage is the union of its spacecraft's observed sets (paper eq.
26), and a spacecraft's set depends only on its own swarm angle, sweep period
and initial attitude. So the evaluator keeps a bank of per-spacecraft masks:

1. map every genome to candidate keys ``(theta, period, ic)`` (angles and
   periods snapped to the gene grid);
2. compute the masks of keys not yet in the bank, in chunks of
   ``chunk_size`` candidates, one dask task per chunk (never one per
   individual), each chunk running the compiled targeting, attitude and
   coverage kernels;
3. score the whole population in one compiled call
   (:func:`ideas_hpc.core.design.union.population_coverage`).

Everything is a pure function of the keys, so results do not depend on the
worker count or the order of evaluation.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

from ideas_hpc.core.design.union import population_coverage
from ideas_hpc.base.progress import map_chunks

TWO_PI = 2.0 * math.pi
Key = tuple  # (theta rad, period s (0: nadir), ic key int)


def snap_angle(theta: float, step: float) -> tuple[float, int]:
    """``(snapped angle in [0, 2 pi), grid index)``; step 0 keeps the angle (index from its bits)."""
    t = float(theta) % TWO_PI
    if step > 0:
        n = max(1, int(round(TWO_PI / step)))
        k = int(round(t / step)) % n
        return k * step, k
    return t, int(np.float64(t).view(np.int64) & 0x7FFFFFFF)


def snap_period(p: float, p_min: float, step: float) -> float:
    """Period snapped to ``p_min + k step`` (s); step 0 keeps it."""
    if step > 0:
        return p_min + round((float(p) - p_min) / step) * step
    return float(p)


class MaskBank:
    """Per-candidate-spacecraft observation masks, filled on demand.

    Parameters
    ----------
    compute : callable
        ``compute(keys: list[Key]) -> (len(keys), V) bool``; must be picklable
        (a module-level function or a ``functools.partial`` of one).
    n_vertices : int
    chunk_size : int
        Candidates per task.
    client : distributed.Client, optional
        Where chunks run; None computes in this process.
    """

    def __init__(self, compute: Callable, n_vertices: int, *, chunk_size: int = 32,
                 client=None, progress: Callable | None = None):
        self.compute = compute
        self.n_vertices = int(n_vertices)
        self.chunk_size = int(chunk_size)
        self.client = client
        self.progress = progress
        self._index: dict[Key, int] = {}
        self._rows: list[np.ndarray] = []
        self._masks = np.zeros((0, self.n_vertices), dtype=np.bool_)
        self.computed = 0
        self.tasks = 0

    def __len__(self) -> int:
        return len(self._index)

    @property
    def masks(self) -> np.ndarray:
        if len(self._rows) != self._masks.shape[0]:
            self._masks = np.ascontiguousarray(np.vstack(self._rows)) if self._rows else \
                np.zeros((0, self.n_vertices), dtype=np.bool_)
        return self._masks

    def ensure(self, keys: Sequence[Key], desc: str | None = None) -> None:
        """Compute the masks of keys the bank does not hold yet (deterministic order);
        ``desc`` shows a progress bar (:mod:`ideas_hpc.base.progress`)."""
        missing = sorted({k for k in keys if k not in self._index})
        if not missing:
            return
        chunks = [missing[i:i + self.chunk_size] for i in range(0, len(missing), self.chunk_size)]
        if self.client is None and self.progress:
            results = []
            for i, c in enumerate(chunks):
                results.append(self.compute(c))
                self.progress(i + 1, len(chunks))
        else:
            results = map_chunks(self.compute, chunks, self.client, desc=desc, retries=2)
        for chunk, res in zip(chunks, results):
            res = np.asarray(res, dtype=np.bool_)
            if res.shape != (len(chunk), self.n_vertices):
                raise RuntimeError(f"mask chunk has shape {res.shape}, expected "
                                   f"({len(chunk)}, {self.n_vertices})")
            for k, row in zip(chunk, res):
                self._index[k] = len(self._rows)
                self._rows.append(row)
        self.computed += len(missing)
        self.tasks += len(chunks)

    def rows(self, keys: Sequence[Key]) -> np.ndarray:
        return np.array([self._index[k] for k in keys], dtype=np.int64)

    def union_coverage(self, members_keys: list[list[Key]], vertex_areas: np.ndarray):
        """Coverage (area, count) of each individual given as a list of keys."""
        flat = [k for ks in members_keys for k in ks]
        self.ensure(flat)
        m = max(1, max((len(ks) for ks in members_keys), default=1))
        members = np.full((len(members_keys), m), -1, dtype=np.int64)
        for i, ks in enumerate(members_keys):
            if ks:
                members[i, :len(ks)] = self.rows(ks)
        a = np.ascontiguousarray(vertex_areas, dtype=np.float64)
        return population_coverage(self.masks, members, a, float(a.sum()))


def nadir_keys(genome: np.ndarray, angle_step: float, ic_offset: int = 0) -> list[Key]:
    """Keys of an NP genome ``[N, theta_1, ..., theta_Nmax]`` (first N angles used)."""
    n = int(round(genome[0]))
    keys = []
    for th in genome[1:1 + n]:
        t, k = snap_angle(th, angle_step)
        keys.append((t, 0.0, ic_offset + k))
    return keys


def fov_keys(genome: np.ndarray, thetas: Sequence[float], p_min: float, step: float,
             ic_offset: int = 0) -> list[Key]:
    """Keys of an FoV genome ``[P_1, ..., P_N]`` for a fixed swarm (spacecraft i keeps its IC)."""
    return [(float(th) % TWO_PI, snap_period(p, p_min, step), ic_offset + i)
            for i, (th, p) in enumerate(zip(thetas, genome))]
