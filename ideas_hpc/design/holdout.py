"""Held-out scoring of the bank's swarms (issue 41, item 4: the optimiser's curse).

The sample-average problem picks, among many swarms, one whose mean over the bank's
scenarios reaches p; that mean is optimistic for the swarm it picked, ``E[P_bank(X*)] >=
P(X*)`` (Pagnoncelli, Ahmed & Shapiro, J. Optim. Theory Appl. 142, 2009; SPEC 7d). With
the failure probability alone deciding, every scenario scores the same and the bias is 0;
once the continuous uncertainties matter (every dispersion at 10x on the quick campaign:
bank 0.952 for its N = 6, validation 0.915) it is the difference between the two.

The bank is therefore drawn with ``S + H`` scenarios of one stream (scenario ``s`` depends
only on ``(seed, s)``): the first S *select* (the designer, its proofs, its swarms per N),
the last H only *score*. A held-out mean is unbiased for a swarm the held-out scenarios
did not choose, so it is what the design reports as the bank's estimate of P, what the
look plan predicts from (:mod:`ideas_hpc.design.look_plan`) and what the validation's
P-hat is compared with; ``P_select - P_heldout`` is the measured bias.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.design.reliability_eval import Evaluator

#: Two-sided normal quantile of the agreement interval (95 %).
Z95 = 1.959963984540054


@dataclass
class HeldOut:
    """The held-out scenarios' exact evaluator (failures enumerated as on the bank)."""

    ev: Evaluator

    @classmethod
    def of(cls, rows, w, need: float, model) -> "HeldOut | None":
        """None when there are no held-out rows (``rows.shape[0] == 0``)."""
        rows = np.asarray(rows, dtype=bool)
        if rows.shape[0] == 0:
            return None
        return cls(Evaluator(rows, w, need, model))

    @property
    def size(self) -> int:
        return int(self.ev.rows.shape[0])

    def values(self, swarm) -> np.ndarray:
        """(H,) exact failure-weighted P of ``swarm`` in each held-out scenario."""
        return self.ev.per_scenario([np.asarray(swarm, dtype=np.int64)])[0]

    def probability(self, swarm) -> float:
        """The held-out mean: unbiased for a swarm these scenarios did not choose."""
        return float(self.values(swarm).mean())


def agreement(p_ref: float, values) -> tuple[float, float, bool]:
    """``(low, high, inside)``: the 95 % normal interval of the mean of ``values`` (a
    validation's per-sample P) and whether ``p_ref`` (a held-out or bank P) lies in it.
    The interval is ``mean +- 1.96 s / sqrt(M)`` with the sample standard deviation ``s``
    (0 when every value is the same: then only the same number agrees)."""
    v = np.asarray(values, dtype=np.float64).ravel()
    if v.size == 0:
        return math.nan, math.nan, False
    half = Z95 * (float(v.std(ddof=1)) if v.size > 1 else 0.0) / math.sqrt(v.size)
    lo, hi = float(v.mean()) - half, float(v.mean()) + half
    return lo, hi, bool(lo - 1e-12 <= p_ref <= hi + 1e-12)
