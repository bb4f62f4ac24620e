"""The certificate of a success-probability design: which swarm, on which data, at which error.

A one-sided lower confidence bound at ``confidence`` certifies a swarm that was
fixed before its sample was drawn (SPEC section 7d, issue 29). The design
procedure is

1. *selection* on the scenario bank: the fewest N whose bank probability
   reaches the solve level ``p'`` (:func:`stricter_level`; ``p' = p`` unless a
   stricter level is asked for), its swarm ``X_N``;
2. *looks*: swarm ``X_N`` is flown through fresh validation samples and the
   bound computed; with ``design.demonstrate`` a look whose bound misses ``p``
   is followed by one at ``X_{N+1}``, the bank's best swarm of one more,
   up to ``K`` looks (:func:`planned_looks`, fixed from the bank before any
   validation sample is drawn).

Each look pays for itself twice over:

* **fresh data**: look ``j`` (0-based) flies validation samples
  ``j M .. (j + 1) M - 1`` of the validation stream
  (:data:`ideas_hpc.base.seeds.VALIDATION_STREAM`; disjoint ``SeedSequence`` keys),
  so the data that certifies the reported swarm was drawn after that swarm was
  fixed and took part in no selection, step-up or tie-break;
* **split error**: every look is made at ``alpha / K`` (``alpha = 1 -
  confidence``, Bonferroni). Fresh data alone would not do: stopping at the
  first look that clears ``p`` gives every swarm short of ``p`` its own chance
  ``alpha`` of a false "demonstrated", so up to ``K alpha`` in all. With the
  split, ``P(false demonstrated) <= sum_j P(look j clears p | P(X_j) < p)
  <= K (alpha / K) = alpha``, whatever the true probabilities.

``tests/test_certificate.py`` runs this whole procedure (bank selection,
step-up, certificate) on synthetic swarms of known probability and measures the
false-"demonstrated" rate.

The stricter level (:func:`stricter_level`) and the statistical lower bound on
the true fewest N from replicated sample problems (:func:`replicated_lower_bound`)
follow Luedtke & Ahmed (SIAM J. Optim. 19(2), 2008) and Pagnoncelli, Ahmed &
Shapiro (J. Optim. Theory Appl. 142, 2009).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ideas_hpc.design.look_plan import plan_looks
from ideas_hpc.design.reliability_stats import lower_confidence_bound
from ideas_hpc.design.settings import DEFAULT_LOOKS, LookPlan  # noqa: F401 (its old home)
from ideas_hpc.base.errors import InputError


def planned_looks(demonstrate: bool, n_bank: int, n_max: int, max_looks: int,
                  exact: bool = False) -> int:
    """K, the looks the procedure may make: 1 without stepping (or when P is exact),
    else ``min(max_looks, n_max - n_bank + 1)``. Depends on the bank only."""
    if not demonstrate or exact:
        return 1
    if int(max_looks) < 1:
        raise InputError(f"must be >= 1, got {max_looks}", field="max_looks")
    return max(1, min(int(max_looks), int(n_max) - int(n_bank) + 1))


def look_confidence(confidence: float, looks: int) -> float:
    """Confidence of each of ``looks`` looks: ``1 - (1 - confidence) / looks`` (Bonferroni)."""
    return 1.0 - (1.0 - float(confidence)) / int(looks)


def verdict(ok: bool, *, stored: bool = False) -> str:
    """The verdict in words, worded here only: ``DEMONSTRATED`` / ``NOT demonstrated`` in
    the printed lines, ``demonstrated`` / ``not demonstrated`` in the store (``stored``)."""
    if stored:
        return "demonstrated" if ok else "not demonstrated"
    return "DEMONSTRATED" if ok else "NOT demonstrated"


@dataclass
class Look:
    """One validation look: swarm of ``n``, samples ``first`` to ``first + size - 1``."""

    n: int
    swarm: np.ndarray
    bank_probability: float
    values: np.ndarray          # per-sample success probabilities (failures exact)
    first: int                  # first validation sample index of this look
    confidence: float           # this look's share of the error: 1 - alpha / K
    lower: float
    extra: object = None        # whatever the validator returned beside the values

    @property
    def p_hat(self) -> float:
        return float(np.mean(self.values))

    @property
    def size(self) -> int:
        return int(np.size(self.values))


@dataclass
class Certificate:
    """Outcome of :func:`certify`: every look, in order; the last one is the reported swarm."""

    p: float
    confidence: float
    planned: int
    exact: bool
    looks: list = field(default_factory=list)
    plan: object = None         # the look plan (:class:`~ideas_hpc.design.look_plan.Plan`)

    @property
    def final(self) -> Look:
        return self.looks[-1]

    @property
    def demonstrated(self) -> bool:
        return bool(self.final.lower >= self.p)

    def line(self) -> str:
        """The certificate in one line: the swarm, the data, the looks and their error."""
        f = self.final
        if self.exact:
            return (f"certificate: N = {f.n} swarm, P = {f.lower:.4f} exact (continuous "
                    "dispersions off: one exact scenario, no sampling error)")
        last = f.first + f.size - 1
        how = ("one look, the full error" if self.planned == 1 else
               f"{len(self.looks)} of {self.planned} planned looks, each on fresh samples "
               f"and at alpha / {self.planned} (Bonferroni)")
        if self.plan is not None and self.plan.predicted:
            how += f"; {self.plan.line()}"
        cmp = ">=" if self.demonstrated else "<"
        return (f"certificate: N = {f.n} swarm {verdict(self.demonstrated)}, {100 * f.confidence:.4g} % lower "
                f"bound {f.lower:.4f} {cmp} p = {self.p:g}"
                + f" on validation samples {f.first}..{last} ({f.size} fresh draws, flown "
                "only after this swarm was fixed: they chose nothing); "
                f"{how}; overall confidence {100 * self.confidence:g} %")


def certify(n_bank: int, best_of: Callable, validate: Callable, plan: LookPlan | None = None,
            *, bound: Callable = lower_confidence_bound, values_of: Callable | None = None,
            rng=None, **keywords) -> Certificate:
    """Run the looks of the module docstring.

    ``plan`` (:class:`~ideas_hpc.design.settings.LookPlan`) holds ``p``,
    ``confidence``, ``n_max``, ``n_samples``, ``demonstrate``, ``max_looks`` and
    ``exact`` below; without it, the same keywords.

    Parameters
    ----------
    n_bank : int
        The bank's fewest N (selection, step 1).
    best_of : callable
        ``n -> (swarm, P_bank)``, the bank's best swarm of n; it must not see
        validation data.
    validate : callable
        ``(swarm, first, size) -> (values, extra)``: per-sample success
        probabilities of ``swarm`` over validation samples ``first .. first +
        size - 1`` (values in [0, 1]) and anything the caller wants kept.
    p, confidence : float
        Requirement and overall confidence.
    n_max, n_samples : int
        Largest swarm; samples per look (M).
    demonstrate : bool
        Step N up while the bound misses p.
    max_looks : int
        Most looks (K is also capped by ``n_max - n_bank + 1``).
    exact : bool
        One exact scenario: the mean is P itself (no bound, one look).
    bound : callable
        ``(values, confidence) -> lower bound``.
    values_of : callable, optional
        ``swarm -> (S,)`` its per-scenario probabilities on the bank (held-out scenarios
        where there are some). With ``demonstrate``, the looks are then planned from them
        (:func:`~ideas_hpc.design.look_plan.plan_looks`: the sizes that cannot clear p are
        skipped, K is the fewest looks predicted to pass); without, every size from
        ``n_bank`` up is a look, ``K = min(max_looks, n_max - n_bank + 1)``.
    rng : numpy.random.Generator, optional
        The plan's resampling (with ``values_of``).
    samples_max : int, optional
        With ``values_of``: the most samples one look may take (the plan doubles a look's M
        from ``n_samples`` toward its target power, :func:`~ideas_hpc.design.look_plan.plan_looks`;
        a :class:`LookPlan` field).
    """
    plan = plan if plan is not None else LookPlan(**keywords)
    p, confidence, n_max, n_samples = plan.p, plan.confidence, plan.n_max, plan.n_samples
    demonstrate, max_looks, exact = plan.demonstrate, plan.max_looks, plan.exact
    k = planned_looks(demonstrate, n_bank, n_max, max_looks, exact)
    schedule = None
    if demonstrate and not exact and values_of is not None:
        schedule = plan_looks(int(n_bank), best_of, values_of, plan,
                              rng if rng is not None else np.random.default_rng(0),
                              max_looks=k, bound=bound)
    # every swarm a look may fly is fixed before the first look: no choice waits on
    # (or times itself against) a validation flight
    if schedule is not None and schedule.looks:
        k = schedule.planned
        picks = [(lk.n, lk.swarm, lk.bank_probability, lk.samples) for lk in schedule.looks]
    else:
        picks = [(int(n_bank) + j, *best_of(int(n_bank) + j), int(n_samples))
                 for j in range(k)]
    conf_look = 1.0 if exact else look_confidence(confidence, k)
    cert = Certificate(p=float(p), confidence=float(confidence), planned=k, exact=exact,
                       plan=schedule)
    first = 0       # look j flies the samples after those of looks 0 .. j - 1: fresh data
    for n, swarm, pb, m in picks:
        swarm = np.asarray(swarm, dtype=np.int64)
        if swarm.size != n:
            break
        values, extra = validate(swarm, first, int(m))
        values = np.asarray(values, dtype=np.float64)
        lower = float(values.mean()) if exact else float(bound(values, conf_look))
        cert.looks.append(Look(n=n, swarm=swarm, bank_probability=float(pb), values=values,
                               first=first, confidence=conf_look, lower=lower, extra=extra))
        first += int(m)
        if lower >= p:
            break
    if not cert.looks:
        raise InputError(f"no swarm of {n_bank} on the bank to validate", field="n_max")
    return cert


def stricter_level(p: float, s_n: int, n_choices: float, delta: float) -> float:
    """Solve level ``p'`` of the sample problem so that its answer meets p with probability
    >= ``1 - delta`` (Luedtke & Ahmed 2008, sec. 2.2, finite feasible set; Pagnoncelli,
    Ahmed & Shapiro 2009, sec. 2.1)::

        p' = p + sqrt(ln(n_choices / delta) / (2 S))

    Why: a swarm X whose true ``P(X) < p`` has a bank mean of S independent
    values in [0, 1] (the per-scenario failure-weighted probabilities) that
    reaches ``p'`` with probability ``<= exp(-2 S (p' - p)^2)`` (Hoeffding);
    over the ``n_choices`` swarms the search may return (union bound) that is
    ``<= n_choices exp(-2 S (p' - p)^2) = delta``. ``n_choices`` is the number
    of swarms the sample problem chooses among (``C(C, N)`` for C grid candidates
    at most; fewer when the search only compares a short list). The level is
    conservative: at S = 256 it is above p + 0.077 even for one choice.

    Returns ``p'``, possibly >= 1 (then no bank of S scenarios can give the
    guarantee: the caller says so).
    """
    if not (0.0 < p < 1.0) or s_n < 1 or n_choices < 1 or not (0.0 < delta < 1.0):
        raise InputError("needs 0 < p < 1, S >= 1, n_choices >= 1, 0 < delta < 1",
                         field="p")
    return float(p) + math.sqrt(math.log(float(n_choices) / float(delta)) / (2.0 * int(s_n)))


def replicated_lower_bound(optima, s_n: int, p: float, solve_p: float,
                           beta: float) -> tuple[float, int, float]:
    """A statistical lower bound on the true fewest N from M independent sample problems
    (Pagnoncelli, Ahmed & Shapiro 2009, sec. 2.2, after Nemirovski & Shapiro).

    Each of the M problems minimises N subject to a bank mean ``>= solve_p`` on
    its own S scenarios (``solve_p <= p``). A true optimal swarm ``X*`` (``P(X*)
    >= p``) is feasible in one of them with probability at least
    ``theta = 1 - exp(-2 S (p - solve_p)^2)`` (Hoeffding on values in [0, 1]),
    and then that problem's optimum is ``<= N*``. With the optima sorted,
    ``v_(1) <= .. <= v_(M)``, ``v_(L) > N*`` needs at most ``L - 1`` problems
    with ``X*`` feasible, so ``P(v_(L) > N*) <= Bin(L - 1; theta, M)``. The bound
    is ``v_(L)`` for the largest ``L`` with ``Bin(L - 1; theta, M) <= beta``.

    Returns ``(bound, L, theta)``; ``bound`` is ``-inf`` (no bound) when even
    ``L = 1`` misses ``beta``.
    """
    v = np.sort(np.asarray(optima, dtype=np.float64))
    m = v.size
    if m < 1 or not (0 < solve_p <= p < 1) or not (0 < beta < 1):
        raise InputError("needs >= 1 optimum, 0 < solve_p <= p < 1, 0 < beta < 1",
                         field="solve_p")
    theta = 1.0 - math.exp(-2.0 * int(s_n) * (p - solve_p) ** 2)
    best_l, cdf = 0, 0.0
    for ell in range(1, m + 1):
        cdf += math.comb(m, ell - 1) * theta ** (ell - 1) * (1 - theta) ** (m - ell + 1)
        if cdf > beta:
            break
        best_l = ell
    if best_l == 0:
        return -math.inf, 0, theta
    return float(v[best_l - 1]), best_l, theta


def group_bounds(lows, n_groups: int, level: float, p_f, n_max: int) -> np.ndarray:
    """Proven lower bounds on the optima of ``n_groups`` independent sample problems cut from
    one bank: the scenarios split in order into groups (i.i.d. draws, so the groups are
    independent sample problems), problem ``i`` asking for the fewest N with bank mean >=
    ``level`` on group ``i``.

    ``lows[s]`` is a proven lower bound on the fewest spacecraft that cover scenario ``s``
    (the ring-gap bound). On group ``i`` an m-swarm reaches at most the fraction
    ``U_m = mean(lows <= m)`` of the scenarios with no failure, so any N-swarm has bank
    mean ``<= UB(N)`` (:func:`~ideas_hpc.design.reliability_stats.failure_upper_bound`;
    ``p_f`` a bare probability or the failure model, whose upper law it takes) and
    the problem's optimum is at least the first N with ``UB(N) >= level``
    (``n_max + 1`` when none). Lower bounds on the optima keep
    :func:`replicated_lower_bound` valid: a problem in which the true optimum is feasible
    still has its bound ``<= N*``.
    """
    from ideas_hpc.design.reliability_stats import failure_upper_bound

    lows = np.asarray(lows, dtype=np.int64)
    out = np.full(int(n_groups), int(n_max) + 1, dtype=np.int64)
    for i, grp in enumerate(np.array_split(lows, int(n_groups))):
        u = [0.0] + [float(np.mean(grp <= m)) for m in range(1, int(n_max) + 1)]
        for n in range(1, int(n_max) + 1):
            if failure_upper_bound(n, u[:n + 1], p_f) >= level - 1e-12:
                out[i] = n
                break
    return out
