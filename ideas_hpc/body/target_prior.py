"""The target prior: worlds of a body known only from the ground (SPEC section 7f, issue 42).

``world = prior.draw(seed, k)`` is one target: a shape (a closed, valid
:class:`~ideas_hpc.body.shape.Shape` in SI), its volume-equivalent size, a spin pole,
a period and the rotation angle at closest approach (TCA). The same ``(seed, k)``
gives the same world bit for bit, from any process (:func:`ideas_hpc.base.seeds.world_rng`:
shape, size, pole and rotation have independent streams, so changing one part's
settings leaves the others' draws unchanged).

Shape of world ``k``
--------------------
1. A nominal (:class:`Nominal`): either a unit icosphere with a stretch to the
   estimated semi-axes (:func:`ellipsoid_nominal`, SPEC 7f's order: perturb the
   sphere, then stretch), or a given shape model with no stretch
   (:func:`mesh_nominal`: the family becomes its radial perturbation). Its base
   vertices ``b_i`` must form a radial graph about the origin
   (:func:`~ideas_hpc.body.random_sphere.radial_graph_problem`).
2. Each base vertex moves along its ray by the Gaussian random sphere's factor,
   ``b_i exp(s(u_i) - beta^2 / 2)`` with ``u_i = b_i / |b_i|``
   (:mod:`ideas_hpc.body.random_sphere`), then the stretch applies. A positive
   factor along each ray and a linear stretch keep the mesh a closed, outward-wound,
   self-intersection-free radial graph, so every draw is valid.
3. The mesh is shifted so that its constant-density centre of mass is the origin of
   frame T (SPEC section 1); its axes are not turned (the pole draw carries the
   orientation's uncertainty). ``star_centre_T_m`` is the point it is star-shaped about.
4. It is scaled so that its volume-equivalent diameter ``D = 2 (3 V / 4 pi)^(1/3)`` is
   the size draw: lognormal with mean ``D0`` and standard deviation ``sigma_D``
   (``ln D ~ N(ln D0 - s^2 / 2, s^2)``, ``s^2 = ln(1 + (sigma_D / D0)^2)``), which keeps
   ``D > 0`` (:class:`SizeEstimate`).

Pole and rotation: :mod:`ideas_hpc.body.spin_prior` (Fisher law with the mirror pole;
the phase rule).

Today's known body is the prior with no spread (:func:`known_prior`); the built-in
Eros-class prior (:func:`eros_class_prior`) needs no data path.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace

import numpy as np

from ideas_hpc.base import seeds
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.base.units import DEG, HOUR
from ideas_hpc.body.analytic import EROS_ELLIPSOID_AXES_M, _check_resolution
from ideas_hpc.body.mass_properties import mass_properties, mean_radius
from ideas_hpc.body.params import PhysicalParams, get_params
from ideas_hpc.body.random_sphere import GaussianRandomSphere, ShapeFamily, radial_graph_problem
from ideas_hpc.body.shape import Shape, build_shape
from ideas_hpc.body.spin_prior import (PoleEstimate, RotationEstimate, angles_from_unit,
                                       DCM_N_EQ)

DAY = 86400.0


@dataclass(frozen=True)
class Nominal:
    """The shape a prior perturbs (module docstring, step 1).

    Attributes
    ----------
    name, source : str
    base_vertices : (V, 3) float64
        Vertices before the stretch, a radial graph about the origin (unit vectors
        for an ellipsoid nominal, metres for a shape model).
    faces : (F, 3) int64
        Outward wound.
    stretch : (3,) float64
        Factors on x, y, z of T after the perturbation (semi-axes in m, or ones).
    """

    name: str
    source: str
    base_vertices: np.ndarray = field(repr=False)
    faces: np.ndarray = field(repr=False)
    stretch: np.ndarray = field(repr=False)

    @property
    def directions(self) -> np.ndarray:
        """Unit rays of the base vertices, ``(V, 3)``."""
        return self.base_vertices / np.linalg.norm(self.base_vertices, axis=1)[:, None]

    @functools.cached_property
    def volume_m3(self) -> float:
        """Volume of the unperturbed nominal (base vertices stretched), m^3."""
        return mass_properties(self.base_vertices * self.stretch, self.faces).volume_m3

    @property
    def diameter_m(self) -> float:
        """Volume-equivalent diameter of the unperturbed nominal, m."""
        return 2.0 * mean_radius(self.volume_m3)

    @property
    def mean_edge_angle_rad(self) -> float:
        """Mean angle an edge subtends at the origin, rad (the sampling of the rays)."""
        u = self.directions
        e = np.concatenate([self.faces[:, [0, 1]], self.faces[:, [1, 2]], self.faces[:, [2, 0]]])
        dots = np.einsum("ij,ij->i", u[e[:, 0]], u[e[:, 1]])
        return float(np.mean(np.arccos(np.clip(dots, -1.0, 1.0))))


def _checked(nominal: Nominal) -> Nominal:
    problem = radial_graph_problem(nominal.base_vertices, nominal.faces)
    if problem is not None:
        raise InputError(f"the nominal shape {nominal.name!r} cannot carry a radial "
                         f"perturbation: {problem}", field="nominal")
    return nominal


def ellipsoid_nominal(axes_m, resolution: int = 3, *, name: str = "ellipsoid") -> Nominal:
    """Unit icosphere (``resolution`` subdivisions, as
    :func:`ideas_hpc.body.analytic.ellipsoid_mesh`) stretched to the semi-axes ``axes_m``
    (m) after the perturbation."""
    axes = np.array([number(a, f"axes_m[{i}]", lo=0.0, lo_open=True)
                     for i, a in enumerate(axes_m)])
    if axes.shape != (3,):
        raise InputError(f"needs 3 semi-axes, got {len(axes)}", field="axes_m")
    res = _check_resolution(resolution)
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=res, radius=1.0)
    src = (f"ellipsoid {axes[0] / 1e3:g} x {axes[1] / 1e3:g} x {axes[2] / 1e3:g} km "
           f"(semi-axes), icosphere resolution {res}")
    return _checked(Nominal(name, src, np.ascontiguousarray(ico.vertices, dtype=np.float64),
                            np.ascontiguousarray(ico.faces, dtype=np.int64), axes))


def mesh_nominal(shape: Shape) -> Nominal:
    """A shape model as the nominal: the family moves its vertices along their rays from
    the origin of T (its centre of mass); refused unless it is a radial graph about it."""
    return _checked(Nominal(shape.name, shape.source, shape.vertices_T.copy(),
                            shape.faces.copy(), np.ones(3)))


@dataclass(frozen=True)
class SizeEstimate:
    """Volume-equivalent diameter ``D0`` and its 1-sigma (module docstring, step 4), m.

    ``diameter_m=None`` takes the nominal's own size.
    """

    diameter_m: float | None = None
    sigma_diameter_m: float = 0.0

    def __post_init__(self):
        if self.diameter_m is not None:
            number(self.diameter_m, "diameter_m", lo=0.0, lo_open=True)
        number(self.sigma_diameter_m, "sigma_diameter_m", lo=0.0)

    def draw(self, rng: np.random.Generator, d0_m: float) -> float:
        """One diameter, m: lognormal with mean ``d0_m`` and sd ``sigma_diameter_m``."""
        s2 = math.log1p((self.sigma_diameter_m / d0_m) ** 2)
        return d0_m * math.exp(math.sqrt(s2) * float(rng.standard_normal()) - 0.5 * s2)


@dataclass(frozen=True)
class TargetWorld:
    """One world of a :class:`TargetPrior` (SI; frames: T body, N ecliptic J2000).

    Attributes
    ----------
    seed, k, family : int
        What drew it (:func:`ideas_hpc.base.seeds.world_rng`).
    shape : Shape
        Closed outward mesh in T, origin at its constant-density centre of mass.
    diameter_m : float
        Volume-equivalent diameter of ``shape`` (the size draw), m.
    size_scale : float
        ``diameter_m`` over the estimate ``D0``.
    star_centre_T_m : (3,) float64
        The point of T the mesh is a radial graph about, m.
    pole_N : (3,) float64
        Spin pole (+z of T), unit vector in N.
    pole_mirrored : bool
        True when the draw took the mirror pole's branch.
    spin_period_s : float
    phase_tca_rad : float
        Rotation angle ``W`` of T about the pole at TCA, in ``[0, 2 pi)``.
    phase_uniform : bool
        True when the phase rule made it uniform.
    """

    seed: int
    k: int
    family: int
    shape: Shape
    diameter_m: float
    size_scale: float
    star_centre_T_m: np.ndarray
    pole_N: np.ndarray
    pole_mirrored: bool
    spin_period_s: float
    phase_tca_rad: float
    phase_uniform: bool

    @property
    def radius_m(self) -> float:
        """Volume-equivalent radius, m."""
        return 0.5 * self.diameter_m

    @property
    def pole_lon_lat_rad(self) -> tuple[float, float]:
        """Pole ``(lambda, beta)`` in N (ecliptic J2000), rad (``PhysicalParams.pole_ra/dec``)."""
        return angles_from_unit(self.pole_N)

    @property
    def pole_ra_dec_rad(self) -> tuple[float, float]:
        """Pole ``(alpha, delta)`` in the J2000 equator, rad."""
        return angles_from_unit(DCM_N_EQ.T @ self.pole_N)

    def prime_meridian_rad(self, t_tca_s: float) -> float:
        """Rotation angle at the flight's ``t = 0`` for a TCA at ``t_tca_s``, ``[0, 2 pi)``."""
        return (self.phase_tca_rad - 2.0 * math.pi * t_tca_s / self.spin_period_s) % (2 * math.pi)

    def physical_params(self, base: PhysicalParams, t_tca_s: float, *,
                        reference_volume_m3: float | None = None,
                        degree2_from_shape: bool = True) -> PhysicalParams:
        """``base`` with this world's spin, pole and prime meridian (for a TCA at ``t_tca_s``).

        ``mu`` is scaled by volume (the same bulk density as ``base`` at
        ``reference_volume_m3``; unscaled if None); C20 and C22 are the shape's at
        constant density unless ``degree2_from_shape`` is False (keep ``base``'s, e.g. the
        paper's Table 1 values for the known Eros).
        """
        lon, lat = self.pole_lon_lat_rad
        mp = self.shape.mass_properties
        mu = base.mu if reference_volume_m3 is None else \
            base.mu * mp.volume_m3 / number(reference_volume_m3, "reference_volume_m3", lo=0.0,
                                            lo_open=True)
        c20, c22 = (mp.c20_m2, mp.c22_m2) if degree2_from_shape else (base.c20, base.c22)
        return replace(base, mu=mu, spin_period=self.spin_period_s, c20=c20, c22=c22,
                       pole_ra=lon, pole_dec=lat, prime_meridian=self.prime_meridian_rad(t_tca_s))


