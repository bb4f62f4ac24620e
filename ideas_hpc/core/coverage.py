"""Coverage kernels: which mesh vertices the swarm's cameras observe (SPEC section 6).

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
      that contain ``p_j`` (BVH any-hit query, :mod:`ideas_hpc.core.bvh`);
    * illumination: ``n_j . s > 0`` for the unit Sun direction ``s`` of the
      image, and the ray ``p_j + t s, t > 0`` crosses no face (not shadowed);
    * minimum elevation ``eps``: the angle between the line of sight ``r - p_j``
      and the local horizontal (plane normal to ``n_j``) is ``>= eps``:
      ``(r - p_j) . n_j >= |r - p_j| sin(eps)``;
    * ground resolution: ``lambda |r - p_j| / D <= X``, passed as a maximum
      range ``X D / lambda`` (m).

The observed set is the union over spacecraft and images (paper eq. 26). Per
vertex the kernels return whether it was observed, the first image time it was
seen (NaN when never) and how many (spacecraft, image) pairs saw it, plus the
area-weighted coverage ``sum(A_j observed) / sum(A_j)`` and the vertex-count
fraction.

Image times must be non-decreasing (the boundary checks it): the early-out
kernels stop scanning a spacecraft's images at its first hit, and skip images
later than the earliest hit found so far.

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
:func:`coverage_counts_tiles` is the previous kernel (spatial vertex tiles
only), kept as an independent cross-check.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .bvh import segment_blocked

#: Vertices per tile of the tiled counting kernel.
BLOCK = 32
#: Images gathered per pass for a tile (SoA buffer of 13 x CHUNK doubles, ~27 kB).
CHUNK = 256
#: Relative slack of the conservative tile rejection tests (DCMs are accepted
#: by the boundary when orthonormal to 1e-6, so |C d| may differ from |d| by
#: that much; 1e-5 keeps the tile tests strictly on the safe side).
_SLACK = 1e-5


@njit(cache=True)
def coverage_fractions(observed, vertex_areas):
    """Area-weighted and count coverage of an observed mask.

    Parameters
    ----------
    observed : (V,) bool
    vertex_areas : (V,) float64
        m^2 (one third of the adjacent face areas, SPEC section 1).

    Returns
    -------
    coverage : float
        ``sum(A_j, j observed) / sum(A_j)`` in 0..1.
    coverage_count : float
        Observed vertices / all vertices.
    """
    a_obs = 0.0
    a_tot = 0.0
    n_obs = 0
    for j in range(observed.shape[0]):
        a_tot += vertex_areas[j]
        if observed[j]:
            a_obs += vertex_areas[j]
            n_obs += 1
    return a_obs / a_tot, n_obs / observed.shape[0]


@njit(cache=True)
def dcm_check(dcm):
    """Validation figures of a stack of 3x3 matrices (for the boundary layer).

    Parameters
    ----------
    dcm : (M, 3, 3) float64

    Returns
    -------
    n_nonfinite : int
        Matrices holding a NaN or inf.
    max_err, i_err : float, int
        Largest ``max |C C^T - I|`` (entrywise) over the finite matrices and where.
    min_det, i_det : float, int
        Smallest determinant and where.
    """
    n_bad = 0
    max_err = 0.0
    i_err = 0
    min_det = np.inf
    i_det = 0
    for m in range(dcm.shape[0]):
        fin = True
        for a in range(3):
            for b in range(3):
                fin = fin and np.isfinite(dcm[m, a, b])
        if not fin:
            n_bad += 1
            continue
        e = 0.0
        for a in range(3):
            for c in range(3):
                s = dcm[m, a, 0] * dcm[m, c, 0] + dcm[m, a, 1] * dcm[m, c, 1] \
                    + dcm[m, a, 2] * dcm[m, c, 2]
                if a == c:
                    s -= 1.0
                e = max(e, abs(s))
        if e > max_err:
            max_err = e
            i_err = m
        det = (dcm[m, 0, 0] * (dcm[m, 1, 1] * dcm[m, 2, 2] - dcm[m, 1, 2] * dcm[m, 2, 1])
               - dcm[m, 0, 1] * (dcm[m, 1, 0] * dcm[m, 2, 2] - dcm[m, 1, 2] * dcm[m, 2, 0])
               + dcm[m, 0, 2] * (dcm[m, 1, 0] * dcm[m, 2, 1] - dcm[m, 1, 1] * dcm[m, 2, 0]))
        if det < min_det:
            min_det = det
            i_det = m
    return n_bad, max_err, i_err, min_det, i_det



@njit(cache=True)
def spatial_order(vertices, block):
    """Permutation that groups vertices into compact tiles of ``block`` (k-d median splits).

    Splits happen at multiples of ``block`` along the longest extent, so every
    tile but the last holds exactly ``block`` vertices, close together in space
    (and, on a surface, with similar normals).
    """
    nv = vertices.shape[0]
    order = np.arange(nv)
    stack = np.empty((2 * nv // max(block, 1) + 64, 2), dtype=np.int64)
    stack[0, 0] = 0
    stack[0, 1] = nv
    sp = 1
    while sp > 0:
        sp -= 1
        start = stack[sp, 0]
        count = stack[sp, 1]
        if count <= block:
            continue
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for i in range(start, start + count):
            for k in range(3):
                x = vertices[order[i], k]
                lo[k] = min(lo[k], x)
                hi[k] = max(hi[k], x)
        ext = hi - lo
        axis = 0
        if ext[1] > ext[axis]:
            axis = 1
        if ext[2] > ext[axis]:
            axis = 2
        seg = order[start:start + count].copy()
        keys = np.empty(count)
        for i in range(count):
            keys[i] = vertices[seg[i], axis]
        srt = np.argsort(keys, kind="mergesort")
        for i in range(count):
            order[start + i] = seg[srt[i]]
        nblk = (count + block - 1) // block
        left = (nblk // 2) * block
        stack[sp, 0] = start
        stack[sp, 1] = left
        stack[sp + 1, 0] = start + left
        stack[sp + 1, 1] = count - left
        sp += 2
    return order


@njit(cache=True)
def _tile_bounds(px, py, pz, nx, ny, nz, nb):
    """Bounding sphere (centre, radius) and normal cone (axis, cos and sin of half angle)."""
    cx = 0.0
    cy = 0.0
    cz = 0.0
    ax = 0.0
    ay = 0.0
    az = 0.0
    for jj in range(nb):
        cx += px[jj]
        cy += py[jj]
        cz += pz[jj]
        ax += nx[jj]
        ay += ny[jj]
        az += nz[jj]
    cx /= nb
    cy /= nb
    cz /= nb
    rho = 0.0
    for jj in range(nb):
        rho = max(rho, np.sqrt((px[jj] - cx) ** 2 + (py[jj] - cy) ** 2 + (pz[jj] - cz) ** 2))
    an = np.sqrt(ax * ax + ay * ay + az * az)
    cos_a = -1.0
    if an > 0.0:
        ax /= an
        ay /= an
        az /= an
        cos_a = 1.0
        for jj in range(nb):
            cos_a = min(cos_a, ax * nx[jj] + ay * ny[jj] + az * nz[jj])
    cos_a = max(-1.0, cos_a - 1e-9)
    sin_a = np.sqrt(max(0.0, 1.0 - cos_a * cos_a))
    return cx, cy, cz, rho * (1.0 + _SLACK) + 1e-9, ax, ay, az, cos_a, sin_a


@njit(cache=True, inline="always")
def _seen(j, k, i, vertices, normals, r_T, dcm_BT, tan_eta, near, far, exact,
          sin_min_elev, max_range, occlusion, illumination, sun_T,
          node_bounds, node_info, tri, tri_vid):
    """True when vertex ``j`` is seen by spacecraft ``k`` in image ``i`` (all tests)."""
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
                           -dx, -dy, -dz, 1.0, j):
            return False
    if illumination:
        if segment_blocked(node_bounds, node_info, tri, tri_vid, px, py, pz,
                           sun_T[i, 0], sun_T[i, 1], sun_T[i, 2], np.inf, j):
            return False
    return True


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
                g = 0.0  # ||C C^T - I||_F^2
                for a in range(3):
                    for c in range(3):
                        s = (dcm_BT[k, i, a, 0] * dcm_BT[k, i, c, 0]
                             + dcm_BT[k, i, a, 1] * dcm_BT[k, i, c, 1]
                             + dcm_BT[k, i, a, 2] * dcm_BT[k, i, c, 2])
                        if a == c:
                            s -= 1.0
                        g += s * s
                sk = np.sqrt(1.0 + np.sqrt(g)) * grow
                smax = max(smax, sk)
                dc = 0.0
                for a in range(3):
                    for c in range(3):
                        dc += (dcm_BT[k, i, a, c] - dcm_BT[k, m, a, c]) ** 2
                ec = max(ec, np.sqrt(dc))
                dr = np.sqrt((r_T[k, i, 0] - r_T[k, m, 0]) ** 2
                             + (r_T[k, i, 1] - r_T[k, m, 1]) ** 2
                             + (r_T[k, i, 2] - r_T[k, m, 2]) ** 2)
                er = max(er, sk * dr)
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


#: Relative floating-point slack of the node tests. The per-image tests round
#: q, r . n and t q_z with errors of a few ulp of |p - r| (resp. |r| |n|);
#: 1e-10 of those scales is ~1e6 times more than needed.
_FP = 1e-10


@njit(cache=True, inline="always")
def _classify(NF, k, node, px, py, pz, nx, ny, nz, nabs, tan_eta, sec_eta, near, far,
              exact):
    """0: no image of the node can see the vertex, 2: every image sees it, 1: unknown."""
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
def _seen_basic(px, py, pz, nx, ny, nz, k, i, r_T, dcm_BT, tan_eta, near, far, exact):
    """Culling + clipping of one (vertex, spacecraft, image), as in :func:`_seen`."""
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
def _scan(j, k, NF, NI, stack, image_times, best, early, vertices, normals, r_T, dcm_BT,
          tan_eta, sec_eta, near, far, exact, strict, sin_min_elev, max_range, occlusion,
          illumination, sun_T, node_bounds, node_info, tri, tri_vid):
    """Sightings of vertex ``j`` by spacecraft ``k``: (count, earliest time).

    Depth-first over the time tree in image order. ``early``: skip images at
    or after ``best`` and stop at the first hit. ``strict``: the node test only
    prunes (culling and clipping are necessary conditions), images of
    accepted nodes still go through :func:`_seen`.
    """
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    nx = normals[j, 0]
    ny = normals[j, 1]
    nz = normals[j, 2]
    nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
    cnt = 0
    sp = 1
    stack[0] = NI.shape[0] - 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        i0 = NI[node, 0]
        i1 = NI[node, 1]
        if early and image_times[i0] >= best:
            continue
        cls = _classify(NF, k, node, px, py, pz, nx, ny, nz, nabs, tan_eta, sec_eta,
                        near, far, exact)
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
                hit = _seen(j, k, i, vertices, normals, r_T, dcm_BT, tan_eta, near, far,
                            exact, sin_min_elev, max_range, occlusion, illumination, sun_T,
                            node_bounds, node_info, tri, tri_vid)
            else:
                hit = _seen_basic(px, py, pz, nx, ny, nz, k, i, r_T, dcm_BT, tan_eta,
                                  near, far, exact)
            if hit:
                cnt += 1
                best = min(best, image_times[i])
                if early:
                    break
    return cnt, best


@njit(parallel=True, cache=True)
def coverage_counts(vertices, normals, vertex_areas, r_T, dcm_BT, image_times,
                    tan_eta, near, far, exact, active, count_all):
    """Full per-vertex counts, culling + clipping only (paper eq. 25-26), time tree.

    Every (spacecraft, image, vertex) triple counts, so ``times_seen`` is
    complete. Camera position and attitude change slowly from image to image,
    so each spacecraft's images are grouped into a binary tree of runs
    (:func:`time_tree`, leaves of :data:`LEAF` images) with rigorous bounds on
    how far ``q = C (p - r)`` can move inside a run (derivation above
    :data:`LEAF`). ``prange`` over vertices; for each (vertex, spacecraft) the
    tree is walked depth-first in image order: a run where every condition
    holds with margin larger than its bound adds its length to the count (and
    its first image time to first-seen), a run where one condition fails by
    more than its bound is skipped, any other run is split, and leaves are
    tested image by image with the exact per-vertex expressions. The bounds
    carry a floating-point slack (:data:`_FP`), so results are identical to
    testing every image.

    Parameters
    ----------
    vertices, normals : (V, 3) float64
        Vertex positions (m) and outward unit normals in frame T.
    vertex_areas : (V,) float64
        m^2.
    r_T : (N, n_img, 3) float64
        Spacecraft positions in T per image, m.
    dcm_BT : (N, n_img, 3, 3) float64
        Camera DCM (B <- T) per image; camera boresight is +z_B.
    image_times : (n_img,) float64
        s, non-decreasing.
    tan_eta : float
        Tangent of the half angle of the square field of view.
    near, far : float
        Clipping distances along the boresight, m, ``0 < near < far``.
    exact : bool
        Exact culling ``(r - p) . n > 0`` instead of the paper's ``r . n >= 0``.
    active : (N,) bool
        Spacecraft that take part (failed ones are False).
    count_all : bool
        True: full counts. False: union and first-seen time only (early-out:
        images at or after the earliest sighting found so far are skipped),
        and ``times_seen`` is 0/1.

    Returns
    -------
    observed : (V,) bool
    first_seen : (V,) float64
        s, NaN when never seen.
    times_seen : (V,) int32
    coverage, coverage_count : float
        See :func:`coverage_fractions`.
    """
    nv = vertices.shape[0]
    nsc = r_T.shape[0]
    NF, NI = time_tree(r_T, dcm_BT, LEAF)
    sec_eta = np.sqrt(1.0 + tan_eta * tan_eta) * (1.0 + 1e-12)
    times_seen = np.zeros(nv, dtype=np.int32)
    first_seen = np.full(nv, np.nan)
    sun_T = np.zeros((1, 3))
    nb_ = np.zeros((1, 6))
    ni_ = np.full((1, 4), -1, dtype=np.int64)
    tr_ = np.zeros((1, 9))
    tv_ = np.zeros((1, 3), dtype=np.int64)
    early = not count_all
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        best = np.inf
        cnt = 0
        for k in range(nsc):
            if not active[k]:
                continue
            c, best = _scan(j, k, NF, NI, stack, image_times, best, early, vertices,
                            normals, r_T, dcm_BT, tan_eta, sec_eta, near, far, exact,
                            False, -2.0, np.inf, False, False, sun_T, nb_, ni_, tr_, tv_)
            cnt += c
        if cnt > 0:
            first_seen[j] = best
            times_seen[j] = cnt if count_all else 1
    observed = times_seen > 0
    cov, cov_n = coverage_fractions(observed, vertex_areas)
    return observed, first_seen, times_seen, cov, cov_n


@njit(parallel=True, cache=True)
def coverage_counts_tiles(vertices, normals, vertex_areas, r_T, dcm_BT, image_times,
                          tan_eta, near, far, exact, active, count_all):
    """Previous tiled kernel (spatial tiles only), kept as a second implementation.

    Same arguments and results as :func:`coverage_counts`; it is slower on
    image sequences (no time coherence) and serves as a cross-check.

    Full per-vertex counts, culling + clipping only (paper eq. 25-26), tiled.

    Every (spacecraft, image, vertex) triple counts, so ``times_seen`` is
    complete. Vertices are grouped into compact tiles of :data:`BLOCK`
    (:func:`spatial_order`), one tile per ``prange`` iteration. For each
    (tile, image) pair two conservative tests may skip the whole tile:

    * the tile's bounding sphere lies entirely outside one of the six
      frustum planes (no vertex can pass clipping);
    * the tile's normal cone faces away from the spacecraft for every normal
      in it (no vertex can pass culling): ``max r . n < 0`` (paper) or
      ``max (r - p) . n <= 0`` (exact), bounded through the cone half angle
      and the sphere radius.

    Both tests carry a relative slack (:data:`_SLACK`) so they never reject a
    tile that holds a visible vertex; the per-vertex tests that follow are
    the exact ones, in a branch-free loop the compiler vectorises. With
    ``count_all`` False the images of all spacecraft are visited in time
    order and a tile stops once all its vertices have been seen.
    """
    nv = vertices.shape[0]
    nsc = r_T.shape[0]
    nimg = r_T.shape[1]
    order = spatial_order(vertices, BLOCK)
    times_seen = np.zeros(nv, dtype=np.int32)
    first_seen = np.full(nv, np.nan)
    # distance from a point to a side plane |x| = t z is (x - t z) / sqrt(1 + t^2)
    inv_side = 1.0 / np.sqrt(1.0 + tan_eta * tan_eta)
    # Per image: camera data in one contiguous row, and whether the body's
    # bounding sphere can meet the frustum at all (images that cannot are dropped).
    bx = 0.0
    by = 0.0
    bz = 0.0
    for j in range(nv):
        bx += vertices[j, 0]
        by += vertices[j, 1]
        bz += vertices[j, 2]
    bx /= nv
    by /= nv
    bz /= nv
    brho = 0.0
    for j in range(nv):
        brho = max(brho, np.sqrt((vertices[j, 0] - bx) ** 2 + (vertices[j, 1] - by) ** 2
                                 + (vertices[j, 2] - bz) ** 2))
    brho = brho * (1.0 + _SLACK) + 1e-9
    m_all = nsc * nimg
    keep = np.zeros(m_all, dtype=np.bool_)
    for m in prange(m_all):
        k = m // nimg
        i = m - k * nimg
        ex = bx - r_T[k, i, 0]
        ey = by - r_T[k, i, 1]
        ez = bz - r_T[k, i, 2]
        sx = dcm_BT[k, i, 0, 0] * ex + dcm_BT[k, i, 0, 1] * ey + dcm_BT[k, i, 0, 2] * ez
        sy = dcm_BT[k, i, 1, 0] * ex + dcm_BT[k, i, 1, 1] * ey + dcm_BT[k, i, 1, 2] * ez
        sz = dcm_BT[k, i, 2, 0] * ex + dcm_BT[k, i, 2, 1] * ey + dcm_BT[k, i, 2, 2] * ez
        marg = brho + _SLACK * (abs(sx) + abs(sy) + abs(sz))
        keep[m] = active[k] and not (
            sz + marg < near or sz - marg > far
            or (abs(sx) - tan_eta * sz) * inv_side > marg
            or (abs(sy) - tan_eta * sz) * inv_side > marg)
    sel = np.flatnonzero(keep)
    nsel = sel.shape[0]
    # time order (stable): the first hit in list order is then the earliest
    tsel = np.empty(nsel)
    for s_ in range(nsel):
        tsel[s_] = image_times[sel[s_] % nimg]
    sel = sel[np.argsort(tsel, kind="mergesort")]
    # Kept images as structure-of-arrays rows, so the per-tile classification
    # and the per-vertex tests both vectorise over images:
    # 0-8 C (row major), 9-11 r, 12 |r|, 13-15 r/|r|, 16 t
    G = np.empty((17, nsel))
    for s_ in prange(nsel):
        m = sel[s_]
        k = m // nimg
        i = m - k * nimg
        for a in range(3):
            for b in range(3):
                G[3 * a + b, s_] = dcm_BT[k, i, a, b]
        rx = r_T[k, i, 0]
        ry = r_T[k, i, 1]
        rz = r_T[k, i, 2]
        G[9, s_] = rx
        G[10, s_] = ry
        G[11, s_] = rz
        rn = np.sqrt(rx * rx + ry * ry + rz * rz)
        G[12, s_] = rn
        inv_rn = 1.0 / rn if rn > 0.0 else 0.0
        G[13, s_] = rx * inv_rn
        G[14, s_] = ry * inv_rn
        G[15, s_] = rz * inv_rn
        G[16, s_] = image_times[i]
    nblk = (nv + BLOCK - 1) // BLOCK
    big = np.int64(1) << 62
    for blk in prange(nblk):
        j0 = blk * BLOCK
        nb = min(nv, j0 + BLOCK) - j0
        px = np.zeros(BLOCK)
        py = np.zeros(BLOCK)
        pz = np.zeros(BLOCK)
        nx = np.zeros(BLOCK)
        ny = np.zeros(BLOCK)
        nz = np.zeros(BLOCK)
        cnt = np.zeros(BLOCK, dtype=np.int64)
        fs = np.full(BLOCK, np.inf)
        cls = np.empty(CHUNK, dtype=np.int64)
        buf = np.empty((13, CHUNK))
        pn_min = np.inf
        pn_max = -np.inf
        for jj in range(nb):
            j = order[j0 + jj]
            px[jj] = vertices[j, 0]
            py[jj] = vertices[j, 1]
            pz[jj] = vertices[j, 2]
            nx[jj] = normals[j, 0]
            ny[jj] = normals[j, 1]
            nz[jj] = normals[j, 2]
            pn = px[jj] * nx[jj] + py[jj] * ny[jj] + pz[jj] * nz[jj]
            pn_min = min(pn_min, pn)
            pn_max = max(pn_max, pn)
        cx, cy, cz, rho, ax, ay, az, cos_a, sin_a = _tile_bounds(px, py, pz, nx, ny, nz, nb)
        # r . n < 0 for every n in the cone iff angle(r, axis) > 90 deg + alpha,
        # r . n > 0 for every n in the cone iff angle(r, axis) < 90 deg - alpha;
        # a cone wider than a hemisphere (alpha > 90 deg) decides nothing.
        cone_none = -sin_a - _SLACK if cos_a > 0.0 else -2.0
        cone_all = sin_a + _SLACK if cos_a > 0.0 else 2.0
        sl_min = _SLACK * abs(pn_min)
        sl_max = _SLACK * abs(pn_max)
        n_full = 0
        t_full = np.inf
        done = False
        for c0 in range(0, nsel, CHUNK):
            nq = min(nsel, c0 + CHUNK) - c0
            # classify (branch-free): 0 no vertex can pass, 2 all pass, 1 test each
            g0 = G[0, c0:c0 + nq]
            g1 = G[1, c0:c0 + nq]
            g2 = G[2, c0:c0 + nq]
            g3 = G[3, c0:c0 + nq]
            g4 = G[4, c0:c0 + nq]
            g5 = G[5, c0:c0 + nq]
            g6 = G[6, c0:c0 + nq]
            g7 = G[7, c0:c0 + nq]
            g8 = G[8, c0:c0 + nq]
            g9 = G[9, c0:c0 + nq]
            g10 = G[10, c0:c0 + nq]
            g11 = G[11, c0:c0 + nq]
            g12 = G[12, c0:c0 + nq]
            g13 = G[13, c0:c0 + nq]
            g14 = G[14, c0:c0 + nq]
            g15 = G[15, c0:c0 + nq]
            for q in range(nq):
                cb = g13[q] * ax + g14[q] * ay + g15[q] * az
                if exact:
                    # (r - p) . n within |r| [min, max](r_hat . n) - [max, min](p . n)
                    sb = np.sqrt(max(0.0, 1.0 - cb * cb))
                    rn = g12[q]
                    none_c = (cb < cone_none) & (
                        rn * (cb * cos_a + sb * sin_a) - pn_min < -_SLACK * rn - sl_min)
                    all_c = (cb > cone_all) & (
                        rn * (cb * cos_a - sb * sin_a) - pn_max > _SLACK * rn + sl_max)
                else:
                    none_c = cb < cone_none
                    all_c = cb > cone_all
                ex = cx - g9[q]
                ey = cy - g10[q]
                ez = cz - g11[q]
                sx = abs(g0[q] * ex + g1[q] * ey + g2[q] * ez)
                sy = abs(g3[q] * ex + g4[q] * ey + g5[q] * ez)
                sz = g6[q] * ex + g7[q] * ey + g8[q] * ez
                marg = rho + _SLACK * (sx + sy + abs(sz))
                tz = tan_eta * sz
                outside = ((sz + marg < near) | (sz - marg > far)
                           | ((sx - tz) * inv_side > marg) | ((sy - tz) * inv_side > marg))
                inside = ((sz - marg >= near) & (sz + marg <= far)
                          & ((tz - sx) * inv_side >= marg) & ((tz - sy) * inv_side >= marg))
                cls[q] = 0 if (outside | none_c) else (2 if (inside & all_c) else 1)
            nbuf = 0
            for q in range(nq):
                if cls[q] == 0:
                    continue
                m = c0 + q
                if cls[q] == 2:
                    n_full += 1
                    t_full = min(t_full, G[16, m])
                    if not count_all:
                        break  # time order: nothing later can be earlier
                    continue
                for c in range(13):
                    buf[c, nbuf] = G[c if c < 12 else 16, m]
                nbuf += 1
            if nbuf > 0:
                c00 = buf[0, :nbuf]
                c01 = buf[1, :nbuf]
                c02 = buf[2, :nbuf]
                c10 = buf[3, :nbuf]
                c11 = buf[4, :nbuf]
                c12 = buf[5, :nbuf]
                c20 = buf[6, :nbuf]
                c21 = buf[7, :nbuf]
                c22 = buf[8, :nbuf]
                brx = buf[9, :nbuf]
                bry = buf[10, :nbuf]
                brz = buf[11, :nbuf]
                for jj in range(nb):
                    pxj = px[jj]
                    pyj = py[jj]
                    pzj = pz[jj]
                    nxj = nx[jj]
                    nyj = ny[jj]
                    nzj = nz[jj]
                    c = np.int64(0)
                    fi = big
                    if exact:
                        for q in range(nbuf):
                            dx = pxj - brx[q]
                            dy = pyj - bry[q]
                            dz = pzj - brz[q]
                            qx = c00[q] * dx + c01[q] * dy + c02[q] * dz
                            qy = c10[q] * dx + c11[q] * dy + c12[q] * dz
                            qz = c20[q] * dx + c21[q] * dy + c22[q] * dz
                            lim = tan_eta * qz
                            hit = (((-dx) * nxj + (-dy) * nyj + (-dz) * nzj > 0.0)
                                   & (qz > 0.0) & (abs(qx) <= lim) & (abs(qy) <= lim)
                                   & (qz >= near) & (qz <= far))
                            c += np.int64(hit)
                            fi = min(fi, np.int64(q) if hit else big)
                    else:
                        for q in range(nbuf):
                            rx = brx[q]
                            ry = bry[q]
                            rz = brz[q]
                            dx = pxj - rx
                            dy = pyj - ry
                            dz = pzj - rz
                            qx = c00[q] * dx + c01[q] * dy + c02[q] * dz
                            qy = c10[q] * dx + c11[q] * dy + c12[q] * dz
                            qz = c20[q] * dx + c21[q] * dy + c22[q] * dz
                            lim = tan_eta * qz
                            hit = ((rx * nxj + ry * nyj + rz * nzj >= 0.0)
                                   & (qz > 0.0) & (abs(qx) <= lim) & (abs(qy) <= lim)
                                   & (qz >= near) & (qz <= far))
                            c += np.int64(hit)
                            fi = min(fi, np.int64(q) if hit else big)
                    cnt[jj] += c
                    if fi < big:
                        fs[jj] = min(fs[jj], buf[12, fi])
            if not count_all:
                if t_full < np.inf:
                    done = True
                else:
                    unseen = 0
                    for jj in range(nb):
                        unseen += fs[jj] == np.inf
                    done = unseen == 0
                if done:
                    break
        for jj in range(nb):
            j = order[j0 + jj]
            cc = cnt[jj] + n_full
            times_seen[j] = cc if count_all else min(cc, 1)
            f = min(fs[jj], t_full)
            if f < np.inf:
                first_seen[j] = f
    observed = times_seen > 0
    cov, cov_n = coverage_fractions(observed, vertex_areas)
    return observed, first_seen, times_seen, cov, cov_n


@njit(parallel=True, cache=True)
def coverage_vertices(vertices, normals, vertex_areas, r_T, dcm_BT, image_times,
                      tan_eta, near, far, exact, active, count_all,
                      sin_min_elev, max_range, occlusion, illumination, sun_T,
                      node_bounds, node_info, tri, tri_vid):
    """Per-vertex coverage with every option, ``prange`` over vertices.

    With ``count_all=False`` only the union and first-seen time are computed
    (early-out): a spacecraft's image scan stops at its first hit, and images
    at or after the earliest hit found so far are skipped; ``times_seen`` is
    then 1 for observed vertices and 0 otherwise. With ``count_all=True`` every
    pair is tested and ``times_seen`` is the full count.

    Parameters
    ----------
    vertices, normals, vertex_areas, r_T, dcm_BT, image_times, tan_eta, near, far, exact, active
        As in :func:`coverage_counts`.
    count_all : bool
        Full counts (True) or union + first-seen with early-out (False).
    sin_min_elev : float
        Sine of the minimum elevation angle; ``-2.0`` disables the test.
    max_range : float
        Largest vertex-spacecraft range, m (``X D / lambda`` for ground
        resolution X, aperture D, wavelength lambda); ``inf`` disables it.
    occlusion, illumination : bool
        Self-occlusion and illumination (lit and unshadowed) tests.
    sun_T : (n_img, 3) float64
        Unit vector from the body to the Sun in T per image (read only when
        ``illumination``; pass a (1, 3) dummy otherwise).
    node_bounds, node_info, tri, tri_vid
        BVH of the mesh from :func:`ideas_hpc.core.bvh.build_bvh` (read only
        when ``occlusion`` or ``illumination``).

    Returns
    -------
    observed, first_seen, times_seen, coverage, coverage_count
        As in :func:`coverage_counts`.
    """
    nv = vertices.shape[0]
    nsc = r_T.shape[0]
    NF, NI = time_tree(r_T, dcm_BT, LEAF)
    sec_eta = np.sqrt(1.0 + tan_eta * tan_eta) * (1.0 + 1e-12)
    strict = occlusion or illumination or sin_min_elev > -1.0 or max_range < np.inf
    times_seen = np.zeros(nv, dtype=np.int32)
    first_seen = np.full(nv, np.nan)
    early = not count_all
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        best = np.inf
        cnt = 0
        for k in range(nsc):
            if not active[k]:
                continue
            c, best = _scan(j, k, NF, NI, stack, image_times, best, early, vertices,
                            normals, r_T, dcm_BT, tan_eta, sec_eta, near, far, exact,
                            strict, sin_min_elev, max_range, occlusion, illumination,
                            sun_T, node_bounds, node_info, tri, tri_vid)
            cnt += c
        if cnt > 0:
            first_seen[j] = best
            times_seen[j] = cnt if count_all else 1
    observed = times_seen > 0
    cov, cov_n = coverage_fractions(observed, vertex_areas)
    return observed, first_seen, times_seen, cov, cov_n


@njit(parallel=True, cache=True)
def observed_by_spacecraft(vertices, normals, r_T, dcm_BT, tan_eta, near, far, exact,
                           sin_min_elev, max_range, occlusion, illumination, sun_T,
                           node_bounds, node_info, tri, tri_vid):
    """Per-spacecraft observed mask (N, V): vertex j seen by spacecraft k in any image.

    The union over a subset of spacecraft is ``mask[subset].any(axis=0)``,
    which lets a genetic algorithm score swarms drawn from a pool of candidate
    ring angles without re-running the geometry. Each (k, j) scan stops at
    the first hit. Arguments as in :func:`coverage_vertices`.

    Returns
    -------
    mask : (N, V) bool
    """
    nv = vertices.shape[0]
    nsc = r_T.shape[0]
    nimg = r_T.shape[1]
    NF, NI = time_tree(r_T, dcm_BT, LEAF)
    sec_eta = np.sqrt(1.0 + tan_eta * tan_eta) * (1.0 + 1e-12)
    strict = occlusion or illumination or sin_min_elev > -1.0 or max_range < np.inf
    idx = np.arange(nimg).astype(np.float64)
    mask = np.zeros((nsc, nv), dtype=np.bool_)
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        for k in range(nsc):
            c, _ = _scan(j, k, NF, NI, stack, idx, np.inf, True, vertices, normals, r_T,
                         dcm_BT, tan_eta, sec_eta, near, far, exact, strict, sin_min_elev,
                         max_range, occlusion, illumination, sun_T, node_bounds, node_info,
                         tri, tri_vid)
            mask[k, j] = c > 0
    return mask
