"""Registry of attitude maneuvers (SPEC section 5).

A maneuver is a reference attitude the controller tracks. Each entry names
the compiled kernels' mode code (:mod:`ideas_hpc.core.attitude.maneuvers`), the
controller gains preset it uses by default (:data:`~ideas_hpc.attitude.gains.GAIN_PRESETS`)
and how its parameters are checked and packed for the kernels. The kernels
take the same two parameters for every maneuver: one period per spacecraft
(s) and one amplitude for the swarm (rad); a maneuver without them gets ones
and zero.

An entry also declares what a campaign needs to fly it: its name in campaign
files and stores (``key``: ``attitude.maneuver`` and the store's ``maneuver``
attr), whether it needs one sweep period per spacecraft (``sweeps``) and its
camera half-angle as a fraction of the nadir half cone (``fov_factor``). The
flyby setup carries the :class:`Maneuver` itself, so no layer above compares
maneuver names.

Adding a maneuver (CONTRIBUTING.md, "A new attitude maneuver"): write its
kernels in ``core/maneuvers.py`` (unless it reuses a mode code) and add one
:class:`Maneuver` to :data:`MANEUVERS` below. The orchestration
(:func:`~ideas_hpc.attitude.simulate_attitude`,
:func:`~ideas_hpc.attitude.ideal_dcm_BT`) and the campaign schema read only this table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ideas_hpc.core.attitude.maneuvers import FOV_MODE, NP_MODE, TRACK_MODE
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.units import MINUTE
from ideas_hpc.base.fields import number

P_MIN_DEFAULT = 0.3 * MINUTE  #: paper: P_min = 0.3 min/sweep, s
THETA_MAX_DEFAULT = math.radians(1.9138)  #: SPEC section 2 / Table 6, rad


def _no_params(n, periods, theta_max, p_min):
    """Maneuvers without parameters: unit periods and zero amplitude (unused by the kernel)."""
    return np.ones(n), 0.0


def _sweep_params(n, periods, theta_max, p_min):
    """FoV sweep: one period per spacecraft (>= ``p_min``, s) and the amplitude (rad)."""
    if periods is None:
        raise InputError("FoV sweeping needs one sweep period per spacecraft (s)",
                         field="periods")
    p = np.broadcast_to(np.asarray(periods, dtype=np.float64), (n,)).copy() \
        if np.ndim(periods) == 0 else np.asarray(periods, dtype=np.float64)
    if p.shape != (n,):
        raise InputError(f"must have one period per spacecraft ({n}), got shape {p.shape}",
                         field="periods")
    pm = number(p_min, "p_min", lo=0.0, lo_open=True)
    if not np.all(np.isfinite(p)) or np.any(p < pm * (1 - 1e-12)):
        raise InputError(f"sweep periods must be >= P_min = {pm} s, got min {np.min(p)!r} s",
                         field="periods")
    tm = THETA_MAX_DEFAULT if theta_max is None else number(theta_max, "theta_max", lo=0.0)
    return p, tm


@dataclass(frozen=True)
class Maneuver:
    """One attitude maneuver.

    Attributes
    ----------
    name : str
        Name used by ``simulate_attitude(mode=...)`` and the ``mode`` attr of results.
    code : int
        Mode code of its kernels in :mod:`ideas_hpc.core.attitude.maneuvers`.
    gains : str
        Default gains preset (key of ``GAIN_PRESETS``).
    params : callable
        ``params(n, periods, theta_max, p_min) -> (periods (n,) s, theta_max rad)``:
        checks the maneuver's parameters (``InputError`` naming the field) and
        packs them for the kernels.
    description : str
    key : str
        Name in campaign files (``attitude.maneuver``) and in the store's
        ``maneuver`` attr; ``""``: ``name``.
    sweeps : bool
        Needs one sweep period per spacecraft (``swarm.sweep_periods_min``).
    fov_factor : float
        Camera half-angle over the nadir half cone ``eta_N`` of the sizing
        (SPEC section 2; FoV sweeping images with half the cone).
    tracks_body : bool
        The camera follows the body centre along the flown positions
        (encounter geometry): ideal attitude is
        :func:`ideas_hpc.flyby.encounter.track_dcms`, simulated attitude reads a
        reference table built from the track (``code`` ``TRACK_MODE``,
        :func:`ideas_hpc.flyby.encounter.track_reference`).
    figures : tuple of (str, int)
        The paper's figure numbers of its report figures (``"pyramids"``: camera
        pyramids, ``"attitude"``: first of the four attitude series); others are
        numbered as nadir pointing's.
    """

    name: str
    code: int
    gains: str
    # the function's repr holds its address, which differs between processes; a
    # maneuver is identified by its data (reprs of setups feed config hashes)
    params: Callable = field(repr=False)
    description: str = ""
    key: str = ""
    sweeps: bool = False
    fov_factor: float = 1.0
    tracks_body: bool = False
    figures: tuple = ()

    def figure(self, what: str, default: int) -> int:
        """The paper's number of report figure ``what``, or ``default``."""
        return dict(self.figures).get(what, default)

    @property
    def campaign_name(self) -> str:
        """The name in campaign files and stores."""
        return self.key or self.name

    def half_angle(self, eta_nadir: float) -> float:
        """Camera half-angle (rad) for the nadir half cone ``eta_nadir`` (rad)."""
        return self.fov_factor * eta_nadir

    def swarm_periods(self, sweep_periods_s):
        """The sweep periods (s) to fly, ``(N,)`` array, or ``None`` when it does not sweep."""
        return np.asarray(sweep_periods_s) if self.sweeps else None


