"""``ideas-hpc study STORE``: the answers only a design under a target prior gives (SPEC 7f
"What to report"; issue 42 deliverable 6).

A thin orchestration of the design's own machinery (the scenario bank, the fewest-N
search, the validation flights: :mod:`ideas_hpc.campaign.bank_design`,
:mod:`ideas_hpc.campaign.validation_flights`) on the store's resolved campaign, with no
new physics:

1. **The price of ignorance** (:func:`price_of_ignorance`): the fewest N on the prior's
   bank against the fewest N on the bank of the *known* target, the prior's nominal body
   (the same setup with ``target = None``: its shape, pole, period and phase exactly) at
   the same encounter, navigation, dispersions, requirement, seed and level. Both are the
   proven fewest N of :func:`~ideas_hpc.design.reliability.min_swarm_reliable` on ``S``
   scenarios (the store's ``design.scenarios``); the price is their difference, ``>= 0``
   unless the nominal body is harder to map than the prior's average world.
2. **The value of a late navigation update** (:func:`navigation_value`): the B-plane
   ellipse and the TCA sigma scaled together to a list of major-axis 1-sigmas
   (:meth:`~ideas_hpc.flyby.navigation.NavigationError.scaled`), a bank at each; the
   designed swarm's ``P_bank`` and the fewest N at each. Every bank draws from the same
   seed and stream, so its worlds, dispersions and the *normals* of its navigation errors
   are the same at every sigma (common random numbers): only the scale changes, and the
   swarm's P against sigma is not blurred by sampling. The campaign's own sigma is a row
   too (its bank is the design's).
3. **Per-target reliability** (:mod:`ideas_hpc.campaign.study_nested`): ``M`` outer worlds,
   ``K`` inner draws each; the share of worlds whose conditional P reaches ``p``.

4. **The closest-approach distance** (:mod:`ideas_hpc.campaign.study_distance`), on
   request: the fewest N, its P, the GSD and LOS rate at each distance of a short list.

Each answer is written into the store as its own group (``study_ignorance``,
``study_navigation``, ``study_per_target``, ``study_distance``) with attrs saying its seeds and streams, and
what no data chose (the study selects nothing: the swarm is the store's, the levels are
the campaign's). Its banks live in ``NAME-study/`` beside the store and are reused while
their shaping config is unchanged; an answer whose group holds the same options is not
recomputed (``--force`` does). ``ideas-hpc report`` shows what is present.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ideas_hpc.base import seeds
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import log, result
from ideas_hpc.base.units import KM
from ideas_hpc.campaign.study_lines import PRICE_UNDEFINED, answer_line
from ideas_hpc.campaign.study_vars import CHOSE_NOTHING, answer_attrs, labels, search_vars

#: The answers, in the order they run and print.
ANSWERS = ("ignorance", "navigation", "per-target", "distance")
#: The answers run by default (``distance`` runs when a distance list is given).
DEFAULT_ANSWERS = ANSWERS[:3]
#: Store group of each answer.
GROUPS = {"ignorance": "study_ignorance", "navigation": "study_navigation",
          "per-target": "study_per_target", "distance": "study_distance"}
@dataclass(frozen=True)
class StudyOptions:
    """The command's choices (SI)."""

    sigmas_m: tuple = (100e3, 30e3, 10e3, 3e3)
    worlds: int = 20
    per_world: int = 10
    answers: tuple = DEFAULT_ANSWERS
    force: bool = False
    distances_m: tuple = ()     # closest-approach distances (the store's is added)
    time_limit_s: float | None = None     # each fewest-N search; None: the campaign's

    def __post_init__(self):
        if not self.sigmas_m or any(not s > 0 for s in self.sigmas_m):
            raise InputError(f"needs positive 1-sigmas, got {list(self.sigmas_m)}",
                             field="--bplane-sigmas-km")
        bad = [a for a in self.answers if a not in ANSWERS]
        if bad:
            raise InputError(f"unknown answer(s) {bad}: choose from {', '.join(ANSWERS)}",
                             field="--answers")
        for name, v in (("--worlds", self.worlds), ("--per-world", self.per_world)):
            if int(v) < 1:
                raise InputError(f"must be >= 1, got {v}", field=name)
        if "distance" in self.answers:
            from ideas_hpc.campaign.study_distance import check_distances
            check_distances(self.distances_m)
        if self.time_limit_s is not None and not self.time_limit_s > 0:
            raise InputError(f"must be > 0 s, got {self.time_limit_s}", field="--time-limit-s")


