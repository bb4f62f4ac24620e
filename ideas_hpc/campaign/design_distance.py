"""The closest-approach distance as a dimension of the success-probability design
(``design.ca_distances_km``; issue 42 deliverable 5: "offer closest-approach distance from
a short list: it trades GSD against line-of-sight rate and navigation error").

For each distance ``d`` of the list (sorted, each once) the campaign is validated again
with ``flyby.d_sep_km = d`` (:func:`~ideas_hpc.campaign.study_distance.distance_campaign`:
the separation, grid-step and pointing checks of that distance apply) and, exactly as a
run of the single-distance design with ``--set flyby.d_sep_km=d`` would:

1. its nominal exact design (:func:`~ideas_hpc.campaign.design_exact.design_exact`: the
   requirement's threshold at that distance, and the search time it spent);
2. its scenario bank from the campaign's seed and scenario stream (common random numbers:
   the same worlds, dispersions and navigation draws at every distance; only the ring's
   radius differs);
3. the fewest N with ``P_bank >= p'`` on it
   (:func:`~ideas_hpc.campaign.bank_design.bank_search`), with what ``design.time_limit_s``
   leaves after step 1.

**The rule.** The chosen distance is the one of fewest N on its bank; at equal N a
distance whose N is proven (solver status ``optimal``, gap 0) beats one whose search
left a gap (``time_limit`` or ``feasible``: sizes below it neither proven short of p' nor
met), then the higher bank P of that fewest-N swarm wins, then the shorter
distance. An unproven N is the fewest *found*, an upper bound on that distance's true
fewest N: a smaller unproven N is therefore truly better than a larger proven one and may
win, but an unproven N never wins a tie against a proven one (its true N may be smaller or
not; the proven one is known). A distance where no swarm of ``design.n_max`` reaches p'
(or where its nominal design finds no grid candidate mapping anything, or no swarm
reaching the target: a single-distance run there stops with that error) takes no part;
when none takes part, the run stops with one line naming ``design.ca_distances_km``. The
choice reads the banks only: the held-out scenarios and the validation samples have chosen
nothing, so the held-out bias and the certificate stay honest. Then the rest of the
design (held-out scoring, the looks, the certificate, the reliability curve:
:func:`~ideas_hpc.campaign.design_reliability.design_on_bank`) runs at the chosen distance
only, exactly as the single-distance design, and the store flies and records that
distance's campaign.

Store variables over ``ca_distance`` (m, ascending): ``ca_distance_swarm_size`` (fewest N,
-1 where none reaches p'), ``ca_distance_bank_probability``, ``ca_distance_proven``,
``ca_distance_solver_status``, ``ca_distance_threshold``, ``ca_distance_gsd_m`` and
``ca_distance_los_rate_rad_s`` (:func:`~ideas_hpc.campaign.study_distance.camera_figures`)
and ``chosen_ca_distance_m``; attrs ``chosen_ca_distance_m``, ``ca_distances_m``,
``ca_distance_rule`` and the one summary line ``ca_distance_choice``.
"""

from __future__ import annotations

import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import log
from ideas_hpc.base.units import KM
from ideas_hpc.campaign.bank_design import (bank_level, bank_search, campaign_bank,
                                            refuse_stereo, search_budget)
from ideas_hpc.campaign.design_exact import checked_setup
from ideas_hpc.campaign.design_reliability import (bank_phase, design_on_bank, nominal_design,
                                                   sizes)
from ideas_hpc.campaign.study_distance import camera_figures, camera_ifov_rad, distance_campaign
from ideas_hpc.engine.job_cluster import phase_client

#: The key naming the list (InputError field).
FIELD = "design.ca_distances_km"
#: The rule, in words (attr ``ca_distance_rule``).
RULE = ("fewest N on the distance's bank; at equal N a proven N before an unproven one "
        "(a gap left: the fewest found, an upper bound), then the higher bank P of the "
        "fewest-N swarm, then the shorter distance; held-out scenarios and validation "
        "samples choose nothing")


