"""``ideas-hpc validate --truth-...``: a design's swarm flown at one given target (issue 42,
deliverable 7; :mod:`ideas_hpc.campaign.validate_truth`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base import seeds
from ideas_hpc.base.errors import InputError
from ideas_hpc.body.analytic import ellipsoid_mesh
from ideas_hpc.body.spin_prior import DCM_N_EQ, angles_from_unit
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import requirement_from_campaign, setup_from_campaign
from ideas_hpc.campaign.validate_store import pooled, validate_store
from ideas_hpc.campaign.validate_truth import (TruthOptions, truth_setup,
                                               truth_shape, truth_world)
from ideas_hpc.campaign.validation_flights import fly_validation_world
from ideas_hpc.cli import main
from ideas_hpc.montecarlo.failure_dispersion import failure_model
from small_stores import small_store

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-class-flyby.toml"
#: the eros-class design made small: a 20 deg grid (18 candidates), 20 scenarios (p = 0.5)
SMALL = ["design.angle_step_deg=20", "design.n_max=8", "design.verify_samples=20",
         "design.time_limit_s=20"]
SWARM = np.deg2rad([0.0, 120.0, 240.0])
#: the whole surface as the reference (the campaign ships the area lit at TCA)
SURFACE = ['design.coverage_reference="surface"']


@pytest.fixture(scope="module")
def drawn():
    c = load(CAMPAIGN, SURFACE)
    return c, setup_from_campaign(c)


@pytest.fixture(scope="module")
def class_store(tmp_path_factory):
    from ideas_hpc.campaign.run import run_file

    return run_file(str(CAMPAIGN), out=str(tmp_path_factory.mktemp("truth") / "ec.zarr"),
                    overrides=SMALL, workers=0, progress=False)


def _fly(c, setup, first, n):
    mc = c.config.monte_carlo
    return fly_validation_world(setup, SWARM, mc, failure_model(mc), requirement_from_campaign(c),
                                seed=77, n_samples=n, first=first, progress=False)


LIT = ['design.coverage_reference="lit_at_tca"', "coverage.max_incidence_deg=80"]


@pytest.mark.parametrize("sets", [[], LIT], ids=["surface", "lit_at_tca"])
def test_a_drawn_world_given_as_truth_flies_as_drawn(drawn, sets):
    """World k of the validation stream, given back as a truth (shape, pole, period, phase),
    flies sample k exactly as the drawn path does, with the same weights (its vertex areas,
    or its area lit at TCA); at sample k + 1 it is still world k (its weights, and not the
    drawn world k + 1's rows)."""
    c, setup = drawn
    if sets:
        c = load(CAMPAIGN, sets)
        setup = setup_from_campaign(c)
    k = 3
    tw = setup.target.draw(77, k, family=seeds.VALIDATION_STREAM)
    ra, dec = angles_from_unit(DCM_N_EQ.T @ tw.pole_N)
    truth = truth_world(setup, tw.shape, pole_ra_dec_rad=(ra, dec),
                        period_s=tw.spin_period_s, phase_rad=tw.phase_tca_rad)
    rows_d, _, areas_d = _fly(c, setup, k, 2)
    rows_t, _, areas_t = _fly(c, truth_setup(setup, truth), k, 2)
    np.testing.assert_array_equal(rows_t[0], rows_d[0])
    np.testing.assert_allclose(areas_t[0], areas_d[0], rtol=1e-12, atol=0)
    np.testing.assert_allclose(areas_t[1], areas_t[0], rtol=1e-12, atol=0)
    if not sets:               # the whole surface: world k's own vertex areas
        np.testing.assert_allclose(areas_t[0], tw.shape.vertex_areas, rtol=1e-12, atol=0)
    else:                      # a part of it, lit at TCA
        assert 0.2 < areas_t[0].sum() / tw.shape.vertex_areas.sum() < 0.8
    assert not np.allclose(areas_d[1], areas_t[1], rtol=1e-6)
    assert not np.array_equal(rows_t[1], rows_d[1])


@pytest.mark.parametrize("in_pass", [False, True], ids=["whole-pass", "losses-in-pass"])
def test_a_truth_of_its_own_mesh_flies_its_own_vertices(drawn, in_pass):
    """A truth of another topology (an ellipsoid at resolution 2: 162 vertices, the design's
    642) gives rows, weights and (losses in the pass) first-seen times per vertex of its own
    mesh; a body inside the ring is seen on every side."""
    c, setup = drawn
    if in_pass:
        # first-seen times are kept for plain visibility only (not for a lit requirement)
        c = load(CAMPAIGN, SURFACE + ["monte_carlo.failure_in_pass_share=0.5",
                                      "coverage.require_lit=false"])
        setup = setup_from_campaign(c)
    shape = ellipsoid_mesh(8e3, 6e3, 5e3, 2)
    rows, seen, areas = _fly(c, truth_setup(setup, truth_world(setup, shape)), 0, 2)
    assert rows.shape == (2, SWARM.size, shape.n_vertices) and shape.n_vertices == 162
    assert areas.shape == (2, shape.n_vertices)
    np.testing.assert_allclose(areas[0], shape.vertex_areas, rtol=1e-12)
    assert rows.any(axis=1).mean() > 0.2
    if in_pass:               # seen: a pass fraction where the row holds, inf elsewhere
        assert seen.shape == rows.shape
        timed = seen[np.isfinite(seen)]
        assert np.all(np.isfinite(seen) <= rows) and np.all((timed >= 0) & (timed <= 1))
        assert timed.size > 0.9 * rows.sum()
    else:
        assert seen is None


def test_a_truth_equal_to_a_known_body_is_the_ordinary_validation(tmp_path_factory):
    store = small_store("design-reliability", tmp_path_factory.mktemp("small-stores"))
    plain = validate_store(store, samples=6, progress=False)
    given = validate_store(store, samples=6, progress=False,
                           truth=TruthOptions(shape="ellipsoid"))
    np.testing.assert_allclose(given.per_sample, plain.per_sample, atol=1e-9)
    np.testing.assert_array_equal(given.success, plain.success)
    assert given.truth and "truth given" in given.line() and plain.truth is None
    # another truth changes the answer: spheres far smaller than the body, which the ring's
    # cameras see otherwise (which one shows it depends on the swarm the design chose: a
    # swarm that needs all its members on both bodies scores p_s^N on each)
    others = [validate_store(store, samples=6, progress=False,
                             truth=TruthOptions(shape=f"ellipsoid:{r},{r},{r}")).per_sample
              for r in (3, 1)]
    assert any(not np.allclose(o, plain.per_sample) for o in others)
    # the same, member by member and vertex by vertex (the store's P-hat is the failures'
    # alone there): the body given back as a truth is flown as the known body is
    from small_stores import CAMPAIGNS, KINDS

    c = load(CAMPAIGNS / KINDS["design-reliability"][0], KINDS["design-reliability"][1])
    setup = setup_from_campaign(c)
    rows, _, areas = _fly(c, setup, 0, 3)
    rows_t, _, areas_t = _fly(c, truth_setup(setup, truth_world(setup)), 0, 3)
    assert areas is None and rows.any()
    np.testing.assert_array_equal(rows_t, rows)
    np.testing.assert_allclose(areas_t[2], setup.body.shape.vertex_areas, rtol=1e-12)


@pytest.mark.parametrize("args,option,words", [
    (["--truth-pole", "10,100"], "--truth-pole", "Dec in [-90, 90]"),
    (["--truth-pole", "400,0"], "--truth-pole", "RA must be in [0, 360)"),
    (["--truth-pole", "ten"], "--truth-pole", "RA,DEC in degrees"),
    (["--truth-period-h", "-5"], "--truth-period-h", "> 0"),
    (["--truth-phase-deg", "nan"], "--truth-phase-deg", "finite"),
    (["--truth-shape", "/nonexistent/truth.obj"], "--truth-shape", "no shape file"),
    (["--truth-shape", "ellipsoid:1,2"], "--truth-shape", "three positive semi-axes"),
    (["--truth-shape", "ellipsoid:1,-2,3"], "--truth-shape", "three positive semi-axes"),
    (["--truth-shape", "ellipsoid:9000,7000,6000"], "--truth-shape", "within a factor 10"),
])
def test_bad_truth_options_are_one_line_naming_the_option(args, option, words,
                                                         tmp_path_factory, capsys):
    store = small_store("design-reliability", tmp_path_factory.mktemp("small-stores"))
    capsys.readouterr()         # the store's own run, when this test built it
    assert main(["validate", str(store), "--samples", "2", "--no-progress", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and option in err[0] and words in err[0]


def test_a_bad_shape_file_names_the_option_and_the_file(tmp_path):
    from ideas_hpc.campaign.validate_truth import truth_shape

    bad = tmp_path / "truth.tab"
    bad.write_text("v 1 0 0\nv 0 1 0\nf 1 2\n")
    with pytest.raises(InputError) as e:
        truth_shape(str(bad))
    assert e.value.field == "--truth-shape" and "truth.tab" in str(e.value)
    assert "\n" not in str(e.value)


def test_pooled_truths_inside_the_prior(class_store, tmp_path, capsys):
    """Three ellipsoids made here (not by the prior), of the class's size with other axis
    ratios, poles and phases: each flown with the CLI and pooled."""
    truths = [("ellipsoid:15,6.5,5.2", "11,17", 40.0), ("ellipsoid:13,8,6", "20,25", 200.0),
              ("ellipsoid:17,5.5,5.5", "5,10", 310.0)]
    runs = []
    for i, (shape, pole, phase) in enumerate(truths):
        out = tmp_path / f"t{i}.npz"
        assert main(["validate", str(class_store), "--samples", "6", "--no-progress",
                     "--truth-shape", shape, "--truth-pole", pole, "--truth-phase-deg",
                     str(phase), "--out", str(out)]) == 0
        line = capsys.readouterr().out.splitlines()[0]
        assert "truth given (" + shape in line
        runs.append(np.load(out))
    vals = [validate_store(class_store, samples=6, progress=False,
                           truth=TruthOptions(shape=s, pole_ra_dec_rad=tuple(
                               math.radians(float(x)) for x in p.split(",")),
                               phase_rad=math.radians(ph))) for s, p, ph in truths]
    for v, r in zip(vals, runs):          # the API and the CLI fly the same samples
        np.testing.assert_allclose(v.per_sample, r["per_sample"], atol=1e-12)
    # inside the prior: the size within 3 sigma (10 % each) of the estimate, the pole within
    # 3 sigma (10 deg) of the estimated one
    c = load(CAMPAIGN)
    setup = setup_from_campaign(c)
    prior_pole = setup.target.pole.pole_N
    for s, p, _ in truths:
        tw = truth_world(setup, truth_shape(s), pole_ra_dec_rad=tuple(
            math.radians(float(x)) for x in p.split(",")))
        assert abs(tw.diameter_m / setup.target.diameter_m - 1.0) < 0.3
        assert math.degrees(math.acos(float(tw.pole_N @ prior_pole))) < 30.0
    pool = pooled(vals)
    # the pooled P-hat is the sample-weighted mean of the truths' own P-hats
    assert pool.p_hat == pytest.approx(sum(v.p_hat * v.samples for v in vals) / 18, abs=1e-12)
    assert pool.samples == 18 and pool.successes == sum(v.successes for v in vals)
    assert 0.0 <= pool.lower <= pool.p_hat
    # one truth pooled alone is its own validation
    assert pooled(vals[:1]).lower == pytest.approx(vals[0].lower, abs=0)
    assert "pooled over 3 given truths" in pool.line()
    print(pool.line())
