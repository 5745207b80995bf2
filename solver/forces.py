"""Force elements: gravity, springs and dampers, rotational springs and dampers, applied loads.

Each declaration is passive data; its set evaluates all instances together. Conservative
elements give a potential, its gradient and Hessian and an exact discrete gradient between two
configurations (∇̄V·(q_f − q_i) = V(q_f) − V(q_i)), so that the energy-preserving scheme
conserves energy to roundoff. Non-conservative elements (dampers, applied loads) give a
generalized force f(q, v, t) and its Jacobians; the integrators book their work.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from solver import rotation_kernels as _rk
from solver.beams import Beam
from solver.bodies import Body, PointMass, PrescribedBody
from solver.element import EMPTY_F, Element, ElementSet
from solver.quadratic import VecExpr

Array = NDArray[np.float64]


def gonzalez_rows(grad_mid: Array, f_i: Array, f_f: Array, dq: Array) -> Array:
    """Gonzalez (1996) discrete gradients of J scalar functions at once: each row of
    ``grad_mid`` (J, k) corrected along its ``dq`` row so that ∇̄f·Δq = Δf."""
    d2 = np.einsum("ij,ij->i", dq, dq)
    ok = d2 > 1e-28
    corr = np.where(ok, (f_f - f_i - np.einsum("ij,ij->i", grad_mid, dq))
                    / np.where(ok, d2, 1.0), 0.0)
    return grad_mid + corr[:, None] * dq


def _outer_pattern(idx: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """(rows, cols) of the dense k × k blocks over each row of ``idx`` (J, k)."""
    k = idx.shape[1]
    return np.repeat(idx, k, axis=1).ravel(), np.tile(idx, (1, k)).ravel()


# ------------------------------------------------------------------------------- gravity
@dataclass(eq=False)
class Gravity(Element):
    """Uniform gravity field g (m/s²) acting on every free body and beam of the model."""

    g: ArrayLike = (0.0, 0.0, -9.81)
    name: str = "gravity"


class GravitySet(ElementSet):
    """Potential Σ −m g·x over the bodies with mass (linear: constant gradient)."""

    constant_gradient = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        g = np.sum([np.asarray(e.g, dtype=float) for e in elements], axis=0)
        idx, val = [], []
        for body in system.bodies:
            if isinstance(body, PrescribedBody) or body.mass == 0.0:
                continue
            o = system.offset[body]
            idx.extend(range(o, o + 3))
            val.extend(-body.mass * g)
        for beam in system.elements:
            if isinstance(beam, Beam):
                # V = −g·∫ρ r dV with r = x + ξ_α d_α: the mass matrix applied to a uniform
                # translation g gives ∫N_a ρA g on x_a and ∫N_a S_α g on d_α,a
                o = system.offset[beam]
                nb = 12 * len(beam.nodes)
                m = system.M[o : o + nb, o : o + nb]
                u = np.zeros((len(beam.nodes), 4, 3))
                u[:, 0] = g
                idx.extend(range(o, o + nb))
                val.extend(-(m @ u.ravel()))
        self.grad_idx = np.array(idx, dtype=np.int64)
        self._val = np.array(val)

    def potential(self, q):
        return float(self._val @ q[self.grad_idx])

    def gradient(self, q):
        return self._val

    def discrete_gradient(self, qi, qf):
        return self._val


Gravity.set_class = GravitySet


# ------------------------------------------------------------------------------- springs
def _matrix(expr: VecExpr, n: int) -> sp.csr_matrix:
    """The 3 × n map q ↦ (vector expression − its constant)."""
    rows, cols, vals = [], [], []
    for c, o in expr.terms:
        for k in range(3):
            rows.append(k)
            cols.append(o + k)
            vals.append(c)
    return sp.csr_matrix((vals, (rows, cols)), shape=(3, n))


def _psd(x: ArrayLike, what: str, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    a = a * np.eye(3) if a.ndim == 0 else (np.diag(a) if a.shape == (3,) else a)
    if (a.shape != (3, 3) or not np.all(np.isfinite(a))
            or np.linalg.eigvalsh(0.5 * (a + a.T)).min() < -1e-12):
        raise ValueError(f"spring {name!r}: {what} must be ≥ 0 (scalar, 3 values or a positive "
                         "semidefinite 3x3 matrix)")
    return a


@dataclass(eq=False)
class Spring(Element):
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

    def __post_init__(self) -> None:
        self.K = _psd(self.stiffness, "stiffness", self.name)
        self.C = _psd(self.damping, "damping", self.name)


class SpringSet(ElementSet):
    """All linear springs and dampers: Δ = B q + b (B sparse, 3J × n), V = ½ eᵀ K e with
    e = Δ − Δ0 and f = −Bᵀ C B v; K, C block diagonal. All matrices are built once."""

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        n = system.n
        blocks, consts = [], []
        for e in elements:
            p = np.asarray(e.point, dtype=float)
            pb = system.point(e.body_b, system.to_local_point(e.body_b, p))
            pa = (VecExpr([], p.copy()) if e.body_a is None
                  else system.point(e.body_a, system.to_local_point(e.body_a, p)))
            d = pb - pa
            blocks.append(_matrix(d, n))
            consts.append(d.const)
        b = sp.vstack(blocks).tocsr()
        q0 = system.q0_raw
        delta0 = b @ q0 + np.concatenate(consts)
        rest = np.concatenate([delta0[3 * i : 3 * i + 3] if e.rest is None
                               else np.asarray(e.rest, dtype=float)
                               for i, e in enumerate(elements)])
        c = np.concatenate(consts) - rest  # e = B q + c
        k = sp.block_diag([e.K for e in elements], format="csr")
        dmp = sp.block_diag([e.C for e in elements], format="csr")
        stiff = (b.T @ k @ b).tocsr()
        stiff.eliminate_zeros()
        damp = (b.T @ dmp @ b).tocsr()
        damp.eliminate_zeros()
        # potential: on the columns the stiff springs touch
        self.grad_idx = np.unique(stiff.nonzero()[0]).astype(np.int64)
        sub = stiff[self.grad_idx][:, self.grad_idx].tocoo()
        self._H = sub.tocsr()
        self._g0 = (b.T @ (k @ c))[self.grad_idx]
        self.stiff_rows, self.stiff_cols = self.grad_idx[sub.row], self.grad_idx[sub.col]
        self._hvals = sub.data
        self._B, self._c, self._K = b, c, k
        # dampers
        self.force_idx = np.unique(damp.nonzero()[0]).astype(np.int64)
        dsub = damp[self.force_idx][:, self.force_idx].tocoo()
        self._D = dsub.tocsr()
        self.fv_rows, self.fv_cols = self.force_idx[dsub.row], self.force_idx[dsub.col]
        self._dvals = -dsub.data
        self.nonconservative = len(self.force_idx) > 0

    def potential(self, q):
        e = self._B @ q + self._c
        return 0.5 * float(e @ (self._K @ e))

    def gradient(self, q):
        return self._H @ q[self.grad_idx] + self._g0

    def stiffness(self, q):
        return self._hvals

    def force(self, q, v, t):
        return -(self._D @ v[self.force_idx])

    def force_jacobians(self, q, v, t):
        return np.zeros(0), self._dvals


Spring.set_class = SpringSet


# ------------------------------------------------------------------ rotational springs
@dataclass(eq=False)
class RelativeRotation(Element):
    """Rotational spring and damper about the common axis of two bodies (e.g. over a revolute).

    Moment on ``body_b`` about ``axis`` = −k (φ − φ0) − c φ̇ (N·m), φ the relative rotation of
    b with respect to a about the axis (rad), measured as in Eq. (3). ``body_a`` None is ground.

    Optional **delayed feedback** (a settling device for periodically forced models): the
    extra moment −a [φ(t) − φ(t − τ)] − b [φ̇(t) − φ̇(t − τ)], with a = ``delayed_stiffness``
    (N·m/rad), b = ``delayed_damping`` (N·m·s/rad) and τ = ``delay`` (s). It vanishes on any
    motion of period τ, so a periodic response of period τ is left exactly as it is, while a
    transient of frequency ω (in the bodies' frame) sees the extra dynamic stiffness
    (a + iωb)(1 − e^{−iωτ}) (time-delayed feedback control, Pyragas 1992). With
    a = bω sin ωτ / (1 − cos ωτ) its stiffness part vanishes and its damping is 2b at ω. The
    past values come from the converged steps (linear interpolation in time); before one
    delay has been marched the feedback is off.
    """

    name: str
    body_a: Body | None
    body_b: Body
    axis: ArrayLike = (0.0, 0.0, 1.0)
    stiffness: float = 0.0
    damping: float = 0.0
    phi0: float = 0.0
    delay: float = 0.0
    delayed_stiffness: float = 0.0
    delayed_damping: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.stiffness) and np.isfinite(self.damping)
                and self.stiffness >= 0 and self.damping >= 0):
            raise ValueError(f"rotational spring {self.name!r}: stiffness and damping must be "
                             "finite and ≥ 0")
        if not (np.isfinite(self.delayed_stiffness) and np.isfinite(self.delayed_damping)
                and self.delayed_damping >= 0):
            raise ValueError(f"rotational spring {self.name!r}: delayed_stiffness must be "
                             "finite and delayed_damping finite and ≥ 0, got "
                             f"{self.delayed_stiffness!r}, {self.delayed_damping!r}")
        if self.feedback and not (np.isfinite(self.delay) and self.delay > 0):
            raise ValueError(f"rotational spring {self.name!r}: delay = {self.delay!r} s must "
                             "be > 0 with delayed feedback")
        for b in (self.body_a, self.body_b):
            if isinstance(b, PointMass):
                raise ValueError(f"rotational spring {self.name!r}: {b.name!r} has no rotation")

    @property
    def feedback(self) -> bool:
        """Whether the element carries delayed feedback."""
        return self.delayed_stiffness != 0.0 or self.delayed_damping != 0.0

    def group_key(self) -> Hashable:
        return (self.body_a is None, self.stiffness != 0.0, self.damping != 0.0,
                self.feedback)


class RelativeRotationSet(ElementSet):
    """Rotational springs and dampers, evaluated together: with e_i^a, e_i^b the joint triad
    carried by each body, c = e1ᵃ·e1ᵇ and s = −e1ᵃ·e2ᵇ are bilinear in the directors and
    φ = atan2(s, c) (unwrapped against the last converged step). φ's gradient and Hessian
    and the damper's tangent are one compiled loop each (:mod:`solver.rotation_kernels`,
    with the formulas)."""

    def __init__(self, elements, system) -> None:
        from solver.joints import _triad

        super().__init__(elements, system)
        e0 = elements[0]
        self.grounded = e0.body_a is None
        nj = len(elements)
        tri = [_triad(e.axis, None) for e in elements]
        # local director coefficients: e1ᵃ = Σ_α ca_α d_α^a (or constant), e1ᵇ, e2ᵇ likewise
        self._cb1 = np.array([system.to_local_vector(e.body_b, t[:, 0])
                              for e, t in zip(elements, tri, strict=True)])
        self._cb2 = np.array([system.to_local_vector(e.body_b, t[:, 1])
                              for e, t in zip(elements, tri, strict=True)])
        # only the directors with a non-zero coefficient in some member enter (structural
        # pattern: a rotation about a body axis touches two of the three directors)
        self._ab = _active(self._cb1, self._cb2)
        ib = np.array([system.offset[e.body_b] + 3 + _director_cols(self._ab) for e in elements])
        if self.grounded:
            self._ea = np.array([t[:, 0] for t in tri])
            self.idx = ib
        else:
            self._ca1 = np.array([system.to_local_vector(e.body_a, t[:, 0])
                                  for e, t in zip(elements, tri, strict=True)])
            self._aa = _active(self._ca1)
            ia = np.array([system.offset[e.body_a] + 3 + _director_cols(self._aa)
                           for e in elements])
            self.idx = np.concatenate([ia, ib], axis=1)
        self.idx = self.idx.astype(np.int64)
        self._nb = ib.shape[1]
        # the kernels' arguments (solver.rotation_kernels): coefficients on the active
        # directors only, contiguous; unused ones empty
        self._kb1 = np.ascontiguousarray(self._cb1[:, self._ab])
        self._kb2 = np.ascontiguousarray(self._cb2[:, self._ab])
        if self.grounded:
            self._na, self._ka1, self._kea = 0, np.zeros((nj, 0)), self._ea
        else:
            self._na = 3 * len(self._aa)
            self._ka1 = np.ascontiguousarray(self._ca1[:, self._aa])
            self._kea = np.zeros((nj, 3))
        self.k = np.array([e.stiffness for e in elements])
        self.c = np.array([e.damping for e in elements])
        self.phi0 = np.array([e.phi0 for e in elements])
        self._ref = np.zeros(nj)  # unwrapped angle at the last converged step
        flat = self.idx.ravel()
        pr, pc = _outer_pattern(self.idx)
        if e0.stiffness != 0.0:
            self.grad_idx = flat
            self.stiff_rows, self.stiff_cols = pr, pc
        self._fb = e0.feedback
        if e0.damping != 0.0 or self._fb:
            self.force_idx = flat
            self.fv_rows, self.fv_cols = pr, pc
            self.fq_rows, self.fq_cols = pr, pc
            self.nonconservative = True
        if self._fb:
            self.step_history = True
            self.a = np.array([e.delayed_stiffness for e in elements])
            self.b = np.array([e.delayed_damping for e in elements])
            self.tau = np.array([e.delay for e in elements])
            self._hist: list[tuple[float, Array, Array]] = []  # (t, φ, φ̇) of converged steps

    def accept(self, q, v, t):
        phi, g = self._phi_grad(q)
        self._ref = phi
        if self._fb:
            self._hist.append((float(t), phi, np.einsum("jk,jk->j", g, v[self.idx])))
            # keep what the longest delay can still reach
            while len(self._hist) > 2 and self._hist[1][0] <= t - self.tau.max():
                self._hist.pop(0)
            # arrays for the lookups of the next step's Newton iterations (built once here)
            self._ht = np.array([h[0] for h in self._hist])
            self._hphi = np.array([h[1] for h in self._hist])
            self._hrate = np.array([h[2] for h in self._hist])

    def _reached(self, t) -> NDArray[np.bool_]:
        """Members whose delay reaches a recorded step from t (the others have no feedback
        yet)."""
        if not self._hist:
            return np.zeros(len(self.tau), dtype=bool)
        return t - self.tau >= self._ht[0] - 1e-9 * self.tau

    def _feedback(self, t, phi, rate):
        """The delayed-feedback moment −a[φ(t) − φ(t − τ)] − b[φ̇(t) − φ̇(t − τ)] (J,), with
        the past values interpolated linearly in the converged steps' history."""
        on = self._reached(t)
        moment = np.zeros(len(self.tau))
        for j in np.nonzero(on)[0]:
            td = t - self.tau[j]
            moment[j] = -(self.a[j] * (phi[j] - np.interp(td, self._ht, self._hphi[:, j]))
                          + self.b[j] * (rate[j] - np.interp(td, self._ht, self._hrate[:, j])))
        return moment

    def _angle(self, c, s):
        """φ = atan2(s, c), unwrapped against the last converged step."""
        phi = np.arctan2(s, c)
        return self._ref + np.angle(np.exp(1j * (phi - self._ref)))

    def _args(self, q):
        return (q, self.idx, self._na, self._kb1, self._kb2, self._ka1, self._kea,
                self.grounded)

    def _phi_grad(self, q):
        """φ (J,) unwrapped against the last converged step, and ∇φ at ``idx`` (J, k)
        (:func:`solver.rotation_kernels.phi_grad`)."""
        c, s, g = _rk.phi_grad(*self._args(q))
        return self._angle(c, s), g

    def _phi_hessian(self, q):
        """φ, ∇φ (J, k) and the Hessian ∇²φ (J, k, k) over ``idx``
        (:func:`solver.rotation_kernels.phi_hessian`)."""
        c, s, g, hess = _rk.phi_hessian(*self._args(q))
        return self._angle(c, s), g, hess

    def _energies(self, q):
        phi, g = self._phi_grad(q)
        return 0.5 * self.k * (phi - self.phi0) ** 2, phi, g

    def potential(self, q):
        return float(self._energies(q)[0].sum())

    def gradient(self, q):
        _, phi, g = self._energies(q)
        return ((self.k * (phi - self.phi0))[:, None] * g).ravel()

    def discrete_gradient(self, qi, qf):
        gm = self.gradient(0.5 * (qi + qf)).reshape(self.idx.shape)
        vi, vf = self._energies(qi)[0], self._energies(qf)[0]
        return gonzalez_rows(gm, vi, vf, qf[self.idx] - qi[self.idx]).ravel()

    def stiffness(self, q):
        _, g = self._phi_grad(q)
        # Gauss–Newton part k ∇φ ∇φᵀ (exact at φ = φ0)
        return (self.k[:, None, None] * g[:, :, None] * g[:, None, :]).ravel()

    def force(self, q, v, t):
        phi, g = self._phi_grad(q)
        rate = np.einsum("jk,jk->j", g, v[self.idx])
        moment = -self.c * rate
        if self._fb:
            moment += self._feedback(t, phi, rate)
        return (moment[:, None] * g).ravel()

    def force_jacobians(self, q, v, t):
        # f = m ∇φ with m = −c φ̇ (+ feedback), φ̇ = ∇φ·v: ∂f/∂v = −(c + b) ∇φ∇φᵀ and
        # ∂f/∂q = ∇φ (∂m/∂q)ᵀ + m ∇²φ, ∂m/∂q = −(c + b) ∇²φ v − a ∇φ. (The moment's
        # rotation with the bodies matters in a rotating frame: leaving it out cost a
        # rotor's Newton its convergence.)
        phi, g, hess = self._phi_hessian(q)
        vi = v[self.idx]
        rate = np.einsum("jk,jk->j", g, vi)
        damp, stiff = self.c.copy(), np.zeros(len(self.c))
        moment = -self.c * rate
        if self._fb:
            on = self._reached(t)  # the feedback's own terms only where it acts
            damp += on * self.b
            stiff += on * self.a
            moment += self._feedback(t, phi, rate)
        return _rk.damper_jacobians(g, hess, vi, damp, stiff, moment)


