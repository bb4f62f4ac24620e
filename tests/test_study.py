"""``ideas-hpc study``: the answers only a design under a target prior gives (issue 42
deliverable 6; :mod:`ideas_hpc.campaign.study`, :mod:`ideas_hpc.campaign.study_nested`).

Oracles: a prior with no spread is the known body (price 0, the same N and P on either
path; every world's conditional P is the plain validation's P over the same inner draws);
world m of the nested draws given back as a truth (:mod:`ideas_hpc.campaign.validate_truth`)
flies its inner draws to the same conditional P; common random numbers make the navigation
draws of every sigma the same normals scaled; the B-plane figure's ellipse is the
covariance's k-sigma contour.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base import seeds
from ideas_hpc.base.units import KM
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import requirement_from_campaign, setup_from_campaign
from ideas_hpc.campaign.study import Study, navigation_value, price_of_ignorance
from ideas_hpc.campaign.study_nested import (conditional_probabilities,
                                             per_target_reliability)
from ideas_hpc.campaign.validate_truth import truth_setup
from ideas_hpc.campaign.validation_flights import (Validation, fly_validation_world,
                                                   sample_weights)
from ideas_hpc.flyby.target_world import world_areas
from ideas_hpc.montecarlo.failure_dispersion import failure_model
from ideas_hpc.montecarlo.scenarios import draw_world

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-class-flyby.toml"
#: the eros-class design made small: a 20 deg grid (18 candidates), 20 scenarios (p = 0.5)
SMALL = ["design.angle_step_deg=20", "design.n_max=6", "design.time_limit_s=20"]
SWARM = np.deg2rad([0.0, 120.0, 240.0])     # on the 20 deg grid
NEED = 0.99                                  # the campaign's: target 100 %, eps_tol 1 %


def _no_spread(prior):
    """``prior`` with every spread zero and the same nominal (its size, pole and the phase it
    propagates to TCA): every world is the nominal body."""
    r = dataclasses.replace
    return r(prior, family=r(prior.family, sigma=0.0), size=r(prior.size, sigma_diameter_m=0.0),
             pole=r(prior.pole, sigma_rad=0.0, p_mirror=0.0),
             rotation=r(prior.rotation, sigma_period_s=0.0, sigma_phase_epoch_rad=0.0))


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    c = load(CAMPAIGN, SMALL)
    return Study(store=tmp_path_factory.mktemp("drawn") / "s.zarr", c=c,
                 setup=setup_from_campaign(c), theta=SWARM, need=NEED,
                 p=float(c.config.design.success_probability))


@pytest.fixture(scope="module")
def zero(drawn, tmp_path_factory):
    setup = dataclasses.replace(drawn.setup, target=_no_spread(drawn.setup.target))
    return dataclasses.replace(drawn, store=tmp_path_factory.mktemp("zero") / "s.zarr",
                               setup=setup)


def test_no_spread_costs_nothing_and_the_known_case_is_the_nominal(drawn, zero):
    """With no spread the prior's and the known case's fewest N and P agree (price 0); the
    full prior's known case is that same nominal body (so its N and P are the zero-spread
    prior's), and the full prior's own case differs from it (ignorance is not free here)."""
    z = price_of_ignorance(zero)
    assert int(z.attrs["price"]) == 0
    n, p = z["fewest_n"].values, z["fewest_probability"].values
    assert n[0] == n[1] > 0
    np.testing.assert_allclose(p[0], p[1], atol=1e-9)
    sw = z["swarm_probability"].values
    np.testing.assert_allclose(sw[0], sw[1], atol=1e-9)
    d = price_of_ignorance(drawn)
    assert d["fewest_n"].values[1] == n[1]
    np.testing.assert_allclose(d["fewest_probability"].values[1], p[1], atol=1e-9)
    np.testing.assert_allclose(d["swarm_probability"].values[1], sw[1], atol=1e-9)
    assert abs(d["swarm_probability"].values[0] - sw[0]) > 0.01
    assert int(d.attrs["price"]) == int(d["fewest_n"].values[0] - d["fewest_n"].values[1])


def test_the_prior_case_is_the_designs_own_recorded_search(drawn):
    """A design store's own fewest-N search on its bank (``bank_swarm_size``,
    ``bank_probability``, ``solver_status``, ``proven_bound``) is the prior case's row as
    recorded, not searched again under the study's time limit; the known case is still
    searched, and the price is their difference."""
    import xarray as xr

    from ideas_hpc.campaign.study import recorded_search

    ds = xr.Dataset({"bank_swarm_size": ((), np.int64(5)), "bank_probability": ((), 0.9031),
                     "solver_status": ((), "optimal"), "proven_bound": ((), 4.9999999999)})
    rec = recorded_search(ds)
    assert rec == {"n": 5, "probability": 0.9031, "status": "optimal", "bound": 5}
    assert recorded_search(ds.drop_vars("proven_bound")) is None
    searched = price_of_ignorance(drawn)
    marked = {"n": 6, "probability": 0.61, "status": "recorded here", "bound": 4}
    got = price_of_ignorance(dataclasses.replace(drawn, design_search=marked))
    assert got["fewest_n"].values[0] == 6 and got["fewest_probability"].values[0] == 0.61
    assert str(got["fewest_status"].values[0]) == "recorded here"
    np.testing.assert_array_equal(got["fewest_n"].values[1], searched["fewest_n"].values[1])
    # the designed swarm's P on the bank is still scored, whichever search is taken
    np.testing.assert_allclose(got["swarm_probability"].values,
                               searched["swarm_probability"].values, atol=0)
    assert int(got.attrs["price"]) == 6 - int(searched["fewest_n"].values[1])


def test_late_update_draws_common_random_numbers_and_p_is_monotone(drawn):
    """Every sigma's bank draws the same normals (scenario s's target offset, B-plane and
    along-track, scales with sigma exactly), and the fixed swarm's P does not fall as the update sharpens; the
    stored monotone flag says so, and the campaign's own sigma is a row."""
    setup, c = drawn.setup, drawn.c
    plan = setup.navigation
    mc = c.config.monte_carlo
    offs = []
    for s in (30e3, 3e3):
        sc = dataclasses.replace(setup, navigation=dataclasses.replace(
            plan, error=plan.error.scaled(s)))
        offs.append(np.array([draw_world(mc, sc, SWARM, c.config.seed, seeds.SCENARIO_STREAM,
                                         k)["target_offset_N"] for k in range(5)]))
    np.testing.assert_allclose(offs[0] / 30e3, offs[1] / 3e3, rtol=1e-12, atol=0)
    ds = navigation_value(drawn, (100e3, 3e3))
    sig = ds["bplane_sigma"].values
    assert np.all(np.diff(sig) < 0) and np.isclose(sig, plan.error.sigma_major_m).sum() == 1
    p = ds["swarm_probability"].values
    assert np.all(np.diff(p) >= -1e-12) and int(ds.attrs["monotone"]) == 1
    assert p[0] < p[-1]                          # 100 km is far worse than 3 km
    np.testing.assert_allclose(ds["tca_sigma"].values / sig,
                               plan.error.sigma_tca_s / plan.error.sigma_major_m, rtol=1e-12)


