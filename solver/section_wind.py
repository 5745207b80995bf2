"""A prescribed, time-periodic velocity of the air at each section of a lifting line.

An analysis that computes the flow induced at a lifting line's sections by something the
multibody model does not carry as states — the vortex wake of a rotor
(:mod:`solver.vortex_wake`), a gust, a measured inflow — hands it to the line as a
:class:`PeriodicWind`: one velocity per section, sampled at equal times over a period and
interpolated linearly between the samples (exact at the samples, which a rotor analysis puts
at its time steps). The sections add it to the free stream
(:class:`~solver.lifting_line.LiftingLine` ``wind``). It depends on time only, so the
airloads' Jacobians need no terms of their own for it (only their values see it).

The samples live in one array that the analysis may update in place between revolutions
(e.g. a wake iterated with the periodic response); several lines may share it with different
delays (the blades of a rotor, each a fraction of a revolution behind the previous one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(eq=False)
class PeriodicWind:
    """Velocity (m/s) at each section of a line, periodic in time.

    Parameters
    ----------
    period
        Period T (s) > 0.
    table
        (n_t, n_sections, 3) velocities (m/s, global axes) at the times j T / n_t, j = 0 …
        n_t − 1 (n_t ≥ 2). Kept by reference: updating it in place changes the wind.
    delay
        The line sees the table at t + ``delay`` (s).
    """

    period: float
    table: Array
    delay: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.period) and self.period > 0.0):
            raise ValueError(f"periodic wind: period = {self.period!r} s must be > 0")
        tab = self.table
        if not (isinstance(tab, np.ndarray) and tab.ndim == 3 and tab.shape[0] >= 2
                and tab.shape[2] == 3 and tab.dtype == np.float64):
            shape = getattr(tab, "shape", None)
            raise ValueError(f"periodic wind: table of shape {shape} must be a float64 array "
                             "(n_t ≥ 2, n_sections, 3)")
        if not math.isfinite(self.delay):
            raise ValueError(f"periodic wind: delay = {self.delay!r} s must be finite")

    @property
    def n_sections(self) -> int:
        return self.table.shape[1]

    def __call__(self, t: float) -> Array:
        """The sections' velocities (n_sections, 3) at time ``t`` (s)."""
        n = self.table.shape[0]
        x = ((t + self.delay) / self.period % 1.0) * n
        j = math.floor(x)
        f = x - j
        j %= n
        if f < 1e-9:  # on a sample (a rotor's time step)
            return self.table[j]
        if f > 1.0 - 1e-9:
            return self.table[(j + 1) % n]
        return (1.0 - f) * self.table[j] + f * self.table[(j + 1) % n]
