"""Sliding-mode controller gains and the paper's presets (SPEC section 5, Tables 5 and 6).

The two departures from SPEC section 5 that :class:`Gains` switches
(``phi_dt_max``, ``int_limit``) are explained in :mod:`ideas_hpc.attitude`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field, validate
from ideas_hpc.attitude.checks import vec3 as _vec3

#: The ``[controller]`` table: a preset and overrides; ranges are checked by
#: :func:`validate_gains` (vectors: a number or 3 numbers).
CONTROLLER_SCHEMA = {
    "preset": Field("str", None, nullable=True, doc="gain preset: np or fov"),
    "gains": Field("str", None, nullable=True, doc="alias of preset"),
    **{k: Field("any", None, nullable=True, doc="a number or 3 numbers")
       for k in ("k_p", "k_i", "eta", "phi")},
    **{k: Field("any", None, nullable=True, doc="positive number or 'inf'")
       for k in ("int_limit", "phi_dt_max")},
}


@dataclass(frozen=True)
class Gains:
    """Sliding-mode gains (SPEC section 5), per body axis.

    The physical gains carry their unit in the name; ``int_limit`` (an MRP
    norm) and ``phi_dt_max`` (the product ``eta phi dt``) are dimensionless
    and stay unitless. The ``[controller]`` keys are ``k_p``, ``k_i``, ``eta``,
    ``phi``, ``int_limit``, ``phi_dt_max`` (:data:`ideas_hpc.campaign.schema.model_fields.GAINS_FIELDS`).

    Attributes
    ----------
    k_p_per_s : tuple of 3 floats
        ``K_P``, 1/s.
    k_i_per_s2 : tuple of 3 floats
        ``K_I``, 1/s^2.
    eta_rad_per_s2 : float or tuple of 3 floats
        Reaching gain, rad/s^2.
    phi_s_per_rad : float or tuple of 3 floats
        Boundary-layer slope, s/rad.
    int_limit : float
        Dimensionless: the error integral accumulates only while
        ``|sigma_B/R| < int_limit`` (conditional integration, module docstring);
        ``inf`` = SPEC as written.
    phi_dt_max : float
        Dimensionless cap on ``eta phi dt`` for the sampled law (module
        docstring); ``inf`` = no cap.
    """

    k_p_per_s: tuple
    k_i_per_s2: tuple
    eta_rad_per_s2: float | tuple = 0.5
    phi_s_per_rad: float | tuple = 100.0
    int_limit: float = 0.005
    phi_dt_max: float = 1.0

    def arrays(self, dt: float):
        """``(k_p, k_i, eta, phi_eff)`` as (3,) float64 (``phi`` capped for ``dt``)."""
        k_p = np.broadcast_to(np.asarray(self.k_p_per_s, float), (3,)).copy()
        k_i = np.broadcast_to(np.asarray(self.k_i_per_s2, float), (3,)).copy()
        eta = np.broadcast_to(np.asarray(self.eta_rad_per_s2, float), (3,)).copy()
        phi = np.broadcast_to(np.asarray(self.phi_s_per_rad, float), (3,)).copy()
        if math.isfinite(self.phi_dt_max):
            with np.errstate(divide="ignore"):
                cap = np.where(eta > 0, self.phi_dt_max / (eta * dt), np.inf)
            phi = np.minimum(phi, cap)
        return k_p, k_i, eta, phi


#: Table 5 (NP) and Table 6 (FoV) of the paper.
GAIN_PRESETS = {
    "np": Gains(k_p_per_s=(0.4, 0.4, 0.4), k_i_per_s2=(0.01, 0.01, 0.01), eta_rad_per_s2=0.5,
                phi_s_per_rad=100.0),
    "fov": Gains(k_p_per_s=(4.0, 0.4, 0.4), k_i_per_s2=(1.0, 0.01, 0.01), eta_rad_per_s2=0.5,
                 phi_s_per_rad=100.0),
}
#: ``[controller]`` keys -> :class:`Gains` fields.
_FIELD_OF_KEY = {"k_p": "k_p_per_s", "k_i": "k_i_per_s2", "eta": "eta_rad_per_s2",
                 "phi": "phi_s_per_rad", "int_limit": "int_limit", "phi_dt_max": "phi_dt_max"}


def validate_gains(g: Gains) -> Gains:
    """Check a :class:`Gains`; raise :class:`InputError` naming its field (``k_p_per_s``)."""
    for name in ("k_p_per_s", "k_i_per_s2", "eta_rad_per_s2", "phi_s_per_rad"):
        _vec3(getattr(g, name), name)
    for key in ("int_limit", "phi_dt_max"):
        v = getattr(g, key)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v) or v <= 0:
            raise InputError(f"must be positive (inf allowed), got {v!r}", field=key)
    return g


def gains_from_config(table, prefix: str = "controller.") -> Gains:
    """Gains from a preset name (``'np'``, ``'fov'``) or a table.

    A table may name a ``preset`` (or ``gains``) and override ``k_p``, ``k_i``,
    ``eta``, ``phi`` (scalar or 3-vector), ``int_limit``, ``phi_dt_max``;
    without a preset all of ``k_p`` and ``k_i`` must be given. Any other key
    is an error naming it (``prefix + key``); a value :func:`validate_gains`
    refuses names the :class:`Gains` field, which the campaign layer maps to the
    file's key (:data:`ideas_hpc.campaign.schema.model_fields.GAINS_FIELDS`).
    """
    if table is None:
        return GAIN_PRESETS["np"]
    if isinstance(table, Gains):
        return validate_gains(table)
    if isinstance(table, str):
        if table not in GAIN_PRESETS:
            raise InputError(f"unknown gain preset {table!r}; known: {sorted(GAIN_PRESETS)}",
                             field=prefix + "preset")
        return GAIN_PRESETS[table]
    table = dict(table)
    validate(table, CONTROLLER_SCHEMA, prefix)  # keys and types: the one field mechanism
    pkey = "preset" if "preset" in table else ("gains" if "gains" in table else None)
    if pkey is not None:
        name = table[pkey]
        if name not in GAIN_PRESETS:
            raise InputError(f"unknown gain preset {name!r}; known: {sorted(GAIN_PRESETS)}",
                             field=prefix + pkey)
        base = GAIN_PRESETS[name]
    else:
        for key in ("k_p", "k_i"):
            if key not in table:
                raise InputError("missing (give it or name a preset: 'np', 'fov')",
                                 field=prefix + key)
        base = GAIN_PRESETS["np"]
    kw = {}
    for key in ("k_p", "k_i", "eta", "phi"):
        if key in table:
            v = _vec3(table[key], prefix + key)
            kw[_FIELD_OF_KEY[key]] = v if key in ("k_p", "k_i") or len(set(v)) > 1 else v[0]
    for key in ("int_limit", "phi_dt_max"):
        if key in table:
            v = table[key]
            if isinstance(v, str) and v.lower() in ("inf", "none", "off"):
                v = math.inf
            kw[_FIELD_OF_KEY[key]] = v
    return validate_gains(replace(base, **kw))
