"""Exact failure-weighted success probability of a swarm (issues 20 and 41).

In one scenario (one draw of the continuous dispersions) the swarm of ``N``
members reaches the threshold with probability::

    P_s = sum_{T subset of swarm} pi(T) 1[cov_s(T) >= need]

with ``pi(T)`` the probability that exactly the members T survive
(:mod:`ideas_hpc.failures.weights`; independent failures of probability ``p_f``:
``pi(T) = (1 - p_f)^|T| p_f^(N - |T|)``),
where ``T`` is the set of survivors and ``cov_s(T)`` the area fraction seen
(or mapped) by the union of their rows. Exact evaluation without a loop over
vertices per subset: group the vertices by the bitmask ``b_v`` of members that
see them, ``W0[b] = sum_{v: b_v = b} w_v``; the subset-sum (zeta) transform
``f[B] = sum_{b subset of B} W0[b]`` gives the area no member of ``T`` sees as
``f[~T]`` (every vertex whose seers all failed), so ``cov_s(T) = sum w - f[~T]``.
Cost per scenario ``O(N V + N 2^N)``.

Vertex weights (issue 42): every kernel takes ``w`` either ``(V,)``, one weight vector
shared by every scenario, or ``(S_w, V)``, the weight of vertex v in scenario s (a drawn
world: same mesh, different vertex areas and reference area), read as row ``s`` when
``S_w > 1`` and row 0 otherwise (:func:`weight_row`). The sums run over the same
vertices in the same order either way, so shared weights give the same floats.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

#: Absolute slack on the coverage comparison (area fractions): the solver and
#: the bank compare unions of the same float sums.
COVER_TOL = 1e-12


@njit(cache=True)
def independent_weights(p_f, n):
    """(n + 1,) weight of one survivor set of k members under independent failures,
    ``(1 - p_f)^k p_f^(n - k)``, computed as the kernel always has (``q ** k * p_f ** (n - k)``
    with integer powers), so sums over it are the same floats as before issue 41.

    Parameters
    ----------
    p_f : float
        Per-spacecraft failure probability, 0..1.
    n : int
        Swarm size.
    """
    q = 1.0 - p_f
    out = np.empty(n + 1)
    for k in range(n + 1):
        out[k] = q ** k * p_f ** (n - k)
    return out


@njit(cache=True)
def weight_row(w, s):
    """(V,) view of the weights of scenario ``s``: ``w`` itself when 1-D (shared), else
    row ``s`` of ``(S_w, V)``, row 0 when ``S_w = 1`` (module docstring)."""
    w2 = w.reshape((-1, w.shape[-1]))
    return w2[s if w2.shape[0] > 1 else 0]


@njit(cache=True)
def weighted_probability(rows, s, members, w, need, weights):
    """Probability that the swarm ``members`` reaches ``need`` in scenario ``s``, its
    survivor sets weighted by ``weights`` (module docstring, ``pi(T)`` for ``p_f``).

    Parameters
    ----------
    rows : (S, C, V) bool
        Vertex v seen (or mapped) by candidate c in scenario s.
    s : int
        Scenario index.
    members : (N,) int64
        Candidate indices of the swarm (N <= 30); bit i of a survivor mask is member i.
    w : (V,) or (S_w, V) float64
        Vertex area fractions (each row sums to 1), shared or per scenario
        (:func:`weight_row`).
    need : float
        Threshold coverage, area fraction.
    weights : (N + 1,) or (2^N,) float64
        ``pi(T)``: by survivor count (an exchangeable failure model: the weight of one
        set of k survivors) or per survivor mask
        (:func:`ideas_hpc.failures.weights.survivor_weights`). For N = 1 both read the same.

    Returns
    -------
    float
        ``sum_T pi(T) 1[cov_s(T) >= need]``, 0..1.
    """
    n = members.size
    full = (1 << n) - 1
    f = np.zeros(1 << n)
    ws = weight_row(w, s)
    v_n = ws.size
    total = 0.0
    for v in range(v_n):
        b = 0
        for i in range(n):
            if rows[s, members[i], v]:
                b |= 1 << i
        f[b] += ws[v]
        total += ws[v]
    for i in range(n):
        bit = 1 << i
        for m in range(1 << n):
            if m & bit:
                f[m] += f[m ^ bit]
    by_mask = weights.size != n + 1
    out = 0.0
    for t in range(1 << n):
        if total - f[full ^ t] >= need - COVER_TOL:
            if by_mask:
                out += weights[t]
            else:
                k = 0
                x = t
                while x:
                    x &= x - 1
                    k += 1
                out += weights[k]
    return out


@njit(cache=True, parallel=True)
def weighted_probabilities(rows, swarms, w, need, weights):
    """(K, S) :func:`weighted_probability` of many swarms of one size in every scenario.

    Parameters
    ----------
    rows : (S, C, V) bool
    swarms : (K, N) int64
        Candidate indices, one swarm per row.
    w : (V,) or (S, V) float64
        Vertex area fractions, shared or per scenario (:func:`weight_row`).
    need : float
        Threshold coverage, area fraction.
    weights : (N + 1,) or (2^N,) float64
        Survivor weights (:func:`weighted_probability`).
    """
    k_n = swarms.shape[0]
    s_n = rows.shape[0]
    out = np.empty((k_n, s_n))
    for j in prange(k_n * s_n):
        k = j // s_n
        s = j - k * s_n
        out[k, s] = weighted_probability(rows, s, swarms[k], w, need, weights)
    return out


@njit(cache=True)
def scenario_probability(rows, s, members, w, need, p_f):
    """:func:`weighted_probability` under independent failures of probability ``p_f``
    (:func:`independent_weights`): the module docstring's ``P_s``."""
    return weighted_probability(rows, s, members, w, need,
                                independent_weights(p_f, members.size))