def _separations(system, pairs) -> tuple[NDArray[np.int64], Array, Array]:
    """The separations Δ_j = p_b − p_a of point pairs, linear in the unknowns: for each pair
    (body_a or None for the ground, point_a, body_b, point_b), points global at t = 0, the
    unknowns y_j = q[idx_j] it reads (J, 3 nt: nt terms of 3 each) and Δ_j = P_j y_j + b_j
    (P: J × 3 × 3 nt, b: J × 3). Pairs with fewer terms are padded with zero coefficients on
    their first term's columns."""
    exprs = []
    for body_a, point_a, body_b, point_b in pairs:
        pa, pb = np.asarray(point_a, dtype=float), np.asarray(point_b, dtype=float)
        xb = system.point(body_b, system.to_local_point(body_b, pb))
        xa = (VecExpr([], pa.copy()) if body_a is None
              else system.point(body_a, system.to_local_point(body_a, pa)))
        exprs.append(xb - xa)
    nt = max(len(d.terms) for d in exprs)
    nj = len(exprs)
    coef = np.zeros((nj, nt))
    ycols = np.zeros((nj, nt), dtype=np.int64)
    for j, d in enumerate(exprs):
        for t, (c, o) in enumerate(d.terms):
            coef[j, t], ycols[j, t] = c, o
        ycols[j, len(d.terms):] = d.terms[0][1]  # padding: zero coefficient, same columns
    idx = (ycols[:, :, None] + np.arange(3)).reshape(nj, 3 * nt)
    p = np.einsum("jt,ik->jitk", coef, np.eye(3)).reshape(nj, 3, 3 * nt)
    return idx, p, np.array([d.const for d in exprs])


