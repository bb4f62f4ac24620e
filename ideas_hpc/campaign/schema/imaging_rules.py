"""Who reads the usable-image keys of ``[instrument]`` (:mod:`~ideas_hpc.campaign.schema.reads`).

The smear keys (``pixels_across``, ``exposure_ms``, ``smear_pixels``) are read by the
closed loop, and by perfect tracking where its geometry tests its images (an encounter:
the camera turns at its reference's rate,
:attr:`~ideas_hpc.flyby.geometry.Geometry.ideal_images_tested`), unless
``monte_carlo.attitude_start`` is the paper's (every image counts), which both then read;
``settle_deg`` only by the closed loop (perfect tracking has no attitude error).
"""

from __future__ import annotations

from ideas_hpc.attitude.modes import ATTITUDE_MODES, ATTITUDE_STARTS
from ideas_hpc.campaign.schema.read_settings import Rule, Settings
from ideas_hpc.flyby.geometry import PAPER, EncounterGeometry


def _names(registry: dict, capability) -> str:
    return " or ".join(f'"{n}"' for n, e in registry.items() if capability(e))


def ideal_tested(s: Settings) -> bool:
    """Perfect tracking faces the usable-image test on the campaign's geometry."""
    paper = s.config.flyby.geometry == "paper"
    return (PAPER if paper else EncounterGeometry).ideal_images_tested


def tested(s: Settings) -> bool:
    """The attitude faces the usable-image test: the closed loop, or perfect tracking where
    the geometry tests ideal images; its start then decides (``usable_images``)."""
    return s.simulated or ideal_tested(s)


def _imaging(s: Settings) -> bool:
    return tested(s) and s.start.usable_images


def _why_imaging(s: Settings) -> str:
    loops = _names(ATTITUDE_MODES, lambda m: m.closed_loop)
    if not tested(s):
        return (f"is ignored with attitude.mode = {s.attitude.name!r} on the paper's geometry: "
                "every image counts, as the paper's ideal mode (the usable-image test judges "
                f"a closed loop, attitude.mode = {loops}, and perfect tracking on an "
                "encounter)")
    return (f"is ignored with monte_carlo.attitude_start = {s.start.name!r}: every image counts "
            f"(attitude_start = {_names(ATTITUDE_STARTS, lambda t: t.usable_images)} applies "
            "the test)")


def _why_settle(s: Settings) -> str:
    if not s.simulated:
        loops = _names(ATTITUDE_MODES, lambda m: m.closed_loop)
        return (f"is ignored with attitude.mode = {s.attitude.name!r}: perfect tracking has no "
                f"attitude error to settle (the settle test judges a closed loop, attitude.mode "
                f"= {loops})")
    return _why_imaging(s)


def _why_start(s: Settings) -> str:
    loops = _names(ATTITUDE_MODES, lambda m: m.closed_loop)
    return (f"is ignored with attitude.mode = {s.attitude.name!r} on the paper's geometry: a "
            f"flight starts from it only in a closed loop (attitude.mode = {loops}); perfect "
            "tracking on an encounter reads it too (\"paper\": every image counts)")


#: The keys of the usable-image test (``[instrument]`` and the start that turns it off)
#: and who reads them.
IMAGING_RULES = {
    "monte_carlo.attitude_start": Rule(tested, _why_start),
    **{f"instrument.{k}": Rule(_imaging, _why_imaging)
       for k in ("pixels_across", "exposure_ms", "smear_pixels")},
    "instrument.settle_deg": Rule(lambda s: s.simulated and s.start.usable_images, _why_settle),
}
