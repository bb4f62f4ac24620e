"""Force model of the flyby dynamics: settings objects and the one factory (SPEC section 4).

The force terms are declared as a list of settings objects, tudatpy style,
and ONE factory, :func:`pack_forces`, turns the list into the record
``(fi, ff)`` of :mod:`ideas_hpc.core.dynamics.forces` that every dynamics kernel takes::

    terms = [Degree2(), CannonballSRP(reflectivity=0.6, sc_mass=4.0, sc_area=BOX_AREA)]
    packed = pack_forces(terms, body.params, body.shape)

Each settings object validates its fields when built (errors name the field).

:class:`ForceModel` is the TOML ``[dynamics]`` table (:func:`force_model_from_config`)::

    gravity      = "degree2"   # point_mass | degree2 | spherical_harmonics | polyhedron
    sh_degree    = 15          # spherical_harmonics: truncation degree
    sh_file      = "n15acoeff.tab"
    srp          = true
    reflectivity = 0.6         # C_r = 1 + reflectivity
    sc_mass      = 4.0         # kg
    sc_area      = 0.035       # m^2 (30x10x10 cm box: total area / 4)
    density      = 2670.0      # kg/m^3, polyhedron (default: body mass / shape volume)
    rtol         = 1e-12       # integrator tolerances (DOP853)
    atol         = 1e-9

and :meth:`ForceModel.terms` its list of settings; validating a
:class:`ForceModel` is building its settings (one validation path).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ideas_hpc.constants import AU, G, MU_SUN, P_SUN_1AU
from ideas_hpc.core.dynamics import forces as _cf
from ideas_hpc.core.dynamics.gravity import polyhedron_precompute
from ideas_hpc.core.dynamics.harmonics import sh_derivative_tables, sh_unnormalise
from ideas_hpc.errors import InputError, config_fields
from ideas_hpc.config.fields import number
from ideas_hpc.body.params import PhysicalParams

#: 30 x 10 x 10 cm box (SPEC section 4): total surface area / 4, m^2.
BOX_AREA = (4 * 0.30 * 0.10 + 2 * 0.10 * 0.10) / 4.0


def _number(v, field, lo=-math.inf, hi=math.inf, lo_open=False):
    number(v, field, lo=None if lo == -math.inf else lo, hi=None if hi == math.inf else hi,
           lo_open=lo_open)


def _prefixed(prefix: str):
    """Re-raise a settings object's InputError with ``prefix`` on the field name."""
    return config_fields(prefix=prefix)


# -------------------------------------------------------------- settings


@dataclass(frozen=True)
class PointMass:
    """Point-mass gravity, ``mu`` of the body parameters."""

    def _pack(self, rec, params, shape):
        rec["model"] = _cf.MODEL_POINT_MASS


@dataclass(frozen=True)
class Degree2:
    """Point mass plus the C20/C22 field of the body parameters (SPEC section 4)."""

    def _pack(self, rec, params, shape):
        rec["model"] = _cf.MODEL_DEGREE2


@dataclass(frozen=True)
class SphericalHarmonics:
    """Spherical harmonics of a coefficient table (GM and reference radius from its label).

    ``gm_scale`` multiplies the table's GM; ``c20``, ``c22`` (m^2, i.e.
    unnormalised coefficient times ``R_ref^2``), when set, replace the table's
    degree-2 terms (Monte Carlo perturbations).
    """

    sh_degree: int = 15
    sh_file: str = "n15acoeff.tab"
    gm_scale: float = 1.0
    c20: float | None = None
    c22: float | None = None

    def __post_init__(self):
        d = self.sh_degree
        if isinstance(d, bool) or not isinstance(d, (int, np.integer)) or not 2 <= d <= 60:
            raise InputError(f"must be an integer in [2, 60], got {d!r}", field="sh_degree")
        if not isinstance(self.sh_file, str) or not self.sh_file:
            raise InputError("must be a file name or path", field="sh_file")
        _number(self.gm_scale, "gm_scale", 0.0, lo_open=True)
        for name in ("c20", "c22"):
            if getattr(self, name) is not None:
                _number(getattr(self, name), name)

    def _pack(self, rec, params, shape):
        fld = _sh_field(self.sh_file, self.sh_degree)
        c, s = sh_unnormalise(fld.cbar, fld.sbar)
        if self.c20 is not None:
            c[2, 0] = self.c20 / fld.r_ref ** 2
        if self.c22 is not None:
            c[2, 2] = self.c22 / fld.r_ref ** 2
        rec["model"] = _cf.MODEL_SH
        rec["sh_ctab"], rec["sh_stab"] = sh_derivative_tables(c, s)
        rec["sh_gm"] = fld.gm * self.gm_scale
        rec["sh_r_ref"] = fld.r_ref


