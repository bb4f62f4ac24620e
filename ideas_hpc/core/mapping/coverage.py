"""Coverage kernels: which mesh vertices the swarm's cameras observe (SPEC section 6).

The visibility tests of one (vertex, spacecraft, image) triple (paper culling
and clipping, eq. 25, and the strict options) are written and derived in
:mod:`ideas_hpc.core.mapping.visibility`; the time tree of image runs that lets the
kernels accept or reject whole runs of images is in
:mod:`ideas_hpc.core.mapping.time_tree`. This module reduces them over vertices,
spacecraft and images.

The observed set is the union over spacecraft and images (paper eq. 26). Per
vertex the kernels return whether it was observed, the first image time it was
seen (NaN when never) and how many (spacecraft, image) pairs saw it, plus the
area-weighted coverage ``sum(A_j observed) / sum(A_j)`` and the vertex-count
fraction.

Image times must be non-decreasing (the boundary checks it): the early-out
kernels stop scanning a spacecraft's images at its first hit, and skip images
later than the earliest hit found so far.

Speed (see ``benchmarks/bench_coverage.py``): per (vertex, spacecraft) the
kernels walk the time tree (:func:`~ideas_hpc.core.mapping.time_tree.time_tree`);
results are identical to testing every image (tests compare bit for bit with
an un-pruned evaluation). With occlusion, each image's query starts at the
face that blocked the scan's previous image (97 % of the main job's queries
are blocked, nearly always by that face; the same any-hit answer). An
independent second implementation (spatial
vertex tiles, no time coherence) lives in ``tests/coverage_tiles.py`` as a
cross-check.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.time_tree import LEAF, _scan, time_tree

__all__ = ["LEAF", "coverage_counts", "coverage_fractions", "coverage_vertices",
           "dcm_check", "first_image_by_spacecraft", "observed_by_spacecraft", "time_tree"]


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
        BVH of the mesh from :func:`ideas_hpc.core.mapping.bvh.build_bvh` (read only
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


@njit(cache=True)
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
    return first_image_by_spacecraft(vertices, normals, r_T, dcm_BT, tan_eta, near, far,
                                     exact, sin_min_elev, max_range, occlusion, illumination,
                                     sun_T, node_bounds, node_info, tri, tri_vid) >= 0


@njit(cache=True, parallel=True)
def first_image_by_spacecraft(vertices, normals, r_T, dcm_BT, tan_eta, near, far, exact,
                              sin_min_elev, max_range, occlusion, illumination, sun_T,
                              node_bounds, node_info, tri, tri_vid):
    """(N, V) int64: first image index at which spacecraft k sees vertex j, -1 if never.

    Arguments as :func:`observed_by_spacecraft` (whose mask is ``>= 0`` of this).
    """
    nv = vertices.shape[0]
    nsc = r_T.shape[0]
    nimg = r_T.shape[1]
    NF, NI = time_tree(r_T, dcm_BT, LEAF)
    sec_eta = np.sqrt(1.0 + tan_eta * tan_eta) * (1.0 + 1e-12)
    strict = occlusion or illumination or sin_min_elev > -1.0 or max_range < np.inf
    idx = np.arange(nimg).astype(np.float64)
    out = np.full((nsc, nv), -1, dtype=np.int64)
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        for k in range(nsc):
            c, best = _scan(j, k, NF, NI, stack, idx, np.inf, True, vertices, normals, r_T,
                            dcm_BT, tan_eta, sec_eta, near, far, exact, strict, sin_min_elev,
                            max_range, occlusion, illumination, sun_T, node_bounds, node_info,
                            tri, tri_vid)
            if c > 0:
                out[k, j] = int(best)
    return out