def _active(*coefs: Array) -> NDArray[np.int64]:
    """Directors α whose coefficient is non-zero in some member (columns of ``coefs``)."""
    return np.nonzero(np.any(np.abs(np.concatenate(coefs, axis=0)) > 0, axis=0))[0]


def _director_cols(alphas: NDArray[np.int64]) -> NDArray[np.int64]:
    """Coordinate offsets (from the first director) of directors ``alphas``."""
    return (3 * alphas[:, None] + np.arange(3)).ravel()


RelativeRotation.set_class = RelativeRotationSet


# ------------------------------------------------------------------------- applied loads
@dataclass(eq=False)
class AppliedLoad(Element):
    """Force F(t) (N) at a body point and moment M(t) (N·m), both global, given as functions.

    ``point`` is the global position of the application point at t = 0 (it moves with the body).
    """

    name: str
    body: Body
    force: Callable[[float], ArrayLike] | None = None
    moment: Callable[[float], ArrayLike] | None = None
    point: ArrayLike | None = None

    def __post_init__(self) -> None:
        if self.moment is not None and isinstance(self.body, PointMass):
            raise ValueError(f"load {self.name!r}: a point mass cannot take a moment")

    def group_key(self) -> Hashable:
        return not isinstance(self.body, PointMass)  # bodies and beam nodes: directors


