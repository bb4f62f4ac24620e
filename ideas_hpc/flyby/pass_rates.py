"""Line-of-sight kinematics of a fast straight pass, and whether the wheels can follow it (SPEC 7f).

At 10 km/s the body's gravity bends the track by ~1e-7 rad (SPEC 7c), so the pass
is the straight line ``p(t) = b + v t S`` relative to the target, ``|b| = d`` the
closest-approach distance, ``t`` from closest approach (TCA). The line of sight
turns in the fixed plane of ``b`` and ``S`` by the angle ``theta(t) = atan(v t / d)``::

    omega(t) = d theta / dt = v d / (d^2 + v^2 t^2),                  peak v / d at t = 0,
    alpha(t) = d omega / dt = -2 v^3 d t / (d^2 + v^2 t^2)^2,

and ``|alpha|`` peaks where ``d/dt [t / (d^2 + v^2 t^2)^2] = 0``, i.e. ``d^2 = 3 v^2 t^2``:
at ``t = +-d / (sqrt(3) v)``::

    alpha_max = 2 v^3 d (d / (sqrt 3 v)) / (4 d^2 / 3)^2 = (3 sqrt(3) / 8) v^2 / d^2 .

Following it with a camera fixed in the body means turning the spacecraft about the
fixed normal of that plane, perpendicular to the boresight (+z_B): the wheels then
hold ``h = I omega`` and deliver ``u = I alpha`` with ``I`` the spacecraft's inertia
about that axis (hub plus the transverse inertia of the other wheels,
:attr:`~ideas_hpc.attitude.spacecraft.SpacecraftModel.inertia_rw`; no gyroscopic term for
a turn about a principal axis). The camera can follow while ``I |alpha(t)| <= u_max``
and ``I omega(t) <= h_max``; outside, the wheels saturate and the images are lost
(:func:`follow_check` gives the windows). The worst axis in the x-y plane of B is used.

Pointing at a body you cannot see precisely: tracking the *predicted* target position
carries the ephemeris error ``delta`` as a bias, the angle between the lines of sight to
the predicted and the true target, ``~ |delta_perp| / rho`` (10 km at 100 km: 5.7 deg),
growing toward closest approach. Terminal tracking (:class:`TerminalTracking`) follows
the measured centroid once the body spans ``detect_pixels`` pixels, i.e. from the range
``D / (detect_pixels IFOV)``, with a residual ``centroid_sigma_rad``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.attitude.spacecraft import SpacecraftModel, default_spacecraft
from ideas_hpc.base.fields import number

#: ``alpha_max = ALPHA_PEAK v^2 / d^2``.
ALPHA_PEAK = 3.0 * math.sqrt(3.0) / 8.0


def _vd(v_m_s, d_m) -> tuple[float, float]:
    return (number(v_m_s, "v_m_s", lo=0.0, lo_open=True),
            number(d_m, "d_m", lo=0.0, lo_open=True))


def los_angle_rad(t_s, v_m_s: float, d_m: float):
    """``theta(t) = atan(v t / d)``, rad (0 at TCA)."""
    v, d = _vd(v_m_s, d_m)
    return np.arctan2(v * np.asarray(t_s, dtype=np.float64), d)


def los_rate_rad_s(t_s, v_m_s: float, d_m: float):
    """``omega(t) = v d / (d^2 + v^2 t^2)``, rad/s."""
    v, d = _vd(v_m_s, d_m)
    t = np.asarray(t_s, dtype=np.float64)
    return v * d / (d * d + v * v * t * t)


def los_acceleration_rad_s2(t_s, v_m_s: float, d_m: float):
    """``alpha(t) = -2 v^3 d t / (d^2 + v^2 t^2)^2``, rad/s^2."""
    v, d = _vd(v_m_s, d_m)
    t = np.asarray(t_s, dtype=np.float64)
    return -2.0 * v ** 3 * d * t / (d * d + v * v * t * t) ** 2


def peak_los_rate_rad_s(v_m_s: float, d_m: float) -> float:
    """``v / d``, rad/s (at TCA)."""
    v, d = _vd(v_m_s, d_m)
    return v / d


def peak_los_acceleration_rad_s2(v_m_s: float, d_m: float) -> float:
    """``(3 sqrt 3 / 8) v^2 / d^2``, rad/s^2, at ``t = +-d / (sqrt 3 v)``."""
    v, d = _vd(v_m_s, d_m)
    return ALPHA_PEAK * v * v / (d * d)


def pointing_bias_rad(los_pred_m, delta_m) -> np.ndarray:
    """Angle between the line of sight to the predicted target ``los_pred_m`` (``(..., 3)``, m)
    and to the true one, ``los_pred_m + delta_m``, rad (exact; ``~ |delta_perp| / rho``)."""
    a = np.asarray(los_pred_m, dtype=np.float64)
    b = a + np.asarray(delta_m, dtype=np.float64)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.arctan2(cross, np.einsum("...i,...i->...", a, b))


def pointing_bias_small_rad(delta_perp_m: float, rho_m: float) -> float:
    """The small-angle form ``|delta_perp| / rho``, rad."""
    return abs(float(delta_perp_m)) / number(rho_m, "rho_m", lo=0.0, lo_open=True)


@dataclass(frozen=True)
class TerminalTracking:
    """Pointing at the measured centroid once the body is resolved (module docstring).

    Attributes
    ----------
    detect_pixels : float
        Apparent size (pixels) at which tracking locks on the centroid.
    centroid_sigma_rad : float
        1-sigma residual of the centroid pointing, rad.
    """

    detect_pixels: float = 5.0
    centroid_sigma_rad: float = 0.0

    def __post_init__(self):
        number(self.detect_pixels, "detect_pixels", lo=0.0, lo_open=True)
        number(self.centroid_sigma_rad, "centroid_sigma_rad", lo=0.0)

    def detection_range_m(self, diameter_m: float, ifov_rad: float) -> float:
        """Range (m) at which a body of ``diameter_m`` spans ``detect_pixels`` pixels of
        ``ifov_rad``."""
        return (number(diameter_m, "diameter_m", lo=0.0, lo_open=True)
                / (self.detect_pixels * number(ifov_rad, "ifov_rad", lo=0.0, lo_open=True)))

    def pointing_error_rad(self, rho_m, bias_rad, diameter_m: float, ifov_rad: float):
        """The pointing error at ranges ``rho_m``: the ephemeris bias ``bias_rad`` beyond the
        detection range, ``centroid_sigma_rad`` within it."""
        rho = np.asarray(rho_m, dtype=np.float64)
        locked = rho <= self.detection_range_m(diameter_m, ifov_rad)
        return np.where(locked, self.centroid_sigma_rad, np.asarray(bias_rad, dtype=np.float64))


@dataclass(frozen=True)
class FollowCheck:
    """Can the wheels follow the line of sight of a straight pass? (:func:`follow_check`)

    Attributes
    ----------
    inertia_kg_m2 : float
        Inertia about the turn axis used.
    omega_max_rad_s, alpha_max_rad_s2 : float
        Peak line-of-sight rate and angular acceleration.
    momentum_peak_N_m_s, torque_peak_N_m : float
        ``I omega_max`` and ``I alpha_max``.
    momentum_ok, torque_ok : bool
        Peaks within ``h_max`` and ``u_max``.
    momentum_window_s : tuple
        ``(t0, t1)`` about TCA where ``I omega > h_max``, or ``()``.
    torque_windows_s : tuple
        The two ``(t0, t1)`` windows where ``I |alpha| > u_max`` (before and after TCA), or ``()``.
    """

    inertia_kg_m2: float
    omega_max_rad_s: float
    alpha_max_rad_s2: float
    momentum_peak_N_m_s: float
    torque_peak_N_m: float
    momentum_ok: bool
    torque_ok: bool
    momentum_window_s: tuple
    torque_windows_s: tuple

    @property
    def feasible(self) -> bool:
        return self.momentum_ok and self.torque_ok

    @property
    def lost_windows_s(self) -> tuple:
        """Union of the windows where the camera cannot follow, sorted, merged."""
        spans = sorted(list(self.torque_windows_s)
                       + ([self.momentum_window_s] if self.momentum_window_s else []))
        out: list[list[float]] = []
        for a, b in spans:
            if out and a <= out[-1][1]:
                out[-1][1] = max(out[-1][1], b)
            else:
                out.append([a, b])
        return tuple((a, b) for a, b in out)


def _bisect(f, lo: float, hi: float) -> float:
    """Root of ``f`` on ``[lo, hi]`` where it changes sign (to machine precision)."""
    flo = f(lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        fm = f(mid)
        if (fm > 0.0) == (flo > 0.0):
            lo, flo = mid, fm
        else:
            hi = mid
    return 0.5 * (lo + hi)


def follow_check(v_m_s: float, d_m: float, spacecraft: SpacecraftModel | None = None, *,
                 inertia_kg_m2: float | None = None) -> FollowCheck:
    """Whether a body-fixed camera can follow a straight pass at ``v_m_s`` and ``d_m``.

    ``inertia_kg_m2`` overrides the spacecraft's (default: the larger transverse moment
    of ``inertia_rw`` of the paper's 4 kg 30 x 10 x 10 cm box). With ``x = v |t| / d``,
    ``I omega > h_max`` iff ``x^2 < v I / (d h_max) - 1`` and ``I |alpha| > u_max`` iff
    ``x / (1 + x^2)^2 > u_max d^2 / (2 v^2 I)``, whose two roots either side of
    ``x = 1 / sqrt 3`` are found by bisection.
    """
    v, d = _vd(v_m_s, d_m)
    sc = spacecraft or default_spacecraft()
    if inertia_kg_m2 is None:
        inertia = float(np.max(sc.inertia_rw[:2]))
    else:
        inertia = number(inertia_kg_m2, "inertia_kg_m2", lo=0.0, lo_open=True)
    w_max, a_max = v / d, ALPHA_PEAK * v * v / (d * d)
    h_peak, u_peak = inertia * w_max, inertia * a_max
    h_lim, u_lim = sc.h_max_N_m_s, sc.u_max_N_m
    mom_win: tuple = ()
    if h_peak > h_lim:
        x = math.sqrt(v * inertia / (d * h_lim) - 1.0) if h_lim > 0.0 else math.inf
        mom_win = (-x * d / v, x * d / v)
    tor_win: tuple = ()
    if u_peak > u_lim:
        c = u_lim * d * d / (2.0 * v * v * inertia)
        g = lambda x: x / (1.0 + x * x) ** 2 - c  # noqa: E731
        xp = 1.0 / math.sqrt(3.0)
        x1 = _bisect(g, 0.0, xp) if c > 0.0 else 0.0
        if c > 0.0:
            hi = 1.0
            while g(hi) > 0.0:
                hi *= 2.0
            x2 = _bisect(g, xp, hi)
        else:
            x2 = math.inf
        tor_win = ((-x2 * d / v, -x1 * d / v), (x1 * d / v, x2 * d / v))
    return FollowCheck(inertia, w_max, a_max, h_peak, u_peak, h_peak <= h_lim, u_peak <= u_lim,
                       mom_win, tor_win)
