"""``ideas-hpc validate``: an independent validation of a design store's swarm (issue 29)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.campaign.validate_store import wilson_interval, validate_store
from ideas_hpc.cli import main
from ideas_hpc.base.errors import InputError
from small_stores import small_store


@pytest.mark.parametrize("k,n", [(0, 10), (3, 10), (10, 10), (983, 1024), (1, 1)])
def test_wilson_ends_solve_the_score_equation(k, n):
    """Wilson's interval is the set of p with |p_hat - p| <= z sqrt(p (1 - p) / n): its ends
    are the roots of that quadratic, clipped to [0, 1]."""
    z = 1.959963984540054
    lo, hi = wilson_interval(k, n)
    p_hat = k / n
    for end in (lo, hi):
        if 0.0 < end < 1.0:
            assert (p_hat - end) ** 2 == pytest.approx(z * z * end * (1 - end) / n, abs=1e-12)
    assert lo <= p_hat <= hi
    assert (lo == 0.0) == (k == 0) and (hi == 1.0) == (k == n)
    mid = 0.5 * (lo + hi)            # inside: the score statistic is below z
    assert abs(p_hat - mid) <= z * math.sqrt(mid * (1 - mid) / n) + 1e-12


def test_validation_reproduces_the_design_and_draws_fresh(tmp_path_factory):
    store = small_store("design-reliability", tmp_path_factory.mktemp("small-stores"))
    ds = xr.open_zarr(store)
    first = int(ds["validation_first_sample"])
    m = int(ds["validation_probability"].size)
    seed = int(ds.attrs["campaign_seed"])
    # on the design's own seed and samples, this independent path gives the stored values
    same = validate_store(store, samples=m, seed=seed, first=first, progress=False,
                          same_seed=True)
    np.testing.assert_allclose(same.per_sample, ds["validation_probability"].values,
                               atol=1e-12)
    need = float(ds.attrs["reliability_threshold"])
    stored_wins = int((ds["validation_coverage"].values >= need - 1e-12).sum())
    assert same.successes == stored_wins
    with pytest.raises(InputError) as e:
        validate_store(store, samples=2, seed=seed, progress=False)
    assert e.value.field == "--seed"
    fresh = validate_store(store, samples=m, progress=False)
    assert fresh.seed == seed + 1 and fresh.samples == m
    assert 0.0 <= fresh.lower <= fresh.p_hat <= 1.0


def test_cli_prints_one_line(tmp_path_factory, capsys):
    store = small_store("design-reliability", tmp_path_factory.mktemp("small-stores"))
    assert main(["validate", str(store), "--samples", "4", "--no-progress"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and out[0].startswith("independent validation: N = ")
    assert "Wilson 95 %" in out[0]
