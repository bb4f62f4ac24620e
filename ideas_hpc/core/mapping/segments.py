"""Segment queries against the body's BVH (:mod:`ideas_hpc.core.mapping.bvh`): the any-hit
occlusion and shadow test, and the same test returning the crossed face so that
a scan can try last image's face first (issue 20)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.mapping.records import Bvh


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


@njit(cache=True, inline="always")
def _crosses(tri, tri_vid, i, ox, oy, oz, dx, dy, dz, t_min, tmax, skip_vertex):
    """Moller-Trumbore test of face ``i`` for :func:`segment_blocked` (same arguments)."""
    if (tri_vid[i, 0] == skip_vertex or tri_vid[i, 1] == skip_vertex
            or tri_vid[i, 2] == skip_vertex):
        return False
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
        return False
    inv = 1.0 / det
    sx = ox - tri[i, 0]
    sy = oy - tri[i, 1]
    sz = oz - tri[i, 2]
    u = (sx * px + sy * py + sz * pz) * inv
    if u < 0.0 or u > 1.0:
        return False
    qx = sy * e1z - sz * e1y
    qy = sz * e1x - sx * e1z
    qz = sx * e1y - sy * e1x
    v = (dx * qx + dy * qy + dz * qz) * inv
    if v < 0.0 or u + v > 1.0:
        return False
    t = (e2x * qx + e2y * qy + e2z * qz) * inv
    return t > t_min and t < tmax


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
    # the record and an int64 hint, as every other caller passes them: one compiled
    # signature of segment_hit instead of three (issue 43, compile time)
    return segment_hit(Bvh(node_bounds, node_info, tri, tri_vid), ox, oy, oz, dx, dy, dz,
                       tmax, skip_vertex, np.int64(-1)) >= 0


@njit(cache=True, inline="always")
def face_hit(tri, tri_vid, f, ox, oy, oz, dx, dy, dz, tmax, skip_vertex):
    """Does face ``f`` block the segment as :func:`segment_hit` tests each face?"""
    # Minimum t: 1 nm (ignore round-off hits at the start point).
    t_min = 1e-9 / np.sqrt(dx * dx + dy * dy + dz * dz)
    return _crosses(tri, tri_vid, f, ox, oy, oz, dx, dy, dz, t_min, tmax, skip_vertex)


@njit(cache=True)
def segment_hit(bvh, ox, oy, oz, dx, dy, dz, tmax, skip_vertex, hint):
    """:func:`segment_blocked` that returns the crossed face (BVH order, -1: none).

    ``bvh`` is the tree ``(node_bounds, node_info, tri, tri_vid)`` (a
    :class:`~ideas_hpc.core.mapping.records.Bvh` or a plain tuple).

    Face ``hint`` (>= 0) is tested first: consecutive images of a scan are
    usually blocked by the same face, and any crossed face answers the
    any-hit query, so the answer ``>= 0`` is exactly ``segment_blocked``'s True.
    """
    node_bounds, node_info, tri, tri_vid = bvh
    if hint >= 0 and face_hit(tri, tri_vid, hint, ox, oy, oz, dx, dy, dz, tmax, skip_vertex):
        return hint
    # Minimum t: 1 nm (ignore round-off hits at the start point).
    t_min = 1e-9 / np.sqrt(dx * dx + dy * dy + dz * dz)
    # A zero direction component gets a huge finite inverse: (b - o) * inf would
    # be NaN when the origin lies on a slab plane.
    ix = 1.0 / dx if dx != 0.0 else 1e300
    iy = 1.0 / dy if dy != 0.0 else 1e300
    iz = 1.0 / dz if dz != 0.0 else 1e300
    stack = np.empty(64, dtype=np.int64)
    sp = 1
    stack[0] = 0
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
            if _crosses(tri, tri_vid, i, ox, oy, oz, dx, dy, dz, t_min, tmax, skip_vertex):
                return i
    return -1


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


@njit(cache=True, inline="always")
def face_blocks_cone(tri, tri_vid, f, skip_vertex, px, py, pz, ax, ay, az, alpha, length):
    """True only when every segment from ``p`` (m) of length ``>= length`` (m) whose
    direction is within ``alpha`` (rad) of the unit axis ``a`` crosses face ``f``
    as :func:`segment_blocked` counts it (so all of them are blocked).

    The directions from ``p`` to the face form a spherical triangle (``p`` off
    the face's plane by more than 1e-6 m); the cone lies inside it when the
    axis is inside and its angular distance to each edge's great circle
    exceeds ``alpha`` (inflated by 1e-9 rad, relative and absolute, far above
    the rounding of the Moller-Trumbore test). The crossing point is a convex
    combination of the corners, so it is nearer than the farthest corner,
    which must be nearer than ``length``. In two parts: :func:`face_cone_frame`
    (what depends on ``p`` and the face) and :func:`cone_in_frame` (the cone).
    """
    frame = np.empty(FRAME)
    return (face_cone_frame(tri, tri_vid, f, skip_vertex, px, py, pz, frame)
            and cone_in_frame(frame, ax, ay, az,
                              np.sin(min(alpha * (1.0 + 1e-9) + 1e-9, 0.5 * np.pi)), length))


#: Length of a :func:`face_cone_frame`.
FRAME = 10


@njit(cache=True, inline="always")
def face_cone_frame(tri, tri_vid, f, skip_vertex, px, py, pz, frame):
    """What :func:`face_blocks_cone` needs of face ``f`` seen from ``p`` (m), into
    ``frame`` (:data:`FRAME`): the unit normals of the great circles through its
    edges, oriented toward the inside of its spherical triangle, and its farthest
    corner's distance inflated by 1e-9 (m). False when the face can block no cone
    (``f < 0``, a face of vertex ``skip_vertex``, degenerate, or ``p`` on its plane)."""
    if f < 0 or tri_vid[f, 0] == skip_vertex or tri_vid[f, 1] == skip_vertex \
            or tri_vid[f, 2] == skip_vertex:
        return False
    x0 = tri[f, 0] - px
    y0 = tri[f, 1] - py
    z0 = tri[f, 2] - pz
    x1 = x0 + tri[f, 3]
    y1 = y0 + tri[f, 4]
    z1 = z0 + tri[f, 5]
    x2 = x0 + tri[f, 6]
    y2 = y0 + tri[f, 7]
    z2 = z0 + tri[f, 8]
    n0 = np.sqrt(x0 * x0 + y0 * y0 + z0 * z0)
    n1 = np.sqrt(x1 * x1 + y1 * y1 + z1 * z1)
    n2 = np.sqrt(x2 * x2 + y2 * y2 + z2 * z2)
    frame[9] = max(n0, n1, n2) * (1.0 + 1e-9)
    # distance from p to the face's plane
    cx = tri[f, 4] * tri[f, 8] - tri[f, 5] * tri[f, 7]
    cy = tri[f, 5] * tri[f, 6] - tri[f, 3] * tri[f, 8]
    cz = tri[f, 3] * tri[f, 7] - tri[f, 4] * tri[f, 6]
    cn = np.sqrt(cx * cx + cy * cy + cz * cz)
    if not (cn > 0.0 and abs(x0 * cx + y0 * cy + z0 * cz) > 1e-6 * cn):
        return False
    x0 /= n0
    y0 /= n0
    z0 /= n0
    x1 /= n1
    y1 /= n1
    z1 /= n1
    x2 /= n2
    y2 /= n2
    z2 /= n2
    det = (y0 * z1 - z0 * y1) * x2 + (z0 * x1 - x0 * z1) * y2 + (x0 * y1 - y0 * x1) * z2
    if abs(det) < 1e-12:
        return False
    sgn = 1.0 if det > 0.0 else -1.0
    for e in range(3):
        if e == 0:
            ux, uy, uz, vx, vy, vz = x0, y0, z0, x1, y1, z1
        elif e == 1:
            ux, uy, uz, vx, vy, vz = x1, y1, z1, x2, y2, z2
        else:
            ux, uy, uz, vx, vy, vz = x2, y2, z2, x0, y0, z0
        nx = uy * vz - uz * vy
        ny = uz * vx - ux * vz
        nz = ux * vy - uy * vx
        nn = np.sqrt(nx * nx + ny * ny + nz * nz)
        if not nn > 0.0:
            return False
        frame[3 * e] = sgn * nx / nn
        frame[3 * e + 1] = sgn * ny / nn
        frame[3 * e + 2] = sgn * nz / nn
    return True


@njit(cache=True, inline="always")
def cone_in_frame(frame, ax, ay, az, s_min, length):
    """:func:`face_blocks_cone` for a face's :func:`face_cone_frame`: the cone of unit
    axis ``a`` whose half-angle has sine ``<= s_min`` (already inflated for rounding)
    lies inside the face's spherical triangle and its segments are ``>= length`` (m)."""
    if not frame[9] < length:
        return False
    for e in range(3):
        if not frame[3 * e] * ax + frame[3 * e + 1] * ay + frame[3 * e + 2] * az > s_min:
            return False
    return True
