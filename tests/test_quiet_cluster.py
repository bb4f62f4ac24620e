"""No "Port 8787 is already in use" noise when another dask cluster runs (issue 22)."""

import socket
import warnings

import pytest

from ideas_hpc.engine.cluster import local_cluster


def test_local_cluster_quiet_when_8787_is_taken():
    s = socket.socket()
    try:
        try:
            s.bind(("0.0.0.0", 8787))
            s.listen()
        except OSError:
            pass  # already taken by another cluster: the case itself
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with local_cluster(1) as lc:
                port = lc.scheduler.http_server.port if hasattr(lc.scheduler.http_server, "port") \
                    else None
        assert not [w for w in caught if "already in use" in str(w.message)]
        assert port != 8787
    finally:
        s.close()


def _exit_slowly(seconds):
    """In a worker process: make its exit take ``seconds`` (a finaliser run at exit)."""
    import multiprocessing.util
    import time

    multiprocessing.util.Finalize(None, time.sleep, args=(seconds,), exitpriority=0)
    return True


@pytest.mark.slow
def test_slow_worker_exit_is_not_killed_with_a_warning(capfd):
    """The main job ended with "Worker process still alive after 4.0 seconds, killing"
    on a loaded machine (workers that ran the OpenMP kernels exit slowly). A worker
    whose exit takes 5 s (more than the nanny's 4 s) now exits on its own, quietly.
    The finaliser's delay is the case itself, not a wait for a state."""
    from distributed import Client

    with local_cluster(2) as lc:
        procs = [w.process.process for w in lc.workers.values()]
        with Client(lc) as client:
            assert all(client.run(_exit_slowly, 5.0).values())
    err = capfd.readouterr().err
    assert "still alive" not in err and "killing" not in err, err
    assert all(p.exitcode == 0 for p in procs)        # exited by itself, not SIGKILLed
