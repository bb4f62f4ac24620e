"""The campaign file schema (SPEC sections 7-9), validated once at load.

One mechanism (:class:`ideas_hpc.base.fields.Field`) validates every table once
into a frozen dataclass with SI values under SI names (:class:`CampaignConfig`:
``c.config.instrument.aperture_m``, ``c.config.design.p_min_s``); the file
keys keep their user units (``aperture_cm``) and errors name them with the
file and line. Tables and their keys, in the file's units (converted to SI here):

``kind`` (``flyby``, ``design-nadir``, ``design-fov``, ``design-pareto``,
``monte-carlo``), ``seed``.

``[body]`` ``name`` (name or path), ``params`` (preset name or a table of
:func:`ideas_hpc.body.params.params_from_mapping` keys), ``resolution`` (analytic
bodies), ``data_path``, ``length_unit`` (:mod:`ideas_hpc.campaign.body_checks`); ``shape``,
``kernels``, ``spice_body``, ``spice_frame``, ``[flyby] epoch_utc``: :mod:`~ideas_hpc.campaign.schema.spice_table`.

``[instrument]`` ``ground_resolution_m``, ``aperture_cm``, ``wavelength_um``,
``min_elevation_deg``, ``near_field_mm``, ``image_rate_hz``, ``half_angle_deg``
(default: the sizing's eta_N for nadir pointing, eta_N/2 for FoV sweeping),
``pixel_pitch_um`` and ``focal_length_mm`` (optional detector, for the quality
pass's ground sample), the usable-image test ``pixels_across``, ``exposure_ms``,
``smear_pixels``, ``settle_deg`` (:mod:`ideas_hpc.campaign.schema.instrument_table`).

``[flyby]`` ``configuration`` (``ring`` or ``helix``), ``t0_s``, ``tf_s``,
``z_start_km``, ``z_stop_km``, ``helix_rise_km`` (helix: extra z_start per full
turn of swarm angle), ``d_sep_km`` (default from the sizing), ``tolerance_m``,
``max_iterations``, ``dt_s`` (attitude step and trajectory sampling),
``epoch_s`` (arrival epoch after the body's element epoch: the Sun direction at
flyby time ``t`` is the ephemeris at ``epoch_s + t``); ``geometry = "encounter"`` and its
keys: :mod:`ideas_hpc.campaign.schema.encounter_table`.

``[swarm]`` ``angles_rad`` and ``sweep_periods_min`` (flyby and Monte Carlo),
``min_separation_km`` (closest allowed distance between two spacecraft on the
ring, default 1 km; checked once ``d_sep`` is known, see
:func:`ideas_hpc.flyby.swarm_geometry.check_separation`).

``[attitude]`` ``mode`` (``ideal`` or ``simulated``), ``maneuver`` (``nadir``,
``fov``, or ``track``: the body centre, encounters in ideal mode), ``decimate`` (keep every k-th attitude step in the store),
``theta_max_deg`` (default eta_N / 2).

``[dynamics]``, ``[spacecraft]``, ``[controller]``, ``[coverage]``: passed to
the owning modules' ``*_from_config`` (see their docstrings).

``[design]`` ``method`` (``exact``, the default, or ``ga`` for design-nadir),
``angle_step_deg``, ``time_limit_s``, ``failures_tolerated``, ``verify_samples``
(Monte Carlo verification of the design with the ``[monte_carlo]`` dispersions)
(exact designer); ``success_probability``, ``confidence``, ``scenarios``,
``demonstrate`` (the success-probability designer, issue 20; tables and checks
in :mod:`ideas_hpc.campaign.schema.design_table`);
(every designer) ``eps_tol_pct`` and ``target_rule``, the coverage requirement
(:func:`ideas_hpc.campaign.setup.requirement_from_campaign`, docs/requirement.md);
(GA) ``population``, ``generations``, ``n_max``, ``angle_step_rad``, ``p_min_min``, ``p_max_min``, ``period_step_min``,
``parents``, ``elitism``, ``mutation_probability``, ``stall_generations``;
(design-pareto) ``objectives`` (two or more names of
:data:`ideas_hpc.design.pareto.objectives.OBJECTIVES`) with ``population``,
``generations``, ``n_max``, ``angle_step_deg``, ``parents``,
``mutation_probability`` and ``time_limit_s`` (the exact reference curve).

``[monte_carlo]`` ``samples`` and the dispersions (see :data:`MC_SCHEMA`).
``[run]`` ``chunk_size``, ``workers``.

``[target]`` ``prior`` (``known`` or ``eros-class``) and the prior's spread overrides:
:mod:`ideas_hpc.campaign.schema.target_table`."""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from dataclasses import dataclass, field
from typing import Any

