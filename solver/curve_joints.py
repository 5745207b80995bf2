"""The curve sliding joint (paper Eqs. 9–24) and the nonholonomic relations (Eqs. 5 and 25).

Curve sliding joint: a point of body ℓ stays on a curve carried by body k,
    C = x_k + R_k p*(η) − (x_ℓ + R_ℓ b) = 0,                                       (Eq. 11)
with the curve parameter η an extra unknown. In director form R_k p* = Σ_α p*_α(η) d_α^k.
Optional rotation constraints keep body ℓ's orientation fixed relative to the Frenet triad of
the curve at the contact point (Eqs. 21–23):
    j_α^k = Σ_β R*_βα(η) d_β^k,  j_α^ℓ = Σ_β c_βα d_β^ℓ,  C = j_α^k·j_β^ℓ − j_β^k·j_α^ℓ,
where c holds the Frenet triad at η0 in body ℓ's frame, so the rows vanish at t = 0.
These rows are not polynomial in η; the integrators take their exact discrete derivative with
Gonzalez's correction, so the energy-preserving scheme still conserves energy exactly.

Nonholonomic relations A(q)·q̇ = 0:
    arc length  ṡ − |p*'(η)| η̇ = 0                                                (Eq. 25)
    rolling     ṡ + σ r (ω_pin − ω_link)·n = 0                                        (Eq. 5)
for a pin of radius r = d/2 whose centre lies on the side σ = +1 (towards the Frenet normal,
the inside of a hole traversed counter-clockwise) or σ = −1 of the curve; ω·n is written with
directors as ½ Σ_α ḋ_α·(n × d_α), linear in q̇. With σ = +1 this is the paper's ṡ = d/2·θ̇
with the pin's rotation θ measured as in Fig. 6 (ω* = −θ̇ e3).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.bodies import Body, PointMass, Scalar
from solver.constraints import HolonomicGroup, NonholonomicGroup

Array = NDArray[np.float64]
_PAIRS = {0: (2, 1), 1: (0, 2), 2: (1, 0)}  # rotation about t, n, b (Eq. 22 rows)


class CurveSliding(HolonomicGroup):
    """Curve sliding joint between the curve of ``body_k`` and a point of ``body_l``.

    Parameters
    ----------
    name
        Joint name; its scalar unknown is called ``name + ".eta"``.
    body_k
        Body carrying the curve (rigid or prescribed).
    curve
        :class:`solver.curves.NurbsCurve` with points in body k's frame (m), relative to body
        k's reference point (its centre of mass).
    body_l
        Body sliding on the curve.
    point
        Global position (m) at t = 0 of the point of body ℓ that touches the curve (default:
        body ℓ's reference point). It must lie on the curve.
    eta0
        Initial curve parameter (default: the nearest point of the curve to ``point``).
    rotation
        Which relative rotations to lock to the Frenet triad: a tuple of 0 (about t), 1
        (about n), 2 (about b); ``True`` for all three, ``False``/() for none.
    """

    def __init__(self, name: str, body_k: Body, curve, body_l: Body,
                 point: ArrayLike | None = None, eta0: float | None = None,
                 rotation: bool | tuple[int, ...] = False) -> None:
        self.name = name
        self.body_k, self.curve, self.body_l = body_k, curve, body_l
        if isinstance(body_k, PointMass):
            raise ValueError(f"curve joint {name!r}: the curve must be carried by a body with "
                             "orientation, not point mass {body_k.name!r}")
        self.rot = (0, 1, 2) if rotation is True else tuple(rotation or ())
        if self.rot and isinstance(body_l, PointMass):
            raise ValueError(f"curve joint {name!r}: rotation constraints need a rigid body_l, "
                             f"{body_l.name!r} is a point mass")
        self._point = None if point is None else np.asarray(point, dtype=float)
        self._eta0 = eta0
        self.eta = Scalar(f"{name}.eta", 0.0, units="1", long_name="curve parameter")

    def scalars(self) -> list:
        return [self.eta]

    def setup(self, s) -> None:
        k, l_ = self.body_k, self.body_l
        xk0, rk0 = s._pose0(k)
        xl0, rl0 = s._pose0(l_)
        p_glob = xl0 if self._point is None else self._point
        p_loc_k = rk0.T @ (p_glob - xk0)
        eta0 = self.curve.closest_eta(p_loc_k) if self._eta0 is None else float(self._eta0)
        if not 0.0 <= eta0 <= 1.0:
            raise ValueError(f"curve joint {self.name!r}: eta0 = {eta0!r} outside [0, 1]")
        gap = np.linalg.norm(self.curve.point(eta0) - p_loc_k)
        scale = max(1.0, float(np.abs(self.curve.control_points).max()))
        if gap > 1e-6 * scale:
            raise ValueError(f"curve joint {self.name!r}: the point {p_glob.tolist()} of "
                             f"{l_.name!r} is {gap:.3g} m off the curve")
        self.eta.initial = eta0
        s.q0_raw[s.scalar_index[self.eta]] = eta0
        self.b = s.to_local_point(l_, p_glob)
        ok, ol = s.offset[k], s.offset[l_]
        self.ok, self.ol = ok, ol
        self.l_rigid = not isinstance(l_, PointMass)
        self.ie = s.scalar_index[self.eta]
        cols = list(range(ok, ok + 12)) + list(range(ol, ol + (12 if self.l_rigid else 3)))
        cols.append(self.ie)
        self.nc = len(cols)
        m = 3 + len(self.rot)
        self.cols = np.tile(np.array(cols, dtype=np.int64), (m, 1))
        r_star0, _ = self.curve.frame(eta0)
        # Frenet triad at η0 expressed in body ℓ's frame (columns t, n, b)
        self.c = rl0.T @ rk0 @ r_star0
        # local column offsets
        self.xl = 12
        self.dl = 15
        self.je = self.nc - 1
        # Jacobian template: the constant blocks of the displacement rows
        eye = np.eye(3)
        g0 = np.zeros((m, self.nc))
        g0[:3, 0:3] = eye
        g0[:3, self.xl : self.xl + 3] = -eye
        if self.l_rigid:
            for a in range(3):
                g0[:3, self.dl + 3 * a : self.dl + 3 + 3 * a] = -self.b[a] * eye
        self._g0 = g0
        self._pr = np.tile(np.arange(3), 3)  # rows/cols of the p*_α I blocks
        self._pc = 3 + np.arange(9)
        self._ra = np.array([_PAIRS[x][0] for x in self.rot], dtype=np.int64)
        self._rb = np.array([_PAIRS[x][1] for x in self.rot], dtype=np.int64)
        self._memo_curve: dict = {}
        self._memo_eval: dict = {}
        # Hessian pattern: dense over the local columns (small: ≤ 25 × 25)
        self.hess_rows = np.repeat(self.cols[0], self.nc)
        self.hess_cols = np.tile(self.cols[0], self.nc)

    def _curve(self, eta: float):
        """Curve point, derivatives and Frenet frame at η, memoized (Newton revisits η)."""
        key = float(eta)
        hit = self._memo_curve.get(key)
        if hit is None:
            d = self.curve.derivatives(key, 2)
            rs, drs = self.curve.frame(key) if self.rot else (None, None)
            hit = (d[0], d[1], d[2], rs, drs)
            if len(self._memo_curve) > 16:
                self._memo_curve.clear()
            self._memo_curve[key] = hit
        return hit

    def _state(self, q: Array):
        eta = q[self.ie]
        p, p1, p2, rs, drs = self._curve(eta)
        dk = q[self.ok + 3 : self.ok + 12].reshape(3, 3)  # rows d1, d2, d3
        dl = q[self.ol + 3 : self.ol + 12].reshape(3, 3) if self.l_rigid else None
        return eta, p, p1, p2, rs, drs, dk, dl

    def evaluate(self, q: Array) -> tuple[Array, Array]:
        key = q[self.cols[0]].tobytes()
        hit = self._memo_eval.get(key)
        if hit is not None:
            return hit
        eta, p, p1, _, rs, drs, dk, dl = self._state(q)
        m = 3 + len(self.rot)
        c = np.empty(m)
        g = self._g0.copy()
        xk, xl = q[self.ok : self.ok + 3], q[self.ol : self.ol + 3]
        # displacement constraints, Eq. (11): constant blocks are in the template _g0
        c[:3] = xk + p @ dk - xl - (self.b @ dl if self.l_rigid else 0.0)
        g[self._pr, self._pc] = np.repeat(p, 3)  # ∂/∂d_α^k = p*_α I
        g[:3, self.je] = p1 @ dk
        if self.rot:
            a, b = self._ra, self._rb
            jk = rs.T @ dk  # rows j_α^k
            jkp = drs.T @ dk
            jl = self.c.T @ dl
            c[3:] = np.einsum("ri,ri->r", jk[a], jl[b]) - np.einsum("ri,ri->r", jk[b], jl[a])
            gk = (np.einsum("br,ri->rbi", rs[:, a], jl[b])
                  - np.einsum("br,ri->rbi", rs[:, b], jl[a]))
            gl = (np.einsum("br,ri->rbi", self.c[:, b], jk[a])
                  - np.einsum("br,ri->rbi", self.c[:, a], jk[b]))
            g[3:, 3:12] = gk.reshape(len(a), 9)
            g[3:, self.dl : self.dl + 9] = gl.reshape(len(a), 9)
            g[3:, self.je] = (np.einsum("ri,ri->r", jkp[a], jl[b])
                              - np.einsum("ri,ri->r", jkp[b], jl[a]))
        if len(self._memo_eval) > 16:
            self._memo_eval.clear()
        self._memo_eval[key] = (c, g)
        return c, g

    def discrete_jacobian(self, qi: Array, qf: Array) -> Array:
        """Exact discrete derivative Ḡ with Ḡ·(q_f − q_i) = C(q_f) − C(q_i).

        Product rule with averages and the secant of the curve (design note): Δ(p_α d_α) =
        p̄_α Δd_α + d̄_α p̄'_α Δη with p̄' = (p(η_f) − p(η_i))/Δη; the rotation rows are
        Σ W_βγ(η) d_β^k·d_γ^ℓ and use the secant of W = f(R*(η)) likewise. Only the end points
        of the step are evaluated, each once per Newton iteration.
        """
        ei, pi, p1i, _, rsi, drsi, dki, dli = self._state(qi)
        ef, pf, p1f, _, rsf, drsf, dkf, dlf = self._state(qf)
        de = ef - ei
        small = abs(de) < 1e-9
        g = self._g0.copy()
        pbar = 0.5 * (pi + pf)
        sec = 0.5 * (p1i + p1f) if small else (pf - pi) / de
        dkbar = 0.5 * (dki + dkf)
        g[self._pr, self._pc] = np.repeat(pbar, 3)
        g[:3, self.je] = sec @ dkbar
        if self.rot:
            a, b = self._ra, self._rb
            dlbar = 0.5 * (dli + dlf)
            # W[r, β, γ] = R*_βa c_γb − R*_βb c_γa for each rotation row r
            wi = (rsi[:, a].T[:, :, None] * self.c[:, b].T[:, None, :]
                  - rsi[:, b].T[:, :, None] * self.c[:, a].T[:, None, :])
            wf = (rsf[:, a].T[:, :, None] * self.c[:, b].T[:, None, :]
                  - rsf[:, b].T[:, :, None] * self.c[:, a].T[:, None, :])
            if small:
                dr = 0.5 * (drsi + drsf)
                dw = (dr[:, a].T[:, :, None] * self.c[:, b].T[:, None, :]
                      - dr[:, b].T[:, :, None] * self.c[:, a].T[:, None, :])
            else:
                dw = (wf - wi) / de
            wbar = 0.5 * (wi + wf)
            xbar = 0.5 * (dki @ dli.T + dkf @ dlf.T)  # X_βγ = d_β^k·d_γ^ℓ averaged
            g[3:, 3:12] = np.einsum("rbg,gi->rbi", wbar, dlbar).reshape(len(a), 9)
            g[3:, self.dl : self.dl + 9] = np.einsum("rbg,bi->rgi", wbar, dkbar).reshape(
                len(a), 9)
            g[3:, self.je] = np.einsum("rbg,bg->r", dw, xbar)
        return g

    def hessian(self, q: Array, lam: Array) -> Array:
        eta, p, p1, p2, rs, drs, dk, dl = self._state(q)
        h = np.zeros((self.nc, self.nc))
        je = self.je
        for a in range(3):
            h[je, 3 + 3 * a : 6 + 3 * a] += p1[a] * lam[:3]
        h[je, je] += lam[:3] @ (p2 @ dk)
        if self.rot:
            jk, jkp, jl = rs.T @ dk, drs.T @ dk, self.c.T @ dl
            eye = np.eye(3)
            for r, axis in enumerate(self.rot, start=3):
                a, b = _PAIRS[axis]
                lr = lam[r]
                for beta in range(3):
                    h[je, 3 + 3 * beta : 6 + 3 * beta] += lr * (
                        drs[beta, a] * jl[b] - drs[beta, b] * jl[a])
                    h[je, self.dl + 3 * beta : self.dl + 3 + 3 * beta] += lr * (
                        self.c[beta, b] * jkp[a] - self.c[beta, a] * jkp[b])
                    for gam in range(3):
                        coef = lr * (rs[beta, a] * self.c[gam, b] - rs[beta, b] * self.c[gam, a])
                        h[3 + 3 * beta : 6 + 3 * beta, self.dl + 3 * gam : self.dl + 3 + 3 * gam] \
                            += coef * eye
        # symmetrize the off-diagonal blocks filled on one side
        h = h + h.T - np.diag(np.diag(h))
        return h.ravel()

    def frenet(self, q: Array) -> Array:
        """Frenet triad (columns t, n, b) at the contact point, global frame."""
        eta = q[self.ie]
        rs, _ = self.curve.frame(eta)
        dk = q[self.ok + 3 : self.ok + 12].reshape(3, 3)
        return dk.T @ rs


class ArcLength(NonholonomicGroup):
    """ṡ − |p*'(η)| η̇ = 0 (Eq. 25): the arc length s travelled along a sliding joint's curve."""

    def __init__(self, joint: CurveSliding, name: str | None = None, s0: float = 0.0) -> None:
        self.joint = joint
        self.name = name or f"{joint.name}.s"
        self.s = Scalar(self.name, s0, units="m", long_name="arc length along the curve")

    def scalars(self) -> list:
        return [self.s]

    def setup(self, sys) -> None:
        self.i_s = sys.scalar_index[self.s]
        self.i_e = sys.scalar_index[self.joint.eta]
        self.cols = np.array([[self.i_s, self.i_e]], dtype=np.int64)

    def matrix(self, q: Array) -> Array:
        return np.array([[1.0, -float(self.joint.curve.speed(q[self.i_e]))]])

    def derivative(self, q: Array, dq: Array) -> Array:
        d = self.joint.curve.derivatives(q[self.i_e], 2)
        sp = float(np.linalg.norm(d[1]))
        return np.array([[0.0, -float(d[1] @ d[2]) / sp * dq[self.i_e]]])


class Rolling(NonholonomicGroup):
    """Rolling without slip of a pin on a curve: ṡ + σ r (ω_pin − ω_link)·n = 0 (Eq. 5).

    Parameters
    ----------
    arc
        The :class:`ArcLength` relation giving s along the curve.
    pin
        The pin body (its rotation is the rolling rotation).
    link
        The fictitious link of the curve sliding joint (locked to the Frenet triad).
    radius
        Pin radius r = d/2 (m), > 0.
    axis
        Rolling axis in the link's frame (the curve binormal; default the link's e3).
    side
        +1 if the pin centre lies towards the Frenet normal of the curve, −1 otherwise.
    """

    def __init__(self, name: str, arc: ArcLength, pin: Body, link: Body, radius: float,
                 axis: ArrayLike = (0.0, 0.0, 1.0), side: int = 1) -> None:
        if not (np.isfinite(radius) and radius > 0):
            raise ValueError(f"rolling {name!r}: radius = {radius!r} m must be > 0")
        if side not in (1, -1):
            raise ValueError(f"rolling {name!r}: side = {side!r} must be +1 or -1")
        for b in (pin, link):
            if isinstance(b, PointMass):
                raise ValueError(f"rolling {name!r}: {b.name!r} must be a rigid body")
        self.name, self.arc, self.pin, self.link = name, arc, pin, link
        self.r, self.side = float(radius), side
        self.axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)

    def setup(self, sys) -> None:
        self.op, self.ol = sys.offset[self.pin], sys.offset[self.link]
        cols = [sys.scalar_index[self.arc.s]]
        cols += list(range(self.op + 3, self.op + 12)) + list(range(self.ol + 3, self.ol + 12))
        self.cols = np.array([cols], dtype=np.int64)

    def matrix(self, q: Array) -> Array:
        dp = q[self.op + 3 : self.op + 12].reshape(3, 3)
        dl = q[self.ol + 3 : self.ol + 12].reshape(3, 3)
        n = self.axis @ dl
        k = 0.5 * self.side * self.r
        row = np.empty(19)
        row[0] = 1.0
        row[1:10] = (k * _cross(n, dp)).ravel()
        row[10:19] = (-k * _cross(n, dl)).ravel()
        return row[None, :]

    def derivative(self, q: Array, dq: Array) -> Array:
        # A·δ = δs + k Σ_α n·(d_α^P × δd_α^P) − k Σ_α n·(d_α^L × δd_α^L), n = Σ_β a_β d_β^L
        dp = q[self.op + 3 : self.op + 12].reshape(3, 3)
        dl = q[self.ol + 3 : self.ol + 12].reshape(3, 3)
        ep = dq[self.op + 3 : self.op + 12].reshape(3, 3)
        el = dq[self.ol + 3 : self.ol + 12].reshape(3, 3)
        n = self.axis @ dl
        k = 0.5 * self.side * self.r
        w = (_cross(dp, ep) - _cross(dl, el)).sum(axis=0)  # ∂/∂n
        row = np.zeros(19)
        row[1:10] = (k * _cross(ep, n)).ravel()
        row[10:19] = (-k * _cross(el, n)).ravel() + k * np.outer(self.axis, w).ravel()
        return row[None, :]


def _cross(a: Array, b: Array) -> Array:
    """Cross product with broadcasting over leading axes (cheaper than np.cross for 3-vectors)."""
    a, b = np.broadcast_arrays(a, b)
    out = np.empty(a.shape)
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out
