"""The one wording of ``ideas-hpc study``'s answers (:mod:`ideas_hpc.campaign.study`), read
from their store groups: the command prints these lines and ``ideas-hpc report`` shows
them."""

from __future__ import annotations

import numpy as np

from ideas_hpc.base.units import KM

#: The stored price of ignorance when a case reaches no N up to ``design.n_max``.
PRICE_UNDEFINED = -999


def _n(ds, i: int) -> str:
    """Row ``i``'s fewest N, with the search's status when it is not proven."""
    n = int(ds["fewest_n"].values[i])
    if n <= 0:
        return "no N <= n_max"
    st = str(ds["fewest_status"].values[i]) if "fewest_status" in ds else "optimal"
    return f"N = {n}" + ("" if st == "optimal" else
                         f" ({st}, proven >= {int(ds['fewest_bound'].values[i])})")


def _p(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{x:.4f}"


def ignorance_line(ds) -> str:
    """The price of ignorance: both fewest N, their P, the difference."""
    p = ds["fewest_probability"].values
    price = int(ds.attrs["price"])
    words = ("undefined (a case reaches no N)" if price == PRICE_UNDEFINED else
             f"{price:+d} spacecraft" + (" (negative: the nominal body is harder to map "
                                         "than the prior's average world)" if price < 0 else ""))
    if price != PRICE_UNDEFINED and "fewest_status" in ds and any(
            str(x) != "optimal" for x in ds["fewest_status"].values):
        words += " (not proven: a search stopped before proving its N)"
    return (f"price of ignorance: prior {_n(ds, 0)} (P_bank {_p(p[0])}), known nominal body "
            f"{_n(ds, 1)} (P_bank {_p(p[1])}) at the same encounter, navigation and "
            f"requirement (level {float(ds.attrs['bank_level']):g}): {words}")


def navigation_line(ds) -> str:
    """P of the designed swarm and the fewest N against the B-plane 1-sigma."""
    own = float(ds.attrs["campaign_sigma_m"])
    parts = []
    for i, (s, sp, n, pn) in enumerate(zip(ds["bplane_sigma"].values,
                                           ds["swarm_probability"].values,
                                           ds["fewest_n"].values,
                                           ds["fewest_probability"].values)):
        mark = "*" if s == own else ""
        parts.append(f"{s / KM:g}{mark} km: P {sp:.4f}, {_n(ds, i)}"
                     + (f" (P {pn:.4f})" if n > 0 else ""))
    mono = "monotone" if int(ds.attrs["monotone"]) else "NOT monotone"
    return (f"value of a late navigation update (B-plane 1-sigma; * the campaign's): "
            + "; ".join(parts) + f"; the designed swarm's P is {mono} in sigma "
            "(common random numbers)")


def per_target_line(ds) -> str:
    """The share of target worlds whose conditional P reaches p."""
    a = ds.attrs
    cond = ds["conditional_probability"].values
    q = np.percentile(cond, [10, 50, 90])
    se = ds["conditional_std_error"].values
    return (f"per-target reliability: {int(a['meeting'])} of {int(a['worlds'])} target worlds "
            f"have conditional P >= {float(a['success_probability']):g} "
            f"({float(a['share']):.3f}, Wilson 95 % [{float(a['wilson_low']):.3f}, "
            f"{float(a['wilson_high']):.3f}]); conditional P 10/50/90 % {q[0]:.3f} / "
            f"{q[1]:.3f} / {q[2]:.3f}, mean {cond.mean():.4f}; {int(a['per_world'])} inner "
            f"draws per world (median standard error "
            f"{float(np.nanmedian(se)) if np.isfinite(se).any() else float('nan'):.3f})")


def distance_line(ds) -> str:
    """Fewest N, its P, GSD and LOS rate against the closest-approach distance, and the
    best distance."""
    own = float(ds.attrs["campaign_distance_m"])
    parts = []
    for i, d in enumerate(ds["ca_distance"].values):
        n, pn = int(ds["fewest_n"].values[i]), float(ds["fewest_probability"].values[i])
        mark = "*" if d == own else ""
        parts.append(f"{d / KM:.4g}{mark} km: {_n(ds, i)}" + (f" (P {pn:.4f})" if n > 0 else "")
                     + f", GSD {float(ds['gsd'].values[i]):.3g} m, LOS rate "
                     f"{np.rad2deg(float(ds['los_rate'].values[i])):.3g} deg/s")
    b = int(ds.attrs["best"])
    best = ("none reaches the level" if b < 0 else
            f"best {float(ds['ca_distance'].values[b]) / KM:.4g} km (fewest N, ties by higher P)")
    return ("closest-approach distance (* the campaign's; same seeds): " + "; ".join(parts)
            + f"; {best}")


LINES = {"ignorance": ignorance_line, "navigation": navigation_line,
         "per-target": per_target_line, "distance": distance_line}


def answer_line(name: str, ds) -> str:
    """The line of answer ``name`` (``ignorance``, ``navigation``, ``per-target``,
    ``distance``)."""
    return LINES[name](ds)
