"""Sliding-mode attitude tracking law with reaction wheels (SPEC section 5).

After Kowalchuk & Hall (2008). Errors (S&J section 8.3 notation)::

    ds = sigma_B/R                      (MRP of B relative to the reference R)
    dw = omega_BN - [BR] omega_RN       (rad/s, B components)
    z  = integral of ds dt              (s; a discrete controller state)
    s  = dw + K_P ds + K_I z            (sliding surface, rad/s)

Reaching law ``s' = -eta sat(phi s)`` (``sat`` clips each component to
[-1, 1]), hence the commanded relative acceleration::

    dw'_cmd = -K_P ds' - K_I ds - eta sat(phi s),   ds' = 1/4 B(ds) dw  (S&J 3.159)

The body acceleration follows from the B-frame derivative of ``dw``
(``omegadot_r`` is the inertial derivative of the reference rate)::

    omega'_cmd = dw'_cmd + [BR] omegadot_r - omega x [BR] omega_r

and the wheel torques from the equations of motion (``core.attitude``),
feeding forward the gyroscopic term::

    u_s = -[I_RW] omega'_cmd - omega x ([I_RW] omega + h_s) + L_known

followed by the actuator limits (``core.attitude.wheel_limits_into``, per wheel
``wheel_limit_s``).

All gains are per axis (B components): ``K_P`` 1/s, ``K_I`` 1/s^2,
``eta`` rad/s^2, ``phi`` s/rad.

Discrete-time note (why ``phi`` is capped). The controller runs at the
integration step ``dt`` with a zero-order hold. Inside the boundary layer the
reaching law is linear, ``s' = -eta phi s``, and its sampled form is
``s_{k+1} = (1 - eta phi dt) s_k``. With Table 5/6 values (``eta phi = 50 1/s``,
``dt = 0.1 s``) the factor is -4: the sampled loop is unstable inside the
layer and settles into a period-2 limit cycle of amplitude about
``eta dt / 2`` = 0.025 rad/s in ``s``, which holds the MRP error near 2e-2
(measured, Eros NP) with torque chatter and never reaches the 1e-5 target. The boundary
layer gain is therefore capped by the caller at ``eta phi dt <= 1``
(``phi_eff = min(phi, phi_dt_cap / (eta dt))``, deadbeat at the cap). The
continuous-time design is unchanged; see ``ideas_hpc.attitude.Gains``.

The integral state ``z`` is advanced by the caller (``core.attitude_batch``),
only while ``|ds| < int_limit`` (conditional integration, anti-windup; the
reason is in the ``ideas_hpc.attitude`` module docstring).
"""

from __future__ import annotations

from numba import njit

from ideas_hpc.core.attitude.rigid_body import wheel_limit_s
from ideas_hpc.core.attitude.mrp import mrp_rotate_s, mrp_sub_s


@njit(cache=True)
def sat_s(v):
    """The boundary-layer saturation ``sat(v) = min(1, max(-1, v))`` (dimensionless),
    written with branches (the same value for every finite ``v``) so that the law
    below also compiles for Numba's CUDA target, which does not type the float
    builtins (:mod:`ideas_hpc.core.attitude.batch_cuda` flies this very function)."""
    if v > 1.0:
        return 1.0
    if v < -1.0:
        return -1.0
    return v


