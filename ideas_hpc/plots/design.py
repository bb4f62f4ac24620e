"""Design figures: the chosen swarm on its ring, the coverage-versus-N trade, the verification.

Each function takes an ``xarray.Dataset`` opened from a design store, writes
one PNG and returns its path (km, deg, %).
"""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import MaxNLocator

from ideas_hpc.plots.ecdf import exceedance_zoom
from ideas_hpc.plots.figures import body_name, plt, save_png

KM = 1e3


def ring_plane(ds):
    """The plane the ring lies in, as the ring figures draw it.

    Returns ``(e1, e2, labels, view)``: unit axes (frame T, at closest approach for an
    encounter) whose ``d_sep (cos theta e1 + sin theta e2)`` are the ring points, the
    axis labels and the view's name. The paper's ring lies in the ``x_T, y_T`` plane
    (looking down ``+z_T``); an encounter's lies normal to ``v_inf``, in the swarm
    frame's ``x_S, y_S`` (paper eqs. 7-14; :func:`ideas_hpc.core.dynamics.encounter.dcm_NS`),
    seen looking along ``v_inf``.
    """
    a = ds.attrs
    if a.get("geometry") == "encounter":
        from ideas_hpc.core.dynamics.encounter import dcm_NS

        m = dcm_NS(float(a["approach_ra_rad"]), float(a["approach_dec_rad"]))
        return m[:, 0], m[:, 1], ("x_S, km", "y_S, km"), "view along v_inf"
    return np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), ("x_T, km", "y_T, km"), \
        "top view"


def ring_view(ds, path) -> "Path":  # noqa: F821
    """The ring and the chosen swarm angles, seen normal to the ring's plane (:func:`ring_plane`).

    The body's vertices are projected onto that plane for scale; each chosen
    spacecraft is marked at ``d_sep (cos theta, sin theta)`` with its angle.
    """
    a = ds.attrs
    d = float(a["d_sep_m"]) / KM
    th = np.asarray(ds["swarm_angle"].values, dtype=float)
    e1, e2, (xlabel, ylabel), view = ring_plane(ds)
    fig, ax = plt.subplots(figsize=(5.6, 5.6))
    if "vertex_position" in ds:
        v = ds["vertex_position"].values / KM
        ax.scatter(v @ e1, v @ e2, s=0.3, c="0.6", label="body (vertices)")
    phi = np.linspace(0, 2 * np.pi, 361)
    ax.plot(d * np.cos(phi), d * np.sin(phi), "k--", lw=0.8, label=f"ring, d_sep {d:.1f} km")
    ax.scatter(d * np.cos(th), d * np.sin(th), s=60, c="tab:red", zorder=3,
               label=f"chosen swarm, N = {th.size}")
    # neighbours closer than 4 deg (a 0.5 deg grid puts pairs side by side) alternate
    # between two label radii instead of printing over each other
    out = 18.0
    prev = None
    for t in np.sort(th):
        out = 34.0 if prev is not None and t - prev < np.radians(4.0) and out == 18.0 else 18.0
        prev = t
        ax.annotate(f"{np.degrees(t):.1f}°", (d * np.cos(t), d * np.sin(t)),
                    textcoords="offset points", xytext=(out * np.cos(t), out * np.sin(t)),
                    ha="center", va="center", fontsize=8)
    status = a.get("solver_status")
    gap = a.get("optimality_gap")
    title = f"chosen swarm ({view})"
    # the outcome on a second line: one line was wider than the figure and clipped
    if a.get("validation_outcome") is not None:     # success-probability design
        word = "DEMONSTRATED" if a["validation_outcome"] == "demonstrated" else "NOT demonstrated"
        title += f"\nrequirement {word} by validation"
    elif status is not None:
        title += f"\n{status}" + ("" if gap is None else f", gap {100 * float(gap):.1f} %")
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    # room around the ring for the angle labels (they sat on the axis labels), and
    # the legend below the axes, where it hides no spacecraft
    lim = 1.32 * d
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3, fontsize=7,
              frameon=False)
    fig.subplots_adjust(bottom=0.2)
    return save_png(fig, path, body=body_name(ds))


def _requirement_lines(ax, ds) -> None:
    """Horizontal target and threshold lines (issue 22 vocabulary), in %."""
    a = ds.attrs
    if a.get("target_coverage") is not None:
        ax.axhline(100 * float(a["target_coverage"]), color="k", ls=":", lw=1,
                   label=f"target {100 * float(a['target_coverage']):.3f} %")
    thr = a.get("threshold_coverage", a.get("verify_threshold"))
    if thr is not None:
        ax.axhline(100 * float(thr), color="tab:purple", ls="-.", lw=1,
                   label=f"threshold {100 * float(thr):.3f} % (target - eps_tol)")


