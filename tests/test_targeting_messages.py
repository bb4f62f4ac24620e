"""Targeting failures become one line naming the spacecraft, its miss and the field to change.

The cause is read off the miss history (:func:`ideas_hpc.flyby.flight.targeting_input_error`),
which names the setup's parameter; the campaign layer maps it to the file's key;
these histories are made up so each branch is checked deterministically (the
end-to-end cases are in ``tests/bad_inputs/cases.toml``).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from ideas_hpc.campaign.schema.model_fields import flyby_errors
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.flight import targeting_input_error
from ideas_hpc.dynamics.trajectory import TargetingError, TargetingResult

R_MAX = 17.0e3


def _error(history, radius=100e3, max_iter=25):
    """A one-spacecraft failure whose miss history is ``history`` (m), flying at ``radius``."""
    n = len(history) - 1
    miss = np.full((1, max_iter + 1), np.nan)
    miss[0, :n + 1] = history
    pos = np.zeros((1, 5, 3))
    pos[0, :, 0] = radius
    res = TargetingResult(v0_T=np.zeros((1, 3)), miss=miss, n_iter=np.array([n]),
                          converged=np.array([False]), times=np.arange(5.0), position_T=pos,
                          velocity_T=np.zeros((1, 5, 3)))
    setup = SimpleNamespace(tol_m=1e-13 if n == max_iter else 0.01, max_iter=max_iter,
                            d_sep_m=radius, body=SimpleNamespace(shape=SimpleNamespace(r_max=R_MAX)))
    return targeting_input_error(TargetingError("x", [0], res), setup, np.array([0.2]))


@pytest.mark.parametrize("history,radius,max_iter,own,key", [
    ([3e3, 6e-4], 100e3, 1, "max_iter", "flyby.max_iterations"),      # still shrinking
    ([3e3] + [2e-11, 3e-11, 1e-11] * 8 + [2e-11], 100e3, 25, "tol_m",
     "flyby.tolerance_m"),                                            # stalled
    ([6e3, 1.6e3, 6.7e4, 6e3], 4e3, 25, "d_sep_m", "flyby.d_sep_km"),  # through the body
    ([5e4, 4e4, np.nan], 100e3, 25, "d_sep_m", "flyby.d_sep_km"),      # integrator gave up
])
def test_cause_and_field(history, radius, max_iter, own, key):
    e = _error(history, radius, max_iter)
    assert e.field == own and f"`{own}`" in e.message and "flyby." not in e.message
    assert "spacecraft 0" in e.message and "swarm angle 0.2 rad" in e.message
    assert "miss" in e.message and "\n" not in str(e)
    with pytest.raises(InputError) as ei, flyby_errors():   # what the user reads
        raise e
    m = ei.value
    assert m.field == key and key in m.message and "`" not in m.message
    assert m.message == e.message.replace(f"`{own}`", key)
