"""Validation of the multibody solver core against analysis.

Every expected value below comes from analysis or from an independent computation written
here (elliptic-integral periods, an independent quaternion ODE solved by scipy, the
generalized-α amplification matrix, closed-form damped and torsional oscillators, finite
differences), never from the solver itself. Each tolerance is commented with the value measured
when the test was written, and why it was chosen.

Runtime (2 shared cores): the default selection takes 45–70 s; the 2-second heavy top
(≈ 45 s) and the tumbling torque-free body (≈ 12 s) are marked ``slow``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.special import ellipk

from solver.bodies import PointMass, RigidBody, ground
from solver.forces import AppliedLoad, Gravity, RelativeRotation, Spring
from solver.joints import Orientation, Planar, Prismatic, Revolute, Rigid, Spherical
from solver.model import Model
from solver.simulation import simulate
from solver.system import System
from solver.timefunctions import linear
from tests.solver.models import (
    TOP_G,
    TOP_J,
    TOP_M,
    TOP_W,
    TOP_X,
    feedback_oscillator,
    fitted_roots,
    heavy_top,
    oscillator,
    pendulum,
    pendulum_period,
    zero_crossings,
)

G = 9.81


# ---------------------------------------------------------------------------- helpers
def _hat(v):
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _rot(axis, angle):
    """Rodrigues (independent of solver.rotations)."""
    n = np.asarray(axis, dtype=float)
    k = _hat(n / np.linalg.norm(n))
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def _vee_angle(s, n):
    """Angle φ of a rotation matrix s = Rot(n, φ) about the known unit axis n."""
    sin = 0.5 * n @ np.array([s[2, 1] - s[1, 2], s[0, 2] - s[2, 0], s[1, 0] - s[0, 1]])
    cos = 0.5 * (np.trace(s) - 1.0)
    return np.arctan2(sin, cos)


def _half_period_estimate(roots):
    """Least-squares slope of crossing times against their index: half the period."""
    k = np.arange(len(roots))
    return np.polyfit(k, roots, 1)[0]


# ---------------------------------------------------------------------------- pendulum
def measured_pendulum_period(theta0, steps_per_period, scheme, record_every=1):
    """Period from the zeros of the rod's angular velocity (turning points, every T/2) over
    two full periods (t ∈ [T/2, 5T/2])."""
    t_ref = pendulum_period(theta0)
    sim = simulate(pendulum(theta0), 2.6 * t_ref, t_ref / steps_per_period, scheme=scheme,
                   reactions=False, record_every=record_every)
    assert sim.converged, sim.message
    ds = sim.dataset
    roots = zero_crossings(ds.time.values, ds.angular_velocity.values[:, 0, 2], 0.25 * t_ref)
    assert len(roots) == 5, roots
    return 2.0 * _half_period_estimate(roots), t_ref, sim


# Steps per period needed for 1e-6 (measured relative errors: 10°: 8.3e-7 at 2000,
# 90°: 7.5e-7 at 2900, 170°: 8.9e-7 at 3500; the error is (ωh)²-like, so ±10 % in N moves it
# by ±20 %). record_every = 5 does not change the crossings (checked: same errors to 4 digits
# as record_every = 1; the spline's interpolation error is O((5h)⁴)).
@pytest.mark.parametrize("amplitude_deg, steps", [(10, 2000), (90, 2900), (170, 3500)])
def test_pendulum_period_ep_fine_step(amplitude_deg, steps):
    theta0 = np.radians(amplitude_deg)
    period, t_ref, sim = measured_pendulum_period(theta0, steps, "ep", record_every=5)
    assert abs(period / t_ref - 1.0) <= 1e-6
    # same run: EP energy to roundoff (measured ≤ 3.2e-11 relative to m g L/2 over ≤ 9100 steps)
    e = sim.dataset.energy.values
    assert np.ptp(e) <= 1e-10 * (1.0 * G * 1.0 / 2)


# Observed orders at 90° from N = 100, 200, 400 steps per period: ep 2.000, galpha 1.995,
# ed 1.956 (errors ep 6.3e-4 → 3.9e-5, galpha 1.6e-3 → 1.0e-4, ed 5.8e-4 → 3.9e-5; ed has no
# jump on this rigid pendulum, only its end-velocity projection).
@pytest.mark.parametrize("scheme", ["ep", "galpha", "ed"])
def test_pendulum_period_convergence_order(scheme):
    theta0 = np.radians(90)
    steps = np.array([100, 200, 400])
    errors = []
    for n in steps:
        period, t_ref, _ = measured_pendulum_period(theta0, n, scheme)
        errors.append(abs(period / t_ref - 1.0))
    order = np.polyfit(np.log(1.0 / steps), np.log(errors), 1)[0]  # log error vs log h
    assert order >= 1.9, (scheme, errors, order)
    assert errors[-1] < 2e-3  # and the errors are small, not just converging (max 8.6e-4)


# ---------------------------------------------------------------------------- heavy top


def _quat_matrix(q):
    e0, e1, e2, e3 = q / np.linalg.norm(q)
    return np.array([
        [e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
        [2 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2 * (e2 * e3 - e0 * e1)],
        [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3],
    ])


def heavy_top_reference(t_end, tol=1e-12):
    """Independent solution: unit quaternion and body angular velocity Ω, Euler's equations
    about the fixed point, J0 Ω̇ + Ω × J0 Ω = X × Rᵀ m g, J0 = J + m(|X|² I − X Xᵀ)."""
    j0 = TOP_J + TOP_M * (TOP_X @ TOP_X * np.eye(3) - np.outer(TOP_X, TOP_X))

    def rhs(_t, y):
        q, w = y[:4], y[4:]
        r = _quat_matrix(q)
        wd = np.linalg.solve(j0, np.cross(TOP_X, r.T @ (TOP_M * TOP_G)) - np.cross(w, j0 @ w))
        qd = 0.5 * np.concatenate([[-q[1:] @ w], q[0] * w + np.cross(q[1:], w)])
        return np.concatenate([qd, wd])

    sol = solve_ivp(rhs, (0.0, t_end), np.concatenate([[1.0, 0, 0, 0], TOP_W]),
                    method="DOP853", rtol=tol, atol=tol)
    assert sol.success
    return _quat_matrix(sol.y[:4, -1])


def _director_momentum(sim_sys, body, qs, vs, inertia):
    """Angular momentum about the origin carried by the director formulation:
    x × m ẋ + Σ_αβ E_αβ d_α × ḋ_β with E = ½ tr(J) I − J (the kinetic energy is
    ½ m ẋ·ẋ + ½ Σ E_αβ ḋ_α·ḋ_β; its momentum conjugate to d_α is Σ_β E_αβ ḋ_β). This is the
    quantity the midpoint rule conserves exactly for rotation-invariant forces."""
    o = sim_sys.offset[body]
    e = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    x, xd = qs[:, o : o + 3], vs[:, o : o + 3]
    d, dd = qs[:, o + 3 : o + 12].reshape(-1, 3, 3), vs[:, o + 3 : o + 12].reshape(-1, 3, 3)
    lm = np.cross(x, body.mass * xd)
    for a in range(3):
        for b in range(3):
            lm += e[a, b] * np.cross(d[:, a], dd[:, b])
    return lm


def _run_top(t_end, h):
    mod, top = heavy_top()
    qs, vs = [], []

    def grab(integ):
        qs.append(integ.q.copy())
        vs.append(integ.v.copy())

    sim = simulate(mod, t_end, h, scheme="ep", reactions=False,
                   record_every=max(1, round(t_end / h / 50)), callback=grab)
    assert sim.converged, sim.message
    return sim, top, sim.integrator.sys, np.array(qs), np.array(vs)


def _dataset_momentum(ds, inertia, mass):
    """L = x × m v + R J Rᵀ ω from the reported position, velocity, rotation, ω."""
    x, v = ds.position.values[:, 0], ds.velocity.values[:, 0]
    r, w = ds.rotation.values[:, 0], ds.angular_velocity.values[:, 0]
    return np.cross(x, mass * v) + np.einsum("tij,jk,tlk,tl->ti", r, inertia, r, w)


def test_heavy_top_ep_half_second():
    """t_end = 0.5 s (≈ 12 spin revolutions) with h = 2e-4 and 1e-4 (≈ 3 s each)."""
    t_end = 0.5
    errors, ds_lz_spread = [], []
    for h in (2e-4, 1e-4):
        sim, top, s, qs, vs = _run_top(t_end, h)
        ds = sim.dataset
        # energy: measured 2.4e-14 relative
        e = ds.energy.values
        assert np.ptp(e) <= 1e-10 * abs(e[0])
        # vertical angular momentum about the fixed point (director form; equal to
        # System.angular_momentum to 3e-14): measured 1.3e-14 … 1.7e-14
        lm = _director_momentum(s, top, qs, vs, TOP_J)
        assert np.ptp(lm[:, 2]) <= 1e-10 * np.linalg.norm(lm[0])
        # rotation at t_end against the independent ODE solution
        r_ref = heavy_top_reference(float(ds.time.values[-1]))
        errors.append(np.abs(ds.rotation.values[-1, 0] - r_ref).max())
        # the same momentum computed from the *reported* x, v, R, ω is only conserved to O(h²)
        # (the nodal director velocities of the index-3 midpoint rule are not exactly rigid:
        # their symmetric part d_α·ḋ_β + d_β·ḋ_α is O(h²)); measured 2.5e-6 and 6.3e-7 on
        # the 50 recorded states.
        lds = _dataset_momentum(ds, TOP_J, TOP_M)
        ds_lz_spread.append(np.ptp(lds[:, 2]) / np.linalg.norm(lds[0]))
    # measured max |R − R_ref| = 5.23e-3 (h = 2e-4) and 1.31e-3 (h = 1e-4): ratio 4.00
    assert errors[1] <= 2e-3, errors
    assert 3.5 <= errors[0] / errors[1] <= 4.5, errors
    assert ds_lz_spread[1] <= 2e-6 and 3.5 <= ds_lz_spread[0] / ds_lz_spread[1] <= 4.5  # 4.00


@pytest.mark.slow
def test_heavy_top_ep_two_seconds():
    """The paper's horizon t = 2 s (10⁴ and 2·10⁴ steps)."""
    t_end = 2.0
    r_ref = heavy_top_reference(t_end)
    # the reference itself: DOP853 at 1e-12 vs 1e-13 (and, checked once while writing this
    # test, Radau at 1e-12 over 0.5 s: 8e-12; Radau over 2 s costs ~2 min)
    assert np.abs(heavy_top_reference(t_end, 1e-13) - r_ref).max() < 1e-9
    errors = []
    for h in (2e-4, 1e-4):
        sim, top, s, qs, vs = _run_top(t_end, h)
        ds = sim.dataset
        assert abs(ds.time.values[-1] - t_end) < 1e-9
        e = ds.energy.values
        assert np.ptp(e) <= 1e-10 * abs(e[0])
        lm = _director_momentum(s, top, qs, vs, TOP_J)
        assert np.ptp(lm[:, 2]) <= 1e-10 * np.linalg.norm(lm[0])
        errors.append(np.abs(ds.rotation.values[-1, 0] - r_ref).max())
    # measured max |R − R_ref| = 1.95e-2 and 4.86e-3 (ratio 4.02); energy 6.5e-14 and
    # L_z 3.1e-14 relative; ≈ 30 s in all
    assert 3.5 <= errors[0] / errors[1] <= 4.5, errors
    assert errors[1] <= 1e-2, errors


