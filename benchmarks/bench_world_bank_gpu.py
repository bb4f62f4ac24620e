"""Benchmark: the world bank's rows on the GPU against the CPU (issue 43, deliverable 4;
docs/gpu.md).

Workload: the world bank of ``campaigns/eros-class-flyby.toml`` (every scenario a world of
the built-in Eros-class prior: its own shape, pole and phase; body tracking, a visual map,
occlusion and a 5 deg elevation mask), 0.5 deg grid = 720 candidates (``--step``), the
prior's nominal meshed at ``body.resolution`` (``--resolution``, 3: 642 vertices). Per
world, once: the draw, the flight of every candidate and the world's statics (mesh, BVH,
lighting at every image, clear cones: :func:`ideas_hpc.mapping.world_rows.world_statics`),
on the CPU, shared by both paths. Then the mapped rows
(:func:`~ideas_hpc.mapping.world_rows.rows_of_world`) from the same statics and flight,
once with ``device = "cpu"`` (:func:`ideas_hpc.core.mapping.world_rows.mapped_by_spacecraft`,
Numba ``prange`` over all cores, the reference) and once with ``device = "cuda"``
(:mod:`ideas_hpc.core.mapping.world_rows_cuda`, one thread per row bit, the transfers
included), in the same run on the same worlds. World 0 is run first on both as warm-up
(compilation) and not timed.

The rows are compared bit for bit on every world. On a GPU, NVVM fuses multiply-adds into
FMAs, so a test whose operands sit within rounding of its boundary may decide otherwise:
the count of differing bits is printed, and the exit status is 1 when any differ.

Prints ``world_bank_gpu: <R>x faster than CPU`` last (R: the per-world visibility time,
statics plus rows, on the CPU against statics plus rows on the GPU; the rows alone on the
line before), or ``not measured: no CUDA device (<reason>)`` where there is none.

Usage: ``python benchmarks/bench_world_bank_gpu.py [--worlds 4] [--step 0.5] [--resolution 3]``
(``--simulator`` with ``NUMBA_ENABLE_CUDASIM=1``: the same steps on the simulator, for a
smoke test at tiny sizes, e.g. ``--worlds 1 --step 60``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_bank_gpu import _no_device  # noqa: E402  (the same test of a usable device)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--worlds", type=int, default=4, help="timed worlds (after warm-up)")
    ap.add_argument("--step", type=float, default=0.5, help="grid step, deg")
    ap.add_argument("--resolution", type=int, default=3, help="icosphere of the prior's nominal")
    ap.add_argument("--simulator", action="store_true",
                    help="run on the CUDA simulator anyway (NUMBA_ENABLE_CUDASIM=1): a smoke "
                    "test of this script at tiny sizes; its times mean nothing")
    args = ap.parse_args(argv)
    why = _no_device()
    if why is not None and not (args.simulator and os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"):
        print(f"not measured: no CUDA device ({why})")
        return 0
    from numba import cuda

    from ideas_hpc.base.seeds import SCENARIO_STREAM
    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.flyby.flight import Perturbation
    from ideas_hpc.flyby.target_world import scenario_world
    from ideas_hpc.mapping.world_rows import rows_of_world, world_statics
    from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, row_engine

    c = load(ROOT / "campaigns" / "eros-class-flyby.toml", [f"body.resolution={args.resolution}"])
    setup = setup_from_campaign(c)
    mc, seed = c.config.monte_carlo, c.config.seed
    theta = grid_theta(np.deg2rad(args.step))
    engine = row_engine(setup, theta, mc, seed, SCENARIO_STREAM)
    name = getattr(cuda.get_current_device(), "name", "?") \
        if hasattr(cuda, "get_current_device") else "simulator"
    frustum = (setup.eta_rad, setup.near_m, setup.far_m)

    def world(k):
        """World ``k``'s flight and statics (CPU, shared) and its statics' time."""
        pert = Perturbation(**draw_world(mc, setup, theta, seed, SCENARIO_STREAM, k))
        w = scenario_world(setup, seed, SCENARIO_STREAM, k, pert.params_override)
        r, d = engine.flight(pert, False, w)
        t = time.perf_counter()
        st = world_statics(w.shape, setup.coverage, w.sun_at_images(setup), r.shape[1])
        return r, d, st, time.perf_counter() - t

    def rows(st, r, d, device):
        t = time.perf_counter()
        out = rows_of_world(st, setup.coverage, r, d, setup.image_times, frustum, device)
        return out, time.perf_counter() - t

    r, d, st, _ = world(0)
    print(f"device: {name.decode() if isinstance(name, bytes) else name}; {theta.size} "
          f"candidates, {st.mesh.vertices_T_m.shape[0]} vertices, {r.shape[1]} images, "
          f"CPU threads {os.cpu_count()}")
    rows(st, r, d, "cpu")
    rows(st, r, d, "cuda")
    t_st = t_cpu = t_gpu = 0.0
    differ = 0
    for k in range(1, args.worlds + 1):
        r, d, st, ts = world(k)
        rc, tc = rows(st, r, d, "cpu")
        rg, tg = rows(st, r, d, "cuda")
        t_st, t_cpu, t_gpu = t_st + ts, t_cpu + tc, t_gpu + tg
        n = int((rc != rg).sum())
        differ += n
        print(f"world {k}: statics {ts:.3f} s, rows CPU {tc:.3f} s, GPU {tg:.3f} s; "
              f"{int(rc.sum())} of {rc.size} bits mapped, {n} differ")
    n = args.worlds
    print(f"per world: statics {t_st / n:.3f} s (CPU), rows CPU {t_cpu / n:.3f} s, "
          f"GPU {t_gpu / n:.3f} s")
    print(f"differing bits: {differ}" + (" (FMA contraction on the device: operands "
                                          "within rounding of a test's boundary)"
                                          if differ else " (rows identical)"))
    print(f"rows alone: {t_cpu / t_gpu:.2f}x")
    print(f"world_bank_gpu: {(t_st + t_cpu) / (t_st + t_gpu):.2f}x faster than CPU")
    return 0 if differ == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
