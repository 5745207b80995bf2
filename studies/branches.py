"""Branches of periodic responses: what a study's ``[continuation]`` table asks of a model.

A case with a continuation is one branch: the model's periodic response followed in one numeric
parameter from ``start`` to ``stop`` by pseudo-arclength continuation (so that it turns around
folds), each point with its Floquet multipliers. A model that can do this gives its
:class:`~studies.parameters.ModelSpec` a ``branch`` function::

    branch(p: Parameters, c: Continuation) -> list[BranchPoint] | BranchResult

``p`` holds the case's parameters (the continued one at ``c.start``); each
:class:`BranchPoint` carries what the model's ``simulate`` would return for that periodic
response (the same declared outputs, so that the archive keeps the same harmonics per point),
its multipliers, whether it is stable and whether it is a fold (a turning point in the
parameter). A :class:`BranchResult` adds results of the case as a whole (e.g. the
absorber's backbone), archived with the points.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import NDArray

from studies.parameters import Param, ParameterError

# The keys of a study file's [continuation] table: (type, default, units, meaning). The step
# controls are arclength steps measured in the continued parameter's units (the state is
# scaled so that a step of the parameter alone and one of the response alone weigh alike).
CONTINUATION_KEYS: dict[str, tuple[type, Any, str, str]] = {
    "parameter": (str, None, "1", "the continued parameter: any numeric parameter of the model"),
    "start": (float, None, "parameter's", "the branch's first value"),
    "stop": (float, None, "parameter's", "the value the branch ends at"),
    "step": (float, 0.0, "parameter's", "first arclength step (0: a 50th of |stop - start|)"),
    "min_step": (float, 0.0, "parameter's",
                 "smallest arclength step before the branch is given up (0: a 10^5th of "
                 "|stop - start|)"),
    "max_step": (float, 0.0, "parameter's", "largest arclength step (0: a 10th of |stop - start|)"),
    "max_points": (int, 200, "1", "most points of the branch"),
    "method": (str, "auto", "1", "auto (the model's own choice), harmonic_balance or shooting"),
}
METHODS = ("auto", "harmonic_balance", "shooting")


@dataclass(frozen=True)
class Continuation:
    """A validated ``[continuation]`` table (see :data:`CONTINUATION_KEYS`); steps in the
    parameter's units, defaults resolved."""

    parameter: str
    start: float
    stop: float
    step: float
    min_step: float
    max_step: float
    max_points: int = 200
    method: str = "auto"

    def as_dict(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in CONTINUATION_KEYS}


def continuation_settings(table: Mapping[str, Any], parameters: Mapping[str, Param],
                          where: str = "[continuation]") -> Continuation:
    """The :class:`Continuation` of a study file's table, checked against the model's
    ``parameters``.

    Raises
    ------
    ParameterError
        One line naming the key, its value and what is valid.
    """
    unknown = sorted(set(table) - set(CONTINUATION_KEYS))
    if unknown:
        raise ParameterError(f"{where}: unknown key(s) {', '.join(unknown)}; known: "
                             f"{', '.join(CONTINUATION_KEYS)}")
    values: dict[str, Any] = {}
    for key, (kind, default, _, meaning) in CONTINUATION_KEYS.items():
        if key not in table:
            if default is None:
                raise ParameterError(f"{where}: {key} is required ({meaning})")
            values[key] = default
            continue
        value = table[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, kind) or isinstance(value, bool):
            raise ParameterError(f"{where}: {key} = {value!r} must be a {kind.__name__} "
                                 f"({meaning})")
        if kind is float and not np.isfinite(value):
            raise ParameterError(f"{where}: {key} = {value!r} must be finite")
        values[key] = value
    name = values["parameter"]
    param = parameters.get(name)
    if param is None or param.kind is not float:
        numeric = sorted(n for n, p in parameters.items() if p.kind is float)
        raise ParameterError(f"{where}: parameter = {name!r} is not a numeric (float) "
                             f"parameter of the model; numeric ones: {', '.join(numeric)}")
    for key in ("start", "stop"):
        param.check(f"{where} {key} of {name}", values[key])
    span = abs(values["stop"] - values["start"])
    if span == 0.0:
        raise ParameterError(f"{where}: start = stop = {values['start']!r}: a branch needs "
                             "two different values")
    for key, fraction in (("step", 1 / 50), ("min_step", 1e-5), ("max_step", 0.1)):
        if values[key] < 0.0:
            raise ParameterError(f"{where}: {key} = {values[key]!r} must be positive (0: the "
                                 "default)")
        values[key] = values[key] or fraction * span
    if not values["min_step"] <= values["step"] <= values["max_step"]:
        raise ParameterError(f"{where}: steps must satisfy min_step <= step <= max_step; got "
                             f"{values['min_step']!r}, {values['step']!r}, "
                             f"{values['max_step']!r}")
    if values["max_points"] < 2 or values["max_points"] > 10_000:
        raise ParameterError(f"{where}: max_points = {values['max_points']!r} must be in "
                             "[2, 10000]")
    if values["method"] not in METHODS:
        raise ParameterError(f"{where}: method = {values['method']!r} must be one of "
                             f"{', '.join(METHODS)}")
    return Continuation(**values)


@dataclass(frozen=True)
class BranchPoint:
    """One periodic response on a branch.

    Attributes
    ----------
    value
        The continued parameter's value (its units).
    result
        What the model's ``simulate`` returns for this periodic response: its declared
        outputs (the archive keeps the same harmonics per point as per case).
    multipliers
        The Floquet multipliers over one revolution (complex; the physical ones, the
        constraint directions removed; largest modulus first; may be only the dominant few).
    stable
        Whether every multiplier is inside the unit circle, within the accuracy the model
        knows its multipliers to.
    fold
        Whether the point is a turning point of the branch in the parameter.
    """

    value: float
    result: xr.Dataset
    multipliers: NDArray[np.complex128]
    stable: bool
    fold: bool = False

    @property
    def multiplier_max(self) -> float:
        """The largest modulus of :attr:`multipliers`."""
        return float(np.max(np.abs(self.multipliers))) if len(self.multipliers) else np.nan


@dataclass(frozen=True)
class BranchResult:
    """A branch with results of the case as a whole.

    Attributes
    ----------
    points
        The branch (:class:`BranchPoint`).
    extras
        Variables along dimensions of their own (not ``point``), each with ``units`` and
        ``long_name``, the same coordinates in every case of a study (e.g. the backbone's
        ``backbone_amplitude``).
    """

    points: list[BranchPoint]
    extras: xr.Dataset
