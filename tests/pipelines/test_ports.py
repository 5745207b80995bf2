"""Clusters take free ports: with dask's default scheduler and dashboard ports (8786, 8787)
held by someone else, the tests' cluster and the sweep's own local cluster start without a
warning (the suite turns warnings into errors) and run their cases."""

from __future__ import annotations

import errno
import socket
import warnings
from collections.abc import Iterator
from urllib.parse import urlsplit

import numpy as np
import pytest

from pipelines.archive import STATUS_OK, open_archive
from pipelines.sweep import run_sweep
from tests.clusters import local_cluster

DASK_DEFAULT_PORTS = (8786, 8787)

STUDY = """model = "tests.pipelines.models:SPEC"
title = "busy ports"
[fixed]
samples_per_rev = 48
[sweep]
tuning_order = [2.8, 3.2]
"""


@pytest.fixture
def default_ports_taken() -> Iterator[None]:
    """Hold dask's default ports on every interface for the test's duration (a port already
    held by another process is taken all the same)."""
    held = []
    for port in DASK_DEFAULT_PORTS:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            sock.bind(("", port))
            sock.listen()
            held.append(sock)
        except OSError as exc:
            sock.close()
            if exc.errno != errno.EADDRINUSE:
                raise
    try:
        yield
    finally:
        for sock in held:
            sock.close()


def test_test_cluster_takes_free_ports(default_ports_taken):
    from distributed import Client

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with local_cluster(1) as cluster, Client(cluster) as client:
            assert client.submit(sum, [1, 2]).result(timeout=60) == 3
            assert urlsplit(cluster.scheduler_address).port not in DASK_DEFAULT_PORTS
            assert urlsplit(cluster.dashboard_link).port not in DASK_DEFAULT_PORTS


def test_sweep_runs_with_the_default_ports_taken(default_ports_taken, tmp_path):
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        path = run_sweep(study, tmp_path / "out", workers=1, progress=False)
    ds = open_archive(path)
    assert np.all(ds["status"].values == STATUS_OK), ds["message"].values
