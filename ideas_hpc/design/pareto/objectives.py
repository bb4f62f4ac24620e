"""Objectives of the multi-objective swarm design (:mod:`ideas_hpc.design.pareto.nsga2`).

Objectives (:data:`OBJECTIVES`) are evaluated for the whole population at
once from an ``(P, N_max)`` member matrix padded with -1 (pymoo style), and
stored with their natural sign; the search minimises ``sense * value``:

* ``n``: swarm size (minimised);
* ``coverage``: area fraction of the union of the members' masks (paper eq.
  26), i.e. the coverage with the ``[coverage]`` requirement baked into the
  bank (maximised);
* ``worst_failure_coverage``: ``min_i A(S \\ {i})``, the coverage after the
  worst single failure, 0 for N = 1 (as :func:`~ideas_hpc.design.worst_failure`);
* ``stereo_coverage``: area fraction mapped in stereo: the union of the
  members' rows of ``bank.stereo`` (a stereo pair from one track) and, when
  the bank has ``pairs``, of the rows of every pair of members (two
  spacecraft; with nadir pointing on Eros that is where stereo comes from);
* ``mean_resolution``: with ``r_v(S) = min_{i in S} bank.resolution[i, v]``
  (m), ``sum_{v in M} a_v r_v / sum_{v in M} a_v`` over the vertices
  ``M = {v : v in the union of the masks, r_v finite}`` (minimised;
  ``inf`` when M is empty, searched as :data:`NO_RESOLUTION`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ideas_hpc.core.design.union import population_coverage
from ideas_hpc.base.errors import InputError
from ideas_hpc.design.bank import CandidateBank

#: The objectives' parameter name (the campaign maps it to ``design.objectives``).
FIELD = "objectives"
#: Mean resolution (m) searched for a swarm that maps no vertex (stored as inf).
NO_RESOLUTION = 1e12


@dataclass(frozen=True)
class Objective:
    """One objective: ``evaluate(bank, members (P, n_max) int64, -1 padded) -> (P,)``
    natural values; ``sense`` +1 minimised, -1 maximised. ``needs`` names the bank
    data beyond the seen masks it reads: ``"quality"`` (per-candidate mapping and
    resolution rows, :data:`BANK_DATA`) and ``"pairs"`` (the stereo pair table)."""

    name: str
    sense: int
    units: str
    long_name: str
    evaluate: Callable[[CandidateBank, np.ndarray], np.ndarray]
    needs: frozenset = frozenset()


def _union(masks: np.ndarray, areas: np.ndarray, members: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(areas, dtype=np.float64)
    cov, _ = population_coverage(np.ascontiguousarray(masks, dtype=bool),
                                 np.ascontiguousarray(members, dtype=np.int64), a, float(a.sum()))
    return cov


def _n(bank, members):
    return (members >= 0).sum(axis=1).astype(np.float64)


def _coverage(bank, members):
    return _union(bank.masks, bank.areas, members)


def _worst_failure(bank, members):
    """All single failures of the whole population in one union call."""
    p, w = members.shape
    n = (members >= 0).sum(axis=1)
    owner, drop = np.nonzero(np.arange(w)[None, :] < n[:, None])   # one row per failure
    rest = members[owner].copy()
    rest[np.arange(owner.size), drop] = -1
    cov = _union(bank.masks, bank.areas, rest) if owner.size else np.zeros(0)
    worst = np.full(p, np.inf)
    np.minimum.at(worst, owner, cov)
    return np.where(n <= 1, 0.0, worst)


def _optional(bank, name: str, objective: str) -> np.ndarray:
    arr = getattr(bank, name, None)
    if arr is None:
        raise InputError(f"objective {objective!r} needs the candidates' {name!r} arrays, which "
                         "this candidate bank does not have", field=FIELD)
    return np.asarray(arr)


def _stereo(bank, members):
    own = _optional(bank, "stereo", "stereo_coverage")
    if getattr(bank, "pairs", None) is None:
        return _union(own, bank.areas, members)
    from ideas_hpc.design.stereo import scorer

    return scorer(bank).coverage([m[m >= 0] for m in members])


def _mean_resolution(bank, members):
    res = _optional(bank, "resolution", "mean_resolution").astype(np.float64)
    best = np.full((members.shape[0], res.shape[1]), np.inf)
    seen = np.zeros(best.shape, dtype=bool)
    for j in range(members.shape[1]):
        col = members[:, j]
        on = col >= 0
        best[on] = np.minimum(best[on], res[col[on]])
        seen[on] |= bank.masks[col[on]]
    use = seen & np.isfinite(best)
    a = np.asarray(bank.areas, dtype=np.float64)
    wsum = use @ a
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = (np.where(use, best, 0.0) @ a) / wsum
    return np.where(wsum > 0, mean, np.inf)


OBJECTIVES: dict[str, Objective] = {o.name: o for o in (
    Objective("n", 1, "1", "number of spacecraft", _n),
    Objective("coverage", -1, "1", "area coverage (with the [coverage] requirement)", _coverage),
    Objective("worst_failure_coverage", -1, "1", "lowest coverage after any single failure",
              _worst_failure),
    Objective("stereo_coverage", -1, "1", "area fraction mapped in stereo", _stereo,
              frozenset({"quality", "pairs"})),
    Objective("mean_resolution", 1, "m", "area-weighted mean best resolution of the mapped "
              "vertices", _mean_resolution, frozenset({"quality"})),
)}

#: What an objective may need from the bank (:attr:`Objective.needs`).
BANK_DATA = ("quality", "pairs")


def bank_needs(names) -> frozenset:
    """The bank data (:data:`BANK_DATA`) objectives ``names`` need together."""
    return frozenset().union(*(OBJECTIVES[x].needs for x in names))


def check_objectives(names) -> tuple[str, ...]:
    """Validated objective names: at least two, distinct, each in :data:`OBJECTIVES`."""
    if not isinstance(names, (list, tuple)) or not all(isinstance(x, str) for x in names):
        raise InputError(f"must be a list of objective names, got {names!r}", field=FIELD)
    names = tuple(names)
    bad = [x for x in names if x not in OBJECTIVES]
    if bad:
        raise InputError(f"unknown objective(s) {', '.join(map(repr, bad))}; choose from "
                         + ", ".join(OBJECTIVES), field=FIELD)
    dup = sorted({x for x in names if names.count(x) > 1})
    if dup:
        raise InputError(f"lists {', '.join(map(repr, dup))} more than once", field=FIELD)
    if len(names) < 2:
        raise InputError(f"needs at least two objectives for a Pareto front, got {list(names)} "
                         "(a single objective is design-nadir's job)", field=FIELD)
    return names


def evaluate(bank: CandidateBank, names, members: np.ndarray) -> np.ndarray:
    """(P, len(names)) natural objective values of the swarms ``members`` (-1 padded)."""
    members = np.atleast_2d(np.asarray(members, dtype=np.int64))
    return np.stack([OBJECTIVES[x].evaluate(bank, members) for x in names], axis=1)


def minimised(names, values: np.ndarray) -> np.ndarray:
    """Values to minimise (``sense * value``), finite (inf resolution -> NO_RESOLUTION)."""
    sense = np.array([OBJECTIVES[x].sense for x in names], dtype=np.float64)
    v = np.where(np.isinf(values), NO_RESOLUTION, values)
    return v * sense
