"""Building the time tree of an image sequence: runs of images with motion bounds.

The tree and its bounds (derivation below) for :mod:`ideas_hpc.core.mapping.time_tree`,
which walks it; split from there by topic (issue 31 added the per-axis bounds).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


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
#
# Per camera axis (issue 31). The bound above is the same for every component of
# ``q``, yet a flyby camera moves almost along one axis: in the main job the
# spacecraft's velocity is 0.999 along the camera's x and 0.001-0.003 along y, so
# a vertex at the y edge of the field of view stays there for the whole pass and
# ``delta`` (metres of motion per run) kept its runs undecided down to single
# images (1.8 M of a scenario's 2.8 M exact image tests failed the y test). Writing
#
#     q_k - q_m = (C_k - C_m)(p - r_m) - C_m (r_k - r_m) - (C_k - C_m)(r_k - r_m),
#
# component ``a`` moves by at most
#
#     |dq_a| <= E_a (|p - r_m| + R) + P_a,
#     E_a = max_k |row_a(C_k - C_m)|, R = max_k |r_k - r_m|,
#     P_a = max_k |row_a(C_m) . (r_k - r_m)|,
#
# (no ``s_k``: every term is explicit). For a parent with reference ``M`` and
# children ``c``: ``E_a <= E_a,c + |row_a(C_mc - C_M)|``, ``R <= R_c + |r_mc - r_M|``
# and ``P_a <= P_a,c + |row_a(C_M - C_mc)| R_c + |row_a(C_M) . (r_mc - r_M)|``. The
# tests use the smaller of this and ``delta``; a tree inflated for every camera
# within a deviation budget ``(b_C, b_r)`` (scenario_proofs.windows) adds ``b_C``
# to ``E_a``, ``b_r`` to ``R`` and ``S b_r`` to ``P_a``.

#: Images per leaf of the time tree.
LEAF = 16
#: Per-node float data: C_m (9, row major), r_m (3), |r_m|, e_C, e_r, S, unused,
#: then per camera axis E_x, E_y, E_z, R, P_x, P_y, P_z (see above).
_NF = 24
#: Index of E_x in a node's float data (E_a at _AX + a, R at _AX + 3, P_a at _AX + 4 + a).
_AX = 17


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


@njit(cache=True, inline="always")
def _row_gap2(dcm, k, i, m, a):
    """``|row_a(dcm[k, i] - dcm[k, m])|^2``."""
    return ((dcm[k, i, a, 0] - dcm[k, m, a, 0]) ** 2 + (dcm[k, i, a, 1] - dcm[k, m, a, 1]) ** 2
            + (dcm[k, i, a, 2] - dcm[k, m, a, 2]) ** 2)


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
    NI = tree_nodes(r_T.shape[1], leaf)
    NF = np.empty((nsc, NI.shape[0], _NF))
    for k in prange(nsc):
        # int64 as the bank's caller passes it (prange's index is uint64): one signature
        fill_tree(NF, NI, r_T, dcm_BT, np.int64(k), leaf)
    return NF, NI


@njit(cache=True)
def tree_nodes(nimg, leaf):
    """``NI`` of :func:`time_tree` for ``nimg`` images in leaves of ``leaf``."""
    counts, offs = _time_tree_shape(nimg, leaf)
    nlev = counts.shape[0]
    nn = offs[nlev]
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
    return NI


@njit(cache=True)
def fill_tree(NF, NI, r_T, dcm_BT, k, leaf, gram2=-1.0):
    """Fill ``NF[k]`` of :func:`time_tree` for spacecraft ``k`` (``NI`` from
    :func:`tree_nodes`): one spacecraft's tree, so that a kernel can build it
    right before it walks it, while that spacecraft's images are in cache.

    ``gram2`` >= 0: a bound on ``||C C^T - I||_F^2`` over all of ``k``'s images
    the caller has already computed (used for every leaf's ``S``); < 0: computed
    here per leaf."""
    nimg = r_T.shape[1]
    counts, offs = _time_tree_shape(nimg, leaf)
    nlev = counts.shape[0]
    grow = 1.0 + 1e-12
    for b in range(counts[0]):
        i0 = NI[b, 0]
        i1 = NI[b, 1]
        m = (i0 + i1 - 1) // 2
        _fill_ref(NF, k, b, r_T, dcm_BT, m)
        # maxima of squares, one root each after the loop (the roots per image
        # were most of the build); e_r = S * R >= max_k s_k |r_k - r_m|
        g2 = 0.0
        c2 = 0.0
        r2 = 0.0
        e2x = 0.0           # per camera axis: squared row gaps, then P_a
        e2y = 0.0
        e2z = 0.0
        p_x = 0.0
        p_y = 0.0
        p_z = 0.0
        if gram2 >= 0.0:
            g2 = gram2
        for i in range(i0, i1):
            if gram2 < 0.0:
                g2 = max(g2, gram_error2(dcm_BT, k, i))
            dx = r_T[k, i, 0] - r_T[k, m, 0]
            dy = r_T[k, i, 1] - r_T[k, m, 1]
            dz = r_T[k, i, 2] - r_T[k, m, 2]
            r2 = max(r2, dx * dx + dy * dy + dz * dz)
            gx = _row_gap2(dcm_BT, k, i, m, 0)
            gy = _row_gap2(dcm_BT, k, i, m, 1)
            gz = _row_gap2(dcm_BT, k, i, m, 2)
            e2x = max(e2x, gx)
            e2y = max(e2y, gy)
            e2z = max(e2z, gz)
            # ||C_i - C_m||_F^2 as the sum of the row gaps (not computed twice); its
            # rounding is far inside the 1e-12 growth of every bound
            c2 = max(c2, gx + gy + gz)
            p_x = max(p_x, abs(dcm_BT[k, m, 0, 0] * dx + dcm_BT[k, m, 0, 1] * dy
                               + dcm_BT[k, m, 0, 2] * dz))
            p_y = max(p_y, abs(dcm_BT[k, m, 1, 0] * dx + dcm_BT[k, m, 1, 1] * dy
                               + dcm_BT[k, m, 1, 2] * dz))
            p_z = max(p_z, abs(dcm_BT[k, m, 2, 0] * dx + dcm_BT[k, m, 2, 1] * dy
                               + dcm_BT[k, m, 2, 2] * dz))
        smax = np.sqrt(1.0 + np.sqrt(g2) * grow) * grow
        r0 = np.sqrt(r2) * grow
        NF[k, b, 13] = np.sqrt(c2) * grow
        NF[k, b, 14] = smax * r0 * grow
        NF[k, b, 15] = smax
        NF[k, b, 16] = 0.0
        NF[k, b, _AX] = np.sqrt(e2x) * grow
        NF[k, b, _AX + 1] = np.sqrt(e2y) * grow
        NF[k, b, _AX + 2] = np.sqrt(e2z) * grow
        NF[k, b, _AX + 3] = r0
        NF[k, b, _AX + 4] = p_x * grow
        NF[k, b, _AX + 5] = p_y * grow
        NF[k, b, _AX + 6] = p_z * grow
    for lv in range(1, nlev):
        for b in range(counts[lv]):
            node = offs[lv] + b
            m = (NI[node, 0] + NI[node, 1] - 1) // 2
            _fill_ref(NF, k, node, r_T, dcm_BT, m)
            ec = 0.0
            er = 0.0
            smax = 0.0
            for c in range(_AX, _NF):
                NF[k, node, c] = 0.0
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
                r_c = NF[k, c, _AX + 3]
                NF[k, node, _AX + 3] = max(NF[k, node, _AX + 3], r_c + dr)
                for a in range(3):
                    d_row = np.sqrt((NF[k, c, 3 * a] - NF[k, node, 3 * a]) ** 2
                                    + (NF[k, c, 3 * a + 1] - NF[k, node, 3 * a + 1]) ** 2
                                    + (NF[k, c, 3 * a + 2] - NF[k, node, 3 * a + 2]) ** 2)
                    shift = abs(NF[k, node, 3 * a] * (NF[k, c, 9] - NF[k, node, 9])
                                + NF[k, node, 3 * a + 1] * (NF[k, c, 10] - NF[k, node, 10])
                                + NF[k, node, 3 * a + 2] * (NF[k, c, 11] - NF[k, node, 11]))
                    NF[k, node, _AX + a] = max(NF[k, node, _AX + a],
                                               NF[k, c, _AX + a] + d_row)
                    NF[k, node, _AX + 4 + a] = max(NF[k, node, _AX + 4 + a],
                                                   NF[k, c, _AX + 4 + a] + d_row * r_c
                                                   + shift)
            NF[k, node, 13] = ec * grow
            NF[k, node, 14] = er * grow
            NF[k, node, 15] = smax
            NF[k, node, 16] = 0.0
            for c in range(_AX, _NF):
                NF[k, node, c] *= grow


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


@njit(cache=True)
def scan_tree_unfilled(cam):
    """:func:`scan_tree`'s fields with ``NF`` not yet filled: the caller fills
    spacecraft ``k``'s part with ``fill_tree(NF, NI, cam.r_T_m, cam.dcm_BT, k, LEAF)``
    before it reads it."""
    NI = tree_nodes(cam.r_T_m.shape[1], LEAF)
    NF = np.empty((cam.r_T_m.shape[0], NI.shape[0], _NF))
    return NF, NI, np.sqrt(1.0 + cam.tan_eta * cam.tan_eta) * (1.0 + 1e-12)
