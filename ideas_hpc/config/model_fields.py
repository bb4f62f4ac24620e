"""The models' own parameter names -> the campaign file's keys (issue 21).

Below the config layer every model names its own parameters, in SI: a failed
targeting asks to raise ``max_iter``, an unreachable approach names
``phase_angle_rad``, a bad spacecraft names ``mass_kg``. The campaign file has
its own keys in user units (``flyby.max_iterations``, ``flyby.phase_angle_deg``,
``spacecraft.mass``). The maps here turn one into the other, in the field and,
between backticks, in the message (:func:`ideas_hpc.errors.config_fields`), so
the user reads the file's key with its file and line:

* :data:`FLYBY_FIELDS`: :class:`~ideas_hpc.flyby.flight.FlybySetup` and the
  flyby layer (targeting, encounter, ring spacing, maneuver names);
  :func:`flyby_errors` applies it where a campaign builds or flies a setup;
* :data:`COVERAGE_FIELDS`, :data:`SPACECRAFT_FIELDS`, :data:`GAINS_FIELDS`: the
  fields of :class:`~ideas_hpc.mapping.options.CoverageOptions`,
  :class:`~ideas_hpc.attitude.spacecraft.SpacecraftModel` and
  :class:`~ideas_hpc.attitude.gains.Gains` -> ``[coverage]``, ``[spacecraft]``,
  ``[controller]`` keys (used by :func:`ideas_hpc.config.campaign_tables.build_models`);
* :data:`STORED_NAMES`: the names under which a store's resolved config records
  those three models (``models.coverage.min_elevation``, ...). They are the
  names the fields had before they carried units, kept so that the config hash of
  a store, ``--resume`` and ``report`` of stores written before are unchanged.
"""

from __future__ import annotations

import contextlib

from ideas_hpc.errors import InputError, config_fields

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
