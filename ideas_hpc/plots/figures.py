"""Report figures from a result store (paper Figs. 19-37), matplotlib Agg.

Each function takes an ``xarray.Dataset`` opened from a store (SPEC section 9
names), writes one PNG and returns its path. Units on the axes are the
reader's: km, deg, rpm, min.
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from ideas_hpc.base.seeds import plot_rng  # noqa: E402

RPM = 60.0 / (2.0 * np.pi)


#: ``{file name: Figure}`` while :func:`kept` is active: figures are kept open
#: (not closed) so that tests can inspect axes, titles and lines.
_KEPT: dict | None = None


@contextmanager
def kept():
    """Keep every figure written in this block open; yields ``{file name: Figure}``."""
    global _KEPT
    old, _KEPT = _KEPT, {}
    try:
        yield _KEPT
    finally:
        _KEPT = old


def close(fig, path) -> None:
    """Close a written figure (or keep it, under :func:`kept`)."""
    if _KEPT is not None:
        _KEPT[Path(path).name] = fig
    else:
        plt.close(fig)


def body_name(ds) -> str:
    """The body a store was computed on, as figures name it: a design over a target
    prior's drawn worlds names the prior and its nominal (``eros-class prior, nominal
    eros-ellipsoid``), not the nominal alone."""
    a = ds.attrs
    if a.get("target_prior") and str(a.get("body", "")).endswith(" prior"):
        return f"{a['body']}, nominal {a.get('shape_model')}"
    return str(a.get("shape_model") or a.get("body") or "body")


def name_body(fig, body: str | None) -> None:
    """Put the body name in the figure's title (the suptitle, else the first axes')."""
    if not body:
        return
    sup = fig._suptitle.get_text() if fig._suptitle is not None else ""
    if sup:
        if body not in sup:
            fig.suptitle(f"{sup} ({body})")
        return
    ax = fig.axes[0]
    t = ax.get_title()
    if body not in t:
        ax.set_title(f"{t} ({body})" if t else body)


def save_png(fig, path, *, body: str | None = None) -> Path:
    """Body name in the title, tight layout, 120 dpi PNG (parent folders created),
    figure closed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    name_body(fig, body)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    close(fig, path)
    return path


def ga_fitness(ds, path, *, title="GA fitness") -> Path:
    """Best and mean fitness per generation (paper Figs. 19 and 30)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    g = np.arange(1, ds.sizes["generation"] + 1)
    ax.plot(g, ds["best_fitness"].values, "o-", ms=3, label="best")
    ax.plot(g, ds["mean_fitness"].values, "s-", ms=3, label="population mean")
    ax.set_xlabel("generation")
    ax.set_ylabel(ds["best_fitness"].attrs.get("long_name", "fitness"))
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.ticklabel_format(axis="y", useOffset=False, style="plain")  # no "+9.999e1"
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend()
    return save_png(fig, path, body=body_name(ds))


def population_histogram(ds, path, *, sizes: bool) -> Path:
    """Final population: swarm sizes (``sizes``: a GA that designs N, NP Fig. 20) or
    coverage (a GA of given N, FoV Fig. 31)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    if sizes:
        n = np.rint(ds["population"].values[:, 0]).astype(int)
        bins = np.arange(n.min() - 0.5, n.max() + 1.5)
        ax.hist(n, bins=bins, color="tab:blue", edgecolor="k")
        ax.set_xlabel("swarm size N")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_title("final population: swarm sizes")
    else:
        c = 100.0 * ds["population_coverage"].values
        ax.hist(c, bins=20, color="tab:green", edgecolor="k")
        ax.set_xlabel("area coverage, %")
        ax.set_title("final population: coverage")
    ax.set_ylabel("individuals in the final generation")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    return save_png(fig, path, body=body_name(ds))


def _body_wire(ax, vertices_km, faces, every=1):
    tri = faces[::every]
    ax.plot_trisurf(vertices_km[:, 0], vertices_km[:, 1], vertices_km[:, 2], triangles=tri,
                    color="0.7", alpha=0.5, linewidth=0)


def _equal_axes(ax, zoom: float = 0.85) -> None:
    """One scale on the three axes of a 3-D plot: a cube around what is drawn."""
    lims = np.array([ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()])
    mid, half = lims.mean(axis=1), 0.5 * float(np.ptp(lims, axis=1).max())
    ax.set_xlim3d(mid[0] - half, mid[0] + half)
    ax.set_ylim3d(mid[1] - half, mid[1] + half)
    ax.set_zlim3d(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1.0, 1.0, 1.0), zoom=zoom)


