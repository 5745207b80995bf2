"""Parameter studies: a study file's cases run on dask, one archive at the end.

:func:`run_sweep` validates the study file (:mod:`pipelines.studyfile`), checks the output
directory and takes its lock (:mod:`pipelines.lock`), runs every case without a case file as
:func:`pipelines.worker.run_case` on a dask cluster (:mod:`pipelines.cluster`), printing one
line per finished case and the models' progress lines (:mod:`pipelines.progress`), and
consolidates the case files into ``archive.nc`` (:mod:`pipelines.archive`).

Each case writes ``cases/<case_id>.nc`` atomically, so running the same command again after an
interruption computes only the cases without a file.
"""
from __future__ import annotations

import contextlib
import os
import shlex
import sys
import traceback
from collections.abc import Callable
from concurrent.futures import CancelledError
from pathlib import Path
from typing import Any

import xarray as xr

from pipelines.archive import (
    STATUS_FAILED,
    STATUS_OK,
    CaseEntry,
    consolidate,
    global_attrs,
    stale_temporaries,
    write_case,
)
from pipelines.checks import (
    InputError,
    check_output_dir,
    check_scheduler_address,
    check_target_file,
    check_workers,
)
from pipelines.cluster import (
    DEFAULT_WORKERS,
    MALLOC_ENVIRON,
    WORKER_TIMEOUT,
    SweepError,
    check_cluster,
    connect,
    dashboard_works,
    wait_for_workers,
)
from pipelines.kernels import warm_up_workers
from pipelines.lock import sweep_lock
from pipelines.progress import finished_line, forward, new_topic, printer
from pipelines.studyfile import (
    MAX_CASES,
    Case,
    CrossChecks,
    Study,
    StudyError,
    load_study,
    make_case_id,
    model_version,
)
from pipelines.worker import ModelFailure, compile_notice, failure_case, one_line, run_case
from studies.registry import resolve_model

# Names importable from here for scripts written against the single sweep module.
__all__ = [
    "ARCHIVE_NAME", "CASES_DIR", "DEFAULT_WORKERS", "MALLOC_ENVIRON", "MAX_CASES", "Case",
    "CrossChecks", "ModelFailure", "Study", "StudyError", "SweepError", "compile_notice",
    "consolidate_study", "load_study", "make_case_id", "model_version", "resolve_model",
    "run_case", "run_sweep",
]

CASES_DIR = "cases"
ARCHIVE_NAME = "archive.nc"


def _case_done(path: Path, retry_failed: bool) -> bool:
    if not path.exists():
        return False
    if not retry_failed:
        return True
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return int(ds.attrs.get("status", STATUS_FAILED)) == STATUS_OK
    except (OSError, ValueError):
        return False  # unreadable: compute it again



def run_sweep(
    study_path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    *,
    retry_failed: bool = False,
    command: str | None = None,
    worker_timeout: float | None = None,
    cluster: str | None = None,
) -> Path:
    """Run every case of a study on dask and consolidate the results into one archive.

    Parameters
    ----------
    study_path
        TOML study file, validated completely before any case starts.
    out_dir
        Output directory: case files go to ``out_dir/cases/<case_id>.nc``, the archive to
        ``out_dir/archive.nc``. Cases whose file already exists are not recomputed (resume).
    workers
        Worker processes of the local cluster (default 2). Exclusive with ``scheduler``.
    scheduler
        Address of a running dask scheduler, e.g. ``"tcp://host:8786"``; its workers must be
        able to import the project and the model.
    progress
        Print one line per finished case to stderr: ``[k/N] case <label> ok (12.3 s)``.
    retry_failed
        Also recompute cases whose existing file records a failure.
    command
        Command line recorded in the archive's ``history`` and in the lock file (default:
        ``sys.argv``).
    cluster
        ``"slurm"`` or ``"pbs"``: run the workers as jobs of that batch system, with the
        resources of the study file's ``[cluster]`` table (:mod:`pipelines.cluster`; needs
        dask-jobqueue). Exclusive with ``workers`` and ``scheduler``.
    worker_timeout
        Seconds to wait for the first worker of a ``scheduler`` or ``cluster`` that has none
        (default :data:`pipelines.cluster.WORKER_TIMEOUT`); the wait is announced on stderr.

    Returns
    -------
    pathlib.Path
        The consolidated archive.

    Raises
    ------
    StudyError
        If the study file is invalid (nothing has run).
    SweepError
        If the dask scheduler cannot be reached.
    pipelines.checks.InputError
        If the output directory cannot be written, its ``archive.nc`` is not a file, another
        sweep holds its lock (:mod:`pipelines.lock`), the number of workers is outside
        1 to :func:`pipelines.checks.max_workers` or the scheduler address is malformed
        (nothing has run).
    """
    if sum(x is not None for x in (workers, scheduler, cluster)) > 1:
        raise InputError("--workers, --scheduler and --cluster are mutually exclusive: give "
                         "one of them")
    if cluster is not None:
        check_cluster(cluster)
    if workers is not None:
        check_workers(workers)
    if scheduler is not None:
        check_scheduler_address(scheduler)
    if worker_timeout is not None and not worker_timeout > 0:
        raise InputError(f"--worker-timeout {worker_timeout:g}: must be > 0 seconds")
    study = load_study(study_path)
    out_dir = check_output_dir(out_dir)
    cases_dir = check_output_dir(out_dir / CASES_DIR, "--out")
    check_target_file(out_dir / ARCHIVE_NAME)
    if command is None:
        command = shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]])

    say = printer(progress)
    with sweep_lock(out_dir, command, say):
        return _sweep(study, out_dir, cases_dir, workers, scheduler, retry_failed, command,
                      worker_timeout, say, cluster)


