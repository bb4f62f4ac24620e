"""The world bank against full recomputation of the same worlds (issue 43; run by
``bench_scenarios.py --world-bank``).

Workload: the bank of ``campaigns/eros-class-flyby.toml``, where every scenario is a
world of the built-in Eros-class prior (its own shape, pole and phase), flown at
10 km/s with the Lutetia navigation errors, body tracking toward the predicted target
and a visual map (only lit terrain counts); 0.5 deg grid = 720 candidates (``--step``).

Two paths on the same worlds, in the same run, interleaved world by world (the world
bank first, so that what both share, the drawn mesh and its BVH, is charged to it):

* **full recomputation** (the bank before issue 43): draw the world, fly every
  candidate through it (the one flight path), and the rows from the quality pass over
  every observation (:func:`ideas_hpc.montecarlo.scenario_rows.full_rows_of`);
* **world bank**: the same draw and flight, the world's statics once (mesh record,
  BVH, lighting at every image, clear cones:
  :func:`~ideas_hpc.montecarlo.scenario_rows.world_statics_of`), then each candidate's
  first usable image (:func:`~ideas_hpc.montecarlo.scenario_rows.world_rows`).

Rows are compared bit for bit on every world. The headline is the ratio of the two
per-scenario times (CPU seconds of the process, which a shared machine's load changes
less than the wall clock; both are printed), with the world bank's phases per
scenario. ``--scaling`` adds the world bank's cost per scenario against the number of
candidates (180 / 360 / 720), of vertices (icosphere resolution 3 / 4 / 5: 642 / 2562 /
10242; the prior's degree 11 needs 3 or finer) and of images per candidate (image rate 2.5 / 5 / 10 Hz: 51 / 101 / 201), with
power-law exponents fitted to the CPU times.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from ideas_hpc.base.seeds import SCENARIO_STREAM
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.flyby.flight import Perturbation
from ideas_hpc.flyby.target_world import scenario_world
from ideas_hpc.montecarlo.scenario_rows import full_rows_of, world_rows, world_statics_of
from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, row_engine

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-class-flyby.toml"
PHASES = ("draw and place the world", "flight", "world statics", "rows")
SCALING = {"candidates": ("step", (2.0, 1.0, 0.5)),
           "vertices": ("body.resolution", (3, 4, 5)),
           "images per candidate": ("instrument.image_rate_hz", (2.5, 5.0, 10.0))}


def _now() -> np.ndarray:
    return np.array([time.perf_counter(), time.process_time()])


class Case:
    """One campaign's setup, grid and engine."""

    def __init__(self, sets=(), step_deg: float = 0.5):
        c = load(CAMPAIGN, list(sets))
        self.seed = int(c.config.seed)
        self.mc = c.config.monte_carlo
        self.setup = setup_from_campaign(c)
        self.theta = grid_theta(np.deg2rad(step_deg))
        self.engine = row_engine(self.setup, self.theta, self.mc, self.seed, SCENARIO_STREAM)

    def world(self, s: int):
        pert = Perturbation(**draw_world(self.mc, self.setup, self.theta, self.seed,
                                         SCENARIO_STREAM, s))
        return pert, scenario_world(self.setup, self.seed, SCENARIO_STREAM, s,
                                    pert.params_override)

    def world_bank(self, s: int):
        """``(rows, (4, 2) wall and cpu seconds of each phase)`` of world ``s``."""
        t = [_now()]
        pert, world = self.world(s)
        t.append(_now())
        r, d = self.engine.flight(pert, True, world)
        t.append(_now())
        world_statics_of(self.setup, world, r.shape[1])
        t.append(_now())
        rows = world_rows(self.setup, world, r, d)
        t.append(_now())
        return rows, np.diff(np.array(t), axis=0)

    def full(self, s: int):
        """``(rows, (2,) wall and cpu seconds)`` of world ``s`` by full recomputation."""
        t0 = _now()
        pert, world = self.world(s)
        r, d = self.engine.flight(pert, True, world)
        rows = full_rows_of(self.setup, world, r, d)
        return rows, _now() - t0


def compare(n_worlds: int, step_deg: float) -> float:
    """Both paths on worlds 1..n (world 0 warms them, untimed); prints the table and
    returns the CPU ratio."""
    case = Case(step_deg=step_deg)
    case.world_bank(0)
    case.full(0)
    bank = np.zeros((len(PHASES), 2))
    full = np.zeros(2)
    for s in range(1, n_worlds + 1):
        a, dt = case.world_bank(s)
        b, df = case.full(s)
        if not np.array_equal(a, b):
            raise SystemExit(f"world {s}: the world bank's rows differ from full "
                             f"recomputation in {int((a != b).sum())} places")
        bank += dt
        full += df
    n = n_worlds
    st = case.setup
    print(f"world bank: {CAMPAIGN.name}, {st.body.shape.n_vertices} vertices, "
          f"{case.theta.size} candidates, {st.image_times.size} images each, {n} worlds "
          f"(one per scenario; load average {os.getloadavg()[0]:.1f} at the end)")
    print(f"  rows identical to full recomputation on all {n} worlds")
    print(f"  {'full recomputation':36s} {full[0] / n:7.3f} s/scenario wall "
          f"({full[1] / n:6.3f} cpu)")
    tot = bank.sum(axis=0)
    print(f"  {'world bank':36s} {tot[0] / n:7.3f} s/scenario wall ({tot[1] / n:6.3f} cpu)")
    for name, (w, c) in zip(PHASES, bank):
        print(f"    {name:34s} {w / n:7.3f} s wall ({c / n:6.3f} cpu, {c / tot[1]:4.0%})")
    print(f"  scenarios per second (cpu): full {n / full[1]:.2f}, world bank {n / tot[1]:.2f}; "
          f"wall ratio {full[0] / tot[0]:.1f}x")
    return float(full[1] / tot[1])


def _exponent(x, y) -> float:
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def scaling(n_worlds: int) -> None:
    """The world bank's CPU seconds per scenario against candidates, vertices and images
    (module docstring), with fitted exponents."""
    print(f"world bank scaling ({n_worlds} worlds each, cpu s/scenario; base: 180 "
          "candidates, 642 vertices, 101 images):")
    for what, (key, values) in SCALING.items():
        xs, ys = [], []
        for v in values:
            if key == "step":
                case = Case(step_deg=v)
            else:
                case = Case([f"{key}={v}"], step_deg=2.0)
            case.world_bank(0)
            cpu = sum(case.world_bank(s)[1].sum(axis=0)[1] for s in range(1, n_worlds + 1))
            x = {"candidates": case.theta.size,
                 "vertices": case.setup.body.shape.n_vertices,
                 "images per candidate": case.setup.image_times.size}[what]
            xs.append(x)
            ys.append(cpu / n_worlds)
            print(f"  {what:22s} {x:6d}: {ys[-1]:7.3f} s")
        print(f"  fitted: cost ~ {what}^{_exponent(xs, ys):.2f}")
