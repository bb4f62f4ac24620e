"""The navigation dispersions of an encounter (SPEC 7f): draws of the two
:data:`~ideas_hpc.montecarlo.dispersions.DISPERSIONS` entries ``navigation`` and
``navigation_member``.

``navigation`` (``level="body"``: once per scenario, shared by every candidate) draws the
target's B-plane offset and TCA shift (:func:`~ideas_hpc.flyby.navigation.draw_common`, 3
normals) and turns them into the true target's offset ``delta`` from the predicted one at
the predicted TCA, in the encounter's frame N (:func:`~ideas_hpc.flyby.navigation.target_offset_N`,
along-track part ``|v| dt S`` included; the B-plane's reference pole is +z of N, the spin
pole, as N = T at closest approach). ``navigation_member`` (``level="spacecraft"``) draws
each member's own error (3 normals a member) and its terminal-tracking centroid error (3
normals a member: the x_B and y_B components of a small rotation; the z_B one, about the
boresight, is zeroed). Both always draw, with or without a ``[navigation]`` table (zeros
then), so switching navigation on shifts no other draw; the flight applies them through
:mod:`ideas_hpc.flyby.nav_flight`. The sigmas come from ``FlybySetup.navigation``
(the campaign's ``[navigation]`` table), not from ``[monte_carlo]``.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.engine.variables import StoreVar
from ideas_hpc.flyby.navigation import (NavigationDraw, NavigationError, draw_common as _common,
                                        draw_members, target_offset_N)

#: No navigation: the draws are made, scaled by zero.
_NONE = NavigationError(0.0, 0.0)

COMMON_VARS = (
    StoreVar("nav_xi", (), np.float64, "m", "target B-plane offset along T (navigation)"),
    StoreVar("nav_eta", (), np.float64, "m", "target B-plane offset along R (navigation)"),
    StoreVar("nav_dt_tca", (), np.float64, "s", "shift of the time of closest approach "
                                                "(navigation; positive: later)"),
    StoreVar("target_offset", ("axis",), np.float64, "m", "true target minus predicted at "
             "the predicted closest approach, encounter frame N (navigation)"))
MEMBER_VARS = (
    StoreVar("member_offset", ("spacecraft", "axis"), np.float64, "m",
             "member's own navigation error at closest approach, encounter frame N"),
    StoreVar("centroid_prv", ("spacecraft", "axis"), np.float64, "rad",
             "terminal-tracking centroid pointing error (PRV in B, no z_B part)"))


def _plan(setup):
    return getattr(setup, "navigation", None)


def applies(setup) -> bool:
    """A flight reads the navigation draws when its setup has a ``[navigation]`` table."""
    return _plan(setup) is not None


def common_active(mc, setup) -> bool:
    p = _plan(setup)
    return p is not None and (p.error.sigma_major_m, p.error.sigma_minor_m,
                              p.error.sigma_tca_s) != (0.0, 0.0, 0.0)


def member_active(mc, setup) -> bool:
    p = _plan(setup)
    return p is not None and (p.error.sigma_member_m != 0.0 or (
        p.detect_range_m > 0.0 and p.centroid_sigma_rad != 0.0))


def draw_common(rng, n, mc, setup, theta) -> dict:
    """``navigation``'s values: 3 normals, always (module docstring)."""
    p = _plan(setup)
    xi, eta, dt = _common(_NONE if p is None else p.error, rng)
    enc = getattr(setup, "encounter", None)
    if enc is None:
        off = np.zeros(3)
    else:
        off = target_offset_N(NavigationDraw(xi, eta, dt, np.zeros((0, 3))), enc.v_inf_T)
    return {"nav_xi": xi, "nav_eta": eta, "nav_dt_tca": dt, "target_offset": off}


def draw_member(rng, n, mc, setup, theta) -> dict:
    """``navigation_member``'s values: ``3 n`` normals for the members' own errors, then
    ``3 n`` for the centroid errors, always (module docstring)."""
    p = _plan(setup)
    own = draw_members(_NONE if p is None else p.error, rng, n)
    sigma = 0.0 if p is None or p.detect_range_m <= 0.0 else p.centroid_sigma_rad
    centroid = rng.standard_normal((int(n), 3)) * sigma
    centroid[:, 2] = 0.0
    return {"member_offset": own, "centroid_prv": centroid}
