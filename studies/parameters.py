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

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike


class ParameterError(ValueError):
    """A model parameter is unknown, of the wrong type or outside its valid range."""


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

    def describe_range(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        lo = "-inf" if self.minimum is None else f"{self.minimum:g}"
        hi = "inf" if self.maximum is None else f"{self.maximum:g}"
        left = "(" if (self.exclusive_minimum or self.minimum is None) else "["
        right = "]" if self.maximum is not None else ")"
        return f"{left}{lo}, {hi}{right} {self.units}".rstrip()

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
                f"{name} = {value:g} {self.units}: outside the valid range {self.describe_range()}"
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
        ``<name>`` (amplitude), ``<name>_cos`` and ``<name>_sin`` with dimensions
        ``(direction, harmonic)``. ``units`` must be the components' units.
    figure
        Stem of the report figure in which :func:`pipelines.plots.plot_archive` draws this output
        (``None``: not drawn as a history; it must be archived, ``history=True``, or a vector of
        archived components). A vector is drawn as an orbit, a history with an extra dimension
        as one panel per case, any other history as one panel per output with one line per
        case. Every vector of a periodic model also gets its harmonic chart
        ``harmonics_<name>``; a non-periodic model gets its scalar results against its sweep.
    """

    units: str
    long_name: str
    dims: tuple[str, ...] = ("time",)
    history: bool = False
    harmonics: bool = False
    components: tuple[str, str] | None = None
    figure: str | None = None

    @property
    def is_scalar(self) -> bool:
        return self.components is None and not self.dims

    @property
    def is_vector(self) -> bool:
        return self.components is not None

    def attrs(self) -> dict[str, str]:
        return {"units": self.units, "long_name": self.long_name}


def check_outputs(outputs: Mapping[str, Output]) -> None:
    """Raise :class:`OutputError` if a set of declarations is inconsistent."""
    for name, out in outputs.items():
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
        Global attributes of the result (run information such as ``converged``).
    partial
        Allow declared outputs to be absent (e.g. a model variant without absorbers).

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
        missing = [n for n, d in outputs.items() if not d.is_vector and n not in values]
        if missing:
            raise OutputError(f"declared output(s) not filled: {', '.join(missing)}")
    return xr.Dataset(data, coords=coords, attrs=dict(attrs or {}))


@dataclass(frozen=True)
class ModelSpec:
    """A study that the pipeline can run: its parameters, its outputs and its run function.

    ``run(params) -> xarray.Dataset`` takes a complete, validated parameter dict and returns
    the declared ``outputs`` (filled with :func:`output_dataset`).
    ``check(params)`` raises :class:`ParameterError` for combinations that are individually
    valid but physically impossible (e.g. a pin wider than its hole); it runs before any case.

    ``version`` is the model's own version string. It is part of every case id
    (:func:`pipelines.sweep.make_case_id`, together with the package version): bump it when a
    change to the model changes its results, and the cases cached in an output directory by the
    previous version are computed again instead of being reused.
    """

    name: str
    parameters: Mapping[str, Param]
    run: Callable[[dict[str, Any]], xr.Dataset]
    check: Callable[[dict[str, Any]], None] | None = None
    description: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    outputs: Mapping[str, Output] = field(default_factory=dict)
    version: str = "1"

    def __post_init__(self) -> None:
        check_outputs(self.outputs)

    @property
    def periodic(self) -> bool:
        """Whether the model records whole rotor revolutions (it has per-rev harmonics)."""
        return any(o.harmonics or o.is_vector for o in self.outputs.values())

    def dataset(self, values: Mapping[str, ArrayLike], attrs: Mapping[str, Any] | None = None,
                *, partial: bool = False) -> xr.Dataset:
        """:func:`output_dataset` with this model's declarations."""
        return output_dataset(self.outputs, values, attrs, partial=partial)

    def complete(self, given: Mapping[str, Any]) -> dict[str, Any]:
        """Defaults filled in, every value type- and range-checked, cross-checks applied."""
        unknown = sorted(set(given) - set(self.parameters))
        if unknown:
            raise ParameterError(
                f"unknown parameter(s) for model {self.name!r}: {', '.join(unknown)}; "
                f"known: {', '.join(sorted(self.parameters))}"
            )
        out = {name: p.default for name, p in self.parameters.items()}
        for name, value in given.items():
            out[name] = self.parameters[name].check(name, value)
        if self.check is not None:
            self.check(out)
        return out
