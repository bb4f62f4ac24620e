"""Store variables and summary lines of the success-probability design (issue 20).

The chosen design replaces the nominal one in ``best_swarm_size`` and
``design_coverage`` (the nominal design stays as ``nominal_swarm_size`` and
``nominal_solver_status``). Two questions are answered apart:

* the optimisation on the scenario bank: ``solver_status`` (optimal,
  time_limit, feasible), ``proven_bound`` and ``optimality_gap`` are those of
  ``bank_swarm_size``, the fewest N found to meet p on the scenarios
  (``bank_probability``);
* the validation: ``validation_outcome`` ("demonstrated" / "not demonstrated",
  ``demonstrated`` the same as a bool); when ``design.demonstrate`` stepped N
  up, ``best_swarm_size`` > ``bank_swarm_size`` (attr ``demonstrate_steps``
  says "from a to b").

The rest is new:

==================================  ======================  =========================================
variable                            dims                    meaning
==================================  ======================  =========================================
success_probability_required        ()                      p
reliability_probability             ()                      P on the scenario bank (failures exact)
scenario_probability                (scenario,)             exact failure-weighted P per scenario
validation_probability              (validation_sample,)    the same for each fresh sample
validation_p_hat, _lower_bound      ()                      their mean and lower confidence bound
bank_swarm_size, _probability       ()                      fewest N meeting p on the bank, its P
validation_outcome, demonstrated    ()                      lower bound >= p (str, bool)
validation_coverage, _n_failed      (validation_sample,)    coverage with failures sampled (figure)
reliability_vs_n (_upper,           (reliability_n,)        best P on the scenarios (proven upper
_validated, _lower, _swarm)                                 bound), validated P-hat and its bound
tolerant_swarm_size, _prob.         (tolerated,)            k-failure-tolerant designs on the curve
bank_level                          ()                      p' the bank was solved at (p by default)
validation_looks (_planned)         ()                      looks made (planned, K) by the design
validation_first_sample             ()                      first validation sample of the final look
validation_look_confidence          ()                      confidence of each look, 1 - alpha / K
validation_look_n (_p_hat,          (validation_look,)      each look's swarm size, P-hat, bound and
_lower_bound, _first_sample)                                first validation sample, in order
statistical_lower_bound             ()                      lower bound on the true fewest N (docs)
holdout_probability, bank_bias      ()                      P of the reported swarm on the held-out
                                                            scenarios; bank P minus it (issue 41)
bank_validation_agree               ()                      held-out P inside the validation's 95 %
                                                            interval
reliability_vs_n_holdout            (reliability_n,)        the curve's swarms on the held-out ones
swarm_size_at_p_f                   (p_f_level,)            p_f uncertain: the fewest N with p_f
                                                            known at each of the prior's levels
probability_at_p_f                  (p_f_level,)            its P on the bank at that p_f
proven_bound_at_p_f                 (p_f_level,)            the proven lower bound on N there
scenario_vertex_weight              (scenario, vertex)      drawn worlds only (issue 42): each
                                                            scenario's vertex area fractions
scenario_reach                      (scenario,)             drawn worlds only: what all grid
                                                            candidates reach in each scenario
==================================  ======================  =========================================

Attrs ``failure_model`` (one line) and ``failure_model_record`` (the resolved
:class:`~ideas_hpc.failures.model.FailureModel`) say which failure model P is
for (docs/failure-model.md); ``p_f_levels`` words the levels.

The certificate (:mod:`ideas_hpc.design.certificate`, docs/certificate.md) is
``validation_lower_bound``: the final look's bound, on its own fresh samples,
at the look's share of the error; attr ``certificate`` words it in one line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from ideas_hpc.base.vertex_weights import normalised
from ideas_hpc.design.reliability_eval import Evaluator
from ideas_hpc.design.api.methods import method_of_designer
from ideas_hpc.base.seeds import SCENARIO_STREAM, VALIDATION_STREAM
from ideas_hpc.campaign.design_exact import ExactDesign
from ideas_hpc.campaign.failures_only import effect_record
from ideas_hpc.design.certificate import verdict as certificate_verdict
from ideas_hpc.design.reliability_levels import levels_line

BOUND_METHOD = "Waudby-Smith & Ramdas betting (predictable plug-in), one-sided"


def _with(ds: xr.Dataset, name: str, units: str | None, long_name: str) -> None:
    if units is not None:
        ds[name].attrs["units"] = units
    ds[name].attrs["long_name"] = long_name


def verdict(val, p: float) -> str:
    return certificate_verdict(val.lower >= p)


def bank_line(n: int, probability: float, status: str, bound: float, gap: float) -> str:
    """The optimisation's answer on the scenario bank, worded apart from the validation."""
    return (f"optimisation on the scenario bank: fewest N meeting p = {int(n)} (P = "
            f"{probability:.4f}; {status}, proven lower bound {bound:g}, gap "
            f"{100 * gap:.1f} %)")


