import pytest

from ideas_hpc.campaign.schema.toml_file import apply_overrides, line_index, load_campaign, parse_override
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field, validate

TOML = """\
kind = "flyby"   # comment
seed = 7

[body]
name = "eros"

[swarm]
angles_rad = [0.2, 1.7,
  2.4]
n_max = 20

[controller]
k_p = [4, 0.4, 0.4]
"""


def test_line_index():
    idx = line_index(TOML)
    assert idx["kind"] == 1 and idx["seed"] == 2 and idx["body"] == 4
    assert idx["body.name"] == 5 and idx["swarm.angles_rad"] == 8 and idx["swarm.n_max"] == 10
    assert idx["controller.k_p"] == 13


def test_overrides_parse_toml_values(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text(TOML)
    src = load_campaign(p, ["swarm.n_max=12", "body.name=eros001708", "controller.k_p=[1, 2, 3]",
                            "new.table.value=1.5", 'body.label="a b"'])
    d = src.data
    assert d["swarm"]["n_max"] == 12 and d["body"]["name"] == "eros001708"
    assert d["controller"]["k_p"] == [1, 2, 3] and d["new"]["table"]["value"] == 1.5
    assert d["body"]["label"] == "a b"
    assert src.where("swarm.n_max") == ("--set", None)
    assert src.where("swarm.angles_rad") == (str(p), 8)


@pytest.mark.parametrize("bad", ["novalue", "=3", "a..b=1", "x=[1,"])
def test_bad_override(bad):
    with pytest.raises(InputError):
        parse_override(bad)


def test_override_into_value_is_error():
    with pytest.raises(InputError, match="seed is a value"):
        apply_overrides({"seed": 1}, ["seed.x=2"])


def test_toml_syntax_error_has_line(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("a = 1\nb = [1, 2\n")
    with pytest.raises(InputError) as ei:
        load_campaign(p)
    assert "c.toml:" in str(ei.value)


SCHEMA = {
    "seed": Field("int", 0, lo=0),
    "body": {"name": Field("str", "eros")},
    "swarm": {
        "angles_rad": Field("floats", None, nullable=True),
        "n_max": Field("int", 20, lo=1),
        "d_sep_km": Field("float", 155.9, to_si=1e3, lo=0, lo_open=True),
    },
    "kind": Field("str", choices=("flyby", "monte-carlo")),
    "controller": {"k_p": Field("floats", [0.4] * 3, length=3, broadcast=True, lo=0)},
}


def test_schema_defaults_and_units(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text(TOML)
    out = validate(load_campaign(p).data, SCHEMA)
    assert out["swarm"]["d_sep_km"] == 155.9e3 and out["seed"] == 7
    assert validate({"kind": "flyby", "controller": {"k_p": 2}}, SCHEMA)["controller"]["k_p"] == [2.0] * 3


@pytest.mark.parametrize("override,field,text", [
    ("swarm.n_max=0", "swarm.n_max", "must be >= 1"),
    ('swarm.n_max="x"', "swarm.n_max", "whole number"),
    ("swarm.bogus=1", "swarm.bogus", "unknown key"),
    ('kind="nope"', "kind", "must be one of"),
    ("controller.k_p=[1, 2]", "controller.k_p", "3 numbers"),
    ("controller.k_p=[1, -2, 3]", "controller.k_p[1]", "must be >= 0"),
])
def test_schema_errors_name_field_file_line(tmp_path, override, field, text):
    p = tmp_path / "c.toml"
    p.write_text(TOML)
    src = load_campaign(p, [override])
    with pytest.raises(InputError) as ei:
        validate(src.data, SCHEMA)
    err = src.locate(ei.value)
    assert err.field == field and text in str(err)


def test_locate_gives_file_line(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text(TOML.replace("n_max = 20", "n_max = -3"))
    src = load_campaign(p)
    with pytest.raises(InputError) as ei:
        validate(src.data, SCHEMA)
    assert str(src.locate(ei.value)).startswith(f"{p}:10: swarm.n_max: must be >= 1")
