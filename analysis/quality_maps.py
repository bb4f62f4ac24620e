"""Per-vertex probabilities of the observation quality in a Monte Carlo store (issue 14).

A Monte Carlo store written with a ``[coverage]`` requirement, or with
``coverage.quality = true``, holds the quality variables of
:data:`ideas_hpc.engine.variables.QUALITY` with a leading ``sample`` dim
(``lit``, ``best_resolution``, ``emission_at_best``, ``incidence_at_best``,
``phase_at_best``, ``n_spacecraft_seen``, ``stereo``, ``mapped``).
:func:`vertex_probabilities` turns them into the probability, over the
samples, that each vertex meets a condition:

.. math:: P_v(c) = \\frac{1}{N_s} \\sum_{k=1}^{N_s} [c(x_{k,v})],

an estimate with standard error ``sqrt(P (1 - P) / N_s)``. A vertex never
observed in sample ``k`` has NaN resolution and angles there (``inf``
resolution when it was only seen edge-on); NaN and ``inf`` never meet a limit,
so they count as failures, not as missing data. Samples of chunks not yet
written (``chunk_done`` False) are left out: their entries are fill values.

The area-weighted mean of ``p_mapped`` is the expected mapped area fraction,
i.e. the mean of the store's ``coverage`` (with a requirement set); that of
``p_observed`` the mean of ``coverage_seen``. :func:`area_exceedance` gives
the fraction of the surface area whose probability is at least ``p``.

The marginal probabilities ``p_resolution``, ``p_emission`` ... are judged at
the best-resolution image only; ``mapped`` asks that one image meet every
limit at once (:mod:`ideas_hpc.mapping.options`), so ``p_mapped`` is not
their product.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from ideas_hpc.plots.coverage_map import render_coverage_map  # noqa: E402
from ideas_hpc.plots.figures import save_png  # noqa: E402
from ideas_hpc.engine.variables import QUALITY  # noqa: E402
from plotting import store_config  # noqa: E402  (analysis/plotting.py)

HOW_TO_GET = ("write the store with the quality pass: `ideas-hpc run CAMPAIGN --out STORE "
              "--set coverage.quality=true` (or set a [coverage] requirement such as "
              "max_resolution_m)")

#: Requirement keys of ``[coverage]`` (user units) and the stored variable each limits.
LIMITS = {"max_resolution_m": ("best_resolution", "p_resolution", "m", 1.0),
          "max_emission_deg": ("emission_at_best", "p_emission", "deg", np.pi / 180.0),
          "max_incidence_deg": ("incidence_at_best", "p_incidence", "deg", np.pi / 180.0),
          "max_phase_deg": ("phase_at_best", "p_phase", "deg", np.pi / 180.0)}
_SI = {"max_resolution_m": "max_resolution", "max_emission_deg": "max_emission",
       "max_incidence_deg": "max_incidence", "max_phase_deg": "max_phase"}


def missing_quality(ds) -> str | None:
    """The first quality variable ``ds`` lacks (or lacks a ``sample`` dim for); None if complete."""
    for name in QUALITY + ("observed",):
        if name not in ds.variables or "sample" not in ds[name].dims:
            return name
    return None


def has_quality(ds) -> bool:
    """True when ``ds`` is a Monte Carlo store with every per-sample quality variable."""
    return missing_quality(ds) is None


def why_no_quality(ds) -> str:
    """One sentence for a store without quality variables: which is missing and what to do."""
    name = missing_quality(ds)
    if name is None:
        return "the store has every quality variable"
    what = "is missing" if name not in ds.variables else "has no 'sample' dim"
    return (f"quality variable {name!r} {what}: not a Monte Carlo store with per-vertex "
            f"quality; {HOW_TO_GET}")


def store_limits(ds) -> dict:
    """The store's own ``[coverage]`` requirement limits in user units (m, deg); unset: absent."""
    cfg = store_config(ds)
    table = cfg.get("coverage") or {}
    models = (cfg.get("models") or {}).get("coverage") or {}
    out = {}
    for key, (_, _, _, to_si) in LIMITS.items():
        if table.get(key) is not None:
            out[key] = float(table[key])
        elif models.get(_SI[key]) is not None:
            out[key] = float(models[_SI[key]]) / to_si
    return out


def done_samples(ds) -> np.ndarray:
    """Bool (sample,): samples whose chunk is written (every sample if no ``chunk_done``)."""
    ok = np.ones(ds.sizes["sample"], dtype=bool)
    if "chunk_done" in ds and "chunk_start" in ds.coords:
        done = np.asarray(ds["chunk_done"].values, dtype=bool)
        starts, stops = ds["chunk_start"].values, ds["chunk_stop"].values
        for d, a, b in zip(done, starts, stops):
            ok[int(a):int(b)] = bool(d)
    return ok


