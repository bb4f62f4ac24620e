"""Job start-up: the in-process rule, one shared cluster per job, the cold-cache helper."""

from __future__ import annotations

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from test_campaign_mc import MC, SHORT


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
    monkeypatch.setattr(precompile, "cache_is_warm", lambda: False)
    monkeypatch.delenv("IDEAS_HPC_PRECOMPILE")
    assert precompile.start(setup) is None  # opt-in only
    monkeypatch.setenv("IDEAS_HPC_PRECOMPILE", "1")
    monkeypatch.setattr(precompile.subprocess, "Popen",
                        lambda cmd, **kw: calls.append(cmd) or _Done())
    h = precompile.start(setup)
    assert calls and calls[0][1:3] == ["-m", "ideas_hpc.campaign.precompile"]
    h.close()  # waits for the helper and removes its setup file
    assert not __import__("os").path.exists(calls[0][3])


class _Done:
    def wait(self, timeout=None):
        return 0
