"""Statistics of the success-probability designer (issue 20).

:func:`failure_upper_bound`: the proven upper bound on the probability of any
swarm of ``N`` from upper bounds ``U_m`` on the fraction of scenarios an
``m``-swarm reaches with no failure (its sum lives in :mod:`ideas_hpc.failures.sums`).

:func:`proof_model`: the failure model every proof of the designer assumes, in one
place (issue 41). The proofs are :func:`failure_upper_bound`,
:func:`ideas_hpc.design.tolerance_bound.downset_upper`, the screen
(:func:`ideas_hpc.design.screen_bound.screen_size` and the kernels of
:mod:`ideas_hpc.core.design.ring_screen`) and the exact evaluator they are
compared with (:mod:`ideas_hpc.core.design.reliability`). Each holds when:

1. **losses bounded by the upper model**: a spacecraft either images its whole row
   or nothing; a loss *in* the pass (which images part of the row) is counted as a
   survival by the proofs' weights (the upper model of
   :mod:`ideas_hpc.failures.weights`), so ``P_true <= P_up``;
2. **the failure law of the model**: the weight of each survivor set is the model's
   (:class:`~ideas_hpc.failures.model.FailureModel`: per-spacecraft ``p_f``, common
   cause, an uncertain ``p_f``, exactly-k); a bound that depends on the size of
   the survivor set only uses the exact law of that size, a bound that picks
   *which* sets uses the heaviest set of each size (the envelope of
   :mod:`ideas_hpc.failures.sums`), exact for an exchangeable model and an upper
   envelope otherwise;
3. **no dependence on the scenario**: the failure law is the same in every
   scenario (the model has no scenario term);
4. **monotone coverage**: a vertex is seen when one survivor sees it, so a
   subset of survivors never covers more;
5. **the separation** ``m`` applied alike to the swarms bounded and the swarms
   compared (a subset of a separated swarm is separated);
6. **one comparison**: a swarm meets p when ``P >= p - P_TOL`` and covers when
   ``coverage >= need - 1e-12`` (the evaluator's ``COVER_TOL``); the bounds keep
   a margin above both.

:func:`proof_model` checks a model once (a bare ``p_f`` outside [0, 1] or not a
number is refused, naming ``p_f``); with today's model (one ``p_f``, independent,
whole-pass) the sums are the papers' binomial sums, the same floats as before.

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
from ideas_hpc.failures.model import FailureModel, as_model
from ideas_hpc.failures.sums import level_bound

#: The designer's comparison of probabilities: a swarm meets p when ``P >= p - P_TOL``.
P_TOL = 1e-12


def proof_model(p_f):
    """The :class:`~ideas_hpc.failures.model.FailureModel` the proofs use (module docstring):
    a model as given, or a bare ``p_f`` in [0, 1] as independent whole-pass losses.

    Raises
    ------
    InputError
        ``p_f`` when a bare value is not a number in [0, 1] (a proof never runs on a
        failure law it cannot state).
    """
    if isinstance(p_f, FailureModel):
        return p_f
    if isinstance(p_f, (bool, np.bool_)) or not isinstance(p_f, (int, float, np.number)) \
            or not math.isfinite(float(p_f)) or not 0.0 <= float(p_f) <= 1.0:
        raise InputError(f"needs a failure probability in [0, 1] or a failure model, got "
                         f"{p_f!r}", field="p_f")
    return as_model(float(p_f))


def failure_upper_bound(n: int, u_bar, p_f) -> float:
    """``sum_j P(j lost) U_{n-j}`` (``C(n, j) p_f^j (1 - p_f)^(n - j)`` for independent
    failures), an upper bound on any n-swarm's P: :func:`ideas_hpc.failures.sums.level_bound`,
    whose docstring has the argument. ``p_f``: a bare probability or a
    :class:`~ideas_hpc.failures.model.FailureModel` (:func:`proof_model`).

    Assumptions (module docstring): the model's law of the number lost, in-pass losses
    counted as survivals (1-3); each ``u_bar[m]`` bounds the best *separated* m-swarm's
    fraction of scenarios covered at the evaluator's tolerance (5, 6; a survivor set of
    a separated swarm is one). ``u_bar`` needs ``n + 1`` entries, each >= 0
    (``InputError`` otherwise).
    """
    u = np.asarray(u_bar, dtype=np.float64).ravel()
    if u.size < n + 1 or np.any(~(u[:n + 1] >= 0.0)):
        raise InputError(f"needs {n + 1} bounds >= 0 (U_0 .. U_{n}), got {u_bar!r}",
                         field="u_bar")
    return level_bound(int(n), u, proof_model(p_f))


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


def _bets(x: np.ndarray, alpha: float) -> np.ndarray:
    """:func:`_log_capital`'s bets for each row of ``x`` (R, M)."""
    r_n, m = x.shape
    t = np.arange(1, m + 1, dtype=np.float64)
    mu_t = (0.5 + np.cumsum(x, axis=1)) / (t + 1.0)
    sq = np.cumsum((x - mu_t) ** 2, axis=1)
    var = (0.25 + np.c_[np.zeros(r_n), sq[:, :-1]]) / t
    return np.minimum(np.sqrt(2.0 * math.log(1.0 / alpha) / (var * t * np.log1p(t))), 0.75)


def clears(x, p: float, confidence: float) -> np.ndarray:
    """(R,) bool: the lower bound of each row of ``x`` (R, M) at ``confidence`` is >= ``p``.

    The rejected means form ``[0, L]`` (:func:`lower_confidence_bound`), so ``L >= p``
    exactly when the mean ``p`` is rejected: one pass of the capital process per row
    instead of the bisection (the look plan's bootstrap, :mod:`ideas_hpc.design.look_plan`).
    """
    x = np.clip(np.atleast_2d(np.asarray(x, dtype=np.float64)), 0.0, 1.0)
    if not (0.5 < confidence < 1.0):
        raise InputError(f"must be in (0.5, 1), got {confidence!r}", field="confidence")
    if x.shape[1] == 0:
        return np.zeros(x.shape[0], dtype=bool)
    alpha = 1.0 - confidence
    lam = _bets(x, alpha)
    cap = np.max(np.cumsum(np.log1p(lam * (x - float(p))), axis=1), axis=1)
    return cap >= math.log(1.0 / alpha)


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
