"""Frozen settings of the closed-loop attitude simulation (issue 30): the run's
times, the pointing, the spacecraft model and the initial state, each a
record whose field names carry their units.

:func:`~ideas_hpc.attitude.simulate.simulate_attitude` reads these; its older
keyword call (``dt=0.1, image_dt=0.2, mode="np", sigma0=...``) is mapped onto
them by :func:`from_keywords`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from ideas_hpc.attitude.maneuvers import P_MIN_DEFAULT


@dataclass(frozen=True)
class AttitudeRun:
    """Times and samples: ``t_f_s`` duration (a multiple of ``dt_s``), ``dt_s`` the
    integration and control step, ``image_dt_s`` the image period, every
    ``decimate``-th step kept; ``n_samples`` initial states drawn from ``seed``
    when none is given; ``start`` 'absolute' or 'reference' and ``acquisition_s``
    (see :func:`~ideas_hpc.attitude.simulate.simulate_attitude`)."""

    t_f_s: float | None = None
    dt_s: float = 0.1
    image_dt_s: float = 0.2
    decimate: int = 1
    seed: int = 0
    n_samples: int = 1
    start: str = "absolute"
    acquisition_s: float = 0.0


@dataclass(frozen=True)
class Pointing:
    """The maneuver flown: ``mode`` (a :data:`~ideas_hpc.attitude.maneuvers.MANEUVERS`
    name), the sweep periods ``periods_s`` and amplitude ``theta_max_rad`` and
    least period ``p_min_s`` (FoV sweeping), the swarm frame ``dcm_TS`` and the
    body-tracking reference table ``ref_table``."""

    mode: str = "np"
    periods_s: Any = None
    theta_max_rad: float | None = None
    p_min_s: float = P_MIN_DEFAULT
    dcm_TS: Any = None
    ref_table: Any = None


@dataclass(frozen=True)
class AttitudeModel:
    """Controller gains (a ``Gains``, preset name or table; None: the mode's preset),
    the spacecraft (None: the default) and the disturbance torque terms."""

    gains: Any = None
    spacecraft: Any = None
    torques: tuple = ()


@dataclass(frozen=True)
class InitialState:
    """``sigma_BN`` (MRP), ``omega_BN_B_rad_s`` and ``wheel_rad_s``, each (S, N, 3)
    or (N, 3); all three given together."""

    sigma_BN: Any = None
    omega_BN_B_rad_s: Any = None
    wheel_rad_s: Any = None

    def arrays(self):
        return self.sigma_BN, self.omega_BN_B_rad_s, self.wheel_rad_s


#: The older keyword names -> (record, field).
_KEYWORDS = {
    "dt": ("run", "dt_s"), "image_dt": ("run", "image_dt_s"), "decimate": ("run", "decimate"),
    "seed": ("run", "seed"), "n_samples": ("run", "n_samples"), "start": ("run", "start"),
    "acquisition_s": ("run", "acquisition_s"),
    "mode": ("pointing", "mode"), "periods": ("pointing", "periods_s"),
    "theta_max": ("pointing", "theta_max_rad"), "p_min": ("pointing", "p_min_s"),
    "dcm_TS": ("pointing", "dcm_TS"), "ref_table": ("pointing", "ref_table"),
    "gains": ("model", "gains"), "spacecraft": ("model", "spacecraft"),
    "torques": ("model", "torques"),
    "sigma0": ("state0", "sigma_BN"), "omega0": ("state0", "omega_BN_B_rad_s"),
    "wheel0": ("state0", "wheel_rad_s"),
}


def from_keywords(t_f, run, pointing, model, state0, keywords: dict):
    """``(run, pointing, model, state0)``: the records given, completed by the older
    keywords (a keyword overrides the record's field)."""
    recs = {"run": run or AttitudeRun(), "pointing": pointing or Pointing(),
            "model": model or AttitudeModel(), "state0": state0 or InitialState()}
    edits: dict = {k: {} for k in recs}
    for key, value in keywords.items():
        if key not in _KEYWORDS:
            raise TypeError(f"simulate_attitude() got an unexpected keyword argument {key!r}")
        rec, name = _KEYWORDS[key]
        edits[rec][name] = value
    if t_f is not None:
        edits["run"]["t_f_s"] = t_f
    out = {k: replace(r, **edits[k]) if edits[k] else r for k, r in recs.items()}
    return out["run"], out["pointing"], out["model"], out["state0"]


__all__ = ["AttitudeRun", "Pointing", "AttitudeModel", "InitialState", "from_keywords"]
