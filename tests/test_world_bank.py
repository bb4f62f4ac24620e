"""The world bank (issue 43): rows of drawn worlds from per-world statics, identical to
full recomputation (:mod:`ideas_hpc.mapping.world_rows`,
:mod:`ideas_hpc.core.mapping.world_rows`, :mod:`ideas_hpc.core.mapping.world_statics`,
:mod:`ideas_hpc.core.mapping.pass_tree`)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from ideas_hpc.base import seeds
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.core.mapping import pass_tree as pt
from ideas_hpc.core.mapping import world_statics as ws
from ideas_hpc.core.mapping.segments import segments_blocked
from ideas_hpc.design.candidates import rows_from_views
from ideas_hpc.flyby.flight import Perturbation
from ideas_hpc.flyby.views import flight_views
from ideas_hpc.mapping.coverage import (camera_record, check_geometry, mesh_record,
                                        occlusion_structure)
from ideas_hpc.mapping.world_rows import rows_of_world, world_statics
from ideas_hpc.montecarlo.scenario_rows import full_rows_of
from ideas_hpc.montecarlo.scenarios import (build_scenario_bank, draw_world, grid_theta,
                                            row_engine)
from ideas_hpc.flyby.target_world import scenario_world

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-class-flyby.toml"
STEP = np.deg2rad(6.0)          # 60 candidates
SEED = 2026


def _flight(setup, mc, theta, k, engine=None):
    """World ``k`` of the bank's stream and the flight of every candidate through it."""
    engine = engine or row_engine(setup, theta, mc, SEED, seeds.SCENARIO_STREAM)
    pert = Perturbation(**draw_world(mc, setup, theta, SEED, seeds.SCENARIO_STREAM, k))
    world = scenario_world(setup, SEED, seeds.SCENARIO_STREAM, k, pert.params_override)
    r, d = engine.flight(pert, False, world)
    return engine, world, r, d


@pytest.fixture(scope="module")
def drawn():
    c = load(CAMPAIGN)
    return c, setup_from_campaign(c)


@pytest.fixture(scope="module")
def rough():
    """A rougher prior (sigma_r 0.6): concave places, shadows and horizons."""
    c = load(CAMPAIGN, ["target.sigma_r=0.6"])
    setup = setup_from_campaign(c)
    theta = grid_theta(STEP)
    engine, world, r, d = _flight(setup, c.config.monte_carlo, theta, 1)
    return setup, world, r, d


def test_world_bank_rows_are_full_recomputations(drawn):
    # the campaign's navigation, body tracking and lit requirement; oracle: today's full
    # recomputation (the quality pass over every observation) of the same flights
    c, setup = drawn
    mc = c.config.monte_carlo
    theta = grid_theta(STEP)
    assert setup.coverage.requirement and setup.coverage.require_lit
    engine = None
    rows = []
    for k in range(4):
        engine, world, r, d = _flight(setup, mc, theta, k, engine)
        got = engine.rows(r, d, world=world)
        want = full_rows_of(setup, world, r, d)
        np.testing.assert_array_equal(got, want)
        assert 0 < want.sum() < want.size
        rows.append(got)
    assert not np.array_equal(rows[0], rows[1])
    # and the bank as built (its chunks, its reused flight buffers)
    bank = build_scenario_bank(setup, STEP, mc, seed=SEED, n_scenarios=2, progress=False,
                               chunk_size=2)
    np.testing.assert_array_equal(bank.rows, np.stack(rows[:2]))


_VARIANTS = {
    "every limit, illumination a filter": dict(
        illumination=True, require_lit=True, max_emission_rad=math.radians(60.0),
        max_incidence_rad=math.radians(70.0), max_phase_rad=math.radians(100.0),
        max_resolution_m=8.0),
    "no occlusion": dict(occlusion=False),
    "paper culling": dict(mode="paper"),
    "stereo": dict(require_stereo=True),
    "seen rows (no requirement)": dict(require_lit=False),
}


