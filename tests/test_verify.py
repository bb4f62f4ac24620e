"""Monte Carlo verification of a design: the same samples as a monte-carlo campaign."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ideas_hpc.campaign.montecarlo import run_sample
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema import load
from ideas_hpc.flyby import setup_from_campaign
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
    for k in range(3):
        r = run_sample(c, k)
        assert v.coverage[k] == r["coverage"][0], k
        assert v.n_failed[k] == int((~r["active"][0]).sum()), k
    assert v.probability == np.mean(v.coverage >= 0.999)


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
    ds = xr.open_zarr(run_file(ROOT / "campaigns" / "eros-design-nominal.toml",
                               out=tmp_path / "d.zarr", overrides=sets))
    cov = ds["verify_coverage"].values
    assert cov.shape == (6,) and ds["verify_coverage"].attrs["units"] == "1"
    assert np.all(ds["verify_n_failed"].values == 1)
    assert np.all(cov >= float(ds["worst_failure_coverage"]) - 1e-12)
    assert np.all(cov <= float(ds["design_coverage"]) + 1e-12)
    assert np.unique(np.round(cov, 10)).size <= ds.sizes["spacecraft"]  # N failure cases
    thr = ds.attrs["verify_threshold"]
    assert thr == ds.attrs["target_coverage"] - 0.001
    assert ds.attrs["verify_probability"] == np.mean(cov >= thr)
