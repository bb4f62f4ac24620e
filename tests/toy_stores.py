"""Shared helpers for the engine tests: the serial toy reference and the bit-for-bit check."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ideas_hpc.engine.chunk_write import done_mask
from ideas_hpc.engine.store_meta import store_attrs
from toy_campaign import run_toy_serial

SAMPLE_VARS = ("coverage", "observed", "first_seen", "times_seen", "sigma_error", "sample_seed")


def serial_reference(tmp_path_factory, toy: dict, name: str = "ref") -> xr.Dataset:
    """The toy campaign written in-process without dask: what every distributed run must equal."""
    p = tmp_path_factory.mktemp(name) / "serial.zarr"
    run_toy_serial(p, **toy)
    return xr.load_dataset(p, engine="zarr")


def assert_same_as(reference: xr.Dataset, path) -> None:
    """Store at ``path`` is complete and bit-identical to the serial reference."""
    assert done_mask(path).all(), f"not all chunks done: {done_mask(path)}"
    ds = xr.load_dataset(path, engine="zarr")
    for name in SAMPLE_VARS:
        np.testing.assert_array_equal(ds[name].values, reference[name].values, err_msg=name)
    assert np.isfinite(ds.coverage.values).all()  # no chunk left at its NaN fill
    assert store_attrs(path)["config_hash"] == reference.attrs["config_hash"]
