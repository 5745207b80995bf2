"""The compiled curve-joint kernels (solver/curve_kernels.py) against independent computations.

On random, constraint-violating states of small models (a free tilted carrier with two
sliders on one curve, each curve placed differently in the carrier by (Q, o)), for a planar
NURBS curve (a rational circle, planar frame built from p' and p'') and a non-planar one (the
same circle bent out of its plane, Frenet frame from ``curve.frame``), with all three, one, two
or no rotation rows and a rigid or point-mass body ℓ:

* the constraint values against Eqs. (11) and (21)–(23) written out here with NumPy;
* the Jacobian against fourth-order central differences of the values;
* the discrete Jacobian's defining property Ḡ·(q_f − q_i) = C(q_f) − C(q_i), for finite
  steps and for |Δη| below the secant's 1e-9 switch (Δη = 0 included);
* the λ-weighted Hessian against central differences of Gᵀλ, and its sparsity pattern
  against the finite-difference Hessian (no coupling left out).

Each tolerance is commented with the value measured when the test was written and the
reason for it. Runtime: a few seconds (plus the kernels' one-time compilation, cached).
"""

from __future__ import annotations

import numpy as np
import pytest

from solver import curve_kernels as _kernels
from solver.bodies import PointMass, RigidBody
from solver.curve_joints import CurveSliding, CurveSlidingSet
from solver.curves import NurbsCurve, circle
from solver.model import Model
from solver.system import System
from tests.solver.models import dense, fd4, rodrigues

SEED = 20250611
# two sliders per curve; η away from the circle's double knots at 0.25, 0.5, 0.75 (p'' jumps)
ETAS = (0.33, 0.63)
PLACEMENTS = (((0.3, -0.5, 1.0), 0.4, (0.1, 0.0, -0.2)),
              ((0.3, -0.5, 1.0), -1.1, (-0.3, 0.2, 0.05)))


def _curve(kind: str) -> NurbsCurve:
    c0 = circle(0.7)
    if kind == "planar":
        return c0
    pts = c0.control_points.copy()  # bent out of its plane: rational, non-planar
    pts[:, 2] = 0.25 * np.sin(3.0 * np.arange(len(pts)))
    return NurbsCurve(c0.degree, c0.knots, pts, c0.weights)


def _model(kind: str, rotation) -> tuple[System, CurveSlidingSet]:
    """Two sliders on one curve carried by a free, tilted body k; ``rotation`` None makes
    body ℓ a point mass, otherwise a rigid body with its contact point off its centre."""
    curve = _curve(kind)
    assert (curve.plane_normal is not None) == (kind == "planar")
    rk = rodrigues((1.0, 2.0, 0.5), 0.6)
    xk = np.array([0.2, -0.1, 0.4])
    carrier = RigidBody("carrier", 5.0, inertia=(1.0, 2.0, 2.5), position=xk, orientation=rk)
    m = Model()
    m.add(carrier)
    for i, (eta, (axis, ang, off)) in enumerate(zip(ETAS, PLACEMENTS, strict=True)):
        q, o = rodrigues(axis, ang), np.array(off)
        contact = xk + rk @ (o + q @ curve.point(eta))
        if rotation is None:
            body = PointMass(f"slider{i}", 1.0, position=contact)
            j = CurveSliding(f"slide{i}", carrier, curve, body, eta0=eta, placement=(q, o))
        else:
            rl = rodrigues((0.3, -1.0, 0.8), 1.1 + i)
            body = RigidBody(f"slider{i}", 1.0, inertia=(0.1, 0.2, 0.25),
                             position=contact + rl @ np.array([0.05, -0.02, 0.03]),
                             orientation=rl)
            j = CurveSliding(f"slide{i}", carrier, curve, body, point=contact, eta0=eta,
                             rotation=rotation, placement=(q, o))
        m.add(body, j)
    s = System(m)
    (cs,) = [x for x in s.hol_sets if isinstance(x, CurveSlidingSet)]
    assert cs.nj == 2
    return s, cs


ROTATIONS = {"all": True, "binormal": (2,), "tangent-normal": (0, 1), "none-rigid": False,
             "point": None}
CASES = [(k, r) for k in ("planar", "space") for r in ROTATIONS]


