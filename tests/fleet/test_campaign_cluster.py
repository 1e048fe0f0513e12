"""gyrodrift.fleet.cluster: a LocalCluster started by `dask_client` takes no dashboard port and warns about none."""

from __future__ import annotations

import socket
import warnings

import pytest

from gyrodrift.fleet.cluster import dask_client


def test_local_cluster_warns_nothing_when_port_8787_is_taken():
    pytest.importorskip("dask.distributed")
    holder = socket.socket()
    try:
        holder.bind(("127.0.0.1", 8787))  # as another cluster's dashboard would
        holder.listen()
    except OSError:  # already taken by something else: the situation this test is about anyway
        pass
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with dask_client(workers=1, processes=False) as client:
                assert client.submit(sum, [1, 2]).result() == 3
                http = client.cluster.scheduler.http_server.port
    finally:
        holder.close()
    assert http != 8787
    messages = [str(w.message) for w in caught]
    assert not [m for m in messages if "already in use" in m or "8787" in m], messages