@dataclass(frozen=True)
class Polyhedron:
    """Constant-density polyhedron of the body's shape; ``density`` kg/m^3 (None: mass / volume)."""

    density: float | None = None

    def __post_init__(self):
        if self.density is not None:
            _number(self.density, "density", 0.0, lo_open=True)

    def _pack(self, rec, params, shape):
        if shape is None:
            raise InputError("the polyhedron needs the body's shape", field="gravity")
        v, f, e, ed, fd = _poly_data(shape)
        rho = self.density if self.density is not None else params.mu / (G * shape.volume)
        rec["model"] = _cf.MODEL_POLYHEDRON
        rec["poly"] = (v, f, e, ed, fd)
        rec["g_rho"] = G * rho


@dataclass(frozen=True)
class CannonballSRP:
    """Cannonball solar radiation pressure, ``C_r = 1 + reflectivity``; kg, m^2."""

    reflectivity: float = 0.6
    sc_mass: float = 4.0
    sc_area: float = BOX_AREA

    def __post_init__(self):
        _number(self.reflectivity, "reflectivity", 0.0, 1.0)
        _number(self.sc_mass, "sc_mass", 0.0, lo_open=True)
        _number(self.sc_area, "sc_area", 0.0, lo_open=True)

    def _pack(self, rec, params, shape):
        rec["srp_coef"] = P_SUN_1AU * AU * AU * (1.0 + self.reflectivity) * self.sc_area \
            / self.sc_mass


GRAVITY_TERMS = (PointMass, Degree2, SphericalHarmonics, Polyhedron)


# -------------------------------------------------------------- the factory


class PackedForceModel(NamedTuple):
    """The force record handed to the kernels (layout: :mod:`ideas_hpc.core.dynamics.forces`)."""

    fi: np.ndarray
    ff: np.ndarray

    def args(self):
        return (self.fi, self.ff)


def elements_and_pole(params: PhysicalParams):
    """Heliocentric elements (6,) and pole ``(ra, dec, flag)`` (3,) arrays of ``params``, SI."""
    elements = np.array([params.orbit_a, params.orbit_e, params.orbit_i, params.orbit_raan,
                         params.orbit_argp, params.orbit_nu], dtype=np.float64)
    pole = np.zeros(3)
    if params.pole_ra is not None and params.pole_dec is not None:
        pole[:] = (params.pole_ra, params.pole_dec, 1.0)
    return elements, pole


def pack_forces(terms, params: PhysicalParams, shape=None) -> PackedForceModel:
    """Build the kernels' force record from a list of settings objects.

    Parameters
    ----------
    terms : sequence
        Exactly one gravity term and at most one :class:`CannonballSRP`.
    params : PhysicalParams
        Body parameters (mu, C20, C22, spin, ephemeris; SI).
    shape : ideas_hpc.body.shape.Shape, optional
        Needed by :class:`Polyhedron`.
    """
    kinds = [type(t) for t in terms]  # one gravity term: the record has one MODEL_ code
    n_grav = sum(k in GRAVITY_TERMS for k in kinds)
    if n_grav != 1:
        raise InputError(f"need exactly one gravity term, got {n_grav}", field="gravity")
    if kinds.count(CannonballSRP) > 1:
        raise InputError("at most one CannonballSRP term", field="srp")
    empty3 = np.zeros((10, 0, 0))
    rec = {"srp_coef": 0.0, "g_rho": 0.0, "sh_gm": 0.0, "sh_r_ref": 0.0,
           "sh_ctab": empty3, "sh_stab": empty3,
           "poly": (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64),
                    np.zeros((0, 2), dtype=np.int64), np.zeros((0, 3, 3)), np.zeros((0, 3, 3)))}
    for t in terms:
        if not hasattr(t, "_pack"):
            raise InputError(f"not a force settings object: {t!r}", field="terms")
        t._pack(rec, params, shape)
    elements, pole = elements_and_pole(params)
    consts = _cf.ForceConstants(*(float(x) for x in (
        params.mu, params.c20, params.c22, params.spin_rate, rec["srp_coef"], rec["g_rho"],
        rec["sh_gm"], rec["sh_r_ref"], params.prime_meridian, MU_SUN)))
    fi, ff = _cf.pack_record(rec["model"], consts, elements, pole,
                             _cf.HarmonicTables(rec["sh_ctab"], rec["sh_stab"]),
                             _cf.PolyhedronData(*rec["poly"]))
    return PackedForceModel(fi, ff)


