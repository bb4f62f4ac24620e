"""One vertex's observations by one spacecraft: the inner scan of the quality pass.

Shared by :func:`ideas_hpc.core.mapping.quality.quality_vertices` (all spacecraft of a
swarm folded into one vertex record) and
:func:`ideas_hpc.core.mapping.quality_masks.quality_by_spacecraft` (one record per
candidate spacecraft, for the designers). The definitions (observation,
usable, effective ground sample, lit) are those of :mod:`ideas_hpc.core.mapping.quality`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.mapping.bvh import cone_clear, segment_blocked
from ideas_hpc.core.mapping.records import Observations
from ideas_hpc.core.mapping.time_tree import _classify
from ideas_hpc.core.mapping.visibility import _seen

#: Layout of ``limits``.
L_RES, L_EMI, L_INC, L_PHA, L_SMIN, L_SMAX = 0, 1, 2, 3, 4, 5

#: Largest cone half-angle (rad) tried above the leaves of the time tree; wider
#: cones rarely clear and cost a BVH walk each.
_CONE_MAX = 0.01


@njit(cache=True, inline="always")
def _run_clear(tree, k, node, px, py, pz, j, bvh, leaf):
    """No image of the time-tree node can be occluded: the segments ``p -> r_i`` lie
    in the cone around ``r_m - p`` of half-angle ``asin(e_r / |r_m - p|)``
    (``|r_i - r_m| <= e_r``) and no face meets it (:func:`~ideas_hpc.core.mapping.bvh.cone_clear`).
    False means unknown (the images are then ray-tested one by one)."""
    NF = tree.NF
    vx = NF[k, node, 9] - px
    vy = NF[k, node, 10] - py
    vz = NF[k, node, 11] - pz
    dist = np.sqrt(vx * vx + vy * vy + vz * vz)
    er = NF[k, node, 14]
    if not er < 0.5 * dist:
        return False
    alpha = np.arcsin(er / dist)
    if alpha > _CONE_MAX and not leaf:
        return False
    return cone_clear(bvh.node_bounds_m, bvh.node_info, bvh.tri_m, bvh.tri_vid, px, py, pz,
                      vx / dist, vy / dist, vz / dist, alpha, j)


@njit(cache=True, inline="always")
def _lit(j, i, lc, px, py, pz, nx, ny, nz, sun_T, bvh):
    """Vertex ``j`` lit at image ``i`` (cached in ``lc``: 0 unknown, 1 lit, 2 dark)."""
    if lc[i] == 0:
        node_bounds, node_info, tri, tri_vid = bvh
        sx = sun_T[i, 0]
        sy = sun_T[i, 1]
        sz = sun_T[i, 2]
        ok = sx * nx + sy * ny + sz * nz > 0.0
        if ok:
            ok = not segment_blocked(node_bounds, node_info, tri, tri_vid, px, py, pz,
                                     sx, sy, sz, np.inf, np.int64(j))
        lc[i] = 1 if ok else 2
    return lc[i] == 1


@njit(cache=True)
def quality_tests(quality):
    """The fields of the :class:`~ideas_hpc.core.mapping.records.QualityTests` of a
    :class:`~ideas_hpc.core.mapping.records.Quality` (build it with
    ``QualityTests(*quality_tests(quality))``, see
    :func:`~ideas_hpc.core.mapping.time_tree.scan_tree`).

    The tests add whether any angle limit is set and the cosines of the
    emission, incidence and phase limits (-2 when a limit is not set: the
    cosine test then always holds).
    """
    limits = quality.limits
    check_ang = limits[L_EMI] < np.inf or limits[L_INC] < np.inf or limits[L_PHA] < np.inf
    c_emi = np.cos(limits[L_EMI]) if limits[L_EMI] < np.inf else -2.0
    c_inc = np.cos(limits[L_INC]) if limits[L_INC] < np.inf else -2.0
    c_pha = np.cos(limits[L_PHA]) if limits[L_PHA] < np.inf else -2.0
    return quality.rho_rad, limits, quality.require_lit, check_ang, c_emi, c_inc, c_pha


@njit(cache=True)
def _scan(j, k, tree, stack, lc, mesh, cam, opts, bvh, tests, U, state):
    """Every observation of vertex ``j`` by spacecraft ``k`` (time-tree pruned), folded in.

    ``state`` is the running per-vertex
    :class:`~ideas_hpc.core.mapping.records.Observations` of
    :func:`ideas_hpc.core.mapping.quality.quality_vertices`; the scan returns it
    updated: ``m`` usable unit lines of sight appended to ``U``, ``lit``, the
    observation count, the first time, the best resolution and its spacecraft
    and image; plus ``seen_k`` (k observed the vertex) and ``usable_k`` (one of
    k's observations meets every limit of ``tests``, a
    :class:`~ideas_hpc.core.mapping.records.QualityTests`). ``lc`` caches lighting
    per image for this vertex (it does not depend on the spacecraft).
    """
    NI = tree.NI
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    r_T = cam.r_T_m
    image_times = cam.times_s
    occlusion = opts.occlusion
    illumination = opts.illumination
    sun_T = opts.sun_T
    rho = tests.rho_rad
    limits = tests.limits
    check_ang = tests.check_ang
    c_emi = tests.c_emi
    c_inc = tests.c_inc
    c_pha = tests.c_pha
    require_lit = tests.require_lit
    m = state.m
    vlit = state.lit
    cnt = state.count
    first = state.first_s
    bres = state.best_res_m
    bk = state.best_k
    bi = state.best_i
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    nx = normals[j, 0]
    ny = normals[j, 1]
    nz = normals[j, 2]
    nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
    seen_k = False
    usable_k = False
    sp = 1
    stack[0] = NI.shape[0] - 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        cls = _classify(tree, k, node, px, py, pz, nx, ny, nz, nabs, cam)
        if cls == 0:
            continue
        # occlusion: one cone query can clear a whole run of images
        occl = occlusion
        leaf = NI[node, 2] < 0
        if occl and (cls == 2 or leaf):
            occl = not _run_clear(tree, k, node, px, py, pz, j, bvh, leaf)
        if (cls == 1 or occl) and not leaf:
            if NI[node, 3] >= 0:
                stack[sp] = NI[node, 3]
                sp += 1
            stack[sp] = NI[node, 2]
            sp += 1
            continue
        for i in range(NI[node, 0], NI[node, 1]):
            if not _seen(j, k, i, mesh, cam, opts, bvh, occl, False):
                continue
            li = False
            if illumination or not vlit:
                li = _lit(j, i, lc, px, py, pz, nx, ny, nz, sun_T, bvh)
                if illumination and not li:
                    continue
                vlit = vlit or li
            cnt += 1
            first = min(first, image_times[i])
            seen_k = True
            lx = r_T[k, i, 0] - px
            ly = r_T[k, i, 1] - py
            lz = r_T[k, i, 2] - pz
            ln = lx * nx + ly * ny + lz * nz
            rng2 = lx * lx + ly * ly + lz * lz
            res = rho * rng2 / ln if ln > 0.0 else np.inf
            if res < bres or bk < 0:
                bres = res
                bk = k
                bi = i
            # limits first, the (cached) shadow ray last
            ok = res <= limits[L_RES]
            rng = np.sqrt(rng2)
            if ok and check_ang:
                sx = sun_T[i, 0]
                sy = sun_T[i, 1]
                sz = sun_T[i, 2]
                ok = (ln >= c_emi * rng * nabs
                      and sx * nx + sy * ny + sz * nz >= c_inc * nabs
                      and sx * lx + sy * ly + sz * lz >= c_pha * rng)
            if ok and require_lit:
                ok = _lit(j, i, lc, px, py, pz, nx, ny, nz, sun_T, bvh)
            if ok:
                usable_k = True
                U[m, 0] = lx / rng
                U[m, 1] = ly / rng
                U[m, 2] = lz / rng
                m += 1
    return Observations(m, vlit, cnt, first, bres, bk, bi, seen_k, usable_k)
