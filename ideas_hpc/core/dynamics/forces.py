"""The packed force-model record of the dynamics kernels (SPEC section 4).

The force model travels through the compiled kernels as ONE record of two
contiguous arrays, ``(fi, ff)``: ``fi`` (int64) and ``ff`` (float64). Their
layout is defined here and nowhere else; :func:`pack_record` fills them,
:func:`gravity_T` and :func:`srp_T` read them. The boundary layer
(:mod:`ideas_hpc.dynamics.forces`) turns a list of force settings into the arguments
of :func:`pack_record`.

``fi`` (int64)::

    [I_MODEL]   gravity model code (MODEL_*)
    [I_SH_K]    K = N + 3, side of the spherical-harmonic derivative tables (0: none)
    [I_NV]      polyhedron vertices V (0: none)
    [I_NF]      polyhedron faces F
    [I_NE]      polyhedron edges E
    [N_IHEAD:]  faces (F*3), then edges (E*2), row-major

``ff`` (float64)::

    [K_*]       scalar constants (below): mu (m^3/s^2), c20, c22 (m^2), spin
                rate (rad/s), SRP coefficient P_sun AU^2 C_r A / m (m^3/s^2),
                G rho (1/s^2), SH GM (m^3/s^2) and reference radius (m),
                prime meridian (rad), MU_SUN, heliocentric elements, pole and
                the ephemeris constants of
                :func:`ideas_hpc.core.dynamics.ephemeris.ephemeris_precompute`
    [N_CONSTS:] SH tables ctab, stab (2 * 10*K*K), then vertices (V*3, m),
                edge dyads (E*9), face dyads (F*9), row-major

Gravity models (``MODEL_*``): 0 point mass; 1 point mass + degree 2 (C20,
C22); 2 spherical harmonics (any degree, :mod:`ideas_hpc.core.dynamics.harmonics`);
3 constant-density polyhedron (:func:`ideas_hpc.core.dynamics.gravity.polyhedron_gravity`).

Solar radiation pressure (cannonball, SPEC section 4)::

    a_srp = -(P_sun (1 AU / d)^2 C_r A / m) s_T(t)

with ``s_T`` the body->Sun unit vector in T (:mod:`ideas_hpc.core.dynamics.ephemeris`);
``ff[K_SRP] = 0`` switches it off. SRP does not depend on r, so it adds
nothing to the gravity gradient.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ideas_hpc.core.dynamics.ephemeris import N_EPH, ephemeris_precompute, sun_T_fast
from ideas_hpc.core.dynamics.gravity import degree2, point_mass, polyhedron_gravity
from ideas_hpc.core.dynamics.harmonics import sh_gravity

# ---------------------------------------------------------------- layout

MODEL_POINT_MASS = 0
MODEL_DEGREE2 = 1
MODEL_SH = 2
MODEL_POLYHEDRON = 3

# fi header
I_MODEL = 0
I_SH_K = 1
I_NV = 2
I_NF = 3
I_NE = 4
N_IHEAD = 5

# ff scalar constants
K_MU = 0
K_C20 = 1
K_C22 = 2
K_SPIN = 3
K_SRP = 4
K_GRHO = 5
K_SH_GM = 6
K_SH_RREF = 7
K_W0 = 8
K_MU_SUN = 9
K_ELEM = 10   # 6 values: a, e, i, RAAN, argp, nu0
K_POLE = 16   # 3 values: ra, dec, flag
K_EPH = 19    # N_EPH derived ephemeris constants (ephemeris_precompute)
N_CONSTS = 19 + N_EPH


class ForceConstants(NamedTuple):
    """The scalar slots of the force record (unused terms 0)."""

    mu_m3s2: float
    c20_m2: float
    c22_m2: float
    spin_rate_rad_s: float
    #: Cannonball SRP coefficient, m^3/s^2.
    srp_coef_m3s2: float
    #: Constant radial field gradient, 1/s^2.
    g_rho_s2: float
    #: Spherical harmonics' GM (m^3/s^2) and reference radius (m).
    sh_gm_m3s2: float
    sh_r_ref_m: float
    #: Prime meridian at epoch, rad.
    w0_rad: float
    mu_sun_m3s2: float


class HarmonicTables(NamedTuple):
    """:func:`ideas_hpc.core.dynamics.harmonics.sh_derivative_tables`, (10, K, K) each (K = 0: none)."""

    ctab: np.ndarray
    stab: np.ndarray


class PolyhedronData(NamedTuple):
    """Polyhedron mesh (m) and :func:`ideas_hpc.core.dynamics.gravity.polyhedron_precompute`
    data, (V, 3), (F, 3), (E, 2), (E, 3, 3), (F, 3, 3) (V = 0: none)."""

    vertices_m: np.ndarray
    faces: np.ndarray
    edges: np.ndarray
    edge_dyads: np.ndarray
    face_dyads: np.ndarray


@njit(cache=True)
def pack_record(model, consts, elements, pole, harmonics, poly):
    """Build the force record ``(fi, ff)`` (layout in the module docstring).

    Parameters
    ----------
    model : int
        ``MODEL_*``.
    consts : ForceConstants
        The scalar slots, SI.
    elements : (6,) float64
        Heliocentric elements a (m), e, i, RAAN, argp, nu0 (rad).
    pole : (3,) float64
        ra, dec (rad), flag (1: set; 0: pole = orbit normal).
    harmonics : HarmonicTables
    poly : PolyhedronData

    Returns
    -------
    fi : int64 array, ff : float64 array
    """
    (mu, c20, c22, spin_rate, srp_coef, g_rho, sh_gm, sh_r_ref, w0,
     mu_sun) = consts
    sh_ctab, sh_stab = harmonics
    vertices, faces, edges, edge_dyads, face_dyads = poly
    k = sh_ctab.shape[1]
    nv = vertices.shape[0]
    nf = faces.shape[0]
    ne = edges.shape[0]
    fi = np.zeros(N_IHEAD + 3 * nf + 2 * ne, dtype=np.int64)
    fi[I_MODEL] = model
    fi[I_SH_K] = k
    fi[I_NV] = nv
    fi[I_NF] = nf
    fi[I_NE] = ne
    fi[N_IHEAD:N_IHEAD + 3 * nf] = faces.ravel()
    fi[N_IHEAD + 3 * nf:] = edges.ravel()
    ff = np.zeros(N_CONSTS + 20 * k * k + 3 * nv + 9 * ne + 9 * nf)
    ff[K_MU] = mu
    ff[K_C20] = c20
    ff[K_C22] = c22
    ff[K_SPIN] = spin_rate
    ff[K_SRP] = srp_coef
    ff[K_GRHO] = g_rho
    ff[K_SH_GM] = sh_gm
    ff[K_SH_RREF] = sh_r_ref
    ff[K_W0] = w0
    ff[K_MU_SUN] = mu_sun
    ff[K_ELEM:K_ELEM + 6] = elements
    ff[K_POLE:K_POLE + 3] = pole
    ff[K_EPH:K_EPH + N_EPH] = ephemeris_precompute(elements, pole, spin_rate, w0, mu_sun)
    o = N_CONSTS
    ff[o:o + 10 * k * k] = sh_ctab.ravel()
    o += 10 * k * k
    ff[o:o + 10 * k * k] = sh_stab.ravel()
    o += 10 * k * k
    ff[o:o + 3 * nv] = vertices.ravel()
    o += 3 * nv
    ff[o:o + 9 * ne] = edge_dyads.ravel()
    o += 9 * ne
    ff[o:o + 9 * nf] = face_dyads.ravel()
    return fi, ff


@njit(cache=True)
def sh_tables(fi, ff):
    """Views ``(ctab, stab)``, (10, K, K), of the spherical-harmonic tables in the record."""
    k = fi[I_SH_K]
    o = N_CONSTS
    return (ff[o:o + 10 * k * k].reshape((10, k, k)),
            ff[o + 10 * k * k:o + 20 * k * k].reshape((10, k, k)))


@njit(cache=True)
def polyhedron_arrays(fi, ff):
    """Views ``(vertices, faces, edges, edge_dyads, face_dyads)`` of the record's polyhedron."""
    k = fi[I_SH_K]
    nv = fi[I_NV]
    nf = fi[I_NF]
    ne = fi[I_NE]
    faces = fi[N_IHEAD:N_IHEAD + 3 * nf].reshape((nf, 3))
    edges = fi[N_IHEAD + 3 * nf:N_IHEAD + 3 * nf + 2 * ne].reshape((ne, 2))
    o = N_CONSTS + 20 * k * k
    vertices = ff[o:o + 3 * nv].reshape((nv, 3))
    o += 3 * nv
    edge_dyads = ff[o:o + 9 * ne].reshape((ne, 3, 3))
    o += 9 * ne
    face_dyads = ff[o:o + 9 * nf].reshape((nf, 3, 3))
    return vertices, faces, edges, edge_dyads, face_dyads


