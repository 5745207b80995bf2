"""The bifilar pendulum on a spinning hub, built from basic joints as in the paper (Fig. 7).

Multibody representation (one bifilar):

* hub — spinning at Ω about z (a prescribed body here; a free rigid body in :mod:`studies.hub`);
  it carries the support arm's tracking hole C1;
* link1 — massless fictitious link: curve sliding joint on C1 with all three rotation
  constraints (it carries the Frenet triad of C1 at the contact point A); the pin centre P is at
  d/2 along its normal;
* pin — the tuning pin's inner race: revolute joint to link1 at P (axis z); it carries the pins'
  mass and polar inertia;
* link2 — massless fictitious link: curve sliding joint (with rotation constraints) on the tuning
  mass's hole C2; revolute joint to the pin at P;
* tuning mass — a rigid body carrying C2, kept from rotating relative to the hub by one rotation
  constraint about z (in the real device the second pin does this);
* rolling ṡ1 = d/2·θ̇ and ṡ2 = d/2·γ̇ (Eq. 5) and the arc-length relations (Eq. 25).

Why one pin: the two pins sit symmetrically about the radial line through the tuning mass's
centre of mass and the tuning mass translates, so the two pins move identically apart from a
constant offset ±c; their kinetic energies add and the ±c cross terms of their centrifugal
potentials cancel. One pin carrying both pins' mass 2m_p and polar inertia 2I_p, on the radial
line, is therefore exact (Eq. 7 with errata 5), and the constraint set has no redundancy:
the pin chain fixes the tuning mass's out-of-plane motion and tilts, the z rotation lock its
remaining rotation (3 + 2 + 1 in-plane unknowns, 2 rolling relations: one degree of freedom).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from solver.bodies import RigidBody, spinning
from solver.curve_joints import ArcLength, CurveSliding, Rolling
from solver.forces import RelativeRotation
from solver.joints import Orientation, Revolute, Rigid
from solver.model import Model
from solver.rotations import rotation_about
from solver.simulation import simulate as simulate_model
from studies.holes import SHAPES, Geometry, Holes, designed
from studies.measure import period_from_crossings
from studies.parameters import (
    RUN_OUTPUTS,
    ModelSpec,
    Output,
    Param,
    ParameterError,
    Parameters,
    run_facts,
)

Z = np.array([0.0, 0.0, 1.0])

# A UH-60-class bifilar (no public source gives the hardware: these are assumptions, sized
# so that Eq. (7) gives 3P at 27 rad/s with holes of a few centimetres, as the paper describes):
# tuning mass 13.6 kg (30 lb) per bifilar; hole centre on the arm 0.40 m from the hub centre;
# centre of mass 0.05 m outboard of the mass's hole centre; steel pins 30 mm in diameter,
# 0.5 kg each (≈ 90 mm long), polar inertia ½ m r² = 5.6e-5 kg·m².
#
# The bifilar hardware and operating point, declared once: the hub model (studies.hub) uses the
# same declarations. Ranges are physical plausibility bounds for a rotorcraft bifilar (the
# geometry itself is checked by studies.holes.design).
HARDWARE: dict[str, Param] = {
    "hole": Param("circle", "1", "tracking hole shape", choices=SHAPES),
    "tuning_order": Param(3.0, "1", "target small-amplitude tuning order n = ω/Ω",
                          minimum=0.5, maximum=10.0),
    "hub_speed": Param(27.0, "rad s-1", "rotor speed Ω", minimum=1.0, maximum=200.0),
    "arm_radius": Param(0.40, "m", "R0: hub centre to the hole centre on the support arm",
                        minimum=0.01, maximum=5.0),
    "cm_offset": Param(0.05, "m", "Rm: tuning mass hole centre to its centre of mass",
                       minimum=0.0, maximum=1.0),
    "tuning_mass": Param(13.6, "kg", "tuning mass m_b of one bifilar", minimum=0.1,
                         maximum=500.0),
    "pin_mass": Param(0.5, "kg", "mass of one pin m_p", minimum=0.0, maximum=50.0),
    "pin_diameter": Param(0.030, "m", "pin diameter d", minimum=0.001, maximum=0.5),
    "pin_inertia": Param(5.6e-5, "kg m2", "polar moment of inertia of one pin I_p",
                         minimum=0.0, maximum=1.0),
}

PARAMETERS: dict[str, Param] = {
    "hole": HARDWARE["hole"],
    "hole_diameter": Param(0.0, "m", "circular hole diameter D (0: size from tuning_order)",
                           minimum=0.0, maximum=2.0),
    **{name: HARDWARE[name] for name in ("tuning_order", "hub_speed", "arm_radius",
                                         "cm_offset", "tuning_mass", "pin_mass",
                                         "pin_diameter", "pin_inertia")},
    "amplitude": Param(10.0, "degree", "release angle (pin angle φ for circles; turn of the "
                       "path tangent from the vertex otherwise)", minimum=0.0,
                       exclusive_minimum=True, maximum=60.0),
    "periods": Param(4.0, "1", "simulated duration in linear periods", minimum=2.0,
                     maximum=1000.0),
    "steps_per_period": Param(400, "1", "time steps per linear period", minimum=16,
                              maximum=100000),
    "scheme": Param("ep", "1", "time integration scheme", choices=("ep", "ed", "galpha")),
    "pin_damping": Param(0.0, "N m s rad-1", "rolling resistance: torque per relative pin "
                         "rotation rate", minimum=0.0, maximum=100.0),
}

# What a run returns; the sweep archive keeps the scalar results and the histories marked
# ``history`` (whole, per case).
OUTPUTS: dict[str, Output] = {
    "time": Output("s", "time", dims=("time",)),
    "relation": Output("1", "rolling or arc-length relation", dims=("relation",)),
    "pin_angle": Output("degree", "pin angle (turn of the hole tangent at the contact from the "
                        "vertex)", history=True, figure="pin_angle_history"),
    "mass_x": Output("m", "tuning mass centre of mass, hub frame, radial", history=True),
    "mass_y": Output("m", "tuning mass centre of mass, hub frame, tangential", history=True),
    "jacobi": Output("J", "Jacobi integral T + V − Ω L_z (energy in the rotating frame; "
                     "Ω̃ = 2tan(Ωh/2)/h for ep)"),
    "energy_balance": Output("J", "energy minus the work of the hub driver (constant for ep)"),
    "rolling_residual": Output("m s-1", "residual of the rolling and arc-length relations as "
                               "the scheme enforces them: A(q_m)(q_f − q_i)/h for ep, "
                               "A(q_f) v_f otherwise", dims=("time", "relation")),
    "constraint_violation": Output("1", "max |C| over holonomic constraints (pins on both "
                                   "curves)"),
    "frequency_order": Output("1", "ω/Ω measured from the free response in the rotating frame",
                              dims=()),
    "frequency_order_linear": Output("1", "small-amplitude order, Eq. (7)", dims=()),
    "vertex_radius": Output("m", "hub centre to the vertex of the tuning mass's path R_v",
                            dims=()),
    "vertex_curvature_radius": Output("m", "radius of curvature of the path at its vertex ρ_v",
                                      dims=()),
    "equivalent_hole_diameter": Output("m", "diameter D of the circular holes with the same "
                                       "vertex curvature (ρ_v = D − d)", dims=()),
    "cycloid_a": Output("m", "generating circle radius a of the cycloidal path", dims=(),
                        optional=True),
    "epicycloid_a": Output("m", "fixed circle radius a of the epicycloidal path", dims=(),
                           optional=True),
    "epicycloid_b": Output("m", "rolling circle radius b of the epicycloidal path", dims=(),
                           optional=True),
    **RUN_OUTPUTS,
}


def holes_for(p: Parameters) -> Holes:
    """The pendulum's designed holes: of ``hole_diameter`` if given, else sized for
    ``tuning_order`` (raises ParameterError for impossible geometry). A pendulum case's
    derived design is its holes alone: its run and its validation share them
    (:func:`studies.holes.designed`)."""
    if p.hole_diameter > 0:
        return designed(p.hole, Geometry.of(p), hole_diameter=p.hole_diameter)
    return designed(p.hole, Geometry.of(p), tuning_order=p.tuning_order)


def check(p: Parameters) -> None:
    """The geometry must admit the holes (raises ParameterError)."""
    holes_for(p)


@dataclass
class BifilarParts:
    """Handles to one bifilar's bodies and joints, for outputs."""

    angle: float
    holes: Holes
    mass: RigidBody
    pin: RigidBody
    link1: RigidBody | None
    joint1: CurveSliding | None
    locked: bool


