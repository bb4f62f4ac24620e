"""Benchmark: the main job's scenario bank, per scenario (issues 20, 31).

Workload: the bank of ``campaigns/eros-design.toml`` (eros001708 when the data
is on IDEAS_HPC_DATA, else the built-in ellipsoid): strict visibility (exact
culling, occlusion, 5 deg elevation), 0.5 deg grid = 720 candidates, the
``[monte_carlo]`` dispersions (gravity, SRP, initial state, misalignment) and
the closed-loop attitude started on its reference with knowledge and control
errors, only sharp and settled images counted (``--ideal``: ideal attitude).

Three paths on the same scenarios, in the same run, interleaved scenario by
scenario so that the machine's load falls alike on each; their rows must be
identical:

* **full recomputation**: the flyby pipeline flies the scenario and every row
  comes from :func:`ideas_hpc.design.candidates.rows_from_views`
  (:func:`ideas_hpc.montecarlo.scenario_rows.full_rows`);
* **fast rows (pipeline flight)**: the pipeline's flight, then the same rows
  from the witness proofs
  (:class:`~ideas_hpc.montecarlo.scenario_rows.RowEngine` with ``one_pass = False``);
* **bank**: what the bank does now: the one flight path
  (:func:`ideas_hpc.flyby.views.flight_views`), which flies the one-pass closed loop
  (:mod:`ideas_hpc.flyby.closed_loop`) into reused buffers, then the same fast rows.

The engine's one-time preparation (targeting, proofs) is reported and amortised
over 256 scenarios. The script runs as a bank worker does: one Numba thread and
the workers' malloc settings (``WORKER_MALLOC_ENV``), which keep each scenario's
large arrays on the heap; it re-executes itself with them when they are not
set. Without them the paths that allocate fresh 52-155 MB arrays per scenario
(the former bank) pay page faults no worker pays: 1.40 against 1.03 s per
scenario for 01c8c61's bank, so the ratio came out 4.0x where the bank's own
is about 3x. Times are wall-clock (``cpu``: the process's CPU time, less
sensitive to a shared machine's load).

``--scaling``: the bank's cost per scenario against the number of candidates
(180 / 360 / 720 on eros001708) and of vertices (eros001708 / eros007790 /
eros022540 at 180 candidates; the models' 856 / 3897 / 11272 vertices), with the
power-law exponents fitted to each (needs the Eros models on IDEAS_HPC_DATA; a few
minutes).

``--against REV``: then the main job's whole bank (256 scenarios on two local
workers, preparation and read-back included), built by git revision ``REV`` and by
this checkout in the same run, rows compared bit for bit
(:mod:`whole_bank`); the headline is that ratio. Issue 31's reference is
``--against 01c8c61``, the bank before it.

``--world-bank``: the world bank instead (issue 43, :mod:`world_bank`): every scenario a
drawn world of ``campaigns/eros-class-flyby.toml``, the world bank against full
recomputation of the same worlds in the same run (``--worlds``, 720 candidates at the
default step), rows compared; with ``--scaling`` its exponents in candidates, vertices
and images per candidate. Headline last: ``scenarios: <R>x faster than full
recomputation`` (CPU seconds per scenario).

Usage: ``python benchmarks/bench_scenarios.py [--scenarios 3] [--ideal] [--step 0.5]
[--scaling] [--against REV [--bank-scenarios 256] [--workers 2]]``, or
``python benchmarks/bench_scenarios.py --world-bank [--worlds 6] [--step 0.5] [--scaling]``
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from ideas_hpc.body.datapath import have_data_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.flyby.flight import Perturbation
from ideas_hpc.montecarlo.scenario_rows import full_rows
from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, row_engine
from ideas_hpc.base.seeds import SCENARIO_STREAM

ROOT = Path(__file__).resolve().parent.parent
AMORTISE = 256
SCALING_STEPS_DEG = (2.0, 1.0, 0.5)           # 180 / 360 / 720 candidates
SCALING_BODIES = ("eros001708", "eros007790", "eros022540")


class Clock:
    """Wall and CPU seconds of one path, summed over scenarios."""

    def __init__(self):
        self.wall = 0.0
        self.cpu = 0.0

    def __call__(self, fn, *args):
        w, c = time.perf_counter(), time.process_time()
        out = fn(*args)
        self.wall += time.perf_counter() - w
        self.cpu += time.process_time() - c
        return out


def _campaign(sets):
    c = load(ROOT / "campaigns" / "eros-design.toml", sets)
    return c, setup_from_campaign(c), c.config.monte_carlo


def _pert(c, setup, mc, theta, s):
    return Perturbation(**draw_world(mc, setup, theta, c.config.seed, SCENARIO_STREAM, s))


def _bank_rows(eng, pert):
    eng.one_pass = True
    return eng.rows(*eng.flight(pert, reuse=True))


def _old_rows(eng, pert):
    eng.one_pass = False
    try:
        return eng.rows(*eng.flight(pert))
    finally:
        eng.one_pass = True


def compare(sets, step_deg: float, n_scenarios: int) -> None:
    """The three paths on scenarios 1..n (module docstring); prints the table."""
    c, setup, mc = _campaign(sets)
    theta = grid_theta(np.deg2rad(step_deg))
    t0 = time.perf_counter()
    eng = row_engine(setup, theta, mc, c.config.seed, SCENARIO_STREAM)
    t_prep = time.perf_counter() - t0
    p0 = _pert(c, setup, mc, theta, 0)          # warm (compile) every path, untimed
    _bank_rows(eng, p0)
    _old_rows(eng, p0)
    new, old, full = Clock(), Clock(), Clock()
    for s in range(1, n_scenarios + 1):
        pert = _pert(c, setup, mc, theta, s)
        a = new(_bank_rows, eng, pert)
        b = old(_old_rows, eng, pert)
        f = full(full_rows, setup, theta, None, eng.r0_T, eng.v0_T, pert)
        for name, other in (("full recomputation", f), ("the fast rows of the pipeline's "
                                                        "flight", b)):
            if not np.array_equal(a, other):
                raise SystemExit(f"scenario {s}: the bank's rows differ from {name} in "
                                 f"{int((a != other).sum())} places")
    ns = n_scenarios
    att = {"simulated": "closed-loop attitude"}.get(setup.attitude_mode, "ideal attitude")
    print(f"{setup.body.shape.name}, strict, {theta.size} candidates, {att}, {ns} scenarios "
          f"(ratios are from the same run)")
    print(f"  one-time preparation (targeting, proofs: windows, witnesses): {t_prep:7.2f} s "
          f"(budget {eng.budget[0]:.3g} Frobenius, {eng.budget[1]:.3g} m)")
    amort = t_prep / AMORTISE
    for name, ck in (("full recomputation", full), ("fast rows, pipeline flight", old),
                     ("bank (one-pass flight, fast rows)", new)):
        print(f"  {name:36s} {ck.wall / ns:7.3f} s/scenario wall ({ck.cpu / ns:6.3f} cpu)")
    per_new = new.wall / ns + amort
    per_old = old.wall / ns + amort
    print(f"  identical rows on all {ns} scenarios; preparation / {AMORTISE} added to both "
          f"fast paths: bank {per_new:.3f} s, before {per_old:.3f} s "
          f"(cpu ratio {old.cpu / new.cpu:.2f}x)")
    print(f"  against full recomputation: {full.wall / ns / per_new:.1f}x")
    print(f"scenarios: {per_old / per_new:.1f}x faster than the pipeline's flight with the "
          "same fast rows")


def _cost(body: str, step_deg: float, n_scenarios: int) -> tuple:
    """``(candidates, vertices, wall s/scenario, preparation s, cpu s/scenario)`` of the
    bank's path."""
    c, setup, mc = _campaign([f'body.name="{body}"'])
    theta = grid_theta(np.deg2rad(step_deg))
    t0 = time.perf_counter()
    eng = row_engine(setup, theta, mc, c.config.seed, SCENARIO_STREAM)
    t_prep = time.perf_counter() - t0
    _bank_rows(eng, _pert(c, setup, mc, theta, 0))
    ck = Clock()
    for s in range(1, n_scenarios + 1):
        ck(_bank_rows, eng, _pert(c, setup, mc, theta, s))
    return theta.size, setup.body.shape.n_vertices, ck.wall / n_scenarios, t_prep, \
        ck.cpu / n_scenarios


