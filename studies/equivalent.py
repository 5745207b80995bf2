r"""The linear fixed-frame equivalent of N identical bifilars (the "industry equivalent absorber").

N identical bifilars on a hub spinning at a constant Ω act on the hub, at small amplitude,
exactly like one particle on an isotropic spring in the (non-rotating) rotor plane plus a mass
riding with the hub. This module derives that equivalent, builds it from solver parts on a
non-rotating carrier, and reconstructs the bifilars' pin angles and the tuning masses' centre of
mass from it, so that a model can swap the four nonlinear multibody bifilars
(:func:`studies.bifilar.add_bifilar`) for it.

Derivation
----------
**One bifilar, linearized.** Notation of :mod:`studies.holes`: tuning mass m_b, two pins of mass
m_p, polar inertia I_p and diameter d each, equivalent circular hole diameter D, arm radius R0,
centre-of-mass offset Rm. The tuning mass translates (it turns with the hub) with its centre of
mass on a path of radius of curvature r = D − d at the vertex (``holes.rho_v``), at
R_v = R0 + Rm + r from the hub centre; each pin centre moves half as far (on a radius r/2
about the arm's hole centre at R0) and the pin turns relative to the hub by (r/d) φ, rolling
without sliding. With φ the pin angle (the turn of the hole tangent at the contact, which for
circles is the angle of the tuning mass on its path), the kinetic energy relative to the hub
and the centrifugal potential are

    T = ½ J φ̇²,     J = r² (m_b + m_p/2 + 2 I_p/d²)                               (kg m²),
    V = −Ω² r (m_b (R0 + Rm) + m_p R0) cos φ  ⇒  K = Ω² r (m_b (R0 + Rm) + m_p R0) = ñ² Ω² J,

ñ the small-amplitude tuning order of Eq. (7) (``holes.order_linear``); the pins' spin adds a
term linear in φ̇ (a total derivative) and Coriolis forces vanish for one coordinate. When the
hub centre translates by z (in-plane, fixed frame) every part of the bifilar is accelerated by
z̈; the swing coordinate feels the generalized force −z̈·∂x/∂φ summed over the parts, with
∂x/∂φ = r τ for the tuning mass and (r/2) τ for each pin (τ the bifilar's tangential unit
vector, the hub's direction of rotation at φ = 0). Hence, adding the rolling resistance,

    J φ̈ + c_φ φ̇ + K φ = −B τ·z̈,     B = r (m_b + m_p)                           (kg m),

B being also the bifilar's translational momentum per unit φ̇. The rolling resistance of
:func:`studies.absorbers.pin_damping` is a damper c_pin on the pin's rotation relative to its
arm-side link; that link turns with the hole tangent (φ) and the pin turns by −(r/d) φ
relative to the hub, so the relative rate is (D/d) φ̇ and the damper dissipates c_pin (D/d)² φ̇²:
c_φ = c_pin (D/d)². For non-circular holes r is the vertex radius of curvature ρ_v and D the
hole diameter of the osculating circle design: this is a linearization about the vertex.

**N bifilars in the fixed frame.** Complex in-plane notation (x + iy in the carrier's axes;
multiplying by i turns by 90° about the rotor axis ẑ). Bifilar k sits at the azimuth
ψ_k = Ωt + α_k, α_k = α_0 + 2πk/N, so τ_k = i e^{iψ_k} and τ_k·z̈ = Re(−i e^{−iψ_k} z̈). The
first mass moment of bifilar k (Σ m x over its parts) varies with φ_k as B i e^{iψ_k} φ_k, so
the absorbers push on the hub with F = −M z̈ − B d²/dt² Σ_k i e^{iψ_k} φ_k
(M = N(m_b + 2 m_p); the steady centrifugal forces cancel for N ≥ 2). Write the cyclic
(whirling) part of the swing as φ_k = Re(A e^{−iψ_k}), A(t) complex: then
Σ_k i e^{iψ_k} φ_k = (iN/2) A exactly when Σ_k e^{2iψ_k} = 0, i.e. N ≥ 3 (the other cyclic
modes exert no net force on the hub and are not excited by it). With
d/dt (A e^{−iψ}) = (Ȧ − iΩA) e^{−iψ}, every bifilar's equation is the real
part of e^{−iψ_k} times one constant-coefficient complex equation:

    J (Ä − 2iΩȦ − Ω²A) + c_φ (Ȧ − iΩA) + K A = i B z̈,      F = −M z̈ − i B (N/2) Ä.

**The particle.** Put w = i (J/B) A (m). Then F = −(M − m_e) z̈ − m_e (z̈ + ẅ) with

    m_e = N B² / (2J)                                                                (kg),

a rigid mass M − m_e riding with the hub and a particle of mass m_e at z + w, whose equation
(the A equation with A = −i (B/J) w, divided by −i B / m_e) is

    m_e (z̈ + ẅ) = −m_e (ñ² − 1) Ω² w + 2 m_e Ω ẑ × ẇ − (m_e c_φ / J) (ẇ − Ω ẑ × w):

an isotropic spring k = m_e (ñ² − 1) Ω² (negative below ñ = 1), a gyroscopic force that does
no work, and a damper c_e = m_e c_φ / J acting on the particle's velocity relative to axes
turning with the hub. Undamped, with the carrier still, w = W e^{iλt} gives
λ² − 2Ωλ − (ñ² − 1)Ω² = 0: λ = (ñ + 1)Ω (progressive whirl) and λ = −(ñ − 1)Ω (regressive
whirl at (ñ − 1)Ω), the fixed-frame images of the rotating-frame ñΩ. Driving the carrier with
z = Z e^{iωt} (ω > 0 progressive, ω < 0 regressive) gives the apparent mass F = M_eff ω² z,

    M_eff(ω) = M + m_e ω² / (ñ²Ω² − (ω − Ω)² + i (c_φ/J)(ω − Ω)),

which for a simple pendulum (B = m r, J = m r², m_e = N m/2) is the classical
N m [1 + ω²/(2(ñ²Ω² − (ω ∓ Ω)²))] for progressive/regressive whirl at |ω|. The reconstruction
inverts w = i (J/B) A: A = −i (B/J) w, φ_k = Re(A e^{−iψ_k}); the tuning masses' centre of mass
moves by (1/N) Σ_k i r e^{iψ_k} φ_k = (i r/2) A = (r B/(2J)) w relative to the hub centre.

**In the model** (:func:`add_equivalent`): the particle is a rigid body of mass m_e and no
inertia, kept in the carrier's plane and from turning by a planar joint and a rotation lock
about the axis; one :class:`solver.forces.FrameCoupling` measured in the carrier's axes holds
the spring, the gyroscopic force and the rotating damper:
f = −K w − C ẇ with K = k I − c_e Ω [ẑ×], C = c_e I − 2 m_e Ω [ẑ×]. The rigid remainder
M − m_e hangs on the spinning hub at its centre, carrying the rotary inertia of the locked
absorbers (which the in-plane equivalent does not otherwise represent: it matters when the
carrier tilts), or on the carrier as a point mass when no hub is given.

What the equivalent leaves out: amplitude detuning (φ²/16 for circles), the hole shape beyond
its vertex curvature, the pins' sliding limits, non-unison motion, and the second-order radial
motion of the tuning masses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from numbers import Integral

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.beams import BeamNode
from solver.bodies import Body, PointMass, PrescribedBody, RigidBody
from solver.forces import FrameCoupling
from solver.joints import Orientation, Planar, Rigid, Spherical
from solver.model import Model
from studies.holes import Holes

Array = NDArray[np.float64]

# skew matrix of ẑ (the rotor axis, the frame's d3): [ẑ×] w = ẑ × w
_ZX = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])


def _positive(name: str, value: float, allow_zero: bool = False) -> None:
    ok = np.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        raise ValueError(f"{name} = {value!r} must be a finite number "
                         f"{'≥ 0' if allow_zero else '> 0'}")


@dataclass(frozen=True)
class EquivalentAbsorber:
    """The linear fixed-frame equivalent of N identical bifilars (passive data, SI units).

    Attributes
    ----------
    n_absorbers
        N, the number of identical bifilars equally spaced in azimuth (≥ 3).
    total_mass
        M = N (m_b + 2 m_p) (kg): all tuning masses and pins.
    inertia
        J (kg·m²): inertia of one bifilar about its swing coordinate φ (the pin angle),
        r² (m_b + m_p/2 + 2 I_p/d²) for the paper's bifilar.
    coupling
        B (kg·m): translational momentum of one bifilar per unit φ̇, r (m_b + m_p).
    order
        ñ: the small-amplitude tuning order (rotating-frame frequency / Ω).
    swing_damping
        c_φ (N·m·s/rad): damping on φ̇ of one bifilar.
    path_radius
        r (m): radius of curvature of the tuning mass's path at the vertex; only used to
        reconstruct the tuning masses' centre of mass (None: not known).
    polar_inertia, tilt_inertia
        Moment of inertia (kg·m²) of the N bifilars locked at their vertex about the rotor axis
        and about an in-plane diameter through the hub centre; carried by the rigid remainder.
    """

    n_absorbers: int
    total_mass: float
    inertia: float
    coupling: float
    order: float
    swing_damping: float = 0.0
    path_radius: float | None = None
    polar_inertia: float = 0.0
    tilt_inertia: float = 0.0

    def __post_init__(self) -> None:
        n = self.n_absorbers
        if isinstance(n, bool) or not isinstance(n, Integral) or n < 3:
            raise ValueError(f"n_absorbers = {n!r} must be an integer ≥ 3: with fewer "
                             "absorbers the swing does not reduce to one whirling mode "
                             "(Σ e^{2iψ_k} ≠ 0)")
        for name in ("total_mass", "inertia", "coupling", "order"):
            _positive(name, getattr(self, name))
        for name in ("swing_damping", "polar_inertia", "tilt_inertia"):
            _positive(name, getattr(self, name), allow_zero=True)
        if self.path_radius is not None:
            _positive("path_radius", self.path_radius)
        if self.effective_mass > self.total_mass * (1.0 + 1e-12):
            raise ValueError(
                f"coupling = {self.coupling!r} kg m is too large for inertia = {self.inertia!r} "
                f"kg m2 and total_mass = {self.total_mass!r} kg: the effective mass "
                f"N B²/(2J) = {self.effective_mass:g} kg exceeds the total mass (the kinetic "
                "energy would not be positive)")

    @property
    def effective_mass(self) -> float:
        """m_e = N B² / (2J) (kg): the particle's mass."""
        return self.n_absorbers * self.coupling**2 / (2.0 * self.inertia)

    @property
    def rigid_mass(self) -> float:
        """M − m_e (kg): the mass that rides with the hub."""
        return self.total_mass - self.effective_mass

    @property
    def particle_damping(self) -> float:
        """c_e = m_e c_φ / J (N·s/m): the damper on the particle's velocity relative to axes
        turning with the hub."""
        return self.effective_mass * self.swing_damping / self.inertia

    @property
    def cm_gain(self) -> float:
        """r B / (2J): displacement of the tuning masses' centre of mass per unit particle
        displacement w (needs ``path_radius``)."""
        if self.path_radius is None:
            raise ValueError("path_radius is not known: the tuning masses' centre of mass "
                             "cannot be reconstructed")
        return self.path_radius * self.coupling / (2.0 * self.inertia)

    def stiffness(self, hub_speed: float) -> float:
        """k = m_e (ñ² − 1) Ω² (N/m) at the hub speed Ω (rad/s)."""
        return self.effective_mass * (self.order**2 - 1.0) * hub_speed**2

    def frequencies(self, hub_speed: float,
                    tuning_speed: float | None = None) -> tuple[float, float]:
        """Free whirl frequencies (rad/s, fixed frame) with the carrier held: progressive
        (ñ + 1)Ω and regressive (ñ − 1)Ω (a negative value whirls progressively).

        Parameters
        ----------
        hub_speed
            Ω (rad/s): sets the gyroscopic and rotating-damper terms.
        tuning_speed
            Ω_t (rad/s) at which the spring was tuned, k = m_e (ñ² − 1) Ω_t²
            (:meth:`stiffness`); ``None``: Ω, the spring retuned at every speed as the
            bifilars it stands for are. With w = W e^{iλt} the particle's equation gives
            λ² − 2Ωλ − k/m_e = 0, so λ = Ω ± √(Ω² + (ñ² − 1) Ω_t²): (ñ ± 1)Ω only at
            Ω = Ω_t.

        Raises
        ------
        ValueError
            If Ω² + (ñ² − 1) Ω_t² < 0 (a spring so negative that the particle is unstable).
        """
        if tuning_speed is None:
            return (self.order + 1.0) * hub_speed, (self.order - 1.0) * hub_speed
        disc = hub_speed**2 + self.stiffness(tuning_speed) / self.effective_mass
        if disc < 0:
            raise ValueError(f"tuning_speed = {tuning_speed!r} rad/s at hub_speed = "
                             f"{hub_speed!r} rad/s: the spring m_e (ñ² − 1) Ω_t² makes the "
                             "particle unstable (no whirl frequency)")
        root = float(np.sqrt(disc))
        return hub_speed + root, root - hub_speed

    def swing_terms(self, hub_speed: float, whirl: float | ArrayLike) -> tuple:
        """(S, D), complex, with Â/Z = S/D (:meth:`swing_response`): S = −i B ω² (kg·m/s²) and
        D = J (ñ²Ω² − (ω − Ω)²) + i c_φ (ω − Ω) (N·m), apart so that a caller can clear the
        denominator, which vanishes for an undamped absorber tuned to the whirl."""
        w = np.asarray(whirl, dtype=float)
        rel = w - hub_speed
        den = (self.inertia * ((self.order * hub_speed) ** 2 - rel**2)
               + 1j * self.swing_damping * rel)
        return -1j * self.coupling * w**2, den

    def swing_response(self, hub_speed: float, whirl: float | ArrayLike) -> complex | NDArray:
        """Â/Z (rad/m, complex): the swing's whirl amplitude A = Â e^{iωt} (φ_k = Re(A e^{−iψ_k}))
        per unit carrier displacement for the carrier whirling as z = Z e^{iωt} at the signed
        frequency ω = ``whirl`` (rad/s; > 0 progressive, < 0 regressive), from the A equation:
        (J (ñ²Ω² − (ω − Ω)²) + i c_φ (ω − Ω)) Â = −i B ω² Z."""
        num, den = self.swing_terms(hub_speed, whirl)
        return num / den

    def apparent_mass(self, hub_speed: float, whirl: float | ArrayLike) -> complex | NDArray:
        """M_eff (kg, complex) with F = M_eff ω² z for the carrier whirling as z = Z e^{iωt}
        at the signed frequency ω = ``whirl`` (rad/s; > 0 progressive, < 0 regressive):
        F = −M z̈ − i B (N/2) Ä, i.e. M_eff = M + i B (N/2) Â/Z (:meth:`swing_response`)."""
        return (self.total_mass + 0.5j * self.n_absorbers * self.coupling
                * self.swing_response(hub_speed, whirl))


