"""The ``ed`` scheme (DG(1) energy decaying) against its analysis.

* linear oscillator: the amplification is the (1, 2) Padé approximant of e^{iωh}
  (1 + z/3)/(1 − 2z/3 + z²/6), z = iωh: third order, L-stable;
* a two-mass chain: a fast mode with ωh = 12 loses 99 % of its amplitude within 5 steps while
  the slow mode keeps it;
* conservative constrained nonlinear systems (heavy top, collar, stiff elastic pivot, a
  torsion-spring pendulum): energy never increases, from fine steps to ωh ≫ 1;
* a driver, dampers and an applied load: the exact balance E_b − E_i = W − D with the
  numerical dissipation D ≥ 0 at every step;
* a nonlinear slow mode: energy lost per period of order h³ and period error of order h²
  against an independent ODE solution (scipy ``solve_ivp``).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from solver.bodies import PointMass, RigidBody, ground, spinning
from solver.forces import AppliedLoad, Gravity, RelativeRotation, Spring
from solver.integrators import make_integrator
from solver.joints import Revolute
from solver.model import Model
from solver.simulation import simulate
from solver.system import System
from tests.solver.models import (
    G,
    collar_on_cycloid,
    fitted_roots,
    heavy_top,
    hub_rolling_disc,
    oscillator,
    rodrigues,
    zero_crossings,
)


def pade12(z: complex) -> complex:
    """DG(1)'s amplification of y' = λy at z = λh."""
    return (1 + z / 3) / (1 - 2 * z / 3 + z * z / 6)


def march(model, h: float, steps: int):
    """Energy E, booked work W and numerical dissipation D after each step (J)."""
    integ = make_integrator(System(model), "ed", h)
    out = [(integ.energy(), integ.work, integ.dissipation)]
    for _ in range(steps):
        info = integ.step()
        assert info.converged, info.message
        out.append((integ.energy(), integ.work, integ.dissipation))
    return np.array(out).T


# ------------------------------------------------------------------------------ linear
@pytest.mark.parametrize("wh", [0.1, 1.0, 10.0, 1000.0])
def test_linear_amplification_is_the_pade_approximant(wh):
    steps = 25 if wh >= 10 else 400
    sim = simulate(oscillator(), wh * steps, wh, scheme="ed", reactions=False)
    assert sim.converged, sim.message
    ds = sim.dataset
    x, v, e = ds.position.values[:, 0, 0], ds.velocity.values[:, 0, 0], ds.energy.values
    n = 8 if wh >= 1000 else steps  # past 8 steps at ωh = 1000 the motion is below roundoff
    roots = fitted_roots([x[:n], v[:n]], 2)
    r = pade12(1j * wh)
    # measured: |fitted − Padé| ≤ 4e-15 (the scheme is linear here, the fit exact)
    assert np.abs(np.sort_complex(roots) - np.sort_complex([r, r.conjugate()])).max() <= 1e-9
    assert np.diff(e).max() <= 0.0  # strictly decaying (measured: every step)


def two_mass_chain(k_slow: float, k_fast: float, v0: tuple[float, float]):
    """Masses 1 kg on a line: ground —k_slow— m1 —k_fast— m2 (zero-length vector springs)."""
    m1 = PointMass("m1", 1.0, velocity=(v0[0], 0, 0))
    m2 = PointMass("m2", 1.0, velocity=(v0[1], 0, 0))
    mod = Model()
    mod.add(m1, m2, Spring("slow", None, m1, stiffness=k_slow),
            Spring("fast", m1, m2, stiffness=k_fast))
    return mod


def test_fast_mode_loses_99_percent_within_five_steps():
    k1, k2, h = 1.0, 7.2e3, 0.1  # ω ≈ 0.71 and ≈ 120 rad/s: ωh ≈ 0.07 and 12
    kmat = np.array([[k1 + k2, -k2], [-k2, k2]])
    w2, modes = np.linalg.eigh(kmat)
    wh = np.sqrt(w2) * h
    v0 = modes[:, 0] + modes[:, 1]  # both modes, 1 m/s each
    sim = simulate(two_mass_chain(k1, k2, tuple(v0)), 5 * h, h, scheme="ed", reactions=False)
    assert sim.converged, sim.message
    x = sim.dataset.position.values[:, :, 0]
    v = sim.dataset.velocity.values[:, :, 0]
    # modal amplitude √(η̇² + ω²η²)/ω... as velocity amplitude: √(η̇² + ω² η²)
    eta, deta = x @ modes, v @ modes
    amp = np.sqrt(deta**2 + w2 * eta**2)
    fast, slow = amp[:, 1] / amp[0, 1], amp[:, 0] / amp[0, 0]
    assert wh[1] >= 10
    # theory |R(iωh)|⁵ = 4.8e-4 at ωh = 12.0; measured the same
    assert fast[5] <= 0.01
    assert fast[5] == pytest.approx(abs(pade12(1j * wh[1])) ** 5, rel=1e-6)
    # the slow mode keeps its amplitude but for the scheme's O((ωh)⁴) loss: 1.7e-6 in 5 steps
    assert slow[5] == pytest.approx(abs(pade12(1j * wh[0])) ** 5, rel=1e-9)


# ------------------------------------------------------------------- nonlinear, conservative
def elastic_pivot_pendulum(theta0: float, k: float, m: float = 1.0, length: float = 1.0):
    """A rod (m, L) whose end hangs from the ground on a stiff isotropic spring (zero rest
    length) under gravity: a slow nonlinear swing on fast spring modes (ω ≥ √(k/m))."""
    c = np.array([np.sin(theta0), -np.cos(theta0), 0.0]) * length / 2
    j = m * length**2 / 12
    rod = RigidBody("rod", m, inertia=(j, 1e-2 * j, j), position=c,
                    orientation=rodrigues((0, 0, 1), theta0))
    mod = Model()
    mod.add(rod, Spring("pivot", None, rod, point=(0, 0, 0), stiffness=k), Gravity((0, -G, 0)))
    return mod


def torsion_pendulum(theta0: float, k: float = 20.0, m: float = 1.0, r: float = 0.5):
    """Disc (m, J = m r²/2 about z) on a revolute at the origin, its centre r off the axis, with
    a torsion spring k to the ground, neutral hanging down:
    (J + m r²) θ̈ = −k θ − m g r sin θ."""
    g0 = ground()
    c = np.array([np.sin(theta0), -np.cos(theta0), 0.0]) * r
    disc = RigidBody("disc", m, inertia=(0.25 * m * r * r, 0.25 * m * r * r, 0.5 * m * r * r),
                     position=c, orientation=rodrigues((0, 0, 1), theta0))
    mod = Model()
    mod.add(g0, disc, Revolute("pin", g0, disc, point=(0, 0, 0), axis=(0, 0, 1)),
            RelativeRotation("spring", None, disc, axis=(0, 0, 1), stiffness=k, phi0=-theta0),
            Gravity((0, -G, 0)))
    return mod


CONSERVATIVE = {
    # name: (model, step sizes, steps); the heavy top spins at 150 rad/s (ωh up to 3)
    "heavy top": (lambda: heavy_top()[0], [1e-4, 1e-3, 2e-2], 100),
    # the pivot spring's ω = 1e4 rad/s: ωh from 0.1 to 1000
    "elastic pivot": (lambda: elastic_pivot_pendulum(np.radians(90), 1e8), [1e-5, 1e-3, 0.1],
                      100),
    "torsion pendulum": (lambda: torsion_pendulum(np.radians(90)), [1e-3, 0.02, 0.1], 100),
    "collar cycloid": (lambda: collar_on_cycloid(np.radians(60.0)), [1e-3, 0.05, 0.2], 100),
}


@pytest.mark.parametrize("name", list(CONSERVATIVE))
def test_conservative_energy_never_increases(name):
    build, steps, n = CONSERVATIVE[name]
    for h in steps:
        e, w, d = march(build(), h, n)
        scale = max(np.abs(e).max(), G)
        # measured max step increase ≤ 1.3e-15 of the scale: roundoff
        assert np.diff(e).max() <= 1e-13 * scale, (h, np.diff(e).max())
        assert np.abs(w).max() <= 1e-12 * scale  # no work: roundoff (measured ≤ 5e-12 J)
        # and the balance: what E lost is the numerical dissipation (measured ≤ 1e-14)
        assert np.abs(e + d - e[0]).max() <= 1e-12 * scale, h


# ------------------------------------------------------------------- driver, damper, load
def driven_damped_loaded():
    """The elastic-pivot rod hung from a hub spun at a prescribed 3 rad/s (a driver), with a
    damper in the pivot spring, a rotational damper between hub and rod, and a force at the
    rod's lower end."""
    hub = spinning("hub", 3.0)
    th = np.radians(60.0)
    rot = rodrigues((0, 0, 1), th)
    c = rot @ np.array([0.0, -0.5, 0.0])
    rod = RigidBody("rod", 1.0, inertia=(1 / 12, 1e-3 / 12, 1 / 12), position=c,
                    orientation=rot)
    mod = Model()
    mod.add(hub, rod, Spring("pivot", hub, rod, point=(0, 0, 0), stiffness=1e6, damping=50.0),
            RelativeRotation("drag", hub, rod, axis=(0, 0, 1), damping=0.5),
            AppliedLoad("push", rod, force=lambda t: (5 * np.cos(7 * t), 5 * np.sin(5 * t), 0),
                        point=2 * c),
            Gravity((0, -G, 0)))
    return mod


