"""One vocabulary for a design's requirement, in summaries, stores and figures (issue 22).

* **target**: the coverage the design is asked for: 100 %, or the highest
  coverage any swarm of grid candidates can reach when 100 % is out of reach
  (store attr ``target_coverage``);
* **threshold** = target - eps_tol: what a swarm must reach to count
  (attr ``threshold_coverage``; the Monte Carlo verification counts the samples
  at or above it, attr ``verify_threshold``);
* **reached**: the coverage the chosen swarm gets (variable ``best_coverage``).

A design *reaches* the threshold (never "the target" unless it does).
"""

from __future__ import annotations

import math

from ideas_hpc.mapping.requirement import meets


def pct(x: float, digits: int = 3) -> str:
    return f"{100 * float(x):.{digits}f} %"


def requirement_line(target: float, threshold: float, reached: float | None = None) -> str:
    """``target 99.837 %, threshold 99.737 % (target - eps_tol), reached 99.781 %``."""
    s = f"target {pct(target)}, threshold {pct(threshold)} (target - eps_tol)"
    if reached is not None and math.isfinite(reached):
        s += f", reached {pct(reached)}"
        if not meets(reached, threshold):
            s += " (below the threshold)"
    return s


def verification_verdict(probability: float, n_samples: int, threshold: float,
                         required: float | None = None) -> str:
    """One plain sentence: did the design pass its Monte Carlo verification?

    With a required success probability (``design.success_probability``) the
    design passes when the fraction of dispersed samples reaching the threshold
    is at least that. Without one the design claims the threshold for the
    nominal flight, so it passes only when every dispersed sample reaches it.
    """
    got = f"{100 * probability:.1f} % of {n_samples} dispersed samples reach the threshold " \
          f"{pct(threshold, 2)}"
    if required is not None:
        ok = probability >= required
        return (f"verification {'PASSED' if ok else 'FAILED'}: {got} (required "
                f"{100 * required:.1f} %)")
    if probability >= 1.0:
        return f"verification PASSED: {got}"
    return (f"verification FAILED: only {got}; the design is sized for the nominal flight "
            "(set design.success_probability to design for the dispersions)")
