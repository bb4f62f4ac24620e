"""Worlds of the target prior (SPEC 7f, issue 42): valid meshes, the same seed the same world.

Oracles: trimesh's own mesh checks (watertight, consistent winding, a volume), rays
cast from the star centre that must meet the surface exactly once (a brute-force
Moller-Trumbore test over every face), the constant-density centre of mass and volume
(the divergence theorem, written out here), the lognormal's mean and sd over many draws,
the orbit normal of paper Table 1 written out by hand, and a second Python process.
"""

from __future__ import annotations

import hashlib
import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from ideas_hpc.base import seeds
from ideas_hpc.body.random_sphere import ShapeFamily
from ideas_hpc.body.target_prior import SizeEstimate, eros_class_prior, known_prior

DEG = math.pi / 180.0


@pytest.fixture(scope="module")
def prior():
    return eros_class_prior()


def _rays_hit_once(v, f, centre, n_rays=60, seed=0):
    """Count each ray's crossings of the surface from ``centre`` (Moller-Trumbore, all faces)."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n_rays, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    a, b, c = v[f[:, 0]] - centre, v[f[:, 1]] - centre, v[f[:, 2]] - centre
    e1, e2 = b - a, c - a
    counts = []
    for ray in d:
        p = np.cross(ray, e2)
        det = np.einsum("ij,ij->i", e1, p)
        inv = 1.0 / det
        tvec = -a
        u = np.einsum("ij,ij->i", tvec, p) * inv
        q = np.cross(tvec, e1)
        w = (q @ ray) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 0)
        counts.append(int(hit.sum()))
    return np.array(counts)


def _volume_and_com(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    vol_t = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    return vol_t.sum(), (vol_t[:, None] * (a + b + c)).sum(axis=0) / (4.0 * vol_t.sum())


def _check_world(w):
    import trimesh

    v, f = w.shape.vertices_T, w.shape.faces
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume
    vol, com = _volume_and_com(v, f)
    assert vol > 0.0 and mesh.volume == pytest.approx(vol, rel=1e-9)
    r = (3.0 * vol / (4.0 * math.pi)) ** (1.0 / 3.0)
    assert 2.0 * r == pytest.approx(w.diameter_m, rel=1e-12)   # the stated size is the mesh's
    assert np.linalg.norm(com) < 1e-9 * r                      # origin of T at the centre of mass
    counts = _rays_hit_once(v, f, w.star_centre_T_m, seed=w.k)
    assert np.all(counts == 1), counts
    assert np.linalg.norm(w.pole_N) == pytest.approx(1.0, abs=1e-14)
    assert 0.0 <= w.phase_tca_rad < 2.0 * math.pi and w.spin_period_s > 0.0


def test_every_world_is_a_valid_closed_mesh(prior):
    for k in range(40):
        _check_world(prior.draw(1234, k))


def test_rough_worlds_stay_valid():
    rough = eros_class_prior(family=ShapeFamily(sigma=0.6, correlation_angle_rad=20.0 * DEG))
    for k in range(15):
        _check_world(rough.draw(7, k))


def test_same_seed_same_world_and_different_seeds_differ(prior):
    a, b = prior.draw(99, 3), eros_class_prior().draw(99, 3)
    assert np.array_equal(a.shape.vertices_T, b.shape.vertices_T)
    assert np.array_equal(a.pole_N, b.pole_N)
    assert (a.spin_period_s, a.phase_tca_rad, a.diameter_m) == \
           (b.spin_period_s, b.phase_tca_rad, b.diameter_m)
    for other in (prior.draw(99, 4), prior.draw(100, 3), prior.draw(99, 3, seeds.SCENARIO_STREAM)):
        assert not np.allclose(other.shape.vertices_T, a.shape.vertices_T)
        assert not np.allclose(other.pole_N, a.pole_N)


def test_a_world_is_the_same_in_another_process(prior):
    w = prior.draw(5, 17)
    code = ("import hashlib; from ideas_hpc.body.target_prior import eros_class_prior; "
            "w = eros_class_prior().draw(5, 17); "
            "print(hashlib.sha256(w.shape.vertices_T.tobytes() + w.pole_N.tobytes()).hexdigest())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == hashlib.sha256(w.shape.vertices_T.tobytes() + w.pole_N.tobytes()).hexdigest()


def test_parts_draw_from_independent_streams(prior):
    """A change to the pole's settings leaves every shape bit-identical."""
    from ideas_hpc.body.spin_prior import PoleEstimate

    other = replace(prior, pole=PoleEstimate(0.3, -0.2, 0.5, 0.5))
    a, b = prior.draw(3, 8), other.draw(3, 8)
    assert np.array_equal(a.shape.vertices_T, b.shape.vertices_T)
    assert a.spin_period_s == b.spin_period_s and not np.allclose(a.pole_N, b.pole_N)


def test_size_draws_are_lognormal_with_the_stated_mean_and_sd():
    est = SizeEstimate(16.0e3, 1.6e3)
    d = np.array([est.draw(seeds.world_rng(1, k, seeds.WORLD_SIZE), 16.0e3)
                  for k in range(20000)])
    assert abs(d.mean() - 16.0e3) < 4.0 * d.std() / math.sqrt(d.size)
    assert abs(d.std() / 1.6e3 - 1.0) < 0.03
    s2 = math.log1p(0.1 ** 2)
    z = (np.log(d) - (math.log(16.0e3) - 0.5 * s2)) / math.sqrt(s2)
    from scipy import stats
    assert stats.kstest(z, "norm").pvalue > 1e-3