def equivalent_absorber(holes: Holes, n_absorbers: int, pin_damping: float) -> EquivalentAbsorber:
    """The equivalent of ``n_absorbers`` bifilars with the designed ``holes``.

    Parameters
    ----------
    holes
        The bifilar design (:func:`studies.holes.design`); non-circular holes are linearized
        about the vertex (radius of curvature ``holes.rho_v``, equivalent hole diameter
        ``holes.hole_diameter``, order ``holes.order_linear``).
    n_absorbers
        N ≥ 3 identical bifilars equally spaced in azimuth.
    pin_damping
        c_pin (N·m·s/rad): rolling resistance on each pin's rotation relative to its arm-side
        link, as :func:`studies.absorbers.pin_damping` gives it; c_φ = c_pin (D/d)².

    Raises
    ------
    ValueError
        Naming the parameter (``n_absorbers``, ``pin_damping``, ``holes``).
    """
    if not isinstance(holes, Holes):
        raise ValueError(f"holes must be a studies.holes.Holes design, got "
                         f"{type(holes).__name__}")
    if (isinstance(n_absorbers, bool) or not isinstance(n_absorbers, Integral)
            or n_absorbers < 3):
        raise ValueError(f"n_absorbers = {n_absorbers!r} must be an integer ≥ 3")
    _positive("pin_damping", pin_damping, allow_zero=True)
    g = holes.geometry
    r = float(holes.rho_v)
    j = r * r * (g.tuning_mass + 0.5 * g.pin_mass + 2.0 * g.pin_inertia / g.pin_diameter**2)
    b = r * (g.tuning_mass + g.pin_mass)
    c_phi = pin_damping * (holes.hole_diameter / g.pin_diameter) ** 2
    n = int(n_absorbers)
    r_v = float(np.linalg.norm(holes.vertex))  # tuning mass's centre of mass at rest
    r_p = float(np.linalg.norm(holes.pin_center(0.0)))  # pin centre at rest
    # locked bifilars: point masses in the rotor plane, pins with polar inertia 2 I_p (and,
    # as in studies.bifilar, I_p about the transverse axes); equal spacing, N ≥ 3, makes the
    # in-plane inertia isotropic: half the polar part of the point masses about any diameter
    ring = g.tuning_mass * r_v**2 + 2.0 * g.pin_mass * r_p**2
    return EquivalentAbsorber(
        n_absorbers=n, total_mass=n * (g.tuning_mass + 2.0 * g.pin_mass), inertia=j,
        coupling=b, order=float(holes.order_linear), swing_damping=c_phi, path_radius=r,
        polar_inertia=n * (ring + 2.0 * g.pin_inertia),
        tilt_inertia=n * (0.5 * ring + g.pin_inertia))


