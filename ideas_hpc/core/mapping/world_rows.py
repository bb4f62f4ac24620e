"""Rows of one world: its lighting once, then each candidate's first usable image (issue 43).

A world of a target prior (SPEC 7f) has its own shape, so no candidate's rows can be
proved from another world's flight; but every candidate of the world flies around
the same mesh under the same Sun. Two things are therefore the world's, not the
candidate's:

* **lighting** (:func:`lit_at_images`): vertex ``j`` is lit at image ``i`` when
  ``n_j . s_i > 0`` and the ray ``p_j + t s_i, t > 0`` crosses no face (the test of
  :func:`ideas_hpc.core.mapping.observations._lit`). Over an encounter the Sun turns
  slowly in the body frame (Eros-class, 20 s: 0.4 deg), so the images are cut into
  runs whose Sun directions lie in a cone of half-angle at most :data:`SUN_CONE_MAX`;
  one :func:`~ideas_hpc.core.mapping.bvh.cone_clear` query per (vertex, run) proves
  the whole run unshadowed (a cleared cone is never one the exact ray test would
  block), and only the vertices whose cone is not cleared cast rays, image by image,
  starting at the face that shadowed the previous image (any crossed face answers the
  any-hit query). The table is the exact per-image test, bit for bit.
* the mesh, its normals and its BVH (built by the boundary, once per world).

A row of the quality pass with a requirement and no stereo is ``mapped[k, j] =
usable[k, j]``: some image of candidate ``k`` observes vertex ``j`` (culling,
clipping, elevation, range, occlusion, and lit when illumination is a filter) and
meets every per-image limit (lit, ``X <= X_max``, the angle cosines), as
:func:`ideas_hpc.core.mapping.quality_masks.quality_by_spacecraft` decides it. That
kernel visits every observation (it also returns the best resolution and the stereo
directions); a row needs one usable image. :func:`mapped_by_spacecraft` walks the same
time tree (:func:`~ideas_hpc.core.mapping.time_tree._classify` prunes runs that
cannot see the vertex) and stops at the first usable image, testing each image's
conditions cheapest first: the lighting table, the geometric tests, the limits, and
last the occlusion ray (from the face that blocked the previous image). Each
condition is the quality pass's own expression, evaluated on the same floats, and a
row is their conjunction's disjunction over images, so the order changes nothing:
the rows are identical to the quality pass's ``mapped``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.bvh import cone_clear
from ideas_hpc.core.mapping.observations import L_EMI, L_INC, L_PHA, L_RES
from ideas_hpc.core.mapping.records import TimeTree
from ideas_hpc.core.mapping.segments import face_hit, segment_hit
from ideas_hpc.core.mapping.time_tree import _classify, scan_tree
from ideas_hpc.core.mapping.visibility import _seen

#: Largest half-angle (rad) of the Sun directions of one lighting run: wider cones
#: rarely clear and cost a longer BVH walk (speed only; the table does not depend on it).
SUN_CONE_MAX = 0.01
#: Candidates per parallel chunk of :func:`mapped_by_spacecraft`.
_CHUNK = 64


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
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    nv = vertices.shape[0]
    nimg = sun_T.shape[0]
    start, axis, half = sun_runs(sun_T, SUN_CONE_MAX)
    nrun = half.shape[0]
    lit = np.zeros((nv, nimg), dtype=np.bool_)
    tree = (bvh.node_bounds_m, bvh.node_info, bvh.tri_m, bvh.tri_vid)
    for j in prange(nv):
        px = vertices[j, 0]
        py = vertices[j, 1]
        pz = vertices[j, 2]
        nx = normals[j, 0]
        ny = normals[j, 1]
        nz = normals[j, 2]
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
                f = segment_hit(tree, px, py, pz, sx, sy, sz, np.inf, np.int64(j), hint)
                if f >= 0:
                    hint = f
                else:
                    lit[j, i] = True
    return lit


@njit(cache=True, inline="always")
def _usable(j, k, i, mesh, cam, opts, tests, lit, hint, bvh):
    """``(usable, hint)``: image ``i`` of candidate ``k`` is a usable observation of
    vertex ``j`` (module docstring), its conditions cheapest first; ``hint`` the face
    that blocked the last occlusion ray (updated)."""
    need_lit = opts.illumination or tests.require_lit
    if need_lit and not lit[j, i]:
        return False, hint
    if not _seen(j, k, i, mesh, cam, opts, bvh, False, False):
        return False, hint
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    r_T = cam.r_T_m
    sun_T = opts.sun_T
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    nx = normals[j, 0]
    ny = normals[j, 1]
    nz = normals[j, 2]
    # the quality pass's expressions (observations._scan), on the same floats
    lx = r_T[k, i, 0] - px
    ly = r_T[k, i, 1] - py
    lz = r_T[k, i, 2] - pz
    ln = lx * nx + ly * ny + lz * nz
    rng2 = lx * lx + ly * ly + lz * lz
    res = tests.rho_rad * rng2 / ln if ln > 0.0 else np.inf
    if not res <= tests.limits[L_RES]:
        return False, hint
    if tests.check_ang:
        nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
        rng = np.sqrt(rng2)
        sx = sun_T[i, 0]
        sy = sun_T[i, 1]
        sz = sun_T[i, 2]
        if not (ln >= tests.c_emi * rng * nabs
                and sx * nx + sy * ny + sz * nz >= tests.c_inc * nabs
                and sx * lx + sy * ly + sz * lz >= tests.c_pha * rng):
            return False, hint
    if opts.occlusion:
        f = segment_hit(bvh, px, py, pz, -(px - r_T[k, i, 0]), -(py - r_T[k, i, 1]),
                        -(pz - r_T[k, i, 2]), 1.0, np.int64(j), hint)
        if f >= 0:
            return False, f
    return True, hint


@njit(cache=True)
def _first_usable(j, k, tree, stack, mesh, cam, opts, bvh, tests, lit):
    """The first usable image of vertex ``j`` by candidate ``k`` (-1: none): the time
    tree's walk in image order (runs that cannot see the vertex are skipped)."""
    NI = tree.NI
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    nx = normals[j, 0]
    ny = normals[j, 1]
    nz = normals[j, 2]
    nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
    hint = np.int64(-1)
    sp = 1
    stack[0] = NI.shape[0] - 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        cls = _classify(tree, k, node, px, py, pz, nx, ny, nz, nabs, cam)
        if cls == 0:
            continue
        if cls == 1 and NI[node, 2] >= 0:
            if NI[node, 3] >= 0:
                stack[sp] = NI[node, 3]
                sp += 1
            stack[sp] = NI[node, 2]
            sp += 1
            continue
        for i in range(NI[node, 0], NI[node, 1]):
            ok, hint = _usable(j, k, i, mesh, cam, opts, tests, lit, hint, bvh)
            if ok:
                return i
    return -1


