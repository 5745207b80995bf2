"""Study files: a model, its common parameters and a Cartesian sweep or a list of cases.

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

Everything in the file is validated before any case starts (:func:`load_study`): each value
once where the file gives it (a swept value once, not once per case), then the model's
cross-checks per case (``ModelSpec.check``, which rejects impossible geometry), each distinct
combination of the values a cross-check reads checked once (:class:`CrossChecks`). A study
holds at most :data:`MAX_CASES` cases.

Continuation
    An optional ``[continuation]`` table makes each case one branch of periodic responses
    instead of one response: the model's ``ModelSpec.branch`` follows the case's periodic
    response in one numeric parameter from ``start`` to ``stop`` by continuation (turning at
    folds) and reports each point's Floquet multipliers and stability
    (:mod:`studies.branches`)::

        [continuation]
        parameter = "excitation_3p"   # any numeric parameter of the model
        start = 0.5
        stop = 2.0
        step = 0.02                   # optional: first, least and largest arclength step
        min_step = 1e-5               #   (the parameter's units; 0 or absent: a 50th, a
        max_step = 0.1                #   10^5th and a 10th of |stop - start|)
        max_points = 200              # optional: most points of a branch
        method = "auto"               # optional: auto, harmonic_balance or shooting

    ``[fixed]``, ``[sweep]`` and ``[[cases]]`` give the cases as without it; each case's
    parameters hold the continued parameter at ``start``, and the continued parameter may not
    be given anywhere else in the file (it is the branch's own axis). Only models with a
    ``branch`` function can be continued. The archive gains a ``point`` dimension
    (:mod:`pipelines.archive`).

An optional ``[cluster]`` table gives the job resources of ``--cluster slurm|pbs`` (``cores``,
``memory``, ``walltime``, ``queue``, ``account``, ``jobs``; see :mod:`pipelines.cluster`); it
does not change the cases or their ids.

Each case's id is a hash of the model name, the code version (package version and the model's
``ModelSpec.version``) and the complete parameters (:func:`make_case_id`): rerunning a study
computes only the cases without a file (a case's ``[continuation]`` settings are part of its
id, so a changed table computes the branches again), and cases cached by another version of
the code or of the model are computed again rather than reused. Bump a model's ``version``
when a change to it changes its results.
"""
from __future__ import annotations

import difflib
import hashlib
import itertools
import json
import math
import os
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import xarray as xr

from pipelines.archive import (
    BRANCH_VARIABLES,
    code_version,
    reserved_names,
)
from studies.branches import Continuation, continuation_settings
from studies.parameters import ModelSpec, Param, ParameterError, read_toml
from studies.registry import available, get_model, resolve_model

# Length of the hex case id: 64 bits makes an accidental clash within one study negligible.
CASE_ID_LENGTH = 16
TOP_LEVEL_KEYS = ("model", "title", "description", "fixed", "sweep", "cases", "continuation",
                  "cluster")
# The [cluster] table: job resources of --cluster slurm|pbs (pipelines.cluster).
CLUSTER_KEYS: dict[str, type] = {"cores": int, "memory": str, "walltime": str, "queue": str,
                                 "account": str, "jobs": int}
# Most cases one study may hold. The study is validated, and its archive consolidated, in
# memory in the driver: 10^5 cases validate in seconds and their archive of a few scalars per
# case is a few hundred megabytes; a larger study belongs in several files.
MAX_CASES = 100_000


class StudyError(ValueError):
    """The study file is unusable; the message names the file, the entry and the fix."""



def model_version(spec: ModelSpec) -> str:
    """The code version a case of ``spec`` is computed with: the package version and the
    model's own ``version`` (e.g. ``"bifilar 0.1.0, hub 1"``)."""
    return f"bifilar {code_version()}, {spec.name} {spec.version}"


