"""The ``bifilar`` command line.

::

    bifilar sweep STUDY.toml --out DIR [--workers N | --scheduler ADDRESS | --cluster slurm|pbs]
                  [--worker-timeout SECONDS] [--retry-failed] [--quiet]
    bifilar plot ARCHIVE --out DIR [--format png --format pdf]
    bifilar run [--out DIR] [--model rotor|hub] [--study table1|envelope|jump|airframe]
                [--workers N | --scheduler ADDRESS | --cluster …]
    bifilar collar --curve circle|cycloid --theta0 DEG --out FILE.nc   (or --figures DIR)
    bifilar pendulum --amplitude DEG --out FILE.nc                    (or --figures DIR)
    bifilar fanplot [--speeds RAD_PER_S ...] --out FILE.nc

A sweep holds the lock file ``DIR/sweep.lock`` while it runs: a second sweep into the same
``DIR`` is refused (a lock left by a process that no longer runs on this host is taken over,
with a line saying so).

Exit status: 0 when every case of the study finished ok; 1 when the sweep finished but some
cases failed or did not run (the archive is still written, and the last line on stderr says how
many and where their messages are); 2 for a problem the user can fix (an invalid study file, a
parameter out of range, a missing file, an unreachable scheduler, an archive with nothing to
plot), reported as one line ``error: ...`` on stderr, never a traceback (a traceback means a
bug); 130 for an interrupted sweep, which resumes when the same command is run again. The
single-model commands exit 1 when their case failed (its file then holds the failure record).
"""

from __future__ import annotations

import contextlib
import shlex
import signal
import sys
from collections.abc import Iterator
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any

import click

from pipelines.archive import ArchiveError, code_version, open_archive, status_counts
from pipelines.checks import (
    InputError,
    check_output_dir,
    check_scheduler_address,
    check_workers,
    max_workers,
)
from pipelines.cluster import SweepError, check_cluster
from pipelines.fanplot_command import fanplot
from pipelines.options import OutPath
from pipelines.progress import printer
from pipelines.single import EXIT_FAILED_CASES, fail
from pipelines.study_commands import collar, pendulum
from pipelines.studyfile import StudyError
from pipelines.sweep import CASES_DIR, run_sweep
from studies.parameters import ParameterError

# The built-in study of each model `bifilar run --model` offers.
BUILT_IN_STUDIES = {"rotor": "rotor_study.toml", "hub": "hub_study.toml"}
# The built-in studies `bifilar run --study` offers: study -> model -> file (a model missing
# from a study's table cannot run it).
STUDIES: dict[str, dict[str, str]] = {
    "table1": BUILT_IN_STUDIES,
    "envelope": {"rotor": "envelope_study.toml"},
    "jump": {"hub": "jump_study.toml"},
    "airframe": {"rotor": "airframe_study.toml"},
}
# Why a built-in study runs on one model only (the error's reason).
ONE_MODEL_ONLY = {"envelope": "the hub model has no trim",
                  "jump": "its branches follow the hub's exact swing equations",
                  "airframe": "the hub model has no airframe or swashplate"}
EXIT_INTERRUPTED = 130

# Errors whose message tells the user what to fix; anything else is a bug and keeps its traceback.
USER_ERRORS = (StudyError, ParameterError, ArchiveError, SweepError, FileNotFoundError,
               InputError)


def default_study(model: str | None = None, study: str = "table1") -> Traversable:
    """A built-in study file.

    Parameters
    ----------
    model
        ``rotor`` or ``hub``; by default the rotor, or the study's only model.
    study
        ``table1`` (default): the paper's Table 1 cases 0–3 and the linear equivalent of case 1;
        ``envelope``: the rotor with propulsive trim over airspeed and rotor speed
        (``studies/envelope_study.toml``, rotor only); ``jump``: the hub's free bifilars
        continued in the 3P excitation, circle, cycloid and epicycloid holes
        (``studies/jump_study.toml``, hub only); ``airframe``: Table 1's cases 0–2 on the
        paper's model and on the modal airframe with a swashplate, and hole shapes
        (``studies/airframe_study.toml``, rotor only).

    Returns
    -------
    importlib.resources.abc.Traversable
        The study file.

    Raises
    ------
    pipelines.checks.InputError
        If ``study`` is unknown or has no file for ``model``.
    """
    if study not in STUDIES:
        raise InputError(f"--study {study}: unknown; valid: {', '.join(STUDIES)}")
    files = STUDIES[study]
    if model is None:
        model = "rotor" if "rotor" in files else next(iter(files))
    if model not in files:
        raise InputError(
            f"--study {study} --model {model}: the {study} study runs on the "
            f"{' or '.join(sorted(files))} model only ({ONE_MODEL_ONLY.get(study, '')}); "
            f"drop --model {model} or use --study table1")
    return resources.files("studies") / files[model]


