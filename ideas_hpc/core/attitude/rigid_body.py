"""Rigid spacecraft with three reaction wheels: equations of motion and RK4 step.

SPEC section 5; Schaub & Junkins, *Analytical Mechanics of Space Systems*
(4th ed., 2018), section 4.5 (cited as S&J), with the wheel spin axes on the
principal body axes (``[G_s] = I``) and no gimbals.

State of one spacecraft, ``x`` (9,) float64::

    x[0:3] = sigma_BN      MRP of body B relative to inertial N (dimensionless)
    x[3:6] = omega_BN_B    body rate, rad/s, B components
    x[6:9] = Omega         wheel speeds relative to the body, rad/s

Equations of motion (S&J eqs. 4.146-4.147 with ``[G_s] = I``)::

    sigma'          = 1/4 B(sigma) omega                        (S&J 3.159)
    [I_RW] omega'   = -omega x ([I_RW] omega + h_s) - u_s + L_ext
    h_s             = J_s (Omega + omega)                       (component-wise)
    J_s Omega'      = u_s - J_s omega'                          (component-wise)

``[I_RW]`` is the hub inertia plus the wheels' transverse inertia; the
wheels' spin inertia ``J_s`` is carried by ``h_s``. Because the wheels sit on
the principal axes, ``[I_RW]`` is diagonal and is passed as its three
principal moments ``I_rw`` (kg m^2). Conserved with ``u_s = 0`` and
``L_ext = 0``: the inertial angular momentum ``[NB]([I_RW] omega + h_s)`` and
the kinetic energy ``1/2 omega.[I_RW] omega + 1/2 sum J_s (Omega + omega)^2``.

The control torque ``u_s`` (N m, torque *on the wheels*; the body feels
``-u_s``) is held constant over a step (zero-order hold, as a flight computer
at 10 Hz would apply it). The MRP is switched to its shadow set between steps
when ``|sigma| > 1`` (S&J 3.150), never inside an RK4 stage.

The hot kernels write into caller-provided arrays and allocate nothing, so the
batched simulation (``core.attitude_batch``) runs at well under a microsecond
per spacecraft step.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def rw_eom(x, u, L_ext, I_rw, J_s, xdot):
    """Time derivative of the spacecraft state (SPEC section 5; S&J 4.146-4.147).

    Parameters
    ----------
    x : (9,) float64
        ``[sigma_BN, omega_BN_B (rad/s), Omega (rad/s)]``.
    u : (3,) float64
        Wheel motor torques ``u_s``, N m (held constant by the caller).
    L_ext : (3,) float64
        External torque on the spacecraft, N m, B components.
    I_rw : (3,) float64
        Principal moments of ``[I_RW]`` (hub plus wheel transverse inertia), kg m^2.
    J_s : (3,) float64
        Wheel spin-axis inertias, kg m^2.
    xdot : (9,) float64
        Output: ``[sigma', omega' (rad/s^2), Omega' (rad/s^2)]``.
    """
    s1 = x[0]
    s2 = x[1]
    s3 = x[2]
    w1 = x[3]
    w2 = x[4]
    w3 = x[5]
    ss = s1 * s1 + s2 * s2 + s3 * s3
    sw = s1 * w1 + s2 * w2 + s3 * w3
    # sigma' = 1/4 [(1 - s^2) w + 2 s x w + 2 (s.w) s]   (S&J 3.159)
    a = 1.0 - ss
    xdot[0] = 0.25 * (a * w1 + 2.0 * (s2 * w3 - s3 * w2) + 2.0 * sw * s1)
    xdot[1] = 0.25 * (a * w2 + 2.0 * (s3 * w1 - s1 * w3) + 2.0 * sw * s2)
    xdot[2] = 0.25 * (a * w3 + 2.0 * (s1 * w2 - s2 * w1) + 2.0 * sw * s3)
    # total angular momentum about the centre of mass, B components
    h1 = I_rw[0] * w1 + J_s[0] * (x[6] + w1)
    h2 = I_rw[1] * w2 + J_s[1] * (x[7] + w2)
    h3 = I_rw[2] * w3 + J_s[2] * (x[8] + w3)
    wd1 = (-(w2 * h3 - w3 * h2) - u[0] + L_ext[0]) / I_rw[0]
    wd2 = (-(w3 * h1 - w1 * h3) - u[1] + L_ext[1]) / I_rw[1]
    wd3 = (-(w1 * h2 - w2 * h1) - u[2] + L_ext[2]) / I_rw[2]
    xdot[3] = wd1
    xdot[4] = wd2
    xdot[5] = wd3
    xdot[6] = u[0] / J_s[0] - wd1
    xdot[7] = u[1] / J_s[1] - wd2
    xdot[8] = u[2] / J_s[2] - wd3


@njit(cache=True, error_model="numpy")
def _eom_s(x, u, L, iI, I, J, iJ):
    """Scalar form of :func:`rw_eom` on tuples: state ``x`` (9), torques ``u`` and
    ``L`` (3, N m), inertias ``I``, ``J`` and their inverses ``iI``, ``iJ`` (3,
    kg m^2 and 1/(kg m^2)); returns the 9-tuple ``xdot``."""
    s1, s2, s3, w1, w2, w3, W1, W2, W3 = x
    u1, u2, u3 = u
    L1, L2, L3 = L
    iI1, iI2, iI3 = iI
    I1, I2, I3 = I
    J1, J2, J3 = J
    iJ1, iJ2, iJ3 = iJ
    ss = s1 * s1 + s2 * s2 + s3 * s3
    sw = s1 * w1 + s2 * w2 + s3 * w3
    a = 1.0 - ss
    h1 = I1 * w1 + J1 * (W1 + w1)
    h2 = I2 * w2 + J2 * (W2 + w2)
    h3 = I3 * w3 + J3 * (W3 + w3)
    wd1 = (-(w2 * h3 - w3 * h2) - u1 + L1) * iI1
    wd2 = (-(w3 * h1 - w1 * h3) - u2 + L2) * iI2
    wd3 = (-(w1 * h2 - w2 * h1) - u3 + L3) * iI3
    return (0.25 * (a * w1 + 2.0 * (s2 * w3 - s3 * w2) + 2.0 * sw * s1),
            0.25 * (a * w2 + 2.0 * (s3 * w1 - s1 * w3) + 2.0 * sw * s2),
            0.25 * (a * w3 + 2.0 * (s1 * w2 - s2 * w1) + 2.0 * sw * s3),
            wd1, wd2, wd3,
            u1 * iJ1 - wd1, u2 * iJ2 - wd2, u3 * iJ3 - wd3)


@njit(cache=True, error_model="numpy")
def rk4_step_into(x, u, L_ext, I_rw, J_s, dt, work, out):
    """One fixed-step RK4 step of :func:`rw_eom` with ``u`` and ``L_ext`` held.

    After the step the MRP is switched to its shadow set if ``|sigma| > 1``
    (S&J 3.150); the stages themselves integrate one smooth branch.

    Parameters
    ----------
    x : (9,) float64
        State at ``t``.
    u, L_ext, I_rw, J_s
        As in :func:`rw_eom`.
    dt : float
        Step, s.
    work : (5, 9) float64
        Scratch space (kept for interface stability; the stages live in registers).
    out : (9,) float64
        Output: state at ``t + dt``. May be the same array as ``x``.
    """
    I1 = I_rw[0]
    I2 = I_rw[1]
    I3 = I_rw[2]
    J1 = J_s[0]
    J2 = J_s[1]
    J3 = J_s[2]
    iI1 = 1.0 / I1
    iI2 = 1.0 / I2
    iI3 = 1.0 / I3
    iJ1 = 1.0 / J1
    iJ2 = 1.0 / J2
    iJ3 = 1.0 / J3
    u1 = u[0]
    u2 = u[1]
    u3 = u[2]
    L1 = L_ext[0]
    L2 = L_ext[1]
    L3 = L_ext[2]
    x0 = x[0]
    x1 = x[1]
    x2 = x[2]
    x3 = x[3]
    x4 = x[4]
    x5 = x[5]
    x6 = x[6]
    x7 = x[7]
    x8 = x[8]
    h = 0.5 * dt
    u_ = (u1, u2, u3)
    L_ = (L1, L2, L3)
    iI = (iI1, iI2, iI3)
    I_ = (I1, I2, I3)
    J_ = (J1, J2, J3)
    iJ = (iJ1, iJ2, iJ3)
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = _eom_s(
        (x0, x1, x2, x3, x4, x5, x6, x7, x8), u_, L_, iI, I_, J_, iJ)
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = _eom_s(
        (x0 + h * a0, x1 + h * a1, x2 + h * a2, x3 + h * a3, x4 + h * a4, x5 + h * a5,
         x6 + h * a6, x7 + h * a7, x8 + h * a8), u_, L_, iI, I_, J_, iJ)
    c0, c1, c2, c3, c4, c5, c6, c7, c8 = _eom_s(
        (x0 + h * b0, x1 + h * b1, x2 + h * b2, x3 + h * b3, x4 + h * b4, x5 + h * b5,
         x6 + h * b6, x7 + h * b7, x8 + h * b8), u_, L_, iI, I_, J_, iJ)
    d0, d1, d2, d3, d4, d5, d6, d7, d8 = _eom_s(
        (x0 + dt * c0, x1 + dt * c1, x2 + dt * c2, x3 + dt * c3, x4 + dt * c4,
         x5 + dt * c5, x6 + dt * c6, x7 + dt * c7, x8 + dt * c8), u_, L_, iI, I_, J_, iJ)
    k = dt / 6.0
    s0 = x0 + k * (a0 + 2.0 * b0 + 2.0 * c0 + d0)
    s1 = x1 + k * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
    s2 = x2 + k * (a2 + 2.0 * b2 + 2.0 * c2 + d2)
    out[3] = x3 + k * (a3 + 2.0 * b3 + 2.0 * c3 + d3)
    out[4] = x4 + k * (a4 + 2.0 * b4 + 2.0 * c4 + d4)
    out[5] = x5 + k * (a5 + 2.0 * b5 + 2.0 * c5 + d5)
    out[6] = x6 + k * (a6 + 2.0 * b6 + 2.0 * c6 + d6)
    out[7] = x7 + k * (a7 + 2.0 * b7 + 2.0 * c7 + d7)
    out[8] = x8 + k * (a8 + 2.0 * b8 + 2.0 * c8 + d8)
    ss = s0 * s0 + s1 * s1 + s2 * s2
    if ss > 1.0:
        s0 = -s0 / ss
        s1 = -s1 / ss
        s2 = -s2 / ss
    out[0] = s0
    out[1] = s1
    out[2] = s2


@njit(cache=True, error_model="numpy")
def rk4_step(x, u, L_ext, I_rw, J_s, dt):
    """Allocating convenience form of :func:`rk4_step_into`; returns the new (9,) state."""
    work = np.empty((5, 9))
    out = np.empty(9)
    rk4_step_into(x, u, L_ext, I_rw, J_s, dt, work, out)
    return out


@njit(cache=True, error_model="numpy")
def wheel_limit_s(v, Omega_j, J_j, u_max, h_max):
    """Scalar actuator limit for one wheel (see :func:`wheel_limits_into`), N m."""
    if v > u_max:
        v = u_max
    elif v < -u_max:
        v = -u_max
    h = J_j * Omega_j
    if (h >= h_max and v > 0.0) or (h <= -h_max and v < 0.0):
        v = 0.0
    return v


@njit(cache=True, error_model="numpy")
def wheel_limits_into(u_cmd, Omega, J_s, u_max, h_max, out):
    """Actuator limits: torque saturation and wheel momentum limit (SPEC section 5).

    Each component is clipped to ``[-u_max, u_max]`` (N m). A wheel whose
    momentum ``J_s Omega`` (N m s) has reached ``+h_max`` gets no positive
    torque, and one at ``-h_max`` no negative torque: a wheel at its momentum
    limit cannot be driven further that way (it may still be driven back).
    The check is made when the torque is computed, so with the torque held
    over a step the momentum can pass ``h_max`` by at most about
    ``u_max dt`` (7e-4 N m s at 0.1 s, 1.4 % of the 0.05 N m s limit).

    Parameters
    ----------
    u_cmd : (3,) float64
        Commanded wheel torques, N m.
    Omega : (3,) float64
        Wheel speeds, rad/s.
    J_s : (3,) float64
        Wheel spin inertias, kg m^2.
    u_max, h_max : float
        Torque limit (N m) and momentum limit (N m s), both >= 0.
    out : (3,) float64
        Output: applied torques, N m. May be ``u_cmd``.
    """
    for j in range(3):
        out[j] = wheel_limit_s(u_cmd[j], Omega[j], J_s[j], u_max, h_max)


@njit(cache=True, error_model="numpy")
def angular_momentum_N(x, I_rw, J_s):
    """Inertial angular momentum ``[NB]([I_RW] omega + h_s)``, N m s, N components."""
    s1 = x[0]
    s2 = x[1]
    s3 = x[2]
    hb = np.empty(3)
    for j in range(3):
        hb[j] = I_rw[j] * x[3 + j] + J_s[j] * (x[6 + j] + x[3 + j])
    # [NB] = [BN]^T, [BN] from S&J 3.153
    ss = s1 * s1 + s2 * s2 + s3 * s3
    sx = np.array([[0.0, -s3, s2], [s3, 0.0, -s1], [-s2, s1, 0.0]])
    c = np.eye(3) + (8.0 * (sx @ sx) - 4.0 * (1.0 - ss) * sx) / ((1.0 + ss) * (1.0 + ss))
    return c.T @ hb


@njit(cache=True, error_model="numpy")
def kinetic_energy(x, I_rw, J_s):
    """Rotational kinetic energy ``1/2 w.[I_RW]w + 1/2 sum J_s (Omega + w)^2``, J."""
    e = 0.0
    for j in range(3):
        w = x[3 + j]
        e += 0.5 * I_rw[j] * w * w + 0.5 * J_s[j] * (x[6 + j] + w) ** 2
    return e
