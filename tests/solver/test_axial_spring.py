"""The axial spring (a two-force link) and the driven prismatic joint, against closed forms.

Expected values come from analysis (the axial oscillator ω = √(k/m), the exact energy balance
of the energy-preserving scheme, the tension along the link) or finite differences of the
element's own potential and force, never from the solver's time integration of itself.
"""

from __future__ import annotations

import numpy as np
import pytest

from solver.bodies import PointMass, RigidBody, ground
from solver.forces import AxialSpring
from solver.joints import Prismatic
from solver.model import Model
from solver.simulation import simulate
from solver.system import System
from solver.timefunctions import harmonic
from tests.solver.models import zero_crossings


def _set(system: System, element):
    return next(s for s in system.sets if element in s.elements)


def _swinging(damping: float = 0.0) -> tuple[Model, AxialSpring]:
    """A rigid body hung from the ground by a link attached off its centre of mass, released
    stretched and moving sideways: stretching, swinging and tumbling at once."""
    g0 = ground()
    body = RigidBody("body", 2.0, inertia=(0.3, 0.4, 0.5), position=(1.2, 0.1, -0.2),
                     velocity=(0.3, 1.1, -0.4), angular_velocity=(0.7, -0.2, 1.3))
    link = AxialSpring("link", None, (0.0, 0.0, 0.5), body, (1.0, 0.2, -0.1),
                       stiffness=400.0, damping=damping, rest_length=1.0)
    return Model([g0, body, link]), link


@pytest.mark.parametrize("damped", [False, True], ids=["spring", "spring_damper"])
def test_axial_spring_fd(damped):
    """Gradient, Hessian and the damper's Jacobians against central differences of the
    element's potential and force, at a random state: measured 7.5e-11 (gradient), 7.6e-11
    (Hessian), 1.9e-10 and 5.3e-10 (the damper's ∂f/∂q, ∂f/∂v) of the largest entry."""
    model, link = _swinging(damping=5.0 if damped else 0.0)
    s = System(model)
    st = _set(s, link)
    rng = np.random.default_rng(3)
    q = s.q0_raw + 0.05 * rng.standard_normal(s.n)
    v = rng.standard_normal(s.n)
    idx = st.idx.ravel()
    eps = 1e-6
    grad = np.zeros(s.n)
    np.add.at(grad, st.grad_idx, st.gradient(q))
    hess = np.zeros((s.n, s.n))
    np.add.at(hess, (st.stiff_rows, st.stiff_cols), st.stiffness(q))
    for i in np.unique(idx):
        dq = np.zeros(s.n)
        dq[i] = eps
        fd = (st.potential(q + dq) - st.potential(q - dq)) / (2 * eps)
        assert abs(fd - grad[i]) <= 1e-8 * max(1.0, np.abs(grad).max())
        gp, gm = np.zeros(s.n), np.zeros(s.n)
        np.add.at(gp, st.grad_idx, st.gradient(q + dq))
        np.add.at(gm, st.grad_idx, st.gradient(q - dq))
        assert np.abs((gp - gm) / (2 * eps) - hess[:, i]).max() <= 1e-6 * np.abs(hess).max()
    if not damped:
        return
    jq_vals, jv_vals = st.force_jacobians(q, v, 0.0)
    jq, jv = np.zeros((s.n, s.n)), np.zeros((s.n, s.n))
    np.add.at(jq, (st.fq_rows, st.fq_cols), jq_vals)
    np.add.at(jv, (st.fv_rows, st.fv_cols), jv_vals)

    def f(qq, vv):
        out = np.zeros(s.n)
        np.add.at(out, st.force_idx, st.force(qq, vv, 0.0))
        return out

    for i in np.unique(idx):
        d = np.zeros(s.n)
        d[i] = eps
        assert np.abs((f(q + d, v) - f(q - d, v)) / (2 * eps) - jq[:, i]).max() <= (
            1e-6 * max(1.0, np.abs(jq).max()))
        assert np.abs((f(q, v + d) - f(q, v - d)) / (2 * eps) - jv[:, i]).max() <= (
            1e-6 * max(1.0, np.abs(jv).max()))