class AppliedLoadSet(ElementSet):
    """Applied loads on bodies of one kind (rigid or point masses): the user functions are
    called once each, the virtual work F·δ(x + Σ p_α d_α) + moment terms is vectorized."""

    nonconservative = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        self.rigid = not isinstance(elements[0].body, PointMass)
        width = 12 if self.rigid else 3
        self.idx = np.array([system.offset[e.body] + np.arange(width) for e in elements])
        self.local = np.array([
            system.to_local_point(e.body, e.body.position if e.point is None
                                  else np.asarray(e.point, dtype=float))
            for e in elements])
        self.force_idx = self.idx.ravel()
        self._zero = np.zeros(3)
        # moments as director forces ½ M × d_α: ∂f_α/∂d_α = ½ skew(M) (3 × 3 per director)
        self._moment = [k for k, e in enumerate(elements) if e.moment is not None and self.rigid]
        if self._moment:
            d = self.idx[self._moment][:, 3:].reshape(-1, 3, 3)  # load, director, component
            self.fq_rows = np.repeat(d, 3, axis=2).ravel()
            self.fq_cols = np.tile(d, (1, 1, 3)).ravel()

    def force(self, q, v, t):
        nj, width = self.idx.shape
        f = np.array([self._zero if e.force is None else np.asarray(e.force(t), dtype=float)
                      for e in self.elements])
        out = np.zeros((nj, width))
        out[:, :3] = f
        if self.rigid:
            out[:, 3:] += (self.local[:, :, None] * f[:, None, :]).reshape(nj, 9)
            if any(e.moment is not None for e in self.elements):
                m = np.array([self._zero if e.moment is None
                              else np.asarray(e.moment(t), dtype=float) for e in self.elements])
                d = q[self.idx[:, 3:]].reshape(nj, 3, 3)
                # f_α = ½ M × d_α gives Σ d_α × f_α = M (moment as director forces)
                out[:, 3:] += 0.5 * np.cross(m[:, None, :], d).reshape(nj, 9)
        return out.ravel()

    def force_jacobians(self, q, v, t):
        if not self._moment:
            return EMPTY_F, EMPTY_F
        m = np.array([np.asarray(self.elements[k].moment(t), dtype=float) for k in self._moment])
        sk = 0.5 * np.array([[[0, -c, b], [c, 0, -a], [-b, a, 0]] for a, b, c in m])
        return np.repeat(sk[:, None], 3, axis=1).ravel(), EMPTY_F


