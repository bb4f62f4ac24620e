"""The ``[flyby]`` keys of a real encounter (issue 24; SPEC section 7c).

``geometry``: ``"paper"`` (default: the paper's slow pole-aligned pass from
``z_start_km`` to ``z_stop_km`` between ``t0_s`` and ``tf_s``) or
``"encounter"`` (ballistic tracks, :mod:`ideas_hpc.flyby.encounter`). An encounter reads:

``speed_km_s`` (``|v_inf|``, default 10), ``approach_dec_deg`` (declination of
``v_inf`` from the body's equator in T at closest approach: 90 flies along the
pole as the paper does; default 90), ``approach_ra_deg`` (right ascension from
the prime meridian, default 0) or instead ``phase_angle_deg`` (Sun-body-spacecraft
angle on approach, which fixes the right ascension from the Sun at ``epoch_s``),
or ``v_inf_km_s`` (the vector in T, instead of all of these);
``d_sep_km`` (the ring's closest-approach distance, as for the paper); the
imaging window ``before_km``/``after_km`` (default 30 km each side) or
``before_s``/``after_s``, rounded to the image period. Closest approach is at
flyby time ``t0_s + before``; ``epoch_s`` sets the Sun and rotation phase as before.
"""

from __future__ import annotations

from ideas_hpc.attitude.maneuvers import campaign_maneuver
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field
from ideas_hpc.base.units import DEG, KM

ENCOUNTER = {
    "geometry": Field("str", "paper", choices=("paper", "encounter"),
                      doc="paper: the slow pole-aligned pass; encounter: ballistic approach"),
    "speed_km_s": Field("float", None, nullable=True, si="speed_m_s", to_si=KM, lo=0,
                        lo_open=True, doc="relative speed |v_inf| (default 10 km/s)"),
    "approach_dec_deg": Field("float", None, nullable=True, si="approach_dec_rad", to_si=DEG,
                              lo=-90, hi=90, doc="declination of v_inf w.r.t. the pole "
                                                 "(default 90: along the pole)"),
    "approach_ra_deg": Field("float", None, nullable=True, si="approach_ra_rad", to_si=DEG,
                             lo=-360, hi=360, doc="right ascension of v_inf in T"),
    "phase_angle_deg": Field("float", None, nullable=True, si="phase_angle_rad", to_si=DEG,
                             lo=0, hi=180, doc="Sun-body-spacecraft angle on approach"),
    "v_inf_km_s": Field("floats", None, nullable=True, length=3, si="v_inf_m_s", to_si=KM,
                        doc="v_inf in T at closest approach (instead of speed and angles)"),
    "before_km": Field("float", None, nullable=True, si="before_m", to_si=KM, lo=0,
                       lo_open=True, doc="imaging starts this far before closest approach"),
    "after_km": Field("float", None, nullable=True, si="after_m", to_si=KM, lo=0,
                      lo_open=True, doc="imaging ends this far after closest approach"),
    "before_s": Field("float", None, nullable=True, lo=0, lo_open=True),
    "after_s": Field("float", None, nullable=True, lo=0, lo_open=True),
}

_ANGLE_KEYS = (("speed_m_s", "speed_km_s"), ("approach_dec_rad", "approach_dec_deg"),
               ("approach_ra_rad", "approach_ra_deg"), ("phase_angle_rad", "phase_angle_deg"))


def check_encounter(fb, attitude) -> None:
    """Cross-checks of the encounter keys (one :class:`InputError` naming the field)."""
    if campaign_maneuver(attitude.maneuver).tracks_body:
        if fb.geometry != "encounter":
            raise InputError('body tracking needs flyby.geometry = "encounter"',
                             field="attitude.maneuver")
    if fb.geometry != "encounter":   # its keys set then: refused as not read (reads.py)
        return
    given = [key for si, key in _ANGLE_KEYS if getattr(fb, si) is not None]
    if fb.configuration != "ring":
        raise InputError("an encounter flies a ring perpendicular to v_inf: use 'ring'",
                         field="flyby.configuration")
    if fb.v_inf_m_s is not None and given:
        raise InputError(f"gives the approach already: drop flyby.{given[0]}",
                         field="flyby.v_inf_km_s")
    if fb.phase_angle_rad is not None and fb.approach_ra_rad is not None:
        raise InputError("fixes the right ascension: drop flyby.approach_ra_deg",
                         field="flyby.phase_angle_deg")
    for side in ("before", "after"):
        if getattr(fb, f"{side}_s") is not None and getattr(fb, f"{side}_m") is not None:
            raise InputError(f"give flyby.{side}_km or flyby.{side}_s, not both",
                             field=f"flyby.{side}_s")