def test_axial_spring_force_along_the_link():
    """The generalized force on a point mass is −T n: the tension k (ℓ − ℓ0) + c ℓ̇ along the
    unit vector from the ground point to the mass (closed form)."""
    g0 = ground()
    p = np.array([0.3, -0.4, 1.2])
    mass = PointMass("m", 1.0, position=p, velocity=(0.2, 0.5, -0.1))
    k, c, l0 = 250.0, 3.0, 0.9
    link = AxialSpring("link", None, (0.0, 0.0, 0.0), mass, p, stiffness=k, damping=c,
                       rest_length=l0)
    s = System(Model([g0, mass, link]))
    st = _set(s, link)
    q, v = s.q0_raw.copy(), np.zeros(s.n)
    o = s.offset[mass]
    v[o : o + 3] = (0.2, 0.5, -0.1)
    n = p / np.linalg.norm(p)
    rate = n @ v[o : o + 3]
    tension = k * (np.linalg.norm(p) - l0) + c * rate
    assert st.tension(q, v)[0] == pytest.approx(tension, rel=1e-14)
    assert np.allclose(st.direction(q)[0], n, rtol=0, atol=1e-15)
    conservative = -st.gradient(q)
    damper = st.force(q, v, 0.0)
    assert np.allclose(conservative + damper, -tension * n, rtol=0, atol=1e-12)


def test_axial_oscillator_frequency():
    """A point mass on a link along x: m ẍ = −k (x − ℓ0), ω = √(k/m) whatever the pre-stretch
    (the motion stays on the line); measured period error at T/400: 2.06e-5 (midpoint, O(h²))."""
    m, k, l0 = 1.5, 600.0, 1.0
    g0 = ground()
    mass = PointMass("m", m, position=(1.1, 0.0, 0.0))
    link = AxialSpring("link", None, (0.0, 0.0, 0.0), mass, (1.1, 0.0, 0.0), stiffness=k,
                       rest_length=l0)
    omega = np.sqrt(k / m)
    t_ref = 2 * np.pi / omega
    sim = simulate(Model([g0, mass, link]), 2.6 * t_ref, t_ref / 400, scheme="ep",
                   reactions=False)
    assert sim.converged, sim.message
    ds = sim.dataset
    vx = ds.velocity.values[:, -1, 0]
    roots = zero_crossings(ds.time.values, vx, 0.25 * t_ref)
    period = 2 * np.polyfit(np.arange(len(roots)), roots, 1)[0]
    assert abs(period / t_ref - 1) <= 1e-4
    # the amplitude about ℓ0 is the initial stretch (released at rest)
    assert abs(ds.position.values[:, -1, 0].min() - (l0 - 0.1)) <= 1e-4


@pytest.mark.parametrize("damped", [False, True], ids=["conservative", "damped"])
def test_axial_spring_energy_balance(damped):
    """ep: the energy of the stretching, swinging, tumbling body is conserved to roundoff (the
    Gonzalez discrete gradient), and with the damper the energy plus the damper's booked work
    is: measured drift 5.5e-15 of the initial energy (the damper takes half of it in 1 s)."""
    model, _ = _swinging(damping=2.0 if damped else 0.0)
    sim = simulate(model, 1.0, 1e-2, scheme="ep", reactions=False)
    assert sim.converged, sim.message
    e, w = sim.dataset.energy.values, sim.dataset.work.values
    drift = np.abs(e - w - e[0]).max() / e[0]
    assert drift <= 1e-12
    if damped:  # the damper did take energy out
        assert e[-1] < 0.99 * e[0]


def test_driven_prismatic():
    """A body on a prismatic joint with a prescribed stroke s(t) = A cos ωt − A follows it
    along the joint axis (constraint to roundoff) and keeps its orientation."""
    g0 = ground()
    axis = np.array([0.0, 0.6, 0.8])
    slider = RigidBody("slider", 1.0, inertia=(0.1, 0.1, 0.1), position=(0.5, 0.0, 0.0))
    a, w = 0.2, 3.0
    stroke = harmonic(a, w)
    drive = type(stroke)(lambda t: stroke.value(t) - a, stroke.rate, stroke.accel)
    model = Model([g0, slider, Prismatic("slide", g0, slider, point=(0.5, 0.0, 0.0),
                                         axis=axis, driven=drive)])
    sim = simulate(model, 2.0, 1e-2, scheme="ep", reactions=False, record_every=10)
    assert sim.converged, sim.message
    ds = sim.dataset
    t = ds.time.values
    expected = np.array([0.5, 0.0, 0.0]) + np.outer(a * np.cos(w * t) - a, axis)
    assert np.abs(ds.position.values[:, -1] - expected).max() <= 1e-10
