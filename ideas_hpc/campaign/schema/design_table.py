"""The ``[design]`` and ``[monte_carlo]`` tables and their cross-checks (split from
:mod:`ideas_hpc.campaign.schema.campaign_tables`).

The success-probability designer (issue 20) reads ``design.success_probability``
(p, 0 < p < 1), ``design.confidence`` (of the validation's lower bound, in
(0.5, 1)), ``design.scenarios`` (S, the scenario bank), ``design.demonstrate`` with
``design.demonstrate_looks`` and ``design.bank_level`` (issue 29, docs/certificate.md);
``design.verify_samples`` (M) defaults to 64, or 256 with p set
(:func:`verify_samples`). S and M must resolve p: at least ``10 / (1 - p)``.
``design.holdout_scenarios`` (H, :func:`holdout_scenarios`) held-out scenarios score the
swarms the bank chose (issue 41); ``design.verify_samples_max`` caps the samples the look
plan may give one look. ``design.ca_distances_km`` (issue 42 deliverable 5) makes the
closest-approach distance a dimension of that design: a short list, checked once
(:func:`check_distances`), from which the design chooses
(:mod:`ideas_hpc.campaign.design_distance`).
"""

from __future__ import annotations

import math

from ideas_hpc.base.errors import InputError
from ideas_hpc.design.api.methods import METHODS
from ideas_hpc.failures.weights import all_lost
from ideas_hpc.mapping.requirement import REFERENCES, TARGET_RULES
from ideas_hpc.montecarlo.dispersions import dispersion_keys
from ideas_hpc.montecarlo.failure_dispersion import failure_model
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.base.fields import Field, LiveTable
import numpy as np

from ideas_hpc.base.units import DEG, KM, MINUTE

#: Validation samples when ``design.verify_samples`` is not given.
VERIFY_DEFAULT, VERIFY_DEFAULT_RELIABILITY = 64, 256

