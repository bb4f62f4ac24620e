"""Navigation errors at a real encounter: the B-plane and the time of closest approach (SPEC 7f).

B-plane convention
------------------
With ``v_inf`` the spacecraft's velocity relative to the target and ``k`` a reference
pole (by default ``+z`` of N, the ecliptic north pole of J2000)::

    S = v_inf / |v_inf|,     T = S x k / |S x k|,     R = S x T,

so ``T`` lies in the reference plane and ``(S, T, R)`` is right-handed (Kizner 1961;
the usual JPL / ESA targeting frame). When ``S`` is within 1e-8 rad of ``k`` the frame
takes ``k = +x`` instead. The rows of :func:`bplane_frame` are ``S, T, R`` in N.

The error model
---------------
Before closest approach, the target's position relative to the swarm is uncertain
by its ephemeris (and the swarm's orbit determination): a Gaussian in the B-plane with
1-sigma semi-axes ``a >= b`` whose major axis makes the angle ``theta`` with ``T``
(counted from ``T`` toward ``R``), and an independent Gaussian error of the time of
closest approach (TCA) with 1-sigma ``sigma_t``. Both are **common to every member**:
the swarm shares the target's ephemeris, so this part moves every member together.
Each member adds its own small relative error, an isotropic 3-D Gaussian of 1-sigma
``sigma_member`` per axis (relative orbit determination within the swarm).

One draw is turned into what a flight needs by :func:`target_offset_N`: the true
target sits at ``delta = xi T + eta R + v dt S`` from the predicted one at the
predicted TCA, so the spacecraft's miss vector is ``b_pred - (xi T + eta R)`` and its
true closest approach is ``dt`` late (the target is ``v dt`` further along the
track). Moving the target by ``delta`` is the same as moving every member by
``-delta``.

Presets
-------
The real last-update figures of SPEC 7f (3-sigma unless said; converted to 1-sigma):

* :data:`LUTETIA`: Rosetta at 21 Lutetia, 10 July 2010, 15 km/s; the 1 July 2010
  solution (9 days out, ground and on-board optical data): B-plane 3-sigma semi-axes
  32 x 16 km, TCA 3-sigma 7.30 s (ESA, "Lutetia flyby navigation campaign up to 1 July
  2010", sci.esa.int, 7 July 2010). The ellipse's orientation is not published: 0.
* :data:`ARROKOTH`: New Horizons at (486958) Arrokoth, 1 January 2019, 14.4 km/s; the
  delivery box 120 x 320 km and the TCA within 140 s quoted by SPEC 7f (issue 42), read
  here as 3-sigma semi-axes (320 km along ``T``) and a 3-sigma TCA error; the
  orientation is ours. The optical navigation of that flyby is described in
  J. Astronaut. Sci. (2020), doi:10.1007/s40295-019-00188-x.
* :data:`DINKINESH`: Lucy at (152830) Dinkinesh, 1 November 2023, 4.5 km/s: ground
  knowledge of a small asteroid's position "up to 100 miles" (160 km) before terminal
  tracking (NASA, "NASA's Lucy will fly by tiny asteroid", October 2023), read here as
  a 3-sigma circle, with the TCA error of that distance along the track
  (160 km / 4.5 km/s = 35.6 s, 3-sigma; our assumption).

None gives a member-relative error: the presets take 0.1 km (1-sigma per axis), a
stated assumption for a swarm navigated together.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.base.units import DEG, KM

#: The default reference pole ``k``: +z of N (ecliptic north pole, J2000).
K_ECLIPTIC_N = np.array([0.0, 0.0, 1.0])
_PARALLEL_TOL = 1e-8


def bplane_frame(v_inf_N, k_N=K_ECLIPTIC_N) -> np.ndarray:
    """``(3, 3)``: rows ``S, T, R`` in N (module docstring)."""
    v = np.asarray(v_inf_N, dtype=np.float64)
    speed = float(np.linalg.norm(v))
    if not math.isfinite(speed) or speed == 0.0:
        raise InputError(f"v_inf must be a nonzero finite vector, got {v.tolist()}",
                         field="v_inf")
    s = v / speed
    k = np.asarray(k_N, dtype=np.float64)
    k = k / np.linalg.norm(k)
    t = np.cross(s, k)
    if np.linalg.norm(t) < _PARALLEL_TOL:
        t = np.cross(s, np.array([1.0, 0.0, 0.0]))
    t /= np.linalg.norm(t)
    return np.vstack([s, t, np.cross(s, t)])


@dataclass(frozen=True)
class NavigationError:
    """1-sigma errors of one navigation update (module docstring), SI.

    Attributes
    ----------
    sigma_major_m, sigma_minor_m : float
        B-plane 1-sigma semi-axes ``a >= b``, m.
    theta_rad : float
        Angle of the major axis from ``T`` toward ``R``, rad.
    sigma_tca_s : float
        1-sigma of the time of closest approach, s.
    sigma_member_m : float
        Each member's own 1-sigma per axis, m.
    speed_m_s : float
        Encounter speed the figures belong to, m/s (0 when not tied to one).
    update : str
        Which update the errors belong to ("last ground update 2 days out").
    source : str
        Where the figures come from.
    """

    sigma_major_m: float
    sigma_minor_m: float
    theta_rad: float = 0.0
    sigma_tca_s: float = 0.0
    sigma_member_m: float = 0.0
    speed_m_s: float = 0.0
    update: str = ""
    source: str = ""

    def __post_init__(self):
        number(self.sigma_major_m, "sigma_major_m", lo=0.0)
        number(self.sigma_minor_m, "sigma_minor_m", lo=0.0)
        if self.sigma_minor_m > self.sigma_major_m:
            raise InputError(f"the minor axis ({self.sigma_minor_m:g} m) exceeds the major "
                             f"axis ({self.sigma_major_m:g} m)", field="sigma_minor_m")
        number(self.theta_rad, "theta_rad")
        number(self.sigma_tca_s, "sigma_tca_s", lo=0.0)
        number(self.sigma_member_m, "sigma_member_m", lo=0.0)
        number(self.speed_m_s, "speed_m_s", lo=0.0)

    @property
    def covariance_TR_m2(self) -> np.ndarray:
        """``(2, 2)`` covariance of ``(xi, eta)`` along ``(T, R)``: ``Q diag(a^2, b^2) Q^T``."""
        c, s = math.cos(self.theta_rad), math.sin(self.theta_rad)
        q = np.array([[c, -s], [s, c]])
        return q @ np.diag([self.sigma_major_m ** 2, self.sigma_minor_m ** 2]) @ q.T

    def scaled(self, sigma_major_m: float) -> "NavigationError":
        """The same ellipse shape, orientation and timing-to-size ratio at another major axis
        (the value of a later update: e.g. 100, 30, 10, 3 km)."""
        f = number(sigma_major_m, "sigma_major_m", lo=0.0) / self.sigma_major_m
        return NavigationError(sigma_major_m, self.sigma_minor_m * f, self.theta_rad,
                               self.sigma_tca_s * f, self.sigma_member_m, self.speed_m_s,
                               f"{self.update}, scaled to {sigma_major_m / KM:g} km",
                               self.source)


@dataclass(frozen=True)
class NavigationDraw:
    """One draw of :class:`NavigationError`: the common part and each member's own.

    Attributes
    ----------
    xi_m, eta_m : float
        Target's B-plane offset along ``T`` and ``R``, m (common).
    dt_tca_s : float
        Shift of the time of closest approach, s (common; positive: later).
    member_offsets_m : (n, 3) float64
        Each member's own position error, m, in N.
    """

    xi_m: float
    eta_m: float
    dt_tca_s: float
    member_offsets_m: np.ndarray


def draw_navigation(err: NavigationError, rng: np.random.Generator,
                    n_members: int) -> NavigationDraw:
    """One draw: 3 normals (major axis, minor axis, TCA), then ``3 n`` for the members
    (isotropic, so drawn directly in N), always in this order."""
    n = int(n_members)
    if n < 0:
        raise InputError(f"must be >= 0, got {n_members}", field="n_members")
    xi, eta, dt = draw_common(err, rng)
    return NavigationDraw(xi_m=xi, eta_m=eta, dt_tca_s=dt,
                          member_offsets_m=draw_members(err, rng, n))


def draw_common(err: NavigationError, rng: np.random.Generator) -> tuple[float, float, float]:
    """The common part of one draw, ``(xi m, eta m, dt_tca s)``, from 3 normals (major axis,
    minor axis, TCA): one per scenario, shared by every member."""
    z = rng.standard_normal(3)
    c, s = math.cos(err.theta_rad), math.sin(err.theta_rad)
    u, w = err.sigma_major_m * z[0], err.sigma_minor_m * z[1]
    return c * u - s * w, s * u + c * w, err.sigma_tca_s * float(z[2])


def draw_members(err: NavigationError, rng: np.random.Generator, n: int) -> np.ndarray:
    """Each member's own error, ``(n, 3)`` m in N, from ``3 n`` normals (isotropic)."""
    return rng.standard_normal((int(n), 3)) * err.sigma_member_m