AppliedLoad.set_class = AppliedLoadSet


# ------------------------------------------------------- coupling in the axes of a body
def _matrix3(x: ArrayLike, what: str, name: str) -> Array:
    """A real 3 × 3 matrix from a scalar (× I), 3 values (diagonal) or a 3 × 3 array."""
    a = np.asarray(x, dtype=float)
    a = a * np.eye(3) if a.ndim == 0 else (np.diag(a) if a.shape == (3,) else a)
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        raise ValueError(f"frame coupling {name!r}: {what} must be finite (a scalar, 3 values "
                         "or a 3x3 matrix)")
    return a


@dataclass(eq=False)
class FrameCoupling(Element):
    """Linear coupling of two body points, measured in the axes of a third body.

    With Δ = p_b − p_a the separation of the two bodies' points (global, m) and
    w = (d1·Δ, d2·Δ, d3·Δ) its components in the axes d1, d2, d3 of ``frame`` (the global axes
    if ``frame`` is None), the coupling exerts on ``body_b`` the force Σ_i f_i d_i with

        f = −K (w − w0) − C ẇ     (components in the frame's axes, N),

    ẇ the rate of w (the velocity of b relative to a as seen in the rotating axes of the
    frame), and the opposite force on ``body_a`` at its point (``body_a`` None: ground). The
    generalized forces are those of the virtual work f·δw, so the frame body takes the moment
    Δ × (−F) of the pair and the three together conserve momentum and angular momentum; the
    power is f·ẇ.

    ``stiffness`` K (N/m) and ``damping`` C (N·s/m) are any real 3 × 3 matrices (a scalar
    stands for that multiple of the identity, 3 values for a diagonal):

    * symmetric K: a spring; skew K: a circulatory force (no potential);
    * symmetric C: a damper; skew C: a gyroscopic force, which does no work;
    * a damper c acting on the velocity relative to axes that turn at the rate Ω about the
      frame's d3, −c (ẇ − Ω e3 × w), is C = c I with the skew stiffness K = −c Ω [e3×].

    ``point`` is the global point at t = 0 where the coupling attaches to both bodies (it moves
    with each of them); ``rest`` is w0 (m, frame axes), by default the initial w. The whole
    force is non-conservative (its work is booked by the integrators), also its symmetric
    stiffness: with a turning frame, ½ (w − w0)ᵀ K (w − w0) is quartic in the unknowns.
    """

    name: str
    body_a: Body | None
    body_b: Body
    frame: Body | None = None
    point: ArrayLike = (0.0, 0.0, 0.0)
    stiffness: ArrayLike = 0.0
    damping: ArrayLike = 0.0
    rest: ArrayLike | None = None

    def __post_init__(self) -> None:
        self.K = _matrix3(self.stiffness, "stiffness", self.name)
        self.C = _matrix3(self.damping, "damping", self.name)
        if isinstance(self.frame, PointMass):
            raise ValueError(f"frame coupling {self.name!r}: frame {self.frame.name!r} is a "
                             "point mass and has no axes")
        if self.rest is not None:
            r = np.asarray(self.rest, dtype=float)
            if r.shape != (3,) or not np.all(np.isfinite(r)):
                raise ValueError(f"frame coupling {self.name!r}: rest must be 3 finite numbers "
                                 "(m, frame axes)")

    def group_key(self) -> Hashable:
        return self.frame is None


