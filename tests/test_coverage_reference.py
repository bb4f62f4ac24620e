"""The coverage reference area (issue 42): the area lit at closest approach.

Oracles: the spherical cap ``2 pi R^2 (1 - cos i_max)`` (a sphere's area with Sun
incidence <= i_max; half the sphere at 90 deg), a brute-force per-vertex dot product and
a brute-force numpy Moller-Trumbore test against every face for cast shadows on a
non-convex body, and the designer's own coverage written out as a sum over vertices.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.body.analytic import sphere_mesh
from ideas_hpc.body.shape import build_shape
from ideas_hpc.design.api import CoverSettings, minimize
from ideas_hpc.design.bank import CandidateBank
from ideas_hpc.mapping.options import CoverageOptions
from ideas_hpc.mapping.reference import lit_at_tca, reference_weights
from ideas_hpc.mapping.requirement import Requirement, threshold_of

R = 1000.0
SUN = np.array([0.3, -0.5, 0.81])


def _lit_requirement(i_max_deg=None, **limits):
    lim = CoverageOptions(max_incidence_rad=None if i_max_deg is None
                          else math.radians(i_max_deg), **limits)
    return Requirement(eps_tol=0.0, limits=lim, reference="lit_at_tca")


@pytest.mark.parametrize("i_max", [None, 90.0, 60.0, 30.0])
def test_a_sphere_lit_fraction_is_the_spherical_cap(i_max):
    """Sum of the weights over the sphere's area = (1 - cos i_max) / 2, within the mesh's
    discretisation (an icosphere of 20 * 4^5 faces: the cap edge's vertex ring holds
    ~0.3 % of the area)."""
    shape = sphere_mesh(R, 5)
    w = reference_weights(shape, SUN, _lit_requirement(i_max))
    truth = (1.0 - math.cos(math.radians(90.0 if i_max is None else i_max))) / 2.0
    frac = w.sum() / shape.vertex_areas.sum()
    assert abs(frac - truth) < 4e-3, (frac, truth)
    # a convex body casts no shadow: the shadow test changes nothing
    assert np.array_equal(w > 0, lit_at_tca(shape, SUN, None if i_max is None
                                            else math.radians(i_max), shadows=True))


def test_membership_is_the_per_vertex_incidence_test():
    """Brute force: n_v . s / |s| against cos i_max, vertex by vertex in plain Python."""
    shape = sphere_mesh(R, 3)
    i_max = math.radians(50.0)
    w = reference_weights(shape, 7.0 * SUN, _lit_requirement(50.0))
    s = SUN / math.sqrt(sum(x * x for x in SUN))
    for v in range(shape.n_vertices):
        n = shape.vertex_normals_T[v]
        c = sum(float(n[k]) * float(s[k]) for k in range(3))
        lit = c > 0.0 and c >= math.cos(i_max)
        assert w[v] == (shape.vertex_areas[v] if lit else 0.0)


def _bumpy_shape():
    """A star-shaped, non-convex body: an icosphere with radius 1 + 0.35 * (bumps)."""
    base = sphere_mesh(1.0, 3)
    u = base.vertices_T / np.linalg.norm(base.vertices_T, axis=1, keepdims=True)
    r = R * (1.0 + 0.35 * np.cos(3.0 * np.arctan2(u[:, 1], u[:, 0])) * (1 - u[:, 2] ** 2))
    return build_shape(u * r[:, None], base.faces, name="bumpy", source="test")


def _shadowed_brute_force(shape, s):
    """(V,) bool: a segment from each vertex toward ``s`` crosses a face not touching
    the vertex (numpy Moller-Trumbore against every face)."""
    p, f = shape.vertices_T, shape.faces
    a, b, c = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
    e1, e2 = b - a, c - a
    h = np.cross(s, e2)
    det = np.einsum("ij,ij->i", e1, h)
    out = np.zeros(p.shape[0], dtype=bool)
    for v in range(p.shape[0]):
        ok = (np.abs(det) > 1e-12) & ~np.any(f == v, axis=1)
        t_vec = p[v] - a
        uu = np.einsum("ij,ij->i", t_vec, h) / np.where(ok, det, 1.0)
        q = np.cross(t_vec, e1)
        vv = (q @ s) / np.where(ok, det, 1.0)
        t = np.einsum("ij,ij->i", e2, q) / np.where(ok, det, 1.0)
        out[v] = np.any(ok & (uu >= 0) & (vv >= 0) & (uu + vv <= 1) & (t > 1e-6))
    return out


def test_cast_shadows_match_a_brute_force_ray_test():
    shape = _bumpy_shape()
    s = np.array([1.0, 0.2, 0.05])
    s = s / np.linalg.norm(s)
    facing = shape.vertex_normals_T @ s > 0.0
    truth = facing & ~_shadowed_brute_force(shape, s)
    got = lit_at_tca(shape, s, None, shadows=True)
    assert (facing & ~truth).sum() > 5          # the body does cast shadows
    # vertices whose ray grazes a face edge may go either way: allow a handful
    assert (got != truth).sum() <= 2, np.flatnonzero(got != truth)
    # the requirement casts them when the coverage reads the Sun (require_lit)
    w = reference_weights(shape, s, _lit_requirement(None, require_lit=True))
    assert np.array_equal(w > 0, got)
    w0 = reference_weights(shape, s, _lit_requirement(None))   # geometric coverage: none
    assert np.array_equal(w0 > 0, facing)


def test_surface_reference_is_the_vertex_areas_bit_for_bit():
    shape = sphere_mesh(R, 2)
    w = reference_weights(shape, None, Requirement(eps_tol=0.01))
    assert w.dtype == np.float64 and np.array_equal(w, shape.vertex_areas)


def test_bad_sun_and_empty_reference_name_their_field():
    shape = sphere_mesh(R, 2)
    with pytest.raises(InputError) as ei:
        reference_weights(shape, [0.0, 0.0, 0.0], _lit_requirement(None))
    assert ei.value.field == "sun_T"
    with pytest.raises(InputError) as ei:
        Requirement(eps_tol=0.0, reference="lit")
    assert ei.value.field == "reference"


def test_a_swarm_mapping_exactly_the_lit_vertices_covers_the_reference():
    """Candidate 0 maps exactly the lit vertices, candidate 1 everything else, candidate 2
    half the lit ones: on the lit reference candidate 0 alone reaches 100 %, candidate 1
    0 %; on the whole surface candidate 0 is the lit share only."""
    shape = sphere_mesh(R, 3)
    w = reference_weights(shape, SUN, _lit_requirement(70.0))
    lit = w > 0
    half = lit & (np.arange(lit.size) % 2 == 0)
    masks = np.stack([lit, ~lit, half])
    bank = CandidateBank(theta=np.array([0.0, 2.0, 4.0]), masks=masks, areas=w,
                         step_rad=2.0, d_sep_m=1.0)
    cov = bank.coverage([[0], [1], [2]])
    assert cov[0] == pytest.approx(1.0, abs=1e-12) and cov[1] == 0.0
    assert cov[2] == pytest.approx(w[half].sum() / w.sum(), rel=1e-12)
    res = minimize(bank, CoverSettings(threshold=threshold_of(1.0, 0.0), n_max=3))
    assert res.n == 1 and list(res.indices) == [0]
    whole = CandidateBank(theta=bank.theta, masks=masks, areas=shape.vertex_areas,
                          step_rad=2.0, d_sep_m=1.0)
    assert whole.coverage([[0]])[0] == pytest.approx(
        shape.vertex_areas[lit].sum() / shape.vertex_areas.sum(), rel=1e-12)


def test_the_requirement_states_its_kind_and_reference():
    geo = Requirement(eps_tol=0.01)
    assert geo.kind == "geometric"
    assert geo.label == "geometric (thermal, the paper's) map of the whole surface"
    vis = Requirement(eps_tol=0.01, reference="lit_at_tca", limits=CoverageOptions(
        require_lit=True, max_incidence_rad=math.radians(60), max_emission_rad=math.radians(70),
        max_resolution_m=5.0))
    assert vis.kind == "visual"
    assert vis.label == ("visual (lit, incidence <= 60 deg, emission <= 70 deg, GSD <= 5 m) "
                         "map of the area lit at closest approach")
