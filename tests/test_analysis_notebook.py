"""analysis/: the Monte Carlo notebook runs on a real (small) campaign store and
writes non-blank PNGs; the reductions it plots agree with their definitions.

The notebook runs under nbclient with the ``python3`` kernel that ipykernel
provides in the same environment (no kernelspec install needed).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parent.parent
ANALYSIS = ROOT / "analysis"
NOTEBOOK = ANALYSIS / "mc_analysis.ipynb"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

sys.path.insert(0, str(ANALYSIS))
import plotting  # noqa: E402  (analysis/plotting.py)

# A 60 s, +-3 km flight keeps the campaign to seconds on a warm numba cache;
# every override is a schema field (ideas_hpc/campaign/schema/campaign_tables.py).
# (test_quality_probabilities runs its own campaign with these.)
SMALL = ["--set", "monte_carlo.samples=4", "--set", "run.chunk_size=2",
         "--set", "flyby.tf_s=60", "--set", "flyby.z_start_km=-3",
         "--set", "flyby.z_stop_km=3", "--set", "attitude.decimate=10"]


@pytest.fixture(scope="module")
def mc_store(tmp_path_factory):
    """A finished 4-sample Monte Carlo store: the session's shared one (tests/small_stores.py,
    also read by the figure, HTML report and store-attribute tests), built once per session."""
    from small_stores import small_store

    return small_store("monte-carlo", tmp_path_factory.mktemp("small-stores"))


def _check_png(path: Path):
    """A real PNG with something drawn on it (not one flat colour)."""
    import matplotlib.image as mpimg

    assert path.is_file(), f"{path.name} was not written"
    raw = path.read_bytes()
    assert raw[:8] == PNG_SIGNATURE, f"{path.name} is not a PNG"
    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 200, img.shape
    assert float(img[..., :3].var()) > 1e-3, f"{path.name} is blank"


def test_notebook_writes_every_figure(mc_store, tmp_path, monkeypatch):
    import nbclient
    import nbformat

    figs = tmp_path / "figures"
    monkeypatch.setenv("IDEAS_HPC_STORE", str(mc_store))
    monkeypatch.setenv("IDEAS_HPC_FIGURES", str(figs))
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbclient.NotebookClient(nb, kernel_name="python3", timeout=300,
                            resources={"metadata": {"path": str(ANALYSIS)}}).execute()
    for name in plotting.FIGURES:
        _check_png(figs / name)
    shown = sum(1 for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
                if "image/png" in o.get("data", {}))
    assert shown == len(plotting.FIGURES)
    # a paper-mode store has no quality variables: those cells say so and draw nothing
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []))
    assert "skipped the quality probabilities: quality variable 'lit' is missing" in text
    assert "coverage.quality=true" in text
    assert not list(figs.glob("mc_quality_*.png"))


def test_committed_notebook_is_clean():
    """Outputs cleared; the first code cell is the parameters cell reading the env."""
    import nbformat

    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(not c.outputs and c.execution_count is None for c in code)
    first = code[0]
    assert "parameters" in first.metadata.get("tags", [])
    assert "IDEAS_HPC_STORE" in first.source and "IDEAS_HPC_FIGURES" in first.source


def test_make_all_on_store(mc_store, tmp_path):
    ds = plotting.open_store(mc_store)
    made = plotting.make_all(ds, tmp_path)
    assert sorted(made) == sorted(plotting.FIGURES)
    for path in made.values():
        _check_png(path)
    # The store's coverage is a fraction: the per-vertex observation matches it.
    area = ds["vertex_area"].values
    frac = plotting.vertex_observed_fraction(ds).values
    cov = ds["coverage"].values
    assert np.isclose((frac * area).sum() / area.sum(), cov.mean(), rtol=0, atol=1e-9)


@pytest.mark.filterwarnings("ignore:Consolidated metadata")
def test_open_store_refuses_other_kinds_and_unfinished(tmp_path):
    ds = xr.Dataset({"coverage": ("sample", np.ones(2))}, attrs={"kind": "flyby"})
    ds.to_zarr(tmp_path / "a.zarr")
    with pytest.raises(ValueError, match="monte-carlo"):
        plotting.open_store(tmp_path / "a.zarr")
    ds = xr.Dataset({"coverage": ("sample", np.ones(2)),
                     "chunk_done": ("chunk", np.array([True, False]))},
                    attrs={"kind": "monte-carlo"})
    ds.to_zarr(tmp_path / "b.zarr")
    with pytest.raises(ValueError, match="1 chunk"):
        plotting.open_store(tmp_path / "b.zarr")


# ------------------------------------------------------------- reductions

def test_ecdf_definition():
    x, f = plotting.ecdf([3.0, 1.0, 2.0, 2.0])
    np.testing.assert_array_equal(x, [1.0, 2.0, 2.0, 3.0])
    np.testing.assert_array_equal(f, [0.25, 0.5, 0.75, 1.0])


def _synthetic(ns=5, n=3, nt=4, seed=0):
    """An in-memory dataset with known attitude errors: rotations by ``phi`` about
    random axes, written as MRPs by scipy (outside truth for ``|sigma| = tan(phi/4)``)."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    phi = rng.uniform(1e-6, np.pi, (ns, n, nt))
    axes = rng.standard_normal((ns, n, nt, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    mrp = Rotation.from_rotvec((axes * phi[..., None]).reshape(-1, 3)).as_mrp()
    torque = rng.uniform(-0.01, 0.01, (ns, n, nt, 3))
    active = rng.uniform(size=(ns, n)) > 0.3
    active[0] = True  # every spacecraft works in some sample: no all-NaN envelope
    s4 = ("sample", "spacecraft", "time")
    ds = xr.Dataset({
        "sigma_error": (s4 + ("axis",), mrp.reshape(ns, n, nt, 3)),
        "wheel_torque": (s4 + ("wheel",), torque),
        "active": (("sample", "spacecraft"), active),
    }, coords={"time": np.arange(nt) * 10.0})
    return ds, phi, torque, active


def test_attitude_error_norm_is_tan_quarter_angle():
    ds, phi, _, active = _synthetic()
    got = plotting.attitude_error_norm(ds, active_only=False).values
    np.testing.assert_allclose(got, np.tan(phi / 4.0), rtol=1e-12)
    masked = plotting.attitude_error_norm(ds).values
    assert np.isnan(masked[~active]).all()
    np.testing.assert_allclose(masked[active], np.tan(phi / 4.0)[active], rtol=1e-12)


def test_envelopes_skip_failed_spacecraft():
    ds, phi, torque, active = _synthetic(ns=7, seed=3)
    env = plotting.sample_envelope(plotting.attitude_error_norm(ds))
    ref = np.where(active[..., None], np.tan(phi / 4.0), np.nan)
    assert (~active).any()
    np.testing.assert_allclose(env["min"].values, np.nanmin(ref, axis=0), rtol=1e-12)
    np.testing.assert_allclose(env["median"].values, np.nanmedian(ref, axis=0), rtol=1e-12)
    np.testing.assert_allclose(env["max"].values, np.nanmax(ref, axis=0), rtol=1e-12)
    tq = plotting.max_wheel_torque(ds, active_only=False).values
    np.testing.assert_array_equal(tq, np.abs(torque).max(axis=-1))


def test_vertex_fraction_and_torque_limit():
    observed = np.array([[1, 0, 1], [1, 0, 0], [1, 1, 0], [1, 0, 0]], dtype=bool)
    cfg = {"spacecraft": {"u_max": 0.005}}
    ds = xr.Dataset({"observed": (("sample", "vertex"), observed)},
                    attrs={"config": json.dumps(cfg)})
    np.testing.assert_array_equal(plotting.vertex_observed_fraction(ds).values,
                                  [1.0, 0.25, 0.25])
    assert plotting.torque_limit(ds) == 0.005
    assert plotting.torque_limit(xr.Dataset()) == plotting.U_MAX_DEFAULT == 0.007


def test_figures_survive_constant_coverage(tmp_path):
    """Every sample at 100 %: histograms still draw (degenerate bin range)."""
    rng = np.random.default_rng(1)
    ns, nv = 6, 50
    ds = xr.Dataset({
        "coverage": ("sample", np.ones(ns)),
        "coverage_count": ("sample", np.ones(ns)),
        "n_failed": ("sample", rng.integers(0, 3, ns)),
        "observed": (("sample", "vertex"), np.ones((ns, nv), bool)),
        "vertex_area": ("vertex", rng.uniform(1, 2, nv)),
    }, coords={"spacecraft": np.arange(4)})
    for f in (plotting.coverage_distribution_figure, plotting.coverage_vs_failures_figure,
              plotting.vertex_observed_fraction_figure):
        _check_png(f(ds, tmp_path / f"{f.__name__}.png"))
    assert os.path.getsize(tmp_path / "coverage_distribution_figure.png") > 1000
