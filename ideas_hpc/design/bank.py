"""Candidate bank of the exact designer: one observation mask per grid angle.

The ring (or helix) is discretised into ``K = round(360 / angle_step_deg)``
swarm angles ``theta_k = k * step``. Spacecraft do not interact, so a swarm's
observed set is the union of its members' masks (paper eq. 26) and the masks
are computed once per candidate with the same code the GA uses
(:func:`ideas_hpc.design.candidates.candidate_masks` through
:class:`ideas_hpc.design.ga.swarm_eval.MaskBank`, keys ``(theta_k, 0, k)``).

Before any integer programme, :func:`reduce_problem` drops vertices no
candidate sees (no swarm can change them) and merges vertices seen by exactly
the same candidates into one weighted group (their areas add). Candidates with
identical masks can be merged too when nothing but coverage tells them apart
(no separation constraint between grid points, no failure redundancy).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ideas_hpc.core.design.union import population_coverage
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import map_chunks
from ideas_hpc.flyby.swarm_geometry import min_separation_angle

TWO_PI = 2.0 * math.pi


@dataclass
class CandidateBank:
    """Observation masks of the grid candidates.

    Attributes
    ----------
    theta : (K,) float64
        Swarm angles, rad, ``k * step_rad``.
    masks : (K, V) bool
        Vertex v observed by candidate k during the flyby.
    areas : (V,) float64
        Vertex areas, m^2.
    step_rad : float
        Grid step, rad.
    d_sep_m : float
        Ring radius, m (separations along the ring are ``d_sep_m * dtheta``).
    usable, stereo : (K, V) bool, optional
        With a ``[coverage]`` requirement and ``build_bank(quality=True)``: a
        usable observation, a stereo pair from the candidate's own track
        (:mod:`ideas_hpc.core.mapping.quality_masks`); ``masks`` is then what the
        candidate maps alone.
    resolution : (K, V) float64, optional
        Best effective ground sample per candidate, m (inf: unobserved).
    pairs : (K (K - 1) / 2, V) bool, optional
        Candidate pairs that map a vertex in stereo (two spacecraft,
        :mod:`ideas_hpc.core.mapping.stereo_pairs`), when a design asks for it.
    """

    theta: np.ndarray
    masks: np.ndarray
    areas: np.ndarray
    step_rad: float
    d_sep_m: float
    usable: np.ndarray | None = None
    stereo: np.ndarray | None = None
    resolution: np.ndarray | None = None
    pairs: np.ndarray | None = None
    #: Scorers derived from the rows, built on first use (:func:`ideas_hpc.design.stereo.scorer`).
    derived: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def n_candidates(self) -> int:
        return int(self.theta.size)

    @property
    def reach(self) -> float:
        """Highest coverage any swarm of grid candidates reaches (all of them flying)."""
        return self.coverage([np.arange(self.n_candidates)])[0]

    def coverage(self, swarms) -> np.ndarray:
        """Area coverage (fraction) of each swarm, given as candidate indices."""
        swarms = [np.asarray(s, dtype=np.int64).ravel() for s in swarms]
        m = max(1, max((s.size for s in swarms), default=1))
        members = np.full((len(swarms), m), -1, dtype=np.int64)
        for i, s in enumerate(swarms):
            members[i, :s.size] = s
        a = np.ascontiguousarray(self.areas, dtype=np.float64)
        cov, _ = population_coverage(np.ascontiguousarray(self.masks), members, a, float(a.sum()))
        return cov


def grid_size(step: float, field: str = "step") -> int:
    """Number of grid angles for a step (rad); the step must be in (0, 90] deg."""
    if not (math.isfinite(step) and 0.0 < step <= 0.5 * math.pi + 1e-12):
        raise InputError(f"must be in (0, 90] deg, got {math.degrees(step):g} deg", field=field)
    return max(1, int(round(TWO_PI / step)))


def build_bank(setup, step: float, *, client=None, chunk_size: int = 32,
               mask_bank=None, snap: bool = True, quality: bool = False,
               pairs: bool = False) -> CandidateBank:
    """Masks of every grid angle (rad step) for a flyby setup, ring or helix.

    ``snap`` makes the step divide the circle (``2 pi / round(2 pi / step)``);
    without it the GA's own keys ``(k step, 0, k)`` are used. ``mask_bank`` (a
    :class:`~ideas_hpc.design.ga.swarm_eval.MaskBank`) is reused when given, so a GA run
    and its exact reference share the computed masks. ``quality`` also fills
    ``usable``, ``stereo`` and ``resolution`` (one quality pass per candidate
    chunk, :func:`ideas_hpc.design.candidates.candidate_quality`); ``pairs`` (implies
    ``quality``) also the stereo table of candidate pairs, from one pass over all
    candidates (a pair spans chunks).
    """
    from ideas_hpc.design.candidates import candidate_masks, candidate_quality
    from ideas_hpc.design.ga.swarm_eval import MaskBank

    n = grid_size(step)
    step = TWO_PI / n if snap else float(step)
    keys = [(k * step, 0.0, k) for k in range(n)]
    common = dict(theta=step * np.arange(n), step_rad=step, d_sep_m=float(setup.d_sep_m),
                  areas=np.asarray(setup.body.shape.vertex_areas, dtype=np.float64))
    if pairs:
        q = candidate_quality(setup, keys, pairs=True)
        return CandidateBank(masks=q["mapped"], usable=q["usable"], stereo=q["stereo"],
                             resolution=q["resolution"], pairs=q["pairs"], **common)
    if quality and mask_bank is None:
        chunks = [keys[i:i + chunk_size] for i in range(0, n, chunk_size)]
        part = functools.partial(candidate_quality, setup)
        rows = map_chunks(part, chunks, client, desc="candidate rows", retries=2)
        q = {name: np.ascontiguousarray(np.concatenate([r[name] for r in rows]))
             for name in ("mapped", "usable", "stereo", "resolution")}
        return CandidateBank(masks=q["mapped"], usable=q["usable"], stereo=q["stereo"],
                             resolution=q["resolution"], **common)
    if mask_bank is None:
        mask_bank = MaskBank(functools.partial(candidate_masks, setup),
                             setup.body.shape.n_vertices, chunk_size=chunk_size, client=client)
    mask_bank.ensure(keys, desc="candidate masks")
    masks = np.ascontiguousarray(mask_bank.masks[mask_bank.rows(keys)])
    return CandidateBank(masks=masks, **common)


def separation_steps(step: float, d_sep: float, min_separation: float, n: int) -> int:
    """Largest grid distance ``m`` whose chord ``2 d_sep sin(m step / 2)`` is below ``min_separation``.

    The distance is the straight line between the two tracks, as
    :func:`ideas_hpc.flyby.swarm_geometry.check_separation` measures it, so a design
    the solver accepts passes the campaign's check when it is flown. Two
    candidates ``i, j`` conflict when their circular grid distance is
    ``1 .. m``. Raises when no two grid points are far enough apart.
    """
    if not (math.isfinite(min_separation) and min_separation >= 0.0):
        raise InputError(f"must be >= 0 km, got {min_separation / 1e3:g}",
                         field="min_separation")
    need = min_separation_angle(min_separation, d_sep)
    widest = (n // 2) * step
    if n > 1 and need > widest * (1 + 1e-12):
        far = 2.0 * d_sep * math.sin(0.5 * min(widest, math.pi))
        raise InputError(f"{min_separation / 1e3:g} km: no two grid angles are that far apart "
                         f"(the largest separation is {far / 1e3:.3f} km, ring radius "
                         f"{d_sep / 1e3:.3f} km)", field="min_separation")
    # a pair exactly min_separation apart is allowed (1e-9 guards the float division)
    return int(math.ceil(need / step - 1e-9)) - 1 if min_separation > 0 else 0


def conflict_windows(n: int, m: int) -> np.ndarray:
    """Clique rows of the separation constraint: candidates ``i`` to ``i+m`` (mod n), one row each.

    Every conflicting pair ``(i, i+d)``, ``1 <= d <= m``, lies in the window
    starting at ``i``, and all pairs inside a window conflict, so ``sum x <= 1``
    over each window is exactly the pairwise constraint set (and tighter in
    the LP relaxation). Returns (rows, m+1) int64; empty when ``m = 0``.
    """
    if m <= 0 or n <= 1:
        return np.zeros((0, 1), dtype=np.int64)
    m = min(m, n - 1)
    return (np.arange(n)[:, None] + np.arange(m + 1)[None, :]) % n


@dataclass
class Reduced:
    """The set-cover data after presolve (see module docstring).

    ``cover[c, g]``: merged candidate ``c`` sees vertex group ``g``; ``weight[g]``
    is the group's area as a fraction of the whole body; ``rep[c]`` is the grid
    index standing for merged candidate ``c`` and ``members[c]`` all of them.
    """

    cover: np.ndarray
    weight: np.ndarray
    rep: np.ndarray
    members: list
    unseen: float

    @property
    def n_groups(self) -> int:
        return int(self.weight.size)


def reduce_problem(masks: np.ndarray, areas: np.ndarray, *, merge_candidates: bool) -> Reduced:
    """Drop unseen vertices, merge identical vertex rows and (optionally) identical candidates."""
    masks = np.asarray(masks, dtype=bool)
    a = np.asarray(areas, dtype=np.float64) / float(np.sum(areas))
    seen = masks.any(axis=0)
    k = masks.shape[0]
    packed = np.packbits(masks[:, seen].T, axis=1)          # one row per seen vertex
    groups, inv = np.unique(packed, axis=0, return_inverse=True)
    weight = np.bincount(inv.ravel(), weights=a[seen], minlength=groups.shape[0])
    cover = np.unpackbits(groups, axis=1, count=k).astype(bool).T   # (K, G)
    if merge_candidates:
        cols, cinv = np.unique(np.packbits(cover, axis=1), axis=0, return_inverse=True)
        cinv = cinv.ravel()
        members = [np.flatnonzero(cinv == c) for c in range(cols.shape[0])]
        rep = np.array([mm[0] for mm in members], dtype=np.int64)
        cover = cover[rep]
    else:
        rep = np.arange(k, dtype=np.int64)
        members = [np.array([i]) for i in range(k)]
    return Reduced(cover=np.ascontiguousarray(cover), weight=weight, rep=rep, members=members,
                   unseen=float(a[~seen].sum()))
