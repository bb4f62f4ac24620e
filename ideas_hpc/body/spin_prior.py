"""Pole and rotation of the target prior (SPEC section 7f).

Frames
------
* ``EQ``: the J2000 mean equator and equinox (right ascension ``alpha``, declination
  ``delta``), where IAU pole solutions are given.
* ``N``: the J2000 mean ecliptic and equinox (longitude ``lambda``, latitude ``beta``),
  the project's inertial frame (:mod:`ideas_hpc.core.dynamics.ephemeris`) and that of
  lightcurve pole solutions. ``x`` is the equinox in both; ``N`` is ``EQ`` turned about
  ``x`` by the J2000 obliquity ``eps = 23.4392911 deg`` (84381.448 arcsec, IAU 1976):
  ``v_N = R1(eps) v_EQ``, i.e. ``y_N = cos(eps) y_EQ + sin(eps) z_EQ`` and
  ``z_N = -sin(eps) y_EQ + cos(eps) z_EQ``.

Pole
----
The pole is drawn from a Fisher (3-D von Mises-Fisher) distribution, density
``kappa / (4 pi sinh kappa) exp(kappa mu . p)``, around a centre that is the
estimated pole ``mu`` or, with probability ``p_mirror``, its mirror
``(lambda + 180 deg, beta)``: lightcurves of a body seen near the ecliptic cannot
tell the two apart (Kaasalainen & Lamberg, Inverse Problems 22, 749, 2006). The
concentration is ``kappa = 1 / sigma^2`` (``sigma`` in rad): for small ``sigma`` the
offset is a 2-D Gaussian with ``sigma`` per axis (RMS angle ``sqrt(2) sigma``).
The angle from the centre is sampled exactly: ``w = cos(angle)`` has the CDF
``(exp(kappa w) - exp(-kappa)) / (2 sinh kappa)``, inverted in closed form (Wood,
Commun. Stat. Simul. Comput. 23, 157, 1994, for ``p = 3``)::

    w = 1 + ln(u + (1 - u) exp(-2 kappa)) / kappa,     u ~ U(0, 1),

and the azimuth about the centre is uniform.

Rotation
--------
The sidereal period is ``P ~ N(P0, sigma_P)``. The rotation angle at closest
approach (TCA) is the last lightcurve epoch's angle carried over ``dt`` (epoch to
TCA) at the drawn period, ``W_TCA = W_epoch + 2 pi dt / P`` plus the epoch's own
error ``N(0, sigma_W_epoch)``: to first order its spread is::

    sigma_phi = sqrt(sigma_W_epoch^2 + (2 pi dt sigma_P / P0^2)^2).

**The rule:** when ``sigma_phi > uniform_above_rad`` (default ``pi``: the wrapped
Gaussian is then within 0.6 % of uniform in density, and the first-order formula no
longer means anything) the phase is drawn uniform on ``[0, 2 pi)``, independent of
the period; otherwise it is the propagated value above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.fields import number
from ideas_hpc.base.units import DEG

#: J2000 mean obliquity of the ecliptic, rad (84381.448 arcsec, IAU 1976).
OBLIQUITY_J2000_RAD = 23.4392911 * DEG
#: Above ``kappa`` this, ``exp(-2 kappa)`` is below 1e-43 and the plain inverse is used.
_KAPPA_LARGE = 50.0


def _r1(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


#: ``v_N = DCM_N_EQ v_EQ``: equatorial J2000 to ecliptic J2000 (module docstring).
DCM_N_EQ = _r1(OBLIQUITY_J2000_RAD)


def unit_from_angles(lon_rad: float, lat_rad: float) -> np.ndarray:
    """``(cos lat cos lon, cos lat sin lon, sin lat)``."""
    return np.array([math.cos(lat_rad) * math.cos(lon_rad),
                     math.cos(lat_rad) * math.sin(lon_rad), math.sin(lat_rad)])


def angles_from_unit(u) -> tuple[float, float]:
    """``(lon in [0, 2 pi), lat)`` of a unit vector, rad."""
    u = np.asarray(u, dtype=np.float64)
    return (math.atan2(u[1], u[0]) % (2.0 * math.pi),
            math.asin(max(-1.0, min(1.0, float(u[2])))))


def ecliptic_from_equatorial(ra_rad: float, dec_rad: float) -> tuple[float, float]:
    """``(lambda, beta)`` of the direction at ``(alpha, delta)``, J2000, rad."""
    return angles_from_unit(DCM_N_EQ @ unit_from_angles(ra_rad, dec_rad))


def equatorial_from_ecliptic(lon_rad: float, lat_rad: float) -> tuple[float, float]:
    """``(alpha, delta)`` of the direction at ``(lambda, beta)``, J2000, rad."""
    return angles_from_unit(DCM_N_EQ.T @ unit_from_angles(lon_rad, lat_rad))


def mirror_pole_N(pole_N) -> np.ndarray:
    """The mirror pole, ``(lambda + 180 deg, beta)`` in the ecliptic frame: ``(-x, -y, z)``."""
    p = np.asarray(pole_N, dtype=np.float64)
    return np.array([-p[0], -p[1], p[2]])


def fisher_cosines(rng: np.random.Generator, kappa: float, n: int) -> np.ndarray:
    """``n`` draws of ``w = cos(angle from the centre)`` of a Fisher law (module docstring)."""
    u = rng.uniform(0.0, 1.0, n)
    if kappa == 0.0:
        return 2.0 * u - 1.0
    if kappa > _KAPPA_LARGE:
        return 1.0 + np.log(u + (1.0 - u) * math.exp(-2.0 * kappa)) / kappa
    # exp(-2k) + u (1 - exp(-2k)) = exp(-2k) (1 + u expm1(2k)): no cancellation at small kappa
    return -1.0 + np.log1p(u * math.expm1(2.0 * kappa)) / kappa


def _basis(mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing ``mu`` to a right-handed orthonormal basis."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(mu[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(mu, helper)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(mu, e1)


def sample_fisher(rng: np.random.Generator, mu, kappa: float, n: int) -> np.ndarray:
    """``(n, 3)`` unit vectors from the Fisher law about unit ``mu`` with concentration ``kappa``.

    Draws ``n`` uniforms for the cosines, then ``n`` for the azimuths.
    """
    mu = np.asarray(mu, dtype=np.float64)
    mu = mu / np.linalg.norm(mu)
    w = fisher_cosines(rng, float(kappa), n)
    az = rng.uniform(0.0, 2.0 * math.pi, n)
    e1, e2 = _basis(mu)
    s = np.sqrt(np.maximum(0.0, 1.0 - w * w))
    out = (s * np.cos(az))[:, None] * e1 + (s * np.sin(az))[:, None] * e2 + w[:, None] * mu
    return out / np.linalg.norm(out, axis=1)[:, None]


@dataclass(frozen=True)
class PoleEstimate:
    """A spin pole known from the ground (module docstring).

    Attributes
    ----------
    ra_rad, dec_rad : float
        Estimated pole, J2000 equatorial, rad (see :meth:`from_ecliptic`).
    sigma_rad : float
        Angular 1-sigma per axis, rad; ``kappa = 1 / sigma^2``; 0 means exact.
    p_mirror : float
        Probability that the mirror pole ``(lambda + 180 deg, beta)`` is the true one.
    """

    ra_rad: float
    dec_rad: float
    sigma_rad: float = 0.0
    p_mirror: float = 0.0

    def __post_init__(self):
        number(self.ra_rad, "ra_rad")
        number(self.dec_rad, "dec_rad", lo=-0.5 * math.pi, hi=0.5 * math.pi)
        number(self.sigma_rad, "sigma_rad", lo=0.0, hi=math.pi)
        number(self.p_mirror, "p_mirror", lo=0.0, hi=1.0)

    @classmethod
    def from_ecliptic(cls, lon_rad: float, lat_rad: float, sigma_rad: float = 0.0,
                      p_mirror: float = 0.0) -> "PoleEstimate":
        """The same estimate from ecliptic J2000 ``(lambda, beta)`` (lightcurve solutions)."""
        number(lat_rad, "lat_rad", lo=-0.5 * math.pi, hi=0.5 * math.pi)
        ra, dec = equatorial_from_ecliptic(number(lon_rad, "lon_rad"), lat_rad)
        return cls(ra, dec, sigma_rad, p_mirror)

    @property
    def pole_N(self) -> np.ndarray:
        """The estimate as a unit vector in the ecliptic frame N."""
        return DCM_N_EQ @ unit_from_angles(self.ra_rad, self.dec_rad)

    @property
    def kappa(self) -> float:
        """Fisher concentration ``1 / sigma^2`` (inf for an exact pole)."""
        return math.inf if self.sigma_rad == 0.0 else 1.0 / self.sigma_rad ** 2

    def draw(self, rng: np.random.Generator) -> tuple[np.ndarray, bool]:
        """One pole ``(unit vector in N, mirrored)``: one uniform picks the centre, then
        :func:`sample_fisher` draws about it (nothing more for an exact pole)."""
        mirrored = bool(rng.uniform() < self.p_mirror)
        centre = mirror_pole_N(self.pole_N) if mirrored else self.pole_N
        if self.sigma_rad == 0.0:
            return centre, mirrored
        return sample_fisher(rng, centre, self.kappa, 1)[0], mirrored


@dataclass(frozen=True)
class RotationEstimate:
    """Period and rotation phase known from lightcurves (module docstring).

    Attributes
    ----------
    period_s : float
        Sidereal period ``P0``, s.
    sigma_period_s : float
        1-sigma of the period, s.
    phase_epoch_rad : float
        Rotation angle ``W`` (prime meridian) at the last lightcurve epoch, rad.
    sigma_phase_epoch_rad : float
        1-sigma of that angle, rad.
    dt_epoch_to_tca_s : float
        Time from the last lightcurve epoch to closest approach, s (>= 0).
    uniform_above_rad : float
        The rule's threshold on ``sigma_phi`` (``pi``).
    """

    period_s: float
    sigma_period_s: float = 0.0
    phase_epoch_rad: float = 0.0
    sigma_phase_epoch_rad: float = 0.0
    dt_epoch_to_tca_s: float = 0.0
    uniform_above_rad: float = math.pi

    def __post_init__(self):
        number(self.period_s, "period_s", lo=0.0, lo_open=True)
        number(self.sigma_period_s, "sigma_period_s", lo=0.0, hi=0.2 * self.period_s)
        number(self.phase_epoch_rad, "phase_epoch_rad")
        number(self.sigma_phase_epoch_rad, "sigma_phase_epoch_rad", lo=0.0)
        number(self.dt_epoch_to_tca_s, "dt_epoch_to_tca_s", lo=0.0)
        number(self.uniform_above_rad, "uniform_above_rad", lo=0.0, lo_open=True)

    @property
    def sigma_phase_rad(self) -> float:
        """``sigma_phi = sqrt(sigma_W_epoch^2 + (2 pi dt sigma_P / P0^2)^2)``, rad."""
        drift = 2.0 * math.pi * self.dt_epoch_to_tca_s * self.sigma_period_s / self.period_s ** 2
        return math.hypot(self.sigma_phase_epoch_rad, drift)

    @property
    def phase_uniform(self) -> bool:
        """The rule: the phase at TCA is uniform when ``sigma_phi > uniform_above_rad``."""
        return self.sigma_phase_rad > self.uniform_above_rad

    @property
    def phase_tca_nominal_rad(self) -> float:
        """``W_epoch + 2 pi dt / P0`` wrapped to ``[0, 2 pi)``, rad."""
        return (self.phase_epoch_rad
                + 2.0 * math.pi * self.dt_epoch_to_tca_s / self.period_s) % (2.0 * math.pi)

    def draw(self, rng: np.random.Generator) -> tuple[float, float]:
        """One ``(period_s, phase_tca_rad in [0, 2 pi))``: three draws, always in this order
        (period normal, epoch-phase normal, uniform), whichever branch the rule takes."""
        z_p, z_w = rng.standard_normal(2)
        u = rng.uniform()
        period = self.period_s + self.sigma_period_s * z_p
        if self.phase_uniform:
            return period, 2.0 * math.pi * u
        w = (self.phase_epoch_rad + self.sigma_phase_epoch_rad * z_w
             + 2.0 * math.pi * self.dt_epoch_to_tca_s / period)
        return period, w % (2.0 * math.pi)