@dataclass
class EquivalentParts:
    """Handles to the equivalent's elements, for outputs.

    ``radial_local`` holds, per bifilar, its radial unit vector at t = 0 in the hub's body
    axes (or, without a hub, in the carrier's), so that its azimuth in the carrier's axes can
    be read from the state."""

    absorber: EquivalentAbsorber
    omega: float
    carrier: Body
    hub: Body | None
    center_local: Array
    particle: RigidBody
    rigid: Body
    coupling: FrameCoupling
    radial_local: Array
    angles: Array
    elements: list = field(default_factory=list)


def _pose0(body: Body) -> tuple[Array, Array]:
    """Position (m) and rotation matrix of a body at t = 0."""
    if isinstance(body, PrescribedBody):
        return body.pose(0.0)
    if isinstance(body, PointMass):
        return np.asarray(body.position, float), np.eye(3)
    return np.asarray(body.position, float), np.asarray(body.orientation, float)


def _velocity0(body: Body, point: Array) -> tuple[Array, Array]:
    """Velocity (m/s) of a point of ``body`` and the body's angular velocity (rad/s), at
    t = 0, from its declaration."""
    if isinstance(body, PrescribedBody):
        x, _, v, w, *_ = (np.asarray(a, dtype=float) for a in body.motion(0.0))
        return v + np.cross(w, point - x), w
    if isinstance(body, BeamNode):
        beam = body.beam
        w = np.asarray(beam.angular_velocity, dtype=float)
        return (np.asarray(beam.velocity, dtype=float)
                + np.cross(w, point - np.asarray(beam.about, dtype=float))), w
    x = np.asarray(body.position, dtype=float)
    w = np.asarray(getattr(body, "angular_velocity", np.zeros(3)), dtype=float)
    return np.asarray(body.velocity, dtype=float) + np.cross(w, point - x), w


