"""Certified swarm design over a bank of candidate spacecraft (issue 13).

Once every candidate's observation mask is known (:mod:`.bank`), choosing the
fewest spacecraft that cover a target area is a weighted set-cover integer
programme, solved exactly with HiGHS (:mod:`.exact`). Around it:
the best coverage for each swarm size (:mod:`.coverage_vs_n`) and the fewest
spacecraft that survive any ``k`` failures (:mod:`.failures`).
"""

from ideas_hpc.design.bank import CandidateBank, build_bank, separation_steps
from ideas_hpc.design.coverage_vs_n import CoverageCurve, coverage_curve
from ideas_hpc.design.exact import ExactResult, max_coverage, min_swarm
from ideas_hpc.design.failures import failure_tolerant, worst_failure

__all__ = ["CandidateBank", "build_bank", "separation_steps", "ExactResult", "min_swarm",
           "max_coverage", "CoverageCurve", "coverage_curve", "failure_tolerant",
           "worst_failure"]
