"""Bounding-volume hierarchy over mesh faces for segment/ray occlusion (SPEC section 6).

A binary BVH of axis-aligned boxes, built by median split of the face
centroids along the longest axis of their bounding box, with at most
``LEAF_SIZE`` faces per leaf. Everything is a flat float64/int64 array so the
tree can be passed to compiled kernels and shipped to dask workers:

``node_bounds`` (M, 6) float64
    ``[xmin, ymin, zmin, xmax, ymax, zmax]`` of each node, m.
``node_info`` (M, 4) int64
    ``[left, right, start, count]``: children (``-1`` for a leaf) and, for a
    leaf, the range ``order[start:start+count]`` of its faces.
``tri`` (F, 9) float64
    Per face in tree order: vertex ``a`` and edges ``b - a``, ``c - a`` (m),
    ready for the Moller-Trumbore test.
``tri_vid`` (F, 3) int64
    The vertex indices of each face in tree order, so a ray that starts at a
    mesh vertex can ignore the faces that share it.

The ray/triangle test is Moller & Trumbore (1997), "Fast, minimum storage
ray-triangle intersection", J. Graphics Tools 2(1); the ray/box test is the
slab method (Kay & Kajiya 1986).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.mapping.segments import segment_blocked, segment_hit, segments_blocked

__all__ = ["build_bvh", "cone_clear", "segment_blocked", "segment_hit", "segments_blocked",
           "tri_cone_gap"]

LEAF_SIZE = 4


@njit(cache=True)
def build_bvh(vertices, faces):
    """Build the BVH of a triangle mesh.

    Parameters
    ----------
    vertices : (V, 3) float64
        Vertex positions, m.
    faces : (F, 3) int64
        Vertex indices per face.

    Returns
    -------
    node_bounds : (M, 6) float64
    node_info : (M, 4) int64
    tri : (F, 9) float64
    tri_vid : (F, 3) int64
        See the module docstring.
    """
    nf = faces.shape[0]
    cen = np.empty((nf, 3))
    fmin = np.empty((nf, 3))
    fmax = np.empty((nf, 3))
    for f in range(nf):
        for k in range(3):
            a = vertices[faces[f, 0], k]
            b = vertices[faces[f, 1], k]
            c = vertices[faces[f, 2], k]
            fmin[f, k] = min(a, min(b, c))
            fmax[f, k] = max(a, max(b, c))
            cen[f, k] = (a + b + c) / 3.0
    order = np.arange(nf)
    max_nodes = 2 * nf + 1
    node_bounds = np.empty((max_nodes, 6))
    node_info = np.full((max_nodes, 4), -1, dtype=np.int64)
    # work stack of (node, start, count)
    stack = np.empty((max_nodes, 3), dtype=np.int64)
    sp = 0
    stack[0, 0] = 0
    stack[0, 1] = 0
    stack[0, 2] = nf
    sp = 1
    n_nodes = 1
    while sp > 0:
        sp -= 1
        node = stack[sp, 0]
        start = stack[sp, 1]
        count = stack[sp, 2]
        bmin = np.full(3, np.inf)
        bmax = np.full(3, -np.inf)
        cmin = np.full(3, np.inf)
        cmax = np.full(3, -np.inf)
        for i in range(start, start + count):
            f = order[i]
            for k in range(3):
                bmin[k] = min(bmin[k], fmin[f, k])
                bmax[k] = max(bmax[k], fmax[f, k])
                cmin[k] = min(cmin[k], cen[f, k])
                cmax[k] = max(cmax[k], cen[f, k])
        for k in range(3):
            node_bounds[node, k] = bmin[k]
            node_bounds[node, 3 + k] = bmax[k]
        ext = cmax - cmin
        axis = 0
        if ext[1] > ext[axis]:
            axis = 1
        if ext[2] > ext[axis]:
            axis = 2
        if count <= LEAF_SIZE or ext[axis] <= 0.0:
            node_info[node, 0] = -1
            node_info[node, 1] = -1
            node_info[node, 2] = start
            node_info[node, 3] = count
            continue
        seg = order[start:start + count].copy()
        keys = np.empty(count)
        for i in range(count):
            keys[i] = cen[seg[i], axis]
        srt = np.argsort(keys)
        for i in range(count):
            order[start + i] = seg[srt[i]]
        half = count // 2
        left = n_nodes
        right = n_nodes + 1
        n_nodes += 2
        node_info[node, 0] = left
        node_info[node, 1] = right
        node_info[node, 2] = start
        node_info[node, 3] = count
        stack[sp, 0] = left
        stack[sp, 1] = start
        stack[sp, 2] = half
        sp += 1
        stack[sp, 0] = right
        stack[sp, 1] = start + half
        stack[sp, 2] = count - half
        sp += 1
    tri = np.empty((nf, 9))
    tri_vid = np.empty((nf, 3), dtype=np.int64)
    for i in range(nf):
        f = order[i]
        ia = faces[f, 0]
        ib = faces[f, 1]
        ic = faces[f, 2]
        tri_vid[i, 0] = ia
        tri_vid[i, 1] = ib
        tri_vid[i, 2] = ic
        for k in range(3):
            tri[i, k] = vertices[ia, k]
            tri[i, 3 + k] = vertices[ib, k] - vertices[ia, k]
            tri[i, 6 + k] = vertices[ic, k] - vertices[ia, k]
    return (node_bounds[:n_nodes].copy(), node_info[:n_nodes].copy(), tri, tri_vid)


@njit(cache=True, inline="always")
def _unit(x, y, z):
    n = np.sqrt(x * x + y * y + z * z)
    return x / n, y / n, z / n, n


@njit(cache=True, inline="always")
def _arc_distance(ux, uy, uz, vx, vy, vz, ax, ay, az):
    """Angular distance from unit ``a`` to the great-circle arc between units u, v."""
    nx = uy * vz - uz * vy
    ny = uz * vx - ux * vz
    nz = ux * vy - uy * vx
    nn = np.sqrt(nx * nx + ny * ny + nz * nz)
    # the foot of a on the circle lies in the arc iff (u x a).n >= 0 and (a x v).n >= 0
    f0 = (uy * az - uz * ay) * nx + (uz * ax - ux * az) * ny + (ux * ay - uy * ax) * nz
    f1 = (ay * vz - az * vy) * nx + (az * vx - ax * vz) * ny + (ax * vy - ay * vx) * nz
    if nn > 0.0 and f0 >= 0.0 and f1 >= 0.0:
        return np.arcsin(min(1.0, abs(nx * ax + ny * ay + nz * az) / nn))
    cx = uy * az - uz * ay
    cy = uz * ax - ux * az
    cz = ux * ay - uy * ax
    du = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), ux * ax + uy * ay + uz * az)
    cx = vy * az - vz * ay
    cy = vz * ax - vx * az
    cz = vx * ay - vy * ax
    dv = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), vx * ax + vy * ay + vz * az)
    return min(du, dv)


@njit(cache=True, inline="always")
def tri_cone_gap(px, py, pz, ax, ay, az, tri, i):
    """Angular distance (rad) from the unit axis ``a`` to face ``i`` seen from ``p``: the
    directions from p to the face form the spherical triangle of the unit vectors
    ``w_k`` toward its corners, and the distance is 0 when the axis is inside it (or
    the face is degenerate, or p (nearly) in its plane), else that to the nearest edge
    arc. Every cone of half-angle below it misses the face."""
    x0 = tri[i, 0] - px
    y0 = tri[i, 1] - py
    z0 = tri[i, 2] - pz
    ax0, ay0, az0, n0 = _unit(x0, y0, z0)
    ax1, ay1, az1, n1 = _unit(x0 + tri[i, 3], y0 + tri[i, 4], z0 + tri[i, 5])
    ax2, ay2, az2, n2 = _unit(x0 + tri[i, 6], y0 + tri[i, 7], z0 + tri[i, 8])
    if n0 == 0.0 or n1 == 0.0 or n2 == 0.0:
        return 0.0
    # orientation of the corner directions; near 0: p (nearly) in the face's plane
    c01x = ay0 * az1 - az0 * ay1
    c01y = az0 * ax1 - ax0 * az1
    c01z = ax0 * ay1 - ay0 * ax1
    det = c01x * ax2 + c01y * ay2 + c01z * az2
    if abs(det) < 1e-12:
        return 0.0
    s0 = (c01x * ax + c01y * ay + c01z * az) * det
    s1 = ((ay1 * az2 - az1 * ay2) * ax + (az1 * ax2 - ax1 * az2) * ay
          + (ax1 * ay2 - ay1 * ax2) * az) * det
    s2 = ((ay2 * az0 - az2 * ay0) * ax + (az2 * ax0 - ax2 * az0) * ay
          + (ax2 * ay0 - ay2 * ax0) * az) * det
    if s0 >= 0.0 and s1 >= 0.0 and s2 >= 0.0:
        return 0.0                       # the axis itself meets the face
    return min(_arc_distance(ax0, ay0, az0, ax1, ay1, az1, ax, ay, az),
               _arc_distance(ax1, ay1, az1, ax2, ay2, az2, ax, ay, az),
               _arc_distance(ax2, ay2, az2, ax0, ay0, az0, ax, ay, az))


@njit(cache=True, inline="always")
def _tri_outside_cone(px, py, pz, ax, ay, az, alpha, tri, i):
    """True when face ``i`` lies wholly outside the cone (apex p, unit axis a, half-angle
    alpha): its :func:`tri_cone_gap` exceeds alpha."""
    return tri_cone_gap(px, py, pz, ax, ay, az, tri, i) > alpha


@njit(cache=True)
def cone_clear(node_bounds, node_info, tri, tri_vid, px, py, pz, ax, ay, az, alpha,
               skip_vertex):
    """Conservative: True only when no face (except those containing ``skip_vertex``)
    meets the infinite cone with apex ``p`` (m), unit axis ``a`` and half-angle
    ``alpha`` (rad, small).

    Then every ray or segment from ``p`` inside the cone is unblocked, which lets
    the quality pass clear a run of images with one query: the segments
    ``p -> r_k`` of a run lie in the cone around ``r_m - p`` of half-angle
    ``asin(e_r / |r_m - p|)``. A box can hold a cone point only if the axis ray
    meets the box grown by ``s sin(alpha)``, ``s`` the largest distance from p
    to the box (slab test); faces are tested exactly through the angular
    distance from the axis to their spherical triangle
    (:func:`_tri_outside_cone`). ``alpha`` is inflated by ``1e-9`` rad
    (relative and absolute), far above the rounding of either test, so a
    cleared cone is never one the exact ray test would block. False means
    "unknown": test the rays one by one.
    """
    alpha = alpha * (1.0 + 1e-9) + 1e-9
    sa = np.sin(alpha)
    ix = 1.0 / ax if ax != 0.0 else 1e300
    iy = 1.0 / ay if ay != 0.0 else 1e300
    iz = 1.0 / az if az != 0.0 else 1e300
    stack = np.empty(64, dtype=np.int64)
    sp = 1
    stack[0] = 0
    while sp > 0:
        sp -= 1
        node = stack[sp]
        b = node_bounds
        hx = 0.5 * (b[node, 3] - b[node, 0])
        hy = 0.5 * (b[node, 4] - b[node, 1])
        hz = 0.5 * (b[node, 5] - b[node, 2])
        hd = np.sqrt(hx * hx + hy * hy + hz * hz)
        cx = b[node, 0] + hx - px
        cy = b[node, 1] + hy - py
        cz = b[node, 2] + hz - pz
        smax = np.sqrt(cx * cx + cy * cy + cz * cz) + hd
        m = smax * sa * (1.0 + 1e-6) + 1e-6 * (smax + hd)
        t0 = (b[node, 0] - m - px) * ix
        t1 = (b[node, 3] + m - px) * ix
        lo = min(t0, t1)
        hi = max(t0, t1)
        t0 = (b[node, 1] - m - py) * iy
        t1 = (b[node, 4] + m - py) * iy
        lo = max(lo, min(t0, t1))
        hi = min(hi, max(t0, t1))
        t0 = (b[node, 2] - m - pz) * iz
        t1 = (b[node, 5] + m - pz) * iz
        lo = max(lo, min(t0, t1))
        hi = min(hi, max(t0, t1))
        if not hi >= max(lo, 0.0):
            continue
        left = node_info[node, 0]
        if left >= 0:
            stack[sp] = left
            stack[sp + 1] = node_info[node, 1]
            sp += 2
            continue
        start = node_info[node, 2]
        for i in range(start, start + node_info[node, 3]):
            if (tri_vid[i, 0] == skip_vertex or tri_vid[i, 1] == skip_vertex
                    or tri_vid[i, 2] == skip_vertex):
                continue
            if not _tri_outside_cone(px, py, pz, ax, ay, az, alpha, tri, i):
                return False
    return True
