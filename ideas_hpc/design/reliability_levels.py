"""The fewest N as a function of an uncertain p_f (issue 41): "N = 5 for p_f <= 0.05, 6 up to 0.08".

With p_f uncertain (:class:`~ideas_hpc.failures.prior.Prior`) the design meets p on
average over the prior. A mission also wants to know how the answer moves with p_f:
:func:`n_at_levels` designs the bank again with p_f *known* at each of the prior's
levels (its quantiles, or its values), each with its own proofs
(:func:`~ideas_hpc.design.reliability.settle`). The bounds on ``U_m`` and the
per-scenario failure-tolerance proofs do not depend on p_f and are shared
(:func:`with_model`).

Why one answer covers an interval: every member's survival probability falls as p_f
rises (``1 - (1 - beta) p_f`` and ``1 - beta p_f``), coverage is monotone, so each
swarm's P is nonincreasing in p_f. A swarm meeting p at ``p_f = x`` meets it for every
``p_f <= x``, and a size proven short at x is short for every ``p_f >= x``.
"""

from __future__ import annotations

from dataclasses import dataclass

import time

import numpy as np

from ideas_hpc.base import progress
from ideas_hpc.base.errors import InputError
from ideas_hpc.design.reliability import ReliabilityDesigner, settle
from ideas_hpc.design.reliability_eval import Evaluator
from ideas_hpc.failures.model import as_model


@dataclass(frozen=True)
class LevelAnswer:
    """The design at one known p_f: ``n`` (0: none of at most n_max meets p), its P on the
    bank, the proven lower bound on N, the status, and the swarm (grid indices)."""

    p_f: float
    label: str
    n: int
    probability: float
    bound: float
    status: str
    indices: np.ndarray


def with_model(designer: ReliabilityDesigner, model, time_limit: float | None = None):
    """A designer of ``designer``'s bank under another failure model: the bounds on ``U_m``
    (programme, ring-gap bounds, screen matrices) and the per-scenario tolerance proofs do
    not depend on the model and are shared; the swarms found and the sizes settled are its
    own, and so is its deadline."""
    other = object.__new__(type(designer))
    other.__dict__.update(designer.__dict__)
    other.ev = Evaluator(designer.ev.rows, designer.ev.w, designer.ev.need, model)
    other.model = as_model(model)
    other.t0 = time.perf_counter()
    other.deadline = None if time_limit is None else other.t0 + float(time_limit)
    other.best, other.exhausted, other.exhausted_upper = {}, set(), {}
    other.settled = False
    other.tol_proved, other.screen_proved, other.screen_found = set(), set(), set()
    return other


def n_at_levels(designer, p: float, n_max: int, levels, time_limit_s: float | None = None):
    """:class:`LevelAnswer` at each ``(p_f, label)`` of ``levels`` (increasing), each design
    on ``designer``'s bank with the failure model at that p_f and its share of the time."""
    out = []
    share = None if time_limit_s is None else float(time_limit_s) / max(1, len(levels))
    for p_f, label in levels:
        progress.note(f"success-probability design at p_f = {p_f:.4g} ({label})")
        d = with_model(designer, designer.model.at(p_f), time_limit=share)
        try:
            r = settle(d, p, n_max)
        except InputError:
            out.append(LevelAnswer(float(p_f), label, 0, 0.0, float(n_max) + 1, "unreached",
                                   np.zeros(0, np.int64)))
            continue
        out.append(LevelAnswer(float(p_f), label, int(r.n), float(r.probability),
                               float(r.bound), r.status, np.asarray(r.indices)))
    return out


def levels_line(answers, p: float) -> str:
    """One line: the fewest N found at each level, then where each N suffices
    (module docstring: a swarm meeting p at p_f also meets it below)."""
    if not answers:
        return ""
    parts = []
    for a in answers:
        what = ("none of at most n_max" if a.n == 0 else
                f"N = {a.n} ({a.status}" + ("" if a.status == "optimal" else
                                           f", proven >= {a.bound:g}") + ")")
        parts.append(f"p_f = {a.p_f:.4g} ({a.label}): {what}")
    spans, last = [], None
    for a in answers:
        if a.n and (last is None or a.n != last[0]):
            spans.append([a.n, a.p_f])
            last = spans[-1]
        elif a.n:
            last[1] = a.p_f
    words = ", ".join((f"N = {n} suffices for p_f <= {x:.4g}" if i == 0 else
                       f"{n} up to {x:.4g}") for i, (n, x) in enumerate(spans))
    return (f"fewest N meeting p = {p:g} at known p_f: " + "; ".join(parts)
            + (f" ({words})" if words else ""))
