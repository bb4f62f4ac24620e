"""analysis/quality_maps.py: per-vertex quality probabilities of a Monte Carlo store
(issue 14 item 6), checked against direct NumPy counts over the stored samples, the
store's own coverage, and hand-made cases (NaN resolution, unwritten chunks); the
notebook runs its quality cells on a store that has the quality variables.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from test_analysis_notebook import ANALYSIS, NOTEBOOK, ROOT, SMALL, _check_png

sys.path.insert(0, str(ANALYSIS))
import plotting  # noqa: E402  (analysis/plotting.py)
import quality_maps  # noqa: E402  (analysis/quality_maps.py)

# 5 samples in chunks of 3 and 2; a requirement (resolution and emission) so that
# `mapped` differs from `observed`; failures likely, so some vertices go unseen.
QUALITY = [*(a if a != "monte_carlo.samples=4" else "monte_carlo.samples=5" for a in SMALL),
           "--set", "run.chunk_size=3", "--set", "coverage.max_resolution_m=3",
           "--set", "coverage.max_emission_deg=60",
           "--set", "monte_carlo.failure_probability=0.4"]
X_M, E_DEG = 3.0, 60.0


@pytest.fixture(scope="module")
def q_store(tmp_path_factory):
    out = tmp_path_factory.mktemp("mcq") / "quality-mc.zarr"
    cmd = [sys.executable, "-m", "ideas_hpc.cli", "run",
           str(ROOT / "campaigns" / "eros-monte-carlo.toml"), "--out", str(out),
           *QUALITY, "--workers", "1", "--no-progress"]
    res = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    return out


@pytest.fixture(scope="module")
def q_ds(q_store):
    return xr.load_dataset(q_store, engine="zarr")


def _below(x, lim):
    """Independent count: finite and <= lim (NaN: never observed; inf: edge-on only)."""
    x = np.asarray(x, dtype=float)
    out = np.zeros(x.shape, bool)
    fin = np.isfinite(x)
    out[fin] = x[fin] <= lim
    return out


def test_probabilities_are_sample_counts(q_ds):
    ds = q_ds
    assert ds.sizes["sample"] == 5 and ds["chunk_done"].values.all()
    p = quality_maps.vertex_probabilities(ds)
    assert p.attrs["n_samples"] == 5
    ref = {"p_observed": ds.observed.values.mean(0), "p_lit": ds.lit.values.mean(0),
           "p_stereo": ds.stereo.values.mean(0), "p_mapped": ds.mapped.values.mean(0),
           "p_multi_spacecraft": (ds.n_spacecraft_seen.values >= 2).mean(0),
           # the store's own limits are the defaults
           "p_resolution": _below(ds.best_resolution.values, X_M).mean(0),
           "p_emission": _below(ds.emission_at_best.values, np.radians(E_DEG)).mean(0)}
    assert sorted(quality_maps.probability_names(p)) == sorted(ref)
    for name, want in ref.items():
        np.testing.assert_array_equal(p[name].values, want, err_msg=name)
        assert p[name].attrs["units"] == "1" and p[name].attrs["long_name"]
        assert p[name].dims == ("vertex",)
    assert p["p_resolution"].attrs["limit"] == X_M and p["p_resolution"].attrs["limit_units"] == "m"
    assert p["p_emission"].attrs["limit"] == E_DEG
    # the store is not degenerate: every probability takes more than one value somewhere
    for name in ("p_mapped", "p_stereo", "p_lit", "p_resolution", "p_multi_spacecraft"):
        assert np.unique(p[name].values).size > 1, name
    assert (p["p_mapped"].values < p["p_observed"].values).any()


def test_area_means_are_the_store_coverage(q_ds):
    """Outside truth: the engine's own coverage (requirement set) and coverage_seen."""
    p = quality_maps.vertex_probabilities(q_ds)
    m = quality_maps.area_weighted_mean(p)
    assert np.isclose(m["p_mapped"], q_ds.coverage.values.mean(), rtol=0, atol=1e-12)
    assert np.isclose(m["p_observed"], q_ds.coverage_seen.values.mean(), rtol=0, atol=1e-12)
    assert m["p_mapped"] < m["p_observed"]


def test_explicit_limits_and_more_limits(q_ds):
    r = q_ds.best_resolution.values
    p = quality_maps.vertex_probabilities(q_ds, max_resolution_m=1.5, max_incidence_deg=70.0,
                                          max_phase_deg=120.0, min_spacecraft=3)
    np.testing.assert_array_equal(p["p_resolution"].values, _below(r, 1.5).mean(0))
    np.testing.assert_array_equal(p["p_incidence"].values,
                                  _below(q_ds.incidence_at_best.values, np.radians(70)).mean(0))
    np.testing.assert_array_equal(p["p_phase"].values,
                                  _below(q_ds.phase_at_best.values, np.radians(120)).mean(0))
    np.testing.assert_array_equal(p["p_multi_spacecraft"].values,
                                  (q_ds.n_spacecraft_seen.values >= 3).mean(0))
    assert "p_emission" in p   # still the store's own 60 deg
    # a looser limit can only raise the probability
    loose = quality_maps.vertex_probabilities(q_ds, max_resolution_m=10.0)
    assert (loose["p_resolution"].values >= p["p_resolution"].values).all()


