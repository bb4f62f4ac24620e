"""Statistics of the success-probability designer (issue 20).

:func:`failure_upper_bound`: the proven upper bound on the probability of any
swarm of ``N`` from upper bounds ``U_m`` on the fraction of scenarios an
``m``-swarm reaches with no failure.

:func:`proof_failure_rate`: the failure model every proof of the designer
assumes, in one place (issue 41). The proofs are :func:`failure_upper_bound`,
:func:`ideas_hpc.design.tolerance_bound.downset_upper`, the screen
(:func:`ideas_hpc.design.screen_bound.screen_size` and the kernels of
:mod:`ideas_hpc.core.design.ring_screen`) and the exact evaluator they are
compared with (:mod:`ideas_hpc.core.design.reliability`). Each holds when:

1. **whole-pass losses**: a spacecraft either works for the whole pass (it
   images what its row says) or fails before it (it images nothing);
2. **independent failures**: no common cause, each failure independent of the
   others' and of the scenario's dispersions;
3. **one p_f**: the same failure probability for every spacecraft and every
   scenario, known exactly (no prior over it);
4. **monotone coverage**: a vertex is seen when one survivor sees it, so a
   subset of survivors never covers more;
5. **the separation** ``m`` applied alike to the swarms bounded and the swarms
   compared (a subset of a separated swarm is separated);
6. **one comparison**: a swarm meets p when ``P >= p - P_TOL`` and covers when
   ``coverage >= need - 1e-12`` (the evaluator's ``COVER_TOL``); the bounds keep
   a margin above both.

A generalised failure model (per-spacecraft ``p_f``, a common-cause beta factor,
loss mid-pass, an uncertain ``p_f``) breaks 1-3: :func:`proof_failure_rate`
then returns None and every proof above declines (the bounds fall back to the
trivial 1, the screen to its search), so the designer takes the search route
only. That function is the one place to teach a new model what still holds.

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

#: The designer's comparison of probabilities: a swarm meets p when ``P >= p - P_TOL``.
P_TOL = 1e-12


def proof_failure_rate(p_f) -> float | None:
    """The one per-spacecraft failure probability the proofs assume, or None (module
    docstring, assumptions 1-3).

    Parameters
    ----------
    p_f : float or sequence of float
        The failure model: one probability for every spacecraft, or one per member.

    Returns
    -------
    float or None
        ``p_f`` when it is one finite number in [0, 1] (or a sequence whose values
        are all that number); None for anything else (members that differ, a model
        object, a value outside [0, 1]): the proofs do not apply and their callers
        take another route. A richer failure model hooks in here: return its one
        ``p_f`` only while it reduces to independent whole-pass losses at one rate
        (beta = 0, a fixed ``p_f``, no partial losses).
    """
    if isinstance(p_f, (bool, np.bool_)):
        return None
    try:
        vals = np.asarray(p_f, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        return None
    if vals.size == 0 or not np.all(np.isfinite(vals)) or np.any(vals != vals[0]):
        return None
    v = float(vals[0])
    return v if 0.0 <= v <= 1.0 else None


def failure_upper_bound(n: int, u_bar, p_f: float) -> float:
    """``sum_j C(n, j) p_f^j (1 - p_f)^(n - j) U_{n-j}``, an upper bound on any n-swarm's P.

    With failure set ``F`` (``|F| = j``) the survivors form an ``(n - j)``-swarm,
    which reaches at most the fraction ``U_{n-j}`` of the scenarios; averaging
    over the independent failures gives the bound. ``u_bar[m]`` bounds
    ``U_m`` (``u_bar[0] = 0``: no survivor maps nothing).

    Assumptions (module docstring): whole-pass, independent failures at one
    ``p_f`` in every scenario (1-3), so ``P(F) = p_f^j (1 - p_f)^(n-j)``; each
    ``u_bar[m]`` bounds the best *separated* m-swarm's fraction of scenarios
    covered at the evaluator's tolerance (5, 6; a survivor set of a separated
    swarm is one). Where :func:`proof_failure_rate` declines ``p_f`` the bound
    is the trivial 1 (true under any model), so no size is proven short on it.
    ``u_bar`` needs ``n + 1`` entries, each >= 0 (``InputError`` otherwise).
    """
    rate = proof_failure_rate(p_f)
    if rate is None:
        return 1.0
    p_f = rate
    u = np.asarray(u_bar, dtype=np.float64).ravel()
    if u.size < n + 1 or np.any(~(u[:n + 1] >= 0.0)):
        raise InputError(f"needs {n + 1} bounds >= 0 (U_0 .. U_{n}), got {u_bar!r}",
                         field="u_bar")
    total = 0.0
    for j in range(n + 1):
        total += math.comb(n, j) * p_f ** j * (1.0 - p_f) ** (n - j) * u[n - j]
    return min(1.0, total)


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
