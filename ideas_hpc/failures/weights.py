"""Survivor weights of a failure model: the law ``pi(T)`` of the survivors of an N-swarm.

The exact kernel (:func:`ideas_hpc.core.design.reliability.weighted_probabilities`)
enumerates every survivor set T of a swarm and adds ``pi(T)`` where the survivors
reach the threshold. It takes ``pi`` as one of

* ``(N + 1,)``, the weight ``w_k`` of *one* survivor set of k members, for an
  exchangeable model (:meth:`~ideas_hpc.failures.model.FailureModel.exchangeable`);
* ``(2^N,)``, ``pi(T)`` per survivor bit mask (bit k: member k), otherwise.

Exchangeable, per drawn p (``r = (1 - beta) p`` independent, ``c = beta p`` common
cause over the whole swarm, K members lost at random)::

    w_k = (1 - c) C(N - k, K) / C(N, K) (1 - r)^k r^(N - K - k) + c [k = 0]

(a survivor set T of k avoids the K-subset in ``C(N - k, K)`` of its ``C(N, K)``
equally likely choices, and the other ``N - K - k`` fail independently). Per mask,
per drawn p, the groups' factors multiply (their events are independent)::

    pi(T) = prod_g [ (1 - c_g) prod_{k in g} (k in T ? 1 - r_k : r_k) + c_g [T and g disjoint] ]

Both are averaged over the prior's nodes (:meth:`~ideas_hpc.failures.prior.Prior.nodes`:
polynomials of degree <= 2N + 1 in p, so exactly). With today's model
(:attr:`~ideas_hpc.failures.model.FailureModel.is_plain`) the count weights are
:func:`~ideas_hpc.core.design.reliability.independent_weights`, the kernel's own
``q ** k * p_f ** (n - k)``, so its sums are those of before bit for bit.

**Loss in the pass.** The scenario bank knows what a candidate sees over the whole
pass only, so the design scores a member lost in the pass as lost for the whole pass
(``score``): the partial image set is a superset of none, so this is a lower bound
on P (coverage is monotone). Proofs need an upper bound: the *upper model* counts a
member lost in the pass as a survivor (its partial set is a subset of the whole),
i.e. the survivors ``T_up = T u (lost members flagged in-pass)``, each loss flagged
independently with probability ``s``::

    pi_up(A) = (1 - s)^(N - |A|) sum_{T subset A} pi(T) s^(|A| - |T|)

(``proof``; ``score`` itself when ``s = 0``). ``counts[m] = P(|T_up| = m)`` and
``envelope[m] = max_{|T| = m} pi_up(T)`` serve the bounds
(:mod:`ideas_hpc.failures.sums`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.core.design.reliability import independent_weights
from ideas_hpc.failures.model import FailureModel

#: Largest swarm whose per-mask table is built (2^N values); above it the bounds of a
#: non-exchangeable model take ``envelope = counts`` (a valid, loose bound) and the
#: exact kernel is out of reach anyway (:data:`~ideas_hpc.design.reliability.N_ENUM_MAX`).
MASK_MAX = 24


@dataclass(frozen=True)
class SurvivorWeights:
    """The weights of one model at one swarm size (module docstring)."""

    n: int
    score: np.ndarray | None      # kernel weights, whole-pass scoring (None: n > MASK_MAX)
    proof: np.ndarray | None      # kernel weights of the upper model (``score`` when s = 0)
    counts: tuple                 # P(|T_up| = m), m = 0..n
    envelope: tuple               # max pi_up(T) over |T| = m
    exchangeable: bool

    @property
    def same(self) -> bool:
        """Scoring and proofs use one law (no loss in the pass)."""
        return self.proof is self.score


@functools.lru_cache(maxsize=48)
def survivor_weights(model: FailureModel, n: int) -> SurvivorWeights:
    """:class:`SurvivorWeights` of ``model`` for swarms of ``n`` (cached per model and size)."""
    n = int(n)
    model.check_size(n)
    s = model.in_pass_share
    if model.is_plain:
        p_f = model.p_f[0]
        score = independent_weights(p_f, n) if n <= MASK_MAX else None
        # the bounds' sums as they were written before: (C(n, j) p^j) q^(n-j), p^j q^(n-j)
        counts = tuple(math.comb(n, n - m) * p_f ** (n - m) * (1.0 - p_f) ** m
                       for m in range(n + 1))
        env = tuple(p_f ** (n - m) * (1.0 - p_f) ** m for m in range(n + 1))
        return SurvivorWeights(n, score, score, counts, env, True)
    if model.exchangeable(n):
        w = _count_weights(model, n)
        up = _thin_counts(w, s) if s > 0.0 else w
        counts = tuple(math.comb(n, m) * float(up[m]) for m in range(n + 1))
        small = n <= MASK_MAX
        return SurvivorWeights(n, w if small else None, up if small else None, counts,
                               tuple(float(x) for x in up), True)
    counts = tuple(float(x) for x in count_distribution(model, n))
    if n > MASK_MAX:
        return SurvivorWeights(n, None, None, counts, counts, False)
    table = _mask_table(model, n)
    up = _thin_masks(table, s) if s > 0.0 else table
    pop = _popcount(n)
    env = np.zeros(n + 1)
    np.maximum.at(env, pop, up)
    return SurvivorWeights(n, table, up, counts, tuple(float(x) for x in env), False)


def kernel_weights(model: FailureModel, n: int) -> np.ndarray:
    """The scoring weights of the exact kernel for swarms of ``n``."""
    return survivor_weights(model, n).score


def _degree(n: int) -> int:
    return 2 * int(n) + 1


def _count_weights(model: FailureModel, n: int) -> np.ndarray:
    """``w_k`` of an exchangeable model (module docstring), averaged over the prior."""
    ps, pw = model.p_nodes(_degree(n))
    kk = model.failures_k
    out = np.zeros(n + 1)
    k = np.arange(n + 1)
    for i, wt in enumerate(pw):
        q_f = model.member_q(n, None if ps is None else ps[i])[0] if n else 0.0
        r, c = (1.0 - model.beta) * q_f, model.beta * q_f
        if kk > n:
            g = (k == 0).astype(float)
        else:
            ok = k <= n - kk
            ways = np.array([math.comb(n - j, kk) / math.comb(n, kk) if j <= n - kk else 0.0
                             for j in k])
            g = np.where(ok, ways * (1.0 - r) ** k * r ** np.maximum(n - kk - k, 0), 0.0)
        out += wt * ((1.0 - c) * g + c * (k == 0))
    return out


def _popcount(n: int) -> np.ndarray:
    m = np.arange(1 << n, dtype=np.int64)
    pop = np.zeros(m.size, dtype=np.int64)
    for j in range(n):
        pop += (m >> j) & 1
    return pop


def _mask_table(model: FailureModel, n: int) -> np.ndarray:
    """``pi(T)`` per survivor mask (module docstring), averaged over the prior."""
    ps, pw = model.p_nodes(_degree(n))
    masks = np.arange(1 << n, dtype=np.int64)
    out = np.zeros(masks.size)
    for i, wt in enumerate(pw):
        q = model.member_q(n, None if ps is None else ps[i])
        table = np.ones(masks.size)
        for g in model.cc_groups(n):
            c = model.beta * max(q[j] for j in g)
            indep = np.ones(masks.size)
            gmask = 0
            for j in g:
                r = (1.0 - model.beta) * q[j]
                indep *= np.where((masks >> j) & 1, 1.0 - r, r)
                gmask |= 1 << j
            table *= (1.0 - c) * indep + c * ((masks & gmask) == 0)
        out += wt * table
    return out


def _thin_counts(w: np.ndarray, s: float) -> np.ndarray:
    """Upper-model weights by count: ``sum_{k' <= k} C(k, k') w_k' s^(k - k') (1 - s)^(n - k)``."""
    n = w.size - 1
    out = np.zeros(n + 1)
    for k in range(n + 1):
        out[k] = sum(math.comb(k, j) * w[j] * s ** (k - j) for j in range(k + 1)) \
            * (1.0 - s) ** (n - k)
    return out


def _thin_masks(table: np.ndarray, s: float) -> np.ndarray:
    """Upper-model weights per mask: the subset sum ``sum_{T subset A} pi(T) s^|A \\ T|``
    (one pass per member), times ``(1 - s)^(n - |A|)``."""
    n = int(round(math.log2(table.size)))
    g = table.copy()
    masks = np.arange(table.size, dtype=np.int64)
    for j in range(n):
        has = ((masks >> j) & 1).astype(bool)
        g[has] += s * g[masks[has] ^ (1 << j)]
    return g * (1.0 - s) ** (n - _popcount(n))


def count_distribution(model: FailureModel, n: int) -> np.ndarray:
    """``P(|T_up| = m)``, m = 0..n, of the upper model, without a 2^N table.

    Exchangeable: ``C(n, m) w_up[m]``. Otherwise the survivors' generating function,
    one factor per common-cause group (their events are independent), averaged over
    the prior: with group g's event (probability ``c_g``) every member is lost and
    survives in the upper model only when flagged in the pass, ``(1 - s + s z)^|g|``;
    without it member k survives with ``1 - r_k`` and is otherwise flagged with ``s``,
    ``prod_k ((1 - r_k) z + r_k (1 - s + s z))`` (z counts survivors).
    """
    n = int(n)
    s = model.in_pass_share
    if model.exchangeable(n):
        w = _count_weights(model, n)
        up = _thin_counts(w, s) if s > 0.0 else w
        return np.array([math.comb(n, m) * up[m] for m in range(n + 1)])
    ps, pw = model.p_nodes(_degree(n))
    out = np.zeros(n + 1)
    lost = np.array([1.0 - s, s])          # one lost member: up-survives with s
    for i, wt in enumerate(pw):
        q = model.member_q(n, None if ps is None else ps[i])
        gf = np.ones(1)
        for g in model.cc_groups(n):
            c = model.beta * max(q[j] for j in g)
            indep = np.ones(1)
            for j in g:
                r = (1.0 - model.beta) * q[j]
                indep = np.convolve(indep, np.array([r * (1.0 - s), (1.0 - r) + r * s]))
            gf = np.convolve(gf, (1.0 - c) * indep + c * _power(lost, len(g)))
        out += wt * _pad(gf, n)
    return out


def _power(f: np.ndarray, k: int) -> np.ndarray:
    out = np.ones(1)
    for _ in range(int(k)):
        out = np.convolve(out, f)
    return out


def _pad(f: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros(n + 1)
    out[:min(f.size, n + 1)] = f[:n + 1]
    return out


def all_lost(model: FailureModel, n: int) -> float:
    """``P(T_up = {})``: no member of n survives, even counting losses in the pass as
    survivals. ``1 - all_lost`` is the most any swarm of n can reach (``1 - p_f^N`` for
    today's model, computed as it was)."""
    if model.is_plain:
        return model.p_f[0] ** int(n)
    return float(count_distribution(model, n)[0])
