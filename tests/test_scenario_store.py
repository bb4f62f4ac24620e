"""The scenario bank store (issue 20): chunked by scenario, reused, resumed, worker-count free."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from gates import Gate, wait_until
from ideas_hpc.engine.gate import GATE_ENV
from ideas_hpc.engine.chunk_write import done_mask
from ideas_hpc.engine.store_meta import is_store, store_attrs
from ideas_hpc.montecarlo.scenarios import build_scenario_bank
from test_scenarios import STEP, _campaign

SEED = 9
N_SCEN = 6


@pytest.fixture(scope="module")
def ellipsoid():
    return _campaign()


@pytest.fixture(scope="module")
def reference(ellipsoid):
    c, setup = ellipsoid
    return build_scenario_bank(setup, STEP, c.config.monte_carlo, seed=SEED,
                               n_scenarios=N_SCEN, progress=False)


def _build(ellipsoid, **kw):
    c, setup = ellipsoid
    return build_scenario_bank(setup, STEP, c.config.monte_carlo, seed=SEED,
                               n_scenarios=N_SCEN, progress=False, chunk_size=2, **kw)


def test_store_is_built_then_reused(ellipsoid, reference, tmp_path):
    path = tmp_path / "bank.zarr"
    a = _build(ellipsoid, store=str(path))
    np.testing.assert_array_equal(a.rows, reference.rows)
    assert a.attrs["chunks_run"] == 3 and done_mask(path).all()
    attrs = store_attrs(path)
    assert attrs["scenario_stream"] == reference.attrs["scenario_stream"]
    assert attrs["validation_stream"] == reference.attrs["validation_stream"]
    b = _build(ellipsoid, store=str(path))           # unchanged config: nothing flown
    assert b.attrs.get("reused") and b.attrs["chunks_run"] == 0
    np.testing.assert_array_equal(b.rows, reference.rows)
    c, setup = ellipsoid                              # a config that shapes it: rebuilt
    other = build_scenario_bank(setup, STEP, c.config.monte_carlo, seed=SEED + 1,
                                n_scenarios=N_SCEN, progress=False, chunk_size=2,
                                store=str(path))
    assert other.attrs.get("rebuilt") and other.attrs["chunks_run"] == 3
    assert not np.array_equal(other.rows, reference.rows)


def test_one_and_two_workers_give_the_same_bank(ellipsoid, reference, tmp_path):
    from distributed import Client, LocalCluster

    for n in (1, 2):
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=False,
                          dashboard_address=None) as lc, Client(lc) as client:
            got = _build(ellipsoid, store=str(tmp_path / f"w{n}.zarr"), client=client)
            np.testing.assert_array_equal(got.rows, reference.rows)
            mem = _build(ellipsoid, client=client)   # in memory, chunks on the workers
            np.testing.assert_array_equal(mem.rows, reference.rows)


_BUILD = """
import sys
sys.path.insert(0, {tests!r})
from test_scenarios import STEP, _campaign
from ideas_hpc.montecarlo.scenarios import build_scenario_bank
c, setup = _campaign()
build_scenario_bank(setup, STEP, c.config.monte_carlo, seed={seed}, n_scenarios={n},
                    progress=False, chunk_size=2, store={path!r})
"""


def test_killed_build_resumes_to_the_same_bank(ellipsoid, reference, tmp_path):
    # The build waits at the chunk gate after two chunks; it is killed there and
    # resumed in this process: only the missing chunk is flown, same rows.
    path = tmp_path / "killed.zarr"
    gate = Gate(tmp_path / "gate")
    script = tmp_path / "build.py"
    script.write_text(_BUILD.format(tests=os.path.dirname(__file__), seed=SEED, n=N_SCEN,
                                    path=str(path)))
    log = tmp_path / "build.log"
    gate.allow(2)
    with open(log, "w") as fh:
        proc = subprocess.Popen([sys.executable, str(script)], stdout=fh, stderr=fh,
                                env={**os.environ, **gate.env})
    try:
        wait_until(lambda: is_store(path) and int(done_mask(path).sum()) == 2 and
                   gate.waiting() == 3, "two chunks done and the third at the gate", proc, log)
    finally:
        proc.kill()
        proc.wait()
    assert int(done_mask(path).sum()) == 2
    os.environ.pop(GATE_ENV, None)
    got = _build(ellipsoid, store=str(path))
    assert got.attrs["chunks_run"] == 1
    np.testing.assert_array_equal(got.rows, reference.rows)
