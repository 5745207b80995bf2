"""Validation of static and relative equilibria and of the linearized modes against analysis.

Every expected value comes from a closed form or an independent small computation written here
(a 2 × 2 eigenproblem, a 3 × 3 state matrix, the Lagrangian of a flapping blade solved with
brentq), never from the code under test. Each tolerance is commented with the error measured
when the test was written and why it was chosen.

Runtime (2 cores): about 2 s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from scipy.optimize import brentq

from solver.bodies import PointMass, RigidBody, ground, spinning
from solver.element import Element
from solver.equilibrium import Spin, equilibrium
from solver.forces import AppliedLoad, Gravity, Spring
from solver.integrators import make_integrator
from solver.joints import Prismatic, Revolute
from solver.model import Model
from solver.modes import linearize, modes, natural_frequencies
from solver.state import StateBlock
from solver.system import System
from tests.solver.models import G, Lag, rodrigues, rolling_disc

TWO_PI = 2.0 * np.pi


def _omega(md):
    """Undamped natural circular frequencies (rad/s)."""
    return md.frequency * TWO_PI


# ---------------------------------------------------------------------------- mass–spring
def test_two_mass_chain_frequencies():
    """m1 on k1 to ground, m2 on k2 to m1 (isotropic springs: each mode three times).
    ω² are the roots of m1 m2 ω⁴ − (m1 k2 + m2 (k1 + k2)) ω² + k1 k2 = 0."""
    m1, m2, k1, k2 = 2.0, 1.0, 300.0, 100.0
    model = Model()
    a, b = model.add(PointMass("m1", m1)), model.add(PointMass("m2", m2))
    model.add(Spring("k1", None, a, stiffness=k1), Spring("k2", a, b, stiffness=k2))
    md = natural_frequencies(model)
    p = m1 * k2 + m2 * (k1 + k2)
    disc = np.sqrt(p * p - 4 * m1 * m2 * k1 * k2)
    w2 = np.array([(p - disc), (p + disc)]) / (2 * m1 * m2)
    # measured 5e-16 relative (symmetric-definite solver): roundoff
    np.testing.assert_allclose(_omega(md), np.repeat(np.sqrt(w2), 3), rtol=1e-12)
    assert md.n_infinite == 0 and np.all(md.damping_ratio == 0.0)
    # shapes: the lower mode moves both masses in phase, ratio u2/u1 = k2 / (k2 − m2 ω²)
    phi = md.shapes[:, 0].real
    s = md.linearization.system
    u1, u2 = phi[s.offset[a] : s.offset[a] + 3], phi[s.offset[b] : s.offset[b] + 3]
    i = int(np.argmax(np.abs(u1)))
    assert u2[i] / u1[i] == pytest.approx(k2 / (k2 - m2 * w2[0]), rel=1e-10)  # measured 0


def test_rigid_body_modes_reported_at_zero():
    """A spring along x only: y and z of both masses are free (four 0 Hz modes)."""
    m1, m2, k1, k2 = 2.0, 1.0, 300.0, 100.0
    model = Model()
    a, b = model.add(PointMass("m1", m1)), model.add(PointMass("m2", m2))
    kx = np.diag([1.0, 0.0, 0.0])
    model.add(Spring("k1", None, a, stiffness=k1 * kx), Spring("k2", a, b, stiffness=k2 * kx))
    md = natural_frequencies(model)
    assert len(md) == 6
    np.testing.assert_array_equal(md.frequency[:4], 0.0)
    p = m1 * k2 + m2 * (k1 + k2)
    disc = np.sqrt(p * p - 4 * m1 * m2 * k1 * k2)
    w = np.sqrt(np.array([(p - disc), (p + disc)]) / (2 * m1 * m2))
    np.testing.assert_allclose(_omega(md)[4:], w, rtol=1e-12)  # measured 1e-16
    # the zero modes move only y and z
    s = md.linearization.system
    for j in range(4):
        for body in (a, b):
            assert abs(md.shapes[s.offset[body], j]) < 1e-12


def test_damped_oscillator():
    """Spring–damper, different stiffness per axis: ζ = c / (2√(km)), ω_d = ω_n √(1 − ζ²)
    (first-order QZ path)."""
    mass, k, c = 1.0, 400.0, 3.0
    model = Model()
    pm = model.add(PointMass("pm", mass))
    kk = k * np.array([1.0, 2.0, 3.0])
    model.add(Spring("s", None, pm, stiffness=np.diag(kk), damping=c))
    md = natural_frequencies(model)
    wn = np.sqrt(kk / mass)
    zeta = c / (2 * np.sqrt(kk * mass))
    np.testing.assert_allclose(_omega(md), wn, rtol=1e-12)  # measured 3e-16
    np.testing.assert_allclose(md.damping_ratio, zeta, rtol=1e-11)  # measured 4e-16
    np.testing.assert_allclose(md.damped_frequency * TWO_PI, wn * np.sqrt(1 - zeta**2),
                               rtol=1e-12)


# ---------------------------------------------------------------------------- first-order
def test_first_order_state_in_the_modes():
    """A mass on a spring fed back through a lag: m ü = −k u − g x, τ ẋ = u − x. The
    eigenvalues are those of the 3 × 3 state matrix (one complex pair, one real root), plus
    the undamped y and z modes √(k/m); the static equilibrium solves f = 0 for x too."""
    mass, k, tau, gain, f = 2.0, 50.0, 0.3, 20.0, 3.0
    model = Model()
    pm = model.add(PointMass("pm", mass))
    model.add(Spring("s", None, pm, stiffness=k))
    model.add(AppliedLoad("push", pm, force=lambda t: (f, 0.0, 0.0)))
    lag = model.add(Lag("lag", pm, tau, gain))
    md = natural_frequencies(model)
    eq = md.equilibrium
    s = eq.system
    # equilibrium: k u + g x = F and x = u
    u = f / (k + gain)
    assert eq.q[s.offset[pm]] == pytest.approx(u, abs=1e-14)  # measured 0 (one Newton step)
    assert eq.q[s.offset[lag]] == pytest.approx(u, abs=1e-14)
    a = np.array([[0.0, 1.0, 0.0], [-k / mass, 0.0, -gain / mass], [1 / tau, 0.0, -1 / tau]])
    ev = np.linalg.eigvals(a)
    ev = np.concatenate([ev[ev.imag >= 0], [1j * np.sqrt(k / mass)] * 2])
    expected = ev[np.lexsort((np.abs(ev.imag), np.abs(ev)))]
    # measured 4e-16 (the pair is unstable: the lag feeds energy in, ζ < 0)
    np.testing.assert_allclose(md.eigenvalues, expected, rtol=1e-11)
    assert md.damping_ratio[-1] < 0


# ---------------------------------------------------------------------------- pendulums
def _pendulum(theta0=0.0, mass=1.5, arm=0.4, inertia=(0.02, 0.05, 0.04)):
    """Rigid body hanging from a revolute (axis y) at the origin, centre of mass at ``arm``."""
    model = Model()
    g0 = model.add(ground())
    c = arm * np.array([np.sin(theta0), 0.0, -np.cos(theta0)])
    rod = model.add(RigidBody("rod", mass, inertia=inertia, position=c,
                              orientation=rodrigues((0, 1, 0), -theta0)))
    model.add(Revolute("pin", g0, rod, point=(0, 0, 0), axis=(0, 1, 0)))
    model.add(Gravity((0.0, 0.0, -G)))
    return model, rod


@pytest.mark.parametrize("theta0", [0.0, 0.7])
def test_pendulum_under_gravity(theta0):
    """ω = √(m g l / I_pivot), I_pivot = I_yy + m l²; started off the bottom, Newton finds it."""
    mass, arm, iyy = 1.5, 0.4, 0.05
    model, rod = _pendulum(theta0)
    md = natural_frequencies(model)
    assert len(md) == 1 and md.equilibrium.converged
    w = np.sqrt(mass * G * arm / (iyy + mass * arm * arm))
    # measured 0 from the bottom, ≤ 2.3e-13 from 0.7 rad (5–6 Newton iterations)
    assert _omega(md)[0] == pytest.approx(w, rel=1e-11)
    q = md.equilibrium.q
    o = md.equilibrium.system.offset[rod]
    np.testing.assert_allclose(q[o : o + 3], [0.0, 0.0, -arm], atol=1e-13)  # measured 8e-15
    if theta0 == 0.0:  # already in equilibrium: no iteration, λ from least squares
        assert md.equilibrium.iterations == 0


# ---------------------------------------------------------------------------- rotors
E_HINGE, L_BLADE, M_BLADE = 0.5, 7.5, 116.5


def _blade(omega, axis, gravity=None, frame=None, centre=(0.0, 0.0, 0.0)):
    """Uniform thin blade (rod along x, inertia (0, mL²/12, mL²/12)) hinged at radius e on a
    hub spinning at ``omega`` about z; everything placed by ``frame`` and ``centre``."""
    e, length, m = E_HINGE, L_BLADE, M_BLADE
    frame = np.eye(3) if frame is None else frame
    c0 = np.asarray(centre, dtype=float)
    model = Model()
    hub = model.add(spinning("hub", omega, axis=frame[:, 2], center=c0))
    blade = model.add(RigidBody("blade", m, inertia=(0.0, m * length**2 / 12, m * length**2 / 12),
                                position=c0 + frame @ [e + length / 2, 0, 0], orientation=frame))
    model.add(Revolute("hinge", hub, blade, point=c0 + frame @ [e, 0, 0], axis=frame @ axis))
    if gravity is not None:
        model.add(Gravity(gravity))
    return model, hub, blade


@pytest.mark.parametrize("omega", [10.0, 27.0])
def test_flap_frequency_of_hinged_blade(omega):
    """Rotating-frame flap frequency ν² = 1 + 3e/(2L) per rev (e hinge radius, L blade length
    from the hinge)."""
    model, hub, _ = _blade(omega, (0.0, 1.0, 0.0))
    md = natural_frequencies(model, spin=Spin.from_body(hub))
    nu = np.sqrt(1 + 1.5 * E_HINGE / L_BLADE)
    assert len(md) == 1
    assert _omega(md)[0] / omega == pytest.approx(nu, rel=1e-12)  # measured 4e-16


@pytest.mark.parametrize("omega", [0.0, 10.0, 27.0])
def test_lag_frequency_of_hinged_blade(omega):
    """Rotating-frame lag frequency ν² = 3e/(2L) per rev; at Ω = 0 a neutral 0 Hz mode."""
    model, _, _ = _blade(omega, (0.0, 0.0, 1.0))
    md = natural_frequencies(model, spin=Spin(omega))
    assert len(md) == 1
    assert _omega(md)[0] == pytest.approx(omega * np.sqrt(1.5 * E_HINGE / L_BLADE),
                                          rel=1e-12, abs=0.0)  # measured 7e-17; Ω = 0: exactly 0


def test_flap_droop_under_gravity():
    """Gravity along the axis: the blade droops to β* with
    Ω² sin β (e S + I cos β) + g S cos β = 0 (S = mL/2, I = mL²/3 about the hinge), and
    flaps at ν² = [Ω²(cos β (e S + I cos β) − I sin² β) − g S sin β] / I about it."""
    omega = 5.0
    model, _, blade = _blade(omega, (0.0, 1.0, 0.0), gravity=(0.0, 0.0, -G))
    md = natural_frequencies(model, spin=Spin(omega))
    e, length, m = E_HINGE, L_BLADE, M_BLADE
    s1, i1 = m * length / 2, m * length**2 / 3

    def moment(b):
        return omega**2 * np.sin(b) * (e * s1 + i1 * np.cos(b)) + G * s1 * np.cos(b)

    beta = brentq(moment, -1.0, 0.0, xtol=1e-15)
    eq = md.equilibrium
    o = eq.system.offset[blade]
    d1 = eq.q[o + 3 : o + 6]
    assert np.arctan2(d1[2], d1[0]) == pytest.approx(beta, rel=1e-12)  # measured 2e-16
    assert eq.iterations >= 3  # a genuinely nonlinear solve from β = 0 (4 iterations)
    k = (omega**2 * (np.cos(beta) * (e * s1 + i1 * np.cos(beta)) - i1 * np.sin(beta) ** 2)
         - G * s1 * np.sin(beta))
    assert _omega(md)[0] == pytest.approx(np.sqrt(k / i1), rel=1e-11)  # measured 2e-16


TILTED = rodrigues((1.0, -2.0, 0.5), 0.9)


@pytest.mark.parametrize("omega", [10.0, 30.0])
@pytest.mark.parametrize("placed", ["z", "tilted"])
def test_centrifugal_pendulum(omega, placed):
    """Point mass (zero-inertia body) on a revolute at radius c, arm l, in the plane of
    rotation: ω = Ω √(c/l); also about a tilted axis through an offset centre (the Ω̂² term off
    the mass pattern, positions turned about the origin)."""
    c, arm, mass = 0.4, 0.05, 1.3
    frame, centre = (np.eye(3), np.zeros(3)) if placed == "z" else (TILTED, (0.3, -0.2, 1.0))
    model = Model()
    hub = model.add(spinning("hub", omega, axis=frame[:, 2], center=centre))
    bob = model.add(RigidBody("bob", mass, position=centre + frame @ [c + arm, 0, 0],
                              orientation=frame))
    model.add(Revolute("pin", hub, bob, point=centre + frame @ [c, 0, 0], axis=frame[:, 2]))
    md = natural_frequencies(model, spin=Spin(omega, frame[:, 2], centre))
    assert len(md) == 1
    assert _omega(md)[0] == pytest.approx(omega * np.sqrt(c / arm), rel=1e-11)  # measured 2e-15
    assert md.equilibrium.residual < 1e-9 * mass * omega**2 * (c + arm)  # measured 1e-16 rel.


@pytest.mark.parametrize("omega", [5.0, 30.0])
def test_gyroscopic_splitting(omega):
    """Point mass on an isotropic spring at the spin axis: in the rotating frame the in-plane
    frequencies split to |ω_n − Ω| and ω_n + Ω, out of plane ω_n (gyroscopic QZ path)."""
    k, mass = 400.0, 1.0
    wn = np.sqrt(k / mass)
    model = Model()
    hub = model.add(spinning("hub", omega))
    pm = model.add(PointMass("pm", mass))
    model.add(Spring("s", hub, pm, stiffness=k, rest=(0, 0, 0)))
    md = natural_frequencies(model, spin=Spin(omega))
    np.testing.assert_allclose(_omega(md), sorted([abs(wn - omega), wn, wn + omega]),
                               rtol=1e-12)  # measured 9e-16
    np.testing.assert_allclose(md.damping_ratio, 0.0, atol=1e-12)  # measured 2e-16


# ---------------------------------------------------------------------------- nonholonomic
def test_rolling_disc_in_circular_track():
    """Disc rolling without slip inside a circular track (nonholonomic rolling and arc-length
    rows): ω² = 2g / (3(R − r)); the free arc length and disc angle are neutral (0 Hz)."""
    big_r, r = 1.0, 0.25
    model, *_ = rolling_disc(0.3, big_r, r)
    md = natural_frequencies(model)  # starts 0.3 rad up the track
    np.testing.assert_array_equal(md.frequency[:2], 0.0)
    # measured 4e-16 (the equilibrium takes 5 minimum-norm steps: s is neutral)
    assert _omega(md)[2] == pytest.approx(np.sqrt(2 * G / (3 * (big_r - r))), rel=1e-11)
    assert md.fractions(2)["disc"] == pytest.approx(1.0)  # the link is massless


# ---------------------------------------------------------------------------- equilibria
def test_spring_under_ramped_load():
    """Linear spring k under a load ramped F(t) = t F: x = F/k at t = 1, one Newton step per
    continuation time (linear problem)."""
    k, f = 100.0, np.array([5.0, -3.0, 2.0])
    model = Model()
    pm = model.add(PointMass("mass", 2.0, position=(1.0, 0.0, 0.0)))
    model.add(Spring("k", None, pm, point=(1.0, 0.0, 0.0), stiffness=k))
    model.add(AppliedLoad("load", pm, force=lambda t: t * f))
    eq = equilibrium(model, t=[0.25, 0.5, 0.75, 1.0])
    assert eq.converged and eq.iterations == 4 and eq.t == 1.0
    np.testing.assert_allclose(eq.q - [1.0, 0.0, 0.0], f / k, atol=1e-15)  # measured 4e-17
    assert eq.residual < 1e-12  # measured 0


def _slider(omega, k=1000.0, mass=2.0):
    """Slider on a radial prismatic in a hub spinning at Ω, zero-length spring to the hub point
    at r = 1: k (r − 1) = m Ω² r, r = k / (k − m Ω²)."""
    model = Model()
    hub = model.add(spinning("hub", omega))
    sl = model.add(RigidBody("slider", mass, inertia=(0.01, 0.02, 0.03), position=(1, 0, 0)))
    model.add(Prismatic("radial", hub, sl, point=(1.0, 0.0, 0.0), axis=(1.0, 0.0, 0.0)))
    model.add(Spring("spring", hub, sl, point=(1.0, 0.0, 0.0), stiffness=k, rest=(0, 0, 0)))
    return model, hub, sl


@pytest.mark.parametrize("t", [0.0, 0.3])
def test_relative_equilibrium_is_steady_in_time(t):
    """The relative equilibrium of the slider is at r = k/(k − mΩ²), and the integrator started
    there with v* stays there up to its own O(h²) error (the chord of a discrete circular
    motion), which vanishes with h: the residual is the integrators' force balance."""
    omega, k, mass = 10.0, 1000.0, 2.0
    model, _, sl = _slider(omega, k, mass)
    eq = equilibrium(model, t=t, spin=Spin(omega))
    s = eq.system
    o = s.offset[sl]
    r = k / (k - mass * omega**2)
    x = eq.q[o : o + 3]
    np.testing.assert_allclose(x, r * np.array([np.cos(omega * t), np.sin(omega * t), 0.0]),
                               atol=1e-13)  # measured 0
    assert eq.residual < 1e-10 * mass * omega**2 * r  # measured 9e-14 N of 250 N
    np.testing.assert_allclose(eq.velocity[o : o + 3], np.cross([0, 0, omega], x), atol=1e-12)
    drift = []
    for h in (1e-3, 5e-4):
        integ = make_integrator(s, "ep", h, t0=t, q0=eq.q, v0=eq.velocity)
        dev = 0.0
        for _ in range(round(0.02 / h)):
            assert integ.step().converged
            dev = max(dev, abs(np.linalg.norm(integ.q[o : o + 3]) - r))
        drift.append(dev)
    # measured 4.1e-7 m and 1.03e-7 m over 0.02 s: ratio 4.00, second order in h
    assert drift[0] < 1e-6
    assert 3.8 < drift[0] / drift[1] < 4.2