@njit(cache=True)
def swarm_probabilities(rows, swarms, w, need, p_f):
    """(K, S) :func:`weighted_probabilities` under independent failures of probability
    ``p_f``; the bank's probability of a swarm is its row mean."""
    return weighted_probabilities(rows, swarms, w, need,
                                  independent_weights(p_f, swarms.shape[1]))


@njit(cache=True)
def minimal_sets(packed):
    """Keep the sets no other kept set is contained in (subset-minimal rows).

    Parameters
    ----------
    packed : (G, W) uint64
        Bit sets, sorted by increasing population count.

    Returns
    -------
    (G,) bool
        True for a set that contains no earlier kept set (a row ``sum_{c in A} x_c >= z``
        is implied by the row of any subset of ``A``).
    """
    g_n, w_n = packed.shape
    keep = np.zeros(g_n, dtype=np.bool_)
    kept = np.empty(g_n, dtype=np.int64)
    n_kept = 0
    for g in range(g_n):
        dominated = False
        for i in range(n_kept):
            k = kept[i]
            sub = True
            for j in range(w_n):
                if packed[k, j] & ~packed[g, j]:
                    sub = False
                    break
            if sub:
                dominated = True
                break
        if not dominated:
            keep[g] = True
            kept[n_kept] = g
            n_kept += 1
    return keep


@njit(cache=True, parallel=True)
def swarm_coverages(rows, swarms, w):
    """(K, S) area fraction of the union of each swarm's rows in each scenario.

    Parameters
    ----------
    rows : (S, C, V) bool
    swarms : (K, N) int64
    w : (V,) or (S, V) float64
        Vertex area fractions, shared or per scenario (:func:`weight_row`).
    """
    k_n, n = swarms.shape
    s_n, _, v_n = rows.shape
    out = np.zeros((k_n, s_n))
    for j in prange(k_n * s_n):
        k = j // s_n
        s = j - k * s_n
        ws = weight_row(w, s)
        a = 0.0
        for v in range(v_n):
            for i in range(n):
                if rows[s, swarms[k, i], v]:
                    a += ws[v]
                    break
        out[k, s] = a
    return out