def target_offset_N(draw: NavigationDraw, v_inf_N, k_N=K_ECLIPTIC_N, *,
                    along_track: bool = True) -> np.ndarray:
    """The true target's offset from the predicted one at the predicted TCA, m in N:
    ``xi T + eta R + |v_inf| dt S`` (module docstring).

    ``along_track=False`` leaves out ``|v_inf| dt S``, for a flight that shifts its
    clock by ``draw.dt_tca_s`` instead (use one or the other, never both).
    """
    frame = bplane_frame(v_inf_N, k_N)
    out = draw.xi_m * frame[1] + draw.eta_m * frame[2]
    if along_track:
        out = out + float(np.linalg.norm(v_inf_N)) * draw.dt_tca_s * frame[0]
    return out


def member_offsets_N(draw: NavigationDraw, v_inf_N, k_N=K_ECLIPTIC_N) -> np.ndarray:
    """Each member's position error relative to the true target, ``(n, 3)`` m in N: its
    own error less the common target offset (along-track part included)."""
    return draw.member_offsets_m - target_offset_N(draw, v_inf_N, k_N)[None, :]


@dataclass(frozen=True)
class NavigationPlan:
    """What a flight knows of its navigation (SPEC 7f), on
    :attr:`~ideas_hpc.flyby.flight.FlybySetup.navigation`.

    Attributes
    ----------
    error : NavigationError
        The update's 1-sigma errors, drawn per scenario (common) and per member.
    detect_range_m : float
        Terminal tracking locks on the measured centroid from this range on, m
        (:meth:`~ideas_hpc.flyby.pass_rates.TerminalTracking.detection_range_m`); 0: never
        (body tracking aims at the predicted target throughout).
    centroid_sigma_rad : float
        1-sigma per camera axis (x_B, y_B) of the locked centroid pointing, rad.
    """

    error: NavigationError
    detect_range_m: float = 0.0
    centroid_sigma_rad: float = 0.0

    def __post_init__(self):
        number(self.detect_range_m, "detect_range_m", lo=0.0)
        number(self.centroid_sigma_rad, "centroid_sigma_rad", lo=0.0)


