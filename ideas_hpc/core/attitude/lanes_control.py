"""The Nadir Pointing controller of :func:`~ideas_hpc.core.attitude.camera_lanes.fly_cameras_lanes_into`,
many spacecraft side by side (issue 31): the lanes' state layout, branch-free MRP
algebra, and the controller in two passes.

The controller's MRP addition and subtraction have rare branches: the flip to
the other set of one operand when the denominator is small (``|den| < 0.1``)
and the switch of the result to its shadow set (``|sigma| > 1``). Computed both
ways and selected (:func:`_mrp_add_lane`, :func:`_mrp_sub_lane`), they cost 17
of the step's 24 packed divisions, the slowest packed operation. So
:func:`_control_lanes` first computes every lane on the common side only
(:func:`_mrp_add_common`, :func:`_mrp_sub_common`: the same operations as the
taken side, so the same bits) and flags the lanes where a rare side is taken;
only those are computed again with both sides (:func:`_control_lane`). The RK4
step's shadow-set switch is treated alike (:mod:`~ideas_hpc.core.attitude.camera_lanes`).
The bank's closed loop per scenario (720 candidates, 6,000 steps, one thread):
0.090 -> 0.081 s.
"""

from __future__ import annotations

from numba import njit

from ideas_hpc.core.attitude.mrp import mrp_rotate_s
from ideas_hpc.core.attitude.rigid_body import wheel_limit_s

#: Spacecraft flown side by side in :func:`fly_cameras_lanes_into`. One spacecraft's
#: step is a long chain of dependent operations; a loop over independent lanes lets
#: the compiler turn it into packed (SIMD) arithmetic, lane for lane the same
#: operations in the same order (no reassociation, no fused multiply-add: the same
#: bits). Measured on a 64-lane block (AVX-512 host): the RK4 step 3-6x and the
#: controller 3x faster packed than scalar; the bank's closed loop per scenario of
#: 720 candidates 0.41 s -> 0.12 s CPU, then 0.11 s with the image's camera DCM
#: packed too and 0.095 s with the settle test's atan only near its threshold.
#: (Before packing, 64 and 128 lanes were 2-3x faster than one spacecraft at a
#: time, 4 to 32 lanes 1.2-1.6x.)
LANES = 64

# Rows of the lanes' state ``S`` (flat, row ``r`` of lane ``l`` at ``r * LANES + l``):
# the offsets are compile-time constants and the trip count is LANES, so LLVM sees that
# the rows do not overlap and vectorises without run-time alias checks (with a 2-D
# array or separate arrays per quantity it did not: the stride is a run-time value).
_X = 0          # 9 rows: sigma_BN, omega_BN_B (rad/s), wheel speeds (rad/s)
_Z = 9          # 3: the MRP error integral
_U = 12         # 3: held wheel torques, N m
_D = 15         # 3: sigma_B/R at the step
_SR = 18        # 3: sigma_RT
_OR = 21        # 3: omega_RN_R, rad/s
_CB = 24        # 9: the camera misalignment [C B], row-major
_CT = 33        # 9: the camera DCM [C T] at the image, row-major
_RARE = 42      # 1: this step takes a rare side (1.0) or not (0.0)
_R = 43         # 3: position at the image, m, T (the smear test)
_V = 46         # 3: velocity relative to T at the image, m/s
_RATE = 49      # 1: the smear rate at the image, rad/s
_NROW = 50

# mrp_add_s, mrp_sub_s and mrp_switch_s with both sides of their branches computed and
# one selected: the same operations on the taken side, so the same bits, but a loop
# over lanes that calls them vectorises (with the branches LLVM left it scalar).

@njit(cache=True, error_model="numpy", inline="always")
def _switch_lane(a, b, c):
    """:func:`~ideas_hpc.core.attitude.mrp.mrp_switch_s`, branch-free."""
    ss = a * a + b * b + c * c
    sw = ss > 1.0
    return (-a / ss if sw else a), (-b / ss if sw else b), (-c / ss if sw else c)


