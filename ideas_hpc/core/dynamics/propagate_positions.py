"""Positions (and velocities) only, at given times: the scenario bank's orbit flights (issue 31).

:func:`propagate_positions_into` is :func:`ideas_hpc.core.dynamics.targeting.propagate_batch`
writing only ``r`` (m, frame T) at the requested times into a caller's buffer, and
the velocities ``v`` (m/s, relative to T) into a second one when the smear test
needs them (SPEC 7d): the integrator's steps do not depend on the output times and
every output is the same dense-output polynomial at the same time, so a position
or velocity is the same bits as in the full ``(N, T, 6)`` states, without writing
(and then striding over) the samples between the images.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.dynamics.propagate import propagate
from ideas_hpc.core.dynamics.targeting import NO_STM


@njit(cache=True, parallel=True)
def propagate_positions_into(r0, v0, t0, tf, rtol, atol, max_steps, t_out, out, v_out, fi, ff):
    """``out[i, k] = r_i(t_out[k])`` (N, T, 3) m and, unless ``v_out`` is ``(0, 0, 3)``,
    ``v_out[i, k] = v_i(t_out[k])`` (N, T, 3) m/s; returns the integrator's status (N,)
    (0: success). Other arguments as
    :func:`~ideas_hpc.core.dynamics.targeting.propagate_batch`."""
    n = r0.shape[0]
    status = np.zeros(n, dtype=np.int64)
    with_v = v_out.shape[0] > 0
    for i in prange(n):
        if with_v:
            # the dense output writes its first m columns: six here, split after
            y = np.empty((t_out.shape[0], 6))
            yf, nf, st = propagate(r0[i], v0[i], t0, tf, NO_STM, rtol, atol, t_out, y,
                                   max_steps, fi, ff)
            for k in range(t_out.shape[0]):
                for j in range(3):
                    out[i, k, j] = y[k, j]
                    v_out[i, k, j] = y[k, 3 + j]
        else:
            yf, nf, st = propagate(r0[i], v0[i], t0, tf, NO_STM, rtol, atol, t_out, out[i],
                                   max_steps, fi, ff)
        status[i] = st
    return status
