"""The rotor's prescribed vortex wake, iterated with its periodic response.

With ``inflow = "prescribed_wake"`` the induced velocity the rotor's lifting lines see on the
periodic response is that of a prescribed tip-vortex wake
(:class:`solver.vortex_wake.TipVortexWake`): each blade trails a tip vortex from
``wake_release_radius`` (the tip-loss station, where the lifting line's circulation drops to
zero) along Beddoes' generalized wake (or a rigid skewed helix), of the blade's
thrust-equivalent circulation when it was trailed, Γ_v ∫ r dr = ∫ Γ r dr over the lifting
span (so that the far wake carries the rotor's thrust, and a local spike of circulation where
a vortex passes a blade does not feed the next vortex), with a Vatistas core of
``wake_core_radius`` tip chords. The other blades' bound vortices, of the same strength, are
included. The shed wake of each section is the Peters finite-state airfoil's.

How it enters the model. The wake is not a state: it is a velocity per section and per
azimuth (:class:`solver.section_wind.PeriodicWind`, one table for the four blades, each a
quarter revolution behind the previous one, so that the model keeps its quarter-revolution
symmetry). The Peters–He inflow states stay in the model, and the table is the *correction*
from their periodic inflow to the wake's: v_table = v_wake − v_Peters–He, both from the
previous revolution. On the periodic response (the fixed point) the sections see exactly the
wake's velocity, whatever the Peters–He truncation (M = 4 instead of 2 moves the 4P hub loads
by 0.3 %); away from it the inflow keeps the Peters–He states' dynamics, so that the rotor's
transients and stability are those of the validated finite-state model rather than of an
inflow frozen over a revolution. Each section sees the wake's
velocity averaged over its width (:data:`SUBSECTIONS` points): a vortex passing a blade makes a
spike that quadrature points would sample, not integrate.

The iteration. The first settling revolution runs on Peters–He alone; after each settling
revolution the table is updated from blade 0's last revolution (its sections' positions, its
tip, its circulation and the Peters–He inflow at every time step) with under-relaxation
``wake_relaxation``, the wake computed at every fourth azimuth and interpolated between
(:meth:`RotorWake.update`'s ``stride``: those tables only bring the wake near its fixed
point); then the run alternates shooting to the periodic response for the current
table and updating it (Anderson-accelerated: :func:`anderson_step`), until the update changes
the table by less than ``wake_tolerance`` of its largest value. Each of those periodic
responses is found only as closely as the table it answers is known: to the last update's
change (:func:`studies.rotor.wake_response_tolerance`), the last to the case's tolerance.
The wake's geometry needs the mean induced inflow (its descent through the disk): momentum
theory's (Glauert) for the thrust of the previous revolution.

Assumptions: the wake is prescribed, not free (no self-induced distortion beyond Beddoes'
descent law, no contraction in hover); one rolled-up tip vortex per blade, no inboard trailed
vorticity and no root vortex (it induces no flow through the disk), and a negatively loaded
advancing tip's counter-rotating vortex is not modelled; the circulation's change along a tip
vortex stands for the shed vorticity that would join it; the core radius is constant with age
and, at one chord, stands for the chordwise averaging that a lifting line (2-D sections at
the quarter chord) cannot resolve closer to a vortex (thinner cores give blade-vortex spikes
that no section spacing resolves).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import NDArray

from solver.inflow import glauert_inflow
from solver.section_wind import PeriodicWind
from solver.vortex_wake import DESCENT_LAWS, TipVortexWake, periodic_interp
from studies.parameters import Param, Parameters
from studies.uh60a import UH60A

Array = NDArray[np.float64]
INFLOW_MODELS = ("peters_he", "prescribed_wake")

PARAMETERS: dict[str, Param] = {
    "inflow": Param("prescribed_wake", "1", "rotor inflow model: Peters–He finite states, or those "
                    "corrected to the inflow of a prescribed tip-vortex wake iterated with the "
                    "periodic response",
                    choices=INFLOW_MODELS),
    "wake_turns": Param(4.0, "1", "length of the prescribed wake, in revolutions of age",
                        minimum=0.5, maximum=50.0),
    "wake_segments_per_turn": Param(72, "1", "straight vortex segments per revolution of "
                                    "wake age", minimum=12, maximum=1440),
    "wake_core_radius": Param(1.0, "1", "Vatistas core radius of the tip vortices as the "
                              "lifting lines see them, in tip chords (a lifting line resolves "
                              "no flow detail closer than about a chord)", minimum=0.05,
                              maximum=5.0),
    "wake_release_radius": Param(UH60A.tip_loss, "1", "radius the tip vortices leave the "
                                 "blades at, on R (the tip-loss station: the circulation "
                                 "drops to zero there)", minimum=0.5, maximum=1.0),
    "wake_descent": Param("beddoes", "1", "descent law of the prescribed wake",
                          choices=DESCENT_LAWS),
    "wake_relaxation": Param(0.5, "1", "under-relaxation of the wake's updates (1: none)",
                             minimum=0.05, maximum=1.0),
    "wake_tolerance": Param(5e-3, "1", "largest change of the wake's induced velocity between "
                            "iterations, relative to its largest value, for convergence",
                            minimum=0.0, exclusive_minimum=True, maximum=0.5),
    "wake_error_estimate": Param(True, "1", "estimate the wake's truncation error of the 4P "
                                 "hub loads (run_wake_error_estimate) by one more periodic "
                                 "response with the wake refined"),
    "wake_iterations": Param(15, "1", "wake updates allowed after settling, at each setting of "
                             "the controls (a trim's)", minimum=1,
                             maximum=100),
}

# Below this chordwise speed (on ΩR) a section's circulation is not read from its lift
# (reversed-flow region near the retreating root).
MIN_SPEED_FRACTION = 0.05
# Iterates Anderson's acceleration combines (RotorWake.update).
ANDERSON_DEPTH = 5
# Points over each section's width at which the wake's velocity is averaged: a tip vortex
# passing a blade makes a spike a few core radii wide, which the sections (Gauss points of the
# blade elements, 0.3–0.9 m apart) would sample, not integrate.
SUBSECTIONS = 4


class RotorWake:
    """The prescribed wake of a rotor case: its induced velocity table and the histories of
    blade 0 it is computed from.

    Parameters
    ----------
    p
        The rotor's parameters (:data:`PARAMETERS` among them).
    span, widths
        Arc length s (m) and quadrature weight ds (m) of each aerodynamic section of a blade
        (:attr:`solver.lifting_line.LiftingLine.sections`).
    blades
        Number of blades Q; blade k trails a quarter (1/Q) revolution behind blade k − 1.
    """

    def __init__(self, p: Parameters, span: Array, widths: Array, blades: int) -> None:
        n_sections = len(span)
        self.p = p
        # each section sees the wake's velocity averaged over SUBSECTIONS points spread over
        # its width ds (positions interpolated linearly along the span between sections)
        u = (np.arange(SUBSECTIONS) + 0.5) / SUBSECTIONS - 0.5
        sub = (span[:, None] + widths[:, None] * u).ravel()
        i = np.clip(np.searchsorted(span, sub), 1, n_sections - 1)
        self._sub = (i, (sub - span[i - 1]) / (span[i] - span[i - 1]))
        self.omega = p.hub_speed
        self.n = p.steps_per_rev
        self.blades = blades
        self.period = 2.0 * math.pi / self.omega
        self.table = np.zeros((self.n, n_sections, 3))
        # blade k at time t is where blade 0 is at t + kT/Q
        self.winds = [PeriodicWind(self.period, self.table, delay=k * self.period / blades)
                      for k in range(blades)]
        # the forward shaft tilt (rad) the wake's geometry is laid out for: a trim that tilts
        # the shaft sets it before each update
        self.shaft_tilt = math.radians(p.shaft_tilt)
        # blade 0's histories over its last revolution, by azimuth slot
        self.points = np.zeros((self.n, n_sections, 3))
        self.inflow = np.zeros((self.n, n_sections, 3))
        self.gamma = np.zeros(self.n)
        self.tip = np.zeros((self.n, 3))
        self.root = np.zeros((self.n, 3))
        self.thrust = np.zeros(self.n)
        self.filled = np.zeros(self.n, dtype=bool)
        # the disk-average weights r ds of the sections inside the tip vortices (from the
        # first recorded step on; until then ds)
        self.weights = widths.copy()
        self.updates = 0
        self.change = math.inf
        self.history: list[tuple[Array, Array]] = []  # (x, G(x) − x) for Anderson
        self.fineness = 1

    # ------------------------------------------------------------------ the wake
    @property
    def mu(self) -> float:
        """Advance ratio: the free stream's component in the disk plane, on ΩR."""
        return (self.p.flight_speed * math.cos(self.shaft_tilt)
                / (self.omega * UH60A.radius))

    @property
    def lam_f(self) -> float:
        """The free stream's inflow through the disk (down), on ΩR."""
        return (self.p.flight_speed * math.sin(self.shaft_tilt)
                / (self.omega * UH60A.radius))

    def wake(self, ct: float) -> TipVortexWake:
        """The wake's geometry for the thrust coefficient ``ct`` (refined :attr:`fineness`
        times in length and segments per turn)."""
        lam0 = max(glauert_inflow(ct, self.mu, self.lam_f), 1e-4)
        return TipVortexWake(UH60A.radius, self.blades, self.mu, self.lam_f, lam0,
                             turns=self.p.wake_turns * self.fineness,
                             segments_per_turn=self.p.wake_segments_per_turn * self.fineness,
                             release_radius=self.p.wake_release_radius,
                             descent=self.p.wake_descent)

    @property
    def core(self) -> float:
        return self.p.wake_core_radius * UH60A.chord

    def _velocities(self, points: Array, gamma: Array, tip: Array, root: Array,
                    ct: float, stride: int = 1) -> Array:
        """The wake's velocity at blade 0's sections at each azimuth slot; with ``stride``,
        computed at every stride-th slot only and interpolated linearly in azimuth between
        (a stride-th of the cost)."""
        n = len(points)
        every = slice(None, None, stride)
        points, gamma, tip, root = points[every], gamma[every], tip[every], root[every]
        bound = np.stack([root, tip], axis=1)
        i, f = self._sub  # the subsections, extrapolated linearly beyond the end sections
        sub = (1.0 - f)[None, :, None] * points[:, i - 1] + f[None, :, None] * points[:, i]
        v = self.wake(ct).blade_velocities(sub, gamma, tip, bound, self.core)
        v = v.reshape(len(points), -1, SUBSECTIONS, 3).mean(axis=2)
        if stride == 1:
            return v
        return periodic_interp(2.0 * math.pi * np.arange(n) / n, v)

    def record(self, t: float, air: dict[str, Array], wind: Array, tip: Array,
               thrust: float) -> None:
        """Keep blade 0's sections, circulation, Peters–He inflow and tip at the time step of
        ``t`` (s), from the lifting lines' ``airloads`` (``line`` 0 is blade 0), the air
        they are given (free stream and wind, :meth:`~solver.lifting_line.LiftingLineSet.air`)
        and blade 0's tip node."""
        j = self.slot(t)
        sel = air["line"] == 0
        # the Peters–He states' induced velocity −λΩR ẑ: the air the sections see less the
        # air they are given
        self.inflow[j] = air["air"][sel] - wind[sel]
        u = air["u"][sel]
        ok = np.abs(u) > MIN_SPEED_FRACTION * self.omega * UH60A.radius
        gam = np.where(ok, air["lift"][sel] / (self.p.air_density * np.where(ok, u, 1.0)), 0.0)
        pos = air["position"][sel]
        self.points[j] = pos
        # the tip vortex of the blade's thrust: Γ_v ∫ r dr = ∫ Γ r dr over the lifting span
        r = np.hypot(pos[:, 0], pos[:, 1])
        self.weights = r * air["ds"][sel] * (r < self.p.wake_release_radius * UH60A.radius)
        self.gamma[j] = float(np.sum(gam * self.weights) / np.sum(self.weights))
        self.root[j] = pos[0]
        self.tip[j] = self.p.wake_release_radius * tip
        self.thrust[j] = thrust
        self.filled[j] = True

    def slot(self, t: float) -> int:
        """The azimuth slot (time step of the revolution) of blade 0 at time ``t`` (s)."""
        return round(t * self.omega / (2.0 * math.pi) * self.n) % self.n

    def mean_inflow(self, t: float) -> float:
        """The induced inflow λ (on ΩR, down through the disk) the blades' sections see at
        time ``t`` (Peters–He's and the correction's), averaged over the disk inside the tip
        vortices (weights r ds): on the periodic response, the wake's."""
        j, quarter = self.slot(t), self.n // self.blades
        w = -np.mean([self.table[i, :, 2] + self.inflow[i, :, 2]
                      for i in ((j + k * quarter) % self.n for k in range(self.blades))], axis=0)
        return (float(np.sum(w * self.weights) / np.sum(self.weights))
                / (self.omega * UH60A.radius))

    @property
    def thrust_coefficient(self) -> float:
        """C_T of the last recorded revolution."""
        return float(self.thrust.mean()) / UH60A.thrust_unit(self.p.air_density, self.omega)

    def refine(self) -> None:
        """Move the table to the wake refined twice (segments per turn and turns) for the
        last recorded revolution: the wake's truncation error estimate."""
        self.fineness = 2
        self.table[:] = (self._velocities(self.points, self.gamma, self.tip, self.root,
                                          self.thrust_coefficient) - self.inflow)

    def forget(self) -> None:
        """Drop the iterates Anderson's acceleration remembers: after a change of the controls
        the response, and with it the wake's fixed-point map, is another (measured on a
        propulsively trimmed case: with the old iterates kept, the change stalled at 0.067 for
        six updates)."""
        self.history.clear()

    def update(self, accelerate: bool = False, stride: int = 1) -> float:
        """Recompute the wake from blade 0's last revolution and move the table towards it;
        returns the change (relative to the table's largest value) before the move.

        The move is the relaxed step x + β (G(x) − x), or with ``accelerate`` Anderson's
        (type II, the last :data:`ANDERSON_DEPTH` iterates; Walker & Ni, SIAM J. Numer. Anal.
        49, 2011): the residual's least-squares combination of the previous ones, which
        removes the slow directions of the fixed-point map that relaxation alone crawls
        along (one with a factor near 0.7 per update on the UH-60 case). Iterates taken
        without it (settling, where the response is not yet periodic) are not remembered.

        With ``stride`` the wake's velocity is computed at every stride-th azimuth slot only
        (the largest divisor of it that keeps the blades on the coarser grid) and
        interpolated linearly between: a stride-th of the cost, for settling's updates,
        whose tables the later ones replace."""
        if not self.filled.all():
            raise RuntimeError("rotor wake: a whole revolution must be recorded before an "
                               "update")
        stride = max(k for k in range(1, max(1, int(stride)) + 1)
                     if self.n % (k * self.blades) == 0)
        new = (self._velocities(self.points, self.gamma, self.tip, self.root,
                                self.thrust_coefficient, stride) - self.inflow)
        scale = max(float(np.abs(new).max()), 1e-12)
        x, f = self.table.ravel().copy(), (new - self.table).ravel()
        self.change = float(np.abs(f).max()) / scale
        if not accelerate:
            self.history.clear()
        step = anderson_step(self.history, x, f, self.p.wake_relaxation,
                             ANDERSON_DEPTH if accelerate else 0)
        self.table += step.reshape(self.table.shape)
        self.updates += 1
        return self.change


def anderson_step(history: list[tuple[Array, Array]], x: Array, f: Array, beta: float,
                  depth: int) -> Array:
    """The step from ``x`` of Anderson's mixing (type II) for the fixed point of G, given the
    residual f = G(x) − x; ``history`` (the previous (x, f), updated here) keeps the last
    ``depth`` + 1 pairs. With ΔX, ΔF the differences of successive iterates and residuals
    and γ = argmin |f − ΔF γ|, the step is β f − (ΔX + β ΔF) γ; with ``depth`` 0 (or a
    single pair) it is the relaxed step β f. On a linear map of dimension n with unlimited
    depth it is GMRES's iterate, exact after n + 1 steps."""
    if depth <= 0:
        return beta * f
    history.append((x, f))
    del history[: -depth - 1]
    if len(history) < 2:
        return beta * f
    dx = np.stack([b[0] - a[0] for a, b in itertools.pairwise(history)], axis=1)
    df = np.stack([b[1] - a[1] for a, b in itertools.pairwise(history)], axis=1)
    gamma = np.linalg.lstsq(df, f, rcond=1e-10)[0]
    return beta * f - (dx + beta * df) @ gamma
