"""Triangle shape models of the target body (SPEC section 1).

The boundary layer for meshes: files are read here (PDS plate ``.tab`` in km,
or anything trimesh reads, with a stated length unit), validated, converted to
metres, oriented outward, and the derived quantities are computed once.
Everything downstream takes the contiguous float64/int64 arrays of
:class:`Shape`.
"""

from __future__ import annotations

import functools
import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.units import KM



@dataclass(frozen=True)
class Shape:
    """A closed, outward-wound triangle mesh in the body frame T (SI units).

    Attributes
    ----------
    name : str
        Short name (``eros001708``, ``sphere``...).
    source : str
        Where it came from: a file path or ``built-in ...``.
    vertices_T : (V, 3) float64
        Vertex positions, m, frame T.
    faces : (F, 3) int64
        Vertex indices, counter-clockwise seen from outside.
    face_normals_T, face_areas : (F, 3), (F,) float64
        Outward unit normals and areas (m^2).
    vertex_normals_T, vertex_areas : (V, 3), (V,) float64
        Area-weighted mean of adjacent face normals (unit), and one third of
        the adjacent face areas (m^2); ``vertex_areas.sum() == area``.
    r_max, r_min, r_av : float
        Largest and smallest vertex radius, and their mean (paper Table 1), m.
    area, volume : float
        Total surface area (m^2) and enclosed volume (m^3).
    """

    name: str
    source: str
    vertices_T: np.ndarray
    faces: np.ndarray
    face_normals_T: np.ndarray = field(repr=False)
    face_areas: np.ndarray = field(repr=False)
    vertex_normals_T: np.ndarray = field(repr=False)
    vertex_areas: np.ndarray = field(repr=False)
    r_max: float = 0.0
    r_min: float = 0.0
    r_av: float = 0.0
    area: float = 0.0
    volume: float = 0.0

    @functools.cached_property
    def mass_properties(self):
        """Constant-density :class:`~ideas_hpc.body.mass_properties.MassProperties` of the
        mesh, computed on first use and kept: the body checks, the default C20/C22 and
        ``ideas-hpc body`` all read this one."""
        from ideas_hpc.body.mass_properties import mass_properties

        return mass_properties(self.vertices_T, self.faces)

    @property
    def n_vertices(self) -> int:
        return int(self.vertices_T.shape[0])

    @property
    def n_faces(self) -> int:
        return int(self.faces.shape[0])

    def summary(self) -> str:
        return (f"{self.name}: {self.n_vertices} vertices, {self.n_faces} faces, "
                f"area {self.area / KM**2:.3f} km^2, R_max {self.r_max / KM:.3f} km, "
                f"R_min {self.r_min / KM:.3f} km, R_av {self.r_av / KM:.3f} km "
                f"[{self.source}]")


#: Digests of face arrays that passed :func:`_edge_check` (bounded). The check reads the
#: topology only, and every world of a target prior shares its nominal's faces: a bank's
#: draws (each built twice, drawn then placed) would otherwise sort the same 3F edges
#: again each time, 75 % of a draw's 11 ms at 1280 faces.
_TOPOLOGIES_PASSED: dict = {}
_TOPOLOGIES_KEPT = 64


def _edge_check(faces: np.ndarray, name: str) -> None:
    """Reject open or non-manifold meshes: every directed edge once, every edge twice."""
    key = (faces.shape, hashlib.blake2b(faces.tobytes(), digest_size=16).digest())
    if key in _TOPOLOGIES_PASSED:
        return
    _edge_rules(faces, name)
    if len(_TOPOLOGIES_PASSED) >= _TOPOLOGIES_KEPT:
        _TOPOLOGIES_PASSED.clear()
    _TOPOLOGIES_PASSED[key] = True


