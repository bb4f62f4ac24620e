"""Figures of the target prior (issue 42): a gallery of world draws, matplotlib Agg."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from ideas_hpc.plots.figures import close  # noqa: E402

#: Direction toward the light in frame T: from the upper left of the default view, so the
#: relief casts shading across the surface the viewer sees.
_LIGHT_T = np.array([-0.55, -0.45, 0.70])


def _shaded(ax, world, lim_km: float, elev: float, azim: float) -> None:
    v = world.shape.vertices_T / 1e3
    f = world.shape.faces
    light = _LIGHT_T / np.linalg.norm(_LIGHT_T)
    # Lambert shading plus an ambient floor, so the unlit side still shows its form
    shade = 0.12 + 0.88 * np.clip(world.shape.face_normals_T @ light, 0.0, 1.0)
    colours = np.column_stack([0.80 * shade, 0.71 * shade, 0.58 * shade, np.ones_like(shade)])
    # edges in the face colour close the hairline gaps antialiasing leaves between faces
    # not clipped to the (square) axes box: the panels are wider than tall, as the bodies
    ax.add_collection3d(Poly3DCollection(v[f], facecolors=colours, edgecolors=colours,
                                         linewidths=0.3, clip_on=False))
    # the spin axis, +z of T (the world's pole in N is in the panel's title)
    ax.plot([0, 0], [0, 0], [-0.5 * lim_km, 0.5 * lim_km], color="0.3", lw=0.8)
    ax.set_xlim(-lim_km, lim_km)
    ax.set_ylim(-lim_km, lim_km)
    ax.set_zlim(-0.5 * lim_km, 0.5 * lim_km)      # flat bodies: half the height, same scale
    ax.set_box_aspect((1, 1, 0.5), zoom=1.7)
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()


def prior_gallery(worlds, path, *, title: str = "", elev: float = 30.0,
                  azim: float = -55.0, notes=None) -> Path:
    """Draw ``worlds`` (:class:`~ideas_hpc.body.target_prior.TargetWorld`) on one scale, four
    per row, each titled with its draw number, volume-equivalent diameter, ecliptic pole
    and spin period (and ``notes[i]``, one more phrase per world, when given); the grey
    line is the spin axis (+z of T). Returns ``path``."""
    worlds = list(worlds)
    n = len(worlds)
    cols = min(4, n)
    rows = math.ceil(n / cols)
    lim = max(float(np.abs(w.shape.vertices_T).max()) for w in worlds) / 1e3 * 0.95
    fig = plt.figure(figsize=(2.6 * cols, (1.8 if notes is None else 2.0) * rows
                              + (0.4 if title else 0.0)))
    for i, w in enumerate(worlds):
        ax = fig.add_subplot(rows, cols, i + 1, projection="3d")
        _shaded(ax, w, lim, elev, azim)
        lon, lat = (math.degrees(a) for a in w.pole_lon_lat_rad)
        mirror = " (mirror)" if w.pole_mirrored else ""
        note = "" if notes is None else f"\n{notes[i]}"
        ax.set_title(f"k = {w.k}: D = {w.diameter_m / 1e3:.1f} km\n"
                     f"pole ({lon:.0f}, {lat:.0f}) deg{mirror}, P = {w.spin_period_s / 3600:.3f} h"
                     f"{note}", fontsize=7, pad=0)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.0, top=0.86 if title else 0.93,
                        wspace=0.0, hspace=0.2)
    path = Path(path)
    fig.savefig(path, dpi=90)
    close(fig, path)
    return path
