"""Observation-quality pass (issue 14): sphere closed forms, the exact stereo test
against all pairs, options, stores, reports and the arrival scan. The eros001708
brute force, trimesh shadows and cone query are in test_quality_eros.py."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ideas_hpc.body.analytic import sphere_mesh
from ideas_hpc.core.mapping import quality as cq
from ideas_hpc.campaign.schema.model_fields import COVERAGE_FIELDS
from ideas_hpc.mapping.options import coverage_options_from_config
from ideas_hpc.base.errors import InputError, config_fields
from ideas_hpc.mapping.coverage import compute_coverage
from ideas_hpc.mapping.options import CoverageOptions
from test_coverage import look_at

DEG = math.pi / 180.0
LAM, APER = 0.55e-6, 0.08


# ---------------------------------------------------------------- sphere, closed forms

@pytest.fixture(scope="module")
def pole_sphere():
    """Sphere R = 1000 m with a vertex exactly at +z, vertices exactly on the sphere
    (to rounding) and exact radial normals."""
    R = 1000.0
    s = sphere_mesh(R, 4)
    v = s.vertices_T / np.linalg.norm(s.vertices_T, axis=1)[:, None]
    j0 = int(np.argmax(v[:, 2]))
    # rotation taking v[j0] to +z (Rodrigues)
    a = v[j0]
    axis = np.cross(a, [0.0, 0.0, 1.0])
    sa = np.linalg.norm(axis)
    if sa > 0.0:
        k = axis / sa
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        rot = np.eye(3) + sa * K + (1 - a[2]) * K @ K
        v = v @ rot.T
    v /= np.linalg.norm(v, axis=1)[:, None]
    v[j0] = [0.0, 0.0, 1.0]
    shape = dataclasses.replace(s, vertices_T=R * v, vertex_normals_T=v.copy())
    return shape, R, j0


def test_sphere_closed_forms(pole_sphere):
    shape, R, j0 = pole_sphere
    d = 5.0 * R
    r = np.array([[[0.0, 0.0, d]]])
    C = look_at(r[0, 0])[None, None]
    eta = math.asin(R / d) + 0.05
    sun = np.array([[1.0, 0.0, 0.0]])
    opts = CoverageOptions(mode="exact", occlusion=True, quality=True)
    res = compute_coverage(shape, r, C, np.zeros(1), eta, 1e-4, 1e7, options=opts, sun_T=sun)
    q = res.quality
    u = shape.vertices_T / R
    x, y, z = u.T
    cosg = z
    sing = np.hypot(x, y)
    vis = d * cosg - R > 0.0
    firm = np.abs(cosg - R / d) > 1e-9
    np.testing.assert_array_equal(res.observed[firm], vis[firm])
    o = res.observed
    assert o.sum() > 100
    rng2 = d * d + R * R - 2 * d * R * cosg
    emi = np.arctan2(d * sing, d * cosg - R)                 # law of sines / cosines
    inc = np.arctan2(np.hypot(y, z), x)                      # Sun along +x
    pha = np.arctan2(np.hypot(R * y, d - R * z), -R * x)     # l = (-R x, -R y, d - R z)
    res_cf = LAM / APER * rng2 / (d * cosg - R)              # rho |l| / cos(e)
    np.testing.assert_allclose(q.emission_at_best[o], emi[o], rtol=0, atol=1e-12)
    np.testing.assert_allclose(q.incidence_at_best[o], inc[o], rtol=0, atol=1e-12)
    np.testing.assert_allclose(q.phase_at_best[o], pha[o], rtol=0, atol=1e-12)
    np.testing.assert_allclose(q.best_resolution[o], res_cf[o], rtol=1e-12)
    # sub-spacecraft point: lambda (d - R) / D
    assert abs(q.best_resolution[j0] / (LAM * (d - R) / APER) - 1.0) < 1e-12
    assert q.emission_at_best[j0] < 1e-12
    # lit hemisphere x > 0 (convex: no cast shadows; the polyhedron's faces tilt
    # by about half an edge, 0.04 rad, so the terminator band is left out)
    band = np.abs(x) > 0.06
    np.testing.assert_array_equal(q.lit[o & band], (x > 0)[o & band])
    assert np.all(np.isnan(q.best_resolution[~o])) and not q.lit[~o].any()
    np.testing.assert_array_equal(q.n_spacecraft_seen, o.astype(np.int32))
    assert not q.stereo.any()                                # a single observation
    assert res.coverage == res.coverage_seen


def test_sphere_stereo_two_spacecraft(pole_sphere):
    """Two distant spacecraft 25 deg apart about the sub-point: stereo only where the
    convergence angle at the vertex is in [10, 40] deg (checked pairwise)."""
    shape, R, j0 = pole_sphere
    d = 1e3 * R
    dirs = [np.array([math.sin(a), 0.0, math.cos(a)]) for a in (-12.5 * DEG, 12.5 * DEG)]
    r = np.array([[d * u] for u in dirs])
    C = np.array([[look_at(ri[0])] for ri in r])
    eta = math.asin(R / d) + 1e-3
    opts = CoverageOptions(mode="exact", quality=True)
    res = compute_coverage(shape, r, C, np.zeros(1), eta, 1.0, 1e9, options=opts,
                           sun_T=np.array([[0.0, 0.0, 1.0]]))
    p = shape.vertices_T
    l1 = r[0, 0] - p
    l2 = r[1, 0] - p
    ang = np.arctan2(np.linalg.norm(np.cross(l1, l2), axis=1), (l1 * l2).sum(1))
    both = res.quality.n_spacecraft_seen == 2
    assert both.sum() > 100
    np.testing.assert_array_equal(res.quality.stereo, both & (ang >= 10 * DEG) & (ang <= 40 * DEG))
    assert res.quality.stereo[j0]


# ---------------------------------------------------------------- exact stereo vs all pairs

def _pairwise(U, smin, smax):
    G = U[:, 0][:, None] * U[:, 0][None] + U[:, 1][:, None] * U[:, 1][None] \
        + U[:, 2][:, None] * U[:, 2][None]
    iu = np.triu_indices(len(U), 1)
    g = G[iu]
    return bool(np.any((math.cos(smax) <= g) & (g <= math.cos(smin))))


def _stereo(U, smin, smax):
    m = len(U)
    mm = max(m, 1)
    return cq._stereo(np.ascontiguousarray(U), m, smin, smax, np.empty(mm, np.int64),
                      np.empty((mm, 3)), np.empty(mm), np.empty(mm, np.int64),
                      np.empty(mm + 1, np.int64), np.empty(mm, np.int64),
                      np.empty(mm, np.int64))


@pytest.mark.parametrize("seed", range(80))
def test_stereo_caps_equal_pairwise(seed):
    rng = np.random.default_rng(seed)
    smin, smax = sorted(rng.uniform(0.5, 60.0, 2) * DEG)
    kind = seed % 4
    if kind == 0:      # scattered directions in a cone
        U = rng.normal(size=(rng.integers(1, 300), 3)) * [0.3, 0.3, 1.0] + [0, 0, 1]
    elif kind == 1:    # tracks (dense arcs) from a few spacecraft
        parts = []
        for _ in range(rng.integers(1, 5)):
            a0 = rng.uniform(-1, 1, 2)
            t = np.linspace(0, rng.uniform(0, 0.3), rng.integers(2, 200))[:, None]
            v = rng.normal(size=2) * 0.3
            parts.append(np.c_[a0 + t * v, np.ones_like(t)])
        U = np.concatenate(parts)
    elif kind == 2:    # a pair just inside / outside a bound, plus a cluster on its arc
        eps = 10.0 ** rng.uniform(-9, -4)
        at_min = bool(rng.integers(2))
        inside = bool(rng.integers(2))
        bound = smin if at_min else smax
        ang = bound + (eps if inside == at_min else -eps)
        # cluster members (on the same great circle) move the pair further outside
        push = 1.0 if at_min else -1.0
        d = push * np.abs(rng.normal(size=rng.integers(0, 30))) * 1e-3
        a = np.r_[0.0, ang, d if not inside else d * 0.0]
        U = np.c_[np.sin(a), np.zeros_like(a), np.cos(a)]
    else:              # a narrow cluster of diameter close to smin
        U = rng.normal(size=(rng.integers(2, 400), 3)) * [smin / 4, smin / 4, 0] + [0, 0, 1]
    U = U / np.linalg.norm(U, axis=1)[:, None]
    assert _stereo(U, smin, smax) == _pairwise(U, smin, smax)


# ---------------------------------------------------------------- boundary

def test_paper_mode_takes_the_old_path(eros1708):
    """No quality option: no quality pass, coverage_seen == coverage."""
    from test_coverage import paper_case

    r, C, t = paper_case(301)
    res = compute_coverage(eros1708.shape, r, C, t, math.radians(3.827), 1e-4, 166.347e3)
    assert res.quality is None and res.coverage_seen == res.coverage


def test_requirement_config_keys():
    o = coverage_options_from_config({"require_lit": True, "max_resolution_m": 2.0,
                                      "max_emission_deg": 60, "max_incidence_deg": 70,
                                      "max_phase_deg": 120, "require_stereo": True,
                                      "stereo_min_deg": 12, "stereo_max_deg": 35,
                                      "pixel_pitch_um": 7, "focal_length_mm": 500})
    assert o.requirement and o.wants_quality and o.needs_sun
    np.testing.assert_allclose(o.limits, [2.0, 60 * DEG, 70 * DEG, 120 * DEG, 12 * DEG,
                                          35 * DEG])
    assert o.rho == pytest.approx(7e-6 / 0.5)
    assert not coverage_options_from_config({}).wants_quality
    assert coverage_options_from_config({}).rho == LAM / APER
    for table, field in [({"require_lit": 1}, "coverage.require_lit"),
                         ({"max_emission_deg": 0}, "coverage.max_emission_deg"),
                         ({"max_resolution_m": -1}, "coverage.max_resolution_m"),
                         ({"stereo_min_deg": 50}, "coverage.stereo_min_deg"),
                         ({"pixel_pitch_um": 7}, "coverage.focal_length_mm")]:
        with pytest.raises(InputError) as ei, config_fields(COVERAGE_FIELDS):  # as the campaign
            coverage_options_from_config(table)
        assert ei.value.field == field, (table, ei.value.field)


def test_quality_needs_sun(eros1708):
    from test_coverage import paper_case

    r, C, t = paper_case(11)
    with pytest.raises(InputError) as ei:
        compute_coverage(eros1708.shape, r, C, t, 0.07, 1e-4, 1e6,
                         options=CoverageOptions(quality=True))
    assert ei.value.field == "sun_T"


# ---------------------------------------------------------------- stores

REQ = ["coverage.mode=\"exact\"", "coverage.occlusion=true", "coverage.require_lit=true",
       "coverage.max_emission_deg=70.0", "coverage.require_stereo=true",
       "coverage.stereo_min_deg=0.5"]


@pytest.mark.slow
def test_quality_in_flyby_and_mc_stores(tmp_path):
    """Monte Carlo (6 samples) and flyby stores on the ellipsoid carry the quality
    variables with units (~1-2 min: slow)."""
    import xarray as xr

    from ideas_hpc.mapping.coverage import QUALITY_VARS
    from ideas_hpc.campaign.run import run_file
    from test_campaign_mc import MC, SHORT

    out = run_file(MC, out=tmp_path / "mc.zarr", overrides=SHORT + REQ, workers=1,
                   progress=False)
    ds = xr.open_zarr(out)
    a = ds["vertex_area"].values
    for name in QUALITY_VARS:
        assert ds[name].dims == ("sample", "vertex"), name
        assert "units" in ds[name].attrs, name
    assert ds["best_resolution"].attrs["units"] == "m"
    assert ds["emission_at_best"].attrs["units"] == "rad"
    mapped = ds["mapped"].values
    np.testing.assert_allclose(ds["coverage"].values, (mapped * a).sum(1) / a.sum(), rtol=1e-12)
    np.testing.assert_allclose(ds["coverage_seen"].values,
                               (ds["observed"].values * a).sum(1) / a.sum(), rtol=1e-12)
    assert np.all(ds["coverage"].values <= ds["coverage_seen"].values)
    assert not np.any(mapped & ~ds["stereo"].values)
    fb = ROOT_CAMPAIGNS / "eros-flyby.toml"
    short = [s for s in SHORT if not s.startswith(("monte_carlo", "run."))]
    out = run_file(fb, out=tmp_path / "fb.zarr", overrides=short + REQ, workers=1,
                   progress=False)
    ds = xr.open_zarr(out)
    for name in QUALITY_VARS:
        assert ds[name].dims == ("vertex",), name
    assert float(ds["coverage"]) <= float(ds["coverage_seen"])
    from ideas_hpc.report.write import write_report

    for store in (tmp_path / "mc.zarr", tmp_path / "fb.zarr"):
        rep = write_report(store, tmp_path / (store.stem + "-report"))
        names = {f.name for f in rep.parent.iterdir()}
        for name in ("best_resolution", "emission_at_best", "incidence_at_best",
                     "n_spacecraft_seen", "stereo", "histograms"):
            assert f"quality_{name}.png" in names, (store, name)


ROOT_CAMPAIGNS = __import__("pathlib").Path(__file__).resolve().parent.parent / "campaigns"


def test_design_campaigns_take_a_requirement_and_refuse_stereo_they_cannot_score():
    from ideas_hpc.campaign.schema.campaign_tables import load

    path = ROOT_CAMPAIGNS / "eros-nadir-ga.toml"
    load(path, ["body.name=\"ellipsoid\"", "coverage.require_lit=true"])   # unions: fine
    with pytest.raises(InputError) as ei:   # the GA's 0.01 rad grid: too many pairs
        load(path, ["body.name=\"ellipsoid\"", "coverage.require_stereo=true"])
    assert ei.value.field == "design.angle_step_deg"   # one key for every designer's grid
    load(path, ["body.name=\"ellipsoid\"", "coverage.require_stereo=true",
                "design.angle_step_deg=4"])
    with pytest.raises(InputError) as ei:
        load(ROOT_CAMPAIGNS / "eros-fov-ga.toml", ["body.name=\"ellipsoid\"",
                                                  "coverage.require_stereo=true"])
    assert ei.value.field == "coverage.require_stereo"
    exact = ROOT_CAMPAIGNS / "eros-design-nominal.toml"
    load(exact, ["body.name=\"ellipsoid\"", "coverage.require_stereo=true",
                 "design.angle_step_deg=4"])
    with pytest.raises(InputError) as ei:
        load(exact, ["body.name=\"ellipsoid\"", "coverage.require_stereo=true"])
    assert ei.value.field == "design.angle_step_deg"


# ---------------------------------------------------------------- arrival epoch scan

def test_arrival_scan_matches_flybys_at_each_epoch():
    from ideas_hpc.campaign.scan import arrival_scan
    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.flyby.flight import fly
    from ideas_hpc.campaign.setup import setup_from_campaign

    sets = ["body.name=\"ellipsoid\"", "flyby.tf_s=60", "flyby.z_start_km=-3",
            "flyby.z_stop_km=3", "coverage.mode=\"exact\"", "coverage.require_lit=true",
            "swarm.angles_rad=[0.2, 1.7]", "flyby.epoch_s=1000.0"]
    c = load(ROOT_CAMPAIGNS / "eros-flyby.toml", sets)
    setup = setup_from_campaign(c)
    assert setup.epoch_s == 1000.0
    period = 2 * math.pi / setup.body.params.spin_rate
    epochs = setup.epoch_s + period * np.array([0.0, 0.25, 0.5, 0.75, 1.0])
    ds = arrival_scan(setup, [0.2, 1.7], None, epochs)
    for m in (0, 2):
        direct = fly(setup.with_(epoch_s=float(epochs[m])), [0.2, 1.7])
        assert ds["coverage"].values[m] == direct.coverage.coverage
        assert ds["coverage_seen"].values[m] == direct.coverage.coverage_seen
    cov = ds["coverage"].values
    assert cov.max() - cov.min() > 0.05          # the arrival epoch matters here
    assert abs(cov[4] - cov[0]) < 0.02            # one rotation later: about the same
    assert ds["epoch"].attrs["units"] == "s" and ds["sun_longitude"].attrs["units"] == "rad"


def test_value_map_renders(tmp_path):
    from ideas_hpc.plots.coverage_map import render_coverage_map

    s = sphere_mesh(1000.0, 2)
    x = s.vertices_T[:, 2].copy()
    x[:10] = np.nan
    out = render_coverage_map(s, x, tmp_path / "v.png", kind="value", label="z, m")
    assert out.stat().st_size > 10_000