@dataclass(frozen=True)
class TargetPrior:
    """What is known of a target before the flyby (module docstring).

    Attributes
    ----------
    nominal : Nominal
    family : ShapeFamily
    size : SizeEstimate
    pole : PoleEstimate
    rotation : RotationEstimate
    name : str
    recentre : bool
        Shift each world so that its constant-density centre of mass is the origin
        (True); False keeps the nominal's origin (a known shape model, whose origin is
        already its centre of mass, stays bit-identical).
    """

    nominal: Nominal
    family: ShapeFamily
    size: SizeEstimate
    pole: PoleEstimate
    rotation: RotationEstimate
    name: str = "prior"
    recentre: bool = True

    @functools.cached_property
    def sphere(self) -> GaussianRandomSphere:
        """The shape family on the nominal's rays (built once per prior)."""
        grs = GaussianRandomSphere(self.family, self.nominal.directions)
        resolvable = math.pi / self.nominal.mean_edge_angle_rad
        if grs.l_max > resolvable:
            raise InputError(f"degree l_max = {grs.l_max} is finer than the nominal mesh "
                             f"resolves (about {resolvable:.0f}): refine the nominal or lower "
                             "`l_max`", field="l_max")
        return grs

    @property
    def diameter_m(self) -> float:
        """The size estimate ``D0``, m (the nominal's own when none is given)."""
        return self.nominal.diameter_m if self.size.diameter_m is None else self.size.diameter_m

    def draw(self, seed: int, k: int, family: int = 0) -> TargetWorld:
        """World ``k`` of campaign seed ``seed`` (``family`` as in
        :func:`ideas_hpc.base.seeds.world_rng`)."""
        rng = functools.partial(seeds.world_rng, seed, k, family=family)
        factor = self.sphere.radius_factor(rng(seeds.WORLD_SHAPE))
        v = self.nominal.base_vertices * factor[:, None] * self.nominal.stretch
        mp = mass_properties(v, self.nominal.faces)
        shift = mp.com_T_m if self.recentre else np.zeros(3)
        v = v - shift
        d0 = self.diameter_m
        d = self.size.draw(rng(seeds.WORLD_SIZE), d0)
        if (self.family.sigma == 0.0 and self.size.diameter_m is None
                and self.size.sigma_diameter_m == 0.0):
            # no spread at all: the nominal at its own size, untouched by a rounded scale of 1
            scale, d = 1.0, 2.0 * mean_radius(mp.volume_m3)
        else:
            scale = 0.5 * d / mean_radius(mp.volume_m3)
        v = v * scale
        src = (f"{self.name} world {k} (seed {seed}): Gaussian random sphere sigma "
               f"{self.family.sigma:g}, l_max {self.sphere.l_max}, on {self.nominal.source}; "
               f"volume-equivalent diameter {d / 1e3:.4g} km")
        shape = build_shape(v, self.nominal.faces, name=f"{self.name}-{k}", source=src)
        pole, mirrored = self.pole.draw(rng(seeds.WORLD_POLE))
        period, phase = self.rotation.draw(rng(seeds.WORLD_ROTATION))
        return TargetWorld(seed=int(seed), k=int(k), family=int(family), shape=shape,
                           diameter_m=d, size_scale=d / d0,
                           star_centre_T_m=-shift * scale, pole_N=pole,
                           pole_mirrored=mirrored, spin_period_s=period, phase_tca_rad=phase,
                           phase_uniform=self.rotation.phase_uniform)