# ---------------------------------------------------------------------------- torque-free body
def _torque_free(w0, t_end, h, record_every=10):
    body = RigidBody("b", 1.0, inertia=(1.0, 2.0, 3.0), angular_velocity=w0)
    mod = Model()
    mod.add(body)
    qs, vs = [], []

    def grab(integ):
        qs.append(integ.q.copy())
        vs.append(integ.v.copy())

    sim = simulate(mod, t_end, h, scheme="ep", reactions=False, record_every=record_every,
                   callback=grab)
    assert sim.converged, sim.message
    return sim, body, np.array(qs), np.array(vs)


def _check_torque_free(w0):
    j = np.diag([1.0, 2.0, 3.0])
    sim, body, qs, vs = _torque_free(w0, 1000.0, 0.1)  # 1e4 steps at h = 0.1 s
    ds = sim.dataset
    assert len(ds.step_time) == 10001
    e = ds.energy.values
    # exact invariants of the scheme: measured 3.2e-13 (E) and 1.6e-13 (L) relative
    assert np.abs(e - e[0]).max() <= 1e-12 * e[0]
    lm = _director_momentum(sim.integrator.sys, body, qs, vs, j)
    l0 = np.linalg.norm(lm[0])
    assert np.abs(lm - lm[0]).max() <= 1e-12 * l0
    # orthonormal directors: measured 4.4e-16
    r = ds.rotation.values[:, 0]
    assert np.abs(np.einsum("tia,tib->tab", r, r) - np.eye(3)).max() <= 1e-12
    assert ds.constraint_violation.max() <= 1e-12
    # the body really tumbles / precesses (guards against a trivial run)
    assert np.ptp(ds.angular_velocity.values[:, 0, 0]) > 0.05


def test_torque_free_body_ep_invariants():
    _check_torque_free((1.0, 0.1, 0.05))


@pytest.mark.slow
def test_torque_free_body_ep_invariants_tumbling():
    """Near the unstable intermediate axis: the body flips (Dzhanibekov)."""
    _check_torque_free((0.05, 1.0, 0.1))


