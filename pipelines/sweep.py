"""Parameter studies: a TOML study file, its cases run on dask, one archive at the end.

A study file names a model, the parameters common to all cases, and either a Cartesian
``[sweep]`` (each key becomes an archive dimension, in file order) or an explicit list of
``[[cases]]`` (archived along one ``case`` dimension)::

    model = "hub"                 # registry name, or "package.module:ATTRIBUTE"
    title = "Table 1 of the paper"
    [fixed]                       # parameters common to all cases
    hub_speed = 27.0
    [sweep]                       # Cartesian product, in this order
    tuning_order = [2.8, 3.0, 3.2]
    fuselage_stiffness_scale = [0.5, 1.0]

    # ... or, instead of [sweep]:
    [[cases]]
    name = "0: locked"
    bifilar = "locked"

Models
    ``model`` is either a name known to :mod:`studies.registry` (``"hub"``) or a plug-in given as
    ``"module:attribute"``, the import path of a :class:`~studies.parameters.ModelSpec` (e.g.
    ``"mylab.rotors:SPEC"``). The plug-in form needs nothing registered: every dask worker imports
    the module itself, so it works on a remote cluster as long as the module is importable there.

Everything in the file is validated before any case starts (:func:`load_study`), including each
case's complete parameter set through ``ModelSpec.complete`` (which rejects impossible geometry).

Each case runs as :func:`run_case` on a dask worker, which writes ``cases/<case_id>.nc``
atomically; the id is a hash of the model name, the code version (package version and the
model's ``ModelSpec.version``) and the complete parameters, so running the same command again
after an interruption computes only the cases without a file, and cases cached by another
version of the code or of the model are computed again rather than reused. Bump a model's
``version`` when a change to it changes its results.

While a case runs, the model's progress lines (:func:`studies.progress.report`: the hub reports
each revolution and its periodicity change) travel from the worker to the client as dask events
and are printed under the case's name.
"""

from __future__ import annotations

import contextlib
import difflib
import hashlib
import importlib
import importlib.util
import itertools
import json
import math
import os
import shlex
import sys
import time
import tomllib
import traceback
import uuid
from collections.abc import Callable, Collection, Iterator, Mapping
from concurrent.futures import CancelledError
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import dask.config
import numpy as np
import xarray as xr

