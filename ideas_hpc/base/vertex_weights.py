"""Vertex weights of a scenario bank: one shared vector or one per scenario (issue 42).

A bank's coverage is ``cov_s(T) = sum_v w_{s,v} [v seen by T in s]`` with area fractions
``w``. On a known body every scenario shares one vector (``(V,)``, the vertex areas over
their sum). When each scenario is a different world (a drawn shape on the same mesh
topology, and a reference area such as the surface lit at closest approach that differs
per world), the weight of vertex v depends on the scenario: ``(S, V)``, zero outside the
reference. :func:`normalised` turns either form into fractions, row by row, so each
scenario's weights sum to 1; the kernels of :mod:`ideas_hpc.core.design.reliability`
read row s (or the one shared row).
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.base.errors import InputError


def normalised(areas, n_scenarios: int | None = None, field: str = "areas") -> np.ndarray:
    """Area fractions of ``areas`` (V,) or (S, V), each row over its own sum (C-contiguous).

    A shared vector is divided by its sum exactly as the designers always have
    (``w / w.sum()``); each row of a per-scenario array likewise, so identical rows give
    the same floats as the shared vector.

    Parameters
    ----------
    areas : (V,) or (S, V) array_like
        Vertex areas (any unit) or weights, >= 0; per scenario when 2-D.
    n_scenarios : int, optional
        S of the bank: a 2-D ``areas`` must have S rows (or one, which is shared).
    field : str
        Name of the input in errors.

    Raises
    ------
    InputError
        ``field``: not 1-D or 2-D, a wrong number of rows, a negative or non-finite
        weight, or a scenario whose weights sum to 0.
    """
    a = np.asarray(areas, dtype=np.float64)
    if a.ndim not in (1, 2) or a.shape[-1] == 0:
        raise InputError(f"vertex weights must be (V,) or (S, V), got shape {a.shape}",
                         field=field)
    if a.ndim == 2 and n_scenarios is not None and a.shape[0] not in (1, int(n_scenarios)):
        raise InputError(f"per-scenario vertex weights have {a.shape[0]} rows for "
                         f"{int(n_scenarios)} scenarios", field=field)
    if not np.all(np.isfinite(a)) or np.any(a < 0.0):
        raise InputError("vertex weights must be finite and >= 0", field=field)
    if a.ndim == 1:
        total = a.sum()
        if not total > 0.0:
            raise InputError("the vertex weights sum to 0", field=field)
        return np.ascontiguousarray(a / total)
    out = np.empty_like(a)
    for s in range(a.shape[0]):
        total = a[s].sum()      # row by row: the same float sum as a shared vector's
        if not total > 0.0:
            raise InputError(f"the vertex weights of scenario {s} sum to 0 (no reference "
                             "area in that world)", field=field)
        out[s] = a[s] / total
    return out


def row(w: np.ndarray, s: int) -> np.ndarray:
    """(V,) the weights of scenario ``s``: ``w`` when shared (1-D or one row), else row s."""
    if w.ndim == 1:
        return w
    return w[s if w.shape[0] > 1 else 0]


def per_scenario(w: np.ndarray) -> bool:
    """True when ``w`` holds more than one row (weights differ by scenario)."""
    return w.ndim == 2 and w.shape[0] > 1
