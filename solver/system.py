"""Assembly of a :class:`~solver.model.Model` into unknowns, a mass matrix and constraint rows.

Unknown numbering: rigid and prescribed bodies carry 12 coordinates (x, d1, d2, d3), point masses
3, joint scalars 1. Holonomic rows are ordered: quadratic rows (orthonormality, prescribed
motion, lower pairs), then the non-quadratic groups; nonholonomic rows follow. The sparse
pattern of the Newton (KKT) matrix is built once; each iteration only scatters values into it
with one ``np.bincount``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from solver.bodies import PointMass, PrescribedBody, RigidBody
from solver.quadratic import QuadraticBuilder, VecExpr
from solver.timefunctions import TimeFunction

Array = NDArray[np.float64]


class System:
    """The assembled model: what the integrators need, vectorized."""

    def __init__(self, model) -> None:
        self.model = model
        self.bodies = list(model.bodies)
        names = [b.name for b in self.bodies]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"body names must be unique; repeated: {', '.join(sorted(dup))}")
        self.offset: dict = {}
        n = 0
        for b in self.bodies:
            self.offset[b] = n
            n += 3 if isinstance(b, PointMass) else 12
        self.scalar_index: dict = {}
        self._block_end = n  # body coordinates come first, in 3-blocks
        for s in model.scalars:
            self.scalar_index[s] = n
            n += 1
        self.n = n
        self.q0_raw = self._initial_q()
        self.M = self._mass_matrix()

        qb = QuadraticBuilder()
        self.body_rows: dict = {}
        for b in self.bodies:
            o = self.offset[b]
            if isinstance(b, RigidBody):
                rows = qb.new_rows(6)
                d = [VecExpr([(1.0, o + 3 + 3 * a)]) for a in range(3)]
                for r, (a, c) in zip(rows, [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0)],
                                     strict=True):
                    qb.add_dot(int(r), d[a], d[c])
                    if a == c:
                        qb.add_constant(int(r), -1.0)
                self.body_rows[b] = rows
            elif isinstance(b, PrescribedBody):
                rows = qb.new_rows(12)
                moving = self._moves(b)
                comps = _prescribed_components(b) if moving else None
                for k in range(12):
                    qb.add_linear(int(rows[k]), o + k, 1.0)
                    if moving:
                        qb.add_constant(int(rows[k]), -1.0, comps[k])
                    elif self.q0_raw[o + k] != 0.0:
                        qb.add_constant(int(rows[k]), -float(self.q0_raw[o + k]))
                self.body_rows[b] = rows
        self.joint_rows = {}
        for j in model.joints:
            self.joint_rows[j] = j.build(qb, self)
        self.quad = qb.build()
        self.mq = self.quad.m

        from solver.curve_joints import batch_curve_joints

        self.groups = batch_curve_joints(list(model.constraints))
        self.group_rows = []
        m = self.mq
        for g in self.groups:
            g.setup(self)
            self.group_rows.append(np.arange(m, m + g.m))
            m += g.m
        self.mh = m
        from solver.curve_joints import batch_nonholonomic

        self.nh_groups = batch_nonholonomic(list(model.nonholonomic))
        self.nh_rows = []
        for g in self.nh_groups:
            g.setup(self)
            self.nh_rows.append(np.arange(m, m + g.m))
            m += g.m
        self.mn = m - self.mh
        self.m = m

        self.forces = list(model.forces)
        for f in self.forces:
            f.setup(self)
        self.potential_elements = [f for f in self.forces if f.has_potential]
        self.force_elements = [f for f in self.forces if f.has_force]
        self.time_dependent = self.quad.time_dependent
        self.has_nonconservative = bool(self.force_elements) or self.time_dependent or any(
            self._moves(b) for b in self.bodies if isinstance(b, PrescribedBody))
        self._build_pattern()

    # ------------------------------------------------------------------ layout helpers
    def _moves(self, b: PrescribedBody) -> bool:
        x0, r0, v0, w0, *_ = b.motion(0.0)
        x1, r1, *_ = b.motion(1.2345)
        return bool(np.any(v0) or np.any(w0) or np.abs(x1 - x0).max() > 0
                    or np.abs(r1 - r0).max() > 0)

    def _pose0(self, b):
        if isinstance(b, PrescribedBody):
            x, r, *_ = b.motion(0.0)
            return np.asarray(x, float), np.asarray(r, float)
        if isinstance(b, PointMass):
            return b.position, np.eye(3)
        return b.position, b.orientation

    def to_local_point(self, body, p) -> Array:
        x, r = self._pose0(body)
        p = np.asarray(p, dtype=float)
        if isinstance(body, PointMass):
            if np.abs(p - x).max() > 1e-9 * max(1.0, np.abs(x).max()):
                raise ValueError(f"a joint or load on point mass {body.name!r} must act at its "
                                 f"position {x.tolist()}, not at {p.tolist()}")
            return np.zeros(3)
        return r.T @ (p - x)

    def to_local_vector(self, body, v) -> Array:
        return self._pose0(body)[1].T @ np.asarray(v, dtype=float)

    def point(self, body, local) -> VecExpr:
        o = self.offset[body]
        terms = [(1.0, o)]
        if not isinstance(body, PointMass):
            terms += [(float(c), o + 3 + 3 * a) for a, c in enumerate(local) if c != 0.0]
        return VecExpr(terms)

    def vector(self, body, local) -> VecExpr:
        if isinstance(body, PointMass):
            raise ValueError(f"point mass {body.name!r} has no body-fixed vectors")
        o = self.offset[body]
        return VecExpr([(float(c), o + 3 + 3 * a) for a, c in enumerate(local) if c != 0.0])

    def _initial_q(self) -> Array:
        q = np.zeros(self.n)
        for b in self.bodies:
            o = self.offset[b]
            x, r = self._pose0(b)
            q[o : o + 3] = x
            if not isinstance(b, PointMass):
                q[o + 3 : o + 12] = r.T.ravel()  # d_α = column α of R
        for s, i in self.scalar_index.items():
            q[i] = s.initial
        return q

    def initial_velocity_guess(self) -> Array:
        v = np.zeros(self.n)
        for b in self.bodies:
            o = self.offset[b]
            if isinstance(b, PrescribedBody):
                _x, r, vel, w, *_ = b.motion(0.0)
                v[o : o + 3] = vel
                v[o + 3 : o + 12] = np.cross(w, np.asarray(r).T).ravel()
            elif isinstance(b, PointMass):
                v[o : o + 3] = b.velocity
            else:
                v[o : o + 3] = b.velocity
                v[o + 3 : o + 12] = np.cross(b.angular_velocity, b.orientation.T).ravel()
        for s, i in self.scalar_index.items():
            v[i] = s.rate
        return v

    def _mass_matrix(self) -> sp.csr_matrix:
        rows, cols, vals = [], [], []
        for b in self.bodies:
            o = self.offset[b]
            for k in range(3):
                rows.append(o + k)
                cols.append(o + k)
                vals.append(b.mass)
            if not isinstance(b, PointMass):
                e = b.director_inertia
                for a in range(3):
                    for c in range(3):
                        if e[a, c] != 0.0:
                            for k in range(3):
                                rows.append(o + 3 + 3 * a + k)
                                cols.append(o + 3 + 3 * c + k)
                                vals.append(e[a, c])
        return sp.csr_matrix((vals, (rows, cols)), shape=(self.n, self.n))

    # ------------------------------------------------------------------ sparse pattern
    def _build_pattern(self) -> None:
        n = self.n
        Mc = self.M.tocoo()
        blocks = [(Mc.row, Mc.col)]
        kr = [f.hess_rows for f in self.potential_elements]
        kc = [f.hess_cols for f in self.potential_elements]
        blocks.append((_cat(kr), _cat(kc)))
        dr = [f.jac_rows for f in self.force_elements]
        dc = [f.jac_cols for f in self.force_elements]
        blocks.append((_cat(dr), _cat(dc)))
        blocks.append((self.quad.hess_rows, self.quad.hess_cols))
        blocks.append((_cat([g.hess_rows for g in self.groups]),
                       _cat([g.hess_cols for g in self.groups])))
        # holonomic Jacobian: quadratic rows then groups
        g_rows = [self.quad.jac_rows] + [
            np.repeat(rows, g.cols.shape[1]) for g, rows in zip(self.groups, self.group_rows,
                                                                 strict=True)]
        g_cols = [self.quad.jac_cols] + [g.cols.ravel() for g in self.groups]
        self.G_rows, self.G_cols = _cat(g_rows), _cat(g_cols)
        blocks.append((self.G_cols, n + self.G_rows))  # Gᵀ in the dynamic rows
        blocks.append((n + self.G_rows, self.G_cols))  # G in the constraint rows
        a_rows = [np.repeat(rows, g.cols.shape[1]) for g, rows in zip(self.nh_groups, self.nh_rows,
                                                                     strict=True)]
        a_cols = [g.cols.ravel() for g in self.nh_groups]
        self.A_rows, self.A_cols = _cat(a_rows), _cat(a_cols)
        blocks.append((self.A_cols, n + self.A_rows))
        blocks.append((n + self.A_rows, self.A_cols))
        self._block_sizes = [len(r) for r, _ in blocks]
        rows = _cat([r for r, _ in blocks])
        cols = _cat([c for _, c in blocks])
        N = n + self.m
        key = cols * N + rows  # column-major order for CSC
        uniq, inv = np.unique(key, return_inverse=True)
        self._scatter = inv
        self._nnz = len(uniq)
        self._indices = (uniq % N).astype(np.int32)
        ucols = uniq // N
        self._indptr = np.searchsorted(ucols, np.arange(N + 1)).astype(np.int32)
        self.N = N
        self.M_vals = Mc.data

    def kkt(self, cM: float, K: Array, D: Array, H: Array, HG: Array,
            GT: Array, G: Array, AT: Array, A: Array) -> sp.csc_matrix:
        """Assemble the Newton matrix from block values in pattern order."""
        data = np.concatenate([cM * self.M_vals, K, D, H, HG, GT, G, AT, A])
        vals = np.bincount(self._scatter, data, minlength=self._nnz).astype(float)
        return sp.csc_matrix((vals, self._indices, self._indptr), shape=(self.N, self.N))

    # ------------------------------------------------------------------ physics kernels
    def kinetic(self, v: Array) -> float:
        return 0.5 * float(v @ (self.M @ v))

    def potential(self, q: Array) -> float:
        return float(sum(f.potential(q) for f in self.potential_elements))

    def gradient(self, q: Array) -> Array:
        g = np.zeros(self.n)
        for f in self.potential_elements:
            i, val = f.gradient(q)
            np.add.at(g, i, val)
        return g

    def discrete_gradient(self, qi: Array, qf: Array) -> Array:
        g = np.zeros(self.n)
        for f in self.potential_elements:
            i, val = f.discrete_gradient(qi, qf)
            np.add.at(g, i, val)
        return g

    def stiffness_values(self, q: Array) -> Array:
        return _cat([f.hessian(q) for f in self.potential_elements], float)

    def applied(self, q: Array, v: Array, t: float) -> Array:
        f = np.zeros(self.n)
        for e in self.force_elements:
            i, val = e.generalized_force(q, v, t)
            np.add.at(f, i, val)
        return f

    def applied_jacobians(self, q: Array, v: Array, t: float) -> tuple[Array, Array]:
        jq, jv = [], []
        for e in self.force_elements:
            a, b = e.force_jacobians(q, v, t)
            jq.append(a)
            jv.append(b)
        return _cat(jq, float), _cat(jv, float)

    def constraint(self, q: Array, t: float) -> Array:
        """All holonomic rows C(q, t) (length mh)."""
        out = [self.quad.value(q, t)]
        for g in self.groups:
            out.append(g.evaluate(q)[0])
        return np.concatenate(out)

    def jacobian_values(self, q: Array, t: float) -> Array:
        out = [self.quad.jacobian_values(q, t)]
        for g in self.groups:
            out.append(g.evaluate(q)[1].ravel())
        return np.concatenate(out)

    def constraint_and_jacobian(self, q: Array, t: float) -> tuple[Array, Array]:
        c = [self.quad.value(q, t)]
        j = [self.quad.jacobian_values(q, t)]
        for g in self.groups:
            cv, gv = g.evaluate(q)
            c.append(cv)
            j.append(gv.ravel())
        return np.concatenate(c), np.concatenate(j)

    def discrete_jacobian_values(self, qi: Array, qf: Array, ti: float, tf: float) -> Array:
        """Rows Ḡ with Ḡ·(q_f − q_i) = C(q_f) − C(q_i) for scleronomic rows (midpoint rule for
        the quadratic rows, Gonzalez's correction for the others)."""
        qm = 0.5 * (qi + qf)
        out = [self.quad.jacobian_values(qm, 0.5 * (ti + tf))]
        for g in self.groups:
            if hasattr(g, "discrete_jacobian"):
                out.append(g.discrete_jacobian(qi, qf).ravel())
                continue
            ci, _ = g.evaluate(qi)
            cf, _ = g.evaluate(qf)
            _, gm = g.evaluate(qm)
            dq = qf[g.cols] - qi[g.cols]
            d2 = np.einsum("ij,ij->i", dq, dq)
            corr = (cf - ci - np.einsum("ij,ij->i", gm, dq)) / np.where(d2 > 1e-28, d2, 1.0)
            gm = gm + np.where(d2 > 1e-28, corr, 0.0)[:, None] * dq
            out.append(gm.ravel())
        return np.concatenate(out)

    def hessian_values(self, q: Array, t: float, lam: Array) -> tuple[Array, Array]:
        hq = self.quad.hessian_values(lam[: self.mq], t)
        hg = [g.hessian(q, lam[r]) for g, r in zip(self.groups, self.group_rows, strict=True)]
        return hq, _cat(hg, float)

    def nonholonomic_values(self, q: Array) -> Array:
        return _cat([g.matrix(q).ravel() for g in self.nh_groups], float)

    def nonholonomic_derivative(self, q: Array, dq: Array) -> Array:
        """Values of ∂(A(q)·dq)/∂q in the A pattern."""
        return _cat([g.derivative(q, dq).ravel() for g in self.nh_groups], float)

    def nonholonomic_residual(self, q: Array, dq: Array) -> Array:
        out = []
        for g in self.nh_groups:
            out.append(np.einsum("ij,ij->i", g.matrix(q), dq[g.cols]))
        return _cat(out, float)

    def gmul_T(self, vals: Array, lam: Array) -> Array:
        """Gᵀλ for Jacobian values in pattern order."""
        return np.bincount(self.G_cols, vals * lam[self.G_rows], minlength=self.n).astype(float)

    def gmul(self, vals: Array, v: Array) -> Array:
        return np.bincount(self.G_rows, vals * v[self.G_cols], minlength=self.mh).astype(float)

    def amul_T(self, vals: Array, nu: Array) -> Array:
        return np.bincount(self.A_cols, vals * nu[self.A_rows - self.mh],
                           minlength=self.n).astype(float)

    def amul(self, vals: Array, v: Array) -> Array:
        return np.bincount(self.A_rows - self.mh, vals * v[self.A_cols],
                           minlength=self.mn).astype(float)

    def constraint_rate(self, q: Array, t: float) -> Array:
        """∂C/∂t at fixed q (prescribed motions, driven joints)."""
        out = np.zeros(self.mh)
        if self.time_dependent:
            out[: self.mq] = self.quad.value(q, t, order=1)
        return out

    def constraint_curvature(self, q: Array, v: Array, t: float) -> Array:
        """C̈ − G q̈ along a motion through (q, v): the acceleration-level right-hand side."""
        out = np.zeros(self.mh)
        out[: self.mq] = self.quad.quadratic_rate_term(q, v, t)
        eps = 1e-6 / max(1e-12, float(np.abs(v).max()))
        for g, rows in zip(self.groups, self.group_rows, strict=True):
            _, gp = g.evaluate(q + eps * v)
            _, gm = g.evaluate(q - eps * v)
            out[rows] = np.einsum("ij,ij->i", (gp - gm) / (2 * eps), v[g.cols])
        return out

    def nonholonomic_curvature(self, q: Array, v: Array) -> Array:
        eps = 1e-6 / max(1e-12, float(np.abs(v).max()))
        out = []
        for g in self.nh_groups:
            da = (g.matrix(q + eps * v) - g.matrix(q - eps * v)) / (2 * eps)
            out.append(np.einsum("ij,ij->i", da, v[g.cols]))
        return _cat(out, float)

    # ------------------------------------------------------------------ outputs
    def angular_momentum(self, q: Array, v: Array) -> Array:
        """Total angular momentum about the global origin (kg·m²/s): Σ over the coordinate
        3-blocks of q_b × (M v)_b (x × m ẋ for positions, d_α × Σ_β E_αβ ḋ_β for directors)."""
        nb = self._block_end // 3
        qb = q[: self._block_end].reshape(nb, 3)
        pb = (self.M @ v)[: self._block_end].reshape(nb, 3)
        return np.cross(qb, pb).sum(axis=0)

    def directors(self, q: Array, body) -> Array:
        """Rotation matrix (columns d1, d2, d3) of a body at q."""
        o = self.offset[body]
        return q[o + 3 : o + 12].reshape(3, 3).T

    def angular_velocity(self, q: Array, v: Array, body) -> Array:
        """ω = ½ Σ d_α × ḋ_α (rad/s, global)."""
        o = self.offset[body]
        d = q[o + 3 : o + 12].reshape(3, 3)
        dd = v[o + 3 : o + 12].reshape(3, 3)
        return 0.5 * np.cross(d, dd).sum(axis=0)

    def reaction(self, joint, q: Array, lam: Array, t: float) -> tuple[Array, Array]:
        """Force (N) and moment about the joint point (N·m) the joint applies to body_b."""
        rows = self.joint_rows[joint]
        gv = self.quad.jacobian_values(q, t)
        mask = np.isin(self.quad.jac_rows, rows)
        f = -np.bincount(self.quad.jac_cols[mask], gv[mask] * lam[self.quad.jac_rows[mask]],
                         minlength=self.n)
        b = joint.body_b
        o = self.offset[b]
        force = f[o : o + 3]
        if isinstance(b, PointMass):
            return force, np.zeros(3)
        d = q[o + 3 : o + 12].reshape(3, 3)
        fd = f[o + 3 : o + 12].reshape(3, 3)
        m_cm = np.cross(d, fd).sum(axis=0)
        p = joint.point_on_b(self).value(q)
        return force, m_cm - np.cross(p - q[o : o + 3], force)


def _cat(arrs, dtype=np.int64):
    arrs = [np.asarray(a) for a in arrs if len(a)]
    return np.concatenate(arrs).astype(dtype) if arrs else np.zeros(0, dtype=dtype)


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