def add_equivalent(model: Model, carrier: Body, hub: Body | None, center: ArrayLike,
                   absorber: EquivalentAbsorber, omega: float, prefix: str = "eq_",
                   first_angle: float = np.pi / 4, displacement: ArrayLike = (0.0, 0.0),
                   rate: ArrayLike = (0.0, 0.0),
                   tuning_speed: float | None = None) -> EquivalentParts:
    """Add the equivalent absorber of N bifilars to ``model``.

    Parameters
    ----------
    model
        The model to add to.
    carrier
        A non-rotating body (rigid body, beam node or prescribed body) whose local d3 is the
        rotor axis; the particle moves in its plane through ``center`` and w is measured in
        its axes.
    hub
        The hub spinning at ``omega`` about the rotor axis through ``center``; the rigid
        remainder M − m_e (with the locked bifilars' rotary inertia) is clamped to it. None:
        the remainder is a point mass on the carrier, and the bifilars' azimuths are taken as
        Ωt + α_k from the carrier's d1.
    center
        The hub centre (m, global, t = 0), a point of the carrier.
    absorber
        From :func:`equivalent_absorber`.
    omega
        The prescribed hub speed Ω (rad/s, > 0, constant: the equivalent is linear
        time-invariant only at constant speed).
    prefix
        Prefix of the names of the added elements.
    first_angle
        α_0 (rad): azimuth of bifilar 0's radial line from the hub's (t = 0: the carrier's) d1;
        the others follow at 2π/N. Only the reconstructed pin angles depend on it.
    displacement, rate
        w and ẇ (m, m/s) at t = 0 in the carrier's axes (d1, d2): the particle's start
        relative to the hub centre, e.g. :func:`particle_state` of given pin angles and rates.
    tuning_speed
        Ω_t (rad/s, > 0) at which the spring was tuned: its stiffness is
        k = m_e (ñ² − 1) Ω_t² whatever ``omega`` is, as a physical spring–mass absorber keeps
        the spring it was built with; the gyroscopic and rotating-damper terms follow
        ``omega``. ``None`` (default): Ω_t = Ω, the spring retuned with the speed as the
        bifilars' centrifugal stiffness is, the exact equivalent of the bifilars.

    Returns
    -------
    EquivalentParts
        Handles for :func:`equivalent_pin_angles` and :func:`equivalent_cm`.
    """
    if not isinstance(absorber, EquivalentAbsorber):
        raise ValueError(f"absorber must be an EquivalentAbsorber, got {type(absorber).__name__}")
    _positive("omega", omega)
    if tuning_speed is not None:
        _positive("tuning_speed", tuning_speed)
    if isinstance(carrier, PointMass) or carrier is None:
        raise ValueError("carrier must be a rigid body, beam node or prescribed body (it needs "
                         "axes: d3 is the rotor axis)")
    if hub is carrier:
        raise ValueError("hub must be the spinning hub, not the non-rotating carrier")
    if hub is not None and isinstance(hub, PointMass):
        raise ValueError("hub must be a rigid body (or None), not a point mass")
    c0 = np.asarray(center, dtype=float).reshape(-1)
    if c0.shape != (3,) or not np.all(np.isfinite(c0)):
        raise ValueError(f"center = {center!r} must be 3 finite numbers (m)")
    start = []
    for name, value in (("displacement", displacement), ("rate", rate)):
        a = np.asarray(value, dtype=float).reshape(-1)
        if a.shape != (2,) or not np.all(np.isfinite(a)):
            raise ValueError(f"{name} = {value!r} must be 2 finite numbers (carrier axes d1, d2)")
        start.append(np.array([a[0], a[1], 0.0]))
    omega = float(omega)
    xc, rc = _pose0(carrier)
    axis = rc[:, 2]
    center_local = rc.T @ (c0 - xc)
    vel, w_carrier = _velocity0(carrier, c0)
    ab = absorber
    m_e, c_e = ab.effective_mass, ab.particle_damping
    # the particle: translates in the carrier's plane, turns with it; w is read in the
    # carrier's axes, so its global rate adds the carrier's turn of it
    w0, wd0 = rc @ start[0], rc @ start[1]
    particle = RigidBody(f"{prefix}particle", m_e, inertia=(0.0, 0.0, 0.0), position=c0 + w0,
                         velocity=vel + np.cross(w_carrier, w0) + wd0)
    # spring k I, rotating damper −c_e (ẇ − Ω ẑ×w) and gyroscopic 2 m_e Ω ẑ×ẇ, in the
    # carrier's axes: f = −K w − C ẇ. The coupling's point is the hub centre c0 on both
    # bodies, so on the particle it sits −w0 from the particle: Δ = w − w0, and the spring is
    # unstretched at w = 0 with the rest value −w0
    spring = ab.stiffness(omega if tuning_speed is None else float(tuning_speed))
    k_mat = spring * np.diag([1.0, 1.0, 0.0]) - c_e * omega * _ZX
    c_mat = c_e * np.diag([1.0, 1.0, 0.0]) - 2.0 * m_e * omega * _ZX
    coupling = FrameCoupling(f"{prefix}coupling", carrier, particle, frame=carrier, point=c0,
                             stiffness=k_mat, damping=c_mat, rest=-start[0])
    elements: list = [particle,
                      Planar(f"{prefix}plane", carrier, particle, point=c0, axis=axis),
                      Orientation(f"{prefix}noturn", carrier, particle, point=c0, axis=axis,
                                  axes=(2,)),
                      coupling]
    # the rigid remainder
    if hub is not None:
        vh, wh = _velocity0(hub, c0)
        if np.linalg.norm(np.cross(wh, axis)) > 1e-9 * np.linalg.norm(wh):
            raise ValueError(f"carrier {carrier.name!r}: its local d3 {np.round(axis, 6)} "
                             f"(the rotor axis of the equivalent) is not along the spin axis "
                             f"of hub {hub.name!r}, {np.round(wh, 6)} rad/s")
        n = axis[:, None]
        inertia = ab.tilt_inertia * (np.eye(3) - n @ n.T) + ab.polar_inertia * (n @ n.T)
        rigid: Body = RigidBody(f"{prefix}rigid", ab.rigid_mass, inertia=inertia, position=c0,
                                velocity=vh, angular_velocity=wh)
        elements += [rigid, Rigid(f"{prefix}mount", hub, rigid, point=c0)]
        _, rh = _pose0(hub)
    else:
        rigid = PointMass(f"{prefix}rigid", ab.rigid_mass, position=c0, velocity=vel)
        elements += [rigid, Spherical(f"{prefix}mount", carrier, rigid, point=c0)]
        rh = rc
    model.add(*elements)
    angles = first_angle + 2.0 * np.pi * np.arange(ab.n_absorbers) / ab.n_absorbers
    # radial unit vectors at t = 0 (in the carrier's plane), in the hub's (carrier's) axes
    radial = np.outer(np.cos(angles), rc[:, 0]) + np.outer(np.sin(angles), rc[:, 1])
    return EquivalentParts(ab, omega, carrier, hub, center_local, particle, rigid, coupling,
                           radial @ rh, angles, elements)


