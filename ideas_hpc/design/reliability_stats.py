"""Statistics of the success-probability designer (issue 20).

:func:`failure_upper_bound`: the proven upper bound on the probability of any
swarm of ``N`` from upper bounds ``U_m`` on the fraction of scenarios an
``m``-swarm reaches with no failure (its sum lives in :mod:`ideas_hpc.failures.sums`).

:func:`lower_confidence_bound`: a one-sided lower confidence bound on the mean
of independent values in [0, 1] (the per-sample failure-weighted success
probabilities of the validation), by the betting martingale of Waudby-Smith &
Ramdas (2023, "Estimating means of bounded random variables by betting",
JRSS-B, sec. 4, predictable plug-in bets). Why this bound: it is valid for any
distribution on [0, 1] and any sample size (Ville's inequality on a
nonnegative martingale, no asymptotics), and it adapts to the variance: the
per-sample probabilities of a good design sit close to 1 with a small spread,
where Hoeffding's ``sqrt(log(1/alpha) / 2M)`` (0.077 for M = 256 at 95 %) is
several times looser. :func:`hoeffding_lower_bound` is kept as the reference
the tests compare with.
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.failures.sums import level_bound


def failure_upper_bound(n: int, u_bar, p_f) -> float:
    """``sum_j P(j lost) U_{n-j}`` (``C(n, j) p_f^j (1 - p_f)^(n - j)`` for independent
    failures), an upper bound on any n-swarm's P: :func:`ideas_hpc.failures.sums.level_bound`,
    whose docstring has the argument. ``p_f``: a bare probability or a
    :class:`~ideas_hpc.failures.model.FailureModel`.
    """
    return level_bound(int(n), np.asarray(u_bar, dtype=np.float64), p_f)


def hoeffding_lower_bound(x, confidence: float) -> float:
    """Hoeffding's one-sided bound ``mean - sqrt(log(1/alpha) / (2 M))`` for values in [0, 1]."""
    x = np.asarray(x, dtype=np.float64)
    alpha = 1.0 - confidence
    return max(0.0, float(x.mean()) - math.sqrt(math.log(1.0 / alpha) / (2.0 * x.size)))


def _log_capital(x: np.ndarray, alpha: float):
    """Predictable bets ``lambda_t`` (WSR eq. 26, one-sided, capped at 3/4) for values ``x``:
    ``sqrt(2 log(1/alpha) / (var_{t-1} t log(1 + t)))`` with the shrunk running variance."""
    t = np.arange(1, x.size + 1, dtype=np.float64)
    csum = np.cumsum(x)
    mu_t = (0.5 + csum) / (t + 1.0)
    sq = np.cumsum((x - mu_t) ** 2)
    var = (0.25 + np.r_[0.0, sq[:-1]]) / t
    lam = np.sqrt(2.0 * math.log(1.0 / alpha) / (var * t * np.log1p(t)))
    return np.minimum(lam, 0.75)


def lower_confidence_bound(x, confidence: float) -> float:
    """One-sided lower bound ``L`` with ``P(L <= E x) >= confidence`` for i.i.d. x in [0, 1].

    The capital ``K_t(m) = prod_{i <= t} (1 + lambda_i (x_i - m))``, with bets
    ``0 <= lambda_i <= 3/4`` fixed from ``x_1 .. x_{i-1}`` only, is a
    nonnegative martingale under the mean ``m``, so by Ville's inequality
    ``P(sup_t K_t(E x) >= 1 / alpha) <= alpha``. The bets do not depend on
    ``m``, so ``K_t(m)`` decreases in ``m``: the rejected means form an
    interval ``[0, L]`` and ``L`` (found by bisection, kept on the rejected
    side) is the bound. All values equal to one number ``c`` give ``L < c``.
    """
    x = np.asarray(x, dtype=np.float64).ravel()
    if not (0.5 < confidence < 1.0):
        raise InputError(f"must be in (0.5, 1), got {confidence!r}", field="confidence")
    if x.size == 0:
        return 0.0
    if np.any(x < -1e-12) or np.any(x > 1.0 + 1e-12):
        raise ValueError("values must lie in [0, 1]")
    x = np.clip(x, 0.0, 1.0)
    alpha = 1.0 - confidence
    lam = _log_capital(x, alpha)
    level = math.log(1.0 / alpha)

    def rejected(m: float) -> bool:
        return bool(np.max(np.cumsum(np.log1p(lam * (x - m)))) >= level)

    lo, hi = 0.0, float(x.max())
    if not rejected(lo):
        return 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if rejected(mid):
            lo = mid
        else:
            hi = mid
    return lo
