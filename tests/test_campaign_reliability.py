"""design-nadir with design.success_probability through run_file (issue 20), ellipsoid body."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.campaign.report import write_report
from ideas_hpc.campaign.report_reliability import bank_answer
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.design import build_bank
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


def test_sample_free_design_is_exact(tmp_path):
    """Continuous dispersions off: one exact scenario; P-hat is the exact P, and so is its
    bound (exact enumeration over the nominal masks, computed here in numpy)."""
    sets = BASE + QUIET + ["design.success_probability=0.9", "monte_carlo.failure_probability=0.05",
                           "design.scenarios=100", "design.verify_samples=100"]
    ds = xr.open_zarr(run_file(DESIGN, out=tmp_path / "r.zarr", overrides=sets))
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
    # the proven bound: no swarm of n - 1 reaches p (the store's upper bound says so)
    assert float(ds.attrs["optimality_gap"]) == 0.0 or ds.attrs["solver_status"] != "optimal"
    assert ds["reliability_vs_n"].attrs["units"] == "1"
    assert "long_name" in ds["validation_lower_bound"].attrs
    # the optimisation on the bank and the validation are stored apart (nothing stepped here)
    assert ds.attrs["solver_status"] in ("optimal", "time_limit", "feasible")
    assert int(ds["bank_swarm_size"]) == n and ds.attrs["demonstrate_steps"] == "none"
    assert float(ds["bank_probability"]) == pytest.approx(p, abs=1e-12)
    assert str(ds["validation_outcome"].values) == ("demonstrated" if p >= 0.9 else
                                                   "not demonstrated")
    with figures.kept() as figs:
        rep = write_report(tmp_path / "r.zarr", tmp_path / "rep")
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
    sets = BASE + ["design.success_probability=0.5", "design.scenarios=20",
                   "design.verify_samples=24", "monte_carlo.failure_probability=0.05",
                   "design.demonstrate=true", "design.n_max=8"]
    ds = xr.open_zarr(run_file(DESIGN, out=tmp_path / "d.zarr", overrides=sets))
    v = ds["validation_probability"].values
    assert v.shape == (24,) and np.all((v >= 0) & (v <= 1))
    assert float(ds["validation_p_hat"]) == pytest.approx(v.mean())
    assert float(ds["validation_lower_bound"]) <= v.mean()
    assert bool(ds["demonstrated"]) == (float(ds["validation_lower_bound"]) >= 0.5)
    assert int(ds["best_swarm_size"]) in ds["reliability_n"].values
    assert ds.attrs["scenario_stream"] != ds.attrs["validation_stream"]
    # design.demonstrate: stepped up until the bound reaches p, or n_max
    assert bool(ds["demonstrated"]) or int(ds["best_swarm_size"]) == 8
    # the optimisation's status, bound and gap are the bank-optimal N's, whatever stepping did
    n, n_bank = int(ds["best_swarm_size"]), int(ds["bank_swarm_size"])
    assert ds.attrs["solver_status"] in ("optimal", "time_limit", "feasible")
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