@njit(cache=True, error_model="numpy", inline="always")
def _mrp_add_lane(a1, a2, a3, b1, b2, b3):
    """:func:`~ideas_hpc.core.attitude.mrp.mrp_add_s`, branch-free."""
    s1s = a1 * a1 + a2 * a2 + a3 * a3
    s2s = b1 * b1 + b2 * b2 + b3 * b3
    den = 1.0 + s1s * s2s - 2.0 * (a1 * b1 + a2 * b2 + a3 * b3)
    flip = abs(den) < 0.1
    f1 = -a1 / s1s
    f2 = -a2 / s1s
    f3 = -a3 / s1s
    fs = 1.0 / s1s
    fden = 1.0 + fs * s2s - 2.0 * (f1 * b1 + f2 * b2 + f3 * b3)
    a1 = f1 if flip else a1
    a2 = f2 if flip else a2
    a3 = f3 if flip else a3
    s1s = fs if flip else s1s
    den = fden if flip else den
    c1 = b2 * a3 - b3 * a2
    c2 = b3 * a1 - b1 * a3
    c3 = b1 * a2 - b2 * a1
    p = 1.0 - s1s
    q = 1.0 - s2s
    return _switch_lane((p * b1 + q * a1 - 2.0 * c1) / den, (p * b2 + q * a2 - 2.0 * c2) / den,
                        (p * b3 + q * a3 - 2.0 * c3) / den)


@njit(cache=True, error_model="numpy", inline="always")
def _mrp_sub_lane(a1, a2, a3, r1, r2, r3):
    """:func:`~ideas_hpc.core.attitude.mrp.mrp_sub_s`, branch-free."""
    srs = r1 * r1 + r2 * r2 + r3 * r3
    sbs = a1 * a1 + a2 * a2 + a3 * a3
    den = 1.0 + srs * sbs + 2.0 * (r1 * a1 + r2 * a2 + r3 * a3)
    flip = abs(den) < 0.1
    f1 = -r1 / srs
    f2 = -r2 / srs
    f3 = -r3 / srs
    fs = 1.0 / srs
    fden = 1.0 + fs * sbs + 2.0 * (f1 * a1 + f2 * a2 + f3 * a3)
    r1 = f1 if flip else r1
    r2 = f2 if flip else r2
    r3 = f3 if flip else r3
    srs = fs if flip else srs
    den = fden if flip else den
    c1 = a2 * r3 - a3 * r2
    c2 = a3 * r1 - a1 * r3
    c3 = a1 * r2 - a2 * r1
    p = 1.0 - srs
    q = 1.0 - sbs
    return _switch_lane((p * a1 - q * r1 + 2.0 * c1) / den, (p * a2 - q * r2 + 2.0 * c2) / den,
                        (p * a3 - q * r3 + 2.0 * c3) / den)


@njit(cache=True, error_model="numpy", inline="always")
def _mrp_add_common(a1, a2, a3, b1, b2, b3):
    """:func:`_mrp_add_lane` on its common side (no flip, no switch), and whether a
    rare side is taken instead: ``(x1, x2, x3, rare)``. Where ``rare`` is False the
    result is :func:`_mrp_add_lane`'s, bit for bit (the same operations)."""
    s1s = a1 * a1 + a2 * a2 + a3 * a3
    s2s = b1 * b1 + b2 * b2 + b3 * b3
    den = 1.0 + s1s * s2s - 2.0 * (a1 * b1 + a2 * b2 + a3 * b3)
    c1 = b2 * a3 - b3 * a2
    c2 = b3 * a1 - b1 * a3
    c3 = b1 * a2 - b2 * a1
    p = 1.0 - s1s
    q = 1.0 - s2s
    x1 = (p * b1 + q * a1 - 2.0 * c1) / den
    x2 = (p * b2 + q * a2 - 2.0 * c2) / den
    x3 = (p * b3 + q * a3 - 2.0 * c3) / den
    return x1, x2, x3, (abs(den) < 0.1) | (x1 * x1 + x2 * x2 + x3 * x3 > 1.0)


