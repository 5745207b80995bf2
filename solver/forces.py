"""Force elements: gravity, springs and dampers, applied loads.

Conservative elements give a potential, its gradient and Hessian and an exact discrete gradient
between two configurations (∇̄V·(q_f − q_i) = V(q_f) − V(q_i)), so that the energy-preserving
scheme conserves energy to roundoff. Non-conservative elements (dampers, applied loads) give a
generalized force f(q, v, t) and its Jacobians; the integrators book their work.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.bodies import Body, PointMass, PrescribedBody
from solver.quadratic import VecExpr

Array = NDArray[np.float64]
EMPTY_I = np.zeros(0, dtype=np.int64)
EMPTY_F = np.zeros(0)


def gonzalez(grad_mid: Array, f_i: float, f_f: float, dq: Array) -> Array:
    """Gonzalez (1996) discrete gradient: ∇f(q_m) corrected along Δq so that ∇̄f·Δq = Δf."""
    d2 = float(dq @ dq)
    if d2 < 1e-28:
        return grad_mid
    return grad_mid + (f_f - f_i - grad_mid @ dq) * dq / d2


class ForceElement:
    """Interface; every method has a do-nothing default."""

    has_potential = False
    has_force = False
    hess_rows = EMPTY_I
    hess_cols = EMPTY_I
    jac_rows = EMPTY_I
    jac_cols = EMPTY_I

    def setup(self, system) -> None: ...
    def accept(self, q: Array) -> None:
        """Called after every converged step (e.g. to unwrap angles)."""
    def potential(self, q: Array) -> float:
        return 0.0
    def gradient(self, q: Array) -> tuple[NDArray[np.int64], Array]:
        return EMPTY_I, EMPTY_F
    def discrete_gradient(self, qi: Array, qf: Array) -> tuple[NDArray[np.int64], Array]:
        return self.gradient(0.5 * (qi + qf))
    def hessian(self, q: Array) -> Array:
        return EMPTY_F
    def generalized_force(self, q: Array, v: Array, t: float) -> tuple[NDArray[np.int64], Array]:
        """Non-conservative generalized force (indices, values) at (q, v, t)."""
        return EMPTY_I, EMPTY_F
    def force_jacobians(self, q: Array, v: Array, t: float) -> tuple[Array, Array]:
        """(∂f/∂q, ∂f/∂v) values at the (jac_rows, jac_cols) pattern."""
        return EMPTY_F, EMPTY_F


def _matrix(b: VecExpr) -> tuple[NDArray[np.int64], NDArray[np.int64], Array]:
    """Sparse rows/cols/vals of the 3×n map q ↦ (vector expression − const)."""
    rows, cols, vals = [], [], []
    for c, o in b.terms:
        for k in range(3):
            rows.append(k)
            cols.append(o + k)
            vals.append(c)
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64), np.array(vals)


class _Linear3:
    """Δ(q) = B q + b0 as a small dense block over the touched coordinates."""

    def __init__(self, expr: VecExpr) -> None:
        r, c, v = _matrix(expr)
        self.idx, inv = np.unique(c, return_inverse=True)
        self.B = np.zeros((3, len(self.idx)))
        np.add.at(self.B, (r, inv), v)
        self.b0 = expr.const.copy()

    def __call__(self, q: Array) -> Array:
        return self.B @ q[self.idx] + self.b0


@dataclass(eq=False)
class Gravity(ForceElement):
    """Uniform gravity field g (m/s²) acting on every free body."""

    g: ArrayLike = (0.0, 0.0, -9.81)
    has_potential = True

    def setup(self, system) -> None:
        g = np.asarray(self.g, dtype=float)
        idx, val = [], []
        for body in system.bodies:
            if isinstance(body, PrescribedBody) or body.mass == 0.0:
                continue
            o = system.offset[body]
            idx.extend(range(o, o + 3))
            val.extend(-body.mass * g)
        self._idx = np.array(idx, dtype=np.int64)
        self._val = np.array(val)

    def potential(self, q):
        return float(self._val @ q[self._idx])

    def gradient(self, q):
        return self._idx, self._val

    def discrete_gradient(self, qi, qf):
        return self._idx, self._val


@dataclass(eq=False)
class Spring(ForceElement):
    """Linear spring and damper between two body points, or a point and the ground.

    Force on ``body_b`` = −K (Δ − Δ0) − C Δ̇, with Δ = p_b − p_a and Δ0 its initial value (or
    ``rest``). ``stiffness`` K (N/m) and ``damping`` C (N·s/m) are scalars or 3×3 global-frame
    matrices (e.g. diag(kx, ky, 0) for an in-plane fuselage restraint). ``body_a`` None is ground.
    """

    name: str
    body_a: Body | None
    body_b: Body
    point: ArrayLike = (0.0, 0.0, 0.0)
    stiffness: ArrayLike = 0.0
    damping: ArrayLike = 0.0
    rest: ArrayLike | None = None

    def setup(self, system) -> None:
        def mat(x, what):
            a = np.asarray(x, dtype=float)
            a = a * np.eye(3) if a.ndim == 0 else (np.diag(a) if a.shape == (3,) else a)
            if a.shape != (3, 3) or np.linalg.eigvalsh(0.5 * (a + a.T)).min() < -1e-12:
                raise ValueError(f"spring {self.name!r}: {what} must be ≥ 0 (scalar, 3 values "
                                 "or a positive semidefinite 3x3 matrix)")
            return a
        self.K = mat(self.stiffness, "stiffness")
        self.C = mat(self.damping, "damping")
        self.has_potential = bool(np.any(self.K))
        self.has_force = bool(np.any(self.C))
        p = np.asarray(self.point, dtype=float)
        pb = system.point(self.body_b, system.to_local_point(self.body_b, p))
        pa = (VecExpr([], p.copy()) if self.body_a is None
              else system.point(self.body_a, system.to_local_point(self.body_a, p)))
        self.delta = _Linear3(pb - pa)
        d0 = self.delta(system.q0_raw)
        self.d0 = d0 if self.rest is None else np.asarray(self.rest, dtype=float)
        i = self.delta.idx
        self.hess_rows = np.repeat(i, len(i))
        self.hess_cols = np.tile(i, len(i))
        self.jac_rows, self.jac_cols = self.hess_rows, self.hess_cols
        self._H = self.delta.B.T @ self.K @ self.delta.B
        self._D = self.delta.B.T @ self.C @ self.delta.B

    def potential(self, q):
        e = self.delta(q) - self.d0
        return 0.5 * float(e @ self.K @ e)

    def gradient(self, q):
        return self.delta.idx, self.delta.B.T @ (self.K @ (self.delta(q) - self.d0))

    # quadratic potential: the midpoint gradient is the exact discrete gradient
    def hessian(self, q):
        return self._H.ravel()

    def generalized_force(self, q, v, t):
        rate = self.delta.B @ v[self.delta.idx]
        return self.delta.idx, -self.delta.B.T @ (self.C @ rate)

    def force_jacobians(self, q, v, t):
        return np.zeros(self._D.size), -self._D.ravel()

    def tension(self, q, v) -> Array:
        """Force (N) the element applies to body_b, global frame."""
        return -self.K @ (self.delta(q) - self.d0) - self.C @ (self.delta.B @ v[self.delta.idx])


@dataclass(eq=False)
class RelativeRotation(ForceElement):
    """Rotational spring and damper about the common axis of two bodies (e.g. over a revolute).

    Moment on ``body_b`` about ``axis`` = −k (φ − φ0) − c φ̇ (N·m), φ the relative rotation of
    b with respect to a about the axis (rad), measured as in Eq. (3). ``body_a`` None is ground.
    """

    name: str
    body_a: Body | None
    body_b: Body
    axis: ArrayLike = (0.0, 0.0, 1.0)
    stiffness: float = 0.0
    damping: float = 0.0
    phi0: float = 0.0

    def setup(self, system) -> None:
        from solver.joints import _triad

        if self.stiffness < 0 or self.damping < 0:
            raise ValueError(f"rotational spring {self.name!r}: stiffness and damping must be ≥ 0")
        tri = _triad(self.axis, None)

        def vec(body, i):
            if body is None:
                return VecExpr([], tri[:, i].copy())
            if isinstance(body, PointMass):
                raise ValueError(f"rotational spring {self.name!r}: {body.name!r} has no rotation")
            return system.vector(body, system.to_local_vector(body, tri[:, i]))

        self.has_potential = self.stiffness != 0.0
        self.has_force = self.damping != 0.0
        e1a, e1b, e2b = vec(self.body_a, 0), vec(self.body_b, 0), vec(self.body_b, 1)
        self.e3 = [vec(self.body_a, 2), vec(self.body_b, 2)]
        self.cs = _Linear2(e1a, e1b, e2b)
        i = self.cs.idx
        self.hess_rows = np.repeat(i, len(i))
        self.hess_cols = np.tile(i, len(i))
        self.jac_rows, self.jac_cols = self.hess_rows, self.hess_cols
        self._ref = 0.0  # unwrapped angle at the last converged step

    def accept(self, q):
        self._ref = self._phi_grad(q)[0]

    def _phi_grad(self, q):
        """φ (rad, unwrapped against the last converged step) and its gradient."""
        c, s, gc, gs = self.cs(q)
        r2 = c * c + s * s
        phi = np.arctan2(s, c)
        phi = self._ref + np.angle(np.exp(1j * (phi - self._ref)))
        return phi, (c * gs - s * gc) / r2

    def potential(self, q):
        phi, _ = self._phi_grad(q)
        return 0.5 * self.stiffness * (phi - self.phi0) ** 2

    def gradient(self, q):
        phi, g = self._phi_grad(q)
        return self.cs.idx, self.stiffness * (phi - self.phi0) * g

    def discrete_gradient(self, qi, qf):
        qm = 0.5 * (qi + qf)
        _, gm = self.gradient(qm)
        i = self.cs.idx
        return i, gonzalez(gm, self.potential(qi), self.potential(qf), qf[i] - qi[i])

    def hessian(self, q):
        _, g = self._phi_grad(q)
        return self.stiffness * np.outer(g, g).ravel()  # Gauss–Newton part (exact at φ = φ0)

    def generalized_force(self, q, v, t):
        _, g = self._phi_grad(q)
        rate = g @ v[self.cs.idx]
        return self.cs.idx, -self.damping * rate * g

    def force_jacobians(self, q, v, t):
        _, g = self._phi_grad(q)
        return np.zeros(g.size**2), -self.damping * np.outer(g, g).ravel()


class _Linear2:
    """c = e1a·e1b and s = −e1a·e2b with their gradients over the touched coordinates."""

    def __init__(self, e1a: VecExpr, e1b: VecExpr, e2b: VecExpr) -> None:
        cols = sorted({o + k for e in (e1a, e1b, e2b) for _, o in e.terms for k in range(3)})
        self.idx = np.array(cols, dtype=np.int64)
        pos = {c: i for i, c in enumerate(cols)}
        self.maps = []
        for e in (e1a, e1b, e2b):
            b = np.zeros((3, len(cols)))
            for c, o in e.terms:
                for k in range(3):
                    b[k, pos[o + k]] += c
            self.maps.append((b, e.const))

    def __call__(self, q):
        ql = q[self.idx]
        (ba, ca), (bb, cb), (b2, c2) = self.maps
        ea, eb, e2 = ba @ ql + ca, bb @ ql + cb, b2 @ ql + c2
        c = ea @ eb
        s = -ea @ e2
        gc = eb @ ba + ea @ bb
        gs = -(e2 @ ba + ea @ b2)
        return c, s, gc, gs


@dataclass(eq=False)
class AppliedLoad(ForceElement):
    """Force F(t) (N) at a body point and moment M(t) (N·m), both global, given as functions.

    ``point`` is the global position of the application point at t = 0 (it moves with the body).
    """

    name: str
    body: Body
    force: Callable[[float], ArrayLike] | None = None
    moment: Callable[[float], ArrayLike] | None = None
    point: ArrayLike | None = None

    has_force = True

    def setup(self, system) -> None:
        b = self.body
        o = system.offset[b]
        p = b.position if self.point is None else np.asarray(self.point, dtype=float)
        self._local = system.to_local_point(b, p)
        self._o = o
        self._rigid = not isinstance(b, PointMass)
        if self.moment is not None and not self._rigid:
            raise ValueError(f"load {self.name!r}: a point mass cannot take a moment")
        n = 12 if self._rigid else 3
        self._idx = np.arange(o, o + n)

    def generalized_force(self, q, v, t):
        out = np.zeros(len(self._idx))
        if self.force is not None:
            f = np.asarray(self.force(t), dtype=float)
            out[:3] = f
            if self._rigid:  # virtual work F·δ(x + Σ p_α d_α)
                for a in range(3):
                    out[3 + 3 * a : 6 + 3 * a] += self._local[a] * f
        if self.moment is not None:
            m = np.asarray(self.moment(t), dtype=float)
            d = q[self._o + 3 : self._o + 12].reshape(3, 3)
            # f_α = ½ M × d_α gives Σ d_α × f_α = M (moment as director forces)
            out[3:] += 0.5 * np.cross(m, d).ravel()
        return self._idx, out