def _look_vars(cert) -> dict:
    """Per-look variables (dimension ``validation_look``): swarm size, P-hat, bound, first sample."""
    looks = cert.looks if cert is not None else []
    rows = [(lk.n, lk.p_hat, lk.lower, lk.first) for lk in looks]
    dim = ("validation_look",)
    return {"validation_look_n": (dim, np.array([r[0] for r in rows], np.int64)),
            "validation_look_p_hat": (dim, np.array([r[1] for r in rows], float)),
            "validation_look_lower_bound": (dim, np.array([r[2] for r in rows], float)),
            "validation_look_first_sample": (dim, np.array([r[3] for r in rows], np.int64))}


def _held_vars(held: dict, curve) -> xr.Dataset:
    """The held-out scoring (issue 41): the reported swarm's P there, the bank's bias, the
    curve's swarms there (dimension ``reliability_n``)."""
    ds = xr.Dataset({
        "holdout_probability": ((), float(held["probability"])),
        "bank_bias": ((), float(held["bias"])),
        "bank_validation_agree": ((), bool(held["agrees"])),
        "reliability_vs_n_holdout": (("reliability_n",), np.array([r[6] for r in curve])),
    })
    _with(ds, "holdout_probability", "1", f"P of the reported swarm on the "
          f"{held['scenarios']} held-out scenarios (they chose nothing: unbiased)")
    _with(ds, "bank_bias", "1", "reliability_probability - holdout_probability: the "
          "optimiser's bias of the bank's P for the swarm it chose")
    _with(ds, "bank_validation_agree", "1", "holdout_probability and validation_p_hat agree "
          "within their 95 % sampling error (|difference| <= 1.96 sqrt(s_v^2/M + s_h^2/H))")
    _with(ds, "reliability_vs_n_holdout", "1", "P of the curve's swarms on the held-out "
          "scenarios")
    return ds


def world_vars(rows, areas) -> xr.Dataset:
    """``scenario_vertex_weight`` (scenario, vertex) and ``scenario_reach`` (scenario,) of a
    bank whose vertex weights differ by scenario (issue 42; a shared (V,) keeps the nominal
    ``vertex_area`` alone): each scenario's area fractions (zero outside its reference) and
    the coverage all candidates reach together there with them."""
    w = normalised(areas, np.shape(rows)[0])
    ds = xr.Dataset({"scenario_vertex_weight": (("scenario", "vertex"), w),
                     "scenario_reach": (("scenario",), Evaluator(rows, w, 0.0, 0.0).reach())})
    _with(ds, "scenario_vertex_weight", "1", "area fraction of each vertex in each scenario's "
          "world (its reference area; each row sums to 1)")
    _with(ds, "scenario_reach", "1", "coverage all grid candidates reach together in each "
          "scenario, with that scenario's weights")
    return ds


