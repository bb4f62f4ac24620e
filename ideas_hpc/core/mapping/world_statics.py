"""What the rows of a world read besides the flight, built once per world (issue 43).

Every candidate of a world of a target prior flies around the same mesh under the same
Sun, so two per-vertex facts are the world's, not the candidate's:

* **lighting** (:func:`lit_at_images`): vertex ``j`` is lit at image ``i`` when
  ``n_j . s_i > 0`` and the ray ``p_j + t s_i, t > 0`` crosses no face (the test of
  :func:`ideas_hpc.core.mapping.observations._lit`). Over an encounter the Sun turns
  slowly in the body frame (Eros-class, 20 s: 0.4 deg), so the images are cut into
  runs whose Sun directions lie in a cone of half-angle at most :data:`SUN_CONE_MAX`
  (:func:`sun_runs`); one :func:`~ideas_hpc.core.mapping.bvh.cone_clear` query per
  (vertex, run) proves the whole run unshadowed (a cleared cone is never one the exact
  ray test would block), and only the vertices whose cone is not cleared cast rays,
  image by image, starting at the face that shadowed the previous image (any crossed
  face answers the any-hit query). The table is the exact per-image test.
* **the clear cone** (:func:`clear_cones`): the largest cone around the vertex normal
  ``n_j`` that no face (other than the vertex's own) meets. A face lying strictly below
  the tangent plane ``(x - p_j) . n_j = 0`` cannot meet a sight line that rises above
  it, nor can a face in a BVH box whose every point lies beyond the cone found so far
  (``(x - p_j) . n_j <= top`` and ``|x - p_j| >= dist`` over the box, so its angle from
  ``n_j`` exceeds ``theta`` when ``top < cos(theta) dist``); every other face ``f`` leaves the cone of half-angle ``theta_f``, its angular
  distance from ``n_j`` seen from ``p_j``
  (:func:`~ideas_hpc.core.mapping.bvh.tri_cone_gap`, the distance
  :func:`~ideas_hpc.core.mapping.bvh.cone_clear` tests). So with
  ``theta_j = min(THETA_CAP, min_f theta_f)``, every sight line within
  ``theta_j / (1 + 1e-9) - 1e-9`` of the normal is one that ``cone_clear`` clears
  (it inflates its half-angle by exactly that), hence unblocked; the table holds
  ``cos`` of that angle less a further 1e-6 rad, far above the rounding of the
  sight line's cosine, or 2 (never) below 0.01 rad. A candidate's sight line within
  it needs no occlusion ray.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.bvh import cone_clear, tri_cone_gap
from ideas_hpc.core.mapping.scenario_proofs import _vertex
from ideas_hpc.core.mapping.segments import segment_hit

#: Largest half-angle (rad) of the Sun directions of one lighting run: wider cones
#: rarely clear and cost a longer BVH walk (speed only; the table does not depend on it).
SUN_CONE_MAX = 0.01


@njit(cache=True)
def sun_runs(sun_T, cone_max):
    """Consecutive runs of images whose unit Sun directions ``sun_T`` (n_img, 3) lie in
    a cone of half-angle ``<= cone_max`` (rad) around the run's first direction, greedily.

    Returns
    -------
    start : (R + 1,) int64
        Run ``r`` holds images ``start[r]`` to ``start[r + 1] - 1``.
    axis : (R, 3) float64
        Unit axis of each run's cone (its first Sun direction).
    half : (R,) float64
        Half-angle of each run's cone, rad: the largest angle
        ``atan2(|a x s|, a . s)`` from its axis to a member (``cone_clear`` inflates
        it by 1e-9, relative and absolute, far above this rounding).
    """
    n = sun_T.shape[0]
    start = np.empty(n + 1, dtype=np.int64)
    axis = np.empty((n, 3))
    half = np.zeros(n)
    nr = 0
    for i in range(n):
        sx = sun_T[i, 0]
        sy = sun_T[i, 1]
        sz = sun_T[i, 2]
        if nr > 0:
            ax = axis[nr - 1, 0]
            ay = axis[nr - 1, 1]
            az = axis[nr - 1, 2]
            cx = ay * sz - az * sy
            cy = az * sx - ax * sz
            cz = ax * sy - ay * sx
            ang = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), ax * sx + ay * sy + az * sz)
            if ang <= cone_max:
                half[nr - 1] = max(half[nr - 1], ang)
                continue
        nn = np.sqrt(sx * sx + sy * sy + sz * sz)
        start[nr] = i
        axis[nr, 0] = sx / nn
        axis[nr, 1] = sy / nn
        axis[nr, 2] = sz / nn
        # the axis is the normalised first direction; its own angle to it is rounding
        cx = axis[nr, 1] * sz - axis[nr, 2] * sy
        cy = axis[nr, 2] * sx - axis[nr, 0] * sz
        cz = axis[nr, 0] * sy - axis[nr, 1] * sx
        half[nr] = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz),
                              axis[nr, 0] * sx + axis[nr, 1] * sy + axis[nr, 2] * sz)
        nr += 1
    start[nr] = n
    return start[:nr + 1].copy(), axis[:nr].copy(), half[:nr].copy()


@njit(parallel=True, cache=True)
def lit_at_images(mesh, sun_T, bvh):
    """(V, n_img) bool: vertex ``j`` lit at image ``i`` (module docstring).

    Parameters
    ----------
    mesh : :class:`~ideas_hpc.core.mapping.records.Mesh`
    sun_T : (n_img, 3) float64
        Unit body -> Sun direction in T per image.
    bvh : :class:`~ideas_hpc.core.mapping.records.Bvh`
    """
    nv = mesh.vertices_T_m.shape[0]
    nimg = sun_T.shape[0]
    start, axis, half = sun_runs(sun_T, SUN_CONE_MAX)
    nrun = half.shape[0]
    lit = np.zeros((nv, nimg), dtype=np.bool_)
    for j in prange(nv):
        px, py, pz, nx, ny, nz, _ = _vertex(mesh, j)
        hint = np.int64(-1)
        for r in range(nrun):
            facing = False
            for i in range(start[r], start[r + 1]):
                if sun_T[i, 0] * nx + sun_T[i, 1] * ny + sun_T[i, 2] * nz > 0.0:
                    facing = True
                    break
            if not facing:
                continue
            clear = cone_clear(bvh.node_bounds_m, bvh.node_info, bvh.tri_m, bvh.tri_vid,
                               px, py, pz, axis[r, 0], axis[r, 1], axis[r, 2], half[r],
                               np.int64(j))
            for i in range(start[r], start[r + 1]):
                sx = sun_T[i, 0]
                sy = sun_T[i, 1]
                sz = sun_T[i, 2]
                if not sx * nx + sy * ny + sz * nz > 0.0:
                    continue
                if clear:
                    lit[j, i] = True
                    continue
                f = segment_hit(bvh, px, py, pz, sx, sy, sz, np.inf, np.int64(j), hint)
                if f >= 0:
                    hint = f
                else:
                    lit[j, i] = True
    return lit


#: Largest half-angle of a clear cone, rad (86 deg: a sight line above the 5 deg
#: elevation mask of a flyby, and below the pi/2 that faces under the tangent plane
#: keep).
THETA_CAP = 1.5
#: Smallest clear cone used, rad (below it every sight line casts its ray).
THETA_MIN = 0.01


@njit(cache=True, inline="always")
def _box_gap2(nb, node, px, py, pz):
    """Squared distance (m^2) from ``p`` to box ``node`` (0 inside)."""
    gx = max(nb[node, 0] - px, 0.0, px - nb[node, 3])
    gy = max(nb[node, 1] - py, 0.0, py - nb[node, 4])
    gz = max(nb[node, 2] - pz, 0.0, pz - nb[node, 5])
    return gx * gx + gy * gy + gz * gz


@njit(parallel=True, cache=True)
def clear_cones(mesh, bvh, theta_cap):
    """(V,) float64: the cosine of each vertex's clear cone (module docstring; 2.0: none)
    of half-angle at most ``theta_cap`` (rad, at most :data:`THETA_CAP`: a wider cap proves
    more sight lines, a narrower one prunes more of the BVH), the BVH walked with boxes
    wholly below the tangent plane or beyond the cone found so far skipped."""
    nb = bvh.node_bounds_m
    info = bvh.node_info
    tri = bvh.tri_m
    vid = bvh.tri_vid
    nv = mesh.vertices_T_m.shape[0]
    out = np.full(nv, 2.0)
    for j in prange(nv):
        px, py, pz, nx, ny, nz, _ = _vertex(mesh, j)
        pn = px * nx + py * ny + pz * nz
        # "strictly below": by 1e-9 of the vertex's scale, far above the rounding
        below = -1e-9 * (np.sqrt(px * px + py * py + pz * pz) + 1.0)
        theta = min(theta_cap, THETA_CAP)
        stack = np.empty(64, dtype=np.int64)
        sp = 1
        stack[0] = 0
        while sp > 0 and theta >= THETA_MIN:
            sp -= 1
            node = stack[sp]
            top = (max(nb[node, 0] * nx, nb[node, 3] * nx) + max(nb[node, 1] * ny, nb[node, 4] * ny)
                   + max(nb[node, 2] * nz, nb[node, 5] * nz)) - pn
            if top < below:
                continue
            # every point x of the box has (x - p) . n <= top and |x - p| >= dist: beyond
            # the cone found so far when top < cos(theta) dist (with a margin)
            dist = np.sqrt(_box_gap2(nb, node, px, py, pz))
            if top < np.cos(theta) * dist * (1.0 - 1e-9) + below:
                continue
            left = info[node, 0]
            if left >= 0:
                # the nearer child first: the faces that narrow the cone are near the vertex
                right = info[node, 1]
                if _box_gap2(nb, left, px, py, pz) < _box_gap2(nb, right, px, py, pz):
                    left, right = right, left
                stack[sp] = left
                stack[sp + 1] = right
                sp += 2
                continue
            for f in range(info[node, 2], info[node, 2] + info[node, 3]):
                if vid[f, 0] == j or vid[f, 1] == j or vid[f, 2] == j:
                    continue
                h0 = (tri[f, 0] - px) * nx + (tri[f, 1] - py) * ny + (tri[f, 2] - pz) * nz
                h1 = h0 + tri[f, 3] * nx + tri[f, 4] * ny + tri[f, 5] * nz
                h2 = h0 + tri[f, 6] * nx + tri[f, 7] * ny + tri[f, 8] * nz
                if max(h0, h1, h2) < below:
                    continue
                theta = min(theta, tri_cone_gap(px, py, pz, nx, ny, nz, tri, f))
        a = (theta - 1e-9) / (1.0 + 1e-9) - 1e-6
        if a >= THETA_MIN:
            out[j] = np.cos(a)
    return out
