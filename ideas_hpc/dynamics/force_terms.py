"""Force terms of the flyby dynamics: one settings object per term (SPEC section 4).

Tudatpy style: each term is a frozen dataclass that validates its fields when
built (an :class:`~ideas_hpc.base.errors.InputError` naming the field, in the
term's own parameter names) and fills its part of the kernels' force record in
``_pack(rec, params, shape)``. :func:`ideas_hpc.dynamics.forces.pack_forces`
turns a list of them into the record of :mod:`ideas_hpc.core.dynamics.forces`::

    terms = [Degree2(), CannonballSRP(reflectivity=0.6, sc_mass=4.0, sc_area=BOX_AREA)]

The expensive data of a term (the polyhedron's edge and face dyads, a
spherical-harmonic table) is cached per shape / file here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.constants import AU, G, P_SUN_1AU
from ideas_hpc.core.dynamics import forces as _cf
from ideas_hpc.core.dynamics.gravity import polyhedron_precompute
from ideas_hpc.core.dynamics.harmonics import sh_derivative_tables, sh_unnormalise
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number

#: 30 x 10 x 10 cm box (SPEC section 4): total surface area / 4, m^2.
BOX_AREA = (4 * 0.30 * 0.10 + 2 * 0.10 * 0.10) / 4.0


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
        number(self.gm_scale, "gm_scale", lo=0.0, lo_open=True)
        for name in ("c20", "c22"):
            if getattr(self, name) is not None:
                number(getattr(self, name), name)

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
            number(self.density, "density", lo=0.0, lo_open=True)

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
        number(self.reflectivity, "reflectivity", lo=0.0, hi=1.0)
        number(self.sc_mass, "sc_mass", lo=0.0, lo_open=True)
        number(self.sc_area, "sc_area", lo=0.0, lo_open=True)

    def _pack(self, rec, params, shape):
        rec["srp_coef"] = P_SUN_1AU * AU * AU * (1.0 + self.reflectivity) * self.sc_area \
            / self.sc_mass


GRAVITY_TERMS = (PointMass, Degree2, SphericalHarmonics, Polyhedron)


# -------------------------------------------------------------- data caches


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
