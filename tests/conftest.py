"""Fixtures shared by the test layers (tests/solver, tests/studies, tests/pipelines)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.clusters import local_cluster


@pytest.fixture(scope="session")
def scheduler() -> Iterator[str]:
    """The address of a local dask cluster of 2 worker processes shared by the session's
    sweeps (loopback, free ports, no dashboard: :func:`tests.clusters.local_cluster`)."""
    with local_cluster(2) as cluster:
        yield cluster.scheduler_address
