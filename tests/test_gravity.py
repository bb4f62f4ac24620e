"""Gravity kernels and the spherical-harmonic loader against outside truth (SPEC section 4).

Truths used: finite differences of the potential (acceleration) and of the
acceleration (gradient); an independent Legendre-function evaluation of the
spherical-harmonic potential with ``scipy.special.lpmv``; the
``polyhedral-gravity`` package (Tsoulis' line-integral method) on eros001708;
the point-mass limit far away.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import lpmv

from ideas_hpc.core.dynamics import gravity as gk
from ideas_hpc.core.dynamics import harmonics as hk
from ideas_hpc.body.datapath import have_data_file
from ideas_hpc.base.errors import InputError
from ideas_hpc.body.gravity_field import load_sh_field, sh_from_degree2
from ideas_hpc.body.params import get_params

EROS = get_params("eros")
R_REF = 16.0e3
rng = np.random.default_rng(20240601)


def _points(n, rmin, rmax):
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d * rng.uniform(rmin, rmax, size=(n, 1))


def _pm(r):
    a = np.zeros(3)
    g = np.zeros((3, 3))
    u = gk.point_mass(r, EROS.mu, a, g)
    return u, a, g


def _d2(r, c20=EROS.c20, c22=EROS.c22):
    a = np.zeros(3)
    g = np.zeros((3, 3))
    u = gk.degree2(r, EROS.mu, c20, c22, a, g)
    return u, a, g


def _sh(tables, gm, rref):
    ct, st = tables
    k = ct.shape[1]

    def f(r):
        a = np.zeros(3)
        g = np.zeros((3, 3))
        u = hk.sh_gravity(r, gm, rref, ct, st, a, g, np.empty((k, k)), np.empty((k, k)))
        return u, a, g
    return f


def _fd_check(fun, r, h):
    """Central differences: grad U vs a, and d a / d r vs the gradient."""
    u, a, g = fun(r)
    a_fd = np.zeros(3)
    g_fd = np.zeros((3, 3))
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        up, ap, _ = fun(r + e)
        um, am, _ = fun(r - e)
        a_fd[k] = (up - um) / (2 * h)
        g_fd[:, k] = (ap - am) / (2 * h)
    return (np.linalg.norm(a - a_fd) / np.linalg.norm(a),
            np.linalg.norm(g - g_fd) / np.linalg.norm(g), np.abs(g - g.T).max() / np.abs(g).max())


@pytest.mark.parametrize("r", list(_points(3, 20e3, 200e3)))
def test_point_mass_and_degree2_derivatives(r):
    for fun in (_pm, _d2):
        ea, eg, asym = _fd_check(fun, r, 1e-4 * np.linalg.norm(r))
        assert ea < 1e-6 and eg < 1e-6 and asym < 1e-14


def test_degree2_matches_closed_form_spec_u2():
    """SPEC section 4: U2 = mu/r^3 [C20 (1 - 1.5 cos^2 d) + 3 C22 cos^2 d cos 2 l]."""
    for r in _points(20, 20e3, 300e3):
        rn = np.linalg.norm(r)
        cd2 = (r[0] ** 2 + r[1] ** 2) / rn ** 2
        lam = math.atan2(r[1], r[0])
        u2 = EROS.mu / rn ** 3 * (EROS.c20 * (1 - 1.5 * cd2) + 3 * EROS.c22 * cd2 * math.cos(2 * lam))
        assert _d2(r)[0] == pytest.approx(u2, rel=1e-12)


def test_degree2_equals_degree2_part_of_sh():
    """Degree 2 = the SH model built from the same C20, C22 (minus its central term)."""
    fld = sh_from_degree2(EROS.c20, EROS.c22, R_REF, EROS.mu)
    c, s = hk.sh_unnormalise(fld.cbar, fld.sbar)
    # unnormalised C20 R^2, C22 R^2 reproduce the m^2 inputs (Kaula normalisation)
    assert c[2, 0] * R_REF ** 2 == pytest.approx(EROS.c20, rel=1e-14)
    assert c[2, 2] * R_REF ** 2 == pytest.approx(EROS.c22, rel=1e-14)
    sh = _sh(hk.sh_derivative_tables(c, s), EROS.mu, R_REF)
    for r in _points(50, 20e3, 300e3):
        u_s, a_s, g_s = sh(r)
        u_p, a_p, g_p = _pm(r)
        u_2, a_2, g_2 = _d2(r)
        assert u_s - u_p == pytest.approx(u_2, rel=1e-9, abs=1e-12 * u_p)
        assert np.linalg.norm(a_s - a_p - a_2) <= 1e-9 * np.linalg.norm(a_2)
        assert np.linalg.norm(g_s - g_p - g_2) <= 1e-9 * np.linalg.norm(g_2)


def _sh_potential_lpmv(r, fld):
    """Independent SH potential: U = GM/r sum (R/r)^n Pbar_nm(sin phi)(C cos m l + S sin m l)."""
    rn = np.linalg.norm(r)
    sphi = r[2] / rn
    lam = math.atan2(r[1], r[0])
    u = 0.0
    for n in range(fld.degree + 1):
        for m in range(n + 1):
            norm = math.sqrt((1 if m == 0 else 2) * (2 * n + 1)
                             * math.factorial(n - m) / math.factorial(n + m))
            p = (-1) ** m * lpmv(m, n, sphi)  # remove the Condon-Shortley phase
            u += (R_REF / rn) ** n * norm * p * (fld.cbar[n, m] * math.cos(m * lam)
                                               + fld.sbar[n, m] * math.sin(m * lam))
    return fld.gm / rn * u


@pytest.fixture(scope="module")
def n15a():
    if not have_data_file("n15acoeff.tab"):
        pytest.skip("n15acoeff.tab not on IDEAS_HPC_DATA")
    return load_sh_field("n15acoeff.tab")


def test_sh_loader_reads_label(n15a):
    assert n15a.degree == 15
    assert n15a.r_ref == 16.0e3
    assert n15a.gm == pytest.approx(4.46275472004e-4 * 1e9, rel=1e-15)
    assert n15a.cbar[0, 0] == 1.0
    assert n15a.cbar[2, 0] == pytest.approx(-5.24618393097e-02, rel=1e-15)
    assert n15a.sbar[15, 15] == pytest.approx(-1.02266014805e-03, rel=1e-15)


def test_sh_full_field_vs_lpmv_and_finite_differences(n15a):
    c, s = hk.sh_unnormalise(n15a.cbar, n15a.sbar)
    sh = _sh(hk.sh_derivative_tables(c, s), n15a.gm, n15a.r_ref)
    for r in _points(6, 20e3, 160e3):
        u = sh(r)[0]
        assert u == pytest.approx(_sh_potential_lpmv(r, n15a), rel=1e-12)
        ea, eg, asym = _fd_check(sh, r, 1e-4 * np.linalg.norm(r))
        assert ea < 1e-6 and eg < 1e-5 and asym < 1e-12


def _write_tab(tmp_path, text, label=None):
    p = tmp_path / "field.tab"
    p.write_text(text)
    if label is not None:
        (tmp_path / "field.lbl").write_text(label)
    return p


ROWS = "    2    0 -5.2E-02  0.0E+00\n    2    2  8.2E-02 -2.8E-02\n"
LABEL = ("DESCRIPTION = \"\n   Reference Radius:  16.0km\n"
         "   Gravitational Constant, GM:   4.46E-04 km^3/s^2\n\"\n")


def test_sh_loader_header_and_label_variants(tmp_path):
    f = load_sh_field(_write_tab(tmp_path, ROWS, LABEL))
    assert (f.degree, f.r_ref, f.gm) == (2, 16e3, pytest.approx(4.46e5))
    f2 = load_sh_field(_write_tab(tmp_path, "16.0, 4.46E-04, 0.0, 2, 2, 1, 0, 0\n" + ROWS))
    assert (f2.r_ref, f2.gm) == (16e3, pytest.approx(4.46e5))


@pytest.mark.parametrize("text,label,field,line", [
    ("16.0, abc, 0.0, 2, 2, 1\n" + ROWS, None, "header", 1),       # bad header value
    ("16.0, 4.46E-04\n" + ROWS, None, "header", 1),                # short header
    ("-16.0, 4.46E-04, 0.0, 2, 2, 1\n" + ROWS, None, "header", 1),  # negative R_ref
    (ROWS, None, "label", None),                                   # no label, no header
    (ROWS, "DESCRIPTION = \"GM: 4.46E-04 km^3/s^2\"", "r_ref", None),
    (ROWS, "DESCRIPTION = \"Reference Radius: 16.0km\"", "gm", None),
    (ROWS + "    3    x  1.0E+00  0.0\n", LABEL, "row", 3),
    (ROWS + "    3    4  1.0E+00  0.0\n", LABEL, "row", 3),
    (ROWS + "    2    2  1.0E+00  0.0\n", LABEL, "row", 3),
    (ROWS + "    3    1  nan  0.0\n", LABEL, "row", 3),
])
def test_sh_loader_bad_input_names_file_and_line(tmp_path, text, label, field, line):
    p = _write_tab(tmp_path, text, label)
    with pytest.raises(InputError) as ei:
        load_sh_field(p)
    assert ei.value.field == field
    assert ei.value.file is not None and "field." in ei.value.file
    assert ei.value.line == line
    assert field in str(ei.value)


# ------------------------------------------------------------------ polyhedron


@pytest.fixture(scope="module")
def poly(eros1708):
    sh = eros1708.shape
    e, ed, fd = gk.polyhedron_precompute(sh.vertices_T, sh.faces)
    rho = eros1708.params.mass / sh.volume
    return eros1708, rho, (sh.vertices_T, sh.faces, e, ed, fd)


def _poly_eval(poly, r):
    body, rho, data = poly
    a = np.zeros(3)
    g = np.zeros((3, 3))
    u = gk.polyhedron_gravity(r, 6.67430e-11 * rho, *data, a, g)
    return u, a, g


def test_polyhedron_vs_polyhedral_gravity_package(poly):
    pg = pytest.importorskip("polyhedral_gravity")
    body, rho, data = poly
    sh = body.shape
    # exterior points: outside the bounding sphere, plus points just outside
    # vertices along their normals (inside the bounding sphere, close to the surface)
    pts = list(_points(80, 1.02 * sh.r_max, 12 * sh.r_max))
    idx = rng.choice(sh.n_vertices, 40, replace=False)
    pts += list(sh.vertices_T[idx] + 500.0 * sh.vertex_normals_T[idx])
    pts = np.array(pts)
    ref_poly = pg.Polyhedron((sh.vertices_T, sh.faces), rho,
                             integrity_check=pg.PolyhedronIntegrity.DISABLE)
    ref = pg.evaluate(ref_poly, pts, parallel=False)
    n_checked = 0
    for r, (u_ref, a_ref, g_ref) in zip(pts, ref):
        u, a, g = _poly_eval(poly, r)
        g_ref6 = np.array(g_ref)
        g6 = np.array([g[0, 0], g[1, 1], g[2, 2], g[0, 1], g[0, 2], g[1, 2]])
        assert u == pytest.approx(u_ref, rel=1e-9)
        assert np.linalg.norm(a - np.array(a_ref)) <= 1e-9 * np.linalg.norm(a_ref)
        # the gradient cancels large edge and face sums far away: 1e-7
        assert np.linalg.norm(g6 - g_ref6) <= 1e-7 * np.linalg.norm(g_ref6)
        n_checked += 1
    assert n_checked >= 100


def test_polyhedron_far_field_tends_to_point_mass(poly):
    body, rho, _ = poly
    mu = 6.67430e-11 * rho * body.shape.volume
    errs = []
    for scale in (10.0, 100.0, 1000.0):
        d = np.array([0.3, -0.5, 0.8])
        r = d / np.linalg.norm(d) * scale * body.shape.r_max
        u, a, g = _poly_eval(poly, r)
        a_pm = -mu * r / np.linalg.norm(r) ** 3
        errs.append(np.linalg.norm(a - a_pm) / np.linalg.norm(a_pm))
        assert u == pytest.approx(mu / np.linalg.norm(r), rel=2.0 / scale ** 2)
    # the deviation is the degree-2 term: falls like (R/r)^2 until the
    # cancellation floor of the edge/face sums (~5e-6 at 1000 R_max)
    assert errs[0] / errs[1] == pytest.approx(100.0, rel=0.1)
    assert errs[2] < 1e-5


def test_polyhedron_gradient_finite_differences_and_laplace(poly):
    for r in _points(3, 25e3, 60e3):
        ea, eg, asym = _fd_check(lambda x: _poly_eval(poly, x), r, 1.0)
        assert ea < 1e-6 and eg < 1e-6 and asym < 1e-12
        g = _poly_eval(poly, r)[2]
        assert abs(np.trace(g)) < 1e-9 * np.abs(g).max()  # Laplace outside the body
