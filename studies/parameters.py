"""Declared model parameters: one place per parameter, with its unit, meaning and valid range.

Every study declares its inputs as :class:`Param` objects. The same declaration validates
command-line and study-file input (with a message that names the parameter, the value and the
valid range) and becomes the ``units``/``long_name`` attributes of the archived variables.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import xarray as xr


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
        if kind is int:
            if float(value) != int(value):
                raise ParameterError(f"{name} = {value!r}: expected a whole number")
            value = int(value)
        else:
            value = float(value)
        if not math.isfinite(value):
            raise ParameterError(f"{name} = {value!r}: must be finite, in {self.describe_range()}")
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


@dataclass(frozen=True)
class ModelSpec:
    """A study that the pipeline can run: its parameters and its run function.

    ``run(params) -> xarray.Dataset`` takes a complete, validated parameter dict.
    ``check(params)`` raises :class:`ParameterError` for combinations that are individually
    valid but physically impossible (e.g. a pin wider than its hole); it runs before any case.
    """

    name: str
    parameters: Mapping[str, Param]
    run: Callable[[dict[str, Any]], xr.Dataset]
    check: Callable[[dict[str, Any]], None] | None = None
    description: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

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
