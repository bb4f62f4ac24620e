"""Kind ``design-nadir`` with ``design.success_probability`` (issue 20): the fewest
spacecraft that map ``target - eps_tol`` with probability >= p.

Orchestration only:

1. the nominal exact design (:func:`~ideas_hpc.campaign.design_exact.design_exact`):
   the target, the plain minimum ``N0`` and the coverage-versus-N curve;
2. the scenario bank (:func:`ideas_hpc.montecarlo.scenarios.build_scenario_bank`,
   ``design.scenarios`` draws of the continuous dispersions);
3. the proven fewest N with ``P_bank >= p``
   (:func:`ideas_hpc.design.reliability.min_swarm_reliable`; failures exact);
4. the validation: the chosen swarm flown through ``design.verify_samples``
   fresh draws (:func:`ideas_hpc.montecarlo.scenarios.fly_members`, a stream
   disjoint from the scenarios'), the exact failure-weighted P of each, their
   mean ``P-hat`` and a lower bound at ``design.confidence``
   (:func:`ideas_hpc.design.reliability_stats.lower_confidence_bound`);
   ``design.demonstrate`` steps N up until the bound reaches p, each look on
   its own fresh samples and at ``(1 - confidence) / K`` for the K =
   ``design.demonstrate_looks`` planned looks
   (:func:`ideas_hpc.design.certificate.certify`, docs/certificate.md);
   ``design.bank_level`` solves step 3 at a stricter level than p;
5. the reliability curve for N from ``N0`` to where P >= 0.99 (or ``n_max``),
   with the k-failure-tolerant designs of the nominal bank evaluated on it
   (:mod:`ideas_hpc.campaign.reliability_vars` assembles the store variables).

With every continuous dispersion off, one scenario and one validation flight
are exact (no sampling): ``P-hat`` is the exact P and so is its bound.
"""

from __future__ import annotations

import math
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from ideas_hpc.base.progress import result
from ideas_hpc.design.api import CoverSettings, minimize
from ideas_hpc.design.settings import LookPlan
from ideas_hpc.design.certificate import (certify, group_bounds, planned_looks,
                                         replicated_lower_bound)
from ideas_hpc.design.reliability import ReliabilityDesigner
from ideas_hpc.design.reliability_levels import n_at_levels
from ideas_hpc.design.reliability_stats import lower_confidence_bound
from ideas_hpc.base.errors import InputError
from ideas_hpc.base import progress
from ideas_hpc.engine.job_cluster import phase_client
from ideas_hpc.montecarlo.dispersions import scenario_dispersed
from ideas_hpc.montecarlo.failure_dispersion import failure_model
from ideas_hpc.campaign.setup import requirement_from_campaign
from ideas_hpc.mapping.requirement import meets
from ideas_hpc.campaign.validation_flights import (  # noqa: F401 (Validation, fly_validation:
    Validation, fly_validation, fly_validation_world, sample_weights)  # their old home)
from ideas_hpc.base import seeds
from ideas_hpc.campaign.design_exact import design_exact
from ideas_hpc.campaign.bank_design import (bank_level, bank_search, campaign_bank, refuse_stereo,
                                           search_budget)
from ideas_hpc.campaign.reliability_vars import BankRun, reliability_dataset
from ideas_hpc.campaign.schema.design_table import (curve_samples, holdout_scenarios,
                                                    verify_samples)
from ideas_hpc.design.holdout import HeldOut, agreement

#: Purpose word of the validation's sampled failures (its old home; now
#: :data:`ideas_hpc.base.seeds.STREAM_FAILURES`): ``(VALIDATION_STREAM, m, 3)``.
STREAM_FAILURES = seeds.STREAM_FAILURES
#: The curve stops at the first N whose best P on the scenarios reaches this.
CURVE_TOP = 0.99
#: Largest k of the k-failure-tolerant designs marked on the curve.
K_MARKED = 2


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def continuous_off(mc, setup) -> bool:
    """True when no dispersion drawn into the scenarios is active (each declares when it
    is: :func:`~ideas_hpc.montecarlo.dispersions.scenario_dispersed`), so a scenario
    is the nominal flight."""
    return not scenario_dispersed(mc, setup)