def test_torque_free_reported_angular_velocity_is_second_order():
    """The momentum R J Rᵀ ω built from the *reported* ω is not an exact invariant: it drifts
    by O(h² t) (measured max deviation over 50 s: 1.88e-3 at h = 0.1, 4.71e-4 at h = 0.05,
    ratio 4.00). The exact invariant is the director form above."""
    j = np.diag([1.0, 2.0, 3.0])
    dev = []
    for h in (0.1, 0.05):
        sim, _, _, _ = _torque_free((1.0, 0.1, 0.05), 50.0, h, record_every=1)
        lds = _dataset_momentum(sim.dataset, j, 1.0)
        dev.append(np.linalg.norm(lds - lds[0], axis=1).max() / np.linalg.norm(lds[0]))
    assert dev[0] <= 3e-3 and 3.5 <= dev[0] / dev[1] <= 4.5, dev


# ---------------------------------------------------------------------------- linear oscillator
def generalized_alpha_roots(wh, rho_inf):
    """Eigenvalues of the amplification matrix of Chung–Hulbert's generalized-α for
    ẍ + ω² x = 0 (state x, v, a; written out from the scheme's definition)."""
    am, af = (2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1)
    g = 0.5 + af - am
    b = 0.25 * (g + 0.5) ** 2
    w2 = wh**2  # h = 1
    lhs = np.array([[1, 0, -b], [0, 1, -g], [(1 - af) * w2, 0, 1 - am]])
    rhs = np.array([[1, 1, 0.5 - b], [0, 1, 1 - g], [-af * w2, 0, -am]])
    return np.linalg.eigvals(np.linalg.solve(lhs, rhs))


def _oscillator_response(scheme, wh, rho_inf=None, steps=None):
    steps = steps or (60 if wh >= 10 else 400)
    sim = simulate(oscillator(), wh * steps, wh, scheme=scheme, rho_inf=rho_inf, reactions=False)
    assert sim.converged, sim.message
    ds = sim.dataset
    return ds.position.values[:, 0, 0], ds.velocity.values[:, 0, 0], ds.energy.values


WH = [0.1, 1.0, 10.0, 1000.0]


@pytest.mark.parametrize("wh", WH)
def test_ep_amplification_is_unitary(wh):
    x, v, e = _oscillator_response("ep", wh)
    # energy ratio of successive steps: measured |E_{n+1}/E_n − 1| ≤ 6.7e-16
    assert np.abs(e[1:] / e[:-1] - 1.0).max() <= 1e-12
    # the roots are the midpoint rule's Cayley transform (1 − (ωh/2)² ± iωh) / (1 + (ωh/2)²)
    roots = fitted_roots([x[:60], v[:60]], 2)
    z = complex(1 - wh**2 / 4, wh) / (1 + wh**2 / 4)
    assert np.abs(np.abs(roots) - 1.0).max() <= 1e-12  # measured ≤ 2.9e-15
    assert min(abs(roots[0] - z), abs(roots[0] - z.conjugate())) <= 1e-10  # measured 1.1e-13


@pytest.mark.parametrize("wh", WH)
def test_galpha_spectral_radius(wh):
    x, v, _ = _oscillator_response("galpha", wh, rho_inf=0.5)
    n = 25 if wh >= 10 else 400  # keep samples well above roundoff for the fast-decaying cases
    rho = np.abs(fitted_roots([x[:n], v[:n]], 3)).max()
    rho_theory = np.abs(generalized_alpha_roots(wh, 0.5)).max()
    # measured rho: 0.999998, 0.989313, 0.682528, 0.507847 = theory to ≤ 1.3e-13 (the scheme is
    # linear here, so the fit is exact up to roundoff)
    assert abs(rho - rho_theory) <= 1e-9
    if wh == 1000.0:
        assert abs(rho - 0.5) <= 0.02


# The rotor's time step (studies.rotor): the frequency error of a 3P and a 4P oscillation at
# 120 steps per revolution, as its docstring quotes them (relative frequency error, numerical
# damping ratio) for ρ∞ = 0.5 (galpha, the rotor's default) and ρ∞ = 0 (ed's linear part).
@pytest.mark.parametrize("scheme, rho_inf, harmonic, error, damping", [
    ("galpha", 0.5, 3, -0.0031, 7e-5),
    ("galpha", 0.5, 4, -0.0054, 1.7e-4),
    ("galpha", 0.0, 3, -0.0107, 1.8e-3),
    ("galpha", 0.0, 4, -0.0183, 4.0e-3),
])
def test_galpha_frequency_error_at_the_rotor_step(scheme, rho_inf, harmonic, error, damping):
    wh = 2 * np.pi * harmonic / 120
    x, v, _ = _oscillator_response(scheme, wh, rho_inf=rho_inf, steps=200)
    roots = fitted_roots([x, v], 3)
    root = roots[np.argmax(roots.imag)]  # the oscillatory pair (the third root is spurious)
    theory = generalized_alpha_roots(wh, rho_inf)
    assert abs(root - theory[np.argmax(theory.imag)]) <= 1e-9
    lam = np.log(root)
    # measured: the quoted values to their last digit
    assert lam.imag / wh - 1 == pytest.approx(error, abs=0.6e-4)
    assert -lam.real / abs(lam) == pytest.approx(damping, rel=0.1, abs=1e-5)


# ed against its analysis (Padé amplification, decay, orders): test_energy_decaying.py


@pytest.mark.parametrize("steps_per_period", [
    25,
    10,  # needs the full-Newton retry of a failed fast iteration
])
def test_ed_energy_never_increases_nonlinear(steps_per_period):
    theta0 = np.radians(170)
    t_ref = pendulum_period(theta0)
    sim = simulate(pendulum(theta0), 2.2 * t_ref, t_ref / steps_per_period, scheme="ed",
                   reactions=False)
    assert sim.converged, sim.message
    e = sim.dataset.energy.values
    e_scale = 1.0 * G * 1.0 / 2
    # measured max step increase 0 (N = 25) — roundoff allowance only
    assert np.diff(e).max() <= 1e-12 * e_scale


# ---------------------------------------------------------------------------- joints
JOINT_POINT = np.array([0.1, -0.9, 0.1])
JOINT_AXIS = np.array([0.2, 0.3, 1.0]) / np.linalg.norm([0.2, 0.3, 1.0])
JOINT_KINDS = ["spherical", "revolute", "rigid", "prismatic", "planar", "orientation",
               "orientation_e1e2", "driven", "point_mass"]