DESIGN = {
    # live: a method registered later is a valid choice (ideas_hpc.design.api.methods)
    "method": Field("str", "exact", choices=METHODS.keys(),
                    doc="design-nadir: exact integer programme or the paper's GA"),
    "angle_step_deg": Field("float", None, nullable=True, si="grid_step_rad", to_si=DEG, lo=0,
                            hi=90, doc="grid of candidate swarm angles of every designer "
                            "(default: exact and Pareto 0.5 deg, GA 0.01 rad; GA: 0 continuous)"),
    "time_limit_s": Field("float", 60.0, lo=0, lo_open=True,
                          doc="exact designer: return the best design so far with its gap"),
    "failures_tolerated": Field("int", 0, lo=0, doc="k: coverage must survive any k failures"),
    "verify_samples": Field("int", None, nullable=True, lo=0, hi=100000,
                            doc="Monte Carlo samples that verify the exact design (0: off; "
                                "default 64, 256 with success_probability)"),
    "success_probability": Field("float", None, nullable=True, lo=0, hi=1, lo_open=True,
                                 hi_open=True, doc="p: design for P(coverage >= target - "
                                 "eps_tol) >= p under the [monte_carlo] dispersions"),
    "confidence": Field("float", 0.95, lo=0.5, hi=1, lo_open=True, hi_open=True,
                        doc="confidence of the validation's lower bound on P"),
    "scenarios": Field("int", 256, lo=1, hi=100000,
                       doc="S: scenarios of the continuous dispersions in the design's bank"),
    "demonstrate": Field("bool", False, doc="step N up until validation demonstrates p"),
    "demonstrate_looks": Field("int", 4, lo=1, hi=20,
                               doc="most validation looks of design.demonstrate; each flies "
                                   "fresh samples at (1 - confidence) / looks (docs/certificate.md)"),
    "bank_level": Field("float", None, nullable=True, lo=0, hi=1, lo_open=True, hi_open=True,
                        doc="p': solve the scenario bank at this stricter level (>= p) so that "
                            "its swarm validates at the first look (default: p)"),
    "holdout_scenarios": Field("int", None, nullable=True, lo=0, hi=1000000,
                               doc="held-out scenarios that score the swarms the bank chose "
                                   "(unbiased P, the optimiser's bias, the look plan; "
                                   "docs/certificate.md), flown for those swarms only: "
                                   "default 4 x design.verify_samples when the bank is "
                                   "sampled, 0 (none) when it is exact"),
    "verify_samples_max": Field("int", None, nullable=True, lo=1, hi=1000000,
                                doc="most validation samples of one look: the look plan "
                                    "doubles a look's M from design.verify_samples toward 80 % "
                                    "predicted power (default: design.verify_samples)"),
    "curve_samples": Field("int", None, nullable=True, lo=0, hi=100000,
                           doc="validation samples of each size on the reliability curve "
                               "other than the looks' (default: design.verify_samples; 0: "
                               "those sizes are scored on the held-out scenarios only, their "
                               "validated P-hat NaN)"),
    "tolerant_markers": Field("bool", False,
                              doc="mark the 1- and 2-failure-tolerant designs on the reliability "
                                  "curve (HiGHS on the nominal bank: about a minute of one "
                                  "worker, ending with 40 % gaps on eros001708; off by default, "
                                  "issue 43)"),
    "ca_distances_km": Field("floats", None, nullable=True, si="ca_distances_m", to_si=KM,
                             lo=0, lo_open=True,
                             doc="closest-approach distances (km) the success-probability "
                                 "design chooses from: a bank at each, the distance of fewest "
                                 "proven N, ties by the higher bank P (docs/study.md); unset: "
                                 "flyby.d_sep_km alone"),
    "population": Field("int", 100, lo=2, doc="GA population size"),
    "generations": Field("int", 115, lo=1),
    "n_max": Field("int", 20, lo=1, hi=200),
    # converted here only: the typed table holds the fraction, design.eps_tol
    "eps_tol_pct": Field("float", 0.1, lo=0, hi=100, si="eps_tol", per=100.0,
                         doc="area a swarm may leave unmapped, % of the reference area: "
                             "threshold = target - eps_tol"),
    # live: a rule registered later is a valid choice (ideas_hpc.mapping.requirement)
    "target_rule": Field("str", "reach", choices=TARGET_RULES.keys(),
                         doc="the target: 'reach' (100 %, or what the candidates reach "
                             "together when less) or 'full' (100 %, else fail)"),
    "coverage_reference": Field("str", "surface", choices=REFERENCES.keys(),
                                doc="what coverage is a fraction of: 'surface' (the whole "
                                    "surface, the paper's) or 'lit_at_tca' (the area lit "
                                    "at closest approach within coverage.max_incidence_deg;"
                                    " docs/requirement.md)"),
    "angle_step_rad": Field("float", None, nullable=True, lo=0, hi=1.0,
                            doc="deprecated alias of angle_step_deg, in rad"),
    "p_min_min": Field("float", 0.3, si="p_min_s", to_si=MINUTE, lo=0, lo_open=True),
    "p_max_min": Field("float", 10.0, si="p_max_s", to_si=MINUTE, lo=0, lo_open=True),
    "period_step_min": Field("float", 0.1, si="period_step_s", to_si=MINUTE, lo=0),
    "parents": Field("int", None, nullable=True, lo=2),
    "elitism": Field("int", 2, lo=0),
    "mutation_probability": Field("float", 0.1, lo=0, hi=1),
    "stall_generations": Field("int", 0, lo=0, doc="stop after this many generations "
                                                     "without improvement (0: never)"),
    "chunk_size": Field("int", 32, lo=1, doc="spacecraft per dask task"),
    "nadir_store": Field("str", None, nullable=True, doc="design-fov: take the swarm from "
                                                          "this design-nadir store"),
    "objectives": Field("any", ("n", "coverage"),
                        doc="design-pareto: two or more of n, coverage, "
                            "worst_failure_coverage, stereo_coverage, mean_resolution"),
}

#: ``[monte_carlo]``: ``samples`` and the keys each dispersion declares
#: (:data:`~ideas_hpc.montecarlo.dispersions.DISPERSIONS`), read live.
MC_SCHEMA = LiveTable(lambda: {"samples": Field("int", 64, lo=1), **dispersion_keys()})


def verify_samples(d) -> int:
    """M: ``design.verify_samples``, or its default (256 with p set, else 64)."""
    if d.verify_samples is not None:
        return int(d.verify_samples)
    return VERIFY_DEFAULT_RELIABILITY if d.success_probability is not None else VERIFY_DEFAULT


#: Held-out scenarios per validation sample by default: their mean's error is half the
#: validation's, so a validation P-hat lands within its own 95 % interval of the held-out P
#: about 92 % of the time when both estimate the same P.
HOLDOUT_PER_SAMPLE = 4


def holdout_scenarios(d, exact: bool) -> int:
    """H: ``design.holdout_scenarios``, or its default: 4 x ``design.verify_samples`` when the
    bank is sampled, none when it is exact (one scenario: nothing to hold out)."""
    if exact:
        return 0
    if d.holdout_scenarios is not None:
        return int(d.holdout_scenarios)
    return HOLDOUT_PER_SAMPLE * verify_samples(d)