@pytest.fixture(scope="module", params=CASES, ids=[f"{k}-{r}" for k, r in CASES])
def case(request):
    kind, rot = request.param
    return _model(kind, ROTATIONS[rot])


def _random_q(s, cs, rng, scale=0.05):
    """A configuration off the constraints (every coordinate perturbed, η kept near ETAS)."""
    q = s.q0_raw + scale * rng.standard_normal(s.n)
    q[cs.ie] = ETAS
    return q


def _values(cs, q):
    return cs.constraint(q, 0.0)[0]


def _jacobian(cs, q, n):
    return dense(cs.constraint(q, 0.0)[1], cs.hol_rows, cs.hol_cols, (cs.n_holonomic, n))


# ---------------------------------------------------------------------------- values
def test_values_match_the_joint_equations(case):
    """C from Eq. (11), x_k + R_k(o + Q p(η)) − x_ℓ − R_ℓ b, and Eq. (23),
    j_a^k·j_b^ℓ − j_b^k·j_a^ℓ with j^k = R_k Q R(η) and j^ℓ = R_ℓ c, written out here with the
    curve's own point and frame (the kernels build the planar frame themselves)."""
    s, cs = case
    q = _random_q(s, cs, np.random.default_rng(SEED))
    c = _values(cs, q).reshape(cs.nj, cs.mj)
    pairs = {0: (2, 1), 1: (0, 2), 2: (1, 0)}
    for j, joint in enumerate(cs.joints):
        eta = q[cs.ie[j]]
        ok, ol = cs.ok[j], cs.ol[j]
        rk = q[ok + 3 : ok + 12].reshape(3, 3).T  # columns d_α
        expect = q[ok : ok + 3] + rk @ (joint.o + joint.Q @ joint.curve.point(eta))
        expect = expect - q[ol : ol + 3]
        if cs.l_rigid:
            rl = q[ol + 3 : ol + 12].reshape(3, 3).T
            expect = expect - rl @ cs.b[j]
        rows = [*expect]
        if cs.rot:
            jk = rk @ joint.Q @ joint.curve.frame(eta)[0]
            jl = rl @ cs.c[j]
            rows += [jk[:, a] @ jl[:, b] - jk[:, b] @ jl[:, a]
                     for a, b in (pairs[x] for x in cs.rot)]
        # measured ≤ 2.3e-16 (|C| up to 0.2): the same sums in another order
        assert np.abs(c[j] - rows).max() < 1e-14, (j, c[j], rows)
    assert np.abs(c).max() > 1e-2  # the state is really off the constraints


# ---------------------------------------------------------------------------- tangents
def test_jacobian_matches_finite_differences(case):
    s, cs = case
    q = _random_q(s, cs, np.random.default_rng(SEED + 1))
    g = _jacobian(cs, q, s.n)
    fd = np.column_stack([fd4(lambda x: _values(cs, x), q, i, 1e-4) for i in range(s.n)])
    # measured max |G − FD| ≤ 3.4e-12 over the cases, 3.5e-13 of max |FD| (FD truncation
    # (1e-4)⁴·|C⁽⁵⁾| and roundoff eps/h ≈ 1e-12); a wrong entry would be off by O(1e-2) or more
    assert np.abs(g - fd).max() < 1e-9 * max(1.0, np.abs(fd).max())
    assert np.abs(g[:, cs.ie]).max() > 0.1  # the rows depend on η (not vacuous)


@pytest.mark.parametrize("deta", [0.037, 5e-10, 3e-12, 0.0])
def test_discrete_jacobian_is_exact(case, deta):
    """Ḡ(q_i, q_f)·(q_f − q_i) = C(q_f) − C(q_i) for a finite step (secant of the curve) and
    for |Δη| < 1e-9 (mean of the end derivatives instead)."""
    s, cs = case
    rng = np.random.default_rng(SEED + 2)
    qi = _random_q(s, cs, rng)
    dq = 0.05 if deta > 1e-3 else 1e-6
    qf = qi + dq * rng.standard_normal(s.n)
    qf[cs.ie] = qi[cs.ie] + deta
    gbar = dense(cs.discrete_jacobian(qi, qf), cs.hol_rows, cs.hol_cols,
                  (cs.n_holonomic, s.n))
    dc = _values(cs, qf) - _values(cs, qi)
    # measured ≤ 4.4e-16 absolute (|C| up to 0.2, |ΔC| up to 0.7): roundoff of C itself
    assert np.abs(gbar @ (qf - qi) - dc).max() <= 5e-15
    # a true secant: within O(|Δq|²) of G at the midpoint (|Δq| ≈ 0.3: measured ≤ 7.7e-2;
    # |Δq| ≈ 6e-6: measured ≤ 7.8e-12); a wrong block would be off by O(1)
    gm = _jacobian(cs, 0.5 * (qi + qf), s.n)
    assert np.abs(gbar - gm).max() < (0.1 if deta > 1e-3 else 1e-10)


