"""The task of one case: run the model, check its result, write its case file.

:func:`run_case` runs on a dask worker in a sweep, and in the command's own process for the
single-model commands (``bifilar collar``, ``bifilar pendulum``, ``bifilar fanplot``). It never
raises for a bad case: a model exception, a result marked failed or not converged, or an
archived output that came out NaN is recorded as a failed case with its message, so one bad
case does not stop an overnight sweep.

While a case runs, the model's progress lines (:func:`studies.progress.report`: the hub reports
each revolution and its periodicity change) travel from the worker to the sweep's client as
dask events, and a cold numba cache is announced before the kernels compile
(:func:`compile_notice`).

A case of a study with a ``[continuation]`` table is one branch: the model's ``branch``
function runs instead of its ``simulate``, and the case file holds every point of the branch
(:func:`pipelines.archive.branch_summary`).
"""
from __future__ import annotations

import contextlib
import json
import math
import time
import traceback
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from pipelines.archive import (
    CONVENTIONS,
    STATUS_FAILED,
    STATUS_OK,
    branch_summary,
    case_summary,
    write_case,
)
from pipelines.studyfile import model_version
from studies.branches import BranchResult, Continuation
from studies.parameters import ModelSpec
from studies.progress import reporting
from studies.registry import resolve_model

# Least time between two forwarded progress lines of one case (s); the first always goes.
PROGRESS_INTERVAL = 10.0
# Wall-clock seconds numba takes to compile the rotor model's kernels (most of the solver's)
# into its cache on a first run, its two warm-up parts on two workers at once
# (pipelines.kernels; benchmarks/first_run.py: 22.8 s at best on a 2-core machine, 28 s in
# one process; 30-35 s inside `bifilar run` with another job beside it, which can make it
# several times longer).
COMPILE_SECONDS = 25


class ModelFailure(RuntimeError):
    """The model returned a result marked ``status = "failed"`` or ``converged = 0``."""



def one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def failure_case(case_id: str, model: str, params: Mapping[str, Any], message: str,
                  wall_time: float, tb: str = "") -> xr.Dataset:
    return xr.Dataset(attrs={
        "Conventions": CONVENTIONS, "case_id": case_id, "model": model,
        "parameters": json.dumps(dict(params), sort_keys=True),
        "status": np.int8(STATUS_FAILED), "message": message, "wall_time": wall_time,
        "traceback": tb,
    })


def _progress_listener(topic: str, case_id: str) -> Any:
    """A :func:`studies.progress.report` listener that forwards lines to the sweep's client as
    dask events (at most one per :data:`PROGRESS_INTERVAL` seconds; the first always, and
    every line sent with ``urgent=True``), or ``None`` outside a dask worker."""
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):
        return None
    last = -math.inf

    def listen(message: str, urgent: bool = False) -> None:
        nonlocal last
        now = time.monotonic()
        if urgent or now - last >= PROGRESS_INTERVAL:
            last = now
            worker.log_event(topic, {"case_id": case_id, "message": message})

    return listen


@contextlib.contextmanager
def compile_notice(say: Any, message: str | None = None) -> Iterator[None]:
    """Say once that numba is compiling kernels, when it starts to (its cache is cold).

    numba raises its ``numba:compile`` event only for a kernel it does not find in its cache
    (``__pycache__`` beside the solver's modules, :mod:`pipelines.kernels`), so the line
    appears on a first run, after an upgrade, or in a fresh environment, and never when the
    kernels load from the cache. A sweep compiles the model's kernels before its cases
    (:func:`pipelines.kernels.warm_up_workers`), so a case says it only for kernels the
    model's warm-up does not call, or for a model without one.

    Parameters
    ----------
    say
        Receives the line.
    message
        The line (default: that kernels are being compiled, and that it happens once).
    """
    try:
        from numba.core import event
    except ImportError:  # a plug-in model's environment without numba compiles nothing
        yield
        return
    told = False

    class Notice(event.Listener):
        def on_start(self, ev: Any) -> None:
            nonlocal told
            if not told:
                told = True
                say(message or "compiling kernels (first run only; numba caches them for "
                    "the next runs)...")

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", Notice()):
        yield