# ----------------------------------------------------------------------- reconstruction
def _carrier_axes(system, parts: EquivalentParts, q: Array) -> tuple[Array, Array]:
    """Carrier rotation matrix (columns d1, d2, d3) and the hub centre (m, global) at q."""
    rc = system.directors(q, parts.carrier)
    o = system.offset[parts.carrier]
    return rc, q[o : o + 3] + rc @ parts.center_local


def particle_displacement(system, parts: EquivalentParts, q: Array) -> Array:
    """w (m): the particle's displacement from the hub centre in the carrier's axes (d1, d2)."""
    rc, p = _carrier_axes(system, parts, q)
    o = system.offset[parts.particle]
    return rc[:, :2].T @ (q[o : o + 3] - p)


def bifilar_azimuths(system, parts: EquivalentParts, q: Array, t: float | None = None) -> Array:
    """ψ_k (rad): azimuth of each bifilar's radial line from the carrier's d1, at q (from the
    hub's directors; without a hub, Ωt + α_k)."""
    if parts.hub is None:
        if t is None:
            raise ValueError("t is needed to place the bifilars when the equivalent has no hub")
        return parts.omega * t + parts.angles
    rc = system.directors(q, parts.carrier)
    radial = parts.radial_local @ system.directors(q, parts.hub).T  # rows: global vectors
    return np.arctan2(radial @ rc[:, 1], radial @ rc[:, 0])