from pipelines.archive import (
    CONVENTIONS,
    STATUS_FAILED,
    STATUS_OK,
    CaseEntry,
    case_summary,
    code_version,
    consolidate,
    global_attrs,
    reserved_names,
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
from pipelines.lock import sweep_lock
from studies.parameters import ModelSpec, Param, ParameterError
from studies.progress import reporting
from studies.registry import available, get_model

CASES_DIR = "cases"
ARCHIVE_NAME = "archive.nc"
DEFAULT_WORKERS = 2
# Length of the hex case id: 64 bits makes an accidental clash within one study negligible.
CASE_ID_LENGTH = 16
# Dask event topic prefix of the progress lines; one topic per sweep.
PROGRESS_TOPIC = "bifilar-progress"
# Least time between two forwarded progress lines of one case (s); the first always goes.
PROGRESS_INTERVAL = 10.0
# Seconds to wait for a --scheduler to answer.
CONNECT_TIMEOUT = 30
# Seconds to wait for the first worker of a scheduler that has none (e.g. workers still queued
# on a batch system); --worker-timeout overrides it.
WORKER_TIMEOUT = 600.0
# Wall-clock minutes numba takes to compile the solver's kernels into its cache on a first run
# (the rotor model, most kernels; measured 1.5-2 minutes on a 2-core machine).
COMPILE_MINUTES = 2
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

TOP_LEVEL_KEYS = ("model", "title", "description", "fixed", "sweep", "cases")
# Most cases one study may hold. The study is validated, and its archive consolidated, in
# memory in the driver: 10^5 cases validate in seconds and their archive of a few scalars per
# case is a few hundred megabytes; a larger study belongs in several files.
MAX_CASES = 100_000


class StudyError(ValueError):
    """The study file is unusable; the message names the file, the entry and the fix."""


class SweepError(RuntimeError):
    """The sweep could not run (e.g. no connection to the dask scheduler)."""


class ModelFailure(RuntimeError):
    """The model returned a result marked ``status = "failed"`` or ``converged = 0``."""


def resolve_model(ref: str) -> ModelSpec:
    """The :class:`ModelSpec` for a registry name or a ``"module:attribute"`` reference.

    Parameters
    ----------
    ref
        ``"hub"`` (a name in :mod:`studies.registry`) or ``"package.module:SPEC"``.

    Raises
    ------
    StudyError
        If the model cannot be found or imported.
    """
    if ":" in ref:
        module_name, _, attr = ref.partition(":")
        try:
            spec = getattr(importlib.import_module(module_name), attr)
        except (ImportError, AttributeError) as exc:
            raise StudyError(
                f"cannot load model {ref!r}: {type(exc).__name__}: {exc} "
                "(a plug-in model is 'importable.module:ATTRIBUTE'; is its module on the path?)"
            ) from exc
        if not isinstance(spec, ModelSpec):
            raise StudyError(f"model {ref!r} is a {type(spec).__name__}, not a ModelSpec")
        return spec
    try:
        return get_model(ref)
    except ParameterError as exc:
        raise StudyError(str(exc)) from exc
    except ImportError as exc:
        raise StudyError(
            f"cannot load model {ref!r}: {type(exc).__name__}: {exc}; available models: "
            f"{', '.join(available())}"
        ) from exc


def model_version(spec: ModelSpec) -> str:
    """The code version a case of ``spec`` is computed with: the package version and the
    model's own ``version`` (e.g. ``"bifilar 0.1.0, hub 1"``)."""
    return f"bifilar {code_version()}, {spec.name} {spec.version}"


def make_case_id(model: str, params: Mapping[str, Any], version: str = "") -> str:
    """Stable identifier of a case: a hash of the model name, the code version and the
    complete parameters.

    JSON with sorted keys and Python's shortest float repr is the same in every process and
    session, so a rerun finds the files of the cases it already computed; another code or model
    version (:func:`model_version`) gives other ids, so stale cases are never reused.

    Parameters
    ----------
    model
        The model's name.
    params
        The complete parameters of the case.
    version
        :func:`model_version` of the model.
    """
    text = json.dumps({"model": model, "version": version, "parameters": dict(params)},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:CASE_ID_LENGTH]


def _format_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


@dataclass(frozen=True)
class Case:
    """One case of a study.

    Attributes
    ----------
    label
        Human-readable name: the ``name`` of an explicit case, ``"k=v, …"`` for a sweep.
    params
        Complete, validated parameters (defaults filled in).
    case_id
        :func:`make_case_id` of the model, its version and ``params``.
    index
        Position along the archive's case dimensions.
    """

    label: str
    params: dict[str, Any]
    case_id: str
    index: tuple[int, ...]

    def path(self, cases_dir: Path) -> Path:
        return Path(cases_dir) / f"{self.case_id}.nc"


@dataclass(frozen=True)
class Study:
    """A validated study file.

    Attributes
    ----------
    path, text
        The study file and its full text (archived as the ``study`` attribute).
    model_ref
        The ``model`` entry as written (registry name or ``module:attribute``); workers resolve
        it again.
    spec
        The model.
    title
        The ``title`` entry (or a default made from the model and file names).
    kind
        ``"sweep"`` (Cartesian product) or ``"cases"`` (explicit list).
    sweep
        For a sweep, the validated values of each swept parameter in file order.
    cases
        All cases, in archive order.
    """

    path: Path
    text: str
    model_ref: str
    spec: ModelSpec
    title: str
    kind: Literal["sweep", "cases"]
    sweep: dict[str, list[Any]]
    cases: tuple[Case, ...]

    def dims(self) -> dict[str, int]:
        """Archive case dimensions and their sizes."""
        if self.kind == "sweep":
            return {name: len(values) for name, values in self.sweep.items()}
        return {"case": len(self.cases)}

    def _param_values(self, name: str, values: list[Any]) -> np.ndarray:
        kind = self.spec.parameters[name].kind
        return np.array(values, dtype=object if kind is str else kind)

    def archive_coords(self) -> tuple[dict[str, xr.Variable], dict[str, xr.Variable]]:
        """Coordinates on the case dimensions, and scalar variables of the common parameters.

        Every parameter of the model appears once: as a coordinate if it varies between
        cases, as a scalar variable if not, with the units and long_name of its declaration.
        """
        params = self.spec.parameters
        coords: dict[str, xr.Variable] = {}
        if self.kind == "sweep":
            for name, values in self.sweep.items():
                coords[name] = xr.Variable(name, self._param_values(name, values),
                                           params[name].attrs())
        else:
            coords["case"] = xr.Variable("case", np.arange(len(self.cases)),
                                         {"units": "1", "long_name": "case number"})
            coords["case_name"] = xr.Variable(
                "case", np.array([c.label for c in self.cases], dtype=object),
                {"units": "1", "long_name": "case name from the study file"},
            )
        constants: dict[str, xr.Variable] = {}
        for name, param in params.items():
            if name in coords:
                continue
            values = [c.params[name] for c in self.cases]
            if all(v == values[0] for v in values):
                constants[name] = xr.Variable((), self._param_values(name, values[0]),
                                              param.attrs())
            else:
                coords[name] = xr.Variable("case", self._param_values(name, values),
                                           param.attrs())
        return coords, constants


class _Reads:
    """A stand-in for a model's parameters that records which of them a cross-check reads.

    Parameter names are recorded whether read as ``p.name`` or ``p["name"]``; any other
    attribute (a method that may look at every parameter) counts as reading them all.
    """

    def __init__(self, target: Any, declared: Collection[str]) -> None:
        self._target = target
        self._declared = declared
        self.names: set[str] | None = set()  # None: every parameter

    def _note(self, name: Any) -> None:
        if self.names is not None:
            if name in self._declared:
                self.names.add(name)
            else:
                self.names = None

    def __getattr__(self, name: str) -> Any:
        self._note(name)
        return getattr(self._target, name)

    def __getitem__(self, name: str) -> Any:
        self._note(name)
        return self._target[name]

    def get(self, name: str, default: Any = None) -> Any:
        self._note(name)
        return self._target.get(name, default)

    def __contains__(self, name: object) -> bool:
        self._note(name)
        return name in self._target

    def __iter__(self) -> Iterator[str]:
        self.names = None
        return iter(self._target)


class CrossChecks:
    """The model's cross-checks (``ModelSpec.check``) over the cases of a study, each distinct
    combination of the values they read checked once.

    A cross-check is a function of the parameters it reads. Once it has passed for some
    values of those, every case with the same values passes too: a sweep of 10^4 cases over
    the fuselage stiffness and the rotor speed designs the bifilar holes once per speed, not
    once per case. A check that fails raises at once, with the model's message.
    """

    def __init__(self, spec: ModelSpec) -> None:
        self.spec = spec
        self.calls = 0
        # names read (sorted) -> the value combinations of those names that passed
        self._passed: dict[tuple[str, ...], set[tuple[Any, ...]]] = {}

    def _typed(self, params: Mapping[str, Any]) -> Any:
        trusted = getattr(self.spec, "trusted", None)
        return trusted(params) if trusted is not None else dict(params)

    def __call__(self, params: Mapping[str, Any]) -> None:
        """Raise :class:`ParameterError` if the model rejects the complete ``params``."""
        if self.spec.check is None:
            return
        for names, passed in self._passed.items():
            if tuple(params[n] for n in names) in passed:
                return
        self.calls += 1
        target = self._typed(params)
        reads = _Reads(target, self.spec.parameters)
        try:
            self.spec.check(reads)
        except ParameterError:
            raise
        except Exception:
            # The check needs the real object (e.g. it copies it): check that, remember nothing.
            self.spec.check(target)
            return
        names = tuple(sorted(reads.names if reads.names is not None else params))
        self._passed.setdefault(names, set()).add(tuple(params[n] for n in names))


def _suggest(name: str, known: Mapping[str, Param]) -> str:
    close = difflib.get_close_matches(name, list(known), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _check_value(where: str, spec: ModelSpec, name: str, value: Any) -> Any:
    """One parameter value checked against its declaration, located in the study file."""
    if name not in spec.parameters:
        raise StudyError(
            f"{where}: unknown parameter {name!r} for model {spec.name!r}"
            f"{_suggest(name, spec.parameters)}; known: {', '.join(sorted(spec.parameters))}"
        )
    try:
        return spec.parameters[name].check(name, value)
    except ParameterError as exc:
        raise StudyError(f"{where}: {exc}") from exc


def _table(where: str, value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise StudyError(f"{where} must be a table of parameter = value entries, "
                         f"not {type(value).__name__}")
    return value


def load_study(path: str | os.PathLike[str]) -> Study:
    """Read and validate a study file; nothing runs if this raises.

    Parameters
    ----------
    path
        TOML study file (see the module documentation for its layout).

    Returns
    -------
    Study
        The validated study with every case's complete parameter set.

    Raises
    ------
    StudyError
        With a one-line message naming the file and the problem: unreadable or invalid TOML
        (with its line), missing or unknown model, unknown top-level key or parameter, wrong
        type or out-of-range value, empty or non-list sweep value, a key both swept and fixed,
        both or neither of ``[sweep]`` and ``[[cases]]``, duplicate cases, and any case whose
        complete parameter set the model rejects (``ModelSpec.complete``).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise StudyError(f"study file not found: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise StudyError(f"cannot read study file {path}: {exc}") from exc
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{path}: not valid TOML: {exc}") from exc
    src = str(path)

    unknown = [k for k in doc if k not in TOP_LEVEL_KEYS]
    if unknown:
        raise StudyError(f"{src}: unknown top-level key(s) {', '.join(map(repr, unknown))}; "
                         f"allowed: {', '.join(TOP_LEVEL_KEYS)}")
    model_ref = doc.get("model")
    if model_ref is None:
        raise StudyError(f"{src}: no model given; add e.g. model = \"hub\" "
                         f"(available: {', '.join(available())}, or 'module:ATTRIBUTE')")
    if not isinstance(model_ref, str):
        raise StudyError(f"{src}: model = {model_ref!r} must be a string, e.g. model = \"hub\"")
    try:
        spec = resolve_model(model_ref)
    except StudyError as exc:
        raise StudyError(f"{src}: {exc}") from exc
    if not spec.outputs:
        raise StudyError(f"{src}: model {spec.name!r} declares no outputs, so nothing would be "
                         "archived; give its ModelSpec outputs={{name: Output(...)}}")
    reserved = sorted(reserved_names(spec) & set(spec.parameters))
    if reserved:
        raise StudyError(f"{src}: model {spec.name!r} has parameter(s) {', '.join(reserved)} "
                         "whose names the archive uses for its own variables; rename them")
    title = doc.get("title", f"{spec.name} study {path.stem}")
    if not isinstance(title, str):
        raise StudyError(f"{src}: title = {title!r} must be a string")

    fixed = {
        name: _check_value(f"{src} [fixed]", spec, name, value)
        for name, value in _table(f"{src}: [fixed]", doc.get("fixed", {})).items()
    }
    has_sweep, has_cases = "sweep" in doc, "cases" in doc
    if has_sweep == has_cases:
        raise StudyError(
            f"{src}: give either a [sweep] table (Cartesian product) or a [[cases]] list, "
            + ("not both" if has_sweep else "found neither")
        )

    # Every value was checked once where the file gives it (each swept value once, not once
    # per case); per case only the model's cross-checks run, and those only for combinations
    # of the values they read that have not passed already.
    defaults = {name: param.default for name, param in spec.parameters.items()}
    cross_check = CrossChecks(spec)

    def complete(label: str, given: dict[str, Any]) -> dict[str, Any]:
        params = {**defaults, **given}
        try:
            cross_check(params)
        except ParameterError as exc:
            raise StudyError(f"{src}: case {label}: {exc}") from exc
        return params

    cases: list[Case] = []
    sweep: dict[str, list[Any]] = {}
    version = model_version(spec)
    if has_sweep:
        kind: Literal["sweep", "cases"] = "sweep"
        for name, values in _table(f"{src}: [sweep]", doc["sweep"]).items():
            where = f"{src} [sweep]"
            if name in fixed:
                raise StudyError(f"{where}: {name!r} is both swept and in [fixed]; remove one")
            if not isinstance(values, list):
                raise StudyError(f"{where}: {name} = {values!r} must be a list of values, "
                                 f"e.g. {name} = [{values!r}]; single values go in [fixed]")
            if not values:
                raise StudyError(f"{where}: {name} = [] is an empty list; give at least one value")
            checked = [_check_value(where, spec, name, v) for v in values]
            if len(set(checked)) != len(checked):
                raise StudyError(f"{where}: {name} = {values!r} repeats a value; "
                                 "each swept value becomes one archive coordinate")
            sweep[name] = checked
        if not sweep:
            raise StudyError(f"{src}: [sweep] is empty; give at least one swept parameter")
        size = math.prod(len(v) for v in sweep.values())
        if size > MAX_CASES:
            sizes = " x ".join(f"{len(v)} {name}" for name, v in sweep.items())
            raise StudyError(f"{src} [sweep]: {sizes} make {size} cases, more than the "
                             f"limit of {MAX_CASES} cases per study; split it into several "
                             "study files (each with its own --out)")
        for index in itertools.product(*(range(len(v)) for v in sweep.values())):
            point = {name: sweep[name][i] for name, i in zip(sweep, index, strict=True)}
            label = ", ".join(f"{k}={_format_value(v)}" for k, v in point.items())
            params = complete(label, {**fixed, **point})
            cases.append(Case(label, params, make_case_id(spec.name, params, version), index))
    else:
        kind = "cases"
        entries = doc["cases"]
        if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
            raise StudyError(f"{src}: cases must be a list of [[cases]] tables")
        if not entries:
            raise StudyError(f"{src}: cases = [] is an empty list; add [[cases]] tables")
        if len(entries) > MAX_CASES:
            raise StudyError(f"{src}: {len(entries)} [[cases]], more than the limit of "
                             f"{MAX_CASES} cases per study; split it into several study files")
        names: set[str] = set()
        for i, entry in enumerate(entries):
            if not entry:
                raise StudyError(f"{src}: [[cases]] number {i + 1} is empty; give it a name "
                                 "and the parameters that make it a case")
            label = entry.get("name", f"case {i}")
            if not isinstance(label, str):
                raise StudyError(f"{src}: case {i}: name = {label!r} must be a string")
            if label in names:
                raise StudyError(f"{src}: two cases are named {label!r}; names must be unique")
            names.add(label)
            where = f"{src} case {label!r}"
            given = dict(fixed)
            for name, value in entry.items():
                if name == "name":
                    continue
                if name in fixed:
                    raise StudyError(f"{where}: {name!r} is also in [fixed]; "
                                     "fixed parameters are common to all cases, remove one")
                given[name] = _check_value(where, spec, name, value)
            params = complete(repr(label), given)
            cases.append(Case(label, params, make_case_id(spec.name, params, version), (i,)))

    seen: dict[str, str] = {}
    for case in cases:
        if case.case_id in seen:
            raise StudyError(f"{src}: cases {seen[case.case_id]!r} and {case.label!r} have "
                             "identical parameters; remove one")
        seen[case.case_id] = case.label
    return Study(path, text, model_ref, spec, title, kind, sweep, tuple(cases))


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _failure_case(case_id: str, model: str, params: Mapping[str, Any], message: str,
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
def compile_notice(say: Any) -> Iterator[None]:
    """Say once that numba is compiling kernels, when it starts to (its cache is cold).

    numba raises its ``numba:compile`` event only for a kernel it does not find in its cache
    (``__pycache__`` beside the solver's modules), so the line appears on a first run, after
    an upgrade, or in a fresh environment, and never when the kernels load from the cache.
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
                say(f"compiling kernels (first run, about {COMPILE_MINUTES} minutes; numba "
                    "caches them for the next runs)...")

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", Notice()):
        yield


def nan_outputs(summary: xr.Dataset) -> list[str]:
    """The archived outputs of a case summary that hold NaN (a result the model could not
    determine, e.g. a period from a record shorter than two periods)."""
    return [name for name, var in summary.data_vars.items()
            if var.dtype.kind == "f" and bool(np.isnan(var.values).any())]


def _urgent(listener: Any, line: str) -> None:
    try:
        listener(line, urgent=True)
    except TypeError:  # a plain callable of one line
        listener(line)


def run_case(model_name: str, params: Mapping[str, Any], case_file: str,
             progress_topic: str | None = None,
             progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Run one case and write its case file atomically; the dask task of a sweep.

    Any exception of the model (or a result with ``attrs["status"] == "failed"`` or
    ``attrs["converged"] == 0``, a simulation that stopped early) is caught and recorded as a
    failed case with its message: one bad case must not stop an overnight sweep. What the case
    file keeps is what the model's outputs declare (:func:`pipelines.archive.case_summary`).
    Only a small summary travels back to the client; the data stay in the file.

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

    Returns
    -------
    dict
        ``case_id``, ``status`` (0 ok, 1 failed), ``message`` (the failure; for an ok case the
        model's note, usually ``""``) and ``wall_time`` (s).
    """
    start = time.perf_counter()
    case_id = Path(case_file).stem
    status, message, tb = STATUS_OK, "", ""
    summary = xr.Dataset()
    version = ""
    listener = _progress_listener(progress_topic, case_id) if progress_topic else None
    if listener is None and progress is not None:
        listener = progress
    try:
        if listener is not None:
            listener(f"started on {_worker_name()}")
        with contextlib.ExitStack() as stack:
            if listener is not None:
                stack.enter_context(reporting(listener))
                stack.enter_context(compile_notice(lambda line: _urgent(listener, line)))
            spec = resolve_model(model_name)
            version = model_version(spec)
            # validated by load_study (or the command) already: the model takes them as given
            result = spec.run(params)
        reported = str(result.attrs.get("status", "ok")).lower()
        if reported in ("failed", str(STATUS_FAILED)):
            raise ModelFailure(str(result.attrs.get("message", "model reported failure")))
        if not int(result.attrs.get("converged", 1)):
            raise ModelFailure("simulation did not converge: "
                               + str(result.attrs.get("message", "no message")))
        summary = case_summary(result, spec)
        nan = nan_outputs(summary)
        if nan:
            raise ModelFailure(
                f"output(s) {', '.join(nan)} came out NaN (not a number): the model could not "
                "determine them from this run (e.g. a record too short to measure a period, "
                "or no motion to measure)")
        # an ok case may carry the model's note (e.g. that shooting fell back to marching)
        message = str(result.attrs.get("message", ""))
    except Exception as exc:
        status, message, tb = STATUS_FAILED, _one_line(exc), traceback.format_exc()
        summary = xr.Dataset()
    wall_time = time.perf_counter() - start
    summary.attrs = {
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
        status, message = STATUS_FAILED, f"cannot write case file: {_one_line(exc)}"
        write_case(_failure_case(case_id, model_name, params, message, wall_time,
                                 traceback.format_exc()), case_file)
    return {"case_id": case_id, "status": status, "message": message, "wall_time": wall_time}


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return "this process"


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


@contextlib.contextmanager
def _connect(workers: int | None, scheduler: str | None) -> Iterator[Any]:
    """A dask client: on an existing scheduler, or on a new local cluster of processes."""
    # Imported here: ``bifilar plot`` and study validation need no dask.
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as exc:
            raise SweepError(f"cannot connect to the dask scheduler at {scheduler}: "
                             f"{_one_line(exc)}") from exc
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
    worker_timeout
        Seconds to wait for the first worker of a ``scheduler`` that has none (default
        :data:`WORKER_TIMEOUT`); the wait is announced on stderr.

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
    if workers is not None and scheduler is not None:
        raise StudyError("give either a number of workers or a scheduler address, not both")
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

    def say(line: str) -> None:
        if progress:
            print(line, file=sys.stderr, flush=True)

    with sweep_lock(out_dir, command, say):
        return _sweep(study, out_dir, cases_dir, workers, scheduler, retry_failed, command,
                      worker_timeout, say)


def _sweep(study: Study, out_dir: Path, cases_dir: Path, workers: int | None,
           scheduler: str | None, retry_failed: bool, command: str,
           worker_timeout: float | None, say: Callable[[str], None]) -> Path:
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
                       worker_timeout)
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


def _dashboard_works(client: Any, info: Mapping[str, Any]) -> bool:
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


def _wait_for_workers(client: Any, scheduler: str, timeout: float, say: Any) -> None:
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


def _run_cases(study: Study, todo: list[Case], cases_dir: Path, workers: int | None,
               scheduler: str | None, finished: int, total: int, say: Any,
               worker_timeout: float | None = None) -> None:
    from distributed import as_completed

    with _connect(workers, scheduler) as client:
        if scheduler is not None:
            _wait_for_workers(client, scheduler, worker_timeout or WORKER_TIMEOUT, say)
        info = client.scheduler_info()
        dashboard = _dashboard_works(client, info)
        say(f"running {len(todo)} case(s) of {study.path} on {len(info.get('workers', {}))} "
            "dask worker(s)" + (f"; dashboard {client.dashboard_link}" if dashboard else ""))
        labels = {c.case_id: c.label for c in todo}
        topic = f"{PROGRESS_TOPIC}-{uuid.uuid4().hex[:12]}"

        def progress_line(event: tuple[float, Any]) -> None:
            msg = event[1]
            if isinstance(msg, dict) and msg.get("case_id") in labels:
                say(f"  case {labels[msg['case_id']]}: {msg.get('message', '')}")

        client.subscribe_topic(topic, progress_line)
        paths = [str(c.path(cases_dir)) for c in todo]
        futures = client.map(
            run_case,
            [study.model_ref] * len(todo),
            [c.params for c in todo],
            paths,
            progress_topic=topic,
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
                result = {"status": STATUS_FAILED, "message": _one_line(exc),
                          "wall_time": float("nan")}
                with contextlib.suppress(OSError):
                    write_case(_failure_case(case.case_id, study.model_ref, case.params,
                                             result["message"], float("nan"),
                                             traceback.format_exc()),
                               case.path(cases_dir))
            future.release()
            finished += 1
            ok = result["status"] == STATUS_OK
            say(f"[{finished}/{total}] case {case.label} {'ok' if ok else 'failed'} "
                f"({result['wall_time']:.1f} s)" + ("" if ok else f": {result['message']}"))


if __name__ == "__main__":
    # ``python -m pipelines.sweep STUDY --out DIR [--workers N | --scheduler ADDRESS]``
    from pipelines.cli import main

    main(["sweep", *sys.argv[1:]], prog_name="bifilar")