def _level_vars(levels) -> xr.Dataset:
    """The designs at the prior's levels (dimension ``p_f_level``, coordinate its p_f)."""
    dim = ("p_f_level",)
    ds = xr.Dataset({
        "swarm_size_at_p_f": (dim, np.array([a.n for a in levels], np.int64)),
        "probability_at_p_f": (dim, np.array([a.probability for a in levels])),
        "proven_bound_at_p_f": (dim, np.array([a.bound for a in levels])),
    }, coords={"p_f_level": np.array([a.p_f for a in levels])})
    _with(ds, "p_f_level", "1", "p_f known at the prior's levels (quantiles or values)")
    _with(ds, "swarm_size_at_p_f", "1", "fewest N found meeting the bank's level with p_f "
          "known at that value (0: none of at most n_max)")
    _with(ds, "probability_at_p_f", "1", "its P on the scenario bank at that p_f")
    _with(ds, "proven_bound_at_p_f", "1", "proven lower bound on N at that p_f")
    return ds


@dataclass(frozen=True)
class BankRun:
    """How the design on the scenario bank went: ``stepped`` the looks' (N, P_bank) past
    the first, ``need`` the coverage threshold (fraction), ``exact`` one exact scenario,
    ``t_bank_s`` the bank's wall time, ``cert`` the certificate, ``level`` the level
    the bank was solved at (None: p), ``stat`` the statistical lower bound, ``model``
    the failure model, ``levels`` the designs at the prior's levels (None: p_f known),
    ``held`` the reported swarm on the held-out scenarios (None: none held out)."""

    stepped: list
    need: float
    exact: bool
    t_bank_s: float
    cert: object = None
    level: float | None = None
    stat: dict | None = None
    model: object = None
    levels: list | None = None
    held: dict | None = None      # the reported swarm on the held-out scenarios (held_scores)