def _sweep(study: Study, out_dir: Path, cases_dir: Path, workers: int | None,
           scheduler: str | None, retry_failed: bool, command: str,
           worker_timeout: float | None, say: Callable[[str], None],
           cluster: str | None = None) -> Path:
    total = len(study.cases)
    todo = [c for c in study.cases if not _case_done(c.path(cases_dir), retry_failed)]
    finished = total - len(todo)
    if finished:
        say(f"resuming: {finished} of {total} case(s) already finished in {cases_dir}, "
            "not recomputed")
    interrupted = False
    if todo:
        for case in todo:
            # Left by a writer killed mid-write; this case is about to be rewritten anyway.
            for tmp in stale_temporaries(cases_dir, case.case_id, all_writers=True):
                tmp.unlink(missing_ok=True)
        try:
            _run_cases(study, todo, cases_dir, workers, scheduler, finished, total, say,
                       worker_timeout, cluster=cluster)
        except KeyboardInterrupt:
            interrupted = True

    archive = consolidate_study(study, out_dir, command=command)
    if interrupted:
        # A partial archive (unfinished cases flagged not_run) is worth having after a batch
        # system's time limit; the case files make the next run resume.
        say(f"interrupted: partial archive {archive} (unfinished cases have status not_run); "
            f"finished cases are kept in {cases_dir}, run the same command again to resume")
        raise KeyboardInterrupt
    say(f"archive written: {archive}")
    return archive


def consolidate_study(study: Study | str | os.PathLike[str], out_dir: str | os.PathLike[str],
                      command: str | None = None) -> Path:
    """Write ``out_dir/archive.nc`` from the case files present now; run nothing.

    Cases without a file get status ``not_run``: this shows the partial results of a sweep that
    is still running or was interrupted.

    Parameters
    ----------
    study
        A validated :class:`Study` or the path of its file.
    out_dir
        The sweep's output directory (holding ``cases/``).
    command
        Command line recorded in the archive's ``history`` (default: ``sys.argv``).

    Returns
    -------
    pathlib.Path
        The archive.
    """
    if not isinstance(study, Study):
        study = load_study(study)
    out_dir = Path(out_dir)
    if command is None:
        command = shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]])
    coords, constants = study.archive_coords()
    return consolidate(
        out_dir / ARCHIVE_NAME,
        dims=study.dims(),
        coords=coords,
        cases=[CaseEntry(c.index, c.case_id, c.path(out_dir / CASES_DIR)) for c in study.cases],
        constants=constants,
        attrs=global_attrs(title=study.title, model=study.model_ref, study_text=study.text,
                           command=command),
    )


def _run_cases(study: Study, todo: list[Case], cases_dir: Path, workers: int | None,
               scheduler: str | None, finished: int, total: int, say: Any,
               worker_timeout: float | None = None, *, cluster: str | None = None) -> None:
    from distributed import as_completed

    with connect(workers, scheduler, cluster, study.cluster) as client:
        if scheduler is not None or cluster is not None:
            wait_for_workers(client, scheduler or client.scheduler.address,
                             worker_timeout or WORKER_TIMEOUT, say, batch=cluster)
        info = client.scheduler_info()
        dashboard = dashboard_works(client, info)
        say(f"running {len(todo)} case(s) of {study.path} on {len(info.get('workers', {}))} "
            "dask worker(s)" + (f"; dashboard {client.dashboard_link}" if dashboard else ""))
        # every worker would otherwise compile the same kernels in its first case
        warm_up_workers(client, study.model_ref, say)
        topic = new_topic()
        client.subscribe_topic(topic, forward(say, {c.case_id: c.label for c in todo}))
        paths = [str(c.path(cases_dir)) for c in todo]
        futures = client.map(
            run_case,
            [study.model_ref] * len(todo),
            [c.params for c in todo],
            paths,
            progress_topic=topic,
            continuation=study.continuation_dict,
            key=[f"bifilar-case-{c.case_id}" for c in todo],
            pure=False,
        )
        by_key = {f.key: c for f, c in zip(futures, todo, strict=True)}
        for future in as_completed(futures):
            case = by_key[future.key]
            try:
                result = future.result()
            except CancelledError:
                # Lost with the scheduler, not the case's fault: leave it without a file, so it
                # is archived as not_run and computed by the next run.
                future.release()
                finished += 1
                say(f"[{finished}/{total}] case {case.label} cancelled (not run)")
                continue
            except Exception as exc:
                # The worker itself died (KilledWorker) or the file could not be written: the
                # case is recorded as failed here so the archive says why.
                result = {"status": STATUS_FAILED, "message": one_line(exc),
                          "wall_time": float("nan")}
                with contextlib.suppress(OSError):
                    write_case(failure_case(case.case_id, study.model_ref, case.params,
                                             result["message"], float("nan"),
                                             traceback.format_exc()),
                               case.path(cases_dir))
            future.release()
            finished += 1
            say(finished_line(finished, total, case.label, result,
                              result["status"] == STATUS_OK))


if __name__ == "__main__":
    # ``python -m pipelines.sweep STUDY --out DIR [--workers N | --scheduler ADDRESS]``
    from pipelines.cli import main

    main(["sweep", *sys.argv[1:]], prog_name="bifilar")

