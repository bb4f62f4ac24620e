"""Visibility of one (vertex, spacecraft, image) triple (SPEC section 6).

For spacecraft ``k`` at image ``i`` (position ``r = r_T[k, i]`` in frame T, m;
camera DCM ``C = dcm_BT[k, i]``, B <- T) a vertex ``p_j`` with unit normal
``n_j`` is *seen* when it passes

culling (paper section "Mapping operation", Fig. 15)
    * paper mode: ``r . n_j >= 0``. The paper writes ``l_i . n_j <= 0`` with the
      line of sight ``l_i = -r_i`` taken from the spacecraft toward the body
      centre, i.e. ``r_i . n_j >= 0``. That sign is the physically right one: a
      surface element faces a spacecraft when its outward normal has a positive
      component toward the spacecraft. It is the exact test with the vertex moved
      to the body centre (the view from far away), so it keeps vertices on the
      limb that the exact test rejects and vice versa near the poles of view.
    * exact mode: ``(r - p_j) . n_j > 0`` (the vertex faces the camera).

clipping (paper eq. 25)
    ``q = C (p_j - r)`` in camera axes; with ``t = tan(eta)``,
    ``a = q_x / (q_z t)``, ``b = q_y / (q_z t)``,
    ``c = ((f + n) q_z - 2 f n) / ((f - n) q_z)``; seen when ``q_z > 0`` and
    ``|a|, |b|, |c| <= 1``. For ``q_z > 0`` and ``f > n > 0`` this is exactly
    ``|q_x| <= t q_z``, ``|q_y| <= t q_z`` and ``n <= q_z <= f``, which the
    kernels evaluate instead (no division, and no cancellation in ``c`` when
    ``n / f`` is ~1e-9 as in the paper case).

strict options (beyond the paper, SPEC section 6), each off in paper mode
    * self-occlusion: the segment ``p_j -> r`` crosses no face other than those
      that contain ``p_j`` (BVH any-hit query, :mod:`ideas_hpc.core.mapping.bvh`);
    * illumination: ``n_j . s > 0`` for the unit Sun direction ``s`` of the
      image, and the ray ``p_j + t s, t > 0`` crosses no face (not shadowed);
    * minimum elevation ``eps``: the angle between the line of sight ``r - p_j``
      and the local horizontal (plane normal to ``n_j``) is ``>= eps``:
      ``(r - p_j) . n_j >= |r - p_j| sin(eps)``;
    * ground resolution: ``lambda |r - p_j| / D <= X``, passed as a maximum
      range ``X D / lambda`` (m).

These per-image tests are the exact expressions; :mod:`ideas_hpc.core.mapping.time_tree`
applies them to runs of images at once and :mod:`ideas_hpc.core.mapping.coverage`
reduces them over vertices, spacecraft and images.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.mapping.bvh import segment_blocked
from ideas_hpc.core.mapping.segments import face_hit, segment_hit


@njit(cache=True, inline="always")
def _seen(j, k, i, mesh, cam, opts, bvh, occlusion, illumination):
    """True when vertex ``j`` is seen by spacecraft ``k`` in image ``i`` (all tests).

    ``mesh``, ``cam``, ``opts`` (:class:`~ideas_hpc.core.mapping.records.Strict`),
    ``bvh``: :mod:`ideas_hpc.core.mapping.records`; ``occlusion`` and
    ``illumination`` switch those tests (callers pass ``opts``' flags or turn one off).
    """
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    r_T = cam.r_T_m
    dcm_BT = cam.dcm_BT
    tan_eta = cam.tan_eta
    near = cam.near_m
    far = cam.far_m
    exact = cam.exact
    sin_min_elev = opts.sin_min_elev
    max_range = opts.max_range_m
    sun_T = opts.sun_T
    node_bounds, node_info, tri, tri_vid = bvh
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    nx = normals[j, 0]
    ny = normals[j, 1]
    nz = normals[j, 2]
    rx = r_T[k, i, 0]
    ry = r_T[k, i, 1]
    rz = r_T[k, i, 2]
    dx = px - rx
    dy = py - ry
    dz = pz - rz
    # line of sight vertex -> spacecraft is -d
    los_n = (-dx) * nx + (-dy) * ny + (-dz) * nz
    if exact:
        if not los_n > 0.0:
            return False
    elif not rx * nx + ry * ny + rz * nz >= 0.0:
        return False
    qz = dcm_BT[k, i, 2, 0] * dx + dcm_BT[k, i, 2, 1] * dy + dcm_BT[k, i, 2, 2] * dz
    if not (qz > 0.0 and qz >= near and qz <= far):
        return False
    lim = tan_eta * qz
    qx = dcm_BT[k, i, 0, 0] * dx + dcm_BT[k, i, 0, 1] * dy + dcm_BT[k, i, 0, 2] * dz
    if not abs(qx) <= lim:
        return False
    qy = dcm_BT[k, i, 1, 0] * dx + dcm_BT[k, i, 1, 1] * dy + dcm_BT[k, i, 1, 2] * dz
    if not abs(qy) <= lim:
        return False
    if sin_min_elev > -1.0 or max_range < np.inf:
        rng = np.sqrt(dx * dx + dy * dy + dz * dz)
        if not rng <= max_range:
            return False
        if not los_n >= rng * sin_min_elev:
            return False
    if illumination:
        sx = sun_T[i, 0]
        sy = sun_T[i, 1]
        sz = sun_T[i, 2]
        if not sx * nx + sy * ny + sz * nz > 0.0:
            return False
    if occlusion:
        if segment_blocked(node_bounds, node_info, tri, tri_vid, px, py, pz,
                           -dx, -dy, -dz, 1.0, np.int64(j)):
            return False
    if illumination:
        if segment_blocked(node_bounds, node_info, tri, tri_vid, px, py, pz,
                           sun_T[i, 0], sun_T[i, 1], sun_T[i, 2], np.inf, np.int64(j)):
            return False
    return True


@njit(cache=True, inline="always")
def _seen_basic(px, py, pz, nx, ny, nz, k, i, cam):
    """Culling + clipping of one (vertex, spacecraft, image), as in :func:`_seen`."""
    r_T = cam.r_T_m
    dcm_BT = cam.dcm_BT
    tan_eta = cam.tan_eta
    near = cam.near_m
    far = cam.far_m
    exact = cam.exact
    rx = r_T[k, i, 0]
    ry = r_T[k, i, 1]
    rz = r_T[k, i, 2]
    dx = px - rx
    dy = py - ry
    dz = pz - rz
    if exact:
        cul = (-dx) * nx + (-dy) * ny + (-dz) * nz > 0.0
    else:
        cul = rx * nx + ry * ny + rz * nz >= 0.0
    qx = dcm_BT[k, i, 0, 0] * dx + dcm_BT[k, i, 0, 1] * dy + dcm_BT[k, i, 0, 2] * dz
    qy = dcm_BT[k, i, 1, 0] * dx + dcm_BT[k, i, 1, 1] * dy + dcm_BT[k, i, 1, 2] * dz
    qz = dcm_BT[k, i, 2, 0] * dx + dcm_BT[k, i, 2, 1] * dy + dcm_BT[k, i, 2, 2] * dz
    lim = tan_eta * qz
    return (cul & (qz > 0.0) & (abs(qx) <= lim) & (abs(qy) <= lim)
            & (qz >= near) & (qz <= far))


@njit(cache=True, inline="always")
def _seen_hint(j, k, i, hint, mesh, cam, opts, bvh):
    """:func:`_seen` with the occlusion query started at face ``hint`` (-1: none).

    Returns ``(seen, hint)``, ``hint`` updated to the face that blocks, if any.
    Consecutive images of a scan are usually blocked by the same face, so that
    face is tested first, before the geometric tests (a blocked vertex is unseen
    whatever they say: a scenario's scans test 0.8 M such images); any crossed face
    answers the any-hit query, so ``seen`` is exactly ``_seen``'s.
    """
    vertices = mesh.vertices_T_m
    r_T = cam.r_T_m
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    dx = r_T[k, i, 0] - px
    dy = r_T[k, i, 1] - py
    dz = r_T[k, i, 2] - pz
    tri = bvh[2]
    tri_vid = bvh[3]
    if opts.occlusion and hint >= 0 and face_hit(tri, tri_vid, hint, px, py, pz, dx, dy, dz,
                                                 1.0, np.int64(j)):
        return False, hint
    if not _seen(j, k, i, mesh, cam, opts, bvh, False, opts.illumination):
        return False, hint
    if not opts.occlusion:
        return True, hint
    # the hint crosses nothing (tested above): the query starts at the root
    f = segment_hit(bvh, px, py, pz, dx, dy, dz, 1.0, np.int64(j), np.int64(-1))
    if f >= 0:
        return False, f
    return True, hint
