"""Batched Newton-Raphson targeting of a whole swarm (SPEC section 4, paper eqs. 4-6).

For each spacecraft i (``prange``), starting at ``r0_i`` at t0 and aiming for
``r_target_i`` at tf:

* initial guess (paper eq. 4): ``v0 = (r_target - r0) / (tf - t0)``;
* iterate (SPEC section 4, the paper's eq. 6 corrected):
  propagate state + STM, ``dr_k = r_k(tf) - r_target``; stop when
  ``|dr_k| <= tol``; otherwise ``v0 <- v0 - Phi_rv^{-1} dr_k`` with
  ``Phi_rv = d r(tf) / d v(t0)``, at most ``max_iter`` updates;
* the converged trajectory (position, velocity) is then sampled on the
  output grid by a state-only run from the same ``v0`` (same integrator and
  tolerances; it agrees with the STM run to the integration tolerance).

A spacecraft that fails (no convergence within ``max_iter``, singular
``Phi_rv``, integrator failure, non-finite miss) is flagged, never dropped:
``converged[i] = False`` and its samples are still the last trajectory tried.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.dynamics.propagate import STATUS_OK, propagate

# ``with_stm`` as a plain (not literal) bool: numba types a literal True/False
# argument as ``Literal[bool]`` and compiled the whole integrator twice (one
# specialisation per flag value) on a cold cache.
STM = np.bool_(True)
NO_STM = np.bool_(False)


@njit(cache=True)
def _solve3(m, b, out):
    """``out = m^{-1} b`` for a 3x3 ``m`` by cofactors; returns False if singular."""
    c00 = m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]
    c01 = m[1, 2] * m[2, 0] - m[1, 0] * m[2, 2]
    c02 = m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]
    det = m[0, 0] * c00 + m[0, 1] * c01 + m[0, 2] * c02
    scale = 0.0
    for i in range(3):
        for j in range(3):
            scale = max(scale, abs(m[i, j]))
    if not np.isfinite(det) or abs(det) <= 1e-14 * scale ** 3:
        return False
    inv = np.empty((3, 3))
    inv[0, 0] = c00
    inv[1, 0] = c01
    inv[2, 0] = c02
    inv[0, 1] = m[0, 2] * m[2, 1] - m[0, 1] * m[2, 2]
    inv[1, 1] = m[0, 0] * m[2, 2] - m[0, 2] * m[2, 0]
    inv[2, 1] = m[0, 1] * m[2, 0] - m[0, 0] * m[2, 1]
    inv[0, 2] = m[0, 1] * m[1, 2] - m[0, 2] * m[1, 1]
    inv[1, 2] = m[0, 2] * m[1, 0] - m[0, 0] * m[1, 2]
    inv[2, 2] = m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    for i in range(3):
        out[i] = (inv[i, 0] * b[0] + inv[i, 1] * b[1] + inv[i, 2] * b[2]) / det
    return True


@njit(cache=True)
def target_one(r0, r_target, t0, tf, tol, max_iter, rtol, atol, max_steps, forces, v0, miss):
    """Newton targeting of one spacecraft.

    Parameters
    ----------
    r0, r_target : (3,) float64
        Start (at t0) and target (at tf) positions, m, frame T.
    t0, tf : float
        s.
    tol : float
        Miss tolerance, m (1 cm in SPEC section 4).
    max_iter : int
        Maximum number of Newton updates (25).
    rtol, atol, max_steps
        Integrator settings (:func:`ideas_hpc.core.dynamics.propagate.dop853`).
    forces : tuple
        The force record ``(fi, ff)`` (:mod:`ideas_hpc.core.dynamics.forces`).
    v0 : (3,) float64
        Output: the final initial velocity, m/s.
    miss : (max_iter + 1,) float64
        Output: ``|dr_k|`` (m) of propagation k, NaN where not run.

    Returns
    -------
    n_iter : int
        Newton updates made.
    converged : bool
    nfev : int
        Right-hand-side evaluations (42-state).
    """
    fi, ff = forces
    dt = tf - t0
    for i in range(3):
        v0[i] = (r_target[i] - r0[i]) / dt  # paper eq. 4
    for k in range(miss.shape[0]):
        miss[k] = np.nan
    empty_t = np.empty(0)
    empty_y = np.empty((0, 6))
    dr = np.empty(3)
    dv = np.empty(3)
    prv = np.empty((3, 3))
    nfev = 0
    k = 0
    converged = False
    while True:
        y, nf, status = propagate(r0, v0, t0, tf, STM, rtol, atol, empty_t, empty_y,
                                  max_steps, fi, ff)
        nfev += nf
        if status != STATUS_OK:
            break
        for i in range(3):
            dr[i] = y[i] - r_target[i]
        err = np.sqrt(dr[0] ** 2 + dr[1] ** 2 + dr[2] ** 2)
        miss[k] = err
        if not np.isfinite(err):
            break
        if err <= tol:
            converged = True
            break
        if k >= max_iter:
            break
        # Phi_rv: rows 0-2, columns 3-5 of the row-major STM at y[6:]
        for i in range(3):
            for j in range(3):
                prv[i, j] = y[6 + 6 * i + 3 + j]
        if not _solve3(prv, dr, dv):
            break
        for i in range(3):
            v0[i] -= dv[i]
        k += 1
    return k, converged, nfev


@njit(cache=True, parallel=True)
def target_batch(r0, r_target, t0, tf, tol, max_iter, rtol, atol, max_steps, t_out,
                 fi, ff):
    """Target every spacecraft in one call (``prange`` over spacecraft).

    Parameters
    ----------
    r0, r_target : (N, 3) float64
        m, frame T.
    t0, tf, tol, max_iter, rtol, atol, max_steps
        As :func:`target_one`.
    t_out : (T,) float64
        Sample times in ``[t0, tf]`` (the attitude step, 0.1 s).
    fi, ff
        Force record (:mod:`ideas_hpc.core.dynamics.forces`).

    Returns
    -------
    v0 : (N, 3) float64
        m/s.
    miss : (N, max_iter + 1) float64
        m, NaN where not run (paper Fig. 23).
    n_iter : (N,) int64
    converged : (N,) bool
    states : (N, T, 6) float64
        ``[r, v]`` of the final trajectory at ``t_out`` (paper Fig. 22).
    nfev : (N,) int64
        Right-hand-side evaluations of the Newton loop (42-state).
    """
    n = r0.shape[0]
    v0 = np.empty((n, 3))
    miss = np.empty((n, max_iter + 1))
    n_iter = np.zeros(n, dtype=np.int64)
    converged = np.zeros(n, dtype=np.bool_)
    nfev = np.zeros(n, dtype=np.int64)
    states = np.full((n, t_out.shape[0], 6), np.nan)
    for i in prange(n):
        k, ok, nf = target_one(r0[i], r_target[i], t0, tf, tol, max_iter, rtol, atol,
                               max_steps, (fi, ff), v0[i], miss[i])
        n_iter[i] = k
        converged[i] = ok
        nfev[i] = nf
        propagate(r0[i], v0[i], t0, tf, NO_STM, rtol, atol, t_out, states[i], max_steps,
                  fi, ff)
    return v0, miss, n_iter, converged, states, nfev


@njit(cache=True, parallel=True)
def propagate_batch(r0, v0, t0, tf, rtol, atol, max_steps, t_out,
                    fi, ff):
    """Propagate every spacecraft from given ``(r0, v0)`` (``prange`` over spacecraft).

    For Monte Carlo flights of a designed trajectory with dispersed initial
    states and force parameters (no retargeting: the spacecraft flies its
    nominal ``v0`` through the perturbed field).

    Returns
    -------
    states : (N, T, 6) float64
        ``[r, v]`` at ``t_out`` (m, m/s, frame T).
    status : (N,) int64
        The integrator's status per spacecraft (0: success).
    """
    n = r0.shape[0]
    states = np.full((n, t_out.shape[0], 6), np.nan)
    status = np.zeros(n, dtype=np.int64)
    for i in prange(n):
        y, nf, st = propagate(r0[i], v0[i], t0, tf, NO_STM, rtol, atol, t_out, states[i],
                              max_steps, fi, ff)
        status[i] = st
    return states, status
