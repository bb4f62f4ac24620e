"""The ``[dynamics]`` table of the flyby dynamics: :class:`ForceModel` (SPEC section 4).

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

and :meth:`ForceModel.terms` its list of settings objects
(:mod:`ideas_hpc.dynamics.force_terms`); validating a :class:`ForceModel` is
building its settings (one validation path). :data:`GRAVITY_MODELS` names the
gravity choices of the table. :func:`pack_force_model` packs a model, with a
Monte Carlo override, through :func:`ideas_hpc.dynamics.forces.pack_forces`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.dynamics.force_terms import (BOX_AREA, CannonballSRP, Degree2, PointMass, Polyhedron,
                                            SphericalHarmonics, _sh_field)
from ideas_hpc.dynamics.forces import PackedForceModel, pack_forces
from ideas_hpc.base.errors import InputError, config_fields
from ideas_hpc.base.fields import number
from ideas_hpc.body.params import PhysicalParams


def _prefixed(prefix: str):
    """Re-raise a settings object's InputError with ``prefix`` on the field name."""
    return config_fields(prefix=prefix)


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
            number(self.rtol, "rtol", lo=0.0, hi=1.0, lo_open=True)
            number(self.atol, "atol", lo=0.0, lo_open=True)
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


#: The force model's own parameter a world may set (besides the body's).
_FORCE_MODEL_KEYS = ("reflectivity",)


def world_parameters() -> tuple[str, ...]:
    """Every parameter a world (:class:`ideas_hpc.flyby.world.World`) or a Monte Carlo
    override may set, SI: each numeric field of
    :class:`~ideas_hpc.body.params.PhysicalParams` (``mu``, ``c20``, ``c22``, the spin
    period, the pole ``pole_ra`` / ``pole_dec``, the rotation phase ``prime_meridian``,
    the heliocentric elements) and the force model's ``reflectivity``. The one list."""
    body = tuple(f.name for f in dataclasses.fields(PhysicalParams) if f.name != "name")
    return body + _FORCE_MODEL_KEYS


#: Parameters that must stay > 0.
_POSITIVE = ("mu", "spin_period", "orbit_a")


def apply_override(params: PhysicalParams, fm: ForceModel, override):
    """(params, reflectivity, changed-keys) after a world's parameters or a Monte Carlo
    override (``{name: SI value}`` of :func:`world_parameters`, or a whole
    :class:`PhysicalParams`); errors name ``params_override.<name>``."""
    if override is None:
        return params, fm.reflectivity, set()
    if isinstance(override, PhysicalParams):
        return override, fm.reflectivity, {"mu", "c20", "c22"}
    if not isinstance(override, dict):
        raise InputError("must be a dict or PhysicalParams", field="params_override")
    keys = world_parameters()
    refl = fm.reflectivity
    rep = {}
    for k, v in override.items():
        if k not in keys:
            raise InputError(f"unknown key {k!r}; allowed: {', '.join(keys)}",
                             field=f"params_override.{k}")
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) \
                or not math.isfinite(v):
            raise InputError(f"must be a finite number, got {v!r}", field=f"params_override.{k}")
        if k in _POSITIVE and v <= 0:
            raise InputError("must be > 0", field=f"params_override.{k}")
        if k == "reflectivity":
            if not 0.0 <= v <= 1.0:
                raise InputError("must be in [0, 1]", field="params_override.reflectivity")
            refl = float(v)
        else:
            rep[k] = float(v)
    out = dataclasses.replace(params, **rep)
    if (out.pole_ra is None) != (out.pole_dec is None):
        raise InputError("give pole_ra and pole_dec together (the body has no pole of its "
                         "own)", field="params_override.pole_ra")
    return out, refl, set(rep)


def pack_force_model(body, force_model: ForceModel = ForceModel(),
                     params_override=None) -> PackedForceModel:
    """Pack a :class:`ForceModel` (plus a Monte Carlo override) for the kernels.

    The expensive parts (polyhedron edge data, the spherical-harmonic table)
    are cached per shape / file, so a Monte Carlo sample that perturbs
    ``mu``, ``c20``, ``c22`` or the reflectivity costs only the packing (and,
    for spherical harmonics, one O(N^2) derivative-table build).

    ``params_override``: dict with SI keys of :func:`world_parameters` (``mu``
    m^3/s^2, ``c20``, ``c22`` m^2, ``reflectivity``, the pole ``pole_ra``, ``pole_dec``
    rad, ...), or a whole :class:`PhysicalParams`.
    """
    nominal = body.require_params()
    params, refl, changed = apply_override(nominal, force_model, params_override)
    sh_kw = {"gm_scale": params.mu / nominal.mu if "mu" in changed else 1.0,
             "c20": params.c20 if "c20" in changed else None,
             "c22": params.c22 if "c22" in changed else None}
    terms = force_model.terms(reflectivity=refl, sh_kw=sh_kw)
    return pack_forces(terms, params, body.shape)