def test_linearize_fd_matches_analytic():
    """The analytic tangent blocks agree with central differences of the force balance (flap
    droop: gravity, constraint Hessian, spin terms)."""
    model, _, _ = _blade(5.0, (0.0, 1.0, 0.0), gravity=(0.0, 0.0, -G))
    eq = equilibrium(model, spin=Spin(5.0))
    a = linearize(eq.system, eq.q, eq.lam, eq.t, eq.spin)
    b = linearize(eq.system, eq.q, eq.lam, eq.t, eq.spin, fd_step=1e-6)
    assert np.abs(a.K - b.K).max() < 1e-8 * np.abs(a.K).max()  # measured 1.4e-12
    wa, wb = modes(a).frequency, modes(b).frequency
    np.testing.assert_allclose(wa, wb, rtol=1e-9)  # measured 7e-13


# ---------------------------------------------------------------------------- errors
def test_spin_input_is_checked():
    with pytest.raises(ValueError, match="spin axis must be a nonzero 3-vector"):
        Spin(10.0, axis=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="finite"):
        Spin(np.inf)
    with pytest.raises(ValueError, match="origin"):
        Spin(1.0, origin=(0.0, 1.0))


@pytest.mark.parametrize("spin", [Spin(11.0), Spin(10.0, axis=(0.0, 0.1, 1.0)),
                                  Spin(10.0, origin=(0.1, 0.0, 0.0)), Spin(0.0)])