def _validate(c, setup, theta, need, w, exact, client, *, first=0, size=None,
              stream=seeds.VALIDATION_STREAM):
    """Validation samples ``first .. first + M - 1`` of ``theta`` (no bound: :func:`_certify`
    and the curve compute theirs); M is ``size``, by default ``design.verify_samples``;
    ``stream``: the held-out scenarios' (:data:`ideas_hpc.base.seeds.HOLDOUT_STREAM`)."""
    d, mc = c.config.design, c.config.monte_carlo
    m = 1 if exact else (verify_samples(d) if size is None else int(size))
    model = failure_model(mc)
    rows, seen, areas = fly_validation_world(setup, theta, mc, model,
                                             requirement_from_campaign(c), seed=c.config.seed,
                                             n_samples=m, client=client,
                                             progress=progress.on(), first=first, stream=stream)
    return Validation(rows, sample_weights(areas, w, rows.shape[0]), need, model,
                      c.config.seed, first=first, seen=seen, stream=stream)


def _held_out_batch(c, setup, theta, swarms, need, w, size, client) -> list:
    """Held-out values (H,) of several swarms from one set of flights: the union of their
    members flies each held-out scenario once (a scenario's world and start are most of a
    flight's cost), and each swarm is scored on its members' rows (with their draws of the
    held-out failures, as when flown alone). A member flies the continuous draws of its
    place in the union: each held-out scenario is still one draw of the dispersions for
    every member, chosen by nothing the held-out values decide."""
    mc = c.config.monte_carlo
    model = failure_model(mc)
    union = np.unique(np.concatenate([np.asarray(s, dtype=np.int64) for s in swarms]))
    rows, seen, areas = fly_validation_world(setup, theta[union], mc, model,
                                             requirement_from_campaign(c), seed=c.config.seed, n_samples=int(size),
                                             client=client, progress=progress.on(),
                                             stream=seeds.HOLDOUT_STREAM)
    w = sample_weights(areas, w, rows.shape[0])     # a sample's world weighs every member
    out = []
    for sw in swarms:
        at = np.searchsorted(union, np.sort(np.asarray(sw, dtype=np.int64)))
        out.append(Validation(rows[:, at], w, need, model, c.config.seed,
                              seen=None if seen is None else seen[:, at],
                              stream=seeds.HOLDOUT_STREAM).per_sample)
    return out


def _scored_swarms(res, rel, n0: int, d, exact: bool) -> list:
    """The swarms the look plan and the reliability curve will score on the held-out
    scenarios, in the order they ask for them (so the bank's searches run in the same
    order as without the prefetch): from the bank's N up to the plan's last possible look
    (one size past its planned looks), on to the first size whose bank P reaches the
    curve's top, then the curve's smaller sizes from the nominal N."""
    k = planned_looks(d.demonstrate, res.n, d.n_max, d.demonstrate_looks, exact)
    # the plan's looks start at the bank's N or past a skipped size: a later start (up to
    # MAX_SKIPPED) flies its last sizes alone, without a search for sizes it never needs
    top = res.n + (k if d.demonstrate else 0)
    out, n = [], res.n
    while n <= int(d.n_max):
        sw, pb = (res.indices, res.probability) if n == res.n else rel.best_of(n)
        if np.asarray(sw).size != n:
            break
        out.append(sw)
        if n >= top and pb >= CURVE_TOP:
            break
        n += 1
    for n in range(min(n0, res.n), res.n):
        sw = rel.best_of(n)[0]
        if np.asarray(sw).size == n:
            out.append(sw)
    return out


def _tolerant_designs(nominal_bank, threshold, d, sep) -> list:
    """(k, DesignResult) of the k-failure-tolerant designs on the nominal bank, k = 1..K_MARKED."""
    out = []
    for k in range(1, K_MARKED + 1):
        if k >= d.n_max:
            break
        try:
            r = minimize(nominal_bank, CoverSettings(
                threshold=threshold, n_max=d.n_max, min_separation_m=sep,
                time_limit_s=min(d.time_limit_s, 30.0), failures_tolerated=k))
        except InputError:
            break
        if r.n > 24:
            break
        out.append((k, r))
    return out


