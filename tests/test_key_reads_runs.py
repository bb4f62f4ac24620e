"""The declaration of the keys each kind reads, against what real runs read (issue 41).

Each kind runs once on the built-in ellipsoid at the small sizes of
``tests/small_stores.py`` (the exact and the success-probability designs, the GA,
the FoV GA, NSGA-II, the flyby and the Monte Carlo kind), with its typed config
tables recording every field the run reads (``c.config.design.population``). Then:

* every key the declaration (:mod:`ideas_hpc.campaign.schema.reads`) says this run
  reads was read, save :data:`UNSEEN` (read where the recorder cannot see it);
* every key the run read is declared read, save :data:`TOUCHED` (fields a run copies
  or checks without their value changing what it computes), so the refusal never
  hits a key a run uses.

Reads that only record the run (the store's resolved config, its attrs) or pick the
runner do not count. The model tables (``[dynamics]``, ``[coverage]``,
``[spacecraft]``, ``[controller]``, ``[torques]``) are built whole at load and are
not recorded; their rules are the attitude mode's (tests/test_key_reads.py).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import pytest

import ideas_hpc.campaign.run as run_module
from ideas_hpc.base.fields import Field
from ideas_hpc.campaign.schema import reads
from ideas_hpc.campaign.schema.campaign_tables import SCHEMA, TABLES
from ideas_hpc.campaign.schema.read_settings import Settings

from small_stores import CAMPAIGNS, KINDS

#: Functions whose reads record the run or pick its runner, and the dataclass machinery.
NOT_READS = {"_run", "__repr__", "__eq__", "__hash__", "asdict", "_asdict_inner", "replace",
             "_replace"}
#: ... and the store's record (its resolved config and attrs), also through the helpers
#: and comprehensions they read in (``verify_samples(d)``).
RECORDS = {"resolved_config", "base_attrs"}
#: Keys whose values reach the run as one field (the deprecated alias and the key).
ALIASES = ({"design.angle_step_deg", "design.angle_step_rad"},)

#: The runs (keys of ``small_stores.KINDS``) with ideal attitude, and with a designed swarm.
ALL = tuple(KINDS)
IDEAL = ("design-exact", "design-ga", "design-fov", "design-pareto", "design-reliability")
DESIGNED = ("design-exact", "design-ga", "design-pareto", "design-reliability")
NOT_SWEEPING = tuple(k for k in ALL if k != "design-fov")

#: Declared read, read where the recorder does not see it: key -> (why, in which runs).
UNSEEN = {
    "run.workers": ("run_file hands it to the kind's runner as its workers argument",
                    tuple(k for k in ALL if k != "flyby")),
    "body.kernels": ("read from the raw table at load (resolve_spice), before the run", ALL),
    "instrument.pixel_pitch_um": ("copied from the raw [instrument] table into [coverage] at "
                                  "load (build_models); the usable-image test, which the "
                                  "paper's start leaves out, reads it too",
                                  ("flyby", "monte-carlo")),
    "instrument.focal_length_mm": ("as instrument.pixel_pitch_um", ("flyby", "monte-carlo")),
    "attitude.maneuver": ("a kind that always flies its own maneuver takes the file's only "
                          "when it names that one", ("design-fov",)),
}
_IMAGING = ("the setup builds the usable-image test for every flight; only a simulated "
            "attitude, or perfect tracking on an encounter, applies it", IDEAL)
_DRAWN = ("the attitude entry always draws, so that turning it on shifts no other stream; an "
          "ideal flight drops the draw", ("design-exact", "design-reliability"))
_POINTING = ("the pointing warning of the setup of every design kind",
             ("design-ga", "design-fov", "design-pareto"))
#: Read by a run, not declared read: touched without changing what it computes.
TOUCHED = {
    "design.p_min_min": ("copied into every FlybySetup; only a sweeping maneuver reads it",
                         NOT_SWEEPING),
    "attitude.theta_max_deg": ("copied into every FlybySetup; only a sweeping maneuver reads "
                               "it", NOT_SWEEPING),
    "flyby.helix_rise_km": ("copied into every FlybySetup; only a helix reads it", ALL),
    "attitude.decimate": ("copied into every FlybySetup; a kind that stores no flight ignores "
                          "it", ("design-pareto",)),
    "monte_carlo.attitude_start": ("copied into every FlybySetup; only a closed loop starts "
                                   "from it", IDEAL),
    "run.device": ("checked in every setup (cuda where there is none is refused); only a "
                   "closed loop flies on it", IDEAL),
    **{f"instrument.{k}": _IMAGING for k in ("pixels_across", "exposure_ms", "smear_pixels",
                                             "settle_deg")},
    "swarm.angles_rad": ("the setup asks whether the file gave angles (to check their "
                         "spacing)", DESIGNED),
    "swarm.sweep_periods_min": ("handed to the maneuver, which keeps them only if it sweeps",
                                ("flyby", "monte-carlo")),
    "monte_carlo.sigma_misalignment_deg": _POINTING,
    "monte_carlo.sigma_position_m": _POINTING,
    "monte_carlo.attitude_dispersion": _DRAWN,
    "monte_carlo.sigma_attitude_deg": _DRAWN,
    "monte_carlo.sigma_rate_rad_s": _DRAWN,
    "monte_carlo.acquisition_s": (_DRAWN[0], ("design-reliability",)),
    "design.method": ("the grid check of every design kind asks whether the method takes "
                      "continuous angles", ("design-fov", "design-pareto")),
    "design.angle_step_deg": ("the grid check of every design kind reads the grid (design-fov "
                              "has none: its default passes)", ("design-fov",)),
    "design.angle_step_rad": ("as design.angle_step_deg", ("design-fov",)),
    "design.coverage_reference": ("the requirement record copies it; a kind that does not "
                                  "declare it refuses the key, so it keeps the whole surface",
                                  ("design-ga", "monte-carlo")),
    "design.eps_tol_pct": ("the FoV GA computes a threshold it keeps for nadir designs only",
                           ("design-fov",)),
    "design.n_max": ("the FoV GA's estimate of its work (the cluster's size)", ("design-fov",)),
    "design.demonstrate_looks": ("handed to the look plan, which plans one look without "
                                 "design.demonstrate", ("design-reliability",)),
    "monte_carlo.failure_in_pass_share": ("the failure model is built whole; the Monte Carlo "
                                          "draws and the verification fly whole-pass losses",
                                          ("design-exact", "monte-carlo")),
}


def _exempt(table: dict, kind: str) -> set:
    return {key for key, (_, runs) in table.items() if kind in runs}


def _keys(table: str) -> dict:
    """SI field name -> dotted file key of a typed table."""
    return {f.si_name(k): f"{table}.{k}" for k, f in SCHEMA[table].items()
            if isinstance(f, Field)}


def _is_read(frame) -> bool:
    """Not a read when the reading function is one of :data:`NOT_READS`, or when it or
    its caller is :data:`RECORDS`."""
    if frame.f_code.co_name in NOT_READS:
        return False
    caller = frame.f_back.f_code.co_name if frame.f_back is not None else ""
    return not RECORDS & {frame.f_code.co_name, caller}


def _record(obj, table: str, log: set) -> None:
    """Make the typed table ``obj`` add the dotted key of every field read to ``log``."""
    names = _keys(table)

    def getattribute(self, name):
        key = names.get(name)
        if key is not None and _is_read(sys._getframe(1)):
            log.add(key)
        return object.__getattribute__(self, name)

    cls = type(obj)
    object.__setattr__(obj, "__class__", type(cls.__name__, (cls,),
                                              {"__getattribute__": getattribute}))


def _with_aliases(keys: set) -> set:
    out = set(keys)
    for group in ALIASES:
        if out & group:
            out |= group
    return out


@pytest.mark.parametrize("kind", KINDS)
def test_what_a_run_reads_is_what_its_kind_declares(kind, tmp_path, monkeypatch):
    campaign, sets, _ = KINDS[kind]
    log: set = set()
    declared: set = set()
    loader = run_module.load

    def load(path, overrides=None):
        c = loader(path, overrides)
        s = Settings(c.config, c.raw)
        declared.update(k for t in TABLES for k in _keys(t).values() if reads.is_read(k, s))
        for table in TABLES:
            _record(getattr(c.config, table), table, log)
        return c

    monkeypatch.setattr(run_module, "load", load)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)      # the GA's angle_step_rad alias
        run_module.run_file(CAMPAIGNS / campaign, out=Path(tmp_path) / "s.zarr",
                            overrides=sets, workers=0, progress=False)
    read = _with_aliases(log)
    declared = _with_aliases(declared)
    unseen, touched = _exempt(UNSEEN, kind), _exempt(TOUCHED, kind)
    unread = sorted(declared - read - unseen)
    assert not unread, f"{kind}: declared read, never read: {unread}"
    undeclared = sorted(read - declared - touched)
    assert not undeclared, f"{kind}: read, declared unread (refused in a file): {undeclared}"
    # the exemptions are exact: each one listed for this run is needed here
    assert unseen <= declared - read, f"{kind}: stale UNSEEN {sorted(unseen - (declared - read))}"
    assert touched <= read - declared, f"{kind}: stale TOUCHED {sorted(touched - (read - declared))}"
