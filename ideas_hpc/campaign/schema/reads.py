"""Which keys a campaign reads, declared once: a key its kind ignores is refused (issue 41).

A campaign file may only set keys that the run it describes reads. Every key the
file sets (present in the file or given with ``--set``; defaults are not "set") is
judged once at load (:func:`check_reads`); a key the run would ignore stops the
load with one :class:`~ideas_hpc.base.errors.InputError` line naming the dotted
key, its file and line, the kind or setting that ignores it and, where there is
one, the setting that would make it read. A store's resolved config, which writes
every default out, is not judged (``CampaignSource.resolved``).

Two declarations decide:

* the kinds registry (:mod:`ideas_hpc.campaign.schema.kinds`): each entry (and each
  ``design.method`` entry) lists the keys of its own that its run reads
  (``Kind.reads``). A key that some entry lists is read only where the entry that
  runs lists it: ``design.population`` is read by the GAs and NSGA-II, not by the
  exact designer;
* :data:`RULES` below: conditions on other settings, for any kind. A rule replaces
  the registry's test for its key and may call it (``s.lists(key)``).

Any other key is read by every kind (the body, the instrument's sizing, the flyby's
geometry, ``[dynamics]``, ``[coverage]``...). ``tests/test_key_reads.py`` loads every
kind with every key; ``tests/test_key_reads_runs.py`` records which config fields small
real runs of every kind read, against this declaration.

``monte_carlo.failures_k`` in a success-probability design is refused while
:data:`FAILURES_K_HONOURED` is False: that design's failure model loses each
spacecraft independently with ``monte_carlo.failure_probability``.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Callable

from ideas_hpc.attitude.maneuvers import MANEUVERS
from ideas_hpc.attitude.modes import ATTITUDE_MODES, ATTITUDE_STARTS
from ideas_hpc.base.errors import InputError
from ideas_hpc.body.formats import builtin_body, length_unit_applies
from ideas_hpc.campaign.schema.encounter_table import ENCOUNTER
from ideas_hpc.campaign.schema.imaging_rules import IMAGING_RULES
from ideas_hpc.campaign.schema.target_table import TARGET_RULES, drawn, why_drawn
from ideas_hpc.campaign.schema.navigation_table import NAVIGATION_RULES
from ideas_hpc.campaign.schema.kinds import DISPERSION_KEYS, KINDS
from ideas_hpc.campaign.schema.read_settings import (Rule, Settings, entry_name, not_listed, owned,
                                                     readers)
from ideas_hpc.design.api.methods import METHODS
from ideas_hpc.design.pareto.objectives import check_objectives
from ideas_hpc.montecarlo import dispersions
from ideas_hpc.montecarlo.dispersions import dispersion_keys

#: The success-probability design flies exactly ``monte_carlo.failures_k`` failures (its
#: failure model, :mod:`ideas_hpc.failures`, does since issue 41): the one switch; False
#: refuses the key there with one line.
FAILURES_K_HONOURED = True


def _applies(d, mode: str) -> bool:
    """``Dispersion.applies`` for a flight of attitude mode ``mode`` (a stand-in setup with
    the mode's name and entry); one that reads more of a setup is taken to apply."""
    setup = SimpleNamespace(attitude_mode=mode, attitude=ATTITUDE_MODES[mode])
    try:
        return d.applies is None or bool(d.applies(setup))
    except AttributeError:
        return True


def _names(registry: dict, capability) -> str:
    """``"a" or "b"``: the registry's names whose entry has ``capability(entry)``."""
    return " or ".join(f'"{n}"' for n, e in registry.items() if capability(e))


def _closed_loop_modes() -> str:
    return _names(ATTITUDE_MODES, lambda m: m.closed_loop)


def _dispersion(key: str):
    name = key.partition(".")[2]
    return next(d for d in dispersions.DISPERSIONS if name in dict(d.keys))   # live


def _dispersed(s: Settings, key: str) -> bool:
    """The dispersion of ``monte_carlo.<name>`` is flown: the entry that runs lists the
    dispersions and the dispersion applies to the campaign's attitude mode."""
    return s.samples and _applies(_dispersion(key), s.config.attitude.mode)


def _why_dispersed(key: str) -> Callable:
    def why(s: Settings) -> str:
        if not s.lists(DISPERSION_KEYS):
            return not_listed(key)(s)
        d = _dispersion(key)
        modes = " or ".join(f'"{m}"' for m in ATTITUDE_MODES if _applies(d, m))   # live
        return (f"is ignored with attitude.mode = {s.config.attitude.mode!r}: the flights apply "
                f"the {d.name!r} dispersion with attitude.mode = {modes} only")
    return why


def _attitude_draw(key: str, start: Callable, what: str) -> Rule:
    """A key of the attitude draw that the starts with ``start(entry)`` read, with
    ``attitude_dispersion = true``."""
    def when(s: Settings) -> bool:
        return (_dispersed(s, key) and s.config.monte_carlo.attitude_dispersion
                and start(s.start))

    def why(s: Settings) -> str:
        if not _dispersed(s, key):
            return _why_dispersed(key)(s)
        return (f"is ignored: it is {what} of monte_carlo.attitude_start = "
                f"{_names(ATTITUDE_STARTS, start)} with attitude_dispersion = true")
    return Rule(when, why)


def _sweeping() -> str:
    return " or ".join(f'"{m.campaign_name}"' for m in MANEUVERS.values() if m.sweeps)


def _why_no_sweep(what: str) -> Callable:
    def why(s: Settings) -> str:
        return (f"is ignored: the {s.maneuver.campaign_name!r} maneuver does not sweep ({what}: "
                f"attitude.maneuver = {_sweeping()})")
    return why


def _angles_read(s: Settings) -> bool:
    return s.kind.swarm == "file" or (s.kind.swarm == "file-angles"
                                      and s.config.design.nadir_store is None)


def _why_angles(s: Settings) -> str:
    if s.kind.swarm == "designed":
        flown = " or ".join(repr(k.name) for k in KINDS.values() if k.swarm != "designed")
        return (f"is ignored by kind {s.kind.name!r}, which designs the angles (kind {flown} "
                "flies given angles)")
    return "is ignored: design.nadir_store gives the swarm to sweep; drop one of the two"


def _why_periods(s: Settings) -> str:
    if s.kind.swarm != "file":
        what = "angles" if s.kind.swarm == "designed" else "sweep periods"
        return f"is ignored by kind {s.kind.name!r}, which designs the {what} it flies"
    return _why_no_sweep("one period per spacecraft")(s)


def _separation_read(s: Settings) -> bool:
    return s.kind.swarm == "designed" or (s.config.flyby.configuration == "ring"
                                          and _angles_read(s))


def _why_separation(s: Settings) -> str:
    if s.config.flyby.configuration != "ring":
        return (f"is ignored with flyby.configuration = {s.config.flyby.configuration!r}: only a "
                "ring's spacing is checked")
    return "is ignored: the swarm of design.nadir_store is flown as designed"


def _closed_loop(what: str) -> Callable:
    def why(s: Settings) -> str:
        return (f"is ignored with attitude.mode = {s.attitude.name!r}: {what} only in a closed "
                f"loop (attitude.mode = {_closed_loop_modes()})")
    return why


def _paper(s: Settings) -> bool:
    return s.config.flyby.geometry == "paper"


def _why_encounter_window(s: Settings) -> str:
    return ("is ignored with flyby.geometry = 'encounter': the imaging window is "
            "flyby.before_km / after_km (or before_s / after_s) around closest approach")


def _kernels(s: Settings) -> bool:
    return (s.raw.get("body") or {}).get("kernels") is not None


def _length_unit(s: Settings) -> bool:
    b = s.config.body
    if b.length_unit == "km":
        return True
    files = [f for f in (b.shape, None if builtin_body(b.name) else b.name) if f is not None]
    return any(length_unit_applies(f) for f in files)


def _why_length_unit(s: Settings) -> str:
    b = s.config.body
    what = (f"body.shape {b.shape!r}" if b.shape is not None else
            f"the built-in body {b.name!r}" if builtin_body(b.name) else f"body.name {b.name!r}")
    return (f"{b.length_unit!r} is not read for {what}: its format fixes its lengths (km); the "
            "unit applies to mesh files such as .obj/.ply/.stl/.off")


def _resolution(s: Settings) -> bool:
    """The analytic built-in bodies are meshed at ``body.resolution`` (Eros without its data
    file falls back to one), and so is a drawn prior's nominal; a shape file has its own
    vertices."""
    if drawn(s):
        return True
    b = s.config.body
    found = builtin_body(b.name)
    return b.shape is None and found is not None and not found[1].real_eros


def _why_resolution(s: Settings) -> str:
    b = s.config.body
    what = f"body.shape {b.shape!r}" if b.shape is not None else f"body.name {b.name!r}"
    return (f"is ignored: {what} is a shape model with its own vertices (the resolution "
            "meshes the analytic built-in bodies: ellipsoid, sphere, eros without its data)")


def _p_key(s: Settings) -> bool:
    return s.p


def _why_p(s: Settings) -> str:
    able = [entry_name(k, m) for k in KINDS.values() if k.success_probability
            for m in METHODS if METHODS[m].success_probability]
    return ("needs design.success_probability (it is read by the success-probability design, "
            f"{' or '.join(able)})")


def _why_success_probability(s: Settings) -> str:
    if not s.kind.success_probability:
        able = ", ".join(repr(k.name) for k in KINDS.values() if k.success_probability)
        return f"is for kind {able}, not {s.kind.name!r}"
    able = [m for m in METHODS if METHODS[m].success_probability]
    return (f"is supported by the {' or '.join(able)} designer only (design.method = "
            f"{', '.join(map(repr, able))}), not {s.method!r}")


def _failures_k(s: Settings) -> bool:
    return _dispersed(s, "monte_carlo.failures_k") and (FAILURES_K_HONOURED or not s.p)


def _why_failures_k(s: Settings) -> str:
    if s.samples and s.p:
        return ("is not honoured by the success-probability design (design.success_probability"
                "): its failure model loses each spacecraft independently with "
                "monte_carlo.failure_probability; drop it (kind 'monte-carlo' and the exact "
                "design's verification fly exactly k failures)")
    return _why_dispersed("monte_carlo.failures_k")(s)


def _samples_why(s: Settings) -> str:
    hint = (" (this design's Monte Carlo flies design.verify_samples samples)"
            if s.lists("design.verify_samples") else "")
    return not_listed("monte_carlo.samples")(s) + hint


def _time_limit(s: Settings) -> bool:
    """NSGA-II reads it only for the exact reference curve of (n, coverage)."""
    if not s.lists("design.time_limit_s"):
        return False
    if s.lists("design.objectives"):
        try:
            return set(check_objectives(s.config.design.objectives)) == {"n", "coverage"}
        except InputError:      # refused with its own line by the cross-checks
            return True
    return True


def _why_time_limit(s: Settings) -> str:
    if not s.lists("design.time_limit_s"):
        return not_listed("design.time_limit_s")(s)
    return ("is ignored: it bounds the exact coverage-vs-N reference curve, which is drawn for "
            'design.objectives = ["n", "coverage"] only')


def _maneuver(s: Settings) -> bool:
    return s.kind.maneuver is None or s.config.attitude.maneuver == s.kind.maneuver


def _simulated(s: Settings) -> bool:
    return s.simulated


def _always(s: Settings) -> bool:
    return True


#: A key of an encounter (:mod:`~ideas_hpc.campaign.schema.encounter_table`).
ENCOUNTER_KEY = Rule(lambda s: not _paper(s),
                     lambda s: 'is an encounter key: set flyby.geometry = "encounter"')


#: Conditions on other settings (module docstring); a key not here and listed by no kind
#: entry is read by every kind.
RULES: dict[str, Rule] = {
    "body.length_unit": Rule(lambda s: not drawn(s) and _length_unit(s),
                             lambda s: why_drawn(s) if drawn(s) else _why_length_unit(s)),
    **TARGET_RULES,
    "body.resolution": Rule(_resolution, _why_resolution),
    "body.spice_body": Rule(_kernels, lambda s: "needs body.kernels (the SPICE kernels that "
                                                "give the body's orbit and spin)"),
    "body.spice_frame": Rule(_kernels, lambda s: "needs body.kernels (the SPICE kernels that "
                                                 "give the body's orbit and spin)"),
    "flyby.epoch_utc": Rule(_kernels, lambda s: "needs body.kernels (a leap-second kernel at "
                                                "least)"),
    "flyby.spice_spacecraft": Rule(
        lambda s: _kernels(s) and not _paper(s),
        lambda s: ("needs body.kernels (the spacecraft's SPK)" if not _kernels(s) else
                   'needs flyby.geometry = "encounter"')),
    "flyby.helix_rise_km": Rule(
        lambda s: s.config.flyby.configuration == "helix" and _paper(s),
        lambda s: ("is ignored with flyby.configuration = 'ring': it raises a helix's turns "
                   '(flyby.configuration = "helix")' if _paper(s) else _why_encounter_window(s))),
    **{f"flyby.{k}": Rule(_paper, _why_encounter_window) for k in ("tf_s", "z_start_km",
                                                                   "z_stop_km")},
    **{f"flyby.{k}": ENCOUNTER_KEY for k in ENCOUNTER if k != "geometry"},
    **NAVIGATION_RULES,
    **IMAGING_RULES,
    "swarm.angles_rad": Rule(_angles_read, _why_angles),
    "swarm.sweep_periods_min": Rule(lambda s: s.kind.swarm == "file" and s.maneuver.sweeps,
                                    _why_periods),
    "swarm.min_separation_km": Rule(_separation_read, _why_separation),
    "attitude.maneuver": Rule(_maneuver, lambda s: f"is ignored: kind {s.kind.name!r} always "
                                                   f"flies {s.kind.maneuver!r}"),
    "attitude.decimate": Rule(lambda s: s.kind.one_swarm,
                              lambda s: f"is ignored by kind {s.kind.name!r}, which stores no "
                                        "flight (no single swarm to fly)"),
    "attitude.theta_max_deg": Rule(lambda s: s.maneuver.sweeps,
                                   _why_no_sweep("the sweep's amplitude")),
    "design.p_min_min": Rule(lambda s: s.maneuver.sweeps,
                             _why_no_sweep("the shortest sweep period")),
    "design.success_probability": Rule(
        lambda s: s.kind.success_probability and METHODS[s.method].success_probability,
        _why_success_probability),
    **{f"design.{k}": Rule(_p_key, _why_p) for k in ("confidence", "scenarios", "demonstrate",
                                                      "bank_level", "holdout_scenarios",
                                                      "verify_samples_max",
                                                      "tolerant_markers", "curve_samples",
                                                      "ca_distances_km")},
    "design.demonstrate_looks": Rule(
        lambda s: s.p and s.config.design.demonstrate,
        lambda s: (_why_p(s) if not s.p else "is ignored with design.demonstrate = false: one "
                   "look (design.demonstrate = true steps N up over several)")),
    "design.time_limit_s": Rule(_time_limit, _why_time_limit),
    "monte_carlo.samples": Rule(lambda s: s.lists("monte_carlo.samples"), _samples_why),
    "monte_carlo.failures_k": Rule(_failures_k, _why_failures_k),
    "monte_carlo.failure_in_pass_share": Rule(
        lambda s: _dispersed(s, "monte_carlo.failure_in_pass_share") and s.p,
        lambda s: ("is read by success-probability designs only (design.success_probability): "
                   "the Monte Carlo kind and the verification fly whole-pass losses"
                   if s.samples else _why_dispersed("monte_carlo.failure_in_pass_share")(s))),
    "monte_carlo.acquisition_s": _attitude_draw("monte_carlo.acquisition_s",
                                                lambda t: t.acquisition, "the acquisition phase"),
    **{f"monte_carlo.{k}": _attitude_draw(f"monte_carlo.{k}", lambda t: not t.random_state,
                                          "the error about the reference")
       for k in ("sigma_attitude_deg", "sigma_rate_rad_s")},
    # the device flies the closed loop, and the mapped rows of drawn worlds (issue 43)
    "run.device": Rule(lambda s: s.simulated or drawn(s),
                       lambda s: _closed_loop("the device flies the attitude")(s)
                       + ", and the rows of a drawn world (target.prior)"),
    "controller": Rule(_simulated, _closed_loop("the controller's gains act")),
    "torques": Rule(_simulated, _closed_loop("disturbance torques act")),
    "spacecraft": Rule(lambda s: s.simulated or s.lists("spacecraft"),
                       lambda s: _closed_loop("the spacecraft (inertia, wheels) flies")(s)
                       + f"; {', '.join(readers('spacecraft'))} also checks its pointing "
                       "against the wheels"),
}


def rule_of(key: str) -> Rule:
    """The rule of dotted ``key``: its :data:`RULES` entry, the dispersions' (a
    ``[monte_carlo]`` key of a dispersion: flown by an entry that lists them and flies
    samples, where the dispersion applies), the registry's (a key some entry lists), or
    read by every kind."""
    if key in RULES:
        return RULES[key]
    if key.startswith("monte_carlo.") and key.partition(".")[2] in dispersion_keys():
        return Rule(lambda s: _dispersed(s, key), _why_dispersed(key))
    if key in owned():
        return Rule(lambda s: s.lists(key), not_listed(key))
    return Rule(_always, lambda s: "")


def is_read(key: str, s: Settings) -> bool:
    """Whether the campaign of settings ``s`` reads dotted ``key``."""
    return bool(rule_of(key).when(s))