class FrameCouplingSet(ElementSet):
    """All frame couplings with (or all without) a frame body, vectorized.

    Per element the unknowns it reads are u = (y, e): y the coordinates of the point terms of
    Δ = P y + b (P = [c_1 I, c_2 I, …]), e the frame's directors of the active components (the
    components i whose row or column of K or C is non-zero in some member). Then
    w_i = e_i·Δ is bilinear, W = ∂w/∂u = [e_iᵀ P | Δᵀ in slot i] and ẇ = W v, and

        Q = Wᵀ f,   ∂Q/∂v = −Wᵀ C W,   ∂Q/∂u = H(f) − Wᵀ K W − Wᵀ C W(v),

    where W(v) = ∂ẇ/∂u = [ė_iᵀ P | Δ̇ᵀ in slot i] and H(f) = Σ_i f_i ∂²w_i/∂u² holds f_i Pᵀ
    in block (y, e_i) and f_i P in (e_i, y). Repeated unknowns in u (the frame is one of the
    two bodies) are summed by the assembly, which is the chain rule."""

    nonconservative = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        self.framed = elements[0].frame is not None
        # Δ = P y + b, P (J, 3, 3 nt)
        self._yidx, self._P, self._b = _separations(
            system, [(e.body_a, e.point, e.body_b, e.point) for e in elements])
        k = np.array([e.K for e in elements])
        c = np.array([e.C for e in elements])
        if self.framed:
            used = np.any((k != 0) | (c != 0), axis=(0, 1)) | np.any((k != 0) | (c != 0),
                                                                     axis=(0, 2))
            self._comps = np.nonzero(used)[0] if used.any() else np.array([0])
            ecols = np.array([[system.offset[e.frame] + 3 + 3 * i + m for i in self._comps
                               for m in range(3)] for e in elements], dtype=np.int64)
            self.idx = np.concatenate([self._yidx, ecols], axis=1)
        else:
            self._comps = np.arange(3)
            self.idx = self._yidx
        cc = self._comps
        self._K = k[:, cc][:, :, cc]
        self._C = c[:, cc][:, :, cc]
        self._ny = self._yidx.shape[1]
        q0 = system.q0_raw
        w0 = self._w(q0)[0]
        self._w0 = np.array([w0[j] if e.rest is None else np.asarray(e.rest, float)[cc]
                             for j, e in enumerate(elements)])
        self.force_idx = self.idx.ravel()
        self.fq_rows, self.fq_cols = _outer_pattern(self.idx)
        self.fv_rows, self.fv_cols = self.fq_rows, self.fq_cols

    # -- kinematics ---------------------------------------------------------------------------
    def _dirs(self, q: Array) -> Array:
        """Frame directors of the active components (J, nc, 3)."""
        nc = len(self._comps)
        if self.framed:
            return q[self.idx[:, self._ny:]].reshape(-1, nc, 3)
        return np.broadcast_to(np.eye(3)[self._comps], (len(self._b), nc, 3))

    def _w(self, q: Array) -> tuple[Array, Array, Array]:
        """w (J, nc), Δ (J, 3), directors (J, nc, 3)."""
        delta = np.einsum("jik,jk->ji", self._P, q[self._yidx]) + self._b
        e = self._dirs(q)
        return np.einsum("jci,ji->jc", e, delta), delta, e

    def _wmat(self, e: Array, delta: Array) -> Array:
        """∂w/∂u (J, nc, ku) for directors e (J, nc, 3) and separation Δ (J, 3); with the
        rates (ė, Δ̇) in their place it is ∂ẇ/∂u."""
        nj, nc = e.shape[:2]
        wy = np.einsum("jci,jik->jck", e, self._P)
        if not self.framed:
            return wy
        we = np.einsum("cd,ji->jcdi", np.eye(nc), delta).reshape(nj, nc, 3 * nc)
        return np.concatenate([wy, we], axis=2)

    def _state(self, q: Array, v: Array):
        w, delta, e = self._w(q)
        wm = self._wmat(e, delta)
        wdot = np.einsum("jck,jk->jc", wm, v[self.idx])
        f = (-np.einsum("jcd,jd->jc", self._K, w - self._w0)
             - np.einsum("jcd,jd->jc", self._C, wdot))
        return f, wm, e, delta

    def local_force(self, q: Array, v: Array) -> Array:
        """f (J, nc): the force on body b in the frame's axes (active components)."""
        return self._state(q, v)[0]

    # -- generalized forces -------------------------------------------------------------------
    def force(self, q, v, t):
        f, wm, *_ = self._state(q, v)
        return np.einsum("jck,jc->jk", wm, f).ravel()

    def force_jacobians(self, q, v, t):
        f, wm, e, _ = self._state(q, v)
        jv = -np.einsum("jck,jcd,jdl->jkl", wm, self._C, wm)
        jq = -np.einsum("jck,jcd,jdl->jkl", wm, self._K, wm)
        if self.framed:
            vu = v[self.idx]
            ddelta = np.einsum("jik,jk->ji", self._P, vu[:, : self._ny])
            de = vu[:, self._ny:].reshape(e.shape)
            wv = self._wmat(de, ddelta)
            jq -= np.einsum("jck,jcd,jdl->jkl", wm, self._C, wv)
            # H(f): f_c Pᵀ in block (y, e_c), its transpose in (e_c, y)
            ny, nc = self._ny, e.shape[1]
            hy = np.einsum("jc,jik->jkci", f, self._P).reshape(len(f), ny, 3 * nc)
            jq[:, :ny, ny:] += hy
            jq[:, ny:, :ny] += hy.transpose(0, 2, 1)
        return jq.ravel(), jv.ravel()


