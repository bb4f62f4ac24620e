"""A per-scenario bound on the success probability from failure tolerance (issue 29).

For a swarm ``X`` of N spacecraft in one scenario s, the failed sets that
leave a covering swarm form a family ``A = {F subset X : X \\ F covers}``.
Coverage is monotone, so ``A`` is closed under subsets (a *down-set*), and::

    P_s(X) = sum_{F in A} p_f^|F| (1 - p_f)^(N - |F|)

(independent failures; any failure model: ``sum_{F in A} pi(X \\ F)``, bounded
set by set by the envelope ``env_{N-|F|}`` of :mod:`ideas_hpc.failures.sums`, which
for an exchangeable model is the weight itself: the argument below holds with
``p_f^j (1 - p_f)^(N-j)`` replaced by ``env_{N-j}``).

Two facts about one scenario restrict ``A`` for *every* N-swarm:

* fewer than ``N0_s`` spacecraft never cover (``N0_s`` the plain minimum),
  so ``|F| <= N - N0_s`` for every F in A;
* when ``N_{k,s}`` (the fewest spacecraft surviving *any* k failures) is
  above N, no N-swarm is k-tolerant: some k-set ``F0`` of X is missing from
  A, and with it every superset of ``F0`` (down-set).

With ``k*`` the smallest such k, the heaviest family allowed is every set of
at most ``N - N0_s`` members that does not contain one fixed k*-set, so::

    P_s(X) <= UB_s(N) = sum_{j=0}^{N-N0_s} p_f^j (1-p_f)^(N-j) [C(N, j) - C(N-k*, j-k*)]

(``C(a, b) = 0`` for ``b < 0``). Lower bounds on ``N0_s`` and ``N_{k,s}`` keep
it valid (a smaller known k* only loosens it). The bank's probability is a
scenario mean, so every N-swarm has ``P(X) <= mean_s UB_s(N)`` (decomposition
by scenario: each scenario may pick its own best swarm). Per scenario the
``N_{k,s}`` come from the k-failure-tolerant design
(:func:`ideas_hpc.design.failures.failure_tolerant`, its proven bound, without
the separation constraint: a relaxation, so still a lower bound).

Example: eros001708, strict, failures only (one scenario), ``p_f = 0.05``:
``N0 = 3`` and ``N_1 = 6``, so every 5-swarm has ``P <= 0.7738 + 4 x 0.0407 +
6 x 0.0021 = 0.94954 < 0.95`` and every 4-swarm ``P <= 0.943``: N = 6 is
proven for p = 0.95, where the level bound alone allows 0.9988.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ideas_hpc.base import progress
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.vertex_weights import row
from ideas_hpc.design.reliability_stats import proof_model
from ideas_hpc.failures.sums import downset_bound

#: Most scenarios to solve before any solve has shown its pace (each is an integer
#: programme of 5-60 s on eros001708's 720 candidates: a 256-scenario bank is out of
#: reach, and its first solve would only spend the time limit).
FIRST_MAX_SCENARIOS = 8
#: Largest k whose tolerant minimum is solved.
K_MAX = 3


def downset_upper(n: int, p_f, n0: int, k_star: int | None) -> float:
    """``UB_s(n)`` of the module docstring (:func:`ideas_hpc.failures.sums.downset_bound`).

    Assumptions (those of :mod:`ideas_hpc.design.reliability_stats`): the model's
    weights with in-pass losses counted as survivals (1-3), each failed set ``F``
    weighing at most the envelope of its size (exactly ``p_f^|F| (1 - p_f)^(n - |F|)``
    for independent failures at one ``p_f``); monotone coverage (4), so the covering
    failed sets form a down-set; ``n0`` and ``k_star`` proven for the swarms bounded
    (the separation of the design, 5: the ring-gap ``n0`` is computed with it, and a
    k-tolerant minimum without it is a relaxation, so still a lower bound). ``n < n0``
    gives 0 under any failure model: fewer than ``n0`` spacecraft never cover, and
    failures only remove images.

    Parameters
    ----------
    n : int
        Swarm size.
    p_f : float or FailureModel
        Per-spacecraft failure probability, or the failure model (its envelope weights
        replace ``p_f^j (1 - p_f)^(n - j)``).
    n0 : int
        Lower bound on the scenario's plain minimum (fewer never cover).
    k_star : int or None
        Smallest k known to have no k-tolerant n-swarm (None: none known).
    """
    return downset_bound(n, proof_model(p_f), n0, k_star)


def k_star(n: int, lows_k: dict) -> int | None:
    """Smallest k with a known lower bound ``N_k > n`` (``lows_k``: k -> lower bound)."""
    ks = [k for k, low in lows_k.items() if 1 <= k <= n and low > n]
    return min(ks) if ks else None


class ToleranceBound:
    """Per-scenario ``N0_s`` and ``N_{k,s}`` lower bounds, solved on demand within a deadline.

    Parameters
    ----------
    rows : (S, C, V) bool
    w : (V,) or (S, V) float64
        Vertex weights (fractions), shared or per scenario: scenario s's tolerant minimum
        is solved with its own row, so each ``N_{k,s}`` bound holds for its world.
    need : float
        Coverage threshold (fraction).
    lows0 : (S,) int
        Known lower bounds on each scenario's plain minimum (e.g. ring-gap bounds).
    step_rad : float
        Grid step of the candidates.
    solver : callable, optional
        ``(masks (C, V), w, need, k, seconds) -> lower bound on N_k`` (tests);
        default :func:`tolerant_lower`.
    """

    def __init__(self, rows, w, need: float, lows0, step_rad: float, solver=None):
        self.rows, self.w, self.need = rows, w, float(need)
        self.s_n = rows.shape[0]
        self.lows = [{0: int(v)} for v in np.asarray(lows0)]
        self.step = float(step_rad)
        self.solver = solver or tolerant_lower
        self.enabled = True
        self.pace: list = []          # seconds of each solve so far

    def _need_k(self, s: int, n: int) -> int | None:
        """The next k worth solving in scenario s for size n (None: nothing to gain)."""
        low = self.lows[s]
        if k_star(n, low) is not None:
            return None
        n0 = low[0]
        for k in range(1, min(K_MAX, n - n0) + 1):
            if k not in low:
                return k
        return None

    def _optimistic(self, s: int, n: int, p_f) -> float:
        """The lowest ``UB_s(n)`` any solve could still give (unknown ``N_k`` taken > n)."""
        low = self.lows[s]
        ks = [k for k in range(1, min(K_MAX, n) + 1) if k not in low or low[k] > n]
        return downset_upper(n, p_f, low[0], min(ks) if ks else None)

    def upper(self, n: int, p_f, deadline: float | None, p: float | None = None,
              solve: bool = True) -> float:
        """``mean_s UB_s(n)``, solving missing ``N_{k,s}`` while time is left (``solve``).

        With ``p``, nothing is solved when even the best outcome of every solve leaves
        the bound >= p; solving stops when the scenarios left would not fit before
        ``deadline`` at the pace of those done.
        """
        if solve and self.enabled and (p is None or np.mean(
                [self._optimistic(s, n, p_f) for s in range(self.s_n)]) < p - 1e-12):
            for s in range(self.s_n):
                while True:
                    k = self._need_k(s, n)
                    left = None if deadline is None else deadline - time.perf_counter()
                    if k is None or (left is not None and left <= 0.0):
                        break
                    todo = sum(self._need_k(r, n) is not None for r in range(s, self.s_n))
                    if (left is not None and self.pace and np.mean(self.pace) * todo > left) \
                            or (not self.pace and todo > FIRST_MAX_SCENARIOS):
                        return self._mean(n, p_f)   # would not finish: keep the time
                    t = time.perf_counter()
                    # the first of several solves may not take all the time left
                    budget = left if left is None or todo == 1 or self.pace else left / 2
                    progress.note(f"failure-tolerance bound, N = {n}: fewest spacecraft "
                                  f"surviving any {k} failure(s) in scenario {s + 1} of "
                                  f"{self.s_n} (integer programme"
                                  + ("" if budget is None else f", at most {budget:.0f} s")
                                  + ")")
                    got = self.solver(self.rows[s], row(self.w, s), self.need, k, budget,
                                      self.step)
                    self.pace.append(time.perf_counter() - t)
                    self.lows[s][k] = max(int(got), self.lows[s][0] + k)
        return self._mean(n, p_f)

    def _mean(self, n: int, p_f) -> float:
        ub = [downset_upper(n, p_f, low[0], k_star(n, low)) for low in self.lows]
        return float(np.mean(ub))



def tolerant_lower(masks, w, need: float, k: int, seconds: float | None,
                   step_rad: float) -> int:
    """Proven lower bound on the fewest grid candidates surviving any k failures in one
    scenario (separation dropped: a relaxation). ``k + 1`` when nothing is proven."""
    from ideas_hpc.design.bank import CandidateBank
    from ideas_hpc.design.exact import FEAS_TOL
    from ideas_hpc.design.failures import failure_tolerant

    k_n = masks.shape[0]
    bank = CandidateBank(theta=step_rad * np.arange(k_n), masks=np.asarray(masks, bool),
                         areas=np.asarray(w, dtype=np.float64), step_rad=step_rad, d_sep_m=1.0)
    try:
        # the programme asks coverage >= need + FEAS_TOL, the evaluator >= need - 1e-12: a
        # threshold lowered by twice FEAS_TOL keeps every swarm the evaluator counts
        r = failure_tolerant(bank, k, target=need - 2 * FEAS_TOL, eps_tol=0.0,
                             n_max=min(k_n, 40), time_limit=seconds)
    except InputError as exc:
        # out of time before a bound: only the trivial one; otherwise no k-tolerant swarm
        # of at most n_max candidates exists at all
        return k + 1 if exc.field == "time_limit" else min(k_n, 40) + 1
    return int(math.ceil(r.bound - 1e-9))
