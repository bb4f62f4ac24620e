"""Where a body's shape comes from: one registry of shape-file formats and one of built-in
bodies (issue 40). :func:`load_shape_file` and
:func:`~ideas_hpc.body.bodies.load_body` dispatch through them, and every message or page
that lists the formats reads :func:`formats_text`, so a new format is one
:class:`ShapeFormat` entry (its reader plus its unit and frame rules), a new built-in one
:class:`BuiltinBody` entry; ``tests/test_recipes.py`` registers a toy format of each from
the test module alone.

Formats (all in the body-fixed frame T of SPEC section 1: origin at the centre of mass,
+z the spin pole, +x the prime meridian; the file's own axes are taken as T):

``tab``
    PDS plate model (``v x y z`` rows in km, ``f i j k`` rows 0-based; SPEC section 1).
    Always km.
``dsk``
    SPICE DSK type 2 (``.bds``, ``.dsk``): plates and vertices in km in the body-fixed
    frame of the segment (SPEC section 7e). Always km; needs spiceypy (the ``spice``
    extra), imported on use.
``mesh``
    Anything trimesh reads (``.obj``, ``.ply``, ``.stl``, ``.off``), lengths in
    ``body.length_unit`` (km by default, or m): these files carry no unit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from ideas_hpc.base.errors import InputError
from ideas_hpc.body import analytic
from ideas_hpc.body.datapath import candidates, find_data_file, have_data_file
from ideas_hpc.body.params import get_params
from ideas_hpc.body.shape import Shape, build_shape, read_mesh, read_plate_tab


@dataclass(frozen=True)
class ShapeFormat:
    """A shape-file format.

    ``read(path, length_unit) -> Shape`` (metres, frame T). ``length_unit`` says how the
    file's lengths are read: ``"km"`` (fixed by the format, ``body.length_unit`` ignored
    and refused when set otherwise) or ``"config"`` (``body.length_unit``). ``frame`` says
    how its axes relate to T, in words.
    """

    name: str
    suffixes: tuple[str, ...]
    read: Callable
    length_unit: str
    frame: str
    doc: str

    def __post_init__(self):
        if self.length_unit not in ("km", "config"):
            raise ValueError(f"format {self.name!r}: length_unit must be 'km' or 'config'")
        if not self.suffixes or any(not s.startswith(".") or s != s.lower()
                                    for s in self.suffixes):
            raise ValueError(f"format {self.name!r}: suffixes are lower-case '.ext' strings")


@dataclass(frozen=True)
class BuiltinBody:
    """A body known by name: ``load(data_path, resolution, params) -> (shape, params, note)``.

    ``params`` is what the caller gave (``None``: the body's own); ``real_eros``: the shape
    is a real NASA PDS Eros model (``Body.is_real_eros``).
    """

    name: str
    load: Callable
    doc: str
    aliases: tuple[str, ...] = ()
    real_eros: bool = False
    #: The body's NAIF ID (``ideas-hpc export``), None when it has none.
    naif_id: int | None = None
    #: A shape file whose name begins with this (``eros_custom.obj``) takes this body's
    #: physical parameters and NAIF ID by default (None: no such family).
    family: str | None = None


def _read_tab(path, length_unit):
    return read_plate_tab(path)


def _read_dsk(path, length_unit):
    from ideas_hpc.body.dsk import read_dsk     # spiceypy itself only on use

    v, f = read_dsk(path)
    try:
        return build_shape(v, f, name=Path(path).stem, source=str(path))
    except InputError as exc:
        raise InputError(exc.message, file=path) from None


def _read_mesh(path, length_unit):
    return read_mesh(path, length_unit=length_unit)


FORMATS: dict[str, ShapeFormat] = {f.name: f for f in (
    ShapeFormat("tab", (".tab",), _read_tab, "km", "T",
                "PDS plate model (v/f rows, km)"),
    ShapeFormat("dsk", (".bds", ".dsk"), _read_dsk, "km", "the segment's body-fixed frame",
                "SPICE DSK type 2 (km; needs spiceypy)"),
    ShapeFormat("mesh", (".obj", ".ply", ".stl", ".off"), _read_mesh, "config", "T",
                "any mesh trimesh reads (km, or m with body.length_unit)"),
)}


def format_of(path) -> ShapeFormat | None:
    """The registered format of ``path`` by its suffix (case-insensitive), or None."""
    suffix = Path(path).suffix.lower()
    for f in FORMATS.values():
        if suffix in f.suffixes:
            return f
    return None


def suffixes() -> tuple[str, ...]:
    """Every registered suffix, in registry order (read live)."""
    return tuple(s for f in FORMATS.values() for s in f.suffixes)


def formats_text() -> str:
    """The suffixes for messages: ``".tab/.bds/.dsk/.obj/.ply/.stl/.off"`` (read live)."""
    return "/".join(suffixes())


def load_shape_file(path, *, length_unit: str = "km") -> Shape:
    """The :class:`~ideas_hpc.body.shape.Shape` of a shape file, read by its registered
    format (:data:`FORMATS`, by suffix). A file of no registered suffix goes to trimesh
    (which knows more formats than the registry lists), with ``length_unit`` as given.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such shape file", file=path)
    fmt = format_of(path)
    if fmt is None:
        return _read_mesh(path, length_unit)
    return fmt.read(path, length_unit if fmt.length_unit == "config" else "km")


def length_unit_applies(path) -> bool:
    """Does ``body.length_unit`` change how ``path`` is read? (False: the format fixes km.)"""
    fmt = format_of(path)
    return fmt is None or fmt.length_unit == "config"


# --- built-in bodies ---------------------------------------------------------------------

REAL_EROS = ("eros001708", "eros007790", "eros010152", "eros022540")
#: 433 Eros (NAIF: asteroids are 2000000 + their number).
EROS_NAIF_ID = 2000433


def _eros(data_path, resolution, params):
    if have_data_file("eros001708.tab", data_path):
        shape = load_shape_file(find_data_file("eros001708.tab", data_path))
        note = f"real NASA PDS shape model eros001708 ({shape.source})"
    else:
        shape = analytic.eros_ellipsoid(resolution)
        looked = ", ".join(str(p) for p in candidates("eros001708.tab", data_path)) or \
            "no data path (IDEAS_HPC_DATA unset)"
        note = (f"built-in Eros-sized ellipsoid (eros001708.tab not found; looked in: "
                f"{looked})")
    return shape, params or get_params("eros"), note


def _real_eros(name):
    def load(data_path, resolution, params):
        shape = load_shape_file(find_data_file(name + ".tab", data_path))
        return (shape, params or get_params("eros"),
                f"real NASA PDS shape model {name} ({shape.source})")
    return load


def _ellipsoid(data_path, resolution, params):
    shape = analytic.eros_ellipsoid(resolution)
    return shape, params or get_params("eros"), shape.source


def _sphere(data_path, resolution, params):
    shape = analytic.sphere_mesh(10.4e3, resolution)
    p = params or replace(get_params("eros"), name="sphere", c20=0.0, c22=0.0)
    return shape, p, shape.source


BUILTIN_BODIES: dict[str, BuiltinBody] = {b.name: b for b in (
    BuiltinBody("eros", _eros, "the real NASA PDS model eros001708.tab when the data path "
                "has it, otherwise the built-in Eros-sized ellipsoid", naif_id=EROS_NAIF_ID,
                family="eros"),
    BuiltinBody("eros-ellipsoid", _ellipsoid, "the built-in Eros-sized ellipsoid with Eros' "
                "Table 1 parameters", aliases=("ellipsoid",)),
    BuiltinBody("sphere", _sphere, "a sphere of Eros' mean radius (10.4 km) with Eros' mass "
                "and no C20/C22"),
    *(BuiltinBody(n, _real_eros(n), f"the real plate model {n}.tab (data path)",
                  real_eros=True) for n in REAL_EROS),
)}


def builtin_body(name: str) -> tuple[str, BuiltinBody] | None:
    """``(name as given, lower case; entry)`` of a built-in body or alias, or None."""
    low = str(name).lower()
    for b in BUILTIN_BODIES.values():
        if low == b.name or low in b.aliases:
            return low, b
    return None


def builtin_names() -> tuple[str, ...]:
    """Every built-in name and alias (read live)."""
    return tuple(n for b in BUILTIN_BODIES.values() for n in (b.name, *b.aliases))


def real_eros_names() -> tuple[str, ...]:
    """The names whose shape is a real NASA PDS Eros model (read live)."""
    return tuple(b.name for b in BUILTIN_BODIES.values() if b.real_eros)


def family_of(name) -> BuiltinBody | None:
    """The built-in body whose ``family`` the name begins with (case-insensitive), or None:
    a mesh file ``eros_custom.obj`` is an Eros model, and takes Eros' parameters and NAIF
    ID unless given others."""
    low = str(name).lower()
    for b in BUILTIN_BODIES.values():
        if b.family is not None and low.startswith(b.family):
            return b
    return None