def _pose(holes: Holes, sig: float, q: np.ndarray, c0: np.ndarray) -> dict[str, Any]:
    """The bifilar's configuration at path parameter ``sig`` (global, hub frame = identity,
    bifilar rotation ``q``, hub centre ``c0``): the tuning mass's centre of mass, the pin centre,
    the contact points a1, a2 with the holes' Frenet triads r1, r2 there and their curve
    parameters."""

    def glob(p2):  # bifilar-frame 2-D point -> global 3-D
        return c0 + q @ np.array([p2[0], p2[1], 0.0])

    cm = glob(holes.path(np.array([sig]))[0])
    pin_c = glob(holes.pin_center(sig))
    eta1 = holes.c1.closest_eta(np.array([*holes.hole_point(sig)[0], 0.0]))
    a1 = c0 + q @ holes.c1.point(eta1)
    # contact on the tuning mass's hole: diametrically opposite a1 on the pin (|P − a1| = d/2),
    # in the mass's frame (= the bifilar frame at t = 0)
    b_loc = q.T @ (2.0 * pin_c - a1 - cm)
    eta2 = holes.c2.closest_eta(b_loc)
    return {"cm": cm, "pin": pin_c, "a1": a1, "r1": q @ holes.c1.frame(eta1)[0], "eta1": eta1,
            "a2": cm + q @ holes.c2.point(eta2), "r2": q @ holes.c2.frame(eta2)[0],
            "eta2": eta2}