def test_nan_resolution_counts_as_not_meeting_the_limit():
    """Vertex 0 never observed (NaN), vertex 1 edge-on once (inf), vertex 2 seen well."""
    nan, inf = np.nan, np.inf
    res = np.array([[nan, inf, 1.0], [nan, 0.5, 2.0], [nan, 0.5, 0.9], [nan, 0.5, 1.0]])
    ds = _synthetic(res)
    p = quality_maps.vertex_probabilities(ds, max_resolution_m=1e9, max_emission_deg=180.0)
    np.testing.assert_array_equal(p["p_resolution"].values, [0.0, 0.75, 1.0])
    np.testing.assert_array_equal(p["p_emission"].values, [0.0, 1.0, 1.0])
    p = quality_maps.vertex_probabilities(ds, max_resolution_m=1.0)
    np.testing.assert_array_equal(p["p_resolution"].values, [0.0, 0.75, 0.75])
    assert "p_emission" not in p  # no limit given, none in the store


def _synthetic(res, chunk_done=None):
    ns, nv = res.shape
    obs = np.isfinite(res) | np.isinf(res)
    ang = np.where(obs, 0.3, np.nan)
    sv = ("sample", "vertex")
    v = {"observed": (sv, obs), "best_resolution": (sv, res), "emission_at_best": (sv, ang),
         "incidence_at_best": (sv, ang), "phase_at_best": (sv, ang),
         "lit": (sv, obs), "stereo": (sv, obs), "mapped": (sv, obs),
         "n_spacecraft_seen": (sv, obs.astype(np.int32) * 2),
         "vertex_area": ("vertex", np.arange(1.0, nv + 1))}
    ds = xr.Dataset(v, attrs={"kind": "monte-carlo"})
    if chunk_done is not None:
        ds["chunk_done"] = ("chunk", np.asarray(chunk_done, bool))
        ds = ds.assign_coords(chunk_start=("chunk", [0, 2]), chunk_stop=("chunk", [2, ns]))
    return ds


def test_unwritten_chunks_are_left_out(q_ds):
    ds = q_ds.copy()
    ds["chunk_done"] = ("chunk", np.array([True, False]))   # samples 3, 4 not written
    p = quality_maps.vertex_probabilities(ds)
    assert p.attrs["n_samples"] == 3
    np.testing.assert_array_equal(p["p_stereo"].values, q_ds.stereo.values[:3].mean(0))
    np.testing.assert_array_equal(p["p_mapped"].values, q_ds.mapped.values[:3].mean(0))
    ds["chunk_done"] = ("chunk", np.array([False, False]))
    with pytest.raises(ValueError, match="no sample written"):
        quality_maps.vertex_probabilities(ds)


def test_exceedance_curve(q_ds):
    p = quality_maps.vertex_probabilities(q_ds)
    a = p["vertex_area"].values
    for name in quality_maps.probability_names(p):
        lv, f = quality_maps.area_exceedance(p[name].values, a)
        assert lv[0] == 0.0 and f[0] == 1.0            # p = 0: the whole surface
        assert (np.diff(f) <= 0).all()                  # non-increasing
        t = np.array([0.0, 0.2, 0.5, 0.6, 0.99, 1.0])
        _, ft = quality_maps.area_exceedance(p[name].values, a, t)
        want = [(a * (p[name].values >= x)).sum() / a.sum() for x in t]
        np.testing.assert_allclose(ft, want, rtol=0, atol=1e-12)
    # at p = 1: the area observed in every sample
    _, f1 = quality_maps.area_exceedance(p["p_observed"].values, a, [1.0])
    always = q_ds.observed.values.all(0)
    assert np.isclose(f1[0], a[always].sum() / a.sum(), rtol=0, atol=1e-12)


def test_refuses_stores_without_quality(q_ds):
    with pytest.raises(ValueError, match=r"'stereo'.*coverage\.quality=true"):
        quality_maps.vertex_probabilities(q_ds.drop_vars("stereo"))
    flyby = q_ds.isel(sample=0)     # quality variables without a sample dim
    with pytest.raises(ValueError, match="'lit' has no 'sample' dim"):
        quality_maps.vertex_probabilities(flyby)
    assert not quality_maps.has_quality(xr.Dataset())
    assert "coverage.quality=true" in quality_maps.why_no_quality(xr.Dataset())


def test_store_limits_from_config(q_ds):
    assert quality_maps.store_limits(q_ds) == {"max_resolution_m": X_M,
                                               "max_emission_deg": E_DEG}
    assert quality_maps.store_limits(xr.Dataset()) == {}


def test_notebook_quality_cells(q_store, tmp_path, monkeypatch):
    """The notebook on a quality store: every figure, the quality ones included."""
    import nbclient
    import nbformat

    figs = tmp_path / "figures"
    monkeypatch.setenv("IDEAS_HPC_STORE", str(q_store))
    monkeypatch.setenv("IDEAS_HPC_FIGURES", str(figs))
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbclient.NotebookClient(nb, kernel_name="python3", timeout=300,
                            resources={"metadata": {"path": str(ANALYSIS)}}).execute()
    probs = quality_maps.vertex_probabilities(plotting.open_store(q_store))
    names = quality_maps.probability_names(probs)
    quality = ["mc_quality_exceedance.png", "mc_quality_histograms.png",
               *(f"mc_quality_{n}.png" for n in names)]
    for name in (*plotting.FIGURES, *quality):
        _check_png(figs / name)
    shown = sum(1 for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
                if "image/png" in o.get("data", {}))
    assert shown == len(plotting.FIGURES) + len(quality)
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []))
    assert "p_mapped" in text and "skipped" not in text
