"""Disturbance torques on the spacecraft, declared as settings objects (as the force terms).

A term is a frozen dataclass that checks its fields in ``__post_init__``
(:class:`~ideas_hpc.base.errors.InputError` naming the field) and adds its torque,
in the body frame B (N m), to the step table in ``_pack(table, ctx)``:
``table`` is ``(N, n_steps + 1, 3)`` (spacecraft, step ``k`` at ``t = k dt``,
component), ``ctx`` a :class:`TorqueContext`. :func:`pack_torques` sums the
terms of a flight into the table that
:func:`~ideas_hpc.core.attitude.batch.simulate_batch` reads as ``L_ext``
(``StepTables.torque_B_N_m``), held over each step of the closed loop; the
controller is not told it. :data:`TORQUE_TERMS` lists the terms by name.

A term that depends only on time and on the spacecraft (a comet's outgassing
jet, a thruster misalignment, a solar torque for a fixed attitude) is one
class here, or in any module that adds it to :data:`TORQUE_TERMS`: no kernel
changes. A term that depends on the flown attitude (gravity gradient) needs a
kernel in ``core/attitude`` and a branch in ``simulate_batch``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ideas_hpc.base.errors import InputError


class TorqueContext(NamedTuple):
    """What a torque term may read when it fills its table."""

    #: (N,) swarm angles, rad.
    theta_rad: np.ndarray
    #: (n_steps + 1,) step times from the start of the attitude run, s.
    times_s: np.ndarray
    #: Target spin rate about +z_T, rad/s.
    spin_rate_rad_s: float


@dataclass(frozen=True)
class ConstantTorque:
    """The same body-frame torque on every spacecraft at all times (N m): a steady
    outgassing jet or a misaligned thruster."""

    torque_B_N_m: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        try:
            v = np.asarray(self.torque_B_N_m, dtype=np.float64)
        except (TypeError, ValueError):
            v = np.full(1, np.nan)
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise InputError(f"must be 3 finite numbers (N m), got {self.torque_B_N_m!r}",
                             field="torque_B_N_m")
        object.__setattr__(self, "torque_B_N_m", tuple(float(x) for x in v))

    def _pack(self, table, ctx: TorqueContext) -> None:
        table += np.asarray(self.torque_B_N_m)


#: The torque terms by name (a flight takes instances: ``FlybySetup.torques``,
#: ``simulate_attitude(torques=...)``).
TORQUE_TERMS: dict[str, type] = {"constant": ConstantTorque}


def pack_torques(terms, theta_rad, n_steps: int, dt_s: float,
                 spin_rate_rad_s: float) -> np.ndarray:
    """The summed disturbance torque ``(N, n_steps + 1, 3)`` in B (N m) of ``terms``;
    ``(N, 0, 3)`` (read as none, and no cost per step) when there are none."""
    th = np.ascontiguousarray(theta_rad, dtype=np.float64)
    if not terms:
        return np.empty((th.size, 0, 3))
    table = np.zeros((th.size, int(n_steps) + 1, 3))
    ctx = TorqueContext(th, np.arange(int(n_steps) + 1) * float(dt_s), float(spin_rate_rad_s))
    for term in terms:
        if not callable(getattr(term, "_pack", None)):
            raise InputError(f"{term!r} is not a torque term (no _pack)", field="torques")
        term._pack(table, ctx)
    if not np.all(np.isfinite(table)):
        raise InputError("the disturbance torque is not finite", field="torques")
    return np.ascontiguousarray(table)


def torques_from_config(table: dict | None, prefix: str = "torques.") -> tuple:
    """Torque terms from a table ``{name: {parameter: value}}`` of :data:`TORQUE_TERMS`
    names (read live); errors name ``<prefix><name>[.<parameter>]``."""
    out = []
    for name, params in (table or {}).items():
        cls = TORQUE_TERMS.get(name)
        if cls is None:
            raise InputError(f"unknown torque term {name!r}; one of "
                             f"{', '.join(sorted(TORQUE_TERMS))}", field=f"{prefix}{name}")
        if not isinstance(params, dict):
            raise InputError(f"must be a table of the term's parameters, got {params!r}",
                             field=f"{prefix}{name}")
        known = {f.name for f in dataclasses.fields(cls)}
        for key in params:
            if key not in known:
                raise InputError(f"unknown parameter; allowed: {', '.join(sorted(known))}",
                                 field=f"{prefix}{name}.{key}")
        try:
            out.append(cls(**params))
        except InputError as e:
            raise InputError(e.message, field=f"{prefix}{name}.{e.field}" if e.field
                             else f"{prefix}{name}") from None
    return tuple(out)
