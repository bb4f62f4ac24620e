"""``--resume`` compares the fully resolved config; code version changes are reported."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import xarray as xr

from ideas_hpc.campaign.schema import campaign_tables as schema
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import EXECUTION_KNOBS, SCHEMA, load, resolved_config
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field

from campaign_copies import fitted

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
FLYBY = CAMPAIGNS / "eros-flyby.toml"
TINY = ['body.name="ellipsoid"', 'attitude.mode="ideal"', "flyby.tf_s=60", "flyby.z_start_km=-3",
        "flyby.z_stop_km=3", "swarm.angles_rad=[0.2, 3.3]"]
#: the shipped flyby without what an ideal attitude does not read ([controller], its start)
IDEAL = fitted("eros-flyby.toml", TINY)
#: a tiny exact design: it reads the execution knobs run.workers and design.chunk_size
NADIR = CAMPAIGNS / "eros-nadir.toml"
TINY_DESIGN = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
               "flyby.z_stop_km=3", "design.angle_step_deg=30", "design.n_max=4",
               "design.verify_samples=2"]


def test_resolved_config_writes_every_default():
    rc = resolved_config(load(FLYBY))
    for table, spec in SCHEMA.items():
        if isinstance(spec, dict):
            keys = {f"{table}.{k}" for k in spec} - set(EXECUTION_KNOBS)
            assert {f"{table}.{k}" for k in rc[table]} == keys, table
    assert rc["flyby"]["helix_rise_km"] == 0.0  # not in the file: its default
    assert rc["swarm"]["min_separation_km"] == 1.0
    assert rc["models"]["force_model"]["rtol"] > 0  # a module default, written out
    assert "workers" not in rc["run"] and "chunk_size" not in rc["design"]


@pytest.fixture(scope="module")
def tiny_store(tmp_path_factory):
    out = tmp_path_factory.mktemp("resume") / "tiny.zarr"
    run_file(IDEAL, out=out, overrides=TINY)
    return out


def test_store_holds_the_resolved_config(tiny_store):
    attrs = xr.open_zarr(tiny_store).attrs
    assert json.loads(attrs["config"]) == resolved_config(load(IDEAL, TINY))


def test_resume_refused_after_a_default_changed(tiny_store, monkeypatch):
    # near_field_mm is not in the file: only its default changes
    monkeypatch.setitem(schema.INSTRUMENT, "near_field_mm",
                        Field("float", 0.2, si="near_field_m", to_si=1e-3, lo=0,
                              lo_open=True))
    with pytest.raises(InputError) as ei:
        run_file(IDEAL, out=tiny_store, overrides=TINY, resume=True)
    assert "instrument.near_field_mm = 0.1 in the store, 0.2 now" in str(ei.value)


def test_resume_ignores_execution_knobs(tmp_path, capsys):
    out = tmp_path / "design.zarr"
    run_file(NADIR, out=out, overrides=TINY_DESIGN, workers=0, progress=False)
    capsys.readouterr()
    run_file(NADIR, out=out, overrides=TINY_DESIGN + ["run.workers=3", "design.chunk_size=5"],
             resume=True)
    assert "nothing to do" in capsys.readouterr().err


def test_resume_warns_once_when_code_version_differs(tiny_store, monkeypatch, capsys):
    import ideas_hpc._version as v

    monkeypatch.setattr(v, "code_version", lambda: "0.0.0+gdeadbee")
    run_file(IDEAL, out=tiny_store, overrides=TINY, resume=True)
    warn = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(warn) == 1 and "code version" in warn[0] and "0.0.0+gdeadbee" in warn[0]


# The keys issue 24 added to [flyby] (the encounter) and issue 22 to [design]:
# stores written before them lack them, and their defaults are the old behaviour.
LATER_KEYS = {"flyby": ["geometry", "speed_km_s", "approach_dec_deg", "approach_ra_deg",
                        "phase_angle_deg", "v_inf_km_s", "before_km", "after_km", "before_s",
                        "after_s"],
              "design": ["confidence", "demonstrate", "scenarios", "success_probability"]}


# What the code before those keys wrote for the keys whose default is now null
# (as read from a store written by a6739bb^): the values the designers still use.
FORMER_DEFAULTS = {"angle_step_deg": 0.5, "angle_step_rad": 0.01, "verify_samples": 64}


def _as_older_code_wrote(config: dict) -> dict:
    """A resolved config as older code wrote it: no later keys (module lists)."""
    config = json.loads(json.dumps(config))
    for table, keys in LATER_KEYS.items():
        for key in keys:
            del config[table][key]  # KeyError: the test's list is stale
    # keys whose default became null ("the designer's own"), written out then
    assert [config["design"][k] for k in FORMER_DEFAULTS] == [None] * len(FORMER_DEFAULTS)
    config["design"].update(FORMER_DEFAULTS)
    return config


@pytest.fixture()
def old_store(tiny_store, tmp_path):
    """A copy of the tiny store as older code wrote it: no later keys, its own hash."""
    import shutil

    from ideas_hpc.engine.store import config_hash, config_json

    out = tmp_path / "old.zarr"
    shutil.copytree(tiny_store, out)
    meta = json.loads((out / "zarr.json").read_text())
    config = _as_older_code_wrote(json.loads(meta["attributes"]["config"]))
    meta["attributes"]["config"] = config_json(config)
    meta["attributes"]["config_hash"] = config_hash(config)
    (out / "zarr.json").write_text(json.dumps(meta))
    return out


def test_resume_accepts_a_store_written_before_keys_with_their_defaults(old_store, capsys):
    from ideas_hpc.engine.store import config_problems, store_attrs

    run_file(IDEAL, out=old_store, overrides=TINY, resume=True)
    assert "nothing to do" in capsys.readouterr().err
    attrs, rc = store_attrs(old_store), resolved_config(load(IDEAL, TINY))
    assert config_problems(attrs, rc, rc["seed"]) == []
    # without the defaults the comparison is the strict one: every later key differs
    strict = config_problems(attrs, dict(rc), rc["seed"])
    assert "design.confidence absent in the store, 0.95 now" in strict


def test_resume_of_an_old_store_still_refuses_real_changes(old_store):
    with pytest.raises(InputError) as ei:
        run_file(IDEAL, out=old_store, overrides=TINY + ["instrument.aperture_cm=9.5"],
                 resume=True)
    assert "instrument.aperture_cm = 8.0 in the store, 9.5 now" in str(ei.value)


#: An exact design and the success-probability one (they read the later design keys).
P = ["design.success_probability=0.5"]


@pytest.mark.parametrize("base, override, message", [
    (P, "design.confidence=0.9", "design.confidence absent in the store, 0.9 now"),
    (P, "design.scenarios=128", "design.scenarios absent in the store, 128 now"),
    ([], "design.verify_samples=32", "design.verify_samples = 64 in the store, 32 now"),
    ([], "design.angle_step_deg=1.0", "design.angle_step_deg = 0.5 in the store, 1.0 now"),
])
def test_an_old_design_config_still_differs_by_real_changes(base, override, message, tmp_path):
    """The comparison ``--resume`` makes (:func:`config_problems`), for the design keys
    added later, against a config as older code wrote it for the same design."""
    from ideas_hpc.engine.store import config_hash, config_problems

    design = tmp_path / "design.toml"
    design.write_text('kind = "design-nadir"\n[body]\nname = "ellipsoid"\n')
    old = _as_older_code_wrote(resolved_config(load(design, base)))
    attrs = {"config": old, "config_hash": config_hash(old), "campaign_seed": 2026}
    same = config_problems(attrs, resolved_config(load(design, base)), 2026)
    assert same == [] if not base else not any(message in p for p in same), same
    changed = config_problems(attrs, resolved_config(load(design, base + [override])), 2026)
    assert any(message in p for p in changed), changed


def test_models_keep_the_names_stores_record():
    """The model fields carry units (``min_elevation_rad``, ``mass_kg``, ``k_p_per_s``); a
    store records them under the names it always has, so its hash and ``--resume`` of
    older stores do not change. Oracle: the names as written by stores before the rename,
    and the values converted by hand."""
    import math

    rc = resolved_config(load(FLYBY, ["coverage.min_elevation_deg=7", "spacecraft.mass=5",
                                      "controller.k_p=[1, 2, 3]"]))
    m = rc["models"]
    assert set(m["coverage"]) == {
        "mode", "occlusion", "illumination", "min_elevation", "max_ground_resolution",
        "wavelength", "aperture", "pixel_pitch", "focal_length", "quality", "require_lit",
        "max_resolution", "max_emission", "max_incidence", "max_phase", "require_stereo",
        "stereo_min", "stereo_max"}
    assert set(m["spacecraft"]) == {"mass", "size", "wheel_mass", "wheel_radius", "u_max",
                                    "h_max", "inertia"}
    assert set(m["gains"]) == {"k_p", "k_i", "eta", "phi", "int_limit", "phi_dt_max"}
    assert m["coverage"]["min_elevation"] == pytest.approx(math.radians(7.0))
    assert m["coverage"]["aperture"] == pytest.approx(0.08)   # the instrument's 8 cm
    assert m["spacecraft"]["mass"] == 5.0 and m["gains"]["k_p"] == [1.0, 2.0, 3.0]
    assert rc.defaults["models.spacecraft.u_max"] == 0.007
    assert rc.defaults["models.coverage.stereo_max"] == pytest.approx(math.radians(40.0))
