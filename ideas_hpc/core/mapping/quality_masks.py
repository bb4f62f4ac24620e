"""Per-spacecraft observation quality: what each candidate alone contributes (issue 14).

The designers score swarms as unions of per-candidate rows, so they need,
for every candidate spacecraft ``k`` and vertex ``j``, with the definitions
of :mod:`ideas_hpc.core.mapping.quality` restricted to ``k``'s own images:

* ``usable[k, j]``: one of ``k``'s observations meets every per-image limit;
* ``stereo[k, j]``: two of ``k``'s usable observations form a stereo pair
  (convergence angle in ``[s_min, s_max]``), from its own track;
* ``resolution[k, j]``: ``k``'s best effective ground sample (m), ``inf``
  when ``k`` never observes ``j``.

A swarm's usable set and best resolution are exactly the union and the
minimum of its members' rows. Its stereo set contains the union of the
``stereo`` rows and may be larger (a pair from two spacecraft), which the
designers account for (:mod:`ideas_hpc.design.requirement`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.observations import L_SMAX, L_SMIN, _scan, quality_tests
from ideas_hpc.core.mapping.quality import _CHUNK, _stereo
from ideas_hpc.core.mapping.time_tree import scan_tree
from ideas_hpc.core.mapping.records import QualityTests, TimeTree, no_observations


@njit(parallel=True, cache=True)
def quality_by_spacecraft(mesh, cam, opts, bvh, quality):
    """Per-spacecraft usable, own-track stereo and best resolution (module docstring).

    Parameters
    ----------
    All as in :func:`ideas_hpc.core.mapping.quality.quality_vertices` (``cam.r_T_m`` is
    (K, n_img, 3) m for K candidate spacecraft, every one active).

    Returns
    -------
    usable, stereo : (K, V) bool
    resolution : (K, V) float64
        m; ``inf`` where the spacecraft never observes the vertex.
    """
    limits = quality.limits
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    nimg = cam.r_T_m.shape[1]
    tree = TimeTree(*scan_tree(cam))
    tests = QualityTests(*quality_tests(quality))
    usable = np.zeros((nsc, nv), dtype=np.bool_)
    stereo = np.zeros((nsc, nv), dtype=np.bool_)
    resolution = np.full((nsc, nv), np.inf)
    nchunk = (nv + _CHUNK - 1) // _CHUNK
    for ch in prange(nchunk):
        stack = np.empty(128, dtype=np.int64)
        lc = np.zeros(nimg, dtype=np.int8)
        U = np.empty((nimg, 3))
        cap = np.empty(nimg, dtype=np.int64)
        capc = np.empty((nimg, 3))
        caprad = np.empty(nimg)
        capn = np.empty(nimg, dtype=np.int64)
        capstart = np.empty(nimg + 1, dtype=np.int64)
        order = np.empty(nimg, dtype=np.int64)
        fill = np.empty(nimg, dtype=np.int64)
        for j in range(ch * _CHUNK, min(nv, (ch + 1) * _CHUNK)):
            lc[:] = 0       # lighting per image: shared by every spacecraft of this vertex
            for k in range(nsc):
                # vlit = True: the per-vertex 'lit' output is not needed here, so
                # shadow rays are cast only for the illumination filter and require_lit
                ob = _scan(j, k, tree, stack, lc, mesh, cam, opts, bvh, tests, U,
                           no_observations(0, True))
                usable[k, j] = ob.usable_k
                resolution[k, j] = ob.best_res_m
                if ob.m >= 2:
                    stereo[k, j] = _stereo(U, ob.m, limits[L_SMIN], limits[L_SMAX], cap, capc,
                                           caprad, capn, capstart, order, fill)
    return usable, stereo, resolution
