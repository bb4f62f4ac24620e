"""The ``[navigation]`` table of an encounter (SPEC 7f; issue 42 deliverables 2 and 3).

``preset`` (``"lutetia"``, ``"arrokoth"``, ``"dinkinesh"``: the real last-update
figures of :data:`ideas_hpc.flyby.navigation.PRESETS`, with their sources) or the
explicit 1-sigma figures ``bplane_major_km``, ``bplane_minor_km``, ``bplane_angle_deg``
(major axis from the B-plane's T axis toward R), ``tca_sigma_s`` and ``member_sigma_km``
(each member's own error per axis); explicit figures replace the preset's one by one.
``update`` says which update the errors belong to ("last ground update 2 days out").
Terminal tracking: ``terminal_pixels`` (lock on the measured centroid once the body
spans that many pixels of the instrument's IFOV; absent: body tracking aims at the
predicted target throughout) and ``centroid_sigma_deg`` (1-sigma per camera axis after
the lock). Read by encounters that fly dispersed samples (``campaign/schema/reads.py``);
the errors are drawn by the ``navigation`` dispersions
(:mod:`ideas_hpc.montecarlo.navigation_dispersion`).
"""

from __future__ import annotations

import dataclasses

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field
from ideas_hpc.base.units import DEG, KM
from ideas_hpc.campaign.schema.kinds import DISPERSION_KEYS
from ideas_hpc.campaign.schema.read_settings import Rule, not_listed
from ideas_hpc.flyby.navigation import PRESETS, NavigationError, NavigationPlan
from ideas_hpc.flyby.pass_rates import TerminalTracking

NAVIGATION = {
    "preset": Field("str", None, nullable=True, choices=tuple(PRESETS),
                    doc="a real last update's figures (flyby/navigation.py, cited there)"),
    "bplane_major_km": Field("float", None, nullable=True, si="bplane_major_m", to_si=KM,
                             lo=0, doc="B-plane 1-sigma semi-major axis"),
    "bplane_minor_km": Field("float", None, nullable=True, si="bplane_minor_m", to_si=KM,
                             lo=0, doc="B-plane 1-sigma semi-minor axis"),
    "bplane_angle_deg": Field("float", None, nullable=True, si="bplane_angle_rad", to_si=DEG,
                              lo=-360, hi=360, doc="major axis from T toward R"),
    "tca_sigma_s": Field("float", None, nullable=True, lo=0,
                         doc="1-sigma of the time of closest approach"),
    "member_sigma_km": Field("float", None, nullable=True, si="member_sigma_m", to_si=KM, lo=0,
                             doc="each member's own 1-sigma per axis"),
    "update": Field("str", None, nullable=True, doc="which update the errors belong to"),
    "terminal_pixels": Field("float", None, nullable=True, lo=0, lo_open=True,
                             doc="terminal tracking locks when the body spans this many "
                                 "pixels (absent: no terminal tracking)"),
    "centroid_sigma_deg": Field("float", 0.0, si="centroid_sigma_rad", to_si=DEG, lo=0, hi=10,
                                doc="1-sigma centroid pointing error per camera axis"),
}

#: NavigationError's parameters -> the table's keys (errors name the file's key).
NAVIGATION_FIELDS = {"sigma_major_m": "navigation.bplane_major_km",
                     "sigma_minor_m": "navigation.bplane_minor_km",
                     "theta_rad": "navigation.bplane_angle_deg",
                     "sigma_tca_s": "navigation.tca_sigma_s",
                     "sigma_member_m": "navigation.member_sigma_km"}


def given(nav) -> bool:
    """The typed ``[navigation]`` table sets anything (else: no navigation errors)."""
    return any(getattr(nav, f.name) != NAVIGATION[k].default
               for k, f in zip(NAVIGATION, dataclasses.fields(nav)))


def check_navigation(nav) -> None:
    """Cross-checks of a given table (one :class:`InputError` naming the key)."""
    if given(nav):
        navigation_error(nav)


def navigation_error(nav) -> NavigationError:
    """The table's :class:`~ideas_hpc.flyby.navigation.NavigationError` (SI)."""
    base = PRESETS[nav.preset] if nav.preset is not None else None
    if base is None and nav.bplane_major_m is None:
        raise InputError("give navigation.preset or navigation.bplane_major_km",
                         field="navigation.bplane_major_km")
    own = {"sigma_major_m": nav.bplane_major_m, "theta_rad": nav.bplane_angle_rad,
           "sigma_tca_s": nav.tca_sigma_s, "sigma_member_m": nav.member_sigma_m,
           "sigma_minor_m": nav.bplane_minor_m, "update": nav.update}
    own = {k: v for k, v in own.items() if v is not None}
    try:
        if base is None:
            own.setdefault("sigma_minor_m", own["sigma_major_m"])
            base = NavigationError(own["sigma_major_m"], own["sigma_minor_m"])
        return dataclasses.replace(base, **own)
    except InputError as exc:
        raise InputError(exc.message, field=NAVIGATION_FIELDS.get(exc.field, exc.field)) \
            from None


def navigation_plan(nav, diameter_m: float, ifov_rad: float) -> NavigationPlan | None:
    """The setup's :class:`~ideas_hpc.flyby.navigation.NavigationPlan`, or None without a
    table: the errors, and terminal tracking's lock range for a body of ``diameter_m``
    seen with ``ifov_rad``."""
    if not given(nav):
        return None
    rng = 0.0
    if nav.terminal_pixels is not None:
        rng = TerminalTracking(nav.terminal_pixels).detection_range_m(diameter_m, ifov_rad)
    return NavigationPlan(navigation_error(nav), rng, nav.centroid_sigma_rad)


def _why_navigation(s) -> str:
    if s.config.flyby.geometry == "paper":
        return ('is a navigation error of an encounter: set flyby.geometry = "encounter" '
                "(the paper's pass has no B-plane)")
    return not_listed(DISPERSION_KEYS)(s) + " (the navigation errors are drawn with them)"


#: Who reads a ``[navigation]`` key (:mod:`~ideas_hpc.campaign.schema.reads`): an
#: encounter's, drawn by the runs that fly dispersed samples.
NAVIGATION_RULES = {f"navigation.{k}": Rule(lambda s: s.config.flyby.geometry != "paper"
                                            and s.samples, _why_navigation)
                    for k in NAVIGATION}
