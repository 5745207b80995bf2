"""Prescribed tip-vortex wakes of a rotor: geometry as straight vortex segments.

Each of Q blades at azimuth ψ_b (ψ = 0 along +x, downstream; the rotor turns about +z) trails
a tip vortex from radius r_v. The element of wake age φ (rad: the rotor has turned φ since it
was trailed) sits, in rotor radii, at

    x = r_v cos(ψ_b − φ) + μ φ,    y = r_v sin(ψ_b − φ),    z = −∫_0^φ λ_c(φ') dφ',

convected downstream by the in-plane free stream μ and down through the disk by the total
flow λ_c = λ_f + λ_i (free stream plus induced, on ΩR). Two descent laws:

* ``"rigid"``: λ_i uniform, the classical skewed helix (tan χ = μ/λ);
* ``"beddoes"``: Beddoes' generalized wake (Beddoes, 10th European Rotorcraft Forum, 1984;
  as given by Leishman, *Principles of Helicopter Aerodynamics*, 2nd ed., ch. 10): over the
  disk λ_i = λ_0 [1 + E (x − |y|³)], downstream of it λ_i = 2 λ_0 (1 − E |y|³), with
  E = χ/2, so that the wake descends slowly at the front of the disk, fast at its rear, and
  the far wake at twice the mean induced flow of momentum theory.

The segments are in metres, ready for :func:`solver.vortex_kernels.induced_velocity`; a tip
vortex's circulation is that of its blade's bound vortex when the element was trailed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.vortex_kernels import induced_velocity

Array = NDArray[np.float64]
DESCENT_LAWS = ("rigid", "beddoes")


@dataclass(frozen=True)
class TipVortexWake:
    """The prescribed tip vortices of one rotor.

    Parameters
    ----------
    radius
        Rotor radius R (m), > 0.
    blades
        Number of blades Q ≥ 1 (equally spaced).
    advance_ratio
        μ, in-plane free stream on ΩR (≥ 0), along +x.
    free_stream_inflow
        λ_f, free stream down through the disk on ΩR.
    mean_induced_inflow
        λ_0, the mean induced inflow on ΩR (> 0), e.g. from momentum theory.
    turns
        Wake length in revolutions of age (> 0).
    segments_per_turn
        Straight segments per revolution of age (≥ 8).
    release_radius
        r_v, the radius the tip vortices leave the blades at, in R (0 < r_v ≤ 1).
    descent
        ``"rigid"`` or ``"beddoes"`` (module docstring).
    """

    radius: float
    blades: int
    advance_ratio: float
    free_stream_inflow: float
    mean_induced_inflow: float
    turns: float = 10.0
    segments_per_turn: int = 72
    release_radius: float = 1.0
    descent: str = "rigid"

    def __post_init__(self) -> None:
        checks = (
            ("radius", self.radius, self.radius > 0.0, "> 0 m"),
            ("blades", self.blades, isinstance(self.blades, int) and self.blades >= 1, "≥ 1"),
            ("advance_ratio", self.advance_ratio, self.advance_ratio >= 0.0, "≥ 0"),
            ("mean_induced_inflow", self.mean_induced_inflow, self.mean_induced_inflow > 0.0,
             "> 0"),
            ("turns", self.turns, 0.0 < self.turns <= 1000.0, "in (0, 1000]"),
            ("segments_per_turn", self.segments_per_turn,
             isinstance(self.segments_per_turn, int) and self.segments_per_turn >= 8, "≥ 8"),
            ("release_radius", self.release_radius, 0.0 < self.release_radius <= 1.0,
             "in (0, 1]"),
        )
        for name, value, ok, valid in checks:
            if not (ok and math.isfinite(value)):
                raise ValueError(f"tip-vortex wake: {name} = {value!r} must be {valid}")
        if not math.isfinite(self.free_stream_inflow):
            raise ValueError(f"tip-vortex wake: free_stream_inflow = "
                             f"{self.free_stream_inflow!r} must be finite")
        if self.descent not in DESCENT_LAWS:
            raise ValueError(f"tip-vortex wake: descent = {self.descent!r} must be one of "
                             f"{', '.join(map(repr, DESCENT_LAWS))}")

    @property
    def skew_angle(self) -> float:
        """χ = atan(μ / (λ_f + λ_0)), the wake skew angle (rad)."""
        return math.atan2(self.advance_ratio, self.free_stream_inflow + self.mean_induced_inflow)

    def ages(self) -> Array:
        """Wake ages φ of the segment ends (rad), 0 … 2π·turns."""
        n = round(self.turns * self.segments_per_turn)
        return np.linspace(0.0, 2.0 * math.pi * self.turns, n + 1)

    def _induced(self, x: Array, y: Array) -> Array:
        lam0 = self.mean_induced_inflow
        if self.descent == "rigid":
            return np.full_like(x, lam0)
        e = self.skew_angle / 2.0
        ay3 = np.abs(y) ** 3
        inside = x <= np.sqrt(np.clip(1.0 - y * y, 0.0, None))
        return np.where(inside, lam0 * (1.0 + e * (x - ay3)), 2.0 * lam0 * (1.0 - e * ay3))

    def filament(self, blade_azimuth: float, release: Array | None = None) -> Array:
        """Points (n + 1, 3) in metres of the tip vortex of a blade now at ``blade_azimuth``
        (rad), from the blade's tip (age 0) back along the wake; the descent is integrated
        over the ages by the trapezoidal rule.

        ``release``: (n_ψ, 3) the point (m) a blade trails its tip vortex from, when at the
        azimuths 2πj/n_ψ (a flapping, lagging blade's tip over a revolution, interpolated
        linearly); the element of age φ left it at the blade's azimuth then, ψ_b − φ.
        Default: the circle r_v R in the plane z = 0."""
        phi = self.ages()
        mu = self.advance_ratio
        if release is None:
            rv = self.release_radius
            x0, y0 = rv * np.cos(blade_azimuth - phi), rv * np.sin(blade_azimuth - phi)
            z0 = np.zeros_like(phi)
        else:
            x0, y0, z0 = (periodic_interp(blade_azimuth - phi, release[:, c]) / self.radius
                          for c in range(3))
        x, y = x0 + mu * phi, y0
        rate = self.free_stream_inflow + self._induced(x, y)
        z = z0 - np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(phi))])
        return self.radius * np.stack([x, y, z], axis=1)

    def segments(self, azimuth: float, release: Array | None = None
                 ) -> tuple[Array, Array, Array]:
        """Segments of every blade's tip vortex with blade 0 at ``azimuth`` (rad) (``release``
        as in :meth:`filament`).

        Returns
        -------
        starts, ends, ages
            (m, 3) ends in metres, each segment from its younger end to its older one: the
            continuation of a bound vortex that runs from root to tip, so that a positive
            circulation is that of a blade lifting along +z; (m,) the age of each segment's
            midpoint (rad), blade 0's segments first. (The root vortex, along the shaft,
            induces no flow through the disk and is not included.)
        """
        starts, ends, ages = [], [], []
        phi = self.ages()
        for k in range(self.blades):
            pts = self.filament(azimuth + 2.0 * math.pi * k / self.blades, release)
            starts.append(pts[:-1])
            ends.append(pts[1:])
            ages.append(0.5 * (phi[:-1] + phi[1:]))
        return np.concatenate(starts), np.concatenate(ends), np.concatenate(ages)

    def blade_velocities(self, points: Array, circulation: Array, release: Array,
                         bound: Array | None = None, core: float = 0.0) -> Array:
        """Velocity the wake induces at blade 0's sections over a revolution, every blade
        trailing as blade 0 does (a periodic response with the blades alike).

        Parameters
        ----------
        points
            (n_ψ, n_p, 3) the sections' positions (m) with blade 0 at azimuths 2πj/n_ψ.
        circulation
            (n_ψ,) a blade's tip-vortex circulation Γ_v (m²/s) at those azimuths: each wake
            segment carries the value of its blade when it was trailed (at its midpoint's
            age).
        release
            (n_ψ, 3) the tip vortex's release point (m) at those azimuths (:meth:`filament`).
        bound
            (n_ψ, 2, 3) the bound vortex's inner and outer ends (m) at those azimuths: the
            other blades' bound vortices, of circulation Γ_v, induce flow at blade 0 too (its
            own, on its sections' line, is left out); ``None``: not included.
        core
            Vatistas core radius r_c (m) of the tip vortices.

        Returns
        -------
        (n_ψ, n_p, 3) velocities (m/s) at the sections' positions.
        """
        n_psi = len(circulation)
        shape_ok = (points.ndim == 3 and points.shape[0] == n_psi and points.shape[2] == 3
                    and release.shape == (n_psi, 3)
                    and (bound is None or bound.shape == (n_psi, 2, 3)))
        if not shape_ok:
            raise ValueError(f"wake: points {points.shape}, circulation {circulation.shape}, "
                             f"release {release.shape} and bound "
                             f"{None if bound is None else bound.shape} must be (n, p, 3), "
                             "(n,), (n, 3) and (n, 2, 3)")
        if n_psi % self.blades:
            raise ValueError(f"wake: {n_psi} azimuths must be a multiple of the {self.blades} "
                             "blades (the blades sit on the grid)")
        out = np.empty_like(points)
        step = n_psi // self.blades
        for j in range(n_psi):
            psi = 2.0 * math.pi * j / n_psi
            a, b, age = self.segments(psi, release)
            blade = np.repeat(np.arange(self.blades), len(age) // self.blades)
            gam = periodic_interp(psi + 2.0 * math.pi * blade / self.blades - age, circulation)
            rc = np.full(len(gam), core)
            if bound is not None and self.blades > 1:
                others = [(j + k * step) % n_psi for k in range(1, self.blades)]
                a = np.concatenate([a, bound[others, 0]])
                b = np.concatenate([b, bound[others, 1]])
                gam = np.concatenate([gam, circulation[others]])
                rc = np.concatenate([rc, np.full(len(others), core)])
            out[j] = induced_velocity(points[j], a, b, gam, rc)
        return out


def periodic_interp(angle: ArrayLike, samples: Array) -> Array:
    """Samples of a 2π-periodic function at 2πj/n (along the first axis of ``samples``, the
    others carried along), interpolated linearly at ``angle`` (rad)."""
    n = len(samples)
    x = np.mod(np.asarray(angle, dtype=float) / (2.0 * math.pi), 1.0) * n
    j = np.floor(x).astype(np.int64)
    f = (x - j).reshape(x.shape + (1,) * (np.ndim(samples) - 1))
    j %= n
    return (1.0 - f) * samples[j] + f * samples[(j + 1) % n]
