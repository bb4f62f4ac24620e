"""Held-out scoring of the bank's swarms (issue 41, item 4: the optimiser's curse).

The sample-average problem picks, among many swarms, one whose mean over the bank's
scenarios reaches p; that mean is optimistic for the swarm it picked, ``E[P_bank(X*)] >=
P(X*)`` (Pagnoncelli, Ahmed & Shapiro, J. Optim. Theory Appl. 142, 2009; SPEC 7d). With
the failure probability alone deciding, every scenario scores the same and the bias is 0;
once the continuous uncertainties matter (every dispersion at 10x on the quick campaign:
bank 0.952 for its N = 6, validation 0.915) it is the difference between the two.

So the swarms the bank chose are *scored* on H held-out scenarios: draws of the same
dispersions on their own stream (:data:`ideas_hpc.base.seeds.HOLDOUT_STREAM`), flown for
the members of the swarms scored only (a swarm of N costs N / C of a bank scenario), each
giving the swarm's exact failure-weighted P. The swarms the looks and the curve will ask
for are flown together (:meth:`HeldOut.prefetch`: the union of their members once per
held-out scenario, one set of flights instead of one per size). A held-out mean is unbiased for a swarm those
draws did not choose, so it is what the design reports as the bank's estimate of P, what
the look plan predicts from (:mod:`ideas_hpc.design.look_plan`) and what the validation's
P-hat is compared with; ``P_bank - P_heldout`` is the measured bias. The held-out draws
choose the looks, so they are never validation data: the certificate's samples are on
the validation stream.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from ideas_hpc.design.reliability_eval import Evaluator

#: Two-sided normal quantile of the agreement interval (95 %).
Z95 = 1.959963984540054


class HeldOut:
    """Per-swarm held-out values, computed once per swarm.

    Parameters
    ----------
    score : callable
        ``swarm (grid indices) -> (H,)`` its exact failure-weighted P in each held-out
        scenario (the campaign flies them; :meth:`of_rows` scores given rows).
    size : int
        H.
    batch : callable, optional
        ``[swarm, ...] -> [(H,), ...]``: several swarms scored together (the campaign flies
        the union of their members once, :meth:`prefetch`); without it, one at a time.
    """

    def __init__(self, score: Callable, size: int, batch: Callable | None = None):
        self._score, self.size, self._batch = score, int(size), batch
        self._cache: dict = {}

    @staticmethod
    def _key(swarm) -> tuple:
        return tuple(int(i) for i in np.sort(np.asarray(swarm, dtype=np.int64)))

    def prefetch(self, swarms) -> None:
        """Score the swarms not yet scored in one batch (the flights of a held-out scenario
        cost mostly its world and start, so flying the union of the members once is about
        a size's cost instead of one per size; issue 43). Without a batch: nothing."""
        if self._batch is None:
            return
        todo = list(dict.fromkeys(k for k in map(self._key, swarms)
                                  if k and k not in self._cache))
        if not todo:
            return
        for k, v in zip(todo, self._batch([np.array(k, dtype=np.int64) for k in todo])):
            self._cache[k] = np.asarray(v, dtype=np.float64)

    @classmethod
    def of_rows(cls, rows, w, need: float, model) -> "HeldOut | None":
        """Held-out scenarios given as rows (S, C, V) of every candidate (None: no rows);
        ``w`` their vertex fractions, (V,) shared or (S, V) per scenario (drawn worlds)."""
        rows = np.asarray(rows, dtype=bool)
        if rows.shape[0] == 0:
            return None
        ev = Evaluator(rows, w, need, model)
        return cls(lambda sw: ev.per_scenario([sw])[0], rows.shape[0])

    def values(self, swarm) -> np.ndarray:
        """(H,) exact failure-weighted P of ``swarm`` in each held-out scenario."""
        key = self._key(swarm)
        if key not in self._cache:
            self._cache[key] = np.asarray(self._score(np.array(key, dtype=np.int64)),
                                          dtype=np.float64)
        return self._cache[key]

    def probability(self, swarm) -> float:
        """The held-out mean: unbiased for a swarm these scenarios did not choose."""
        return float(self.values(swarm).mean())


def agreement(held_values, values) -> dict:
    """Do a held-out P and a validation's P-hat agree within their sampling error?

    Both are means of independent per-sample probabilities of one fixed swarm (the
    held-out scenarios and the validation samples are i.i.d. draws of the same
    dispersions), so their difference has standard error
    ``se = sqrt(s_v^2 / M + s_h^2 / H)``; they agree when ``|P-hat - P_held| <= 1.96 se``
    (95 %, normal). Also returned: the validation's own 95 % interval
    ``P-hat +- 1.96 s_v / sqrt(M)`` and whether the held-out P lies in it (which ignores
    the held-out P's own error, so it is stricter by about sqrt(1 + M s_h^2 / (H s_v^2))).
    With every value equal (spread 0) only the same number agrees.
    """
    h = np.asarray(held_values, dtype=np.float64).ravel()
    v = np.asarray(values, dtype=np.float64).ravel()
    if h.size == 0 or v.size == 0:
        return {"held": math.nan, "p_hat": math.nan, "se": math.nan, "agrees": False,
                "interval": (math.nan, math.nan), "inside": False}
    sv = float(v.std(ddof=1)) if v.size > 1 else 0.0
    sh = float(h.std(ddof=1)) if h.size > 1 else 0.0
    se = math.sqrt(sv ** 2 / v.size + sh ** 2 / h.size)
    ph, pv = float(h.mean()), float(v.mean())
    half = Z95 * sv / math.sqrt(v.size)
    return {"held": ph, "p_hat": pv, "se": se,
            "agrees": bool(abs(pv - ph) <= Z95 * se + 1e-12),
            "interval": (pv - half, pv + half),
            "inside": bool(pv - half - 1e-12 <= ph <= pv + half + 1e-12)}
