"""Does the mesh resolve the coverage requirement? (SPEC 7d, issue 29)

Coverage is a sum of vertex areas ``w_v`` (fractions of the total). A tolerance
``eps_tol`` below the typical ``w_v`` makes ``coverage >= target - eps_tol`` a
statement about single vertices: "miss no reachable vertex", whose swarm size
follows the mesh, not the body. :func:`mesh_resolution` gives the figures and
:func:`eps_tol_warning` the one-line warning the designs print (they still run).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MeshResolution:
    """Vertex-area figures of a mesh, as fractions of the total area."""

    n_vertices: int
    median: float
    smallest: float
    largest: float

    def under(self, eps: float, areas) -> int:
        """How many vertices hold less than ``eps`` of the area."""
        w = np.asarray(areas, dtype=np.float64)
        return int(np.count_nonzero(w / w.sum() < eps))


def mesh_resolution(areas) -> MeshResolution:
    """Median, smallest and largest vertex area fraction of ``areas`` (any unit)."""
    w = np.asarray(areas, dtype=np.float64)
    w = w / w.sum()
    return MeshResolution(int(w.size), float(np.median(w)), float(w.min()), float(w.max()))


def eps_tol_warning(areas, eps_tol: float, field: str = "design.eps_tol_pct") -> str | None:
    """The warning when ``eps_tol`` (fraction) is below the median vertex area fraction;
    None when the mesh resolves it."""
    r = mesh_resolution(areas)
    if not eps_tol < r.median:
        return None
    return (f"warning: {field} = {100 * eps_tol:.3g} % is finer than the mesh resolves: "
            f"the median vertex holds {100 * r.median:.3f} % of the area and the smallest "
            f"{100 * r.smallest:.3f} % ({r.under(eps_tol, areas)} of {r.n_vertices} vertices "
            f"are under {100 * eps_tol:.3g} %), so the requirement reads 'miss no reachable "
            f"vertex' and N follows the mesh; see docs/requirement.md")
