"""Rows of one world: each candidate's first usable image, from the world's statics (issue 43).

A world of a target prior (SPEC 7f) has its own shape, so no candidate's rows can be
proved from another world's flight; but every candidate of the world flies around the
same mesh under the same Sun, and what that fixes is built once per world
(:mod:`ideas_hpc.core.mapping.world_statics`: the lighting at every image and each
vertex's clear cone).

A row of the quality pass with a requirement and no stereo is ``mapped[k, j] =
usable[k, j]``: some image of candidate ``k`` observes vertex ``j`` (culling,
clipping, elevation, range, occlusion, and lit when illumination is a filter) and
meets every per-image limit (lit, ``X <= X_max``, the angle cosines), as
:func:`ideas_hpc.core.mapping.quality_masks.quality_by_spacecraft` decides it. That
kernel visits every observation (it also returns the best resolution and the stereo
directions); a row needs one usable image. :func:`mapped_by_spacecraft`

* skips the vertices that no image lights (when light is needed);
* tries first the image at which the previous candidate of its chunk found the vertex
  usable (neighbouring candidates of the ring see a vertex at nearly the same time);
* else walks the candidate's pass tree (:mod:`ideas_hpc.core.mapping.pass_tree`) in
  image order, skipping runs that no image of can see the vertex, and stops at the
  first usable image;

and tests each image's conditions cheapest first: the lighting table, the geometric
tests, the limits, and last the occlusion ray (none inside the vertex's clear cone;
else from the face that blocked the previous image). Each condition is the quality
pass's own expression on the same floats, or a proof that it holds or fails, and a
row is the disjunction over images of their conjunction, so neither the order nor
the skipped work changes it: the rows are identical to the quality pass's ``mapped``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.observations import L_RES
from ideas_hpc.core.mapping.scenario_proofs import _vertex
from ideas_hpc.core.mapping.pass_tree import LEAF, pass_runs, pass_tree, run_rejected
from ideas_hpc.core.mapping.segments import segment_hit
from ideas_hpc.core.mapping.visibility import _seen

#: Candidates per parallel chunk of :func:`mapped_by_spacecraft`.
_CHUNK = 64


@njit(cache=True, inline="always")
def limits_met(tests, sun_T, i, lx, ly, lz, nx, ny, nz):
    """``(met, l_dot_n, l_sq)``: whether image ``i``'s line of sight ``l = r - p`` (m) to a
    vertex of normal ``n`` meets the per-image limits of ``tests``, with ``l_dot_n`` the dot
    product of ``l`` and ``n`` and ``l_sq`` the square of ``|l|``.

    ``tests`` is a :class:`~ideas_hpc.core.mapping.records.QualityTests`, ``sun_T`` the unit
    Sun directions per image. The limits: the resolution ``rho l_sq / l_dot_n <= X_max``,
    then the emission, incidence and phase cosines, the quality pass's expressions
    (:func:`ideas_hpc.core.mapping.observations._scan`) on the same floats. Shared with
    the CUDA kernel (:mod:`ideas_hpc.core.mapping.world_rows_cuda`)."""
    ln = lx * nx + ly * ny + lz * nz
    rng2 = lx * lx + ly * ly + lz * lz
    res = tests.rho_rad * rng2 / ln if ln > 0.0 else np.inf
    if not res <= tests.limits[L_RES]:
        return False, ln, rng2
    if tests.check_ang:
        nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
        rng = np.sqrt(rng2)
        sx = sun_T[i, 0]
        sy = sun_T[i, 1]
        sz = sun_T[i, 2]
        if not (ln >= tests.c_emi * rng * nabs
                and sx * nx + sy * ny + sz * nz >= tests.c_inc * nabs
                and sx * lx + sy * ly + sz * lz >= tests.c_pha * rng):
            return False, ln, rng2
    return True, ln, rng2


@njit(cache=True, inline="always")
def _usable(j, k, i, mesh, cam, opts, tests, light, hint, bvh):
    """``(usable, hint)``: image ``i`` of candidate ``k`` is a usable observation of
    vertex ``j`` (module docstring), its conditions cheapest first; ``hint`` the face
    that blocked the last occlusion ray (updated)."""
    lit, cos_clear = light
    need_lit = opts.illumination or tests.require_lit
    if need_lit and not lit[j, i]:
        return False, hint
    if not _seen(j, k, i, mesh, cam, opts, bvh, False, False):
        return False, hint
    r_T = cam.r_T_m
    px, py, pz, nx, ny, nz, _ = _vertex(mesh, j)
    ok, ln, rng2 = limits_met(tests, opts.sun_T, i, r_T[k, i, 0] - px, r_T[k, i, 1] - py,
                              r_T[k, i, 2] - pz, nx, ny, nz)
    if not ok:
        return False, hint
    if opts.occlusion and not ln >= np.sqrt(rng2) * np.sqrt(nx * nx + ny * ny + nz * nz) \
            * cos_clear[j]:
        # outside the vertex's clear cone (world_statics.clear_cones): cast the ray
        f = segment_hit(bvh, px, py, pz, -(px - r_T[k, i, 0]), -(py - r_T[k, i, 1]),
                        -(pz - r_T[k, i, 2]), 1.0, np.int64(j), hint)
        if f >= 0:
            return False, f
    return True, hint


@njit(cache=True)
def _first_usable(j, k, tree, runs, stack, mesh, cam, opts, bvh, tests, light):
    """The first usable image of vertex ``j`` by candidate ``k`` (-1: none): the walk of
    its pass tree (:mod:`ideas_hpc.core.mapping.pass_tree`) in image order, runs that no
    image of can see the vertex skipped."""
    r_T = cam.r_T_m
    px, py, pz, nx, ny, nz, _ = _vertex(mesh, j)
    hint = np.int64(-1)
    sp = 1
    stack[0] = 0
    while sp > 0:
        sp -= 1
        d = stack[sp]
        if run_rejected(tree, runs, k, d, r_T, px, py, pz, nx, ny, nz, cam):
            continue
        if runs[d, 1] - runs[d, 0] > LEAF:
            stack[sp] = 2 * d + 2
            stack[sp + 1] = 2 * d + 1
            sp += 2
            continue
        for i in range(runs[d, 0], runs[d, 1]):
            ok, hint = _usable(j, k, i, mesh, cam, opts, tests, light, hint, bvh)
            if ok:
                return i
    return -1


@njit(parallel=True, cache=True)
def mapped_by_spacecraft(mesh, cam, opts, bvh, tests, lit, cos_clear):
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
        :func:`~ideas_hpc.core.mapping.world_statics.lit_at_images` of the mesh under
        ``opts.sun_T`` (read only when illumination is a filter or the requirement asks
        for light).
    cos_clear : (V,) float64
        :func:`~ideas_hpc.core.mapping.world_statics.clear_cones` of the mesh (read only
        with occlusion).
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    runs = pass_runs(cam.r_T_m.shape[1])
    tree = pass_tree(cam.r_T_m, cam.dcm_BT, runs)
    need_lit = opts.illumination or tests.require_lit
    light = (lit, cos_clear)
    # the vertices some image lights (the others: no candidate maps them)
    live = np.empty(nv, dtype=np.int64)
    nlive = 0
    for j in range(nv):
        if not need_lit or lit[j].any():
            live[nlive] = j
            nlive += 1
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
                    ok, _ = _usable(j, k, g, mesh, cam, opts, tests, light, np.int64(-1),
                                    bvh)
                    if ok:
                        out[k, j] = True
                        continue
                g = _first_usable(j, k, tree, runs, stack, mesh, cam, opts, bvh, tests, light)
                if g >= 0:
                    out[k, j] = True
                    guess[j] = g
    return out