@dataclass
class Study:
    """A design store's campaign, setup and swarm (:func:`open_study`)."""

    store: Path
    c: object
    setup: object
    theta: np.ndarray           # (N,) the designed swarm's angles, rad
    need: float                 # coverage threshold (area fraction)
    p: float                    # required success probability
    client: object = None
    time_limit_s: float | None = None   # each fewest-N search (None: design.time_limit_s)
    design_search: dict | None = None   # the design's own fewest N on its bank (the store's)
    bank_name: str | None = None        # its bank's store beside it (attr scenario_bank_store)

    @property
    def work(self) -> Path:
        """Folder of the study's banks, beside the store."""
        return self.store.with_name(self.store.name.removesuffix(".zarr") + "-study")

    @property
    def level(self) -> float:
        d = self.c.config.design
        return self.p if d.bank_level is None else float(d.bank_level)

    def bank(self, setup, name: str | None):
        """The campaign's bank of ``setup``; ``name`` None: the design's own store."""
        from ideas_hpc.campaign.bank_design import campaign_bank
        from ideas_hpc.campaign.design_reliability import continuous_off, scenario_store_path

        s_n = 1 if continuous_off(self.c.config.monte_carlo, setup) else \
            int(self.c.config.design.scenarios)
        if name is None:        # the design's own bank (at a chosen distance, that one's)
            path = scenario_store_path(self.store) if self.bank_name is None else \
                str(self.store.with_name(self.bank_name))
        else:
            self.work.mkdir(exist_ok=True)
            path = str(self.work / f"{name}-scenarios.zarr")
        return campaign_bank(self.c, setup, s_n, self.client, path)

    def indices(self, bank) -> np.ndarray:
        """The designed swarm as grid indices of ``bank``."""
        step = 2.0 * np.pi / bank.theta.size
        return np.round(np.mod(self.theta, 2.0 * np.pi) / step).astype(np.int64) % bank.theta.size

    def fewest(self, setup, bank, recorded: dict | None = None) -> dict:
        """The proven fewest N on ``bank`` at the design's level (``n`` -1 when no swarm of
        at most ``n_max`` reaches it), and the designed swarm's ``P_bank`` there.
        ``recorded``: the design's own search on this very bank (:attr:`design_search`),
        taken as it is instead of searching again."""
        from ideas_hpc.base.vertex_weights import normalised
        from ideas_hpc.campaign.bank_design import bank_settings
        from ideas_hpc.design.api import ScenarioProblem, minimize
        from ideas_hpc.design.reliability_eval import Evaluator

        limit = self.c.config.design.time_limit_s if self.time_limit_s is None else \
            self.time_limit_s
        settings = bank_settings(self.c, setup, self.need, self.level, float(limit))
        ev = Evaluator(bank.rows, normalised(bank.areas, bank.rows.shape[0]), self.need,
                       settings.model)
        swarm_p = float(ev([self.indices(bank)])[0])
        if recorded is not None:
            return {**recorded, "swarm_probability": swarm_p}
        try:
            res = minimize(ScenarioProblem(bank.rows, bank.areas, bank.theta), settings).detail
        except InputError as exc:
            log(f"no swarm of at most {settings.n_max} reaches {self.level:g}: {exc.message}")
            return {"n": -1, "probability": np.nan, "status": "not reached", "bound": -1,
                    "swarm_probability": swarm_p}
        return {"n": int(res.n), "probability": float(res.probability),
                "status": str(res.status), "bound": int(math.ceil(res.bound - 1e-9)),
                "swarm_probability": swarm_p}


def open_study(store, client=None) -> Study:
    """The store's campaign (its resolved config), setup and designed swarm."""
    import xarray as xr

    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.campaign.validate_store import store_campaign

    c, attrs = store_campaign(store)
    ds = xr.open_zarr(store)
    theta = np.asarray(ds["swarm_angle"].values, dtype=np.float64)
    return Study(store=Path(store), c=c, setup=setup_from_campaign(c), theta=theta,
                 need=float(attrs["reliability_threshold"]),
                 p=float(attrs["success_probability"]), client=client,
                 design_search=recorded_search(ds), bank_name=attrs.get("scenario_bank_store"))


def recorded_search(ds) -> dict | None:
    """The design's fewest-N search on its own bank as the store records it
    (``bank_swarm_size``, ``bank_probability``, ``solver_status``, ``proven_bound``), or
    None for a store without it. The study's prior case is that same search (the same
    bank, at the same level ``design.bank_level`` or p), so it is read, not run again:
    searched again under the study's own time limit it may stop short of the proof the
    design reached (the main job: the design proved N = 5; a 60 s search gave 6,
    unproven)."""
    names = ("bank_swarm_size", "bank_probability", "solver_status", "proven_bound")
    if any(n not in ds for n in names):
        return None
    return {"n": int(ds["bank_swarm_size"].values), "probability": float(ds["bank_probability"].values),
            "status": str(ds["solver_status"].values),
            "bound": int(math.ceil(float(ds["proven_bound"].values) - 1e-9))}


