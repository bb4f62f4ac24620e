"""Test oracle: the previous tiled coverage kernel (spatial vertex tiles only).

An independent second implementation of
:func:`ideas_hpc.core.mapping.coverage.coverage_counts` (same arguments, same
results) that uses no time coherence: vertices are grouped into compact tiles
and whole tiles are rejected per image with conservative bounding-sphere and
normal-cone tests. Used by ``tests/test_coverage.py`` and
``benchmarks/bench_coverage.py`` as a cross-check; not part of the package.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.coverage import coverage_fractions

#: Vertices per tile of the tiled counting kernel.
BLOCK = 32
#: Images gathered per pass for a tile (SoA buffer of 13 x CHUNK doubles, ~27 kB).
CHUNK = 256
#: Relative slack of the conservative tile rejection tests (DCMs are accepted
#: by the boundary when orthonormal to 1e-6, so |C d| may differ from |d| by
#: that much; 1e-5 keeps the tile tests strictly on the safe side).
_SLACK = 1e-5


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