@contextlib.contextmanager
def _terminate_as_interrupt() -> Iterator[None]:
    """Handle SIGTERM (a batch system's time limit, ``kill``) like Ctrl-C: shut the cluster down
    and write the partial archive instead of dying mid-way."""

    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread (e.g. called from a notebook worker thread)
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def _user_errors() -> Iterator[None]:
    """Turn the errors a user can act on into one ``error:`` line and exit status 2."""
    try:
        yield
    except USER_ERRORS as exc:
        fail(str(exc))
    except KeyboardInterrupt:
        click.echo("error: interrupted; finished cases are kept, run the same command again "
                   "to resume", err=True)
        raise click.exceptions.Exit(EXIT_INTERRUPTED) from None


def _not_ok(archive: Path) -> tuple[dict[str, int], str | None]:
    """Status counts of a finished sweep's archive and, if some case is not ok, the line that
    says how many and where their messages are."""
    counts = status_counts(open_archive(archive))
    bad = counts["failed"] + counts["not_run"]
    if not bad:
        return counts, None
    total = sum(counts.values())
    return counts, (
        f"error: {bad} of {total} case(s) not ok ({counts['failed']} failed, "
        f"{counts['not_run']} not run); their messages are in the 'message' variable of "
        f"{archive} and in {archive.parent / CASES_DIR}/<case_id>.nc (--retry-failed "
        "recomputes failed cases)"
    )


def _exit_if_not_ok(line: str | None) -> None:
    if line is not None:
        click.echo(line, err=True)
        raise click.exceptions.Exit(EXIT_FAILED_CASES)


def _check_cluster(workers: int | None, scheduler: str | None,
                   cluster: str | None = None) -> None:
    if workers is not None and scheduler is not None:
        fail("--workers and --scheduler are mutually exclusive: --workers starts a local "
              "cluster, --scheduler uses a running one")
    if cluster is not None and (workers is not None or scheduler is not None):
        fail("--cluster is exclusive with --workers and --scheduler: it submits its own "
              "worker jobs")
    with _user_errors():
        if cluster is not None:
            check_cluster(cluster)
        if workers is not None:
            check_workers(workers)
        if scheduler is not None:
            check_scheduler_address(scheduler)


def _command_line(ctx: click.Context, *args: str) -> str:
    """The command as the user could type it again, for the archive's ``history``."""
    return f"{ctx.command_path} {shlex.join(args)}"


def _cluster_args(workers: int | None, scheduler: str | None,
                  cluster: str | None = None) -> list[str]:
    if cluster is not None:
        return ["--cluster", cluster]
    if workers is not None:
        return ["--workers", str(workers)]
    if scheduler is not None:
        return ["--scheduler", scheduler]
    return []


workers_option = click.option(
    "--workers", type=click.IntRange(min=1), default=None, metavar="N",
    help=f"Worker processes of a new local dask cluster (default 2; at most {max_workers()}, "
         "4 per CPU core).",
)
scheduler_option = click.option(
    "--scheduler", default=None, metavar="ADDRESS",
    help="Address of a running dask scheduler, e.g. tcp://host:8786 (exclusive with --workers).",
)
cluster_option = click.option(
    "--cluster", type=click.Choice(["slurm", "pbs"]), default=None,
    help="Run the workers as jobs of a SLURM or PBS batch system, with the resources of the "
         "study file's [cluster] table or dask's jobqueue configuration (needs dask-jobqueue: "
         "pip install 'bifilar[cluster]'; exclusive with --workers and --scheduler).",
)
worker_timeout_option = click.option(
    "--worker-timeout", type=click.FloatRange(min=0, min_open=True), default=None,
    metavar="SECONDS",
    help="How long to wait for the first worker of a --scheduler or --cluster that has none, "
         "saying so on stderr; then exit 2 without running anything (default 600).",
)