def price_of_ignorance(st: Study):
    """Answer 1 (module docstring): ``xarray.Dataset`` over ``case = [prior, known]``."""
    import xarray as xr

    if st.setup.target is None:
        raise InputError("the design's target is known ([target] prior = \"known\"): there is "
                         "no ignorance to price", field="--answers")
    known = dataclasses.replace(st.setup, target=None)
    rows = [st.fewest(st.setup, st.bank(st.setup, None), recorded=st.design_search),
            st.fewest(known, st.bank(known, "known"))]
    price = rows[0]["n"] - rows[1]["n"] if min(r["n"] for r in rows) > 0 else None
    return xr.Dataset(
        search_vars("case", rows),
        coords={"case": ("case", labels("prior", "known"),
                         {"long_name": "the target prior, or its nominal body known exactly"})},
        # PRICE_UNDEFINED: a case reaches the level with no N up to n_max
        attrs=answer_attrs(st, price=PRICE_UNDEFINED if price is None else int(price),
                     scenario_stream=seeds.SCENARIO_STREAM,
                     known_bank=str(st.work / "known-scenarios.zarr")))


def navigation_value(st: Study, sigmas_m):
    """Answer 2 (module docstring): ``xarray.Dataset`` over ``bplane_sigma`` (descending),
    the campaign's own sigma included."""
    import xarray as xr

    plan = st.setup.navigation
    if plan is None or plan.error.sigma_major_m <= 0.0:
        raise InputError("the campaign has no [navigation] errors to scale", field="--answers")
    own = float(plan.error.sigma_major_m)
    sig = sorted({float(s) for s in sigmas_m} | {own}, reverse=True)
    rows = []
    for s in sig:
        if s == own:
            setup, name = st.setup, None
        else:
            setup = dataclasses.replace(st.setup, navigation=dataclasses.replace(
                plan, error=plan.error.scaled(s)))
            name = f"nav-{s / KM:g}km"
        t0 = time.perf_counter()
        rows.append(st.fewest(setup, st.bank(setup, name),
                              recorded=st.design_search if name is None else None))
        log(f"B-plane 1-sigma {s / KM:g} km: bank and search in {time.perf_counter() - t0:.1f} s")
    sp = np.array([r["swarm_probability"] for r in rows])
    # sigma descending: P must not fall as the update sharpens
    monotone = bool(np.all(np.diff(sp) >= -1e-12))
    bp_cov, bp_swarm = bplane_geometry(st)
    return xr.Dataset(
        {**search_vars("bplane_sigma", rows),
         "tca_sigma": ("bplane_sigma", np.array([plan.error.sigma_tca_s * s / own
                                                 for s in sig]),
                       {"units": "s", "long_name": "1-sigma of the time of closest approach "
                                                   "(scaled with the ellipse)"}),
         "bplane_covariance": (("bplane_axis", "bplane_axis2"), bp_cov,
                               {"units": "m2", "long_name": "covariance of the target's "
                                "B-plane offset (xi along T, eta along R), the campaign's"}),
         "swarm_bplane": (("spacecraft", "bplane_axis"), bp_swarm,
                          {"units": "m", "long_name": "designed members' closest-approach "
                                                      "points in the B-plane (T, R)"})},
        coords={"bplane_sigma": ("bplane_sigma", np.array(sig), {
            "units": "m", "long_name": "B-plane 1-sigma semi-major axis"}),
                "bplane_axis": ("bplane_axis", labels("T", "R")),
                "spacecraft": ("spacecraft", np.arange(bp_swarm.shape[0])),
                "bplane_axis2": ("bplane_axis2", labels("T", "R"))},
        attrs=answer_attrs(st, monotone=int(monotone), campaign_sigma_m=own,
                     scenario_stream=seeds.SCENARIO_STREAM,
                     common_random_numbers="every bank: the same seed and scenario stream, "
                     "so the same worlds, dispersions and navigation normals; only the scale "
                     "differs", update=plan.error.update))


