"""A custom body without guesswork (issue 32, deliverable 4).

Mass properties against closed forms (a box is a polyhedron, so its integrals are
exact), and the five cases of the issue, each refused (exit 2, one line naming
the key) or warned (one stderr line naming the key), on the example contact
binary that ``campaigns/custom-body/make_contact_binary.py`` generates.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.body.mass_properties import implied_density, mass_properties
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.base.constants import G
from ideas_hpc.base.errors import InputError

ROOT = Path(__file__).resolve().parent.parent
MASS_KG = 4.5e10


def _maker():
    spec = importlib.util.spec_from_file_location(
        "make_contact_binary", ROOT / "campaigns" / "custom-body" / "make_contact_binary.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def binary_km():
    return _maker().contact_binary(2)


def _write_obj(path, v, f):
    _maker().write_obj(path, v, f)
    return path


def _campaign(tmp_path, obj, kind="flyby", extra="", sets=()):
    from ideas_hpc.campaign.schema.kinds import KINDS

    toml = tmp_path / "c.toml"
    # the angles only for a kind that flies given angles (a design refuses them)
    angles = "" if KINDS[kind].swarm == "designed" else "angles_rad = [0.5, 2.5, 4.5]"
    toml.write_text(f"""kind = "{kind}"
[body]
name = "{obj}"
[body.params]
mass_kg = {MASS_KG}
spin_period_h = 4.0
a_au = 1.1
e = 0.2
[swarm]
{angles}
[attitude]
mode = "ideal"
{extra}
""")
    return load(toml, list(sets))


def _box(a, b, c, shift=(0.0, 0.0, 0.0)):
    import trimesh

    m = trimesh.creation.box(extents=(2 * a, 2 * b, 2 * c))
    return np.asarray(m.vertices) + np.asarray(shift), np.asarray(m.faces)


def test_box_integrals_are_exact():
    """Box of half-sides a, b, c: V = 8abc, S_xx = a^2/3, so C20 R^2 = (c^2 - (a^2+b^2)/2)/3,
    C22 R^2 = (a^2 - b^2)/12; the centroid follows a shift."""
    a, b, c = 300.0, 170.0, 110.0
    p = mass_properties(*_box(a, b, c, shift=(40.0, -25.0, 7.0)))
    assert p.volume_m3 == pytest.approx(8 * a * b * c, rel=1e-13)
    np.testing.assert_allclose(p.com_T_m, [40.0, -25.0, 7.0], atol=1e-9)
    np.testing.assert_allclose(np.diag(p.second_moments_T_m2), [a * a / 3, b * b / 3, c * c / 3],
                               rtol=1e-12)
    assert p.c20_m2 == pytest.approx((c * c - 0.5 * (a * a + b * b)) / 3, rel=1e-12)
    assert p.c22_m2 == pytest.approx((a * a - b * b) / 12, rel=1e-12)
    np.testing.assert_allclose(np.abs(p.principal_T), np.eye(3), atol=1e-12)


def test_rotated_box_principal_axes():
    """A box turned 30 deg about z: the principal axes are the turned box axes."""
    a, b, c = 300.0, 170.0, 110.0
    v, f = _box(a, b, c)
    t = np.radians(30.0)
    rot = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    p = mass_properties(v @ rot.T, f)
    assert abs(p.principal_T[:, 0] @ rot[:, 0]) == pytest.approx(1.0, abs=1e-12)
    assert p.axes_tilt_rad == pytest.approx(t, abs=1e-12)


def test_eros_constant_density_matches_table1(eros1708):
    """Table 1's C20 = -30.010 km^2 and C22 = 14.382 km^2 are close to the constant-density
    values of the eros001708 shape (Miller et al. 2002 find Eros nearly homogeneous)."""
    p = mass_properties(eros1708.shape.vertices_T, eros1708.shape.faces)
    assert p.c20_m2 / 1e6 == pytest.approx(-30.010, rel=0.01)
    assert p.c22_m2 / 1e6 == pytest.approx(14.382, rel=0.06)
    assert implied_density(eros1708.params.mu, p.volume_m3) == pytest.approx(2670, rel=0.02)


def test_example_campaign_uses_the_constant_density_degree2(tmp_path, binary_km):
    obj = _write_obj(tmp_path / "cb.obj", *binary_km)
    c = _campaign(tmp_path, obj)
    s = setup_from_campaign(c)
    p = mass_properties(binary_km[0] * 1e3, binary_km[1])
    # the OBJ keeps 9 decimals of km (1 um): the file's values agree to 1e-7
    assert s.body.params.c20 == pytest.approx(p.c20_m2, rel=1e-7)
    assert s.body.params.c22 == pytest.approx(p.c22_m2, rel=1e-7)
    assert p.c20_m2 < 0 < p.c22_m2          # elongated along x, axisymmetric about it
    assert p.c22_m2 == pytest.approx(-0.5 * p.c20_m2, rel=0.02)
    given = _campaign(tmp_path, obj, sets=["body.params.c20_km2=-0.001"])
    assert setup_from_campaign(given).body.params.c20 == pytest.approx(-1e3, rel=1e-12)
    density = MASS_KG / p.volume_m3
    assert 1000 < density < 3000


def test_mass_properties_are_computed_once_per_custom_body(tmp_path, binary_km, monkeypatch):
    """The default C20/C22 and the body checks read one computation of the mesh's mass
    properties (a 0.5 M-plate mesh pays its volume integrals once)."""
    import ideas_hpc.body.mass_properties as mp

    calls = []
    real = mp.mass_properties
    monkeypatch.setattr(mp, "mass_properties", lambda v, f: calls.append(1) or real(v, f))
    s = setup_from_campaign(_campaign(tmp_path, _write_obj(tmp_path / "cb.obj", *binary_km)))
    assert len(calls) == 1
    assert s.body.params.c20 == s.body.shape.mass_properties.c20_m2


def test_case1_mesh_in_metres_is_refused(tmp_path, binary_km, capsys):
    v, f = binary_km
    obj = _write_obj(tmp_path / "cb_m.obj", v * 1e3, f)    # metres, read as km
    with pytest.raises(InputError) as ei:
        setup_from_campaign(_campaign(tmp_path, obj))
    assert ei.value.field == "body.length_unit" and "density" in ei.value.message
    ok = setup_from_campaign(_campaign(tmp_path, obj, sets=['body.length_unit="m"']))
    assert ok.body.shape.r_max == pytest.approx(np.linalg.norm(v, axis=1).max() * 1e3)
    r = subprocess.run([sys.executable, "-m", "ideas_hpc.cli", "body", str(obj), "--mass-kg",
                        str(MASS_KG)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "--length-unit" in r.stderr and "Traceback" not in r.stderr


def test_case2_origin_outside_the_body_is_refused(tmp_path, binary_km):
    v, f = binary_km
    shifted = v + np.array([0.25 + 0.4, 0.0, 0.0])   # origin 0.4 km beyond the -x tip
    obj = _write_obj(tmp_path / "cb_off.obj", shifted, f)
    with pytest.raises(InputError) as ei:
        setup_from_campaign(_campaign(tmp_path, obj))
    assert ei.value.field == "body.name" and "centre of mass" in ei.value.message
    assert "0.65" in ei.value.message                  # the offset, km
    r = subprocess.run([sys.executable, "-m", "ideas_hpc.cli", "body", str(obj), "--mass-kg",
                        str(MASS_KG)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "FILE" in r.stderr


@pytest.mark.parametrize("key,value", [("sigma_misalignment_deg", 0.2),
                                       ("sigma_position_m", 100.0)])
def test_case3_4_pointing_dispersion_beyond_the_fov_warns(tmp_path, binary_km, capsys, key,
                                                         value):
    """The Eros dispersions on this body: 3 x 0.2 deg against a half angle near 0.07 deg, and
    3 x 100 m against a footprint near 180 m; each warns once, naming its key."""
    obj = _write_obj(tmp_path / "cb.obj", *binary_km)
    c = _campaign(tmp_path, obj, kind="monte-carlo", extra=f"[monte_carlo]\n{key} = {value}\n")
    s = setup_from_campaign(c)
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(lines) == 1 and f"monte_carlo.{key}" in lines[0]
    foot = (s.d_sep_m - s.sizing.r_av) * np.tan(s.eta_rad)
    assert (3 * np.radians(value) > s.eta_rad) if "deg" in key else (3 * value > foot)


def test_case5_grid_finer_than_the_separation_is_refused(tmp_path, binary_km):
    obj = _write_obj(tmp_path / "cb.obj", *binary_km)
    c = _campaign(tmp_path, obj, kind="design-nadir",
                  extra="[design]\nangle_step_deg = 0.001\n")
    with pytest.raises(InputError) as ei:
        setup_from_campaign(c)
    assert ei.value.field == "design.angle_step_deg" and "360,000" in ei.value.message
    fine = _campaign(tmp_path, obj, kind="design-nadir", extra="[design]\nangle_step_deg = 0.1\n")
    setup_from_campaign(fine)      # 0.1 deg: 4 steps within the 0.39 deg separation


def test_eros_campaigns_pass_the_checks_silently(capsys):
    for name in ("eros-monte-carlo.toml", "eros-nadir.toml", "eros-flyby.toml"):
        setup_from_campaign(load(ROOT / "campaigns" / name))
    assert "warning" not in capsys.readouterr().err


def test_body_command_prints_the_convention(eros1708, capsys):
    from ideas_hpc.cli import main

    assert main(["body", "eros001708"]) == 0
    out = capsys.readouterr().out
    p = mass_properties(eros1708.shape.vertices_T, eros1708.shape.faces)
    assert f"c20_km2 = {p.c20_m2 / 1e6:.6g}" in out and "unnormalised" in out
    assert f"{eros1708.params.mu / G / p.volume_m3:.4g} kg/m^3" in out


def test_example_campaign_file_is_valid(tmp_path, binary_km):
    """The shipped example validates and passes every check on the mesh its script writes."""
    obj = _write_obj(tmp_path / "contact_binary.obj", *_maker().contact_binary(3))
    c = load(ROOT / "campaigns" / "custom-body" / "contact-binary.toml", [f'body.name="{obj}"'])
    s = setup_from_campaign(c)
    assert s.body.shape.n_faces == 1280 and s.eta_rad < 0.1 * np.pi / 180


def test_implausible_mass_of_a_builtin_shape_names_the_params():
    """Eros' shape with a 1e9 kg mass (density 4e-4 kg/m^3): the mesh is right, the mass is not."""
    c = load(ROOT / "campaigns" / "eros-flyby.toml",
             ['body.params={mass_kg=1e9, spin_period_h=5.27, a_au=1.457, e=0.222}'])
    with pytest.raises(InputError) as ei:
        setup_from_campaign(c)
    assert ei.value.field == "body.params" and "density" in ei.value.message