def _three_sigma(major_km, minor_km, tca_s, speed_km_s, update, source, theta_deg=0.0,
                 member_km=0.1) -> NavigationError:
    return NavigationError(major_km * KM / 3.0, minor_km * KM / 3.0, theta_deg * DEG,
                           tca_s / 3.0, member_km * KM, speed_km_s * KM, update, source)


LUTETIA = _three_sigma(32.0, 16.0, 7.30, 15.0, "1 July 2010 solution, 9 days before TCA "
                       "(ground and on-board optical data)",
                       "ESA, Lutetia flyby navigation campaign up to 1 July 2010 (7 July 2010)")
ARROKOTH = _three_sigma(320.0, 120.0, 140.0, 14.4, "delivery before the final optical "
                        "navigation (SPEC 7f)", "SPEC 7f / issue 42; read as 3-sigma semi-axes")
DINKINESH = _three_sigma(160.0, 160.0, 160.0 / 4.5, 4.5, "ground knowledge before terminal "
                         "tracking", "NASA, Lucy at Dinkinesh (Oct 2023): 'up to 100 miles'; "
                         "read as a 3-sigma circle")
#: The presets by name.
PRESETS = {"lutetia": LUTETIA, "arrokoth": ARROKOTH, "dinkinesh": DINKINESH}
