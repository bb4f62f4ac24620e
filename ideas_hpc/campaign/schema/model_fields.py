"""The models' own parameter names -> the campaign file's keys (issue 21).

Below the config layer every model names its own parameters, in SI: a failed
targeting asks to raise ``max_iter``, an unreachable approach names
``phase_angle_rad``, a bad spacecraft names ``mass_kg``. The campaign file has
its own keys in user units (``flyby.max_iterations``, ``flyby.phase_angle_deg``,
``spacecraft.mass``). The maps here turn one into the other, in the field and,
between backticks, in the message (:func:`ideas_hpc.base.errors.config_fields`), so
the user reads the file's key with its file and line:

* :data:`FLYBY_FIELDS`: :class:`~ideas_hpc.flyby.flight.FlybySetup` and the
  flyby layer (targeting, encounter, ring spacing, maneuver names);
  :func:`flyby_errors` applies it where a campaign builds or flies a setup;
* :data:`COVERAGE_FIELDS`, :data:`SPACECRAFT_FIELDS`, :data:`GAINS_FIELDS`: the
  fields of :class:`~ideas_hpc.mapping.options.CoverageOptions`,
  :class:`~ideas_hpc.attitude.spacecraft.SpacecraftModel` and
  :class:`~ideas_hpc.attitude.gains.Gains` -> ``[coverage]``, ``[spacecraft]``,
  ``[controller]`` keys (used by :func:`ideas_hpc.campaign.schema.model_tables.build_models`);
* :data:`STORED_NAMES`: the names under which a store's resolved config records
  those three models (``models.coverage.min_elevation``, ...). They are the
  names the fields had before they carried units, kept so that the config hash of
  a store, ``--resume`` and ``report`` of stores written before are unchanged.
"""

from __future__ import annotations

import contextlib

from ideas_hpc.base.errors import InputError, config_fields

#: The flyby layer's parameter names -> campaign keys.
FLYBY_FIELDS = {
    "d_sep_m": "flyby.d_sep_km", "tol_m": "flyby.tolerance_m", "max_iter": "flyby.max_iterations",
    "z_start_m": "flyby.z_start_km", "z_stop_m": "flyby.z_stop_km",
    "before_m": "flyby.before_km", "v_inf_T_m_s": "flyby.v_inf_km_s",
    "phase_angle_rad": "flyby.phase_angle_deg", "theta": "swarm.angles_rad",
    "min_separation": "swarm.min_separation_km", "maneuver": "attitude.maneuver",
}


@contextlib.contextmanager
def flyby_errors(c=None):
    """Re-raise a flyby-layer :class:`InputError` under the file's key (:data:`FLYBY_FIELDS`),
    with its file and line when the campaign ``c`` is given. Other errors pass unchanged."""
    try:
        yield
    except InputError as exc:
        if exc.field not in FLYBY_FIELDS:
            raise
        try:
            with config_fields(FLYBY_FIELDS):
                raise exc
        except InputError as mapped:
            if c is None or mapped.file is not None:
                raise mapped from None
            raise c.source.locate(mapped) from None

#: :class:`~ideas_hpc.mapping.options.CoverageOptions` fields -> ``[coverage]`` keys.
COVERAGE_FIELDS = {
    "mode": "coverage.mode", "occlusion": "coverage.occlusion",
    "illumination": "coverage.illumination", "min_elevation_rad": "coverage.min_elevation_deg",
    "max_ground_resolution_m": "coverage.max_ground_resolution_m",
    "wavelength_m": "coverage.wavelength_um", "aperture_m": "coverage.aperture_cm",
    "pixel_pitch_m": "coverage.pixel_pitch_um", "focal_length_m": "coverage.focal_length_mm",
    "quality": "coverage.quality", "require_lit": "coverage.require_lit",
    "max_resolution_m": "coverage.max_resolution_m",
    "max_emission_rad": "coverage.max_emission_deg",
    "max_incidence_rad": "coverage.max_incidence_deg", "max_phase_rad": "coverage.max_phase_deg",
    "require_stereo": "coverage.require_stereo", "stereo_min_rad": "coverage.stereo_min_deg",
    "stereo_max_rad": "coverage.stereo_max_deg",
}
#: :class:`~ideas_hpc.attitude.spacecraft.SpacecraftModel` fields -> ``[spacecraft]`` keys.
SPACECRAFT_FIELDS = {
    "mass_kg": "spacecraft.mass", "size_m": "spacecraft.size",
    "wheel_mass_kg": "spacecraft.wheel_mass", "wheel_radius_m": "spacecraft.wheel_radius",
    "u_max_N_m": "spacecraft.u_max", "h_max_N_m_s": "spacecraft.h_max",
    "inertia_kg_m2": "spacecraft.inertia",
}
#: :class:`~ideas_hpc.attitude.gains.Gains` fields -> ``[controller]`` keys.
GAINS_FIELDS = {
    "k_p_per_s": "controller.k_p", "k_i_per_s2": "controller.k_i",
    "eta_rad_per_s2": "controller.eta", "phi_s_per_rad": "controller.phi",
    "int_limit": "controller.int_limit", "phi_dt_max": "controller.phi_dt_max",
}
#: The three models' fields by the campaign's name for the model (``c.extras``).
MODEL_FIELDS = {"coverage": COVERAGE_FIELDS, "spacecraft": SPACECRAFT_FIELDS,
                "gains": GAINS_FIELDS}

_OLD_COVERAGE = {"min_elevation_rad": "min_elevation",
                 "max_ground_resolution_m": "max_ground_resolution",
                 "wavelength_m": "wavelength", "aperture_m": "aperture",
                 "pixel_pitch_m": "pixel_pitch", "focal_length_m": "focal_length",
                 "max_resolution_m": "max_resolution", "max_emission_rad": "max_emission",
                 "max_incidence_rad": "max_incidence", "max_phase_rad": "max_phase",
                 "stereo_min_rad": "stereo_min", "stereo_max_rad": "stereo_max"}
#: Field -> the name a store's ``models`` records it under (SI values; names as before
#: the units were added: the coverage fields' names, the spacecraft and controller keys).
STORED_NAMES = {
    "coverage": {f: _OLD_COVERAGE.get(f, f) for f in COVERAGE_FIELDS},
    "spacecraft": {f: k.partition(".")[2] for f, k in SPACECRAFT_FIELDS.items()},
    "gains": {f: k.partition(".")[2] for f, k in GAINS_FIELDS.items()},
}


def stored_fields(name: str, fields: dict) -> dict:
    """``fields`` (a model's field -> value) under the names a store records for the
    model ``name`` (:data:`STORED_NAMES`; other models keep their field names)."""
    names = STORED_NAMES.get(name, {})
    return {names.get(k, k): v for k, v in fields.items()}
