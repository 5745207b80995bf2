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
rotation relative to its arm-side link, sized from a pendulum damping ratio.

The run starts from the periodic response of the same model on its swing coordinates
(``initial_state``, :func:`nonlinear_start`: :mod:`studies.reduced_hub`, exact for rigid
bodies rolling without sliding, solved by harmonic balance), so that only the time step's
error is transient. It reaches the periodic response by shooting on the quarter-revolution map
(the model is symmetric under a quarter turn of the hub with the bifilars permuted,
:func:`symmetry`; :func:`studies.periodic.shoot`) and records whole revolutions. The time
integration is the energy-preserving ``ep`` step composed into a fourth-order step
(``composition``, :mod:`solver.composition`). Each run also computes the periodic response at
about twice the step (:func:`studies.periodic.sector_response`), which gives the step-error
estimate of the harmonics (``error_estimate``) and, with ``richardson``, harmonics 0–8
extrapolated to zero step (:func:`studies.periodic.richardson`).

``docs/models.md`` gives the assumptions, the defaults and the measured accuracy.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import NDArray

from solver.bodies import RigidBody, ground
from solver.composition import COMPOSITIONS, Composed
from solver.forces import AppliedLoad, Spring
from solver.integrators import make_integrator
from solver.joints import Orientation, Planar, Revolute
from solver.model import Model
from solver.period_map import map_multipliers
from solver.symmetry import CyclicSymmetry
from solver.system import System
from solver.timefunctions import linear
from studies import periodic
from studies.absorbers import (
    AZIMUTHS,
    N_BIFILARS,
    AbsorberProbe,
    AbsorberStart,
    add_absorbers,
    holes_for,
    pin_damping,
)
from studies.absorbers import OUTPUTS as ABSORBER_OUTPUTS
from studies.absorbers import PARAMETERS as ABSORBERS
from studies.bifilar import BifilarParts
from studies.bifilar import compile_kernels as compile_bifilar
from studies.equivalent import EquivalentParts, equivalent_absorber
from studies.harmonics import N_MAX
from studies.holes import MAX_TANGENT_ANGLE, Holes
from studies.parameters import ModelSpec, Output, Param, ParameterError, Parameters
from studies.periodic import march, shoot, stepper, to_rotating
from studies.reduced_hub import (
    SAMPLES,
    PeriodicSwing,
    ReducedHub,
    path_terms,
    periodic_swing,
    tangent_angle,
)

Z = np.array([0.0, 0.0, 1.0])
NEWTON_TOL = 1e-8  # relative Newton tolerance on q (m); see run()
PLAIN_MIN_STEPS = 64  # steps per revolution at least, for the plain (uncomposed) ep step
# relative accuracy of the coarser step's periodic harmonics against their change from the
# recorded ones (studies.periodic.sector_response): the error estimate's own accuracy. The
# extrapolated harmonics carry a 15th of it; measured, 0.01 instead made them no better (free
# case 3.3e-4 → 2.3e-4 of the largest harmonic, 3.3P at 1.5× stiffness 2.5e-3 → 3.5e-3: the
# O(h⁶) remainder and the periodicity tolerance dominate) for 1.75 more revolutions at 2h
ESTIMATE_ACCURACY = 0.1
# the largest pin angle from which the linear start is used (rad): the linearization drops the
# amplitude detuning, φ²/16 of the frequency for circular holes (1.7 % at 30°)
LINEAR_START_LIMIT = np.radians(30.0)
# the largest pin angle of the nonlinear start's periodic response (rad): the holes cover the
# path to this turn of its tangent
NONLINEAR_START_LIMIT = MAX_TANGENT_ANGLE

