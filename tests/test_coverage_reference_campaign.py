"""``design.coverage_reference`` in a campaign (issue 42): the key, the default, a small
exact design weighed by the area lit at closest approach, and the labels of its store,
summary and HTML page.

Oracles: the targeted trajectory's own closest approach (the sampled minimum of |r|),
the lit test written out per vertex with the Sun at that time, the store's per-vertex
``observed`` summed by hand against the reference, and the default's vertex areas.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import requirement_from_campaign, setup_from_campaign
from ideas_hpc.flyby.flight import target
from ideas_hpc.flyby.reference_area import reference_areas, sun_at_closest_approach
from ideas_hpc.report.html import write_html
from ideas_hpc.report.requirement import GEOMETRIC_WHOLE, coverage_meaning
from ideas_hpc.report.write import write_report

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "campaigns" / "eros-nadir.toml"
BASE = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        "dynamics.srp=false", "design.angle_step_deg=30", 'attitude.mode="ideal"',
        "run.workers=0", "design.time_limit_s=60"]
LIT = ['design.coverage_reference="lit_at_tca"', "design.verify_samples=0"]
#: a visual requirement: lit, incidence <= 75 deg
VISUAL = ["coverage.require_lit=true", "coverage.max_incidence_deg=75"]


def test_a_bad_reference_is_one_line_naming_the_key_and_its_line(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text('kind = "design-nadir"\n[body]\nname = "ellipsoid"\n[design]\n'
                 'verify_samples = 0\ncoverage_reference = "lit"\n')
    with pytest.raises(InputError) as ei:
        load(f)
    e = ei.value
    assert e.field == "design.coverage_reference" and e.line == 6 and "\n" not in str(e)
    assert "lit_at_tca" in e.message and "surface" in e.message


def test_lit_reference_refuses_a_verification_that_ignores_it():
    with pytest.raises(InputError) as ei:
        load(DESIGN, BASE + ['design.coverage_reference="lit_at_tca"'])
    assert ei.value.field == "design.coverage_reference" and "\n" not in str(ei.value)
    assert "design.verify_samples = 0" in ei.value.message


def test_a_kind_that_does_not_weigh_by_it_refuses_the_key():
    with pytest.raises(InputError) as ei:
        load(ROOT / "campaigns" / "eros-monte-carlo.toml",
             ['design.coverage_reference="lit_at_tca"', 'body.name="ellipsoid"'])
    assert ei.value.field == "design.coverage_reference"


def test_the_default_is_the_whole_surface_bit_for_bit():
    c = load(DESIGN, BASE)
    req = requirement_from_campaign(c)
    assert req.reference == "surface" and req.kind == "geometric"
    setup = setup_from_campaign(c)
    w = reference_areas(setup, req)
    assert w.dtype == np.float64
    assert np.array_equal(w, np.asarray(setup.body.shape.vertex_areas, dtype=np.float64))


def test_the_paper_closest_approach_is_the_trajectory_minimum():
    """An asymmetric pass (z from -3 to +9 km; the body turns under it): the targeted arc's
    sampled minimum range is within one sample of the geometry's TCA, which is not the
    z = 0 crossing (15 s) here."""
    c = load(DESIGN, [k if not k.startswith("flyby.z_stop") else "flyby.z_stop_km=9"
                      for k in BASE])
    setup = setup_from_campaign(c)
    t_ca = setup.geometry.closest_approach_s(setup)
    res = target(setup, [0.0])
    rng = np.linalg.norm(res.position_T[0], axis=1)
    t_min = res.times[int(np.argmin(rng))]
    assert abs(t_ca - t_min) <= 1.01 * setup.dt_s, (t_ca, t_min)
    assert abs(t_ca - 15.0) > 5 * setup.dt_s


@pytest.fixture(scope="module")
def lit_store(tmp_path_factory):
    return run_file(DESIGN, out=tmp_path_factory.mktemp("lit") / "r.zarr", overrides=BASE + LIT + VISUAL)


def test_a_design_on_the_lit_reference(lit_store, tmp_path):
    c = load(DESIGN, BASE + LIT + VISUAL)
    setup = setup_from_campaign(c)
    ds = xr.open_zarr(lit_store)
    a = ds.attrs
    assert a["coverage_reference"] == "lit_at_tca" and a["requirement_kind"] == "visual"
    label = "visual (lit, incidence <= 75 deg) map of the area lit at closest approach"
    assert a["requirement"] == label
    # the reference: the per-vertex lit test with the Sun at the trajectory's TCA (the
    # ellipsoid is convex: no cast shadow); TCA from the arc itself, not the geometry
    res = target(setup, [0.0])
    t_ca = res.times[int(np.argmin(np.linalg.norm(res.position_T[0], axis=1)))]
    s = setup.sun_T([t_ca])[0]
    assert np.allclose(s, sun_at_closest_approach(setup), atol=1e-6)
    n = setup.body.shape.vertex_normals_T
    c75 = math.cos(math.radians(75.0))
    lit = np.array([float(np.dot(n[v], s)) >= c75 for v in range(n.shape[0])])
    w = ds["reference_area"].values
    assert np.array_equal(w > 0, lit) and 0.05 < lit.mean() < 0.8
    assert np.allclose(w[lit], ds["vertex_area"].values[lit], rtol=0, atol=0)
    # the flown swarm's coverage, a fraction of the lit area, summed by hand
    seen = ds["mapped"].values.astype(bool)
    frac = w[seen].sum() / w.sum()
    assert float(ds["best_coverage_of_reference"]) == pytest.approx(frac, rel=1e-12)
    assert frac >= float(a["threshold_coverage"]) - 1e-9
    # the designer weighed its rows by the same reference (the flight is its nominal)
    assert float(ds["design_coverage"]) == pytest.approx(frac, rel=1e-9)
    # ... and not the whole surface's: the two differ on this pass
    whole = ds["vertex_area"].values[seen].sum() / ds["vertex_area"].values.sum()
    assert abs(frac - whole) > 0.05
    # the summary and the HTML page say what the map is
    text = write_report(lit_store, tmp_path / "rep").read_text()
    assert f"coverage requirement: {label}" in text
    assert f"of the reference area: {100 * frac:.3f} %" in text
    page = write_html(ds, text, tmp_path / "r.html").read_text()
    assert "map of the area lit at closest approach" in page


def test_a_store_without_the_label_reads_as_the_papers_map():
    assert coverage_meaning(xr.Dataset()) == f"coverage requirement: {GEOMETRIC_WHOLE}"
    vis = xr.Dataset(attrs={"requirement": "visual (lit, incidence <= 60 deg) map of the "
                                           "area lit at closest approach"})
    assert coverage_meaning(vis).endswith("visual (lit, incidence <= 60 deg) map of the area "
                                          "lit at closest approach")
    assert "geometric" not in coverage_meaning(xr.Dataset({"mapped": ((), True)}))


def test_a_success_probability_design_weighs_the_lit_area(tmp_path):
    """The scenario bank and the validation (and ``ideas-hpc validate``) weigh by the lit
    area: continuous dispersions off, P is the exact enumeration over the nominal masks
    with the lit weights, written out in numpy (test_campaign_reliability.exact_p); on
    the whole surface the same swarm would score 0 (it maps ~75 % of it)."""
    from ideas_hpc.campaign.validate_store import validate_store
    from ideas_hpc.design import build_bank
    from test_campaign_reliability import DESIGN as RELIABLE, FREE, exact_p

    lit = ['design.coverage_reference="lit_at_tca"']
    store = run_file(RELIABLE, out=tmp_path / "p.zarr", overrides=FREE + lit)
    ds = xr.open_zarr(store)
    c = load(RELIABLE, FREE + lit)
    setup = setup_from_campaign(c)
    bank = build_bank(setup, c.config.design.grid_step_rad)
    s = setup.sun_T([setup.geometry.closest_approach_s(setup)])[0]
    facing = setup.body.shape.vertex_normals_T @ s > 0.0     # convex: no cast shadow
    w = np.where(facing, bank.areas, 0.0)
    assert np.array_equal(ds["reference_area"].values, w)
    need = ds.attrs["reliability_threshold"]
    idx = list(np.rint(ds["swarm_angle"].values / bank.step_rad).astype(int)
               % bank.n_candidates)
    p = exact_p(bank.masks, w / w.sum(), idx, need, 0.05)
    assert p >= 0.9
    assert float(ds["reliability_probability"]) == pytest.approx(p, abs=1e-12)
    assert float(ds["validation_p_hat"]) == pytest.approx(p, abs=1e-12)
    whole = bank.areas / bank.areas.sum()
    assert exact_p(bank.masks, whole, idx, need, 0.05) < 0.5
    v = validate_store(store, samples=2, progress=False)
    assert v.p_hat == pytest.approx(p, abs=1e-12)
