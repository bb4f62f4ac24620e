"""The scenario bank of the reliability designer, and the validation flights (issue 20).

A *scenario* is one draw of the continuous ``[monte_carlo]`` dispersions for
the whole candidate grid:

* the body-level ones (gravity ``mu``, ``C20``, ``C22``; SRP reflectivity) are
  drawn once and shared by every candidate;
* the per-spacecraft ones (initial position and velocity errors, camera
  misalignment and, with ``attitude.mode = "simulated"``, the initial attitude,
  rates and wheel speeds) are drawn independently for every candidate.

Failures are not drawn: the designer handles them exactly. Every candidate is
targeted once on the nominal model and flown open loop through each scenario
(:func:`ideas_hpc.flyby.flight.open_loop_views`); its row is what it sees, or with a
``[coverage]`` requirement what it maps (:func:`ideas_hpc.design.candidates.rows_from_views`).
Members fly independently, so a swarm's coverage in scenario ``s`` is the union
of its members' rows ``rows[s, members]``.

Streams: :mod:`ideas_hpc.seeds` (``SCENARIO_STREAM`` for the bank,
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
from ideas_hpc.flyby.flight import FlybySetup, Perturbation, endpoints, target
from ideas_hpc.seeds import (SCENARIO_STREAM, STREAM_ATTITUDE, STREAM_BODY, STREAM_SPACECRAFT,
                     VALIDATION_STREAM, stream_rng)
from ideas_hpc.montecarlo.dispersions import DISPERSIONS, attitude_draw, attitude_perturbation
from ideas_hpc.montecarlo.scenario_rows import RowEngine
from ideas_hpc.montecarlo.scenario_store import build_into_store, chunk_task

TWO_PI = 2.0 * math.pi
#: Dispersions drawn once per scenario and shared by all spacecraft.
BODY_LEVEL = ("gravity", "reflectivity")
#: Dispersions drawn independently for every spacecraft (attitude has its own stream).
PER_SPACECRAFT = ("initial_state", "misalignment")
#: Not drawn: failures are exact in the designer; the attitude is drawn below.
NOT_DRAWN = ("failures", "attitude")
_unclassified = {d.name for d in DISPERSIONS} - set(BODY_LEVEL + PER_SPACECRAFT + NOT_DRAWN)
assert not _unclassified, f"classify dispersions {_unclassified} in scenarios.py"


@dataclass(frozen=True)
class ScenarioBank:
    """Per-scenario candidate rows (module docstring).

    Attributes
    ----------
    theta : (C,) rad
        The design grid, ``theta_k = k 2 pi / C``.
    rows : (S, C, V) bool
        Vertex ``v`` seen (or mapped) by candidate ``c`` in scenario ``s``.
    areas : (V,) m^2
        Vertex areas.
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

    Body-level dispersions from purpose ``STREAM_BODY``, per-spacecraft ones
    from ``STREAM_SPACECRAFT`` (each in :data:`~ideas_hpc.montecarlo.dispersions.DISPERSIONS`
    order, ``n = theta.size`` rows), the initial attitude (simulated attitude
    only) from ``STREAM_ATTITUDE`` with the laws of ``monte_carlo.attitude_start``
    (:func:`~ideas_hpc.montecarlo.dispersions.attitude_draw`; on the reference
    flown when ``monte_carlo.attitude_dispersion`` is off). No failures.
    """
    n = theta.size
    body = stream_rng(seed, stream, k, STREAM_BODY)
    per_sc = stream_rng(seed, stream, k, STREAM_SPACECRAFT)
    pert: dict = {}
    for d in DISPERSIONS:
        if d.name in NOT_DRAWN:
            continue
        v = d.draw(body if d.name in BODY_LEVEL else per_sc, n, mc, setup, theta)
        for key, val in d.perturb(v).items():
            if isinstance(val, dict):
                pert.setdefault(key, {}).update(val)
            else:
                pert[key] = val
    if setup.attitude_mode == "simulated":
        v = attitude_draw(stream_rng(seed, stream, k, STREAM_ATTITUDE), n, mc)
        pert.update(attitude_perturbation(mc, v))
    return pert


def _rows_chunk(ks, *, engine: RowEngine, mc, seed, stream):
    setup = engine.setup
    out = np.empty((len(ks), engine.theta.size, setup.body.shape.n_vertices), dtype=bool)
    for i, k in enumerate(ks):
        pert = Perturbation(**draw_world(mc, setup, engine.theta, seed, stream, int(k)))
        out[i] = engine.rows(*engine.flight(pert))
    return out


def row_engine(setup: FlybySetup, theta, mc, seed: int, stream: int) -> RowEngine:
    """Targeted candidates ``theta`` with their nominal witnesses; budget from draw 0."""
    r0, v0 = nominal_start(setup, theta)
    pilot = Perturbation(**draw_world(mc, setup, theta, seed, stream, 0))
    return RowEngine(setup, theta, r0, v0).prepare(pilot)


def _apply(part, fn):
    return fn(part)


def _run_chunks(ks, fn, client, chunk_size, progress, label):
    parts = [ks[i:i + chunk_size] for i in range(0, len(ks), chunk_size)]
    bar = None
    if progress:
        import sys

        from tqdm.auto import tqdm
        bar = tqdm(total=len(ks), desc=label, unit="scenario", file=sys.stderr, leave=False)
    out = []
    if client is None:
        for p in parts:
            out.append(fn(p))
            if bar is not None:
                bar.update(len(p))
    else:
        from distributed import as_completed
        # the row engine once per worker (see engine.runner._submit_all)
        fn_f = client.scatter(fn, broadcast=True, hash=False)
        futures = client.map(_apply, parts, fn=fn_f, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        res = [None] * len(parts)
        for f in as_completed(futures):
            res[index[f.key]] = f.result()
            if bar is not None:
                bar.update(len(parts[index[f.key]]))
        out = res
    if bar is not None:
        bar.close()
    return np.concatenate(out) if out else None


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
    skip = {"samples", "failure_probability", "failures_k"}
    mc_d = {f.name: getattr(mc, f.name) for f in dataclasses.fields(mc) if f.name not in skip}
    sh = setup.body.shape
    fs = {f.name: repr(getattr(setup, f.name)) for f in dataclasses.fields(setup)
          if f.name not in ("body", "seed", "decimate")}
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
    areas = np.asarray(setup.body.shape.vertex_areas, dtype=np.float64)
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


def fly_members(setup: FlybySetup, theta, periods, mc, *, seed: int, n_samples: int,
                client=None, progress: bool = True, chunk_size: int = 8) -> np.ndarray:
    """(M, N, V) bool: per-member rows of swarm ``theta`` (rad) in ``n_samples`` fresh draws
    of the continuous dispersions (no failures), stream ``VALIDATION_STREAM``."""
    th = np.asarray(theta, dtype=np.float64).ravel()
    if periods is not None:
        raise NotImplementedError("fly_members: FoV sweeping periods are not supported yet")
    fn = functools.partial(_rows_chunk, engine=row_engine(setup, th, mc, seed, VALIDATION_STREAM),
                           mc=mc, seed=int(seed), stream=VALIDATION_STREAM)
    return _run_chunks(list(range(int(n_samples))), fn, client, chunk_size, progress,
                       "validation flights")
