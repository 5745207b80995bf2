"""A linear structure given by its modes, and the joint that attaches a body to it.

An airframe (or any linear elastic structure) is brought in as the normal modes of a finite
element model: n modal coordinates η_i, each obeying

    m_i η̈_i + 2 ζ_i ω_i m_i η̇_i + m_i ω_i² η_i = Q_i,

with ω_i = 2π f_i, ζ_i the modal damping ratio, m_i the generalized mass and Q_i the generalized
force of whatever is attached (virtual work Q·δη). The structure is linear: its motion is small
and its physical displacement at a point is Φ η, Φ the mode shapes there.

:class:`ModalStructure` owns the η as second-order unknowns with the constant mass matrix
diag(m_i), so the kinetic energy ½ Σ m_i η̇_i² is in the model's mass matrix like a body's. Its
set gives the quadratic potential ½ Σ m_i ω_i² η_i² (its midpoint gradient is the exact
discrete gradient, so ``ep`` conserves energy and ``ed`` keeps its dissipation inequality) and
the damping force −2 ζ_i ω_i m_i η̇_i, a damper whose work the integrators book with every other
damper's (negative: energy lost).

:class:`ModalAttachment` is a joint with Lagrange multipliers: a body's material point follows
the structure's displacement and the body's small rotation follows the structure's. Its rows
are linear in the unknowns (quadratic in η when the point turns on the arc about a rotation
centre), so they go into the model's shared quadratic constraint tensor (:mod:`solver.quadratic`,
compiled and vectorized with the lower-pair joints): the midpoint rule is exact on them as a
discrete derivative, and their multipliers do no work. The multipliers' forces on the η columns
are the generalized forces Q of the attachment.

Conventions
-----------
Units are those of the shape normalization, consistent if m_i |Φ|² is a mass. The documented
default: η in m (shapes scaled to unit displacement at a reference point of the airframe),
translation shapes Φ_t in m per m of η (dimensionless), rotation shapes Φ_r in rad per m of η,
generalized masses m_i in kg, Q_i in N. A shape scaled by s has its generalized mass scaled by
s² and its η by 1/s; with mass-normalized finite-element shapes (Φᵀ M_FE Φ = I) pass
``masses`` = 1: η is then in kg^½·m and Φ in kg^-½. Shapes are in global axes; η positive
moves the structure along +Φ.

Limitations: the modal coordinates are second-order scalars, not 3-vectors, so a model with a
modal structure cannot be linearized about a steadily spinning state (``solver.modes`` with a
``Spin`` refuses its state block, naming it) and :meth:`solver.system.System.angular_momentum`
(which reads the second-order coordinates as 3-vectors) does not apply to it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.beams import BeamNode
from solver.bodies import PointMass, PrescribedBody, RigidBody
from solver.element import EMPTY_F, Element, ElementSet
from solver.integrators import initial_accelerations
from solver.quadratic import QuadraticBuilder, QuadraticSet, VecExpr
from solver.rotations import skew
from solver.state import SECOND, StateBlock

if TYPE_CHECKING:
    from solver.integrators import Integrator
    from solver.system import System

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi
ACCELERATION_SOURCES = ("equations", "scheme")


# --------------------------------------------------------------------------- validation
def _modal_vector(x: ArrayLike, what: str, unit: str, owner: str, n: int | None,
                  allow_scalar: bool = False) -> Array:
    """A 1-D array of finite numbers (length ``n`` if given; a scalar is broadcast when
    ``allow_scalar``)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 and (allow_scalar or n is None):
        a = np.full(1 if n is None else n, float(a))
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"{owner}: {what} must be a 1-D sequence of numbers (one per mode), "
                         f"got shape {a.shape}")
    if n is not None and a.size != n:
        raise ValueError(f"{owner}: {what} has {a.size} values but frequencies has {n}: "
                         "every modal parameter needs one value per mode")
    bad = np.nonzero(~np.isfinite(a))[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{owner}: {what}[{i}] = {float(a[i])!r}{unit} must be finite")
    return a


def _check_range(a: Array, what: str, unit: str, owner: str, ok: NDArray[np.bool_],
                 valid: str) -> None:
    bad = np.nonzero(~ok)[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{owner}: {what}[{i}] = {float(a[i])!r}{unit}: outside the valid range "
                         f"{valid}")


def _shape_matrix(x: ArrayLike, what: str, unit: str, owner: str, n: int) -> Array:
    """A 3 × n matrix of finite shape values (a 3-vector is accepted for a single mode)."""
    a = np.asarray(x, dtype=float)
    if a.shape == (3,) and n == 1:
        a = a.reshape(3, 1)
    if a.shape != (3, n):
        raise ValueError(f"{owner}: {what} must be a 3 x {n} array (global x, y, z rows, one "
                         f"column per mode, {unit}), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{owner}: {what} must be finite")
    return a


# ------------------------------------------------------------------------ the structure
@dataclass
class StationMotion:
    """Motion of a response station of a modal structure (global axes): Φ_s η, Φ_s η̇, Φ_s η̈
    (units of the station shapes times those of η, per s and per s²; m, m/s, m/s² for
    translation shapes in m per m of η, rad, rad/s, rad/s² for rotation shapes)."""

    displacement: Array
    velocity: Array
    acceleration: Array


@dataclass(eq=False)
class ModalStructure(Element):
    """A linear structure represented by n of its normal modes.

    The modal coordinates η obey m_i η̈_i + 2 ζ_i ω_i m_i η̇_i + m_i ω_i² η_i = Q_i (ω_i = 2π f_i,
    Q_i the generalized forces of the attachments, :class:`ModalAttachment`). Kinetic energy
    ½ Σ m_i η̇_i², potential ½ Σ m_i ω_i² η_i²; the modal damping is a damper whose (negative)
    work the integrators book. See the module docstring for units and sign.

    Parameters
    ----------
    name
        Unique name; its state block is reported under it.
    frequencies
        Undamped natural frequencies f_i (Hz), finite and ≥ 0 (0: a rigid-body mode).
    damping_ratios
        Modal damping ratios ζ_i (fraction of critical), 0 ≤ ζ_i < 1; a scalar applies to
        every mode.
    masses
        Generalized masses m_i > 0 (kg with η in m; see the module docstring).
    displacement, velocity
        Initial η (m) and η̇ (m/s); zero by default. The attached bodies should be placed and
        moving consistently (at t = 0 the model is projected onto its constraints, least
        squares, moving the bodies and η alike).
    """

    name: str
    frequencies: ArrayLike
    damping_ratios: ArrayLike
    masses: ArrayLike
    displacement: ArrayLike | None = None
    velocity: ArrayLike | None = None

    def __post_init__(self) -> None:
        owner = f"modal structure {self.name!r}"
        f = _modal_vector(self.frequencies, "frequencies", " Hz", owner, None)
        n = f.size
        _check_range(f, "frequencies", " Hz", owner, f >= 0.0, "[0, inf) Hz")
        z = _modal_vector(self.damping_ratios, "damping_ratios", "", owner, n,
                          allow_scalar=True)
        _check_range(z, "damping_ratios", "", owner, (z >= 0.0) & (z < 1.0),
                     "[0, 1) (fraction of critical damping)")
        m = _modal_vector(self.masses, "masses", " kg", owner, n)
        _check_range(m, "masses", " kg", owner, m > 0.0, "(0, inf) kg (generalized mass)")
        self.n_modes = n
        self.frequency, self.damping_ratio, self.mass = f, z, m
        self.omega = TWO_PI * f
        # modal stiffness m ω² (N/m) and damping 2 ζ ω m (N·s/m), per mode
        self.modal_stiffness = m * self.omega**2
        self.modal_damping = 2.0 * z * self.omega * m
        self.eta0 = (np.zeros(n) if self.displacement is None
                     else _modal_vector(self.displacement, "displacement", " m", owner, n))
        self.eta_dot0 = (np.zeros(n) if self.velocity is None
                         else _modal_vector(self.velocity, "velocity", " m/s", owner, n))

    def states(self) -> list[StateBlock]:
        block = StateBlock(self, SECOND, self.n_modes, initial=self.eta0, rate=self.eta_dot0,
                           mass=np.diag(self.mass), units="m",
                           long_name=f"modal coordinates of {self.name}")
        # scalars, neither positions nor directors (a block of 3 or 12·k would otherwise be
        # taken for 3-vectors, and turned as such by a spinning analysis)
        block.positions = None
        return [block]

    # -- outputs ------------------------------------------------------------------------
    def indices(self, system: System) -> NDArray[np.int64]:
        """Indices of η in the system's unknowns."""
        o = system.offset[self]
        return np.arange(o, o + self.n_modes)

    def modal_state(self, integrator: Integrator,
                    acceleration: str = "equations") -> tuple[Array, Array, Array]:
        """(η, η̇, η̈) at the integrator's current state (m, m/s, m/s²).

        ``acceleration`` says where η̈ comes from:

        * ``"equations"`` (default, any scheme): the equations of motion solved at the
          current (q, v, t) for the consistent accelerations and multipliers (one sparse
          factorization of [[M, Gᵀ], [G, 0]] per call). Exact for the state reached, so its
          error is that of the state, of the scheme's order.
        * ``"scheme"``: the acceleration the scheme keeps, q̈_{n+1} of ``galpha`` (which
          satisfies the discrete equations of motion at t_{n+1}) or the stage-b acceleration
          of ``ed``; ``ep`` keeps none (its step only has the mean (v_f − v_i)/h, an O(h)
          estimate at the step's end) and raises.
        """
        s = integrator.sys
        idx = self.indices(s)
        qdd = _accelerations(integrator, acceleration)
        return integrator.q[idx].copy(), integrator.v[idx].copy(), qdd[idx].copy()

    def station_motion(self, stations: Mapping[str, ArrayLike], integrator: Integrator,
                       acceleration: str = "equations") -> dict[str, StationMotion]:
        """Motion of named response stations: displacement Φ_s η, velocity Φ_s η̇ and
        acceleration Φ_s η̈ at the integrator's current state.

        Parameters
        ----------
        stations
            Station name → its shapes Φ_s (3 × n: global x, y, z rows, one column per mode;
            a 3-vector for a single mode), translation (m per m of η) or rotation (rad per m).
        integrator
            The running integrator (its current q, v, t, and for ``"scheme"`` its kept
            acceleration).
        acceleration
            ``"equations"`` or ``"scheme"``: see :meth:`modal_state`.

        Returns
        -------
        dict
            Station name → :class:`StationMotion`.
        """
        shapes = {k: _shape_matrix(v, f"station {k!r} shapes", "per m of η",
                                   f"modal structure {self.name!r}", self.n_modes)
                  for k, v in stations.items()}
        eta, rate, acc = self.modal_state(integrator, acceleration)
        return {k: StationMotion(p @ eta, p @ rate, p @ acc) for k, p in shapes.items()}

    def generalized_force(self, integrator: Integrator,
                          acceleration: str = "equations") -> Array:
        """Q (N): the generalized forces of the attachments on the modes, −(Gᵀλ) on η, at the
        integrator's current state; with ``"equations"`` the multipliers consistent with the
        state's accelerations (then Q = m η̈ + 2ζωm η̇ + mω² η exactly), with ``"scheme"`` the
        scheme's own multipliers (``ep``: the step's mean constraint force; ``galpha``: those
        at t_{n+1})."""
        s = integrator.sys
        _check_source(acceleration)
        if acceleration == "scheme":
            lam = integrator.lam
        else:
            lam = _equations_of_motion(integrator)[1]
        g = s.jacobian_values(integrator.q, integrator.t)
        return -s.gmul_T(g, lam)[self.indices(s)]


def _check_source(source: str) -> None:
    if source not in ACCELERATION_SOURCES:
        raise ValueError(f"acceleration = {source!r}: must be one of "
                         f"{', '.join(ACCELERATION_SOURCES)}")


def _accelerations(integrator: Integrator, source: str) -> Array:
    """q̈ at the integrator's state from the equations of motion or kept by the scheme."""
    _check_source(source)
    if source == "equations":
        return _equations_of_motion(integrator)[0]
    qdd = getattr(integrator, "qdd", None)
    if qdd is None:
        raise ValueError(f"acceleration = 'scheme': the {integrator.name!r} scheme keeps no "
                         "end-of-step acceleration; use acceleration = 'equations'")
    return qdd


def _equations_of_motion(integrator: Integrator) -> tuple[Array, Array]:
    """(q̈, λ) consistent with the integrator's (q, v, t): the equations of motion with the
    constraints at the acceleration level."""
    qdd, lam, _ = initial_accelerations(integrator.sys, integrator.q, integrator.v,
                                        integrator.t, multipliers=True)
    return qdd, lam


class ModalStructureSet(ElementSet):
    """All modal structures of a model: a diagonal quadratic potential ½ Σ k_i η_i²
    (k = m ω²; its midpoint gradient is the exact discrete gradient) and the diagonal damper
    f = −c η̇ (c = 2 ζ ω m) on the modes with ζ > 0."""

    def __init__(self, elements: list[ModalStructure], system: System) -> None:
        super().__init__(elements, system)
        idx = np.concatenate([e.indices(system) for e in elements]).astype(np.int64)
        k = np.concatenate([e.modal_stiffness for e in elements])
        c = np.concatenate([e.modal_damping for e in elements])
        stiff = k > 0.0
        self.grad_idx = idx[stiff]
        self.stiff_rows = self.stiff_cols = self.grad_idx
        self._k = k[stiff]
        damped = c > 0.0
        self.force_idx = idx[damped]
        self.fv_rows = self.fv_cols = self.force_idx
        self._c = c[damped]
        self.nonconservative = bool(damped.any())

    def potential(self, q: Array) -> float:
        eta = q[self.grad_idx]
        return 0.5 * float(self._k @ (eta * eta))

    def gradient(self, q: Array) -> Array:
        return self._k * q[self.grad_idx]

    def stiffness(self, q: Array) -> Array:
        return self._k

    def force(self, q: Array, v: Array, t: float) -> Array:
        return -self._c * v[self.force_idx]

    def force_jacobians(self, q: Array, v: Array, t: float) -> tuple[Array, Array]:
        return EMPTY_F, -self._c


ModalStructure.set_class = ModalStructureSet


# ------------------------------------------------------------------------- the attachment
@dataclass(eq=False)
class ModalAttachment(Element):
    """Attaches a body to a modal structure at a point (a joint with Lagrange multipliers).

    With p the body's material point that is at ``point`` at t = 0, d_k the body's directors
    (d_k0 their values at t = 0) and η0 the structure's initial ``displacement`` (zero by
    default), the rows are

        p − point − Φ_t (η − η0) = 0              (3 rows, if ``translation_shapes`` given)
        ½ Σ_k d_k0 × d_k − Φ_r (η − η0) = 0       (3 rows, if ``rotation_shapes`` given):

    the displacement of the point from its initial position is Φ_t (η − η0) and the body's
    small rotation from its initial orientation Φ_r (η − η0); the body is declared where the
    structure deflected by η0 carries it (with η0 = 0, the undeformed structure).

    With a ``rotation_centre`` c, the translation rows gain the second-order term of a rigid
    rotation, p − point − Φ_t u − ½ θ × (θ × r) = 0 with u = η − η0, θ = Φ_r u and
    r = point − c: the attached point turns on an arc about c, not along its tangent. The
    linear rows leave out the geometric stiffness of a steady load at the point, which matters
    when that load is large: a rotor's thrust T at a hub h above an airframe's centre of
    gravity turns with the shaft when the airframe rolls by φ, and on the tangent its moment
    about the centre is T h φ, a negative roll stiffness that soft rigid-body modes cannot
    hold (on the arc it is zero, as for the rigid body). The rows are then quadratic in η,
    still exact as discrete derivatives (the midpoint rule is exact on quadratics), and their
    forces still do no work.

    The structure is linear (small motions) and so is this measure of the body's rotation from
    its initial orientation: for a rotation by φ about the unit axis n it is sin φ n, the
    rotation vector exact to first order (error φ³/6) and built from the directors the body's
    orthonormality rows keep orthonormal (it is the axial vector of the rotation's skew part,
    independent of the three orthonormality rows, which fix its symmetric part). Both row
    sets are linear in the unknowns (without a ``rotation_centre``, below): their Jacobian is
    constant, so they are exact as discrete derivatives and their forces do no work in any
    scheme.

    The constraint forces are −Gᵀλ: the body takes the force −λ_t at the point and (to first
    order) the moment −λ_r, and the same rows give the modes the generalized forces
    Q = Φ_tᵀ λ_t + Φ_rᵀ λ_r (with a centre, plus the arc term's derivative), the virtual work
    of the opposite force and moment, which the body
    applies to the structure (action and reaction: the constraint forces on body and modes
    together do no work). :meth:`solver.system.System.reaction` reports the force and moment
    on the body, :meth:`modal_force` the generalized force on the modes.

    Parameters
    ----------
    name
        Joint name.
    body
        A rigid body, beam node, prescribed body (base excitation of the modes) or point mass
        (translation only).
    modal
        The :class:`ModalStructure` followed.
    point
        Global position (m) at t = 0 of the attached material point (a point mass: its
        position), on the structure deflected by its initial η0.
    translation_shapes
        Φ_t (3 × n, global axes, m per m of η) at the point; ``None``: the point's translation
        is left free (the body is then held in rotation only).
    rotation_shapes
        Φ_r (3 × n, global axes, rad per m of η); ``None``: the body's rotation is left free
        (a spherical attachment). At least one of the two is needed.
    rotation_centre
        Global position (m) at t = 0 of the centre about which the rotations Φ_r η turn the
        point (an airframe's centre of gravity, about which its rigid-body rotation modes are
        given); ``None`` keeps the translation rows linear. Needs both shape blocks.
    """

    name: str
    body: RigidBody | PointMass | PrescribedBody | BeamNode
    modal: ModalStructure
    point: ArrayLike
    translation_shapes: ArrayLike | None
    rotation_shapes: ArrayLike | None = None
    rotation_centre: ArrayLike | None = None

    set_class = QuadraticSet

    def __post_init__(self) -> None:
        owner = f"modal attachment {self.name!r}"
        if not isinstance(self.modal, ModalStructure):
            raise ValueError(f"{owner}: modal must be a ModalStructure, got "
                             f"{type(self.modal).__name__}")
        if not isinstance(self.body, (RigidBody, PointMass, PrescribedBody, BeamNode)):
            raise ValueError(f"{owner}: body must be a body (rigid body, beam node, point "
                             f"mass, prescribed body), got {type(self.body).__name__}")
        p = np.asarray(self.point, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"{owner}: point must be 3 finite numbers (m, global), got "
                             f"{self.point!r}")
        self.point = p
        n = self.modal.n_modes
        if self.translation_shapes is None and self.rotation_shapes is None:
            raise ValueError(f"{owner}: translation_shapes and rotation_shapes are both None: "
                             "the attachment would constrain nothing")
        self.phi_t = (None if self.translation_shapes is None else
                      _shape_matrix(self.translation_shapes, "translation_shapes",
                                    "m per m of η", owner, n))
        self.phi_r = (None if self.rotation_shapes is None else
                      _shape_matrix(self.rotation_shapes, "rotation_shapes",
                                    "rad per m of η", owner, n))
        if self.phi_r is not None and isinstance(self.body, PointMass):
            raise ValueError(f"{owner}: rotation_shapes given but {self.body.name!r} is a point "
                             "mass and has no rotation; attach a rigid body or pass None")
        self.arm = None
        if self.rotation_centre is not None:
            c = np.asarray(self.rotation_centre, dtype=float).reshape(-1)
            if c.shape != (3,) or not np.all(np.isfinite(c)):
                raise ValueError(f"{owner}: rotation_centre must be 3 finite numbers (m, "
                                 f"global) or None, got {self.rotation_centre!r}")
            if self.phi_t is None or self.phi_r is None:
                raise ValueError(f"{owner}: rotation_centre needs both translation_shapes and "
                                 "rotation_shapes")
            self.arm = p - c  # r, from the centre to the point (m)

    @property
    def body_b(self) -> RigidBody | PointMass | PrescribedBody | BeamNode:
        """The attached body (the body a joint's reaction is reported on)."""
        return self.body

    def point_on_b(self, lay) -> VecExpr:
        """The attached material point as a vector expression (m)."""
        return lay.point(self.body, lay.to_local_point(self.body, self.point))

    def quadratic_rows(self, qb: QuadraticBuilder, lay) -> tuple[NDArray[np.int64], dict]:
        """The translation rows p − point − Φ_t (η − η0) and the rotation rows
        ½ Σ_k [d_k0×] d_k − Φ_r (η − η0), all linear (see the class docstring)."""
        eta = lay.offset[self.modal]
        eta0 = self.modal.eta0
        out = []
        if self.phi_t is not None:
            rows = qb.new_rows(3)
            qb.add_vector(rows, self.point_on_b(lay)
                          - VecExpr([], self.point - self.phi_t @ eta0))
            _add_modal_terms(qb, rows, -self.phi_t, eta)
            if self.arm is not None:
                _add_arc_terms(qb, rows, self.phi_r, self.arm, eta, eta0)
            out.append(rows)
        if self.phi_r is not None:
            rows = qb.new_rows(3)
            # R0, the initial rotation (columns d_k0): to_local_vector(e_j) = R0ᵀ e_j is its
            # row j
            r0 = np.array([lay.to_local_vector(self.body, e) for e in np.eye(3)])
            for k in range(3):
                dk = lay.vector(self.body, np.eye(3)[k])  # director d_k
                _add_matrix_vector(qb, rows, 0.5 * skew(r0[:, k]), dk)
            for i, c in enumerate(self.phi_r @ eta0):
                if c != 0.0:
                    qb.add_constant(int(rows[i]), float(c))
            _add_modal_terms(qb, rows, -self.phi_r, eta)
            out.append(rows)
        return np.concatenate(out), {}

    def modal_force(self, system: System, q: ArrayLike, lam: ArrayLike,
                    t: float = 0.0) -> Array:
        """Q (n,): the generalized force this attachment applies to the modes, −(Gᵀλ) on η of
        its own rows, for multipliers ``lam`` (all holonomic rows) at ``q``."""
        quad, rows = system.quad, system.quad_set.rows[self]
        entries = np.flatnonzero(np.isin(quad.jac_rows, rows))
        q = np.asarray(q, dtype=float)
        lam = np.asarray(lam, dtype=float)
        gv = quad.jacobian_values(q, t)[entries]
        f = -np.bincount(quad.jac_cols[entries], gv * lam[quad.jac_rows[entries]],
                         minlength=system.n)
        return f[self.modal.indices(system)]


def _add_matrix_vector(qb: QuadraticBuilder, rows: NDArray[np.int64], a: Array,
                       u: VecExpr) -> None:
    """rows[i] += Σ_j a_ij u_j for a constant 3 × 3 matrix a and a vector expression u."""
    for c, o in u.terms:
        for i in range(3):
            for j in range(3):
                if a[i, j] != 0.0:
                    qb.add_linear(int(rows[i]), o + j, c * float(a[i, j]))
    const = a @ u.const
    for i in range(3):
        if const[i] != 0.0:
            qb.add_constant(int(rows[i]), float(const[i]))


def _add_arc_terms(qb: QuadraticBuilder, rows: NDArray[np.int64], phi_r: Array, arm: Array,
                   eta: int, eta0: Array) -> None:
    """rows[k] −= ½ [θ × (θ × r)]_k, θ = Φ_r u, u = η − η0 (η_j at index eta + j).

    θ × (θ × r) = θ (θ·r) − r (θ·θ), so row k's term is uᵀ S_k u with S_k the symmetric part
    of Φ_r[k]ᵀ (Φ_rᵀ r)ᵀ − r_k Φ_rᵀ Φ_r; with u = η − η0 it is ηᵀ S_k η − 2 (S_k η0)·η +
    η0ᵀ S_k η0."""
    w = phi_r.T @ arm  # θ·r = w·u
    gram = phi_r.T @ phi_r  # θ·θ = uᵀ gram u
    n = phi_r.shape[1]
    lin = np.zeros((3, n))
    for k in range(3):
        a = np.outer(phi_r[k], w) - arm[k] * gram
        s = -0.25 * (a + a.T)  # −½ times the symmetric part
        row = int(rows[k])
        for i in range(n):
            for j in range(n):
                if s[i, j] != 0.0:
                    qb.add_product(row, eta + i, eta + j, float(s[i, j]))
        lin[k] = -2.0 * (s @ eta0)
        const = float(eta0 @ s @ eta0)
        if const != 0.0:
            qb.add_constant(row, const)
    _add_modal_terms(qb, rows, lin, eta)


def _add_modal_terms(qb: QuadraticBuilder, rows: NDArray[np.int64], phi: Array,
                     eta: int) -> None:
    """rows[i] += Σ_j phi_ij η_j (η_j at index eta + j); structural zeros left out."""
    for i in range(3):
        for j in range(phi.shape[1]):
            if phi[i, j] != 0.0:
                qb.add_linear(int(rows[i]), eta + j, float(phi[i, j]))
