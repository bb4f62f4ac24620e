"""Ring-gap screening over swarms and scenarios at once (issue 29, proof at scale).

The per-scenario ring-gap relaxation (:mod:`ideas_hpc.core.design.ring_gaps`)
says: in scenario s a swarm ``p_1 < .. < p_n`` of grid indices can cover only if
its gap misses sum to at most the scenario's slack::

    miss_s(p) = sum_i M_s[p_i, p_{i+1} - p_i] <= slack_s = reach_s - need

with ``M_s[i, d]`` the weight of the vertex groups inside the open arc
``(i, i + d)`` (the last gap wraps to ``p_1 + K``; a swarm of one member has
one gap, the whole ring but its member, ``d = K``, and ``M_s[i, K]`` is then
exactly the weight it does not see). The kernels here take one array
``Mt[i, d, s]`` for every scenario, already *clipped*: an entry above its
scenario's slack is ``+inf`` (that gap alone fails there), and gaps of ``Dn``
steps or more fail in every scenario (``M_s[i, d]`` grows with d, so the
columns from the first one that fails for every i on are dropped; a single
member that covers alone keeps ``Dn = K + 1``). Entries must never exceed the
true ``M_s`` (round down), so every count is an upper bound on the true one.

What the counts prove rests on (the assumptions of the screen's proof,
:func:`ideas_hpc.design.screen_bound.screen_size`):

* a vertex group is seen by a swarm when one member sees it (coverage is a
  union, so it is monotone: a subset never covers more);
* ``Mt`` is the full grid in grid order (one row per grid candidate, no merged
  candidates), every entry rounded *down* from the true ``M_s`` and set to
  ``+inf`` only above its scenario's slack;
* ``slack`` already holds the comparison's tolerance (the evaluator counts
  ``coverage >= need - 1e-12``; the caller adds more than that).

* :func:`screen_swarms` lists every n-swarm (gaps > ``m``) that the relaxation
  lets cover at least ``thr`` scenarios, for every ``n >= 1``: a depth-first
  search over sorted members that keeps, per level, the scenarios still alive
  and the partial misses, and stops a branch as soon as fewer than ``thr`` are
  alive (``n = 1``: each member alone against its full-ring gap).
* :func:`relaxed_probabilities` is the failure-weighted probability of swarms
  with every survivor set judged by the relaxation, an upper bound on the exact
  ``P_bank`` (:mod:`ideas_hpc.core.design.reliability`) under the failure model
  stated there.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.design.reliability import independent_weights


@njit(cache=True)
def _gap_miss(Mt, i, d, s):
    """``M_s[i, d]`` clipped (``+inf`` when the arc fails alone or ``d >= Dn``)."""
    if d >= Mt.shape[1]:
        return np.inf
    return Mt[i, d, s]


@njit(cache=True)
def _coprime(a, b):
    """``gcd(a, b) == 1`` (Euclid; ``gcd(0, b) = b``)."""
    a = abs(a)
    b = abs(b)
    while b:
        a, b = b, a % b
    return a == 1


@njit(cache=True)
def _single_count(Mt, slack, x0, k, thr):
    """Scenarios in which the member ``x0`` alone passes the relaxation: its one gap is
    the whole ring but itself, ``(x0, x0 + K)`` (stops counting once ``thr`` is out of
    reach and returns what it has)."""
    s_n = Mt.shape[2]
    na = 0
    for s in range(s_n):
        if _gap_miss(Mt, x0, k, s) <= slack[s]:
            na += 1
        elif na + s_n - s - 1 < thr:
            break
    return na


@njit(cache=True)
def screen_swarms(Mt, slack, n, m, thr, cap, max_nodes, x0_step=1):
    """Every n-swarm whose relaxed cover count is at least ``thr`` (module docstring).

    The list is complete (third return True) only when neither ``cap`` nor
    ``max_nodes`` stopped it; it is then every n-swarm with consecutive members
    more than ``m`` steps apart whose relaxed count reaches ``thr``, for every
    ``n >= 1`` (a one-member swarm is judged on its full-ring gap). The counts
    bound the true ones from above under the module docstring's assumptions.

    Parameters
    ----------
    Mt : (K, Dn, S) float32
        Clipped gap misses (area fractions), never above the true ones.
    slack : (S,) float64
        ``reach_s - need`` plus the comparison's tolerance.
    n : int
        Swarm size (>= 1; ``ValueError`` otherwise).
    m : int
        Consecutive members must be more than ``m`` grid steps apart (the wrap from
        the last to the first included; a single member has no neighbour).
    thr : int
        Least number of scenarios.
    cap : int
        Most swarms returned; the search stops after ``cap + 1`` (the caller
        treats that as too many).
    max_nodes : int
        Most members tried in all (a bound on the time); past it the search stops.
    x0_step : int
        The smallest members are taken in the order ``0, x0_step, 2 x0_step, ..`` (mod K;
        coprime with K, so every one is taken): a list cut short by ``cap`` then
        spreads around the ring instead of starting at candidate 0
        (``ValueError`` when not coprime: the list would miss members).

    Returns
    -------
    swarms : (F, n) int64
        Sorted grid indices, ``F <= cap + 1``.
    counts : (F,) int64
        Relaxed cover counts.
    complete : bool
        The list holds every such swarm (neither ``cap`` nor ``max_nodes`` was hit).
    """
    k, dn, s_n = Mt.shape
    if n < 1:
        raise ValueError("screen_swarms: n must be at least 1")
    if not _coprime(x0_step, k):
        raise ValueError("screen_swarms: x0_step must be coprime with the grid size")
    out = np.empty((cap + 1, n), dtype=np.int64)
    cnt = np.empty(cap + 1, dtype=np.int64)
    found = 0
    sw = np.empty(n, dtype=np.int64)
    alive = np.empty((n + 1, s_n), dtype=np.int64)      # scenario ids alive per level
    n_alive = np.zeros(n + 1, dtype=np.int64)
    acc = np.empty((n + 1, s_n), dtype=np.float64)      # partial miss of those scenarios
    nxt = np.empty(n + 1, dtype=np.int64)               # next candidate per level
    nodes = 0
    for xi in range(k):
        x0 = (xi * x0_step) % k
        sw[0] = x0
        if n == 1:          # no second member: the one gap wraps the whole ring
            nodes += 1
            if nodes > max_nodes:
                return out[:found], cnt[:found], False
            na = _single_count(Mt, slack, x0, k, thr)
            if na >= thr:
                out[found, 0] = x0
                cnt[found] = na
                found += 1
                if found > cap:
                    return out[:found], cnt[:found], False
            continue
        for j in range(s_n):
            alive[1, j] = j
            acc[1, j] = 0.0
        n_alive[1] = s_n
        lvl = 1
        nxt[1] = x0 + m + 1
        while lvl >= 1:
            c = nxt[lvl]
            prev = sw[lvl - 1]
            # members left after this one: n - lvl - 1, each gap < dn; the wrap to x0 + k too
            left = n - lvl
            hi = min(prev + dn - 1, x0 + k - (m + 1) * left, k - 1)
            lo = max(c, x0 + k - (dn - 1) * left)
            if c < lo:
                c = lo
            if c > hi:
                lvl -= 1
                if lvl >= 1:
                    nxt[lvl] += 1
                continue
            sw[lvl] = c
            nxt[lvl] = c
            nodes += 1
            if nodes > max_nodes:
                return out[:found], cnt[:found], False
            d = c - prev
            na = 0
            last = lvl == n - 1
            dw = x0 + k - c
            for q in range(n_alive[lvl]):
                s = alive[lvl, q]
                v = acc[lvl, q] + Mt[prev, d, s]
                if last:
                    v += _gap_miss(Mt, c, dw, s)
                if v <= slack[s]:
                    alive[lvl + 1, na] = s
                    acc[lvl + 1, na] = v
                    na += 1
                elif n_alive[lvl] - q - 1 + na < thr:
                    break
            if na < thr:
                nxt[lvl] += 1
                continue
            if last:
                out[found, :] = sw
                cnt[found] = na
                found += 1
                if found > cap:
                    return out[:found], cnt[:found], False
                nxt[lvl] += 1
                continue
            n_alive[lvl + 1] = na
            lvl += 1
            nxt[lvl] = c + m + 1
    return out[:found], cnt[:found], True


@njit(cache=True)
def _subset_covers(Mt, slack, s, members, mask, k):
    """The survivors ``members[mask]`` pass the relaxation in scenario s."""
    first = -1
    prev = -1
    tot = 0.0
    for i in range(members.size):
        if mask >> i & 1:
            if first < 0:
                first = members[i]
            else:
                tot += _gap_miss(Mt, prev, members[i] - prev, s)
                if tot > slack[s]:
                    return False
            prev = members[i]
    if first < 0:
        return False
    tot += _gap_miss(Mt, prev, first + k - prev, s)
    return tot <= slack[s]


@njit(cache=True)
def relaxed_probabilities(Mt, slack, swarms, p_f):
    """(F,) mean over scenarios of the failure-weighted probability, each survivor set
    judged by the relaxation: an upper bound on the exact ``P_bank`` (swarms sorted),
    under independent failures of probability ``p_f`` (:func:`relaxed_weighted`).

    ``P_s(X) = sum_{T subset X} (1-p_f)^|T| p_f^(n-|T|) 1[T passes the relaxation in s]``,
    the exact ``P_bank`` with each indicator replaced by one that is never smaller.
    It is an upper bound when (the failure model of
    :func:`ideas_hpc.design.reliability_stats.proof_failure_rate`): every spacecraft
    fails independently of the others and of the scenario, with the same ``p_f``,
    for the whole pass (a failed one images nothing, a working one all its pass);
    coverage is monotone (a scenario whose full swarm fails the relaxation is
    skipped: the full swarm does not cover there, so no subset does); and the
    module docstring's conditions on ``Mt`` and ``slack`` hold. Survivor sets of
    one member use their full-ring gap (``d = K``).
    """
    return relaxed_weighted(Mt, slack, swarms, independent_weights(p_f, swarms.shape[1]))


@njit(parallel=True, cache=True)
def relaxed_weighted(Mt, slack, swarms, weights):
    """:func:`relaxed_probabilities` with survivor sets weighted by ``weights`` (N + 1,), the
    weight of one survivor set by its size (issue 41: any failure model through
    :func:`ideas_hpc.failures.sums.count_envelope`, never below the set's own weight, so the
    result stays an upper bound on the exact ``P_bank`` of that model)."""
    k, dn, s_n = Mt.shape
    f_n, n = swarms.shape
    out = np.zeros(f_n)
    full = (1 << n) - 1
    for f in prange(f_n):
        members = swarms[f]
        tot = 0.0
        for s in range(s_n):
            if not _subset_covers(Mt, slack, s, members, full, k):
                continue
            for mask in range(1, full + 1):
                if _subset_covers(Mt, slack, s, members, mask, k):
                    alive = 0
                    for i in range(n):
                        alive += mask >> i & 1
                    tot += weights[alive]
        out[f] = tot / s_n
    return out
