"""The area row of the bank designers' integer programmes (issue 40), built here only.

Every programme that asks a swarm to reach a
:class:`~ideas_hpc.mapping.requirement.Threshold` counts the area of the vertex
groups it covers, ``y_g`` in [0, 1] with weights ``w_g`` (area fractions), and asks::

    sum_g w_g y_g >= need + FEAS_TOL

(:func:`area_constraint`; :func:`area_row` and :func:`area_floor` for a programme that
stacks its rows itself, as the failure-tolerant one does). The margin
:data:`FEAS_TOL` keeps the solver's own tolerances from passing a short swarm; the
designers recompute the union of the swarm HiGHS returns from the masks. Used by
:mod:`ideas_hpc.design.exact`, :mod:`ideas_hpc.design.failures` and
:mod:`ideas_hpc.design.stereo`. The scenario programme of the success-probability
designer (:mod:`ideas_hpc.design.scenario_mip`) asks a different row per scenario,
``(need - W_heavy,s) z_s <= sum_light w y``, without the margin: it bounds
``P_bank`` from above and must keep every swarm the evaluator counts.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import LinearConstraint

from ideas_hpc.mapping.requirement import Threshold

#: Margin of the programmes' area row above ``need`` (area fraction); the true union
#: coverage of every returned swarm is recomputed from the masks.
FEAS_TOL = 1e-9


def area_floor(threshold: Threshold) -> float:
    """The least covered area the programmes ask, ``need + FEAS_TOL``."""
    return threshold.need + FEAS_TOL


def area_row(weights: np.ndarray, start: int, n_var: int) -> np.ndarray:
    """``(n_var,)`` coefficients: the group ``weights`` in the columns from ``start`` to
    ``start + G - 1`` (the ``y_g``), zero elsewhere."""
    w = np.asarray(weights, dtype=np.float64)
    row = np.zeros(n_var)
    row[start:start + w.size] = w
    return row


def area_constraint(threshold: Threshold, weights: np.ndarray, start: int,
                    n_var: int) -> LinearConstraint:
    """``sum_g w_g y_g >= need + FEAS_TOL`` over the columns from ``start`` of ``n_var``."""
    return LinearConstraint(area_row(weights, start, n_var)[None, :], area_floor(threshold),
                            np.inf)
