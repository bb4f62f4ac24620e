"""The declared Monte Carlo dispersions: stream layout, draw order, store layout."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.campaign.schema import load
from ideas_hpc.flyby import setup_from_campaign
from ideas_hpc.montecarlo.dispersions import (DISPERSION_CHILD, DISPERSION_ORDER,
                                              DISPERSION_VARS, DISPERSIONS, draw_sample)
from test_campaign_mc import MC, SHORT, one_worker  # noqa: F401  (module fixture)

THETA = np.array([0.2, 1.7, 2.4])


@pytest.fixture(scope="module")
def campaign():
    c = load(MC, SHORT)
    return c, setup_from_campaign(c)


def test_child_stream_is_drawn_in_the_documented_order(campaign):
    # Independent re-derivation from numpy's SeedSequence, in the order the
    # module docstring promises: gravity(3), reflectivity(1), r(n,3), v(n,3),
    # failures (permutation, n uniforms), misalignment (axes n x 3, angles n).
    c, setup = campaign
    mc, seed, k, n = c.config.monte_carlo, 99, 5, THETA.size
    values, pert = draw_sample(mc, seed, k, THETA, setup)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k, DISPERSION_CHILD)))
    z = rng.standard_normal(3)
    u = rng.uniform()
    dr, dv = rng.standard_normal((n, 3)), rng.standard_normal((n, 3))
    perm, bern = rng.permutation(n), rng.uniform(0, 1, n)
    axes, ang = rng.standard_normal((n, 3)), rng.standard_normal(n)
    p = setup.body.params
    assert values["c20"] == p.c20 * (1 + mc.sigma_c20_pct / 100 * z[0])
    assert values["mu"] == p.mu * (1 + mc.sigma_gm_pct / 100 * z[2])
    lo, hi = mc.reflectivity_min, mc.reflectivity_max
    assert values["reflectivity"] == lo + (hi - lo) * u
    np.testing.assert_array_equal(values["position_error"], mc.sigma_position_m * dr)
    np.testing.assert_array_equal(values["velocity_error"], mc.sigma_velocity_m_s * dv)
    expect_active = np.ones(n, bool)
    expect_active[perm[:mc.failures_k]] = False
    expect_active &= bern >= mc.failure_probability
    np.testing.assert_array_equal(values["active"], expect_active)
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    np.testing.assert_allclose(values["misalignment_prv"],
                               axes * (mc.sigma_misalignment_rad * ang)[:, None], rtol=0)
    # and the perturbation carries exactly those values to the flyby
    assert pert["params_override"] == {k2: values[k2] for k2 in ("mu", "c20", "c22",
                                                                  "reflectivity")}
    assert pert["active"] is values["active"]


def test_switching_a_dispersion_off_does_not_shift_the_others(campaign):
    c, setup = campaign
    mc = c.config.monte_carlo
    on, _ = draw_sample(mc, 7, 3, THETA, setup)
    off, _ = draw_sample(dataclasses.replace(mc, sigma_c20_pct=0.0, sigma_position_m=0.0), 7, 3,
                         THETA,
                         setup)
    assert off["c20"] == setup.body.params.c20 and not off["position_error"].any()
    for name in ("c22", "mu", "reflectivity", "velocity_error", "active", "misalignment_prv",
                 "sigma0"):
        np.testing.assert_array_equal(on[name], off[name], err_msg=name)


def test_declared_list_is_the_store_layout(one_worker):  # noqa: F811
    ds = xr.open_zarr(one_worker)
    assert tuple(ds.attrs["dispersion_order"]) == DISPERSION_ORDER
    assert len(set(DISPERSION_ORDER)) == len(DISPERSIONS)
    for var in DISPERSION_VARS:
        assert ds[var.name].dims == ("sample", *var.dims), var.name
        assert ds[var.name].dtype == np.dtype(var.dtype), var.name
        assert ds[var.name].attrs.get("units") == var.units, var.name
