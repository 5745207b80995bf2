"""Body declarations: rigid bodies, point masses, ground and bodies with prescribed motion.

Declarations are passive data; :mod:`solver.system` turns them into unknowns. A rigid body is
carried by its centre of mass x and three orthonormal directors d1, d2, d3 (the columns of its
rotation matrix): 12 coordinates, a constant mass matrix and six orthonormality constraints
(Betsch & Steinmann 2002). Every joint and inertia term is then at most quadratic in the
unknowns, which is what makes the midpoint rule exactly energy preserving.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.element import Element
from solver.quadratic import QuadraticBuilder, QuadraticSet, VecExpr
from solver.state import ALGEBRAIC, SECOND, StateBlock
from solver.timefunctions import TimeFunction


def _vec(v: ArrayLike, name: str, owner: str) -> NDArray[np.float64]:
    a = np.asarray(v, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{owner}: {name} must be 3 finite numbers, got {v!r}")
    return a


def _rot(r: ArrayLike | None, owner: str) -> NDArray[np.float64]:
    if r is None:
        return np.eye(3)
    a = np.asarray(r, dtype=float)
    if a.shape != (3, 3) or np.abs(a.T @ a - np.eye(3)).max() > 1e-9 or np.linalg.det(a) < 0:
        raise ValueError(f"{owner}: orientation must be a proper rotation matrix (3x3, RᵀR = I)")
    return a


def _director_mass(mass: float, e: NDArray[np.float64] | None) -> NDArray[np.float64]:
    """Mass matrix of (x, d1, d2, d3): m I for x, E_αβ I for the directors."""
    if e is None:
        return mass * np.eye(3)
    out = np.zeros((12, 12))
    out[:3, :3] = mass * np.eye(3)
    out[3:, 3:] = np.kron(e, np.eye(3))
    return out


# which of a body's 12 coordinates (x, d1, d2, d3) form its position 3-vector
BODY_POSITIONS = np.repeat([True, False, False, False], 3)


def _director_state(body, x, r, v, w, e) -> StateBlock:
    """The 12 coordinates (x, d1, d2, d3) of a body with rotation r (d_α = column α)."""
    return StateBlock(body, SECOND, 12, initial=np.concatenate([x, np.asarray(r).T.ravel()]),
                      rate=np.concatenate([v, np.cross(w, np.asarray(r).T).ravel()]),
                      mass=_director_mass(body.mass, e), units="m",
                      long_name=f"position and directors of {body.name}",
                      positions=BODY_POSITIONS)


@dataclass(eq=False)
class RigidBody(Element):
    """A rigid body.

    Parameters
    ----------
    name
        Unique name, used in results.
    mass
        Mass (kg), ≥ 0.
    inertia
        Inertia tensor about the centre of mass in the body frame (kg·m²): 3 principal values
        or a symmetric 3×3 matrix. Zero inertia is allowed for bodies whose rotation is fully
        fixed by joints (e.g. the paper's fictitious pins).
    position
        Initial centre of mass (m), global frame.
    orientation
        Initial rotation matrix from the body frame to the global frame.
    velocity, angular_velocity
        Initial linear (m/s) and angular velocity (rad/s), global frame. Projected onto the
        constraints before the first step.
    """

    name: str
    mass: float
    inertia: ArrayLike = (0.0, 0.0, 0.0)
    position: ArrayLike = (0.0, 0.0, 0.0)
    orientation: ArrayLike | None = None
    velocity: ArrayLike = (0.0, 0.0, 0.0)
    angular_velocity: ArrayLike = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        owner = f"body {self.name!r}"
        if not (np.isfinite(self.mass) and self.mass >= 0):
            raise ValueError(f"{owner}: mass = {self.mass!r} kg must be ≥ 0")
        j = np.asarray(self.inertia, dtype=float)
        j = np.diag(j) if j.shape == (3,) else j
        if j.shape != (3, 3) or np.abs(j - j.T).max() > 1e-12 * max(1.0, np.abs(j).max()):
            raise ValueError(f"{owner}: inertia must be 3 values or a symmetric 3x3 matrix")
        ev = np.linalg.eigvalsh(j)
        tol = 1e-12 * max(1.0, ev.max())
        if ev.min() < -tol or ev[0] + ev[1] < ev[2] - tol:
            raise ValueError(
                f"{owner}: inertia {np.round(ev, 6).tolist()} is not physical "
                "(principal values must be ≥ 0 and satisfy the triangle inequality)"
            )
        self.inertia_tensor = j
        self.position = _vec(self.position, "position", owner)
        self.orientation = _rot(self.orientation, owner)
        self.velocity = _vec(self.velocity, "velocity", owner)
        self.angular_velocity = _vec(self.angular_velocity, "angular_velocity", owner)

    set_class = QuadraticSet
    quadratic_priority = 0  # orthonormality rows come before the joints' rows

    @property
    def director_inertia(self) -> NDArray[np.float64]:
        """E = ½ tr(J) I − J: kinetic energy ½ Σ E_αβ ḋα·ḋβ of the rotation (kg·m²)."""
        j = self.inertia_tensor
        return 0.5 * np.trace(j) * np.eye(3) - j

    def states(self) -> list[StateBlock]:
        return [_director_state(self, self.position, self.orientation, self.velocity,
                                self.angular_velocity, self.director_inertia)]

    def quadratic_rows(self, qb: QuadraticBuilder, lay) -> tuple[NDArray[np.int64], dict]:
        """Six orthonormality rows d_α·d_β − δ_αβ = 0."""
        return orthonormality_rows(qb, lay.offset[self]), {}


def orthonormality_rows(qb: QuadraticBuilder, o: int) -> NDArray[np.int64]:
    """The six rows d_α·d_β − δ_αβ = 0 of the directors at coordinates o+3 … o+11 (a rigid
    body or a beam node: position first, then d1, d2, d3)."""
    rows = qb.new_rows(6)
    d = [VecExpr([(1.0, o + 3 + 3 * a)]) for a in range(3)]
    for r, (a, c) in zip(rows, [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0)], strict=True):
        qb.add_dot(int(r), d[a], d[c])
        if a == c:
            qb.add_constant(int(r), -1.0)
    return rows


@dataclass(eq=False)
class PointMass(Element):
    """A particle (kg, m, m/s): three coordinates, no orientation."""

    name: str
    mass: float
    position: ArrayLike = (0.0, 0.0, 0.0)
    velocity: ArrayLike = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        owner = f"point mass {self.name!r}"
        if not (np.isfinite(self.mass) and self.mass >= 0):
            raise ValueError(f"{owner}: mass = {self.mass!r} kg must be ≥ 0")
        self.position = _vec(self.position, "position", owner)
        self.velocity = _vec(self.velocity, "velocity", owner)

    def states(self) -> list[StateBlock]:
        return [StateBlock(self, SECOND, 3, initial=self.position, rate=self.velocity,
                           mass=_director_mass(self.mass, None), units="m",
                           long_name=f"position of {self.name}", positions=np.ones(3, bool))]


@dataclass(eq=False)
class PrescribedBody(Element):
    """A body whose motion is a given function of time (a driver), e.g. a hub spinning at Ω.

    ``motion(t)`` returns (x, R, v, ω, a, α): position (m), rotation matrix, velocity (m/s),
    angular velocity (rad/s), acceleration (m/s²) and angular acceleration (rad/s²), all global.
    The ground is a prescribed body at rest. Mass and inertia only enter the reported energy.
    """

    name: str
    motion: object
    mass: float = 0.0
    inertia: ArrayLike = (0.0, 0.0, 0.0)

    set_class = QuadraticSet
    quadratic_priority = 0

    def __post_init__(self) -> None:
        j = np.asarray(self.inertia, dtype=float)
        self.inertia_tensor = np.diag(j) if j.shape == (3,) else j

    @property
    def director_inertia(self) -> NDArray[np.float64]:
        j = self.inertia_tensor
        return 0.5 * np.trace(j) * np.eye(3) - j

    def pose(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Position (m) and rotation matrix at time t."""
        x, r, *_ = self.motion(t)
        return np.asarray(x, float), np.asarray(r, float)

    def moves(self) -> bool:
        """Whether the prescribed motion depends on time (a driver that can do work)."""
        x0, r0, v0, w0, *_ = self.motion(0.0)
        x1, r1, *_ = self.motion(1.2345)
        return bool(np.any(v0) or np.any(w0) or np.abs(np.subtract(x1, x0)).max() > 0
                    or np.abs(np.subtract(r1, r0)).max() > 0)

    def states(self) -> list[StateBlock]:
        x, r, v, w, *_ = (np.asarray(z, dtype=float) for z in self.motion(0.0))
        return [_director_state(self, x, r, v, w, self.director_inertia)]

    def quadratic_rows(self, qb: QuadraticBuilder, lay) -> tuple[NDArray[np.int64], dict]:
        """Twelve rows q_k − c_k(t) = 0 (constants for a body at rest)."""
        o = lay.offset[self]
        rows = qb.new_rows(12)
        moving = self.moves()
        comps = _prescribed_components(self) if moving else None
        q0 = lay.q0_raw
        for k in range(12):
            qb.add_linear(int(rows[k]), o + k, 1.0)
            if moving:
                qb.add_constant(int(rows[k]), -1.0, comps[k])
            elif q0[o + k] != 0.0:
                qb.add_constant(int(rows[k]), -float(q0[o + k]))
        return rows, {}


def _prescribed_components(body: PrescribedBody) -> list[TimeFunction]:
    """Coordinates (x, d1, d2, d3) of a prescribed body as time functions with derivatives."""

    @lru_cache(maxsize=4)
    def state(t: float):
        x, r, v, w, a, al = (np.asarray(z, dtype=float) for z in body.motion(t))
        d = r.T  # rows are directors
        dd = np.cross(w, d)
        ddd = np.cross(al, d) + np.cross(w, dd)
        return (np.concatenate([x, d.ravel()]), np.concatenate([v, dd.ravel()]),
                np.concatenate([a, ddd.ravel()]))

    def comp(k: int) -> TimeFunction:
        return TimeFunction(lambda t: state(t)[0][k], lambda t: state(t)[1][k],
                            lambda t: state(t)[2][k])

    return [comp(k) for k in range(12)]


def ground(name: str = "ground") -> PrescribedBody:
    """The inertial frame: a prescribed body at rest at the origin."""
    zero = np.zeros(3)
    eye = np.eye(3)
    return PrescribedBody(name, lambda t: (zero, eye, zero, zero, zero, zero))


def spinning(name: str, omega: float | TimeFunction, axis: ArrayLike = (0.0, 0.0, 1.0),
             center: ArrayLike = (0.0, 0.0, 0.0), mass: float = 0.0,
             inertia: ArrayLike = (0.0, 0.0, 0.0)) -> PrescribedBody:
    """A body spinning about a fixed ``axis`` through ``center``.

    ``omega`` is a constant speed (rad/s) or a :class:`TimeFunction` giving the angle ψ(t) (rad).
    """
    from solver.rotations import rotation_about

    n = np.asarray(axis, dtype=float)
    n = n / np.linalg.norm(n)
    c = np.asarray(center, dtype=float)
    angle = omega if isinstance(omega, TimeFunction) else None
    w = float(omega) if angle is None else 0.0

    def motion(t: float):
        psi, rate, acc = (w * t, w, 0.0) if angle is None else angle(t)
        r = rotation_about(n, psi)
        return c, r, np.zeros(3), rate * n, np.zeros(3), acc * n

    return PrescribedBody(name, motion, mass=mass, inertia=inertia)


Body = RigidBody | PointMass | PrescribedBody


@dataclass(eq=False)
class Scalar(Element):
    """An extra scalar unknown owned by a joint (curve parameter η, arc length s); massless.

    The joint or relation that owns it lists it in its own :meth:`states`."""

    name: str
    initial: float = 0.0
    rate: float = 0.0
    units: str = "1"
    long_name: str = ""

    def states(self) -> list[StateBlock]:
        return [StateBlock(self, ALGEBRAIC, 1, initial=self.initial, rate=self.rate,
                           units=self.units, long_name=self.long_name)]