def nan_outputs(summary: xr.Dataset) -> list[str]:
    """The archived outputs of a case summary that hold NaN (a result the model could not
    determine, e.g. a period from a record shorter than two periods).

    A direction along which a variable is NaN throughout, while it has values along
    another, is a component it does not have (an in-plane vector's z beside the x, y, z of a
    model's stations), not a failure."""
    return [name for name, var in summary.data_vars.items()
            if var.dtype.kind == "f" and bool(np.isnan(_held(var).values).any())]


def _held(var: xr.DataArray) -> xr.DataArray:
    """``var`` without the directions along which it is NaN throughout, unless it is NaN
    everywhere."""
    if "direction" not in var.dims or var.sizes["direction"] < 2:
        return var
    held = var.notnull().any([d for d in var.dims if d != "direction"])
    return var.isel(direction=held.values) if bool(held.any()) else var


def _check_result(result: xr.Dataset) -> None:
    """Raise :class:`ModelFailure` for a result the model marked failed or not converged."""
    reported = str(result.attrs.get("status", "ok")).lower()
    if reported in ("failed", str(STATUS_FAILED)):
        raise ModelFailure(str(result.attrs.get("message", "model reported failure")))
    if "run_converged" in result and not int(result["run_converged"]):
        raise ModelFailure("simulation did not converge: "
                           + str(result.attrs.get("message", "no message")))


def _check_summary(summary: xr.Dataset, where: str = "") -> None:
    """Raise :class:`ModelFailure` if an archived output of a summary came out NaN."""
    nan = nan_outputs(summary)
    if nan:
        raise ModelFailure(
            f"output(s) {', '.join(nan)}{where} came out NaN (not a number): the model could "
            "not determine them from this run (e.g. a record too short to measure a period, "
            "or no motion to measure)")


def run_branch(spec: ModelSpec, params: Mapping[str, Any],
               continuation: Mapping[str, Any]) -> tuple[xr.Dataset, str]:
    """One branch case: the model's ``branch`` and what the archive keeps of it.

    Parameters
    ----------
    spec
        The model (its ``branch`` is set; :func:`pipelines.studyfile.load_study` checked).
    params
        Complete parameters of the case, the continued one at ``start``.
    continuation
        The study's validated ``[continuation]`` settings (:meth:`Continuation.as_dict`).

    Returns
    -------
    tuple
        :func:`pipelines.archive.branch_summary` of the branch, and the case's message: the
        notes of its points' results (e.g. why the branch ended before ``stop``), each once.

    Raises
    ------
    ModelFailure
        If the branch has no points, a point's result is marked failed or not converged, or
        an archived output of a point came out NaN.
    """
    settings = Continuation(**continuation)
    found = spec.branch(spec.trusted(params), settings)
    extras = found.extras if isinstance(found, BranchResult) else xr.Dataset()
    points = found.points if isinstance(found, BranchResult) else found
    if not points:
        raise ModelFailure(f"the branch in {settings.parameter} from {settings.start:g} has "
                           "no points")
    notes: list[str] = []
    summaries = []
    for k, point in enumerate(points):
        _check_result(point.result)
        summaries.append(case_summary(point.result, spec))
        _check_summary(summaries[-1], f" at point {k} ({settings.parameter} = {point.value:g})")
        note = str(point.result.attrs.get("message", "")).strip()
        if note and note not in notes:
            notes.append(note)
    summary = branch_summary(points, spec, settings.parameter, summaries=summaries)
    return summary.merge(extras), "; ".join(notes)


def _urgent(listener: Any, line: str) -> None:
    try:
        listener(line, urgent=True)
    except TypeError:  # a plain callable of one line
        listener(line)


