"""Stereo from two spacecraft: which candidate pairs map each vertex (issue 14 item 4).

With nadir pointing one spacecraft sees a vertex from a narrow cone of
directions (on eros001708 no single track gives a 10-40 deg pair), so stereo
comes from two spacecraft. A swarm ``S`` maps vertex ``j`` in stereo when
some candidate of ``S`` has a stereo pair on its own track or some pair
``a < b`` of ``S`` has a usable observation each whose unit lines of sight
``u, w`` satisfy ``cos(s_max) <= u . w <= cos(s_min)``. This kernel tabulates
the second condition for every pair of candidates; the designer then
solves a set cover over pairs (:mod:`ideas_hpc.design.stereo`).

Per vertex, each candidate's usable directions are collected with the scan
of :mod:`ideas_hpc.core.mapping.observations` and bounded by a cap (centre: the first
direction, radius: the largest angle to it). For caps with centre angle ``t``
and radii ``ra, rb`` every cross pair lies in ``[t - ra - rb, t + ra + rb]``
(triangle inequality on the sphere): a cap interval inside ``[s_min, s_max]``
decides True, one outside decides False, and only the rest are tested pair by
pair. The result is that of the pairwise test (:data:`SLACK` guards the
rounding of ``acos``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.observations import L_SMAX, L_SMIN, _scan, quality_tests
from ideas_hpc.core.mapping.quality import _CHUNK
from ideas_hpc.core.mapping.time_tree import scan_tree
from ideas_hpc.core.mapping.records import QualityTests, TimeTree, no_observations

class Scratch(NamedTuple):
    """Per-chunk scratch arrays of :func:`stereo_pairs` (reused vertex after vertex)."""

    #: (128,) int64, time-tree walk.
    stack: np.ndarray
    #: (n_img,) int8, lighting cache of the vertex.
    lc: np.ndarray
    #: (K n_img, 3) float64, usable unit lines of sight, candidate after candidate.
    U: np.ndarray
    #: (K + 1,) int64, first row of each candidate in ``U``.
    start: np.ndarray
    #: (K,) float64, radius of each candidate's whole-track cap, rad.
    rad: np.ndarray
    #: (K n_img + 1, 5) float64, caps: centre xyz, radius (rad), first member.
    cap: np.ndarray
    #: (K + 1,) int64, first cap of each candidate.
    cstart: np.ndarray


#: Angular slack of the cap decisions, rad (see module docstring).
SLACK = 1e-6
#: Radius of the caps of consecutive directions, rad (efficiency only).
CAP_RADIUS = np.radians(0.5)


@njit(cache=True)
def pair_index(a, b, k):
    """Row of the pair ``a < b`` of ``k`` candidates in the upper-triangle order."""
    return a * (2 * k - a - 1) // 2 + (b - a - 1)


@njit(parallel=True, cache=True)
def stereo_pairs(mesh, cam, opts, bvh, quality):
    """(K (K - 1) / 2, V) bool: candidate pair ``(a, b)`` maps vertex ``j`` in stereo.

    Arguments as in :func:`ideas_hpc.core.mapping.quality_masks.quality_by_spacecraft`
    (``cam.r_T_m`` holds the K candidates). Rows are in :func:`pair_index` order.
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    nimg = cam.r_T_m.shape[1]
    tree = TimeTree(*scan_tree(cam))
    tests = QualityTests(*quality_tests(quality))
    out = np.zeros((nsc * (nsc - 1) // 2, nv), dtype=np.bool_)
    nchunk = (nv + _CHUNK - 1) // _CHUNK
    for ch in prange(nchunk):
        stack = np.empty(128, dtype=np.int64)
        lc = np.zeros(nimg, dtype=np.int8)
        U = np.empty((nsc * nimg, 3))
        start = np.zeros(nsc + 1, dtype=np.int64)
        rad = np.zeros(nsc)
        cap = np.zeros((nsc * nimg + 1, 5))        # centre xyz, radius, first member
        cstart = np.zeros(nsc + 1, dtype=np.int64)
        for j in range(ch * _CHUNK, min(nv, (ch + 1) * _CHUNK)):
            _pairs_of_vertex(j, out, Scratch(stack, lc, U, start, rad, cap, cstart), mesh, cam,
                             opts, bvh, tests, tree)
    return out


@njit(cache=True)
def _pairs_of_vertex(j, out, scratch, mesh, cam, opts, bvh, tests, tree):
    """Fill column ``j`` of :func:`stereo_pairs` (scratch arrays given by the caller)."""
    stack, lc, U, start, rad, cap, cstart = scratch
    limits = tests.limits
    smin = limits[L_SMIN]
    smax = limits[L_SMAX]
    cmin = np.cos(smax)
    cmax = np.cos(smin)
    nsc = cam.r_T_m.shape[0]
    lc[:] = 0
    m = 0
    nc = 0
    cos_cap = np.cos(CAP_RADIUS)
    for k in range(nsc):
        start[k] = m
        cstart[k] = nc
        m = _scan(j, k, tree, stack, lc, mesh, cam, opts, bvh, tests, U,
                  no_observations(m, True)).m
        # whole-track cap (centre: first direction) and caps of consecutive directions
        r = 0.0
        for x in range(start[k], m):
            d = U[x, 0] * U[start[k], 0] + U[x, 1] * U[start[k], 1] + U[x, 2] * U[start[k], 2]
            r = max(r, np.arccos(min(1.0, max(-1.0, d))))
            if nc > cstart[k]:
                c = nc - 1
                d = U[x, 0] * cap[c, 0] + U[x, 1] * cap[c, 1] + U[x, 2] * cap[c, 2]
                if d >= cos_cap:
                    cap[c, 3] = max(cap[c, 3], np.arccos(min(1.0, max(-1.0, d))))
                    continue
            cap[nc, 0] = U[x, 0]
            cap[nc, 1] = U[x, 1]
            cap[nc, 2] = U[x, 2]
            cap[nc, 3] = 0.0
            cap[nc, 4] = x
            nc += 1
        rad[k] = r
    start[nsc] = m
    cstart[nsc] = nc
    cap[nc, 4] = m
    for a in range(nsc):
        if start[a + 1] == start[a]:
            continue
        for b in range(a + 1, nsc):
            if start[b + 1] == start[b]:
                continue
            state = _decide(U[start[a]], U[start[b]], rad[a], rad[b], smin, smax)
            if state == 0:
                continue
            hit = state == 1
            P = cstart[a]
            while not hit and P < cstart[a + 1]:
                for Q in range(cstart[b], cstart[b + 1]):
                    st = _decide(cap[P, :3], cap[Q, :3], cap[P, 3], cap[Q, 3], smin, smax)
                    if st == 1 or (st == 2 and _members(U, int(cap[P, 4]), int(cap[P + 1, 4]),
                                                        int(cap[Q, 4]), int(cap[Q + 1, 4]),
                                                        cmin, cmax)):
                        hit = True
                        break
                P += 1
            if hit:
                out[pair_index(a, b, nsc), j] = True


@njit(cache=True, inline="always")
def _decide(u, w, ru, rw, smin, smax):
    """Cap test: 0 no member pair in [smin, smax], 1 every pair, 2 undecided."""
    d = u[0] * w[0] + u[1] * w[1] + u[2] * w[2]
    t = np.arccos(min(1.0, max(-1.0, d)))
    lo = t - ru - rw
    hi = t + ru + rw
    if lo - SLACK > smax or hi + SLACK < smin:
        return 0
    if lo - SLACK >= smin and hi + SLACK <= smax:
        return 1
    return 2


@njit(cache=True)
def _members(U, a0, a1, b0, b1, cmin, cmax):
    """Some member pair of the two caps has cmin <= u . w <= cmax."""
    for x in range(a0, a1):
        for y in range(b0, b1):
            c = U[x, 0] * U[y, 0] + U[x, 1] * U[y, 1] + U[x, 2] * U[y, 2]
            if cmin <= c and c <= cmax:
                return True
    return False