def add_bifilar(model: Model, hub, holes: Holes, amplitude: float, angle: float = 0.0,
                prefix: str = "", omega: float = 0.0, locked: bool = False,
                pin_damping: float = 0.0, hub_center=(0.0, 0.0, 0.0), rate: float = 0.0,
                hub_velocity=(0.0, 0.0, 0.0)) -> BifilarParts:
    """Add one bifilar to ``model`` on ``hub`` (whose frame is the identity at t = 0).

    ``angle`` (rad) places the bifilar's radial line about z; ``amplitude`` (rad) is the pin
    angle at t = 0 and ``rate`` (rad/s) its rate; ``omega`` (rad/s) the hub speed and
    ``hub_center``, ``hub_velocity`` (m, m/s, global) the position and velocity of the hub
    centre at t = 0, for the initial velocities (with ``rate`` = 0: at rest relative to the
    hub); ``locked`` clamps the tuning mass and the pins to the hub (the paper's case 0).
    """
    g = holes.geometry
    q = rotation_about(Z, angle)
    c0 = np.asarray(hub_center, dtype=float)
    v0 = np.asarray(hub_velocity, dtype=float)
    w = omega * Z
    sig = holes.sigma_of_angle(amplitude)
    pose = _pose(holes, sig, q, c0)
    cm, pin_c = pose["cm"], pose["pin"]
    # velocities relative to the hub: the swing's, by central differences of the same
    # configuration in the pin angle; the links turn with their triads, and the pin spins so
    # that it rolls on the arm's hole (its contact point at rest on the hub:
    # v_P + ω ẑ × (a1 − P) = 0)
    rel = dict.fromkeys(("cm", "pin", "a1", "a2"), np.zeros(3))
    spin = dict.fromkeys(("r1", "r2", "pin"), 0.0)
    if rate and not locked:
        d = 1e-6  # rad
        hi, lo = (_pose(holes, holes.sigma_of_angle(amplitude + e), q, c0) for e in (d, -d))
        rel = {k: (hi[k] - lo[k]) * (rate / (2 * d)) for k in rel}
        for k in ("r1", "r2"):  # z component of the triad's turn rate: (ṙ rᵀ)[1, 0]
            spin[k] = float(((hi[k] - lo[k]) @ pose[k].T)[1, 0] * (rate / (2 * d)))
        arm = pose["a1"] - pose["pin"]
        spin["pin"] = -float(np.cross(arm, rel["pin"])[2] / (arm @ arm))

    def vel(x, key):  # hub centre's velocity + rotation about it + the swing
        return v0 + np.cross(w, x - c0) + rel[key]

    jp = 2.0 * g.pin_inertia
    mass = RigidBody(f"{prefix}mass", g.tuning_mass, inertia=(0.0, 0.0, 0.0), position=cm,
                     orientation=q, velocity=vel(cm, "cm"), angular_velocity=w)
    pin = RigidBody(f"{prefix}pin", 2.0 * g.pin_mass, inertia=(0.5 * jp, 0.5 * jp, jp),
                    position=pin_c, orientation=q, velocity=vel(pin_c, "pin"),
                    angular_velocity=w + spin["pin"] * Z)
    if locked:
        model.add(mass, pin, Rigid(f"{prefix}lock", hub, mass, point=cm),
                  Rigid(f"{prefix}pinlock", hub, pin, point=pin_c))
        return BifilarParts(angle, holes, mass, pin, None, None, True)
    a1, a2, eta1, eta2 = pose["a1"], pose["a2"], pose["eta1"], pose["eta2"]
    link1 = RigidBody(f"{prefix}link1", 0.0, position=a1, orientation=pose["r1"],
                      velocity=vel(a1, "a1"), angular_velocity=w + spin["r1"] * Z)
    link2 = RigidBody(f"{prefix}link2", 0.0, position=a2, orientation=pose["r2"],
                      velocity=vel(a2, "a2"), angular_velocity=w + spin["r2"] * Z)
    # the arm's hole, placed on the hub by the bifilar's rotation (one curve for all bifilars)
    j1 = CurveSliding(f"{prefix}slide1", hub, holes.c1, link1, point=a1, eta0=eta1,
                      rotation=True, placement=(q, c0 * 0.0))
    j2 = CurveSliding(f"{prefix}slide2", mass, holes.c2, link2, point=a2, eta0=eta2,
                      rotation=True)
    arc1, arc2 = ArcLength(j1), ArcLength(j2)
    rd = 0.5 * g.pin_diameter
    model.add(mass, link1, pin, link2, j1, j2,
              Revolute(f"{prefix}rev1", link1, pin, point=pin_c, axis=Z),
              Revolute(f"{prefix}rev2", link2, pin, point=pin_c, axis=Z),
              Orientation(f"{prefix}nospin", hub, mass, point=cm, axis=Z, axes=(2,)),
              arc1, arc2,
              Rolling(f"{prefix}roll1", arc1, pin, link1, rd, side=1),
              Rolling(f"{prefix}roll2", arc2, pin, link2, rd, side=1))
    if pin_damping > 0:
        model.add(RelativeRotation(f"{prefix}rolling_resistance", link1, pin, axis=Z,
                                   damping=pin_damping))
    return BifilarParts(angle, holes, mass, pin, link1, j1, False)


