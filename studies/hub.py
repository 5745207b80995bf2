"""A four-bladed rotor hub with four bifilars, on a shaft head restrained by the fuselage.

The model (paper Fig. 13, Table 1, with the fuselage-beam reduced to springs and dampers):

* shaft head — a non-rotating rigid body that translates in the rotor plane (planar joint to
  ground, yaw locked), restrained by in-plane fuselage springs and dampers (stiffness scaled by
  ``fuselage_stiffness_scale``);
* hub — rigid, carrying the rotor's mass and polar inertia, spinning at Ω on the shaft head
  through a driven revolute joint (ψ = Ωt);
* four bifilars (:func:`studies.bifilar.add_bifilar`) at 90° intervals, 45° from the blades, each
  ``free`` or ``locked`` (tuning masses clamped to the hub: the paper's case 0), or, with
  ``equivalent``, their linear fixed-frame equivalent (:mod:`studies.equivalent`: a particle on
  the shaft head and a rigid mass on the hub), whose pin angles and tuning-mass centre of mass
  are reconstructed from the particle for the same outputs;
* excitation — the blades' in-plane root shears as a hub load rotating with the hub, with 3P and
  5P harmonics in the rotating frame: f = A3 e^{i(3ψ+φ3)} + A5 e^{−i(5ψ+φ5)} (complex in-plane
  components in the hub frame); in the fixed frame both are 4P (progressive and regressive),
  as the paper describes for a four-bladed rotor.

The pins dissipate a little (rolling resistance), modelled as a rotational damper on each pin's
rotation relative to its arm-side link, sized from a pendulum damping ratio; the free pendulum
transient then decays and the run stops being transient when two successive revolutions give
the same harmonics within ``periodic_tolerance``. Whole revolutions are then recorded.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import xarray as xr

from solver.bodies import RigidBody, ground
from solver.forces import AppliedLoad, Spring
from solver.integrators import make_integrator
from solver.joints import Orientation, Planar, Revolute
from solver.model import Model
from solver.system import System
from solver.timefunctions import linear
from studies.bifilar import HARDWARE, BifilarParts, add_bifilar, pin_angle
from studies.equivalent import (
    EquivalentParts,
    add_equivalent,
    equivalent_absorber,
    equivalent_cm,
    equivalent_pin_angles,
)
from studies.holes import Geometry, design
from studies.parameters import ModelSpec, Output, Param, ParameterError
from studies.progress import report

Z = np.array([0.0, 0.0, 1.0])
N_BIFILARS = 4
NEWTON_TOL = 1e-11  # relative Newton tolerance on q (m); see run()

# UH-60-class values (public: 4 blades of 116.5 kg, R = 8.18 m, Ω = 27 rad/s). The hub mass,
# shaft-head mass and fuselage restraint are assumptions: the fuselage in-plane mode at the hub
# is placed at 0.9 × 4P with 2% damping (below the 4P excitation, so the hub response is
# mass-controlled and halving the stiffness changes it by tens of percent, the sensitivity the
# paper's case 3 shows), and away from the bifilars' coupled modes.
PARAMETERS: dict[str, Param] = {
    "bifilar": Param("free", "1", "bifilar tuning masses free, locked to the hub, or replaced "
                     "by their linear fixed-frame equivalent",
                     choices=("free", "locked", "equivalent")),
    "tuning_order": HARDWARE["tuning_order"],
    "hole": HARDWARE["hole"],
    "hub_speed": HARDWARE["hub_speed"],
    "fuselage_stiffness_scale": Param(1.0, "1", "scale on the nominal fuselage stiffness",
                                      minimum=0.01, maximum=100.0),
    "fuselage_stiffness": Param(1.015e7, "N m-1", "nominal in-plane fuselage stiffness at the "
                                "hub", minimum=1e4, maximum=1e10),
    "fuselage_damping_ratio": Param(0.02, "1", "damping ratio of the nominal fuselage mode",
                                    minimum=0.0, maximum=1.0),
    "shaft_mass": Param(300.0, "kg", "effective non-rotating mass of the shaft head",
                        minimum=1.0, maximum=1e5),
    "rotor_mass": Param(716.0, "kg", "rotor mass (hub and 4 blades)", minimum=1.0,
                        maximum=1e5),
    "excitation_3p": Param(1500.0, "N", "amplitude of the 3P rotating-frame hub shear",
                           minimum=0.0, maximum=1e6),
    "excitation_5p": Param(1000.0, "N", "amplitude of the 5P rotating-frame hub shear",
                           minimum=0.0, maximum=1e6),
    "phase_3p": Param(0.0, "degree", "phase of the 3P hub shear", minimum=-360.0,
                      maximum=360.0),
    "phase_5p": Param(0.0, "degree", "phase of the 5P hub shear", minimum=-360.0,
                      maximum=360.0),
    **{name: HARDWARE[name] for name in ("arm_radius", "cm_offset", "tuning_mass", "pin_mass",
                                         "pin_diameter", "pin_inertia")},
    "pin_damping_ratio": Param(0.01, "1", "pendulum damping ratio from rolling resistance",
                               minimum=0.0, maximum=0.5),
    "steps_per_rev": Param(160, "1", "time steps per revolution", minimum=64, maximum=20000),
    "revolutions": Param(2, "1", "whole revolutions recorded once periodic", minimum=1,
                         maximum=50),
    "max_revolutions": Param(80, "1", "revolutions allowed to reach a periodic response",
                             minimum=2, maximum=2000),
    "periodic_tolerance": Param(1e-3, "1", "max change of harmonics between successive "
                                "revolutions, relative to the largest", minimum=0.0,
                                exclusive_minimum=True, maximum=1.0),
}


# What a run returns: whole revolutions of time histories. The in-plane vectors (components)
# get their per-rev harmonics archived; the histories marked ``history`` are archived over the
# last revolution; ``figure`` names the report figure that draws them (pipelines.plots).
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
}


def _geometry(p: dict[str, Any]) -> Geometry:
    return Geometry(p["arm_radius"], p["cm_offset"], p["pin_diameter"], p["tuning_mass"],
                    p["pin_mass"], p["pin_inertia"])


def check(p: dict[str, Any]) -> None:
    """Geometry must admit holes of the requested order (raises ParameterError)."""
    design(p["hole"], _geometry(p), tuning_order=p["tuning_order"])


def pin_damping(p: dict[str, Any], holes) -> float:
    """Rotational damping (N·m·s/rad) on the pin's rotation relative to its link giving the
    pendulum damping ratio ζ: the pin turns at (D/d) φ̇ relative to the link for circular
    holes (D the equivalent hole diameter), the pendulum's inertia is r²(m_b + m_p/2 + 2I_p/d²)
    per Eq. (7), so c = 2 ζ ω M_eff (d/D)²."""
    g = holes.geometry
    r = holes.rho_v
    d_hole = holes.hole_diameter
    m_eff = r * r * (g.tuning_mass + 0.5 * g.pin_mass + 2 * g.pin_inertia / g.pin_diameter**2)
    omega = holes.order_linear * p["hub_speed"]
    return 2.0 * p["pin_damping_ratio"] * omega * m_eff * (g.pin_diameter / d_hole) ** 2


def build(p: dict[str, Any]):
    """The hub model: (model, hub, shaft, parts, holes, (k, c)) with handles for outputs;
    ``parts`` is the list of :class:`BifilarParts` or, for ``bifilar = "equivalent"``, the
    :class:`studies.equivalent.EquivalentParts`."""
    omega = p["hub_speed"]
    holes = design(p["hole"], _geometry(p), tuning_order=p["tuning_order"])
    m_bif = p["tuning_mass"] + 2 * p["pin_mass"]
    g0 = ground()
    shaft = RigidBody("shaft", p["shaft_mass"], inertia=(1.0, 1.0, 1.0))
    # The rotor's speed is prescribed, so its polar inertia only sets the driving torque, not
    # the motion; it is left out (a unit inertia keeps the hub's rotation well posed). With the
    # real 1e4 kg·m² the midpoint rule's two-step velocity mode of the driven rotation, of
    # relative size (Ωh)², would show up as a large alternating driving torque and slow Newton.
    hub = RigidBody("hub", p["rotor_mass"], inertia=(1.0, 1.0, 1.0),
                    angular_velocity=omega * Z)
    k = p["fuselage_stiffness"] * p["fuselage_stiffness_scale"]
    m_tot = p["shaft_mass"] + p["rotor_mass"] + N_BIFILARS * m_bif
    # damping fixed by the nominal mode so that the stiffness scale changes stiffness only
    c = 2 * p["fuselage_damping_ratio"] * np.sqrt(p["fuselage_stiffness"] * m_tot)
    a3, a5 = p["excitation_3p"], p["excitation_5p"]
    f3, f5 = np.radians(p["phase_3p"]), np.radians(p["phase_5p"])

    def shear(t: float) -> np.ndarray:
        psi = omega * t
        rot = a3 * np.exp(1j * (3 * psi + f3)) + a5 * np.exp(-1j * (5 * psi + f5))
        fixed = np.exp(1j * psi) * rot  # hub frame → fixed frame (hub angle ψ = Ωt)
        return np.array([fixed.real, fixed.imag, 0.0])

    model = Model()
    model.add(g0, shaft, hub,
              Planar("shaft_plane", g0, shaft, axis=Z),
              Orientation("shaft_noyaw", g0, shaft, axis=Z, axes=(2,)),
              Revolute("rotor", shaft, hub, axis=Z, driven=linear(omega)),
              Spring("fuselage", None, shaft, stiffness=np.diag([k, k, 0.0]),
                     damping=np.diag([c, c, 0.0])),
              AppliedLoad("blade_shears", hub, force=shear))
    if p["bifilar"] == "equivalent":
        # the four bifilars' linear equivalent: the particle on the (non-rotating) shaft head,
        # the rigid remainder on the hub; the same rolling resistance, as swing damping
        absorber = equivalent_absorber(holes, N_BIFILARS, pin_damping(p, holes))
        eq = add_equivalent(model, shaft, hub, np.zeros(3), absorber, omega,
                            first_angle=np.pi / 4)
        return model, hub, shaft, eq, holes, (k, c)
    parts: list[BifilarParts] = []
    locked = p["bifilar"] == "locked"
    cp = 0.0 if locked else pin_damping(p, holes)
    for i in range(N_BIFILARS):
        ang = np.pi / 4 + i * np.pi / 2
        parts.append(add_bifilar(model, hub, holes, 0.0, angle=ang, prefix=f"b{i}_",
                                 omega=omega, locked=locked, pin_damping=cp))
    return model, hub, shaft, parts, holes, (k, c)


def _rev_harmonics(block: np.ndarray, n_max: int = 8) -> np.ndarray:
    """Complex per-rev harmonics 0..n_max of the columns of one revolution of samples."""
    f = np.fft.rfft(block, axis=0) / block.shape[0]
    return f[: n_max + 1]


def run(params: dict[str, Any]) -> xr.Dataset:
    """Simulate until periodic, then record whole revolutions (see the module docstring)."""
    p = SPEC.complete(params)
    model, hub, shaft, parts, holes, (k, c) = build(p)
    omega = p["hub_speed"]
    nrev = p["steps_per_rev"]
    h = 2 * np.pi / omega / nrev
    sysm = System(model)
    # harmonics need positions to ~1e-9 m, not the roundoff-level solve that exact energy
    # bookkeeping needs: a looser Newton tolerance saves about two iterations per step
    integ = make_integrator(sysm, "ep", h, tol=NEWTON_TOL)
    os_ = sysm.offset[shaft]
    equivalent = isinstance(parts, EquivalentParts)
    mass_off = [] if equivalent else [sysm.offset[b.mass] for b in parts]

    def sample() -> np.ndarray:
        q, v = integ.q, integ.v
        x = q[os_ : os_ + 3]
        xd = v[os_ : os_ + 3]
        if equivalent:
            cm = equivalent_cm(sysm, parts, q, integ.t)
            phis = equivalent_pin_angles(sysm, parts, q, integ.t)
        else:
            cm = np.mean([q[o : o + 3] for o in mass_off], axis=0)
            phis = [0.0 if b.locked else pin_angle(sysm, b, hub, q) for b in parts]
        f = k * x + c * xd  # force the springs and dampers pass to the fuselage
        return np.array([integ.t, x[0], x[1], f[0], f[1], cm[0], cm[1], *np.degrees(phis)])

    t0 = time.perf_counter()
    prev = None
    rows: list[np.ndarray] = []
    transient = None
    for rev in range(p["max_revolutions"] + p["revolutions"]):
        block = [sample()] if not rows else []
        for _ in range(nrev):
            info = integ.step()
            if not info.converged:
                raise RuntimeError(f"time step failed at t = {integ.t:.6g} s "
                                   f"(revolution {rev}): {info.message}")
            block.append(sample())
        if transient is None:
            blk = np.array(block[-nrev:])
            psi = omega * blk[:, 0]
            xr_ = np.cos(psi) * blk[:, 1] + np.sin(psi) * blk[:, 2]
            yr_ = -np.sin(psi) * blk[:, 1] + np.cos(psi) * blk[:, 2]
            cur = _rev_harmonics(np.column_stack([xr_, yr_, blk[:, 7:]]))
            if prev is not None:
                # per signal (hub x, y in m; pin angles in degree): the largest change of a
                # harmonic relative to that signal's largest harmonic; all-zero signals (locked
                # pins) are skipped
                scale = np.abs(cur).max(axis=0)
                live = scale > 0
                change = float(np.max(np.abs(cur - prev)[:, live] / scale[live]))
                if change <= p["periodic_tolerance"]:
                    transient = rev + 1
                report(f"revolution {rev + 1} of at most {p['max_revolutions']}: periodicity "
                       f"change {change:.2e}, tolerance {p['periodic_tolerance']:g}"
                       + (" (periodic: recording)" if transient is not None else ""))
            prev = cur
            if transient is None and rev + 1 >= p["max_revolutions"]:
                raise RuntimeError(f"response not periodic after {p['max_revolutions']} "
                                   f"revolutions (last change {change:.2e} > tolerance "
                                   f"{p['periodic_tolerance']:g}); raise max_revolutions or "
                                   "pin_damping_ratio")
            continue
        rows.extend(block[-nrev:] if len(block) > nrev else block)
        if len(rows) >= nrev * p["revolutions"]:
            break
    data = np.array(rows[: nrev * p["revolutions"]])
    t = data[:, 0]
    psi = omega * t
    cs, sn = np.cos(psi), np.sin(psi)
    ds = SPEC.dataset({
        "time": t,
        "bifilar": np.arange(N_BIFILARS),
        "hub_x_fixed": data[:, 1],
        "hub_y_fixed": data[:, 2],
        "hub_x_rotating": cs * data[:, 1] + sn * data[:, 2],
        "hub_y_rotating": -sn * data[:, 1] + cs * data[:, 2],
        "hub_force_x_fixed": data[:, 3],
        "hub_force_y_fixed": data[:, 4],
        "bifilar_cm_x_fixed": data[:, 5],
        "bifilar_cm_y_fixed": data[:, 6],
        "pin_angle": data[:, 7:].T,
    })
    ds.attrs.update(hub_speed=float(omega), revolutions=int(p["revolutions"]),
                    samples_per_rev=int(nrev), transient_revolutions=int(transient),
                    tuning_order_linear=float(holes.order_linear),
                    pin_damping=float(0.0 if p["bifilar"] == "locked" else pin_damping(p, holes)),
                    fuselage_stiffness=float(k), fuselage_damping=float(c),
                    solver_seconds=time.perf_counter() - t0,
                    steps=int(integ.n_steps), newton_iterations=int(integ.n_iterations))
    return ds


def _check(p: dict[str, Any]) -> None:
    if p["revolutions"] > p["max_revolutions"]:
        raise ParameterError("revolutions must not exceed max_revolutions")
    check(p)


SPEC = ModelSpec("hub", PARAMETERS, run, _check,
                 description="four-bladed hub with four bifilars on a fuselage restraint",
                 outputs=OUTPUTS)