@njit(cache=True)
def pass_chords(r_T):
    """(K, 2) float64: per candidate the half-width (m) of the pass about its chord
    (the largest distance from a position ``r_T[k, i]`` to the segment from the first
    to the last), inflated by ``1e-9`` relative and ``1e-9 max |r|`` absolute, and the
    floating-point allowance of the culling value ``(r - p) . n`` (m per unit normal):
    ``1e-9`` of the largest ``|r|``.

    Every position lies within the half-width of the chord, on which ``r . n`` is
    linear, so ``max_i (r_i - p) . n <= max((r_0 - p) . n, (r_last - p) . n) + |n| w``:
    a vertex for which this bound is below minus the allowance faces away from the
    candidate at every image (:func:`_faces_away`)."""
    nsc = r_T.shape[0]
    nimg = r_T.shape[1]
    out = np.empty((nsc, 2))
    for k in range(nsc):
        ax = r_T[k, 0, 0]
        ay = r_T[k, 0, 1]
        az = r_T[k, 0, 2]
        ex = r_T[k, nimg - 1, 0] - ax
        ey = r_T[k, nimg - 1, 1] - ay
        ez = r_T[k, nimg - 1, 2] - az
        ee = ex * ex + ey * ey + ez * ez
        w = 0.0
        rmax = 0.0
        for i in range(nimg):
            x = r_T[k, i, 0] - ax
            y = r_T[k, i, 1] - ay
            z = r_T[k, i, 2] - az
            t = (x * ex + y * ey + z * ez) / ee if ee > 0.0 else 0.0
            t = min(1.0, max(0.0, t))
            x -= t * ex
            y -= t * ey
            z -= t * ez
            w = max(w, np.sqrt(x * x + y * y + z * z))
            rmax = max(rmax, np.sqrt(r_T[k, i, 0] ** 2 + r_T[k, i, 1] ** 2 + r_T[k, i, 2] ** 2))
        out[k, 0] = w * (1.0 + 1e-9) + 1e-9 * rmax
        out[k, 1] = 1e-9 * rmax
    return out