@njit(cache=True, error_model="numpy")
def sliding_mode_into(x, z, ref, gains, wheels, L_known, u_out, err_out):
    """Sliding-mode wheel torques for one spacecraft (SPEC section 5).

    Parameters
    ----------
    x : (9,) float64
        ``[sigma_BN, omega_BN_B (rad/s), Omega (rad/s)]``.
    z : (3,) float64
        Integral of the MRP error, s.
    ref : (9,) float64
        ``[sigma_RN, omega_RN_R (rad/s), omegadot_RN_R (rad/s^2)]`` from
        ``core.maneuvers``.
    gains : :class:`~ideas_hpc.core.attitude.records.ControlGains`
        ``K_P`` (1/s), ``K_I`` (1/s^2), reaching gain ``eta`` (rad/s^2) and
        boundary-layer slope ``phi`` (s/rad, already capped for the step, see
        module doc), each (3,).
    wheels : :class:`~ideas_hpc.core.attitude.records.Wheels`
        ``[I_RW]`` principal moments and wheel spin inertias (kg m^2), torque
        (N m) and wheel momentum (N m s) limits.
    L_known : (3,) float64
        Known external torque fed forward, N m (zero in SPEC).
    u_out : (3,) float64
        Output: applied wheel torques, N m (after limits).
    err_out : (6,) float64
        Output: ``[ds, dw (rad/s)]``.
    """
    k_p = gains.k_p
    k_i = gains.k_i
    eta = gains.eta
    phi = gains.phi
    I_rw = wheels.I_rw_kgm2
    J_s = wheels.J_s_kgm2
    u_max = wheels.u_max_Nm
    h_max = wheels.h_max_Nms
    s1 = x[0]
    s2 = x[1]
    s3 = x[2]
    w1 = x[3]
    w2 = x[4]
    w3 = x[5]
    d1, d2, d3 = mrp_sub_s(s1, s2, s3, ref[0], ref[1], ref[2])
    # reference rate and inertial acceleration in B components
    r1, r2, r3 = mrp_rotate_s(d1, d2, d3, ref[3], ref[4], ref[5])
    if ref[6] == 0.0 and ref[7] == 0.0 and ref[8] == 0.0:  # NP: no reference acceleration
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
    else:
        a1, a2, a3 = mrp_rotate_s(d1, d2, d3, ref[6], ref[7], ref[8])
    e1 = w1 - r1
    e2 = w2 - r2
    e3 = w3 - r3
    # ds' = 1/4 B(ds) dw
    dd = d1 * d1 + d2 * d2 + d3 * d3
    de = d1 * e1 + d2 * e2 + d3 * e3
    q = 1.0 - dd
    sd1 = 0.25 * (q * e1 + 2.0 * (d2 * e3 - d3 * e2) + 2.0 * de * d1)
    sd2 = 0.25 * (q * e2 + 2.0 * (d3 * e1 - d1 * e3) + 2.0 * de * d2)
    sd3 = 0.25 * (q * e3 + 2.0 * (d1 * e2 - d2 * e1) + 2.0 * de * d3)
    sv1 = e1 + k_p[0] * d1 + k_i[0] * z[0]
    sv2 = e2 + k_p[1] * d2 + k_i[1] * z[1]
    sv3 = e3 + k_p[2] * d3 + k_i[2] * z[2]
    p1 = sat_s(phi[0] * sv1)
    p2 = sat_s(phi[1] * sv2)
    p3 = sat_s(phi[2] * sv3)
    dwd1 = -k_p[0] * sd1 - k_i[0] * d1 - eta[0] * p1
    dwd2 = -k_p[1] * sd2 - k_i[1] * d2 - eta[1] * p2
    dwd3 = -k_p[2] * sd3 - k_i[2] * d3 - eta[2] * p3
    # omega'_cmd = dw'_cmd + omegadot_r - omega x omega_r
    wd1 = dwd1 + a1 - (w2 * r3 - w3 * r2)
    wd2 = dwd2 + a2 - (w3 * r1 - w1 * r3)
    wd3 = dwd3 + a3 - (w1 * r2 - w2 * r1)
    h1 = I_rw[0] * w1 + J_s[0] * (x[6] + w1)
    h2 = I_rw[1] * w2 + J_s[1] * (x[7] + w2)
    h3 = I_rw[2] * w3 + J_s[2] * (x[8] + w3)
    u_out[0] = wheel_limit_s(-I_rw[0] * wd1 - (w2 * h3 - w3 * h2) + L_known[0],
                             x[6], J_s[0], u_max, h_max)
    u_out[1] = wheel_limit_s(-I_rw[1] * wd2 - (w3 * h1 - w1 * h3) + L_known[1],
                             x[7], J_s[1], u_max, h_max)
    u_out[2] = wheel_limit_s(-I_rw[2] * wd3 - (w1 * h2 - w2 * h1) + L_known[2],
                             x[8], J_s[2], u_max, h_max)
    err_out[0] = d1
    err_out[1] = d2
    err_out[2] = d3
    err_out[3] = e1
    err_out[4] = e2
    err_out[5] = e3
