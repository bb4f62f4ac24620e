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
def _ray_box(ox, oy, oz, ix, iy, iz, tmax, b, node):
    """Slab test: does the ray ``o + t d`` (``i = 1/d``) meet box ``node`` for t in [0, tmax]?"""
    t0 = (b[node, 0] - ox) * ix
    t1 = (b[node, 3] - ox) * ix
    lo = min(t0, t1)
    hi = max(t0, t1)
    t0 = (b[node, 1] - oy) * iy
    t1 = (b[node, 4] - oy) * iy
    lo = max(lo, min(t0, t1))
    hi = min(hi, max(t0, t1))
    t0 = (b[node, 2] - oz) * iz
    t1 = (b[node, 5] - oz) * iz
    lo = max(lo, min(t0, t1))
    hi = min(hi, max(t0, t1))
    return hi >= max(lo, 0.0) and lo <= tmax


@njit(cache=True)
def segment_blocked(node_bounds, node_info, tri, tri_vid,
                    ox, oy, oz, dx, dy, dz, tmax, skip_vertex):
    """Any-hit query: does the ray ``o + t d``, ``t_min < t < tmax``, cross a face?

    Parameters
    ----------
    node_bounds, node_info, tri, tri_vid : arrays from :func:`build_bvh`
    ox, oy, oz : float
        Ray origin, m (a mesh vertex for the occlusion and shadow tests).
    dx, dy, dz : float
        Ray direction (any length; ``t`` is in units of it).
    tmax : float
        Largest ``t`` that counts (``1`` for the segment ``o -> o + d``;
        ``inf`` for a ray to the Sun).
    skip_vertex : int
        Faces that contain this vertex are ignored (the ray starts on them);
        ``-1`` ignores none.

    Returns
    -------
    bool
        True when a face is crossed (Moller-Trumbore, both face sides). Hits
        with ``t <= 1e-9 |d|``-relative slack at the origin are ignored.
    """
    # A zero direction component gets a huge finite inverse: (b - o) * inf would
    # be NaN when the origin lies on a slab plane.
    ix = 1.0 / dx if dx != 0.0 else 1e300
    iy = 1.0 / dy if dy != 0.0 else 1e300
    iz = 1.0 / dz if dz != 0.0 else 1e300
    dn = np.sqrt(dx * dx + dy * dy + dz * dz)
    # Minimum t: 1 nm (ignore round-off hits at the start point).
    t_min = 1e-9 / dn
    stack = np.empty(64, dtype=np.int64)
    sp = 0
    stack[0] = 0
    sp = 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if not _ray_box(ox, oy, oz, ix, iy, iz, tmax, node_bounds, node):
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
            e1x = tri[i, 3]
            e1y = tri[i, 4]
            e1z = tri[i, 5]
            e2x = tri[i, 6]
            e2y = tri[i, 7]
            e2z = tri[i, 8]
            px = dy * e2z - dz * e2y
            py = dz * e2x - dx * e2z
            pz = dx * e2y - dy * e2x
            det = e1x * px + e1y * py + e1z * pz
            if det == 0.0:
                continue
            inv = 1.0 / det
            sx = ox - tri[i, 0]
            sy = oy - tri[i, 1]
            sz = oz - tri[i, 2]
            u = (sx * px + sy * py + sz * pz) * inv
            if u < 0.0 or u > 1.0:
                continue
            qx = sy * e1z - sz * e1y
            qy = sz * e1x - sx * e1z
            qz = sx * e1y - sy * e1x
            v = (dx * qx + dy * qy + dz * qz) * inv
            if v < 0.0 or u + v > 1.0:
                continue
            t = (e2x * qx + e2y * qy + e2z * qz) * inv
            if t > t_min and t < tmax:
                return True
    return False


@njit(cache=True)
def segments_blocked(node_bounds, node_info, tri, tri_vid, origins, targets, skip):
    """Batch of :func:`segment_blocked` for segments ``origins[k] -> targets[k]`` (m).

    ``skip[k]`` is the vertex whose faces are ignored (``-1``: none). Serial;
    used by tests and by the boundary for one-off queries.
    """
    n = origins.shape[0]
    out = np.empty(n, dtype=np.bool_)
    for k in range(n):
        out[k] = segment_blocked(node_bounds, node_info, tri, tri_vid,
                                 origins[k, 0], origins[k, 1], origins[k, 2],
                                 targets[k, 0] - origins[k, 0],
                                 targets[k, 1] - origins[k, 1],
                                 targets[k, 2] - origins[k, 2], 1.0, skip[k])
    return out