def vertex_probabilities(ds, *, max_resolution_m=None, max_emission_deg=None,
                         max_incidence_deg=None, max_phase_deg=None,
                         min_spacecraft: int = 2) -> xr.Dataset:
    """Per-vertex probabilities over the Monte Carlo samples (dim ``vertex``).

    Parameters
    ----------
    ds : xarray.Dataset
        A Monte Carlo store with the quality variables (``sample`` first).
    max_resolution_m, max_emission_deg, max_incidence_deg, max_phase_deg : float, optional
        Limits for the marginal probabilities ``P(best_resolution <= X)``,
        ``P(emission_at_best <= e)`` ... (m, deg). None: the store's own
        ``[coverage]`` value if it set one, else that probability is left out.
    min_spacecraft : int
        ``p_multi_spacecraft = P(n_spacecraft_seen >= min_spacecraft)``.

    Returns
    -------
    xarray.Dataset
        ``p_observed``, ``p_lit``, ``p_stereo``, ``p_mapped``,
        ``p_multi_spacecraft`` and, with a limit, ``p_resolution``,
        ``p_emission``, ``p_incidence``, ``p_phase``, each (vertex,) in
        [0, 1] with ``units = "1"``, a ``long_name`` and (limits) ``limit`` /
        ``limit_units`` attrs; ``vertex_area`` (m^2) for area weights; attr
        ``n_samples`` (the written samples used).

    Raises
    ------
    ValueError
        A store without the quality variables (message names the first
        missing one and how to write them), or with no written sample.
    """
    if not has_quality(ds):
        raise ValueError(why_no_quality(ds))
    keep = done_samples(ds)
    if not keep.any():
        raise ValueError("no sample written yet (chunk_done all False): run with --resume")
    ns = int(keep.sum())

    def per_sample(name):
        return np.asarray(ds[name].transpose("sample", "vertex").values)[keep]

    def prob(hits):  # (ns, V) bool -> (V,) mean over samples
        return hits.sum(axis=0) / ns

    out = {}
    for name, var in (("p_observed", "observed"), ("p_lit", "lit"), ("p_stereo", "stereo"),
                      ("p_mapped", "mapped")):
        out[name] = (prob(per_sample(var).astype(bool)),
                     f"probability over samples: {var} ({ds[var].attrs.get('long_name', var)})")
    out["p_multi_spacecraft"] = (prob(per_sample("n_spacecraft_seen") >= int(min_spacecraft)),
                                 f"probability over samples: n_spacecraft_seen >= "
                                 f"{int(min_spacecraft)}")
    given = {"max_resolution_m": max_resolution_m, "max_emission_deg": max_emission_deg,
             "max_incidence_deg": max_incidence_deg, "max_phase_deg": max_phase_deg}
    own = store_limits(ds)
    limits = {}
    for key, (var, pname, unit, to_si) in LIMITS.items():
        lim = given[key] if given[key] is not None else own.get(key)
        if lim is None:
            continue
        x = per_sample(var).astype(np.float64)
        # NaN (never observed) and inf (edge-on only) compare False: not meeting the limit.
        with np.errstate(invalid="ignore"):
            hits = x <= float(lim) * to_si
        out[pname] = (prob(hits), f"probability over samples: {var} <= {float(lim):g} {unit}")
        limits[pname] = (float(lim), unit)
    res = xr.Dataset(coords={"vertex": ds["vertex"].values if "vertex" in ds.coords
                             else np.arange(ds.sizes["vertex"])})
    for name, (p, long_name) in out.items():
        res[name] = ("vertex", p, {"units": "1", "long_name": long_name})
        if name in limits:
            res[name].attrs.update(limit=limits[name][0], limit_units=limits[name][1])
    res["vertex_area"] = ("vertex", np.asarray(ds["vertex_area"].values, dtype=float),
                          {"units": "m^2", "long_name": "vertex area (area weights)"})
    res.attrs["n_samples"] = ns
    return res


def probability_names(probs: xr.Dataset) -> list[str]:
    """The probability variables of a :func:`vertex_probabilities` result, in order."""
    return [n for n in probs.data_vars if n.startswith("p_")]


def area_weighted_mean(probs: xr.Dataset) -> dict:
    """name -> ``sum(A_v P_v) / sum(A_v)``: the expected area fraction meeting each condition."""
    a = probs["vertex_area"].values
    return {n: float((a * probs[n].values).sum() / a.sum()) for n in probability_names(probs)}


def area_exceedance(p, area, levels=None):
    """Fraction of the area with probability ``>= level``: ``sum(A_v [P_v >= p]) / sum(A_v)``.

    ``levels`` default: 0, every distinct value of ``p`` and 1, sorted. Returns
    ``(levels, fraction)``; the curve is 1 at level 0 and non-increasing.
    """
    p = np.asarray(p, dtype=float)
    area = np.asarray(area, dtype=float)
    if levels is None:
        levels = np.unique(np.r_[0.0, p[np.isfinite(p)], 1.0])
    levels = np.asarray(levels, dtype=float)
    order = np.argsort(p)
    ps, cum = p[order], np.r_[0.0, np.cumsum(area[order])]
    # area of vertices with p >= level = total - area of those with p < level
    below = cum[np.searchsorted(ps, levels, side="left")]
    return levels, (cum[-1] - below) / cum[-1]