from ideas_hpc.attitude.maneuvers import CAMPAIGN_NAMES, campaign_maneuver
from ideas_hpc.attitude.modes import ATTITUDE_MODES
from ideas_hpc.campaign.schema.toml_file import CampaignSource, load_campaign
from ideas_hpc.design.pareto.objectives import check_objectives
from ideas_hpc.base.errors import InputError, config_fields
from ideas_hpc.montecarlo.dispersions import check_dispersions
from ideas_hpc.montecarlo.failure_dispersion import check_fleet
from ideas_hpc.base.fields import (Field, live_typed_table, schema_defaults, to_typed,
                                     typed_table, validate, with_defaults)
from ideas_hpc.base.units import DEG, KM, MINUTE
from ideas_hpc.campaign.schema.design_checks import DESIGNER_FIELDS, resolve_angle_step
from ideas_hpc.campaign.schema.encounter_table import ENCOUNTER, check_encounter
from ideas_hpc.campaign.schema.navigation_table import NAVIGATION, check_navigation
from ideas_hpc.campaign.schema.spice_table import SPICE_BODY, SPICE_FLYBY, resolve_spice
from ideas_hpc.campaign.schema.target_table import TARGET
from ideas_hpc.campaign.schema.instrument_table import INSTRUMENT, exposure_ms
from ideas_hpc.campaign.schema.model_fields import STORED_NAMES, flyby_errors, stored_fields
from ideas_hpc.campaign.schema.model_tables import build_models
from ideas_hpc.campaign.schema.kinds import KINDS as REGISTRY
from ideas_hpc.campaign.schema.read_check import check_reads, switched_off
from ideas_hpc.campaign.schema.design_table import (DESIGN, MC_SCHEMA, reference_checks,
                                                reliability_checks, verify_samples)

KINDS = REGISTRY.keys()   # live: a kind registered later is a valid choice

BODY = {
    "name": Field("str", "eros", doc="body name or shape file"),
    "params": Field("any", None, nullable=True, doc="preset name or table"),
    "resolution": Field("int", 3, lo=1, hi=7),
    "data_path": Field("str", None, nullable=True),
    "length_unit": Field("str", "km", choices=("km", "m"), doc="unit of an OBJ/PLY/STL/OFF mesh"),
    **SPICE_BODY,
}

FLYBY = {
    "configuration": Field("str", "ring", choices=("ring", "helix")),
    "t0_s": Field("float", 0.0),
    "tf_s": Field("float", 600.0),
    "z_start_km": Field("float", -30.0, si="z_start_m", to_si=KM),
    "z_stop_km": Field("float", 30.0, si="z_stop_m", to_si=KM),
    "helix_rise_km": Field("float", 0.0, si="helix_rise_m", to_si=KM),
    "d_sep_km": Field("float", None, nullable=True, si="d_sep_m", to_si=KM, lo=0, lo_open=True),
    "tolerance_m": Field("float", 0.01, lo=0, lo_open=True),
    "max_iterations": Field("int", 25, lo=1),
    "dt_s": Field("float", 0.1, lo=0, lo_open=True),
    "epoch_s": Field("float", 0.0, doc="arrival epoch: flyby time 0 is this many seconds "
                                       "after the body's element epoch (sets the Sun "
                                       "direction and the body's rotation phase)"),
    **ENCOUNTER, **SPICE_FLYBY,
}

