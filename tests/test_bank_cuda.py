"""The GPU path of the bank's closed-loop flights (issue 31, deliverable 3; docs/gpu.md).

The CUDA kernel (:mod:`ideas_hpc.core.attitude.batch_cuda`) runs here on Numba's CUDA
simulator, which must be switched on before ``numba.cuda`` is first imported: the
comparison runs this file as a script in a fresh interpreter with
``NUMBA_ENABLE_CUDASIM=1`` and reads its JSON. The reference is the CPU path
(``core.attitude.batch.simulate_batch``, the default). The bank's rows must be
identical. The flown states must agree to ``RTOL`` of each output's largest value:
the simulator runs the same double-precision operations in the same order, except
``tan``/``sin``/``cos``, which it takes from NumPy while compiled code takes the C
library's (NumPy's scalar ``tan`` differs in the last bit on about 0.7 % of small
arguments); one ulp in the reference passes through the stable loop without growing
(measured: 0 on these cases, <= 5.6e-16 on the main job's camera DCMs). A wrong
mirror of the control law or a skipped step differs by many orders more.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "campaigns" / "eros-design-nominal.toml"
TINY = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        "dynamics.srp=false", 'attitude.mode="simulated"']
STEP_DEG = 60.0     # 6 candidates
RTOL = 1e-12        # of each output's largest magnitude (module docstring)
N_SCENARIOS = 2


def _env(**extra) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    env.update(extra)
    return env


def _kernel_cases():
    """Direct calls of both kernels: NP, FoV with a disturbance torque and body tracking
    from a table, random (paper) starts that drive the wheels into their torque limit."""
    from ideas_hpc.attitude.simulate import initial_conditions
    from ideas_hpc.core.attitude.records import ControlGains, Initial, StepTables, Wheels
    from ideas_hpc.core.dynamics.frames import dcm_RT

    n, n_s, n_steps = 3, 2, 60
    rings = np.ascontiguousarray([dcm_RT(float(t), np.eye(3)) for t in (0.0, 2.0, 4.0)])
    draws = [initial_conditions(11, k, n) for k in range(n_s)]
    init = Initial(*(np.ascontiguousarray(np.stack([d[j] for d in draws])) for j in range(3)))
    # the conditional integral both ways: always on (inf, as SPEC writes it) and only near
    # the goal (0.2, mostly off from these starts)
    always = ControlGains(np.full(3, 0.2), np.full(3, 0.002), np.full(3, 0.05),
                          np.full(3, 20.0), np.inf)
    near = always._replace(int_limit=0.2)
    wheels = Wheels(np.array([10.0, 11.0, 12.0]), np.full(3, 0.01), 0.01, 0.05)
    rng = np.random.default_rng(4)
    torque = rng.normal(size=(n, n_steps + 1, 3)) * 1e-4
    track = np.concatenate([rng.uniform(-0.3, 0.3, (n, n_steps + 1, 3)),
                            rng.normal(size=(n, n_steps + 1, 6)) * 1e-3], axis=2)
    none9, none3 = np.empty((n, 0, 9)), np.empty((n, 0, 3))
    for name, mode, gains, tables in (("np", 0, always, StepTables(none9, none3)),
                                      ("fov-torque", 1, near, StepTables(none9, torque)),
                                      ("track", 2, always, StepTables(track, none3))):
        yield name, (mode, rings, 3.3e-4, np.array([30.0, 40.0, 50.0]), 0.03, gains, wheels,
                     0.1, n_steps, (4, 2), init, tables), wheels.u_max_Nm


def _simulator_report() -> dict:
    """Runs under the simulator: both paths on the kernel cases and on a tiny bank."""
    from numba import cuda

    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.core.attitude.batch import simulate_batch
    from ideas_hpc.core.attitude.batch_cuda import simulate_batch_cuda
    from ideas_hpc.montecarlo.scenarios import build_scenario_bank

    from numba import config

    rep = {"simulator": bool(config.ENABLE_CUDASIM) and cuda.is_available(), "kernels": {}}
    for name, args, u_max in _kernel_cases():
        cpu, gpu = simulate_batch(*args), simulate_batch_cuda(*args)
        rep["kernels"][name] = {
            "shapes_equal": all(a.shape == b.shape for a, b in zip(cpu, gpu)),
            "identical": [bool(np.array_equal(a, b)) for a, b in zip(cpu, gpu)],
            "max_abs": [float(np.max(np.abs(a - b))) for a, b in zip(cpu, gpu)],
            "scale": [float(np.max(np.abs(a))) for a in cpu],
            "saturated": bool(np.any(cpu[5] >= u_max)),
            "n_images": int(cpu[7].shape[2])}
    from ideas_hpc.core.attitude import batch_cuda

    launches = []
    real = batch_cuda.simulate_batch_cuda
    batch_cuda.simulate_batch_cuda = lambda *a: launches.append(a[-2].sigma_BN.shape[:2]) or real(*a)
    c = load(DESIGN, TINY)
    rows = {}
    for device in ("cpu", "cuda"):
        c_dev = load(DESIGN, TINY + [f'run.device="{device}"'])
        setup = setup_from_campaign(c_dev)
        bank = build_scenario_bank(setup, np.deg2rad(STEP_DEG), c.config.monte_carlo, seed=7,
                                   n_scenarios=N_SCENARIOS, progress=False)
        rows[device] = bank
    a, b = rows["cpu"], rows["cuda"]
    rep["bank"] = {"shape": list(a.rows.shape),
                   "rows_identical": bool(np.array_equal(a.rows, b.rows)),
                   "hash_equal": a.attrs["config_hash"] == b.attrs["config_hash"],
                   "budget_equal": a.attrs.get("budget") == b.attrs.get("budget"),
                   "scenarios_differ": bool((a.rows[0] != a.rows[1]).any()),
                   "seen": int(a.rows.sum()), "cuda_launches": len(launches),
                   "launch_jobs": sorted({int(np.prod(s)) for s in launches})}
    rep["device_cuda"] = setup_from_campaign(load(DESIGN, TINY + ['run.device="cuda"'])).device
    return rep


# slow: the CUDA simulator runs each thread in Python (90 s on the quiet machine); the slow
# session, beside the default one in CI, has the room (.ci/run)
@pytest.mark.slow
def test_cuda_kernel_and_bank_rows_match_the_cpu_under_the_simulator():
    out = subprocess.run([sys.executable, __file__], env=_env(NUMBA_ENABLE_CUDASIM="1"),
                         capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-3000:]
    rep = json.loads(out.stdout.strip().splitlines()[-1])
    assert rep["simulator"]
    assert set(rep["kernels"]) == {"np", "fov-torque", "track"}
    for name, k in rep["kernels"].items():
        assert k["shapes_equal"], name
        # sigma, omega, wheel, torque, dcm_BT, max_u, max_h, image_omega, image_error
        for j, (d, m) in enumerate(zip(k["max_abs"], k["scale"])):
            assert d <= RTOL * m, (name, j, d, m)
        assert k["n_images"] == 31
    assert any(k["saturated"] for k in rep["kernels"].values())   # the limit branch ran
    bank = rep["bank"]
    assert bank["shape"][:2] == [N_SCENARIOS, 6]
    assert bank["scenarios_differ"] and bank["seen"] > 0
    assert bank["rows_identical"]
    # the bank's flights went to the kernel: the pilot and each scenario, all candidates at once
    assert bank["cuda_launches"] >= N_SCENARIOS and bank["launch_jobs"] == [6]
    assert bank["hash_equal"]          # the device is no part of the bank's shaping hash
    assert rep["device_cuda"] == "cuda"


def test_cuda_without_a_device_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    from ideas_hpc import cli
    from ideas_hpc.attitude import device

    monkeypatch.setattr(device, "cuda_available", lambda: False)
    out = tmp_path / "x.zarr"
    rc = cli.main(["run", str(DESIGN), "--device", "cuda", "--out", str(out), "--no-progress",
                   *[a for s in TINY for a in ("--set", s)]])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "run.device" in err[0] and "numba.cuda.is_available() is false" in err[0]
    assert not out.exists()


def test_a_bad_device_names_the_field(tmp_path, capsys):
    from ideas_hpc import cli

    rc = cli.main(["run", str(DESIGN), "--set", 'run.device="gpu"', "--out",
                   str(tmp_path / "x.zarr")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "run.device" in err[0] and "gpu" in err[0], err


def test_cpu_runs_never_import_numba_cuda():
    code = ("import sys\n"
            "from ideas_hpc.attitude import simulate_attitude\n"
            "import ideas_hpc.cli, ideas_hpc.campaign.setup, ideas_hpc.montecarlo.scenarios\n"
            "r = simulate_attitude([0.0, 1.0], 3e-4, 1.0, device='cpu')\n"
            "assert r.image_rate.shape == (1, 2, 6)\n"
            "print('numba.cuda' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], env=_env(), capture_output=True,
                         text=True, timeout=600, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "False"


if __name__ == "__main__":     # the simulator half (see the module docstring)
    if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        sys.exit("run with NUMBA_ENABLE_CUDASIM=1")
    print(json.dumps(_simulator_report()))
