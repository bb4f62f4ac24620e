"""Gravity kernels in the body-fixed frame T (SPEC section 4).

Every model returns the acceleration ``a = grad U`` (m/s^2) and the gravity
gradient ``G = d a / d r`` (3x3, 1/s^2) at a field point ``r_T`` (m); the
potential ``U`` (m^2/s^2, positive convention: ``U = mu / r`` for a point mass)
is available where the validation needs it. The gradient feeds the
variational equations of the STM (SPEC section 4, ``A = [[0, I], [G - W W, -2 W]]``).

Models
------
* point mass: ``U = mu / r``.
* degree 2 (SPEC section 4, ``C20``/``C22`` in m^2, i.e. unnormalised
  coefficients times ``R_ref^2``)::

      U2 = (mu / r^3) [C20 (1 - 1.5 cos^2 delta) + 3 C22 cos^2 delta cos 2 lambda]

  which in Cartesian form is the harmonic quadratic form
  ``U2 = mu x^T Q x / r^5`` with
  ``Q = diag(-C20/2 + 3 C22, -C20/2 - 3 C22, C20)`` (trace 0).
* spherical harmonics to any degree: :mod:`ideas_hpc.core.dynamics.harmonics`.
* constant-density polyhedron (Werner & Scheeres 1997, Celest. Mech. 65,
  313-344, eqs. 15-17)::

      U  =  G rho / 2 [ sum_e L_e r_e.E_e.r_e - sum_f w_f r_f.F_f.r_f ]
      a  = -G rho     [ sum_e L_e E_e.r_e     - sum_f w_f F_f.r_f     ]
      dA =  G rho     [ sum_e L_e E_e         - sum_f w_f F_f         ]

  with face dyads ``F_f = n_f n_f^T``, edge dyads
  ``E_e = n_A n_A,12^T + n_B n_B,21^T``, the edge factor
  ``L_e = ln((a + b + e) / (a + b - e))`` and the signed solid angle ``w_f``.
  The edge and face data come from :func:`polyhedron_precompute`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


# ---------------------------------------------------------------- point mass


@njit(cache=True)
def point_mass(r_T, mu, acc, grad):
    """Point-mass acceleration and gradient; returns the potential.

    Parameters
    ----------
    r_T : (3,) float64
        Field point, m, frame T.
    mu : float
        Gravitational parameter, m^3/s^2.
    acc : (3,) float64
        Output, ``a = -mu r / r^3`` (m/s^2), overwritten.
    grad : (3, 3) float64
        Output, ``G = mu (3 r r^T / r^5 - I / r^3)`` (1/s^2), overwritten.

    Returns
    -------
    float
        ``U = mu / r``, m^2/s^2.
    """
    x, y, z = r_T[0], r_T[1], r_T[2]
    r2 = x * x + y * y + z * z
    r = np.sqrt(r2)
    ir3 = mu / (r2 * r)
    ir5 = 3.0 * ir3 / r2
    acc[0] = -ir3 * x
    acc[1] = -ir3 * y
    acc[2] = -ir3 * z
    for i in range(3):
        for j in range(3):
            grad[i, j] = ir5 * r_T[i] * r_T[j]
        grad[i, i] -= ir3
    return mu / r


# ----------------------------------------------------------------- degree 2


@njit(cache=True)
def degree2(r_T, mu, c20, c22, acc, grad):
    """Degree-2 part of the field (C20, C22 only), SPEC section 4 ``U2``.

    ``U2 = mu x^T Q x / r^5``, ``Q = diag(-C20/2 + 3 C22, -C20/2 - 3 C22, C20)``;
    ``a = mu (2 Q x / r^5 - 5 P x / r^7)`` with ``P = x^T Q x``;
    ``G = mu [2 Q / r^5 - 10 (Qx x^T + x (Qx)^T) / r^7 - 5 P I / r^7 + 35 P x x^T / r^9]``.

    Parameters
    ----------
    r_T : (3,) float64
        Field point, m, frame T.
    mu : float
        m^3/s^2.
    c20, c22 : float
        Unnormalised coefficients times ``R_ref^2``, m^2 (paper Table 1).
    acc, grad : (3,), (3, 3) float64
        Outputs (overwritten): the degree-2 acceleration only (no central term).

    Returns
    -------
    float
        ``U2``, m^2/s^2.
    """
    q0 = -0.5 * c20 + 3.0 * c22
    q1 = -0.5 * c20 - 3.0 * c22
    q2 = c20
    x, y, z = r_T[0], r_T[1], r_T[2]
    r2 = x * x + y * y + z * z
    ir2 = 1.0 / r2
    ir5 = mu * ir2 * ir2 / np.sqrt(r2)
    qx0 = q0 * x
    qx1 = q1 * y
    qx2 = q2 * z
    p = x * qx0 + y * qx1 + z * qx2
    acc[0] = ir5 * (2.0 * qx0 - 5.0 * p * x * ir2)
    acc[1] = ir5 * (2.0 * qx1 - 5.0 * p * y * ir2)
    acc[2] = ir5 * (2.0 * qx2 - 5.0 * p * z * ir2)
    qx = (qx0, qx1, qx2)
    for i in range(3):
        for j in range(3):
            grad[i, j] = ir5 * (-10.0 * ir2 * (qx[i] * r_T[j] + r_T[i] * qx[j])
                                + 35.0 * p * ir2 * ir2 * r_T[i] * r_T[j])
    grad[0, 0] += ir5 * (2.0 * q0 - 5.0 * p * ir2)
    grad[1, 1] += ir5 * (2.0 * q1 - 5.0 * p * ir2)
    grad[2, 2] += ir5 * (2.0 * q2 - 5.0 * p * ir2)
    return ir5 * p


# ---------------------------------------------------------------- polyhedron


@njit(cache=True)
def polyhedron_precompute(vertices, faces):
    """Edge and face data of a closed outward-wound mesh (Werner & Scheeres 1997).

    Parameters
    ----------
    vertices : (V, 3) float64
        m, frame T.
    faces : (F, 3) int64
        Counter-clockwise seen from outside.

    Returns
    -------
    edges : (E, 2) int64
        Vertex indices of each undirected edge.
    edge_dyads : (E, 3, 3) float64
        ``E_e = n_A n_A,12^T + n_B n_B,21^T`` (outward face normals times the
        outward in-plane edge normals of the two adjacent faces).
    face_dyads : (F, 3, 3) float64
        ``F_f = n_f n_f^T``.
    """
    nf = faces.shape[0]
    nface_n = np.empty((nf, 3))
    face_dyads = np.empty((nf, 3, 3))
    for f in range(nf):
        p0 = vertices[faces[f, 0]]
        p1 = vertices[faces[f, 1]]
        p2 = vertices[faces[f, 2]]
        n = np.cross(p1 - p0, p2 - p0)
        n /= np.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        nface_n[f] = n
        for i in range(3):
            for j in range(3):
                face_dyads[f, i, j] = n[i] * n[j]
    # directed edges (a -> b) of each face; an undirected edge appears twice
    ne_dir = 3 * nf
    key = np.empty(ne_dir, dtype=np.int64)
    nv = vertices.shape[0]
    for f in range(nf):
        for k in range(3):
            a = faces[f, k]
            b = faces[f, (k + 1) % 3]
            lo = min(a, b)
            hi = max(a, b)
            key[3 * f + k] = lo * nv + hi
    order = np.argsort(key, kind="mergesort")
    n_edges = ne_dir // 2
    edges = np.empty((n_edges, 2), dtype=np.int64)
    edge_dyads = np.zeros((n_edges, 3, 3))
    e = 0
    i = 0
    while i < ne_dir:
        for t in range(2):
            d = order[i + t]
            f = d // 3
            k = d % 3
            a = faces[f, k]
            b = faces[f, (k + 1) % 3]
            if t == 0:
                edges[e, 0] = a
                edges[e, 1] = b
            ed = vertices[b] - vertices[a]
            nn = nface_n[f]
            # outward edge normal in the face plane: edge x face normal
            en = np.cross(ed, nn)
            en /= np.sqrt(en[0] ** 2 + en[1] ** 2 + en[2] ** 2)
            for p in range(3):
                for q in range(3):
                    edge_dyads[e, p, q] += nn[p] * en[q]
        e += 1
        i += 2
    return edges, edge_dyads, face_dyads


@njit(cache=True)
def polyhedron_gravity(r_T, g_rho, vertices, faces, edges, edge_dyads, face_dyads,
                       acc, grad):
    """Constant-density polyhedron gravity (Werner & Scheeres 1997, eqs. 15-17).

    Parameters
    ----------
    r_T : (3,) float64
        Field point, m, frame T.
    g_rho : float
        ``G * density``, 1/s^2.
    vertices, faces : (V, 3) float64, (F, 3) int64
        The mesh (m).
    edges, edge_dyads, face_dyads
        From :func:`polyhedron_precompute`.
    acc, grad : (3,), (3, 3) float64
        Outputs, overwritten.

    Returns
    -------
    float
        U, m^2/s^2 (positive convention, ``-> G M / r`` far away).
    """
    nv = vertices.shape[0]
    rel = np.empty((nv, 3))
    nrm = np.empty(nv)
    for i in range(nv):
        for k in range(3):
            rel[i, k] = vertices[i, k] - r_T[k]
        nrm[i] = np.sqrt(rel[i, 0] ** 2 + rel[i, 1] ** 2 + rel[i, 2] ** 2)
    u = 0.0
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    g = np.zeros((3, 3))
    for e in range(edges.shape[0]):
        i = edges[e, 0]
        j = edges[e, 1]
        dx = vertices[j, 0] - vertices[i, 0]
        dy = vertices[j, 1] - vertices[i, 1]
        dz = vertices[j, 2] - vertices[i, 2]
        le = np.sqrt(dx * dx + dy * dy + dz * dz)
        s = nrm[i] + nrm[j]
        lf = np.log((s + le) / (s - le))
        ex = edge_dyads[e]
        rx, ry, rz = rel[i, 0], rel[i, 1], rel[i, 2]
        b0 = ex[0, 0] * rx + ex[0, 1] * ry + ex[0, 2] * rz
        b1 = ex[1, 0] * rx + ex[1, 1] * ry + ex[1, 2] * rz
        b2 = ex[2, 0] * rx + ex[2, 1] * ry + ex[2, 2] * rz
        u += lf * (rx * b0 + ry * b1 + rz * b2)
        a0 += lf * b0
        a1 += lf * b1
        a2 += lf * b2
        for p in range(3):
            for q in range(3):
                g[p, q] += lf * ex[p, q]
    for f in range(faces.shape[0]):
        i = faces[f, 0]
        j = faces[f, 1]
        k = faces[f, 2]
        r1 = rel[i]
        r2 = rel[j]
        r3 = rel[k]
        c0 = r2[1] * r3[2] - r2[2] * r3[1]
        c1 = r2[2] * r3[0] - r2[0] * r3[2]
        c2 = r2[0] * r3[1] - r2[1] * r3[0]
        num = r1[0] * c0 + r1[1] * c1 + r1[2] * c2
        d23 = r2[0] * r3[0] + r2[1] * r3[1] + r2[2] * r3[2]
        d31 = r3[0] * r1[0] + r3[1] * r1[1] + r3[2] * r1[2]
        d12 = r1[0] * r2[0] + r1[1] * r2[1] + r1[2] * r2[2]
        den = nrm[i] * nrm[j] * nrm[k] + nrm[i] * d23 + nrm[j] * d31 + nrm[k] * d12
        om = 2.0 * np.arctan2(num, den)
        fx = face_dyads[f]
        b0 = fx[0, 0] * r1[0] + fx[0, 1] * r1[1] + fx[0, 2] * r1[2]
        b1 = fx[1, 0] * r1[0] + fx[1, 1] * r1[1] + fx[1, 2] * r1[2]
        b2 = fx[2, 0] * r1[0] + fx[2, 1] * r1[1] + fx[2, 2] * r1[2]
        u -= om * (r1[0] * b0 + r1[1] * b1 + r1[2] * b2)
        a0 -= om * b0
        a1 -= om * b1
        a2 -= om * b2
        for p in range(3):
            for q in range(3):
                g[p, q] -= om * fx[p, q]
    # rel = vertex - field point, as W&S' r_e, r_f (eqs. 15-17)
    acc[0] = -g_rho * a0
    acc[1] = -g_rho * a1
    acc[2] = -g_rho * a2
    for p in range(3):
        for q in range(3):
            grad[p, q] = g_rho * g[p, q]
    return 0.5 * g_rho * u
