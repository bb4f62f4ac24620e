"""``ideas-hpc report STORE --html``: one self-contained, interactive HTML page (issue 22).

The page holds the text summary and plotly figures, with plotly.js inlined once
so that it opens offline:

* the body in 3-D coloured by the per-vertex result the store has (P(seen)
  over Monte Carlo samples, seen, first seen, best resolution), never-seen
  faces in red, a menu to switch between them;
* the ring seen from above with the chosen swarm (flyby and design stores);
* the trade curves (coverage versus N with target and threshold, the Pareto
  front);
* the coverage distribution of the dispersed samples (Monte Carlo verification
  or a Monte Carlo campaign) with the threshold;
* a success-probability design's reliability curve and validation distribution
  (:mod:`ideas_hpc.report.html_reliability`).

The PNG figures of :mod:`ideas_hpc.report.write` stay for papers.
"""

from __future__ import annotations

import html
import warnings
from pathlib import Path

import numpy as np

KM = 1e3
UNSEEN = "rgb(220, 38, 26)"


def _vertex_fields(ds) -> list[tuple[str, np.ndarray, str]]:
    """``(label, per-vertex values with NaN where never seen, colour scale)`` the store has."""
    out = []
    mc = "observed" in ds and ds["observed"].ndim == 2
    if "observed" in ds:
        obs = ds["observed"].values.astype(float)
        if mc:
            out.append(("P(seen) over Monte Carlo samples", obs.mean(axis=0), "Blues"))
        else:
            seen = np.where(obs > 0, 1.0, np.nan)
            out.append(("seen", seen, [[0, "rgb(40, 90, 215)"], [1, "rgb(40, 90, 215)"]]))
    if "first_seen" in ds and not mc:
        out.append(("first seen, s", ds["first_seen"].values.astype(float), "Viridis"))
    if "best_resolution" in ds:
        r = ds["best_resolution"].values.astype(float)
        if r.ndim == 2:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)     # never-seen vertices
                r = np.nanmedian(r, axis=0)
            label = "median best resolution, m"
        else:
            label = "best resolution, m"
        out.append((label, r, "Viridis_r"))
    return out