def _plain(st, setup, m, k):
    """Per-sample P of the swarm over samples m K .. m K + K - 1 of the nested stream."""
    c = st.c
    mc, model = c.config.monte_carlo, failure_model(c.config.monte_carlo)
    rows, seen, areas = fly_validation_world(setup, SWARM, mc, model,
                                             requirement_from_campaign(c), seed=c.config.seed,
                                             n_samples=k, first=m * k, progress=False,
                                             stream=seeds.NESTED_STREAM)
    # the known body's flights bring no weights: its own reference area (lit at TCA)
    ref = world_areas(setup, c.config.seed, seeds.NESTED_STREAM, [0],
                      requirement_from_campaign(c))
    w = sample_weights(areas, ref / ref.sum(), rows.shape[0])
    return Validation(rows, w, NEED, model, c.config.seed, first=m * k, seen=seen,
                      stream=seeds.NESTED_STREAM).per_sample


def test_each_nested_world_is_its_truth_flown_through_its_inner_draws(drawn):
    """World m's conditional P is world m of the nested family, given as a truth and flown
    through inner draws m K .. m K + K - 1: the nesting maps samples to worlds and draws
    exactly so."""
    m_n, k = 3, 2
    r = per_target_reliability(drawn.c, drawn.setup, SWARM, NEED, drawn.p, worlds=m_n,
                               per_world=k)
    for m in range(m_n):
        tw = drawn.setup.target.draw(drawn.c.config.seed, m, family=seeds.NESTED_STREAM)
        ref = _plain(drawn, truth_setup(drawn.setup, tw), m, k)
        np.testing.assert_allclose(r.per_sample[m], ref, atol=1e-12)
        np.testing.assert_allclose(r.conditional[m], ref.mean(), atol=1e-12)
    assert len({round(float(x), 9) for x in r.per_sample.ravel()}) > 1   # not all alike
    assert r.meeting == int((r.conditional >= drawn.p).sum())


