"""Figures of the success-probability design (issue 20): the reliability curve and the
validation flights' coverage with sampled failures (an exceedance curve zoomed on the
threshold, :mod:`ideas_hpc.plots.ecdf`).

Each function takes an ``xarray.Dataset`` opened from a design store, writes
one PNG and returns its path (%).
"""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import MaxNLocator

from ideas_hpc.plots.ecdf import exceedance_zoom
from ideas_hpc.plots.figures import body_name, plt, save_png


def _threshold_pct(ds) -> float:
    return 100.0 * float(ds.attrs["reliability_threshold"])


def reliability_curve(ds, path) -> "Path":  # noqa: F821
    """Probability of mapping >= X % against the number of spacecraft.

    The best P of N spacecraft on the scenario bank with the proven upper
    bound on any N, the validated P-hat of that swarm with its lower
    confidence bound, the requirement p, and the k-failure-tolerant designs.
    """
    n = ds["reliability_n"].values
    p_bank = 100.0 * ds["reliability_vs_n"].values
    up = 100.0 * ds["reliability_vs_n_upper"].values
    ph = 100.0 * ds["reliability_vs_n_validated"].values
    lo = 100.0 * ds["reliability_vs_n_lower"].values
    conf = 100.0 * float(ds.attrs.get("confidence", 0.95))
    fig, ax = plt.subplots(figsize=(6.6, 4.2))
    ax.plot(n, p_bank, "o-", color="tab:blue", label="best P on the scenarios")
    ax.plot(n, up, "v", color="tab:blue", mfc="none", label="proven upper bound (any N-swarm)")
    ax.errorbar(n + 0.08, ph, yerr=[np.maximum(ph - lo, 0.0), np.zeros_like(ph)], fmt="s",
                color="tab:green", capsize=3,
                label=f"validated P-hat, {conf:g} % lower bound")
    p = 100.0 * float(ds["success_probability_required"])
    ax.axhline(p, color="k", ls=":", lw=1, label=f"required p = {p:g} %")
    if "tolerant_swarm_size" in ds and ds.sizes.get("tolerated", 0):
        for k, nk, pk in zip(ds["tolerated"].values, ds["tolerant_swarm_size"].values,
                             ds["tolerant_probability"].values):
            ax.plot([nk], [100 * pk], "*", ms=13, color="tab:purple")
            ax.annotate(f"k = {int(k)} tolerant", (nk, 100 * pk), textcoords="offset points",
                        xytext=(6, -12), fontsize=8, color="tab:purple")
    ax.axvline(int(ds["best_swarm_size"]), color="tab:red", ls="--", lw=1,
               label=f"design: N = {int(ds['best_swarm_size'])}")
    ax.set_xlabel("number of spacecraft N")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel(f"P(mapping >= {_threshold_pct(ds):.2f} %), %")
    # two lines: on one, a long body name pushed the end past the figure's edge
    ax.set_title(f"{body_name(ds)}: probability of mapping >= {_threshold_pct(ds):.2f} %\n"
                 "against the number of spacecraft", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    return save_png(fig, path)


def validation_coverage(ds, path) -> "Path":  # noqa: F821
    """Coverage of the validation flights with failures sampled: the fraction of flights
    reaching each coverage (complementary ECDF, zoomed on the threshold, every flight
    a point; flights with a failure in orange), the fraction at or above the
    threshold, and the validation's P-hat (failures enumerated exactly) beside it."""
    cov = 100.0 * ds["validation_coverage"].values
    failed = ds["validation_n_failed"].values > 0
    thr = _threshold_pct(ds)
    fig, ax = plt.subplots(figsize=(7.2, 4.4))
    e = exceedance_zoom(ax, cov, thr, what="flights")
    hit = failed[e["order"]]
    if hit.any():
        ax.plot(e["coverage"][hit], e["fraction_at"][hit], "o", color="tab:orange", ms=4,
                label=f"flights with a failure ({int(hit.sum())})")
    # Two numbers answer one question: the flights drew one failure case each (the
    # points, the title's first figure); P-hat weighs every failure case of the same
    # flights exactly (the design's figure). The title names both, so they never
    # look like a contradiction.
    exact = ""
    if "validation_p_hat" in ds:
        ph = float(ds["validation_p_hat"])
        ax.axhline(ph, color="tab:green", ls="--", lw=1,
                   label=f"validation P-hat (failures exact) = {100 * ph:.1f} %")
        exact = f"; with every failure case weighed exactly, P-hat = {100 * ph:.1f} %"
    ax.set_title(f"{body_name(ds)}: validation, {cov.size} flights with sampled failures "
                 f"({int(failed.sum())} with a failure)\n{100 * e['fraction']:.1f} % of them "
                 f"reach the threshold {thr:.2f} %{exact}", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    return save_png(fig, path)
