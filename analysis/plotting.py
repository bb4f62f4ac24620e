"""Monte Carlo plots for a campaign store (SPEC sections 8-9), matplotlib Agg.

``analysis/mc_analysis.ipynb`` calls these; they are plain functions so the
tests can run them without a notebook. Each ``*_figure`` function takes an
``xarray.Dataset`` opened from a Monte Carlo store (``xarray.open_zarr``),
writes one PNG and returns its path. The reductions they draw
(:func:`ecdf`, :func:`sample_envelope`, :func:`vertex_observed_fraction`) are
separate, so they can be checked on their own.

Units on the axes are the reader's: coverage in %, time in min, torque in N m.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from ideas_hpc.campaign.schema.kinds import KINDS  # noqa: E402
from ideas_hpc.plots.figures import save_png  # noqa: E402

#: Wheel torque limit of the paper's spacecraft, N m (SPEC section 5); a store
#: whose config sets ``spacecraft.u_max`` uses that value instead.
U_MAX_DEFAULT = 0.007

FIGURES = ("mc_coverage_distribution.png", "mc_coverage_vs_failures.png",
           "mc_attitude_envelopes.png", "mc_vertex_observed_fraction.png")


def open_store(path) -> xr.Dataset:
    """Open a Monte Carlo store lazily; refuse anything that is not one."""
    ds = xr.open_zarr(str(path))
    kind = ds.attrs.get("kind")
    if not getattr(KINDS.get(kind), "samples", False):
        able = ", ".join(repr(k.name) for k in KINDS.values() if k.samples)
        raise ValueError(f"{path}: kind is {kind!r}, not a {able} store")
    if "chunk_done" in ds and not bool(ds["chunk_done"].all()):
        missing = int((~ds["chunk_done"].values).sum())
        raise ValueError(f"{path}: {missing} chunk(s) not written yet (run with --resume)")
    return ds


def store_config(ds: xr.Dataset) -> dict:
    """The resolved campaign config stored in the attrs (empty dict if absent)."""
    raw = ds.attrs.get("config")
    return json.loads(raw) if raw else {}


def torque_limit(ds: xr.Dataset) -> float:
    """Wheel torque limit ``u_max`` in N m: the store's config, else 0.007."""
    sc = store_config(ds).get("spacecraft") or {}
    return float(sc.get("u_max", U_MAX_DEFAULT)) if isinstance(sc, dict) else U_MAX_DEFAULT


def summary(ds: xr.Dataset) -> str:
    """A few lines describing the store and its coverage statistics."""
    cov = 100.0 * ds["coverage"].values
    lines = [
        f"kind {ds.attrs.get('kind')}, {ds.sizes['sample']} samples, "
        f"{ds.sizes['spacecraft']} spacecraft, {ds.sizes['vertex']} vertices, "
        f"seed {ds.attrs.get('campaign_seed')}, code {ds.attrs.get('code_version')}",
        f"body: {ds.attrs.get('body_note', ds.attrs.get('body', '?'))}",
        f"area coverage %: min {cov.min():.2f}, median {np.median(cov):.2f}, "
        f"mean {cov.mean():.2f}, max {cov.max():.2f}",
    ]
    if "n_failed" in ds:
        nf = ds["n_failed"].values
        counts = ", ".join(f"{k}: {int((nf == k).sum())}" for k in np.unique(nf))
        lines.append(f"samples by failed spacecraft ({{n_failed: samples}}): {counts}")
    return "\n".join(lines)


# ---------------------------------------------------------------- reductions

def ecdf(values):
    """Empirical CDF: sorted values ``x`` and ``F(x_i) = i / n`` for i = 1..n."""
    x = np.sort(np.asarray(values, dtype=float).ravel())
    return x, np.arange(1, x.size + 1) / x.size


def sample_envelope(da: xr.DataArray, dim: str = "sample") -> xr.Dataset:
    """min, median and max of ``da`` over ``dim``, skipping NaN (masked entries)."""
    return xr.Dataset({"min": da.min(dim, skipna=True),
                       "median": da.median(dim, skipna=True),
                       "max": da.max(dim, skipna=True)})


def attitude_error_norm(ds: xr.Dataset, active_only: bool = True) -> xr.DataArray:
    """``|sigma_B/R|`` (sample, spacecraft, time); failed spacecraft NaN if ``active_only``.

    For an MRP, ``|sigma| = tan(Phi / 4)`` with ``Phi`` the principal angle of
    the error rotation, so it is a monotone measure of the pointing error.
    """
    s = np.sqrt((ds["sigma_error"] ** 2).sum("axis"))
    return s.where(ds["active"]) if active_only else s