@pytest.mark.parametrize("h", [1e-3, 1e-2, 3e-2])  # pivot ωh = 1, 10, 30
def test_balance_with_driver_dampers_and_load(h):
    e, w, d = march(driven_damped_loaded(), h, 200)
    scale = G
    assert np.abs(w).max() > 1e-3 * scale  # the driver, dampers and load do work
    # E_b − E_i = ΔW − ΔD exactly (measured ≤ 2e-15 of the scale) with ΔD ≥ 0 every step
    assert np.abs(e - w + d - e[0]).max() <= 1e-12 * scale
    assert np.diff(d).min() >= 0.0
    assert np.diff(e - w).max() <= 1e-13 * scale


def test_rolling_on_spinning_hub_balance():
    """A bifilar pin in miniature (nonholonomic rolling, a curve joint, rolling resistance) in
    the hole of its prescribed hub."""
    model, _hub, _disc = hub_rolling_disc(np.radians(20.0), damping=1e-4)
    period = 2 * np.pi / 27.0 / 3  # about the swing's period (tuning order ≈ 3)
    for n in (10, 200):
        e, w, d = march(model, period / n, 100)
        scale = np.abs(e).max()
        assert np.abs(w).max() > 1e-3 * scale
        assert np.abs(e - w + d - e[0]).max() <= 1e-12 * scale  # measured ≤ 3.8e-15
        assert np.diff(d).min() >= 0.0