_POLY_CACHE: dict = {}
_SH_CACHE: dict = {}


def _poly_data(shape):
    key = id(shape.vertices_T)
    hit = _POLY_CACHE.get(key)
    if hit is None or hit[0] is not shape.vertices_T:
        v = np.ascontiguousarray(shape.vertices_T, dtype=np.float64)
        f = np.ascontiguousarray(shape.faces, dtype=np.int64)
        e, ed, fd = polyhedron_precompute(v, f)
        hit = (shape.vertices_T, v, f, e, ed, fd)
        _POLY_CACHE[key] = hit
    return hit[1:]


def _sh_field(sh_file: str, sh_degree: int):
    from ideas_hpc.body.gravity_field import load_sh_field

    if sh_file not in _SH_CACHE:
        _SH_CACHE[sh_file] = load_sh_field(sh_file)
    fld = _SH_CACHE[sh_file]
    if sh_degree > fld.degree:
        raise InputError(f"sh_degree {sh_degree} above the table's degree {fld.degree}",
                         field="sh_degree")
    return fld.truncated(sh_degree)


# -------------------------------------------------------------- the [dynamics] table


GRAVITY_MODELS = ("point_mass", "degree2", "spherical_harmonics", "polyhedron")


@dataclass(frozen=True)
class ForceModel:
    """Force model of the flyby dynamics, the ``[dynamics]`` table (SPEC section 4). SI units.

    Attributes
    ----------
    gravity : {'point_mass', 'degree2', 'spherical_harmonics', 'polyhedron'}
        ``degree2`` is the point mass plus the C20/C22 field of the body
        parameters; ``spherical_harmonics`` uses ``sh_file`` (GM and reference
        radius from its label); ``polyhedron`` the body's shape at ``density``.
    sh_degree : int
        Truncation degree of the spherical harmonics.
    sh_file : str
        Table name on the data path or a path.
    srp : bool
        Cannonball solar radiation pressure.
    reflectivity, sc_mass, sc_area : float
        ``C_r = 1 + reflectivity``; kg; m^2 (:class:`CannonballSRP`).
    density : float or None
        kg/m^3 for the polyhedron; None means body mass / shape volume.
    rtol, atol : float
        DOP853 tolerances (the accuracy contract of SPEC section 4 is checked at
        1e-12 / 1e-9).
    """

    gravity: str = "degree2"
    sh_degree: int = 15
    sh_file: str = "n15acoeff.tab"
    srp: bool = True
    reflectivity: float = 0.6
    sc_mass: float = 4.0
    sc_area: float = BOX_AREA
    density: float | None = None
    rtol: float = 1e-12
    atol: float = 1e-9

    def __post_init__(self):
        self._settings("")

    def _settings(self, prefix: str, sh_kw=None):
        """Validate (errors name ``<prefix><field>``) and build every settings object."""
        if self.gravity not in GRAVITY_MODELS:
            raise InputError(f"must be one of {', '.join(GRAVITY_MODELS)}, got {self.gravity!r}",
                             field=f"{prefix}gravity")
        with _prefixed(prefix):
            sh = SphericalHarmonics(self.sh_degree, self.sh_file, **(sh_kw or {}))
            if not isinstance(self.srp, (bool, np.bool_)):
                raise InputError(f"must be true or false, got {self.srp!r}", field="srp")
            srp = CannonballSRP(self.reflectivity, self.sc_mass, self.sc_area)
            _number(self.rtol, "rtol", 0.0, 1.0, lo_open=True)
            _number(self.atol, "atol", 0.0, lo_open=True)
            poly = Polyhedron(self.density)
        grav = {"point_mass": PointMass(), "degree2": Degree2(), "spherical_harmonics": sh,
                "polyhedron": poly}[self.gravity]
        return [grav, srp] if self.srp else [grav]

    def terms(self, *, reflectivity=None, sh_kw=None) -> list:
        """The settings objects of this model (``reflectivity``/``sh_kw``: Monte Carlo overrides)."""
        fm = self if reflectivity is None else dataclasses.replace(self, reflectivity=reflectivity)
        return fm._settings("", sh_kw)