SWARM = {
    "angles_rad": Field("floats", None, nullable=True, lo=0.0, hi=2 * math.pi, hi_open=True,
                        doc="ring angle of each spacecraft, in [0, 2 pi)"),
    "sweep_periods_min": Field("floats", None, nullable=True, si="sweep_periods_s",
                               to_si=MINUTE, lo=0, lo_open=True),
    "min_separation_km": Field("float", 1.0, si="min_separation_m", to_si=KM, lo=0, lo_open=True,
                               doc="closest allowed distance between two spacecraft"),
}

ATTITUDE = {
    "mode": Field("str", "ideal", choices=ATTITUDE_MODES),
    "maneuver": Field("str", "nadir", choices=CAMPAIGN_NAMES),
    "decimate": Field("int", 10, lo=1),
    "theta_max_deg": Field("float", None, nullable=True, si="theta_max_rad",
                           to_si=DEG, lo=0, lo_open=True, hi=90),
}

RUN = {
    "chunk_size": Field("int", 8, lo=1, doc="samples per dask task"),
    "workers": Field("int", None, nullable=True, lo=0),
    "device": Field("str", "cpu", choices=("cpu", "cuda"),
                    doc="where the closed-loop attitude flights run (docs/gpu.md)"),
}

SCHEMA = {
    "kind": Field("str", choices=KINDS, doc="campaign kind"),
    "seed": Field("int", 2026, lo=0),
    "description": Field("str", ""),
    "body": BODY,
    "instrument": INSTRUMENT,
    "flyby": FLYBY,
    "swarm": SWARM,
    "attitude": ATTITUDE,
    "dynamics": Field("any", None, nullable=True),
    "spacecraft": Field("any", None, nullable=True),
    "controller": Field("any", None, nullable=True),
    "coverage": Field("any", None, nullable=True),
    # disturbance torque terms by name (ideas_hpc.attitude.torque_terms.TORQUE_TERMS)
    "torques": Field("any", None, nullable=True),
    "design": DESIGN,
    "monte_carlo": MC_SCHEMA,
    "run": RUN,
    "target": TARGET,
    "navigation": NAVIGATION,
}


Body = typed_table("Body", BODY, __name__)
Instrument = typed_table("Instrument", INSTRUMENT, __name__)
Flyby = typed_table("Flyby", FLYBY, __name__)
Swarm = typed_table("Swarm", SWARM, __name__)
Attitude = typed_table("Attitude", ATTITUDE, __name__)
Design = typed_table("Design", DESIGN, __name__)
MonteCarlo = typed_table("MonteCarlo", MC_SCHEMA, __name__)
Run = typed_table("Run", RUN, __name__)
Target = typed_table("Target", TARGET, __name__)
Navigation = typed_table("Navigation", NAVIGATION, __name__)
TABLES = {"body": Body, "instrument": Instrument, "flyby": Flyby, "swarm": Swarm,
          "attitude": Attitude, "design": Design, "monte_carlo": MonteCarlo, "run": Run,
          "target": Target, "navigation": Navigation}


@dataclass(frozen=True)
class CampaignConfig:
    """The validated campaign: one frozen table per ``[table]``, SI values under SI names
    (``config.instrument.aperture_m``, ``config.design.p_min_s``). The model tables
    (``[dynamics]``, ``[spacecraft]``, ``[controller]``, ``[coverage]``) are built
    by their modules into :attr:`Campaign.extras`."""

    kind: str
    seed: int
    description: str
    body: Any
    instrument: Any
    flyby: Any
    swarm: Any
    attitude: Any
    design: Any
    monte_carlo: Any
    run: Any
    target: Any
    navigation: Any = None


def typed_config(values: dict) -> CampaignConfig:
    """:class:`CampaignConfig` from :func:`~ideas_hpc.base.fields.validate`'s output."""
    tables = {k: to_typed(live_typed_table(cls, SCHEMA[k], __name__), values[k], SCHEMA[k])
              for k, cls in TABLES.items()}
    return CampaignConfig(kind=values["kind"], seed=values["seed"],
                          description=values["description"], **tables)