# UH-60-class values (public: 4 blades of 116.5 kg, R = 8.18 m, Ω = 27 rad/s). The hub mass,
# shaft-head mass and fuselage restraint are assumptions: the fuselage in-plane mode at the hub
# is placed at 0.9 × 4P with 2% damping (below the 4P excitation, so the hub response is
# mass-controlled and halving the stiffness changes it by tens of percent, the sensitivity the
# paper's case 3 shows), and away from the bifilars' coupled modes.
PARAMETERS: dict[str, Param] = {
    **{name: ABSORBERS[name] for name in ("bifilar", "tuning_order", "hole", "hub_speed")},
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
    **{name: ABSORBERS[name] for name in ("arm_radius", "cm_offset", "tuning_mass", "pin_mass",
                                          "pin_diameter", "pin_inertia", "pin_damping_ratio")},
    "initial_state": Param("nonlinear", "1", "state at t = 0: nonlinear (the periodic "
                           "response of the hub on its swing coordinates, exact for rigid "
                           "bifilars, by harmonic balance: studies.reduced_hub), linear (the "
                           "closed-form periodic response of the linearized model: the hub's "
                           "whirl and the bifilars' swing from their fixed-frame equivalent) "
                           "or rest (hub centred, bifilars at rest at their vertex)",
                           choices=("linear", "nonlinear", "rest")),
    "start_swing": Param(0.0, "degree", "largest pin angle of the guess from which the "
                         "nonlinear start's harmonic balance is solved (0: the linear "
                         "response's): where a softening absorber has two stable responses, "
                         "a guess near either reaches that one", minimum=0.0, maximum=70.0),
    "floquet": Param(True, "1", "compute the periodic response's Floquet multipliers "
                     "(floquet_multiplier_max; 13 quarter revolutions of the multibody model "
                     "at the recorded step, the equivalent's by Arnoldi on its whole state)"),
    "steps_per_rev": Param(40, "1", "time steps per revolution (each of them `composition`'s "
                           "substeps)", minimum=20, maximum=20000),
    "composition": Param("suzuki", "1", "symmetric composition of the ep step into a "
                         "fourth-order step: suzuki (5 substeps), yoshida (3), or none (the "
                         "plain second-order ep step)", choices=(*COMPOSITIONS, "none")),
    **periodic.STEP_ERROR_PARAMETERS,
    "revolutions": Param(2, "1", "whole revolutions recorded once periodic", minimum=1,
                         maximum=50),
    "max_revolutions": Param(80, "1", "revolutions allowed to reach a periodic response",
                             minimum=2, maximum=2000),
    "periodic_tolerance": Param(1e-3, "1", "max change of harmonics between successive "
                                "revolutions, relative to the largest", minimum=0.0,
                                exclusive_minimum=True, maximum=1.0),
    **periodic.PARAMETERS,
    # 20 iterates: from the linear start, tuned at 3.3P with 1.5 times the fuselage stiffness
    # the extrapolation needs 18 (with a window of 12 the case takes 21.75 revolutions instead
    # of 10.25; at 2.8P 12.75); the Table 1 cases restart after 8-9, before the window fills
    **periodic.shooting_parameters(window=20),
}


# What a run returns: the absorbers' shared hub-level outputs (studies.absorbers).
OUTPUTS: dict[str, Output] = {
    **ABSORBER_OUTPUTS,
    "effective_fuselage_stiffness": Output(
        "N m-1", "in-plane fuselage stiffness at the hub (nominal times "
        "fuselage_stiffness_scale)", dims=()),
    "fuselage_damping": Output("N s m-1", "in-plane fuselage damping at the hub", dims=()),
    **periodic.RUN_OUTPUTS,
    **periodic.STEP_ERROR_OUTPUTS,
    "run_substeps": Output("1", "substeps of the composed time steps taken", dims=()),
    "floquet_multiplier_max": Output(
        "1", "largest modulus of the periodic response's Floquet multipliers over one "
        "revolution (above 1: unstable), from the multibody quarter-revolution map's Jacobian "
        "in minimal coordinates (studies.hub_branches), the equivalent's by Arnoldi on the "
        "whole state (solver.period_map)", dims=(), optional=True),
}


def check(p: Parameters) -> None:
    """Geometry must admit holes of the requested order, and shooting on the quarter-revolution
    map needs whole quarter revolutions of steps (raises ParameterError)."""
    holes_for(p)
    if p.composition == "none" and p.steps_per_rev < PLAIN_MIN_STEPS:
        raise ParameterError(f"steps_per_rev = {p.steps_per_rev}: must be at least "
                             f"{PLAIN_MIN_STEPS} with composition = 'none' (the plain "
                             "second-order step errs by 13 % at 80 steps/rev)")
    # shooting steps whole quarter revolutions (the coarser step of the estimate too:
    # periodic.coarser_steps)
    if p.shooting_window and p.steps_per_rev % N_BIFILARS:
        raise ParameterError(f"steps_per_rev = {p.steps_per_rev}: must be a multiple of "
                             f"{N_BIFILARS} (shooting on the quarter-revolution map steps whole "
                             "quarter revolutions)")


def total_mass(p: Parameters) -> float:
    """The in-plane mass on the fuselage restraint (kg): shaft head, rotor and bifilars."""
    m_bif = p.tuning_mass + 2 * p.pin_mass
    return p.shaft_mass + p.rotor_mass + N_BIFILARS * m_bif


