"""One case of a model run from a command (``bifilar collar``, ``bifilar pendulum``,
``bifilar fanplot``), the same way a sweep runs each of its cases.

:func:`run_single` validates the parameters through the model's
:class:`~studies.parameters.ModelSpec`, runs the case with :func:`pipelines.worker.run_case` in
this process (the same failure handling as a sweep's case: a model exception, a result that
did not converge or an output that came out NaN makes the case failed) and writes the model's
whole result with :func:`pipelines.archive.write_case` (atomic, CF-encoded, compressed). The
figure modes of the commands run their cases as a sweep (:func:`pipelines.sweep.run_sweep`).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any, NoReturn

import click
import xarray as xr

from pipelines.archive import STATUS_OK
from pipelines.checks import InputError, check_output_dir, check_output_file
from pipelines.studyfile import make_case_id, model_version
from pipelines.worker import run_case
from studies.parameters import ModelSpec, ParameterError

EXIT_FAILED_CASES = 1
EXIT_USER_ERROR = 2


def fail(message: str, status: int = EXIT_USER_ERROR) -> NoReturn:
    """One ``error:`` line on stderr and the exit status (2: bad input), from any command."""
    click.echo(f"error: {' '.join(str(message).split())}", err=True)
    raise click.exceptions.Exit(status)


def check_writable(out: Path | None, figures: Path | None = None) -> None:
    """Refuse an unwritable ``--out`` file or ``--figures`` directory before any run."""
    try:
        if out is not None:
            check_output_file(out, "--out")
        if figures is not None:
            check_output_dir(figures, "--figures")
    except InputError as exc:
        fail(str(exc))


def validated(spec: ModelSpec, given: Mapping[str, Any]) -> dict[str, Any]:
    """The complete, validated parameters, or exit 2 with the line naming the bad one."""
    try:
        return spec.complete(given)
    except ParameterError as exc:
        fail(str(exc))


def run_single(spec: ModelSpec, model_ref: str, given: Mapping[str, Any],
               out: Path) -> xr.Dataset:
    """Validate, run one case of ``spec`` and write its whole result to ``out``.

    Parameters
    ----------
    spec
        The model.
    model_ref
        How a worker finds it again: its registry name or ``"module:attribute"``.
    given
        The parameters given on the command line (defaults fill the rest).
    out
        The netCDF file to write.

    Returns
    -------
    xarray.Dataset
        The result as written (read back from ``out``, variables as the file has them).

    Raises
    ------
    SystemExit
        2 with one line for a bad parameter; 1 with one line naming the failure if the case
        failed (its file then holds the failure record).
    """
    params = validated(spec, given)
    case_id = make_case_id(spec.name, params, model_version(spec))

    def say(line: str) -> None:
        click.echo(line, err=True)

    result = run_case(model_ref, params, str(out), progress=say, case_id=case_id, whole=True)
    if result["status"] != STATUS_OK:
        fail(f"the case failed: {result['message']} (failure record in {out})",
             EXIT_FAILED_CASES)
    # as written: the file's own layout (read_case would turn a "<dim>_label" variable
    # into the names of "<dim>", as it does for the archive's string dimensions)
    with xr.open_dataset(out, engine="netcdf4") as ds:
        return ds.load()


def finish_figure(fig: Any, ax: Any, stem: Path) -> list[Path]:
    """Grid, legend, layout; save as PNG and PDF next to ``stem``; close."""
    import matplotlib.pyplot as plt

    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths = []
    for ext in ("png", "pdf"):
        paths.append(stem.with_suffix(f".{ext}"))
        fig.savefig(paths[-1], dpi=150)
    plt.close(fig)
    return paths


def toml_value(value: Any) -> str:
    """A parameter value as TOML (for the study files the figure modes write)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(value)


def command_line() -> str:
    """This process's command line, for an archive's ``history``."""
    return " ".join([Path(sys.argv[0]).name, *sys.argv[1:]])
