"""No "Port 8787 is already in use" noise when another dask cluster runs (issue 22)."""

import socket
import warnings

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