def joint_model(kind):
    """Body a hangs from the ground on a spherical joint at the origin; body b is attached to
    a by the joint under test at JOINT_POINT with axis JOINT_AXIS. Off-axis initial velocities
    and angular velocities everywhere (projected onto the constraints by the solver)."""
    g0 = ground()
    a = RigidBody("a", 2.0, inertia=(0.3, 0.4, 0.5), position=(0, -0.5, 0),
                  orientation=_rot((1, 2, 3), 0.4), velocity=(0.2, -0.1, 0.4),
                  angular_velocity=(0.5, -1.0, 2.0))
    if kind == "point_mass":
        b = PointMass("b", 0.7, position=JOINT_POINT, velocity=(-0.3, 0.5, 0.1))
        joint = Spherical("j", a, b, point=JOINT_POINT)
    else:
        b = RigidBody("b", 1.5, inertia=(0.2, 0.25, 0.3), position=(0.3, -1.1, 0.2),
                      orientation=_rot((0, 1, 1), -0.7), velocity=(-0.3, 0.5, 0.1),
                      angular_velocity=(1.5, 0.7, -0.8))
        cls, kw = {
            "spherical": (Spherical, {}),
            "revolute": (Revolute, {}),
            "rigid": (Rigid, {}),
            "prismatic": (Prismatic, {}),
            "planar": (Planar, {}),
            "orientation": (Orientation, {}),
            "orientation_e1e2": (Orientation, {"axes": (0, 1)}),
            "driven": (Revolute, {"driven": linear(2.0)}),
        }[kind]
        joint = cls("j", a, b, point=JOINT_POINT, axis=JOINT_AXIS, **kw)
    mod = Model()
    mod.add(g0, a, b, Spherical("hang", g0, a, point=(0, 0, 0)), joint, Gravity((0.3, -G, 0.5)))
    return mod, a, b, joint


@pytest.mark.parametrize("kind", JOINT_KINDS)
def test_joint_constraints_and_kinematics(kind):
    mod, a, b, _ = joint_model(kind)
    sim = simulate(mod, 1.0, 0.01, scheme="ep")
    assert sim.converged, sim.message
    ds = sim.dataset
    # measured max violation ≤ 1e-15 at every step (Newton stops at 1e-14 · scale)
    assert ds.constraint_violation.max() <= 1e-10
    t = ds.time.values
    ia, ib = list(ds.body.values).index("a"), list(ds.body.values).index("b")
    xa, ra = ds.position.values[:, ia], ds.rotation.values[:, ia]
    xb, rb = ds.position.values[:, ib], ds.rotation.values[:, ib]
    rot_a = np.einsum("tij,kj->tik", ra, a.orientation)  # A(t) = R_a(t) R_a(0)ᵀ
    pa = xa + rot_a @ (JOINT_POINT - a.position)  # material joint point on a
    n_a = rot_a @ JOINT_AXIS
    tol = 1e-10  # position-level quantities of size O(1); measured ≤ 8.6e-16
    if kind == "point_mass":
        assert np.abs(xb - pa).max() <= tol
        # rides on a, which pivots about the origin: constant distance, but it does move
        assert np.ptp(np.linalg.norm(xb, axis=1)) <= tol
        assert np.ptp(xb, axis=0).max() > 1e-3
        return
    rot_b = np.einsum("tij,kj->tik", rb, b.orientation)
    pb = xb + rot_b @ (JOINT_POINT - b.position)
    n_b = rot_b @ JOINT_AXIS
    rel = np.einsum("tji,tjk->tik", rot_a, rot_b)  # AᵀB: relative rotation since t = 0
    rel_angle = np.array([np.arccos(np.clip(0.5 * (np.trace(s) - 1), -1, 1)) for s in rel])
    sep = pb - pa
    if kind in ("spherical", "revolute", "rigid", "driven"):
        assert np.abs(sep).max() <= tol
    if kind in ("revolute", "driven", "planar", "orientation_e1e2"):
        assert np.abs(n_a - n_b).max() <= tol  # common axis stays aligned
    if kind in ("rigid", "prismatic", "orientation"):
        assert np.abs(rel - np.eye(3)).max() <= tol
    if kind in ("revolute", "driven"):
        # reported angle = rotation of b relative to a about the axis, from the directors
        phi = np.array([_vee_angle(s, JOINT_AXIS) for s in rel])
        rep = ds.joint_angle.sel(revolute="j").values
        assert np.abs(np.angle(np.exp(1j * (rep - phi)))).max() <= tol
    if kind == "driven":
        np.testing.assert_allclose(ds.joint_angle.sel(revolute="j").values, 2.0 * t,
                                   rtol=0, atol=1e-10)  # measured 4.4e-16
    if kind == "prismatic":
        along = np.einsum("ti,ti->t", sep, n_a)
        assert np.abs(sep - along[:, None] * n_a).max() <= tol
        assert np.ptp(along) > 1e-3  # it does slide
    if kind == "planar":
        assert np.abs(np.einsum("ti,ti->t", sep, n_a)).max() <= tol  # out-of-plane offset 0
        assert np.linalg.norm(sep, axis=1).max() > 1e-3  # in-plane motion happens
    if kind == "orientation":
        assert np.linalg.norm(sep, axis=1).max() > 1e-3
    if kind in ("spherical", "revolute", "planar", "orientation_e1e2"):
        assert rel_angle.max() > 1e-2  # the free rotation is exercised


def _dense_jacobian(s, vals):
    g = np.zeros((s.mh, s.n))
    np.add.at(g, (s.G_rows, s.G_cols), vals)
    return g


@pytest.mark.parametrize("kind", JOINT_KINDS)
def test_joint_jacobians_against_finite_differences(kind):
    mod, *_ , joint = joint_model(kind)
    s = System(mod)
    rng = np.random.default_rng(7)
    q = s.q0_raw + 0.1 * rng.standard_normal(s.n)
    t = 0.37
    g = _dense_jacobian(s, s.jacobian_values(q, t))
    eps = 1e-5
    fd = np.zeros_like(g)
    for k in range(s.n):
        dq = np.zeros(s.n)
        dq[k] = eps
        fd[:, k] = (s.constraint(q + dq, t) - s.constraint(q - dq, t)) / (2 * eps)
    # the rows are quadratic, so central differences are exact up to roundoff
    # (measured ≤ 1.7e-11 absolute on entries of size ≤ 2)
    assert np.abs(g - fd).max() <= 1e-7 * max(1.0, np.abs(g).max())

    # discrete Jacobian: Ḡ(q_i, q_f)·(q_f − q_i) = C(q_f) − C(q_i) (midpoint rule is exact for
    # quadratic rows); measured ≤ 4e-16
    qi = s.q0_raw + 0.1 * rng.standard_normal(s.n)
    qf = qi + 0.2 * rng.standard_normal(s.n)
    dq = qf - qi
    gbar = _dense_jacobian(s, s.discrete_jacobian_values(qi, qf, t, t))
    assert np.abs(gbar @ dq - (s.constraint(qf, t) - s.constraint(qi, t))).max() <= 1e-13
    # with t_i ≠ t_f the identity holds for every time-independent row; a driven row instead
    # satisfies it at the mid-time (its Ḡ is the Jacobian at (q_m, t_m))
    ti, tf = 0.3, 0.45
    gbar = _dense_jacobian(s, s.discrete_jacobian_values(qi, qf, ti, tf))
    lhs = gbar @ dq
    rhs = s.constraint(qf, tf) - s.constraint(qi, ti)
    timed = np.zeros(s.mh, dtype=bool)
    if kind == "driven":
        timed[s.joint_rows[joint][5]] = True
        tm = 0.5 * (ti + tf)
        mid = s.constraint(qf, tm) - s.constraint(qi, tm)
        assert np.abs(lhs[timed] - mid[timed]).max() <= 1e-13
        assert np.abs(lhs[timed] - rhs[timed]).max() > 1e-3  # the row is really time dependent
    assert np.abs(lhs[~timed] - rhs[~timed]).max() <= 1e-13


