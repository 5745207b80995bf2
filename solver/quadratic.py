"""Constraints that are at most quadratic in the unknowns, stored as one sparse 3-tensor.

With directors, every lower-pair joint and every orthonormality condition is a sum of dot
products of coordinate blocks: C_r(q, t) = Σ_e h_e w_e(t) q_i q_j + Σ_l g_l w_l(t) q_k + Σ c w(t).
Storing all rows of all joints as flat entry arrays lets one vectorized numpy pass evaluate
values, Jacobians and λ-weighted Hessians for every constraint at once; and because the
Jacobian at the midpoint is the exact discrete derivative of a quadratic (∂C(q_m)·Δq =
C(q_f) − C(q_i)), the energy-preserving scheme needs no special treatment for them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from solver.element import ElementSet
from solver.jit import njit
from solver.timefunctions import TimeFunction, constant


@njit(cache=True)
def _evaluate(q, m, h, h_row, h_i, h_j, g, g_row, g_k, c, c_row, jac):
    """C(q) of every row, and (if ``jac`` is not empty) the Jacobian values in pattern order
    (h q_j at (row, i), h q_i at (row, j), g at (row, k)), in one pass. The three kinds of
    term are summed separately and then added, in the order of three ``np.bincount`` calls
    (the NumPy form this replaced, to the bit)."""
    quad = np.zeros(m)
    lin = np.zeros(m)
    const = np.zeros(m)
    nh = len(h)
    for e in range(nh):
        a = h[e] * q[h_i[e]]
        quad[h_row[e]] += a * q[h_j[e]]
        if len(jac):
            jac[e] = h[e] * q[h_j[e]]
            jac[nh + e] = a
    for e in range(len(g)):
        lin[g_row[e]] += g[e] * q[g_k[e]]
        if len(jac):
            jac[2 * nh + e] = g[e]
    for e in range(len(c)):
        const[c_row[e]] += c[e]
    out = np.empty(m)
    for r in range(m):
        out[r] = quad[r] + lin[r] + const[r]
    return out


@dataclass
class VecExpr:
    """A 3-vector linear in the unknowns: Σ coef·q[offset:offset+3] + const."""

    terms: list[tuple[float, int]] = field(default_factory=list)
    const: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def __add__(self, other: VecExpr) -> VecExpr:
        return VecExpr(self.terms + other.terms, self.const + other.const)

    def __sub__(self, other: VecExpr) -> VecExpr:
        return self + other.scaled(-1.0)

    def scaled(self, s: float) -> VecExpr:
        return VecExpr([(s * c, o) for c, o in self.terms], s * self.const)

    def value(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        out = self.const.copy()
        for c, o in self.terms:
            out += c * q[o : o + 3]
        return out


class QuadraticBuilder:
    """Collects quadratic constraint rows during model assembly."""

    def __init__(self) -> None:
        self.funcs: list[TimeFunction] = [constant(1.0)]
        self._fid: dict[int, int] = {}
        self.h: list[tuple[int, int, int, float, int]] = []  # row, i, j, h, fun
        self.g: list[tuple[int, int, float, int]] = []  # row, k, g, fun
        self.c: list[tuple[int, float, int]] = []  # row, c, fun
        self.n_rows = 0

    def fun(self, f: TimeFunction | None) -> int:
        if f is None:
            return 0
        if id(f) not in self._fid:
            self._fid[id(f)] = len(self.funcs)
            self.funcs.append(f)
        return self._fid[id(f)]

    def new_rows(self, n: int) -> NDArray[np.int64]:
        rows = np.arange(self.n_rows, self.n_rows + n)
        self.n_rows += n
        return rows

    def add_dot(self, row: int, u: VecExpr, w: VecExpr, coef: float = 1.0,
                f: TimeFunction | None = None) -> None:
        """Add coef·f(t)·(u·w) to row ``row``."""
        fid = self.fun(f)
        for a, oa in u.terms:
            for b, ob in w.terms:
                for k in range(3):
                    self.h.append((row, oa + k, ob + k, coef * a * b, fid))
            for k in range(3):
                if w.const[k] != 0.0:
                    self.g.append((row, oa + k, coef * a * w.const[k], fid))
        for b, ob in w.terms:
            for k in range(3):
                if u.const[k] != 0.0:
                    self.g.append((row, ob + k, coef * b * u.const[k], fid))
        cc = float(u.const @ w.const)
        if cc != 0.0:
            self.c.append((row, coef * cc, fid))

    def add_vector(self, rows: NDArray[np.int64], u: VecExpr) -> None:
        """Rows[k] += component k of u (a linear vector constraint)."""
        for a, o in u.terms:
            for k in range(3):
                self.g.append((int(rows[k]), o + k, a, 0))
        for k in range(3):
            if u.const[k] != 0.0:
                self.c.append((int(rows[k]), float(u.const[k]), 0))

    def add_product(self, row: int, i: int, j: int, coef: float) -> None:
        """Add coef·q_i·q_j to row ``row``."""
        self.h.append((row, i, j, coef, 0))

    def add_linear(self, row: int, index: int, coef: float, f: TimeFunction | None = None) -> None:
        self.g.append((row, index, coef, self.fun(f)))

    def add_constant(self, row: int, value: float, f: TimeFunction | None = None) -> None:
        self.c.append((row, value, self.fun(f)))

    def build(self) -> QuadraticConstraints:
        return QuadraticConstraints(self)


class QuadraticConstraints:
    """Vectorized evaluation of all quadratic constraint rows."""

    def __init__(self, b: QuadraticBuilder) -> None:
        self.m = b.n_rows
        self.funcs = b.funcs
        h = np.array(b.h, dtype=float).reshape(-1, 5)
        g = np.array(b.g, dtype=float).reshape(-1, 4)
        c = np.array(b.c, dtype=float).reshape(-1, 3)
        self.h_row, self.h_i, self.h_j = (h[:, k].astype(np.int64) for k in range(3))
        self.h_val, self.h_fun = h[:, 3].copy(), h[:, 4].astype(np.int64)
        self.g_row, self.g_k = g[:, 0].astype(np.int64), g[:, 1].astype(np.int64)
        self.g_val, self.g_fun = g[:, 2].copy(), g[:, 3].astype(np.int64)
        self.c_row, self.c_fun = c[:, 0].astype(np.int64), c[:, 2].astype(int)
        self.c_val = c[:, 1].copy()
        self.time_dependent = len(self.funcs) > 1
        # Jacobian pattern: (row, i) with value h q_j, (row, j) with value h q_i, (row, k) with g.
        self.jac_rows = np.concatenate([self.h_row, self.h_row, self.g_row])
        self.jac_cols = np.concatenate([self.h_i, self.h_j, self.g_k])
        # λ-weighted Hessian pattern: (i, j) and (j, i).
        self.hess_rows = np.concatenate([self.h_i, self.h_j])
        self.hess_cols = np.concatenate([self.h_j, self.h_i])
        self._w_cache: dict[float, NDArray[np.float64]] = {}
        self._s_cache: dict[tuple, tuple] = {}
        self._no_jac = np.zeros(0)

    def weights(self, t: float, order: int = 0) -> NDArray[np.float64]:
        """Values (order 0), rates (1) or second derivatives (2) of the time functions."""
        w = self._w_cache.get(t)  # Newton evaluates many times at the same few instants
        if w is None:
            if len(self._w_cache) > 8:
                self._w_cache.clear()
            w = self._w_cache[t] = np.array([f(t) for f in self.funcs]).T
        return w[order]

    def _scaled(self, t: float, order: int = 0):
        if not self.time_dependent:
            if order == 0:
                return self.h_val, self.g_val, self.c_val
            z = np.zeros
            return z(len(self.h_val)), z(len(self.g_val)), z(len(self.c_val))
        key = (t, order)  # the scaled coefficients too: Newton's iterations share one t
        out = self._s_cache.get(key)
        if out is None:
            if len(self._s_cache) > 8:
                self._s_cache.clear()
            w = self.weights(t, order)
            out = (self.h_val * w[self.h_fun], self.g_val * w[self.g_fun],
                   self.c_val * w[self.c_fun])
            for a in out:
                a.flags.writeable = False  # shared by the calls at this t
            self._s_cache[key] = out
        return out

    def value(self, q: NDArray[np.float64], t: float, order: int = 0) -> NDArray[np.float64]:
        """C(q, t) (order 0) or its partial time derivatives ∂ⁿC/∂tⁿ at fixed q."""
        return self._evaluate(q, t, order, self._no_jac)

    def value_and_jacobian(self, q: NDArray[np.float64], t: float):
        """C(q, t) and the Jacobian values at the (jac_rows, jac_cols) pattern, in one pass."""
        jac = np.empty(len(self.jac_rows))
        return self._evaluate(q, t, 0, jac), jac

    def _evaluate(self, q, t, order, jac):
        if order or self.time_dependent:
            h, g, c = self._scaled(t, order)
        else:  # the constant coefficients (every Newton iteration of a model without drivers)
            h, g, c = self.h_val, self.g_val, self.c_val
        return _evaluate(np.ascontiguousarray(q, dtype=float), self.m, h, self.h_row, self.h_i,
                         self.h_j, g, self.g_row, self.g_k, c, self.c_row, jac)

    def jacobian_values(self, q: NDArray[np.float64], t: float, order: int = 0):
        """Values at the (jac_rows, jac_cols) pattern of ∂C/∂q (or of ∂/∂q ∂ⁿC/∂tⁿ)."""
        h, g, _ = self._scaled(t, order)
        return np.concatenate([h * q[self.h_j], h * q[self.h_i], g])

    def hessian_values(self, lam: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        """Values at the (hess_rows, hess_cols) pattern of Σ_r λ_r ∂²C_r/∂q²."""
        h, _, _ = self._scaled(t)
        v = lam[self.h_row] * h
        return np.concatenate([v, v])

    def quadratic_rate_term(self, q, v, t) -> NDArray[np.float64]:
        """C̈ − (∂C/∂q)·q̈ for a motion through (q, v) at time t (exact for these rows)."""
        h0, _g0, _ = self._scaled(t, 0)
        out = np.zeros(self.m)
        out += np.bincount(self.h_row, 2 * h0 * v[self.h_i] * v[self.h_j], minlength=self.m)
        if self.time_dependent:
            h1, g1, _ = self._scaled(t, 1)
            h2, g2, c2 = self._scaled(t, 2)
            qq = q[self.h_i] * v[self.h_j] + v[self.h_i] * q[self.h_j]
            out += np.bincount(self.h_row, 2 * h1 * qq + h2 * q[self.h_i] * q[self.h_j],
                               minlength=self.m)
            out += np.bincount(self.g_row, 2 * g1 * v[self.g_k] + g2 * q[self.g_k],
                               minlength=self.m)
            out += np.bincount(self.c_row, c2, minlength=self.m)
        return out


class QuadraticSet(ElementSet):
    """All elements whose rows are at most quadratic — rigid-body orthonormality, prescribed
    motions and every lower-pair joint — as one :class:`QuadraticConstraints` tensor.

    Members implement ``quadratic_rows(builder, layout) -> (rows, data)``; ``data`` (a dict)
    is kept per member for outputs (e.g. a revolute's joint frames). Bodies' rows come first
    (``quadratic_priority`` 0), then the joints', each in model order.
    """

    def __init__(self, elements: list, system) -> None:
        ordered = sorted(elements, key=lambda e: getattr(e, "quadratic_priority", 1))
        super().__init__(ordered, system)
        qb = QuadraticBuilder()
        self.rows: dict = {}
        self.data: dict = {}
        for e in ordered:
            self.rows[e], self.data[e] = e.quadratic_rows(qb, system)
        self.quad = quad = qb.build()
        self.n_holonomic = quad.m
        self.hol_rows, self.hol_cols = quad.jac_rows, quad.jac_cols
        self.hess_rows, self.hess_cols = quad.hess_rows, quad.hess_cols
        self.time_dependent = self.nonconservative = quad.time_dependent
        self._owner = np.zeros(quad.m, dtype=np.int64)
        for k, e in enumerate(ordered):
            self._owner[self.rows[e]] = k

    def row_owner(self, row: int, holonomic: bool = True) -> str:
        return self.elements[int(self._owner[row])].name

    def constraint(self, q, t):
        return self.quad.value_and_jacobian(q, t)

    def constraint_value(self, q, t):
        return self.quad.value(q, t)

    def constraint_jacobian(self, q, t):
        return self.quad.jacobian_values(q, t)

    def discrete_jacobian(self, qi, qf, ti, tf):
        # the midpoint Jacobian of a quadratic is its exact discrete derivative
        return self.quad.jacobian_values(0.5 * (qi + qf), 0.5 * (ti + tf))

    def constraint_hessian(self, q, t, lam):
        return self.quad.hessian_values(lam, t)

    def constraint_rate(self, q, t):
        if not self.time_dependent:
            return np.zeros(self.n_holonomic)
        return self.quad.value(q, t, order=1)

    def constraint_curvature(self, q, v, t):
        return self.quad.quadratic_rate_term(q, v, t)
