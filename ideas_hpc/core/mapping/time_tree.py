"""Time coherence of image sequences: trees of image runs with motion bounds.

Speed (see ``benchmarks/bench_coverage.py``): camera position and attitude
change slowly from image to image, so :func:`time_tree` groups each
spacecraft's images into a binary tree of runs with rigorous bounds on how
far the camera coordinates ``q`` of any vertex can move inside a run (the
derivation is in :mod:`~ideas_hpc.core.mapping.time_tree_build`). For each (vertex, spacecraft) the
kernels walk the tree: a run whose reference image passes every condition
with margin larger than the bound is accepted whole, one that fails a
condition by more than the bound is skipped, other runs are split, and leaf
runs are tested image by image with the exact expressions. The bounds carry
floating-point slack, so the results are identical to testing every image
(tests compare bit for bit with an un-pruned evaluation, including vertices
placed on a clipping or culling plane and fast-spinning or jumping cameras).
With strict options the tree only prunes (culling and clipping are
necessary), the images of accepted runs still go through the ray queries.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.mapping.records import Sightings
# the tree is built there and walked here; its builders are re-exported (__all__)
from ideas_hpc.core.mapping.time_tree_build import (_AX, LEAF, dcm_gap2, fill_tree, gap,
                                                    gram_error2, scan_tree, scan_tree_unfilled,
                                                    time_tree)
from ideas_hpc.core.mapping.visibility import _seen_basic, _seen_hint

__all__ = ["_AX", "LEAF", "_FP", "_below_elevation", "_classify", "_scan", "dcm_gap2",
           "fill_tree", "gap", "gram_error2", "scan_tree", "scan_tree_unfilled", "time_tree"]


#: Relative floating-point slack of the node tests. The per-image tests round
#: q, r . n and t q_z with errors of a few ulp of |p - r| (resp. |r| |n|);
#: 1e-10 of those scales is ~1e6 times more than needed.
_FP = 1e-10


@njit(cache=True, inline="always")
def _classify(tree, k, node, px, py, pz, nx, ny, nz, nabs, cam):
    """0: no image of the node can see the vertex, 2: every image sees it, 1: unknown.

    ``tree``: :class:`~ideas_hpc.core.mapping.records.TimeTree` (its ``NF`` may
    carry inflated bounds), ``cam``: :class:`~ideas_hpc.core.mapping.records.Camera`.
    """
    NF = tree.NF
    sec_eta = tree.sec_eta
    tan_eta = cam.tan_eta
    near = cam.near_m
    far = cam.far_m
    exact = cam.exact
    dx = px - NF[k, node, 9]
    dy = py - NF[k, node, 10]
    dz = pz - NF[k, node, 11]
    dn = np.sqrt(dx * dx + dy * dy + dz * dz)
    er = NF[k, node, 14]
    delta = NF[k, node, 13] * dn + er
    fp = _FP * (dn + er)
    # per camera axis (derivation above), never looser than delta
    far_r = dn + NF[k, node, _AX + 3]
    d_x = min(delta, NF[k, node, _AX] * far_r + NF[k, node, _AX + 4])
    d_y = min(delta, NF[k, node, _AX + 1] * far_r + NF[k, node, _AX + 5])
    d_z = min(delta, NF[k, node, _AX + 2] * far_r + NF[k, node, _AX + 6])
    m1 = d_z + fp
    m2x = min(sec_eta * delta, d_x + tan_eta * d_z) + (1.0 + tan_eta) * fp
    m2y = min(sec_eta * delta, d_y + tan_eta * d_z) + (1.0 + tan_eta) * fp
    qx = NF[k, node, 0] * dx + NF[k, node, 1] * dy + NF[k, node, 2] * dz
    qy = NF[k, node, 3] * dx + NF[k, node, 4] * dy + NF[k, node, 5] * dz
    qz = NF[k, node, 6] * dx + NF[k, node, 7] * dy + NF[k, node, 8] * dz
    if exact:
        cul = -(dx * nx + dy * ny + dz * nz)
        mc = nabs * (er + _FP * (dn + er))
    else:
        cul = NF[k, node, 9] * nx + NF[k, node, 10] * ny + NF[k, node, 11] * nz
        mc = nabs * (er + _FP * (NF[k, node, 12] + er))
    tz = tan_eta * qz
    sx = tz - abs(qx)
    sy = tz - abs(qy)
    if (cul < -mc) or (qz - near < -m1) or (far - qz < -m1) or (sx < -m2x) or (sy < -m2y):
        return 0
    if (cul > mc) and (qz - near > m1) and (far - qz > m1) and (sx > m2x) and (sy > m2y):
        return 2
    return 1


@njit(cache=True, inline="always")
def _scan(j, k, tree, stack, best, early, mesh, cam, strict, bvh, opts):
    """Sightings of vertex ``j`` by spacecraft ``k``, as a
    :class:`~ideas_hpc.core.mapping.records.Sightings` (count, earliest time).

    Depth-first over the time tree in image order. ``early``: skip images at
    or after ``best`` and stop at the first hit. ``strict``: the node test only
    prunes (culling and clipping are necessary conditions), images of
    accepted nodes still go through
    :func:`~ideas_hpc.core.mapping.visibility._seen_hint` with the options of
    ``opts`` (a :class:`~ideas_hpc.core.mapping.records.Strict`): the
    occlusion query starts at the face that blocked the scan's previous image
    (issue 19 item 5).
    """
    NI = tree.NI
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    image_times = cam.times_s
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    nx = normals[j, 0]
    ny = normals[j, 1]
    nz = normals[j, 2]
    nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
    cnt = 0
    hint = np.int64(-1)
    sp = 1
    stack[0] = NI.shape[0] - 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        i0 = NI[node, 0]
        i1 = NI[node, 1]
        if early and image_times[i0] >= best:
            continue
        cls = _classify(tree, k, node, px, py, pz, nx, ny, nz, nabs, cam)
        if cls == 0:
            continue
        if cls == 2 and not strict:
            cnt += i1 - i0
            best = min(best, image_times[i0])
            continue
        if cls == 1 and NI[node, 2] >= 0:
            if NI[node, 3] >= 0:
                stack[sp] = NI[node, 3]
                sp += 1
            stack[sp] = NI[node, 2]
            sp += 1
            continue
        for i in range(i0, i1):
            if early and image_times[i] >= best:
                break
            if strict:
                # occlusion starts at the face that blocked the previous image
                hit, hint = _seen_hint(j, k, i, hint, mesh, cam, opts, bvh)
            else:
                hit = _seen_basic(px, py, pz, nx, ny, nz, k, i, cam)
            if hit:
                cnt += 1
                best = min(best, image_times[i])
                if early:
                    break
    return Sightings(cnt, best)


@njit(cache=True, inline="always")
def _below_elevation(NF, k, node, px, py, pz, nx, ny, nz, nabs, sin_min_elev, max_range):
    """True when every image of the node fails the elevation or the range test.

    With ``|r_k - r_m| <= e_r``: ``(r_k - p) . n <= (r_m - p) . n + |n| e_r`` and
    ``|r_k - p| >= |r_m - p| - e_r``.
    """
    vx = NF[k, node, 9] - px
    vy = NF[k, node, 10] - py
    vz = NF[k, node, 11] - pz
    dist = np.sqrt(vx * vx + vy * vy + vz * vz)
    er = NF[k, node, 14]
    fp = _FP * (dist + er + NF[k, node, 12])
    if dist - er - fp > max_range:
        return True
    if sin_min_elev <= 0.0:
        return False
    los_hi = vx * nx + vy * ny + vz * nz + nabs * er + fp
    return los_hi < (dist - er - fp) * sin_min_elev