def test_spin_inconsistent_with_hub_names_it(spin):
    model, _, _ = _slider(10.0)
    with pytest.raises(ValueError, match="'hub' does not move with the spin"):
        equilibrium(model, spin=spin)


def test_asymmetric_gravity_is_named():
    model, _, _ = _blade(10.0, (0.0, 1.0, 0.0), gravity=(G, 0.0, 0.0))
    with pytest.raises(ValueError, match="'gravity' is not symmetric about the spin axis"):
        equilibrium(model, spin=Spin(10.0))


def test_modes_of_spinning_model_need_a_spin():
    model, _, _ = _blade(10.0, (0.0, 1.0, 0.0))
    with pytest.raises(ValueError, match="prescribed body 'hub' move"):
        natural_frequencies(model)


def test_newton_failure_names_the_culprit():
    """A load along y on a mass held only along x: no equilibrium; the message names the
    coordinate and the singular tangent."""
    model = Model()
    pm = model.add(PointMass("mass", 1.0))
    model.add(Spring("k", None, pm, stiffness=np.diag([100.0, 0.0, 0.0])))
    model.add(AppliedLoad("push", pm, force=lambda t: (1.0, 2.0, 0.0)))
    eq = equilibrium(model, max_iter=5)
    assert not eq.converged
    assert "'mass' (coordinate 1)" in eq.message and "singular" in eq.message
    with pytest.raises(RuntimeError, match="no equilibrium to linearize about"):
        natural_frequencies(model, max_iter=5)


