"""The compiled rotational-spring kernels (solver/rotation_kernels.py) against independent
computations.

Models: three rotational springs/dampers between pairs of tilted free bodies (or from ground),
about a body axis (two active directors) and about skew axes (all three), evaluated together
by one :class:`solver.forces.RelativeRotationSet`. On random configurations off the
orthonormality constraints (c² + s² ≠ 1, every director perturbed):

* c = e1ᵃ·e1ᵇ and s = −e1ᵃ·e2ᵇ against the triads written out here with NumPy from the full
  3 × 3 director matrices (the kernels gather only the active directors);
* on rigid motions, φ against the relative rotation angle imposed;
* ∇φ and ∇²φ against central differences of atan2(s, c) computed here;
* the damper tangent ∂f/∂q, ∂f/∂v (with delayed feedback acting) against central differences
  of the set's force.

Each tolerance is commented with the value measured when the test was written.
"""

from __future__ import annotations

import numpy as np
import pytest

from solver import rotation_kernels as rk
from solver.bodies import RigidBody, ground
from solver.forces import RelativeRotation, RelativeRotationSet
from solver.model import Model
from solver.system import System
from tests.solver.models import rodrigues

SEED = 20250612
AXES = {"body": (0.0, 0.0, 1.0), "skew": (0.2, 0.3, 1.0), "x": (1.0, 0.0, 0.0)}


def _model(grounded: bool, axis, feedback: bool = False):
    """Three elements on one axis (one set), bodies tilted differently."""
    m = Model()
    m.add(ground())
    for i in range(3):
        a = RigidBody(f"a{i}", 1.0, inertia=(1, 2, 3),
                      orientation=rodrigues((1, 2, 3 + i), 0.3 + i))
        b = RigidBody(f"b{i}", 1.0, inertia=(1, 2, 3), position=(0.3, 0.1, i),
                      orientation=rodrigues((3, 1, 2 - i), 0.7))
        extra = (dict(delay=0.1, delayed_stiffness=2.0, delayed_damping=0.7) if feedback
                 else {})
        m.add(a, b, RelativeRotation(f"r{i}", None if grounded else a, b, axis=axis,
                                     stiffness=3.0, damping=1.5, phi0=0.1 * i, **extra))
    s = System(m)
    (st,) = [x for x in s.sets if isinstance(x, RelativeRotationSet)]
    return s, st


CASES = [(g, ax) for g in (True, False) for ax in AXES]


@pytest.fixture(scope="module", params=CASES, ids=[f"{'ground' if g else 'pair'}-{a}"
                                                   for g, a in CASES])
def case(request):
    grounded, axis = request.param
    return _model(grounded, AXES[axis])


def _directors(q, body, s):
    """3 × 3 matrix with columns d_1, d_2, d_3 of ``body``."""
    o = s.offset[body]
    return q[o + 3 : o + 12].reshape(3, 3).T


def _cs(s, st, q):
    """c, s (J,) with NumPy from the full director matrices and the set's triad
    coefficients (e = R coefficient vector)."""
    c, sn = np.empty(len(st.elements)), np.empty(len(st.elements))
    for j, e in enumerate(st.elements):
        rb = _directors(q, e.body_b, s)
        ea = st._ea[j] if st.grounded else _directors(q, e.body_a, s) @ st._ca1[j]
        c[j] = ea @ (rb @ st._cb1[j])
        sn[j] = -ea @ (rb @ st._cb2[j])
    return c, sn


def _phi(s, st, q):
    c, sn = _cs(s, st, q)
    return np.arctan2(sn, c)


def _random_q(s, rng, scale=0.05):
    return s.q0_raw + scale * rng.standard_normal(s.n)


def _full(st, vals, n):
    """(J, n) per-element rows from values over ``idx`` (J, k)."""
    out = np.zeros((len(st.elements), n))
    for j in range(len(st.elements)):
        np.add.at(out[j], st.idx[j], vals[j])
    return out


def test_c_s_match_the_triads(case):
    s, st = case
    q = _random_q(s, np.random.default_rng(SEED))
    c, sn, _ = rk.phi_grad(*st._args(q))
    ce, se = _cs(s, st, q)
    # measured 0 (|c|, |s| ≤ 1.1): the same products; a director gathered from the wrong
    # column or coefficient would be off by O(0.1)
    assert np.abs(c - ce).max() < 1e-14 and np.abs(sn - se).max() < 1e-14
    assert np.abs(c * c + sn * sn - 1.0).max() > 1e-3  # really off the manifold