@dataclass
class DistanceRow:
    """One distance of the list: its campaign, setup, nominal design, bank and search."""

    d_m: float
    c: object
    setup: object
    nominal: object = None
    spent_s: float = 0.0        # the nominal design's search time (issue 29 budget)
    bank: object = None
    t_bank_s: float = 0.0
    res: object = None          # the bank search's detail; None: the distance takes no part
    why: str = ""               # why it takes no part
    store: str | None = None    # the bank's store (None: in memory)

    @property
    def n(self) -> int:
        return -1 if self.res is None else int(self.res.n)

    @property
    def probability(self) -> float:
        return float("nan") if self.res is None else float(self.res.probability)

    @property
    def proven(self) -> bool:
        return self.res is not None and str(self.res.status) == "optimal"


def choose(n, probability, proven) -> int:
    """Index of the chosen distance (module docstring's rule; ``n <= 0``: none reaches),
    -1 when none reaches. Rows are in ascending distance."""
    ok = [i for i in range(len(n)) if n[i] > 0]
    if not ok:
        return -1
    return min(ok, key=lambda i: (int(n[i]), not bool(proven[i]), -float(probability[i]), i))


def _distance_store(bank_store, d_m: float, own_m: float):
    """The bank store of distance ``d_m``: the design's own beside the store at the
    campaign's distance, ``NAME-ca<d>km-scenarios.zarr`` at the others."""
    if bank_store is None or d_m == own_m:
        return bank_store
    p = Path(bank_store)
    return str(p.with_name(p.name.removesuffix("-scenarios.zarr") + f"-ca{d_m / KM:g}km"
                           "-scenarios.zarr"))


def _at_distance(c, setup, d_m: float):
    """(campaign, setup) at ``d_m``: the run's own at its distance, else validated again."""
    if d_m == float(setup.d_sep_m):
        return c, setup
    try:
        cd = distance_campaign(c, d_m)
        return cd, checked_setup(cd, np.linspace(0.0, 2 * np.pi, 16, endpoint=False))
    except InputError as exc:
        raise InputError(f"at {d_m / KM:g} km: {exc.message} ({exc.field})",
                         field=FIELD) from None


def _row(c, setup, client, d_m, store, s_n) -> DistanceRow:
    """Steps 1 to 3 of the module docstring at one distance. A distance the design cannot
    serve (an :class:`InputError` of its nominal design or search: no grid candidate maps
    anything from that ring, no swarm of ``n_max`` reaches the target or p') takes no part,
    its reason kept; a single-distance run there stops with that same error."""
    d = c.config.design
    row = DistanceRow(d_m=d_m, c=c, setup=setup, store=store)
    try:
        row.nominal, row.spent_s = nominal_design(c, setup, client)
        t0 = time.perf_counter()
        row.bank = campaign_bank(c, setup, s_n, phase_client(client), store)
        row.t_bank_s = time.perf_counter() - t0
        row.res = bank_search(c, setup, row.bank, row.nominal.threshold, bank_level(d),
                              search_budget(d, row.spent_s))
    except InputError as exc:
        row.res, row.why = None, f"{exc.message} ({exc.field})"
    log(f"closest approach {d_m / KM:g} km: fewest N "
        + (f"{row.n} ({row.res.status}), bank P {row.probability:.4f}; bank "
           f"{row.t_bank_s:.1f} s" if row.res is not None else f"none: {row.why}"))
    return row


def design_distances(c, setup, client, *, bank_store: str | None = None):
    """The success-probability design over ``design.ca_distances_km`` (module docstring).

    Returns the :class:`~ideas_hpc.campaign.design_exact.ExactDesign` of the chosen
    distance's design, with the distance variables, attrs and summary line added and
    ``flown`` set to that distance's (campaign, setup).
    """
    d = c.config.design
    refuse_stereo(c, setup)
    dist = sorted({float(x) for x in d.ca_distances_m})
    own = float(setup.d_sep_m)
    made = [s for s in (_distance_store(bank_store, x, own) for x in dist)
            if s is not None and not Path(s).exists()]
    try:
        rows = []
        for x in dist:
            cx, sx = _at_distance(c, setup, x)
            rows.append(_row(cx, sx, client, x, _distance_store(bank_store, x, own),
                             sizes(cx, sx)[0]))
        best = choose([r.n for r in rows], [r.probability for r in rows],
                      [r.proven for r in rows])
        if best < 0:
            raise InputError("no swarm of design.n_max reaches the bank's level at any "
                             "distance: " + "; ".join(f"{r.d_m / KM:g} km: {r.why}"
                                                       for r in rows), field=FIELD)
        out = _design_at(rows[best], client)
    except InputError:
        for s in made:      # bad input leaves no store: the banks this run made go too
            shutil.rmtree(s, ignore_errors=True)
        raise
    return _with_distances(out, rows, best)


