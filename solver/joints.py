"""Joint declarations: holonomic constraints enforced with Lagrange multipliers.

Every lower pair is written as dot products of director combinations, so that all rows are at
most quadratic in the unknowns (see :mod:`solver.quadratic`). A joint is declared at the initial
configuration by a global point and a global triad (e1, e2, e3); at that instant the joint
triads of both bodies coincide (paper, Fig. 3). Reactions are reported as the force and the
moment (about the joint point) that the joint applies to the second body.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.bodies import Body, PointMass
from solver.element import Element
from solver.quadratic import QuadraticBuilder, QuadraticSet, VecExpr
from solver.timefunctions import TimeFunction, cos_of, sin_of


def _triad(axis: ArrayLike | None, frame: ArrayLike | None) -> NDArray[np.float64]:
    """Columns e1, e2, e3 with e3 along ``axis`` (or the given frame)."""
    if frame is not None:
        f = np.asarray(frame, dtype=float)
        if f.shape != (3, 3) or np.abs(f.T @ f - np.eye(3)).max() > 1e-9:
            raise ValueError("joint frame must be a rotation matrix (columns e1, e2, e3)")
        return f
    e3 = np.asarray((0.0, 0.0, 1.0) if axis is None else axis, dtype=float)
    nrm = np.linalg.norm(e3)
    if not np.isfinite(nrm) or nrm == 0:
        raise ValueError(f"joint axis must be a nonzero vector, got {axis!r}")
    e3 = e3 / nrm
    helper = np.eye(3)[np.argmin(np.abs(e3))]
    e1 = np.cross(helper, e3)
    e1 /= np.linalg.norm(e1)
    return np.column_stack([e1, np.cross(e3, e1), e3])


class Layout:
    """Protocol (implemented by :class:`solver.system.System`) giving vector expressions."""

    def point(self, body: Body, local: NDArray[np.float64]) -> VecExpr: ...
    def vector(self, body: Body, local: NDArray[np.float64]) -> VecExpr: ...
    def to_local_point(self, body: Body, p: NDArray[np.float64]) -> NDArray[np.float64]: ...
    def to_local_vector(self, body: Body, v: NDArray[np.float64]) -> NDArray[np.float64]: ...


@dataclass(eq=False)
class Joint(Element):
    """Base of the lower-pair joints between ``body_a`` (k) and ``body_b`` (ℓ).

    A joint adds its rows to the model's quadratic tensor in :meth:`quadratic_rows`
    (returning the rows and a dict of data kept for outputs)."""

    name: str
    body_a: Body
    body_b: Body
    point: ArrayLike = (0.0, 0.0, 0.0)
    axis: ArrayLike | None = None
    frame: ArrayLike | None = None

    set_class = QuadraticSet

    def __post_init__(self) -> None:
        self.point = np.asarray(self.point, dtype=float)
        self.triad = _triad(self.axis, self.frame)

    # -- helpers used by subclasses -------------------------------------------------------
    def _frames(self, lay: Layout) -> tuple[list[VecExpr], list[VecExpr]]:
        ja = [lay.vector(self.body_a, lay.to_local_vector(self.body_a, self.triad[:, i]))
              for i in range(3)]
        jb = [lay.vector(self.body_b, lay.to_local_vector(self.body_b, self.triad[:, i]))
              for i in range(3)]
        return ja, jb

    def _points(self, lay: Layout) -> tuple[VecExpr, VecExpr]:
        pa = lay.point(self.body_a, lay.to_local_point(self.body_a, self.point))
        pb = lay.point(self.body_b, lay.to_local_point(self.body_b, self.point))
        return pa, pb

    def _need_orientation(self) -> None:
        for b in (self.body_a, self.body_b):
            if isinstance(b, PointMass):
                raise ValueError(f"joint {self.name!r}: {b.name!r} is a point mass and has no "
                                 "orientation; use a spherical joint or a rigid body")

    def point_on_b(self, lay: Layout) -> VecExpr:
        return self._points(lay)[1]

    def quadratic_rows(self, qb: QuadraticBuilder,
                       lay: Layout) -> tuple[NDArray[np.int64], dict]:
        raise NotImplementedError


def _rotation_rows(qb: QuadraticBuilder, ja, jb, which: tuple[int, ...]) -> NDArray[np.int64]:
    """Eq. (22): rows j_a[α]·j_b[β] − j_a[β]·j_b[α] locking the rotation about each axis."""
    pairs = {0: (2, 1), 1: (0, 2), 2: (1, 0)}
    rows = qb.new_rows(len(which))
    for r, axis in zip(rows, which, strict=True):
        a, b = pairs[axis]
        qb.add_dot(int(r), ja[a], jb[b])
        qb.add_dot(int(r), ja[b], jb[a], coef=-1.0)
    return rows


@dataclass(eq=False)
class Spherical(Joint):
    """Coincident points, free relative rotation (3 rows)."""

    def quadratic_rows(self, qb, lay):
        pa, pb = self._points(lay)
        rows = qb.new_rows(3)
        qb.add_vector(rows, pa - pb)
        return rows, {}


@dataclass(eq=False)
class Revolute(Joint):
    """Rotation about the common axis e3 only (Eqs. 2–3); ``driven`` prescribes φ(t) (rad).

    The relative rotation φ is reported from Eq. (3): φ = atan2(−e1ᵃ·e2ᵇ, e1ᵃ·e1ᵇ), unwrapped.
    """

    driven: TimeFunction | None = None

    def quadratic_rows(self, qb, lay):
        self._need_orientation()
        pa, pb = self._points(lay)
        ja, jb = self._frames(lay)
        rows = qb.new_rows(5 + (self.driven is not None))
        qb.add_vector(rows[:3], pa - pb)
        qb.add_dot(int(rows[3]), ja[2], jb[0])  # Eq. (2)
        qb.add_dot(int(rows[4]), ja[2], jb[1])
        if self.driven is not None:  # Eq. (3) with φ prescribed
            qb.add_dot(int(rows[5]), ja[0], jb[0], f=sin_of(self.driven))
            qb.add_dot(int(rows[5]), ja[0], jb[1], f=cos_of(self.driven))
        return rows, {"frames": (ja, jb)}

    @staticmethod
    def angle_from(data: dict, q: NDArray[np.float64]) -> float:
        """Relative rotation φ (rad, wrapped to (−π, π]) at q, from the joint's build data."""
        ja, jb = data["frames"]
        e1a = ja[0].value(q)
        return float(np.arctan2(-e1a @ jb[1].value(q), e1a @ jb[0].value(q)))