def fuselage(p: Parameters) -> tuple[float, float]:
    """The fuselage restraint's in-plane stiffness (N/m) and damping (N·s/m)."""
    # damping fixed by the nominal mode so that the stiffness scale changes stiffness only
    c = 2 * p.fuselage_damping_ratio * np.sqrt(p.fuselage_stiffness * total_mass(p))
    return p.fuselage_stiffness * p.fuselage_stiffness_scale, c


def excitation(p: Parameters) -> tuple[np.ndarray, np.ndarray]:
    """The blade shears in the fixed frame, f = Σ F_j e^{iω_j t} (complex in-plane components):
    the whirl frequencies ω_j (rad/s; the rotating 3P at +4Ω, the rotating 5P at −4Ω) and the
    complex amplitudes F_j (N)."""
    omega = p.hub_speed
    return (omega * np.array([1.0 + 3.0, 1.0 - 5.0]),
            np.array([p.excitation_3p * np.exp(1j * np.radians(p.phase_3p)),
                      p.excitation_5p * np.exp(-1j * np.radians(p.phase_5p))]))


@dataclass(frozen=True)
class HubDesign:
    """What a hub case derives from its parameters, once (:func:`design`): everything the
    model, its starts and its reduced equations are built from.

    Attributes
    ----------
    holes
        The bifilars' tracking holes (:func:`studies.absorbers.holes_for`).
    fuselage_stiffness, fuselage_damping
        The fuselage restraint's in-plane stiffness (N/m, scaled by
        ``fuselage_stiffness_scale``) and damping (N·s/m, from the nominal mode).
    pin_damping
        Rotational damping on each pin's rotation relative to its link (N·m·s/rad; zero for
        locked bifilars).
    total_mass
        In-plane mass on the fuselage restraint (kg): shaft head, rotor and bifilars.
    whirl, force
        The blade shears in the fixed frame, f = Σ F_j e^{iω_j t}: whirl frequencies ω_j
        (rad/s) and complex amplitudes F_j (N) (:func:`excitation`).
    """

    holes: Holes
    fuselage_stiffness: float
    fuselage_damping: float
    pin_damping: float
    total_mass: float
    whirl: NDArray[np.float64]
    force: NDArray[np.complex128]


def design(p: Parameters) -> HubDesign:
    """The derived design of a hub case: holes, fuselage restraint, pin dampers, shears."""
    holes = holes_for(p)
    k, c = fuselage(p)
    whirl, force = excitation(p)
    return HubDesign(holes=holes, fuselage_stiffness=float(k), fuselage_damping=float(c),
                     pin_damping=pin_damping(p, holes), total_mass=total_mass(p),
                     whirl=whirl, force=force)