def test_force_gradients_and_discrete_gradients():
    """Gravity, a linear spring and a rotational spring: ∇V against central differences of V,
    and the discrete gradient's defining identity ∇̄V·Δq = V(q_f) − V(q_i)."""
    mod, a, b, _ = joint_model("revolute")
    mod.add(Spring("k", None, b, point=(0.3, -1.1, 0.2), stiffness=np.diag([3.0, 4.0, 5.0])),
            RelativeRotation("kr", a, b, axis=JOINT_AXIS, stiffness=7.0, phi0=0.2))
    s = System(mod)
    rng = np.random.default_rng(3)
    q = s.q0_raw + 0.05 * rng.standard_normal(s.n)
    grad = s.gradient(q)
    eps = 1e-6
    fd = np.array([(s.potential(q + eps * e) - s.potential(q - eps * e)) / (2 * eps)
                   for e in np.eye(s.n)])
    # measured 1.6e-9 on |∇V| ≤ 19.6 (the rotational spring is not polynomial: O(eps²) terms)
    assert np.abs(grad - fd).max() <= 1e-6 * max(1.0, np.abs(grad).max())
    qi, qf = q, q + 0.05 * rng.standard_normal(s.n)
    dv = s.discrete_gradient(qi, qf) @ (qf - qi)
    # measured 4.4e-16 on ΔV ≈ 1.24
    assert abs(dv - (s.potential(qf) - s.potential(qi))) <= 1e-12 * max(1.0, abs(dv))


# ---------------------------------------------------------------------------- springs, work
def test_damped_oscillator_log_decrement():
    """x(t) = A e^{−ζωt} sin(ω_d t): successive maxima, one damped period apart, have the ratio
    e^δ, δ = 2πζ/√(1 − ζ²). Measured ζ relative error at T_d/200: 1.6e-4 (O(h²))."""
    k, m, zeta = 4.0, 1.0, 0.05
    c = 2 * zeta * np.sqrt(k * m)
    td = 2 * np.pi / (np.sqrt(k / m) * np.sqrt(1 - zeta**2))
    sim = simulate(oscillator(m, k, c), 4.3 * td, td / 200, scheme="ep", reactions=False)
    assert sim.converged, sim.message
    ds = sim.dataset
    t, x, v = ds.time.values, ds.position.values[:, 0, 0], ds.velocity.values[:, 0, 0]
    peaks = CubicSpline(t, x)(zero_crossings(t, v))
    maxima = peaks[peaks > 0]
    assert len(maxima) >= 4
    delta = np.mean(np.log(maxima[:-1] / maxima[1:]))
    zeta_measured = delta / np.sqrt(4 * np.pi**2 + delta**2)
    assert abs(zeta_measured / zeta - 1) <= 1e-3
    # energy balance with the damper's work: measured 2.3e-15 relative
    e, w = ds.energy.values, ds.work.values
    assert np.abs(e - e[0] - w).max() <= 1e-10 * e[0]
    assert w[-1] < -0.5 * e[0]  # the damper did take most of the energy out (0.93 E0)


def test_ep_work_balance_loads_and_drivers():
    """E(t) − E0 equals the booked work of loads and drivers; for a constant force the work is
    F·Δx exactly (independent of the scheme), for a constant moment M·n Δφ about a fixed axis."""
    # constant force on a point mass plus a damper, no gravity
    f = np.array([0.3, -0.2, 0.5])
    p = PointMass("p", 2.0, velocity=(0.1, 0.2, 0.0))
    mod = Model()
    mod.add(p, Spring("s", None, p, point=(0, 0, 0), stiffness=3.0, damping=0.4),
            AppliedLoad("F", p, force=lambda t: f))
    # (the damper makes the balance non-trivial; the force's own work is checked separately)
    sim = simulate(mod, 5.0, 0.01, scheme="ep", reactions=False)
    assert sim.converged, sim.message
    ds = sim.dataset
    e, w = ds.energy.values, ds.work.values
    assert np.abs(e - e[0] - w).max() <= 1e-10 * np.abs(e).max()  # measured 7.3e-16

    p2 = PointMass("p", 2.0, velocity=(0.1, 0.2, 0.0))
    mod2 = Model()
    mod2.add(p2, Spring("s", None, p2, point=(0, 0, 0), stiffness=3.0),
             AppliedLoad("F", p2, force=lambda t: f))
    ds2 = simulate(mod2, 5.0, 0.01, scheme="ep", reactions=False).dataset
    x = ds2.position.values[:, 0]
    np.testing.assert_allclose(ds2.work.values, (x - x[0]) @ f, atol=1e-12)  # measured 1.9e-16

    # constant moment about a revolute axis (plus gravity). The scheme books the moment as
    # director forces ½ M × d_α at the midpoint, whose work over a step of rotation Δφ is
    # M·n sin Δφ, not M·n Δφ: the booked work is second-order accurate (measured max
    # |work − M (φ − φ0)| = 1.15e-5 at h = 0.01, 2.88e-6 at h = 0.005), while the balance
    # E − E0 = work stays exact.
    mz = 0.8
    moment_err = []
    for h in (0.01, 0.005):
        mod3 = pendulum(np.radians(30))
        rod = next(bd for bd in mod3.bodies if bd.name == "rod")
        mod3.add(AppliedLoad("M", rod, moment=lambda t: np.array([0.0, 0.0, mz])))
        ds3 = simulate(mod3, 2.0, h, scheme="ep", reactions=False).dataset
        phi = ds3.joint_angle.values[:, 0]
        moment_err.append(np.abs(ds3.work.values - mz * (phi - phi[0])).max())
        e3 = ds3.energy.values
        assert np.abs(e3 - e3[0] - ds3.work.values).max() <= 1e-10 * 5.0  # measured 2e-14
    assert moment_err[1] <= 5e-6 and 3.5 <= moment_err[0] / moment_err[1] <= 4.5, moment_err

    # driven revolute (driver work through the constraint force)
    mod4, *_ = joint_model("driven")
    ds4 = simulate(mod4, 1.0, 0.01, scheme="ep", reactions=False).dataset
    e4, w4 = ds4.energy.values, ds4.work.values
    assert np.abs(w4).max() > 1e-2  # the driver does work (up to 7.96 J)
    assert np.abs(e4 - e4[0] - w4).max() <= 1e-10 * np.abs(e4).max()  # measured 2.8e-16


