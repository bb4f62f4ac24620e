"""Benchmark: scenario rows of the reliability designer's bank (issue 20).

Workload: the main job's grid (eros001708 when the data is on IDEAS_HPC_DATA,
else the built-in ellipsoid), strict visibility (exact culling, occlusion, 5 deg
elevation), 0.5 deg grid = 720 candidates, the ``[monte_carlo]`` dispersions of
``campaigns/eros-design.toml`` (gravity, SRP, initial state, misalignment);
the closed-loop attitude from dispersed initial attitudes, as the main job
(``--ideal``: ideal attitude).

Baseline: full recomputation with the flyby pipeline, what the bank would do
without the shortcuts: each scenario's perturbed flight (open-loop propagation
of every candidate, camera attitude and misalignment) and every candidate's row
from :func:`ideas_hpc.design.candidates.rows_from_views`
(:func:`ideas_hpc.montecarlo.scenario_rows.full_rows`). Fast path: the same
flight, rows by :class:`~ideas_hpc.montecarlo.scenario_rows.RowEngine`
(witness proofs, budget windows with occlusion proofs,
:mod:`ideas_hpc.core.mapping.scenario_proofs`). Both are timed on the same
scenarios in the same run and their rows must be identical; the rows alone
(the pipeline's rows of the same flight against the fast rows) are printed
too, and so is the floor the flight sets (both paths fly it). The engine's
one-time preparation is reported and amortised over 256 scenarios in the
headline.

Usage: ``python benchmarks/bench_scenarios.py [--scenarios 3] [--ideal] [--step 0.5]``
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.body.datapath import have_data_file
from ideas_hpc.flyby.flight import Perturbation
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.montecarlo.scenario_rows import full_rows
from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, row_engine
from ideas_hpc.seeds import SCENARIO_STREAM

ROOT = Path(__file__).resolve().parent.parent
AMORTISE = 256


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenarios", type=int, default=3)
    ap.add_argument("--ideal", action="store_true",
                    help="fly ideal attitude (the campaign flies the closed loop)")
    ap.add_argument("--step", type=float, default=0.5, help="grid step, deg")
    args = ap.parse_args(argv)
    sets = [] if have_data_file("eros001708.tab") else ['body.name="ellipsoid"']
    if args.ideal:
        sets.append('attitude.mode="ideal"')
    c = load(ROOT / "campaigns" / "eros-design.toml", sets)
    setup = setup_from_campaign(c)
    mc = c.config.monte_carlo
    theta = grid_theta(np.deg2rad(args.step))
    t0 = time.perf_counter()
    eng = row_engine(setup, theta, mc, c.config.seed, SCENARIO_STREAM)
    t_prep = time.perf_counter() - t0
    # warm: compile both paths on scenario 0 (not timed)
    p0 = Perturbation(**draw_world(mc, setup, theta, c.config.seed, SCENARIO_STREAM, 0))
    eng.rows(*eng.flight(p0))
    t_flight = t_fast = t_rows = t_full = 0.0
    n_rows = 0
    for s in range(1, args.scenarios + 1):
        pert = Perturbation(**draw_world(mc, setup, theta, c.config.seed, SCENARIO_STREAM, s))
        t0 = time.perf_counter()
        view = eng.flight(pert)
        t1 = time.perf_counter()
        fast = eng.rows(*view)
        t2 = time.perf_counter()
        full = full_rows(setup, theta, None, eng.r0_T, eng.v0_T, pert)
        t3 = time.perf_counter()
        rows = eng._full(*view)              # the pipeline's rows of the same flight
        t4 = time.perf_counter()
        for name, other in (("full recomputation", full), ("the pipeline's rows", rows)):
            if not np.array_equal(fast, other):
                raise SystemExit(f"scenario {s}: rows differ from {name} in "
                                 f"{int((fast != other).sum())} places")
        t_flight += t1 - t0
        t_fast += t2 - t1
        t_full += t3 - t2
        t_rows += t4 - t3
        n_rows += theta.size
    ns = args.scenarios
    att = {"simulated": "closed-loop attitude"}.get(setup.attitude_mode, "ideal attitude")
    print(f"{setup.body.shape.name}, strict, {theta.size} candidates, {att}, {ns} scenarios "
          f"(ratios are from the same run)")
    print(f"  one-time preparation (targeting, proofs: windows, witnesses): {t_prep:7.2f} s "
          f"(budget {eng.budget[0]:.3g} Frobenius, {eng.budget[1]:.3g} m)")
    print(f"  full recomputation (flight + rows):  {t_full / ns:7.3f} s/scenario  "
          f"{n_rows / t_full:9.0f} rows/s")
    print(f"  perturbed flight (both paths):       {t_flight / ns:7.3f} s/scenario")
    print(f"  the pipeline's rows of the flight:   {t_rows / ns:7.3f} s/scenario")
    print(f"  fast rows of the flight:             {t_fast / ns:7.3f} s/scenario  "
          f"({t_rows / t_fast:.1f}x the pipeline's rows alone)")
    per = (t_flight + t_fast) / ns + t_prep / AMORTISE
    print(f"  fast scenario (flight + rows + preparation / {AMORTISE}): {per:7.3f} s  "
          f"{theta.size / per:9.0f} rows/s; identical rows")
    print(f"  floor: the flight alone would be {t_full / t_flight:.1f}x")
    print(f"scenarios: {t_full / ns / per:.1f}x faster than full recomputation with the "
          "flyby pipeline")


if __name__ == "__main__":
    main()