def _edge_rules(faces: np.ndarray, name: str) -> None:
    """The topology rules of :func:`_edge_check`, computed."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    und = np.sort(e, axis=1)
    _, counts = np.unique(und, axis=0, return_counts=True)
    if np.any(counts == 1):
        raise InputError(f"mesh is open: {int(np.sum(counts == 1))} edges belong to one face only "
                         "(a closed surface is required)", field=name)
    if np.any(counts > 2):
        raise InputError(f"mesh is non-manifold: {int(np.sum(counts > 2))} edges shared by more "
                         "than two faces", field=name)
    _, dcounts = np.unique(e, axis=0, return_counts=True)
    if np.any(dcounts > 1):
        raise InputError("mesh faces are not consistently wound (an edge is traversed twice in "
                         "the same direction)", field=name)


def build_shape(vertices_T, faces, *, name: str, source: str) -> Shape:
    """Validate a mesh given in metres and compute the derived quantities.

    Faces that are all wound inward (negative enclosed volume) are flipped.
    Raises :class:`InputError` for NaN coordinates, indices out of range,
    zero-area faces, and open or non-manifold meshes.
    """
    v = np.ascontiguousarray(vertices_T, dtype=np.float64)
    f = np.ascontiguousarray(faces, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] < 4:
        raise InputError(f"vertices must have shape (V>=4, 3), got {v.shape}", field=name)
    if f.ndim != 2 or f.shape[1] != 3 or f.shape[0] < 4:
        raise InputError(f"faces must have shape (F>=4, 3), got {f.shape}", field=name)
    if not np.all(np.isfinite(v)):
        bad = int(np.argmax(~np.isfinite(v).all(axis=1)))
        raise InputError(f"vertex {bad} has a non-finite coordinate", field=name)
    if f.min() < 0 or f.max() >= v.shape[0]:
        bad = int(np.argmax((f < 0).any(axis=1) | (f >= v.shape[0]).any(axis=1)))
        raise InputError(f"face {bad} has a vertex index out of range 0..{v.shape[0] - 1}",
                         field=name)
    _edge_check(f, name)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    cr = np.cross(b - a, c - a)
    dbl = np.linalg.norm(cr, axis=1)
    scale = float(np.max(np.linalg.norm(v, axis=1)))
    tiny = dbl <= 1e-12 * scale * scale
    if np.any(tiny):
        raise InputError(f"face {int(np.argmax(tiny))} has zero area", field=name)
    vol = float(np.sum(np.einsum("ij,ij->i", a, np.cross(b, c)))) / 6.0
    if vol < 0.0:
        # Every face wound inward (consistent winding was checked above): flip all.
        f = np.ascontiguousarray(f[:, [0, 2, 1]])
        cr = -cr
        vol = -vol
    fa = 0.5 * dbl
    fn = cr / dbl[:, None]
    vn = np.zeros_like(v)
    va = np.zeros(v.shape[0])
    for k in range(3):
        np.add.at(vn, f[:, k], fn * fa[:, None])
        np.add.at(va, f[:, k], fa / 3.0)
    nn = np.linalg.norm(vn, axis=1)
    if np.any(nn == 0.0):
        raise InputError(f"vertex {int(np.argmax(nn == 0.0))} belongs to no face", field=name)
    vn /= nn[:, None]
    r = np.linalg.norm(v, axis=1)
    return Shape(name=name, source=source, vertices_T=v, faces=f,
                 face_normals_T=np.ascontiguousarray(fn), face_areas=fa,
                 vertex_normals_T=np.ascontiguousarray(vn), vertex_areas=va,
                 r_max=float(r.max()), r_min=float(r.min()),
                 r_av=0.5 * float(r.max() + r.min()), area=float(fa.sum()), volume=vol)


def read_plate_tab(path) -> Shape:
    """Read a PDS plate model (``v x y z`` rows in km, then ``f i j k`` rows, 0-based).

    Errors name the file and the 1-based line.
    """
    path = Path(path)
    verts: list[tuple[float, float, float]] = []
    faces: list[tuple[int, int, int]] = []
    face_lines: list[int] = []
    with open(path, encoding="ascii", errors="replace") as fh:
        for lineno, raw in enumerate(fh, start=1):
            parts = raw.split()
            if not parts:
                continue
            tag = parts[0].lower()
            if tag not in ("v", "f"):
                raise InputError(f"expected a 'v x y z' or 'f i j k' row, got {raw.strip()[:40]!r}",
                                 file=path, line=lineno)
            if len(parts) != 4:
                raise InputError(f"'{tag}' row needs 3 values, got {len(parts) - 1} "
                                 "(truncated file?)", file=path, line=lineno)
            if tag == "v":
                if faces:
                    raise InputError("vertex row after face rows", file=path, line=lineno)
                try:
                    xyz = tuple(float(p) for p in parts[1:])
                except ValueError:
                    raise InputError(f"vertex coordinates are not numbers: {raw.strip()!r}",
                                     file=path, line=lineno) from None
                if not all(math.isfinite(x) for x in xyz):
                    raise InputError("vertex has a non-finite (NaN/inf) coordinate",
                                     file=path, line=lineno)
                verts.append(xyz)
            else:
                try:
                    ijk = tuple(int(p) for p in parts[1:])
                except ValueError:
                    raise InputError(f"face indices are not integers: {raw.strip()!r}",
                                     file=path, line=lineno) from None
                if min(ijk) < 0 or max(ijk) >= len(verts):
                    raise InputError(f"face index out of range 0..{len(verts) - 1}: {ijk}",
                                     file=path, line=lineno)
                faces.append(ijk)
                face_lines.append(lineno)
    if len(verts) < 4 or len(faces) < 4:
        raise InputError(f"too few rows: {len(verts)} vertices and {len(faces)} faces "
                         "(truncated file?)", file=path)
    v = np.asarray(verts) * KM
    f = np.asarray(faces, dtype=np.int64)
    try:
        return build_shape(v, f, name=path.stem, source=str(path))
    except InputError as exc:
        line = None
        if exc.message.startswith("face "):
            try:
                line = face_lines[int(exc.message.split()[1])]
            except (ValueError, IndexError):
                line = None
        raise InputError(exc.message, file=path, line=line) from None


def read_mesh(path, *, length_unit: str = "km") -> Shape:
    """Read any mesh trimesh reads (OBJ, PLY, STL, OFF...) with lengths in ``length_unit``."""
    import trimesh

    units = {"m": 1.0, "km": KM}
    if length_unit not in units:
        raise InputError(f"unknown length unit {length_unit!r}; use 'm' or 'km'",
                         field="length_unit")
    path = Path(path)
    try:
        mesh = trimesh.load(path, force="mesh", process=True)
    except Exception as exc:  # trimesh raises many types; all mean the file is unreadable
        raise InputError(f"cannot read mesh: {exc}", file=path) from None
    if len(mesh.faces) == 0:
        raise InputError("mesh has no faces", file=path)
    try:
        return build_shape(np.asarray(mesh.vertices) * units[length_unit],
                           np.asarray(mesh.faces), name=path.stem, source=str(path))
    except InputError as exc:
        raise InputError(exc.message, file=path) from None