def _torsion_model(free):
    n = np.array([1.0, 2.0, 2.0]) / 3
    e1 = np.cross((0, 0, 1), n)
    e1 /= np.linalg.norm(e1)
    frame = np.column_stack([e1, np.cross(n, e1), n])  # body z along n
    jz, ja, k = 0.75, 1.25, 3.0
    disc = RigidBody("disc", 2.0, inertia=(0.5, 0.5, jz), orientation=frame,
                     angular_velocity=0.8 * n)
    mod = Model()
    if free:
        hub = RigidBody("hub", 3.0, inertia=(0.7, 0.7, ja), orientation=frame,
                        angular_velocity=-0.3 * n)
        mod.add(hub, disc, Revolute("pin", hub, disc, point=(0, 0, 0), axis=n),
                RelativeRotation("tor", hub, disc, axis=n, stiffness=k))
        omega = np.sqrt(k * (ja + jz) / (ja * jz))  # free–free: reduced inertia
    else:
        g0 = ground()
        mod.add(g0, disc, Revolute("pin", g0, disc, point=(0, 0, 0), axis=n),
                RelativeRotation("tor", None, disc, axis=n, stiffness=k))
        omega = np.sqrt(k / jz)
    return mod, n, omega


@pytest.mark.parametrize("free", [False, True], ids=["to_ground", "free_free"])
def test_rotational_spring_frequency(free):
    """J φ̈ = −k φ exactly (φ is the true relative angle), T = 2π √(J/k); measured relative
    period error at T/400: 2.2e-5 (midpoint O(h²)) for both cases."""
    mod, n, omega = _torsion_model(free)
    t_ref = 2 * np.pi / omega
    sim = simulate(mod, 2.6 * t_ref, t_ref / 400, scheme="ep", reactions=False, record_every=2)
    assert sim.converged, sim.message
    ds = sim.dataset
    w = ds.angular_velocity.values @ n  # (time, body)
    rate = w[:, -1] - (w[:, 0] if free else 0.0)  # relative rate φ̇ (disc is the last body)
    roots = zero_crossings(ds.time.values, rate, 0.25 * t_ref)
    assert len(roots) == 5
    period = 2 * _half_period_estimate(roots)
    assert abs(period / t_ref - 1) <= 1e-4
    assert ds.constraint_violation.max() <= 1e-10


def test_rotational_spring_beyond_half_a_turn():
    """Same linear oscillator J φ̈ = −k φ, amplitude ω0/ω = 3.5 rad > π: the amplitude and the
    period T = 2π√(J/k) do not depend on the amplitude."""
    k, jz, w0 = 3.0, 0.75, 7.0
    n = np.array([0.0, 0.0, 1.0])
    g0 = ground()
    disc = RigidBody("disc", 2.0, inertia=(0.5, 0.5, jz), angular_velocity=w0 * n)
    mod = Model()
    mod.add(g0, disc, Revolute("pin", g0, disc, point=(0, 0, 0), axis=n),
            RelativeRotation("tor", None, disc, axis=n, stiffness=k))
    omega = np.sqrt(k / jz)
    t_ref = 2 * np.pi / omega
    sim = simulate(mod, 2.6 * t_ref, t_ref / 400, scheme="ep", reactions=False)
    assert sim.converged, sim.message
    phi = sim.dataset.joint_angle.values[:, 0]
    # φ is unwrapped beyond half a turn (wrapped, the spring's angle would run away)
    assert abs(phi.max() - w0 / omega) <= 1e-3
    roots = zero_crossings(sim.dataset.time.values,
                            sim.dataset.angular_velocity.values[:, 0, 2], 0.25 * t_ref)
    assert len(roots) == 5
    # measured 1.46e-4 at T/400: the midpoint phase error plus the O(h²) error of angular
    # velocities reported from director rates
    assert abs(2 * _half_period_estimate(roots) / t_ref - 1) <= 3e-4


# ---------------------------------------------------------------------------- rotating hub
def centrifugal_pendulum(radius, length, spin, theta0, m=1.0):
    """Slender rod (m, l) hinged about z at radius R on a hub spinning at Ω (no gravity),
    released at θ0 from the radial direction while co-rotating with the hub."""
    from solver.bodies import spinning

    hub = spinning("hub", spin)
    xc = np.array([radius, 0.0, 0.0]) + length / 2 * np.array([np.cos(theta0),
                                                                np.sin(theta0), 0.0])
    rod = RigidBody("rod", m, inertia=(0.0, m * length**2 / 12, m * length**2 / 12),
                    position=xc, orientation=_rot((0, 0, 1), theta0),
                    velocity=np.cross([0.0, 0.0, spin], xc), angular_velocity=(0.0, 0.0, spin))
    mod = Model()
    mod.add(hub, rod, Revolute("pin", hub, rod, point=(radius, 0, 0), axis=(0, 0, 1)))
    return mod


def _centrifugal_run(theta0, steps, scheme, radius=0.3, length=0.2, spin=10.0):
    """Lagrange: J_h θ̈ + m R c Ω² sin θ = 0 exactly (c = l/2, J_h = m l²/3): a pendulum with
    ω0 = Ω √(3R / 2l), i.e. tuned order n = 1.5 here, and period 4 K(sin θ0/2) / ω0."""
    w0 = spin * np.sqrt(3 * radius / (2 * length))
    t_ref = 4 * ellipk(np.sin(theta0 / 2) ** 2) / w0
    sim = simulate(centrifugal_pendulum(radius, length, spin, theta0), 2.6 * t_ref,
                   t_ref / steps, scheme=scheme, reactions=False)
    assert sim.converged, sim.message
    return sim, t_ref, spin


@pytest.mark.parametrize("amplitude_deg", [30, 120])
def test_centrifugal_pendulum_period(amplitude_deg):
    """Validates the spinning prescribed body, a revolute on a moving body and the driver
    work. Measured relative period error at T/400: 4.2e-5 (30°), 8.8e-5 (120°), O(h²)."""
    sim, t_ref, spin = _centrifugal_run(np.radians(amplitude_deg), 400, "ep")
    ds = sim.dataset
    rate = ds.angular_velocity.sel(body="rod").values[:, 2] - spin  # θ̇
    roots = zero_crossings(ds.time.values, rate, 0.25 * t_ref)
    assert len(roots) == 5
    assert abs(2 * _half_period_estimate(roots) / t_ref - 1) <= 1.5e-4
    # energy changes only by the work of the hub's drive: measured ≤ 3e-11 J on E ≈ 5 J
    e, w = ds.energy.values, ds.work.values
    assert np.abs(e - e[0] - w).max() <= 1e-10 * np.abs(e).max()
    assert np.ptp(w) > 0.1  # the drive does exchange energy with the rod
    assert ds.constraint_violation.max() <= 1e-12  # measured 2.6e-14 (coordinates ~ 0.4 m)


