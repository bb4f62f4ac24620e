"""Per-spacecraft seen masks with coherent occlusion queries (issue 19 item 5).

The designers' candidate masks ask, per (spacecraft ``k``, vertex ``j``),
only *whether* some image sees the vertex (paper eq. 26 over one
spacecraft). :func:`seen_by_spacecraft` answers it with the exact scan of
the scenario rows (:func:`ideas_hpc.core.mapping.scenario_rows._scan_range`
over all images), which exploits what the occlusion queries of one
(spacecraft, vertex) have in common:

* the image runs of the time tree are pruned by culling and clipping
  (:func:`~ideas_hpc.core.mapping.time_tree._classify`) and by the elevation
  and range limits with the same motion bounds;
* a run whose sight lines all lie in a cone that the last blocking face
  covers is skipped whole
  (:func:`~ideas_hpc.core.mapping.segments.face_blocks_cone`, a proof);
* an image's occlusion query tests that face first
  (:func:`~ideas_hpc.core.mapping.segments.segment_hit`): any crossed face
  answers the any-hit query, so the answer is the BVH's.

Every answer is an exact per-image test or a proof from the bounds, so the
mask equals ``first_image_by_spacecraft(...) >= 0``
(:func:`ideas_hpc.core.mapping.coverage.observed_by_spacecraft`) bit for bit
(tests compare them on the ellipsoid and eros001708). On the main job's 720
strict candidates of eros001708, 97 % of the occlusion queries are blocked,
nearly always by the face that blocked the previous image: the masks take
about a fifth of the time of the per-image BVH scan, and the occlusion queries
cost less than Embree's (``benchmarks/bench_coverage.py``, Embree section).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.scenario_rows import _scan_range
from ideas_hpc.core.mapping.time_tree import LEAF, time_tree

__all__ = ["seen_by_spacecraft"]


@njit(cache=True, parallel=True)
def seen_by_spacecraft(vertices, normals, r_T, dcm_BT, tan_eta, near, far, exact,
                       sin_min_elev, max_range, occlusion, illumination, sun_T,
                       node_bounds, node_info, tri, tri_vid):
    """(N, V) bool: vertex ``j`` is seen by spacecraft ``k`` in some image.

    Arguments (SI: m, rad via ``tan_eta`` and ``sin_min_elev``) as
    :func:`ideas_hpc.core.mapping.coverage.observed_by_spacecraft`, whose
    result this equals; ``prange`` over vertices, one blocking-face hint per
    (spacecraft, vertex) scan.

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
    mask = np.zeros((nsc, nv), dtype=np.bool_)
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        hint = np.full(1, -1, dtype=np.int64)
        for k in range(nsc):
            hint[0] = -1
            mask[k, j] = _scan_range(j, k, 0, nimg, NF, NI, stack, hint, vertices, normals,
                                     r_T, dcm_BT, tan_eta, sec_eta, near, far, exact, strict,
                                     sin_min_elev, max_range, occlusion, illumination, sun_T,
                                     node_bounds, node_info, tri, tri_vid)
    return mask
