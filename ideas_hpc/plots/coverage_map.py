"""Coverage map of the target body: faces coloured by observed or first-seen time (paper Fig. 25).

The body is drawn twice side by side (the given view and the opposite side,
azimuth + 180 deg) with the Agg backend. A face takes the mean of its three
vertex values: for ``kind='observed'`` the fraction of its vertices observed
(blue = observed, red = not), for ``kind='first_seen'`` the mean first-seen
time in s (faces with a never-seen vertex are red), for ``kind='fraction'`` a
per-vertex fraction in 0..1 (e.g. of Monte Carlo samples that saw the vertex),
for ``kind='value'`` any per-vertex quantity (issue 14 quality maps: best
resolution, angles, spacecraft counts; NaN red), labelled by ``label``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ideas_hpc.base.errors import InputError

_KINDS = ("observed", "first_seen", "fraction", "value")



def _never_note(never_v) -> str:
    """What the title says about the red: the never-seen vertices (dots) and faces."""
    k = int(np.count_nonzero(never_v))
    if not k:
        return "every vertex seen"
    return ("red: never seen (1 vertex, marked by a dot)" if k == 1 else
            f"red: never seen ({k} vertices, each marked by a dot)")

def render_coverage_map(shape, values, path, *, kind: str = "observed", title=None,
                        view=(20.0, -60.0), dpi: int = 120, label: str | None = None) -> Path:
    """Write a PNG of ``shape`` coloured by per-vertex ``values``.

    Parameters
    ----------
    shape : ideas_hpc.body.shape.Shape
    values : (V,) array
        bool observed mask (``kind='observed'``) or first-seen times in s with
        NaN for never seen (``kind='first_seen'``).
    path : str or Path
        Output PNG file (parent folders are created).
    kind : {'observed', 'first_seen', 'fraction'}
    title : str, optional
    view : (elev, azim)
        Viewing angles of the left panel, deg; the right panel shows the far side.
    dpi : int
    label : str, optional
        Colour-bar label for ``kind='value'`` or ``kind='fraction'``.

    Returns
    -------
    Path
        The written file.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib import cm, colors
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from ideas_hpc.plots.figures import close

    if kind not in _KINDS:
        raise InputError(f"must be one of {_KINDS}, got {kind!r}", field="kind")
    vals = np.asarray(values)
    nv = shape.vertices_T.shape[0]
    if vals.shape != (nv,):
        raise InputError(f"must have shape ({nv},) (one per vertex), got {vals.shape}",
                         field="values")
    try:
        elev, azim = (float(view[0]), float(view[1]))
    except (TypeError, ValueError, IndexError):
        raise InputError(f"must be (elev, azim) in deg, got {view!r}", field="view") from None
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)

    v_km = shape.vertices_T / 1e3
    tris = v_km[shape.faces]
    grey = np.array([0.78, 0.78, 0.78, 1.0])
    unseen = np.array([0.86, 0.15, 0.1, 1.0])   # never-seen faces stand out (issue 22)
    area = np.asarray(shape.vertex_areas, dtype=np.float64)
    never_v = None   # vertices never seen, marked as red dots (kinds with a "seen")
    if kind == "fraction":
        v01 = np.clip(np.nan_to_num(vals.astype(np.float64), nan=0.0), 0.0, 1.0)
        frac = v01[shape.faces].mean(axis=1)
        cmap = colors.LinearSegmentedColormap.from_list("frac", [grey[:3], (0.12, 0.35, 0.85)])
        norm = colors.Normalize(0.0, 1.0)
        fc = cmap(norm(frac))
        fc[frac == 0.0] = unseen
        label = label or "fraction"
        never_v = v01 == 0.0
        stat = (f"area-weighted mean {100 * float(area @ v01 / area.sum()):.3f} %; "
                + _never_note(never_v))
    elif kind == "observed":
        frac = vals.astype(bool)[shape.faces].mean(axis=1)
        cmap = colors.LinearSegmentedColormap.from_list("obs", [grey[:3], (0.12, 0.35, 0.85)])
        norm = colors.Normalize(0.0, 1.0)
        fc = cmap(norm(frac))
        fc[frac == 0.0] = unseen
        label = "observed fraction of face vertices"
        obs = vals.astype(bool)
        never_v = ~obs
        stat = (f"seen: {100 * float(area[obs].sum() / area.sum()):.3f} % of the area "
                f"({int(obs.sum())}/{nv} vertices); " + _never_note(never_v))
    elif kind == "value":
        x = vals.astype(np.float64)
        fin = np.isfinite(x)
        t = x[shape.faces]
        never = ~np.isfinite(t).all(axis=1)
        tm = np.where(never, 0.0, np.where(np.isfinite(t), t, 0.0).mean(axis=1))
        lo, hi = (float(np.percentile(x[fin], 2)), float(np.percentile(x[fin], 98))) \
            if fin.any() else (0.0, 1.0)
        if hi <= lo:
            hi = lo + 1.0
        cmap = cm.viridis
        norm = colors.Normalize(lo, hi)
        fc = cmap(norm(tm))
        fc[never] = unseen
        label = label or "value"
        stat = (f"median {float(np.median(x[fin])):.3g} over {int(fin.sum())}/{nv} vertices"
                if fin.any() else "no finite values")
    else:
        t = vals.astype(np.float64)[shape.faces]
        never = ~np.isfinite(t).all(axis=1)
        tm = np.where(never, 0.0, np.where(np.isfinite(t), t, 0.0).mean(axis=1))
        finite = vals[np.isfinite(vals)]
        lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        if hi <= lo:
            hi = lo + 1.0
        cmap = cm.viridis
        norm = colors.Normalize(lo, hi)
        fc = cmap(norm(tm))
        fc[never] = unseen
        label = "first seen, s"
        seen = np.isfinite(vals)
        never_v = ~seen
        stat = (f"seen: {100 * float(area[seen].sum() / area.sum()):.3f} % of the area; "
                + _never_note(never_v))
    # Simple Lambert shading so the shape reads in 3-D.
    light = np.array([0.4, -0.5, 0.77])
    light /= np.linalg.norm(light)
    shade = 0.55 + 0.45 * np.clip(shape.face_normals_T @ light, 0.0, 1.0)
    fc = fc.copy()
    fc[:, :3] *= shade[:, None]

    fig = plt.figure(figsize=(12, 5.0))
    lo3 = v_km.min(axis=0)
    hi3 = v_km.max(axis=0)
    for p, az in enumerate((azim, azim + 180.0)):
        ax = fig.add_subplot(1, 2, p + 1, projection="3d")
        coll = Poly3DCollection(tris, facecolors=fc, edgecolors=(0, 0, 0, 0.08),
                                linewidths=0.2)
        ax.add_collection3d(coll)
        for k, setl in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
            setl(lo3[k], hi3[k])
        ax.set_box_aspect(tuple(hi3 - lo3), zoom=0.95)
        ax.view_init(elev=elev, azim=az)
        ax.set_xlabel("x, km")
        ax.set_ylabel("y, km")
        ax.set_zlabel("z, km")
        ax.set_title(f"view azimuth {az % 360:.0f} deg", fontsize=9)
        if never_v is not None and never_v.any():
            # A few unseen vertices colour no whole face: mark each one, so the red the
            # title names is always on the figure.
            pts = v_km[never_v]
            ax.computed_zorder = False   # the dots over the surface, not sorted under it
            ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], color=unseen[:3], s=22,
                       depthshade=False, edgecolors="k", linewidths=0.4, zorder=10)
    sm = cm.ScalarMappable(norm=norm, cmap=cmap)
    two_lines = bool(title)   # the title, then the statistic: room for both lines
    fig.subplots_adjust(left=0.0, right=0.9, bottom=0.02, top=0.84 if two_lines else 0.9,
                        wspace=0.08)
    cax = fig.add_axes((0.93, 0.2, 0.012, 0.6))
    fig.colorbar(sm, cax=cax, label=label)
    fig.suptitle((title + f" ({shape.name})\n" if title else f"{shape.name}: ") + stat)
    fig.savefig(path, dpi=dpi)
    close(fig, path)
    return path
