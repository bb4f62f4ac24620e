"""Job start-up: the in-process rule, one shared cluster per job, the cold-cache helper."""

from __future__ import annotations

from pathlib import Path

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from test_campaign_mc import MC, SHORT

ROOT = Path(__file__).resolve().parent.parent


def test_job_cluster_rule_and_one_shared_cluster():
    from ideas_hpc.engine.job_cluster import (IN_PROCESS_MAX_TESTS, JobCluster,
                                              runs_in_process, visibility_tests)

    small, big = IN_PROCESS_MAX_TESTS / 2, IN_PROCESS_MAX_TESTS * 2
    assert visibility_tests(2, 3, 5, 7) == 210.0
    assert runs_in_process(workers=None, scheduler=None, cluster="local", work=small)
    assert not runs_in_process(workers=None, scheduler=None, cluster="local", work=big)
    assert runs_in_process(workers=0, scheduler=None, cluster="local", work=big)
    for kw in (dict(workers=1), dict(workers=None, scheduler="tcp://x:1"),
               dict(workers=None, cluster="slurm")):  # explicit: honoured
        assert not runs_in_process(**{"scheduler": None, "cluster": "local", **kw},
                                   work=small), kw
    calls = []
    with JobCluster(workers=None, work=small) as job:
        assert job.client(warm=lambda: calls.append(1)) is None and job.started == 0
    assert calls == []  # in process: nothing to warm for
    with JobCluster(workers=1, work=small) as job:
        a = job.client(warm=lambda: calls.append("masks"))
        b = job.client(warm=lambda: calls.append("verification"))
        assert a is b and job.started == 1
        assert len(a.scheduler_info()["workers"]) == 1
    assert calls == ["masks", "verification"]  # each phase warmed here first



def test_precompile_helper_warms_the_kernels_the_job_calls(monkeypatch):
    from ideas_hpc.campaign import precompile

    setup = setup_from_campaign(load(MC, SHORT + ['coverage.mode="exact"',
                                                  "coverage.occlusion=true"]))
    precompile.warm_kernels(setup)  # the helper's work, here
    assert precompile.cache_is_warm()
    monkeypatch.setenv("IDEAS_HPC_PRECOMPILE", "1")
    assert precompile.start(setup) is None  # nothing to do on a warm cache
    calls = []
    monkeypatch.setattr(precompile, "cache_is_warm", lambda bank=False, setup=None: False)
    monkeypatch.setenv("IDEAS_HPC_PRECOMPILE", "0")
    assert precompile.start(setup) is None  # turned off
    monkeypatch.setenv("IDEAS_HPC_PRECOMPILE", "1")
    monkeypatch.setattr(precompile.subprocess, "Popen",
                        lambda cmd, **kw: calls.append(cmd) or _Done())
    h = precompile.start(setup)
    assert calls and calls[0][1:3] == ["-m", "ideas_hpc.campaign.precompile"]
    h.close()  # stops the helper and removes its setup file
    assert not __import__("os").path.exists(calls[0][3])


class _Done:
    def poll(self):
        return 0

    def wait(self, timeout=None):
        return 0


#: The main job's bank features (closed-loop attitude, strict coverage) on a short ellipsoid
#: flyby: what a worker's bank chunk compiles.
BANK = ROOT / "campaigns" / "eros-design.toml"
BANK_SETS = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
             "flyby.z_stop_km=3", "design.angle_step_deg=90", "design.scenarios=100"]

#: Run in a fresh process: the helper's work (precompile.warm_all), then print every
#: kernel signature it compiled or loaded (that process only ever did the warm-up).
_HELPER = """
import json, sys
from ideas_hpc.base.compile_once import loaded_kernels
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.campaign import precompile
c = load(sys.argv[1], json.loads(sys.argv[2]))
precompile.warm_all(setup_from_campaign(c), (c.config.monte_carlo, c.config.seed))
print(json.dumps(loaded_kernels()))
"""


def test_the_warm_up_covers_every_kernel_a_bank_worker_runs():
    """What the cold-start helper compiles (one scenario of two candidates, in its own
    process) must include every kernel and signature a dask worker then runs for the
    scenario bank (its chunks reach it pickled, through dask): a worker only loads
    (issue 43). Compared as signature sets, so it holds whatever the cache holds."""
    import json
    import subprocess
    import sys

    from distributed import Client

    from ideas_hpc.engine.cluster import local_cluster
    from ideas_hpc.montecarlo.scenarios import build_scenario_bank

    from ideas_hpc.base.compile_once import loaded_kernels

    p = subprocess.run([sys.executable, "-c", _HELPER, str(BANK), json.dumps(BANK_SETS)],
                       capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr[-3000:]
    warmed = json.loads(p.stdout.strip().splitlines()[-1])
    c = load(BANK, BANK_SETS)
    setup = setup_from_campaign(c)
    with local_cluster(1) as lc, Client(lc) as client:
        build_scenario_bank(setup, c.config.design.grid_step_rad, c.config.monte_carlo,
                            seed=c.config.seed, n_scenarios=2, client=client, progress=False)
        worker = next(iter(client.run(loaded_kernels).values()))
    assert worker, "the worker ran no kernel"
    missing = {k: sorted(set(v) - set(warmed.get(k, []))) for k, v in worker.items()}
    missing = {k: v for k, v in missing.items() if v}
    assert not missing, f"kernels a worker compiles that the warm-up did not: {missing}"