def _design_at(row: DistanceRow, client):
    """The rest of the design at the chosen distance, as
    :func:`~ideas_hpc.campaign.design_reliability.design_reliable` runs it."""
    client, _, tolerant = bank_phase(row.c, row.setup, client, row.nominal)
    return design_on_bank(row.c, row.setup, client, row.nominal, row.bank, row.t_bank_s,
                          tolerant, spent_s=row.spent_s, searched=row.res)


def _fmt(vals, spec: str) -> str:
    return " / ".join("-" if not np.isfinite(v) else format(v, spec) for v in vals)


def choice_line(dist_m, n, probability, proven, gsd_m, los_rad_s, best: int) -> str:
    """The one summary line of the choice (``ideas-hpc run`` and ``report``)."""
    ns = " / ".join("-" if k <= 0 else f"{k}" + ("" if ok else "*")
                    for k, ok in zip(n, proven))
    return (f"closest-approach distance: {dist_m[best] / KM:g} km chosen of "
            f"{_fmt(np.asarray(dist_m) / KM, 'g')} km (fewest N {ns}; bank P "
            f"{_fmt(probability, '.4f')}; GSD at TCA {_fmt(gsd_m, '.3g')} m; peak LOS rate "
            f"{_fmt(np.degrees(los_rad_s), '.3g')} deg/s)"
            + ("; * not proven (the search left a gap)" if not all(
                ok for k, ok in zip(n, proven) if k > 0) else "")
            + "; rule: fewest N, ties by the higher bank P")


def _with_distances(out, rows, best: int):
    """``out`` with the distance variables, attrs and line (module docstring)."""
    row = rows[best]
    dist = np.array([r.d_m for r in rows])
    cam = camera_figures(row.setup, dist, camera_ifov_rad(row.c, row.setup))
    n = np.array([r.n for r in rows], dtype=np.int64)
    prob = np.array([r.probability for r in rows])
    proven = np.array([r.proven for r in rows])
    dim = "ca_distance"
    ds = xr.Dataset({
        "ca_distance_swarm_size": (dim, n, {"units": "1", "long_name": "fewest N on the "
                                            "distance's bank (-1: none reaches the level)"}),
        "ca_distance_bank_probability": (dim, prob, {"units": "1", "long_name": "bank P of "
                                                     "that fewest-N swarm"}),
        "ca_distance_proven": (dim, proven, {"units": "1", "long_name": "fewest N proven "
                                             "(solver status optimal)"}),
        "ca_distance_solver_status": (dim, np.array([
            "not reached" if r.res is None else str(r.res.status) for r in rows], dtype="U16"),
            {"units": "1", "long_name": "solver status of the distance's search"}),
        "ca_distance_threshold": (dim, np.array([np.nan if r.nominal is None else
                                                  r.nominal.threshold.need for r in rows]),
                                  {"units": "1", "long_name": "coverage threshold at the "
                                                              "distance"}),
        "ca_distance_gsd_m": (dim, cam["gsd_m"], {"units": "m", "long_name": "ground sample "
                                                  "distance at closest approach, (d - R_av) "
                                                  "IFOV"}),
        "ca_distance_los_rate_rad_s": (dim, cam["los_rate_rad_s"], {
            "units": "rad/s", "long_name": "peak line-of-sight rate v / d (at TCA)"}),
        "chosen_ca_distance_m": ((), float(row.d_m), {"units": "m", "long_name":
                                                      "closest-approach distance chosen"}),
    }, coords={dim: (dim, dist, {"units": "m", "long_name": "closest-approach distance"})})
    line = choice_line(dist, n, prob, proven, cam["gsd_m"], cam["los_rate_rad_s"], best)
    out.data = xr.merge([out.data, ds], combine_attrs="override")
    out.attrs.update({"chosen_ca_distance_m": float(row.d_m),
                      "ca_distances_m": [float(x) for x in dist], "ca_distance_rule": RULE,
                      "ca_distance_choice": line})
    if row.store is not None:   # the chosen distance's bank, which `ideas-hpc study` reads
        out.attrs["scenario_bank_store"] = Path(row.store).name
    out.summary = f"{out.summary}\n{line}"
    out.flown = (row.c, row.setup)
    return out
