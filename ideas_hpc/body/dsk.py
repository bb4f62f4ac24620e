"""DSK type 2 shape models (SPEC section 7e): plates and vertices in km, body-fixed frame.

A DSK type 2 segment holds the same data as a PDS plate ``.tab`` (vertices in km in
the body-fixed frame, plates as 1-based vertex triples, outward by the right-hand
rule), so :func:`read_dsk` gives the :class:`~ideas_hpc.body.shape.Shape` that the
``.tab`` of the same model gives, array for array (``formats.load_shape_file``). :func:`write_dsk` writes one
segment with its spatial index (``dskmi2``), as NAIF's ``mkdsk`` does, for the
export and the tests. Both need spiceypy (imported on use).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.spice import spiceypy
from ideas_hpc.base.units import KM



def read_dsk(path, *, field: str = "body.shape"):
    """``(vertices_T_m, faces)`` of the single type 2 segment of a DSK file: vertices
    converted from km to m, plates to 0-based indices (``formats.load_shape_file`` builds
    the :class:`~ideas_hpc.body.shape.Shape`)."""
    sp = spiceypy(field)
    path = Path(path)
    try:
        handle = sp.dasopr(str(path))
    except sp.utils.exceptions.SpiceyError as exc:
        raise InputError(f"cannot open as a DSK: {exc.short or exc}", file=path) from None
    try:
        with sp.no_found_check():        # spiceypy >= 3 raises on not-found otherwise
            dladsc, found = sp.dlabfs(handle)
            if not found:
                raise InputError("DSK has no segment", file=path)
            _, more = sp.dlafns(handle, dladsc)
        if more:
            raise InputError("DSK has several segments; give a file with one type 2 segment "
                             "(one shape of one body)", file=path)
        dskdsc = sp.dskgd(handle, dladsc)
        if dskdsc.dtype != 2:
            raise InputError(f"DSK segment is of type {dskdsc.dtype}; only type 2 (plates) is "
                             "read", file=path)
        nv, np_ = sp.dskz02(handle, dladsc)
        verts_km = np.asarray(sp.dskv02(handle, dladsc, 1, nv), dtype=np.float64)
        plates = np.asarray(sp.dskp02(handle, dladsc, 1, np_), dtype=np.int64) - 1
    finally:
        sp.dascls(handle)
    return verts_km * KM, plates


def write_dsk(path, vertices_km, plates, *, body_id: int, frame: str, surface_id: int = 1,
              first_et: float = -1e10, last_et: float = 1e10) -> None:
    """Write one DSK type 2 segment (latitudinal coordinates, vertices in km, plates 0-based).

    ``body_id`` is the NAIF ID of the centre, ``frame`` the body-fixed frame name;
    ``first_et``/``last_et`` the time coverage (TDB seconds past J2000).
    """
    sp = spiceypy("export")
    v = np.ascontiguousarray(vertices_km, dtype=np.float64)
    p = np.ascontiguousarray(np.asarray(plates, dtype=np.int64) + 1, dtype=np.int32)
    # Spatial index sizes: the bounds of NAIF's DSK examples (dskw02, mkdsk) for
    # meshes up to a few 1e5 plates; the fine voxels hold about a plate each.
    finscl, corscl = 5.0, 4
    worksz = max(100_000, 40 * len(p))
    voxpsz, voxlsz = max(100_000, 20 * len(p)), max(100_000, 40 * len(p))
    spxisz = 2_000_000 + 400 * len(p)
    spaixd, spaixi = sp.dskmi2(v, p, finscl, corscl, worksz, voxpsz, voxlsz, True, spxisz)
    r = np.linalg.norm(v, axis=1)
    corpar = np.zeros(10)
    path = Path(path)
    if path.exists():
        path.unlink()
    handle = sp.dskopn(str(path), "ideas_hpc shape", 0)
    try:
        sp.dskw02(handle, body_id, surface_id, 1, frame, 1, corpar, -math.pi, math.pi,
                  -0.5 * math.pi, 0.5 * math.pi, float(r.min()), float(r.max()),
                  first_et, last_et, v, p, spaixd, spaixi)
    finally:
        sp.dskcls(handle, True)