def _tolerant(designs, rel: ReliabilityDesigner) -> list:
    """(k, N_k, P_bank, indices) of the k-failure-tolerant designs, P on the scenario bank."""
    return [(k, r.n, float(rel.ev([r.indices])[0]), r.indices) for k, r in designs]


def scenario_store_path(out) -> str | None:
    """Where a design store's scenario bank lives: ``NAME-scenarios.zarr`` beside ``NAME.zarr``
    (reused while the config that shapes it is unchanged, resumed when cut short)."""
    if out is None:
        return None
    out = Path(out)
    return str(out.with_name(out.name.removesuffix(".zarr") + "-scenarios.zarr"))


def nominal_design(c, setup, client) -> tuple:
    """(the nominal exact design, the time its searches spent): design.time_limit_s bounds
    the searches of the phase together (issue 29): the nominal design, then the bank's
    search gets what is left. Sampling (the bank's flights, the validation) is not search:
    it has its own progress bars."""
    t_nominal = time.perf_counter()
    nominal = design_exact(c, setup, client)
    return nominal, time.perf_counter() - t_nominal - float(nominal.attrs.get("design_masks_s",
                                                                               0.0))


def sizes(c, setup) -> tuple:
    """``(S, H, exact)``: the bank's scenarios (one when no continuous dispersion is drawn),
    the held-out scenarios, and whether the validation is exact (one flight)."""
    d, mc = c.config.design, c.config.monte_carlo
    exact = continuous_off(mc, setup)
    s_n = 1 if exact else d.scenarios
    # held-out scenarios (issue 41): H draws of their own stream, flown for the swarms
    # they score only (design/holdout.py)
    h_n = holdout_scenarios(d, exact)
    # losses in the pass are drawn per validation flight: sampling, even on one scenario
    return s_n, h_n, exact and failure_model(mc).in_pass_share == 0.0


def bank_phase(c, setup, client, nominal) -> tuple:
    """After the nominal design (its line printed): ``(client, S, tolerant)``, the phase's
    client, the bank's scenarios and the tolerant markers' future (or None)."""
    d = c.config.design
    result(nominal.summary.replace("exact design:", "nominal exact design (nothing goes wrong):"))
    client = phase_client(client)   # the job's one cluster (None: in this process)
    s_n = sizes(c, setup)[0]
    sep = c.config.swarm.min_separation_m
    # the tolerant designs (single-threaded HiGHS) on one worker while the other
    # builds the bank: their ~17 s no longer wait for it (same designs)
    tolerant = (client.submit(_tolerant_designs, nominal.bank, nominal.threshold, d, sep,
                              pure=False)
                if client is not None and d.tolerant_markers else None)
    return client, s_n, tolerant


def design_reliable(c, setup, client, *, bank_store: str | None = None):
    """The success-probability design of a campaign (module docstring).

    Returns the :class:`~ideas_hpc.campaign.design_exact.ExactDesign` of the
    chosen swarm (its data holds the nominal design's variables and the
    reliability ones) and its summary lines.
    """
    refuse_stereo(c, setup)
    # the most any swarm of n_max can reach is checked with the other cross-checks
    # (campaign/schema/design_table.py reliability_checks)
    nominal, spent = nominal_design(c, setup, client)
    client, s_n, tolerant = bank_phase(c, setup, client, nominal)
    t0 = time.perf_counter()
    fresh = bank_store is not None and not Path(bank_store).exists()
    bank = campaign_bank(c, setup, s_n, client, bank_store)
    t_bank = time.perf_counter() - t0
    try:
        return design_on_bank(c, setup, client, nominal, bank, t_bank, tolerant, spent_s=spent)
    except InputError:
        if fresh:    # bad input leaves no store: the bank this run made goes too
            shutil.rmtree(bank_store, ignore_errors=True)
        raise


