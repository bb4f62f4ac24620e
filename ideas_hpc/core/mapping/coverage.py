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

from ideas_hpc.core.mapping.time_tree import LEAF, _scan, scan_tree, time_tree
from ideas_hpc.core.mapping.records import Bvh, Camera, Strict, TimeTree

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
def coverage_counts(mesh, cam, active, count_all):
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
    mesh : :class:`~ideas_hpc.core.mapping.records.Mesh`
        Vertex positions (m), outward unit normals and areas (m^2) in frame T.
    cam : :class:`~ideas_hpc.core.mapping.records.Camera`
        Spacecraft positions (m) and camera DCMs (B <- T, boresight +z_B) per
        image, image times (s, non-decreasing), ``tan(eta)`` of the square
        field of view, clipping distances (m, ``0 < near < far``) and whether
        culling is exact (``(r - p) . n > 0``) instead of the paper's ``r . n >= 0``.
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
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    tree = TimeTree(*scan_tree(cam))
    times_seen = np.zeros(nv, dtype=np.int32)
    first_seen = np.full(nv, np.nan)
    opts = Strict(-2.0, np.inf, False, False, np.zeros((1, 3)))
    bvh = Bvh(np.zeros((1, 6)), np.full((1, 4), -1, dtype=np.int64), np.zeros((1, 9)),
              np.zeros((1, 3), dtype=np.int64))
    early = not count_all
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        best = np.inf
        cnt = 0
        for k in range(nsc):
            if not active[k]:
                continue
            s = _scan(j, k, tree, stack, best, early, mesh, cam, False, bvh, opts)
            best = s.first_s
            cnt += s.count
        if cnt > 0:
            first_seen[j] = best
            times_seen[j] = cnt if count_all else 1
    observed = times_seen > 0
    cov, cov_n = coverage_fractions(observed, mesh.areas_m2)
    return observed, first_seen, times_seen, cov, cov_n


@njit(parallel=True, cache=True)
def coverage_vertices(mesh, cam, active, count_all, opts, bvh):
    """Per-vertex coverage with every option, ``prange`` over vertices.

    With ``count_all=False`` only the union and first-seen time are computed
    (early-out): a spacecraft's image scan stops at its first hit, and images
    at or after the earliest hit found so far are skipped; ``times_seen`` is
    then 1 for observed vertices and 0 otherwise. With ``count_all=True`` every
    pair is tested and ``times_seen`` is the full count.

    Parameters
    ----------
    mesh, cam, active
        As in :func:`coverage_counts`.
    count_all : bool
        Full counts (True) or union + first-seen with early-out (False).
    opts : :class:`~ideas_hpc.core.mapping.records.Strict`
        Minimum elevation (its sine; ``-2.0`` disables it), largest
        vertex-spacecraft range (m, ``X D / lambda`` for ground resolution X,
        aperture D, wavelength lambda; ``inf`` disables it), the
        self-occlusion and illumination (lit and unshadowed) tests, and the
        unit body -> Sun direction per image in T (read only when
        ``illumination``; a (1, 3) dummy otherwise).
    bvh : :class:`~ideas_hpc.core.mapping.records.Bvh`
        BVH of the mesh from :func:`ideas_hpc.core.mapping.bvh.build_bvh` (read only
        when occlusion or illumination is on).

    Returns
    -------
    observed, first_seen, times_seen, coverage, coverage_count
        As in :func:`coverage_counts`.
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    tree = TimeTree(*scan_tree(cam))
    strict = _is_strict(opts)
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
            s = _scan(j, k, tree, stack, best, early, mesh, cam, strict, bvh, opts)
            best = s.first_s
            cnt += s.count
        if cnt > 0:
            first_seen[j] = best
            times_seen[j] = cnt if count_all else 1
    observed = times_seen > 0
    cov, cov_n = coverage_fractions(observed, mesh.areas_m2)
    return observed, first_seen, times_seen, cov, cov_n


@njit(cache=True, inline="always")
def _is_strict(opts):
    """Some strict option is on (the time tree then only prunes)."""
    return (opts.occlusion or opts.illumination or opts.sin_min_elev > -1.0
            or opts.max_range_m < np.inf)


@njit(cache=True)
def observed_by_spacecraft(mesh, cam, opts, bvh):
    """Per-spacecraft observed mask (N, V): vertex j seen by spacecraft k in any image.

    The union over a subset of spacecraft is ``mask[subset].any(axis=0)``,
    which lets a genetic algorithm score swarms drawn from a pool of candidate
    ring angles without re-running the geometry. Each (k, j) scan stops at
    the first hit. Arguments as in :func:`coverage_vertices` (the image times
    are not read).

    Returns
    -------
    mask : (N, V) bool
    """
    return first_image_by_spacecraft(mesh, cam, opts, bvh) >= 0


@njit(cache=True, parallel=True)
def first_image_by_spacecraft(mesh, cam, opts, bvh):
    """(N, V) int64: first image index at which spacecraft k sees vertex j, -1 if never.

    Arguments as :func:`observed_by_spacecraft` (whose mask is ``>= 0`` of this).
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    nimg = cam.r_T_m.shape[1]
    tree = TimeTree(*scan_tree(cam))
    strict = _is_strict(opts)
    # the scan's "times" are the image indices
    cam_i = Camera(cam.r_T_m, cam.dcm_BT, np.arange(nimg).astype(np.float64), cam.tan_eta,
                   cam.near_m, cam.far_m, cam.exact)
    out = np.full((nsc, nv), -1, dtype=np.int64)
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        for k in range(nsc):
            s = _scan(j, k, tree, stack, np.inf, True, mesh, cam_i, strict, bvh, opts)
            if s.count > 0:
                out[k, j] = int(s.first_s)
    return out
