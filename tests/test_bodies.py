import pytest

from ideas_hpc import load_body
from ideas_hpc.base.errors import DataNotFoundError, InputError


def test_eros_falls_back_to_ellipsoid_without_data(monkeypatch, tmp_path):
    monkeypatch.setenv("IDEAS_HPC_DATA", str(tmp_path))
    b = load_body("eros")
    assert b.shape.name == "eros-ellipsoid"
    assert "built-in Eros-sized ellipsoid" in b.note and str(tmp_path) in b.note
    assert b.params.name == "eros"


def test_eros_uses_real_model_when_present(eros1708):
    b = load_body("eros")
    assert b.shape.name == "eros001708" and "real NASA PDS" in b.note


def test_missing_real_model_lists_places(monkeypatch, tmp_path):
    monkeypatch.setenv("IDEAS_HPC_DATA", str(tmp_path))
    with pytest.raises(DataNotFoundError) as ei:
        load_body("eros007790", data_path=tmp_path / "explicit")
    msg = str(ei.value)
    assert str(tmp_path / "explicit" / "eros007790.tab") in msg
    assert str(tmp_path / "eros" / "eros007790.tab") in msg


def test_unknown_body_name():
    with pytest.raises(InputError, match="unknown body 'vesta'"):
        load_body("vesta")


def test_params_eros_table1():
    import math
    p = load_body("sphere").params
    assert p.c20 == 0.0
    e = load_body("ellipsoid").params
    assert math.isclose(e.mass, 6.689e15)
    assert math.isclose(e.c20, -30.010e6) and math.isclose(e.c22, 14.382e6)
    assert math.isclose(e.spin_period, 5.270 * 3600)
    assert math.isclose(math.degrees(e.orbit_raan), 304.320)


def test_user_params_from_toml_errors():
    from ideas_hpc.body.params import params_from_mapping
    with pytest.raises(InputError, match="body.params.spin_period_h"):
        params_from_mapping({"mass_kg": 1e15, "a_au": 1.0, "e": 0.1}, prefix="body.params.")
    with pytest.raises(InputError, match="body.params.e"):
        params_from_mapping({"mass_kg": 1e15, "a_au": 1.0, "e": 1.5, "spin_period_h": 5},
                            prefix="body.params.")
    with pytest.raises(InputError, match="unknown key 'masss'"):
        params_from_mapping({"masss": 1}, prefix="body.params.")
    p = params_from_mapping({"gm_km3_s2": 4.46e-4, "a_au": 1.0, "e": 0.1, "spin_period_h": 5})
    assert abs(p.mu - 4.46e5) < 1e-6