def test_prior_world_sizes_follow_the_estimate(prior):
    d = np.array([prior.draw(21, k).diameter_m for k in range(150)])
    d0, sd = prior.diameter_m, prior.size.sigma_diameter_m
    assert abs(d.mean() - d0) < 4.0 * sd / math.sqrt(d.size)
    assert d0 == pytest.approx(2.0 * (17.0 * 5.6 * 5.4) ** (1 / 3) * 1e3, rel=1e-2)  # ellipsoid


def test_unperturbed_prior_is_the_stretched_icosphere():
    """sigma = 0 and no size spread: the built-in ellipsoid body's vertices, bit for bit."""
    from ideas_hpc.body.analytic import eros_ellipsoid

    flat = replace(eros_class_prior(), family=ShapeFamily(sigma=0.0), size=SizeEstimate())
    w = flat.draw(0, 0)
    want = eros_ellipsoid(3).vertices_T
    np.testing.assert_allclose(w.shape.vertices_T, want, rtol=0, atol=1e-9)


def test_known_body_is_one_case_of_the_prior():
    from ideas_hpc.body.bodies import load_body

    body = load_body("eros-ellipsoid")
    p = body.params
    t_tca = 300.0
    w = known_prior(body.shape, p, t_tca_s=t_tca).draw(11, 4)
    assert np.array_equal(w.shape.vertices_T, body.shape.vertices_T)
    assert np.array_equal(w.shape.faces, body.shape.faces)
    # paper Table 1 has no pole: the orbit normal (sin i sin RAAN, -sin i cos RAAN, cos i)
    i, raan = p.orbit_i, p.orbit_raan
    np.testing.assert_allclose(w.pole_N, [math.sin(i) * math.sin(raan),
                                          -math.sin(i) * math.cos(raan), math.cos(i)], atol=1e-12)
    assert w.spin_period_s == p.spin_period and not w.pole_mirrored
    assert w.phase_tca_rad == pytest.approx(
        (p.prime_meridian + 2.0 * math.pi * t_tca / p.spin_period) % (2 * math.pi), abs=1e-12)
    assert w.prime_meridian_rad(t_tca) == pytest.approx(p.prime_meridian % (2 * math.pi),
                                                        abs=1e-12)


def test_physical_params_of_a_world(prior):
    from ideas_hpc.body.params import get_params

    w = prior.draw(2, 2)
    base = get_params("eros")
    ref = math.pi / 6.0 * prior.diameter_m ** 3
    p = w.physical_params(base, 300.0, reference_volume_m3=ref)
    assert p.mu == pytest.approx(base.mu * (w.diameter_m / prior.diameter_m) ** 3, rel=1e-9)
    lon, lat = p.pole_ra, p.pole_dec
    np.testing.assert_allclose([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon),
                                math.sin(lat)], w.pole_N, atol=1e-12)
    assert p.spin_period == w.spin_period_s
    # degree 2 of the shape at constant density: a triaxial body's (2c^2 - a^2 - b^2)/10 is < 0
    assert p.c20 == pytest.approx(w.shape.mass_properties.c20_m2) and p.c20 < 0.0
    kept = w.physical_params(base, 300.0, degree2_from_shape=False)
    assert (kept.c20, kept.c22, kept.mu) == (base.c20, base.c22, base.mu)
    # W(t_tca) from the flight's t = 0 is the world's phase at TCA
    assert (p.prime_meridian + 2 * math.pi * 300.0 / p.spin_period) % (2 * math.pi) == \
        pytest.approx(w.phase_tca_rad, abs=1e-9)


def test_real_eros_as_the_nominal(eros1708):
    from ideas_hpc.body.target_prior import mesh_nominal

    prior = replace(eros_class_prior(), nominal=mesh_nominal(eros1708.shape),
                    size=SizeEstimate(None, 1.0e3))
    for k in range(5):
        _check_world(prior.draw(8, k))


def test_world_streams_are_the_documented_seed_sequences():
    for fam in (0, seeds.SCENARIO_STREAM):
        got = seeds.world_rng(42, 5, seeds.WORLD_POLE, fam).random(8)
        want = np.random.default_rng(np.random.SeedSequence(
            42, spawn_key=(seeds.WORLD_STREAM, fam, 5, seeds.WORLD_POLE))).random(8)
        assert np.array_equal(got, want)
    nav = np.random.default_rng(np.random.SeedSequence(
        42, spawn_key=(seeds.NAVIGATION_STREAM, 0, 5, 2))).random(8)
    assert np.array_equal(seeds.navigation_rng(42, 5, 2).random(8), nav)
    parts = [seeds.world_rng(42, 5, p).random(4) for p in range(4)]
    assert len({tuple(p) for p in parts}) == 4
    with pytest.raises(ValueError, match="purpose"):
        seeds.world_rng(42, 5, 9)


def test_gallery_figure(prior, tmp_path):
    from ideas_hpc.plots import figures
    from ideas_hpc.plots.prior import prior_gallery

    with figures.kept() as figs:
        path = prior_gallery([prior.draw(0, k) for k in range(3)], tmp_path / "g.png",
                             title="t")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    fig = figs["g.png"]
    titles = [ax.get_title() for ax in fig.axes]
    assert len(titles) == 3 and all(t.startswith(f"k = {i}:") for i, t in enumerate(titles))