# ---- built-in priors --------------------------------------------------------------------------

#: IAU pole of 433 Eros, J2000 equatorial (Archinal et al., Celest. Mech. Dyn. Astr. 130:22, 2018).
EROS_POLE_RA_DEC_DEG = (11.35, 17.22)
#: Assumed ground knowledge of an Eros-class target (issue 42; these are stated choices, not
#: measurements): 10 % on the radiometric diameter, a lightcurve pole good to 10 deg per axis
#: with a 25 % chance of the mirror solution, the period to 0.001 h, the rotation angle to
#: 10 deg at the last lightcurve, 60 days before closest approach.
EROS_CLASS_KNOWLEDGE = {"sigma_diameter_rel": 0.10, "sigma_pole_deg": 10.0, "p_mirror": 0.25,
                        "period_h": 5.270, "sigma_period_h": 0.001,
                        "sigma_phase_epoch_deg": 10.0, "dt_epoch_to_tca_days": 60.0}


def eros_class_prior(resolution: int = 3, *, family: ShapeFamily | None = None) -> TargetPrior:
    """The built-in prior of an Eros-class target (no data path needed).

    Nominal: the built-in Eros-sized ellipsoid's semi-axes
    (:data:`ideas_hpc.body.analytic.EROS_ELLIPSOID_AXES_M`, 17 x 5.6 x 5.4 km) on an icosphere of
    ``resolution``; family: the Gaussian random sphere with Muinonen & Lagerros's
    ``sigma = 0.245``, ``Gamma = 33 deg``; pole: Eros's IAU pole; spin period: paper Table 1;
    spreads: :data:`EROS_CLASS_KNOWLEDGE`.
    """
    kn = EROS_CLASS_KNOWLEDGE
    nominal = ellipsoid_nominal(EROS_ELLIPSOID_AXES_M, resolution, name="eros-ellipsoid")
    ra, dec = EROS_POLE_RA_DEC_DEG
    return TargetPrior(
        nominal=nominal, family=family or ShapeFamily(),
        size=SizeEstimate(nominal.diameter_m, kn["sigma_diameter_rel"] * nominal.diameter_m),
        pole=PoleEstimate(ra * DEG, dec * DEG, kn["sigma_pole_deg"] * DEG, kn["p_mirror"]),
        rotation=RotationEstimate(kn["period_h"] * HOUR, kn["sigma_period_h"] * HOUR, 0.0,
                                  kn["sigma_phase_epoch_deg"] * DEG,
                                  kn["dt_epoch_to_tca_days"] * DAY),
        name="eros-class")


