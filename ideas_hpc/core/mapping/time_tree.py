"""Time coherence of image sequences: trees of image runs with motion bounds.

Speed (see ``benchmarks/bench_coverage.py``): camera position and attitude
change slowly from image to image, so :func:`time_tree` groups each
spacecraft's images into a binary tree of runs with rigorous bounds on how
far the camera coordinates ``q`` of any vertex can move inside a run (the
derivation is written above :data:`LEAF`). For each (vertex, spacecraft) the
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
from numba import njit, prange

from ideas_hpc.core.mapping.records import Sightings
from ideas_hpc.core.mapping.visibility import _seen_basic, _seen_hint


# ------------------------------------------------------------ time coherence
#
# Derivation of the conservative bounds used by the time tree (all exact
# arithmetic; floating-point slack is added on top, see ``_classify``).
#
# A node of the tree is a run of consecutive images ``k in [i0, i1)`` of one
# spacecraft with a reference image ``m`` inside it. For a vertex ``p``,
#
#     q_k - q_m = C_k (p - r_k) - C_m (p - r_m)
#               = (C_k - C_m)(p - r_m) + C_k (r_m - r_k),
#
# so ``|q_k - q_m| <= ||C_k - C_m||_2 |p - r_m| + ||C_k||_2 |r_k - r_m|
#                   <= e_C |p - r_m| + e_r =: delta``
# with ``e_C = max_k ||C_k - C_m||_F`` (Frobenius >= spectral norm) and
# ``e_r = max_k s_k |r_k - r_m|``, ``s_k = sqrt(1 + ||C_k C_k^T - I||_F) >=
# ||C_k||_2`` (eigenvalues of C^T C lie within ||C C^T - I|| of 1), so the bound
# holds for any input matrix, orthonormal or not. Every clipping condition is
# linear or |linear| in q:
#
#     q_z - n >= 0,  f - q_z >= 0          (gradient norm 1)
#     t q_z - |q_x| >= 0, t q_z - |q_y| >= 0 (|d(t q_z - |q_x|)| <= |dq_x| + t |dq_z|
#                                            <= sqrt(1 + t^2) |dq|, Cauchy-Schwarz)
#
# and culling changes by at most ``|n| |r_k - r_m| <= |n| e_r`` (paper
# ``r . n``, exact ``(r - p) . n``). Hence if every condition holds at ``m``
# with margin > its change bound, it holds at every image of the node; if one
# condition fails at ``m`` by more than its bound, it fails at every image.
# Otherwise the node is split (children are halves) down to leaves whose images
# are tested one by one with the same expressions as the brute-force kernels.
#
# Node bounds are built bottom-up: for a parent with reference ``M`` and
# children ``c`` (reference ``m_c``), by the triangle inequality
# ``||C_k - C_M|| <= e_C,c + ||C_mc - C_M||`` and
# ``s_k |r_k - r_M| <= e_r,c + S_c |r_mc - r_M|`` with ``S_c = max_k s_k``.
# Each computed bound is inflated by a relative 1e-12 to cover its own rounding.

#: Images per leaf of the time tree.
LEAF = 16
#: Per-node float data: C_m (9, row major), r_m (3), |r_m|, e_C, e_r, S.
_NF = 17


@njit(cache=True, inline="always")
def gram_error2(dcm, k, i):
    """``||C C^T - I||_F^2`` of ``C = dcm[k, i]`` (``||C||_2 <= sqrt(1 + its root)``)."""
    g = 0.0
    for a in range(3):
        for c in range(3):
            s = (dcm[k, i, a, 0] * dcm[k, i, c, 0] + dcm[k, i, a, 1] * dcm[k, i, c, 1]
                 + dcm[k, i, a, 2] * dcm[k, i, c, 2])
            if a == c:
                s -= 1.0
            g += s * s
    return g


@njit(cache=True, inline="always")
def dcm_gap2(dcm_a, k, i, dcm_b, m):
    """``||dcm_a[k, i] - dcm_b[k, m]||_F^2``."""
    d = 0.0
    for a in range(3):
        for c in range(3):
            d += (dcm_a[k, i, a, c] - dcm_b[k, m, a, c]) ** 2
    return d


@njit(cache=True, inline="always")
def gap(r_a, k, i, r_b, m):
    """``|r_a[k, i] - r_b[k, m]|`` (m)."""
    return np.sqrt((r_a[k, i, 0] - r_b[k, m, 0]) ** 2 + (r_a[k, i, 1] - r_b[k, m, 1]) ** 2
                   + (r_a[k, i, 2] - r_b[k, m, 2]) ** 2)


@njit(cache=True)
def _time_tree_shape(nimg, leaf):
    """Level offsets of a binary tree over ``ceil(nimg / leaf)`` leaves."""
    nlev = 1
    cnt = (nimg + leaf - 1) // leaf
    while cnt > 1:
        cnt = (cnt + 1) // 2
        nlev += 1
    counts = np.empty(nlev, dtype=np.int64)
    offs = np.empty(nlev + 1, dtype=np.int64)
    counts[0] = (nimg + leaf - 1) // leaf
    offs[0] = 0
    for lv in range(1, nlev):
        counts[lv] = (counts[lv - 1] + 1) // 2
    for lv in range(nlev):
        offs[lv + 1] = offs[lv] + counts[lv]
    return counts, offs


@njit(cache=True, inline="always")
def _fill_ref(NF, k, node, r_T, dcm_BT, m):
    for a in range(3):
        for b in range(3):
            NF[k, node, 3 * a + b] = dcm_BT[k, m, a, b]
    rx = r_T[k, m, 0]
    ry = r_T[k, m, 1]
    rz = r_T[k, m, 2]
    NF[k, node, 9] = rx
    NF[k, node, 10] = ry
    NF[k, node, 11] = rz
    NF[k, node, 12] = np.sqrt(rx * rx + ry * ry + rz * rz)


@njit(parallel=True, cache=True)
def time_tree(r_T, dcm_BT, leaf):
    """Per spacecraft, a binary tree of image runs with motion bounds (time coherence).

    Parameters
    ----------
    r_T : (N, n_img, 3) float64
        Spacecraft positions in T, m.
    dcm_BT : (N, n_img, 3, 3) float64
        Camera DCMs (B <- T).
    leaf : int
        Images per leaf.

    Returns
    -------
    NF : (N, n_nodes, 17) float64
        Per node: reference ``C_m`` (9), ``r_m`` (3, m), ``|r_m|`` (m),
        ``e_C = max ||C_k - C_m||_F``, ``e_r = max s_k |r_k - r_m|`` (m) and
        ``S = max s_k`` over the node's images (see the derivation above).
    NI : (n_nodes, 4) int64
        First image, one past the last image, left and right child (-1: none;
        leaves have no children). Nodes are stored leaves first, the root last.
    """
    nsc = r_T.shape[0]
    nimg = r_T.shape[1]
    counts, offs = _time_tree_shape(nimg, leaf)
    nlev = counts.shape[0]
    nn = offs[nlev]
    NF = np.empty((nsc, nn, _NF))
    NI = np.full((nn, 4), -1, dtype=np.int64)
    for b in range(counts[0]):
        NI[b, 0] = b * leaf
        NI[b, 1] = min(nimg, (b + 1) * leaf)
    for lv in range(1, nlev):
        for b in range(counts[lv]):
            node = offs[lv] + b
            c0 = offs[lv - 1] + 2 * b
            c1 = c0 + 1 if 2 * b + 1 < counts[lv - 1] else -1
            NI[node, 2] = c0
            NI[node, 3] = c1
            NI[node, 0] = NI[c0, 0]
            NI[node, 1] = NI[c1, 1] if c1 >= 0 else NI[c0, 1]
    grow = 1.0 + 1e-12
    for k in prange(nsc):
        for b in range(counts[0]):
            i0 = NI[b, 0]
            i1 = NI[b, 1]
            m = (i0 + i1 - 1) // 2
            _fill_ref(NF, k, b, r_T, dcm_BT, m)
            ec = 0.0
            er = 0.0
            smax = 0.0
            for i in range(i0, i1):
                sk = np.sqrt(1.0 + np.sqrt(gram_error2(dcm_BT, k, i))) * grow
                smax = max(smax, sk)
                ec = max(ec, np.sqrt(dcm_gap2(dcm_BT, k, i, dcm_BT, m)))
                er = max(er, sk * gap(r_T, k, i, r_T, m))
            NF[k, b, 13] = ec * grow
            NF[k, b, 14] = er * grow
            NF[k, b, 15] = smax
            NF[k, b, 16] = 0.0
        for lv in range(1, nlev):
            for b in range(counts[lv]):
                node = offs[lv] + b
                m = (NI[node, 0] + NI[node, 1] - 1) // 2
                _fill_ref(NF, k, node, r_T, dcm_BT, m)
                ec = 0.0
                er = 0.0
                smax = 0.0
                for h in range(2):
                    c = NI[node, 2 + h]
                    if c < 0:
                        continue
                    dc = 0.0
                    for a in range(9):
                        dc += (NF[k, c, a] - NF[k, node, a]) ** 2
                    dr = np.sqrt((NF[k, c, 9] - NF[k, node, 9]) ** 2
                                 + (NF[k, c, 10] - NF[k, node, 10]) ** 2
                                 + (NF[k, c, 11] - NF[k, node, 11]) ** 2)
                    ec = max(ec, NF[k, c, 13] + np.sqrt(dc))
                    er = max(er, NF[k, c, 14] + NF[k, c, 15] * dr)
                    smax = max(smax, NF[k, c, 15])
                NF[k, node, 13] = ec * grow
                NF[k, node, 14] = er * grow
                NF[k, node, 15] = smax
                NF[k, node, 16] = 0.0
    return NF, NI


@njit(cache=True)
def scan_tree(cam):
    """The fields ``(NF, NI, sec_eta)`` of the
    :class:`~ideas_hpc.core.mapping.records.TimeTree` of a
    :class:`~ideas_hpc.core.mapping.records.Camera`'s images (leaves of :data:`LEAF`;
    the secant of the half angle carries a relative 1e-12 margin, as the node bounds).

    Kernels build the record with ``TimeTree(*scan_tree(cam))``: Numba's parfor
    lowering re-creates a named tuple that a ``prange`` loop reads by the name of
    the callable that made it, so it must be a call of the class itself.
    """
    NF, NI = time_tree(cam.r_T_m, cam.dcm_BT, LEAF)
    return NF, NI, np.sqrt(1.0 + cam.tan_eta * cam.tan_eta) * (1.0 + 1e-12)


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
    m1 = delta + fp
    m2 = sec_eta * delta + (1.0 + tan_eta) * fp
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
    if (cul < -mc) or (qz - near < -m1) or (far - qz < -m1) or (sx < -m2) or (sy < -m2):
        return 0
    if (cul > mc) and (qz - near > m1) and (far - qz > m1) and (sx > m2) and (sy > m2):
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
