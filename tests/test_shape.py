import math

import numpy as np
import pytest

from ideas_hpc.body.analytic import ellipsoid_mesh, sphere_mesh
from ideas_hpc.base.errors import InputError
from ideas_hpc.body.formats import load_shape_file
from ideas_hpc.body.shape import build_shape, read_plate_tab

KM = 1e3


def test_eros1708_matches_table1(eros1708):
    s = eros1708.shape
    assert (s.n_vertices, s.n_faces) == (856, 1708)
    assert abs(s.area / KM**2 - 1103.45) <= 0.05
    assert round(s.r_max / KM, 3) == 17.648
    assert round(s.r_min / KM, 3) == 3.219
    assert abs(s.r_av / KM - 10.434) < 5e-4
    # Independent: trimesh's own area/volume of the same file must agree.
    import trimesh
    tm = trimesh.Trimesh(s.vertices_T, s.faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    assert math.isclose(tm.area, s.area, rel_tol=1e-12)
    assert math.isclose(tm.volume, s.volume, rel_tol=1e-12)
    # Eros' volume is 2503 +- 25 km^3 (Thomas et al. 2002); the coarse model is within 2 %.
    assert abs(s.volume / KM**3 - 2503) / 2503 < 0.02


def test_vertex_areas_and_normals(eros1708):
    s = eros1708.shape
    assert math.isclose(s.vertex_areas.sum(), s.area, rel_tol=1e-12)
    assert np.allclose(np.linalg.norm(s.vertex_normals_T, axis=1), 1.0)
    # outward: normals point away from the centroid for most vertices of a star-ish body
    out = np.einsum("ij,ij->i", s.vertex_normals_T, s.vertices_T) > 0
    assert out.mean() > 0.9
    assert s.vertices_T.flags.c_contiguous and s.vertices_T.dtype == np.float64


@pytest.mark.parametrize("res", [1, 2, 3, 4, 5])
def test_sphere_converges(res):
    r = 1000.0
    s = sphere_mesh(r, res)
    area_err = abs(s.area - 4 * math.pi * r**2) / (4 * math.pi * r**2)
    vol_err = abs(s.volume - 4 / 3 * math.pi * r**3) / (4 / 3 * math.pi * r**3)
    # Inscribed polyhedron: the error is O(edge^2), so it falls ~4x per subdivision.
    assert area_err < 0.08 / 3.8 ** (res - 1)
    assert vol_err < 0.13 / 3.8 ** (res - 1)
    assert s.area < 4 * math.pi * r**2 and s.volume < 4 / 3 * math.pi * r**3


def test_ellipsoid_volume_converges():
    a, b, c = 3.0, 2.0, 1.0
    exact = 4 / 3 * math.pi * a * b * c
    errs = [abs(ellipsoid_mesh(a, b, c, r).volume - exact) / exact for r in (2, 3, 4)]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 3e-3


def _tetra():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * KM
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return v, f


def test_inward_mesh_is_flipped():
    v, f = _tetra()
    out = build_shape(v, f, name="t", source="t")
    inward = build_shape(v, f[:, [0, 2, 1]], name="t", source="t")
    assert inward.volume > 0
    assert math.isclose(inward.volume, out.volume) and math.isclose(inward.volume, KM**3 / 6)
    assert np.allclose(inward.face_normals_T, out.face_normals_T)


def test_open_mesh_rejected():
    s = sphere_mesh(KM, 1)
    with pytest.raises(InputError, match="open"):
        build_shape(s.vertices_T, s.faces[1:], name="t", source="t")


def test_topology_memo_still_rejects_what_differs():
    """The edge check is remembered per face array (every world of a prior shares its
    nominal's faces): a mesh whose faces passed is accepted again at any vertices, and a
    face array that differs by one face (or by its winding) is checked afresh."""
    s = sphere_mesh(KM, 1)
    build_shape(s.vertices_T, s.faces, name="t", source="t")
    build_shape(1.3 * s.vertices_T, s.faces, name="t", source="t")   # remembered: no error
    for _ in range(2):          # a failed check is never remembered
        with pytest.raises(InputError, match="open"):
            build_shape(s.vertices_T, s.faces[1:], name="t", source="t")
    f = s.faces.copy()
    f[0] = f[0, [0, 2, 1]]      # one face wound the other way
    with pytest.raises(InputError, match="wound"):
        build_shape(s.vertices_T, f, name="t", source="t")


def test_nonmanifold_rejected():
    v, f = _tetra()
    v2 = np.vstack([v, v + 5 * KM])
    f2 = np.vstack([f, f + 4, [[0, 1, 4]], [[1, 0, 5]]])
    with pytest.raises(InputError, match="non-manifold|open"):
        build_shape(v2, f2, name="t", source="t")


def _write_tab(path, v_km, f):
    lines = [f"v {x:.6E} {y:.6E} {z:.6E}" for x, y, z in v_km]
    lines += [f"f {i} {j} {k}" for i, j, k in f]
    path.write_text("\n".join(lines) + "\n")


def test_tab_roundtrip_and_obj(tmp_path):
    s = sphere_mesh(2 * KM, 2)
    p = tmp_path / "ball.tab"
    _write_tab(p, s.vertices_T / KM, s.faces)
    back = read_plate_tab(p)
    assert math.isclose(back.area, s.area, rel_tol=1e-5)
    import trimesh
    obj = tmp_path / "ball.obj"
    trimesh.Trimesh(s.vertices_T / KM, s.faces, process=False).export(obj)
    viaobj = load_shape_file(obj)
    assert math.isclose(viaobj.volume, s.volume, rel_tol=1e-9)


def _err(tmp_path, text):
    p = tmp_path / "bad.tab"
    p.write_text(text)
    with pytest.raises(InputError) as ei:
        read_plate_tab(p)
    return str(ei.value)


def test_bad_tab_files_name_file_and_line(tmp_path):
    s = sphere_mesh(KM, 1)
    good = [f"v {x} {y} {z}" for x, y, z in s.vertices_T / KM] + \
           [f"f {i} {j} {k}" for i, j, k in s.faces]
    nv = len(s.vertices_T)
    # truncated last row
    msg = _err(tmp_path, "\n".join(good[:-1] + ["f 1 2"]) + "\n")
    assert f"bad.tab:{len(good)}" in msg and "truncated" in msg
    # face index out of range
    bad = list(good)
    bad[nv + 3] = f"f 0 1 {nv + 7}"
    msg = _err(tmp_path, "\n".join(bad))
    assert f"bad.tab:{nv + 4}" in msg and "out of range" in msg
    # NaN coordinate
    bad = list(good)
    bad[5] = "v nan 0 0"
    msg = _err(tmp_path, "\n".join(bad))
    assert "bad.tab:6" in msg and "non-finite" in msg
    # zero-area face: collapse a vertex onto a neighbour
    i, j, k = s.faces[0]
    v = s.vertices_T / KM
    v2 = v.copy()
    v2[k] = 0.5 * (v[i] + v[j])
    rows = [f"v {x} {y} {z}" for x, y, z in v2] + [f"f {a} {b} {c}" for a, b, c in s.faces]
    msg = _err(tmp_path, "\n".join(rows))
    assert "zero area" in msg and "bad.tab:" in msg
    # open mesh: drop one face
    msg = _err(tmp_path, "\n".join(good[:-1]))
    assert "open" in msg and "bad.tab" in msg
    # garbage row
    msg = _err(tmp_path, "\n".join(good[:3] + ["hello world"] + good[3:]))
    assert "bad.tab:4" in msg


def test_bad_resolution():
    with pytest.raises(InputError, match="resolution"):
        sphere_mesh(KM, 0)
    with pytest.raises(InputError, match="radius"):
        sphere_mesh(-1.0, 2)