def pin_angle(system, parts: BifilarParts, hub, q: np.ndarray) -> float:
    """Release-angle measure (rad): the turn of the arm hole's tangent at the contact point
    relative to the vertex tangent, in the hub frame (for circular holes: the pin angle φ)."""
    rh = system.directors(q, hub)
    t = rh.T @ system.directors(q, parts.link1)[:, 0]
    # turned back by the bifilar's angle about the hub's axis z (a sampler asks at every step)
    c, s = math.cos(parts.angle), math.sin(parts.angle)
    return math.atan2(-(c * t[0] + s * t[1]), c * t[1] - s * t[0])


def build(p: Parameters, holes: Holes | None = None):
    """Hub spinning at Ω (prescribed) with one bifilar released at the given amplitude, in
    ``holes`` (default :func:`holes_for`'s)."""
    holes = holes_for(p) if holes is None else holes
    model = Model()
    hub = spinning("hub", p.hub_speed)
    model.add(hub)
    parts = add_bifilar(model, hub, holes, np.radians(p.amplitude), omega=p.hub_speed,
                        pin_damping=p.pin_damping)
    return model, hub, parts


def run(given: Mapping[str, Any] | Parameters = ()) -> xr.Dataset:
    """One pendulum case from its parameters (validated here unless they are the pendulum's
    :class:`~studies.parameters.Parameters` already): see :func:`simulate`."""
    return simulate(SPEC.validate(given))