def spacecraft_colors(n: int) -> list:
    """One distinct colour per spacecraft: tab10 up to 10, tab20 up to 20, then viridis."""
    if n <= 10:
        return [plt.get_cmap("tab10")(i) for i in range(n)]
    if n <= 20:
        return [plt.get_cmap("tab20")(i) for i in range(n)]
    return [plt.get_cmap("viridis")(x) for x in np.linspace(0.0, 1.0, n)]


def _legend_spacecraft(ax, n: int, **kw) -> None:
    """A legend naming every spacecraft, in columns of at most 10."""
    ax.legend(fontsize=7, ncol=max(1, -(-n // 10)), **kw)


def trajectories(ds, path, *, vertices=None, faces=None) -> Path:
    """Targeted trajectories in frame T (paper Fig. 22)."""
    fig = plt.figure(figsize=(6.4, 5.6))
    ax = fig.add_subplot(projection="3d")
    pos = ds["position"].values / 1e3
    if pos.ndim == 4:
        pos = pos[0]
    cols = spacecraft_colors(pos.shape[0])
    for i in range(pos.shape[0]):
        ax.plot(pos[i, :, 0], pos[i, :, 1], pos[i, :, 2], lw=1.5, color=cols[i],
                label=f"sc {i + 1}")
        ax.scatter(*pos[i, 0], marker="o", s=10, color="k")
    if vertices is not None:
        _body_wire(ax, vertices / 1e3, faces)
    ax.set_xlabel("x_T, km")
    ax.set_ylabel("y_T, km")
    ax.set_zlabel("z_T, km")
    ax.set_title("Targeted trajectories (frame T)")
    _legend_spacecraft(ax, pos.shape[0], loc="upper left")
    ax.set_box_aspect(None, zoom=0.85)   # room for the z label
    return save_png(fig, path, body=body_name(ds))


def targeting_error(ds, path) -> Path:
    """``|dr_k|`` per Newton iteration and spacecraft (paper Fig. 23)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    miss = ds["targeting_miss"].values
    if miss.ndim == 3:
        miss = miss[0]
    n_sc = miss.shape[0]
    markers = "osD^vP*X<>"
    for i in range(n_sc):
        m = miss[i]
        k = np.isfinite(m)
        # spacecraft with the same iterates would hide each other: a small x offset
        # and a marker each keep every one visible
        dx = 0.3 * (i - (n_sc - 1) / 2) / max(n_sc, 1)
        ax.semilogy(np.arange(m.size)[k] + dx, m[k], "-", marker=markers[i % len(markers)],
                    ms=5, mfc="none", lw=1, alpha=0.85, label=f"sc {i + 1}")
    tol = ds.attrs.get("targeting_tolerance_m")
    if tol:
        ax.axhline(float(tol), color="k", ls="--", lw=1, label="tolerance")
    ax.set_xlabel("iteration k")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("|Δr_k|, m")
    ax.set_title("Targeting: position miss per Newton iteration")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    return save_png(fig, path, body=body_name(ds))


def attitude_series(ds, var, path, *, ylabel, scale=1.0, title=None, log=False) -> Path:
    """Per-spacecraft time series of a 3-component variable (paper Figs. 26-29, 34-37).

    A sample dimension, if present, is drawn as a min-max envelope per spacecraft.
    """
    da = ds[var]
    # Time on a log axis: the acquisition takes the first tens of seconds of a
    # 10-minute pass and the steady state the rest; a linear axis squeezed the whole
    # transient into its first tick. t = 0 has no place on it and is left out.
    t_s = ds["time"].values
    keep = t_s > 0
    t = t_s[keep]
    vals = (da.values * scale)[..., keep, :]
    fig, axes = plt.subplots(3, 1, figsize=(6.8, 6.4), sharex=True)
    labels = da.attrs.get("components", ["1", "2", "3"])
    n_sc = vals.shape[-3]
    cols = spacecraft_colors(n_sc)
    for c in range(3):
        ax = axes[c]
        if vals.ndim == 4:  # sample, spacecraft, time, comp
            for i in range(vals.shape[1]):
                y = np.abs(vals[:, i, :, c]) if log else vals[:, i, :, c]
                ax.fill_between(t, y.min(axis=0), y.max(axis=0), alpha=0.3, color=cols[i],
                                label=f"sc {i + 1}" if c == 0 else None)
        else:
            for i in range(vals.shape[0]):
                y = np.abs(vals[i, :, c]) if log else vals[i, :, c]
                ax.plot(t, y, lw=1, color=cols[i], label=f"sc {i + 1}" if c == 0 else None)
        if log:
            ax.set_yscale("log")
        ax.set_xscale("log")
        ax.set_ylabel(f"{ylabel} [{labels[c]}]")
        ax.grid(alpha=0.3, which="both" if log else "major")
    axes[-1].set_xlabel("time since the start of the pass, s (log scale: the acquisition, "
                        "then the steady state)", fontsize=9)
    _legend_spacecraft(axes[0], n_sc, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # off the data
    kind = "Monte Carlo min-max envelope per spacecraft, " if vals.ndim == 4 else ""
    axes[0].set_title(title or f"{kind}{da.attrs.get('long_name', var)}")
    return save_png(fig, path, body=body_name(ds))


def fov_pyramids(path, r_T, dcm_BT, eta, time_s, *, vertices, faces, body=None) -> Path:
    """FoV pyramids of every spacecraft at one instant, with the body (Figs. 24, 33).

    ``r_T`` (N, 3) m and ``dcm_BT`` (N, 3, 3) at time ``time_s``; ``eta`` rad.
    """
    fig = plt.figure(figsize=(6.4, 5.6))
    ax = fig.add_subplot(projection="3d")
    _body_wire(ax, vertices / 1e3, faces)
    t = np.tan(eta)
    for r, c_bt in zip(r_T, dcm_BT):
        length = np.linalg.norm(r)
        corners_b = np.array([[t, t, 1], [-t, t, 1], [-t, -t, 1], [t, -t, 1]]) * length
        corners = (c_bt.T @ corners_b.T).T + r
        for q in corners:
            ax.plot(*np.c_[r, q] / 1e3, color="tab:orange", lw=0.8)
        loop = np.vstack([corners, corners[:1]]) / 1e3
        ax.plot(loop[:, 0], loop[:, 1], loop[:, 2], color="tab:orange", lw=0.8)
        ax.scatter(*(r / 1e3), color="tab:blue", s=12)
    ax.set_title(f"FoV pyramids at t = {time_s / 60.0:.2f} min (equal axes)")
    ax.set_xlabel("x_T, km")
    ax.set_ylabel("y_T, km")
    ax.set_zlabel("z_T, km", labelpad=8)
    _equal_axes(ax, zoom=0.8)   # a km is a km on every axis: the body keeps its shape
    return save_png(fig, path, body=body)


def mc_coverage(ds, path) -> Path:
    """Monte Carlo: coverage distribution, and coverage against failed spacecraft."""
    cov = 100.0 * ds["coverage"].values
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    axes[0].hist(cov, bins=min(30, max(5, cov.size // 4)), color="tab:blue", edgecolor="k")
    axes[0].set_xlabel("area coverage, %")
    axes[0].set_ylabel("samples")
    axes[0].yaxis.set_major_locator(MaxNLocator(integer=True))
    axes[0].set_title(f"coverage of {cov.size} samples")
    if "n_failed" in ds:
        nf = ds["n_failed"].values
        axes[1].scatter(nf + plot_rng().uniform(-0.1, 0.1, nf.size), cov, s=8)
        axes[1].set_xlabel("failed spacecraft")
        axes[1].xaxis.set_major_locator(MaxNLocator(integer=True))
        axes[1].set_ylabel("area coverage, %")
        axes[1].set_title("coverage against failed spacecraft")
    else:
        axes[1].set_visible(False)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle("Monte Carlo coverage")
    return save_png(fig, path, body=body_name(ds))


def quality_histograms(ds, path):
    """Area-weighted histograms of the quality variables (issue 14): best
    resolution (m) and emission, incidence, phase at best (deg). Monte Carlo
    stores pool every sample."""
    a = np.asarray(ds["vertex_area"].values, dtype=float)
    panels = [("best_resolution", "best resolution, m", 1.0),
              ("emission_at_best", "emission at best, deg", 180.0 / np.pi),
              ("incidence_at_best", "incidence at best, deg", 180.0 / np.pi),
              ("phase_at_best", "phase at best, deg", 180.0 / np.pi)]
    fig, axes = plt.subplots(1, 4, figsize=(14, 3.4))
    for ax, (name, label, scale) in zip(axes, panels):
        x = np.asarray(ds[name].values, dtype=float) * scale
        w = np.broadcast_to(a, x.shape)
        ok = np.isfinite(x)
        if ok.any():
            ax.hist(x[ok], bins=40, weights=w[ok] / w.sum(), color="C0")
        ax.set_xlabel(label)
        ax.set_ylabel("area fraction")
    fig.suptitle("observation quality, area-weighted")
    return save_png(fig, path, body=body_name(ds))
