"""A first-order element declared in a test, coupled to a pendulum, against an independent ODE.

The element is a first-order lag τ ẋ + x = u(q) whose input is the horizontal position of a
pendulum's centre of mass, u = X_c, and whose output pushes back on it with a horizontal force
F = −k x at the centre of mass. It is declared outside ``solver/`` (``tests/models.py``, shared
with the modes tests), with one declaration class and one set class: what adding a first-order
element to the library takes.

Reference: the same system in minimal coordinates (angle θ from the downward vertical),
    I_O θ̈ = −m g (L/2) sin θ − k x (L/2) cos θ,   τ ẋ = (L/2) sin θ − x,
integrated by DOP853 at rtol 1e-12.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from solver.bodies import RigidBody
from solver.model import Model
from solver.simulation import simulate
from tests.solver.models import Lag, rod_pendulum

M, L, G = 1.0, 1.0, 9.81
J_CM = M * L * L / 12.0  # slender rod about its centre
TAU, K = 0.2, 5.0  # s, N/m
THETA0 = np.radians(30.0)
T_END = 1.0


def model() -> tuple[Model, RigidBody]:
    return rod_pendulum(M, L, THETA0, lambda rod: Lag("lag", rod, TAU, K), G)


def reference(t_eval: np.ndarray) -> np.ndarray:
    """(θ, x) at t_eval from the minimal-coordinate ODE."""
    i_o = J_CM + M * (0.5 * L) ** 2

    def rhs(t, y):
        th, om, x = y
        acc = (-M * G * 0.5 * L * np.sin(th) - K * x * 0.5 * L * np.cos(th)) / i_o
        return [om, acc, (0.5 * L * np.sin(th) - x) / TAU]

    sol = solve_ivp(rhs, (0.0, t_eval[-1]), [THETA0, 0.0, 0.0], method="DOP853", rtol=1e-12,
                    atol=1e-14, t_eval=t_eval)
    return sol.y[[0, 2]].T


def run(scheme: str, h: float) -> tuple[np.ndarray, np.ndarray, object]:
    mod, rod = model()
    rec = []
    sim = simulate(mod, T_END, h, scheme=scheme, reactions=False, record_every=10**9,
                   callback=lambda integ: rec.append(
                       (integ.t, *integ.q[integ.sys.offset[rod] : integ.sys.offset[rod] + 2],
                        integ.q[integ.sys.offset[mod.elements[-1]]])),
                   record_initial=True)
    assert sim.converged, sim.message
    a = np.array(rec)
    theta = np.arctan2(a[:, 1], -a[:, 2])
    return a[:, 0], np.column_stack([theta, a[:, 3]]), sim


@pytest.mark.parametrize("scheme", ["ep", "galpha", "ed"])
def test_lag_coupled_to_pendulum_matches_independent_ode(scheme):
    errors = []
    for h in (2e-3, 1e-3):
        t, y, sim = run(scheme, h)
        ref = reference(t)
        errors.append(np.abs(y - ref).max())
        if scheme == "ep":
            # energy plus the work of the lag force is conserved exactly by ep (the lag state
            # carries no energy; its force's work is booked): measured 4.8e-13 relative after
            # 1000 steps, roundoff accumulated at the Newton tolerance
            ds = sim.dataset
            e, w = ds.energy.values, ds.work.values
            assert np.abs(e - e[0] - w).max() <= 1e-12 * np.abs(e).max()
    order = np.log2(errors[0] / errors[1])
    # measured max error in θ (rad) and x (m) at h = 2e-3 → 1e-3 s: ep 9.0e-6 → 2.25e-6,
    # galpha (ρ∞ 0.8) 1.25e-5 → 3.1e-6, ed (ρ∞ 0) 6.0e-5 → 1.5e-5; orders 2.000, 2.000, 1.985
    assert errors[1] < 2e-5, errors
    assert 1.9 < order < 2.1, (errors, order)


def test_first_order_states_are_numbered_after_the_mechanical_ones():
    from solver.system import System

    mod, rod = model()
    s = System(mod)
    assert list(s.first_order) == [s.n - 1]
    assert s.offset[rod] == 12  # ground first, then the rod
    assert s.A1[s.n - 1, s.n - 1] == TAU and s.M[s.n - 1, s.n - 1] == 0.0
    # assembling the same model twice gives the same system: the model is not written
    s2 = System(mod)
    assert s2.n == s.n and np.array_equal(s2.q0_raw, s.q0_raw)


@pytest.mark.parametrize("scheme", ["ep", "galpha", "ed"])
def test_restore_continues_exactly_on_a_rebuilt_model(scheme):
    """``state``/``restore``: 10 steps, a fresh integrator on a rebuilt model restored from
    that state, 10 more steps — the same trajectory as 20 steps of one integrator (the
    rotor's settling phase hands its state over this way). Measured: identical to roundoff."""
    from solver.integrators import make_integrator
    from solver.system import System

    h = 0.01

    def fresh():
        return make_integrator(System(model()[0]), scheme, h)

    one = fresh()
    for _ in range(20):
        assert one.step().converged
    first = fresh()
    for _ in range(10):
        assert first.step().converged
    second = fresh()
    second.restore(first.state())
    for _ in range(10):
        assert second.step().converged
    assert second.t == pytest.approx(one.t, abs=1e-12)
    np.testing.assert_allclose(second.q, one.q, rtol=0, atol=1e-11)
    np.testing.assert_allclose(second.v, one.v, rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="unknowns"):
        make_integrator(System(rod_pendulum(M, L, THETA0, lambda rod: [])[0]), scheme,
                        h).restore(first.state())
