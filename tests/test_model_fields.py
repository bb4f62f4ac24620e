"""The config layer's maps from the models' own parameter names to the file's keys.

Oracles: the models' dataclass fields (every field is mapped), the tables'
schemas (each file key is the one whose SI name is that field), and the
campaign schema (every mapped key exists).
"""

from __future__ import annotations

import dataclasses

import pytest

from ideas_hpc.attitude.gains import CONTROLLER_SCHEMA, Gains
from ideas_hpc.attitude.spacecraft import SPACECRAFT_SCHEMA, SpacecraftModel
from ideas_hpc.campaign.schema.campaign_tables import SCHEMA
from ideas_hpc.campaign.schema.model_fields import (COVERAGE_FIELDS, FLYBY_FIELDS, GAINS_FIELDS,
                                           SPACECRAFT_FIELDS, flyby_errors)
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.flight import FlybySetup
from ideas_hpc.mapping.options import COVERAGE_SCHEMA, CoverageOptions


@pytest.mark.parametrize("cls,fields,schema,table", [
    (CoverageOptions, COVERAGE_FIELDS, COVERAGE_SCHEMA, "coverage"),
    (SpacecraftModel, SPACECRAFT_FIELDS, SPACECRAFT_SCHEMA, "spacecraft"),
])
def test_every_field_maps_to_the_key_of_its_schema(cls, fields, schema, table):
    names = [f.name for f in dataclasses.fields(cls)]
    assert sorted(fields) == sorted(names)
    by_si = {f.si_name(k): k for k, f in schema.items()}
    for name in names:
        assert fields[name] == f"{table}.{by_si[name]}", name


def test_gains_map_covers_every_field_and_controller_key():
    assert sorted(GAINS_FIELDS) == sorted(f.name for f in dataclasses.fields(Gains))
    keys = {v.partition(".")[2] for v in GAINS_FIELDS.values()}
    assert keys == set(CONTROLLER_SCHEMA) - {"preset", "gains"}


def test_units_in_the_field_names():
    """Physical fields end in their unit; the unitless ones are flags, modes and the two
    dimensionless controller limits."""
    unitless = {"mode", "occlusion", "illumination", "quality", "require_lit", "require_stereo",
                "int_limit", "phi_dt_max"}
    units = ("_rad", "_m", "_kg", "_N_m", "_N_m_s", "_kg_m2", "_per_s", "_per_s2",
             "_rad_per_s2", "_s_per_rad")
    for cls in (CoverageOptions, SpacecraftModel, Gains):
        for f in dataclasses.fields(cls):
            assert f.name in unitless or f.name.endswith(units), (cls.__name__, f.name)


def test_flyby_map_targets_campaign_keys():
    setup_fields = {f.name for f in dataclasses.fields(FlybySetup)}
    for own, key in FLYBY_FIELDS.items():
        table, _, name = key.partition(".")
        assert name in SCHEMA[table], key
    assert {"d_sep_m", "tol_m", "max_iter", "z_start_m", "z_stop_m"} <= setup_fields


def test_flyby_errors_maps_field_and_message_and_leaves_others_alone():
    with pytest.raises(InputError) as ei, flyby_errors():
        raise InputError("raise `max_iter` (now 1); or `d_sep_m`", field="max_iter")
    assert ei.value.field == "flyby.max_iterations"
    assert ei.value.message == "raise flyby.max_iterations (now 1); or flyby.d_sep_km"
    other = InputError("check `squeue` first", field="--workers")
    with pytest.raises(InputError) as ei, flyby_errors():
        raise other
    assert ei.value is other