def bplane_geometry(st: Study) -> tuple[np.ndarray, np.ndarray]:
    """``(2, 2)`` covariance of the target's B-plane offset (m^2) and ``(N, 2)`` the
    designed members' closest-approach points in the B-plane ``(T, R)`` (m), the pole +z of
    N as the navigation draws take it (:mod:`ideas_hpc.montecarlo.navigation_dispersion`)."""
    from ideas_hpc.flyby.encounter import endpoints_encounter
    from ideas_hpc.flyby.navigation import bplane_frame

    frame = bplane_frame(st.setup.encounter.v_inf_T)
    ring = endpoints_encounter(st.setup, st.theta)[1]
    return st.setup.navigation.error.covariance_TR_m2, ring @ frame[1:].T


def per_target(st: Study, worlds: int, per_world: int):
    """Answer 3 (:mod:`ideas_hpc.campaign.study_nested`) as an ``xarray.Dataset``."""
    import xarray as xr

    from ideas_hpc.campaign.study_nested import per_target_reliability

    r = per_target_reliability(st.c, st.setup, st.theta, st.need, st.p, worlds=worlds,
                               per_world=per_world, client=st.client)
    lo, hi = r.interval()
    return xr.Dataset(
        {"conditional_probability": ("world", r.conditional, {
            "units": "1", "long_name": "conditional P of the designed swarm in the world"}),
         "conditional_std_error": ("world", r.std_error, {
             "units": "1", "long_name": "standard error of the conditional P (inner draws)"}),
         "inner_probability": (("world", "inner"), r.per_sample, {
             "units": "1", "long_name": "exact failure-weighted P of each inner draw"})},
        coords={"world": ("world", np.arange(r.worlds), {
                    "long_name": "outer target world m (world m of family NESTED_STREAM)"}),
                "inner": ("inner", np.arange(r.per_world), {
                    "long_name": "inner draw j (sample m K + j of NESTED_STREAM)"})},
        attrs=answer_attrs(st, worlds=r.worlds, per_world=r.per_world, meeting=r.meeting,
                     share=r.share, wilson_low=lo, wilson_high=hi,
                     nested_stream=seeds.NESTED_STREAM,
                     streams=f"world m: world_rng family NESTED_STREAM ({seeds.NESTED_STREAM:#x}); "
                             "inner draw j: sample m K + j of NESTED_STREAM"))


def _stored(store: Path, group: str, options: dict):
    """The stored answer of ``group`` when it was made with ``options``, else None."""
    import xarray as xr

    try:
        ds = xr.open_zarr(store, group=group, consolidated=False)
    except Exception:
        return None
    return ds if ds.attrs.get("study_options") == json.dumps(options, sort_keys=True) else None


def not_applicable(st: Study, name: str) -> str | None:
    """Why answer ``name`` does not apply to the store's design (None: it does)."""
    nav = st.setup.navigation
    if name in ("ignorance", "per-target") and st.setup.target is None:
        return "the target is known ([target] prior = \"known\"): every world is the same"
    if name == "navigation" and (nav is None or nav.error.sigma_major_m <= 0.0):
        return "the campaign has no [navigation] errors to scale"
    return None


def _compute(st: Study, name: str, opts: StudyOptions):
    if name == "ignorance":
        return price_of_ignorance(st)
    if name == "navigation":
        return navigation_value(st, opts.sigmas_m)
    if name == "distance":
        from ideas_hpc.campaign.study_distance import distance_value
        return distance_value(st, opts.distances_m)
    return per_target(st, opts.worlds, opts.per_world)


def run_study(store, opts: StudyOptions = StudyOptions(), client=None) -> list[str]:
    """Run the chosen answers on a design store (module docstring); returns their lines,
    also printed as results (an answer that does not apply says why in its line)."""
    st = dataclasses.replace(open_study(store, client), time_limit_s=opts.time_limit_s)
    out = []
    for name in opts.answers:
        options = {"answer": name}
        if name == "navigation":
            options["sigmas_m"] = [float(s) for s in opts.sigmas_m]
        if name == "distance":
            options["distances_m"] = [float(d) for d in opts.distances_m]
        if name == "per-target":
            options.update(worlds=int(opts.worlds), per_world=int(opts.per_world))
        else:
            options["time_limit_s"] = opts.time_limit_s
        why = not_applicable(st, name)
        if why is not None:
            line = f"{name}: does not apply: {why}"
        else:
            ds = None if opts.force else _stored(st.store, GROUPS[name], options)
            if ds is None:
                t0 = time.perf_counter()
                ds = _compute(st, name, opts)
                ds.attrs.update(study_options=json.dumps(options, sort_keys=True),
                                wall_s=time.perf_counter() - t0)
                ds.to_zarr(st.store, group=GROUPS[name], mode="w", consolidated=False)
            line = answer_line(name, ds)
        result(line)
        out.append(line)
    return out