class OneLineErrors(click.Group):
    """A command group whose usage errors (bad option value, unknown option, missing argument)
    are one ``error:`` line with exit status 2, like every other user error."""

    def main(self, args: Any = None, prog_name: str | None = None,
             complete_var: str | None = None, standalone_mode: bool = True,
             **extra: Any) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.ClickException as exc:
            message = " ".join(exc.format_message().split())
            ctx = getattr(exc, "ctx", None)
            hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
            click.echo(f"error: {message}{hint}", err=True)
            sys.exit(exc.exit_code)
        except click.Abort:
            click.echo("error: interrupted", err=True)
            sys.exit(EXIT_INTERRUPTED)
        sys.exit(rv if isinstance(rv, int) else 0)


@click.group(cls=OneLineErrors, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(code_version(), prog_name="bifilar")
def main() -> None:
    """Bifilar pendulum absorbers: parameter studies, archives and report plots."""


# --- studies and archives ---------------------------------------------------------------------


@main.command()
@click.argument("study", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", required=True, type=OutPath(file_okay=False, path_type=Path),
              help="Output directory: cases/, archive.nc and the lock file sweep.lock.")
@workers_option
@scheduler_option
@cluster_option
@worker_timeout_option
@click.option("--retry-failed", is_flag=True, help="Recompute cases recorded as failed.")
@click.option("--quiet", is_flag=True, help="No progress lines.")
@click.pass_context
def sweep(ctx: click.Context, study: Path, out_dir: Path, workers: int | None,
          scheduler: str | None, cluster: str | None, worker_timeout: float | None,
          retry_failed: bool, quiet: bool) -> None:
    """Run every case of STUDY (a TOML study file) and write DIR/archive.nc.

    The study's model is a registry name (model = "hub") or a plug-in given as
    model = "package.module:SPEC". Cases already in DIR/cases are not recomputed, so an
    interrupted sweep resumes when run again. Prints the archive path. Exit status 0 if every
    case is ok, 1 if some failed or did not run, 2 for bad input.
    """
    _check_cluster(workers, scheduler, cluster)
    command = _command_line(ctx, str(study), "--out", str(out_dir),
                            *_cluster_args(workers, scheduler, cluster),
                            *(["--retry-failed"] if retry_failed else []))
    with _user_errors(), _terminate_as_interrupt():
        archive = run_sweep(study, out_dir, workers=workers, scheduler=scheduler,
                            progress=not quiet, retry_failed=retry_failed, command=command,
                            worker_timeout=worker_timeout, cluster=cluster)
        _, not_ok = _not_ok(archive)
    click.echo(str(archive))
    _exit_if_not_ok(not_ok)


@main.command()
@click.argument("archive", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", required=True, type=OutPath(file_okay=False, path_type=Path),
              help="Directory for the figures.")
@click.option("--format", "formats", multiple=True, type=click.Choice(["png", "pdf", "svg"]),
              default=("png", "pdf"), show_default=True, help="File format (repeatable).")
def plot(archive: Path, out_dir: Path, formats: tuple[str, ...]) -> None:
    """Write the report figures of ARCHIVE into DIR; prints their paths.

    Exit status 2 with one error line if ARCHIVE is not a sweep archive or no case in it
    finished ok.
    """
    from pipelines.plots import plot_archive  # matplotlib only when plotting

    with _user_errors():
        check_output_dir(out_dir)
        paths = plot_archive(archive, out_dir, formats=formats)
    for path in paths:
        click.echo(str(path))


@main.command()
@click.option("--out", "out_dir", default=Path("results"), show_default=True,
              type=OutPath(file_okay=False, path_type=Path),
              help="Output directory: cases/, archive.nc and plots/.")
@click.option("--model", "model", default=None, show_default="rotor, or the study's only "
              "model", type=click.Choice(sorted(BUILT_IN_STUDIES)),
              help="rotor: the paper's UH-60 rotor with elastic blades and aerodynamics; "
                   "hub: a rigid hub with assumed 3P/5P blade shears (faster). The README "
                   "gives the times.")
@click.option("--study", "study_name", default="table1", show_default=True,
              type=click.Choice(list(STUDIES)),
              help="table1: the paper's Table 1 cases 0-3 and the linear equivalent of case 1; "
                   "envelope: the rotor with propulsive trim at 40-160 kt and at 95-105 % "
                   "rotor speed, bifilars locked, free and equivalent (rotor model only; "
                   "studies/envelope_study.toml, 33 cases); jump: the hub's free bifilars "
                   "continued in the 3P excitation with their stability and backbones, "
                   "circle, cycloid and epicycloid holes (hub model only; "
                   "studies/jump_study.toml); airframe: Table 1's cases 0-2 on the paper's "
                   "model and on the UH-60A-class modal airframe with a swashplate, and hole "
                   "shapes (rotor model only; studies/airframe_study.toml, 14 cases).")
@workers_option
@scheduler_option
@cluster_option
@worker_timeout_option
@click.pass_context
def run(ctx: click.Context, out_dir: Path, model: str | None, study_name: str,
        workers: int | None,
        scheduler: str | None, cluster: str | None, worker_timeout: float | None) -> None:
    """Run a built-in study and plot it into DIR/plots: the paper's Table 1 (cases 0-3, and
    the linear equivalent of case 1) on the rotor (default) or the hub model, or with
    --study envelope the rotor's flight envelope with propulsive trim, with --study airframe
    Table 1 on a modal airframe with a swashplate.

    Exit status 0 if every case is ok, 1 if some failed (the ok ones are still plotted).
    """
    from pipelines.plots import plot_archive

    _check_cluster(workers, scheduler, cluster)
    with _user_errors():
        study_file = default_study(model, study_name)
    command = _command_line(ctx, "--out", str(out_dir), *(("--model", model) if model else ()),
                            "--study", study_name, *_cluster_args(workers, scheduler, cluster))
    with _user_errors():
        check_output_dir(out_dir)
        check_output_dir(out_dir / "plots", "--out")
    with _user_errors(), _terminate_as_interrupt(), \
            resources.as_file(study_file) as study:
        archive = run_sweep(study, out_dir, workers=workers, scheduler=scheduler,
                            command=command, worker_timeout=worker_timeout, cluster=cluster)
        counts, not_ok = _not_ok(archive)
        paths = plot_archive(archive, out_dir / "plots") if counts["ok"] else []
    click.echo(str(archive))
    for path in paths:
        click.echo(str(path))
    _exit_if_not_ok(not_ok)


@main.command("compile")
@click.option("--model", "models", multiple=True, metavar="NAME",
              help="A model whose kernels to compile (repeatable; default: every built-in "
                   "model with a warm-up: hub, pendulum, rotor).")
@click.option("--processes", type=click.IntRange(min=1), default=2, show_default=True,
              help="Processes compiling at the same time (numba compiles in one thread).")
def compile_(models: tuple[str, ...], processes: int) -> None:
    """Compile the solver's kernels into numba's cache now rather than in the first run.

    A first `bifilar run` or `bifilar sweep` does this itself before its cases; this command
    is for an installation whose workers run elsewhere (batch jobs sharing the file system) or
    should not wait. Prints where the kernels are cached; does nothing when they are already.
    """
    from pipelines.kernels import warm_up_locally
    from studies.registry import available, resolve_model

    with _user_errors():
        names = list(models) or [m for m in available() if resolve_model(m).warm_up]
        for name in names:
            resolve_model(name)  # an unknown model is one error line before anything runs
        results = warm_up_locally(names, printer(), processes)
    if any(r["error"] for r in results):
        raise click.exceptions.Exit(EXIT_FAILED_CASES)


# --- single-model commands ----------------------------------------------------------------------
# The validation studies: `bifilar collar` (paper Figs. 10-12) and `bifilar pendulum` (Eq. 7).
main.add_command(collar)
main.add_command(pendulum)
main.add_command(fanplot)


# --- end of single-model commands ---------------------------------------------------------------


if __name__ == "__main__":
    main()