def _exponent(x, y) -> float:
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def scaling(n_scenarios: int) -> None:
    """Cost per scenario against candidates and vertices, with fitted exponents."""
    if not all(have_data_file(f"{b}.tab") for b in SCALING_BODIES):
        print("scaling: needs eros001708/007790/022540 on IDEAS_HPC_DATA: not measured")
        return
    print(f"scaling (bank path, {n_scenarios} scenarios each; cpu: the process's CPU "
          "seconds, what the fits use, as wall time on a shared machine is the load's):")
    rows = [_cost(SCALING_BODIES[0], st, n_scenarios) for st in SCALING_STEPS_DEG]
    for k, v, t, p, cpu in rows:
        print(f"  {SCALING_BODIES[0]} {k:4d} candidates: {cpu:7.3f} s/scenario cpu "
              f"({t:6.3f} wall), preparation {p:6.1f} s wall")
    e_c = _exponent([r[0] for r in rows], [r[4] for r in rows])
    e_cp = _exponent([r[0] for r in rows], [r[3] for r in rows])
    rows_v = [rows[0]] + [_cost(b, SCALING_STEPS_DEG[0], n_scenarios)
                          for b in SCALING_BODIES[1:]]
    for b, (k, v, t, p, cpu) in zip(SCALING_BODIES, rows_v):
        print(f"  {b} {v:6d} vertices, {k} candidates: {cpu:7.3f} s/scenario cpu "
              f"({t:6.3f} wall), preparation {p:6.1f} s wall")
    e_v = _exponent([r[1] for r in rows_v], [r[4] for r in rows_v])
    e_vp = _exponent([r[1] for r in rows_v], [r[3] for r in rows_v])
    print(f"  fitted: cost/scenario ~ candidates^{e_c:.2f} x vertices^{e_v:.2f} (cpu); "
          f"preparation ~ candidates^{e_cp:.2f} x vertices^{e_vp:.2f} (wall)")