#: The maneuvers, by name. Paper: Nadir Pointing (Table 5 gains) and FoV Sweeping
#: (eqs. 20-24, Table 6 gains).
MANEUVERS = {m.name: m for m in (
    Maneuver("np", NP_MODE, "np", _no_params, "Nadir Pointing: camera along the ring -z axis",
             key="nadir", figures=(("pyramids", 24), ("attitude", 26))),
    Maneuver("fov", FOV_MODE, "fov", _sweep_params,
             "FoV Sweeping: theta_max sin(2 pi t / P_i) about the ring x axis",
             sweeps=True, fov_factor=0.5, figures=(("pyramids", 33), ("attitude", 34))),
    Maneuver("track", TRACK_MODE, "np", _no_params,
             "Body tracking: boresight on the body centre along the flown track (encounters)",
             tracks_body=True),
)}


class _CampaignNames:
    """The campaign names of :data:`MANEUVERS`, read live (schema choices)."""

    def __contains__(self, key) -> bool:
        return any(m.campaign_name == key for m in MANEUVERS.values())

    def __iter__(self):
        return iter([m.campaign_name for m in MANEUVERS.values()])


#: ``attitude.maneuver`` choices: follows :data:`MANEUVERS`, including entries added later.
CAMPAIGN_NAMES = _CampaignNames()


def store_figure(maneuver_attr, what: str, default: int) -> int:
    """Report figure number ``what`` for a store whose ``maneuver`` attr is ``maneuver_attr``."""
    for m in MANEUVERS.values():
        if m.campaign_name == maneuver_attr:
            return m.figure(what, default)
    return default


def campaign_maneuver(key: str) -> Maneuver:
    """The :class:`Maneuver` whose campaign name is ``key``; else an ``InputError`` naming
    ``maneuver`` (the campaign layer maps it to ``attitude.maneuver``)."""
    for m in MANEUVERS.values():
        if m.campaign_name == key:
            return m
    raise InputError(f"must be one of {', '.join(CAMPAIGN_NAMES)}; got {key!r}", field="maneuver")


def get_maneuver(mode) -> Maneuver:
    """The registered :class:`Maneuver` called ``mode``; ``InputError`` naming ``mode`` if none."""
    if mode not in MANEUVERS:
        known = ", ".join(repr(k) for k in MANEUVERS)
        raise InputError(f"must be one of {known}, got {mode!r}", field="mode")
    return MANEUVERS[mode]


def maneuver_args(mode, n, periods, theta_max, p_min, *, from_track: bool = False):
    """``(maneuver, periods (n,) s, theta_max rad)`` for the kernels, checked.

    A body-tracking maneuver needs its reference from the flown track
    (``from_track``: the caller passes the reference table)."""
    m = get_maneuver(mode)
    if m.tracks_body and not from_track:
        raise InputError(f"maneuver {mode!r} has no reference of its own: it follows the "
                         "flown track (give the track's reference table)", field="mode")
    p, tm = m.params(n, periods, theta_max, p_min)
    return m, p, tm