def curve_samples(d, exact: bool) -> int:
    """Validation samples of each reliability-curve size that no look flew:
    ``design.curve_samples``, or ``design.verify_samples`` (one when exact)."""
    if exact:
        return 1
    return verify_samples(d) if d.curve_samples is None else int(d.curve_samples)


def check_distances(distances_m, field: str) -> tuple:
    """Closest-approach distances (m) as a tuple of positive finite floats, else one
    :class:`InputError` naming ``field`` (the study's ``--ca-distances-km``, the design's
    ``design.ca_distances_km``): an empty list, a non-number, zero, a negative or a
    non-finite value."""
    try:
        vals = tuple(float(x) for x in distances_m)
    except (TypeError, ValueError):
        vals = ()
    if not vals or any(not (np.isfinite(v) and v > 0) for v in vals):
        raise InputError(f"needs positive closest-approach distances, got {distances_m!r}",
                         field=field)
    return vals


def reference_checks(c) -> None:
    """``design.coverage_reference`` other than the whole surface where a run would read
    coverage that ignores it: the plain exact design's Monte Carlo verification flies
    whole-surface coverage (the success-probability design's bank and validation weigh by
    the reference, docs/requirement.md)."""
    d = c.design
    if d.coverage_reference != "surface" and d.success_probability is None \
            and verify_samples(d) > 0:
        raise InputError(f"{d.coverage_reference!r} weighs the design but not the Monte Carlo "
                         "verification of a design without design.success_probability (its "
                         "coverage is of the whole surface): set design.verify_samples = 0, "
                         "or design.success_probability", field="design.coverage_reference")


def reliability_checks(c) -> None:
    """Cross-checks of the success-probability keys (bad inputs of issue 20)."""
    d = c.design
    p = d.success_probability
    # p for a kind or method that does not design for it, and the keys that need p,
    # are refused as keys the run does not read (campaign/schema/reads.py)
    if p is None or not (KINDS[c.kind].success_probability
                         and METHODS[d.method].success_probability):
        return
    if d.failures_tolerated:
        raise InputError("must be 0 with design.success_probability, which replaces it "
                         "(failures enter the probability exactly through "
                         "monte_carlo.failure_probability)", field="design.failures_tolerated")
    _reachable(c.monte_carlo, p, d.n_max)
    if d.ca_distances_m is not None:     # each distance's own checks run with its campaign
        check_distances(d.ca_distances_m, "design.ca_distances_km")
    if d.bank_level is not None and d.bank_level < p:
        raise InputError(f"{d.bank_level:g} is below design.success_probability = {p:g}: the "
                         "bank's level may only be stricter", field="design.bank_level")
    least = math.ceil(10.0 / (1.0 - p) - 1e-9)
    if d.scenarios < least:
        raise InputError(f"{d.scenarios} scenarios cannot resolve p = {p:g}: at least "
                         f"10 / (1 - p) = {least} are needed (a bank with fewer than 10 "
                         "expected misses cannot tell P from p); for a quick check run "
                         "campaigns/eros-design-quick.toml, or lower "
                         "design.success_probability", field="design.scenarios")
    m = verify_samples(d)
    if d.verify_samples_max is not None and d.verify_samples_max < m:
        raise InputError(f"{d.verify_samples_max} is below the {m} samples of a look "
                         "(design.verify_samples)", field="design.verify_samples_max")
    if m < least:
        raise InputError(f"{m} validation samples cannot resolve p = {p:g}: at least "
                         f"10 / (1 - p) = {least} are needed (fewer than 10 expected misses "
                         "cannot tell P from p); lower design.success_probability for a "
                         "smaller check", field="design.verify_samples")


def _reachable(mc, p: float, n_max: int) -> None:
    """Refuse a p no swarm of ``n_max`` can reach under the failure model: one that always
    maps the target still needs a survivor (losses in the pass counted as survivals), so
    ``P <= 1 - P(none survives)`` (``1 - p_f^N`` for independent failures)."""
    model = failure_model(mc)
    most = 1.0 - all_lost(model, n_max)
    if most < p:
        how = ("1 - p_f^N" if model.is_plain else
               "1 - P(no spacecraft survives) under the failure model")
        raise InputError(f"{p:g} is not reached: even a swarm of design.n_max = {n_max} that "
                         f"always maps the target succeeds with at most {how} = {most:.6g}",
                         field="design.success_probability")
