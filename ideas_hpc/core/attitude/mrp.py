"""Modified Rodrigues parameter (MRP) kernels.

Conventions follow Schaub & Junkins, *Analytical Mechanics of Space Systems*
(4th ed., 2018), section 3.7 (cited below as S&J):

* ``sigma_BN`` is the MRP set of frame B relative to frame N;
  ``dcm_from_mrp(sigma_BN)`` returns ``[BN]``, which maps N components to B
  components: ``v_B = [BN] v_N``.
* MRPs are dimensionless; principal angles are in rad.
* A set with ``|sigma| > 1`` can be replaced by its shadow set
  ``-sigma / |sigma|^2``; both give the same DCM.

All functions are ``@njit(cache=True)`` and take contiguous float64 arrays,
except the scalar forms ``*_s`` (:func:`mrp_switch_s`, :func:`mrp_add_s`,
:func:`mrp_sub_s`, :func:`mrp_rotate_s`), which take and return 3-tuples of
floats: hot loops (attitude references, the controller) call them millions of
times without allocating. The array forms :func:`mrp_add` and :func:`mrp_sub`
are built on them, so each formula is written once.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def skew(v):
    """Cross-product matrix ``[v x]`` so that ``skew(a) @ b == cross(a, b)``."""
    m = np.zeros((3, 3))
    m[0, 1] = -v[2]
    m[0, 2] = v[1]
    m[1, 0] = v[2]
    m[1, 2] = -v[0]
    m[2, 0] = -v[1]
    m[2, 1] = v[0]
    return m


@njit(cache=True)
def cross3(a, b):
    """Cross product of two 3-vectors (allocation-light helper for kernels)."""
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit(cache=True)
def mrp_shadow(sigma):
    """Shadow set ``-sigma / |sigma|^2`` (S&J eq. 3.150). Same attitude, other branch."""
    s2 = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2]
    return -sigma / s2


@njit(cache=True)
def mrp_switch(sigma):
    """Return the short-rotation set: the shadow set when ``|sigma| > 1``, else a copy."""
    s2 = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2]
    if s2 > 1.0:
        return -sigma / s2
    return sigma.copy()


@njit(cache=True)
def dcm_from_mrp(sigma):
    """DCM ``[BN]`` from ``sigma_BN`` (S&J eq. 3.153).

    ``C = I + (8 [s x]^2 - 4 (1 - s^2) [s x]) / (1 + s^2)^2``
    """
    s2 = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2]
    sx = skew(sigma)
    sx2 = sx @ sx
    den = (1.0 + s2) * (1.0 + s2)
    c = np.eye(3) + (8.0 * sx2 - 4.0 * (1.0 - s2) * sx) / den
    return c


@njit(cache=True)
def quat_from_dcm(c):
    """Unit quaternion ``(q0, q1, q2, q3)`` (scalar first, q0 >= 0) from a DCM.

    Sheppard's method (S&J section 3.5.3): pick the largest of the four squared
    components to avoid dividing by a small number.
    """
    tr = c[0, 0] + c[1, 1] + c[2, 2]
    b2 = np.empty(4)
    b2[0] = 0.25 * (1.0 + tr)
    b2[1] = 0.25 * (1.0 + 2.0 * c[0, 0] - tr)
    b2[2] = 0.25 * (1.0 + 2.0 * c[1, 1] - tr)
    b2[3] = 0.25 * (1.0 + 2.0 * c[2, 2] - tr)
    i = np.argmax(b2)
    q = np.empty(4)
    if i == 0:
        q[0] = np.sqrt(b2[0])
        q[1] = (c[1, 2] - c[2, 1]) / (4.0 * q[0])
        q[2] = (c[2, 0] - c[0, 2]) / (4.0 * q[0])
        q[3] = (c[0, 1] - c[1, 0]) / (4.0 * q[0])
    elif i == 1:
        q[1] = np.sqrt(b2[1])
        q[0] = (c[1, 2] - c[2, 1]) / (4.0 * q[1])
        q[2] = (c[0, 1] + c[1, 0]) / (4.0 * q[1])
        q[3] = (c[2, 0] + c[0, 2]) / (4.0 * q[1])
    elif i == 2:
        q[2] = np.sqrt(b2[2])
        q[0] = (c[2, 0] - c[0, 2]) / (4.0 * q[2])
        q[1] = (c[0, 1] + c[1, 0]) / (4.0 * q[2])
        q[3] = (c[1, 2] + c[2, 1]) / (4.0 * q[2])
    else:
        q[3] = np.sqrt(b2[3])
        q[0] = (c[0, 1] - c[1, 0]) / (4.0 * q[3])
        q[1] = (c[2, 0] + c[0, 2]) / (4.0 * q[3])
        q[2] = (c[1, 2] + c[2, 1]) / (4.0 * q[3])
    if q[0] < 0.0:
        q = -q
    return q / np.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


@njit(cache=True)
def mrp_from_quat(q):
    """MRP from a unit quaternion (scalar first): ``sigma = q_v / (1 + q0)`` (S&J eq. 3.145).

    The quaternion is first flipped to ``q0 >= 0`` so the result has ``|sigma| <= 1``.
    """
    if q[0] < 0.0:
        return -q[1:4] / (1.0 - q[0])
    return q[1:4] / (1.0 + q[0])


@njit(cache=True)
def quat_from_mrp(sigma):
    """Unit quaternion (scalar first) from an MRP (S&J eq. 3.146).

    ``q0 = (1 - s^2) / (1 + s^2)``, ``q_v = 2 sigma / (1 + s^2)``.
    """
    s2 = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2]
    q = np.empty(4)
    q[0] = (1.0 - s2) / (1.0 + s2)
    q[1:4] = 2.0 * sigma / (1.0 + s2)
    return q


@njit(cache=True)
def mrp_from_dcm(c):
    """``sigma_BN`` (short set, ``|sigma| <= 1``) from the DCM ``[BN]``, via the quaternion."""
    return mrp_from_quat(quat_from_dcm(c))


@njit(cache=True)
def mrp_from_prv(prv):
    """MRP from the principal rotation vector ``phi * e`` (rad): ``tan(phi / 4) e`` (S&J eq. 3.139)."""
    phi = np.sqrt(prv[0] * prv[0] + prv[1] * prv[1] + prv[2] * prv[2])
    if phi < 1e-300:
        return np.zeros(3)
    return np.tan(0.25 * phi) * prv / phi


@njit(cache=True)
def prv_from_mrp(sigma):
    """Principal rotation vector ``phi * e`` (rad), ``phi = 4 atan |sigma|``.

    The input is taken as given (no shadow switch), so a set with
    ``|sigma| > 1`` returns ``phi > pi``.
    """
    s = np.sqrt(sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2])
    if s < 1e-300:
        return np.zeros(3)
    return 4.0 * np.arctan(s) * sigma / s


@njit(cache=True, error_model="numpy")
def mrp_switch_s(a, b, c):
    """Scalar :func:`mrp_switch`: the short set of ``(a, b, c)`` as a 3-tuple."""
    ss = a * a + b * b + c * c
    if ss > 1.0:
        return -a / ss, -b / ss, -c / ss
    return a, b, c


@njit(cache=True, error_model="numpy")
def mrp_add_s(a1, a2, a3, b1, b2, b3):
    """Scalar :func:`mrp_add`: ``sigma1 = sigma_BN``, ``sigma2 = sigma_FB`` -> ``sigma_FN``
    (S&J 3.160), short set returned as a 3-tuple."""
    s1s = a1 * a1 + a2 * a2 + a3 * a3
    s2s = b1 * b1 + b2 * b2 + b3 * b3
    den = 1.0 + s1s * s2s - 2.0 * (a1 * b1 + a2 * b2 + a3 * b3)
    if abs(den) < 0.1:
        a1 = -a1 / s1s
        a2 = -a2 / s1s
        a3 = -a3 / s1s
        s1s = 1.0 / s1s
        den = 1.0 + s1s * s2s - 2.0 * (a1 * b1 + a2 * b2 + a3 * b3)
    # num = (1 - |s1|^2) s2 + (1 - |s2|^2) s1 - 2 s2 x s1
    c1 = b2 * a3 - b3 * a2
    c2 = b3 * a1 - b1 * a3
    c3 = b1 * a2 - b2 * a1
    p = 1.0 - s1s
    q = 1.0 - s2s
    return mrp_switch_s((p * b1 + q * a1 - 2.0 * c1) / den,
                   (p * b2 + q * a2 - 2.0 * c2) / den,
                   (p * b3 + q * a3 - 2.0 * c3) / den)


@njit(cache=True, error_model="numpy")
def mrp_sub_s(a1, a2, a3, r1, r2, r3):
    """Scalar :func:`mrp_sub`: ``sigma_BN``, ``sigma_RN`` -> ``sigma_BR`` (S&J 3.161)."""
    srs = r1 * r1 + r2 * r2 + r3 * r3
    sbs = a1 * a1 + a2 * a2 + a3 * a3
    den = 1.0 + srs * sbs + 2.0 * (r1 * a1 + r2 * a2 + r3 * a3)
    if abs(den) < 0.1:
        r1 = -r1 / srs
        r2 = -r2 / srs
        r3 = -r3 / srs
        srs = 1.0 / srs
        den = 1.0 + srs * sbs + 2.0 * (r1 * a1 + r2 * a2 + r3 * a3)
    # num = (1 - |sR|^2) sB - (1 - |sB|^2) sR + 2 sB x sR
    c1 = a2 * r3 - a3 * r2
    c2 = a3 * r1 - a1 * r3
    c3 = a1 * r2 - a2 * r1
    p = 1.0 - srs
    q = 1.0 - sbs
    return mrp_switch_s((p * a1 - q * r1 + 2.0 * c1) / den,
                   (p * a2 - q * r2 + 2.0 * c2) / den,
                   (p * a3 - q * r3 + 2.0 * c3) / den)


@njit(cache=True, error_model="numpy")
def mrp_rotate_s(s1, s2, s3, v1, v2, v3):
    """``dcm_from_mrp(sigma) @ v`` without forming the matrix (S&J 3.153).

    ::

        C v = v + (8 s x (s x v) - 4 (1 - s^2) s x v) / (1 + s^2)^2
    """
    ss = s1 * s1 + s2 * s2 + s3 * s3
    a1 = s2 * v3 - s3 * v2
    a2 = s3 * v1 - s1 * v3
    a3 = s1 * v2 - s2 * v1
    b1 = s2 * a3 - s3 * a2
    b2 = s3 * a1 - s1 * a3
    b3 = s1 * a2 - s2 * a1
    d = 1.0 / ((1.0 + ss) * (1.0 + ss))
    k = 4.0 * (1.0 - ss)
    return (v1 + (8.0 * b1 - k * a1) * d,
            v2 + (8.0 * b2 - k * a2) * d,
            v3 + (8.0 * b3 - k * a3) * d)


@njit(cache=True)
def _vec(a, b, c):
    out = np.empty(3)
    out[0] = a
    out[1] = b
    out[2] = c
    return out


@njit(cache=True)
def mrp_add(sigma1, sigma2):
    """Compose two rotations: ``sigma1 = sigma_BN``, ``sigma2 = sigma_FB`` -> ``sigma_FN``.

    In DCM terms ``[FN] = [FB][BN]``, i.e.
    ``dcm_from_mrp(mrp_add(s1, s2)) == dcm_from_mrp(s2) @ dcm_from_mrp(s1)``
    (S&J eq. 3.160)::

        sigma = ((1 - |s1|^2) s2 + (1 - |s2|^2) s1 - 2 s2 x s1)
                / (1 + |s1|^2 |s2|^2 - 2 s1 . s2)

    The denominator vanishes when the composed rotation is 360 deg; then
    ``sigma1`` is replaced by its shadow set (same attitude), which moves the
    result to the other branch. The result is switched to ``|sigma| <= 1``.
    """
    a, b, c = mrp_add_s(sigma1[0], sigma1[1], sigma1[2], sigma2[0], sigma2[1], sigma2[2])
    return _vec(a, b, c)


@njit(cache=True)
def mrp_sub(sigma, sigma1):
    """Relative attitude: ``sigma = sigma_BN``, ``sigma1 = sigma_RN`` -> ``sigma_BR``.

    Inverse of :func:`mrp_add`: ``mrp_add(sigma1, mrp_sub(sigma, sigma1))``
    gives ``sigma`` (up to the shadow set), and ``[BR] = [BN][RN]^T``
    (S&J eq. 3.161)::

        sigma_BR = ((1 - |s_R|^2) s_B - (1 - |s_B|^2) s_R + 2 s_B x s_R)
                   / (1 + |s_R|^2 |s_B|^2 + 2 s_R . s_B)

    Near-zero denominators are handled with the shadow set of ``sigma1``;
    the result has ``|sigma| <= 1``.
    """
    a, b, c = mrp_sub_s(sigma[0], sigma[1], sigma[2], sigma1[0], sigma1[1], sigma1[2])
    return _vec(a, b, c)


@njit(cache=True)
def mrp_bmat(sigma):
    """MRP kinematics matrix ``B(sigma)`` (S&J eq. 3.159; paper eq. 19).

    ``sigma' = 1/4 B(sigma) omega`` with ``omega = omega_BN_B`` in rad/s and
    ``B = (1 - s^2) I + 2 [s x] + 2 s s^T``.
    """
    s2 = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2]
    b = (1.0 - s2) * np.eye(3) + 2.0 * skew(sigma) + 2.0 * np.outer(sigma, sigma)
    return b


@njit(cache=True)
def mrp_rate(sigma, omega):
    """``sigma' = 1/4 B(sigma) omega`` (1/s) for ``omega = omega_BN_B`` in rad/s."""
    return 0.25 * (mrp_bmat(sigma) @ omega)
