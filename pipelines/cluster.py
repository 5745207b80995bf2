"""The dask cluster a sweep runs on: a new local cluster of worker processes, or a running
scheduler given by its address.

A scheduler without workers (workers still queued on a batch system, or not started) is
announced on stderr and waited for up to ``--worker-timeout`` seconds (default
:data:`WORKER_TIMEOUT`); then the sweep stops with exit status 2 and runs nothing.
"""
from __future__ import annotations

import contextlib
import importlib
import importlib.util
from collections.abc import Iterator, Mapping
from typing import Any

import dask.config

from pipelines.worker import one_line

DEFAULT_WORKERS = 2

# Seconds to wait for a --scheduler to answer.
CONNECT_TIMEOUT = 30
# Seconds to wait for the first worker of a scheduler that has none (e.g. workers still queued
# on a batch system); --worker-timeout overrides it.
WORKER_TIMEOUT = 600.0
# glibc's malloc thresholds of the local cluster's worker processes (bytes), set before they
# start. Dask's default MALLOC_TRIM_THRESHOLD_ = 65536 returns freed memory to the system at
# once, and setting any threshold also fixes the mmap threshold at 128 KiB: the solver's
# per-step arrays of a few hundred kilobytes then fault their pages in again at every step.
# Measured on the rotor benchmark (benchmarks/rotor.py --revolutions 2): with dask's setting
# 9.0 s per revolution, 7 s of system time, 2.1 million page faults; with these 4.7–4.9 s,
# 0.4–0.5 s, 60 000, like glibc's adaptive defaults (no variable set: 4.5–5.5 s, 0.5 s,
# 84 000). A case's peak memory is under 1 GB.
MALLOC_ENVIRON = {"MALLOC_MMAP_THRESHOLD_": 32 * 2**20, "MALLOC_TRIM_THRESHOLD_": 256 * 2**20}
WORKER_ENVIRON = {f"distributed.nanny.pre-spawn-environ.{k}": v
                  for k, v in MALLOC_ENVIRON.items()}


class SweepError(RuntimeError):
    """The sweep could not run (e.g. no connection to the dask scheduler)."""



@contextlib.contextmanager
def connect(workers: int | None, scheduler: str | None) -> Iterator[Any]:
    """A dask client: on an existing scheduler, or on a new local cluster of processes."""
    # Imported here: ``bifilar plot`` and study validation need no dask.
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as exc:
            raise SweepError(f"cannot connect to the dask scheduler at {scheduler}: "
                             f"{one_line(exc)}") from exc
        with client:
            yield client
        return
    # One thread per worker process: the solver holds the GIL, so processes give the
    # parallelism. Port 0 for the dashboard so that two sweeps on one machine do not collide.
    # The workers start with malloc thresholds that suit the solver (MALLOC_ENVIRON).
    with (
        dask.config.set(WORKER_ENVIRON),
        LocalCluster(n_workers=workers or DEFAULT_WORKERS, threads_per_worker=1, processes=True,
                     dashboard_address=":0") as cluster,
        Client(cluster) as client,
    ):
        yield client


def dashboard_works(client: Any, info: Mapping[str, Any]) -> bool:
    """Whether the scheduler serves a real dashboard (it needs bokeh in the scheduler's
    environment; without it the link leads to a page asking for bokeh)."""
    if "dashboard" not in info.get("services", {}):
        return False
    try:
        return bool(client.run_on_scheduler(_has_bokeh))
    except Exception:  # an old or restricted scheduler: do not advertise what may not work
        return False


def _has_bokeh() -> bool:
    return importlib.util.find_spec("bokeh") is not None


def wait_for_workers(client: Any, scheduler: str, timeout: float, say: Any) -> None:
    """Wait for the first worker of a scheduler that has none, saying so; SweepError after
    ``timeout`` seconds."""
    if client.scheduler_info().get("workers"):
        return
    say(f"the dask scheduler at {scheduler} has no workers yet; waiting up to {timeout:g} s "
        f"for one (start them with: dask worker {scheduler}; --worker-timeout changes the wait)")
    try:
        client.wait_for_workers(1, timeout=timeout)
    except (TimeoutError, OSError) as exc:
        raise SweepError(
            f"no dask worker joined the scheduler at {scheduler} within {timeout:g} s; start "
            f"workers with 'dask worker {scheduler}' (they must be able to import bifilar and "
            "the model) or give a longer --worker-timeout; nothing was run") from exc


