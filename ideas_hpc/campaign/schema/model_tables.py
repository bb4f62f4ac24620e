"""The model tables of a campaign: ``[dynamics]``, ``[spacecraft]``, ``[controller]``,
``[coverage]`` and ``[torques]``, validated by the modules that own them (split from
:mod:`ideas_hpc.campaign.schema.campaign_tables`).

Their errors name the file's keys through the maps of
:mod:`ideas_hpc.campaign.schema.model_fields`. The ``[coverage]`` options take the
instrument's camera (``wavelength_um``, ``aperture_cm``, ``pixel_pitch_um``,
``focal_length_mm``) unless the table gives its own.
"""

from __future__ import annotations

from ideas_hpc.attitude.maneuvers import campaign_maneuver
from ideas_hpc.base.errors import InputError, config_fields
from ideas_hpc.base.fields import with_defaults
from ideas_hpc.campaign.schema.design_checks import check_stereo_design
from ideas_hpc.campaign.schema.instrument_table import INSTRUMENT
from ideas_hpc.campaign.schema.kinds import KINDS as REGISTRY
from ideas_hpc.campaign.schema.model_fields import COVERAGE_FIELDS, GAINS_FIELDS, SPACECRAFT_FIELDS


def sub_table(cfg: dict, key: str) -> dict:
    """The file's ``[key]`` table (``{}`` when absent); an InputError naming ``key`` when it
    is not a table."""
    v = cfg.get(key)
    if v is None:
        return {}
    if not isinstance(v, dict):
        raise InputError(f"must be a table, got {v!r}", field=key)
    return v


def build_models(raw: dict, config) -> dict:
    """Build the sub-models whose schemas live with their modules.

    The ``[dynamics]``, ``[spacecraft]``, ``[controller]``, ``[coverage]`` and
    ``[torques]`` tables are validated by the modules that own them, so a field is checked
    in one place only. They are read in the file's units, as written.
    """
    from ideas_hpc.attitude import gains_from_config, spacecraft_from_config
    from ideas_hpc.attitude.torque_terms import torques_from_config
    from ideas_hpc.mapping.options import coverage_options_from_config
    from ideas_hpc.dynamics.force_model import force_model_from_config

    cov = dict(sub_table(raw, "coverage"))
    # The ground-resolution test and the quality pass use the instrument's camera
    # unless the coverage table says otherwise (one source of truth for the camera).
    inst = with_defaults(raw.get("instrument"), INSTRUMENT)
    for key in ("wavelength_um", "aperture_cm", "pixel_pitch_um", "focal_length_mm"):
        if inst.get(key) is not None:
            cov.setdefault(key, inst[key])
    ctrl = sub_table(raw, "controller")
    if not ctrl:
        ctrl = {"preset": campaign_maneuver(config.attitude.maneuver).gains}
    with config_fields(COVERAGE_FIELDS):   # the models' field names -> the file's keys
        coverage = coverage_options_from_config(cov, prefix="coverage.")
    if coverage.require_stereo and REGISTRY[config.kind].designs:
        check_stereo_design(config, raw.get("design"))
    with config_fields(SPACECRAFT_FIELDS):
        sc = spacecraft_from_config(sub_table(raw, "spacecraft"), prefix="spacecraft.")
    with config_fields(GAINS_FIELDS):
        gains = gains_from_config(ctrl, prefix="controller.")
    # checked here (errors name torques.<term>.<parameter>); the setup builds the
    # terms from the file's table, which the resolved config already records
    torques_from_config(sub_table(raw, "torques"), prefix="torques.")
    return {"force_model": force_model_from_config(sub_table(raw, "dynamics"), prefix="dynamics."),
            "spacecraft": sc, "gains": gains, "coverage": coverage}