def test_hessian_matches_finite_differences(case):
    """Σ_r λ_r ∂²C_r/∂q² against central differences of Gᵀλ, and no coupling outside the
    structural pattern."""
    s, cs = case
    rng = np.random.default_rng(SEED + 3)
    q = _random_q(s, cs, rng)
    lam = rng.standard_normal(cs.n_holonomic)
    h = dense(cs.constraint_hessian(q, 0.0, lam), cs.hess_rows, cs.hess_cols, (s.n, s.n))

    def glam(x):
        return _jacobian(cs, x, s.n).T @ lam

    fd = np.column_stack([fd4(glam, q, i, 1e-4) for i in range(s.n)])
    scale = np.abs(fd).max()  # 16 to 53 over the cases
    ee = np.zeros((s.n, s.n), dtype=bool)
    ee[cs.ie, cs.ie] = True
    # every entry but ∂²/∂η²: measured max |H − FD| / max |FD| ≤ 4.7e-12 (FD truncation and
    # roundoff); a missing or misplaced block would be off by O(0.1)
    assert np.abs(h - fd)[~ee].max() < 1e-10 * scale
    # ∂²/∂η² takes d²R*/dη² from the kernel's own central difference of dR/dη (step 1e-6), whose
    # roundoff eps·|dR/dη|/1e-6 dominates: measured ≤ 2.3e-9 of |H_ηη| (binormal rows; the
    # same with FD steps 3e-5 to 3e-4, so not the test's FD). The Hessian only shapes the
    # Newton matrix; a wrong term would be off by O(1)
    assert (np.abs(h - fd)[ee] / np.abs(fd[ee])).max() < 1e-7
    assert np.abs(h - h.T).max() == 0.0
    pattern = np.zeros((s.n, s.n), dtype=bool)
    pattern[cs.hess_rows, cs.hess_cols] = True
    # measured ≤ 5.7e-13 of the scale outside the pattern (FD noise of zero entries)
    assert np.abs(fd[~pattern]).max(initial=0.0) < 1e-10 * scale
    assert np.abs(h[:, cs.ie]).max() > 0.1  # the η couplings are there (not vacuous)


# ------------------------------------------------------------- planar frame, η ± h (Hessian)
def test_planar_dframe_matches_the_curve_frame():
    """The Hessian's dR/dη of a planar curve (built in the kernel from p', p'') against
    ``NurbsCurve.frame`` (η inside, at the ends and beyond them: clipped like the curve)."""
    curve = _curve("planar")
    eta = np.array([0.0, 0.13, 0.33, 0.63, 0.97, 1.0, -0.2, 1.3])
    dr = _kernels.planar_dframe(*curve.spline, eta, curve.plane_normal)
    expect = curve.frame(eta)[1]
    # measured ≤ 1.5e-16 of max |dR/dη| ≈ 5.9 (1/|p'| applied as a product there, a
    # quotient here)
    assert np.abs(dr - expect).max() < 1e-14 * np.abs(expect).max()