def test_no_spread_every_world_is_the_plain_p(zero):
    """A prior with no spread has one world: each world's conditional P is the known body's
    plain validation P over the same inner draws, and the share meeting p follows."""
    m_n, k = 3, 3
    r = per_target_reliability(zero.c, zero.setup, SWARM, NEED, zero.p, worlds=m_n,
                               per_world=k)
    known = dataclasses.replace(zero.setup, target=None)
    ref = np.concatenate([_plain(zero, known, m, k) for m in range(m_n)])
    np.testing.assert_allclose(r.per_sample.ravel(), ref, atol=1e-9)
    np.testing.assert_allclose(r.conditional, ref.reshape(m_n, k).mean(axis=1), atol=1e-9)
    assert r.share == np.mean(ref.reshape(m_n, k).mean(axis=1) >= zero.p)


def test_conditional_probabilities_by_hand():
    """World-major blocks: sample m K + j is world m's draw j; the standard error is the
    sample standard deviation over sqrt K."""
    v = np.array([1.0, 0.0, 0.5, 0.5, 0.2, 0.4])
    p, se = conditional_probabilities(v, 2)
    np.testing.assert_allclose(p, [0.5, 0.5, 0.3])
    np.testing.assert_allclose(se, [np.sqrt(0.5) / np.sqrt(2), 0.0, np.sqrt(0.02) / np.sqrt(2)])


def test_ellipse_contour_is_the_k_sigma_mahalanobis_level():
    """Every point of the k-sigma contour has x^T C^-1 x = k^2, and it spans the major axis."""
    from ideas_hpc.plots.study import ellipse_points
    from ideas_hpc.flyby.navigation import NavigationError

    cov = NavigationError(10.0 * KM, 4.0 * KM, np.deg2rad(30.0)).covariance_TR_m2
    e = ellipse_points(cov, 2.0)
    np.testing.assert_allclose(np.einsum("ni,ij,nj->n", e, np.linalg.inv(cov), e), 4.0,
                               rtol=1e-10)
    assert np.isclose(np.linalg.norm(e, axis=1).max(), 20.0 * KM, rtol=1e-3)


