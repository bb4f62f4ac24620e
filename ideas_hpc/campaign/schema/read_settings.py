"""The machinery of :mod:`ideas_hpc.campaign.schema.reads`: what decides which keys a
campaign reads (:class:`Settings`: its typed config and its kind's registry entry), a
:class:`Rule`, and the registry's side (the keys each kind entry lists, who reads one).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ideas_hpc.attitude.maneuvers import campaign_maneuver
from ideas_hpc.attitude.modes import attitude_mode, attitude_start
from ideas_hpc.campaign.schema.kinds import DISPERSION_KEYS, KINDS
from ideas_hpc.design.api.methods import METHODS
from ideas_hpc.montecarlo.dispersions import dispersion_keys


@dataclass(frozen=True)
class Rule:
    """When a key is read: ``when(s)`` (``s``: :class:`Settings`) is true; else ``why(s)``
    is the refusal's message (after the file, line and key), which names the setting
    that ignores the key and the one that would read it."""

    when: Callable
    why: Callable


class Settings:
    """What decides the keys a campaign reads: its typed config (before the angle
    step is resolved) and its kind's registry entry."""

    def __init__(self, config, raw: dict):
        self.config, self.raw = config, raw
        self.kind = KINDS[config.kind]
        self.method = config.design.method
        self.own = expand(self.kind.reads_of(self.method))

    def lists(self, key: str) -> bool:
        """The entry that runs lists ``key`` among its own (``Kind.reads``)."""
        return key in self.own

    @property
    def runs(self) -> str:
        """``kind 'K'`` (with its ``design.method`` where the kind has several entries)."""
        return entry_name(self.kind, self.method)

    @property
    def maneuver(self):
        """The maneuver flown: the kind's own, else ``attitude.maneuver``."""
        return campaign_maneuver(self.kind.maneuver or self.config.attitude.maneuver)

    @property
    def attitude(self):
        """The registry entry of ``attitude.mode`` (:mod:`ideas_hpc.attitude.modes`)."""
        return attitude_mode(self.config.attitude.mode)

    @property
    def start(self):
        """The registry entry of ``monte_carlo.attitude_start``."""
        return attitude_start(self.config.monte_carlo.attitude_start)

    @property
    def simulated(self) -> bool:
        """The attitude flies a closed loop (``AttitudeMode.closed_loop``)."""
        return self.attitude.closed_loop

    @property
    def p(self) -> bool:
        """A success-probability design runs (``design.success_probability``, a kind and
        method that design for it)."""
        return (self.config.design.success_probability is not None
                and self.kind.success_probability and METHODS[self.method].success_probability)

    @property
    def samples(self) -> bool:
        """It flies dispersed samples: its entry lists the dispersions (a Monte Carlo kind,
        a design's verification or validation; ``design.verify_samples = 0`` turns the
        verification off, which the run says on its result line)."""
        return self.lists(DISPERSION_KEYS)


def expand(keys) -> frozenset:
    """``keys`` with every dispersion's keys (live) where :data:`DISPERSION_KEYS` is among
    them (the marker stays: ``Settings.lists(DISPERSION_KEYS)``)."""
    out = set(keys)
    if DISPERSION_KEYS in out:
        out |= {f"monte_carlo.{k}" for k in dispersion_keys()}
    return frozenset(out)


def entry_name(kind, method, *, method_too: bool = True) -> str:
    """``kind 'design-nadir' with design.method = 'exact'`` (the method only where the
    kind has entries by method)."""
    with_method = method_too and kind.methods
    return f"kind {kind.name!r}" + (f" with design.method = {method!r}" if with_method else "")


def readers(key: str) -> list[str]:
    """Every kind entry that lists ``key``: ``kind 'K'``, with the ``design.method`` values
    that read it where the kind's entries differ (``kind 'K' with design.method = 'm'``)."""
    out = []
    for kind in KINDS.values():
        listed = {m for m, *_ in kind.methods}
        methods = set()
        for method, reads in kind.entries():
            if key in expand(reads):
                methods |= {method} if method is not None else set(METHODS) - listed
        if methods and (not kind.methods or methods >= set(METHODS)):
            out.append(entry_name(kind, None, method_too=False))
        else:
            out += [entry_name(kind, m) for m in METHODS if m in methods]
    return out


def owned() -> frozenset:
    """Every key some kind entry lists (read live)."""
    return frozenset(k for kind in KINDS.values() for _, reads in kind.entries()
                     for k in expand(reads))


def not_listed(key: str) -> Callable:
    """The refusal of a key the running entry does not list: who does."""
    def why(s: Settings) -> str:
        who = readers(key)
        return (f"is ignored by {s.runs}" + (f"; it is read by {', '.join(who)}" if who else ""))
    return why


def set_keys(data: dict, schema: dict) -> list[str]:
    """The dotted keys a campaign's data sets, in file order: ``table.key`` in the tables,
    the key itself for a top-level value or a model's table (``controller``)."""
    out = []
    for key, value in (data or {}).items():
        if isinstance(schema.get(key), dict) and isinstance(value, dict):
            out += [f"{key}.{k}" for k in value]
        else:
            out.append(key)
    return out