def body_figure(ds):
    """The body mesh (km, frame T) coloured by each per-vertex field; a menu switches."""
    import plotly.graph_objects as go

    v = ds["vertex_position"].values / KM
    f = ds["face_vertices"].values.astype(np.int64)
    fields = _vertex_fields(ds)
    fig = go.Figure()
    for k, (label, x, scale) in enumerate(fields):
        fin = np.isfinite(x)
        fill = float(np.nanmin(x)) if fin.any() else 0.0
        fig.add_trace(go.Mesh3d(
            x=v[:, 0], y=v[:, 1], z=v[:, 2], i=f[:, 0], j=f[:, 1], k=f[:, 2],
            intensity=np.where(fin, x, fill), colorscale=scale, name=label,
            **(dict(cmin=0.0, cmax=1.0) if label.startswith("P(") else {}),
            colorbar=dict(title=dict(text=label, side="right")), visible=k == 0,
            showscale=label != "seen", flatshading=False,
            lighting=dict(ambient=0.55, diffuse=0.7), hovertemplate="%{intensity:.4g}"))
        never = ~fin[f].any(axis=1)
        fig.add_trace(go.Mesh3d(
            x=v[:, 0], y=v[:, 1], z=v[:, 2], i=f[never, 0], j=f[never, 1], k=f[never, 2],
            color=UNSEEN, name="never seen", visible=k == 0, showlegend=k == 0,
            hoverinfo="name"))
    buttons = [dict(label=label, method="update",
                    args=[{"visible": [t // 2 == k for t in range(2 * len(fields))]},
                          {"title.text": _title(ds, f"{label}; red: never seen")}])
               for k, (label, _, _) in enumerate(fields)]
    first = fields[0][0] if fields else "shape"
    fig.update_layout(
        title=_title(ds, f"{first}; red: never seen"), height=620,
        legend=dict(x=0.0, y=0.9, xanchor="left"),
        margin=dict(l=0, r=0, t=60, b=0),
        scene=dict(aspectmode="data", xaxis_title="x_T, km", yaxis_title="y_T, km",
                   zaxis_title="z_T, km"),
        updatemenus=[dict(buttons=buttons, x=0.0, y=1.0, xanchor="left", yanchor="top")]
        if len(fields) > 1 else [])
    return fig


def _title(ds, text: str) -> str:
    from ideas_hpc.plots.figures import body_name
    from ideas_hpc.report.requirement import coverage_meaning

    return f"{text} ({body_name(ds)})"


def ring_figure(ds):
    """The ring seen normal to its plane (:func:`ideas_hpc.plots.design.ring_plane`) with the
    chosen swarm and the body for scale."""
    import plotly.graph_objects as go

    from ideas_hpc.plots.design import ring_plane

    e1, e2, (xlabel, ylabel), view = ring_plane(ds)
    d = float(ds.attrs["d_sep_m"]) / KM
    th = np.asarray(ds["swarm_angle"].values, dtype=float)
    phi = np.linspace(0, 2 * np.pi, 361)
    fig = go.Figure()
    if "vertex_position" in ds:
        v = ds["vertex_position"].values / KM
        fig.add_trace(go.Scatter(x=v @ e1, y=v @ e2, mode="markers", name="body",
                                 marker=dict(size=2, color="grey")))
    fig.add_trace(go.Scatter(x=d * np.cos(phi), y=d * np.sin(phi), mode="lines",
                             name=f"ring, d_sep {d:.1f} km", line=dict(dash="dash", color="black")))
    fig.add_trace(go.Scatter(x=d * np.cos(th), y=d * np.sin(th), mode="markers+text",
                             name=f"swarm, N = {th.size}", text=[f"{np.degrees(t):.1f}°" for t in th],
                             textposition="top center", marker=dict(size=11, color="crimson")))
    fig.update_layout(title=_title(ds, f"ring and chosen swarm ({view})"), height=520,
                      xaxis_title=xlabel, yaxis_title=ylabel,
                      yaxis=dict(scaleanchor="x", scaleratio=1))
    return fig


def _hlines(fig, ds, **where) -> None:
    a = ds.attrs
    thr = a.get("threshold_coverage", a.get("verify_threshold"))
    for value, label, dash in ((a.get("target_coverage"), "target", "dot"),
                               (thr, "threshold (target - eps_tol)", "dashdot")):
        if value is not None:
            fig.add_hline(y=100 * float(value), line_dash=dash,
                          annotation_text=f"{label} {100 * float(value):.3f} %", **where)


def trade_figure(ds):
    """Coverage versus N (proven per point) with the target and threshold."""
    import plotly.graph_objects as go

    n = ds["n_spacecraft"].values
    c = 100.0 * ds["coverage_vs_n"].values
    fig = go.Figure(go.Scatter(x=n, y=c, mode="lines+markers", name="best coverage of N"))
    _hlines(fig, ds)
    if "spacecraft" in ds.sizes and "design_method" in ds:
        fig.add_vline(x=ds.sizes["spacecraft"], line_dash="dash", line_color="crimson",
                      annotation_text=f"design N = {ds.sizes['spacecraft']}")
    fig.update_layout(title=_title(ds, "coverage versus swarm size (zoom with the mouse)"),
                      xaxis=dict(title="swarm size N", dtick=1), yaxis_title="area coverage, %",
                      height=460)
    return fig


def pareto_figure(ds):
    import json

    import plotly.graph_objects as go

    names = json.loads(ds.attrs.get("objectives", '["n", "coverage"]'))
    x, y = (ds[f"pareto_{names[0]}"].values, ds[f"pareto_{names[1]}"].values)
    scale = [100.0 if ds[f"pareto_{k}"].attrs.get("units") == "1" and k != "n" else 1.0
             for k in names[:2]]
    fig = go.Figure(go.Scatter(x=x * scale[0], y=y * scale[1], mode="markers",
                               name="non-dominated swarms", marker=dict(size=10)))
    fig.update_layout(title=_title(ds, "Pareto front"), xaxis_title=names[0],
                      yaxis_title=names[1] + (", %" if scale[1] == 100.0 else ""), height=460)
    return fig


def distribution_figure(ds):
    """Fraction of dispersed samples reaching each coverage, with the threshold."""
    import plotly.graph_objects as go

    name = "verify_coverage" if "verify_coverage" in ds else "coverage"
    cov = np.sort(100.0 * np.ravel(ds[name].values))
    cov = cov[np.isfinite(cov)]
    m = cov.size
    frac = 1.0 - np.arange(m) / m
    fig = go.Figure(go.Scatter(x=cov, y=frac, mode="lines+markers", line_shape="hv",
                               name=f"P(coverage >= x), {m} samples"))
    thr = ds.attrs.get("verify_threshold", ds.attrs.get("threshold_coverage"))
    from ideas_hpc.report.reliability import swarm_label

    who = f" {swarm_label(ds)}" if name == "verify_coverage" else ""
    title = f"coverage of {m} dispersed samples{who}"
    if thr is not None:
        t = 100 * float(thr)
        p = float(np.mean(cov >= t - 1e-9))
        fig.add_vline(x=t, line_dash="dashdot", line_color="purple",
                      annotation_text=f"threshold {t:.3f} %")
        title = f"P(coverage >= {t:.2f} %) = {100 * p:.1f} % over {m} samples{who}"
    fig.update_layout(title=_title(ds, title), xaxis_title="area coverage x, %",
                      yaxis=dict(title="fraction of samples with coverage >= x", range=[0, 1.05]),
                      height=460)
    return fig


def figures_of(ds) -> list:
    """The interactive figures that apply to a store, in page order."""
    figs = []
    if "vertex_position" in ds and "face_vertices" in ds:
        figs.append(body_figure(ds))
    if "swarm_angle" in ds and "d_sep_m" in ds.attrs and "sample" not in ds["swarm_angle"].dims:
        figs.append(ring_figure(ds))
    if "coverage_vs_n" in ds:
        figs.append(trade_figure(ds))
    if "pareto_n" in ds:
        figs.append(pareto_figure(ds))
    if "verify_coverage" in ds or ("coverage" in ds and ds["coverage"].ndim == 1
                                   and ds["coverage"].size > 1):
        figs.append(distribution_figure(ds))
    from ideas_hpc.report.html_reliability import reliability_html_figures

    figs.extend(reliability_html_figures(ds))
    return figs


def _image(png: Path) -> str:
    """A PNG inlined as a data URI (the page stays one file)."""
    import base64

    data = base64.b64encode(Path(png).read_bytes()).decode("ascii")
    return (f'<figure><img alt="{html.escape(Path(png).stem)}" style="max-width:100%" '
            f'src="data:image/png;base64,{data}"></figure>')


def write_html(ds, summary: str, path, images=()) -> Path:
    """One self-contained page: the summary and :func:`figures_of`, plotly.js inlined;
    ``images``: PNGs shown under "Answers under the target prior" (``ideas-hpc study``'s
    figures, the prior's gallery, the B-plane ellipse: :mod:`ideas_hpc.report.study`)."""
    path = Path(path)
    parts = []
    for k, fig in enumerate(figures_of(ds)):
        parts.append(fig.to_html(full_html=False, include_plotlyjs=k == 0,
                                 div_id=f"figure-{k}", config={"displaylogo": False}))
    if images:
        parts.append("<h2>Answers under the target prior</h2>"
                     + "\n".join(_image(p) for p in images))
    from ideas_hpc.plots.figures import body_name
    from ideas_hpc.report.requirement import coverage_meaning

    page = (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>ideas_hpc report: {html.escape(body_name(ds))}</title>"
            "<style>body{font-family:sans-serif;margin:1em 2em}pre{white-space:pre-wrap;"
            "background:#f6f6f6;padding:.8em}</style></head><body>"
            f"<h1>ideas_hpc report: {html.escape(str(ds.attrs.get('kind', '')))} on "
            f"{html.escape(body_name(ds))}</h1>"
            f"<p><b>{html.escape(coverage_meaning(ds))}</b></p>" + "\n".join(parts)
            + f"<h2>Summary</h2><pre>{html.escape(summary)}</pre></body></html>\n")
    path.write_text(page, encoding="utf-8")
    return path
