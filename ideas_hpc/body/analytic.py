"""Built-in analytic bodies: sphere and triaxial ellipsoid meshes.

They let everything run with no data files. The mesh is a geodesic icosphere
(trimesh) with ``resolution`` subdivisions (``20 * 4**resolution`` faces),
scaled to the semi-axes. Lengths are in m.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.body.shape import Shape, build_shape

#: Eros-sized stand-in used when the real shape model is not on the data path:
#: semi-axes close to Eros' 34.4 x 11.2 x 11.2 km bounding box (Yeomans et al.
#: 2000), which gives R_av near Table 1's 10.4 km.
EROS_ELLIPSOID_AXES_M = (17.0e3, 5.6e3, 5.4e3)


def _check_resolution(resolution) -> int:
    if isinstance(resolution, bool) or not isinstance(resolution, (int, np.integer)):
        raise InputError(f"must be a whole number, got {resolution!r}", field="resolution")
    if resolution <= 0:
        raise InputError(f"must be >= 1 (icosphere subdivisions), got {resolution}",
                         field="resolution")
    if resolution > 7:
        raise InputError(f"must be <= 7 (7 gives 327,680 faces), got {resolution}",
                         field="resolution")
    return int(resolution)


def ellipsoid_mesh(a: float, b: float, c: float, resolution: int = 3, *,
                   name: str = "ellipsoid") -> Shape:
    """Triaxial ellipsoid with semi-axes ``a, b, c`` (m) along x, y, z of frame T."""
    a = number(a, "a", lo=0.0, lo_open=True)
    b = number(b, "b", lo=0.0, lo_open=True)
    c = number(c, "c", lo=0.0, lo_open=True)
    res = _check_resolution(resolution)
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=res, radius=1.0)
    v = np.asarray(ico.vertices) * np.array([a, b, c])
    src = f"built-in ellipsoid {a / 1e3:g} x {b / 1e3:g} x {c / 1e3:g} km, resolution {res}"
    return build_shape(v, np.asarray(ico.faces), name=name, source=src)


def sphere_mesh(radius: float, resolution: int = 3, *, name: str = "sphere") -> Shape:
    """Sphere of ``radius`` (m) as a geodesic icosphere with vertices on the sphere."""
    r = number(radius, "radius", lo=0.0, lo_open=True)
    shape = ellipsoid_mesh(r, r, r, resolution, name=name)
    object.__setattr__(shape, "source", f"built-in sphere R = {r / 1e3:g} km, "
                                        f"resolution {resolution}")
    return shape


def eros_ellipsoid(resolution: int = 3) -> Shape:
    """The built-in Eros-sized ellipsoid (see :data:`EROS_ELLIPSOID_AXES_M`)."""
    return ellipsoid_mesh(*EROS_ELLIPSOID_AXES_M, resolution, name="eros-ellipsoid")
