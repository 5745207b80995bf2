"""Prescribed functions of time (drivers): value, first and second derivative.

Drivers (a hub spinning at Ω, a prescribed revolute angle φ(t)) need their derivatives for
consistent initial velocities and accelerations; they are given explicitly, not differenced.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TimeFunction:
    """f(t) with ḟ(t) and f̈(t). ``value``, ``rate``, ``accel`` map seconds to floats;
    ``joint``, if given, maps seconds to all three at once (a composed function's inner parts
    then evaluated once: the constraints take every driver's three at each new time)."""

    value: Callable[[float], float]
    rate: Callable[[float], float]
    accel: Callable[[float], float]
    joint: Callable[[float], tuple[float, float, float]] | None = None

    def __call__(self, t: float) -> tuple[float, float, float]:
        if self.joint is not None:
            return self.joint(t)
        return self.value(t), self.rate(t), self.accel(t)

    @classmethod
    def of(cls, joint: Callable[[float], tuple[float, float, float]]) -> TimeFunction:
        """The function whose value, rate and acceleration ``joint(t)`` gives together."""
        return cls(lambda t: joint(t)[0], lambda t: joint(t)[1], lambda t: joint(t)[2], joint)


def constant(c: float) -> TimeFunction:
    """f(t) = c."""
    return TimeFunction(lambda t: c, lambda t: 0.0, lambda t: 0.0)


def linear(rate: float, offset: float = 0.0) -> TimeFunction:
    """f(t) = offset + rate·t (e.g. a hub angle Ω t, rate in rad/s)."""
    return TimeFunction(lambda t: offset + rate * t, lambda t: rate, lambda t: 0.0)


def harmonic(amplitude: float, omega: float, phase: float = 0.0) -> TimeFunction:
    """f(t) = A cos(ω t + phase)."""
    return TimeFunction(
        lambda t: amplitude * np.cos(omega * t + phase),
        lambda t: -amplitude * omega * np.sin(omega * t + phase),
        lambda t: -amplitude * omega**2 * np.cos(omega * t + phase),
    )


def sin_of(f: TimeFunction) -> TimeFunction:
    """sin(f(t)) with chain-rule derivatives."""

    def joint(t: float) -> tuple[float, float, float]:
        v, r, a = f(t)
        s, c = np.sin(v), np.cos(v)
        return s, c * r, -s * r**2 + c * a

    return TimeFunction.of(joint)


def cos_of(f: TimeFunction) -> TimeFunction:
    """cos(f(t)) with chain-rule derivatives."""

    def joint(t: float) -> tuple[float, float, float]:
        v, r, a = f(t)
        s, c = np.sin(v), np.cos(v)
        return c, -s * r, -c * r**2 - s * a

    return TimeFunction.of(joint)
