"""The world bank's mapped rows (:func:`ideas_hpc.core.mapping.world_rows.mapped_by_spacecraft`)
as a ``numba.cuda`` kernel (issue 43, deliverable 4).

One GPU thread decides one (candidate ``k``, vertex ``j``) row bit: it walks the images
``i = 0, 1, ...`` and stops at the first usable one. Each image's test is the CPU
kernel's ``_usable`` on the same floats, cheapest condition first:

* lit at the image (the world's lighting table, when illumination is a filter or the
  requirement asks for light);
* culling and clipping (:func:`~ideas_hpc.core.mapping.visibility._seen_basic`, compiled
  for the device), then the range and elevation tests of
  :func:`~ideas_hpc.core.mapping.visibility._seen`;
* the resolution limit and the emission, incidence and phase cosines of the quality pass
  (:func:`~ideas_hpc.core.mapping.world_rows.limits_met`, the CPU kernel's own, compiled
  for the device);
* with occlusion, the vertex's clear cone, and outside it the occlusion ray through the
  BVH: the any-hit walk of :func:`~ideas_hpc.core.mapping.segments.segment_hit` (same slab
  test and Moller-Trumbore test, compiled for the device, same traversal order) with a
  fixed 64-node local stack, the face that blocked the previous image tried first.

A row is the disjunction over images of that conjunction, so walking every image in order
(the CPU kernel's pass tree, its per-chunk image guesses and its lighting pre-filter are
speed-ups that skip only images whose test fails or whose answer is known) gives the same
bit. Consecutive threads hold consecutive vertices of one candidate: a warp reads one
camera per image and neighbouring vertices.

Importing this module imports ``numba.cuda``: only :func:`ideas_hpc.mapping.world_rows.rows_of_world`
does, and only when ``device = "cuda"``. Under ``NUMBA_ENABLE_CUDASIM=1`` the same kernel
runs on Numba's CUDA simulator (the tests). On a GPU, NVVM contracts multiply-adds into
FMAs, so a test whose operands sit within rounding of its boundary may decide otherwise
than the CPU (docs/gpu.md); the benchmark counts such bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import cuda, int64

from ideas_hpc.core.mapping.records import Bvh, Camera, Mesh, QualityTests, Strict
from ideas_hpc.core.mapping.segments import _crosses, _ray_box
from ideas_hpc.core.mapping.visibility import _seen_basic
from ideas_hpc.core.mapping.world_rows import limits_met

#: Threads per block (one row bit each).
THREADS = 128
#: Depth of the BVH walk's local stack: :func:`~ideas_hpc.core.mapping.segments.segment_hit`'s.
STACK = 64

_cross = cuda.jit(device=True)(_crosses.py_func)
_box = cuda.jit(device=True)(_ray_box.py_func)
_basic = cuda.jit(device=True)(_seen_basic.py_func)
_limits = cuda.jit(device=True)(limits_met.py_func)


@cuda.jit(device=True)
def _ray_hit(bvh, ox, oy, oz, dx, dy, dz, skip_vertex, hint):
    """:func:`~ideas_hpc.core.mapping.segments.segment_hit` with ``tmax = 1`` (the segment
    ``o -> o + d``): the crossed face (``hint`` first), -1 none."""
    node_bounds, node_info, tri, tri_vid = bvh
    # Minimum t: 1 nm (ignore round-off hits at the start point).
    t_min = 1e-9 / math.sqrt(dx * dx + dy * dy + dz * dz)
    if hint >= 0 and _cross(tri, tri_vid, hint, ox, oy, oz, dx, dy, dz, t_min, 1.0, skip_vertex):
        return hint
    # a zero component gets a huge finite inverse, as on the CPU
    ix = 1.0 / dx if dx != 0.0 else 1e300
    iy = 1.0 / dy if dy != 0.0 else 1e300
    iz = 1.0 / dz if dz != 0.0 else 1e300
    stack = cuda.local.array(STACK, int64)
    sp = 1
    stack[0] = 0
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if not _box(ox, oy, oz, ix, iy, iz, 1.0, node_bounds, node):
            continue
        left = node_info[node, 0]
        if left >= 0:
            stack[sp] = left
            stack[sp + 1] = node_info[node, 1]
            sp += 2
            continue
        start = node_info[node, 2]
        for f in range(start, start + node_info[node, 3]):
            if _cross(tri, tri_vid, f, ox, oy, oz, dx, dy, dz, t_min, 1.0, skip_vertex):
                return f
    return -1


@cuda.jit(device=True)
def _usable(j, k, i, mesh, cam, opts, tests, lit, cos_clear, bvh, hint):
    """``(usable, hint)`` of image ``i`` of candidate ``k`` for vertex ``j``: the CPU
    kernel's ``_usable`` (module docstring), ``hint`` the face that blocked the last ray."""
    if (opts.illumination or tests.require_lit) and not lit[j, i]:
        return False, hint
    p = mesh.vertices_T_m
    n = mesh.normals_T
    r_T = cam.r_T_m
    px = p[j, 0]
    py = p[j, 1]
    pz = p[j, 2]
    nx = n[j, 0]
    ny = n[j, 1]
    nz = n[j, 2]
    if not _basic(px, py, pz, nx, ny, nz, k, i, cam):
        return False, hint
    # _seen's range and elevation tests, as written there
    if opts.sin_min_elev > -1.0 or opts.max_range_m < math.inf:
        dx = px - r_T[k, i, 0]
        dy = py - r_T[k, i, 1]
        dz = pz - r_T[k, i, 2]
        rng = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not rng <= opts.max_range_m:
            return False, hint
        if not (-dx) * nx + (-dy) * ny + (-dz) * nz >= rng * opts.sin_min_elev:
            return False, hint
    ok, ln, rng2 = _limits(tests, opts.sun_T, i, r_T[k, i, 0] - px, r_T[k, i, 1] - py,
                           r_T[k, i, 2] - pz, nx, ny, nz)
    if not ok:
        return False, hint
    if opts.occlusion and not ln >= math.sqrt(rng2) * math.sqrt(nx * nx + ny * ny + nz * nz) \
            * cos_clear[j]:
        f = _ray_hit(bvh, px, py, pz, -(px - r_T[k, i, 0]), -(py - r_T[k, i, 1]),
                     -(pz - r_T[k, i, 2]), j, hint)
        if f >= 0:
            return False, f
    return True, hint


