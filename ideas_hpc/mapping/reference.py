"""The reference area a coverage is a fraction of (issue 42, SPEC 7f "Visual mapping").

A coverage is ``sum(w_v [v mapped]) / sum(w_v)`` with per-vertex weights ``w_v``. The
requirement's ``reference`` (:data:`ideas_hpc.mapping.requirement.REFERENCES`) says which
weights:

* ``"surface"``: the vertex areas ``a_v`` (the paper's geometric, thermal map of the
  whole surface);
* ``"lit_at_tca"``: the area lit at the time of closest approach (TCA),
  ``w_v = a_v [v lit at TCA]`` with

      lit at TCA:  n_v . s > 0  and  n_v . s >= cos(i_max)  (i_max: the requirement's
                   incidence limit, ``[coverage] max_incidence_deg``; none: < 90 deg)
                   and, when the coverage reads the Sun or casts shadows
                   (``occlusion``, ``illumination`` or any requirement), the segment
                   from p_v toward the Sun crosses no face (a cast shadow),

  ``n_v`` the unit vertex normal and ``s`` the unit body -> Sun direction in T at TCA.
  This is the coverage kernels' own lit and incidence test (SPEC 6b;
  :func:`ideas_hpc.core.mapping.observations._lit` and the quality pass's ``c_inc``), so
  a swarm that maps exactly the lit vertices has coverage 1.

On a sphere of radius R the area with incidence <= i_max is the cap of polar angle i_max
around the sub-solar point, ``2 pi R^2 (1 - cos i_max)``: half the sphere for i_max =
90 deg (a convex body casts no shadow); the tests check the weights against it.

:func:`reference_weights` is the one function; a drawn world (issue 42, one world per
scenario) calls it with its own shape and Sun at its TCA.
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.core.mapping.segments import segments_blocked
from ideas_hpc.mapping.coverage import occlusion_structure

__all__ = ["lit_at_tca", "reference_weights", "SHADOW_REACH"]

#: The shadow test's segment runs from each vertex toward the Sun over this many body
#: extents (the largest vertex radius): past the body, so any face between the vertex
#: and the Sun is crossed, and short enough that the ray-box slabs stay well scaled.
SHADOW_REACH = 4.0


def _sun_unit(sun_T) -> np.ndarray:
    s = np.asarray(sun_T, dtype=np.float64).reshape(-1)
    if s.shape != (3,) or not np.all(np.isfinite(s)) or not np.linalg.norm(s) > 0.0:
        raise InputError(f"must be one finite non-zero (3,) direction, got {sun_T!r}",
                         field="sun_T")
    return s / np.linalg.norm(s)


def lit_at_tca(shape, sun_T, max_incidence_rad: float | None = None, *,
               shadows: bool = False) -> np.ndarray:
    """(V,) bool: vertex lit by the Sun ``sun_T`` (T, any length) with incidence
    ``<= max_incidence_rad`` (None: < 90 deg), not in a cast shadow when ``shadows``
    (module docstring)."""
    s = _sun_unit(sun_T)
    n = np.asarray(shape.vertex_normals_T, dtype=np.float64)
    cos_i = n @ s
    lit = cos_i > 0.0
    if max_incidence_rad is not None:
        lit &= cos_i >= math.cos(float(max_incidence_rad))
    if shadows and lit.any():
        p = np.ascontiguousarray(shape.vertices_T, dtype=np.float64)
        reach = SHADOW_REACH * float(np.max(np.linalg.norm(p, axis=1)))
        idx = np.flatnonzero(lit)
        origins = np.ascontiguousarray(p[idx])
        bvh = occlusion_structure(shape)
        blocked = segments_blocked(bvh.node_bounds_m, bvh.node_info, bvh.tri_m, bvh.tri_vid,
                                   origins, np.ascontiguousarray(origins + reach * s),
                                   idx.astype(np.int64))
        lit[idx[blocked]] = False
    return lit


def reference_weights(shape, sun_T_at_tca, requirement) -> np.ndarray:
    """(V,) float64: the vertex weights of ``requirement``'s reference area (m^2, not
    normalised: the designers divide by the sum).

    Parameters
    ----------
    shape : Shape
        The body (vertex areas, unit vertex normals, vertices in T).
    sun_T_at_tca : (3,) array_like or None
        Body -> Sun direction in T at closest approach (read only for ``"lit_at_tca"``).
    requirement : Requirement
        Its ``reference`` picks the weights, its ``limits`` the incidence limit and
        whether shadows are cast (module docstring).
    """
    areas = np.asarray(shape.vertex_areas, dtype=np.float64)
    if requirement.reference == "surface":
        return areas.copy()
    if requirement.reference != "lit_at_tca":
        raise InputError(f"no weights for reference {requirement.reference!r}",
                         field="reference")
    if sun_T_at_tca is None:
        raise InputError("the area lit at closest approach needs the Sun there",
                         field="sun_T")
    lim = requirement.limits
    mask = lit_at_tca(shape, sun_T_at_tca, lim.max_incidence_rad,
                      shadows=bool(lim.occlusion or lim.needs_sun))
    if not mask.any():
        raise InputError("no vertex is lit at closest approach within the incidence "
                         "limit: the reference area is empty", field="reference")
    return np.where(mask, areas, 0.0)
