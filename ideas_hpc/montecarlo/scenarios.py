"""The scenario bank of the reliability designer, and the validation flights (issue 20).

A *scenario* is one draw of the continuous ``[monte_carlo]`` dispersions for
the whole candidate grid; each entry of
:data:`~ideas_hpc.montecarlo.dispersions.DISPERSIONS` says how (read live):

* ``level="body"`` (gravity ``mu``, ``C20``, ``C22``; SRP reflectivity): drawn
  once and shared by every candidate;
* ``level="spacecraft"`` (initial position and velocity errors, camera
  misalignment, the initial attitude, rates and wheel speeds, which only a
  simulated attitude reads): drawn independently for every candidate.

Entries with ``designer="exact"`` (failures) are not drawn: the designer
handles them exactly. Every candidate is
targeted once on the nominal model and flown open loop through each scenario's
world (:class:`~ideas_hpc.flyby.world.World`: the nominal one with the scenario's
body-level draws) by the one flight path
(:func:`ideas_hpc.flyby.views.flight_views`); its row is what it sees, or with a
``[coverage]`` requirement what it maps (:func:`ideas_hpc.design.candidates.rows_from_views`).
Members fly independently, so a swarm's coverage in scenario ``s`` is the union
of its members' rows ``rows[s, members]``.

Streams: :mod:`ideas_hpc.base.seeds` (``SCENARIO_STREAM`` for the bank,
``VALIDATION_STREAM`` for :func:`fly_members`); scenario ``s`` depends only on
``(seed, s)``, never on the chunking or the worker count.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass

import numpy as np

from ideas_hpc.engine.store_meta import config_hash
from ideas_hpc.base.progress import map_chunks
from ideas_hpc.flyby.flight import FlybySetup, Perturbation, endpoints, target
from ideas_hpc.base.seeds import (HOLDOUT_STREAM, SCENARIO_STREAM, STREAM_ATTITUDE,
                                  STREAM_BODY, STREAM_SPACECRAFT, VALIDATION_STREAM, stream_rng)
from ideas_hpc.montecarlo import dispersions as _dispersions
from ideas_hpc.flyby.target_world import scenario_world, world_areas
from ideas_hpc.montecarlo.scenario_rows import RowEngine
from ideas_hpc.montecarlo.scenario_store import build_into_store, chunk_task

TWO_PI = 2.0 * math.pi
#: The purpose word of each dispersion level's generator in a design stream.
LEVEL_STREAMS = {"body": STREAM_BODY, "spacecraft": STREAM_SPACECRAFT}


@dataclass(frozen=True)
class ScenarioBank:
    """Per-scenario candidate rows (module docstring).

    Attributes
    ----------
    theta : (C,) rad
        The design grid, ``theta_k = k 2 pi / C``.
    rows : (S, C, V) bool
        Vertex ``v`` seen (or mapped) by candidate ``c`` in scenario ``s``.
    areas : (V,) or (S, V) m^2
        Vertex areas: the body's, or with a target prior each scenario's world's
        (:func:`~ideas_hpc.flyby.target_world.world_areas`).
    attrs : dict
        Provenance: seed, stream words, ``n_scenarios``, config hash, timing.
    """

    theta: np.ndarray
    rows: np.ndarray
    areas: np.ndarray
    attrs: dict

    @property
    def n_scenarios(self) -> int:
        return int(self.rows.shape[0])


def draw_world(mc, setup: FlybySetup, theta: np.ndarray, seed: int, stream: int,
               k: int) -> dict:
    """Perturbation keywords of draw ``k`` of a design stream for spacecraft ``theta`` (rad).

    Each ``designer="scenario"`` entry of
    :data:`~ideas_hpc.montecarlo.dispersions.DISPERSIONS` draws, in its order,
    from its level's generator (purpose ``STREAM_BODY`` or
    ``STREAM_SPACECRAFT``; ``n = theta.size`` rows), or, with a stream of its own
    in the Monte Carlo kind (``stream="sample"``: the initial attitude, rates
    and wheel speeds with the laws of ``monte_carlo.attitude_start``, or the
    start exactly on the reference when ``monte_carlo.attitude_dispersion`` is
    off: :func:`~ideas_hpc.montecarlo.dispersions.attitude_draw`), from purpose
    ``STREAM_ATTITUDE``. No failures (``designer="exact"``), and nothing of an
    entry that does not apply to ``setup`` (the attitude of an ideal-attitude flight).
    """
    n = theta.size
    rngs = {level: stream_rng(seed, stream, k, word) for level, word in LEVEL_STREAMS.items()}
    pert: dict = {}
    for d in _dispersions.DISPERSIONS:
        flown = d.applies is None or d.applies(setup)
        if d.designer != "scenario" or (not flown and d.stream != "child"):
            continue
        rng = rngs[d.level] if d.stream == "child" else stream_rng(seed, stream, k,
                                                                     STREAM_ATTITUDE)
        v = d.draw(rng, n, mc, setup, theta)   # a shared stream draws all the same
        if not flown:
            continue
        for key, val in d.perturbation(v, mc).items():
            if isinstance(val, dict):
                pert.setdefault(key, {}).update(val)
            else:
                pert[key] = val
    return pert


def _rows_chunk(ks, *, engine: RowEngine, mc, seed, stream):
    setup = engine.setup
    out = None
    for i, k in enumerate(ks):
        pert = Perturbation(**draw_world(mc, setup, engine.theta, seed, stream, int(k)))
        if setup.target is None:
            row = engine.scenario_rows(pert, reuse=True)
        else:
            # world k of the stream's family: its own shape, so the nominal's proofs do not
            # hold; its rows come from its own statics (the world bank, RowEngine.rows)
            world = scenario_world(setup, seed, stream, int(k), pert.params_override)
            row = engine.rows(*engine.flight(pert, True, world), world=world)
        out = _rows_out(out, len(ks), row)
        out[i] = row
    return out


def _rows_out(out, n: int, row: np.ndarray) -> np.ndarray:
    """The chunk's (n, K, V) array, made at its first row: V is the flown world's vertex
    count (a given truth, :mod:`ideas_hpc.campaign.validate_truth`, may have its own mesh)."""
    return np.empty((n,) + row.shape, dtype=row.dtype) if out is None else out


def row_engine(setup: FlybySetup, theta, mc, seed: int, stream: int) -> RowEngine:
    """Targeted candidates ``theta`` with their nominal witnesses; budget from draw 0.
    With a target prior no world is the nominal one: no witnesses (every world's rows
    come from its own statics, :func:`~ideas_hpc.montecarlo.scenario_rows.world_rows`)."""
    r0, v0 = nominal_start(setup, theta)
    if setup.target is not None:
        return RowEngine(setup, theta, r0, v0)
    pilot = Perturbation(**draw_world(mc, setup, theta, seed, stream, 0))
    return RowEngine(setup, theta, r0, v0).prepare(pilot)


def _run_chunks(ks, fn, client, chunk_size, progress, label):
    parts = [ks[i:i + chunk_size] for i in range(0, len(ks), chunk_size)]
    # the row engine once per worker (see engine.runner._submit_all)
    out = map_chunks(fn, parts, client, desc=label if progress else None, unit="scenario",
                     sizes=[len(p) for p in parts], scatter=True)
    return np.concatenate(out) if out else None


def warm_rows(setup: FlybySetup, mc, seed: int, n_candidates: int = 2) -> None:
    """Scenario 0 of the bank for ``n_candidates`` candidates, rows discarded: compiles (or
    loads) the kernels of the bank's chunks, which the held-out and validation flights
    share, with their argument types (the row engine's nominal flight and proofs, the
    scenario's world, flight and rows). A cold cache's warm-up
    (:mod:`ideas_hpc.campaign.precompile`); the bank itself is untouched."""
    theta = (TWO_PI / 8) * np.arange(int(n_candidates))   # grid_theta's type, 8-point grid
    _rows_chunk([0], engine=row_engine(setup, theta, mc, seed, SCENARIO_STREAM), mc=mc,
                seed=int(seed), stream=SCENARIO_STREAM)


def grid_theta(step_rad: float) -> np.ndarray:
    """The snapped design grid ``k 2 pi / C`` (as :func:`ideas_hpc.design.bank.build_bank`)."""
    from ideas_hpc.design.bank import grid_size
    n = grid_size(step_rad)
    return (TWO_PI / n) * np.arange(n)


def nominal_start(setup: FlybySetup, theta) -> tuple[np.ndarray, np.ndarray]:
    """Start states (N, 3) m, m/s of spacecraft ``theta`` targeted on the nominal model."""
    r0, _ = endpoints(setup, theta)
    return r0, target(setup, theta).v0_T


def shaping_config(setup: FlybySetup, mc, step_rad: float, seed: int, n: int) -> dict:
    """What shapes a scenario bank (its hash decides reuse): the flyby, the body,
    the continuous dispersions, the grid, the seed and the number of scenarios."""
    # failures are enumerated by the designer, never flown: their keys shape no bank
    skip = {"samples"} | {f.si_name(k) for d in _dispersions.DISPERSIONS
                          if d.designer == "exact" for k, f in d.keys}
    mc_d = {f.name: getattr(mc, f.name) for f in dataclasses.fields(mc) if f.name not in skip}
    sh = setup.body.shape
    # a setup without a target prior hashes as before the field existed (stores reused)
    fs = {f.name: repr(getattr(setup, f.name)) for f in dataclasses.fields(setup)
          if f.name not in ("body", "seed", "decimate", "device")
          and not (f.name == "target" and setup.target is None)}
    import hashlib
    mesh = hashlib.sha256(np.ascontiguousarray(sh.vertices_T).tobytes()
                          + np.ascontiguousarray(sh.faces).tobytes()).hexdigest()
    return {"setup": fs, "body": {"params": repr(setup.body.params), "mesh": mesh},
            "monte_carlo": mc_d, "step_rad": float(step_rad), "seed": int(seed),
            "n_scenarios": int(n), "stream": SCENARIO_STREAM}


def build_scenario_bank(setup: FlybySetup, step_rad: float, mc, *, seed: int, n_scenarios: int,
                        client=None, store: str | None = None, progress: bool = True,
                        chunk_size: int = 4) -> ScenarioBank:
    """Rows of every grid candidate in ``n_scenarios`` scenarios (module docstring).

    Parameters
    ----------
    setup : FlybySetup
        The exact designer's setup.
    step_rad : float
        Grid step, rad (snapped to divide the circle).
    mc : MonteCarlo
        The validated ``[monte_carlo]`` table (SI); failures are not used.
    seed : int
        Campaign seed; scenario ``s`` draws from ``(SCENARIO_STREAM, s, purpose)``.
    n_scenarios : int
    client : distributed.Client, optional
        Spread chunks of ``chunk_size`` scenarios over its workers (same numbers).
    store : str, optional
        Zarr path to build into: an engine store chunked by scenario, resumed
        when some chunks are missing and read back without flying when it is
        complete and its shaping config is unchanged
        (:mod:`ideas_hpc.montecarlo.scenario_store`).
    progress : bool
        Progress bar on stderr.
    """
    t0 = time.perf_counter()
    theta = grid_theta(step_rad)
    areas = world_areas(setup, seed, SCENARIO_STREAM, range(int(n_scenarios)))
    config = shaping_config(setup, mc, step_rad, seed, n_scenarios)
    attrs = {"seed": int(seed), "scenario_stream": SCENARIO_STREAM,
             "validation_stream": VALIDATION_STREAM, "n_scenarios": int(n_scenarios),
             "config_hash": config_hash(config)}
    engines: list = []

    def chunk_rows():
        if not engines:
            engines.append(row_engine(setup, theta, mc, seed, SCENARIO_STREAM))
        return functools.partial(_rows_chunk, engine=engines[0], mc=mc, seed=int(seed),
                                 stream=SCENARIO_STREAM)

    if store is None:
        rows = _run_chunks(list(range(int(n_scenarios))), chunk_rows(), client, chunk_size,
                           progress, "scenario bank")
    else:
        rows, note = build_into_store(store, make_chunk_fn=lambda: chunk_task(chunk_rows()),
                                      theta=theta, areas=areas, n_scenarios=n_scenarios,
                                      chunk_size=chunk_size, config=config, seed=seed,
                                      attrs=attrs, client=client, progress=progress)
        attrs.update(note)
    if engines:
        attrs["budget"] = [float(x) for x in engines[0].budget]
    attrs["build_s"] = time.perf_counter() - t0
    return ScenarioBank(theta=theta, rows=rows, areas=areas, attrs=attrs)


#: Samples per chunk task of the validation and held-out flights.
VALIDATION_CHUNK = 8


def fly_members(setup: FlybySetup, theta, periods, mc, *, seed: int, n_samples: int,
                client=None, progress: bool = True, first: int = 0,
                stream: int = VALIDATION_STREAM) -> np.ndarray:
    """(M, N, V) bool: per-member rows of swarm ``theta`` (rad) in ``n_samples`` fresh draws
    of the continuous dispersions (no failures), stream ``VALIDATION_STREAM`` (or
    ``stream``: the held-out scenarios' ``HOLDOUT_STREAM``), samples ``first`` to
    ``first + n_samples - 1`` (a validation look's own draws, issue 29)."""
    th = np.asarray(theta, dtype=np.float64).ravel()
    if periods is not None:
        raise NotImplementedError("fly_members: FoV sweeping periods are not supported yet")
    fn = functools.partial(_rows_chunk, engine=row_engine(setup, th, mc, seed, int(stream)),
                           mc=mc, seed=int(seed), stream=int(stream))
    return _run_chunks(list(range(int(first), int(first) + int(n_samples))), fn, client,
                       VALIDATION_CHUNK, progress, _flights_label(stream))


def flight_areas(setup: FlybySetup, *, seed: int, n_samples: int, first: int = 0,
                 stream: int = VALIDATION_STREAM, requirement=None) -> np.ndarray:
    """Vertex areas (m^2) of the flights :func:`fly_members` (same arguments) flies:
    ``(V,)`` of the body without a target prior, else ``(M, V)``, row ``m`` sample
    ``first + m``'s world of ``stream``; with a ``requirement``, its reference area in
    each world (:func:`~ideas_hpc.flyby.target_world.world_areas`)."""
    return world_areas(setup, seed, stream, range(int(first), int(first) + int(n_samples)),
                       requirement)


def _flights_label(stream: int) -> str:
    return "held-out flights" if int(stream) == HOLDOUT_STREAM else "validation flights"


def _seen_chunk(ks, *, engine: RowEngine, mc, seed, stream):
    """(len(ks), K, V) int32 of each flight: the first image at which a member sees a vertex
    of its row, ``UNTIMED`` for one of its row without a first image (never on one flight;
    counted as seen only at the end), -1 outside its row."""
    setup = engine.setup
    out = None
    for i, k in enumerate(ks):
        pert = Perturbation(**draw_world(mc, setup, engine.theta, seed, stream, int(k)))
        world = scenario_world(setup, seed, stream, int(k), pert.params_override)
        r_img, dcm = engine.flight(pert, True, world)
        rows = engine.rows(r_img, dcm, world=world)
        first = engine.first_seen(r_img, dcm, world)
        row = np.where(rows, np.where(first >= 0, first, UNTIMED), -1).astype(np.int32)
        out = _rows_out(out, len(ks), row)
        out[i] = row
    return out


#: :func:`fly_members_seen`'s mark of a vertex in a member's row without a first image.
UNTIMED = -2


def fly_members_seen(setup: FlybySetup, theta, mc, *, seed: int, n_samples: int,
                     client=None, progress: bool = True, first: int = 0,
                     stream: int = VALIDATION_STREAM):
    """:func:`fly_members` with, per member and vertex, when in the pass it is first seen:
    returns ``rows`` (M, N, V) bool and ``seen`` (M, N, V) float32, the pass fraction
    ``(t - t0) / (tf - t0)`` of that first image (``inf``: not seen). Seen mode only (a
    ``[coverage]`` requirement maps, and when a vertex is mapped is not its first sight):
    what a member lost in the pass imaged before its loss (issue 41)."""
    th = np.asarray(theta, dtype=np.float64).ravel()
    fn = functools.partial(_seen_chunk, engine=row_engine(setup, th, mc, seed, int(stream)),
                           mc=mc, seed=int(seed), stream=int(stream))
    idx = _run_chunks(list(range(int(first), int(first) + int(n_samples))), fn, client,
                      VALIDATION_CHUNK, progress, _flights_label(stream))
    frac = ((setup.image_times - setup.t0_s) / (setup.tf_s - setup.t0_s)).astype(np.float32)
    frac = np.concatenate([frac, [np.inf]]).astype(np.float32)
    seen = frac[np.where(idx >= 0, idx, frac.size - 1)]
    return idx != -1, seen
