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

from solver import curve_kernels as _kernels
from solver.bodies import Body, PointMass, Scalar
from solver.element import Element, ElementSet, dense_pattern
from solver.state import StateBlock

Array = NDArray[np.float64]
_PAIRS = {0: (2, 1), 1: (0, 2), 2: (1, 0)}  # rotation about t, n, b (Eq. 22 rows)
_NO_FRAME = np.zeros((0, 3, 3))  # frame arguments the kernels do not read
_D2_STEP = 1e-6  # central-difference step in η of d²R*/dη² (the Hessian's ∂²/∂η²)


class CurveSliding(Element):
    """Curve sliding joint between the curve of ``body_k`` and a point of ``body_l``.

    Parameters
    ----------
    name
        Joint name; its scalar unknown is called ``name + ".eta"``.
    body_k
        Body carrying the curve (rigid or prescribed).
    curve
        :class:`solver.curves.NurbsCurve`, points in m.
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
    placement
        Rotation matrix Q and offset o (m) placing the curve in body k's frame:
        p*(η) = o + Q p(η). Joints that share one curve object with different placements (the
        holes of several bifilars) are evaluated together, vectorized.

    The joints of a model are evaluated in batches (:class:`CurveSlidingSet`), one per curve
    object, rotation set and kind of body ℓ.
    """

    def __init__(self, name: str, body_k: Body, curve, body_l: Body,
                 point: ArrayLike | None = None, eta0: float | None = None,
                 rotation: bool | tuple[int, ...] = False,
                 placement: tuple[ArrayLike, ArrayLike] | None = None) -> None:
        self.name = name
        self.body_k, self.curve, self.body_l = body_k, curve, body_l
        if isinstance(body_k, PointMass):
            raise ValueError(f"curve joint {name!r}: the curve must be carried by a body with "
                             f"orientation, not point mass {body_k.name!r}")
        self.rot = (0, 1, 2) if rotation is True else tuple(rotation or ())
        if self.rot and isinstance(body_l, PointMass):
            raise ValueError(f"curve joint {name!r}: rotation constraints need a rigid body_l, "
                             f"{body_l.name!r} is a point mass")
        self._point = None if point is None else np.asarray(point, dtype=float)
        self._eta0 = eta0
        if placement is None:
            self.Q, self.o = np.eye(3), np.zeros(3)
        else:
            self.Q = np.asarray(placement[0], dtype=float)
            self.o = np.asarray(placement[1], dtype=float)
        self.eta = Scalar(f"{name}.eta", 0.0, units="1", long_name="curve parameter")

    def states(self) -> list[StateBlock]:
        return self.eta.states()

    def group_key(self) -> tuple:
        return (id(self.curve), self.rot, isinstance(self.body_l, PointMass))

    def local_point(self, eta) -> Array:
        """p*(η): the curve point in body k's frame (m)."""
        return self.o + self.curve.point(eta) @ self.Q.T

    def local_frame(self, eta) -> Array:
        """Frenet triad (columns t, n, b) in body k's frame."""
        return self.Q @ self.curve.frame(eta)[0]

    def initial_contact(self, s) -> tuple[float, np.ndarray, np.ndarray]:
        """(η0, the point b of body ℓ in its frame (m), the Frenet triad at η0 in body ℓ's
        frame) from the initial configuration; checks that the point lies on the curve."""
        k, l_ = self.body_k, self.body_l
        xk0, rk0 = s._pose0(k)
        xl0, rl0 = s._pose0(l_)
        p_glob = xl0 if self._point is None else self._point
        p_loc_k = rk0.T @ (p_glob - xk0)
        p_curve = self.Q.T @ (p_loc_k - self.o)
        eta0 = self.curve.closest_eta(p_curve) if self._eta0 is None else float(self._eta0)
        if not 0.0 <= eta0 <= 1.0:
            raise ValueError(f"curve joint {self.name!r}: eta0 = {eta0!r} outside [0, 1]")
        gap = np.linalg.norm(self.local_point(eta0) - p_loc_k)
        scale = max(1.0, float(np.abs(self.curve.control_points).max()))
        if gap > 1e-6 * scale:
            raise ValueError(f"curve joint {self.name!r}: the point {p_glob.tolist()} of "
                             f"{l_.name!r} is {gap:.3g} m off the curve")
        return eta0, s.to_local_point(l_, p_glob), rl0.T @ rk0 @ self.local_frame(eta0)


