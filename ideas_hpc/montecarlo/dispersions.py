"""The Monte Carlo dispersions, declared once (SPEC section 8).

Each entry of :data:`DISPERSIONS` says what one dispersion draws, how it turns
into a :class:`~ideas_hpc.flyby.flight.Perturbation` of the flyby, and which store
variables record it (name, dims, units), and which ``[monte_carlo]`` keys it
reads (``keys``: :class:`~ideas_hpc.base.fields.Field` s, with its cross-check
``check``). The campaign's ``[monte_carlo]`` table, the Monte Carlo kind's store
layout, its per-sample draws and its perturbations are built from this list and
nothing else, so a new dispersion is one entry here (plus, if it perturbs
something the flyby cannot perturb yet, one field of ``Perturbation``).

Streams and order
-----------------
The seed scheme is :mod:`ideas_hpc.base.seeds`. Sample ``k`` of campaign seed ``s`` owns ``SeedSequence(s, spawn_key=(k,))``.
Entries with ``stream="sample"`` draw from that sequence itself (the attitude
start, :func:`attitude_draw`: with ``attitude_start = "paper"`` equal to
:func:`ideas_hpc.attitude.initial_conditions` ``(s, k, N)``); every other entry draws from the child
``SeedSequence(s, spawn_key=(k, 1))``, in the order of :data:`DISPERSIONS`,
and always draws, switched on or not, so switching one on does not shift the
others. Append new entries at the end: an entry inserted earlier changes the
numbers of every sample of existing campaigns. The order is stored in the
store's ``dispersion_order`` attr.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ideas_hpc.attitude import draw_initial_conditions
from ideas_hpc.attitude.modes import ATTITUDE_STARTS, attitude_start
from ideas_hpc.core.attitude.mrp import mrp_from_prv
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field
from ideas_hpc.base.seeds import sample_rng
from ideas_hpc.engine.variables import StoreVar
from ideas_hpc.montecarlo import failure_dispersion, navigation_dispersion
from ideas_hpc.base.units import DEG, MM

DISPERSION_CHILD = 1  # spawn_key suffix of the child stream


@dataclass(frozen=True)
class Dispersion:
    """One declared dispersion.

    ``draw(rng, n, mc, setup, theta)`` (``mc``: the typed ``[monte_carlo]`` table) returns the sample's values of
    ``variables`` (SI, per spacecraft where the dims say so) from generator
    ``rng``; ``perturb(values)`` returns the
    :class:`~ideas_hpc.flyby.flight.Perturbation` fields it sets. ``keys`` are its
    ``[monte_carlo]`` keys, ``((key, Field), ...)`` (the draw reads them by SI name
    from ``mc``); ``check(mc)`` cross-checks them, raising ``InputError`` naming
    its own key (the campaign prefixes ``monte_carlo.``).

    Every entry also says, for the success-probability designer's scenario bank
    (:mod:`ideas_hpc.montecarlo.scenarios`), how it is drawn there:

    ``level``
        ``"body"``: one draw per scenario shared by every candidate (the body's
        gravity, its SRP reflectivity); ``"spacecraft"``: drawn with one row
        per candidate (``n = theta.size``), independently for each.
    ``active(mc, setup) -> bool``
        Whether, under this table and setup, it draws anything but the nominal
        value. When no ``designer="scenario"`` entry is active a scenario is the
        nominal flight and the designer is exact (one scenario).
    ``designer``
        ``"scenario"``: drawn into every scenario; ``"exact"``: not drawn, the
        designer handles it exactly (failures are enumerated).
    ``applies(setup) -> bool``
        Whether a flight of this setup reads its values at all (``None``:
        always); the initial attitude only matters to a simulated attitude. A
        scenario leaves out the perturbation of an entry that does not apply
        (and, on a stream of its own, its draws).

    ``level`` and ``active`` have no default: an entry that does not say is
    refused when it is declared, not flown as something it is not.
    """

    name: str
    draw: Callable[..., dict]
    perturb: Callable[[dict], dict]
    variables: tuple[StoreVar, ...]
    stream: str = "child"
    keys: tuple = ()
    check: Callable | None = None
    level: str | None = None
    active: Callable | None = None
    designer: str = "scenario"
    applies: Callable | None = None
    reads_mc: bool = False

    def perturbation(self, values: dict, mc) -> dict:
        """The :class:`~ideas_hpc.flyby.flight.Perturbation` fields of ``values``:
        ``perturb(values)``, or ``perturb(values, mc)`` for an entry with ``reads_mc``
        (the attitude start, whose meaning depends on ``monte_carlo.attitude_start``)."""
        return self.perturb(values, mc) if self.reads_mc else self.perturb(values)

    def __post_init__(self):
        if self.level not in LEVELS:
            raise ValueError(f"dispersion {self.name!r}: level must be one of {LEVELS}, "
                             f"got {self.level!r}")
        if not callable(self.active):
            raise ValueError(f"dispersion {self.name!r}: declare active(mc, setup) -> bool")
        if self.designer not in ("scenario", "exact"):
            raise ValueError(f"dispersion {self.name!r}: designer must be 'scenario' or "
                             f"'exact', got {self.designer!r}")
        if self.stream not in ("child", "sample"):
            raise ValueError(f"dispersion {self.name!r}: stream must be 'child' or 'sample'")


#: Where a dispersion acts: the whole body, or each spacecraft.
LEVELS = ("body", "spacecraft")

#: ``[monte_carlo] attitude_start`` choices (docs/attitude-start.md): the registry
#: :data:`ideas_hpc.attitude.modes.ATTITUDE_STARTS`, read live.


def _attitude(rng, n, mc, setup, theta):
    # rng: the sample's own generator (stream="sample"), so that with the paper's
    # start sample k's draws equal initial_conditions(seed, k, n)
    return attitude_draw(rng, n, mc)


def attitude_draw(rng, n: int, mc) -> dict:
    """The initial attitude of ``n`` spacecraft from ``rng`` (SPEC section 7d).

    A start with ``random_state`` (``attitude_start = "paper"`` and ``"acquisition"``):
    the paper's random state
    (:func:`ideas_hpc.attitude.draw_initial_conditions`: ``sigma_BN``, ``omega_BN_B``,
    wheels), flown from t0 ("paper") or for ``acquisition_s`` before the window.
    Otherwise (``"reference"``): the errors about the reference of the geometry flown, a
    rotation of normal angle ``sigma_attitude_rad`` per axis (as an MRP
    ``sigma_B/R``) and a rate error of ``sigma_rate_rad_s`` per axis
    (``omega_B/R``, B), wheels at rest. ``attitude_dispersion = false``: no draw,
    every start exactly on the reference (zeros).
    """
    if not mc.attitude_dispersion:
        z = np.zeros((n, 3))
        return {"sigma0": z, "omega0": z.copy(), "wheel0": z.copy()}
    if not attitude_start(mc.attitude_start).random_state:
        prv = mc.sigma_attitude_rad * rng.standard_normal((n, 3))
        w = mc.sigma_rate_rad_s * rng.standard_normal((n, 3))
        return {"sigma0": np.stack([mrp_from_prv(np.ascontiguousarray(v)) for v in prv])
                .reshape(n, 3), "omega0": w, "wheel0": np.zeros((n, 3))}
    s0, w0, W0 = draw_initial_conditions(rng, n)
    return {"sigma0": s0, "omega0": w0, "wheel0": W0}


def attitude_perturbation(mc, v: dict) -> dict:
    """:class:`~ideas_hpc.flyby.flight.Perturbation` keywords of an attitude draw ``v``:
    absolute (``ics``, with ``acquisition_s`` for a start with ``acquisition``) for the
    random starts, relative to the reference flown (``ics_reference``) otherwise."""
    ics = (v["sigma0"], v["omega0"], v["wheel0"])
    start = attitude_start(mc.attitude_start)
    if not mc.attitude_dispersion or not start.random_state:
        return {"ics_reference": ics}
    if start.acquisition:
        return {"ics": ics, "acquisition_s": float(mc.acquisition_s)}
    return {"ics": ics}


def _attitude_active(mc, setup) -> bool:
    """A closed loop whose start draws anything: a random state, or errors about the
    reference with a non-zero sigma."""
    return (setup.attitude.closed_loop and mc.attitude_dispersion
            and (attitude_start(mc.attitude_start).random_state
                 or mc.sigma_attitude_rad != 0 or mc.sigma_rate_rad_s != 0))


def _check_attitude(mc):
    if attitude_start(mc.attitude_start).acquisition and mc.attitude_dispersion and \
            not mc.acquisition_s > 0.0:
        raise InputError("must be > 0 s with `attitude_start = \"acquisition\"`",
                         field="acquisition_s")


def _gravity(rng, n, mc, setup, theta):
    z = rng.standard_normal(3)
    p = setup.body.params
    return {"c20": p.c20 * (1.0 + mc.sigma_c20_pct / 100.0 * z[0]),
            "c22": p.c22 * (1.0 + mc.sigma_c22_pct / 100.0 * z[1]),
            "mu": p.mu * (1.0 + mc.sigma_gm_pct / 100.0 * z[2])}


def _check_reflectivity(mc):
    if mc.reflectivity_min > mc.reflectivity_max:
        raise InputError("must be >= `reflectivity_min`", field="reflectivity_max")


def _reflectivity(rng, n, mc, setup, theta):
    u = rng.uniform(0.0, 1.0)
    lo, hi = mc.reflectivity_min, mc.reflectivity_max
    return {"reflectivity": lo + (hi - lo) * u}


def _state(rng, n, mc, setup, theta):
    dr = rng.standard_normal((n, 3))
    dv = rng.standard_normal((n, 3))
    return {"position_error": mc.sigma_position_m * dr,
            "velocity_error": mc.sigma_velocity_m_s * dv}


def _misalignment(rng, n, mc, setup, theta):
    axes = rng.standard_normal((n, 3))
    angles = rng.standard_normal(n)
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    return {"misalignment_prv": axes * (mc.sigma_misalignment_rad * angles)[:, None]}


SC3 = ("spacecraft", "axis")
DISPERSIONS: tuple[Dispersion, ...] = (
    Dispersion("attitude", _attitude, lambda v, mc: attitude_perturbation(mc, v),
               (StoreVar("sigma0", SC3, np.float64, "1", "initial sigma_BN (attitude_start "
                         "paper, acquisition) or sigma_B/R about the reference (reference)"),
                StoreVar("omega0", SC3, np.float64, "rad/s", "initial omega_BN_B (paper, "
                         "acquisition) or omega_B/R in B about the reference (reference)"),
                StoreVar("wheel0", ("spacecraft", "wheel"), np.float64, "rad/s",
                         "initial wheel speeds")),
               stream="sample",
               keys=(("attitude_dispersion",
                      Field("bool", True, doc="draw the initial attitude (false: start "
                                              "exactly on the reference)")),
                     ("attitude_start",
                      Field("str", "reference", choices=ATTITUDE_STARTS,
                            doc="reference: on the reference with knowledge and control "
                                "errors; acquisition: closed loop from a random attitude "
                                "for acquisition_s before the window; paper: random "
                                "attitude at the window's start (paper Figs. 26-29)")),
                     ("acquisition_s", Field("float", 300.0, lo=0,
                                             doc="acquisition phase before the window, s")),
                     ("sigma_attitude_deg", Field("float", 0.03, si="sigma_attitude_rad",
                                                  to_si=DEG, lo=0, hi=10,
                                                  doc="1-sigma attitude error per axis at "
                                                      "the window's start")),
                     ("sigma_rate_rad_s", Field("float", 5e-5, lo=0, hi=0.1,
                                                doc="1-sigma rate error per axis, rad/s"))),
               check=_check_attitude, level="spacecraft", reads_mc=True,
               active=_attitude_active, applies=lambda setup: setup.attitude.closed_loop),
    Dispersion("gravity", _gravity,
               lambda v: {"params_override": {"mu": v["mu"], "c20": v["c20"], "c22": v["c22"]}},
               (StoreVar("c20", (), np.float64, "m^2", "C20 (dispersed)"),
                StoreVar("c22", (), np.float64, "m^2", "C22 (dispersed)"),
                StoreVar("mu", (), np.float64, "m^3/s^2", "GM (dispersed)")),
               keys=(("sigma_c20_pct", Field("float", 0.0, lo=0, doc="1-sigma relative C20 "
                                                                   "error, %")),
                     ("sigma_c22_pct", Field("float", 0.0, lo=0)),
                     ("sigma_gm_pct", Field("float", 0.0, lo=0))),
               level="body",
               active=lambda mc, setup: (mc.sigma_c20_pct, mc.sigma_c22_pct,
                                         mc.sigma_gm_pct) != (0, 0, 0)),
    Dispersion("reflectivity", _reflectivity,
               lambda v: {"params_override": {"reflectivity": v["reflectivity"]}},
               (StoreVar("reflectivity", (), np.float64, "1", "SRP reflectivity (dispersed)"),),
               keys=(("reflectivity_min", Field("float", 0.6, lo=0, hi=1)),
                     ("reflectivity_max", Field("float", 0.6, lo=0, hi=1))),
               check=_check_reflectivity, level="body",
               active=lambda mc, setup: mc.reflectivity_min != mc.reflectivity_max),
    Dispersion("initial_state", _state,
               lambda v: {"position_error_T": v["position_error"],
                          "velocity_error_T": v["velocity_error"]},
               (StoreVar("position_error", SC3, np.float64, "m",
                         "initial position error, frame T"),
                StoreVar("velocity_error", SC3, np.float64, "m/s",
                         "initial velocity error, frame T")),
               keys=(("sigma_position_m", Field("float", 0.0, lo=0, doc="1-sigma initial "
                                                                        "position error per axis")),
                     ("sigma_velocity_mm_s", Field("float", 0.0, si="sigma_velocity_m_s",
                                                   to_si=MM, lo=0))),
               level="spacecraft",
               active=lambda mc, setup: (mc.sigma_position_m, mc.sigma_velocity_m_s) != (0, 0)),
    # the failure model (issue 41): keys, check and draw in montecarlo/failure_dispersion.py
    Dispersion("failures", failure_dispersion.draw, lambda v: {"active": v["active"]},
               (StoreVar("active", ("spacecraft",), bool, "1",
                         "spacecraft working (False: failed)"),
                StoreVar("n_failed", (), np.int32, "1", "failed spacecraft")),
               keys=failure_dispersion.FAILURE_KEYS, check=failure_dispersion.check,
               level="spacecraft", designer="exact",
               active=lambda mc, setup: failure_dispersion.failures_active(mc)),
    Dispersion("misalignment", _misalignment,
               lambda v: {"misalignment_prv": v["misalignment_prv"]},
               (StoreVar("misalignment_prv", SC3, np.float64, "rad",
                         "camera misalignment (PRV)"),),
               keys=(("sigma_misalignment_deg", Field("float", 0.0, si="sigma_misalignment_rad",
                                                      to_si=DEG, lo=0, hi=90)),),
               level="spacecraft", active=lambda mc, setup: mc.sigma_misalignment_rad != 0),
    # navigation at an encounter (SPEC 7f; the [navigation] table, FlybySetup.navigation):
    # the target's ephemeris error once per scenario for the whole swarm, each member's own
    Dispersion("navigation", navigation_dispersion.draw_common,
               lambda v: {"target_offset_N": v["target_offset"]},
               navigation_dispersion.COMMON_VARS, level="body",
               active=navigation_dispersion.common_active,
               applies=navigation_dispersion.applies),
    Dispersion("navigation_member", navigation_dispersion.draw_member,
               lambda v: {"member_offset_N": v["member_offset"],
                          "centroid_prv": v["centroid_prv"]},
               navigation_dispersion.MEMBER_VARS, level="spacecraft",
               active=navigation_dispersion.member_active,
               applies=navigation_dispersion.applies),
)
DISPERSION_ORDER = tuple(d.name for d in DISPERSIONS)
DISPERSION_VARS: tuple[StoreVar, ...] = tuple(v for d in DISPERSIONS for v in d.variables)


def dispersion_order() -> tuple[str, ...]:
    """The names of :data:`DISPERSIONS` in draw order (read live)."""
    return tuple(d.name for d in DISPERSIONS)


def dispersion_vars() -> tuple[StoreVar, ...]:
    """Every store variable the dispersions declare, in draw order (read live)."""
    return tuple(v for d in DISPERSIONS for v in d.variables)


def dispersion_keys() -> dict:
    """Every dispersion's ``[monte_carlo]`` keys, ``{key: Field}``, in draw order (read live)."""
    return {k: f for d in DISPERSIONS for k, f in d.keys}


