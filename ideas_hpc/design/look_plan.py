"""Looks that can pass (issue 41): which swarms the certificate flies, chosen from the bank.

The certificate (:mod:`ideas_hpc.design.certificate`) splits its error over the K
looks it plans, ``alpha / K`` each. A look whose swarm cannot clear p spends its share
on a certain failure: on the main job the bank's optimum N = 4 has P = 0.90024 in every
scenario (failures decide alone), and a lower bound from M such samples stays below that
mean (the betting bound of 256 samples at 98.75 % is about 0.877; even 16,384 samples give
0.89989 < 0.9). So before any validation sample is drawn, each candidate look is
*predicted* from bank data alone:

    power(N) = Pr[ bound(v_1 .. v_M; 1 - alpha / K) >= p ],  v_i ~ the bank's values of X_N

estimated by resampling the bank's per-scenario probabilities of the swarm ``X_N``
(``draws`` bootstrap samples of size M; the per-scenario values are i.i.d. draws of what a
validation sample of ``X_N`` gives, exactly so on held-out scenarios, optimistically on
the scenarios that chose ``X_N``). The plan then

* fixes K, the looks the certificate may make (``max_looks``, or fewer sizes left),
* skips the sizes whose power at the share ``alpha / K`` is below :data:`MIN_POWER` (no
  error is spent on them; at most :data:`MAX_SKIPPED`): the looks are the first size that
  can pass and the next ones, K at most (fewer when ``n_max`` comes first, which raises
  each look's share).

The plan reads the bank only, so it is fixed before the first validation sample: the
certificate's guarantee (false "demonstrated" at most ``alpha``) holds whatever the
prediction says; a wrong prediction costs power, never validity.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ideas_hpc.design.reliability_stats import clears, lower_confidence_bound
from ideas_hpc.design.settings import LookPlan

#: A look predicted to clear p less often than this is not planned (its share of the error
#: would be spent on a near-certain failure).
MIN_POWER = 0.05
#: Bootstrap samples per prediction.
DRAWS = 200
#: Most sizes skipped before the first look: past them the plan looks from the bank's N
#: as it would without prediction (each size considered costs the search of its swarm).
MAX_SKIPPED = 3
#: With a larger sample allowed (``samples_max``), a look's M is doubled until its predicted
#: power reaches this.
TARGET_POWER = 0.8


@dataclass
class PlannedLook:
    """One look of the plan: swarm of ``n`` (``swarm``, bank P ``bank_probability``) and its
    predicted chance ``power`` of clearing p with ``samples`` fresh samples at ``confidence``."""

    n: int
    swarm: np.ndarray
    bank_probability: float
    samples: int
    confidence: float
    power: float


@dataclass
class Plan:
    """The looks to fly, in order, and the sizes skipped with their predicted power."""

    looks: list
    skipped: list = field(default_factory=list)     # (n, power at the first look's share)
    predicted: bool = True                          # False: no values to predict from

    @property
    def planned(self) -> int:
        return len(self.looks)

    def line(self) -> str:
        """The plan in words (one clause of the certificate line)."""
        if not self.predicted:
            return "looks not predicted (no bank values)"
        pw = ", ".join(f"N = {lk.n}: {100 * lk.power:.0f} % with {lk.samples} samples"
                       for lk in self.looks)
        out = f"predicted chance to clear p from the bank alone: {pw}"
        if self.skipped:
            out += "; skipped (cannot clear p: no error spent): " + ", ".join(
                f"N = {n} ({100 * pw:.1f} %)" for n, pw in self.skipped)
        return out


def pass_power(values, p: float, samples: int, confidence: float, rng, *,
               draws: int = DRAWS, bound: Callable = lower_confidence_bound) -> float:
    """Predicted chance that ``samples`` fresh values, drawn like ``values``, give a lower
    bound at ``confidence`` of at least ``p`` (module docstring; bootstrap). For the betting
    bound every draw is decided at once (:func:`~ideas_hpc.design.reliability_stats.clears`:
    is the mean ``p`` rejected?); another ``bound`` is computed one draw at a time."""
    v = np.asarray(values, dtype=np.float64).ravel()
    if v.size == 0 or samples < 1:
        return 0.0
    if np.all(v == v[0]):           # one value: every look gives the same bound
        return float(bound(np.full(int(samples), v[0]), confidence) >= p)
    x = rng.choice(v, size=(int(draws), int(samples)), replace=True)
    if bound is lower_confidence_bound:
        return float(np.mean(clears(x, p, confidence)))
    return float(np.mean([bound(row, confidence) >= p for row in x]))


def plan_looks(n_bank: int, best_of: Callable, values_of: Callable, plan: LookPlan, rng,
               *, max_looks: int | None = None,
               bound: Callable = lower_confidence_bound) -> Plan:
    """The looks of the module docstring.

    Parameters
    ----------
    n_bank : int
        The bank's fewest N (the first size considered).
    best_of : callable
        ``n -> (swarm, P_bank)`` of the bank; must not see validation data.
    values_of : callable
        ``swarm -> (S,)`` per-scenario success probabilities of the swarm on the bank
        (held-out scenarios where there are some).
    plan : LookPlan
        ``p`` and ``confidence`` (``alpha = 1 - confidence``), ``n_max`` the largest
        swarm, ``n_samples`` fresh samples per look, ``max_looks`` the most looks and
        ``samples_max`` the most fresh samples of one look: a look's M is doubled from
        ``n_samples`` while its predicted power is below :data:`TARGET_POWER` and M
        stays within it (the power to demonstrate a swarm just above p grows with M; so
        does the cost).
    rng : numpy.random.Generator
        The prediction's resampling (:func:`ideas_hpc.base.seeds.search_rng`).
    max_looks : int, optional
        In place of ``plan.max_looks`` (the certificate's K, capped by ``n_max``).
    """
    p, confidence, n_max = plan.p, plan.confidence, plan.n_max
    samples, samples_max = plan.n_samples, plan.samples_max
    max_looks = plan.max_looks if max_looks is None else max_looks
    alpha = 1.0 - float(confidence)
    sizes: list = []

    def size(i):
        """Size ``n_bank + i`` (its swarm, bank P and held-out values), computed on first
        use: a size's best swarm costs a search, so only the sizes looked at are built."""
        while len(sizes) <= i:
            n = int(n_bank) + len(sizes)
            if n > int(n_max):
                return None
            sw, pb = best_of(n)
            sw = np.asarray(sw, dtype=np.int64)
            if sw.size != n:
                return None
            sizes.append((n, sw, float(pb), np.asarray(values_of(sw), dtype=np.float64)))
        return sizes[i]

    if size(0) is None:
        return Plan(looks=[], predicted=False)
    # K as the certificate plans it without prediction: max_looks, or the sizes up to n_max
    k = max(1, min(int(max_looks), int(n_max) - int(n_bank) + 1))

    conf = 1.0 - alpha / k
    ladder = [int(samples)]
    while samples_max is not None and 2 * ladder[-1] <= int(samples_max):
        ladder.append(2 * ladder[-1])
    sized: dict = {}

    def look_of(i, share):
        """(M, power) of size i at confidence ``share``: the smallest M of the ladder whose
        power reaches TARGET_POWER, else the largest."""
        key = (i, share)
        if key not in sized:
            for m in ladder:
                pw = pass_power(sizes[i][3], p, m, share, rng, bound=bound)
                if pw >= TARGET_POWER:
                    break
            sized[key] = (m, pw)
        return sized[key]

    # K is fixed first (the sizes the certificate may step through), so each look's share
    # is known: alpha / K. The first look is the first size predicted to clear p at that
    # share (with the most samples allowed); the looks are it and the next sizes, K at
    # most (fewer when n_max comes first, which raises each look's share). Fewer looks
    # would give the first more of alpha, but a look cut from the plan cannot catch a
    # first one the prediction got wrong.
    first = next((i for i in range(MAX_SKIPPED + 1)
                  if size(i) is not None and look_of(i, conf)[1] >= MIN_POWER), None)
    if first is None:       # nothing can pass: today's plan, from the bank's N (it says so)
        first = 0
    idx = [i for i in range(first, first + k) if size(i) is not None]
    conf = 1.0 - alpha / len(idx)
    looks = []
    for i in idx:
        m, pw = look_of(i, conf)
        looks.append(PlannedLook(n=sizes[i][0], swarm=sizes[i][1],
                                 bank_probability=sizes[i][2], samples=m, confidence=conf,
                                 power=pw))
    skipped = [(sizes[i][0], look_of(i, conf)[1]) for i in range(first)]
    return Plan(looks=looks, skipped=skipped)
