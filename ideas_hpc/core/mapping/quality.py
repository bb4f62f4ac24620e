"""Per-vertex observation quality: light, resolution, viewing angles, stereo (issue 14).

One compiled pass over all images (``prange`` over vertices, the time tree of
:mod:`ideas_hpc.core.mapping.time_tree` prunes image runs). An *observation* of vertex
``j`` is an image ``(k, i)`` that passes every visibility test of
:func:`ideas_hpc.core.mapping.visibility._seen` switched on by the options (culling,
clipping, elevation, range, occlusion, and illumination when it is a filter).
Over the observations of a vertex, with the line of sight ``l = r - p`` (vertex
-> spacecraft, m), the unit outward normal ``n`` and the unit Sun direction
``s`` of the image:

* emission ``e = atan2(|n x l|, n . l)``, incidence ``i = atan2(|n x s|, n . s)``,
  phase ``g = atan2(|s x l|, s . l)`` (rad; ``atan2`` of sine and cosine is
  accurate to an ulp at every angle, unlike ``acos`` near 0 and pi);
* effective ground sample ``X = rho |l| / cos e = rho |l|^2 / (n . l)`` (m),
  where ``rho`` is the angular sample: ``lambda / D`` (diffraction, as the
  sizing's eq. for the ground resolution) or ``pixel pitch / focal length``
  (detector IFOV). ``1 / cos e`` is the foreshortening of a tilted facet. When
  ``n . l <= 0`` (a paper-mode sighting from below the local horizon),
  ``X = inf``;
* lit: ``n . s > 0`` and the ray ``p + t s, t > 0`` crosses no face (the same
  BVH query as the strict illumination test); cached per image, since it does
  not depend on the spacecraft.

Outputs per vertex: ``lit`` (lit at some observation), ``best_resolution``
(smallest ``X``; ties go to the first observation in (spacecraft, image)
order) and ``emission/incidence/phase_at_best`` at that observation (NaN when
never observed), ``n_spacecraft_seen``, and

* ``usable`` observation: meets every per-image limit that is set (lit,
  ``X <= X_max``, ``e <= e_max``, ``i <= i_max``, ``g <= g_max``; the angle
  limits are tested on cosines, ``n . l >= |n| |l| cos e_max``,
  ``n . s >= |n| cos i_max``, ``s . l >= |l| cos g_max``, which needs no
  inverse trigonometry per image);
* ``stereo``: two different usable observations (one spacecraft's track or
  two spacecraft) whose unit lines of sight ``u1, u2`` satisfy
  ``cos(s_max) <= u1 . u2 <= cos(s_min)`` (convergence angle in
  ``[s_min, s_max]``);
* ``mapped``: a usable observation exists, and stereo when required.

Stereo is exact (identical to testing every pair) in O(M) typical work for M
usable observations (see :func:`_stereo`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.observations import L_SMAX, L_SMIN, _scan, quality_tests
from ideas_hpc.core.mapping.time_tree import scan_tree
from ideas_hpc.core.mapping.records import QualityTests, TimeTree, no_observations

#: Radius of the direction caps of the stereo test, rad (an efficiency knob
#: only; the result does not depend on it).
CAP_RADIUS = np.radians(0.5)
#: Angular slack of the cap bounds, rad: covers the rounding of ``acos`` near
#: 1 (~3e-8) and of the dot products, so cap decisions never contradict the
#: pairwise test.
_SLACK = 1e-6
#: Vertices per parallel chunk (scratch arrays are allocated once per chunk).
_CHUNK = 64


@njit(cache=True, inline="always")
def _angle(ax, ay, az, bx, by, bz):
    """Angle between two vectors, ``atan2(|a x b|, a . b)``, rad."""
    cx = ay * bz - az * by
    cy = az * bx - ax * bz
    cz = ax * by - ay * bx
    return np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)


@njit(cache=True)
def _pairs_in(U, a0, a1, b0, b1, same, order, cmin, cmax):
    """True when some pair (x in order[a0:a1], y in order[b0:b1]) has cmin <= u_x . u_y <= cmax."""
    for p in range(a0, a1):
        x = order[p]
        start = p + 1 if same else b0
        for q in range(start, b1):
            y = order[q]
            c = U[x, 0] * U[y, 0] + U[x, 1] * U[y, 1] + U[x, 2] * U[y, 2]
            if cmin <= c and c <= cmax:
                return True
    return False


@njit(cache=True)
def _stereo(U, m, smin, smax, cap, capc, caprad, capn, capstart, order, fill):
    """Exact: do two of the unit vectors ``U[:m]`` make an angle in [smin, smax]?

    The pairwise test is ``cos(smax) <= u_x . u_y <= cos(smin)``. Directions
    are grouped greedily into caps of radius :data:`CAP_RADIUS` around their
    first member (consecutive images fall into the same cap, so the last cap
    is tried first). For caps ``P, Q`` with centre angle ``t`` and member
    radii ``rP, rQ`` every member pair has an angle in
    ``[t - rP - rQ, t + rP + rQ]`` (triangle inequality on the sphere). A pair
    of caps whose interval lies inside ``[smin, smax]`` (with :data:`_SLACK`)
    decides True, one whose interval misses it is skipped, and only the
    undecided ones are tested member by member, with an early exit. The
    result is that of the pairwise test.
    """
    if m < 2:
        return False
    cmin = np.cos(smax)
    cmax = np.cos(smin)
    cos_cap = np.cos(CAP_RADIUS)
    K = 0
    last = -1
    for x in range(m):
        ux = U[x, 0]
        uy = U[x, 1]
        uz = U[x, 2]
        c = -1
        if last >= 0 and ux * capc[last, 0] + uy * capc[last, 1] + uz * capc[last, 2] >= cos_cap:
            c = last
        else:
            for q in range(K):
                if ux * capc[q, 0] + uy * capc[q, 1] + uz * capc[q, 2] >= cos_cap:
                    c = q
                    break
        if c < 0:
            c = K
            K += 1
            capc[c, 0] = ux
            capc[c, 1] = uy
            capc[c, 2] = uz
            caprad[c] = 0.0
            capn[c] = 0
        d = ux * capc[c, 0] + uy * capc[c, 1] + uz * capc[c, 2]
        caprad[c] = max(caprad[c], np.arccos(min(1.0, max(-1.0, d))))
        capn[c] += 1
        cap[x] = c
        last = c
    # members grouped by cap (counting sort)
    capstart[0] = 0
    for c in range(K):
        capstart[c + 1] = capstart[c] + capn[c]
        fill[c] = capstart[c]
    for x in range(m):
        order[fill[cap[x]]] = x
        fill[cap[x]] += 1
    for P in range(K):
        for Q in range(P, K):
            if P == Q:
                if capn[P] < 2:
                    continue
                lo = 0.0
                hi = 2.0 * caprad[P]
            else:
                d = (capc[P, 0] * capc[Q, 0] + capc[P, 1] * capc[Q, 1]
                     + capc[P, 2] * capc[Q, 2])
                t = np.arccos(min(1.0, max(-1.0, d)))
                lo = t - caprad[P] - caprad[Q]
                hi = t + caprad[P] + caprad[Q]
            if lo - _SLACK > smax or hi + _SLACK < smin:
                continue
            if lo - _SLACK >= smin and hi + _SLACK <= smax:
                return True
            if _pairs_in(U, capstart[P], capstart[P + 1], capstart[Q], capstart[Q + 1],
                         P == Q, order, cmin, cmax):
                return True
    return False


@njit(parallel=True, cache=True)
def quality_vertices(mesh, cam, active, opts, bvh, quality, require_stereo):
    """Coverage and observation quality per vertex in one pass (module docstring).

    Parameters
    ----------
    mesh, cam, active
        As in :func:`ideas_hpc.core.mapping.coverage.coverage_counts`.
    opts, bvh
        As in :func:`ideas_hpc.core.mapping.coverage.coverage_vertices` (the visibility
        tests; ``illumination`` True drops unlit observations); ``opts.sun_T``
        (n_img, 3), the unit body -> Sun direction per image, is always needed.
    quality : :class:`~ideas_hpc.core.mapping.records.Quality`
        Angular sample ``rho_rad`` (``lambda / D`` or ``pixel pitch / focal
        length``), ``limits`` ``[X_max (m), e_max, i_max, g_max, s_min, s_max
        (rad)]`` (``inf`` disables a maximum) and ``require_lit``.
    require_stereo : bool

    Returns
    -------
    times_seen : (V,) int32
        Observations (full count).
    first_seen : (V,) float64
        s, NaN when never observed.
    lit, stereo, mapped : (V,) bool
    best_resolution, emission, incidence, phase : (V,) float64
        m and rad; NaN when never observed.
    n_spacecraft : (V,) int32
    """
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    r_T = cam.r_T_m
    sun_T = opts.sun_T
    limits = quality.limits
    nv = vertices.shape[0]
    nsc = r_T.shape[0]
    nimg = r_T.shape[1]
    tree = TimeTree(*scan_tree(cam))
    tests = QualityTests(*quality_tests(quality))
    times_seen = np.zeros(nv, dtype=np.int32)
    first_seen = np.full(nv, np.nan)
    lit = np.zeros(nv, dtype=np.bool_)
    stereo = np.zeros(nv, dtype=np.bool_)
    mapped = np.zeros(nv, dtype=np.bool_)
    best_res = np.full(nv, np.nan)
    emission = np.full(nv, np.nan)
    incidence = np.full(nv, np.nan)
    phase = np.full(nv, np.nan)
    n_sc = np.zeros(nv, dtype=np.int32)
    nchunk = (nv + _CHUNK - 1) // _CHUNK
    mmax = nsc * nimg
    for ch in prange(nchunk):
        stack = np.empty(128, dtype=np.int64)
        lc = np.zeros(nimg, dtype=np.int8)
        U = np.empty((mmax, 3))
        cap = np.empty(mmax, dtype=np.int64)
        capc = np.empty((mmax, 3))
        caprad = np.empty(mmax)
        capn = np.empty(mmax, dtype=np.int64)
        capstart = np.empty(mmax + 1, dtype=np.int64)
        order = np.empty(mmax, dtype=np.int64)
        fill = np.empty(mmax, dtype=np.int64)
        for j in range(ch * _CHUNK, min(nv, (ch + 1) * _CHUNK)):
            lc[:] = 0
            px = vertices[j, 0]
            py = vertices[j, 1]
            pz = vertices[j, 2]
            nx = normals[j, 0]
            ny = normals[j, 1]
            nz = normals[j, 2]
            vusable = False
            nk = 0
            ob = no_observations(0, False)
            for k in range(nsc):
                if not active[k]:
                    continue
                ob = _scan(j, k, tree, stack, lc, mesh, cam, opts, bvh, tests, U, ob)
                vusable = vusable or ob.usable_k
                if ob.seen_k:
                    nk += 1
            m = ob.m
            vlit = ob.lit
            cnt = ob.count
            first = ob.first_s
            bres = ob.best_res_m
            bk = ob.best_k
            bi = ob.best_i
            times_seen[j] = cnt
            n_sc[j] = nk
            lit[j] = vlit
            if cnt > 0:
                first_seen[j] = first
                best_res[j] = bres
                lx = r_T[bk, bi, 0] - px
                ly = r_T[bk, bi, 1] - py
                lz = r_T[bk, bi, 2] - pz
                sx = sun_T[bi, 0]
                sy = sun_T[bi, 1]
                sz = sun_T[bi, 2]
                emission[j] = _angle(nx, ny, nz, lx, ly, lz)
                incidence[j] = _angle(nx, ny, nz, sx, sy, sz)
                phase[j] = _angle(sx, sy, sz, lx, ly, lz)
            st = _stereo(U, m, limits[L_SMIN], limits[L_SMAX], cap, capc, caprad, capn,
                         capstart, order, fill)
            stereo[j] = st
            mapped[j] = vusable and (st or not require_stereo)
    return (times_seen, first_seen, lit, best_res, emission, incidence, phase, n_sc,
            stereo, mapped)
