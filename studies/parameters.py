"""Declared model inputs and outputs: one place per quantity, with its unit and meaning.

Every study declares its inputs as :class:`Param` objects. The same declaration validates
command-line and study-file input (with a message that names the parameter, the value and the
valid range), generates the command-line options of the single-model commands, and becomes the
``units``/``long_name`` attributes of the archived variables.

Every study declares its results as :class:`Output` objects (name, units, long_name,
dimensions, and what the archive keeps of it). The run function fills its dataset through the
declarations (:func:`output_dataset`), and the sweep pipeline generates the archive layout,
the per-rev harmonics and the report figures from them (:mod:`pipelines.archive`,
:mod:`studies.harmonics`, :mod:`pipelines.plots`).
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike


class ParameterError(ValueError):
    """A model parameter is unknown, of the wrong type or outside its valid range."""


def read_toml(path: Path, error: type[Exception], what: str) -> tuple[str, dict[str, Any]]:
    """The text of the TOML file at ``path`` and its document; a missing or unreadable file,
    or invalid TOML, raises ``error`` with a one-line message naming the ``what`` ("study
    file", "airframe file") and the path."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(f"{what} not found: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"cannot read {what} {path}: {exc}") from exc
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from exc


@dataclass(frozen=True)
class Param:
    """A scalar model input.

    Parameters
    ----------
    default
        Value used when the input does not give one. Its Python type (float, int, str, bool)
        is the parameter's type.
    units
        UDUNITS string, e.g. ``"m"``, ``"rad s-1"``, ``"1"`` for dimensionless.
    long_name
        Human-readable meaning, used in error messages, plots and netCDF attributes.
    minimum, maximum
        Inclusive bounds for numbers (``None`` for unbounded).
    exclusive_minimum
        If true the lower bound itself is invalid (``value > minimum``).
    choices
        The allowed values for a string parameter.
    """

    default: Any
    units: str = "1"
    long_name: str = ""
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    choices: tuple[str, ...] | None = None

    @property
    def kind(self) -> type:
        return type(self.default)

    @property
    def shown_units(self) -> str:
        """The units as messages and help show them: ``(dimensionless)`` for ``"1"``."""
        return "(dimensionless)" if self.units == "1" else self.units

    def describe_range(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        lo = "-inf" if self.minimum is None else f"{self.minimum:g}"
        hi = "inf" if self.maximum is None else f"{self.maximum:g}"
        left = "(" if (self.exclusive_minimum or self.minimum is None) else "["
        right = "]" if self.maximum is not None else ")"
        return f"{left}{lo}, {hi}{right} {self.shown_units}".rstrip()

    def check(self, name: str, value: Any) -> Any:
        """Return ``value`` converted to the parameter's type, or raise :class:`ParameterError`."""
        kind = self.kind
        if kind is bool:
            if not isinstance(value, bool):
                raise ParameterError(f"{name} = {value!r}: expected true or false")
            return value
        if kind is str:
            if not isinstance(value, str):
                raise ParameterError(
                    f"{name} = {value!r}: expected a string, {self.describe_range()}")
            if self.choices is not None and value not in self.choices:
                raise ParameterError(f"{name} = {value!r}: must be {self.describe_range()}")
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(
                f"{name} = {value!r}: expected a number in {self.describe_range()}")
        try:
            as_float = float(value)
        except OverflowError:  # an integer too large for a float
            as_float = math.inf
        if not math.isfinite(as_float):
            raise ParameterError(f"{name} = {value!r}: must be finite, in {self.describe_range()}")
        if kind is int:
            if as_float != int(value):
                raise ParameterError(f"{name} = {value!r}: expected a whole number")
            value = int(value)
        else:
            value = as_float
        low_bad = self.minimum is not None and (
            value <= self.minimum if self.exclusive_minimum else value < self.minimum
        )
        high_bad = self.maximum is not None and value > self.maximum
        if low_bad or high_bad:
            raise ParameterError(
                f"{name} = {value:g}{'' if self.units == '1' else ' ' + self.units}: outside "
                f"the valid range {self.describe_range()}"
                + (f" ({self.long_name})" if self.long_name else "")
            )
        return value

    def attrs(self) -> dict[str, str]:
        return {"units": self.units, "long_name": self.long_name}


class OutputError(ValueError):
    """A model filled an output it did not declare, or with the wrong shape (a bug)."""


@dataclass(frozen=True)
class Output:
    """A declared model result.

    Parameters
    ----------
    units
        UDUNITS string of the values, ``"1"`` for dimensionless.
    long_name
        Human-readable meaning; becomes the ``long_name`` attribute in every file.
    dims
        Dimension names of the values: ``()`` for a scalar result, ``("time",)`` for a time
        history, e.g. ``("bifilar", "time")`` for one history per absorber. A declaration whose
        ``dims`` is its own name alone (``"time": Output("s", "time", dims=("time",))``) is a
        coordinate.
    history
        Keep the time history in the sweep archive: the last recorded revolution (dimension
        ``time_in_rev``) for a per-rev periodic model, the whole history (dimension ``sample``)
        otherwise. Scalar results (``dims == ()``) are always archived.
    harmonics
        Archive the per-rev harmonics of this time history as ``<name>_amplitude``,
        ``<name>_cos`` and ``<name>_sin`` (its other dimensions kept, ``harmonic`` last). A model
        with any harmonic output is per-rev periodic (see :mod:`studies.harmonics`).
    components
        For an in-plane vector: the names of its declared x and y time histories. The vector is
        derived, never filled by the model: the archive holds its per-rev harmonics as
        ``<name>_amplitude``, ``<name>_cos`` and ``<name>_sin`` (as for ``harmonics``) with
        dimensions ``(direction, harmonic)``. ``units`` must be the components' units.
    figure
        Stem of the report figure in which :func:`pipelines.plots.plot_archive` draws this output
        (``None``: not drawn as a history; it must be archived, ``history=True``, or a vector of
        archived components). A vector is drawn as an orbit, a history with an extra dimension
        as one panel per case, any other history as one panel per output with one line per
        case. Every vector of a periodic model also gets its harmonic chart
        ``harmonics_<name>``; a non-periodic model gets its scalar results against its sweep.
        A scalar result named ``run_*`` is a fact about the run (its time base, cost,
        convergence): archived like any other, not drawn.
    optional
        A scalar result, history or coordinate only some runs have (e.g. a step-error
        estimate, not made when it is not asked for; the stations of a modal airframe): the
        run leaves it out rather than filling NaN, and the archive holds NaN for the cases
        without it.
    """

    units: str
    long_name: str
    dims: tuple[str, ...] = ("time",)
    history: bool = False
    harmonics: bool = False
    components: tuple[str, str] | None = None
    figure: str | None = None
    optional: bool = False

    @property
    def is_scalar(self) -> bool:
        return self.components is None and not self.dims

    @property
    def is_vector(self) -> bool:
        return self.components is not None

    def attrs(self) -> dict[str, str]:
        return {"units": self.units, "long_name": self.long_name}


# What a simulation of a fixed duration (not per-rev periodic) reports of its run, as
# declared scalar results.
RUN_OUTPUTS: dict[str, Output] = {
    "run_converged": Output("1", "1 if every time step converged, else 0 (the run stopped "
                            "early)", dims=()),
    "run_time_step": Output("s", "time step", dims=()),
    "run_solver_seconds": Output("s", "time spent in the run", dims=()),
}


def run_facts(sim: Any, time_step: float) -> dict[str, np.generic]:
    """The values of :data:`RUN_OUTPUTS` for a :func:`solver.simulation.simulate` result
    ``sim`` (its ``converged`` and ``seconds``) at ``time_step`` (s)."""
    return {"run_converged": np.int32(sim.converged), "run_time_step": np.float64(time_step),
            "run_solver_seconds": np.float64(sim.seconds)}


def check_outputs(outputs: Mapping[str, Output]) -> None:
    """Raise :class:`OutputError` if a set of declarations is inconsistent."""
    for name, out in outputs.items():
        if out.optional and not (out.is_scalar or out.history or out.dims == (name,)):
            raise OutputError(f"output {name!r}: only a scalar result, a history or a "
                              "coordinate can be optional")
        if out.components is None:
            if out.harmonics and "time" not in out.dims:
                raise OutputError(f"output {name!r}: harmonics need a 'time' dimension")
            continue
        if len(out.components) != 2:
            raise OutputError(f"output {name!r}: a vector has two components (x, y)")
        for comp in out.components:
            decl = outputs.get(comp)
            if decl is None or decl.is_vector or decl.dims != ("time",):
                raise OutputError(f"output {name!r}: component {comp!r} must be a declared "
                                  "time history with dims ('time',)")
            if decl.units != out.units:
                raise OutputError(f"output {name!r} has units {out.units!r} but its component "
                                  f"{comp!r} has {decl.units!r}")


def output_dataset(outputs: Mapping[str, Output], values: Mapping[str, ArrayLike],
                   attrs: Mapping[str, Any] | None = None, *,
                   partial: bool = False) -> xr.Dataset:
    """A model result filled through its output declarations.

    Parameters
    ----------
    outputs
        The model's declarations (name -> :class:`Output`).
    values
        Name -> values (in the declared units, shaped as the declared ``dims``). Declarations
        that are coordinates (``dims == (name,)``) become coordinates.
    attrs
        Global attributes of the result: only the case's ``message`` (what the run reports
        in words) and, for a result that failed, ``status``; every run fact is a declared
        output.
    partial
        Allow declared outputs to be absent (e.g. a model variant without absorbers). Outputs
        declared ``optional`` may be absent in any case.

    Returns
    -------
    xarray.Dataset
        Every variable with the ``units`` and ``long_name`` of its declaration.

    Raises
    ------
    OutputError
        For an undeclared name, a derived (vector) output, values whose number of dimensions
        differs from the declaration, or (unless ``partial``) a declared output left out.
    """
    undeclared = sorted(set(values) - set(outputs))
    if undeclared:
        raise OutputError(f"undeclared output(s) {', '.join(undeclared)}; declared: "
                          f"{', '.join(outputs)}")
    coords: dict[str, xr.Variable] = {}
    data: dict[str, xr.Variable] = {}
    for name, value in values.items():
        decl = outputs[name]
        if decl.is_vector:
            raise OutputError(f"output {name!r} is derived from {decl.components}; fill those")
        arr = np.asarray(value)
        if arr.ndim != len(decl.dims):
            raise OutputError(f"output {name!r} has {arr.ndim} dimension(s), declared "
                              f"{decl.dims}")
        var = xr.Variable(decl.dims, arr, decl.attrs())
        (coords if decl.dims == (name,) else data)[name] = var
    if not partial:
        missing = [n for n, d in outputs.items()
                   if not d.is_vector and not d.optional and n not in values]
        if missing:
            raise OutputError(f"declared output(s) not filled: {', '.join(missing)}")
    return xr.Dataset(data, coords=coords, attrs=dict(attrs or {}))


class Parameters:
    """A validated, complete parameter set of one model: frozen, with one typed attribute per
    declared :class:`Param` (``p.hub_speed``).

    Each model's class is generated from its declarations (:func:`parameters_class`) as a
    frozen dataclass whose fields have the declared types (float, int, str, bool). Build one
    with :meth:`ModelSpec.validate` (defaults filled, every value type- and range-checked, the
    model's cross-checks applied), or with :meth:`ModelSpec.trusted` from a dict that was
    validated already (the sweep's worker receives a plain dict).
    """

    model: ClassVar[str] = ""
    declarations: ClassVar[Mapping[str, Param]] = {}
    cross_check: ClassVar[Callable[[Any], Any] | None] = None

    def as_dict(self) -> dict[str, Any]:
        """Name -> value of every parameter, in declaration order (for archives and case
        ids)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def replace(self, **changes: Any) -> Parameters:
        """A variation: these values changed, each type- and range-checked, and the model's
        cross-checks applied to the result.

        Raises
        ------
        ParameterError
            For an unknown name, a value outside its range or an impossible combination.
        """
        unknown = sorted(set(changes) - set(self.declarations))
        if unknown:
            raise ParameterError(f"unknown parameter(s) for model {self.model!r}: "
                                 f"{', '.join(unknown)}")
        checked = {name: self.declarations[name].check(name, value)
                   for name, value in changes.items()}
        new = dataclasses.replace(self, **checked)
        if self.cross_check is not None:
            new = self.cross_check(new) or new
        return new

    def __getitem__(self, name: str) -> Any:
        """The value of parameter ``name`` (for code written against the validated dict)."""
        if name not in self.declarations:
            raise KeyError(name)
        return getattr(self, name)

    def __reduce__(self) -> tuple[Any, ...]:
        # the class is generated at run time: pickle rebuilds it from its declarations
        return (_unpickle, (self.model, dict(self.declarations), self.cross_check,
                            self.as_dict()))


# generated classes by (model, declarations): one class per model and process
_CLASSES: dict[tuple[str, tuple[tuple[str, Param], ...]], type[Parameters]] = {}


def parameters_class(model: str, declarations: Mapping[str, Param],
                     cross_check: Callable[[Any], Any] | None = None) -> type[Parameters]:
    """The frozen dataclass of ``model``'s parameters: one field per declaration, typed as
    its default (the same class for the same model and declarations)."""
    key = (model, tuple(declarations.items()))
    cls = _CLASSES.get(key)
    if cls is None:
        clash = sorted(set(declarations) & set(dir(Parameters)))
        if clash:
            raise ParameterError(f"model {model!r}: parameter name(s) {', '.join(clash)} are "
                                 "taken by the parameter object itself; choose others")
        stem = "".join(part.capitalize() for part in model.replace("-", "_").split("_"))
        cls = dataclasses.make_dataclass(
            f"{stem}Parameters",
            [(name, param.kind) for name, param in declarations.items()],
            bases=(Parameters,), frozen=True)
        cls.model = model
        cls.declarations = dict(declarations)
        cls.__module__ = __name__
        _CLASSES[key] = cls
    cls.cross_check = staticmethod(cross_check) if cross_check is not None else None
    return cls


def _unpickle(model: str, declarations: Mapping[str, Param],
              cross_check: Callable[[Any], Any] | None,
              values: Mapping[str, Any]) -> Parameters:
    return parameters_class(model, declarations, cross_check)(**values)


@dataclass(frozen=True)
class ModelSpec:
    """A study that the pipeline can run: its parameters, its outputs and its run function.

    Parameters
    ----------
    name
        The model's name in the registry and in study files.
    parameters
        Its inputs (name -> :class:`Param`); they generate its :class:`Parameters` class.
    simulate
        ``simulate(p) -> xarray.Dataset`` takes the validated :class:`Parameters` and returns
        the declared ``outputs`` (filled with :func:`output_dataset`). Call it through
        :meth:`run`.
    check
        ``check(p)`` raises :class:`ParameterError` for combinations that are individually
        valid but physically impossible (e.g. a pin wider than its hole); it runs once, in
        :meth:`validate`, before any case. It may return the parameters completed with
        derived values (e.g. the digest of a file a parameter names, so that the case id
        follows the file's content), which :meth:`validate` then returns; ``None`` keeps
        them.
    description
        One line on what the model is.
    extra
        Model-specific information for the pipeline.
    outputs
        Its results (name -> :class:`Output`).
    version
        The model's own version string. It is part of every case id
        (:func:`pipelines.sweep.make_case_id`, together with the package version): bump it
        when a change to the model changes its results, and the cases cached in an output
        directory by an earlier version are computed again instead of being reused.
    warm_up
        Tiny runs of the model (each a small build and a few time steps, no argument) that
        between them call every compiled kernel its cases call, so that numba compiles them
        into its on-disk cache before the cases start (:mod:`pipelines.kernels`). They are
        independent of one another: a sweep runs them at the same time on different
        workers, so a split into parts of similar compile time shortens a first run. Empty
        (the default): the cases compile what they call.
    branch
        ``branch(p, c) -> list[BranchPoint]``: the model's periodic response followed in one
        parameter by continuation (:mod:`studies.branches`; a study file's
        ``[continuation]`` table), or ``None`` if the model cannot continue its responses.
    """

    name: str
    parameters: Mapping[str, Param]
    simulate: Callable[[Any], xr.Dataset]
    check: Callable[[Any], Any] | None = None
    description: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    outputs: Mapping[str, Output] = field(default_factory=dict)
    version: str = "1"
    warm_up: tuple[Callable[[], None], ...] = ()
    branch: Callable[[Any, Any], list[Any]] | None = None

    def __post_init__(self) -> None:
        check_outputs(self.outputs)
        # (a frozen dataclass: its derived attribute set once, here)
        object.__setattr__(self, "_parameters_type",
                           parameters_class(self.name, self.parameters, self.check))

    @property
    def parameters_type(self) -> type[Parameters]:
        """The frozen dataclass of this model's parameters."""
        return self._parameters_type  # type: ignore[attr-defined]

    @property
    def periodic(self) -> bool:
        """Whether the model records whole rotor revolutions (it has per-rev harmonics)."""
        return any(o.harmonics or o.is_vector for o in self.outputs.values())

    def dataset(self, values: Mapping[str, ArrayLike], attrs: Mapping[str, Any] | None = None,
                *, partial: bool = False) -> xr.Dataset:
        """:func:`output_dataset` with this model's declarations."""
        return output_dataset(self.outputs, values, attrs, partial=partial)

    def validate(self, given: Mapping[str, Any] | Parameters = ()) -> Parameters:
        """The typed parameters of ``given``: defaults filled in, every value type- and
        range-checked, the model's cross-checks applied. Already validated parameters of this
        model are returned as they are.

        Raises
        ------
        ParameterError
            One line naming the parameter, its value and its valid range.
        """
        cls = self.parameters_type
        if isinstance(given, cls):
            return given
        given = dict(given)
        unknown = sorted(set(given) - set(self.parameters))
        if unknown:
            raise ParameterError(
                f"unknown parameter(s) for model {self.name!r}: {', '.join(unknown)}; "
                f"known: {', '.join(sorted(self.parameters))}"
            )
        values = {name: p.default for name, p in self.parameters.items()}
        for name, value in given.items():
            values[name] = self.parameters[name].check(name, value)
        p = cls(**values)
        if self.check is not None:
            # the cross-check may complete the parameters with derived values (e.g. the hash
            # of a file a parameter names), returning them
            p = self.check(p) or p
        return p

    def complete(self, given: Mapping[str, Any]) -> dict[str, Any]:
        """:meth:`validate` as a plain dict (what a case id is made of and a worker
        receives)."""
        return self.validate(given).as_dict()

    def trusted(self, values: Mapping[str, Any] | Parameters) -> Parameters:
        """The typed parameters of a complete parameter set validated already (by
        :meth:`validate` or :meth:`complete`, possibly in another process): not checked
        again.

        Raises
        ------
        ParameterError
            If ``values`` does not name exactly this model's parameters.
        """
        cls = self.parameters_type
        if isinstance(values, cls):
            return values
        if set(values) != set(self.parameters):
            missing = sorted(set(self.parameters) - set(values))
            unknown = sorted(set(values) - set(self.parameters))
            raise ParameterError(
                f"not a complete parameter set of model {self.name!r}"
                + (f"; missing: {', '.join(missing)}" if missing else "")
                + (f"; unknown: {', '.join(unknown)}" if unknown else ""))
        return cls(**values)

    def run(self, params: Mapping[str, Any] | Parameters) -> xr.Dataset:
        """Run one case: ``params`` is this model's :class:`Parameters` or the complete,
        validated dict of them (:meth:`complete`), passed to the model as
        :class:`Parameters` without checking it again."""
        return self.simulate(self.trusted(params))