def design_on_bank(c, setup, client, nominal, bank, t_bank, tolerant=None, *, spent_s=0.0,
                   searched=None):
    """Steps 3 to 5 of the module docstring on a built bank (``searched``: step 3 already
    made by the caller on this bank, at :func:`bank_level` and :func:`search_budget`)."""
    d, mc = c.config.design, c.config.monte_carlo
    _, h_n, exact = sizes(c, setup)
    left = search_budget(d, spent_s)
    p, model = float(d.success_probability), failure_model(mc)
    need = nominal.threshold.need
    s_n = bank.rows.shape[0]
    _log(f"scenario bank: {s_n} scenarios x {bank.theta.size} candidates in {t_bank:.1f} s"
         + (" (continuous dispersions off: one exact scenario)" if exact else "")
         # the markers' ~60 s of HiGHS hold a worker the bank would otherwise use
         + (" (one worker designed the failure-tolerant markers meanwhile)"
            if tolerant is not None and not bank.attrs.get("reused") else ""))
    sep = c.config.swarm.min_separation_m
    level = bank_level(d)
    # searched: the search a caller already made on this bank (the distance's, whose
    # choice it decided: campaign/design_distance.py), with this budget and level
    res = searched if searched is not None else bank_search(c, setup, bank, nominal.threshold,
                                                             level, left)
    rel = res.designer
    w = rel.ev.w
    if rel.ev.per_scenario_weights:     # drawn worlds: the threshold is one fraction of each
        reach = rel.ev.reach()          # world's reference; where all candidates miss it, P_s = 0
        _log(f"drawn worlds: all candidates reach {100 * reach.min():.3f} % to "
             f"{100 * reach.max():.3f} % of the scenarios' reference areas; "
             f"{int((~meets(reach, need)).sum())} of {s_n} scenarios are below the threshold "
             f"{100 * need:.3f} % whatever flies")
    held = None if not h_n else HeldOut(lambda sw: _validate(
        c, setup, bank.theta[sw], need, w, exact, client, size=h_n,
        stream=seeds.HOLDOUT_STREAM).per_sample, h_n,
        batch=lambda swarms: _held_out_batch(c, setup, bank.theta, swarms, need, w, h_n, client))
    if held is not None:    # the swarms the looks and the curve score, flown together
        held.prefetch(_scored_swarms(res, rel, int(nominal.data["best_swarm_size"]), d, exact))
    cert = _certify(c, setup, client, bank, res, rel, need, w, exact, held)
    chosen_val = cert.final.extra
    # the looks past the bank's answer: stepped up (design.demonstrate), or planned past
    # sizes that could not clear p (design/look_plan.py)
    stepped = [(lk.n, lk.bank_probability) for lk in cert.looks if lk.n != res.n]
    if cert.final.n == res.n:
        chosen = res
    else:       # status, bound and gap stay the optimisation's (of the bank-optimal res.n):
        sw = cert.final.swarm   # stepping up is the validation's decision (reliability_vars)
        chosen = type(res)(indices=sw, n=cert.final.n, probability=cert.final.bank_probability,
                           per_scenario=rel.ev.per_scenario([sw])[0], status=res.status,
                           bound=res.bound, gap=res.gap, solve_time=res.solve_time)
    looked = {lk.n: lk.extra for lk in cert.looks}
    # the reliability curve: N0 .. first N with P >= CURVE_TOP (or n_max)
    n0 = int(nominal.data["best_swarm_size"])
    m_curve = curve_samples(d, exact)
    curve = []
    for n in range(min(n0, chosen.n), d.n_max + 1):
        sw, pb = (chosen.indices, chosen.probability) if n == chosen.n else rel.best_of(n)
        if sw.size != n:
            break
        # the curve reports each N alone at design.confidence (it certifies nothing);
        # design.curve_samples = 0: the held-out scenarios alone score the other sizes
        v = looked.get(n) or (_validate(c, setup, bank.theta[sw], need, w, exact, client,
                                        size=m_curve) if m_curve else None)
        ph_v = math.nan if v is None else v.p_hat
        low = ph_v if exact or v is None else lower_confidence_bound(v.per_sample, d.confidence)
        ph = held.probability(sw) if held is not None else math.nan
        curve.append((n, pb, rel.upper(n), ph_v, low, sw, ph))
        if pb >= CURVE_TOP and n >= chosen.n:
            break
    # the markers only when asked (design.tolerant_markers): their HiGHS minute held a
    # worker idle for the bank on the main job (issue 43)
    tolerant = [] if not d.tolerant_markers else _tolerant(
        tolerant.result() if tolerant is not None else
        _tolerant_designs(nominal.bank, nominal.threshold, d, sep), rel)
    stat = None if exact else statistical_bound(rel, p, model, d.n_max, d.confidence)
    # the levels get what the design's time limit has left, at least a tenth of it
    levels = None if model.prior is None else n_at_levels(
        rel, level, d.n_max, model.prior.levels(),
        time_limit_s=max(0.1 * left, left - res.solve_time))
    return reliability_dataset(c, nominal, bank, res, chosen, chosen_val, curve, tolerant,
                               BankRun(stepped=stepped, need=need, exact=exact, t_bank_s=t_bank,
                                       cert=cert, level=level, stat=stat, model=model,
                                       levels=levels,
                                       held=None if held is None else held_scores(
                                           held, chosen, chosen_val)))


