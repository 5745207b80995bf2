"""Fourth-order symmetric composition of the ep scheme (solver/composition.py) against closed
forms: the order on a damped oscillator and on the nonlinear pendulum, exact energy balance,
and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from solver.composition import COMPOSITIONS, Composed
from solver.integrators import StepInfo, make_integrator
from solver.system import System
from tests.solver.models import feedback_oscillator, oscillator, pendulum, pendulum_period


def _composed(model, h: float, method: str | None, tol: float = 1e-13):
    integ = make_integrator(System(model), "ep", h, tol=tol)
    return integ if method is None else Composed(integ, method)


def _run(integ, steps: int):
    for _ in range(steps):
        info = integ.step()
        assert info.converged, info.message
    return integ


def test_weights_cancel_the_third_order_term():
    """Palindromic, Σγ = 1 and Σγ³ = 0 (the conditions for order 4), to roundoff."""
    for g in COMPOSITIONS.values():
        g = np.array(g)
        np.testing.assert_allclose(g, g[::-1], rtol=0, atol=0)
        assert abs(g.sum() - 1.0) < 1e-15
        assert abs((g**3).sum()) < 1e-15


def _oscillator_error(method, steps, m=1.0, k=4.0, c=0.2, v0=1.0, t_end=3.0):
    """|x(t_end) − exact| of the damped oscillator m ẍ + c ẋ + k x = 0, x(0) = 0,
    ẋ(0) = v0: x = v0/ω_d e^{−ζωt} sin ω_d t."""
    integ = _run(_composed(oscillator(m, k, c, v0), t_end / steps, method), steps)
    w = np.sqrt(k / m)
    z = c / (2 * np.sqrt(k * m))
    wd = w * np.sqrt(1 - z * z)
    exact = v0 / wd * np.exp(-z * w * t_end) * np.sin(wd * t_end)
    return abs(integ.q[0] - exact)


@pytest.mark.parametrize("method", sorted(COMPOSITIONS))
def test_fourth_order_on_a_damped_oscillator(method):
    """The composed ep is of order 4 on a damped linear oscillator (ω = 2 rad/s, ζ = 5 %,
    3 s); the plain ep of order 2. Measured orders log2(e_h/e_{h/2}) for 40 → 80 → 160 steps:
    yoshida 3.98, 3.99 (errors 7.3e-5 … 2.9e-7 m), suzuki 4.00, 4.00 (1.0e-6 … 4.1e-9 m: 70
    times smaller than yoshida's at 5/3 the substeps), plain ep 2.00, 2.00 (4.1e-3 m at 40)."""
    for m, order in ((method, 4), (None, 2)):
        e = [_oscillator_error(m, n) for n in (40, 80, 160)]
        ratios = np.log2(np.array(e[:-1]) / np.array(e[1:]))
        np.testing.assert_allclose(ratios, order, atol=0.05)


@pytest.mark.parametrize("method", sorted(COMPOSITIONS))
def test_fourth_order_on_the_pendulum_and_energy_exact(method):
    """Rod pendulum released at 90° (a revolute joint: constraints and multipliers): after one
    exact period (4K(k)/ω0) the composed scheme is back at its turning point, at rest: its
    velocity there (first order in the phase error, where the position is second order) has
    an error of order 4 (measured 3.93 yoshida, 3.99 suzuki, 40 → 80 steps), and its energy
    is constant to roundoff over every step (each ep substep is exactly conservative;
    measured drift ≤ 4.4e-14 J)."""
    theta0 = np.radians(90.0)
    period = pendulum_period(theta0)
    errs = []
    for n in (40, 80):
        integ = _composed(pendulum(theta0), period / n, method)
        e0 = integ.energy()
        drift = 0.0
        for _ in range(n):
            assert integ.step().converged
            drift = max(drift, abs(integ.energy() - e0))
        errs.append(np.abs(integ.v).max())
        assert drift <= 1e-12 * 5.0  # the rod's energy scale: m g L/2 ≈ 4.9 J
    assert 3.8 <= np.log2(errs[0] / errs[1]) <= 4.3
    assert integ.n_steps == 80 and integ.n_substeps == 80 * len(COMPOSITIONS[method])


def test_nonsymmetric_schemes_and_unknown_methods_refused():
    system = System(oscillator())
    with pytest.raises(ValueError, match=r"symmetric scheme.*galpha"):
        Composed(make_integrator(system, "galpha", 0.1), "suzuki")
    with pytest.raises(ValueError, match="composition = 'rk4'"):
        Composed(make_integrator(system, "ep", 0.1), "rk4")


def test_delayed_feedback_refused():
    """A delay line records the converged steps in time order; a backward substep would
    corrupt it, so a model with delayed feedback cannot be composed."""
    model, _ = feedback_oscillator(1.0, feedback=True)
    with pytest.raises(ValueError, match="delayed feedback"):
        Composed(make_integrator(System(model), "ep", 0.01), "suzuki")


def test_failed_substep_leaves_the_step_undone():
    """A substep that fails (here the third) takes the state, the time and the booked work back
    to the step's start, and the message names the substep."""
    integ = _run(_composed(oscillator(c=0.3), 0.05, "suzuki"), 3)
    q0, v0, t0, w0 = integ.q.copy(), integ.v.copy(), integ.t, integ.work
    inner_step, calls = integ._inner.step, []

    def failing_step():
        calls.append(1)
        return inner_step() if len(calls) < 3 else StepInfo(False, 30, 1, "Newton diverged")

    integ._inner.step = failing_step
    info = integ.step()
    assert not info.converged and "substep 3 of 5" in info.message
    assert integ.t == t0 and integ.work == w0 and integ.n_steps == 3
    np.testing.assert_array_equal(integ.q, q0)
    np.testing.assert_array_equal(integ.v, v0)


def test_state_and_restore_round_trip():
    """A restored composed integrator repeats the same steps (its substep histories are reset
    with the state, as a fresh integrator's are)."""
    a = _composed(oscillator(c=0.3), 0.05, "suzuki")
    s0 = a.state()
    _run(a, 10)
    q10 = a.q.copy()
    a.restore(s0)
    _run(a, 10)
    np.testing.assert_allclose(a.q, q10, rtol=0, atol=1e-14)
