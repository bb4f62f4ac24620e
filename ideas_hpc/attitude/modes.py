"""Registries of the attitude mode and of the attitude start, each entry with its
capabilities (issue 40; SPEC sections 5 and 7d).

``attitude.mode`` (:data:`ATTITUDE_MODES`) says how the camera follows its
maneuver's reference: perfectly (``ideal``) or through the reaction-wheel closed
loop (``simulated``). ``monte_carlo.attitude_start`` (:data:`ATTITUDE_STARTS`)
says where that closed loop starts (docs/attitude-start.md): on the reference
with knowledge and control errors (``reference``), from the paper's random
attitude flown for an acquisition phase before the window (``acquisition``), or
from that random attitude at the window's start (``paper``).

The flyby, the candidates, the scenario bank, the dispersions and the campaign
read an entry's capabilities (``closed_loop``; ``random_state``,
``acquisition``, ``nominal_random``, ``usable_images``) and never compare its
name, so a new mode or start is one entry here (``tests/test_layers.py`` fails on
a comparison with a registered name outside this module). The setups and stores
keep the names (``FlybySetup.attitude_mode``, ``FlybySetup.attitude_start``, the
``attitude_mode`` attr), so config hashes and older stores do not change.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError


@dataclass(frozen=True)
class AttitudeMode:
    """One attitude mode.

    Attributes
    ----------
    name : str
        Its name in campaign files (``attitude.mode``), setups and stores.
    closed_loop : bool
        The camera is flown by the closed-loop reaction-wheel attitude (sliding
        mode, SPEC section 5) from an initial state; False: it is the maneuver's
        reference frame at every image (perfect tracking, no initial state).
    doc : str
    """

    name: str
    closed_loop: bool
    doc: str = ""


@dataclass(frozen=True)
class AttitudeStart:
    """One attitude start of the closed loop (SPEC 7d, docs/attitude-start.md).

    Attributes
    ----------
    name : str
        Its name in campaign files (``monte_carlo.attitude_start``) and setups.
    random_state : bool
        A dispersed start draws the paper's random attitude, rates and wheel
        speeds (:func:`ideas_hpc.attitude.draw_initial_conditions`); False: errors
        about the reference flown (``sigma_B/R``, ``omega_B/R``, wheels at rest).
    acquisition : bool
        The loop first flies ``monte_carlo.acquisition_s`` from that state before
        the window (``simulate_attitude(acquisition_s=...)``).
    nominal_random : bool
        A flight without a drawn state (the nominal flight, the designers'
        candidates) starts from the seeded random state of its sample
        (:func:`ideas_hpc.attitude.initial_conditions`); False: exactly on the reference.
    usable_images : bool
        Images are tested for smear and settling (:mod:`ideas_hpc.flyby.usable`);
        False: every image counts (the paper's start).
    doc : str
    """

    name: str
    random_state: bool
    acquisition: bool
    nominal_random: bool
    usable_images: bool
    doc: str = ""


#: The attitude modes, by name (``attitude.mode`` choices, read live).
ATTITUDE_MODES: dict[str, AttitudeMode] = {m.name: m for m in (
    AttitudeMode("ideal", closed_loop=False,
                 doc="perfect tracking: the camera frame is the reference frame at every image"),
    AttitudeMode("simulated", closed_loop=True,
                 doc="closed-loop reaction-wheel attitude with the sliding-mode controller"),
)}

#: The attitude starts, by name (``monte_carlo.attitude_start`` choices, read live).
ATTITUDE_STARTS: dict[str, AttitudeStart] = {s.name: s for s in (
    AttitudeStart("reference", random_state=False, acquisition=False, nominal_random=False,
                  usable_images=True,
                  doc="on the reference with knowledge and control errors"),
    AttitudeStart("acquisition", random_state=True, acquisition=True, nominal_random=False,
                  usable_images=True,
                  doc="closed loop from a random attitude for acquisition_s before the window"),
    AttitudeStart("paper", random_state=True, acquisition=False, nominal_random=True,
                  usable_images=False,
                  doc="random attitude at the window's start (paper Figs. 26-29)"),
)}


def attitude_mode(name: str) -> AttitudeMode:
    """The registered :class:`AttitudeMode` called ``name``; else an ``InputError``
    naming ``attitude_mode``."""
    return _entry(ATTITUDE_MODES, name, "attitude_mode")


def attitude_start(name: str) -> AttitudeStart:
    """The registered :class:`AttitudeStart` called ``name``; else an ``InputError``
    naming ``attitude_start``."""
    return _entry(ATTITUDE_STARTS, name, "attitude_start")


def _entry(registry: dict, name, field: str):
    try:
        return registry[name]
    except (KeyError, TypeError):
        raise InputError(f"must be one of {', '.join(registry)}, got {name!r}",
                         field=field) from None


def perfect_tracking() -> str:
    """The name of the mode without a closed loop (the bank's nominal flight flies it)."""
    return next(m.name for m in ATTITUDE_MODES.values() if not m.closed_loop)


def undrawn_start(start: str, n: int, random_state) -> tuple[tuple, str]:
    """Where a closed loop without a drawn initial state starts (SPEC 7d): the one rule of
    the nominal flight, the designers' candidates and a flyby's own start.

    ``start`` names an :class:`AttitudeStart`; ``random_state()`` returns the seeded
    random ``(sigma_BN, omega_BN_B, wheels)`` (N, 3) of the flight's sample(s). Returns
    ``((sigma, omega, wheels), start word of simulate_attitude)``: that random state,
    ``"absolute"``, when the start's ``nominal_random``; else zero errors about the
    reference flown, ``"reference"`` (exactly on it).
    """
    if attitude_start(start).nominal_random:
        return tuple(random_state()), "absolute"
    return tuple(np.zeros((int(n), 3)) for _ in range(3)), "reference"