def max_wheel_torque(ds: xr.Dataset, active_only: bool = True) -> xr.DataArray:
    """Largest ``|u_s|`` over the three wheels (sample, spacecraft, time), N m."""
    u = abs(ds["wheel_torque"]).max("wheel")
    return u.where(ds["active"]) if active_only else u


def vertex_observed_fraction(ds: xr.Dataset) -> xr.DataArray:
    """Fraction of samples in which each vertex was observed (vertex,), in [0, 1]."""
    return ds["observed"].astype(float).mean("sample")


# ------------------------------------------------------------------- figures

def _bins(values, n_max=30):
    """Histogram edges that also work when every sample has the same value."""
    lo, hi = float(np.min(values)), float(np.max(values))
    n = int(min(n_max, max(5, np.sqrt(np.size(values)) * 2)))
    if hi - lo < 1e-9:
        return np.linspace(lo - 0.5, hi + 0.5, 6)
    return np.linspace(lo, hi, n + 1)


def coverage_distribution_figure(ds: xr.Dataset, path) -> Path:
    """Histogram and empirical CDF of the per-sample coverage, in %."""
    cov = 100.0 * ds["coverage"].values
    fig, (ax_h, ax_c) = plt.subplots(1, 2, figsize=(10.0, 4.0))
    ax_h.hist(cov, bins=_bins(cov), color="tab:blue", edgecolor="k", label="area-weighted")
    ax_h.axvline(np.median(cov), color="k", ls="--", lw=1,
                 label=f"median {np.median(cov):.2f} %")
    ax_h.set_xlabel("area coverage, %")
    ax_h.set_ylabel("samples")
    ax_h.set_title(f"Coverage distribution ({cov.size} samples)")
    ax_h.legend(fontsize=8)
    x, f = ecdf(cov)
    ax_c.step(np.r_[x[0], x], 100.0 * np.r_[0.0, f], where="post", color="tab:blue",
              label="area-weighted (coverage)")
    if "coverage_count" in ds:
        xc, fc = ecdf(100.0 * ds["coverage_count"].values)
        ax_c.step(np.r_[xc[0], xc], 100.0 * np.r_[0.0, fc], where="post", color="tab:orange",
                  ls="--", label="vertex count (coverage_count)")
    ax_c.set_xlabel("coverage, %")
    ax_c.set_ylabel("samples with coverage ≤ x, %")
    ax_c.set_ylim(-2, 102)
    ax_c.set_title("Empirical CDF")
    ax_c.legend(fontsize=8, loc="upper left")
    for ax in (ax_h, ax_c):
        ax.grid(alpha=0.3)
    return save_png(fig, path)


def coverage_vs_failures_figure(ds: xr.Dataset, path) -> Path:
    """Box plot of coverage (%) per number of failed spacecraft, samples as points."""
    cov = 100.0 * ds["coverage"].values
    nf = ds["n_failed"].values.astype(int)
    groups = np.unique(nf)
    data = [cov[nf == k] for k in groups]
    fig, ax = plt.subplots(figsize=(6.8, 4.2))
    ax.boxplot(data, positions=groups, widths=0.5, showfliers=False,
               medianprops={"color": "k"})
    jitter = np.random.default_rng(0).uniform(-0.15, 0.15, cov.size)
    ax.scatter(nf + jitter, cov, s=12, color="tab:blue", alpha=0.7, zorder=3,
               label="samples")
    ax.set_xticks(groups)
    ax.set_xticklabels([f"{k}\n(n={len(d)})" for k, d in zip(groups, data)])
    ax.set_xlim(groups.min() - 0.7, groups.max() + 0.7)
    pad = max(0.5, 0.05 * (cov.max() - cov.min()))
    ax.set_ylim(cov.min() - pad, min(100.0 + pad, cov.max() + pad))
    n_sc = ds.sizes["spacecraft"]
    ax.set_xlabel(f"failed spacecraft (of {n_sc})")
    ax.set_ylabel("area coverage, %")
    ax.set_title("Coverage against spacecraft failures")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    return save_png(fig, path)


def _positive(a):
    """Values for a log axis: non-positive entries become NaN (gaps, not -inf)."""
    a = np.asarray(a, dtype=float)
    return np.where(a > 0, a, np.nan)