def make_case_id(model: str, params: Mapping[str, Any], version: str = "",
                 continuation: Mapping[str, Any] | None = None) -> str:
    """Stable identifier of a case: a hash of the model name, the code version, the complete
    parameters and, for a branch, the continuation settings.

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
    continuation
        The case's validated ``[continuation]`` settings (:meth:`Continuation.as_dict`), or
        ``None`` for a case of one response.
    """
    entries: dict[str, Any] = {"model": model, "version": version, "parameters": dict(params)}
    if continuation is not None:
        # (only for a branch: the ids of cases of one response do not change)
        entries["continuation"] = dict(continuation)
    text = json.dumps(entries, sort_keys=True)
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
    cluster
        The validated ``[cluster]`` table.
    continuation
        The validated ``[continuation]`` table: each case is one branch; ``None`` for cases
        of one response each.
    """

    path: Path
    text: str
    model_ref: str
    spec: ModelSpec
    title: str
    kind: Literal["sweep", "cases"]
    sweep: dict[str, list[Any]]
    cases: tuple[Case, ...]
    cluster: dict[str, Any] = field(default_factory=dict)
    continuation: Continuation | None = None

    @property
    def continuation_dict(self) -> dict[str, Any] | None:
        """The continuation as the worker receives it (a plain dict), or ``None``."""
        return None if self.continuation is None else self.continuation.as_dict()

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
        The continued parameter of a branch study is left out: the archive holds its value per
        point of each branch, as a variable of the same name.
        """
        params = self.spec.parameters
        continued = None if self.continuation is None else self.continuation.parameter
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
            if name in coords or name == continued:
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

    def __call__(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """Raise :class:`ParameterError` if the model rejects the complete ``params``; return
        the values the check derived that differ from ``params`` (a check may complete the
        parameters, e.g. with the digest of a file one names: see ``ModelSpec.check``)."""
        if self.spec.check is None:
            return {}
        for names, passed in self._passed.items():
            if tuple(params[n] for n in names) in passed:
                return {}
        self.calls += 1
        target = self._typed(params)
        reads = _Reads(target, self.spec.parameters)
        try:
            out = self.spec.check(reads)
        except ParameterError:
            raise
        except Exception:
            # The check needs the real object (e.g. it copies it, or completes it): check
            # that, remember nothing, and keep what it derived.
            return _derived(params, self.spec.check(target))
        if out is not None:  # derived values: per case, remember nothing
            return _derived(params, out)
        names = tuple(sorted(reads.names if reads.names is not None else params))
        self._passed.setdefault(names, set()).add(tuple(params[n] for n in names))
        return {}


def _derived(params: Mapping[str, Any], out: Any) -> dict[str, Any]:
    """The values of a check's completed parameters ``out`` that differ from ``params``."""
    if out is None:
        return {}
    values = out.as_dict() if hasattr(out, "as_dict") else dict(out)
    return {k: v for k, v in values.items() if k in params and params[k] != v}


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
        both or neither of ``[sweep]`` and ``[[cases]]``, duplicate cases, more than
        :data:`MAX_CASES` cases (refused before the cases are made), a bad ``[cluster]``
        table, and any case whose complete parameter set the model's cross-checks reject
        (``ModelSpec.check``); for a ``[continuation]`` table (:func:`_continuation`): a
        model without a ``branch`` function, a bad key or value, or the continued parameter
        also given in ``[fixed]``, ``[sweep]`` or a case.
    """
    path = Path(path)
    text, doc = read_toml(path, StudyError, "study file")
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
    except ParameterError as exc:
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
    continuation = (_continuation(src, spec, doc["continuation"], fixed)
                    if "continuation" in doc else None)
    # the continued parameter is the branch's own axis: every case starts its branch there
    continued = {} if continuation is None else {continuation.parameter: continuation.start}
    settings = None if continuation is None else continuation.as_dict()
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
        params = {**defaults, **given, **continued}
        try:
            params.update(cross_check(params))
            if continuation is not None:
                # the branch's other end, where a combination the model rejects would stop it
                cross_check({**params, continuation.parameter: continuation.stop})
        except ParameterError as exc:
            where = "" if continuation is None else (
                f" (with {continuation.parameter} from {continuation.start:g} to "
                f"{continuation.stop:g})")
            raise StudyError(f"{src}: case {label}{where}: {exc}") from exc
        return params

    def case_id(params: Mapping[str, Any]) -> str:
        return make_case_id(spec.name, params, version, settings)

    def not_continued(where: str, name: str) -> None:
        if name in continued:
            raise StudyError(f"{where}: {name!r} is the continued parameter of "
                             "[continuation] (each branch's own axis, from start to stop); "
                             "remove it here")

    cases: list[Case] = []
    sweep: dict[str, list[Any]] = {}
    version = model_version(spec)
    if has_sweep:
        kind: Literal["sweep", "cases"] = "sweep"
        for name, values in _table(f"{src}: [sweep]", doc["sweep"]).items():
            where = f"{src} [sweep]"
            if name in fixed:
                raise StudyError(f"{where}: {name!r} is both swept and in [fixed]; remove one")
            not_continued(where, name)
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
            cases.append(Case(label, params, case_id(params), index))
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
                not_continued(where, name)
                given[name] = _check_value(where, spec, name, value)
            params = complete(repr(label), given)
            cases.append(Case(label, params, case_id(params), (i,)))

    seen: dict[str, str] = {}
    for case in cases:
        if case.case_id in seen:
            raise StudyError(f"{src}: cases {seen[case.case_id]!r} and {case.label!r} have "
                             "identical parameters; remove one")
        seen[case.case_id] = case.label
    return Study(path, text, model_ref, spec, title, kind, sweep, tuple(cases),
                 _cluster_table(src, doc.get("cluster", {})), continuation)


def branch_models() -> list[str]:
    """The registered models that can follow a branch of their responses (those whose
    ``ModelSpec.branch`` is set)."""
    names = []
    for name in available():
        try:
            if get_model(name).branch is not None:
                names.append(name)
        except Exception:  # a model that cannot load cannot continue either
            continue
    return names


def _continuation(src: str, spec: ModelSpec, table: Any,
                  fixed: Mapping[str, Any]) -> Continuation:
    """The validated ``[continuation]`` table of a study file (see the module notes)."""
    where = f"{src} [continuation]"
    if not isinstance(table, dict):
        raise StudyError(f"{where} must be a table of key = value entries (parameter, start, "
                         f"stop, ...), not {type(table).__name__}")
    if spec.branch is None:
        able = branch_models()
        raise StudyError(
            f"{where}: model {spec.name!r} cannot follow a branch of its responses (its "
            "ModelSpec has no branch function); models that can: "
            + (", ".join(able) if able else "none registered; a plug-in model "
               "('module:ATTRIBUTE') with ModelSpec(branch=...)"))
    try:
        settings = continuation_settings(table, spec.parameters, where)
    except ParameterError as exc:
        raise StudyError(" ".join(str(exc).split())) from exc
    if settings.parameter in fixed:
        raise StudyError(f"{where}: parameter = {settings.parameter!r} is also in [fixed]; the "
                         "continued parameter runs from start to stop, remove it from [fixed]")
    # a model's own floquet_multiplier_max (of its single runs) means the branch's: the
    # branch's value is archived
    clash = sorted((set(BRANCH_VARIABLES) & set(spec.parameters))
                   | ((set(BRANCH_VARIABLES) - {"floquet_multiplier_max"}) & set(spec.outputs)))
    if clash:
        raise StudyError(f"{where}: model {spec.name!r} has parameter(s) or output(s) "
                         f"{', '.join(clash)} whose names a branch archive uses for its own "
                         "variables; rename them")
    return settings


def _cluster_table(src: str, table: Any) -> dict[str, Any]:
    """The validated ``[cluster]`` table: job resources for ``--cluster slurm|pbs``."""
    table = _table(f"{src}: [cluster]", table)
    for key, value in table.items():
        kind = CLUSTER_KEYS.get(key)
        if kind is None:
            raise StudyError(f"{src} [cluster]: unknown key {key!r}; allowed: "
                             f"{', '.join(CLUSTER_KEYS)}")
        if kind is int and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise StudyError(f"{src} [cluster]: {key} = {value!r} must be a whole number >= 1")
        if kind is str and (not isinstance(value, str) or not value.strip()):
            raise StudyError(f"{src} [cluster]: {key} = {value!r} must be a non-empty string, "
                             "e.g. memory = \"16GB\", walltime = \"02:00:00\"")
    return dict(table)