def summary_table(probs: xr.Dataset, thresholds=(0.5, 0.9, 1.0)) -> str:
    """Text table: per probability, the expected area fraction and the area with P >= thresholds."""
    a = probs["vertex_area"].values
    head = "  ".join(f"P>={t:g}" for t in thresholds)
    lines = [f"{'':20s} {'E[area]':>8s}  {head}   (area fractions, %, "
             f"{probs.attrs.get('n_samples')} samples)"]
    means = area_weighted_mean(probs)
    for n in probability_names(probs):
        _, f = area_exceedance(probs[n].values, a, thresholds)
        cols = "  ".join(f"{100 * x:6.2f}" for x in f)
        lines.append(f"{n:20s} {100 * means[n]:8.2f}  {cols}")
    return "\n".join(lines)


# ------------------------------------------------------------------- figures

def _label(probs, name):
    a = probs[name].attrs
    base = name.removeprefix("p_")
    return f"{base} <= {a['limit']:g} {a['limit_units']}" if "limit" in a else base


def exceedance_figure(probs: xr.Dataset, path) -> Path:
    """Area fraction (%) with per-vertex probability >= p, one curve per condition."""
    a = probs["vertex_area"].values
    fig, ax = plt.subplots(figsize=(7.2, 4.6))
    for i, n in enumerate(probability_names(probs)):
        lv, f = area_exceedance(probs[n].values, a)
        # exact step: constant on (lv[j-1], lv[j]], equal to f[j] there
        ax.step(lv, 100.0 * f, where="pre", color=plt.get_cmap("tab10")(i % 10), lw=1.6,
                ls=("-", "--", ":", "-.")[i % 4], label=_label(probs, n))
    ax.set_xlabel("probability over samples, p")
    ax.set_ylabel("surface area with P(vertex) ≥ p, %")
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(-2.0, 102.0)
    ax.set_title(f"Area exceedance of per-vertex probabilities ({probs.attrs.get('n_samples')}"
                 " samples)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    return save_png(fig, path)


def probability_histograms_figure(probs: xr.Dataset, path) -> Path:
    """Area-weighted histograms of each per-vertex probability (bars: % of surface area)."""
    names = probability_names(probs)
    a = probs["vertex_area"].values
    share = 100.0 * a / a.sum()
    ns = int(probs.attrs.get("n_samples", 20))
    nb = min(ns + 1, 21)   # one bin per possible value k/ns, at most 21
    edges = np.linspace(-0.5 / (nb - 1), 1 + 0.5 / (nb - 1), nb + 1)
    ncol = min(3, len(names))
    nrow = -(-len(names) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.0 * ncol, 3.0 * nrow), squeeze=False)
    for ax, n in zip(axes.ravel(), names):
        ax.hist(probs[n].values, bins=edges, weights=share, color="tab:purple", edgecolor="k")
        ax.set_title(f"P({_label(probs, n)})", fontsize=9)
        ax.set_xlabel("probability over samples")
        ax.set_ylabel("surface area, %")
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    return save_png(fig, path)


def store_shape(ds):
    """The body mesh stored in ``ds`` (``vertex_position``, ``face_vertices``)."""
    from ideas_hpc.body.shape import build_shape

    return build_shape(ds["vertex_position"].values, ds["face_vertices"].values.astype(np.int64),
                       name=str(ds.attrs.get("shape_model", "body")), source="store")


def probability_maps(ds, probs: xr.Dataset, out, names=None) -> dict:
    """Maps on the body of the probabilities (the report's fraction map); name -> PNG path."""
    out = Path(out)
    shape = store_shape(ds)
    made = {}
    for n in names or probability_names(probs):
        made[n] = render_coverage_map(shape, probs[n].values, out / f"mc_quality_{n}.png",
                                      kind="fraction", title=f"P({_label(probs, n)}) per vertex",
                                      label="probability over samples")
    return made


def make_all(ds, out, **limits) -> dict:
    """Probabilities, maps, exceedance and histograms into ``out``; name -> PNG path."""
    probs = vertex_probabilities(ds, **limits)
    out = Path(out)
    made = {"mc_quality_exceedance.png": exceedance_figure(probs,
                                                           out / "mc_quality_exceedance.png"),
            "mc_quality_histograms.png": probability_histograms_figure(
                probs, out / "mc_quality_histograms.png")}
    made.update({p.name: p for p in probability_maps(ds, probs, out).values()})
    return made