def coverage_vs_n(ds, path) -> "Path":  # noqa: F821
    """Best coverage any N spacecraft reach against N (each point proven unless
    marked): the whole curve, and a zoom on the decision region around the threshold."""
    n = ds["n_spacecraft"].values
    c = 100.0 * ds["coverage_vs_n"].values
    a = ds.attrs
    tgt = 100.0 * float(a.get("target_coverage", c.max() / 100.0))
    thr = 100.0 * float(a.get("threshold_coverage", a.get("verify_threshold", tgt / 100.0)))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    open_ = ds["coverage_vs_n_gap"].values > 0 if "coverage_vs_n_gap" in ds else \
        np.zeros(n.size, bool)
    for ax in axes:
        ax.plot(n, c, "o-", color="tab:blue", label="best coverage of N spacecraft")
        if open_.any():
            ax.plot(n[open_], c[open_], "x", color="tab:orange", ms=9,
                    label="not proven (time limit): best found")
        _requirement_lines(ax, ds)
        if "spacecraft" in ds.sizes:
            ax.axvline(ds.sizes["spacecraft"], color="tab:red", ls="--", lw=1,
                       label=f"design: N = {ds.sizes['spacecraft']}")
        ax.set_xlabel("swarm size N")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel("area coverage, %")
        ax.grid(alpha=0.3)
    axes[0].set_title("what each extra spacecraft buys")
    # The decision lies between the threshold and the target: a few eps_tol around them.
    band = max(tgt - thr, 0.05)
    lo, hi = thr - 4 * band, max(tgt, float(c.max())) + band
    axes[1].set_ylim(lo, hi)
    near = np.flatnonzero(c >= lo)
    k0 = int(n[near[0]]) if near.size else int(n[0])
    design_n = ds.sizes.get("spacecraft", int(n[0]))   # the zoom always shows the design
    axes[1].set_xlim(max(int(n[0]), min(k0 - 1, design_n - 1)) - 0.5,
                     max(min(int(n[-1]), k0 + 6), design_n + 1) + 0.5)
    axes[1].ticklabel_format(axis="y", useOffset=False, style="plain")
    axes[1].set_title("zoom on the decision region")
    axes[1].legend(fontsize=7, loc="lower right")
    fig.suptitle("coverage versus swarm size")
    return save_png(fig, path, body=body_name(ds))


def verification(ds, path) -> "Path":  # noqa: F821
    """Monte Carlo verification: the fraction of dispersed samples reaching each
    coverage (complementary ECDF, every sample resolved) with the threshold."""
    cov = 100.0 * ds["verify_coverage"].values
    thr = 100.0 * float(ds.attrs["verify_threshold"])
    p = float(ds.attrs["verify_probability"])
    fig, ax = plt.subplots(figsize=(7.2, 4.2))
    exceedance_zoom(ax, cov, thr, fraction=p, what="samples")
    ax.set_title(f"verification: P(coverage >= {thr:.2f} %) = {100 * p:.1f} % ({cov.size} "
                 "samples)", fontsize=10)
    ax.legend(fontsize=7, loc="lower left")
    return save_png(fig, path, body=body_name(ds))


def _axis(ds, name):
    """Values and axis label of one stored objective, in display units."""
    v = np.asarray(ds[f"pareto_{name}"].values, dtype=float)
    units = ds[f"pareto_{name}"].attrs.get("units", "")
    if name == "n":
        return v, "swarm size N"
    if units == "1":
        return 100.0 * v, f"{name.replace('_', ' ')}, %"
    return v, f"{name.replace('_', ' ')}, {units}"


def pareto_front(ds, path) -> "Path":  # noqa: F821
    """The non-dominated swarms, one panel per pair of objectives; with (n, coverage)
    the proven coverage-versus-N curve is drawn under the front."""
    import itertools
    import json

    names = json.loads(ds.attrs.get("objectives", '["n", "coverage"]'))
    pairs = list(itertools.combinations(names, 2))
    cols = min(3, len(pairs))
    rows = -(-len(pairs) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 4.0 * rows), squeeze=False)
    for ax, (a, b) in zip(axes.ravel(), pairs):
        x, xl = _axis(ds, a)
        y, yl = _axis(ds, b)
        if {a, b} == {"n", "coverage"} and "coverage_vs_n" in ds:
            n = ds["n_spacecraft"].values.astype(float)
            c = 100.0 * ds["coverage_vs_n"].values
            ax.plot(*((n, c) if a == "n" else (c, n)), "s--", color="0.55", mfc="none", ms=9,
                    label="proven best coverage of N (exact)")
        ax.plot(x, y, "o", color="tab:red", label=f"non-dominated swarms ({x.size})")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        if a == "n":
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes.ravel()[len(pairs):]:
        ax.set_visible(False)
    fig.suptitle("design-pareto: non-dominated swarms (NSGA-II)")
    return save_png(fig, path, body=body_name(ds))