@pytest.mark.parametrize("name", list(_VARIANTS))
def test_rows_of_a_world_match_the_quality_pass_under_every_option(rough, name):
    setup, world, r, d = rough
    options = dataclasses.replace(setup.coverage, **_VARIANTS[name])
    flown = dataclasses.replace(world.flown(setup), coverage=options)
    sun = world.sun_at_images(flown)
    want = rows_from_views(flown, r, d, sun)
    st = world_statics(world.shape, options, sun, r.shape[1])
    got = rows_of_world(st, options, r, d, setup.image_times,
                        (setup.eta_rad, setup.near_m, setup.far_m))
    np.testing.assert_array_equal(got, want)
    assert 0 < want.sum() < want.size


def test_lighting_table_is_the_shadow_ray_test(rough):
    # a low Sun sweeping across a rough body: 20-odd runs of several images each, shadow
    # edges inside runs; oracle: the exact ray test image by image
    setup, world, _, _ = rough
    shape = world.shape
    tree = occlusion_structure(shape)
    ang = np.radians(np.linspace(-12.0, 12.0, 241))
    sun = np.stack([np.cos(ang) * 0.2, np.sin(ang) * 0.2, np.full_like(ang, 0.3)], axis=1)
    sun = np.ascontiguousarray(sun / np.linalg.norm(sun, axis=1)[:, None])
    lit = ws.lit_at_images(mesh_record(shape), sun, tree)
    v, n = shape.vertices_T, shape.vertex_normals_T
    nv, ni = v.shape[0], sun.shape[0]
    origins = np.repeat(v, ni, axis=0)
    far = origins + 1e9 * np.tile(sun, (nv, 1))
    blocked = segments_blocked(*tree, origins, far, np.repeat(np.arange(nv), ni))
    facing = (n @ sun.T) > 0.0
    want = facing & ~blocked.reshape(nv, ni)
    np.testing.assert_array_equal(lit, want)
    start, _, half = ws.sun_runs(sun, ws.SUN_CONE_MAX)
    assert start.size > 15 and np.diff(start).min() > 2 and half.max() <= ws.SUN_CONE_MAX
    shade = facing & ~want
    edges = sum(int((shade[:, a:b].any(axis=1) & ~shade[:, a:b].all(axis=1)).sum())
                for a, b in zip(start[:-1], start[1:]))
    assert edges >= 10, "shadow edges must fall inside runs"


def test_clear_cones_hold_no_blocked_sight_line(rough):
    # oracle: the exact segment test along sight lines on each clear cone's rim (just
    # inside), and some cones narrowed by the rough body's horizons
    setup, world, _, _ = rough
    shape = world.shape
    tree = occlusion_structure(shape)
    cos_c = ws.clear_cones(mesh_record(shape), tree, ws.THETA_CAP)
    v, n = shape.vertices_T, shape.vertex_normals_T
    used = cos_c < 2.0
    theta = np.arccos(np.minimum(cos_c[used], 1.0))
    assert used.mean() > 0.9 and (theta < ws.THETA_CAP - 0.1).sum() > 20
    rng = np.random.default_rng(3)
    j = np.flatnonzero(used)
    reps = 32
    jj = np.repeat(j, reps)
    th = np.repeat(theta, reps) * (1.0 - 1e-6)
    nrm = n[jj]
    a = rng.normal(size=nrm.shape)
    a -= (a * nrm).sum(axis=1)[:, None] * nrm
    a /= np.linalg.norm(a, axis=1)[:, None]
    dirs = np.cos(th)[:, None] * nrm + np.sin(th)[:, None] * a
    blocked = segments_blocked(*tree, v[jj], v[jj] + 2e5 * dirs, jj)
    assert not blocked.any()
    # and wider cones than these are blocked somewhere (the cones are not just small)
    wide = np.cos(np.minimum(np.repeat(theta, reps) * 1.3 + 0.05, 1.55))[:, None] * nrm \
        + np.sin(np.minimum(np.repeat(theta, reps) * 1.3 + 0.05, 1.55))[:, None] * a
    assert segments_blocked(*tree, v[jj], v[jj] + 2e5 * wide, jj).any()


