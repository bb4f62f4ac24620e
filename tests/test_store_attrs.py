"""Self-describing stores (issue 22): every variable of every store kind has CF
``units`` (``"1"`` when dimensionless) and a ``long_name``, every dim has a
coordinate, and a name means the same units in every store."""

from __future__ import annotations

import pytest
import xarray as xr

from small_stores import KINDS, small_store


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    root = tmp_path_factory.mktemp("stores")
    return {k: xr.open_zarr(small_store(k, root)) for k in KINDS}


@pytest.mark.parametrize("kind", list(KINDS))
def test_every_variable_has_units_and_long_name(stores, kind):
    ds = stores[kind]
    bad = [f"{n}: {sorted({'units', 'long_name'} - set(v.attrs))}"
           for n, v in ds.variables.items()
           if not (str(v.attrs.get("units", "")) and str(v.attrs.get("long_name", "")))]
    assert not bad, f"{kind}: variables without units or long_name: {bad}"


@pytest.mark.parametrize("kind", list(KINDS))
def test_every_dim_has_a_coordinate(stores, kind):
    ds = stores[kind]
    assert not [d for d in ds.dims if d not in ds.coords]
    for d in ds.dims:
        assert ds[d].size == ds.sizes[d]


def test_a_name_has_one_unit_in_every_store(stores):
    units: dict[str, set] = {}
    for ds in stores.values():
        for n, v in ds.variables.items():
            units.setdefault(n, set()).add(v.attrs.get("units"))
    assert not {n: u for n, u in units.items() if len(u) > 1}
    assert units["coverage_vs_n_swarm"] == {"rad"}
