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
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .bvh import segment_blocked

#: Vertices per tile of the tiled counting kernel (fits L1 with the image data).
BLOCK = 64


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


@njit(parallel=True, cache=True)
def coverage_counts(vertices, normals, vertex_areas, r_T, dcm_BT, image_times,
                    tan_eta, near, far, exact, active):
    """Full per-vertex counts, culling + clipping only (paper eq. 25-26), tiled.

    Every (spacecraft, image, vertex) triple is tested, so ``times_seen`` is
    complete. Vertices are processed in tiles of :data:`BLOCK`, one tile per
    ``prange`` iteration, with a branch-free inner loop over the tile.

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
    nimg = r_T.shape[1]
    times_seen = np.zeros(nv, dtype=np.int32)
    first_seen = np.full(nv, np.nan)
    nblk = (nv + BLOCK - 1) // BLOCK
    for blk in prange(nblk):
        j0 = blk * BLOCK
        nb = min(nv, j0 + BLOCK) - j0
        px = np.empty(BLOCK)
        py = np.empty(BLOCK)
        pz = np.empty(BLOCK)
        nx = np.empty(BLOCK)
        ny = np.empty(BLOCK)
        nz = np.empty(BLOCK)
        cnt = np.zeros(BLOCK, dtype=np.int32)
        fs = np.full(BLOCK, np.inf)
        for jj in range(nb):
            px[jj] = vertices[j0 + jj, 0]
            py[jj] = vertices[j0 + jj, 1]
            pz[jj] = vertices[j0 + jj, 2]
            nx[jj] = normals[j0 + jj, 0]
            ny[jj] = normals[j0 + jj, 1]
            nz[jj] = normals[j0 + jj, 2]
        for k in range(nsc):
            if not active[k]:
                continue
            for i in range(nimg):
                t = image_times[i]
                rx = r_T[k, i, 0]
                ry = r_T[k, i, 1]
                rz = r_T[k, i, 2]
                c00 = dcm_BT[k, i, 0, 0]
                c01 = dcm_BT[k, i, 0, 1]
                c02 = dcm_BT[k, i, 0, 2]
                c10 = dcm_BT[k, i, 1, 0]
                c11 = dcm_BT[k, i, 1, 1]
                c12 = dcm_BT[k, i, 1, 2]
                c20 = dcm_BT[k, i, 2, 0]
                c21 = dcm_BT[k, i, 2, 1]
                c22 = dcm_BT[k, i, 2, 2]
                for jj in range(nb):
                    dx = px[jj] - rx
                    dy = py[jj] - ry
                    dz = pz[jj] - rz
                    if exact:
                        cull = (-dx) * nx[jj] + (-dy) * ny[jj] + (-dz) * nz[jj] > 0.0
                    else:
                        cull = rx * nx[jj] + ry * ny[jj] + rz * nz[jj] >= 0.0
                    qx = c00 * dx + c01 * dy + c02 * dz
                    qy = c10 * dx + c11 * dy + c12 * dz
                    qz = c20 * dx + c21 * dy + c22 * dz
                    lim = tan_eta * qz
                    hit = (cull & (qz > 0.0) & (abs(qx) <= lim) & (abs(qy) <= lim)
                           & (qz >= near) & (qz <= far))
                    cnt[jj] += np.int32(hit)
                    fs[jj] = min(fs[jj], t if hit else np.inf)
        for jj in range(nb):
            times_seen[j0 + jj] = cnt[jj]
            if fs[jj] < np.inf:
                first_seen[j0 + jj] = fs[jj]
    observed = times_seen > 0
    cov, cov_n = coverage_fractions(observed, vertex_areas)
    return observed, first_seen, times_seen, cov, cov_n


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
    nimg = r_T.shape[1]
    times_seen = np.zeros(nv, dtype=np.int32)
    first_seen = np.full(nv, np.nan)
    for j in prange(nv):
        best = np.inf
        cnt = 0
        for k in range(nsc):
            if not active[k]:
                continue
            for i in range(nimg):
                t = image_times[i]
                if not count_all and t >= best:
                    break
                if _seen(j, k, i, vertices, normals, r_T, dcm_BT, tan_eta, near, far,
                         exact, sin_min_elev, max_range, occlusion, illumination, sun_T,
                         node_bounds, node_info, tri, tri_vid):
                    cnt += 1
                    if t < best:
                        best = t
                    if not count_all:
                        break
        if best < np.inf:
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
    mask = np.zeros((nsc, nv), dtype=np.bool_)
    for j in prange(nv):
        for k in range(nsc):
            for i in range(nimg):
                if _seen(j, k, i, vertices, normals, r_T, dcm_BT, tan_eta, near, far,
                         exact, sin_min_elev, max_range, occlusion, illumination, sun_T,
                         node_bounds, node_info, tri, tri_vid):
                    mask[k, j] = True
                    break
    return mask
