"""Encounter scan figure: ring coverage and greedy N against approach declination and
phase angle (``ideas-hpc scan-encounter --plot``)."""

from __future__ import annotations

import numpy as np

from ideas_hpc.plots.figures import body_name, plt, save_png

#: the narrowest colour scale, percentage points of coverage
MIN_SPAN_PCT = 1.0


def scan_map(ds, path) -> "Path":  # noqa: F821
    """Heat map of ``ring_coverage`` (%) over (phase, declination) in deg, each cell
    labelled with its coverage and greedy N; unreachable cells blank."""
    dec = np.degrees(ds["dec"].values)
    ph = np.degrees(ds["phase"].values)
    cov = 100.0 * ds["ring_coverage"].values
    n = ds["n_greedy"].values
    fig, ax = plt.subplots(figsize=(max(1.4 * ph.size + 2.5, 5.0), 0.7 * dec.size + 2.0))
    # The colour scale spans at least MIN_SPAN_PCT points below the best cell: a scan
    # whose cells differ by 0.13 points must not look like one spanning the whole
    # range. The title states the span.
    fin = cov[np.isfinite(cov)]
    hi = float(fin.max()) if fin.size else 100.0
    lo = min(float(fin.min()) if fin.size else 0.0, hi - MIN_SPAN_PCT)
    im = ax.imshow(np.ma.masked_invalid(cov), origin="lower", aspect="auto", cmap="viridis",
                   vmin=lo, vmax=hi)
    for i in range(dec.size):
        for j in range(ph.size):
            if np.isfinite(cov[i, j]):
                bright = im.norm(cov[i, j]) > 0.6
                ax.text(j, i, f"{cov[i, j]:.2f} %\nN <= {n[i, j]:.0f}", ha="center",
                        va="center", fontsize=7, color="k" if bright else "w")
    ax.set_xticks(range(ph.size), [f"{p:g}" for p in ph])
    ax.set_yticks(range(dec.size), [f"{d:g}" for d in dec])
    ax.set_xlabel("phase angle, deg")
    ax.set_ylabel("approach declination, deg")
    ax.set_title(f"ring coverage at {ds.attrs['speed_m_s'] / 1e3:g} km/s, "
                 f"d_sep {ds.attrs['d_sep_m'] / 1e3:.4g} km\nblank: unreachable\n"
                 f"colour scale {lo:.2f}-{hi:.2f} %", fontsize=9)
    fig.colorbar(im, ax=ax, label="ring coverage, %")
    return save_png(fig, path, body=body_name(ds))