@njit
def _rejections(tree, runs, k, r, v, n, cam):
    out = np.zeros((runs.shape[0], v.shape[0]), dtype=np.bool_)
    for dn in range(runs.shape[0]):
        if runs[dn, 0] < 0:
            continue
        for j in range(v.shape[0]):
            out[dn, j] = pt.run_rejected(tree, runs, k, dn, r, v[j, 0], v[j, 1], v[j, 2],
                                         n[j, 0], n[j, 1], n[j, 2], cam)
    return out


def test_pass_tree_rejects_only_runs_that_no_image_sees(rough):
    # oracle: culling, clipping and the field of view image by image (numpy)
    setup, world, r_all, d_all = rough
    shape = world.shape
    r, c, tan_eta, near, far, _ = check_geometry(shape, r_all[::7], d_all[::7], setup.eta_rad,
                                                 setup.near_m, setup.far_m)
    cam = camera_record(r, c, np.asarray(setup.image_times, float), tan_eta, near, far, True)
    runs = pt.pass_runs(r.shape[1])
    tree = pt.pass_tree(r, c, runs)
    v = np.ascontiguousarray(shape.vertices_T, dtype=np.float64)
    n = np.ascontiguousarray(shape.vertex_normals_T, dtype=np.float64)
    n_rejected = n_nodes = 0
    for k in range(r.shape[0]):
        dvec = v[:, None, :] - r[k][None, :, :]                      # (V, I, 3)
        q = np.einsum("iab,vib->via", c[k], dvec)
        sees = ((-(dvec * n[:, None, :]).sum(axis=2) > 0.0) & (q[..., 2] > 0.0)
                & (q[..., 2] >= near) & (q[..., 2] <= far)
                & (np.abs(q[..., 0]) <= tan_eta * q[..., 2])
                & (np.abs(q[..., 1]) <= tan_eta * q[..., 2]))
        rej = _rejections(tree, runs, k, r, v, n, cam)
        for dn in range(runs.shape[0]):
            a, b = runs[dn]
            if a < 0:
                continue
            assert not (rej[dn][:, None] & sees[:, a:b]).any(), (k, dn)
            n_rejected += int(rej[dn].sum())
            n_nodes += v.shape[0]
    assert n_rejected > 0.3 * n_nodes


def test_the_bank_blinds_the_images_a_whole_flight_blinds():
    # perfect tracking on an encounter faces the smear test (issue 42): in 2 ms
    # the body-tracking parallax near closest approach blinds some images; the bank's
    # flight (reused buffers) and the flyby pipeline's whole flight (time series kept) blind
    # the same ones, and the bank's rows are the full recomputation's
    c = load(CAMPAIGN, ["instrument.exposure_ms=2.0"])
    setup = setup_from_campaign(c)
    mc = c.config.monte_carlo
    theta = grid_theta(np.deg2rad(30.0))
    engine = row_engine(setup, theta, mc, SEED, seeds.SCENARIO_STREAM)
    for k in range(2):
        pert = Perturbation(**draw_world(mc, setup, theta, SEED, seeds.SCENARIO_STREAM, k))
        world = scenario_world(setup, SEED, seeds.SCENARIO_STREAM, k, pert.params_override)
        r, d = engine.flight(pert, True, world)
        full = flight_views(setup, theta, None, engine.r0_T, engine.v0_T, pert, world=world)
        np.testing.assert_array_equal(r, full.r_img_T)
        np.testing.assert_array_equal(d, full.imaging_BT)
        blinded = ~np.all(full.imaging_BT == full.dcm_BT, axis=(-2, -1))
        assert blinded.any() and not blinded.all()
        np.testing.assert_array_equal(engine.rows(r, d, world=world),
                                      full_rows_of(setup, world, full.r_img_T, full.imaging_BT))