# ---------------------------------------------------------------------- slow-mode accuracy
def test_slow_mode_energy_loss_and_period_orders():
    theta0, k, m, r = np.radians(90), 20.0, 1.0, 0.5
    inertia = 1.5 * m * r * r

    def rhs(_t, y):
        return [y[1], (-k * y[0] - m * G * r * np.sin(y[0])) / inertia]

    ref = solve_ivp(rhs, (0, 1.0), [theta0, 0.0], rtol=1e-12, atol=1e-12,
                    events=lambda _t, y: y[1])
    turns = ref.t_events[0]
    period = turns[turns > 1e-6][1]  # θ̇ = 0 at T/2 and T
    steps = [50, 100, 200]
    loss, perr = [], []
    for n in steps:
        sim = simulate(torsion_pendulum(theta0, k, m, r), 2.2 * period, period / n,
                       scheme="ed", reactions=False)
        assert sim.converged, sim.message
        ds = sim.dataset
        t, e = ds.time.values, ds.energy.values
        roots = zero_crossings(t, ds.angular_velocity.values[:, 0, 2], 0.25 * period)
        perr.append(abs((roots[2] - roots[0]) / period - 1))
        loss.append((e[0] - e[n]) / abs(e[0]))
    order_loss = np.log2(np.array(loss[:-1]) / loss[1:])
    order_period = np.log2(np.array(perr[:-1]) / perr[1:])
    # measured: loss per period 2.9e-3, 3.7e-4, 4.6e-5 (orders 2.98, 3.00; without the
    # end-velocity projection 1.0e-3, 1.3e-4, 1.7e-5); period error 1.7e-3, 4.3e-4, 1.1e-4
    # (orders 1.97, 1.99)
    assert order_loss.min() >= 2.8, loss
    assert order_period.min() >= 1.9, perr
    assert loss[-1] < 1e-4 and perr[-1] < 2e-4


