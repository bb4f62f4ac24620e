"""Figures of ``ideas-hpc study``'s answers (issue 42 deliverable 6), matplotlib Agg: the
B-plane error ellipse with the swarm, and the value of a late update beside the
per-target reliability."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ideas_hpc.plots.figures import close  # noqa: E402

KM = 1e3


def ellipse_points(cov_m2, k_sigma: float, n: int = 181) -> np.ndarray:
    """``(n, 2)`` points of the ``k_sigma`` contour of a 2-D Gaussian of covariance ``cov_m2``:
    ``k L (cos t, sin t)`` with ``L L^T = cov`` (Cholesky), i.e. ``x^T cov^-1 x = k^2``."""
    cov = np.asarray(cov_m2, dtype=np.float64)
    w, v = np.linalg.eigh(cov)
    t = np.linspace(0.0, 2.0 * math.pi, n)
    circle = np.column_stack([np.cos(t), np.sin(t)])
    return k_sigma * circle * np.sqrt(np.clip(w, 0.0, None)) @ v.T


def bplane_figure(cov_m2, swarm_m, path, *, d_sep_m: float | None = None,
                  other_sigmas_m=(), body_radius_m: float | None = None,
                  title: str = "") -> Path:
    """The target's B-plane error ellipses (1, 2, 3 sigma of ``cov_m2``, m^2, axes T and R)
    about the predicted target, and the swarm members' closest-approach points
    ``swarm_m`` (N, 2) m; the ring of radius ``d_sep_m`` dashed; ``other_sigmas_m`` the
    1-sigma contours of the same ellipse scaled to those major axes (dotted). Km."""
    cov = np.asarray(cov_m2, dtype=np.float64)
    sw = np.asarray(swarm_m, dtype=np.float64) / KM
    major = math.sqrt(max(float(np.linalg.eigvalsh(cov)[-1]), 0.0))
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.8))
    for ax, zoom in zip(axes, (False, True)):
        if d_sep_m and not zoom:
            t = np.linspace(0.0, 2.0 * math.pi, 361)
            ax.plot(d_sep_m / KM * np.cos(t), d_sep_m / KM * np.sin(t), "--", color="0.6",
                    lw=0.8, label=f"ring, d = {d_sep_m / KM:.0f} km")
        others = [s for s in other_sigmas_m
                  if major > 0 and not math.isclose(s, major, rel_tol=1e-6)]
        if not zoom and others:
            for i, s in enumerate(others):
                e = ellipse_points(cov * (s / major) ** 2, 1.0) / KM
                ax.plot(e[:, 0], e[:, 1], ":", color="0.45", lw=0.8, label=None if i else (
                    "1-sigma at " + ", ".join(f"{x / KM:g}" for x in others) + " km"))
        for k, a in ((3, 0.12), (2, 0.2), (1, 0.32)):
            e = ellipse_points(cov, k) / KM
            ax.fill(e[:, 0], e[:, 1], color="tab:red", alpha=a, lw=0)
            ax.plot(e[:, 0], e[:, 1], color="tab:red", lw=0.8)
        if body_radius_m:
            t = np.linspace(0.0, 2.0 * math.pi, 181)
            ax.plot(body_radius_m / KM * np.cos(t), body_radius_m / KM * np.sin(t),
                    color="k", lw=0.8, label=f"body, mean radius {body_radius_m / KM:.1f} km")
        ax.plot(0, 0, "k+", ms=9, label="predicted target")
        if not zoom:
            ax.plot(sw[:, 0], sw[:, 1], "o", color="tab:blue", ms=7,
                    label=f"swarm members (N = {len(sw)})")
            for i, (x, y) in enumerate(sw):
                ax.annotate(str(i), (x, y), xytext=(4, 4), textcoords="offset points",
                            fontsize=8, color="tab:blue")
        ax.set_aspect("equal")
        ax.set_xlabel("T, km")
        ax.set_ylabel("R, km")
        ax.grid(alpha=0.3)
    lim = 3.6 * major / KM if major > 0 else 1.0
    axes[1].set_xlim(-lim, lim)
    axes[1].set_ylim(-lim, lim)
    axes[0].set_title("B-plane: swarm and the target's 1/2/3-sigma ellipses", fontsize=9)
    axes[1].set_title(f"the ellipses (1-sigma {major / KM:.3g} km major axis)", fontsize=9)
    axes[0].legend(fontsize=7, loc="upper left")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=90)
    close(fig, path)
    return path


def answers_figure(nav, per_target, path, *, p: float) -> Path:
    """Left: the designed swarm's P and the fewest N against the B-plane 1-sigma (``nav``,
    the ``study_navigation`` group, or None). Right: the conditional P of each target world,
    sorted, against ``p`` (``per_target``, the ``study_per_target`` group, or None)."""
    panels = [x for x in (nav, per_target) if x is not None]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.0), squeeze=False)
    axes = list(axes[0])
    if nav is not None:
        ax = axes.pop(0)
        s = nav["bplane_sigma"].values / KM
        ax.semilogx(s, nav["swarm_probability"].values, "o-", color="tab:blue",
                    label="designed swarm's P_bank")
        ax.axhline(p, color="tab:red", ls="--", lw=0.8, label=f"p = {p:g}")
        own = float(nav.attrs["campaign_sigma_m"]) / KM
        ax.axvline(own, color="0.5", ls=":", lw=0.8, label=f"campaign's {own:.3g} km")
        for i, (x, n, y) in enumerate(zip(s, nav["fewest_n"].values,
                                          nav["swarm_probability"].values)):
            # neighbours close in sigma (the campaign's own beside a listed one) alternate
            below = i % 2 == 0 and y > 0.1
            ax.annotate(f"N={n}" if n > 0 else "no N", (x, y), xytext=(0, -14 if below else 8),
                        textcoords="offset points", ha="center", fontsize=8)
        ticks = [x for x in s if not math.isclose(x, own, rel_tol=1e-9)] or list(s)
        ax.set_xticks(ticks, [f"{x:.3g}" for x in ticks])
        ax.minorticks_off()
        ax.set_ylim(-0.05, 1.1)
        ax.set_xlabel("B-plane 1-sigma semi-major axis, km")
        ax.set_ylabel("P(coverage >= threshold)")
        ax.set_title("value of a late navigation update (fewest N annotated)", fontsize=9)
        ax.legend(fontsize=7, loc="lower left")
        ax.grid(alpha=0.3, which="both")
    if per_target is not None:
        ax = axes.pop(0)
        c = np.sort(per_target["conditional_probability"].values)
        se = per_target["conditional_std_error"].values[np.argsort(
            per_target["conditional_probability"].values)]
        x = np.arange(1, c.size + 1)
        ax.errorbar(x, c, yerr=np.nan_to_num(se), fmt="o", ms=4, color="tab:blue", lw=0.8,
                    label="world's conditional P (+- 1 s.e.)")
        ax.axhline(p, color="tab:red", ls="--", lw=0.8, label=f"p = {p:g}")
        a = per_target.attrs
        ax.set_title(f"per-target reliability: {int(a['meeting'])} of {int(a['worlds'])} worlds "
                     f">= p (Wilson 95 % [{float(a['wilson_low']):.2f}, "
                     f"{float(a['wilson_high']):.2f}])", fontsize=9)
        ax.set_xlabel("target world, sorted")
        ax.set_ylabel("conditional P")
        ax.set_ylim(-0.05, 1.05)
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=90)
    close(fig, path)
    return path