# ---------------------------------------------------------------- accelerations


@njit(cache=True)
def gravity_T(r_T, fi, ff, acc, grad, a2, g2):
    """Gravity acceleration (m/s^2) and gradient (1/s^2) of the force record at ``r_T`` (m, T).

    Returns the potential (m^2/s^2). ``acc, grad`` (3,), (3, 3) are the
    outputs, ``a2, g2`` (3,), (3, 3) work arrays.
    """
    model = fi[I_MODEL]
    if model == MODEL_SH:
        ctab, stab = sh_tables(fi, ff)
        kk = ctab.shape[1]
        v = np.empty((kk, kk))
        w = np.empty((kk, kk))
        return sh_gravity(r_T, ff[K_SH_GM], ff[K_SH_RREF], ctab, stab, acc, grad, v, w)
    if model == MODEL_POLYHEDRON:
        pv, pf, pe, ped, pfd = polyhedron_arrays(fi, ff)
        return polyhedron_gravity(r_T, ff[K_GRHO], pv, pf, pe, ped, pfd, acc, grad)
    u = point_mass(r_T, ff[K_MU], acc, grad)
    if model == MODEL_DEGREE2:
        u += degree2(r_T, ff[K_MU], ff[K_C20], ff[K_C22], a2, g2)
        for i in range(3):
            acc[i] += a2[i]
            for j in range(3):
                grad[i, j] += g2[i, j]
    return u


@njit(cache=True)
def srp_T(t, ff, out):
    """Cannonball SRP acceleration in T at ``t`` (s after t0 = 0), m/s^2, written to ``out``."""
    if ff[K_SRP] == 0.0:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = 0.0
        return
    d = sun_T_fast(t, ff[K_EPH:K_EPH + N_EPH], out)
    f = -ff[K_SRP] / (d * d)
    out[0] *= f
    out[1] *= f
    out[2] *= f