class CurveSlidingSet(ElementSet):
    """All curve sliding joints that share one curve, rotation set and kind of body ℓ,
    evaluated together: one curve evaluation and one compiled loop over the J joints per call
    (the arithmetic, with the formulas, is in :mod:`solver.curve_kernels`)."""

    def __init__(self, joints: list[CurveSliding], s) -> None:
        super().__init__(joints, s)
        self.joints = joints
        self.curve = joints[0].curve
        self.rot = joints[0].rot
        self.l_rigid = not isinstance(joints[0].body_l, PointMass)
        js = self.joints
        contact = [j.initial_contact(s) for j in js]
        self._eta0 = np.array([c[0] for c in contact])
        nj = len(js)
        self.nj = nj
        self.ok = np.array([s.offset[j.body_k] for j in js], dtype=np.int64)
        self.ol = np.array([s.offset[j.body_l] for j in js], dtype=np.int64)
        self.ie = np.array([s.scalar_index[j.eta] for j in js], dtype=np.int64)
        self.Q = np.array([j.Q for j in js])
        self.o = np.array([j.o for j in js])
        self.b = np.array([c[1] for c in contact])
        self.c = np.array([c[2] for c in contact])
        nl = 12 if self.l_rigid else 3
        cols = np.concatenate([self.ok[:, None] + np.arange(12), self.ol[:, None] + np.arange(nl),
                               self.ie[:, None]], axis=1)
        self.nc = cols.shape[1]
        self.mj = 3 + len(self.rot)
        self.cols = np.repeat(cols, self.mj, axis=0)  # (J·m, nc)
        self._cols_j = cols
        self.xl, self.dl, self.je = _kernels.XL, _kernels.DL, self.nc - 1
        self._ra = np.array([_PAIRS[x][0] for x in self.rot], dtype=np.int64)
        self._rb = np.array([_PAIRS[x][1] for x in self.rot], dtype=np.int64)
        self._planar = self.curve.plane_normal is not None
        self._normal = (np.asarray(self.curve.plane_normal, dtype=float) if self._planar
                        else np.zeros(3))
        self._memo_curve: dict = {}
        self._memo_eval: dict = {}
        self._structure(cols)

    def _structure(self, cols: np.ndarray) -> None:
        """Structural non-zeros of the Jacobian rows and of the λ-weighted Hessian."""
        nc, mj, je, dl = self.nc, self.mj, self.je, self.dl
        jm = np.zeros((mj, nc), dtype=bool)
        for i in range(3):  # displacement rows: x_k, p*_α d_α^k, x_ℓ, b_α d_α^ℓ, η
            jm[i, [i, 3 + i, 6 + i, 9 + i, self.xl + i, je]] = True
            if self.l_rigid:
                jm[i, [dl + i, dl + 3 + i, dl + 6 + i]] = True
        jm[3:, 3:12] = True  # rotation rows: directors of both bodies and η
        jm[3:, je] = True
        if self.l_rigid:
            jm[3:, dl : dl + 9] = True
        hm = np.zeros((nc, nc), dtype=bool)
        hm[je, 3:12] = hm[3:12, je] = hm[je, je] = True
        if self.rot:
            hm[je, dl : dl + 9] = hm[dl : dl + 9, je] = True
            # ∂²/∂d_β^k ∂d_γ^ℓ = coef_βγ I: only equal components couple
            same = np.kron(np.ones((3, 3), dtype=bool), np.eye(3, dtype=bool))
            hm[3:12, dl : dl + 9] |= same
            hm[dl : dl + 9, 3:12] |= same
        self._jr, self._jc = np.nonzero(jm)
        self._hr, self._hc = np.nonzero(hm)
        nj = len(cols)
        self.n_holonomic = nj * mj
        self.hol_rows = (np.arange(nj)[:, None] * mj + self._jr).ravel()
        self.hol_cols = cols[:, self._jc].ravel()
        self.hess_rows = cols[:, self._hr].ravel()
        self.hess_cols = cols[:, self._hc].ravel()

    def initialize(self, q0: Array) -> None:
        q0[self.ie] = self._eta0

    def row_owner(self, row: int, holonomic: bool = True) -> str:
        return self.joints[row // self.mj].name

    def constraint(self, q: Array, t: float) -> tuple[Array, Array]:
        return self.evaluate(q)

    def _curve_state(self, eta: Array) -> tuple[Array, Array, Array, Array, Array]:
        """p*, p*', p*'' (J, 3) in body k frames and the rotation rows' W, dW/dη (J, r, 3, 3)
        (:func:`solver.curve_kernels.curve_state`), memoized: a Newton iteration meets the
        same η at the start of the step and in the constraint values at its end."""
        key = eta.tobytes()
        hit = self._memo_curve.get(key)
        if hit is None:
            if self.rot and not self._planar:
                r, dr = self.curve.frame(eta)
            else:  # the planar frame is built in the kernel from the curve's p', p''
                r = dr = _NO_FRAME
            hit = _kernels.curve_state(*self.curve.spline, eta, r, dr, self.Q, self.o,
                                       self._normal, self._planar, self.c, self._ra, self._rb)
            if len(self._memo_curve) > 16:
                self._memo_curve.clear()
            self._memo_curve[key] = hit
        return hit

    def evaluate(self, q: Array) -> tuple[Array, Array]:
        """Constraint values (J·m,) and Jacobian values in pattern order (Eqs. 11 and 23),
        memoized (the residual and the Newton matrix ask for both at the same q)."""
        key = q[self._cols_j].tobytes()
        hit = self._memo_eval.get(key)
        if hit is not None:
            return hit
        p, p1, _, w, dw = self._curve_state(q[self.ie])
        out = _kernels.evaluate(q, self.ok, self.ol, self.l_rigid, self.b, p, p1, w, dw,
                                self._jr, self._jc, self.nc)
        if len(self._memo_eval) > 16:
            self._memo_eval.clear()
        self._memo_eval[key] = out
        return out

    def discrete_jacobian(self, qi: Array, qf: Array, ti: float = 0.0,
                          tf: float = 0.0) -> Array:
        """Exact discrete derivative Ḡ with Ḡ·(q_f − q_i) = C(q_f) − C(q_i): the secant of
        the curve and of W (:func:`solver.curve_kernels.discrete_jacobian`). Only the end
        points of the step are evaluated, each once per Newton iteration."""
        pi, p1i, _, wi, dwi = self._curve_state(qi[self.ie])
        pf, p1f, _, wf, dwf = self._curve_state(qf[self.ie])
        return _kernels.discrete_jacobian(qi, qf, self.ok, self.ol, self.ie, self.l_rigid,
                                          self.b, pi, p1i, wi, dwi, pf, p1f, wf, dwf,
                                          self._jr, self._jc, self.nc)

    def constraint_hessian(self, q: Array, t: float, lam: Array) -> Array:
        """Σ_r λ_r ∂²C_r/∂q² (:func:`solver.curve_kernels.constraint_hessian`)."""
        eta = q[self.ie]
        _, p1, p2, w, dw = self._curve_state(eta)
        if self.rot and self._planar:  # d²R*/dη² by a central difference of the exact dR/dη
            drp = _kernels.planar_dframe(*self.curve.spline, eta + _D2_STEP, self._normal)
            drm = _kernels.planar_dframe(*self.curve.spline, eta - _D2_STEP, self._normal)
        elif self.rot:
            drp = self.curve.frame(np.clip(eta + _D2_STEP, 0, 1))[1]
            drm = self.curve.frame(np.clip(eta - _D2_STEP, 0, 1))[1]
        else:
            drp = drm = _NO_FRAME
        return _kernels.constraint_hessian(q, self.ok, self.ol, lam, p1, p2, w, dw, self.Q,
                                           drp, drm, _D2_STEP, self.c, self._ra, self._rb,
                                           self._hr, self._hc, self.nc)


class ArcLength(Element):
    """ṡ − |p*'(η)| η̇ = 0 (Eq. 25): the arc length s travelled along a sliding joint's curve.

    A declaration: all of them on one curve are evaluated together (:class:`ArcLengthSet`)."""

    def __init__(self, joint: CurveSliding, name: str | None = None, s0: float = 0.0) -> None:
        self.joint = joint
        self.name = name or f"{joint.name}.s"
        self.s = Scalar(self.name, s0, units="m", long_name="arc length along the curve")

    def states(self) -> list[StateBlock]:
        return self.s.states()

    def group_key(self) -> int:
        return id(self.joint.curve)


class Rolling(Element):
    """Rolling without slip of a pin on a curve: ṡ + σ r (ω_pin − ω_link)·n = 0 (Eq. 5).

    A declaration: all of them are evaluated together (:class:`RollingSet`).

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


class _RelationSet(ElementSet):
    """Nonholonomic rows over a fixed set of columns per row (``cols``, m × k)."""

    def _rows(self, cols: np.ndarray) -> None:
        self.cols = cols
        self.n_nonholonomic = len(cols)
        self.nh_rows, self.nh_cols = dense_pattern(cols)
        self.row_names = [e.name for e in self.elements]

    def row_owner(self, row: int, holonomic: bool = False) -> str:
        return self.row_names[row]

    def nh_matrix(self, q: Array) -> Array:
        return self.matrix(q).ravel()

    def nh_derivative(self, q: Array, dq: Array) -> Array:
        return self.derivative(q, dq).ravel()


class ArcLengthSet(_RelationSet):
    """All :class:`ArcLength` relations on one curve, evaluated together: one compiled call
    (:func:`solver.curve_kernels.arc_length_matrix`, ``arc_length_derivative``) that evaluates
    the curve and the rows."""

    def __init__(self, arcs: list[ArcLength], sys) -> None:
        super().__init__(arcs, sys)
        self.curve = arcs[0].joint.curve
        self.i_e = np.array([sys.scalar_index[a.joint.eta] for a in arcs], dtype=np.int64)
        self._rows(np.array([[sys.scalar_index[a.s], sys.scalar_index[a.joint.eta]]
                             for a in arcs], dtype=np.int64))

    def matrix(self, q: Array) -> Array:
        """Rows (J, 2) of ṡ − |p*'(η)| η̇ = 0 over (s, η)."""
        return _kernels.arc_length_matrix(*self.curve.spline, q, self.i_e)

    def derivative(self, q: Array, dq: Array) -> Array:
        """∂(A(q)·dq)/∂q (J, 2) over (s, η)."""
        return _kernels.arc_length_derivative(*self.curve.spline, q, dq, self.i_e)


class RollingSet(_RelationSet):
    """All :class:`Rolling` relations of a model, evaluated together in one compiled call
    (:func:`solver.curve_kernels.rolling_matrix`, ``rolling_derivative``, with the formulas)."""

    def __init__(self, rolls: list[Rolling], sys) -> None:
        super().__init__(rolls, sys)
        op = np.array([sys.offset[r.pin] for r in rolls])
        ol = np.array([sys.offset[r.link] for r in rolls])
        self.ip = op[:, None] + 3 + np.arange(9)
        self.il = ol[:, None] + 3 + np.arange(9)
        i_s = np.array([sys.scalar_index[r.arc.s] for r in rolls])
        self._rows(np.concatenate([i_s[:, None], self.ip, self.il], axis=1).astype(np.int64))
        self._op = (op + 3).astype(np.int64)  # first director of the pin and of the link
        self._ol = (ol + 3).astype(np.int64)
        self.k = np.array([0.5 * r.side * r.r for r in rolls])  # ½ σ r (m)
        self.axis = np.array([r.axis for r in rolls])

    def matrix(self, q: Array) -> Array:
        """Rows (J, 19) over (s, the pin's directors, the link's directors)."""
        return _kernels.rolling_matrix(q, self._op, self._ol, self.k, self.axis)

    def derivative(self, q: Array, dq: Array) -> Array:
        """∂(A(q)·dq)/∂q (J, 19) over the same columns."""
        return _kernels.rolling_derivative(q, dq, self._op, self._ol, self.k, self.axis)


CurveSliding.set_class = CurveSlidingSet
ArcLength.set_class = ArcLengthSet
Rolling.set_class = RollingSet