def known_prior(shape: Shape, params: PhysicalParams | None = None, *,
                t_tca_s: float = 0.0) -> TargetPrior:
    """A known body as the prior with no spread.

    Every world is ``shape`` bit for bit (not recentred: a shape model's origin is its
    centre of mass by SPEC section 1), with ``params``' pole (its orbit normal when it has
    none), period and the rotation angle its prime meridian reaches at ``t_tca_s``.
    """
    from ideas_hpc.core.dynamics.ephemeris import dcm_PN

    p = params or get_params("eros")
    pole = np.zeros(3)
    if p.pole_ra is not None and p.pole_dec is not None:
        pole[:] = (p.pole_ra, p.pole_dec, 1.0)
    elements = np.array([p.orbit_a, p.orbit_e, p.orbit_i, p.orbit_raan, p.orbit_argp,
                         p.orbit_nu])
    ra, dec = angles_from_unit(DCM_N_EQ.T @ dcm_PN(elements, pole)[2])
    return TargetPrior(
        nominal=mesh_nominal(shape), family=ShapeFamily(sigma=0.0), size=SizeEstimate(),
        pole=PoleEstimate(ra, dec), name=shape.name, recentre=False,
        rotation=RotationEstimate(p.spin_period, 0.0, p.prime_meridian, 0.0,
                                  number(t_tca_s, "t_tca_s", lo=0.0)))
