"""The coverage requirement as one record (issue 40): what a swarm must map, in SI fractions.

A :class:`Requirement` is built once from the campaign
(:func:`ideas_hpc.campaign.setup.requirement_from_campaign`) and handed to the
designers, the verification, the scans and the report. It holds

* ``eps_tol``: the area a swarm may leave unmapped, a fraction of the reference
  area (the file's ``design.eps_tol_pct`` / 100, converted once by its field);
* ``limits``: the observation limits, the ``[coverage]`` table's
  :class:`~ideas_hpc.mapping.options.CoverageOptions` (lit, elevation, emission,
  incidence, phase, resolution, stereo): a vertex counts only when an image meets
  them, which the coverage kernels decide, so every candidate row a designer reads
  already honours them;
* ``rule``: the target rule, a :data:`TARGET_RULES` entry (``design.target_rule``);
* ``reference``: what coverage is a fraction of, a :data:`REFERENCES` entry
  (``design.coverage_reference``: the whole surface, or the area lit at closest
  approach, issue 42; weights by :func:`ideas_hpc.mapping.reference.reference_weights`).

Its :attr:`Requirement.kind` is ``"visual"`` when a vertex must be lit (``require_lit``
or an incidence limit; with the emission and GSD limits that is the visual-mapping
requirement of SPEC 7f) and ``"geometric"`` otherwise (the paper's map, fit for thermal
mapping); :attr:`Requirement.label` states it and the reference in one line, which the
store records (attr ``requirement``) and the summary and the report print.

One method resolves it against what the candidates can reach,
:meth:`Requirement.threshold`, into a :class:`Threshold`::

    target = rule(reach, eps_tol)       rule "reach": 1, or the reach when reach < 1 - eps_tol
    need   = target - eps_tol           (the threshold, :func:`threshold_of`)

and one predicate says whether a coverage meets it, :func:`meets`:
``coverage >= need - COVER_TOL``, the comparison of the success-probability
evaluator (:data:`ideas_hpc.core.design.reliability.COVER_TOL`): unions of the same
float sums must not fail by rounding. The integer programmes ask a margin above
``need`` instead (:mod:`ideas_hpc.design.area`), so that a solver's tolerance never
hides a shortfall.

A new target rule is one :func:`register_rule` call (any module; the test module in
``tests/test_recipe_requirement.py``): ``design.target_rule`` reads the registry live.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.core.design.reliability import COVER_TOL
from ideas_hpc.mapping.options import CoverageOptions

__all__ = ["COVER_TOL", "REFERENCES", "REFERENCE_LABELS", "TARGET_RULES", "Requirement", "TargetRule", "Threshold",
           "as_threshold", "meets", "register_rule", "threshold_of"]


def meets(coverage, need: float):
    """``coverage >= need - COVER_TOL`` (scalars or arrays of area fractions): the one
    comparison of a coverage with a threshold (module docstring)."""
    return coverage >= need - COVER_TOL


@dataclass(frozen=True)
class Threshold:
    """A requirement resolved against a reach: ``target``, ``eps_tol``, ``need = target -
    eps_tol`` (area fractions) and the ``reach`` it was resolved against (None: not known,
    e.g. a Monte Carlo campaign or a GA on continuous angles). Build it with
    :func:`threshold_of` or :meth:`Requirement.threshold`, never by hand."""

    target: float
    eps_tol: float
    need: float
    reach: float | None = None

    @property
    def floor(self) -> float:
        """The least coverage that meets the threshold, ``need - COVER_TOL``."""
        return self.need - COVER_TOL

    def meets(self, coverage):
        """:func:`meets` against this threshold's ``need``."""
        return meets(coverage, self.need)


def threshold_of(target: float, eps_tol: float, reach: float | None = None) -> Threshold:
    """The threshold of ``target`` and ``eps_tol``: the one place ``need = target -
    eps_tol`` is computed."""
    target, eps_tol = float(target), float(eps_tol)
    return Threshold(target=target, eps_tol=eps_tol, need=target - eps_tol,
                     reach=None if reach is None else float(reach))


def as_threshold(threshold: Threshold | None = None, target: float | None = None,
                 eps_tol: float | None = None) -> Threshold:
    """``threshold``, or the one of the older keywords ``target`` and ``eps_tol`` (the
    designers' public calls keep them); raises when neither is given, or when both are
    and disagree."""
    if threshold is not None:
        if (target not in (None, threshold.target)
                or eps_tol not in (None, threshold.eps_tol)):
            raise InputError(f"`target` {target!r} and `eps_tol` {eps_tol!r} disagree with "
                             f"the threshold given ({threshold.target!r}, "
                             f"{threshold.eps_tol!r}): give one of them", field="threshold")
        return threshold
    if target is None or eps_tol is None:
        raise InputError("give a threshold, or both `target` and `eps_tol`",
                         field="target" if target is None else "eps_tol")
    return threshold_of(target, eps_tol)


