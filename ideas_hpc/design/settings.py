"""Frozen settings of the bank designers (issue 30): each search's knobs in one
object, fields named with their units.

:class:`CoverSettings` is read by the certified designers of the candidate
bank (plain, failure-tolerant, stereo), :class:`ReliableSettings` by the
success-probability designer of the scenario bank. Coverages and tolerances
are area fractions; separations in m; times in s.
"""

from __future__ import annotations

from dataclasses import KW_ONLY, dataclass, field
from typing import Callable

import numpy as np

from ideas_hpc.mapping.requirement import Threshold, as_threshold


@dataclass(frozen=True)
class CoverSettings:
    """Fewest grid candidates that cover the ``threshold``
    (:class:`~ideas_hpc.mapping.requirement.Threshold`: ``need = target - eps_tol``).

    The older keywords ``target`` and ``eps_tol`` build the same threshold; after
    construction all three are set. ``failures_tolerated`` k > 0 asks for a swarm that
    keeps it after any k failures; ``time_limit_s`` None: no limit.
    """

    target: float | None = None
    eps_tol: float | None = None
    n_max: int | None = None
    min_separation_m: float = 0.0
    time_limit_s: float | None = None
    failures_tolerated: int = 0
    threshold: Threshold | None = None

    def __post_init__(self):
        thr = as_threshold(self.threshold, self.target, self.eps_tol)
        object.__setattr__(self, "threshold", thr)
        object.__setattr__(self, "target", thr.target)
        object.__setattr__(self, "eps_tol", thr.eps_tol)


@dataclass(frozen=True)
class ReliableSettings:
    """Fewest grid candidates with ``P_bank >= p``
    (:func:`~ideas_hpc.design.reliability.min_swarm_reliable`).

    ``need``: the coverage threshold (area fraction, ``target - eps_tol``), or the
    ``threshold`` record it comes from (then ``need`` is its ``need``);
    ``sep_steps``: candidates within this many grid steps conflict;
    ``enumerate_budget``: score every swarm of a size when there are at most
    this many; ``ring_prebound``: bound ``U_m`` first by the per-scenario
    ring-gap bounds; ``bound_solver`` / ``tolerance_solver``: stand-ins for
    the programmes (tests). ``p_f``: independent failures of that probability, or
    ``failures``, the failure model (:class:`~ideas_hpc.failures.model.FailureModel`,
    issue 41), which then wins.
    """

    p: float
    p_f: float
    need: float | None = None
    _: KW_ONLY
    n_max: int
    sep_steps: int = 0
    time_limit_s: float | None = None
    enumerate_budget: int = 20000
    ring_prebound: bool = True
    bound_solver: Callable | None = None
    tolerance_solver: Callable | None = None
    failures: object = None
    threshold: Threshold | None = None

    def __post_init__(self):
        if self.threshold is None and self.need is None:
            raise TypeError("ReliableSettings needs `need` or `threshold`")
        if self.threshold is not None:
            if self.need not in (None, self.threshold.need):
                raise TypeError(f"need {self.need!r} disagrees with the threshold's "
                                f"{self.threshold.need!r}")
            object.__setattr__(self, "need", self.threshold.need)

    @property
    def model(self):
        """The failure model: ``failures``, or a bare ``p_f``."""
        return self.failures if self.failures is not None else self.p_f


#: Most looks ``design.demonstrate`` plans when the file does not say.
DEFAULT_LOOKS = 4


@dataclass(frozen=True)
class LookPlan:
    """The looks of :func:`~ideas_hpc.design.certificate.certify`: requirement ``p``
    and overall ``confidence``; ``n_max`` the largest swarm; ``n_samples`` (M)
    validation samples per look; ``demonstrate`` steps N up while the bound
    misses p, in at most ``max_looks`` looks; ``exact``: one exact scenario;
    ``samples_max``: the most samples the look plan may give one look
    (:func:`~ideas_hpc.design.look_plan.plan_looks`; None: ``n_samples`` each)."""

    p: float
    confidence: float
    n_max: int
    n_samples: int
    demonstrate: bool
    max_looks: int = DEFAULT_LOOKS
    exact: bool = False
    samples_max: int | None = None


@dataclass
class ReliableResult:
    """Outcome of :func:`~ideas_hpc.design.reliability.min_swarm_reliable` (store variables of issue 20)."""

    indices: np.ndarray
    n: int
    probability: float            # P_bank of the chosen swarm
    per_scenario: np.ndarray      # (S,) exact failure-weighted P in each scenario
    status: str
    bound: float                  # proven lower bound on N
    gap: float
    solve_time: float
    upper: dict = field(default_factory=dict)      # N -> UB(N) proven
    best: dict = field(default_factory=dict)       # N -> (swarm, P_bank) best found
    u_bar: dict = field(default_factory=dict)      # m -> Ubar_m (fraction)
    notes: list = field(default_factory=list)
    designer: object = field(default=None, repr=False, compare=False)
