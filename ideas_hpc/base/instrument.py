"""The paper's camera (Table 3): the one place the instrument defaults are written.

A ground-floor module, so that the mapping options (aperture and wavelength of
the resolution model), the flyby sizing and the campaign's ``[instrument]``
table all read the same numbers without importing one another.
"""

from __future__ import annotations

from ideas_hpc.base.units import CM, DEG, MM, UM

#: Paper Table 3 camera, in the units campaign files and the CLI use
#: (``[instrument]`` and ``ideas-hpc size`` read them).
INSTRUMENT_DEFAULTS = {"ground_resolution_m": 1.0, "aperture_cm": 8.0, "wavelength_um": 0.55,
                       "min_elevation_deg": 5.0, "near_field_mm": 0.1}
#: The same, SI (converted as a campaign file's values are): m, m, m, rad, m.
GROUND_RESOLUTION = INSTRUMENT_DEFAULTS["ground_resolution_m"]
APERTURE = INSTRUMENT_DEFAULTS["aperture_cm"] * CM
WAVELENGTH = INSTRUMENT_DEFAULTS["wavelength_um"] * UM
MIN_ELEVATION = INSTRUMENT_DEFAULTS["min_elevation_deg"] * DEG
NEAR_FIELD = INSTRUMENT_DEFAULTS["near_field_mm"] * MM