def _as_a_bank_worker() -> None:
    """Re-execute with a bank worker's environment unless it is set (module docstring):
    glibc reads its malloc settings and Numba its thread count when the process starts."""
    from ideas_hpc.engine.cluster import WORKER_MALLOC_ENV

    want = {**WORKER_MALLOC_ENV, "NUMBA_NUM_THREADS": "1"}
    if any(os.environ.get(k) != v for k, v in want.items()):
        sys.stdout.flush()
        os.execve(sys.executable, [sys.executable, *sys.argv], {**os.environ, **want})


def main(argv=None) -> None:
    if argv is None:
        _as_a_bank_worker()
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenarios", type=int, default=3)
    ap.add_argument("--ideal", action="store_true",
                    help="fly ideal attitude (the campaign flies the closed loop)")
    ap.add_argument("--step", type=float, default=0.5, help="grid step, deg")
    ap.add_argument("--scaling", action="store_true",
                    help="also the cost against candidates and vertices (a few minutes)")
    ap.add_argument("--scaling-scenarios", type=int, default=2)
    ap.add_argument("--against", metavar="REV",
                    help="also the main job's whole bank, built by REV and by this checkout "
                         "(whole_bank.py; eros001708 needed; headline last)")
    ap.add_argument("--bank-scenarios", type=int, default=256)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--world-bank", action="store_true",
                    help="the world bank (a drawn world per scenario) against full "
                         "recomputation of the same worlds (world_bank.py; headline last)")
    ap.add_argument("--worlds", type=int, default=6, help="worlds of --world-bank")
    args = ap.parse_args(argv)
    if args.world_bank:
        import world_bank
        if args.scaling:
            world_bank.scaling(args.scaling_scenarios)
        ratio = world_bank.compare(args.worlds, args.step)
        print(f"scenarios: {ratio:.1f}x faster than full recomputation")
        return
    sets = [] if have_data_file("eros001708.tab") else ['body.name="ellipsoid"']
    if args.ideal:
        sets.append('attitude.mode="ideal"')
    if args.scaling:
        scaling(args.scaling_scenarios)
    compare(sets, args.step, args.scenarios)
    if args.against:
        if not have_data_file("eros001708.tab"):
            print("whole bank: needs eros001708 on IDEAS_HPC_DATA: not measured")
            return
        from whole_bank import against
        against(args.against, args.bank_scenarios, args.workers)


if __name__ == "__main__":
    main()
