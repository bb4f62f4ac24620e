"""A candidate's pass as a tree of image runs that rejects what no image of a run can see.

The time tree (:mod:`ideas_hpc.core.mapping.time_tree`) bounds how far the camera
coordinates ``q = C (p - r)`` of a vertex move inside a run by the camera's motion,
``e_C |p - r_m| + e_r``: over a 10 km/s encounter a run of 13 images moves the
spacecraft by 26 km, so a vertex that faces the candidate only while it is beyond the
far plane, and has turned away by the time it is in range, is rejected by neither
test at any level and every image is tested (issue 43: 80 k such pairs per world,
38 images each). The world bank's rows only need runs rejected, and the two
conditions that fail there are nearly linear along the pass. Splitting
``q_a = C_a . p - C_a . r`` (``C_a`` the row of axis ``a``):

* the position part ``c_a(i) = -C_{i,a} . r_i`` is kept exactly per run: its minimum
  and maximum over the run's images;
* the pointing part moves only with the camera's turn: with the run's reference image
  ``m`` and ``e_C = max_i ||C_i - C_m||_F``, ``|C_{i,a} . p - C_{m,a} . p| <= e_C |p|``.

So over a run ``q_a`` lies in ``[min c_a + C_{m,a} . p - e_C |p|, max c_a + C_{m,a} . p +
e_C |p|]``, which rejects the run when it lies beyond the far plane, before the near
one, or outside the field of view (``|q_x| <= tan(eta) q_z``) at every image. The
exact culling value ``(r - p) . n`` is linear in ``r``, and every position of the run
lies within the run's half-width ``w`` of its chord (first to last position), so
``max_i (r_i - p) . n <= max((r_first - p) . n, (r_last - p) . n) + |n| w``: a run
whose bound is negative faces away at every image.

Runs halve down to :data:`LEAF` images (an implicit binary tree, node ``d`` with
children ``2d + 1`` and ``2d + 2``); every bound carries an allowance of ``1e-9`` of
the largest ``|r|`` and ``|p|`` (m), some million times the rounding of the per-image
expressions, so a rejected run holds no image the exact tests
(:func:`~ideas_hpc.core.mapping.visibility._seen`) would pass. No bound assumes an
orthonormal ``C``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Images per leaf run.
LEAF = 4
#: Layout of a node's record: ``[min c_z, max c_z, min c_x, max c_x, min c_y, max c_y,
#: e_C, chord half-width w, max |r|, C_m (9, row-major)]``.
N_ZLO, N_ZHI, N_XLO, N_XHI, N_YLO, N_YHI, N_EC, N_W, N_RMAX, N_C = range(10)
NODE = N_C + 9
#: Relative allowance of the bounds (module docstring).
_ALLOW = 1e-9


@njit(cache=True)
def pass_runs(nimg):
    """(n_nodes, 2) int64: image range ``[start, stop)`` of every node of the implicit
    tree over ``nimg`` images (``-1``: no such node); a node of more than :data:`LEAF`
    images has children ``2 d + 1`` (first half) and ``2 d + 2``."""
    depth = 0
    size = nimg
    while size > LEAF:
        size = (size + 1) // 2
        depth += 1
    n = 2 ** (depth + 1) - 1
    runs = np.full((n, 2), -1, dtype=np.int64)
    runs[0, 0] = 0
    runs[0, 1] = nimg
    for d in range(n):
        a = runs[d, 0]
        b = runs[d, 1]
        if a < 0 or b - a <= LEAF:
            continue
        mid = (a + b) // 2
        runs[2 * d + 1, 0] = a
        runs[2 * d + 1, 1] = mid
        runs[2 * d + 2, 0] = mid
        runs[2 * d + 2, 1] = b
    return runs


@njit(cache=True)
def pass_tree(r_T, dcm_BT, runs):
    """(K, n_nodes, :data:`NODE`) float64: every candidate's node records (module
    docstring) over the runs of :func:`pass_runs`."""
    nsc = r_T.shape[0]
    nn = runs.shape[0]
    out = np.zeros((nsc, nn, NODE))
    for k in range(nsc):
        for d in range(nn):
            a = runs[d, 0]
            b = runs[d, 1]
            if a < 0:
                continue
            m = (a + b - 1) // 2
            rec = out[k, d]
            for e in range(9):
                rec[N_C + e] = dcm_BT[k, m, e // 3, e % 3]
            rec[N_ZLO] = np.inf
            rec[N_XLO] = np.inf
            rec[N_YLO] = np.inf
            rec[N_ZHI] = -np.inf
            rec[N_XHI] = -np.inf
            rec[N_YHI] = -np.inf
            ox = r_T[k, a, 0]
            oy = r_T[k, a, 1]
            oz = r_T[k, a, 2]
            ex = r_T[k, b - 1, 0] - ox
            ey = r_T[k, b - 1, 1] - oy
            ez = r_T[k, b - 1, 2] - oz
            ee = ex * ex + ey * ey + ez * ez
            ec = 0.0
            w = 0.0
            rmax = 0.0
            for i in range(a, b):
                rx = r_T[k, i, 0]
                ry = r_T[k, i, 1]
                rz = r_T[k, i, 2]
                for ax, lo, hi in ((2, N_ZLO, N_ZHI), (0, N_XLO, N_XHI), (1, N_YLO, N_YHI)):
                    c = -(dcm_BT[k, i, ax, 0] * rx + dcm_BT[k, i, ax, 1] * ry
                          + dcm_BT[k, i, ax, 2] * rz)
                    rec[lo] = min(rec[lo], c)
                    rec[hi] = max(rec[hi], c)
                g = 0.0
                for e in range(9):
                    x = dcm_BT[k, i, e // 3, e % 3] - rec[N_C + e]
                    g += x * x
                ec = max(ec, np.sqrt(g))
                x = rx - ox
                y = ry - oy
                z = rz - oz
                t = (x * ex + y * ey + z * ez) / ee if ee > 0.0 else 0.0
                t = min(1.0, max(0.0, t))
                x -= t * ex
                y -= t * ey
                z -= t * ez
                w = max(w, np.sqrt(x * x + y * y + z * z))
                rmax = max(rmax, np.sqrt(rx * rx + ry * ry + rz * rz))
            rec[N_EC] = ec * (1.0 + _ALLOW)
            rec[N_W] = w * (1.0 + _ALLOW)
            rec[N_RMAX] = rmax
    return out


@njit(cache=True, inline="always")
def run_rejected(tree, runs, k, d, r_T, px, py, pz, nx, ny, nz, cam):
    """True when no image of node ``d`` of candidate ``k`` can pass culling, clipping
    and the field of view for the vertex ``p`` with normal ``n`` (module docstring);
    ``tree`` from :func:`pass_tree`, ``cam`` the
    :class:`~ideas_hpc.core.mapping.records.Camera`."""
    rec = tree[k, d]
    a = runs[d, 0]
    b = runs[d, 1] - 1
    pabs = np.sqrt(px * px + py * py + pz * pz)
    nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
    fp = _ALLOW * (rec[N_RMAX] + pabs + 1.0)
    # culling: linear in r along the chord, within w of it
    c0 = r_T[k, a, 0] * nx + r_T[k, a, 1] * ny + r_T[k, a, 2] * nz
    c1 = r_T[k, b, 0] * nx + r_T[k, b, 1] * ny + r_T[k, b, 2] * nz
    if cam.exact:
        c0 -= px * nx + py * ny + pz * nz
        c1 -= px * nx + py * ny + pz * nz
    if max(c0, c1) + nabs * (rec[N_W] + fp) < 0.0:
        return True
    spread = rec[N_EC] * pabs + fp
    pz_ = rec[N_C + 6] * px + rec[N_C + 7] * py + rec[N_C + 8] * pz
    z_lo = rec[N_ZLO] + pz_ - spread
    z_hi = rec[N_ZHI] + pz_ + spread
    if z_lo > cam.far_m or z_hi < cam.near_m or z_hi <= 0.0:
        return True
    lim = cam.tan_eta * z_hi + fp
    px_ = rec[N_C] * px + rec[N_C + 1] * py + rec[N_C + 2] * pz
    if rec[N_XLO] + px_ - spread > lim or rec[N_XHI] + px_ + spread < -lim:
        return True
    py_ = rec[N_C + 3] * px + rec[N_C + 4] * py + rec[N_C + 5] * pz
    return rec[N_YLO] + py_ - spread > lim or rec[N_YHI] + py_ + spread < -lim
