"""The ``failures`` entry of :data:`~ideas_hpc.montecarlo.dispersions.DISPERSIONS`: its
``[monte_carlo]`` keys, their check, the failure model they describe, and one sample's
draw (issue 41, docs/failure-model.md).

``failure_model(mc)`` is the one place the keys become a
:class:`~ideas_hpc.failures.model.FailureModel`; the Monte Carlo kind's draws, the
success-probability design, its bounds and its validation all take that record.
"""

from __future__ import annotations

from ideas_hpc.base.errors import InputError, config_fields
from ideas_hpc.base.fields import Field
from ideas_hpc.base.seeds import side_rng
from ideas_hpc.failures.model import FailureModel
from ideas_hpc.failures.prior import Prior
from ideas_hpc.failures.sampling import draw_failures

#: The entry's keys, in the order they were added (the first two since issue 20).
FAILURE_KEYS = (
    ("failures_k", Field("int", 0, lo=0, doc="exactly k of N spacecraft lost")),
    ("failure_probability",
     Field("any", 0.0, doc="per-spacecraft loss probability: a number (every spacecraft) or "
                           "a list, one per spacecraft of the fleet (spacecraft k flies "
                           "member k of the swarm: a design's k-th grid candidate in "
                           "increasing order, or the k-th of swarm.angles)")),
    ("failure_probability_sd",
     Field("float", 0.0, lo=0, doc="p_f uncertain: p_f ~ Beta with mean failure_probability "
                                   "and this standard deviation (0: p_f known)")),
    ("failure_probability_values",
     Field("any", None, nullable=True, doc="p_f uncertain: equally likely among these values "
                                           "(replaces failure_probability)")),
    ("common_cause_beta",
     Field("float", 0.0, lo=0, hi=1, doc="beta factor (IEC 61508): the share of each loss "
                                         "probability that is a common-cause event taking "
                                         "out the whole group")),
    ("common_cause_groups",
     Field("any", None, nullable=True, doc="common-cause groups of spacecraft (0-based), e.g. "
                                           "[[0, 1, 2], [3, 4]]; default: the whole swarm")),
    ("failure_in_pass_share",
     Field("float", 0.0, lo=0, hi=1, doc="share of losses during the pass, at a uniform "
                                         "time (the spacecraft images until then); "
                                         "success-probability designs only")),
)

#: The model's parameter names -> the keys (errors name the keys).
FIELDS = {"p_f": "failure_probability", "p_f_sd": "failure_probability_sd",
          "p_f_values": "failure_probability_values", "beta": "common_cause_beta",
          "groups": "common_cause_groups", "in_pass_share": "failure_in_pass_share",
          "failures_k": "failures_k"}


def failure_model(mc) -> FailureModel:
    """The :class:`~ideas_hpc.failures.model.FailureModel` of a typed ``[monte_carlo]``
    table. Errors name the keys (the campaign adds the ``monte_carlo.`` prefix)."""
    with config_fields(FIELDS):
        return _model(mc)


def _model(mc) -> FailureModel:
    p = mc.failure_probability
    if isinstance(p, bool) or not isinstance(p, (int, float, list, tuple)):
        raise InputError(f"must be a number or a list of numbers, got {p!r}", field="p_f")
    p = tuple(p) if isinstance(p, (list, tuple)) else (p,)
    values, sd = mc.failure_probability_values, mc.failure_probability_sd
    prior = None
    if values is not None:
        if not isinstance(values, (list, tuple)) or not values:
            raise InputError(f"must be a non-empty list of numbers, got {values!r}",
                             field="p_f_values")
        if sd:
            raise InputError("cannot be combined with `p_f_values` (one prior)",
                             field="p_f_sd")
        if p != (0,) and p != (0.0,):
            raise InputError("is replaced by `p_f_values`: leave it out", field="p_f")
        prior = Prior(values=tuple(values))
        p = (sum(prior.values) / len(prior.values),)
    elif sd:
        if len(p) != 1:
            raise InputError("an uncertain p_f (`p_f_sd`) is one p_f shared by every "
                             "spacecraft: give `p_f` one value", field="p_f")
        prior = Prior(mean=p[0], sd=sd)
    return FailureModel(p_f=p, beta=mc.common_cause_beta, groups=mc.common_cause_groups,
                        in_pass_share=mc.failure_in_pass_share, prior=prior,
                        failures_k=mc.failures_k)


def failures_active(mc) -> bool:
    """Whether the table asks for any loss at all."""
    m = failure_model(mc)
    return bool(m.failures_k) or m.prior is not None or any(v > 0 for v in m.p_f)


def draw(rng, n, mc, setup, theta) -> dict:
    """One Monte Carlo sample's losses: the permutation and the uniforms drawn from the
    shared stream as always (so the dispersions after it keep their numbers), everything
    the model adds from :func:`~ideas_hpc.base.seeds.side_rng`
    (:func:`~ideas_hpc.failures.sampling.draw_failures`). Losses are whole-pass here
    (``failure_in_pass_share`` is refused outside success-probability designs)."""
    perm = rng.permutation(n)
    bern = rng.uniform(0.0, 1.0, n)
    d = draw_failures(failure_model(mc), n, bern, side_rng(rng), perm=perm)
    return {"active": d.active, "n_failed": int(d.failed.sum())}


def check(mc) -> None:
    """The keys make one model (errors name the key)."""
    failure_model(mc)


def check_fleet(mc, n: int, what: str, swarm: bool = False) -> None:
    """Refuse a model that names fewer or more spacecraft than fly: a per-spacecraft list
    shorter than ``n`` (``what``: ``design.n_max`` or the swarm size), a group naming a
    spacecraft ``>= n``, or (``swarm``: ``n`` is the swarm's own size) more certain losses
    than spacecraft."""
    m = failure_model(mc)
    if swarm and m.failures_k > n:
        raise InputError(f"cannot exceed the swarm size {n}", field="failures_k")
    if len(m.p_f) > 1 and len(m.p_f) < n:
        raise InputError(f"has {len(m.p_f)} values for {what} = {n} spacecraft: give one per "
                         "spacecraft that may fly", field="failure_probability")
    if m.groups:
        top = max(max(g) for g in m.groups)
        if top >= n:
            raise InputError(f"names spacecraft {top} (0-based), but {what} = {n}",
                             field="common_cause_groups")