@njit(cache=True, inline="always")
def _faces_away(j, k, mesh, r_T, chords):
    """Vertex ``j`` fails exact culling ``(r - p) . n > 0`` at every image of candidate
    ``k`` (:func:`pass_chords`; the allowance also covers ``|p|``)."""
    p = mesh.vertices_T_m
    n = mesh.normals_T
    nx = n[j, 0]
    ny = n[j, 1]
    nz = n[j, 2]
    last = r_T.shape[1] - 1
    pn = p[j, 0] * nx + p[j, 1] * ny + p[j, 2] * nz
    c0 = r_T[k, 0, 0] * nx + r_T[k, 0, 1] * ny + r_T[k, 0, 2] * nz
    c1 = r_T[k, last, 0] * nx + r_T[k, last, 1] * ny + r_T[k, last, 2] * nz
    nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
    pabs = np.sqrt(p[j, 0] ** 2 + p[j, 1] ** 2 + p[j, 2] ** 2)
    return max(c0, c1) - pn + nabs * (chords[k, 0] + chords[k, 1] + 1e-9 * pabs) < 0.0


@njit(parallel=True, cache=True)
def mapped_by_spacecraft(mesh, cam, opts, bvh, tests, lit):
    """(K, V) bool: candidate ``k`` maps vertex ``j`` on its own (module docstring): the
    ``usable`` (and, without a stereo requirement, ``mapped``) rows of
    :func:`~ideas_hpc.core.mapping.quality_masks.quality_by_spacecraft`, identical.

    Candidates are the outer loop (one candidate's flight and time tree stay in cache
    while the vertices stream by), and the image at which the previous candidate of the
    chunk found vertex ``j`` usable is tried first: neighbouring candidates of the ring
    see a vertex at nearly the same time, and any usable image decides the row.

    Parameters
    ----------
    mesh, cam, opts, bvh
        As in :func:`~ideas_hpc.core.mapping.quality_masks.quality_by_spacecraft`.
    tests : :class:`~ideas_hpc.core.mapping.records.QualityTests`
        The requirement's per-image tests
        (:func:`~ideas_hpc.core.mapping.observations.quality_tests`).
    lit : (V, n_img) bool
        :func:`lit_at_images` of the mesh under ``opts.sun_T`` (read only when
        illumination is a filter or the requirement asks for light).
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    tree = TimeTree(*scan_tree(cam))
    need_lit = opts.illumination or tests.require_lit
    # the vertices some image lights (the others: no candidate maps them)
    live = np.empty(nv, dtype=np.int64)
    nlive = 0
    for j in range(nv):
        if not need_lit or lit[j].any():
            live[nlive] = j
            nlive += 1
    chords = pass_chords(cam.r_T_m)
    out = np.zeros((nsc, nv), dtype=np.bool_)
    nchunk = (nsc + _CHUNK - 1) // _CHUNK
    for ch in prange(nchunk):
        stack = np.empty(128, dtype=np.int64)
        guess = np.full(nv, -1, dtype=np.int64)
        for k in range(ch * _CHUNK, min(nsc, (ch + 1) * _CHUNK)):
            for q in range(nlive):
                j = live[q]
                g = guess[j]
                if g >= 0:
                    ok, _ = _usable(j, k, g, mesh, cam, opts, tests, lit, np.int64(-1), bvh)
                    if ok:
                        out[k, j] = True
                        continue
                if cam.exact and _faces_away(j, k, mesh, cam.r_T_m, chords):
                    continue
                g = _first_usable(j, k, tree, stack, mesh, cam, opts, bvh, tests, lit)
                if g >= 0:
                    out[k, j] = True
                    guess[j] = g
    return out