def test_galpha_work_balance_is_second_order():
    mism = []
    for steps in (100, 200):
        sim, _, _ = _centrifugal_run(np.radians(30), steps, "galpha")
        e, w = sim.dataset.energy.values, sim.dataset.work.values
        mism.append(np.abs(e - e[0] - w).max() / np.ptp(e))
    assert mism[1] <= 1e-2 and mism[0] / mism[1] >= 3.5, mism


@pytest.mark.parametrize("scheme", ["galpha", "ep", "ed"])
def test_a_run_without_work_booking_takes_the_same_steps(scheme):
    """``book_work=False`` (the rotor's runs) leaves the work NaN, never a wrong number, and
    changes no step: the states agree to the bit with a run that books the drive's work."""
    from solver.integrators import make_integrator

    model = centrifugal_pendulum(0.3, 0.2, 10.0, np.radians(30))
    runs = []
    for book in (True, False):
        integ = make_integrator(System(model), scheme, 2e-3, book_work=book)
        for _ in range(50):
            assert integ.step().converged
        runs.append(integ)
    assert np.isfinite(runs[0].work) and runs[0].work != 0.0
    assert np.isnan(runs[1].work)
    assert np.array_equal(runs[0].q, runs[1].q) and np.array_equal(runs[0].v, runs[1].v)


# ---------------------------------------------------------------------------- reactions
def _pendulum_reaction(theta, theta0, m=1.0, length=1.0):
    """Force of the pin on the rod: m a_cm − m g, with θ̇² = (3g/L)(cos θ − cos θ0) and
    θ̈ = −(3g/2L) sin θ (energy and moment balance about the pin)."""
    thd2 = (3 * G / length) * (np.cos(theta) - np.cos(theta0))
    thdd = -(3 * G / (2 * length)) * np.sin(theta)
    rh = np.stack([np.sin(theta), -np.cos(theta)], 1)
    tt = np.stack([np.cos(theta), np.sin(theta)], 1)
    acc = (length / 2) * (thdd[:, None] * tt - thd2[:, None] * rh)
    return m * acc - m * np.array([0.0, -G])


@pytest.mark.parametrize("scheme", ["galpha", "ep"])
def test_pendulum_reaction_force_converges(scheme):
    """galpha reports the multiplier at t_{n+1}: second order against the analytic pin force
    there (measured max error 4.1e-2 → 1.0e-2 N at T/100 → T/200, forces up to 24.5 N). EP's
    multiplier is the step average (it enters M Δv = −h(… + Ḡᵀλ)): it is second order against
    the mean of the analytic force at t_n and t_{n+1} (measured 4.0e-2 → 1.0e-2 N) but only
    first order against the force at the reported time t_{n+1} (1.15 → 0.58 N)."""
    theta0 = np.radians(90)
    t_ref = pendulum_period(theta0)
    errs = []
    for n in (100, 200):
        ds = simulate(pendulum(theta0), t_ref, t_ref / n, scheme=scheme).dataset
        theta = ds.joint_angle.values[:, 0] + theta0
        exact = _pendulum_reaction(theta, theta0)
        rep = ds.reaction_force.sel(joint="pin").values[1:, :2]  # t = 0 excluded (see below)
        ref = 0.5 * (exact[1:] + exact[:-1]) if scheme == "ep" else exact[1:]
        errs.append(np.abs(rep - ref).max())
    assert errs[1] <= 2e-2 and 3.5 <= errs[0] / errs[1] <= 4.5, errs


def test_reaction_at_time_zero():
    theta0 = np.radians(90)
    ds = simulate(pendulum(theta0), 0.05, 0.01, scheme="galpha").dataset
    exact = _pendulum_reaction(np.array([theta0]), theta0)[0]  # (0, m g/4) = (0, 2.4525) N
    np.testing.assert_allclose(ds.reaction_force.sel(joint="pin").values[0, :2], exact,
                               atol=1e-8)


# ---------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, word", [
    ({"mass": -1.0}, "mass"),
    ({"mass": float("nan")}, "mass"),
    ({"mass": 1.0, "inertia": (1.0, 1.0, 3.0)}, "inertia"),  # violates J1 + J2 ≥ J3
    ({"mass": 1.0, "inertia": (-1.0, 1.0, 1.0)}, "inertia"),
    ({"mass": 1.0, "inertia": [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]}, "inertia"),  # asymmetric
    ({"mass": 1.0, "orientation": np.diag([1.0, 1.0, -1.0])}, "orientation"),  # reflection
    ({"mass": 1.0, "orientation": 2 * np.eye(3)}, "orientation"),
    ({"mass": 1.0, "orientation": np.eye(2)}, "orientation"),
])
def test_rigid_body_rejects_bad_parameters(kwargs, word):
    with pytest.raises(ValueError, match=word):
        RigidBody("b", **kwargs)


@pytest.mark.parametrize("h", [0.0, -0.01, float("nan"), float("inf")])
def test_simulate_rejects_bad_step(h):
    with pytest.raises(ValueError, match="h"):
        simulate(pendulum(0.3), 1.0, h)


def test_simulate_rejects_unknown_scheme():
    with pytest.raises(ValueError, match="scheme"):
        simulate(pendulum(0.3), 1.0, 0.01, scheme="rk4")


def _redundant(kind):
    g0 = ground()
    n = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
    rod = RigidBody("rod", 1.0, inertia=(0.1, 0.2, 0.25), position=(0.2, -0.4, 0.1),
                    orientation=_rot((1, -2, 0.5), 1.1), angular_velocity=(0.3, -0.7, 1.1))
    mod = Model()
    mod.add(g0, rod, Revolute("pin", g0, rod, point=(0, 0, 0), axis=(0, 0, 1)),
            Gravity((0, -G, 0)))
    if kind == "two_revolutes":
        mod.add(Revolute("pin2", g0, rod, point=(0, 0, 0), axis=(0, 0, 1)))
    elif kind == "oblique_pair":  # same axis, declared at another point and reversed
        mod.joints.clear()
        mod.add(Revolute("pin", g0, rod, point=(0, 0, 0), axis=n),
                Revolute("pin2", g0, rod, point=0.37 * n, axis=-n))
    elif kind == "spherical_on_axis":
        mod.add(Spherical("s", g0, rod, point=(0, 0, 0.7)))
    elif kind == "zero_inertia":  # a free rotation with no inertia: singular mass matrix
        mod.joints.clear()
        mod.bodies.remove(rod)
        free = RigidBody("free", 1.0, inertia=(0.0, 0.0, 0.0), angular_velocity=(0, 0, 1))
        mod.add(free, Spherical("s", g0, free, point=(0, 0, 0)))
    return mod


