"""Dask clusters for the tests: on the loopback, on free ports only.

A test cluster must not take a fixed port. The scheduler always serves HTTP (its dashboard or
at least its health routes) and, given no address, binds dask's default port 8787; when that
port is taken (another cluster, another user) dask warns and moves, and the test suite turns
warnings into errors. So the scheduler, its HTTP server and the workers all bind port 0, and
the workers serve no dashboard.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any


@contextlib.contextmanager
def local_cluster(n_workers: int = 2) -> Iterator[Any]:
    """A ``distributed.LocalCluster`` of ``n_workers`` single-threaded worker processes (the
    solver holds the GIL) on 127.0.0.1, every port chosen by the system."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                      host="127.0.0.1", scheduler_port=0, dashboard_address="127.0.0.1:0",
                      worker_dashboard_address=None) as cluster:
        yield cluster
