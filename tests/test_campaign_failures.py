"""A success-probability design under the failure model of issue 41, end to end: a beta
factor and an uncertain p_f (sample-free, so the one scenario's masks are the oracle's)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.design import build_bank
from ideas_hpc.plots import figures
from ideas_hpc.report.write import write_report

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "campaigns" / "eros-design.toml"
FREE = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        "dynamics.srp=false", "design.angle_step_deg=30", 'attitude.mode="ideal"',
        "run.workers=0", "design.time_limit_s=60"] + [
    f"monte_carlo.{k}=0.0" for k in ("sigma_c20_pct", "sigma_c22_pct", "sigma_gm_pct",
                                     "sigma_position_m", "sigma_velocity_mm_s",
                                     "sigma_misalignment_deg")] + [
    "monte_carlo.reflectivity_min=0.6", "monte_carlo.reflectivity_max=0.6",
    "design.success_probability=0.9", "monte_carlo.failure_probability=0.05",
    "design.scenarios=100", "design.verify_samples=100"]
MODEL = ["monte_carlo.common_cause_beta=0.1", "monte_carlo.failure_probability_sd=0.02"]


def direct_mc(masks, w, swarm, need, draws, seed):
    """Direct draws of the model: p_f ~ Beta(mean 0.05, sd 0.02), a common-cause event of
    probability 0.1 p_f over the swarm, independent failures of 0.9 p_f; success when the
    survivors' masks cover ``need``."""
    rng = np.random.default_rng(seed)
    nu = 0.05 * 0.95 / 0.02 ** 2 - 1.0
    p = rng.beta(0.05 * nu, 0.95 * nu, draws)
    n = len(swarm)
    failed = (rng.random((draws, n)) < 0.9 * p[:, None]) | (rng.random(draws) < 0.1 * p)[:, None]
    cover = np.array([bool(mask) and w[masks[[swarm[i] for i in range(n) if mask >> i & 1]]
                                        .any(axis=0)].sum() >= need - 1e-12
                      for mask in range(1 << n)])
    return cover[((~failed) * (1 << np.arange(n))).sum(axis=1)].mean()


def test_design_under_common_cause_and_prior(tmp_path):
    store = run_file(DESIGN, out=tmp_path / "r.zarr", overrides=FREE + MODEL)
    ds = xr.open_zarr(store)
    c = load(DESIGN, FREE + MODEL)
    bank = build_bank(setup_from_campaign(c), c.config.design.grid_step_rad)
    w = bank.areas / bank.areas.sum()
    need = float(ds.attrs["reliability_threshold"])
    idx = list(np.rint(np.asarray(ds["swarm_angle"].values) / bank.step_rad).astype(int)
               % bank.n_candidates)
    draws = 400_000
    got = direct_mc(bank.masks, w, idx, need, draws, seed=3)
    want = float(ds["reliability_probability"])
    se = math.sqrt(want * (1 - want) / draws)
    assert abs(got - want) < 4 * se, (got, want, se)
    assert want >= 0.9 and int(ds["best_swarm_size"]) == len(idx)
    # the curve, each N's P the exact one of its swarm (the same direct draws)
    for n, p_n, sw in zip(ds["reliability_n"].values, ds["reliability_vs_n"].values,
                          ds["reliability_vs_n_swarm"].values):
        members = list(np.rint(sw[:int(n)] / bank.step_rad).astype(int) % bank.n_candidates)
        mc = direct_mc(bank.masks, w, members, need, 100_000, seed=int(n))
        assert abs(mc - p_n) < 4 * math.sqrt(max(p_n * (1 - p_n), 1e-4) / 100_000) + 1e-12
    # N at the prior's quantiles, each proven (12 candidates): P falls as p_f rises, so the
    # fewest N cannot fall; each level's swarm meets p
    lv = ds["swarm_size_at_p_f"].values
    assert lv.size == 5 and np.all(np.diff(ds["p_f_level"]) > 0)
    assert np.array_equal(ds["proven_bound_at_p_f"].values, lv) and np.all(np.diff(lv) >= 0)
    assert np.all(ds["probability_at_p_f"].values >= 0.9)
    assert "common cause beta = 0.1" in ds.attrs["failure_model"]
    assert ds.attrs["failure_model_record"]["prior"] == {"beta_mean": 0.05, "beta_sd": 0.02}
    with figures.kept():
        text = Path(write_report(store, tmp_path / "rep")).read_text()
    figures.plt.close("all")
    assert "Beta(mean 0.05, sd 0.02" in text and "at known p_f" in text