def linear_response(p: Parameters, d: HubDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The periodic response of the linearized hub model, in closed form: per tone of the
    shears (:func:`excitation`) its whirl frequency ω (rad/s), the hub's whirl amplitude Z (m,
    complex: z = Σ Z e^{iωt}, fixed frame) and the bifilars' swing whirl amplitude Â (rad:
    A = Σ Â e^{iωt}, φ_k = Re(A e^{−iψ_k})).

    At small swing the four bifilars act on the hub as their fixed-frame equivalent
    (:mod:`studies.equivalent`): an apparent mass M_eff(ω) = M + i B (N/2) S/D under a hub
    whirl at ω, Â/Z = S/D (:meth:`~studies.equivalent.EquivalentAbsorber.swing_terms`; locked:
    the total mass M). Each tone F e^{iωt} of the shears then moves the hub by
    Z = F / (K0 − ω² (M_eff − M)), K0 = k + iωc − ω² (m_shaft + m_rotor + M), computed with D
    cleared, Z = F D / Δ and Â = F S / Δ with Δ = D K0 − i ω² B (N/2) S: finite also for an
    undamped absorber tuned to a tone (D = 0), which then cancels it (Z = 0,
    Â = 2iF/(ω² N B)). Not finite only at an undamped resonance of the coupled system.
    """
    omega = p.hub_speed
    whirl, force = d.whirl, d.force
    k, c = d.fuselage_stiffness, d.fuselage_damping
    locked = p.bifilar == "locked"
    absorber = equivalent_absorber(d.holes, N_BIFILARS, d.pin_damping)
    k0 = k + 1j * whirl * c - whirl**2 * (p.shaft_mass + p.rotor_mass + absorber.total_mass)
    if locked:
        return whirl, force / k0, np.zeros(len(whirl), dtype=complex)
    num, den = absorber.swing_terms(omega, whirl)
    delta = den * k0 - 0.5j * N_BIFILARS * absorber.coupling * whirl**2 * num
    return whirl, force * den / delta, force * num / delta


def linear_start(p: Parameters, d: HubDesign) -> AbsorberStart:
    """The state at t = 0 of :func:`linear_response`: the hub centre's position and
    velocity, each bifilar's pin angle φ_k = Re(A e^{−iψ_k}) and rate
    Re((Ȧ − iΩA) e^{−iψ_k}). What the linearization leaves out (amplitude detuning, the hole
    shape beyond its vertex curvature) is the transient the shooting removes."""
    whirl, zz, aa = linear_response(p, d)
    z0, zd0 = zz.sum(), (1j * whirl * zz).sum()
    a0, ad0 = aa.sum(), (1j * whirl * aa).sum()
    rot = np.exp(-1j * AZIMUTHS)  # e^{−iψ_k} at t = 0
    return AbsorberStart(angles=np.real(a0 * rot),
                         rates=np.real((ad0 - 1j * p.hub_speed * a0) * rot),
                         center=np.array([z0.real, z0.imag, 0.0]),
                         velocity=np.array([zd0.real, zd0.imag, 0.0]))


def reduced_model(p: Parameters, d: HubDesign) -> ReducedHub:
    """The hub model on swing coordinates (:mod:`studies.reduced_hub`): the same masses,
    fuselage restraint, shears and rolling resistance as :func:`build`'s."""
    return ReducedHub(d.holes, p.hub_speed, AZIMUTHS, d.total_mass, d.fuselage_stiffness,
                      d.fuselage_damping, d.whirl, d.force, d.pin_damping)


def reduced_response(p: Parameters, d: HubDesign, **kw) -> PeriodicSwing:
    """The periodic response of :func:`reduced_model` by harmonic balance
    (:func:`studies.reduced_hub.periodic_swing`, options ``kw``), from :func:`linear_response`
    (σ ≈ φ/φ'(0): the linear response knows only the vertex).

    With ``start_swing`` set, the linear response scaled to that largest pin angle and the
    same in opposite phase are both tried (a softening absorber's large response lags the
    small one by about half a period), and the solution whose swing is nearest is returned.
    Raises RuntimeError if the balance does not converge.
    """
    omega = p.hub_speed
    m = kw.get("samples", SAMPLES)
    t = 2 * np.pi / omega * np.arange(m) / m
    whirl, _, aa = linear_response(p, d)
    phi0 = np.real((aa[:, None] * np.exp(1j * np.outer(whirl, t))).sum(axis=0)
                   * np.exp(-1j * (omega * t + AZIMUTHS[0])))
    model = reduced_model(p, d)
    slope = tangent_angle(d.holes, np.zeros(1))[1][0]
    if not (p.start_swing > 0 and np.abs(phi0).max() > 0):
        return periodic_swing(model, phi0 / slope, **kw)
    target = np.radians(p.start_swing)
    found, failures = [], []
    for sign in (1.0, -1.0):
        try:
            sol = periodic_swing(model, sign * phi0 * target / np.abs(phi0).max() / slope, **kw)
        except RuntimeError as exc:
            failures.append(str(exc))
            continue
        swing = np.abs(tangent_angle(d.holes, sol.sigma(t))[0]).max()
        found.append((abs(swing - target), sol))
    if not found:
        raise RuntimeError(f"from start_swing = {p.start_swing:g}°: {failures[0]}")
    return min(found, key=lambda f: f[0])[1]


def reduced_samples(p: Parameters, d: HubDesign, t: np.ndarray, **kw) -> np.ndarray:
    """The run's sampled rows at times ``t`` (s) — time, hub centre x, y (m) and the force on
    the fuselage x, y (N), fixed frame; the tuning masses' centre of mass x, y (m); the pin
    angles (degree) — from :func:`reduced_response`: the exact equations' periodic response, a
    reference for :func:`run`'s that shares none of its numerics."""
    return solution_rows(p, d, reduced_response(p, d, **kw), t)