def test_unclassified_state_block_cannot_spin():
    """A second-order block of 6 coordinates does not say which 3-vectors are positions."""

    @dataclass(eq=False)
    class Pair(Element):
        name: str

        def states(self):
            return [StateBlock(self, SECOND_KIND, 6, mass=np.eye(6))]

    SECOND_KIND = "second"
    model = Model()
    model.add(Pair("pair"))
    with pytest.raises(ValueError, match=r"'pair'.*StateBlock\.positions"):
        equilibrium(model, spin=Spin(1.0))
    assert np.array_equal(StateBlock(None, "second", 6, positions=[True, False]).positions,
                          [True] * 3 + [False] * 3)
    with pytest.raises(ValueError, match="whole 3-vectors"):
        StateBlock(None, "second", 6, positions=[True, False, True, True, True, True])


def test_system_reused():
    """equilibrium and natural_frequencies accept an assembled System."""
    model, _ = _pendulum()
    s = System(model)
    assert natural_frequencies(s).linearization.system is s


# ---------------------------------------------------------------------------- solver paths
def test_massless_node_is_condensed():
    """Two springs in series through a massless point: ω² = k1 k2 / ((k1 + k2) m); the
    massless coordinates are infinite eigenvalues, dropped."""
    k1, k2, m = 300.0, 100.0, 2.0
    model = Model()
    p, b = model.add(PointMass("massless", 0.0)), model.add(PointMass("mass", m))
    model.add(Spring("k1", None, p, stiffness=k1), Spring("k2", p, b, stiffness=k2))
    md = natural_frequencies(model)
    np.testing.assert_allclose(_omega(md), np.sqrt(k1 * k2 / ((k1 + k2) * m)), rtol=1e-12)
    # measured 0
    assert len(md) == 3 and md.n_infinite == 3


