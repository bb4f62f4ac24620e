"""The world bank's mapped rows on ``numba.cuda`` (issue 43, deliverable 4; docs/gpu.md).

The kernel (:mod:`ideas_hpc.core.mapping.world_rows_cuda`) runs here on Numba's CUDA
simulator, which must be switched on before ``numba.cuda`` is first imported: the
comparison runs this file as a script in a fresh interpreter with
``NUMBA_ENABLE_CUDASIM=1`` and reads its JSON. The simulator runs each thread's
double-precision operations as written, so the rows must be identical to the CPU
kernel's (:func:`ideas_hpc.core.mapping.world_rows.mapped_by_spacecraft`) and to full
recomputation (the quality pass over every observation,
:func:`ideas_hpc.design.candidates.rows_from_views`).

The world is a rough draw of the Eros-class prior on an icosphere of resolution 2 (162
vertices), flown by 4 candidates over its 101 images, with the minimum elevation at 0 so
that grazing sight lines reach past the clear cones: some (candidate, vertex) pairs are
mapped only without occlusion, some only without the lighting (vertices in shadow, and
vertices never facing the Sun), some only without the limits, so each test of the kernel
decides bits of these rows.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-class-flyby.toml"
SETS = ["body.resolution=2", "target.sigma_r=0.6", "target.correlation_deg=45",
        "coverage.min_elevation_deg=0"]
#: 4 candidates (360 / 90): the simulator runs one Python thread per (candidate, vertex) bit,
#: so its time goes with the candidates. 4 of them still leave bits that only occlusion (4,
#: as many as 12 candidates at 30 deg left), only the lighting (198), only the resolution
#: limit (31) and only the incidence limit (9) decide, which
#: test_the_world_exercises_occlusion_lighting_and_limits asserts; rays are blocked at
#: successive images, so the kernel's blocking-face hint decides bits too (measured by
#: mutation: ignoring a hint hit changes 2 bits, the clear cone flipped 4).
STEP_DEG = 90.0
N_CANDIDATES = round(360.0 / STEP_DEG)     # the snapped grid (scenarios.grid_theta)
SEED, WORLD = 2026, 2
#: Every per-image limit, with illumination a filter (tests/test_world_bank.py's set, the
#: resolution limit tightened until it decides bits of its own on this world).
LIMITS = dict(illumination=True, max_emission_rad=math.radians(60.0),
              max_incidence_rad=math.radians(70.0), max_phase_rad=math.radians(100.0),
              max_resolution_m=1.5)


def _env(**extra) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    env.update(extra)
    return env


def _world(sets):
    """Setup, world and every candidate's flight through draw ``WORLD`` of the bank's stream."""
    from ideas_hpc.base import seeds
    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.flyby.flight import Perturbation
    from ideas_hpc.flyby.target_world import scenario_world
    from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, row_engine

    c = load(CAMPAIGN, sets)
    setup = setup_from_campaign(c)
    mc = c.config.monte_carlo
    theta = grid_theta(np.deg2rad(STEP_DEG))
    engine = row_engine(setup, theta, mc, SEED, seeds.SCENARIO_STREAM)
    pert = Perturbation(**draw_world(mc, setup, theta, SEED, seeds.SCENARIO_STREAM, WORLD))
    world = scenario_world(setup, SEED, seeds.SCENARIO_STREAM, WORLD, pert.params_override)
    r, d = engine.flight(pert, False, world)
    return setup, engine, world, r, d


def _simulator_report() -> dict:
    """Runs under the simulator: the CPU and the CUDA kernel on the same records, the
    full recomputation, and the rows with each test switched off (which bits it decides)."""
    from numba import config, cuda

    from ideas_hpc.core.mapping import world_rows_cuda
    from ideas_hpc.core.mapping.observations import quality_tests
    from ideas_hpc.core.mapping.records import QualityTests
    from ideas_hpc.core.mapping.world_rows import mapped_by_spacecraft
    from ideas_hpc.design.candidates import rows_from_views
    from ideas_hpc.mapping.coverage import camera_record, check_geometry, quality_record
    from ideas_hpc.mapping.world_rows import rows_of_world, world_statics

    setup, _, world, r, d = _world(SETS)
    rep = {"simulator": bool(config.ENABLE_CUDASIM) and cuda.is_available(),
           "shape": list(r.shape), "cases": {}}
    rc, cc, tan_eta, near, far, _ = check_geometry(None, r, d, setup.eta_rad, setup.near_m,
                                                   setup.far_m)
    cam = camera_record(rc, cc, np.asarray(setup.image_times, float), tan_eta, near, far, True)
    frustum = (setup.eta_rad, setup.near_m, setup.far_m)

    def both(cuda_too=True, **over):
        options = dataclasses.replace(setup.coverage, **over)
        sun = world.sun_at_images(dataclasses.replace(world.flown(setup), coverage=options))
        st = world_statics(world.shape, options, sun, r.shape[1])
        q = QualityTests(*quality_tests(quality_record(options)))
        args = (st.mesh, cam, st.opts, st.bvh, q, st.lit, st.cos_clear)
        return (mapped_by_spacecraft(*args),
                world_rows_cuda.mapped_by_spacecraft_cuda(*args) if cuda_too else None,
                options, sun, st)

    for name, over, off in (("campaign", {}, {"occlusion": False, "require_lit": False}),
                            ("limits", LIMITS, {"occlusion": False, "max_resolution_m": None,
                                                "max_emission_rad": None,
                                                "max_incidence_rad": None,
                                                "max_phase_rad": None})):
        cpu, gpu, options, sun, st = both(**over)
        flown = dataclasses.replace(world.flown(setup), coverage=options)
        full = rows_from_views(flown, r, d, sun)
        case = {"identical": bool(np.array_equal(cpu, gpu)), "differ": int((cpu != gpu).sum()),
                "full_identical": bool(np.array_equal(gpu, full)), "mapped": int(gpu.sum()),
                "size": int(gpu.size)}
        for key, value in off.items():      # the bits each test decides (CPU rows only:
            rows_off = both(False, **{**over, key: value})[0]   # nothing compares them)
            case[f"without {key}"] = int((rows_off & ~cpu).sum())
        # vertices in shadow (facing the Sun at some image, lit at none) and never facing
        facing = (world.shape.vertex_normals_T @ sun.T > 0.0).any(axis=1)
        case["shadowed"] = int((facing & ~st.lit.any(axis=1)).sum())
        case["unlit"] = int((~st.lit.any(axis=1)).sum())
        case["rays"] = bool(options.occlusion and (st.cos_clear < 2.0).any())
        rep["cases"][name] = case
    # through the switch: run.device = "cuda" sends a world's mapped rows to the kernel
    launches = []
    real = world_rows_cuda.mapped_by_spacecraft_cuda
    world_rows_cuda.mapped_by_spacecraft_cuda = lambda *a: launches.append(1) or real(*a)
    cuda_setup, engine, world_c, rr, dd = _world(SETS + ['run.device="cuda"'])
    got = engine.rows(rr, dd, world=world_c)
    want = rows_of_world(world_statics(world.shape, setup.coverage,
                                       world.sun_at_images(setup), r.shape[1]),
                         setup.coverage, r, d, setup.image_times, frustum)
    rep["switch"] = {"device": cuda_setup.device, "launches": len(launches),
                     "identical": bool(np.array_equal(got, want) and np.array_equal(rr, r))}
    return rep


@pytest.fixture(scope="module")
def report():
    out = subprocess.run([sys.executable, __file__], env=_env(NUMBA_ENABLE_CUDASIM="1"),
                         capture_output=True, text=True, timeout=900, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_cuda_rows_are_the_cpu_kernels_and_full_recomputation(report):
    assert report["simulator"]
    assert report["shape"][0] == N_CANDIDATES and report["shape"][1] > 50
    for name, case in report["cases"].items():
        assert case["identical"], (name, case["differ"])
        assert case["full_identical"], name
        assert 0 < case["mapped"] < case["size"], name


def test_the_world_exercises_occlusion_lighting_and_limits(report):
    # each of the kernel's tests decides bits of these rows (else the comparison above
    # could not see it wrong)
    camp, lim = report["cases"]["campaign"], report["cases"]["limits"]
    assert camp["rays"] and camp["without occlusion"] > 0        # occluded (k, j)
    assert camp["without require_lit"] > 0 and camp["unlit"] > 0
    assert lim["without max_resolution_m"] > 0
    assert (lim["without max_emission_rad"] + lim["without max_incidence_rad"]
            + lim["without max_phase_rad"]) > 0


def test_run_device_cuda_sends_world_rows_to_the_kernel(report):
    sw = report["switch"]
    assert sw["device"] == "cuda" and sw["launches"] >= 1 and sw["identical"]


def test_cuda_without_a_device_names_the_field(monkeypatch):
    from ideas_hpc.attitude import device
    from ideas_hpc.mapping.coverage import mesh_record
    from ideas_hpc.mapping.world_rows import WorldStatics, rows_of_world

    monkeypatch.setattr(device, "cuda_available", lambda: False)
    setup, _, world, r, d = _world(SETS)
    st = WorldStatics(mesh_record(world.shape), None, None, None, None)
    for dev, words in (("cuda", "numba.cuda.is_available() is false"), ("gpu", "gpu")):
        with pytest.raises(InputError) as exc:
            rows_of_world(st, setup.coverage, r, d, setup.image_times,
                          (setup.eta_rad, setup.near_m, setup.far_m), dev)
        assert exc.value.field == "device" and words in str(exc.value)


if __name__ == "__main__":     # the simulator half (see the module docstring)
    if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        sys.exit("run with NUMBA_ENABLE_CUDASIM=1")
    print(json.dumps(_simulator_report()))