@njit(cache=True, error_model="numpy", inline="always")
def _mrp_sub_common(a1, a2, a3, r1, r2, r3):
    """:func:`_mrp_sub_lane` on its common side, as :func:`_mrp_add_common`."""
    srs = r1 * r1 + r2 * r2 + r3 * r3
    sbs = a1 * a1 + a2 * a2 + a3 * a3
    den = 1.0 + srs * sbs + 2.0 * (r1 * a1 + r2 * a2 + r3 * a3)
    c1 = a2 * r3 - a3 * r2
    c2 = a3 * r1 - a1 * r3
    c3 = a1 * r2 - a2 * r1
    p = 1.0 - srs
    q = 1.0 - sbs
    x1 = (p * a1 - q * r1 + 2.0 * c1) / den
    x2 = (p * a2 - q * r2 + 2.0 * c2) / den
    x3 = (p * a3 - q * r3 + 2.0 * c3) / den
    return x1, x2, x3, (abs(den) < 0.1) | (x1 * x1 + x2 * x2 + x3 * x3 > 1.0)



@njit(cache=True, error_model="numpy", inline="always")
def _params(gains, wheels):
    """The controller's and wheels' parameters as one tuple of scalars: loads from
    other arrays inside the lane loops would need alias checks against the stores
    into ``S``."""
    return (gains.k_p[0], gains.k_p[1], gains.k_p[2], gains.k_i[0], gains.k_i[1],
            gains.k_i[2], gains.eta[0], gains.eta[1], gains.eta[2], gains.phi[0],
            gains.phi[1], gains.phi[2], wheels.I_rw_kgm2[0], wheels.I_rw_kgm2[1],
            wheels.I_rw_kgm2[2], wheels.J_s_kgm2[0], wheels.J_s_kgm2[1], wheels.J_s_kgm2[2],
            wheels.u_max_Nm, wheels.h_max_Nms)


@njit(cache=True, error_model="numpy", inline="always")
def _sliding_mode(d1, d2, d3, w, W, z, om_R, P):
    """:func:`~ideas_hpc.core.attitude.control.sliding_mode_into` on scalars: the held
    wheel torques (N m) from the attitude error ``sigma_B/R = (d1, d2, d3)``, the rates
    ``w`` (rad/s), wheel speeds ``W`` (rad/s), error integral ``z`` and reference rate
    ``om_R`` (rad/s), all 3-tuples, and the parameters ``P`` (:func:`_params`).

    Scalars in and out: an array passed to an inlined function inside the lane loop
    brings reference counting into it, and LLVM no longer vectorises the loop."""
    (kp1, kp2, kp3, ki1, ki2, ki3, et1, et2, et3, ph1, ph2, ph3,
     I1, I2, I3, J1, J2, J3, u_max, h_max) = P
    w1, w2, w3 = w
    W1, W2, W3 = W
    r1, r2, r3 = mrp_rotate_s(d1, d2, d3, om_R[0], om_R[1], om_R[2])
    e1 = w1 - r1
    e2 = w2 - r2
    e3 = w3 - r3
    dd = d1 * d1 + d2 * d2 + d3 * d3
    de = d1 * e1 + d2 * e2 + d3 * e3
    q = 1.0 - dd
    sd1 = 0.25 * (q * e1 + 2.0 * (d2 * e3 - d3 * e2) + 2.0 * de * d1)
    sd2 = 0.25 * (q * e2 + 2.0 * (d3 * e1 - d1 * e3) + 2.0 * de * d2)
    sd3 = 0.25 * (q * e3 + 2.0 * (d1 * e2 - d2 * e1) + 2.0 * de * d3)
    sv1 = e1 + kp1 * d1 + ki1 * z[0]
    sv2 = e2 + kp2 * d2 + ki2 * z[1]
    sv3 = e3 + kp3 * d3 + ki3 * z[2]
    p1 = min(1.0, max(-1.0, ph1 * sv1))
    p2 = min(1.0, max(-1.0, ph2 * sv2))
    p3 = min(1.0, max(-1.0, ph3 * sv3))
    dwd1 = -kp1 * sd1 - ki1 * d1 - et1 * p1
    dwd2 = -kp2 * sd2 - ki2 * d2 - et2 * p2
    dwd3 = -kp3 * sd3 - ki3 * d3 - et3 * p3
    wd1 = dwd1 + 0.0 - (w2 * r3 - w3 * r2)
    wd2 = dwd2 + 0.0 - (w3 * r1 - w1 * r3)
    wd3 = dwd3 + 0.0 - (w1 * r2 - w2 * r1)
    h1 = I1 * w1 + J1 * (W1 + w1)
    h2 = I2 * w2 + J2 * (W2 + w2)
    h3 = I3 * w3 + J3 * (W3 + w3)
    return (wheel_limit_s(-I1 * wd1 - (w2 * h3 - w3 * h2) + 0.0, W1, J1, u_max, h_max),
            wheel_limit_s(-I2 * wd2 - (w3 * h1 - w1 * h3) + 0.0, W2, J2, u_max, h_max),
            wheel_limit_s(-I3 * wd3 - (w1 * h2 - w2 * h1) + 0.0, W3, J3, u_max, h_max))