def solution_rows(p: Parameters, d: HubDesign, sol: PeriodicSwing, t: np.ndarray
                  ) -> np.ndarray:
    """:func:`reduced_samples`' rows of the swing-coordinate solution ``sol`` at ``t`` (s)."""
    holes = d.holes
    k, c = d.fuselage_stiffness, d.fuselage_damping
    z, zd = sol.center(t), sol.center(t, derivative=1)
    f = k * z + c * zd
    sigmas = [sol.sigma(t, k=j) for j in range(N_BIFILARS)]
    cm = z + np.mean([np.exp(1j * (p.hub_speed * t + a)) * path_terms(holes, s)[0]
                      for a, s in zip(AZIMUTHS, sigmas, strict=True)], axis=0)
    pins = [np.degrees(tangent_angle(holes, s)[0]) for s in sigmas]
    return np.column_stack([t, z.real, z.imag, f.real, f.imag, cm.real, cm.imag, *pins])


def nonlinear_start(p: Parameters, d: HubDesign) -> tuple[AbsorberStart, float]:
    """The state at t = 0 of :func:`reduced_response`, and the largest pin angle over its
    revolution (rad). Raises RuntimeError if the balance does not converge."""
    omega = p.hub_speed
    holes = d.holes
    sol = reduced_response(p, d)
    t0 = np.zeros(1)
    angles, rates = [], []
    for j in range(N_BIFILARS):
        phi, turn = tangent_angle(holes, sol.sigma(t0, k=j))
        angles.append(phi[0])
        rates.append(turn[0] * sol.sigma(t0, k=j, derivative=1)[0])
    z0, zd0 = sol.center(0.0), sol.center(0.0, derivative=1)
    t = 2 * np.pi / omega * np.arange(SAMPLES) / SAMPLES
    swing = float(np.abs(tangent_angle(holes, sol.sigma(t))[0]).max())
    return AbsorberStart(angles=np.array(angles), rates=np.array(rates),
                         center=np.array([z0.real, z0.imag, 0.0]),
                         velocity=np.array([zd0.real, zd0.imag, 0.0])), swing


def initial_start(p: Parameters, d: HubDesign) -> tuple[AbsorberStart, str]:
    """The state the run starts from as ``initial_state`` says, and what the case message
    should say about it: the nonlinear start where the harmonic balance converges with every
    pin within :data:`NONLINEAR_START_LIMIT`, else the linear one; the linear start only where
    the linearization holds — finite, and every pin within :data:`LINEAR_START_LIMIT` and on
    its hole — else rest."""
    if p.initial_state == "rest":
        return AbsorberStart(), ""
    note = ""
    if p.initial_state == "nonlinear" and p.bifilar == "free":
        # (locked bifilars and the equivalent are linear: their linear start is exact)
        try:
            with np.errstate(all="ignore"):
                start, swing = nonlinear_start(p, d)
        except RuntimeError as exc:
            note = f"nonlinear start not found ({exc})"
        else:
            if swing <= NONLINEAR_START_LIMIT:
                return start, ""
            note = (f"nonlinear start not used: it swings the pins to {np.degrees(swing):.3g}°, "
                    f"beyond the {np.degrees(NONLINEAR_START_LIMIT):g}° the holes cover")
    start, reason = _linear_start_checked(p, d)
    if note and not reason:
        reason = "started from the linear response"
    return start, "; ".join(x for x in (note, reason) if x)


def _linear_start_checked(p: Parameters, d: HubDesign) -> tuple[AbsorberStart, str]:
    """The linear start where the linearization holds, else rest and why."""
    with np.errstate(all="ignore"):  # a non-finite response is reported, not warned about
        start = linear_start(p, d)
    values = np.concatenate([start.angles, start.rates, start.center, start.velocity])
    if not np.all(np.isfinite(values)):
        return AbsorberStart(), ("started at rest: the linear response is not finite (an "
                                 "undamped resonance of the linearized hub)")
    big = float(np.abs(start.angles).max())
    reach = ""
    if big > LINEAR_START_LIMIT:
        reach = f"beyond the {np.degrees(LINEAR_START_LIMIT):g}° where the linearization holds"
    else:
        try:
            for a in (big, -big):
                d.holes.sigma_of_angle(a)
        except ParameterError:
            reach = "beyond the end of the holes"
    if reach:
        return AbsorberStart(), (f"started at rest: the linear response swings the pins to "
                                 f"{np.degrees(big):.3g}°, {reach}")
    return start, ""


