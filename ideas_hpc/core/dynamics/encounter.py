"""Encounter geometry kernels: the swarm frame of a real approach, straight-line
reference tracks in the rotating body frame, and the pointing demand (SPEC section 7c).

Frames:

* ``N``: inertial frame that coincides with the body frame ``T`` at closest
  approach ``t_ca``; the body spins about ``+z`` at ``w``, so
  ``[T N](t) = R3(w (t - t_ca))`` (``r_T = [T N] r_N``).
* ``S``: swarm frame of the approach (paper eqs. 7-12 with ``v_SC`` along the
  asymptotic relative velocity): ``z_S = v_inf / |v_inf|``, ``x_S`` toward the
  ring point at swarm angle 0, ``y_S = z_S x x_S``. ``[N S]`` is the smallest
  rotation taking ``+z`` to ``z_S``, so a pole-aligned approach (declination
  90 deg) gives ``[N S] = I``, the paper's frame.
* ``R_i``: ring frames, ``[R_i S]`` as in :func:`ideas_hpc.core.dynamics.frames.dcm_RS`;
  fixed in ``N`` for a straight track.

Lengths in m, times in s, angles in rad.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True)
def dcm_NS(ra, dec):
    """Swarm frame ``[N S]`` (columns ``x_S, y_S, z_S`` in N) of an approach direction.

    ``z_S = (cos dec cos ra, cos dec sin ra, sin dec)`` is the direction of
    ``v_inf`` (right ascension ``ra`` and declination ``dec`` with respect to
    the pole ``+z_T`` at closest approach, rad). Rodrigues' formula with axis
    ``k = (-sin ra, cos ra, 0)`` and angle ``g = pi/2 - dec``:
    ``[N S] = cos g I + sin g [k x] + (1 - cos g) k k^T``.
    """
    g = 0.5 * np.pi - dec
    cg = np.cos(g)
    sg = np.sin(g)
    k = np.array([-np.sin(ra), np.cos(ra), 0.0])
    m = np.empty((3, 3))
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    for i in range(3):
        for j in range(3):
            m[i, j] = (1.0 - cg) * k[i] * k[j] + sg * kx[i, j]
        m[i, i] += cg
    return m


@njit(cache=True)
def _r3_apply(phi, x, y, z, out):
    """``out = R3(phi) (x, y, z)`` with ``R3 = [[c, s, 0], [-s, c, 0], [0, 0, 1]]``."""
    c = np.cos(phi)
    s = np.sin(phi)
    out[0] = c * x + s * y
    out[1] = -s * x + c * y
    out[2] = z


@njit(cache=True, parallel=True)
def straight_tracks_T(theta, dcm_NS_, d_sep, speed, t_ca, spin_rate, times):
    """Straight-line tracks through the ring points, in the rotating frame T.

    ``r_N(t) = d_sep (cos theta x_S + sin theta y_S) + speed (t - t_ca) z_S`` and
    ``r_T(t) = R3(spin_rate (t - t_ca)) r_N(t)`` (SPEC section 7c): the gravity-free
    encounter, and the start and aim points of the targeting.

    Parameters
    ----------
    theta : (N,) float64
        Swarm angles, rad.
    dcm_NS_ : (3, 3) float64
        Swarm frame (:func:`dcm_NS`).
    d_sep : float
        Closest-approach distance of the ring, m.
    speed : float
        ``|v_inf|``, m/s.
    t_ca : float
        Flyby time of closest approach, s.
    spin_rate : float
        Body spin rate about ``+z_T``, rad/s.
    times : (T,) float64
        s.

    Returns
    -------
    (N, T, 3) float64
        m, frame T.
    """
    n = theta.shape[0]
    m = times.shape[0]
    out = np.empty((n, m, 3))
    for i in prange(n):
        c = np.cos(theta[i]) * d_sep
        s = np.sin(theta[i]) * d_sep
        for k in range(m):
            tau = times[k] - t_ca
            x = c * dcm_NS_[0, 0] + s * dcm_NS_[0, 1] + speed * tau * dcm_NS_[0, 2]
            y = c * dcm_NS_[1, 0] + s * dcm_NS_[1, 1] + speed * tau * dcm_NS_[1, 2]
            z = c * dcm_NS_[2, 0] + s * dcm_NS_[2, 1] + speed * tau * dcm_NS_[2, 2]
            _r3_apply(spin_rate * tau, x, y, z, out[i, k])
    return out


@njit(cache=True, parallel=True)
def dcm_BT_from_BN(dcm_BN, spin_rate, times, t_ca):
    """``[B T](t) = [B N](t) [T N](t)^T`` with ``[T N] = R3(spin_rate (t - t_ca))``.

    Parameters
    ----------
    dcm_BN : (N, T, 3, 3) float64
    spin_rate : float
        rad/s.
    times : (T,) float64
        Flyby times of the rows, s.
    t_ca : float
        s.

    Returns
    -------
    (N, T, 3, 3) float64
    """
    n = dcm_BN.shape[0]
    m = dcm_BN.shape[1]
    out = np.empty_like(dcm_BN)
    for i in prange(n):
        for k in range(m):
            phi = spin_rate * (times[k] - t_ca)
            c = np.cos(phi)
            s = np.sin(phi)
            for r in range(3):
                b0 = dcm_BN[i, k, r, 0]
                b1 = dcm_BN[i, k, r, 1]
                out[i, k, r, 0] = b0 * c + b1 * s
                out[i, k, r, 1] = -b0 * s + b1 * c
                out[i, k, r, 2] = dcm_BN[i, k, r, 2]
    return out


@njit(cache=True)
def _omega_B(c0, c1, dt, out):
    """Body rate (B components, rad/s) that turns ``c0 = [B N](t)`` into ``c1 = [B N](t + dt)``.

    ``[B N]' = -[w x][B N]``, so the relative rotation ``c1 c0^T = exp(-[w x] dt)``;
    its principal rotation vector, divided by ``dt``, is ``w`` (exact for a
    constant rate over the step).
    """
    m = c1 @ c0.T
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    ca = min(1.0, max(-1.0, 0.5 * (tr - 1.0)))
    ang = np.arccos(ca)
    f = 0.5 if ang < 1e-8 else 0.5 * ang / np.sin(ang)
    # exp(-[w x] dt): the antisymmetric part is -sin(ang) [e x]
    out[0] = -f * (m[2, 1] - m[1, 2]) / dt
    out[1] = -f * (m[0, 2] - m[2, 0]) / dt
    out[2] = -f * (m[1, 0] - m[0, 1]) / dt


@njit(cache=True, parallel=True)
def pointing_demand(dcm_BN, dt, inertia):
    """What a pointing profile asks of the spacecraft: peak rate, torque and momentum.

    Rates between consecutive attitudes (:func:`_omega_B`, at mid-steps),
    accelerations by differences of those rates; the torque the wheels must
    supply is Euler's ``u = I w' + w x (I w)`` and the momentum they must absorb
    ``|I w|`` (starting from rest, no external torque).

    Parameters
    ----------
    dcm_BN : (N, T, 3, 3) float64
        Inertial attitudes at times ``k dt``.
    dt : float
        s.
    inertia : (3,) float64
        Principal moments about the B axes, kg m^2.

    Returns
    -------
    rate : (N,) float64
        Peak ``|w|``, rad/s.
    torque : (N,) float64
        Peak ``|u|``, N m.
    momentum : (N,) float64
        Peak ``|I w|``, N m s.
    """
    n = dcm_BN.shape[0]
    m = dcm_BN.shape[1]
    rate = np.zeros(n)
    torque = np.zeros(n)
    mom = np.zeros(n)
    for i in prange(n):
        w0 = np.zeros(3)
        w1 = np.zeros(3)
        for k in range(m - 1):
            _omega_B(dcm_BN[i, k], dcm_BN[i, k + 1], dt, w1)
            h = np.sqrt((inertia[0] * w1[0]) ** 2 + (inertia[1] * w1[1]) ** 2
                        + (inertia[2] * w1[2]) ** 2)
            rate[i] = max(rate[i], np.sqrt(w1[0] ** 2 + w1[1] ** 2 + w1[2] ** 2))
            mom[i] = max(mom[i], h)
            if k > 0:
                u = np.empty(3)
                for a in range(3):
                    u[a] = inertia[a] * (w1[a] - w0[a]) / dt
                wm = 0.5 * (w0 + w1)
                iw = inertia * wm
                u[0] += wm[1] * iw[2] - wm[2] * iw[1]
                u[1] += wm[2] * iw[0] - wm[0] * iw[2]
                u[2] += wm[0] * iw[1] - wm[1] * iw[0]
                torque[i] = max(torque[i], np.sqrt(u[0] ** 2 + u[1] ** 2 + u[2] ** 2))
            w0[:] = w1
    return rate, torque, mom


@njit(cache=True, parallel=True)
def track_dcm_BN(r_T, times, t_ca, spin_rate, z_S):
    """Body-tracking camera ``[B N]``: boresight on the body centre along the actual track.

    With ``r_N = R3(spin_rate (t - t_ca))^T r_T``: ``z_B = -r_N / |r_N|``,
    ``x_B = unit(z_S - (z_S . z_B) z_B)`` (along track, as the ring frame's
    ``x_R = z_S``), ``y_B = z_B x x_B``. At closest approach this is the ring
    frame of nadir pointing; for a straight track at speed ``v`` and distance
    ``d`` it turns about ``y_B`` at ``v d / (d^2 + v^2 tau^2)``.

    Parameters
    ----------
    r_T : (N, T, 3) float64
        Positions at ``times``, m, frame T.
    times : (T,) float64
        s.
    t_ca, spin_rate : float
        s, rad/s.
    z_S : (3,) float64
        Approach direction (unit), frame N.

    Returns
    -------
    (N, T, 3, 3) float64
        Rows ``x_B, y_B, z_B`` in N components.
    """
    n = r_T.shape[0]
    m = r_T.shape[1]
    out = np.empty((n, m, 3, 3))
    for i in prange(n):
        for k in range(m):
            phi = spin_rate * (times[k] - t_ca)
            c = np.cos(phi)
            s = np.sin(phi)
            x = c * r_T[i, k, 0] - s * r_T[i, k, 1]
            y = s * r_T[i, k, 0] + c * r_T[i, k, 1]
            z = r_T[i, k, 2]
            rn = np.sqrt(x * x + y * y + z * z)
            # scalars, not 3-arrays: the same operations, and no array expressions for
            # the parallel lowering to compile (issue 43: 7.4 s to compile before)
            zb0 = -x / rn
            zb1 = -y / rn
            zb2 = -z / rn
            d = z_S[0] * zb0 + z_S[1] * zb1 + z_S[2] * zb2
            xb0 = z_S[0] - d * zb0
            xb1 = z_S[1] - d * zb1
            xb2 = z_S[2] - d * zb2
            nb = np.sqrt(xb0 ** 2 + xb1 ** 2 + xb2 ** 2)
            xb0 /= nb
            xb1 /= nb
            xb2 /= nb
            out[i, k, 0, 0] = xb0
            out[i, k, 0, 1] = xb1
            out[i, k, 0, 2] = xb2
            out[i, k, 1, 0] = zb1 * xb2 - zb2 * xb1
            out[i, k, 1, 1] = zb2 * xb0 - zb0 * xb2
            out[i, k, 1, 2] = zb0 * xb1 - zb1 * xb0
            out[i, k, 2, 0] = zb0
            out[i, k, 2, 1] = zb1
            out[i, k, 2, 2] = zb2
    return out
