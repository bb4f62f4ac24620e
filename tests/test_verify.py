"""Monte Carlo verification of a design: the same samples as a monte-carlo campaign."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from design_oracle import subset_coverage
from ideas_hpc.design import build_bank

from ideas_hpc.campaign.montecarlo import run_sample
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign

from campaign_copies import fitted
from ideas_hpc.montecarlo.verify import verify_swarm
from test_campaign_mc import MC, ROOT, SHORT


def test_verification_samples_are_monte_carlo_samples():
    # Sample k of a verification is sample k of a monte-carlo campaign with the
    # same seed, swarm and [monte_carlo] table: a user can re-run any of them.
    c = load(MC, SHORT + ["monte_carlo.failure_probability=0.3"])
    setup = setup_from_campaign(c)
    theta = np.asarray(c.config.swarm.angles_rad)
    v = verify_swarm(setup, theta, None, mc=c.config.monte_carlo, seed=c.config.seed,
                     n_samples=3, threshold=0.999)
    flown = []
    for k in range(3):
        r = run_sample(c, k)
        flown.append(r["coverage"][0])
        assert v.coverage[k] == r["coverage"][0], k
        assert v.n_failed[k] == int((~r["active"][0]).sum()), k
    # P counted over the monte-carlo campaign's own samples
    assert v.probability == sum(f >= 0.999 for f in flown) / 3


def test_design_store_holds_the_verification(tmp_path):
    sets = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
            "flyby.z_stop_km=3", "design.angle_step_deg=5", "design.verify_samples=6",
            "monte_carlo.failures_k=1", "monte_carlo.failure_probability=0.0",
            "run.workers=0", "dynamics.srp=false"]
    # every dispersion but one failure off: each sample is the nominal swarm
    # minus one spacecraft, one of the failure cases the design enumerated
    for key in ("sigma_c20_pct", "sigma_c22_pct", "sigma_gm_pct", "sigma_position_m",
                "sigma_velocity_mm_s", "sigma_misalignment_deg"):
        sets.append(f"monte_carlo.{key}=0.0")
    campaign = ROOT / "campaigns" / "eros-design-nominal.toml"
    ds = xr.open_zarr(run_file(campaign, out=tmp_path / "d.zarr", overrides=sets))
    cov = ds["verify_coverage"].values
    assert cov.shape == (6,) and ds["verify_coverage"].attrs["units"] == "1"
    assert np.all(ds["verify_n_failed"].values == 1)
    # the N failure cases, counted here from freshly computed candidate masks: the swarm
    # without spacecraft i, for every i
    c = load(campaign, sets)
    bank = build_bank(setup_from_campaign(c), np.deg2rad(5.0))
    idx = np.rint(np.mod(ds["swarm_angle"].values, 2 * np.pi) / bank.step_rad).astype(int)
    cases = subset_coverage(bank.masks, bank.areas,
                            np.array([np.delete(idx, i) for i in range(idx.size)]))
    assert float(ds["worst_failure_coverage"]) == pytest.approx(cases.min(), abs=1e-12)
    for x in cov:     # every sample is one of them
        assert np.min(np.abs(cases - x)) <= 1e-12, (x, cases)
    # the threshold is the configured requirement (the file's percentage), and P the
    # fraction of samples that meet it (the designers' comparison, 1e-12 below included)
    thr = ds.attrs["verify_threshold"]
    assert thr == pytest.approx(ds.attrs["target_coverage"] - c.raw["design"]["eps_tol_pct"]
                                / 100, abs=1e-15)
    above = [np.any((np.abs(cases - x) <= 1e-12) & (cases >= thr - 1e-12)) for x in cov]
    assert ds.attrs["verify_probability"] == pytest.approx(np.mean(above), abs=1e-15)


def _counted_vs_uncounted(c, ks):
    """Fly samples ``ks`` both ways; the counted path is the oracle (full scan)."""
    from ideas_hpc.flyby.flight import Perturbation
    from ideas_hpc.montecarlo.dispersions import draw_sample
    from ideas_hpc.montecarlo.sample import design_nominal, fly_sample

    setup = setup_from_campaign(c)
    nom = design_nominal(setup, c.config.swarm.angles_rad, None)
    most = 0
    for k in ks:
        _, pert = draw_sample(c.config.monte_carlo, c.config.seed, k, nom.theta, setup)
        full = fly_sample(setup, nom, Perturbation(**pert))
        fast = fly_sample(setup, nom, Perturbation(**pert), counts=False)
        most = max(most, int(full["times_seen"].max()))
        assert fast["coverage"] == full["coverage"], k
        assert fast["coverage_count"] == full["coverage_count"], k
        assert np.array_equal(fast["observed"], full["times_seen"] > 0), k
        assert np.array_equal(fast["first_seen"], full["first_seen"], equal_nan=True), k
        assert np.array_equal(fast["times_seen"], (full["times_seen"] > 0).astype(np.int32))
        assert 0.0 < full["coverage"] or not pert["active"].any(), k
    assert most > 1  # the counted path really counted


STRICT = ['attitude.mode="ideal"', 'coverage.mode="exact"', "coverage.occlusion=true",
          "coverage.min_elevation_deg=5.0", "monte_carlo.failure_probability=0.3"]
#: the shipped Monte Carlo without what an ideal attitude does not read (its start)
IDEAL_MC = fitted("eros-monte-carlo.toml", STRICT)


def test_uncounted_samples_have_the_counted_coverage_ellipsoid():
    # the verification's no-counts path against full per-vertex counts, paper and strict
    _counted_vs_uncounted(load(MC, SHORT + ["monte_carlo.failure_probability=0.3"]), range(3))
    _counted_vs_uncounted(load(IDEAL_MC, SHORT + STRICT), range(3))


def test_uncounted_samples_have_the_counted_coverage_eros(eros1708):
    c = load(IDEAL_MC, ['body.name="eros"', "flyby.tf_s=300", "flyby.z_start_km=-20",
                  "flyby.z_stop_km=20", "swarm.angles_rad=[0.2, 2.4, 4.4]"] + STRICT)
    assert setup_from_campaign(c).body.shape.n_vertices == eros1708.shape.n_vertices
    _counted_vs_uncounted(c, range(4))