def build(p: Parameters, d: HubDesign | None = None, start: AbsorberStart | None = None
          ) -> tuple[Model, RigidBody, RigidBody, list[BifilarParts] | EquivalentParts]:
    """The hub model: (model, hub, shaft, parts) with handles for outputs; ``parts`` is the
    list of :class:`BifilarParts` or, for ``bifilar = "equivalent"``, the
    :class:`studies.equivalent.EquivalentParts`. ``d`` (the derived design) and ``start`` (the
    state at t = 0) default to :func:`design`'s and :func:`initial_start`'s."""
    omega = p.hub_speed
    d = design(p) if d is None else d
    if start is None:
        start, _ = initial_start(p, d)
    x0, v0 = start.center, start.velocity
    g0 = ground()
    shaft = RigidBody("shaft", p.shaft_mass, inertia=(1.0, 1.0, 1.0), position=x0,
                      velocity=v0)
    # The rotor's speed is prescribed, so its polar inertia only sets the driving torque, not
    # the motion; it is left out (a unit inertia keeps the hub's rotation well posed). With the
    # real 1e4 kg·m² the midpoint rule's two-step velocity mode of the driven rotation, of
    # relative size (Ωh)², would show up as a large alternating driving torque and slow Newton.
    hub = RigidBody("hub", p.rotor_mass, inertia=(1.0, 1.0, 1.0), position=x0,
                    velocity=v0, angular_velocity=omega * Z)
    k, c = d.fuselage_stiffness, d.fuselage_damping
    whirl, force = d.whirl, d.force

    def shear(t: float) -> np.ndarray:
        fixed = force @ np.exp(1j * whirl * t)
        return np.array([fixed.real, fixed.imag, 0.0])

    model = Model()
    # the fuselage spring acts on the shaft centre (Δ = x − x0) and is unstretched with the
    # shaft at the origin (rest −x0)
    model.add(g0, shaft, hub,
              Planar("shaft_plane", g0, shaft, axis=Z),
              Orientation("shaft_noyaw", g0, shaft, axis=Z, axes=(2,)),
              Revolute("rotor", shaft, hub, point=x0, axis=Z, driven=linear(omega)),
              Spring("fuselage", None, shaft, point=x0, stiffness=np.diag([k, k, 0.0]),
                     damping=np.diag([c, c, 0.0]), rest=-x0),
              AppliedLoad("blade_shears", hub, force=shear))
    parts = add_absorbers(model, hub, shaft, d.holes, p, d.pin_damping, start)
    return model, hub, shaft, parts


def run(given: Mapping[str, Any] | Parameters = ()) -> xr.Dataset:
    """One hub case from its parameters (validated here unless they are the hub's
    :class:`~studies.parameters.Parameters` already): see :func:`simulate`."""
    return simulate(SPEC.validate(given))


