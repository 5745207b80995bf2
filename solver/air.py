"""The air a model flies in: free stream and density (a flight condition).

Model axes (the ground frame of a rotor model): ``z`` is the rotor shaft, pointing up (the
thrust direction; the rotor turns counter-clockwise about it, seen from above); ``x`` points aft,
the azimuth ψ = 0 of a blade pointing downstream; ``y = z × x`` (ψ = 90°, the advancing side).
The aircraft flies towards −x at speed U with its shaft tilted forward by α_s, so the free stream
the model sees (the air's velocity relative to the aircraft, which moves with constant velocity:
an inertial frame) is

    V∞ = U (cos α_s, 0, −sin α_s),

blowing aft and, for α_s > 0, down through the disk (the usual sign of forward flight).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
SEA_LEVEL_DENSITY = 1.225  # kg/m³, ISA sea level


@dataclass(frozen=True)
class FlightCondition:
    """Free-stream speed, shaft tilt and air density.

    Parameters
    ----------
    speed
        Flight speed U (m/s), ≥ 0 (0: hover).
    shaft_tilt
        Forward tilt of the rotor shaft α_s (rad), in [−π/4, π/4]; positive tilts the disk nose
        down, so that the free stream has a component down through the disk.
    density
        Air density ρ (kg/m³), in (0, 2].
    """

    speed: float = 0.0
    shaft_tilt: float = 0.0
    density: float = SEA_LEVEL_DENSITY

    def __post_init__(self) -> None:
        if not (math.isfinite(self.speed) and 0.0 <= self.speed <= 200.0):
            raise ValueError(f"flight speed = {self.speed!r} m/s must be in [0, 200]")
        if not (math.isfinite(self.shaft_tilt) and abs(self.shaft_tilt) <= math.pi / 4):
            raise ValueError(f"shaft_tilt = {self.shaft_tilt!r} rad must be in [−π/4, π/4]")
        if not (math.isfinite(self.density) and 0.0 < self.density <= 2.0):
            raise ValueError(f"air density = {self.density!r} kg/m³ must be in (0, 2]")

    @property
    def air_velocity(self) -> Array:
        """V∞ (m/s) in model axes (see the module docstring)."""
        a = self.shaft_tilt
        return self.speed * np.array([math.cos(a), 0.0, -math.sin(a)])
