"""Figure content (issue 22): titles with the body name, integer ticks for counts,
the decision region resolved, unseen patches visible. Figures are inspected as
matplotlib objects (``figures.kept()``), not only as files."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.report.write import write_report
from ideas_hpc.plots import design, figures
from small_stores import small_store


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    root = tmp_path_factory.mktemp("fig-stores")
    figures.plt.rcParams["figure.max_open_warning"] = 0      # kept open to be inspected
    out = {}
    for kind in ("flyby", "design-exact", "design-fov", "design-pareto", "monte-carlo"):
        ds = xr.open_zarr(small_store(kind, root))
        with figures.kept() as figs:
            write_report(small_store(kind, root), root / f"{kind}-report")
        out[kind] = (ds, dict(figs))
    yield out
    figures.plt.close("all")


def _titles(fig) -> str:
    sup = fig._suptitle.get_text() if fig._suptitle is not None else ""
    return " | ".join([sup] + [ax.get_title() for ax in fig.axes])


def _integer_ticks(axis) -> bool:
    locs = [t for t in axis.get_ticklocs() if axis.get_view_interval()[0] <= t
            <= axis.get_view_interval()[1]]
    return bool(locs) and np.allclose(locs, np.round(locs))


@pytest.mark.parametrize("kind", ["flyby", "design-exact", "design-fov", "design-pareto",
                                  "monte-carlo"])
def test_every_figure_has_a_title_naming_the_body(reports, kind):
    ds, figs = reports[kind]
    assert figs, kind
    body = ds.attrs["shape_model"]
    for name, fig in figs.items():
        t = _titles(fig)
        assert body in t, f"{kind}/{name}: {t!r}"
        assert len(t.replace(body, "").strip(" |()-")) > 3, f"{kind}/{name} has no title"


def test_targeting_figure(reports):
    ds, figs = reports["flyby"]
    ax = figs["fig23_targeting_error.png"].axes[0]
    n_sc = ds.sizes["spacecraft"]
    assert len(ax.get_lines()) == n_sc + 1                 # one per spacecraft + tolerance
    assert _integer_ticks(ax.xaxis) and "Newton iteration" in ax.get_title()
    x0 = [line.get_xdata()[0] for line in ax.get_lines()[:n_sc]]
    assert len(set(np.round(x0, 6))) == n_sc               # no spacecraft hidden under another


def test_fov_pyramids_z_label_inside(reports):
    _, figs = reports["flyby"]
    fig = figs["fig24_fov_pyramids.png"]
    fig.canvas.draw()
    ax = fig.axes[0]
    box = ax.zaxis.label.get_window_extent(fig.canvas.get_renderer())
    w, h = fig.canvas.get_width_height()
    assert ax.get_zlabel() and 0 <= box.x0 and box.x1 <= w and 0 <= box.y0 and box.y1 <= h


def test_ga_fitness_no_offset_and_integer_generations(reports):
    _, figs = reports["design-fov"]
    fig = figs["fig30_ga_fitness.png"]
    fig.canvas.draw()
    ax = fig.axes[0]
    assert ax.yaxis.get_major_formatter().get_offset() == ""
    assert _integer_ticks(ax.xaxis)


def test_monte_carlo_figures(reports):
    ds, figs = reports["monte-carlo"]
    fig = figs["mc_coverage.png"]
    assert "Monte Carlo" in _titles(fig)
    hist, scatter = fig.axes[:2]
    assert sum(p.get_height() for p in hist.patches) == ds.sizes["sample"]
    assert _integer_ticks(scatter.xaxis)
    assert "envelope" in figs["fig26_sigma_error.png"].axes[0].get_title()


def test_coverage_vs_n_zooms_on_the_decision_region(reports):
    ds, figs = reports["design-exact"]
    full, zoom = figs["design_coverage_vs_n.png"].axes[:2]
    thr = 100 * ds.attrs["threshold_coverage"]
    tgt = 100 * ds.attrs["target_coverage"]
    lo, hi = zoom.get_ylim()
    assert lo < thr <= tgt < hi and hi - lo < 1.0          # a 45-100 % axis hides the decision
    assert full.get_ylim()[0] < 100 * ds["coverage_vs_n"].values.min()
    assert _integer_ticks(full.xaxis) and _integer_ticks(zoom.xaxis)
    labels = [line.get_label() for line in zoom.get_lines()]
    assert any(lb.startswith("threshold") for lb in labels)
    assert any(lb.startswith("target") for lb in labels)


def test_verification_resolves_the_threshold_region(tmp_path):
    """57 of 64 samples between 99.74 % and 99.9 %, 7 failures near 95 %: every sample
    near the threshold is a point of its own, and the probability line is the count."""
    rng = np.random.default_rng(1)
    cov = np.r_[rng.uniform(0.9974, 0.9990, 57), rng.uniform(0.94, 0.96, 7)]
    ds = xr.Dataset({"verify_coverage": (("verify_sample",), cov)},
                    attrs={"verify_threshold": 0.9974, "shape_model": "eros001708",
                           "verify_probability": float(np.mean(cov >= 0.9974))})
    with figures.kept() as figs:
        design.verification(ds, tmp_path / "v.png")
    ax = figs["v.png"].axes[0]
    lo, hi = ax.get_xlim()
    assert lo > 97.0 and hi > 99.9 and lo < 99.74              # the 0.16-point band is readable
    pts = [line for line in ax.get_lines() if line.get_marker() == "o"][0]
    x = pts.get_xdata()
    assert x.size == 64 and ((x >= lo) & (x <= hi)).sum() == 57
    p_line = [line for line in ax.get_lines() if line.get_label().startswith("P(coverage")]
    assert np.isclose(p_line[-1].get_ydata()[0], 57 / 64)
    assert "7 samples below" in ax.get_xlabel() and "eros001708" in ax.get_title()
    figures.plt.close("all")


def test_coverage_map_unseen_faces_red_and_area_title(tmp_path):
    from ideas_hpc.body.bodies import load_body
    from ideas_hpc.plots.coverage_map import render_coverage_map

    shape = load_body("ellipsoid", resolution=2).shape
    seen = shape.vertices_T[:, 0] < 5e3                     # one end never seen
    with figures.kept() as figs:
        render_coverage_map(shape, seen, tmp_path / "m.png", kind="observed", title="map")
    fig = figs["m.png"]
    fc = fig.axes[0].collections[0].get_facecolor()
    red = (fc[:, 0] > 2 * fc[:, 1]) & (fc[:, 0] > 2 * fc[:, 2])
    assert red.sum() == (~seen[shape.faces]).all(axis=1).sum() > 0
    area = shape.vertex_areas
    assert f"{100 * area[seen].sum() / area.sum():.3f} % of the area" in fig._suptitle.get_text()
    figures.plt.close("all")


def test_validation_coverage_resolves_the_threshold_region(tmp_path):
    """The success-probability validation figure is the same exceedance curve: 50 flights in
    a 0.15-point band at the threshold, 6 with a failure far below, 4 with a failure
    that still reach it. Every flight near the threshold is a point, failures are marked,
    and the fraction line is the count (50 + 4 of 60, not the failure-exact P-hat)."""
    from ideas_hpc.plots import reliability

    rng = np.random.default_rng(2)
    cov = np.r_[rng.uniform(0.9974, 0.9989, 50), rng.uniform(0.90, 0.95, 6),
                rng.uniform(0.9975, 0.9980, 4)]
    n_failed = np.r_[np.zeros(50, int), np.ones(6, int), np.ones(4, int)]
    ds = xr.Dataset({"validation_coverage": (("validation_sample",), cov),
                     "validation_n_failed": (("validation_sample",), n_failed),
                     "validation_p_hat": ((), 0.8)},
                    attrs={"reliability_threshold": 0.9974, "shape_model": "eros001708"})
    with figures.kept() as figs:
        reliability.validation_coverage(ds, tmp_path / "val.png")
    ax = figs["val.png"].axes[0]
    lo, hi = ax.get_xlim()
    assert 97.0 < lo < 99.74 and hi > 99.89                 # the band is readable
    pts = [line for line in ax.get_lines() if line.get_marker() == "o"]
    x = pts[0].get_xdata()
    assert x.size == 60 and ((x >= lo) & (x <= hi)).sum() == 54
    orange = [line for line in pts if line.get_label().startswith("flights with a failure")]
    assert orange[0].get_xdata().size == 10
    thr = [line for line in ax.get_lines() if line.get_label().startswith("threshold")]
    assert np.allclose(thr[0].get_xdata(), 99.74)
    p_line = [line for line in ax.get_lines() if line.get_label().startswith("P(coverage >= t")]
    assert np.isclose(p_line[0].get_ydata()[0], 54 / 60)
    assert "90.0 % of them reach" in ax.get_title() and "eros001708" in ax.get_title()
    assert "6 flights below" in ax.get_xlabel()
    figures.plt.close("all")