def simulate(p: Parameters) -> xr.Dataset:
    """Simulate the free response and measure the tuning order ω/Ω."""
    from solver.system import System

    model, hub, parts = build(p)
    omega = p.hub_speed
    order_lin = parts.holes.order_linear
    t_lin = 2 * np.pi / (order_lin * omega)
    h = t_lin / p.steps_per_period
    sysm = System(model)
    # The midpoint rule turns the hub by Δψ with 2 tan(Δψ/2) = Ω̃ h per step in Cayley form,
    # so its discrete Jacobi integral is T + V − Ω̃ L_z with Ω̃ = 2 tan(Ω h/2)/h (→ Ω as
    # h → 0). Without pin inertia it is constant to roundoff; the pins' spin adds a bounded
    # O(h² A²) oscillation (1e-12 at 1°, 4e-9 at 30° with the defaults). Exactly constant is
    # the energy minus the work of the hub driver, recorded as ``energy_balance``.
    omega_j = 2.0 * np.tan(0.5 * omega * h) / h if p.scheme == "ep" else omega
    rec: dict[str, list] = {k: [] for k in ("t", "phi", "x", "y", "jacobi", "roll", "viol",
                                              "balance")}
    prev = {"q": None}

    def record(integ):
        q, v = integ.q, integ.v
        rec["t"].append(integ.t)
        rec["phi"].append(pin_angle(sysm, parts, hub, q))
        rh = sysm.directors(q, hub)
        xm = rh.T @ q[sysm.offset[parts.mass] : sysm.offset[parts.mass] + 3]
        rec["x"].append(xm[0])
        rec["y"].append(xm[1])
        lz = sysm.angular_momentum(q, v)[2]
        energy = sysm.kinetic(v) + sysm.potential(q)
        rec["jacobi"].append(energy - omega_j * lz)
        rec["balance"].append(energy - integ.work)
        if p.scheme == "ep":  # what EP enforces: A(q_m)(q_f − q_i)/h = 0
            if prev["q"] is not None:
                dq = q - prev["q"]
                rec["roll"].append(sysm.nonholonomic_residual(prev["q"] + 0.5 * dq, dq) / h)
            else:
                rec["roll"].append(np.zeros(sysm.mn))
        else:  # generalized-α and ED enforce A(q_f) v_f = 0
            rec["roll"].append(sysm.nonholonomic_residual(q, v))
        rec["viol"].append(integ.violation())
        prev["q"] = q.copy()

    sim = simulate_model(model, p.periods * t_lin, h, scheme=p.scheme, reactions=False,
                   record_every=10**9, system=sysm, callback=record, record_initial=True)
    t = np.array(rec["t"])
    phi = np.degrees(np.array(rec["phi"]))
    period = period_from_crossings(t, phi, center=0.0) if sim.converged else float("nan")
    order = 2 * np.pi / period / omega if np.isfinite(period) else float("nan")
    holes = parts.holes
    shape = {k: np.float64(v) for k, v in holes.params.items()
             if k in ("cycloid_a", "epicycloid_a", "epicycloid_b")}
    return SPEC.dataset({
        **shape,
        "vertex_radius": np.float64(holes.params["vertex_radius"]),
        "vertex_curvature_radius": np.float64(holes.rho_v),
        "equivalent_hole_diameter": np.float64(holes.hole_diameter),
        **run_facts(sim, h),
        "time": t,
        "relation": sysm.relation_names,
        "pin_angle": phi,
        "mass_x": np.array(rec["x"]),
        "mass_y": np.array(rec["y"]),
        "jacobi": np.array(rec["jacobi"]),
        "energy_balance": np.array(rec["balance"]),
        "rolling_residual": np.array(rec["roll"]),
        "constraint_violation": np.array(rec["viol"]),
        "frequency_order": order,
        "frequency_order_linear": order_lin,
    }, {"message": sim.message})


def compile_kernels(scheme: str = "ep", steps: int = 3) -> None:
    """Compile every kernel a bifilar calls into numba's cache (or load it from there): the
    pendulum at its defaults, built and marched ``steps`` steps with ``scheme``.

    A warm-up part (:attr:`ModelSpec.warm_up`) of this model, of :mod:`studies.hub` and of
    :mod:`studies.rotor`: a few steps call every kernel a case calls, the curve sliding and
    rolling joints' the most expensive to compile (5–10 s of its 14 s alone). The pins
    are damped, as the hub's and the rotor's are (their dampers have kernels of their own).
    """
    from solver.integrators import make_integrator
    from solver.system import System

    p = SPEC.validate({"scheme": scheme, "pin_damping": 1.0})
    model, _, parts = build(p)
    h = 2 * np.pi / (parts.holes.order_linear * p.hub_speed) / p.steps_per_period
    integ = make_integrator(System(model), scheme, h)
    for _ in range(steps):
        integ.step()


def _check_params(p: Parameters) -> None:
    if p.hole_diameter > 0 and p.hole != "circle":
        raise ParameterError("hole_diameter applies to circular holes; give tuning_order for "
                             f"hole = {p.hole!r}")
    check(p)


SPEC = ModelSpec("pendulum", PARAMETERS, simulate, _check_params,
                 description="one bifilar pendulum on a hub spinning at constant speed",
                 outputs=OUTPUTS, version="3", warm_up=(compile_kernels,))