def reliability_dataset(c, nominal: ExactDesign, bank, res, chosen, val, curve, tolerant,
                        run: BankRun) -> ExactDesign:
    """The :class:`ExactDesign` of the chosen swarm with the variables of the module docstring."""
    stepped, need, exact, t_bank = run.stepped, run.need, run.exact, run.t_bank_s
    cert, level, stat = run.cert, run.level, run.stat
    d = c.config.design
    p = float(d.success_probability)
    conf = float(d.confidence)
    level = p if level is None else float(level)
    look_conf = conf if cert is None else float(cert.final.confidence)
    looks = 1 if cert is None else len(cert.looks)
    planned = 1 if cert is None else int(cert.planned)
    first = 0 if cert is None else int(cert.final.first)
    idx = np.asarray(chosen.indices, dtype=np.int64)
    theta = bank.theta[idx]
    width = max(r[0] for r in curve) if curve else idx.size
    sw = np.full((len(curve), width), np.nan)
    for i, r in enumerate(curve):
        sw[i, :r[0]] = bank.theta[r[5]]
    nominal_cov = float(nominal.bank.coverage([idx])[0]) if nominal.bank is not None else np.nan
    outcome = certificate_verdict(val.lower >= p, stored=True)
    steps = f"N stepped up from {res.n} to {chosen.n}" if stepped else "none"
    ds = nominal.data.copy()
    ds = ds.rename({"best_swarm_size": "nominal_swarm_size",
                    "solver_status": "nominal_solver_status"})
    _with(ds, "nominal_swarm_size", "1", "fewest spacecraft of the nominal design (nothing "
          "goes wrong)")
    _with(ds, "nominal_solver_status", "1", "solver status of the nominal design (optimal, "
          "time_limit, feasible)")
    new = xr.Dataset({
        "best_swarm_size": ((), np.int64(chosen.n)),
        "solver_status": ((), res.status),
        "optimality_gap": ((), float(res.gap)),
        "proven_bound": ((), float(res.bound)),
        "bank_swarm_size": ((), np.int64(res.n)),
        "bank_probability": ((), float(res.probability)),
        "validation_outcome": ((), outcome),
        "design_coverage": ((), nominal_cov),
        "success_probability_required": ((), p),
        "reliability_probability": ((), float(chosen.probability)),
        "scenario_probability": (("scenario",), chosen.per_scenario),
        "validation_probability": (("validation_sample",), val.per_sample),
        "validation_p_hat": ((), val.p_hat),
        "validation_lower_bound": ((), val.lower),
        "demonstrated": ((), bool(val.lower >= p)),
        "validation_coverage": (("validation_sample",), val.coverage),
        "validation_n_failed": (("validation_sample",), val.n_failed),
        "reliability_vs_n": (("reliability_n",), np.array([r[1] for r in curve])),
        "reliability_vs_n_upper": (("reliability_n",), np.array([r[2] for r in curve])),
        "reliability_vs_n_validated": (("reliability_n",), np.array([r[3] for r in curve])),
        "reliability_vs_n_lower": (("reliability_n",), np.array([r[4] for r in curve])),
        "reliability_vs_n_swarm": (("reliability_n", "reliability_slot"), sw),
        "tolerant_swarm_size": (("tolerated",), np.array([t[1] for t in tolerant], np.int64)),
        "tolerant_probability": (("tolerated",), np.array([t[2] for t in tolerant])),
        "bank_level": ((), level),
        "validation_looks": ((), np.int64(looks)),
        "validation_looks_planned": ((), np.int64(planned)),
        "validation_first_sample": ((), np.int64(first)),
        "validation_look_confidence": ((), look_conf),
        **_look_vars(cert),
        "statistical_lower_bound": ((), float("nan") if stat is None or stat["rank"] == 0
                                    else float(stat["bound"])),
    }, coords={"reliability_n": np.array([r[0] for r in curve], dtype=np.int64),
               "tolerated": np.array([t[0] for t in tolerant], dtype=np.int64)})
    thr = f"coverage >= {100 * need:.3f} %"
    _with(new, "optimality_gap", "1", "(N - proven lower bound) / N of bank_swarm_size")
    _with(new, "bank_swarm_size", "1", f"fewest N found with P({thr}) >= p on the scenario "
          "bank (the optimisation's answer, before design.demonstrate)")
    _with(new, "bank_probability", "1", f"P({thr}) of that swarm on the scenario bank")
    _with(new, "validation_outcome", "1", "requirement demonstrated by the validation or not "
          "(lower bound >= required probability)")
    _with(new, "design_coverage", "1", "nominal coverage of the chosen swarm")
    _with(new, "success_probability_required", "1", f"required P({thr})")
    _with(new, "reliability_probability", "1", f"P({thr}) on the scenario bank, failures exact")
    _with(new, "scenario_probability", "1", f"P({thr}) in each scenario, failures exact")
    _with(new, "validation_probability", "1", f"P({thr}) in each validation sample, "
          "failures exact")
    _with(new, "validation_p_hat", "1", "mean of validation_probability")
    _with(new, "validation_lower_bound", "1", f"{100 * look_conf:.4g} % lower confidence bound on "
          f"P of the reported swarm over its own fresh samples ({BOUND_METHOD}; the look's share "
          f"of 1 - {conf:g}: the certificate)")
    _with(new, "bank_level", "1", "level p' >= p the scenario bank was solved at")
    _with(new, "statistical_lower_bound", "1", f"{100 * conf:g} % statistical lower bound on "
          "the true fewest N (replicated sample problems cut from the bank, ring-gap bounds; "
          "NaN: none)")
    _with(new, "validation_look_n", "1", "swarm size of each validation look, in order")
    _with(new, "validation_look_p_hat", "1", "P-hat of each look")
    _with(new, "validation_look_lower_bound", "1", "lower bound of each look at "
          "validation_look_confidence (the last is the certificate)")
    _with(new, "validation_look_first_sample", "1", "first validation sample of each look")
    _with(new, "validation_looks", "1", "validation looks made (one swarm size each)")
    _with(new, "validation_looks_planned", "1", "looks planned from the bank, K; each at "
          "(1 - confidence) / K")
    _with(new, "validation_first_sample", "1", "index of the final look's first validation "
          "sample (its samples follow, disjoint from every other look's)")
    _with(new, "validation_look_confidence", "1", "confidence of each look's bound, "
          "1 - (1 - confidence) / K")
    _with(new, "demonstrated", "1", "validation lower bound >= required probability")
    _with(new, "validation_coverage", "1", "coverage of each validation flight with failures "
          "sampled")
    _with(new, "validation_n_failed", "1", "failed spacecraft in each validation flight")
    _with(new, "reliability_vs_n", "1", f"best P({thr}) of N spacecraft on the scenarios")
    _with(new, "reliability_vs_n_upper", "1", "proven upper bound on P of any N spacecraft "
          "(scenario programme)")
    _with(new, "reliability_vs_n_validated", "1", "validated P-hat of that swarm")
    _with(new, "reliability_vs_n_lower", "1", f"{100 * conf:g} % lower confidence bound of each "
          "N alone (samples from 0, not a certificate)")
    _with(new, "reliability_vs_n_swarm", "rad", "swarm angles of the curve's swarms (NaN: unused)")
    _with(new, "tolerant_swarm_size", "1", "spacecraft of the k-failure-tolerant design")
    _with(new, "tolerant_probability", "1", "its P on the scenario bank")
    if run.levels:
        new = new.merge(_level_vars(run.levels))
    if run.held is not None:
        new = new.merge(_held_vars(run.held, curve))
    if np.ndim(bank.areas) == 2:        # drawn worlds: the weights differ by scenario
        new = new.merge(world_vars(bank.rows, bank.areas))
    effect = None if exact else effect_record(nominal.bank, idx, need, run.model, val, run.held)
    if effect is not None:              # do the continuous uncertainties decide? (issue 42)
        new = new.merge(xr.Dataset(effect[0]))
        _with(new, "failures_only_probability", "1", f"P({thr}) of the chosen swarm on the "
              "nominal world, failures only (enumerated)")
    ds = xr.merge([ds.drop_vars([k for k in new.data_vars if k in ds]), new],
                  combine_attrs="override")
    attrs = dict(nominal.attrs)
    attrs.update({
        "design_method": method_of_designer("success-probability").name, "solver_status": res.status,
        "optimality_gap": float(res.gap), "proven_bound": float(res.bound),
        "bank_swarm_size": int(res.n), "validation_outcome": outcome,
        "demonstrate_steps": steps, "success_probability": p, "confidence": conf,
        "n_scenarios": int(bank.rows.shape[0]), "reliability_threshold": float(need),
        "failure_probability": (float(run.model.p_f[0]) if len(run.model.p_f) == 1
                                else list(run.model.p_f)),
        "failure_model": run.model.describe(), "failure_model_record": run.model.record(),
        "verify_samples": int(val.per_sample.size),
        "scenario_stream": SCENARIO_STREAM, "validation_stream": VALIDATION_STREAM,
        "scenario_bank_hash": str(bank.attrs.get("config_hash", "")),
        "scenario_bank_s": float(t_bank), "reliability_solve_s": float(res.solve_time),
        "validation_p_hat": float(val.p_hat), "validation_lower_bound": float(val.lower),
        "demonstrated": int(val.lower >= p), "confidence_bound": BOUND_METHOD,
        "continuous_dispersions": "off (exact)" if exact else "sampled",
        "nominal_swarm_size": int(nominal.data["best_swarm_size"]),
        "bank_level": level, "validation_looks": looks, "validation_looks_planned": planned,
        "validation_first_sample": first, "validation_look_confidence": look_conf,
    })
    if cert is not None:
        attrs["certificate"] = cert.line()
    if effect is not None:
        attrs.update(effect[1])
    if run.levels:
        attrs["p_f_levels"] = levels_line(run.levels, level)
    if run.held is not None:
        h = run.held
        attrs.update({"n_holdout_scenarios": int(h["scenarios"]),
                      "holdout_probability": float(h["probability"]),
                      "bank_bias": float(h["bias"]),
                      "bank_validation_agreement": (
                          f"held-out P {h['probability']:.4f} and validation P-hat "
                          f"{h['p_hat']:.4f} {'agree' if h['agrees'] else 'DISAGREE'} within "
                          f"their sampling error (difference {h['p_hat'] - h['probability']:+.4f}"
                          f", 95 %: +-{1.959963984540054 * h['se']:.4f}); the validation's own "
                          f"95 % interval [{h['interval'][0]:.4f}, {h['interval'][1]:.4f}] "
                          f"{'holds' if h['inside'] else 'misses'} the held-out P; bank P "
                          f"{chosen.probability:.4f} on the scenarios that chose the swarm: "
                          f"bias {h['bias']:+.4f}")})
    if stat is not None:
        attrs["statistical_lower_bound"] = (
            f"true fewest N >= {stat['bound']:g} at {100 * conf:g} % confidence: the "
            f"{stat['rank']}-th smallest of {stat['groups']} sample problems' bounds "
            f"({stat['group_scenarios']} scenarios each, level {stat['level']:.4f}; "
            f"{[int(b) for b in stat['group_bounds']]})" if stat["rank"] else
            f"none at {100 * conf:g} % confidence from {stat['groups']} sample problems of "
            f"{stat['group_scenarios']} scenarios")
    # the nominal design's notes describe the nominal swarm, not the reported one (issue 29)
    notes = [f"nominal design (N = {attrs['nominal_swarm_size']}): {n}" for n in nominal.notes] \
        + list(res.notes)
    if stepped:
        notes.append(f"design.demonstrate: {steps} until the validation bound reached p = {p:g}"
                     if val.lower >= p else
                     f"design.demonstrate: {steps} (n_max) without demonstrating p")
    if not run.model.is_plain:
        notes.append(f"failure model: {run.model.describe()}"
                     + ("; the bank scores a loss in the pass as a whole-pass loss (a lower "
                        "bound on P), its proofs as a survival (an upper bound); the validation "
                        "draws the loss times" if run.model.in_pass_share else ""))
    if run.levels:
        notes.append(attrs["p_f_levels"])
    if level != p:
        notes.append(f"design.bank_level: the bank solved at the stricter level p' = {level:g} "
                     f"(p = {p:g}) so that its swarm validates at the first look")
    n_val = val.per_sample.size
    samples = "the one exact scenario (continuous dispersions off)" if exact else f"{n_val} fresh samples"
    summary = (f"success-probability design for P({thr}) >= {p:g}: N = {chosen.n}, "
               f"requirement {verdict(val, p)} by validation"
               + (f" (design.demonstrate: {steps})" if stepped else "")
               + f"; P = {chosen.probability:.4f} on {bank.rows.shape[0]} scenarios"
               + ("" if run.held is None else
                  f", {run.held['probability']:.4f} on {run.held['scenarios']} held-out "
                  f"(bias {run.held['bias']:+.4f})") + "; "
               f"validation over {samples}: P-hat = {val.p_hat:.4f}, {100 * look_conf:.4g} % "
               f"lower bound {val.lower:.4f}; "
               f"{bank_line(res.n, res.probability, res.status, res.bound, res.gap)}; "
               f"nominal N = {attrs['nominal_swarm_size']}"
               + (f"\n{attrs['certificate']}" if cert is not None else "")
               + (f"\n{effect[2]}" if effect is not None else ""))
    return ExactDesign(theta=theta, data=ds, attrs=attrs, notes=notes, summary=summary,
                       bank=nominal.bank)
