"""The weighted sums the success-probability proofs rest on, in one place (issues 20, 29, 41).

Every proof bounds ``P(X) = sum_T pi(T) U(T)`` from above (``U(T)``: the fraction of
scenarios the survivors T cover) by bounding ``U`` and taking the weights of the
*upper* model (:mod:`ideas_hpc.failures.weights`: losses in the pass counted as
survivals, so ``P_true <= P_up``). Two forms of the weights serve:

* ``counts[m] = P(|T_up| = m)``, exact for any model (``C(n, m) w_m`` for an
  exchangeable one, ``C(n, j) p_f^j (1 - p_f)^(n-j)`` with ``j = n - m`` for
  independent failures), where a bound depends on ``|T|`` only
  (:func:`level_bound`);
* ``envelope[m] >= pi_up(T)`` for every T of m, where a bound picks *which* sets
  (:func:`downset_bound`, :func:`screen_terms`). For an exchangeable model it is
  the weight ``w_m`` itself (every set of m weighs the same), so the bounds are
  those of the papers' binomial sums with ``p_f^j (1 - p_f)^(n-j)`` replaced by
  ``w_{n-j}``. For a non-exchangeable model (per-spacecraft p_f, stated groups) it
  is the heaviest set of m, ``max_{|T| = m} pi_up(T)``: every sum of ``pi_up``
  over a family of sets is at most the same family counted at the envelope, since
  the terms are nonnegative, so the bounds stay valid (looser, and possibly above 1;
  each is clipped to 1).

With today's model the sums are computed in the same order as before issue 41
(``C(n, j) p^j q^(n-j) U`` left to right), so the numbers are the same floats.
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.failures.model import as_model
from ideas_hpc.failures.weights import survivor_weights


def weights_of(model, n: int):
    """The :class:`~ideas_hpc.failures.weights.SurvivorWeights` of ``model`` (a
    :class:`~ideas_hpc.failures.model.FailureModel` or a bare ``p_f``) at size n."""
    return survivor_weights(as_model(model), int(n))


def level_bound(n: int, u_bar, model) -> float:
    """``sum_j P(j lost) U_{n-j}``, an upper bound on any n-swarm's P.

    With failure set ``F`` (``|F| = j``) the survivors form an ``(n - j)``-swarm, which
    reaches at most the fraction ``U_{n-j}`` of the scenarios; averaging over the
    failures gives the bound, for any law of F (only ``P(|T_up| = m)`` enters).
    ``u_bar[m]`` bounds ``U_m`` (``u_bar[0] = 0``: no survivor maps nothing).
    """
    c = weights_of(model, n).counts
    total = 0.0
    for j in range(n + 1):
        total += c[n - j] * u_bar[n - j]
    return min(1.0, total)


def downset_bound(n: int, model, n0: int, k_star: int | None) -> float:
    """``sum_{j <= n - n0} env_{n-j} [C(n, j) - C(n - k*, j - k*)]``: the heaviest down-set
    of failed sets allowed in one scenario (:mod:`ideas_hpc.design.tolerance_bound`: no
    failed set above ``n - n0``, and none containing one fixed k*-set). Every failed set
    of the family weighs at most ``env_{n-j}``; for an exchangeable model exactly that,
    so the bound is the heaviest family's weight.
    """
    if n < n0 or n <= 0:
        return 0.0
    env = weights_of(model, n).envelope
    out = 0.0
    for j in range(0, n - max(n0, 0) + 1):
        cnt = math.comb(n, j)
        if k_star is not None and 1 <= k_star <= j:
            cnt -= math.comb(n - k_star, j - k_star)
        out += env[n - j] * cnt
    return min(1.0, out)


def screen_terms(n: int, u_bar, model) -> tuple[float, float]:
    """``(base, one)`` of the screen's decomposition (:mod:`ideas_hpc.design.screen_bound`).

    ``P(X) = pi(X) U(X) + sum_i pi(X - x_i) U(X - x_i) + (two or more lost)``: ``base``
    bounds the first and last parts, ``env_n Ubar_n + sum_{j >= 2} P(j lost) Ubar_{n-j}``
    (``pi(X) = env_n``: one set of n); ``one = env_{n-1}`` bounds each single-loss
    weight, so ``X`` reaches p only if ``sum_i U(X - x_i) >= (p - base) / one``.
    """
    sw = weights_of(model, n)
    rest = 0.0
    for j in range(2, n + 1):
        rest += sw.counts[n - j] * u_bar[n - j]
    return sw.envelope[n] * u_bar[n] + rest, sw.envelope[n - 1]


def count_envelope(model, n: int) -> np.ndarray:
    """(n + 1,) kernel weights by survivor count that bound ``pi_up(T)`` set by set: the
    upper model's own weights when exchangeable (for today's model the exact kernel's,
    :func:`~ideas_hpc.core.design.reliability.independent_weights`), else the envelope.
    What a relaxed score (never below the exact one) weighs its survivor sets by."""
    sw = weights_of(model, n)
    return sw.proof if sw.exchangeable else np.asarray(sw.envelope, dtype=np.float64)
