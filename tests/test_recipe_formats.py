"""The body-format recipe is true (issue 40): a shape-file format is one
:class:`~ideas_hpc.body.formats.ShapeFormat` entry and a built-in body one
:class:`~ideas_hpc.body.formats.BuiltinBody` entry, registered here from the test module
alone; the loaders, the campaign and the messages follow. No suffix or built-in name is
compared outside the registry."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.base.errors import InputError
from ideas_hpc.body import analytic, formats
from ideas_hpc.body.bodies import load_body
from ideas_hpc.body.params import get_params
from ideas_hpc.body.shape import build_shape
from ideas_hpc.campaign.run import run_file

from campaign_copies import fitted

PACKAGE = Path(__file__).resolve().parents[1] / "ideas_hpc"
SHORT = ["flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3", 'attitude.mode="ideal"',
         "swarm.angles_rad=[0.2, 2.4, 4.1]", 'body.params="eros"']
#: the shipped flyby without what an ideal attitude does not read ([controller], its start)
FLYBY = fitted("eros-flyby.toml", SHORT)


def _read_toy(path, length_unit):
    """A toy format: JSON ``{"v": [[x, y, z] km, ...], "f": [[i, j, k], ...]}``."""
    d = json.loads(Path(path).read_text())
    return build_shape(np.asarray(d["v"], dtype=float) * 1e3, np.asarray(d["f"]),
                       name=Path(path).stem, source=str(path))


def _toy_format(monkeypatch):
    toy = formats.ShapeFormat("toyjson", (".toyjson",), _read_toy, "km", "T",
                              "a toy JSON mesh (km)")
    monkeypatch.setitem(formats.FORMATS, toy.name, toy)
    return toy


def _write_both(tmp_path):
    """The built-in ellipsoid as a toy file and as an OBJ (km): two paths to one mesh."""
    shape = analytic.eros_ellipsoid(2)
    v_km, f = shape.vertices_T / 1e3, shape.faces
    toy = tmp_path / "blob.toyjson"
    toy.write_text(json.dumps({"v": v_km.tolist(), "f": f.tolist()}))
    obj = tmp_path / "blob.obj"
    obj.write_text("".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in v_km)
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f))
    return toy, obj


def test_recipe_shape_format(tmp_path, monkeypatch):
    _toy_format(monkeypatch)
    toy, obj = _write_both(tmp_path)
    a, b = load_body(toy, params="eros"), load_body(obj, params="eros")
    np.testing.assert_allclose(a.shape.vertices_T, b.shape.vertices_T, rtol=0, atol=1e-6)
    assert a.shape.area == pytest.approx(b.shape.area, rel=1e-12)
    # end to end through a campaign: the same coverage as the OBJ of the same mesh
    got = [xr.open_zarr(run_file(FLYBY, out=tmp_path / f"{p.suffix[1:]}.zarr",
                                 overrides=SHORT + [f'body.name="{p}"'], workers=0,
                                 progress=False)) for p in (toy, obj)]
    np.testing.assert_array_equal(got[0]["observed"].values, got[1]["observed"].values)
    assert float(got[0]["coverage"]) == float(got[1]["coverage"]) > 0.0
    # the messages list the new format (read live)
    with pytest.raises(InputError, match=r"\.toyjson"):
        load_body(tmp_path, params="eros")


def test_a_format_that_fixes_km_refuses_another_length_unit(tmp_path, monkeypatch):
    _toy_format(monkeypatch)
    toy, obj = _write_both(tmp_path)
    with pytest.raises(InputError, match="body.length_unit"):
        run_file(FLYBY, out=tmp_path / "m.zarr", overrides=SHORT + [
            f'body.name="{toy}"', 'body.length_unit="m"'], workers=0, progress=False)
    with pytest.raises(InputError, match="body.length_unit"):
        run_file(FLYBY, out=tmp_path / "e.zarr", overrides=SHORT + [
            'body.name="ellipsoid"', 'body.length_unit="m"'], workers=0, progress=False)
    assert formats.length_unit_applies(obj) and not formats.length_unit_applies(toy)


def test_recipe_builtin_body(monkeypatch):
    def load(data_path, resolution, params):
        shape = analytic.sphere_mesh(2.5e3, resolution, name="pebble")
        return shape, params or get_params("eros"), "a toy built-in sphere of 2.5 km"

    entry = formats.BuiltinBody("pebble", load, "a toy body", aliases=("stone",))
    monkeypatch.setitem(formats.BUILTIN_BODIES, entry.name, entry)
    for name in ("pebble", "STONE"):
        b = load_body(name, resolution=2)
        assert b.name == name.lower() and b.shape.r_max == pytest.approx(2.5e3, rel=1e-9)
    with pytest.raises(InputError, match="pebble, stone"):
        load_body("no-such-body")


def test_every_registered_format_is_read_by_its_own_reader(tmp_path):
    """Dispatch by suffix, case-insensitive; an unknown suffix goes to trimesh."""
    seen = []
    for f in formats.FORMATS.values():
        for sfx in f.suffixes:
            assert formats.format_of(tmp_path / f"x{sfx.upper()}") is f
            seen.append(sfx)
    assert len(seen) == len(set(seen)), "a suffix registered twice"
    assert formats.format_of(tmp_path / "x.glb") is None


def _literal_strings(node):
    return [c.value for c in ast.walk(node) if isinstance(c, ast.Constant)
            and isinstance(c.value, str)]


def test_no_format_suffix_or_builtin_name_is_compared_outside_the_registry():
    """Formats and built-in bodies declare themselves in ``body/formats.py``; a comparison
    (``==``, ``in``, ``startswith``) with a registered suffix or built-in name elsewhere is
    refused, so a new format or body needs no edit elsewhere."""
    names = set(formats.suffixes()) | set(formats.builtin_names())
    hits = []
    for f in PACKAGE.rglob("*.py"):
        if f.name == "formats.py":
            continue
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if isinstance(node, ast.Compare):
                found = [s for s in _literal_strings(node) if s.lower() in names]
            elif isinstance(node, ast.Call) and getattr(node.func, "attr", "") in (
                    "startswith", "endswith"):
                found = [s for a in node.args for s in _literal_strings(a)
                         if s.lower() in names]
            else:
                continue
            hits += [f"{f.relative_to(PACKAGE)}:{node.lineno} {s!r}" for s in found]
    assert not hits, f"format suffixes or body names compared outside the registry: {hits}"
