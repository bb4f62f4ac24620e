"""The ``[instrument]`` table: the camera (SPEC sections 2, 6b) and the usable-image test (7d).

``pixels_across`` (detector pixels across the field of view; the IFOV is then
``2 eta / n_pix``, else ``pixel_pitch_um / focal_length_mm`` with a detector, else
``lambda / D``), ``exposure_ms`` (exposure time ``t_exp``; by default 10 ms on the paper's
pass and 1 ms on an encounter, :data:`ideas_hpc.flyby.usable.ENCOUNTER_EXPOSURE_MS`), ``smear_pixels``
(largest smear of a usable image, ``|omega_img x u| t_exp / IFOV``: the motion of
the scene's image on the detector at the footprint centre, the camera's rate
relative to the turning line of sight, SPEC 7d) and ``settle_deg`` (largest
attitude error of a usable image): :mod:`ideas_hpc.flyby.usable`. The
test applies to the closed loop (``attitude.mode = "simulated"``) unless
``monte_carlo.attitude_start = "paper"``, and its smear part to perfect tracking on an
encounter (at the reference's rate; no settle test) (docs/attitude-start.md).
"""

from __future__ import annotations

from ideas_hpc.base.fields import Field
from ideas_hpc.base.instrument import INSTRUMENT_DEFAULTS as _CAM
from ideas_hpc.flyby.usable import (ENCOUNTER_EXPOSURE_MS, EXPOSURE_MS, SETTLE_DEG, SMEAR_PIXELS,
                                    default_exposure_s)
from ideas_hpc.base.units import CM, DEG, MM, UM

INSTRUMENT = {
    "ground_resolution_m": Field("float", _CAM["ground_resolution_m"], lo=0, lo_open=True),
    "aperture_cm": Field("float", _CAM["aperture_cm"], si="aperture_m",
                         to_si=CM, lo=0, lo_open=True),
    "wavelength_um": Field("float", _CAM["wavelength_um"], si="wavelength_m",
                           to_si=UM, lo=0, lo_open=True),
    "min_elevation_deg": Field("float", _CAM["min_elevation_deg"], si="min_elevation_rad",
                               to_si=DEG, lo=0, hi=90, hi_open=True),
    "near_field_mm": Field("float", _CAM["near_field_mm"], si="near_field_m",
                           to_si=MM, lo=0, lo_open=True),
    "image_rate_hz": Field("float", 5.0, lo=0, lo_open=True),
    "half_angle_deg": Field("float", None, nullable=True, si="half_angle_rad",
                            to_si=DEG, lo=0, hi=90,
                            lo_open=True, hi_open=True),
    "pixel_pitch_um": Field("float", None, nullable=True, si="pixel_pitch_m",
                            to_si=UM, lo=0, lo_open=True,
                            doc="detector pixel pitch (with focal_length_mm: the quality "
                                "pass uses pitch/focal length instead of lambda/D)"),
    "focal_length_mm": Field("float", None, nullable=True, si="focal_length_m",
                             to_si=MM, lo=0, lo_open=True),
    "pixels_across": Field("int", None, nullable=True, lo=1,
                           doc="detector pixels across the field of view (IFOV 2 eta / n)"),
    "exposure_ms": Field("float", None, nullable=True, si="exposure_s", to_si=MM, lo=0,
                         lo_open=True,
                         doc=f"exposure time of one image (the smear test's t_exp); default "
                             f"{EXPOSURE_MS:g} on the paper's pass, {ENCOUNTER_EXPOSURE_MS:g} on "
                             f"an encounter (flyby.usable.ENCOUNTER_EXPOSURE_MS)"),
    "smear_pixels": Field("float", SMEAR_PIXELS, lo=0, lo_open=True,
                          doc="largest smear of a usable image, pixels: the scene's image "
                              "motion across the line of sight at the footprint centre over "
                              "the exposure (camera rate relative to the line of sight, body "
                              "spin included)"),
    "settle_deg": Field("float", SETTLE_DEG, si="settle_rad", to_si=DEG, lo=0,
                        lo_open=True, hi=180, doc="largest attitude error of a usable image"),
}


def exposure_ms(config) -> float:
    """``instrument.exposure_ms`` as flown (ms) of a typed campaign config: the file's, else
    the geometry's default (:func:`ideas_hpc.flyby.usable.default_exposure_s`); a resolved
    config's ``effective`` value, so that a store written when the default was 10 ms on
    every geometry resumes on the paper's pass."""
    s = config.instrument.exposure_s
    return (default_exposure_s(config.flyby.geometry == "encounter") if s is None else s) / MM
