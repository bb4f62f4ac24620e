"""Ring-gap relaxation of the swarm design: a dynamic programme over sorted grid angles.

A swarm is a set of grid indices ``p_1 < ... < p_N`` on a circle of ``K``
candidates; consecutive members leave *gaps* ``(p_i, p_{i+1})`` (open, the
last one wrapping to ``p_1 + K``). A vertex group is certainly missed when
every candidate that sees it lies inside one gap. The kernels here minimise,
over all N-swarms, the total weight of groups lying inside a gap:

    miss(p) = sum_i M[p_i, p_{i+1} - p_i]

with ``M[i, d]`` the weight of the groups whose candidate set lies in the
open arc ``(i, i + d)``. That sum is additive over gaps, so the minimum is a
shortest path, ``O(N K^3 / 6)`` for all first members at once. Because a
group inside a gap is missed, ``miss(p)`` never exceeds the true missed
weight, and ``reach - min_p miss(p)`` is a proven upper bound on the coverage
any N grid candidates reach (:mod:`ideas_hpc.design.ring_bound` builds ``M``
and uses the bound). Grid distances between consecutive members must exceed
``m`` (the separation constraint of :func:`ideas_hpc.design.bank.conflict_windows`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(parallel=True, cache=True)
def gap_matrix_of(cover, weight):
    """``M[i, d]`` (K, K + 1): weight of the groups inside the open arc ``(i, i + d)``.

    Parameters
    ----------
    cover : (K, G) bool
        Which grid candidate sees which vertex group (every group seen by at
        least one candidate, as :func:`ideas_hpc.design.bank.reduce_problem`
        leaves them).
    weight : (G,) float64
        Group weights (area fractions).

    A group's candidate set lies inside an arc exactly when the arc contains
    the complement of one of the group's gaps (its circular runs of
    candidates that do not see it), itself an arc: start ``gap start + gap
    length``, length ``K - gap length``. ``M[i, d]`` sums the weights of the
    arcs that start inside ``(i, i + K)`` and end by ``i + d``; the sums are
    accumulated per row in the order groups, then gaps, appear (the order of
    the NumPy reference in the tests), then cumulated along ``d``.
    """
    k, g = cover.shape
    n_arcs = 0
    for j in range(g):
        for t in range(k):
            if not cover[t, j] and cover[t - 1 if t > 0 else k - 1, j]:
                n_arcs += 1
    a_start = np.empty(n_arcs, dtype=np.int64)
    a_len = np.empty(n_arcs, dtype=np.int64)
    a_w = np.empty(n_arcs)
    q = 0
    for j in range(g):
        i0 = -1
        for t in range(k):
            if cover[t, j]:
                i0 = t
                break
        full = True
        for t in range(k):
            if not cover[t, j]:
                full = False
                break
        if i0 < 0 or full:
            continue
        t = 0
        while t < k:                       # runs of "not seen", from the first seeing one
            if not cover[(t + i0) % k, j]:
                st = t
                while t < k and not cover[(t + i0) % k, j]:
                    t += 1
                gl = t - st
                a_start[q] = ((st + i0) % k + gl) % k
                a_len[q] = k - gl
                a_w[q] = weight[j]
                q += 1
            else:
                t += 1
    m = np.zeros((k, k + 1))
    for i in prange(k):
        for r in range(q):
            off = a_start[r] - i
            if off < 0:
                off += k
            need = off + a_len[r]
            if off >= 1 and need <= k:
                m[i, need] += a_w[r]
        for d in range(1, k + 1):
            m[i, d] += m[i, d - 1]
    return m


@njit(cache=True, fastmath={"nnan", "nsz"})
def _band_min(a, b, lo, hi):
    """``min(a[i] + b[i] for lo <= i < hi)`` (``inf`` when empty), four running minima
    at once: one running minimum is bound by its own latency."""
    b0 = np.inf
    b1 = np.inf
    b2 = np.inf
    b3 = np.inf
    i = lo
    while i + 3 < hi:
        b0 = min(b0, a[i] + b[i])
        b1 = min(b1, a[i + 1] + b[i + 1])
        b2 = min(b2, a[i + 2] + b[i + 2])
        b3 = min(b3, a[i + 3] + b[i + 3])
        i += 4
    while i < hi:
        b0 = min(b0, a[i] + b[i])
        i += 1
    return min(min(b0, b1), min(b2, b3))


@njit(cache=True)
def _arc_ends(M):
    """``E[j, i] = M[i, j - i]`` for ``i < j`` (inf elsewhere): the weight missed by a gap
    from member ``i`` to member ``j``, contiguous in ``i``."""
    K = M.shape[0]
    E = np.full((K, K), np.inf)
    for j in range(K):
        for i in range(j):
            E[j, i] = M[i, j - i]
    return E


@njit(cache=True, fastmath={"nnan", "nsz"})
def _layer_row(ps, cs, E, M, s, n, m):
    """Row ``s`` of layer ``n`` of the shortest path: ``cs[j]`` (least missed weight of
    ``n`` members from ``s`` to ``j``) from the previous layer's row ``ps``;
    returns the least miss of the closed ring (the last gap back to ``s + K``)."""
    K = M.shape[0]
    cs[s] = np.inf
    least = np.inf
    for j in range(s + 1, K):
        if n == 2:      # ps is 0 at s and inf elsewhere: the minimum is E[j, s]
            best = E[j, s] if s < j - m else np.inf
        else:
            best = _band_min(ps, E[j], s, j - m)
        cs[j] = best
        if s + K - j > m:
            v = best + M[j, s + K - j]
            if v < least:
                least = v
    return least


@njit(parallel=True, cache=True, fastmath={"nnan", "nsz"})
def ring_gap_bound(M, n_max, m, stop_miss, extra):
    """Least gap-missed weight of every swarm size, per first member.

    Parameters
    ----------
    M : (K, K + 1) float64
        ``M[i, d]``: weight (area fraction) of the groups inside the open arc
        ``(i, i + d)`` of grid indices (mod K); non-decreasing in ``d``.
    n_max : int
        Largest swarm size.
    m : int
        Consecutive members must be more than ``m`` grid steps apart.
    stop_miss : float
        Stop ``extra`` sizes after the first size whose least missed weight is
        ``<= stop_miss`` (the bound can no longer exclude it); ``-1`` computes
        every size.
    extra : int
        Sizes computed past that one (their swarms start local searches).

    Returns
    -------
    tot : (n_max + 1, K) float64
        ``tot[n, s]``: least missed weight of an n-swarm whose smallest index
        is ``s`` (``inf`` when none fits, rows after the stop are ``inf``).

    Notes
    -----
    The inner minimum runs over the previous member ``i`` with both operands
    contiguous in ``i``: ``E[j, i] = M[i, j - i]`` is laid out once per call
    (a strided ``M[i, j - i]`` walk cost most of the time). A minimum does not
    depend on the order of its terms and no NaN can occur (``inf + finite``
    only), so the vectorised loop (``fastmath`` without ``ninf``) gives the
    same numbers.
    """
    K = M.shape[0]
    tot = np.full((n_max + 1, K), np.inf)
    if n_max < 1:
        return tot
    E = _arc_ends(M)
    # two layers of the shortest path, one row per first member s
    prev = np.full((K, K), np.inf)
    cur = np.full((K, K), np.inf)
    low = np.inf
    for s in range(K):
        prev[s, s] = 0.0
        tot[1, s] = M[s, K]
        low = min(low, tot[1, s])
    left = extra if low <= stop_miss else -1
    if left == 0:
        return tot
    for n in range(2, n_max + 1):
        for s in prange(K):
            tot[n, s] = _layer_row(prev[s], cur[s], E, M, np.int64(s), np.int64(n),
                                   np.int64(m))
        prev, cur = cur, prev
        low = np.inf
        for s in range(K):
            low = min(low, tot[n, s])
        if left < 0 and low <= stop_miss:
            left = extra
        elif left > 0:
            left -= 1
        if left == 0:
            break
    return tot


@njit(cache=True)
def ring_gap_swarm(M, n, m, s):
    """The n-swarm with smallest index ``s`` reaching ``ring_gap_bound``'s ``tot[n, s]``.

    Returns ``(indices (n,) int64 sorted, missed weight)``; indices are -1 when
    no swarm fits.
    """
    K = M.shape[0]
    D = np.full((n + 1, K), np.inf)
    P = np.full((n + 1, K), -1, dtype=np.int64)
    D[1, s] = 0.0
    for k in range(2, n + 1):
        for j in range(s + 1, K):
            for i in range(s, j - m):
                v = D[k - 1, i] + M[i, j - i]
                if v < D[k, j]:
                    D[k, j] = v
                    P[k, j] = i
    out = np.full(n, -1, dtype=np.int64)
    if n == 1:
        out[0] = s
        return out, M[s, K]
    best = np.inf
    bj = -1
    for j in range(s + 1, K):
        if s + K - j > m:
            v = D[n, j] + M[j, s + K - j]
            if v < best:
                best = v
                bj = j
    j = bj
    for k in range(n, 0, -1):
        if j < 0:
            break
        out[k - 1] = j
        j = P[k, j]
    return out, best
