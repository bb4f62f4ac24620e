"""One world per scenario, drawn from the target prior (issue 42, SPEC 7f;
:mod:`ideas_hpc.flyby.target_world`, the ``[target]`` table)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base import seeds
from ideas_hpc.base.errors import InputError
from ideas_hpc.body.target_prior import eros_class_prior
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.flyby.flight import Perturbation, fly_open_loop
from ideas_hpc.flyby.target_world import drawn_world, placed_world
from ideas_hpc.montecarlo.scenarios import (build_scenario_bank, draw_world, flight_areas,
                                            fly_members, nominal_start, shaping_config)

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-class-flyby.toml"
FAST = ROOT / "campaigns" / "eros-fast-encounter.toml"
STEP = np.deg2rad(30.0)


@pytest.fixture(scope="module")
def drawn():
    c = load(CAMPAIGN)
    return c, setup_from_campaign(c)


def test_campaign_needs_no_data_file(drawn, monkeypatch):
    # the prior supplies the body: nothing is read from a data path
    monkeypatch.setenv("IDEAS_HPC_DATA", "/nonexistent")
    c = load(CAMPAIGN)
    setup = setup_from_campaign(c)
    prior = eros_class_prior(3)
    nom = prior.nominal
    np.testing.assert_array_equal(setup.body.shape.vertices_T, nom.base_vertices * nom.stretch)
    assert setup.target is not None and setup.encounter.speed_m_s == 10e3


def test_same_seed_same_worlds_and_rows_whatever_the_chunking(drawn):
    c, setup = drawn
    mc = c.config.monte_carlo
    a = build_scenario_bank(setup, STEP, mc, seed=11, n_scenarios=3, progress=False, chunk_size=1)
    b = build_scenario_bank(setup, STEP, mc, seed=11, n_scenarios=3, progress=False, chunk_size=3)
    np.testing.assert_array_equal(a.rows, b.rows)
    np.testing.assert_array_equal(a.areas, b.areas)
    # a world drawn afresh (no process cache) is the same mesh, bit for bit
    for k in range(3):
        w = placed_world(setup, setup.target.draw(11, k, family=seeds.SCENARIO_STREAM))
        np.testing.assert_array_equal(w.shape.vertices_T,
                                      drawn_world(setup, 11, seeds.SCENARIO_STREAM, k).shape.vertices_T)
    assert not np.array_equal(a.rows[0], a.rows[1])       # the worlds differ


def test_streams_give_disjoint_worlds(drawn):
    _, setup = drawn
    v = [drawn_world(setup, 5, f, 0).shape.vertices_T
         for f in (seeds.SCENARIO_STREAM, seeds.VALIDATION_STREAM, seeds.HOLDOUT_STREAM)]
    for i in range(3):
        for j in range(i):
            assert np.abs(v[i] - v[j]).max() > 10.0    # metres: other shapes


def _row(setup, flight):
    """What a bank row holds: the vertices mapped under the campaign's [coverage]
    requirement (lit, here), or seen without one."""
    cov = flight.coverage
    return cov.quality.mapped if setup.coverage.requirement else cov.observed


def test_drawn_rows_are_full_recomputations(drawn):
    # oracle: the flyby pipeline (whole flight, coverage from scratch) of the world's body
    # as a known target, from the bank's nominal start states and the scenario's draws
    c, setup = drawn
    mc = c.config.monte_carlo
    bank = build_scenario_bank(setup, STEP, mc, seed=7, n_scenarios=2, progress=False)
    r0, v0 = nominal_start(setup, bank.theta)
    for s in range(2):
        world = drawn_world(setup, 7, seeds.SCENARIO_STREAM, s)
        known = dataclasses.replace(setup, body=world.body, target=None)
        pert = Perturbation(**draw_world(mc, setup, bank.theta, 7, seeds.SCENARIO_STREAM, s))
        f = fly_open_loop(known, bank.theta, None, r0, v0, pert)
        np.testing.assert_array_equal(bank.rows[s].any(axis=0), _row(setup, f))
        for k in (0, 5):
            # per-candidate draws cut to candidate k; shared ones (parameters, the
            # navigation's common target offset) kept whole
            one = {key: (np.ascontiguousarray(val[k:k + 1]) if key != "params_override"
                         and np.ndim(val) and np.shape(val)[0] == bank.theta.size else val)
                   for key, val in draw_world(mc, setup, bank.theta, 7, seeds.SCENARIO_STREAM,
                                              s).items()}
            fk = fly_open_loop(known, bank.theta[k:k + 1], None, r0[k:k + 1], v0[k:k + 1],
                               Perturbation(**one))
            np.testing.assert_array_equal(bank.rows[s, k], _row(setup, fk))


def test_areas_are_each_drawn_shapes(drawn):
    c, setup = drawn
    bank = build_scenario_bank(setup, STEP, c.config.monte_carlo, seed=3, n_scenarios=2,
                               progress=False)
    assert bank.areas.shape == (2, setup.body.shape.n_vertices)
    for s in range(2):
        raw = setup.target.draw(3, s, family=seeds.SCENARIO_STREAM).shape
        np.testing.assert_allclose(bank.areas[s], raw.vertex_areas, rtol=1e-12, atol=0)
    assert np.abs(bank.areas[0] / bank.areas[1] - 1.0).max() > 0.1     # other shapes
    val = flight_areas(setup, seed=3, n_samples=2, first=1)
    raw = setup.target.draw(3, 2, family=seeds.VALIDATION_STREAM).shape
    np.testing.assert_allclose(val[1], raw.vertex_areas, rtol=1e-12, atol=0)
    rows = fly_members(setup, bank.theta[:2], None, c.config.monte_carlo, seed=3, n_samples=2,
                       first=1, progress=False)
    assert rows.shape == (2, 2, val.shape[1])


def _exact(prior, phase_shift):
    """The prior without spread, its phase at TCA shifted by ``phase_shift`` (rad)."""
    fam = dataclasses.replace(prior.family, sigma=0.0)
    size = dataclasses.replace(prior.size, sigma_diameter_m=0.0)
    pole = dataclasses.replace(prior.pole, sigma_rad=0.0, p_mirror=0.0)
    rot = dataclasses.replace(prior.rotation, sigma_period_s=0.0, sigma_phase_epoch_rad=0.0,
                              phase_epoch_rad=prior.rotation.phase_epoch_rad + phase_shift)
    return dataclasses.replace(prior, family=fam, size=size, pole=pole, rotation=rot)


def test_world_is_placed_by_its_pole_and_phase(drawn):
    # a world at the prior's estimate is the nominal body; one whose body has turned a
    # quarter turn further about the same pole appears turned by +90 deg about z of T0:
    # (x, y, z) -> (-y, x, z)
    _, setup = drawn
    nom = setup.body.shape.vertices_T
    scale = float(np.abs(nom).max())
    w0 = placed_world(setup, _exact(setup.target, 0.0).draw(1, 0))
    np.testing.assert_allclose(w0.shape.vertices_T, nom, rtol=0, atol=1e-9 * scale)
    w1 = placed_world(setup, _exact(setup.target, 0.5 * math.pi).draw(1, 0))
    np.testing.assert_allclose(w1.shape.vertices_T, np.stack([-nom[:, 1], nom[:, 0], nom[:, 2]],
                                                             axis=1), rtol=0, atol=1e-9 * scale)
    # mu scales with volume (here the nominal's): unchanged; the Sun is the nominal's
    assert w1.params.mu == pytest.approx(setup.body.params.mu, rel=1e-12)
    np.testing.assert_array_equal(w1.sun_T([3.0]), setup.world.sun_T([3.0]))


def test_known_prior_is_todays_bank():
    # [target] prior = "known" is no table at all: same setup, same shaping hash, same rows
    sets = ["design.angle_step_deg=30.0", "flyby.before_km=10", "flyby.after_km=10"]
    c0 = load(FAST, sets)
    c1 = load(FAST, sets + ['target.prior="known"'])
    s0, s1 = setup_from_campaign(c0), setup_from_campaign(c1)
    assert s1.target is None
    mc = c0.config.monte_carlo
    assert shaping_config(s0, mc, STEP, 2, 2) == shaping_config(s1, mc, STEP, 2, 2)
    a = build_scenario_bank(s0, STEP, mc, seed=2, n_scenarios=2, progress=False)
    b = build_scenario_bank(s1, STEP, mc, seed=2, n_scenarios=2, progress=False)
    np.testing.assert_array_equal(a.rows, b.rows)
    assert b.areas.shape == (s1.body.shape.n_vertices,)


@pytest.mark.parametrize("sets, field", [
    (['target.prior="fuzzy"'], "target.prior"),
    (["target.sigma_r=-0.1"], "target.sigma_r"),
    (["target.p_mirror=1.5"], "target.p_mirror"),
    (['target.prior="known"', "target.sigma_pole_deg=5.0"], "target.sigma_pole_deg"),
    (['body.name="eros"'], "body.name"),
    (['body.data_path="/tmp"'], "body.data_path"),
    (['body.length_unit="m"'], "body.length_unit"),
])
def test_bad_target_input_is_one_line_naming_the_field(sets, field):
    with pytest.raises(InputError) as err:
        load(CAMPAIGN, sets)
    assert err.value.field == field
    assert "\n" not in str(err.value) and field in str(err.value)


def test_overrides_reach_the_prior():
    c = load(CAMPAIGN, ["target.sigma_r=0.1", "target.correlation_deg=40.0",
                        "target.sigma_diameter_pct=5.0", "target.sigma_pole_deg=2.0",
                        "target.p_mirror=0.0", "target.sigma_phase_deg=3.0",
                        "target.lightcurve_days=10.0"])
    p = setup_from_campaign(c).target
    assert p.family.sigma == 0.1
    assert p.family.correlation_angle_rad == pytest.approx(math.radians(40.0))
    assert p.size.sigma_diameter_m == pytest.approx(0.05 * p.diameter_m)
    assert p.pole.sigma_rad == pytest.approx(math.radians(2.0)) and p.pole.p_mirror == 0.0
    assert p.rotation.sigma_phase_epoch_rad == pytest.approx(math.radians(3.0))
    assert p.rotation.dt_epoch_to_tca_s == pytest.approx(10 * 86400.0)


def test_the_eros_class_campaign_runs(tmp_path):
    # the whole success-probability design on drawn worlds, coarse (about 30 s warm)
    import xarray as xr

    from ideas_hpc.campaign.run import run_file

    ds = xr.open_zarr(run_file(str(CAMPAIGN), out=str(tmp_path / "ec.zarr"), workers=0,
                               progress=False, overrides=[
                                   "design.angle_step_deg=15",
                                   "design.holdout_scenarios=20"]))
    assert 1 <= int(ds["best_swarm_size"]) <= 20
    # the design weighed scenario s by world s's own vertex areas over its lit part (the
    # campaign's lit_at_tca reference): the areas drawn here from the prior directly (an
    # area is unchanged by the world's turn into the nominal frame)
    w = ds["scenario_vertex_weight"].values
    prior = eros_class_prior(resolution=3)
    assert ds.attrs["coverage_reference"] == "lit_at_tca"
    for s in (0, 7, w.shape[0] - 1):
        a = prior.draw(2026, s, family=seeds.SCENARIO_STREAM).shape.vertex_areas
        lit = w[s] > 0
        assert 0.25 < a[lit].sum() / a.sum() < 0.75     # about the half facing the Sun
        np.testing.assert_allclose(w[s][lit], a[lit] / a[lit].sum(), rtol=1e-10)
    # the worlds decide: the chosen swarm's P differs between scenarios (on one known
    # world with failures alone every scenario would score the same binomial sum)
    assert np.ptp(ds["scenario_probability"].values) > 0.1


def test_worlds_never_share_statics(drawn):
    # two meshes with the same bounding and footprint radii still key apart (the digest)
    from ideas_hpc.body.shape import build_shape
    from ideas_hpc.flyby.usable import scene_radius_m

    _, setup = drawn
    a = drawn_world(setup, 1, seeds.SCENARIO_STREAM, 0)
    v = a.shape.vertices_T.copy()
    r = np.linalg.norm(v, axis=1)
    i = int(np.argsort(r)[r.size // 2])        # a middling vertex: not the farthest
    v[i] *= 0.999
    shape = build_shape(v, a.shape.faces, name="moved", source="test")
    b = dataclasses.replace(a, body=dataclasses.replace(a.body, shape=shape))
    assert shape.r_max == a.shape.r_max
    assert a.attitude_key != b.attitude_key and a.mapping_key(setup) != b.mapping_key(setup)
    if scene_radius_m(shape) == scene_radius_m(a.shape):
        assert a.attitude_key[:4] == b.attitude_key[:4]


def test_a_bank_store_keeps_each_worlds_areas(drawn, tmp_path):
    import zarr

    c, setup = drawn
    mc = c.config.monte_carlo
    path = str(tmp_path / "bank.zarr")
    a = build_scenario_bank(setup, STEP, mc, seed=4, n_scenarios=3, progress=False,
                            chunk_size=2, store=path)
    b = build_scenario_bank(setup, STEP, mc, seed=4, n_scenarios=3, progress=False,
                            chunk_size=2, store=path)
    assert b.attrs.get("reused") and not a.attrs.get("reused")
    np.testing.assert_array_equal(a.rows, b.rows)
    stored = zarr.open_group(path, mode="r")["areas"][...]
    for s in range(3):
        raw = setup.target.draw(4, s, family=seeds.SCENARIO_STREAM).shape
        np.testing.assert_allclose(stored[s], raw.vertex_areas, rtol=1e-12, atol=0)
    free = build_scenario_bank(setup, STEP, mc, seed=4, n_scenarios=3, progress=False)
    np.testing.assert_array_equal(a.rows, free.rows)
