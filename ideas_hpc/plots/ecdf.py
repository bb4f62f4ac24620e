"""The exceedance curve with a zoom on the threshold (issue 22): the shared axes of the
Monte Carlo verification figure and the success-probability validation figure.

Most dispersed flights land in a band a few tenths of a per cent wide next to
the threshold, and the few with a failure far below it; a histogram puts the
band in one bar. The complementary ECDF draws every flight as a point of its
own, and the x axis is zoomed on the threshold region (values far below are
counted in the axis label, not drawn).
"""

from __future__ import annotations

import numpy as np


def exceedance_zoom(ax, coverage_pct, threshold_pct: float, *, fraction: float | None = None,
                    what: str = "samples", color: str = "tab:green") -> dict:
    """Draw P(coverage >= x) of ``coverage_pct`` on ``ax``, zoomed on ``threshold_pct``.

    Parameters
    ----------
    ax : matplotlib Axes
    coverage_pct : array_like, shape (m,)
        Coverage of each flight, %.
    threshold_pct : float
        Threshold (target - eps_tol), %; a vertical line.
    fraction : float, optional
        The fraction at or above the threshold to annotate (a horizontal line);
        default: counted from ``coverage_pct``.
    what : str
        What one value is ("samples", "flights"), for the labels.

    Returns
    -------
    dict
        ``order`` (the sort permutation of ``coverage_pct``), ``coverage`` (sorted, %),
        ``fraction_at`` (P(coverage >= coverage[i]) of each sorted value), ``fraction``,
        ``lo`` (left end of the x axis, %) and ``cut`` (values left of it, not shown).
    """
    raw = np.asarray(coverage_pct, dtype=float)
    order = np.argsort(raw, kind="stable")
    cov = raw[order]
    thr = float(threshold_pct)
    m = cov.size
    p = float(np.mean(cov >= thr)) if fraction is None else float(fraction)
    frac = 1.0 - np.arange(m) / m          # P(coverage >= cov[i])
    ax.step(cov, frac, where="pre", color=color, lw=1.5,   # P(cov >= x) on (c_i-1, c_i]
            label=f"P(coverage >= x), {m} {what}")
    ax.plot(cov, frac, "o", color=color, ms=3)
    ax.axvline(thr, color="tab:purple", ls="-.", label=f"threshold {thr:.3f} % "
               "(target - eps_tol)")
    ax.axhline(p, color="k", ls=":", lw=1, label=f"P(coverage >= threshold) = {100 * p:.1f} %")
    # x range on the threshold region: values far below (failures) are counted, not drawn
    span = max(cov[-1] - thr, thr - float(np.median(cov)), 0.05)
    lo = thr - 3 * span
    cut = int((cov < lo).sum())
    ax.set_xlim(lo, max(cov[-1], thr) + 0.3 * span)
    ax.set_ylim(0.0, 1.05)
    ax.ticklabel_format(axis="x", useOffset=False, style="plain")
    ax.set_xlabel("area coverage x, %" + (f" ({cut} {what} below {lo:.2f} % not shown)"
                                          if cut else ""))
    ax.set_ylabel(f"fraction of {what} with coverage >= x")
    ax.grid(alpha=0.3)
    return {"order": order, "coverage": cov, "fraction_at": frac, "fraction": p, "lo": lo,
            "cut": cut}