@njit(cache=True, error_model="numpy")
def _control_lane(S, lane, tz, P):
    """The controller of one lane of ``S`` with both sides of every MRP branch."""
    B = LANES
    rr1, rr2, rr3 = _mrp_add_lane(0.0, 0.0, tz, S[_SR * B + lane], S[(_SR + 1) * B + lane],
                                  S[(_SR + 2) * B + lane])
    d1, d2, d3 = _mrp_sub_lane(S[_X * B + lane], S[(_X + 1) * B + lane],
                               S[(_X + 2) * B + lane], rr1, rr2, rr3)
    u1, u2, u3 = _sliding_mode(
        d1, d2, d3,
        (S[(_X + 3) * B + lane], S[(_X + 4) * B + lane], S[(_X + 5) * B + lane]),
        (S[(_X + 6) * B + lane], S[(_X + 7) * B + lane], S[(_X + 8) * B + lane]),
        (S[_Z * B + lane], S[(_Z + 1) * B + lane], S[(_Z + 2) * B + lane]),
        (S[_OR * B + lane], S[(_OR + 1) * B + lane], S[(_OR + 2) * B + lane]), P)
    S[_U * B + lane] = u1
    S[(_U + 1) * B + lane] = u2
    S[(_U + 2) * B + lane] = u3
    S[_D * B + lane] = d1
    S[(_D + 1) * B + lane] = d2
    S[(_D + 2) * B + lane] = d3


@njit(cache=True, error_model="numpy")
def _control_lanes(S, tz, gains, wheels):
    """The Nadir Pointing reference (``sigma_TN = tz z``) and
    :func:`~ideas_hpc.core.attitude.control.sliding_mode_into` of every lane of ``S``
    (no reference acceleration, no known torque): writes the held torques and
    ``sigma_B/R``. Common sides first, packed; then the lanes where a rare side is
    taken again with both sides (:func:`_control_lane`): the same bits on every lane."""
    B = LANES
    P = _params(gains, wheels)
    n_rare = 0
    for lane in range(B):
        rr1, rr2, rr3, rare_a = _mrp_add_common(0.0, 0.0, tz, S[_SR * B + lane],
                                                S[(_SR + 1) * B + lane],
                                                S[(_SR + 2) * B + lane])
        d1, d2, d3, rare_s = _mrp_sub_common(S[_X * B + lane], S[(_X + 1) * B + lane],
                                             S[(_X + 2) * B + lane], rr1, rr2, rr3)
        # the lines of _control_lane: passing S to an inlined function would not vectorise
        u1, u2, u3 = _sliding_mode(
            d1, d2, d3,
            (S[(_X + 3) * B + lane], S[(_X + 4) * B + lane], S[(_X + 5) * B + lane]),
            (S[(_X + 6) * B + lane], S[(_X + 7) * B + lane], S[(_X + 8) * B + lane]),
            (S[_Z * B + lane], S[(_Z + 1) * B + lane], S[(_Z + 2) * B + lane]),
            (S[_OR * B + lane], S[(_OR + 1) * B + lane], S[(_OR + 2) * B + lane]), P)
        S[_U * B + lane] = u1
        S[(_U + 1) * B + lane] = u2
        S[(_U + 2) * B + lane] = u3
        S[_D * B + lane] = d1
        S[(_D + 1) * B + lane] = d2
        S[(_D + 2) * B + lane] = d3
        rare = rare_a | rare_s
        S[_RARE * B + lane] = 1.0 if rare else 0.0
        n_rare += 1 if rare else 0
    if n_rare > 0:
        for lane in range(B):
            if S[_RARE * B + lane] != 0.0:
                _control_lane(S, lane, tz, P)