def test_maxwell_element():
    """Mass on a spring in series with a dashpot to ground (massless node between them):
    s (m c s² + m k s + c k) = 0 — the free drift of the dashpot is a 0 Hz mode, the rest a
    damped pair (first-order behaviour of a massless damped coordinate)."""
    k, c, m = 100.0, 20.0, 1.0
    model = Model()
    p, b = model.add(PointMass("node", 0.0)), model.add(PointMass("mass", m))
    model.add(Spring("dashpot", None, p, damping=c), Spring("spring", p, b, stiffness=k))
    md = natural_frequencies(model)
    roots = np.roots([m * c, m * k, c * k])
    pair = roots[roots.imag > 0][0]
    assert len(md) == 6
    np.testing.assert_array_equal(md.frequency[:3], 0.0)
    np.testing.assert_allclose(md.eigenvalues[3:], pair, rtol=1e-12)  # measured 9e-16


def test_lowest_modes_of_a_large_model():
    """Fixed–free chain of N = 110 equal masses, springs k, a dashpot c to ground on each:
    ω_j = 2√(k/m) sin((2j − 1)π / (2(2N + 1))), s = −c/2m ± i√(ω² − (c/2m)²). Asking for a
    few modes uses shift-invert Arnoldi (first-order form of 660 unknowns)."""
    n_masses, m, k, c = 110, 1.0, 1.0e4, 0.5
    model = Model()
    prev = None
    for i in range(n_masses):
        p = model.add(PointMass(f"p{i}", m))
        model.add(Spring(f"k{i}", prev, p, stiffness=k), Spring(f"c{i}", None, p, damping=c))
        prev = p
    md = natural_frequencies(model, n=6)
    j = np.arange(1, 3)
    w = 2 * np.sqrt(k / m) * np.sin((2 * j - 1) * np.pi / (2 * (2 * n_masses + 1)))
    s = -c / (2 * m) + 1j * np.sqrt(w**2 - (c / (2 * m)) ** 2)
    assert len(md) == 6 and md.n_infinite is None
    np.testing.assert_allclose(md.eigenvalues, np.repeat(s, 3), rtol=1e-11)  # measured 9e-14


def test_massless_unrestrained_directions_are_removed():
    """A massless point that nothing holds enters no equation: the equilibrium takes the
    minimum-norm step (none), the modes drop its three directions and keep the oscillator."""
    k, m = 100.0, 4.0
    model = Model()
    model.add(PointMass("loose", 0.0))
    b = model.add(PointMass("mass", m))
    model.add(Spring("k", None, b, stiffness=k))
    md = natural_frequencies(model)
    assert md.equilibrium.iterations == 0
    assert md.n_undetermined == 3 and len(md) == 3
    np.testing.assert_allclose(_omega(md), np.sqrt(k / m), rtol=1e-12)  # measured 0