FrameCoupling.set_class = FrameCouplingSet


# -------------------------------------------------------------------- axial springs (links)
@dataclass(eq=False)
class AxialSpring(Element):
    """A massless two-force member (a link, a rod with a spring and a damper in it) between two
    body points.

    With Δ = p_b − p_a the separation of the points, ℓ = |Δ| its length and n = Δ/ℓ its
    direction, the link carries the tension

        T = k (ℓ − ℓ0) + c ℓ̇     (N, positive when it pulls the points together),

    and applies −T n to ``body_b`` at its point and +T n to ``body_a`` at its point (the force
    always along the current line of the link: it follows the points as they move). The
    spring's part derives from the potential V = ½ k (ℓ − ℓ0)², the damper's is
    non-conservative (its work −c ℓ̇² is booked by the integrators).

    Parameters
    ----------
    name
        Unique name.
    body_a, body_b
        The bodies (rigid bodies, point masses, prescribed bodies or beam nodes); ``body_a``
        None is ground.
    point_a, point_b
        Global positions of the two attachment points at t = 0 (m); each moves with its body.
    stiffness
        Axial stiffness k (N/m), ≥ 0.
    damping
        Axial damping c (N·s/m), ≥ 0.
    rest_length
        Unstretched length ℓ0 (m), > 0; by default the initial distance of the points.
    """

    name: str
    body_a: Body | None
    point_a: ArrayLike
    body_b: Body
    point_b: ArrayLike
    stiffness: float = 0.0
    damping: float = 0.0
    rest_length: float | None = None

    def __post_init__(self) -> None:
        self.point_a = np.asarray(self.point_a, dtype=float)
        self.point_b = np.asarray(self.point_b, dtype=float)
        if self.point_a.shape != (3,) or self.point_b.shape != (3,):
            raise ValueError(f"axial spring {self.name!r}: point_a and point_b must be 3 "
                             "numbers (m)")
        if not (np.isfinite(self.stiffness) and np.isfinite(self.damping)
                and self.stiffness >= 0 and self.damping >= 0):
            raise ValueError(f"axial spring {self.name!r}: stiffness = {self.stiffness!r} N/m "
                             f"and damping = {self.damping!r} N s/m must be finite and ≥ 0")
        length = (float(np.linalg.norm(self.point_b - self.point_a))
                  if self.rest_length is None else float(self.rest_length))
        if not (np.isfinite(length) and length > 0):
            raise ValueError(f"axial spring {self.name!r}: the rest length {length!r} m must "
                             "be > 0 (distinct points, or a positive rest_length)")
        if np.linalg.norm(self.point_b - self.point_a) == 0.0:
            raise ValueError(f"axial spring {self.name!r}: its points coincide (no direction)")
        self.length0 = length

    def group_key(self) -> Hashable:
        return (self.stiffness != 0.0, self.damping != 0.0)


