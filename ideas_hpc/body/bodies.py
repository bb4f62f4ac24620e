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
    A shape file of a registered format (:data:`ideas_hpc.body.formats.FORMATS`: PDS
    ``.tab``, DSK, or any mesh trimesh reads, lengths in km unless ``length_unit``).

The names are the entries of :data:`ideas_hpc.body.formats.BUILTIN_BODIES`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from ideas_hpc.base.errors import InputError
from ideas_hpc.body.formats import (builtin_body, builtin_names, family_of, formats_text,
                                    load_shape_file, real_eros_names)
from ideas_hpc.body.params import PhysicalParams, get_params
from ideas_hpc.body.shape import Shape

#: The real NASA PDS Eros models, and every built-in name (from the registry,
#: :mod:`ideas_hpc.body.formats`).
REAL_EROS = real_eros_names()
BUILTIN = builtin_names()


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
        return self.shape.name in real_eros_names()

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
    if isinstance(params, str):
        params = get_params(params)
    known = builtin_body(key)
    if known is not None:
        low, entry = known
        shape, p, note = entry.load(data_path, resolution, params)
        return Body(low, shape, p, note)
    path = Path(key).expanduser()
    if path.is_dir():
        raise InputError(f"{key!r} is a directory, not a shape file ({formats_text()})",
                         field="body")
    if path.suffix and (path.is_file() or "/" in key or "\\" in key):
        shape = load_shape_file(path, length_unit=length_unit)
        family = family_of(shape.name)
        if params is None and family is not None:
            params = get_params(family.name)
        return Body(shape.name, shape, params, f"shape file {path}")
    raise InputError(f"unknown body {key!r}; known names: {', '.join(builtin_names())}, or a "
                     f"path to a {formats_text()} file", field="body")