@dataclass(eq=False)
class Rigid(Joint):
    """Clamp: no relative motion (6 rows)."""

    def quadratic_rows(self, qb, lay):
        self._need_orientation()
        pa, pb = self._points(lay)
        ja, jb = self._frames(lay)
        rows = qb.new_rows(3)
        qb.add_vector(rows, pa - pb)
        return np.concatenate([rows, _rotation_rows(qb, ja, jb, (0, 1, 2))]), {}


@dataclass(eq=False)
class Orientation(Joint):
    """Locks the relative rotation about the chosen joint axes (0, 1, 2 = e1, e2, e3)."""

    axes: tuple[int, ...] = (0, 1, 2)

    def quadratic_rows(self, qb, lay):
        self._need_orientation()
        ja, jb = self._frames(lay)
        return _rotation_rows(qb, ja, jb, tuple(self.axes)), {}


@dataclass(eq=False)
class Prismatic(Joint):
    """Relative translation along e3 only, no relative rotation (5 rows); ``driven``
    prescribes the translation s(t) (m) of body b's joint point along body a's e3, counted
    from the initial configuration (one more row, (p_b − p_a)·e3ᵃ − s(t) = 0)."""

    driven: TimeFunction | None = None

    def quadratic_rows(self, qb, lay):
        self._need_orientation()
        pa, pb = self._points(lay)
        ja, jb = self._frames(lay)
        rows = qb.new_rows(2 + (self.driven is not None))
        r = pb - pa
        qb.add_dot(int(rows[0]), r, ja[0])
        qb.add_dot(int(rows[1]), r, ja[1])
        if self.driven is not None:
            qb.add_dot(int(rows[2]), r, ja[2])
            qb.add_constant(int(rows[2]), -1.0, self.driven)
        return np.concatenate([rows, _rotation_rows(qb, ja, jb, (0, 1, 2))]), {}


@dataclass(eq=False)
class Planar(Joint):
    """Body b moves in the plane ⟂ e3 of body a and rotates about e3 only (3 rows)."""

    def quadratic_rows(self, qb, lay):
        self._need_orientation()
        pa, pb = self._points(lay)
        ja, jb = self._frames(lay)
        rows = qb.new_rows(3)
        qb.add_dot(int(rows[0]), pb - pa, ja[2])
        qb.add_dot(int(rows[1]), ja[2], jb[0])
        qb.add_dot(int(rows[2]), ja[2], jb[1])
        return rows, {}