class AxialSpringSet(ElementSet):
    """All axial springs, vectorized.

    Per member the separation is affine in the coordinates y it reads, Δ = P y + b
    (P = [c_1 I, c_2 I, …], the points' coefficients on positions and directors). With
    ℓ = |Δ|, n = Δ/ℓ and the projector N = I − n nᵀ:

        ∇V = k (ℓ − ℓ0) Pᵀ n,
        ∇²V = Pᵀ [k n nᵀ + k (ℓ − ℓ0)/ℓ N] P      (material part k n nᵀ, geometric part the
                                                  tension's turning with the link),
        f = −c ℓ̇ Pᵀ n,  ℓ̇ = nᵀ P v,
        ∂f/∂v = −c Pᵀ n nᵀ P,  ∂f/∂y = −c Pᵀ [ℓ̇ N/ℓ + n Δ̇ᵀ N/ℓ] P.

    The discrete gradient is the midpoint gradient with Gonzalez's correction along Δq (the
    potential is not quadratic in q), exact: ∇̄V·(q_f − q_i) = V_f − V_i."""

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        self.idx, self._P, self._b = _separations(
            system, [(e.body_a, e.point_a, e.body_b, e.point_b) for e in elements])
        self.k = np.array([e.stiffness for e in elements], dtype=float)
        self.c = np.array([e.damping for e in elements], dtype=float)
        self.l0 = np.array([e.length0 for e in elements])
        flat = self.idx.ravel()
        pr, pc = _outer_pattern(self.idx)
        if np.any(self.k):
            self.grad_idx = flat
            self.stiff_rows, self.stiff_cols = pr, pc
        if np.any(self.c):
            self.force_idx = flat
            self.fq_rows, self.fq_cols = pr, pc
            self.fv_rows, self.fv_cols = pr, pc
            self.nonconservative = True

    # -- kinematics ---------------------------------------------------------------------------
    def separation(self, q: Array) -> Array:
        """Δ = p_b − p_a of each member (J, 3), m."""
        return np.einsum("jik,jk->ji", self._P, q[self.idx]) + self._b

    def _geometry(self, q: Array) -> tuple[Array, Array, Array]:
        """Δ (J, 3), ℓ (J,), n (J, 3)."""
        delta = self.separation(q)
        length = np.linalg.norm(delta, axis=1)
        return delta, length, delta / length[:, None]

    def rate(self, q: Array, v: Array) -> Array:
        """ℓ̇ of each member (J,), m/s."""
        _, _, n = self._geometry(q)
        return np.einsum("ji,jik,jk->j", n, self._P, v[self.idx])

    def tension(self, q: Array, v: Array) -> Array:
        """The axial force T = k (ℓ − ℓ0) + c ℓ̇ of each member (J,), N, positive in
        tension."""
        _, length, n = self._geometry(q)
        rate = np.einsum("ji,jik,jk->j", n, self._P, v[self.idx])
        return self.k * (length - self.l0) + self.c * rate

    def direction(self, q: Array) -> Array:
        """The unit vector n from point a to point b of each member (J, 3)."""
        return self._geometry(q)[2]

    # -- potential ------------------------------------------------------------------------------
    def _energies(self, q: Array) -> Array:
        _, length, _ = self._geometry(q)
        return 0.5 * self.k * (length - self.l0) ** 2

    def potential(self, q):
        if not len(self.grad_idx):
            return 0.0
        return float(self._energies(q).sum())

    def _gradient_rows(self, q: Array) -> Array:
        _, length, n = self._geometry(q)
        return np.einsum("jik,ji->jk", self._P, (self.k * (length - self.l0))[:, None] * n)

    def gradient(self, q):
        if not len(self.grad_idx):
            return EMPTY_F
        return self._gradient_rows(q).ravel()

    def discrete_gradient(self, qi, qf):
        if not len(self.grad_idx):
            return EMPTY_F
        gm = self._gradient_rows(0.5 * (qi + qf))
        return gonzalez_rows(gm, self._energies(qi), self._energies(qf),
                             qf[self.idx] - qi[self.idx]).ravel()

    def _hessians(self, q: Array, geometric: bool) -> Array:
        _, length, n = self._geometry(q)
        nn = n[:, :, None] * n[:, None, :]
        mid = self.k[:, None, None] * nn
        if geometric:
            proj = np.eye(3) - nn
            mid = mid + (self.k * (length - self.l0) / length)[:, None, None] * proj
        return np.einsum("jik,jil,jlm->jkm", self._P, mid, self._P)

    def stiffness(self, q):
        if not len(self.grad_idx):
            return EMPTY_F
        return self._hessians(q, geometric=True).ravel()

    def material_stiffness(self, q):
        if not len(self.grad_idx):
            return EMPTY_F
        return self._hessians(q, geometric=False).ravel()

    # -- damper ---------------------------------------------------------------------------------
    def force(self, q, v, t):
        _, _, n = self._geometry(q)
        rate = np.einsum("ji,jik,jk->j", n, self._P, v[self.idx])
        return np.einsum("jik,ji->jk", self._P, (-self.c * rate)[:, None] * n).ravel()

    def force_jacobians(self, q, v, t):
        _, length, n = self._geometry(q)
        ddelta = np.einsum("jik,jk->ji", self._P, v[self.idx])
        rate = np.einsum("ji,ji->j", n, ddelta)
        proj = np.eye(3) - n[:, :, None] * n[:, None, :]
        # ∂(ℓ̇ n)/∂Δ = ℓ̇ N/ℓ + n (N Δ̇)ᵀ/ℓ
        mid_q = (rate[:, None, None] * proj
                 + n[:, :, None] * np.einsum("jab,jb->ja", proj, ddelta)[:, None, :]
                 ) / length[:, None, None]
        jq = -self.c[:, None, None] * np.einsum("jik,jil,jlm->jkm", self._P, mid_q, self._P)
        nn = n[:, :, None] * n[:, None, :]
        jv = -self.c[:, None, None] * np.einsum("jik,jil,jlm->jkm", self._P, nn, self._P)
        return jq.ravel(), jv.ravel()


AxialSpring.set_class = AxialSpringSet