def attitude_envelopes_figure(ds: xr.Dataset, path, *, per_spacecraft=True,
                              active_only=True, u_max=None) -> Path:
    """Envelopes over samples of ``|sigma_B/R|`` per spacecraft, and of the wheel torque.

    Top: min-max band and median of ``|sigma|`` over samples for each spacecraft
    (``per_spacecraft=False``: over samples and spacecraft together), log axis.
    Bottom: the same for the largest wheel torque over the three wheels, all
    spacecraft together, against the limit ``u_max`` (N m). Failed spacecraft are
    left out when ``active_only``.
    """
    if u_max is None:
        u_max = torque_limit(ds)
    t = ds["time"].values / 60.0
    sig = attitude_error_norm(ds, active_only)
    tq = max_wheel_torque(ds, active_only)
    fig, (ax_s, ax_u) = plt.subplots(2, 1, figsize=(8.2, 7.0), sharex=True)
    if per_spacecraft:
        env = sample_envelope(sig).compute()
        colors = plt.get_cmap("tab10")
        for i in range(ds.sizes["spacecraft"]):
            e = env.isel(spacecraft=i)
            c = colors(i % 10)
            ax_s.fill_between(t, _positive(e["min"]), _positive(e["max"]), color=c, alpha=0.15,
                              lw=0)
            ax_s.plot(t, _positive(e["median"]), color=c, lw=1.2, label=f"sc {i + 1}")
        ax_s.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                    title="median\nband: min-max", title_fontsize=7)
    else:
        env = sample_envelope(sig.stack(run=("sample", "spacecraft")), "run").compute()
        ax_s.fill_between(t, _positive(env["min"]), _positive(env["max"]), color="tab:blue",
                          alpha=0.25, lw=0, label="min-max")
        ax_s.plot(t, _positive(env["median"]), color="tab:blue", lw=1.5, label="median")
        ax_s.legend(fontsize=8)
    ax_s.set_yscale("log")
    ax_s.set_ylabel("|σ_B/R| (MRP, = tan(Φ/4))")
    who = "working spacecraft" if active_only else "all spacecraft"
    ax_s.set_title(f"Attitude error over {ds.sizes['sample']} samples ({who})")
    ax_s.grid(alpha=0.3)

    tenv = sample_envelope(tq.stack(run=("sample", "spacecraft")), "run").compute()
    ax_u.fill_between(t, _positive(tenv["min"]), _positive(tenv["max"]), color="tab:green",
                      alpha=0.25, lw=0, label="min-max over\nsamples and\nspacecraft")
    ax_u.plot(t, _positive(tenv["median"]), color="tab:green", lw=1.5, label="median")
    ax_u.axhline(u_max, color="tab:red", ls="--", lw=1.2, label=f"limit {u_max:g} N m")
    ax_u.set_yscale("log")
    ax_u.set_ylabel("max wheel torque |u_s|, N m")
    ax_u.set_xlabel("time, min")
    ax_u.set_title("Reaction wheel torque (largest of 3 wheels)")
    ax_u.grid(alpha=0.3)
    ax_u.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return save_png(fig, path)


def vertex_observed_fraction_figure(ds: xr.Dataset, path) -> Path:
    """Histogram of the fraction of samples that observed each vertex.

    Bars are weighted by vertex area (``vertex_area``), so their heights are
    shares of the body's surface area; the title gives the vertex counts at the
    two extremes (seen in every sample, never seen).
    """
    frac = vertex_observed_fraction(ds).values
    area = ds["vertex_area"].values
    share = 100.0 * area / area.sum()
    ns = ds.sizes["sample"]
    # One bin per possible value k/ns (capped at 20 bins for large campaigns).
    nb = min(ns + 1, 21)
    edges = np.linspace(-0.5 / (nb - 1), 1 + 0.5 / (nb - 1), nb + 1) * 100.0
    fig, ax = plt.subplots(figsize=(6.8, 4.2))
    ax.hist(100.0 * frac, bins=edges, weights=share, color="tab:purple", edgecolor="k")
    ax.set_xlabel("samples in which the vertex was observed, %")
    ax.set_ylabel("share of surface area, %")
    ax.set_xlim(edges[0], edges[-1])
    always = int((frac == 1.0).sum())
    never = int((frac == 0.0).sum())
    ax.set_title(f"Per-vertex observation over {ns} samples\n"
                 f"{always} of {frac.size} vertices seen in every sample, {never} never")
    ax.grid(alpha=0.3)
    return save_png(fig, path)


def make_all(ds: xr.Dataset, out) -> dict:
    """The Monte Carlo figures into directory ``out``; returns name -> path.

    The attitude envelopes need ``attitude.mode = "simulated"`` (a store
    without ``sigma_error`` skips that figure).
    """
    out = Path(out)
    funcs = (coverage_distribution_figure, coverage_vs_failures_figure,
             attitude_envelopes_figure, vertex_observed_fraction_figure)
    made = {}
    for name, f in zip(FIGURES, funcs):
        if f is attitude_envelopes_figure and "sigma_error" not in ds:
            continue
        made[name] = f(ds, out / name)
    return made
