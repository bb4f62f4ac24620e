"""The sliding-mode law (core/attitude/control.py) closes the loop it was designed for:
with the wheel torques it commands applied to the rigid-body-with-wheels plant, the
sliding surface s = dw + K_P ds + K_I z obeys the reaching law s' = -eta sat(phi s).

Oracle: s is computed here from DCMs (NumPy, independent of the kernels' MRP algebra)
and differentiated in time by central differences along the plant's motion and the
reference's rotation; the case is chosen so that every term of ds' = 1/4 B(ds) dw
(the cross product included) is of the size of the result.
"""

from __future__ import annotations

import numpy as np
import pytest

from ideas_hpc.core.attitude.control import sliding_mode_into
from ideas_hpc.core.attitude.records import ControlGains, Wheels
from ideas_hpc.core.attitude.rigid_body import rw_eom


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _dcm(sigma):
    """[XN] of the MRP sigma (S&J 3.147)."""
    s = np.asarray(sigma, dtype=float)
    S = _skew(s)
    q = s @ s
    return np.eye(3) + (8.0 * S @ S - 4.0 * (1.0 - q) * S) / (1.0 + q) ** 2


def _mrp(C):
    """Short MRP of the DCM C via the quaternion (Sheppard's method)."""
    tr = np.trace(C)
    b2 = np.array([(1 + tr) / 4, (1 + 2 * C[0, 0] - tr) / 4, (1 + 2 * C[1, 1] - tr) / 4,
                   (1 + 2 * C[2, 2] - tr) / 4])
    i = int(np.argmax(b2))
    b = np.empty(4)
    b[i] = np.sqrt(b2[i])
    pairs = {0: ((1, C[1, 2] - C[2, 1]), (2, C[2, 0] - C[0, 2]), (3, C[0, 1] - C[1, 0])),
             1: ((0, C[1, 2] - C[2, 1]), (2, C[0, 1] + C[1, 0]), (3, C[2, 0] + C[0, 2])),
             2: ((0, C[2, 0] - C[0, 2]), (1, C[0, 1] + C[1, 0]), (3, C[1, 2] + C[2, 1])),
             3: ((0, C[0, 1] - C[1, 0]), (1, C[2, 0] + C[0, 2]), (2, C[1, 2] + C[2, 1]))}
    for j, v in pairs[i]:
        b[j] = v / (4 * b[i])
    if b[0] < 0:
        b = -b
    return b[1:] / (1.0 + b[0])


AXIS = np.array([1.0, 2.0, 2.0]) / 3.0     # reference: constant rate about a fixed axis
W_R = 0.02                                  # rad/s
THETA0 = 0.7                                # rad


def _sigma_RN(t):
    return AXIS * np.tan((THETA0 + W_R * t) / 4.0)


def _surface(t, x, z, k_p, k_i):
    """(ds, s) at time t for the state x and integral z, from DCMs."""
    C_BR = _dcm(x[:3]) @ _dcm(_sigma_RN(t)).T
    ds = _mrp(C_BR)
    dw = x[3:6] - C_BR @ (W_R * AXIS)   # omega_RN is AXIS * W_R in R (and N) components
    return ds, dw + k_p * ds + k_i * z


@pytest.mark.parametrize("phi", [[40.0, 60.0, 50.0], [2.0, 3.0, 1.5]])
def test_closed_loop_obeys_the_reaching_law(phi):
    # phi large: every component saturated (s' = -eta sign s); small: the boundary layer
    k_p = np.array([0.3, 0.4, 0.35])
    k_i = np.array([0.02, 0.03, 0.025])
    eta = np.array([0.02, 0.03, 0.025])
    gains = ControlGains(k_p, k_i, eta, np.array(phi), np.inf)
    wheels = Wheels(np.array([90.0, 120.0, 70.0]), np.array([0.08, 0.1, 0.12]), 1e9, 1e9)
    t = 3.0
    x = np.array([0.1, -0.25, 0.3, 0.06, -0.04, 0.05, 150.0, -80.0, 30.0])
    z = np.array([0.4, -0.3, 0.5])
    ref = np.concatenate([_sigma_RN(t), W_R * AXIS, np.zeros(3)])
    u = np.empty(3)
    err = np.empty(6)
    sliding_mode_into(x, z, ref, gains, wheels, np.zeros(3), u, err)
    ds, s = _surface(t, x, z, k_p, k_i)
    np.testing.assert_allclose(err[:3], ds, rtol=0, atol=1e-13)
    # the cross term of ds' is of the size of the result, on every axis
    dw = err[3:]
    assert np.all(np.abs(k_p * 0.5 * np.cross(ds, dw)) > 0.05 * eta)
    xdot = np.empty(9)
    rw_eom(x, u, np.zeros(3), wheels.I_rw_kgm2, wheels.J_s_kgm2, xdot)
    h = 1e-4
    _, s_p = _surface(t + h, x + h * xdot, z + h * ds, k_p, k_i)
    _, s_m = _surface(t - h, x - h * xdot, z - h * ds, k_p, k_i)
    s_dot = (s_p - s_m) / (2 * h)
    want = -eta * np.clip(np.array(phi) * s, -1.0, 1.0)
    np.testing.assert_allclose(s_dot, want, rtol=0, atol=1e-8 + 1e-6 * np.abs(want).max())
