"""Where the closed loop starts: on the reference of the geometry flown (SPEC section 7d).

A start *relative to the reference* gives, per spacecraft, the attitude error
``sigma_B/R`` (MRP), the rate error ``omega_B/R`` (rad/s, B components) and the
wheel speeds (rad/s) at the first attitude step. The reference there is the one
the controller will track: the ring frame (Nadir Pointing), the FoV-sweep frame,
either turned into the encounter's swarm frame (``dcm_TS = [N S]`` on an
encounter), or the first row of a body-tracking table. :func:`absolute_start`
turns such a start into the absolute ``sigma_BN``, ``omega_BN_B`` the kernel
integrates, so a start with zero errors is exactly on the reference whatever the
geometry (a fixed ``[TN](t0) = I`` ring frame is right only for a pole-aligned pass).
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.core.attitude.maneuvers import TRACK_MODE, reference
from ideas_hpc.core.attitude.mrp import dcm_from_mrp, mrp_from_dcm


def reference_state0(mode: int, ring_dcms: np.ndarray, spin_rate: float, periods: np.ndarray,
                     theta_max: float, table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(sigma_RN (N, 3), omega_RN_R (N, 3) rad/s)``: the reference at the first step.

    ``mode``: maneuver code (``core.attitude.maneuvers``); ``ring_dcms`` (N, 3, 3)
    ``[R_i T]`` as the kernel receives them; ``table`` (N, T, 9) the body-tracking
    reference (``mode == TRACK_MODE``).
    """
    n = ring_dcms.shape[0]
    if mode == TRACK_MODE:
        return (np.ascontiguousarray(table[:, 0, 0:3]), np.ascontiguousarray(table[:, 0, 3:6]))
    s = np.empty((n, 3))
    w = np.empty((n, 3))
    for i in range(n):
        s[i], w[i], _ = reference(mode, 0.0, float(spin_rate),
                                  np.ascontiguousarray(ring_dcms[i]), float(theta_max),
                                  float(periods[i]))
    return s, w


def absolute_start(sigma_RN: np.ndarray, omega_RN_R: np.ndarray, sigma_BR: np.ndarray,
                   omega_BR_B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(sigma_BN, omega_BN_B)`` (S, N, 3) of errors ``sigma_BR``, ``omega_BR_B`` (S, N, 3)
    about the reference ``sigma_RN``, ``omega_RN_R`` (N, 3):
    ``[BN] = [BR][RN]``, ``omega_BN = [BR] omega_RN_R + omega_BR``."""
    n_s, n = sigma_BR.shape[0], sigma_BR.shape[1]
    s_out = np.empty((n_s, n, 3))
    w_out = np.empty((n_s, n, 3))
    rn = [dcm_from_mrp(np.ascontiguousarray(sigma_RN[i])) for i in range(n)]
    for a in range(n_s):
        for i in range(n):
            br = dcm_from_mrp(np.ascontiguousarray(sigma_BR[a, i]))
            s_out[a, i] = mrp_from_dcm(np.ascontiguousarray(br @ rn[i]))
            w_out[a, i] = br @ omega_RN_R[i] + omega_BR_B[a, i]
    return s_out, w_out
