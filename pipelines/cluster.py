"""The dask cluster a sweep runs on: a new local cluster of worker processes, a running
scheduler given by its address, or worker jobs on a SLURM or PBS batch system.

Batch systems (``--cluster slurm|pbs``) go through dask-jobqueue, an optional extra
(``pip install "bifilar[cluster]"``). The sweep starts the scheduler in its own process and
submits ``jobs`` worker jobs with the resources of the study file's ``[cluster]`` table::

    [cluster]
    cores = 8              # per job: one single-threaded worker process per core
    memory = "16GB"        # per job
    walltime = "02:00:00"
    queue = "short"
    account = "rotorlab"
    jobs = 4               # worker jobs to submit (default 1)

Any resource left out comes from dask's configuration (``jobqueue.slurm.cores`` … in
``~/.config/dask/jobqueue.yaml``), as dask-jobqueue documents. The jobs start with the same
Python as the sweep, so the project must be installed where the jobs run.

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

from pipelines.checks import InputError
from pipelines.worker import one_line

# Batch systems of --cluster: the dask-jobqueue class of each.
JOBQUEUE_CLUSTERS = {"slurm": "SLURMCluster", "pbs": "PBSCluster"}

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



def check_cluster(kind: str) -> str:
    """Check ``--cluster`` before any work: a known batch system, dask-jobqueue installed.

    Raises
    ------
    pipelines.checks.InputError
        If ``kind`` is not one of :data:`JOBQUEUE_CLUSTERS` or dask-jobqueue is missing.
    """
    if kind not in JOBQUEUE_CLUSTERS:
        raise InputError(f"--cluster {kind!r}: one of {', '.join(JOBQUEUE_CLUSTERS)}")
    if importlib.util.find_spec("dask_jobqueue") is None:
        raise InputError(f"--cluster {kind} needs dask-jobqueue, which is not installed: "
                         "pip install 'bifilar[cluster]' (or pip install dask-jobqueue)")
    return kind


def jobqueue_cluster(kind: str, resources: Mapping[str, Any], **options: Any) -> Any:
    """A dask-jobqueue cluster of ``kind`` with the study's ``[cluster]`` resources; no job is
    submitted until it is scaled.

    Parameters
    ----------
    kind
        ``"slurm"`` or ``"pbs"``.
    resources
        The ``[cluster]`` table (``cores``, ``memory``, ``walltime``, ``queue``, ``account``;
        ``jobs`` is for :func:`connect`); what is missing comes from dask's configuration.
    options
        Further keyword arguments of the dask-jobqueue class (e.g. ``scheduler_options``).

    Raises
    ------
    pipelines.checks.InputError
        If dask-jobqueue is not installed, or cores and memory are given neither in the study
        file nor in dask's configuration.
    """
    check_cluster(kind)
    import dask_jobqueue
    given = {k: v for k, v in resources.items() if k != "jobs"}
    if "cores" in given:
        # one single-threaded worker process per core: the solver holds the GIL
        given["processes"] = given["cores"]
    prologue = [f"export {k}={v}" for k, v in MALLOC_ENVIRON.items()]
    try:
        return getattr(dask_jobqueue, JOBQUEUE_CLUSTERS[kind])(
            job_script_prologue=prologue, **given, **options)
    except ValueError as exc:
        raise InputError(f"--cluster {kind}: {one_line(exc)}; give cores and memory in the "
                         "study file's [cluster] table or in dask's jobqueue configuration"
                         ) from None


@contextlib.contextmanager
def connect(workers: int | None, scheduler: str | None, cluster: str | None = None,
            resources: Mapping[str, Any] | None = None) -> Iterator[Any]:
    """A dask client: on an existing scheduler, on worker jobs of a batch system
    (``cluster``, with the study's ``[cluster]`` ``resources``), or on a new local cluster of
    processes."""
    # Imported here: ``bifilar plot`` and study validation need no dask.
    from distributed import Client, LocalCluster

    if cluster is not None:
        resources = dict(resources or {})
        with jobqueue_cluster(cluster, resources,
                              scheduler_options={"dashboard_address": ":0"}) as jobs, \
                Client(jobs) as client:
            jobs.scale(jobs=int(resources.get("jobs", 1)))
            yield client
        return
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


def wait_for_workers(client: Any, scheduler: str, timeout: float, say: Any,
                     batch: str | None = None) -> None:
    """Wait for the first worker of a scheduler that has none, saying so; SweepError after
    ``timeout`` seconds. ``batch`` names the batch system whose jobs bring the workers."""
    if client.scheduler_info().get("workers"):
        return
    if batch is not None:
        say(f"waiting up to {timeout:g} s for the {batch} worker jobs to start "
            "(--worker-timeout changes the wait)")
        try:
            client.wait_for_workers(1, timeout=timeout)
        except (TimeoutError, OSError) as exc:
            raise SweepError(
                f"no {batch} worker job started within {timeout:g} s (see the batch queue, "
                "e.g. squeue or qstat); give a longer --worker-timeout; nothing was run"
            ) from exc
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