# ------------------------------------------------------------- arc length and rolling rows
@pytest.mark.parametrize("kind", ["planar", "space"])
def test_arc_length_rows_match_finite_differences(kind):
    """A = (1, −|p'(η)|) with |p'| from fourth-order central differences of the curve's
    points, and ∂(A·dq)/∂q from those of A·dq; several relations in one call."""
    curve = _curve(kind)
    rng = np.random.default_rng(SEED + 4)
    n = 12
    ie = np.array([2, 7, 9, 4], dtype=np.int64)
    q = rng.standard_normal(n)
    q[ie] = [0.11, 0.33, 0.63, 0.9]
    dq = rng.standard_normal(n)
    a = _kernels.arc_length_matrix(*curve.spline, q, ie)
    h = 3e-4
    sp = np.linalg.norm(fd4(curve.point, q[ie], slice(None), h), axis=1)
    assert np.all(a[:, 0] == 1.0)
    # measured ≤ 4.1e-12 of |p'| ≈ 4.7 (FD truncation h⁴|p⁽⁵⁾|: 4.8e-10 with h = 1e-3)
    assert np.abs(a[:, 1] + sp).max() < 1e-10 * sp.max()
    d = _kernels.arc_length_derivative(*curve.spline, q, dq, ie)

    def adq(x):
        return _kernels.arc_length_matrix(*curve.spline, x, ie)[:, 1] * dq[ie]

    fd = np.array([fd4(adq, q, i, h)[j] for j, i in enumerate(ie)])
    assert np.all(d[:, 0] == 0.0)
    # measured ≤ 9.2e-11 of the largest |FD| (2.2 to 2.6; FD truncation, the space curve's
    # the larger); a wrong sign or factor would be off by O(1)
    assert np.abs(d[:, 1] - fd).max() < 3e-9 * max(1.0, np.abs(fd).max())
    # beyond the ends: the curve at η clipped to [0, 1], as NurbsCurve.derivatives
    q[ie[:2]] = (-0.3, 1.4)
    a = _kernels.arc_length_matrix(*curve.spline, q, ie)
    # measured 0 (the same evaluation)
    assert np.abs(a[:2, 1] + curve.speed(np.array([0.0, 1.0]))).max() < 1e-14


def _rolling_rows(q, op, ol, k, axis):
    """The rolling rows written out with np.cross: (1, k n × d_α^pin, −k n × d_α^link)."""
    rows = []
    for j in range(len(op)):
        dp = q[op[j] : op[j] + 9].reshape(3, 3)
        dl = q[ol[j] : ol[j] + 9].reshape(3, 3)
        n = axis[j] @ dl
        rows.append(np.concatenate([[1.0], (k[j] * np.cross(n, dp)).ravel(),
                                    (-k[j] * np.cross(n, dl)).ravel()]))
    return np.array(rows)


def test_rolling_rows_match_cross_products_and_finite_differences():
    """Three rolling rows (sides ±1, radii, axes in the link's frame) on random, non-unit
    directors: A against np.cross; ∂(A·dq)/∂q against central differences of A·dq (A·dq is
    bilinear in q, so the differences are exact to roundoff)."""
    rng = np.random.default_rng(SEED + 5)
    n = 60
    op = np.array([3, 23, 41], dtype=np.int64)
    ol = np.array([12, 32, 50], dtype=np.int64)
    k = np.array([0.5 * 0.02, -0.5 * 0.035, 0.5 * 0.01])
    axis = rng.standard_normal((3, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    q = rng.standard_normal(n)
    dq = rng.standard_normal(n)
    a = _kernels.rolling_matrix(q, op, ol, k, axis)
    expect = _rolling_rows(q, op, ol, k, axis)
    # measured 0 (entries up to 0.04: the same products)
    assert np.abs(a - expect).max() < 1e-15
    cols = np.concatenate([np.zeros((3, 1), dtype=np.int64), op[:, None] + np.arange(9),
                           ol[:, None] + np.arange(9)], axis=1)

    def adq(x):
        return np.einsum("jc,jc->j", _rolling_rows(x, op, ol, k, axis)[:, 1:], dq[cols[:, 1:]])

    d = _kernels.rolling_derivative(q, dq, op, ol, k, axis)
    h = 1e-3
    for j in range(3):
        for c in range(1, 19):
            e = np.zeros(n)
            e[cols[j, c]] = h
            fd = (adq(q + e) - adq(q - e))[j] / (2 * h)
            # measured ≤ 8.1e-15 (entries up to 0.11): the differences' roundoff eps|A·dq|/h;
            # a missing term (the link block's k axis_α w) would be off by O(1e-2)
            assert abs(d[j, c] - fd) < 1e-12, (j, c, d[j, c], fd)
    assert np.all(d[:, 0] == 0.0)
    assert np.abs(d[:, 10:]).max() > 1e-3  # the link block's n-derivative is there
