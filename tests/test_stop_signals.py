"""SIGTERM in the design phase (issue 29): one line, a non-zero exit, and ``--resume``
finishes the run; a design time limit of ~0 s is honoured; no third-party warning."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.design.reliability import min_swarm_reliable
from ideas_hpc.design.scenario_mip import BoundResult

from campaign_copies import fitted

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "campaigns" / "eros-design.toml"
SETS = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        "dynamics.srp=false", "design.angle_step_deg=10", 'attitude.mode="ideal"',
        "design.time_limit_s=60", "design.success_probability=0.5",
        "design.scenarios=20", "design.verify_samples=20", "design.demonstrate=false"]
#: the main job without its demonstrate_looks, which one look (demonstrate = false) ignores
DESIGN = fitted("eros-design.toml", SETS)

# The child blocks inside the design phase (after the scenario bank is stored) until
# the signal arrives: the test waits on that state, not on a clock.
CHILD = """
import select, sys
# the success-probability designer's adapter (design.api) calls this name at run time
from ideas_hpc.design.api import designers as d
def blocked(*a, **k):
    print("IN DESIGN", file=sys.stderr, flush=True)
    # wait for the signal in short selects, not one blocking read: the OS may hand the
    # signal to another thread (tqdm's monitor), and then only a main thread that wakes
    # runs Python's handler (a read() of stdin hung a loaded CI run here)
    while True:
        if select.select([sys.stdin], [], [], 0.05)[0] and not sys.stdin.read(1):
            raise SystemExit("stdin closed without a signal")
d.min_swarm_reliable = blocked
from ideas_hpc.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _cmd(out: Path, *extra):
    sets = [a for s in SETS for a in ("--set", s)]
    return [sys.executable, "-c", CHILD, "run", str(DESIGN), "--out", str(out), "--workers",
            "0", "--no-progress", *sets, *extra]


def test_sigterm_one_line_exit_code_and_resume(tmp_path):
    out = tmp_path / "d.zarr"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen(_cmd(out), stdin=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    for line in proc.stderr:
        if line.strip() == "IN DESIGN":
            break
    else:
        pytest.fail(f"the child ended before the design phase: rc {proc.wait()}")
    proc.send_signal(signal.SIGTERM)
    rest = proc.stderr.read().splitlines()
    rc = proc.wait()
    proc.stdin.close()
    assert rc == 128 + signal.SIGTERM
    assert rest == ["ideas-hpc: stopped by SIGTERM (rerun with --resume to continue)"]
    bank = tmp_path / "d-scenarios.zarr"
    assert bank.exists() and not out.exists()       # the main store is written atomically
    # --resume (the real designer this time) reuses the bank and completes the store
    sets = [a for s in SETS for a in ("--set", s)]
    done = subprocess.run([sys.executable, "-m", "ideas_hpc.cli", "run", str(DESIGN), "--out",
                           str(out), "--workers", "0", "--no-progress", "--resume", *sets],
                          capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "stopped" not in done.stderr and "Warning" not in done.stderr
    ds = xr.open_zarr(out)
    assert int(ds["best_swarm_size"]) >= 1


def _rows(seed=5, s_n=3, c_n=12, v_n=30):
    rng = np.random.default_rng(seed)
    rows = np.zeros((s_n, c_n, v_n), dtype=bool)
    for s in range(s_n):
        for v in range(v_n):
            lo = (c_n * v) // v_n + rng.integers(-1, 2)
            rows[s, np.arange(lo, lo + rng.integers(3, 6)) % c_n, v] = True
    return rows, rng.uniform(0.5, 1.5, v_n)


def test_time_limit_of_zero_stops_every_proof():
    """A limit already spent when the search starts: no programme and no tolerant design is
    started (recorded by the stand-ins), and the answer says the limit stopped it. One
    scenario: on a sampled bank the screen goes first and may settle every size without a
    programme (design.reliability.settle), so the second half would call nothing."""
    rows, areas = _rows(s_n=1)
    calls = []

    def bound_solver(m, seconds):
        calls.append(("mip", m))
        return BoundResult(m, rows.shape[0], 0, None, "optimal", 0.0)

    def tol_solver(*a):
        calls.append(("tol",) + a[3:4])
        return 0

    res = min_swarm_reliable(rows, areas, p=0.9, p_f=0.05, need=0.95, n_max=8,
                             time_limit=1e-9, bound_solver=bound_solver,
                             tolerance_solver=tol_solver, enumerate_budget=0)
    assert calls == []
    assert res.gap == 0.0 or res.status == "time_limit"
    # with time, the same stand-ins are called: the limit (not the data) stopped them
    min_swarm_reliable(rows, areas, p=0.9, p_f=0.05, need=0.95, n_max=8, time_limit=None,
                       bound_solver=bound_solver, tolerance_solver=tol_solver,
                       enumerate_budget=0)
    assert calls


def test_designer_raises_no_warning_at_a_spent_limit():
    """HiGHS refuses a time limit <= 0 (SciPy's OptimizeWarning): never shown."""
    rows, areas = _rows(7)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        min_swarm_reliable(rows, areas, p=0.9, p_f=0.05, need=0.95, n_max=8, time_limit=1e-6)
        min_swarm_reliable(rows, areas, p=0.9, p_f=0.05, need=0.95, n_max=8, time_limit=30)


def test_sizes_past_the_search_do_not_depend_on_the_clock():
    """After the fewest-N search has settled, the swarms of larger sizes (the looks' step-ups,
    the reliability curve) are the same whether the design's time limit is spent or not: a
    first run that spent it compiling gets the swarm a warm run gets (the main job's N = 7
    step-up differed from a fresh clone, 2026-11-29). The reference has no limit at all."""
    rows, areas = _rows(11, s_n=6, c_n=24, v_n=40)
    kw = dict(p=0.5, p_f=0.05, need=0.9, n_max=12, enumerate_budget=0)
    free = min_swarm_reliable(rows, areas, time_limit=None, **kw)
    timed = min_swarm_reliable(rows, areas, time_limit=600.0, **kw)
    assert (timed.n, timed.status) == (free.n, free.status)
    timed.designer.deadline = time.perf_counter() - 1.0      # spent once the search is over
    for n in range(free.n + 1, free.n + 4):
        sw_free, p_free = free.designer.best_of(n)
        sw_timed, p_timed = timed.designer.best_of(n)
        np.testing.assert_array_equal(sw_timed, sw_free)
        assert p_timed == p_free