@dataclass
class Campaign:
    """A validated campaign: its typed config, the raw data and its source."""

    config: CampaignConfig
    raw: dict
    source: CampaignSource
    extras: dict = field(default_factory=dict)

    @property
    def kind(self) -> str:
        return self.config.kind

    def error(self, message: str, dotted: str) -> InputError:
        return self.source.error(message, dotted)


def _cross_checks(c: CampaignConfig) -> None:
    fb, d, mc, sw = c.flyby, c.design, c.monte_carlo, c.swarm
    if fb.tf_s <= fb.t0_s:
        raise InputError(f"must be > flyby.t0_s ({fb.t0_s:g} s)", field="flyby.tf_s")
    if fb.z_start_m == fb.z_stop_m:
        raise InputError(f"equals flyby.z_start_km ({fb.z_start_m / KM:g} km): the flyby "
                         "would start and end at the same point", field="flyby.z_stop_km")
    if d.p_min_s >= d.p_max_s:
        raise InputError(f"must be > design.p_min_min ({d.p_min_s / MINUTE:g} min)",
                         field="design.p_max_min")
    with config_fields(prefix="monte_carlo."):
        check_dispersions(mc)
    if d.failures_tolerated >= d.n_max:
        raise InputError(f"must be < design.n_max ({d.n_max}): {d.failures_tolerated} "
                         "failures would leave no spacecraft", field="design.failures_tolerated")
    kind = REGISTRY[c.kind]
    if kind.swarm != "designed":
        if not sw.angles_rad and not (kind.swarm == "file-angles" and d.nadir_store):
            raise InputError(f"is required for kind {c.kind!r}", field="swarm.angles_rad")
        if (sw.sweep_periods_s is not None and sw.angles_rad is not None
                and len(sw.sweep_periods_s) != len(sw.angles_rad)):
            raise InputError(f"has {len(sw.sweep_periods_s)} periods for "
                             f"{len(sw.angles_rad)} spacecraft", field="swarm.sweep_periods_min")
    if campaign_maneuver(c.attitude.maneuver).sweeps and kind.swarm == "file":
        if sw.sweep_periods_s is None:
            raise InputError(f"is required for attitude.maneuver = {c.attitude.maneuver!r}",
                             field="swarm.sweep_periods_min")
    with config_fields(prefix="monte_carlo."):   # the failure model against the fleet
        if kind.swarm == "designed":
            check_fleet(mc, d.n_max, "design.n_max")
        elif sw.angles_rad:
            check_fleet(mc, len(sw.angles_rad), "the swarm size", swarm=True)
    with config_fields(DESIGNER_FIELDS):
        check_objectives(d.objectives)
    check_encounter(fb, c.attitude)
    check_navigation(c.navigation)
    reliability_checks(c)
    reference_checks(c)
    step = fb.dt_s
    img = 1.0 / c.instrument.image_rate_hz
    if abs(img / step - round(img / step)) > 1e-9:
        raise InputError(f"attitude step {step:g} s does not divide the image period {img:g} s",
                         field="flyby.dt_s")
    span = (fb.tf_s - fb.t0_s) / step
    if abs(span - round(span)) > 1e-6:
        raise InputError(f"step {step:g} s does not divide the flyby duration", field="flyby.dt_s")


def validate_campaign(source: CampaignSource) -> Campaign:
    """Validate a loaded source; every error carries the field, file and line. A key the
    campaign sets but its kind (under its settings) does not read is refused
    (:mod:`~ideas_hpc.campaign.schema.reads`), unless the source is a store's resolved
    config."""
    try:
        values = validate(source.data, SCHEMA)
        config = typed_config(values)
        if not source.resolved:     # a key the run ignores is refused (reads.py)
            off = switched_off(source, SCHEMA, lambda path: load_campaign(path, []),
                               lambda data: typed_config(validate(data, SCHEMA)))
            for key, why in check_reads(config, source.data, SCHEMA, off):
                f, ln = source.where(key)
                print(f"ideas-hpc: warning: {f}:{ln}: {key}: {why} (switched off by --set: "
                      "the file's value is not read)", file=sys.stderr)
        config = resolve_angle_step(config)
        with flyby_errors():   # the maneuver registry names `maneuver`
            _cross_checks(config)
        extras = build_models(source.data, config)
        extras.update(resolve_spice(source.data, config.body.name, source.path))  # {} without
    except InputError as exc:
        raise source.locate(exc) from None
    return Campaign(config=config, raw=source.data, source=source, extras=extras)


