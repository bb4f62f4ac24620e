"""design-nadir with design.success_probability through run_file (issue 20), ellipsoid body."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.stats import binom

from ideas_hpc.report.write import write_report
from ideas_hpc.report.html_reliability import reliability_html_figures
from ideas_hpc.report.reliability import bank_answer
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.core.design.reliability import swarm_probabilities
from ideas_hpc.design import build_bank
from ideas_hpc.design.bank import separation_steps
from ideas_hpc.design.reliability import ReliabilityDesigner, all_swarms
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.plots import figures
from report_numbers import lines_for, printed, printed_int

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "campaigns" / "eros-design.toml"
BASE = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        "dynamics.srp=false", "design.angle_step_deg=10", 'attitude.mode="ideal"',
        "run.workers=0", "design.time_limit_s=60"]
QUIET = [f"monte_carlo.{k}=0.0" for k in ("sigma_c20_pct", "sigma_c22_pct", "sigma_gm_pct",
                                          "sigma_position_m", "sigma_velocity_mm_s",
                                          "sigma_misalignment_deg")] + [
    "monte_carlo.reflectivity_min=0.6", "monte_carlo.reflectivity_max=0.6"]


def exact_p(masks, w, swarm, need, p_f):
    """Direct enumeration of the survivors (numpy), one scenario."""
    n = len(swarm)
    out = 0.0
    for alive in itertools.product((False, True), repeat=n):
        mem = [c for c, a in zip(swarm, alive) if a]
        if mem and w[masks[mem].any(axis=0)].sum() >= need - 1e-12:
            out += 0.95 ** sum(alive) * 0.05 ** (n - sum(alive))
    return out


# 12 candidates (30 deg): every swarm of the sizes in question is scored, so the bank's
# answer must be proven (status optimal, gap 0); at 10 deg (20 deg) sizes 5-6 (7) stay unresolved
BASE20 = [k if not k.startswith("design.angle_step_deg") else "design.angle_step_deg=30"
          for k in BASE]
FREE = BASE20 + QUIET + ["design.success_probability=0.9", "monte_carlo.failure_probability=0.05",
                       "design.scenarios=100", "design.verify_samples=100"]


@pytest.fixture(scope="module")
def free_store(tmp_path_factory):
    """The sample-free design (continuous dispersions off), shared by two tests."""
    return run_file(DESIGN, out=tmp_path_factory.mktemp("free") / "r.zarr",
                    overrides=FREE + ["design.tolerant_markers=true"])


def test_sample_free_design_is_exact(free_store, tmp_path):
    """Continuous dispersions off: one exact scenario; P-hat is the exact P, and so is its
    bound (exact enumeration over the nominal masks, computed here in numpy)."""
    sets = FREE
    ds = xr.open_zarr(free_store)
    c = load(DESIGN, sets)
    setup = setup_from_campaign(c)
    bank = build_bank(setup, c.config.design.grid_step_rad)
    w = bank.areas / bank.areas.sum()
    need = ds.attrs["reliability_threshold"]
    n = int(ds["best_swarm_size"])
    idx = np.rint(np.asarray(ds["swarm_angle"].values) / bank.step_rad).astype(int) % bank.n_candidates
    p = exact_p(bank.masks, w, list(idx), need, 0.05)
    assert float(ds["reliability_probability"]) == pytest.approx(p, abs=1e-12)
    assert float(ds["validation_p_hat"]) == pytest.approx(p, abs=1e-12)
    assert float(ds["validation_lower_bound"]) == pytest.approx(p, abs=1e-12)
    assert bool(ds["demonstrated"]) == (p >= 0.9)
    assert p >= 0.9
    # one scenario of 12 candidates: the answer is proven, and no swarm of n - 1
    # reaches p (every one of them scored here, within the design's separation)
    assert ds.attrs["solver_status"] == "optimal" and float(ds.attrs["optimality_gap"]) == 0.0
    assert int(ds["proven_bound"]) == n
    m_sep = separation_steps(bank.step_rad, setup.d_sep_m, c.config.swarm.min_separation_m,
                             bank.n_candidates)
    smaller = all_swarms(bank.n_candidates, n - 1, m_sep)
    assert smaller.shape[0] > 0
    best_smaller = swarm_probabilities(np.ascontiguousarray(bank.masks[None]), smaller, w,
                                       need, 0.05).max()
    assert best_smaller < 0.9
    # asked for, the k-failure-tolerant markers: P at least the binomial chance of at most
    # k failures of N_k, and no (N_k - 1)-swarm keeps the threshold through every k failures
    # (k = 2 only when 12 candidates can tolerate two failures within n_max)
    ks = list(ds["tolerated"].values)
    assert ks and ks == list(range(1, len(ks) + 1))

    def covers(members):
        return bool(members) and w[bank.masks[list(members)].any(axis=0)].sum() >= need - 1e-12

    for k, n_k, p_k in zip(ds["tolerated"].values, ds["tolerant_swarm_size"].values,
                           ds["tolerant_probability"].values):
        assert p_k >= binom.cdf(k, n_k, 0.05) - 1e-12
        for sw in all_swarms(bank.n_candidates, int(n_k) - 1, m_sep):
            assert not all(covers(sub) for sub in itertools.combinations(sw, int(n_k) - 1 - k))
    assert ds["reliability_vs_n"].attrs["units"] == "1"
    assert "long_name" in ds["validation_lower_bound"].attrs
    # the optimisation on the bank and the validation are stored apart (nothing stepped here)
    assert int(ds["bank_swarm_size"]) == n and ds.attrs["demonstrate_steps"] == "none"
    assert float(ds["bank_probability"]) == pytest.approx(p, abs=1e-12)
    assert str(ds["validation_outcome"].values) == ("demonstrated" if p >= 0.9 else
                                                   "not demonstrated")
    with figures.kept() as figs:
        rep = write_report(free_store, tmp_path / "rep")
    text = Path(rep).read_text()
    printed_int(text, "optimisation on the scenario bank", n, int(ds["proven_bound"]))
    printed(text, "optimisation on the scenario bank", p, 100 * float(ds["optimality_gap"]))
    printed(text, "^validation", p, p)
    assert [ln for ln in lines_for(text, "^success-probability design") if f"N = {n}," in ln
            and "requirement DEMONSTRATED by validation" in ln and "stepped" not in ln]
    assert "status" not in text.split("success-probability design")[0].splitlines()[-1]
    assert "DEMONSTRATED by validation" in figs["design_ring.png"].axes[0].get_title()
    # a store written before the split, stepped up by one: the bank's answer comes back
    old = ds.drop_vars(["bank_swarm_size", "bank_probability", "validation_outcome"]).assign(
        solver_status=((), "demonstrated"), best_swarm_size=((), np.int64(n + 1)))
    nb, pb, _, _, gap, steps = bank_answer(old)
    assert nb == n and steps == f"N stepped up from {n} to {n + 1}"
    assert pb == pytest.approx(p, abs=1e-12) and gap == pytest.approx(float(ds["optimality_gap"]))
    ax = figs["design_validation_coverage.png"].axes[0]      # all flights at one coverage
    thr = [line for line in ax.get_lines() if line.get_label().startswith("threshold")]
    assert np.allclose(thr[0].get_xdata(), 100 * need)
    lo, hi = ax.get_xlim()
    assert lo < 100 * need < hi and ds.attrs["shape_model"] in ax.get_title()
    figures.plt.close("all")


@pytest.mark.slow
def test_dispersed_design_stores_validation(tmp_path):
    # a 20 deg grid (18 candidates): the scenario programme (HiGHS, most of this test's
    # time at 10 deg) still has to prove the bank's answer, and the looks, bounds, stored
    # validation and report checked below do not depend on how many candidates there are
    sets = [k if not k.startswith("design.angle_step_deg") else "design.angle_step_deg=20"
            for k in BASE] + ["design.success_probability=0.5", "design.scenarios=20",
                   "design.verify_samples=24", "monte_carlo.failure_probability=0.05",
                   "design.demonstrate=true", "design.n_max=8"]
    ds = xr.open_zarr(run_file(DESIGN, out=tmp_path / "d.zarr", overrides=sets))
    v = ds["validation_probability"].values
    assert v.shape == (24,) and np.all((v >= 0) & (v <= 1))
    # no failure-tolerant markers unless asked (design.tolerant_markers, issue 43)
    assert ds.sizes.get("tolerated", 0) == 0
    assert float(ds["validation_p_hat"]) == pytest.approx(v.mean())
    assert float(ds["validation_lower_bound"]) <= v.mean()
    assert bool(ds["demonstrated"]) == (float(ds["validation_lower_bound"]) >= 0.5)
    assert int(ds["best_swarm_size"]) in ds["reliability_n"].values
    assert ds.attrs["scenario_stream"] != ds.attrs["validation_stream"]
    # p = 0.5 with swarms of up to 8 of p_f = 0.05: demonstrated, at the first look whose
    # bound (at its share 0.05 / K) reaches p; every earlier look missed it
    n, n_bank = int(ds["best_swarm_size"]), int(ds["bank_swarm_size"])
    lows = ds["validation_look_lower_bound"].values
    assert bool(ds["demonstrated"]) and lows[-1] >= 0.5 and np.all(lows[:-1] < 0.5)
    assert list(ds["validation_look_n"].values) == list(range(n_bank, n + 1))
    assert list(ds["validation_look_first_sample"].values) == [24 * j for j in range(lows.size)]
    # 20 scenarios x 18 candidates: the scenario programme proves the bank's answer
    assert ds.attrs["solver_status"] == "optimal"
    assert n_bank <= n and float(ds["bank_probability"]) >= 0.5
    assert float(ds["optimality_gap"]) == pytest.approx((n_bank - float(ds["proven_bound"]))
                                                        / n_bank)
    steps = ds.attrs["demonstrate_steps"]
    assert steps == ("none" if n == n_bank else f"N stepped up from {n_bank} to {n}")
    text = Path(write_report(tmp_path / "d.zarr", tmp_path / "rep")).read_text()
    printed_int(text, "optimisation on the scenario bank", n_bank)
    verdict = "DEMONSTRATED" if bool(ds["demonstrated"]) else "NOT demonstrated"
    assert [ln for ln in lines_for(text, "^success-probability design")
            if f"N = {n}, requirement {verdict}" in ln and (n == n_bank or steps in ln)]
    assert (tmp_path / "d-scenarios.zarr").exists()      # the bank, for reuse


def test_sample_free_design_is_exact_on_a_fast_encounter(tmp_path):
    """The success-probability design over the ring perpendicular to a 10 km/s approach
    (issue 24): with the continuous dispersions off its P, P-hat and bound are the exact
    failure-enumerated P of the chosen swarm over the nominal masks (numpy here)."""
    enc = ROOT / "campaigns" / "eros-fast-encounter.toml"
    sets = ['body.name="ellipsoid"', "dynamics.srp=false", "design.angle_step_deg=15",
            "coverage.require_lit=false", "coverage.occlusion=false", "run.workers=0", "design.verify_samples=100",
            "design.success_probability=0.9", "monte_carlo.failure_probability=0.05",
            "design.scenarios=100"] + QUIET
    ds = xr.open_zarr(run_file(enc, out=tmp_path / "e.zarr", overrides=sets))
    c = load(enc, sets)
    assert c.config.flyby.geometry == "encounter"
    setup = setup_from_campaign(c)
    bank = build_bank(setup, c.config.design.grid_step_rad)
    w = bank.areas / bank.areas.sum()
    need = ds.attrs["reliability_threshold"]
    idx = np.rint(np.asarray(ds["swarm_angle"].values) / bank.step_rad).astype(int) % bank.n_candidates
    p = exact_p(bank.masks, w, list(idx), need, 0.05)
    assert p >= 0.9
    assert float(ds["reliability_probability"]) == pytest.approx(p, abs=1e-12)
    assert float(ds["validation_p_hat"]) == pytest.approx(p, abs=1e-12)
    assert float(ds["validation_lower_bound"]) == pytest.approx(p, abs=1e-12)


def test_design_must_step_n_up(free_store, tmp_path):
    """design.demonstrate steps N up when it must (issue 34), each look on fresh samples at
    (1 - confidence) / K (issue 29).

    Setup that forces it: continuous dispersions of 1 mm in position only, so every scenario
    and every validation sample sees the nominal masks and the per-sample P of a swarm is
    one number c; p_f is chosen so that the fewest N0 covering spacecraft have c = p exactly.
    The bank then answers N0, but a bound on M values all equal to c lies below c = p: the
    first look must fail, and N0 + 1 (P well above p) must be looked at on new samples.
    With no held-out scenarios the looks are not predicted (every size from N0 up is a
    look: the step-up of issue 34); the planned looks are
    :func:`test_planned_looks_skip_the_size_that_cannot_pass`.
    """
    base = BASE20 + QUIET + ["monte_carlo.sigma_position_m=0.001", "design.holdout_scenarios=0"]
    c = load(DESIGN, base + ["design.success_probability=0.9"])
    setup = setup_from_campaign(c)
    bank = build_bank(setup, c.config.design.grid_step_rad)
    # the threshold and the plain minimum N0 of the sample-free design of this file
    free = xr.open_zarr(free_store)
    need, n0 = free.attrs["reliability_threshold"], int(free["nominal_swarm_size"])
    p_f = 1.0 - 0.55 ** (1.0 / n0)
    m_sep = separation_steps(bank.step_rad, setup.d_sep_m, c.config.swarm.min_separation_m,
                             bank.n_candidates)
    rel = ReliabilityDesigner(bank.masks[None], bank.areas, need=need, p_f=p_f, sep_steps=m_sep)
    p = float(rel.best_of(n0)[1])
    assert 0.5 < p < 0.9 and rel.best_of(n0 - 1)[1] < p
    sets = base + [f"design.success_probability={p!r}", f"monte_carlo.failure_probability={p_f!r}",
                   "design.scenarios=24", "design.verify_samples=200", "design.demonstrate=true",
                   "design.n_max=12"]
    ds = xr.open_zarr(run_file(DESIGN, out=tmp_path / "s.zarr", overrides=sets))
    assert ds.attrs["continuous_dispersions"] == "sampled"
    assert int(ds["bank_swarm_size"]) == n0
    looks_n = ds["validation_look_n"].values
    lows = ds["validation_look_lower_bound"].values
    hats = ds["validation_look_p_hat"].values
    assert hats[0] == pytest.approx(p, abs=1e-12)          # the premise: every value is c = p
    assert lows[0] < p                                     # so the first look must fail
    assert list(looks_n[:2]) == [n0, n0 + 1] and int(ds["best_swarm_size"]) == looks_n[-1]
    assert list(ds["validation_look_first_sample"].values) == [200 * j
                                                               for j in range(looks_n.size)]
    k = min(4, 12 - n0 + 1)
    assert int(ds["validation_looks_planned"]) == k
    assert float(ds["validation_look_confidence"]) == pytest.approx(1 - 0.05 / k)
    assert bool(ds["demonstrated"]) and lows[-1] >= p and np.all(lows[:-1] < p)
    assert ds.attrs["demonstrate_steps"] == f"N stepped up from {n0} to {int(looks_n[-1])}"
    # 24 scenarios cut no two sample problems of >= 16: no statistical lower bound, said so
    assert np.isnan(float(ds["statistical_lower_bound"]))
    for name in ("bank_level", "validation_look_confidence", "validation_look_lower_bound",
                 "statistical_lower_bound", "validation_first_sample"):
        assert ds[name].attrs["long_name"]
    assert float(ds["bank_level"]) == p
    cert = ds.attrs["certificate"]
    first = 200 * (looks_n.size - 1)
    assert f"N = {int(looks_n[-1])} swarm DEMONSTRATED" in cert
    assert f"samples {first}..{first + 199}" in cert and "chose nothing" in cert
    text = Path(write_report(tmp_path / "s.zarr", tmp_path / "rep", html=True)).read_text()
    assert cert in text
    # report --html: the reliability curve and the certified swarm's validation distribution
    n = int(looks_n[-1])
    page = (tmp_path / "rep" / "report.html").read_text()
    curve, val = reliability_html_figures(ds)
    assert curve.layout.title.text in page and val.layout.title.text in page
    traces = {t.name: t for t in curve.data}
    assert np.array_equal(traces["validated P-hat"].x, ds["reliability_n"].values)
    assert np.allclose(traces["best P on the scenario bank"].y, ds["reliability_vs_n"].values)
    marks = [a.text for a in curve.layout.annotations]
    assert f"certified N = {n} (DEMONSTRATED)" in marks and f"bank N = {n0}" in marks
    assert f"validation of the certified N = {n} swarm (samples {first}..{first + 199})" \
        in val.layout.title.text
    assert np.allclose(val.data[0].x, np.sort(ds["validation_probability"].values))
    assert np.allclose(val.data[1].x, np.sort(100 * ds["validation_coverage"].values))
    printed(text, f"^validation of the N = {int(looks_n[-1])} swarm", hats[-1], lows[-1])
    # the nominal design's worst failure (stored for N0 > 1) names the nominal swarm
    assert n0 > 1 and "worst_failure_coverage" in ds
    assert lines_for(text, f"^worst case.*of the nominal N = {n0} swarm")


def test_planned_looks_skip_the_size_that_cannot_pass(free_store, tmp_path):
    """Looks that can pass (issue 41, item 3): the setup of :func:`test_design_must_step_n_up`
    (every scenario and sample gives N0 exactly P = p), now with held-out scenarios. The plan
    sees from them alone that no 200 samples of N0 can give a bound >= p (the bound of
    values all equal to p lies below p), skips N0 without spending error on it and looks
    first at N0 + 1, which it demonstrates; the certificate line names the skipped size.
    The held-out P of every curve swarm equals its bank P (the scenarios do not differ)."""
    base = BASE20 + QUIET + ["monte_carlo.sigma_position_m=0.001"]
    free = xr.open_zarr(free_store)
    need, n0 = free.attrs["reliability_threshold"], int(free["nominal_swarm_size"])
    c = load(DESIGN, base + ["design.success_probability=0.9"])
    setup = setup_from_campaign(c)
    bank = build_bank(setup, c.config.design.grid_step_rad)
    p_f = 1.0 - 0.55 ** (1.0 / n0)
    m_sep = separation_steps(bank.step_rad, setup.d_sep_m, c.config.swarm.min_separation_m,
                             bank.n_candidates)
    rel = ReliabilityDesigner(bank.masks[None], bank.areas, need=need, p_f=p_f, sep_steps=m_sep)
    p = float(rel.best_of(n0)[1])
    sets = base + [f"design.success_probability={p!r}", f"monte_carlo.failure_probability={p_f!r}",
                   "design.scenarios=24", "design.holdout_scenarios=24",
                   "design.verify_samples=200", "design.demonstrate=true", "design.n_max=12"]
    ds = xr.open_zarr(run_file(DESIGN, out=tmp_path / "s.zarr", overrides=sets))
    assert int(ds["bank_swarm_size"]) == n0
    looks_n = ds["validation_look_n"].values
    assert looks_n[0] == n0 + 1 and bool(ds["demonstrated"]) and looks_n.size == 1
    assert int(ds["best_swarm_size"]) == n0 + 1
    k = int(ds["validation_looks_planned"])
    assert k == min(4, 12 - (n0 + 1) + 1)
    assert float(ds["validation_look_confidence"]) == pytest.approx(1 - 0.05 / k)
    assert f"N = {n0} (0.0 %)" in ds.attrs["certificate"] and "skipped" in ds.attrs["certificate"]
    assert ds.attrs["n_holdout_scenarios"] == 24 and float(ds["bank_bias"]) == 0.0
    np.testing.assert_allclose(ds["reliability_vs_n_holdout"].values,
                               ds["reliability_vs_n"].values, rtol=0, atol=1e-12)
    assert bool(ds["bank_validation_agree"])     # one value everywhere: held-out = P-hat