def simulate(p: Parameters) -> xr.Dataset:
    """Reach the periodic response (shooting or marching) and record whole revolutions; then
    estimate the harmonics' time-step error from the periodic response at a coarser step
    and, with ``richardson``, extrapolate them to zero step (see the module docstring)."""
    d = design(p)
    # the start, and what the case message says of it (that it is rest, and why)
    start, start_note = initial_start(p, d)
    model, hub, shaft, parts = build(p, d, start)
    k, c = d.fuselage_stiffness, d.fuselage_damping
    omega = p.hub_speed
    nrev = p.steps_per_rev
    sysm = System(model)
    os_ = sysm.offset[shaft]
    absorbers = AbsorberProbe(sysm, parts, hub)
    sym = symmetry(sysm, hub, shaft, parts) if p.shooting_window else None

    def integrator(n: int):
        return time_integration(p, sysm, n)

    def sampler(integ):
        return recorder(integ, d, absorbers, os_)

    def signals(block: np.ndarray) -> np.ndarray:
        # per signal (hub x, y in the rotating frame, m; pin angles, degree): changes
        # relative to that signal's largest harmonic
        xr_, yr_ = to_rotating(omega, block[:, 0], block[:, 1], block[:, 2])
        return np.column_stack([xr_, yr_, block[:, 7:]])

    n_sec = N_BIFILARS if sym is not None else 1  # sectors of the map iterated

    def align(block: np.ndarray, j: int) -> np.ndarray:
        # a block of samples ending j sector periods after t = 0 at the phase of t = 0: the
        # fixed-frame hub signals as they are (the 4P forcing repeats every quarter
        # revolution), the pin angles moved ahead by the bifilars turned past
        out = block.copy()
        out[:, 7:] = np.roll(block[:, 7:], j * (N_BIFILARS // n_sec), axis=1)
        return out

    def observe(block: np.ndarray, j: int) -> np.ndarray:
        # the quarter-revolution map's observations: the hub motion and the pin angles
        return align(block, j)[:, [1, 2, *range(7, block.shape[1])]]

    t0 = time.perf_counter()
    integ = integrator(nrev)
    hint = "raise max_revolutions or pin_damping_ratio"
    if sym is not None:
        rec = shoot(integ, sampler(integ), signals, observe=observe, symmetry=sym,
                    system=sysm, steps_per_rev=nrev, revolutions=p.revolutions,
                    max_revolutions=p.max_revolutions, tolerance=p.periodic_tolerance,
                    window=p.shooting_window, max_restarts=p.shooting_restarts,
                    secant=True, hint=hint)
    else:
        rec = march(stepper(integ, omega), sampler(integ), signals, steps_per_rev=nrev,
                    revolutions=p.revolutions, max_revolutions=p.max_revolutions,
                    tolerance=p.periodic_tolerance, hint=hint,
                    window=p.extrapolation_window)
    data = rec.samples
    runs = [(integ, nrev)]
    notes = [note for note in (start_note, rec.note) if note]
    floquet = {}
    if p.floquet and p.bifilar != "equivalent":
        from studies.hub_branches import run_multipliers  # (it builds on this module)
        try:
            mult = run_multipliers(p, integ, sysm, hub, shaft, parts)
        except RuntimeError as exc:
            notes.append(f"no Floquet multipliers: {exc}")
        else:
            floquet["floquet_multiplier_max"] = np.float64(np.abs(mult[0]))
    elif p.floquet and sym is not None:
        # the equivalent has no pins to read minimal coordinates from: Arnoldi on the whole
        # state's quarter map (the energy-conserving step's discrete gradients want a
        # perturbation of 1e-5 or more: solver.period_map)
        mm = map_multipliers(integ, nrev // N_BIFILARS, symmetry=sym, rate=omega, eps=1e-5)
        if mm.failure:
            notes.append(mm.failure)
        else:
            floquet["floquet_multiplier_max"] = np.float64(mm.largest)
    est = None
    if p.error_estimate or p.richardson:
        # the periodic response at the coarser step, from the recorded one's end state: its
        # harmonics against the recorded ones estimate the time-step error (Richardson). At
        # most six revolutions of iterates: without shooting's iterates (a run that marched),
        # tuned to 2.8P the estimate needs 17 quarter revolutions (with 16 it stays uncertain
        # and the step's 0.63 % error is archived); with them, the slow modes known before the
        # coarse iterates span them (at the coarse samples: every other step's), the cases of
        # a 60-case sweep stop after 4–7
        est = periodic.step_error(
            rec, integ.state(), integrator, sampler, align, n_sectors=n_sec,
            steps_per_rev=nrev, omega=omega, order=2 if p.composition == "none" else 4,
            extrapolate=p.richardson, accuracy=ESTIMATE_ACCURACY,
            max_iterates=6 * max(n_sec, 2), n_max=N_MAX)
        data = est.samples
        notes.append(est.note)
        if est.integrator is not None:
            runs.append((est.integrator, est.steps_per_rev))
    series = recorded_outputs(omega, data)
    facts = {
        **periodic.run_facts(
            rec, hub_speed=omega, revolutions=p.revolutions, samples_per_rev=nrev,
            transient=rec.transient, simulated=sum(i.n_steps / n for i, n in runs),
            steps=sum(i.n_steps for i, _ in runs),
            iterations=sum(i.n_iterations for i, _ in runs),
            seconds=time.perf_counter() - t0),
        **(periodic.StepError(data) if est is None else est).facts(),
        "run_substeps": np.int32(sum(getattr(i, "n_substeps", i.n_steps) for i, _ in runs)),
        "tuning_order_linear": np.float64(d.holes.order_linear),
        "pin_damping": np.float64(d.pin_damping),
        "effective_fuselage_stiffness": np.float64(k),
        "fuselage_damping": np.float64(c),
    }
    facts.update(floquet)
    ds = SPEC.dataset({**series, **facts}, {"message": "; ".join(filter(None, notes))})
    return ds


def time_integration(p: Parameters, system: System, steps_per_rev: int | None = None,
                     tol: float = NEWTON_TOL):
    """The hub's time integration of ``system``: the ``ep`` step at ``steps_per_rev`` (default
    the case's) steps a revolution, composed as ``composition`` says, its Newton solved to
    ``tol`` relative. Harmonics do not need the roundoff-level solve that exact energy
    bookkeeping needs: measured on the free case, the default 1e-8 instead of 1e-11 moves
    every archived output by ≤ 4e-10 of its scale and takes 3.13 → 2.26 Newton iterations a
    step."""
    n = steps_per_rev or p.steps_per_rev
    integ = make_integrator(system, "ep", 2 * np.pi / p.hub_speed / n, tol=tol)
    return integ if p.composition == "none" else Composed(integ, p.composition)


def recorder(integ, d: HubDesign, absorbers: AbsorberProbe, offset: int
             ) -> Callable[[], np.ndarray]:
    """The sample of ``integ``'s current state that a run records: time (s), the hub centre
    x, y (m) and the force on the fuselage x, y (N), fixed frame; the tuning masses' centre of
    mass x, y (m); the pin angles (degree). ``offset`` is the shaft head's in q."""
    k, c = d.fuselage_stiffness, d.fuselage_damping

    def sample() -> np.ndarray:
        q, v = integ.q, integ.v
        x = q[offset : offset + 3]
        xd = v[offset : offset + 3]
        cm, phis = absorbers(q, integ.t)
        f = k * x + c * xd  # force the springs and dampers pass to the fuselage
        return np.array([integ.t, x[0], x[1], f[0], f[1], cm[0], cm[1], *np.degrees(phis)])
    return sample


def recorded_outputs(omega: float, data: np.ndarray) -> dict[str, np.ndarray]:
    """The declared time series of a recording: ``data``'s rows are time (s), the hub centre
    x, y (m) and the force on the fuselage x, y (N), fixed frame; the tuning masses' centre of
    mass x, y (m); the pin angles (degree) (:func:`simulate`'s samples,
    :func:`reduced_samples`' rows)."""
    t = data[:, 0]
    x_rot, y_rot = to_rotating(omega, t, data[:, 1], data[:, 2])
    return {
        "time": t,
        "bifilar": np.arange(N_BIFILARS),
        "hub_x_fixed": data[:, 1],
        "hub_y_fixed": data[:, 2],
        "hub_x_rotating": x_rot,
        "hub_y_rotating": y_rot,
        "hub_force_x_fixed": data[:, 3],
        "hub_force_y_fixed": data[:, 4],
        "bifilar_cm_x_fixed": data[:, 5],
        "bifilar_cm_y_fixed": data[:, 6],
        "pin_angle": data[:, 7:].T,
    }


def symmetry(system: System, hub, shaft, parts) -> CyclicSymmetry:
    """The hub model's quarter-revolution symmetry: the hub turns about the shaft head, bifilar
    j + 1 takes bifilar j's place (the equivalent's particle is non-rotating and its hub mass
    part of the hub's turn)."""
    sectors: list[list] = [[] for _ in range(N_BIFILARS)]
    rotating = [hub]
    if isinstance(parts, list):
        for j, b in enumerate(parts):
            prefix = b.mass.name[: -len("mass")]
            sectors[j] = [blk.owner for blk in system.layout.blocks
                          if getattr(blk.owner, "name", "").startswith(prefix)]
    else:  # the equivalent's rigid mass turns with the hub, its particle does not
        rotating.append(parts.rigid)
    return CyclicSymmetry(system, sectors, rotating=rotating, axis=Z, centre=shaft)


def compile_kernels(steps: int = 3) -> None:
    """Compile the kernels of the hub without its bifilars into numba's cache (or load them
    from there): the hub with their linear equivalent, built and marched ``steps`` steps with
    its composed ``ep`` step.

    A warm-up part of this model (:attr:`ModelSpec.warm_up`); the bifilars' kernels are the
    other (:func:`studies.bifilar.compile_kernels`), compiled at the same time on another
    worker.
    """
    p = SPEC.validate({"bifilar": "equivalent"})
    model, *_ = build(p)
    integ = time_integration(p, System(model))
    for _ in range(steps):
        integ.step()


def _check(p: Parameters) -> None:
    periodic.check(p)
    check(p)


def _branch(p: Parameters, c: Any) -> list:
    """:func:`studies.hub_branches.branch` (imported on use: it builds on this module)."""
    from studies.hub_branches import branch
    return branch(p, c)


SPEC = ModelSpec("hub", PARAMETERS, simulate, _check,
                 description="four-bladed hub with four bifilars on a fuselage restraint",
                 outputs=OUTPUTS, version="4", warm_up=(compile_bifilar, compile_kernels),
                 branch=_branch)
