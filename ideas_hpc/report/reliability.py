"""Report lines and figures of the success-probability design (issue 20)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ideas_hpc.campaign.reliability_vars import bank_line
from ideas_hpc.design.certificate import verdict


def bank_answer(ds) -> tuple:
    """(N, P, status, bound, gap, steps) of the optimisation on the scenario bank.

    Stores written before the two answers were split say ``solver_status =
    "demonstrated"`` when design.demonstrate stepped N up, with the gap taken
    against the chosen N; their bank answer is the first N of the stored curve
    meeting p, and the status is ``optimal`` exactly when its gap is 0.
    """
    bound = float(ds["proven_bound"])
    if "bank_swarm_size" in ds:
        return (int(ds["bank_swarm_size"]), float(ds["bank_probability"]),
                str(ds["solver_status"].values), bound, float(ds["optimality_gap"]),
                ds.attrs.get("demonstrate_steps", "none"))
    n = int(ds["best_swarm_size"])
    if str(ds["solver_status"].values) != "demonstrated":
        return (n, float(ds["reliability_probability"]), str(ds["solver_status"].values),
                bound, float(ds["optimality_gap"]), "none")
    curve_n, curve_p = ds["reliability_n"].values, ds["reliability_vs_n"].values
    k = int(np.argmax(curve_p >= float(ds["success_probability_required"]) - 1e-12))
    nb = int(curve_n[k])
    gap = (nb - bound) / nb
    return (nb, float(curve_p[k]), "optimal" if gap == 0 else "not stored (older store)",
            bound, gap, f"N stepped up from {nb} to {n}" if nb < n else "none")


def swarm_label(ds) -> str:
    """Which swarm the nominal design's lines describe (issue 29): in a success-probability
    store the nominal design's, not the reported N's."""
    if "nominal_swarm_size" in ds and "success_probability_required" in ds:
        return (f"of the nominal N = {int(ds['nominal_swarm_size'])} swarm (nothing goes wrong;"
                f" not the success-probability design's N = {int(ds['best_swarm_size'])})")
    return f"of the N = {int(ds['best_swarm_size'])} design" if "best_swarm_size" in ds else ""


def reliability_lines(ds) -> list[str]:
    """The requirement, the design's P on the scenarios, the validation and the curve."""
    if "success_probability_required" not in ds:
        return []
    a = ds.attrs
    p = float(ds["success_probability_required"])
    thr = 100 * float(a["reliability_threshold"])
    conf = 100 * float(a.get("confidence", 0.95))
    ok = bool(ds["demonstrated"])
    n = int(ds["best_swarm_size"])
    n_bank, p_bank, status, bound, gap, steps = bank_answer(ds)
    failures = (a["failure_model"] if "failure_model" in a else   # stores before issue 41
                f"p_f = {float(a.get('failure_probability', float('nan'))):g} each")
    out = [f"requirement: P(coverage >= {thr:.3f} %) >= {p:g} at {conf:g} % confidence, "
           f"failures ({failures}) enumerated exactly; {a['n_scenarios']} scenarios, "
           f"{a['verify_samples']} validation samples ({a['continuous_dispersions']})",
           bank_line(n_bank, p_bank, status, bound, gap),
           f"validation of the N = {n} swarm: P-hat = {float(ds['validation_p_hat']):.4f}, "
           f"{100 * float(ds['validation_look_confidence']) if 'validation_look_confidence' in ds else conf:.4g} % lower bound "
           f"{float(ds['validation_lower_bound']):.4f} ({a['confidence_bound']}) -> "
           + "requirement " + verdict(ok),
           f"success-probability design: N = {n}, requirement "
           + verdict(ok) + " by validation"
           + (f" (design.demonstrate: {steps})" if steps != "none" else "")
           + f"; P on the scenarios = {float(ds['reliability_probability']):.4f}; nominal "
           f"N = {a['nominal_swarm_size']}"]
    if "ca_distance_choice" in a:       # design.ca_distances_km (campaign/design_distance.py)
        out.append(str(a["ca_distance_choice"]))
    if "certificate" in a:
        out.append(str(a["certificate"]))
    if "statistical_lower_bound" in a:
        out.append("statistical lower bound (beside the proof on the bank): "
                   + str(a["statistical_lower_bound"]))
    if "bank_validation_agreement" in a:
        out.append(f"held-out scoring ({a['n_holdout_scenarios']} scenarios that chose "
                   f"nothing): {a['bank_validation_agreement']}")
    if "failures_only" in a:           # do the continuous uncertainties decide? (issue 42)
        out.append(str(a["failures_only"]))
    if "p_f_levels" in a:
        out.append(str(a["p_f_levels"]))
    if "bank_level" in ds and float(ds["bank_level"]) != p:
        out.append(f"bank solved at the stricter level p' = {float(ds['bank_level']):g} "
                   f"(p = {p:g}; docs/certificate.md)")
    held = (ds["reliability_vs_n_holdout"].values if "reliability_vs_n_holdout" in ds
            else np.full(ds.sizes["reliability_n"], np.nan))
    # a size design.curve_samples = 0 left unvalidated shows its held-out P instead
    pts = [f"{int(n)}: {float(b):.4f} (<= {float(u):.4f}; " + (
           f"validated {float(v):.4f}, >= {float(lo):.4f})" if not np.isnan(v) else
           f"held-out {float(h):.4f})") for n, b, u, v, lo, h in zip(
               ds["reliability_n"].values, ds["reliability_vs_n"].values,
               ds["reliability_vs_n_upper"].values, ds["reliability_vs_n_validated"].values,
               ds["reliability_vs_n_lower"].values, held)]
    out.append("P of mapping the threshold vs N (scenarios, proven bound; validation): "
               + "; ".join(pts))
    if ds.sizes.get("tolerated", 0):
        out.append("k-failure-tolerant designs on the scenarios: " + ", ".join(
            f"k = {int(k)}: N = {int(n)}, P = {float(q):.4f}" for k, n, q in zip(
                ds["tolerated"].values, ds["tolerant_swarm_size"].values,
                ds["tolerant_probability"].values)))
    return out


def reliability_figures(ds, out: Path) -> list[Path]:
    from ideas_hpc.plots import reliability

    if "reliability_vs_n" not in ds:
        return []
    return [reliability.reliability_curve(ds, out / "design_reliability_curve.png"),
            reliability.validation_coverage(ds, out / "design_validation_coverage.png")]
