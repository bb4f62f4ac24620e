"""Smear: the motion of the scene's image on the detector during an exposure (SPEC 7d).

The camera frame C is fixed in the spacecraft body B (misaligned by ``[C B]``),
boresight ``+z_C``. The target's body-fixed frame T turns in N at
``omega_TN = w_s z_T``; the spacecraft moves relative to T at ``v`` (m/s, the
velocity the propagator in T gives, ``d r / dt`` seen in T).

Derivation. Let P be a point fixed in T at range ``rho`` along the unit line of
sight ``u`` from the camera (``r_P - r = rho u``). Seen in T, P is still and the
camera moves at ``v``, so ``d(rho u)/dt|_T = -v`` and the line of sight turns
relative to T at ``omega_LOS/T = u x (du/dt|_T) = -u x v / rho`` (the part of
``v`` along ``u`` only changes ``rho``). In N it turns at
``omega_LOS = omega_TN - u x v / rho``: the same as SPEC 7d's
``(u x v_rel) / rho`` with ``v_rel = omega_TN x r_P - (v + omega_TN x r)`` the
point's inertial velocity relative to the camera, up to a component along
``u``, which turns the image about P without moving P. The image of P moves on
the detector at the camera's rate relative to that line of sight::

    omega_img = omega_CN - omega_LOS = (omega_CN - omega_TN) + u x v / rho,

and P is smeared by the part across the line of sight, ``|omega_img x u| t_exp``.
At the footprint centre ``u = z_C``; in C components, with ``z_C x v =
(-v_y, v_x, 0)``::

    |omega_img x z_C| = sqrt((w_x - wT_x - v_y / rho)^2 + (w_y - wT_y + v_x / rho)^2),

``w = [C B] omega_BN_B`` (the camera is fixed in B: ``omega_CN = omega_BN``),
``wT = [C T] (0, 0, w_s)``, ``v_C = [C T] v_T``. Two limits check it: a camera
fixed in N (``omega_CN = 0``) over a still body (``w_s = 0``) sees the scene
move at ``|v_perp| / rho``; a camera that turns with the line of sight to P
(``omega_CN = omega_LOS`` across it) sees P still.

Approximation (stated, SPEC 7d): smear is evaluated at the footprint centre only
(a point off the boresight also moves by the roll about it and by its own
range), and P is where the boresight meets a sphere of radius ``R`` about the
body centre: the body's volume-equivalent mean radius
(:func:`ideas_hpc.flyby.usable.scene_radius_m`). ``rho`` is the nearer
intersection in front of the camera; from inside the sphere, the one in front;
when the boresight misses the sphere (or it lies behind), ``rho`` is the range
of the sphere's limb, ``sqrt(|r|^2 - R^2)``, which equals the hit range at
grazing incidence, so ``rho`` is continuous where the boresight leaves the
sphere (:func:`scene_inverse_range_s`).

Every closed loop that tests its images calls :func:`smear_rate_s` with the same
operands (the one-pass kernels at the images, :func:`smear_rates` for the
batched loop's recorded rates), so the flags are the same bits on every variant.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.attitude.compose import dot3_fma


@njit(cache=True, error_model="numpy", inline="always")
def scene_inverse_range_s(r0, r1, r2, u0, u1, u2, radius):
    """``1 / rho`` (1/m): ``rho`` the range from the camera at ``r`` (m, T) along the unit
    boresight ``u`` to the imaged point on the sphere of ``radius`` (m) about the body
    centre (module docstring).

    With ``b = u . r`` and ``q = |r|^2 - R^2`` the ranges solve ``s^2 + 2 b s + q = 0``:
    inside the sphere (``q <= 0``) the root in front, ``rho = -b + sqrt(b^2 - q)``;
    outside with the sphere ahead (``b < 0``, ``b^2 >= q``) the nearer root,
    ``rho = q / (-b + sqrt(b^2 - q))`` (no cancellation), so ``1 / rho = (-b + sqrt(b^2
    - q)) / q``; otherwise the limb's range ``rho = sqrt(q)``. One square root and one
    division, selected without a branch, so that a loop over spacecraft side by side
    vectorises (:func:`~ideas_hpc.core.attitude.camera_lanes.fly_cameras_lanes_into`)."""
    b = u0 * r0 + u1 * r1 + u2 * r2
    q = r0 * r0 + r1 * r1 + r2 * r2 - radius * radius
    disc = b * b - q
    inside = q <= 0.0
    ahead = (b < 0.0) & (disc >= 0.0) & (q > 0.0)
    s = np.sqrt(disc if ahead | inside else q)
    far = -b + s
    num = far if ahead else 1.0
    den = q if ahead else (far if inside else s)
    return num / den


@njit(cache=True, error_model="numpy", inline="always")
def camera_rate_xy_s(w0, w1, w2, m00, m01, m02, m10, m11, m12, misaligned):
    """``(w_x, w_y)``: the first two C components of ``omega_CN = [C B] omega_BN_B``
    (rad/s) from ``omega_BN_B = (w0, w1, w2)`` and the first two rows of ``[C B]``
    (:func:`~ideas_hpc.core.attitude.compose.dot3_fma`, as the camera DCMs are
    composed); without misalignment C = B and the rows are not read."""
    if not misaligned:
        return w0, w1
    return dot3_fma(m00, m01, m02, w0, w1, w2), dot3_fma(m10, m11, m12, w0, w1, w2)


@njit(cache=True, error_model="numpy", inline="always")
def camera_rate_xy(w0, w1, w2, dcm_CB, i):
    """:func:`camera_rate_xy_s` with the misalignment ``dcm_CB[i]`` of an (N, 3, 3) array
    (``(0, 3, 3)``: none)."""
    if dcm_CB.shape[0] == 0:
        return w0, w1
    return camera_rate_xy_s(w0, w1, w2, dcm_CB[i, 0, 0], dcm_CB[i, 0, 1], dcm_CB[i, 0, 2],
                            dcm_CB[i, 1, 0], dcm_CB[i, 1, 1], dcm_CB[i, 1, 2], True)


@njit(cache=True, error_model="numpy", inline="always")
def smear_rate_s(wx, wy, ct, r, v, spin, radius):
    """The footprint centre's image rate across the line of sight, rad/s (module docstring).

    Parameters
    ----------
    wx, wy : float
        ``omega_CN`` in C, its x and y components, rad/s (:func:`camera_rate_xy_s`).
    ct : 9-tuple of float
        ``[C T]`` row by row (rows: the camera axes in T; row 3 the boresight).
    r, v : 3-tuples of float
        The spacecraft's position (m) and velocity relative to T (m/s), T components.
    spin : float
        ``w_s``, rad/s: ``omega_TN = w_s z_T``.
    radius : float
        The sphere the footprint centre lies on, m (:func:`scene_inverse_range_s`).
    """
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = ct
    inv = scene_inverse_range_s(r[0], r[1], r[2], c20, c21, c22, radius)
    vx = c00 * v[0] + c01 * v[1] + c02 * v[2]
    vy = c10 * v[0] + c11 * v[1] + c12 * v[2]
    ox = wx - c02 * spin - vy * inv
    oy = wy - c12 * spin + vx * inv
    return np.sqrt(ox * ox + oy * oy)


@njit(cache=True, error_model="numpy", inline="always")
def image_smear_rate(w0, w1, w2, dcm_CB, dcm_CT, r_T, v_T, i, n, spin, radius):
    """:func:`smear_rate_s` of spacecraft ``i`` at image ``n`` with ``omega_BN_B = (w0, w1,
    w2)``, the camera ``dcm_CT[i, n]`` and the state ``r_T[i, n]``, ``v_T[i, n]``
    (arrays as :func:`smear_rates`)."""
    wx, wy = camera_rate_xy(w0, w1, w2, dcm_CB, i)
    c = dcm_CT[i, n]
    return smear_rate_s(wx, wy, (c[0, 0], c[0, 1], c[0, 2], c[1, 0], c[1, 1], c[1, 2],
                                 c[2, 0], c[2, 1], c[2, 2]),
                        (r_T[i, n, 0], r_T[i, n, 1], r_T[i, n, 2]),
                        (v_T[i, n, 0], v_T[i, n, 1], v_T[i, n, 2]), spin, radius)


@njit(cache=True, parallel=True, error_model="numpy")
def smear_rates(omega_BN_B, dcm_CB, dcm_CT, r_T, v_T, spin, radius):
    """:func:`smear_rate_s` at every image of ``N`` spacecraft: (N, n_img) rad/s.

    Parameters
    ----------
    omega_BN_B : (N, n_img, 3) float64
        The body's inertial rate at the images, B components, rad/s.
    dcm_CB : (N, 3, 3) float64
        Camera misalignments ``[C B]``; ``(0, 3, 3)``: none (C = B).
    dcm_CT : (N, n_img, 3, 3) float64
        The cameras ``[C T]`` at the images.
    r_T, v_T : (N, n_img, 3) float64
        Positions (m) and velocities relative to T (m/s) at the images.
    spin, radius : float
        ``w_s`` (rad/s) and the footprint sphere's radius (m).
    """
    n = dcm_CT.shape[0]
    k = dcm_CT.shape[1]
    out = np.empty((n, k))
    for job in prange(n * k):
        i = job // k
        j = job % k
        out[i, j] = image_smear_rate(omega_BN_B[i, j, 0], omega_BN_B[i, j, 1],
                                     omega_BN_B[i, j, 2], dcm_CB, dcm_CT, r_T, v_T, i, j, spin,
                                     radius)
    return out