def load(path, overrides: list[str] | None = None) -> Campaign:
    """Load, override and validate a campaign file."""
    return validate_campaign(load_campaign(path, overrides))


# Settings that change how a run is executed but not its numbers: kept out of
# the resolved config (and so out of its hash), so a resume may change them.
EXECUTION_KNOBS = ("run.workers", "run.chunk_size", "design.chunk_size", "run.device")


class ResolvedConfig(dict):
    """A resolved config (a plain dict: stored and hashed as such) that knows its defaults.

    ``defaults`` maps dotted keys to their default: the schema's (file units)
    and, under ``models.<name>.``, the sub-model dataclasses' field defaults.
    The engine uses it on ``--resume`` to accept a store written before a key
    existed when the key still has its default (the old behaviour). ``effective``
    maps keys whose default is null (the code picks the value) to the value
    picked, so a store that wrote that value out (older code) still matches.
    """

    defaults: dict[str, Any]
    effective: dict[str, Any]


def _model_defaults(extras: dict) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, model in extras.items():
        if dataclasses.is_dataclass(model):
            for f in dataclasses.fields(model):    # under the stored names
                key = f"models.{name}.{STORED_NAMES.get(name, {}).get(f.name, f.name)}"
                if f.default is not dataclasses.MISSING:
                    out[key] = f.default
                elif f.default_factory is not dataclasses.MISSING:
                    out[key] = f.default_factory()
    return out


def resolved_config(c: Campaign) -> dict[str, Any]:
    """The campaign as run, with nothing implicit: what a store records and hashes.

    Every schema key with its value or default in the file's units
    (:func:`ideas_hpc.base.fields.with_defaults`), and under ``models`` the
    resolved sub-models of ``[dynamics]``, ``[spacecraft]``, ``[controller]``
    and ``[coverage]`` (SI, every default of their modules written out, under the
    names of :data:`~ideas_hpc.campaign.schema.model_fields.STORED_NAMES`). So a
    changed default changes the hash, and ``--resume`` names the field. The
    :data:`EXECUTION_KNOBS` are left out: they do not change the numbers.
    Every store writer (flyby, designs, Monte Carlo) uses this one function.
    The result is a :class:`ResolvedConfig`: its ``defaults`` let ``--resume``
    accept a store written before a key was added, while the key keeps its default.
    """
    from ideas_hpc.engine.store_meta import config_json  # the engine's canonical JSON, for one hash

    out = json.loads(config_json(with_defaults(c.raw, SCHEMA)))
    out["models"] = json.loads(config_json({k: stored_fields(k, dataclasses.asdict(v)) if
                                            dataclasses.is_dataclass(v) else v
                                            for k, v in c.extras.items()}))
    for dotted in EXECUTION_KNOBS:
        table, _, key = dotted.partition(".")
        out.get(table, {}).pop(key, None)
    out = ResolvedConfig(out)
    out.defaults = {**schema_defaults(SCHEMA), **_model_defaults(c.extras)}
    # its default is not the old behaviour (the paper's start): a store written before
    # the key existed must not resume under it
    out.defaults.pop("monte_carlo.attitude_start", None)
    d = c.config.design
    out.effective = {"design.angle_step_deg": d.grid_step_rad / DEG,
                     "design.angle_step_rad": d.angle_step_rad,
                     "design.verify_samples": verify_samples(d),
                     "instrument.exposure_ms": exposure_ms(c.config)}
    return out