def scenario_dispersed(mc, setup) -> bool:
    """True when some dispersion drawn into the designer's scenarios is active (read live):
    False means every scenario is the nominal flight."""
    return any(d.active(mc, setup) for d in DISPERSIONS if d.designer == "scenario")


def check_dispersions(mc) -> None:
    """Every dispersion's cross-check of the typed ``[monte_carlo]`` table."""
    for d in DISPERSIONS:
        if d.check is not None:
            d.check(mc)


def draw_sample(mc, seed: int, k: int, theta: np.ndarray, setup) -> tuple[dict, dict]:
    """Every dispersion of sample ``k``, in declared order.

    ``mc`` is the validated ``[monte_carlo]`` table
    (:class:`~ideas_hpc.campaign.schema.campaign_tables.MonteCarlo`: SI values under SI names).

    Returns
    -------
    values : dict
        Store variable -> this sample's value (SI).
    perturbation : dict
        Keyword arguments of :class:`~ideas_hpc.flyby.flight.Perturbation`.
    """
    n = theta.size
    child = sample_rng(seed, k, DISPERSION_CHILD)
    values: dict = {}
    pert: dict = {}
    for d in DISPERSIONS:
        rng = sample_rng(seed, k) if d.stream == "sample" else child
        v = d.draw(rng, n, mc, setup, theta)
        values.update(v)
        for key, val in d.perturbation(v, mc).items():
            if isinstance(val, dict):
                pert.setdefault(key, {}).update(val)
            else:
                pert[key] = val
    return values, pert