@pytest.mark.parametrize("theta", [0.4, -2.5, 3.0])
def test_angle_of_a_rigid_relative_rotation(case, theta):
    """Body b turned by θ about the axis relative to its start, both bodies then turned by a
    common rotation: φ = θ."""
    s, st = case
    q = s.q0_raw.copy()
    common = np.eye(3) if st.grounded else rodrigues((0.4, -1.0, 0.2), 0.9)
    for e in st.elements:
        axis = np.asarray(e.axis, dtype=float) / np.linalg.norm(e.axis)
        ob = s.offset[e.body_b]
        rb = common @ rodrigues(axis, theta) @ _directors(s.q0_raw, e.body_b, s)
        q[ob + 3 : ob + 12] = rb.T.ravel()
        if not st.grounded:
            oa = s.offset[e.body_a]
            q[oa + 3 : oa + 12] = (common @ _directors(s.q0_raw, e.body_a, s)).T.ravel()
    phi, _ = st._phi_grad(q)
    # measured ≤ 4.4e-16 rad
    assert np.abs(phi - theta).max() < 1e-13


def test_gradient_and_hessian_match_finite_differences(case):
    s, st = case
    rng = np.random.default_rng(SEED + 1)
    q = _random_q(s, rng)
    c, sn, g = rk.phi_grad(*st._args(q))
    c2, s2, g2, hess = rk.phi_hessian(*st._args(q))
    assert np.array_equal(g, g2) and np.array_equal(c, c2) and np.array_equal(sn, s2)
    h = 1e-6
    cols = np.unique(st.idx)
    fd = np.zeros((len(st.elements), s.n))
    for i in cols:
        e = np.zeros(s.n)
        e[i] = h
        fd[:, i] = (_phi(s, st, q + e) - _phi(s, st, q - e)) / (2 * h)
    # measured ≤ 5.5e-11 (|∇φ| up to 1.0): FD truncation h²|φ'''| and roundoff eps/h
    assert np.abs(_full(st, g, s.n) - fd).max() < 1e-8
    assert np.abs(fd[:, np.setdiff1d(np.arange(s.n), cols)]).max(initial=0.0) == 0.0
    # ∇²φ against central differences of the kernel's ∇φ (itself checked against the
    # independent φ just above)
    fdh = np.zeros((len(st.elements), s.n, s.n))
    for i in cols:
        e = np.zeros(s.n)
        e[i] = h
        gp = _full(st, rk.phi_grad(*st._args(q + e))[2], s.n)
        gm = _full(st, rk.phi_grad(*st._args(q - e))[2], s.n)
        fdh[:, :, i] = (gp - gm) / (2 * h)
    hk = np.zeros_like(fdh)
    for j in range(len(st.elements)):
        hk[j][np.ix_(st.idx[j], st.idx[j])] += hess[j]
    # measured ≤ 2.7e-10 (|∇²φ| up to 1.0): FD truncation and roundoff
    assert np.abs(hk - fdh).max() < 1e-7
    # symmetric to roundoff (measured ≤ 5.6e-16: the 2∇φ(c∇c + s∇s)ᵀ term is not
    # symmetric term by term)
    assert np.abs(hk - hk.transpose(0, 2, 1)).max() < 1e-14


@pytest.mark.parametrize("feedback", [False, True])
@pytest.mark.parametrize("grounded", [True, False])
def test_damper_jacobians_match_finite_differences(grounded, feedback):
    """∂f/∂q and ∂f/∂v of f = m ∇φ (damping, and the delayed feedback's stiffness and
    damping where it acts) against central differences of the set's force."""
    s, st = _model(grounded, AXES["skew"], feedback)
    rng = np.random.default_rng(SEED + 2)
    t = 0.0
    if feedback:  # a history reaching back one delay: the feedback acts
        for i in range(5):
            st.accept(_random_q(s, rng), rng.standard_normal(s.n), 0.04 * i)
        t = 0.17
        assert st._reached(t).all()
    q = _random_q(s, rng)
    v = rng.standard_normal(s.n)
    fq, fv = st.force_jacobians(q, v, t)
    nj, k = st.idx.shape
    fq, fv = fq.reshape(nj, k, k), fv.reshape(nj, k, k)
    h = 1e-6
    for m in range(k):
        for x, jac in ((q, fq), (v, fv)):
            for j in range(nj):
                e = np.zeros(s.n)
                e[st.idx[j, m]] = h
                fp = (st.force(q + e, v, t) if x is q else st.force(q, v + e, t))
                fm = (st.force(q - e, v, t) if x is q else st.force(q, v - e, t))
                fd = (fp - fm).reshape(nj, k)[j] / (2 * h)
                # measured ≤ 1.6e-9 of max(1, |FD|) (|∂f/∂q| up to 6.2): FD truncation and
                # roundoff; a term left out (m ∇²φ, ∇φ(∇²φ v)ᵀ) would be off by O(0.1)
                assert np.abs(jac[j, :, m] - fd).max() < 1e-7 * max(1.0, np.abs(fd).max())
