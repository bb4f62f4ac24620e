"""Interactive figures of a success-probability design for ``report --html`` (issue 29).

* the reliability curve: best P on the scenario bank for each N, its proven upper
  bound, the validated P-hat and its lower bound, the requirement p, the bank's
  N and the certified N;
* the validation distribution of the certified swarm: each fresh sample's exact
  failure-weighted success probability (the values the certificate's bound is
  computed on) and each validation flight's coverage with failures sampled,
  against the threshold.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.design.certificate import verdict


def _title(ds, text: str) -> str:
    from ideas_hpc.plots.figures import body_name

    return f"{text} ({body_name(ds)})"


def reliability_curve_figure(ds):
    """P of mapping the threshold versus N, the requirement and the two answers marked."""
    import plotly.graph_objects as go

    n = ds["reliability_n"].values
    p = float(ds["success_probability_required"])
    fig = go.Figure()
    for name, label, dash in (("reliability_vs_n", "best P on the scenario bank", None),
                              ("reliability_vs_n_upper", "proven upper bound (any swarm)", "dot"),
                              ("reliability_vs_n_validated", "validated P-hat", None),
                              ("reliability_vs_n_lower", "validation lower bound (each N "
                               "alone)", "dash")):
        fig.add_trace(go.Scatter(x=n, y=ds[name].values, mode="lines+markers", name=label,
                                 line=dict(dash=dash)))
    fig.add_hline(y=p, line_dash="dashdot", line_color="purple",
                  annotation_text=f"required p = {p:g}")
    n_cert = int(ds["best_swarm_size"])
    ok = bool(ds["demonstrated"])
    fig.add_vline(x=n_cert, line_dash="dash", line_color="crimson",
                  annotation_text=f"certified N = {n_cert} ({verdict(ok)})")
    if "bank_swarm_size" in ds and int(ds["bank_swarm_size"]) != n_cert:
        fig.add_vline(x=int(ds["bank_swarm_size"]), line_dash="dot", line_color="grey",
                      annotation_text=f"bank N = {int(ds['bank_swarm_size'])}",
                      annotation_position="bottom right")
    fig.update_layout(title=_title(ds, "probability of mapping the threshold versus swarm size"),
                      xaxis=dict(title="swarm size N", dtick=1),
                      yaxis=dict(title="P(coverage >= threshold)"), height=480)
    return fig


def _exceedance(values):
    x = np.sort(np.ravel(values))
    return x, 1.0 - np.arange(x.size) / max(x.size, 1)


def validation_figure(ds):
    """Two panels for the certified swarm: per-sample success probability (what the bound
    sees) and the validation flights' coverage with the threshold."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    n = int(ds["best_swarm_size"])
    a = ds.attrs
    prob = np.asarray(ds["validation_probability"].values, dtype=float)
    cov = 100.0 * np.asarray(ds["validation_coverage"].values, dtype=float)
    thr = 100.0 * float(a["reliability_threshold"])
    lower = float(ds["validation_lower_bound"])
    conf = 100 * float(ds["validation_look_confidence"]) if "validation_look_confidence" in ds \
        else 100 * float(a.get("confidence", 0.95))
    fig = make_subplots(rows=1, cols=2, subplot_titles=(
        f"per-sample P (failures exact): P-hat {prob.mean():.4f}, {conf:.4g} % bound {lower:.4f}",
        f"coverage with failures sampled, threshold {thr:.3f} %"))
    x, f = _exceedance(prob)
    fig.add_trace(go.Scatter(x=x, y=f, mode="lines", line_shape="hv",
                             name=f"P(sample's P >= x), {prob.size} samples"), row=1, col=1)
    fig.add_vline(x=float(ds["success_probability_required"]), line_dash="dashdot",
                  line_color="purple", row=1, col=1)
    fig.add_vline(x=lower, line_dash="dash", line_color="crimson", row=1, col=1)
    x, f = _exceedance(cov)
    fig.add_trace(go.Scatter(x=x, y=f, mode="lines", line_shape="hv",
                             name=f"P(coverage >= x), {cov.size} flights"), row=1, col=2)
    fig.add_vline(x=thr, line_dash="dashdot", line_color="purple", row=1, col=2)
    first = int(ds["validation_first_sample"]) if "validation_first_sample" in ds else 0
    fig.update_layout(title=_title(ds, f"validation of the certified N = {n} swarm (samples "
                                       f"{first}..{first + prob.size - 1})"), height=460)
    fig.update_xaxes(title_text="success probability x", row=1, col=1)
    fig.update_xaxes(title_text="area coverage x, %", row=1, col=2)
    fig.update_yaxes(title_text="fraction >= x", range=[0, 1.05])
    return fig


def reliability_html_figures(ds) -> list:
    """The figures above when the store is a success-probability design."""
    if "reliability_vs_n" not in ds or "validation_probability" not in ds:
        return []
    return [reliability_curve_figure(ds), validation_figure(ds)]
