"""Whole-population swarm coverage from per-spacecraft observation masks.

Spacecraft of a swarm do not interact: each one's trajectory, attitude and
images depend only on its own swarm angle (and sweep period), so the swarm's
observed set is the union of per-spacecraft sets (paper eq. 26). The GA
evaluates a whole population at once by indexing precomputed masks.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, parallel=True)
def population_coverage(masks, members, vertex_areas, total_area):
    """Area and count coverage of every individual's swarm (paper eq. 26).

    Parameters
    ----------
    masks : (K, V) bool
        Vertex j is observed by candidate spacecraft k.
    members : (P, M) int64
        Candidate indices of each individual's spacecraft; -1 marks an unused slot.
    vertex_areas : (V,) float64
        m^2.
    total_area : float
        m^2 (sum of ``vertex_areas``).

    Returns
    -------
    cov, cov_n : (P,) float64
        Area-weighted and vertex-count fraction observed, 0..1.
    """
    p, m = members.shape
    v = masks.shape[1]
    cov = np.zeros(p)
    cov_n = np.zeros(p)
    for i in prange(p):
        seen = np.zeros(v, dtype=np.bool_)
        for s in range(m):
            k = members[i, s]
            if k < 0:
                continue
            for j in range(v):
                if masks[k, j]:
                    seen[j] = True
        a = 0.0
        c = 0
        for j in range(v):
            if seen[j]:
                a += vertex_areas[j]
                c += 1
        cov[i] = a / total_area
        cov_n[i] = c / v
    return cov, cov_n