@pytest.mark.parametrize("scheme", ["ep", "galpha", "ed"])
@pytest.mark.parametrize("kind", ["two_revolutes", "oblique_pair", "spherical_on_axis",
                                  "zero_inertia"])
def test_singular_models_fail_cleanly(kind, scheme):
    try:
        sim = simulate(_redundant(kind), 0.1, 0.01, scheme=scheme)
    except ValueError as exc:
        assert "singular" in str(exc) or "redundant" in str(exc), str(exc)
        return
    assert not sim.converged
    assert "singular" in sim.message or "redundant" in sim.message, sim.message


# ------------------------------------------------------------------ rotational damper tangent
@pytest.mark.parametrize("grounded", [True, False])
def test_rotational_damper_jacobians_match_finite_differences(grounded):
    """f = −c φ̇ ∇φ: ∂f/∂q holds the moment's turn with the bodies (m ∇²φ) and the rate's
    (∇φ (∇²φ v)ᵀ) — what a spinning rotor's lag damper needs for Newton to converge."""
    rng = np.random.default_rng(3)
    a = RigidBody("a", 1.0, inertia=(1, 2, 3), orientation=_rot((1, 2, 3), 0.3))
    b = RigidBody("b", 1.0, inertia=(1, 2, 3), position=(0.3, 0.1, 0),
                  orientation=_rot((3, 1, 2), 0.7))
    mod = Model()
    mod.add(ground(), a, b, RelativeRotation("r", None if grounded else a, b,
                                             axis=(0.2, 0.3, 1.0), damping=2.0))
    s = System(mod)
    st = next(x for x in s.sets if len(x.fq_rows))
    q = s.q0_raw + 0.05 * rng.standard_normal(s.n)
    v = rng.standard_normal(s.n)
    jq, jv = st.force_jacobians(q, v, 0.0)
    nj, k = st.idx.shape
    fd_q, fd_v = np.zeros((nj, k, k)), np.zeros((nj, k, k))
    for c in range(k):
        for x, out in ((q, fd_q), (v, fd_v)):
            e = 1e-6
            xp, xm = x.copy(), x.copy()
            xp[st.idx[:, c]] += e
            xm[st.idx[:, c]] -= e
            args = ((xp, v), (xm, v)) if x is q else ((q, xp), (q, xm))
            fp, fm = (st.force(*arg, 0.0).reshape(nj, k) for arg in args)
            out[:, :, c] = (fp - fm) / (2 * e)
    # measured ≤ 8e-10 against entries up to 5 (central differences' truncation)
    assert np.abs(jq.reshape(nj, k, k) - fd_q).max() <= 1e-7 * np.abs(fd_q).max()
    assert np.abs(jv.reshape(nj, k, k) - fd_v).max() <= 1e-7 * np.abs(fd_v).max()


# ------------------------------------------------------------------ delayed feedback damping
def _per_period_peaks(sim, steps):
    phi = sim.dataset.joint_angle.values[:, 0]
    return np.abs(phi[: len(phi) // steps * steps].reshape(-1, steps)).max(axis=1)


def test_delayed_feedback_damps_the_transient_at_the_characteristic_root():
    """Free disc started at φ̇ = 0.1 rad/s: once the feedback −a[φ(t) − φ(t − τ)] −
    b[φ̇(t) − φ̇(t − τ)] is on (after one delay), the motion decays with the rightmost root of
    the delay equation J s² + c s + k + (a + b s)(1 − e^{−sτ}) = 0 (found by Newton from a grid
    of starts): s = −0.693 ± 1.254i, a factor 0.50 per delay, against 0.983 (−0.017 ± 1.696i)
    without feedback. The root is fitted to the simulated φ(t) over t = 6 … 12 τ (linear
    prediction of order 2 on samples 0.1 τ apart, where the next roots, −1.42 ± 4.10i and
    beyond, have decayed below 3 % of it)."""
    mod, (jz, c, k, a, b, tau) = feedback_oscillator(0.0, True, spin=0.1)
    steps = 240
    sim = simulate(mod, 12 * tau, tau / steps, scheme="galpha", rho_inf=0.5, reactions=False,
                   tol=1e-12)
    assert sim.converged, sim.message

    def f(s):
        return jz * s * s + c * s + k + (a + b * s) * (1 - np.exp(-s * tau))

    def df(s):
        return 2 * jz * s + c + b * (1 - np.exp(-s * tau)) + (a + b * s) * tau * np.exp(-s * tau)

    roots = []
    for s0 in [complex(x, y) for x in (-3, -1, -0.3) for y in np.linspace(0, 15, 16)]:
        s = s0
        for _ in range(60):
            s -= f(s) / df(s)
        if abs(f(s)) < 1e-10:
            roots.append(s)
    rightmost = max(roots, key=lambda s: (s.real, s.imag))
    t = sim.dataset.time.values
    phi = sim.dataset.joint_angle.values[:, 0][(t >= 6 * tau - 1e-9)][:: steps // 10]
    # φ_{n+2} = p1 φ_{n+1} + p2 φ_n: roots z of z² − p1 z − p2 are exp(s Δt)
    p1, p2 = np.linalg.lstsq(np.column_stack([phi[1:-1], phi[:-2]]), phi[2:], rcond=None)[0]
    z = np.roots([1.0, -p1, -p2])
    fitted = np.log(z[np.argmax(z.imag)]) / (tau / 10)
    # measured: 2.5e-3 from the root (the scheme's error at 240 steps per delay and the
    # faster roots left in the window)
    assert abs(fitted - rightmost) <= 5e-3 * abs(rightmost), (fitted, rightmost)
    assert np.exp(rightmost.real * tau) < 0.51  # against 0.983 without feedback


def test_delayed_feedback_leaves_the_periodic_response_exact():
    """Forced at the delay's period, the response with feedback settles to the closed-form
    steady state of the plain oscillator, |φ| = M / |k − JΩ² + icΩ|: the feedback vanishes on
    it. Without feedback the 1 %-damped transient still spoils it after the same 10 periods."""
    steps = 240
    errors = {}
    for fb in (True, False):
        mod, (jz, c, k, _a, _b, tau) = feedback_oscillator(1.0, fb)
        sim = simulate(mod, 11 * tau, tau / steps, scheme="galpha", rho_inf=0.5,
                       reactions=False, tol=1e-12)
        assert sim.converged, sim.message
        om = 2 * np.pi / tau
        exact = 1.0 / abs(k - jz * om**2 + 1j * c * om)
        errors[fb] = abs(_per_period_peaks(sim, steps)[10] / exact - 1)
    # measured 3.6e-4 (the transient left after 10 periods, 0.50^9 of its start, and the
    # scheme's error at 240 steps per period) against 0.45 without feedback
    assert errors[True] <= 1e-3, errors
    assert errors[False] >= 0.05, errors
