"""Do the continuous uncertainties decide the answer? (issue 42's first target)

A success-probability design weighs failures (enumerated exactly) and the continuous
uncertainties (drawn worlds, navigation, dispersions). When the continuous part never
changes whether a swarm's survivors keep the map, the design's P of a swarm is its
**failures-only** probability: the exact failure-weighted P of the same swarm on the
nominal world (nothing goes wrong but failures),

    P_f(X) = sum over surviving subsets A of X of Pr(A) [cov_nominal(A) >= need],

for independent failures the binomial sum the issue quotes (N = 4 with one spare pair:
0.95^4 + 2 x 0.05 x 0.95^3). The continuous uncertainties decide when the validation's
P-hat of X differs from ``P_f(X)`` by more than the validation's sampling error::

    |P-hat - P_f| > z_{0.975} s_v / sqrt(M),

``s_v`` the spread of the M per-sample probabilities (95 %, normal; ``P_f`` is exact, so
the validation's error is the whole error). The held-out P (when scored) is reported
against the same number.
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.base.vertex_weights import normalised
from ideas_hpc.design.holdout import Z95
from ideas_hpc.design.reliability_eval import Evaluator


def failures_only_probability(nominal_bank, indices, need: float, model) -> float:
    """``P_f``: the exact failure-weighted P of the swarm ``indices`` (grid candidates of
    ``nominal_bank``, a :class:`~ideas_hpc.design.bank.CandidateBank` of the nominal world,
    its ``areas`` the design's weights) under the failure ``model`` (module docstring)."""
    idx = np.sort(np.asarray(indices, dtype=np.int64))
    rows = np.asarray(nominal_bank.masks, dtype=bool)[None, :, :]
    ev = Evaluator(rows, normalised(nominal_bank.areas, 1), need, model)
    return float(ev([idx])[0])


def continuous_effect(p_failures: float, per_sample, held: float | None = None) -> dict:
    """The gap of the validation's P-hat (``per_sample``: its M probabilities) to
    ``p_failures``, its 95 % sampling half-width and whether the gap exceeds it (module
    docstring); ``held``: the held-out P, reported beside it."""
    v = np.asarray(per_sample, dtype=np.float64).ravel()
    p_hat = float(v.mean()) if v.size else math.nan
    s_v = float(v.std(ddof=1)) if v.size > 1 else 0.0
    half = Z95 * s_v / math.sqrt(v.size) if v.size else math.nan
    gap = p_hat - float(p_failures)
    # a gap within the rounding of M summed probabilities is no gap: with no spread (every
    # sample at P_f) the half-width is 0 and the gap a last-bit residue of the mean
    rounding = 8.0 * np.finfo(np.float64).eps * max(v.size, 1)
    return {"failures_only": float(p_failures), "p_hat": p_hat, "gap": gap,
            "half_width": half, "decides": bool(abs(gap) > half + rounding),
            "held": math.nan if held is None else float(held)}


def effect_line(e: dict) -> str:
    """One result line: the failures-only P, the gaps and the verdict."""
    held = "" if math.isnan(e["held"]) else (
        f", held-out P {e['held']:.4f} ({e['held'] - e['failures_only']:+.4f})")
    verdict = ("the continuous uncertainties decide" if e["decides"] else
               "failures alone decide (the continuous uncertainties do not move P beyond "
               "the validation's sampling error)")
    return (f"failures alone: P = {e['failures_only']:.4f} for the same swarm on the nominal "
            f"world (failures enumerated); validation P-hat {e['p_hat']:.4f} differs by "
            f"{e['gap']:+.4f} against a 95 % sampling error of +-{e['half_width']:.4f}{held}: "
            f"{verdict}")


def effect_record(nominal_bank, indices, need: float, model, val, held: dict | None):
    """(store variables, attrs, result line) of the chosen swarm's failures-only P against
    its validation (``val``: a :class:`~ideas_hpc.campaign.validation_flights.Validation`)
    and held-out P; ``None`` without a nominal bank."""
    if nominal_bank is None:
        return None
    e = continuous_effect(failures_only_probability(nominal_bank, indices, need, model),
                          val.per_sample, None if held is None else held["probability"])
    line = effect_line(e)
    data = {"failures_only_probability": ((), e["failures_only"])}
    attrs = {"failures_only_probability": e["failures_only"],
             "continuous_uncertainties_decide": int(e["decides"]), "failures_only": line}
    return data, attrs, line
