"""Swarm and ring frames (SPEC section 3; paper section 3, eqs. 11-13).

Frames:

* ``T``: body-fixed frame of the target (origin at the centre of mass,
  +z spin pole, +x prime meridian).
* ``S``: swarm frame. ``x_S = unit(r_0 - R_SC)``, ``y_S = unit(v_SC x x_S)``,
  ``z_S = x_S x y_S``; ``[TS] = [x_S y_S z_S]`` (columns in T components).
* ``R_i``: ring frame of spacecraft i: origin at the spacecraft, z toward the
  ring centre, x along ``z_S``, ``y = z x x``. The paper's eq. 13 does not
  satisfy its own words; SPEC section 3 gives the rows used here.

Lengths in m, angles in rad.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ideas_hpc.core.attitude.mrp import cross3


@njit(cache=True)
def _unit(v):
    n = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return v / n


@njit(cache=True)
def dcm_TS(r_0_T, R_SC_T, v_SC_T):
    """Swarm frame ``[TS]`` (columns ``x_S, y_S, z_S`` in T components).

    Parameters
    ----------
    r_0_T : (3,) float64
        Ring point at swarm angle 0, m, frame T.
    R_SC_T : (3,) float64
        Swarm centre, m, frame T.
    v_SC_T : (3,) float64
        Swarm-centre velocity, m/s, frame T. Must not be parallel to
        ``r_0_T - R_SC_T``.
    """
    x = _unit(r_0_T - R_SC_T)
    y = _unit(cross3(v_SC_T, x))
    z = cross3(x, y)
    m = np.empty((3, 3))
    m[:, 0] = x
    m[:, 1] = y
    m[:, 2] = z
    return m


@njit(cache=True)
def dcm_RS(theta):
    """Ring frame of a spacecraft at swarm angle ``theta`` (rad), ``[R_i S]``.

    Rows (SPEC section 3, corrected eq. 13)::

        x_R = (0, 0, 1)
        y_R = (-sin theta, cos theta, 0)
        z_R = (-cos theta, -sin theta, 0)
    """
    c = np.cos(theta)
    s = np.sin(theta)
    m = np.zeros((3, 3))
    m[0, 2] = 1.0
    m[1, 0] = -s
    m[1, 1] = c
    m[2, 0] = -c
    m[2, 1] = -s
    return m


@njit(cache=True)
def dcm_RT(theta, dcm_TS_):
    """Ring frame in body components, ``[R_i T] = [R_i S][TS]^T``."""
    return dcm_RS(theta) @ dcm_TS_.T


@njit(cache=True)
def ring_positions_T(theta, d_sep, z):
    """Nominal ring positions ``[d cos theta_i, d sin theta_i, z_i]`` (m), shape (N, 3)."""
    n = theta.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        out[i, 0] = d_sep * np.cos(theta[i])
        out[i, 1] = d_sep * np.sin(theta[i])
        out[i, 2] = z[i]
    return out
