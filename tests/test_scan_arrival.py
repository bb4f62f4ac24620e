"""``ideas-hpc scan-arrival`` end to end (issue 23 item 7): the epoch grid, ``--span-h``,
the netCDF output opened with xarray, and one scanned epoch equal to a flyby campaign
flown at that epoch."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.cli import main
from ideas_hpc.campaign.setup import setup_from_campaign

from campaign_copies import fitted

EPOCH0 = 3600.0
# lit mapping as the requirement, so that coverage depends on the Sun (on the epoch)
SETS = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        'attitude.mode="ideal"', "coverage.require_lit=true", f"flyby.epoch_s={EPOCH0}"]
#: the shipped flyby without what an ideal attitude does not read ([controller], its start)
FLYBY = fitted("eros-flyby.toml", SETS)


def _scan(tmp_path, name, *args):
    out = tmp_path / name
    cli = ["scan-arrival", str(FLYBY), *args, "--out", str(out)]
    for s in SETS:
        cli += ["--set", s]
    assert main(cli) == 0
    return xr.open_dataset(out)


def test_scan_arrival_grid_span_netcdf_and_one_flyby(tmp_path, capsys):
    ds = _scan(tmp_path, "span.nc", "--n", "3", "--span-h", "2.5")
    # the grid: n epochs from flyby.epoch_s, span / n apart
    np.testing.assert_allclose(ds["epoch"].values, EPOCH0 + 9000.0 * np.arange(3) / 3,
                               rtol=0, atol=1e-9)
    assert ds["epoch"].attrs["units"] == "s"
    for v in ("coverage", "coverage_seen", "lit_fraction", "stereo_fraction",
              "sun_longitude", "sun_latitude"):
        assert ds[v].dims == ("epoch",) and np.isfinite(ds[v].values).all(), v
        assert "units" in ds[v].attrs, v
    assert np.all(ds["coverage"].values <= ds["coverage_seen"].values + 1e-12)
    # the Sun turns in T as the body spins (2 h is not a multiple of its period): the
    # scanned longitudes differ, and the swarm's geometry (seen) does not
    lon = ds["sun_longitude"].values
    assert np.ptp(np.unwrap(lon)) > 0.1
    np.testing.assert_array_equal(ds["coverage_seen"].values,
                                  np.full(3, ds["coverage_seen"].values[0]))
    printed = capsys.readouterr().out
    assert "best arrival epoch" in printed
    # the middle epoch equals a flyby campaign flown at that epoch
    e = float(ds["epoch"].values[1])
    fly = xr.open_zarr(run_file(FLYBY, out=tmp_path / "f.zarr",
                                overrides=SETS + [f"flyby.epoch_s={e!r}"]))
    assert float(ds["coverage"][1]) == pytest.approx(float(fly["coverage"]), abs=1e-12)
    assert float(ds["coverage_seen"][1]) == pytest.approx(float(fly["coverage_seen"]),
                                                          abs=1e-12)
    a = setup_from_campaign(load(FLYBY, SETS)).body.shape.vertex_areas
    lit = fly["lit"].values.astype(bool)
    assert float(ds["lit_fraction"][1]) == pytest.approx(a[lit].sum() / a.sum(), abs=1e-12)


def test_scan_arrival_default_span_is_one_rotation(tmp_path):
    ds = _scan(tmp_path, "rot.nc", "--n", "2")
    setup = setup_from_campaign(load(FLYBY, SETS))
    period = 2 * math.pi / setup.body.params.spin_rate
    np.testing.assert_allclose(ds["epoch"].values, [EPOCH0, EPOCH0 + period / 2], atol=1e-6)
    # half a turn later the Sun is on the other side in longitude
    d = (ds["sun_longitude"].values[1] - ds["sun_longitude"].values[0]) % (2 * math.pi)
    assert d == pytest.approx(math.pi, abs=0.05)


def test_scan_arrival_refuses_bad_arguments(tmp_path, capsys):
    for args, field in ((["--n", "0"], "--n"), (["--span-h", "-1"], "--span-h")):
        cli = ["scan-arrival", str(FLYBY), *args, "--out", str(tmp_path / "x.nc")]
        for s in SETS:
            cli += ["--set", s]
        assert main(cli) == 2
        assert field in capsys.readouterr().err
        assert not (tmp_path / "x.nc").exists()
