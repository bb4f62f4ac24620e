"""Registry of attitude maneuvers (SPEC section 5).

A maneuver is a reference attitude the controller tracks. Each entry names
the compiled kernels' mode code (:mod:`ideas_hpc.core.maneuvers`), the
controller gains preset it uses by default (:data:`~ideas_hpc.attitude.gains.GAIN_PRESETS`)
and how its parameters are checked and packed for the kernels. The kernels
take the same two parameters for every maneuver: one period per spacecraft
(s) and one amplitude for the swarm (rad); a maneuver without them gets ones
and zero.

Adding a maneuver (CONTRIBUTING.md, "A new attitude maneuver"): write its
kernels in ``core/maneuvers.py`` and add one :class:`Maneuver` to
:data:`MANEUVERS` below. The orchestration (:func:`~ideas_hpc.attitude.simulate_attitude`,
:func:`~ideas_hpc.attitude.ideal_dcm_BT`) reads only this table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..core.maneuvers import FOV_MODE, NP_MODE
from ..errors import InputError
from ..units import MINUTE
from .checks import pos_float as _pos_float

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
    pm = _pos_float(p_min, "p_min")
    if not np.all(np.isfinite(p)) or np.any(p < pm * (1 - 1e-12)):
        raise InputError(f"sweep periods must be >= P_min = {pm} s, got min {np.min(p)!r} s",
                         field="periods")
    tm = THETA_MAX_DEFAULT if theta_max is None else _pos_float(theta_max, "theta_max",
                                                                allow_zero=True)
    return p, tm


@dataclass(frozen=True)
class Maneuver:
    """One attitude maneuver.

    Attributes
    ----------
    name : str
        Name used by ``simulate_attitude(mode=...)`` and the ``mode`` attr of results.
    code : int
        Mode code of its kernels in :mod:`ideas_hpc.core.maneuvers`.
    gains : str
        Default gains preset (key of ``GAIN_PRESETS``).
    params : callable
        ``params(n, periods, theta_max, p_min) -> (periods (n,) s, theta_max rad)``:
        checks the maneuver's parameters (``InputError`` naming the field) and
        packs them for the kernels.
    description : str
    """

    name: str
    code: int
    gains: str
    params: Callable
    description: str = ""


#: The maneuvers, by name. Paper: Nadir Pointing (Table 5 gains) and FoV Sweeping
#: (eqs. 20-24, Table 6 gains).
MANEUVERS = {m.name: m for m in (
    Maneuver("np", NP_MODE, "np", _no_params, "Nadir Pointing: camera along the ring -z axis"),
    Maneuver("fov", FOV_MODE, "fov", _sweep_params,
             "FoV Sweeping: theta_max sin(2 pi t / P_i) about the ring x axis"),
)}


def get_maneuver(mode) -> Maneuver:
    """The registered :class:`Maneuver` called ``mode``; ``InputError`` naming ``mode`` if none."""
    if mode not in MANEUVERS:
        known = ", ".join(repr(k) for k in MANEUVERS)
        raise InputError(f"must be one of {known}, got {mode!r}", field="mode")
    return MANEUVERS[mode]


def maneuver_args(mode, n, periods, theta_max, p_min):
    """``(maneuver, periods (n,) s, theta_max rad)`` for the kernels, checked."""
    m = get_maneuver(mode)
    p, tm = m.params(n, periods, theta_max, p_min)
    return m, p, tm
