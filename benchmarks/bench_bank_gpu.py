"""Benchmark: the scenario bank with its closed-loop flights on the GPU against the CPU
(issue 31, deliverable 3; docs/gpu.md).

Workload: the main job's bank (``campaigns/eros-design.toml``: eros001708 when the data
is on IDEAS_HPC_DATA, else the built-in ellipsoid; 0.5 deg grid = 720 candidates;
its dispersions and closed-loop attitude). One row engine (the nominal proofs, built
once on the CPU); then per scenario the perturbed flight and its rows
(:class:`~ideas_hpc.montecarlo.scenario_rows.RowEngine` ``flight`` + ``rows``), once with
``device = "cpu"`` (Numba ``prange`` over all cores, the reference) and once with
``device = "cuda"`` (:mod:`ideas_hpc.core.attitude.batch_cuda`), in the same run on the
same scenarios. Scenario 0 is flown first on both as warm-up (compilation) and not
timed. The rows must be identical on every scenario; the largest camera-DCM
difference is printed (the GPU rounds multiply-adds as FMAs).

Prints ``bank_gpu: <R>x faster than CPU`` last, or ``not measured: no CUDA device
(<reason>)`` where there is none.

Usage: ``python benchmarks/bench_bank_gpu.py [--scenarios 4] [--step 0.5]``
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _no_device() -> str | None:
    """Why the GPU cannot be timed here, or None."""
    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
        return "the CUDA simulator is on (NUMBA_ENABLE_CUDASIM=1): its times mean nothing"
    try:
        from numba import cuda
        if not cuda.is_available():
            return "numba.cuda.is_available() is false"
        return None
    except Exception as exc:        # a broken driver install: say what it said
        return f"{type(exc).__name__}: {str(exc).splitlines()[0]}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenarios", type=int, default=4, help="timed scenarios (after warm-up)")
    ap.add_argument("--step", type=float, default=0.5, help="grid step, deg")
    args = ap.parse_args(argv)
    why = _no_device()
    if why is not None:
        print(f"not measured: no CUDA device ({why})")
        return 0
    from numba import cuda

    from ideas_hpc.body.datapath import have_data_file
    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.flyby.flight import Perturbation
    from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, row_engine
    from ideas_hpc.base.seeds import SCENARIO_STREAM

    sets = [] if have_data_file("eros001708.tab") else ['body.name="ellipsoid"']
    c = load(ROOT / "campaigns" / "eros-design.toml", sets)
    setup = setup_from_campaign(c)
    mc, seed = c.config.monte_carlo, c.config.seed
    theta = grid_theta(np.deg2rad(args.step))
    name = getattr(cuda.get_current_device(), "name", "?") \
        if hasattr(cuda, "get_current_device") else "simulator"
    print(f"device: {name.decode() if isinstance(name, bytes) else name}; "
          f"body {setup.body.name}, {theta.size} candidates, "
          f"{int(round((setup.tf_s - setup.t0_s) / setup.dt_s))} attitude steps, "
          f"attitude {setup.attitude_mode}, CPU threads {os.cpu_count()}")
    t0 = time.perf_counter()
    cpu = row_engine(setup, theta, mc, seed, SCENARIO_STREAM)
    print(f"row engine (once, CPU): {time.perf_counter() - t0:.1f} s")
    # same nominal proofs and budget (same token): only the flights' device differs
    gpu = replace(cpu, setup=setup.with_(device="cuda"))

    def one(engine, k):
        pert = Perturbation(**draw_world(mc, setup, theta, seed, SCENARIO_STREAM, k))
        t = time.perf_counter()
        r_img, dcm = engine.flight(pert)
        t_fly = time.perf_counter() - t
        rows = engine.rows(r_img, dcm)
        return rows, dcm, t_fly, time.perf_counter() - t

    for engine in (cpu, gpu):       # warm-up: compile / load caches
        one(engine, 0)
    t_cpu = t_gpu = f_cpu = f_gpu = 0.0
    same, dmax = 0, 0.0
    for k in range(1, args.scenarios + 1):
        rc, dc, fc, tc = one(cpu, k)
        rg, dg, fg, tg = one(gpu, k)
        t_cpu, t_gpu, f_cpu, f_gpu = t_cpu + tc, t_gpu + tg, f_cpu + fc, f_gpu + fg
        same += int(np.array_equal(rc, rg))
        dmax = max(dmax, float(np.max(np.abs(dc - dg))))
        print(f"scenario {k}: CPU {tc:.3f} s (flight {fc:.3f}), GPU {tg:.3f} s "
              f"(flight {fg:.3f}), rows identical: {np.array_equal(rc, rg)}")
    n = args.scenarios
    print(f"per scenario: CPU {t_cpu / n:.3f} s, GPU {t_gpu / n:.3f} s; flight alone: "
          f"CPU {f_cpu / n:.3f} s, GPU {f_gpu / n:.3f} s ({f_cpu / f_gpu:.2f}x)")
    print(f"rows identical on {same}/{n} scenarios; max |camera DCM difference| {dmax:.2e}")
    print(f"bank_gpu: {t_cpu / t_gpu:.2f}x faster than CPU")
    return 0 if same == n else 1


if __name__ == "__main__":
    sys.exit(main())
