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
==================================  ======================  =========================================
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ideas_hpc.seeds import SCENARIO_STREAM, VALIDATION_STREAM
from ideas_hpc.campaign.design_exact import ExactDesign

BOUND_METHOD = "Waudby-Smith & Ramdas betting (predictable plug-in), one-sided"


def _with(ds: xr.Dataset, name: str, units: str | None, long_name: str) -> None:
    if units is not None:
        ds[name].attrs["units"] = units
    ds[name].attrs["long_name"] = long_name


def verdict(val, p: float) -> str:
    return "DEMONSTRATED" if val.lower >= p else "NOT demonstrated"


def bank_line(n: int, probability: float, status: str, bound: float, gap: float) -> str:
    """The optimisation's answer on the scenario bank, worded apart from the validation."""
    return (f"optimisation on the scenario bank: fewest N meeting p = {int(n)} (P = "
            f"{probability:.4f}; {status}, proven lower bound {bound:g}, gap "
            f"{100 * gap:.1f} %)")


def reliability_dataset(c, nominal: ExactDesign, bank, res, chosen, val, curve, tolerant, *,
                        stepped, need: float, exact: bool, t_bank: float) -> ExactDesign:
    """The :class:`ExactDesign` of the chosen swarm with the variables of the module docstring."""
    d = c.config.design
    p = float(d.success_probability)
    conf = float(d.confidence)
    idx = np.asarray(chosen.indices, dtype=np.int64)
    theta = bank.theta[idx]
    width = max(r[0] for r in curve) if curve else idx.size
    sw = np.full((len(curve), width), np.nan)
    for i, r in enumerate(curve):
        sw[i, :r[0]] = bank.theta[r[5]]
    nominal_cov = float(nominal.bank.coverage([idx])[0]) if nominal.bank is not None else np.nan
    outcome = "demonstrated" if val.lower >= p else "not demonstrated"
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
    _with(new, "validation_lower_bound", "1", f"{100 * conf:g} % lower confidence bound on P "
          f"({BOUND_METHOD})")
    _with(new, "demonstrated", "1", "validation lower bound >= required probability")
    _with(new, "validation_coverage", "1", "coverage of each validation flight with failures "
          "sampled")
    _with(new, "validation_n_failed", "1", "failed spacecraft in each validation flight")
    _with(new, "reliability_vs_n", "1", f"best P({thr}) of N spacecraft on the scenarios")
    _with(new, "reliability_vs_n_upper", "1", "proven upper bound on P of any N spacecraft "
          "(scenario programme)")
    _with(new, "reliability_vs_n_validated", "1", "validated P-hat of that swarm")
    _with(new, "reliability_vs_n_lower", "1", f"{100 * conf:g} % lower confidence bound")
    _with(new, "reliability_vs_n_swarm", "rad", "swarm angles of the curve's swarms (NaN: unused)")
    _with(new, "tolerant_swarm_size", "1", "spacecraft of the k-failure-tolerant design")
    _with(new, "tolerant_probability", "1", "its P on the scenario bank")
    ds = xr.merge([ds.drop_vars([k for k in new.data_vars if k in ds]), new],
                  combine_attrs="override")
    attrs = dict(nominal.attrs)
    attrs.update({
        "design_method": "exact-reliability", "solver_status": res.status,
        "optimality_gap": float(res.gap), "proven_bound": float(res.bound),
        "bank_swarm_size": int(res.n), "validation_outcome": outcome,
        "demonstrate_steps": steps, "success_probability": p, "confidence": conf,
        "n_scenarios": int(bank.rows.shape[0]), "reliability_threshold": float(need),
        "failure_probability": float(c.config.monte_carlo.failure_probability), "verify_samples": int(val.per_sample.size),
        "scenario_stream": SCENARIO_STREAM, "validation_stream": VALIDATION_STREAM,
        "scenario_bank_hash": str(bank.attrs.get("config_hash", "")),
        "scenario_bank_s": float(t_bank), "reliability_solve_s": float(res.solve_time),
        "validation_p_hat": float(val.p_hat), "validation_lower_bound": float(val.lower),
        "demonstrated": int(val.lower >= p), "confidence_bound": BOUND_METHOD,
        "continuous_dispersions": "off (exact)" if exact else "sampled",
        "nominal_swarm_size": int(nominal.data["best_swarm_size"]),
    })
    notes = list(nominal.notes) + list(res.notes)
    if stepped:
        notes.append(f"design.demonstrate: {steps} until the validation bound reached p = {p:g}"
                     if val.lower >= p else
                     f"design.demonstrate: {steps} (n_max) without demonstrating p")
    n_val = val.per_sample.size
    samples = "the one exact scenario (continuous dispersions off)" if exact else f"{n_val} fresh samples"
    summary = (f"success-probability design for P({thr}) >= {p:g}: N = {chosen.n}, "
               f"requirement {verdict(val, p)} by validation"
               + (f" (design.demonstrate: {steps})" if stepped else "")
               + f"; P = {chosen.probability:.4f} on {bank.rows.shape[0]} scenarios; "
               f"validation over {samples}: P-hat = {val.p_hat:.4f}, {100 * conf:g} % lower "
               f"bound {val.lower:.4f}; "
               f"{bank_line(res.n, res.probability, res.status, res.bound, res.gap)}; "
               f"nominal N = {attrs['nominal_swarm_size']}")
    return ExactDesign(theta=theta, data=ds, attrs=attrs, notes=notes, summary=summary,
                       bank=nominal.bank)