_FM_FIELDS = {f.name for f in dataclasses.fields(ForceModel)}


def force_model_from_config(table: dict | None, prefix: str = "dynamics.") -> ForceModel:
    """Build a :class:`ForceModel` from a TOML table (keys as the attributes, SI units).

    Unknown keys and bad values raise :class:`InputError` naming ``<prefix><key>``.
    """
    table = dict(table or {})
    for k in table:
        if k not in _FM_FIELDS:
            raise InputError(f"unknown key {k!r}; allowed: {', '.join(sorted(_FM_FIELDS))}",
                             field=f"{prefix}{k}")
    kw = {}
    for k, v in table.items():
        if k in ("reflectivity", "sc_mass", "sc_area", "rtol", "atol", "density") \
                and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        kw[k] = v
    fm = ForceModel.__new__(ForceModel)
    for f in dataclasses.fields(ForceModel):
        object.__setattr__(fm, f.name, kw.get(f.name, f.default))
    fm._settings(prefix)
    if fm.gravity == "spherical_harmonics":   # the table's degree bounds sh_degree
        with _prefixed(prefix):
            _sh_field(fm.sh_file, fm.sh_degree)
    return fm


# -------------------------------------------------------------- Monte Carlo overrides


_OVERRIDE_KEYS = ("mu", "c20", "c22", "reflectivity")


def _apply_override(params: PhysicalParams, fm: ForceModel, override):
    """(params, reflectivity, changed-keys) after a Monte Carlo override."""
    if override is None:
        return params, fm.reflectivity, set()
    if isinstance(override, PhysicalParams):
        return override, fm.reflectivity, {"mu", "c20", "c22"}
    if not isinstance(override, dict):
        raise InputError("must be a dict or PhysicalParams", field="params_override")
    refl = fm.reflectivity
    rep = {}
    for k, v in override.items():
        if k not in _OVERRIDE_KEYS:
            raise InputError(f"unknown key {k!r}; allowed: {', '.join(_OVERRIDE_KEYS)}",
                             field=f"params_override.{k}")
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) \
                or not math.isfinite(v):
            raise InputError(f"must be a finite number, got {v!r}", field=f"params_override.{k}")
        if k == "mu" and v <= 0:
            raise InputError("must be > 0", field="params_override.mu")
        if k == "reflectivity":
            if not 0.0 <= v <= 1.0:
                raise InputError("must be in [0, 1]", field="params_override.reflectivity")
            refl = float(v)
        else:
            rep[k] = float(v)
    return dataclasses.replace(params, **rep), refl, set(rep)


def pack_force_model(body, force_model: ForceModel = ForceModel(),
                     params_override=None) -> PackedForceModel:
    """Pack a :class:`ForceModel` (plus a Monte Carlo override) for the kernels.

    The expensive parts (polyhedron edge data, the spherical-harmonic table)
    are cached per shape / file, so a Monte Carlo sample that perturbs
    ``mu``, ``c20``, ``c22`` or the reflectivity costs only the packing (and,
    for spherical harmonics, one O(N^2) derivative-table build).

    ``params_override``: dict with SI keys ``mu`` (m^3/s^2), ``c20``, ``c22``
    (m^2), ``reflectivity``, or a whole :class:`PhysicalParams`.
    """
    nominal = body.require_params()
    params, refl, changed = _apply_override(nominal, force_model, params_override)
    sh_kw = {"gm_scale": params.mu / nominal.mu if "mu" in changed else 1.0,
             "c20": params.c20 if "c20" in changed else None,
             "c22": params.c22 if "c22" in changed else None}
    terms = force_model.terms(reflectivity=refl, sh_kw=sh_kw)
    return pack_forces(terms, params, body.shape)
