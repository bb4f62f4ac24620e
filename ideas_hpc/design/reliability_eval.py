"""The exact ``P_bank`` of swarms on one scenario bank, under a failure model (issues 20, 41).

:class:`Evaluator` scores swarms with the exact kernel
(:func:`~ideas_hpc.core.design.reliability.weighted_probabilities`), the survivor
weights of its :class:`~ideas_hpc.failures.model.FailureModel` precomputed once per
swarm size (:func:`~ideas_hpc.failures.weights.survivor_weights`). Two laws:

* ``ev(swarms)``: the design's score, losses in the pass counted as whole-pass losses
  (the bank knows whole-pass rows only): a lower bound on the true P, exact when no
  loss happens in the pass. A swarm found with score >= p meets p.
* ``ev.upper(swarms)``: losses in the pass counted as survivals, an upper bound on the
  true P (the same numbers when no loss happens in the pass). A size is proven short of
  p by an exhaustive search only when every swarm's upper value is below p.

A model that is not exchangeable (per-spacecraft p_f, stated common-cause groups)
depends on which spacecraft flies which member: member k is the k-th grid candidate
of the swarm in increasing order (the order the design stores), so swarms are sorted
before they are scored.

Vertex weights ``w``: ``(V,)`` shared by every scenario, or ``(S, V)`` per scenario (issue
42: each scenario a drawn world with its own vertex areas and reference area); the kernels
read scenario s's row (:func:`~ideas_hpc.core.design.reliability.weight_row`), and
:meth:`Evaluator.reach` is then a per-scenario array.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base import vertex_weights
from ideas_hpc.core.design.reliability import swarm_coverages, weighted_probabilities
from ideas_hpc.failures.model import as_model
from ideas_hpc.failures.weights import survivor_weights

#: Largest swarm whose 2^N failure subsets are enumerated.
N_ENUM_MAX = 24


class Evaluator:
    """Exact ``P_bank`` of swarms on one bank (compiled, batched; module docstring).

    ``p_f``: a :class:`~ideas_hpc.failures.model.FailureModel`, or a bare per-spacecraft
    failure probability (independent failures, today's model). ``w``: area fractions,
    ``(V,)`` shared or ``(S, V)`` per scenario (module docstring; normalised by the
    caller, :func:`ideas_hpc.base.vertex_weights.normalised`).
    """

    def __init__(self, rows, w, need: float, p_f):
        self.rows = np.ascontiguousarray(rows, dtype=np.bool_)
        self.w = np.ascontiguousarray(w, dtype=np.float64)
        if self.w.ndim not in (1, 2) or self.w.shape[-1] != self.rows.shape[2] or (
                self.w.ndim == 2 and self.w.shape[0] not in (1, self.rows.shape[0])):
            raise InputError(f"vertex weights of shape {self.w.shape} do not fit rows of "
                             f"shape {self.rows.shape} (need (V,) or (S, V))", field="areas")
        self.need = float(need)
        self.model = as_model(p_f)

    @property
    def per_scenario_weights(self) -> bool:
        """True when the vertex weights differ by scenario (``w`` is (S, V), S > 1)."""
        return vertex_weights.per_scenario(self.w)

    def w_of(self, s: int) -> np.ndarray:
        """(V,) the vertex weights of scenario ``s``."""
        return vertex_weights.row(self.w, s)

    def reach(self) -> np.ndarray:
        """(S,) the coverage all candidates reach together in each scenario, with that
        scenario's weights (shared weights: the same union rule as a single bank's
        :attr:`~ideas_hpc.design.bank.CandidateBank.reach`, per scenario)."""
        seen = self.rows.any(axis=1)
        return np.array([float(self.w_of(s)[seen[s]].sum()) for s in range(seen.shape[0])])

    @property
    def p_f(self):
        """The bare p_f of today's model (None for any other)."""
        return self.model.p_f[0] if self.model.is_plain else None

    def _swarms(self, swarms) -> np.ndarray:
        sw = np.atleast_2d(np.asarray(swarms, dtype=np.int64))
        if sw.shape[1] > N_ENUM_MAX:
            raise InputError(f"swarms above {N_ENUM_MAX} spacecraft are out of reach of the "
                             "exact failure enumeration", field="n_max")
        if not survivor_weights(self.model, sw.shape[1]).exchangeable:
            sw = np.sort(sw, axis=1)
        return np.ascontiguousarray(sw)

    def per_scenario(self, swarms) -> np.ndarray:
        """(K, S) the score of each swarm in each scenario."""
        sw = self._swarms(swarms)
        weights = survivor_weights(self.model, sw.shape[1]).score
        return weighted_probabilities(self.rows, sw, self.w, self.need, weights)

    def __call__(self, swarms) -> np.ndarray:
        return self.per_scenario(swarms).mean(axis=1)

    def upper(self, swarms) -> np.ndarray:
        """(K,) ``P_bank`` under the upper model (module docstring)."""
        sw = self._swarms(swarms)
        sws = survivor_weights(self.model, sw.shape[1])
        if sws.same:
            return self(sw)
        return weighted_probabilities(self.rows, sw, self.w, self.need, sws.proof).mean(axis=1)

    def with_upper(self, swarms) -> tuple[np.ndarray, np.ndarray]:
        """``(self(swarms), self.upper(swarms))``, the second computed only when it differs."""
        sw = self._swarms(swarms)
        vals = self(sw)
        return vals, (vals if survivor_weights(self.model, sw.shape[1]).same
                      else self.upper(sw))

    def scored(self, swarms) -> np.ndarray:
        """(K,) order keys: ``P_bank``, ties (e.g. P = 0 below the threshold) broken by
        the mean coverage, so searches move on the plateaus too."""
        sw = self._swarms(swarms)
        p = self(sw)
        cov = swarm_coverages(self.rows, sw, self.w).mean(axis=1)
        return np.round(p, 12) + 1e-6 * cov
