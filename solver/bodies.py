"""Body declarations: rigid bodies, point masses, ground and bodies with prescribed motion.

Declarations are passive data; :mod:`solver.system` turns them into unknowns. A rigid body is
carried by its centre of mass x and three orthonormal directors d1, d2, d3 (the columns of its
rotation matrix): 12 coordinates, a constant mass matrix and six orthonormality constraints
(Betsch & Steinmann 2002). Every joint and inertia term is then at most quadratic in the
unknowns, which is what makes the midpoint rule exactly energy preserving.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

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


@dataclass(eq=False)
class RigidBody:
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

    @property
    def director_inertia(self) -> NDArray[np.float64]:
        """E = ½ tr(J) I − J: kinetic energy ½ Σ E_αβ ḋα·ḋβ of the rotation (kg·m²)."""
        j = self.inertia_tensor
        return 0.5 * np.trace(j) * np.eye(3) - j


@dataclass(eq=False)
class PointMass:
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


@dataclass(eq=False)
class PrescribedBody:
    """A body whose motion is a given function of time (a driver), e.g. a hub spinning at Ω.

    ``motion(t)`` returns (x, R, v, ω, a, α): position (m), rotation matrix, velocity (m/s),
    angular velocity (rad/s), acceleration (m/s²) and angular acceleration (rad/s²), all global.
    The ground is a prescribed body at rest. Mass and inertia only enter the reported energy.
    """

    name: str
    motion: object
    mass: float = 0.0
    inertia: ArrayLike = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        j = np.asarray(self.inertia, dtype=float)
        self.inertia_tensor = np.diag(j) if j.shape == (3,) else j

    @property
    def director_inertia(self) -> NDArray[np.float64]:
        j = self.inertia_tensor
        return 0.5 * np.trace(j) * np.eye(3) - j


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
class Scalar:
    """An extra scalar unknown owned by a joint (curve parameter η, arc length s); massless."""

    name: str
    initial: float = 0.0
    rate: float = 0.0
    units: str = "1"
    long_name: str = ""
    meta: dict = field(default_factory=dict)