def test_answer_figures_are_drawn(tmp_path):
    """The answers' figure and the B-plane figure from hand-made groups (PNG files)."""
    import xarray as xr

    from ideas_hpc.flyby.navigation import LUTETIA
    from ideas_hpc.plots.study import answers_figure, bplane_figure

    sig = np.array([100e3, 10e3, 3e3])
    nav = xr.Dataset({"swarm_probability": ("bplane_sigma", [0.0, 0.6, 0.9]),
                      "fewest_n": ("bplane_sigma", [-1, 2, 2])},
                     coords={"bplane_sigma": sig}, attrs={"campaign_sigma_m": 10e3})
    per = xr.Dataset({"conditional_probability": ("world", [0.0, 0.7, 0.9]),
                      "conditional_std_error": ("world", [0.0, 0.1, np.nan])},
                     attrs={"meeting": 2, "worlds": 3, "wilson_low": 0.2, "wilson_high": 0.94})
    a = answers_figure(nav, per, tmp_path / "a.png", p=0.5)
    b = bplane_figure(LUTETIA.covariance_TR_m2, [[150e3, 0.0], [-75e3, 130e3]],
                      tmp_path / "b.png", d_sep_m=150e3, other_sigmas_m=sig,
                      body_radius_m=8e3)
    assert a.stat().st_size > 10_000 and b.stat().st_size > 10_000


@pytest.mark.slow
def test_study_command_writes_groups_and_the_report_shows_them(tmp_path, capsys):
    """The command on a small design store prints one line per answer, stores each as a
    group (not recomputed when asked again), and the report lists the lines and draws the
    answers, the prior's gallery and the B-plane figures (PNG files, inlined in the HTML)."""
    import xarray as xr

    from ideas_hpc.campaign.run import run_file
    from ideas_hpc.cli import main

    store = run_file(str(CAMPAIGN), out=str(tmp_path / "ec.zarr"),
                     overrides=SMALL + ["design.verify_samples=20", "design.holdout_scenarios=0"],
                     workers=0, progress=False)
    capsys.readouterr()
    args = ["study", str(store), "--no-progress", "--answers", "navigation,per-target",
            "--bplane-sigmas-km", "30", "--worlds", "2", "--per-world", "2"]
    assert main(args) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("value of a late navigation update")
    assert lines[1].startswith("per-target reliability: ") and " of 2 target worlds" in lines[1]
    g = xr.open_zarr(store, group="study_per_target", consolidated=False)
    assert g["inner_probability"].shape == (2, 2)
    assert g.attrs["nested_stream"] == seeds.NESTED_STREAM
    stamp = g.attrs["wall_s"]
    assert main(args) == 0                       # stored: read back, not recomputed
    assert xr.open_zarr(store, group="study_per_target",
                        consolidated=False).attrs["wall_s"] == stamp
    capsys.readouterr()
    assert main(["report", str(store), "--html"]) == 0
    out = Path(str(store).removesuffix(".zarr") + "-report")
    text = (out / "summary.txt").read_text()
    assert "value of a late navigation update" in text and "per-target reliability" in text
    for name in ("study_answers.png", "study_prior_gallery.png", "study_bplane.png"):
        assert (out / name).stat().st_size > 10_000 and name in text
    page = (out / "report.html").read_text()
    for name in ("study_answers", "study_prior_gallery", "study_bplane"):
        assert f'<img alt="{name}" style="max-width:100%" src="data:image/png;base64,' in page


def test_answers_that_do_not_apply_say_why(tmp_path_factory, capsys):
    """A design of a known body without navigation errors: every answer says it does not
    apply, and the store gains no study group."""
    from small_stores import small_store

    from ideas_hpc.campaign.study import DEFAULT_ANSWERS
    from ideas_hpc.cli import main
    from ideas_hpc.report.study import study_groups

    store = small_store("design-reliability", tmp_path_factory.mktemp("small-stores"))
    capsys.readouterr()
    assert main(["study", str(store), "--no-progress"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [ln.split(":")[0] for ln in lines] == list(DEFAULT_ANSWERS)
    assert all(": does not apply: " in ln for ln in lines)
    assert study_groups(store) == {}
