"""Per-target reliability from nested draws (SPEC 7f "What to report"; issue 42 deliverable 6).

A design's ``P(X) = E_w[P_w(X)]`` averages over the target worlds ``w`` of the prior. A
mission asks a sharper question: *for the one target that is really there*, how likely is
the swarm to succeed? That is the conditional ``P_w(X)`` of one world, an average over the
navigation errors, the continuous dispersions and the failures with the world held fixed.
Its distribution over the prior answers "the share of possible targets for which the
design meets ``p``":

    r(p) = Pr_w[ P_w(X) >= p ].

Nested draws estimate it: ``M`` outer worlds ``w_1 .. w_M`` (world ``m`` of family
:data:`~ideas_hpc.base.seeds.NESTED_STREAM`), each flown through ``K`` inner draws
(sample ``m K + j`` of that design stream: navigation errors, dispersions, and failures
enumerated exactly as in the design's validation, :class:`~ideas_hpc.campaign.validation_flights.Validation`).
World ``m``'s conditional P is the mean of its ``K`` per-sample values,

    P_m = (1/K) sum_j P(X | w_m, xi_mj),

and ``r(p)`` is estimated by the share of worlds with ``P_m >= p``, with the Wilson 95 %
interval of that binomial share (:func:`~ideas_hpc.campaign.validate_store.wilson_interval`).
The interval counts the outer sampling only: each ``P_m`` carries its own inner error
(reported as its standard error), which blurs worlds near ``p``; more inner draws
sharpen the classification, more worlds narrow the interval.

All ``M K`` flights go through the validation's one path in one batch: the setup's
target is :class:`NestedWorlds`, whose draw ``k`` is outer world ``k // K``. The mean of
all ``P_m`` is an ordinary (two-stage) estimate of ``P(X)``. A prior with no spread has
one world: every ``P_m`` is then the plain validation's mean over the same inner draws
(``tests/test_study.py``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base import progress, seeds
from ideas_hpc.base.errors import InputError


@dataclass(frozen=True)
class NestedWorlds:
    """A target prior whose draw ``k`` is world ``k // per_world`` of ``prior`` in family
    ``world_family``: ``per_world`` consecutive samples share one world (module docstring)."""

    prior: object
    per_world: int
    world_family: int = seeds.NESTED_STREAM

    def __post_init__(self):
        if int(self.per_world) < 1:
            raise InputError(f"must be >= 1, got {self.per_world}", field="--per-world")

    @property
    def name(self) -> str:
        return f"{getattr(self.prior, 'name', 'prior')} (nested, {self.per_world} per world)"

    def world_of(self, k: int) -> int:
        """The outer world of sample ``k``."""
        return int(k) // int(self.per_world)

    def draw(self, seed: int, k: int, family: int = 0):
        return self.prior.draw(int(seed), self.world_of(k), family=int(self.world_family))


@dataclass(frozen=True)
class PerTarget:
    """Outcome of :func:`per_target_reliability`."""

    conditional: np.ndarray     # (M,) P_m, each world's conditional P
    std_error: np.ndarray       # (M,) standard error of P_m over its K inner draws
    per_sample: np.ndarray      # (M, K) exact failure-weighted P of each inner draw
    p: float
    seed: int

    @property
    def worlds(self) -> int:
        return int(self.conditional.size)

    @property
    def per_world(self) -> int:
        return int(self.per_sample.shape[1])

    @property
    def meeting(self) -> int:
        """Worlds whose conditional P is at least p."""
        return int(np.count_nonzero(self.conditional >= self.p))

    @property
    def share(self) -> float:
        return self.meeting / self.worlds

    def interval(self) -> tuple[float, float]:
        """Wilson 95 % interval of the share of worlds meeting p (outer sampling only)."""
        from ideas_hpc.campaign.validate_store import wilson_interval

        return wilson_interval(self.meeting, self.worlds)


def conditional_probabilities(per_sample: np.ndarray, per_world: int):
    """``(P_m, standard errors)`` of ``M K`` per-sample values in world-major order (sample
    ``m K + j`` is world ``m``'s inner draw ``j``)."""
    v = np.asarray(per_sample, dtype=np.float64)
    k = int(per_world)
    if v.ndim != 1 or k < 1 or v.size % k:
        raise InputError(f"{v.size} values are not whole worlds of {k} inner draws",
                         field="per_sample")
    block = v.reshape(-1, k)
    se = block.std(axis=1, ddof=1) / math.sqrt(k) if k > 1 else np.full(block.shape[0], np.nan)
    return block.mean(axis=1), se


def per_target_reliability(c, setup, theta, need: float, p: float, *, worlds: int,
                           per_world: int, client=None) -> PerTarget:
    """The nested estimate of ``r(p)`` for swarm ``theta`` (rad) under ``setup``'s target
    prior (module docstring); ``need`` the coverage threshold, ``p`` the level."""
    from ideas_hpc.campaign.setup import requirement_from_campaign
    from ideas_hpc.campaign.validation_flights import (Validation, fly_validation_world,
                                                       sample_weights)
    from ideas_hpc.montecarlo.failure_dispersion import failure_model

    if setup.target is None:
        raise InputError("the target is known ([target] prior = \"known\"): every world is the "
                         "same, so per-target reliability is the design's P", field="--worlds")
    m, k = int(worlds), int(per_world)
    if m < 1:
        raise InputError(f"must be >= 1, got {worlds}", field="--worlds")
    nested = dataclasses.replace(setup, target=NestedWorlds(setup.target, k))
    mc, model = c.config.monte_carlo, failure_model(c.config.monte_carlo)
    seed = int(c.config.seed)
    rows, seen, areas = fly_validation_world(nested, np.asarray(theta, dtype=np.float64), mc,
                                             model, requirement_from_campaign(c), seed=seed,
                                             n_samples=m * k, client=client,
                                             progress=progress.on(), stream=seeds.NESTED_STREAM)
    w = sample_weights(areas, np.zeros(0), rows.shape[0])
    per = Validation(rows, w, need, model, seed, seen=seen,
                     stream=seeds.NESTED_STREAM).per_sample
    cond, se = conditional_probabilities(per, k)
    return PerTarget(conditional=cond, std_error=se, per_sample=per.reshape(m, k), p=float(p),
                     seed=seed)