#: Sample problems cut from the bank for the statistical lower bound, and the fewest
#: scenarios each needs.
STAT_GROUPS, STAT_GROUP_MIN = 8, 16


def statistical_bound(rel, p, p_f, n_max, confidence):
    """A statistical lower bound on the true fewest N (Pagnoncelli, Ahmed & Shapiro 2009,
    sec. 2; docs/certificate.md): the bank's scenarios cut into M groups, each an
    independent sample problem at the looser level ``p'' = p - sqrt(ln 10 / (2 S_g))``
    (the true optimum feasible in each with probability >= 0.9), each bounded by the
    ring-gap bounds (:func:`~ideas_hpc.design.certificate.group_bounds`; ``p_f`` a bare
    probability or the failure model, whose upper law bounds P). Returns a dict,
    or None when the bank is too small or has no ring-gap bounds."""
    lows = rel._lows
    m = min(STAT_GROUPS, rel.s_n // STAT_GROUP_MIN)
    if lows is None or m < 2:
        return None
    s_g = rel.s_n // m
    loose = p - math.sqrt(math.log(10.0) / (2.0 * s_g))
    if loose <= 0.0:
        return None
    bounds = group_bounds(lows[:m * s_g], m, loose, p_f, n_max)
    lb, rank, theta = replicated_lower_bound(bounds, s_g, p, loose, 1.0 - confidence)
    return {"bound": lb, "rank": rank, "groups": m, "group_scenarios": s_g, "level": loose,
            "theta": theta, "group_bounds": bounds}


def held_scores(held, chosen, val) -> dict:
    """The reported swarm on the held-out scenarios: its P there, the bias of the bank's
    (selection) P, and whether the validation's P-hat agrees with the held-out P within
    their sampling error (:func:`~ideas_hpc.design.holdout.agreement`)."""
    a = agreement(held.values(chosen.indices), val.per_sample)
    return {"scenarios": held.size, "probability": a["held"],
            "bias": float(chosen.probability) - a["held"], **a}


def _certify(c, setup, client, bank, res, rel, need, w, exact, held=None):
    """The looks of :func:`ideas_hpc.design.certificate.certify` on validation flights; each
    look's ``extra`` is its :class:`Validation` (bound at the look's share of the error).
    With held-out scenarios the looks are planned from their values
    (:mod:`ideas_hpc.design.look_plan`: sizes that cannot clear p are skipped)."""
    d = c.config.design
    m = 1 if exact else verify_samples(d)

    def best_of(n):
        return (res.indices, res.probability) if n == res.n else rel.best_of(n)

    def validate(sw, first, size):
        v = _validate(c, setup, bank.theta[sw], need, w, exact, client, first=first, size=size)
        return v.per_sample, v

    cert = certify(res.n, best_of, validate, LookPlan(
        p=float(d.success_probability), confidence=d.confidence, n_max=d.n_max, n_samples=m,
        demonstrate=d.demonstrate, max_looks=d.demonstrate_looks, exact=exact,
        samples_max=d.verify_samples_max),
        values_of=None if held is None else held.values,
        rng=seeds.search_rng(c.config.seed, seeds.LOOK_PLAN))
    for lk in cert.looks:       # the one bound of each look: certify's
        lk.extra.lower = lk.lower
    return cert
