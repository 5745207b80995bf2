"""The four hub-mounted absorbers as one part, shared by the hub and the rotor models.

Four bifilars (:func:`studies.bifilar.add_bifilar`) at 90° intervals, 45° from the blades, on a
hub spinning at Ω: ``free``, ``locked`` (tuning masses and pins clamped to the hub: the paper's
case 0) or ``equivalent`` (their linear fixed-frame equivalent, :mod:`studies.equivalent`: a
particle on the non-rotating carrier and a rigid mass on the hub). Declared here once: the
inputs that choose and size them, the pin damping from a pendulum damping ratio, the building,
the measured response (pin angles, the tuning masses' centre of mass) and the outputs both
models archive with the same names and units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from solver.model import Model
from studies.bifilar import HARDWARE, BifilarParts, add_bifilar, pin_angle
from studies.equivalent import (
    EquivalentParts,
    add_equivalent,
    equivalent_absorber,
    equivalent_cm,
    equivalent_pin_angles,
    particle_state,
)
from studies.holes import Geometry, Holes, designed
from studies.parameters import Output, Param, Parameters

N_BIFILARS = 4
FIRST_ANGLE = np.pi / 4  # bifilar 0 at 45° from blade 0
AZIMUTHS = FIRST_ANGLE + 2 * np.pi * np.arange(N_BIFILARS) / N_BIFILARS  # at t = 0 (rad)

PARAMETERS: dict[str, Param] = {
    "bifilar": Param("free", "1", "bifilar tuning masses free, locked to the hub, or replaced "
                     "by their linear fixed-frame equivalent",
                     choices=("free", "locked", "equivalent")),
    "tuning_order": HARDWARE["tuning_order"],
    "hole": HARDWARE["hole"],
    "hub_speed": HARDWARE["hub_speed"],
    **{name: HARDWARE[name] for name in ("arm_radius", "cm_offset", "tuning_mass", "pin_mass",
                                         "pin_diameter", "pin_inertia")},
    "pin_damping_ratio": Param(0.01, "1", "pendulum damping ratio from rolling resistance",
                               minimum=0.0, maximum=0.5),
}

# The hub-level results of both models (the rotor adds its own): whole revolutions of time
# histories; the in-plane vectors (components) get their per-rev harmonics archived; the
# histories marked ``history`` are archived over the last revolution; ``figure`` names the
# report figure that draws them (pipelines.plots).
OUTPUTS: dict[str, Output] = {
    "time": Output("s", "time", dims=("time",)),
    "bifilar": Output("1", "bifilar absorber number (0 and 2 are opposite)", dims=("bifilar",)),
    "hub_x_fixed": Output("m", "hub in-plane displacement x, fixed frame", history=True),
    "hub_y_fixed": Output("m", "hub in-plane displacement y, fixed frame", history=True),
    "hub_x_rotating": Output("m", "hub in-plane displacement along the rotating x axis"),
    "hub_y_rotating": Output("m", "hub in-plane displacement along the rotating y axis"),
    "hub_force_x_fixed": Output("N", "in-plane force transmitted to the fuselage, x",
                                history=True, figure="hub_force_history"),
    "hub_force_y_fixed": Output("N", "in-plane force transmitted to the fuselage, y",
                                history=True, figure="hub_force_history"),
    "bifilar_cm_x_fixed": Output("m", "centre of mass of the 4 tuning masses, x", history=True),
    "bifilar_cm_y_fixed": Output("m", "centre of mass of the 4 tuning masses, y", history=True),
    "pin_angle": Output("degree", "pin angle of each bifilar", dims=("bifilar", "time"),
                        history=True, harmonics=True, figure="pin_angles"),
    "hub_displacement_rotating": Output(
        "m", "hub in-plane displacement in the rotating frame",
        components=("hub_x_rotating", "hub_y_rotating")),
    "hub_displacement_fixed": Output(
        "m", "hub in-plane displacement in the fixed frame",
        components=("hub_x_fixed", "hub_y_fixed"), figure="orbits"),
    "hub_force_fixed": Output(
        "N", "in-plane hub force transmitted to the fuselage, fixed frame",
        components=("hub_force_x_fixed", "hub_force_y_fixed")),
    "bifilar_cm_displacement": Output(
        "m", "displacement of the centre of mass of the bifilar tuning masses, fixed frame",
        components=("bifilar_cm_x_fixed", "bifilar_cm_y_fixed"), figure="orbits"),
    "tuning_order_linear": Output("1", "small-amplitude tuning order of the designed holes, "
                                  "Eq. (7) with the pins", dims=()),
    "pin_damping": Output("N m s rad-1", "rotational damping on each pin's rotation relative "
                          "to its link (0 for locked bifilars)", dims=()),
}


def holes_for(p: Parameters) -> Holes:
    """Holes of the requested shape and tuning order (raises ParameterError if the geometry
    admits none), designed once per hardware (:func:`studies.holes.designed`)."""
    return designed(p.hole, Geometry.of(p), tuning_order=p.tuning_order)


def pin_damping(p: Parameters, holes: Holes) -> float:
    """Rotational damping (N·m·s/rad) on the pin's rotation relative to its link giving the
    pendulum damping ratio ζ: the pin turns at (D/d) φ̇ relative to the link for circular
    holes (D the equivalent hole diameter), the pendulum's inertia is r²(m_b + m_p/2 + 2I_p/d²)
    per Eq. (7), so c = 2 ζ ω M_eff (d/D)². Zero for locked bifilars (their pins do not
    turn)."""
    if p.bifilar == "locked":
        return 0.0
    g = holes.geometry
    r = holes.rho_v
    d_hole = holes.hole_diameter
    m_eff = r * r * (g.tuning_mass + 0.5 * g.pin_mass + 2 * g.pin_inertia / g.pin_diameter**2)
    omega = holes.order_linear * p.hub_speed
    return 2.0 * p.pin_damping_ratio * omega * m_eff * (g.pin_diameter / d_hole) ** 2


@dataclass(frozen=True)
class AbsorberStart:
    """The absorbers' state at t = 0: each bifilar's pin angle and its rate (rad, rad/s; the
    equivalent's particle carries their cyclic whirl), and the hub centre's position and
    velocity (m, m/s, global). The default is at rest at the vertex, the hub centre at the
    origin."""

    angles: NDArray[np.float64] = field(default_factory=lambda: np.zeros(N_BIFILARS))
    rates: NDArray[np.float64] = field(default_factory=lambda: np.zeros(N_BIFILARS))
    center: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    velocity: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))


def add_absorbers(model: Model, hub, carrier, holes: Holes, p: Parameters, damping: float,
                  start: AbsorberStart | None = None, tuning_speed: float | None = None
                  ) -> list[BifilarParts] | EquivalentParts:
    """The four absorbers on ``hub`` (spinning at ``hub_speed`` about +z, frame = identity at
    t = 0, centre and state as ``start`` says) as ``p.bifilar`` says, with the pin damping
    ``damping`` (N·m·s/rad, :func:`pin_damping`); the equivalent's particle rides on
    ``carrier`` (non-rotating, d3 the rotor axis), its spring tuned at ``tuning_speed``
    (rad/s; ``None``: at ``hub_speed``, see :func:`studies.equivalent.add_equivalent`).
    Returns the bifilars' parts or the equivalent's."""
    omega = p.hub_speed
    s = start if start is not None else AbsorberStart()
    if p.bifilar == "equivalent":
        # the same rolling resistance, as swing damping
        absorber = equivalent_absorber(holes, N_BIFILARS, damping)
        w0, wd0 = particle_state(absorber, omega, s.angles, s.rates, AZIMUTHS)
        return add_equivalent(model, carrier, hub, s.center, absorber, omega,
                              first_angle=FIRST_ANGLE, displacement=w0, rate=wd0,
                              tuning_speed=tuning_speed)
    locked = p.bifilar == "locked"
    return [add_bifilar(model, hub, holes, 0.0 if locked else s.angles[i], angle=AZIMUTHS[i],
                        prefix=f"b{i}_", omega=omega, locked=locked, pin_damping=damping,
                        hub_center=s.center, hub_velocity=s.velocity,
                        rate=0.0 if locked else s.rates[i])
            for i in range(N_BIFILARS)]


class AbsorberProbe:
    """The absorbers' response at a state: the tuning masses' centre of mass (m, global) and
    each bifilar's pin angle (rad; zero when locked)."""

    def __init__(self, system, parts: list[BifilarParts] | EquivalentParts, hub) -> None:
        self.s = system
        self.parts = parts
        self.hub = hub
        self.equivalent = isinstance(parts, EquivalentParts)
        self.mass_off = [] if self.equivalent else [system.offset[b.mass] for b in parts]

    def __call__(self, q: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        if self.equivalent:
            return (equivalent_cm(self.s, self.parts, q, t),
                    np.asarray(equivalent_pin_angles(self.s, self.parts, q, t)))
        cm = np.mean([q[o : o + 3] for o in self.mass_off], axis=0)
        phis = [0.0 if b.locked else pin_angle(self.s, b, self.hub, q) for b in self.parts]
        return cm, np.array(phis)