@cuda.jit
def _rows(mesh, cam, opts, bvh, tests, lit, cos_clear, out):
    """One thread per row bit ``t = k V + j``: ``out[k, j]`` is True when some image of
    candidate ``k`` is usable for vertex ``j`` (records as in
    :func:`~ideas_hpc.core.mapping.world_rows.mapped_by_spacecraft`)."""
    nv = out.shape[1]
    t = cuda.grid(1)
    if t >= out.shape[0] * nv:
        return
    k = t // nv
    j = t - k * nv
    hint = -1
    for i in range(cam.r_T_m.shape[1]):
        ok, hint = _usable(j, k, i, mesh, cam, opts, tests, lit, cos_clear, bvh, hint)
        if ok:
            out[k, j] = True
            return
    out[k, j] = False


def mapped_by_spacecraft_cuda(mesh, cam, opts, bvh, tests, lit, cos_clear):
    """:func:`~ideas_hpc.core.mapping.world_rows.mapped_by_spacecraft` on the current CUDA
    device: same arguments (host arrays in the records), same (K, V) bool rows."""
    dev = cuda.to_device
    nv = mesh.vertices_T_m.shape[0]
    nsc, nimg = cam.r_T_m.shape[0], cam.r_T_m.shape[1]
    if nsc == 0 or nv == 0 or nimg == 0:
        return np.zeros((nsc, nv), dtype=np.bool_)
    if lit.shape[1] == 0:       # not read: a zero-size device array is best avoided
        lit = np.zeros((nv, 1), dtype=np.bool_)
    m = Mesh(*(dev(np.ascontiguousarray(a)) for a in mesh))
    c = Camera(dev(cam.r_T_m), dev(cam.dcm_BT), dev(cam.times_s), *cam[3:])
    o = Strict(*opts[:4], dev(opts.sun_T))
    b = Bvh(*(dev(np.ascontiguousarray(a)) for a in bvh))
    q = QualityTests(tests.rho_rad, dev(tests.limits), *tests[2:])
    out = cuda.device_array((nsc, nv), dtype=np.bool_)
    blocks = -(-(nsc * nv) // THREADS)
    _rows[blocks, THREADS](m, c, o, b, q, dev(np.ascontiguousarray(lit)),
                           dev(np.ascontiguousarray(cos_clear)), out)
    cuda.synchronize()
    return out.copy_to_host()