def test_newton_matrix_matches_finite_differences():
    """ed's Newton matrix against central differences of its residual, at two iterates (the
    second assembly reuses the first one's sparse pattern), on the driven, damped, loaded
    rod: springs, dampers, a prescribed (massless) hub, constraints."""
    integ = make_integrator(System(driven_damped_loaded()), "ed", 1e-2)
    for _ in range(3):
        assert integ.step().converged
    integ._begin()
    x0 = integ._predict()
    for scale in (1.01, 0.98):
        x = x0 * scale
        jac = integ._jacobian(x).toarray()
        fd = np.zeros_like(jac)
        for j in range(len(x)):
            e = 1e-7 * max(1e-2, abs(x[j]))
            xp, xm = x.copy(), x.copy()
            xp[j] += e
            xm[j] -= e
            fd[:, j] = (integ._residual(xp) - integ._residual(xm)) / (2 * e)
        # measured 7.3e-8 and 8.0e-8 of the largest entry (finite-difference truncation)
        assert np.abs(jac - fd).max() <= 1e-6 * np.abs(fd).max()


def test_newton_matrix_keeps_one_pattern():
    """Entries that come out exactly zero (here every velocity-dependent one at rest) stay in
    the Newton matrix's pattern, so the LU refactors with the first matrix's pivot order at
    every later step: with the zeros dropped, the pattern changed from step to step on the
    rotor and every step paid a fresh SuperLU factorization (1.2 s instead of 0.1 s)."""
    integ = make_integrator(System(driven_damped_loaded()), "ed", 1e-2)
    integ._begin()
    x = integ._predict()
    moving, at_rest = integ._jacobian(x), integ._jacobian(np.zeros_like(x))
    assert np.count_nonzero(at_rest.data) < np.count_nonzero(moving.data)
    assert np.array_equal(moving.indptr, at_rest.indptr)
    assert np.array_equal(moving.indices, at_rest.indices)
    for _ in range(50):
        assert integ.step().converged
    lu = integ.lin._factors  # fresh: 0 if an earlier test left this pattern's pivot order
    assert lu.fresh <= 1 and lu.refactored >= 49


@pytest.mark.parametrize("name", ["rolling on hub", "driven rod", "heavy top"])
def test_end_velocity_is_tangent_to_the_constraints(name):
    """The step's constraint force acts through the chord only, so the rows alone leave a
    velocity component normal to the constraints undamped: it would alternate in sign from
    step to step and, fed by the aerodynamic loads, grow until Newton fails on the rotor in
    forward flight. The end velocity is projected (M-closest) onto G(q)v + ∂C/∂t = 0,
    A(q)v = 0; the projection's kinetic-energy loss is booked as numerical dissipation."""
    if name == "rolling on hub":
        model, h = hub_rolling_disc(np.radians(20.0))[0], 2 * np.pi / 27.0 / 3 / 20
    elif name == "driven rod":
        model, h = driven_damped_loaded(), 1e-2
    else:
        model, h = heavy_top()[0], 2e-2
    s = System(model)
    integ = make_integrator(s, "ed", h)
    # start off the velocity constraints: a normal component the rows cannot see
    g = s.jacobian_values(integ.q, integ.t)
    gm = np.zeros((s.mh, s.n))
    np.add.at(gm, (s.G_rows, s.G_cols), g)
    normal = np.linalg.lstsq(gm, np.ones(s.mh), rcond=None)[0]
    integ.v = integ.v + 1e-3 * normal / np.abs(normal).max() * max(1.0, np.abs(integ.v).max())
    d0 = integ.dissipation
    for _ in range(20):
        assert integ.step().converged
        rate = s.gmul(s.jacobian_values(integ.q, integ.t), integ.v) + s.constraint_rate(
            integ.q, integ.t)
        if s.mn:
            rate = np.concatenate([rate, s.amul(s.nonholonomic_values(integ.q), integ.v)])
        # measured ≤ 7e-16 of the speed scale: roundoff (without the projection: 0.04 to
        # 0.7 at these coarse steps, alternating on the driven rod)
        assert np.abs(rate).max() <= 1e-10 * max(1.0, np.abs(integ.v).max())
    assert integ.dissipation > d0
