"""The local cluster of ``campaign`` and ``verify --smc-workers``: its connections where ``--listen`` says, its HTTP
servers (Dask starts one per scheduler and worker, dashboard or not) on loopback only, and no dashboard."""
from __future__ import annotations

import pytest

from genom2bip.campaign.cluster import ClusterSpec, connect

distributed = pytest.importorskip("distributed")


def test_the_local_clusters_arguments_keep_http_on_loopback_and_the_dashboards_off():
    from genom2bip.campaign.cluster import local_cluster_arguments

    args = local_cluster_arguments(ClusterSpec(workers=3, listen="0.0.0.0"))
    assert (args["host"], args["n_workers"], args["threads_per_worker"]) == ("0.0.0.0", 3, 1)
    assert args["dashboard_address"] == "127.0.0.1:0" and args["scheduler_kwargs"] == {"dashboard": False}
    assert "worker_dashboard_address" not in args  # LocalCluster would turn the workers' dashboard on with it
    assert issubclass(args["worker_class"], distributed.Nanny)


def _listening(dask_worker) -> dict:
    """In a worker: its comm port, and every TCP socket its process listens on."""
    import psutil

    sockets = [c.laddr for c in psutil.Process().net_connections(kind="tcp") if c.status == psutil.CONN_LISTEN]
    return {"comm": int(dask_worker.address.rsplit(":", 1)[1]), "listening": [(a.ip, a.port) for a in sockets],
            "dashboard": dask_worker._dashboard}


def test_a_workers_http_server_listens_on_loopback_whatever_listen_says():
    # 127.0.0.2 is a loopback address too, so nothing is opened to the network; a worker's HTTP server used to
    # follow its host there (and to every interface with --listen 0.0.0.0)
    client, cluster = connect(ClusterSpec(workers=1, listen="127.0.0.2"))
    try:
        (seen,) = client.run(_listening).values()
        scheduler = client.scheduler_info()["address"]
    finally:
        client.close()
        cluster.close()
    assert scheduler.startswith("tcp://127.0.0.2:")
    assert ("127.0.0.2", seen["comm"]) in seen["listening"]
    http = [(ip, port) for ip, port in seen["listening"] if port != seen["comm"]]
    assert http, seen  # Dask's HTTP server is there: it is where it listens that is checked
    assert all(ip == "127.0.0.1" for ip, _ in http), seen
    assert seen["dashboard"] is False