def run_case(model_name: str, params: Mapping[str, Any], case_file: str,
             progress_topic: str | None = None,
             progress: Callable[[str], None] | None = None, *, case_id: str | None = None,
             whole: bool = False,
             continuation: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Run one case and write its case file atomically; the dask task of a sweep.

    Any exception of the model (or a result with ``attrs["status"] == "failed"`` or
    ``run_converged == 0``, a simulation that stopped early, or an archived output that came
    out NaN, named in the message) is caught and recorded as a failed case with its message:
    one bad case must not stop an overnight sweep. What the case file keeps is what the
    model's outputs declare (:func:`pipelines.archive.case_summary`), or with ``whole`` the
    model's whole result. Only a small summary travels back to the client; the data stay in
    the file.

    Parameters
    ----------
    model_name
        Registry name or ``"module:attribute"`` (resolved in the worker process).
    params
        Complete parameters of the case.
    case_file
        Path of the case file to write, ``<out>/cases/<case_id>.nc``.
    progress_topic
        Dask event topic to which the model's progress lines are sent (on a dask worker).
    progress
        Receives the progress lines instead, outside dask (the single-model commands).
    case_id
        The case's id (default: the case file's stem, ``<case_id>.nc`` in a sweep).
    whole
        Write the model's whole result, every variable and its global attributes, instead of
        what the sweep archive keeps of it (the single-model commands' output files).
    continuation
        The study's validated ``[continuation]`` settings: the case is one branch
        (:func:`run_branch`; its points' notes become the case's message), ``whole`` does not
        apply. ``None``: one response.

    Returns
    -------
    dict
        ``case_id``, ``status`` (0 ok, 1 failed), ``message`` (the failure; for an ok case the
        model's note, usually ``""``) and ``wall_time`` (s).
    """
    start = time.perf_counter()
    case_id = case_id or Path(case_file).stem
    status, message, tb = STATUS_OK, "", ""
    summary = xr.Dataset()
    model_attrs: dict[str, Any] = {}
    version = ""
    listener = _progress_listener(progress_topic, case_id) if progress_topic else None
    if listener is not None:
        listener(f"started on {_worker_name()}")
    elif progress is not None:
        listener = progress
    try:
        with contextlib.ExitStack() as stack:
            if listener is not None:
                stack.enter_context(reporting(listener))
                stack.enter_context(compile_notice(lambda line: _urgent(listener, line)))
            spec = resolve_model(model_name)
            version = model_version(spec)
            if continuation is not None:
                summary, message = run_branch(spec, params, continuation)
            else:
                # validated by load_study (or the command) already: the model takes them as
                # given
                result = spec.run(params)
        if continuation is None:
            _check_result(result)
            summary = case_summary(result, spec)
            _check_summary(summary)
            # an ok case may carry the model's note (e.g. that shooting fell back to marching)
            message = str(result.attrs.get("message", ""))
        if whole and continuation is None:
            summary = result
            # netCDF has no booleans: the model's flags (converged, …) are kept as 0/1
            model_attrs = {k: int(v) if isinstance(v, bool) else v
                           for k, v in result.attrs.items() if v is not None}
    except Exception as exc:
        status, message, tb = STATUS_FAILED, one_line(exc), traceback.format_exc()
        summary, model_attrs = xr.Dataset(), {}
    wall_time = time.perf_counter() - start
    summary.attrs = {
        **model_attrs,
        "Conventions": CONVENTIONS, "case_id": case_id, "model": model_name,
        "model_version": version,
        "parameters": json.dumps(dict(params), sort_keys=True),
        "status": np.int8(status), "message": message, "wall_time": wall_time, "traceback": tb,
    }
    try:
        write_case(summary, case_file)
    except Exception as exc:
        if status != STATUS_OK:
            raise
        # The result could not be written (e.g. a variable netCDF cannot hold): keep a failure
        # record so the archive says why, rather than a case that silently never finishes.
        status, message = STATUS_FAILED, f"cannot write case file: {one_line(exc)}"
        write_case(failure_case(case_id, model_name, params, message, wall_time,
                                 traceback.format_exc()), case_file)
    return {"case_id": case_id, "status": status, "message": message, "wall_time": wall_time}


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return "this process"