@dataclass(frozen=True)
class TargetRule:
    """A target rule: ``target(reach, eps_tol) -> target`` (fractions; ``reach`` None when
    not known) and one line for ``design.target_rule``'s documentation."""

    name: str
    target: Callable[[float | None, float], float]
    doc: str = ""


def _reach_target(reach: float | None, eps_tol: float) -> float:
    if reach is not None and reach < 1.0 - eps_tol:
        return reach
    return 1.0


def _full_target(reach: float | None, eps_tol: float) -> float:
    if reach is not None and reach < 1.0 - eps_tol:
        raise InputError(f"100 % - eps_tol is out of reach: every candidate together maps "
                         f"{100 * reach:.3f} %; use the rule 'reach' to design for that",
                         field="rule")
    return 1.0


#: Target rules by name (``design.target_rule`` reads it live).
TARGET_RULES: dict[str, TargetRule] = {}


def register_rule(rule: TargetRule) -> TargetRule:
    """Add ``rule`` to :data:`TARGET_RULES` (a campaign can then name it)."""
    TARGET_RULES[rule.name] = rule
    return rule


register_rule(TargetRule("reach", _reach_target,
                         "100 %, or the highest coverage the candidates reach together "
                         "when 100 % - eps_tol is out of their reach"))
register_rule(TargetRule("full", _full_target,
                         "100 %; the design fails when 100 % - eps_tol is out of reach"))

#: What coverage is a fraction of (``design.coverage_reference``): the weights of each are
#: :func:`ideas_hpc.mapping.reference.reference_weights`.
REFERENCES = {
    "surface": "the whole surface: the observed area over the total vertex area",
    "lit_at_tca": ("the area lit at closest approach: the vertices whose Sun incidence at "
                   "TCA is within the incidence limit (< 90 deg when none), cast shadows "
                   "included when the coverage reads the Sun"),
}
#: How the summary and the report name each reference.
REFERENCE_LABELS = {"surface": "the whole surface",
                    "lit_at_tca": "the area lit at closest approach"}


@dataclass(frozen=True)
class Requirement:
    """The coverage requirement (module docstring): ``eps_tol`` (fraction, in [0, 1]),
    the observation ``limits``, the target ``rule`` and the ``reference`` area."""

    eps_tol: float
    limits: CoverageOptions = field(default_factory=CoverageOptions)
    rule: str = "reach"
    reference: str = "surface"

    def __post_init__(self):
        number(self.eps_tol, "eps_tol", lo=0.0, hi=1.0)
        if self.rule not in TARGET_RULES:
            raise InputError(f"must be one of {', '.join(TARGET_RULES)}; got {self.rule!r}",
                             field="rule")
        if self.reference not in REFERENCES:
            raise InputError(f"must be one of {', '.join(REFERENCES)}; got "
                             f"{self.reference!r}", field="reference")

    def threshold(self, reach: float | None = None) -> Threshold:
        """The :class:`Threshold` of this requirement when the candidates together reach
        ``reach`` (area fraction; None: unknown, the rule's target for an unknown reach)."""
        target = TARGET_RULES[self.rule].target(reach, self.eps_tol)
        return threshold_of(target, self.eps_tol, reach)

    @property
    def kind(self) -> str:
        """``"visual"`` when a vertex must be lit (``require_lit`` or an incidence limit):
        a map of the surface as the Sun shows it; else ``"geometric"``, the paper's map
        of what the cameras see, lit or not (fit for thermal mapping)."""
        lim = self.limits
        return "visual" if (lim.require_lit or lim.max_incidence_rad is not None) \
            else "geometric"

    @property
    def label(self) -> str:
        """One line for the store, the summary and the report: ``"visual (lit, incidence
        <= 60 deg, emission <= 70 deg, GSD <= 5 m) map of the area lit at closest
        approach"`` or ``"geometric (thermal, the paper's) map of the whole surface"``."""
        lim = self.limits
        if self.kind == "visual":
            parts = ["lit"]
            for name, rad in (("incidence", lim.max_incidence_rad),
                              ("emission", lim.max_emission_rad),
                              ("phase", lim.max_phase_rad)):
                if rad is not None:
                    parts.append(f"{name} <= {math.degrees(rad):g} deg")
            if lim.max_resolution_m is not None:
                parts.append(f"GSD <= {lim.max_resolution_m:g} m")
            if lim.require_stereo:
                parts.append("stereo")
            head = f"visual ({', '.join(parts)})"
        else:
            head = "geometric (thermal, the paper's)"
        return f"{head} map of {REFERENCE_LABELS[self.reference]}"
