"""Mass properties of a constant-density polyhedron and the checks a custom body needs.

The volume integrals are exact for the closed, outward-wound mesh of a
:class:`~ideas_hpc.body.shape.Shape`: the body is the signed sum of the
tetrahedra (origin, a, b, c) of its faces, and for a tetrahedron with one vertex
at the origin

    V = a . (b x c) / 6,    int x dV = V (a + b + c) / 4,
    int x_j x_k dV = V / 20 [sum_v v_j v_k + (sum_v v_j)(sum_v v_k)]

(the second-moment formula of a simplex, e.g. Tonon, J. Math. Stat. 1, 2004).

Degree-2 coefficients follow the project's gravity convention (SPEC section 4,
:func:`ideas_hpc.core.dynamics.gravity.degree2`): unnormalised C20 and C22
multiplied by R_ref^2, in m^2, in frame T about the centre of mass. With
``S = int (x - c)(x - c)^T dV / V`` (the centred second moments per unit volume)

    C20 R^2 = S_zz - (S_xx + S_yy) / 2,    C22 R^2 = (S_xx - S_yy) / 4,

which is MacCullagh's ``((A + B)/2 - C) / M`` and ``(B - A) / (4 M)`` with the
moments of inertia A, B, C about x, y, z. A triaxial ellipsoid gives
``(2 c^2 - a^2 - b^2) / 10`` and ``(a^2 - b^2) / 20``. Terms that the degree-2
model of frame T omits (C21, S21, S22, nonzero when the mesh axes are not its
principal axes) are reported as the angle between the two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Bulk densities a small body can have, kg/m^3 (rubble piles ~1000, metal ~8000).
DENSITY_RANGE_KG_M3 = (100.0, 10_000.0)
#: Largest centre-of-mass offset from the mesh origin, as a fraction of the mean radius.
COM_OFFSET_LIMIT = 0.05


@dataclass(frozen=True)
class MassProperties:
    """Constant-density mass properties of a closed mesh (SI, frame T).

    Attributes
    ----------
    volume_m3 : float
    com_T_m : (3,) float64
        Centre of mass (centroid of the volume), m.
    second_moments_T_m2 : (3, 3) float64
        ``int (x - c)(x - c)^T dV / V`` about the centre of mass, m^2.
    c20_m2, c22_m2 : float
        Degree-2 coefficients times R_ref^2 in frame T (module docstring), m^2.
    principal_T : (3, 3) float64
        Columns: principal axes in T, ordered by increasing moment of inertia
        (long axis first), each with a non-negative component on its T axis.
    principal_moments_m2 : (3,) float64
        Moments of inertia per unit mass about those axes, m^2.
    extent_T_m : (3,) float64
        Size of the bounding box along x, y, z of T, m.
    """

    volume_m3: float
    com_T_m: np.ndarray
    second_moments_T_m2: np.ndarray
    c20_m2: float
    c22_m2: float
    principal_T: np.ndarray
    principal_moments_m2: np.ndarray
    extent_T_m: np.ndarray

    @property
    def axes_tilt_rad(self) -> float:
        """Largest angle between a principal axis and the T axis it is closest to, rad."""
        cosines = np.clip(np.abs(self.principal_T).max(axis=0), 0.0, 1.0)
        return float(np.max(np.arccos(cosines)))


def mass_properties(vertices_T, faces) -> MassProperties:
    """Exact volume integrals of a closed, outward-wound triangle mesh (m, frame T)."""
    v = np.asarray(vertices_T, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    vol_t = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    vol = float(vol_t.sum())
    s = a + b + c
    com = (vol_t[:, None] * s).sum(axis=0) / (4.0 * vol)
    outer = (np.einsum("i,ij,ik->jk", vol_t, a, a) + np.einsum("i,ij,ik->jk", vol_t, b, b)
             + np.einsum("i,ij,ik->jk", vol_t, c, c) + np.einsum("i,ij,ik->jk", vol_t, s, s))
    second = outer / (20.0 * vol) - np.outer(com, com)
    inertia = np.trace(second) * np.eye(3) - second
    moments, axes = np.linalg.eigh(inertia)
    # Order the axes like T's as far as possible (long axis first), signs toward +T.
    axes = axes * np.where(np.diag(axes) < 0.0, -1.0, 1.0)
    return MassProperties(
        volume_m3=vol, com_T_m=com, second_moments_T_m2=second,
        c20_m2=float(second[2, 2] - 0.5 * (second[0, 0] + second[1, 1])),
        c22_m2=float(0.25 * (second[0, 0] - second[1, 1])),
        principal_T=axes, principal_moments_m2=moments,
        extent_T_m=v.max(axis=0) - v.min(axis=0))


def implied_density(mu_m3_s2: float, volume_m3: float) -> float:
    """Bulk density, kg/m^3, of a body of gravitational parameter ``mu`` and volume ``V``."""
    from ideas_hpc.base.constants import G

    return mu_m3_s2 / G / volume_m3


def density_problem(density_kg_m3: float) -> str | None:
    """Why a density is implausible for a small body (a mesh in m read as km), or None."""
    lo, hi = DENSITY_RANGE_KG_M3
    if lo <= density_kg_m3 <= hi:
        return None
    hint = ("the mesh is probably in metres" if density_kg_m3 < lo
            else "the mesh is probably smaller than its file unit says")
    return (f"implied density {density_kg_m3:.3g} kg/m^3 (mass / mesh volume) is outside "
            f"{lo:g}-{hi:,.0f} kg/m^3: {hint}, or the mass is wrong")


def com_problem(props: MassProperties, r_mean_m: float) -> str | None:
    """Why the mesh origin cannot be the centre of mass (SPEC section 1), or None."""
    off = float(np.linalg.norm(props.com_T_m))
    if off <= COM_OFFSET_LIMIT * r_mean_m:
        return None
    x, y, z = (props.com_T_m / 1e3).tolist()
    return (f"the constant-density centre of mass ({x:.4g}, {y:.4g}, {z:.4g}) km is "
            f"{off / 1e3:.4g} km from the mesh origin, more than {100 * COM_OFFSET_LIMIT:g} % "
            f"of the mean radius {r_mean_m / 1e3:.4g} km; frame T has its origin at the centre "
            "of mass: shift the mesh by minus that vector")


def mean_radius(volume_m3: float) -> float:
    """Radius of the sphere of the same volume, m."""
    return (3.0 * volume_m3 / (4.0 * math.pi)) ** (1.0 / 3.0)
