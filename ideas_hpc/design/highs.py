"""One call into HiGHS (:func:`scipy.optimize.milp`) for every design programme.

SciPy warns (``OptimizeWarning``) when an option is out of HiGHS's range, e.g. a
time limit that ran out (<= 0 s) before the call; such warnings are the
designer's business, not the user's (issue 29). The limit is clamped to a
positive value, and any warning SciPy still raises is kept on the result as
``res.solver_warnings`` (a list of one-line strings) instead of being printed.
"""

from __future__ import annotations

import math
import warnings

from scipy.optimize import milp

#: Shortest time limit handed to HiGHS, s (it refuses 0 and negative limits).
MIN_LIMIT_S = 1e-3


def run_milp(c, *, constraints, integrality, bounds, time_limit=None, mip_rel_gap=0.0):
    """``milp`` with ``time_limit`` (s, None: none) clamped to >= :data:`MIN_LIMIT_S`;
    warnings raised inside are returned on the result, never shown."""
    opts = {"mip_rel_gap": float(mip_rel_gap)}
    if time_limit is not None and math.isfinite(float(time_limit)):
        opts["time_limit"] = max(MIN_LIMIT_S, float(time_limit))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = milp(c, constraints=constraints, integrality=integrality, bounds=bounds,
                   options=opts)
    res.solver_warnings = [f"{w.category.__name__}: {w.message}" for w in caught]
    return res
