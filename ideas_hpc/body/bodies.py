"""``load_body``: a target body = shape model + physical parameters.

Names understood by :func:`load_body`:

``eros``
    The real NASA PDS model ``eros001708.tab`` when the data path has it,
    otherwise the built-in Eros-sized ellipsoid. ``Body.source`` says which.
``eros001708``, ``eros007790``, ``eros010152``, ``eros022540``
    The real plate models; an error lists where it looked when absent.
``eros-ellipsoid``, ``ellipsoid``
    The built-in Eros-sized ellipsoid, with Eros' Table 1 parameters.
``sphere``
    A sphere of Eros' mean radius (10.4 km) with Eros' mass and no C20/C22.
a path
    A ``.tab`` plate model or any mesh trimesh reads (lengths in km).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from ideas_hpc.body import analytic
from ideas_hpc.body.datapath import candidates, find_data_file, have_data_file
from ideas_hpc.base.errors import InputError
from ideas_hpc.body.params import PhysicalParams, get_params
from ideas_hpc.body.shape import Shape, load_shape_file

REAL_EROS = ("eros001708", "eros007790", "eros010152", "eros022540")
BUILTIN = ("eros", "eros-ellipsoid", "ellipsoid", "sphere") + REAL_EROS


@dataclass(frozen=True)
class Body:
    """A target body.

    Attributes
    ----------
    name : str
    shape : Shape
        Closed mesh in frame T, metres.
    params : PhysicalParams or None
        Gravity, spin and orbit; None for a bare mesh file (then anything
        that needs them raises an error naming ``body.params``).
    note : str
        One line saying what was loaded and, for a fallback, why.
    """

    name: str
    shape: Shape
    params: PhysicalParams | None
    note: str

    @property
    def is_real_eros(self) -> bool:
        return self.shape.name in REAL_EROS

    def require_params(self) -> PhysicalParams:
        if self.params is None:
            raise InputError(f"body {self.name!r} has no physical parameters; set body.params "
                             "to a preset name or a table", field="body.params")
        return self.params


def load_body(name_or_path, *, data_path=None, resolution: int = 3,
              params: PhysicalParams | str | None = None, length_unit: str = "km") -> Body:
    """Load a body by name or file path (see the module docstring).

    Parameters
    ----------
    name_or_path : str or path-like
    data_path : path-like, optional
        Searched before ``IDEAS_HPC_DATA``.
    resolution : int
        Icosphere subdivisions of the built-in analytic bodies.
    params : PhysicalParams or str, optional
        Overrides the default parameter set (a preset name or an object).
    length_unit : {'km', 'm'}
        Length unit of a mesh file read by trimesh (``.tab`` files are km).
    """
    key = str(name_or_path)
    low = key.lower()
    if isinstance(params, str):
        params = get_params(params)
    if low == "eros":
        if have_data_file("eros001708.tab", data_path):
            shape = load_shape_file(find_data_file("eros001708.tab", data_path))
            note = f"real NASA PDS shape model eros001708 ({shape.source})"
        else:
            shape = analytic.eros_ellipsoid(resolution)
            looked = ", ".join(str(p) for p in candidates("eros001708.tab", data_path)) or \
                "no data path (IDEAS_HPC_DATA unset)"
            note = (f"built-in Eros-sized ellipsoid (eros001708.tab not found; looked in: "
                    f"{looked})")
        return Body("eros", shape, params or get_params("eros"), note)
    if low in REAL_EROS:
        shape = load_shape_file(find_data_file(low + ".tab", data_path))
        return Body(low, shape, params or get_params("eros"),
                    f"real NASA PDS shape model {low} ({shape.source})")
    if low in ("eros-ellipsoid", "ellipsoid"):
        shape = analytic.eros_ellipsoid(resolution)
        return Body(low, shape, params or get_params("eros"), shape.source)
    if low == "sphere":
        eros = get_params("eros")
        shape = analytic.sphere_mesh(10.4e3, resolution)
        p = params or dataclasses.replace(eros, name="sphere", c20=0.0, c22=0.0)
        return Body("sphere", shape, p, shape.source)
    path = Path(key).expanduser()
    if path.is_dir():
        raise InputError(f"{key!r} is a directory, not a shape file (.tab/.obj/.ply/.stl/.off)",
                         field="body")
    if path.suffix and (path.is_file() or "/" in key or "\\" in key):
        shape = load_shape_file(path, length_unit=length_unit)
        if params is None and shape.name.lower().startswith("eros"):
            params = get_params("eros")
        return Body(shape.name, shape, params, f"shape file {path}")
    raise InputError(f"unknown body {key!r}; known names: {', '.join(BUILTIN)}, or a path to a "
                     ".tab/.obj/.ply/.stl/.off file", field="body")
