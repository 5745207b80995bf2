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
    """f(t) with ḟ(t) and f̈(t). ``value``, ``rate``, ``accel`` map seconds to floats."""

    value: Callable[[float], float]
    rate: Callable[[float], float]
    accel: Callable[[float], float]

    def __call__(self, t: float) -> tuple[float, float, float]:
        return self.value(t), self.rate(t), self.accel(t)


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
    return TimeFunction(
        lambda t: np.sin(f.value(t)),
        lambda t: np.cos(f.value(t)) * f.rate(t),
        lambda t: -np.sin(f.value(t)) * f.rate(t) ** 2 + np.cos(f.value(t)) * f.accel(t),
    )


def cos_of(f: TimeFunction) -> TimeFunction:
    """cos(f(t)) with chain-rule derivatives."""
    return TimeFunction(
        lambda t: np.cos(f.value(t)),
        lambda t: -np.sin(f.value(t)) * f.rate(t),
        lambda t: -np.cos(f.value(t)) * f.rate(t) ** 2 - np.sin(f.value(t)) * f.accel(t),
    )