def equivalent_pin_angles(system, parts: EquivalentParts, q: Array,
                          t: float | None = None) -> Array:
    """φ_k (rad) of each bifilar, reconstructed from the particle: A = −i (B/J) w,
    φ_k = Re(A e^{−iψ_k}) (the cyclic whirl mode; linear)."""
    ab = parts.absorber
    w = particle_displacement(system, parts, q)
    a = -1j * ab.coupling / ab.inertia * (w[0] + 1j * w[1])
    return np.real(a * np.exp(-1j * bifilar_azimuths(system, parts, q, t)))


def equivalent_cm(system, parts: EquivalentParts, q: Array, t: float | None = None) -> Array:
    """Centre of mass (m, global) of the N tuning masses (pins excluded), reconstructed: the
    hub centre plus (r B / 2J) w (linear; ``t`` is accepted for symmetry with
    :func:`equivalent_pin_angles`)."""
    rc, p = _carrier_axes(system, parts, q)
    return p + parts.absorber.cm_gain * (rc[:, :2] @ particle_displacement(system, parts, q))


def particle_state(absorber: EquivalentAbsorber, hub_speed: float,
                   pin_angles: Sequence[float] | Array, pin_rates: Sequence[float] | Array,
                   azimuths: Array) -> tuple[Array, Array]:
    """w and ẇ (m, m/s; the carrier's axes d1, d2) of the particle carrying the cyclic whirl of
    the pin angles φ_k and rates φ̇_k (rad, rad/s) of bifilars at azimuths ψ_k (rad): the
    inverse of :func:`equivalent_pin_angles`. With A = (2/N) Σ φ_k e^{iψ_k}
    (:func:`whirl_amplitude`) and φ̇_k = Re((Ȧ − iΩA) e^{−iψ_k}), Ȧ = (2/N) Σ φ̇_k e^{iψ_k}
    + iΩA; w = i (J/B) A."""
    a = whirl_amplitude(pin_angles, azimuths)
    adot = whirl_amplitude(pin_rates, azimuths) + 1j * hub_speed * a
    gain = 1j * absorber.inertia / absorber.coupling
    return (np.array([(gain * a).real, (gain * a).imag]),
            np.array([(gain * adot).real, (gain * adot).imag]))


def whirl_amplitude(pin_angles: Sequence[float] | Array, azimuths: Array) -> complex:
    """A (rad, complex) from N ≥ 3 pin angles φ_k at azimuths ψ_k: (2/N) Σ φ_k e^{iψ_k}, the
    cyclic component that the equivalent carries (for comparing with a full model)."""
    phi = np.asarray(pin_angles, dtype=float)
    return complex(2.0 / len(phi) * np.sum(phi * np.exp(1j * np.asarray(azimuths))))
