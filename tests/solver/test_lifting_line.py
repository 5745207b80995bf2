"""Lifting line with Peters finite-state airfoil sections, against closed forms.

* Typical section (a prescribed rigid wing, one section, elastic axis a = −0.2): harmonic pitch
  and plunge against the finite-state model's own frequency response (Theodorsen's loads with
  C_N(k), :func:`solver.airfoil.lift_deficiency`) and against Theodorsen's C(k); the indicial
  (Wagner) response to a step in plunge velocity against the finite-state step response and
  Wagner's function.
* Hover: rigid untwisted blades (prescribed spin) with the Pitt–Peters inflow, whose steady
  state has a closed form: with a uniform inflow λ, Kutta–Joukowski on sections of pitch θ gives
  exactly dT/dr = ρ a b Ω r (Ω r sin θ − λ Ω R cos θ), so
  C_T = (σ a / 2) [(1 − x0³) sin θ / 3 − λ (1 − x0²) cos θ / 2], and momentum theory
  λ = √(C_T/2) closes it.
* A straight beam in a uniform stream: total lift and root moment of the consistent loads.
* Energy: ``ep`` with aerodynamics on a free pitching wing books the air's work exactly.
* Jacobians (complex steps) against central differences, on a beam in forward flight with a
  Peters–He inflow.
"""

from __future__ import annotations

import numpy as np
import pytest

from solver.air import FlightCondition
from solver.airfoil import (
    DEFAULT_STATES,
    harmonic_airloads,
    lift_deficiency,
    peters_matrices,
    peters_step_response,
    theodorsen,
    wagner,
)
from solver.bodies import PrescribedBody, RigidBody, ground
from solver.forces import RelativeRotation
from solver.joints import Revolute
from solver.lifting_line import LiftingLine
from solver.model import Model
from solver.rotations import rotation_about
from solver.simulation import simulate
from solver.system import System
from tests.solver.lifting_line_models import (
    OMEGA,
    R_ROTOR,
    RHO,
    beam_line,
    hover_closed_form,
    rotor,
    wing_beam,
)

B, U, A_EA = 0.25, 50.0, -0.2  # semichord (m), speed (m/s), elastic axis
# wing frame at zero pitch: d1 span (+y), d2 towards the leading edge (−x: the air blows +x),
# d3 up
WING = np.column_stack([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def _set(system, line):
    return next(s for s in system.sets if line in s.elements)


def _midpoint_recorder(system, fn):
    """Callback recording fn(q_m, v_m, a_m, t_m) with the midpoint values the ``ep`` residual
    uses: q_m = (q_i + q_f)/2, v_m = Δq/h, a_m = (v_f − v_i)/h."""
    rec, prev = [], []

    def cb(integ):
        if prev:
            qp, vp = prev.pop()
            h = integ.h
            rec.append(fn(0.5 * (qp + integ.q), (integ.q - qp) / h, (integ.v - vp) / h,
                          integ.t - 0.5 * h))
        prev.append((integ.q.copy(), integ.v.copy()))

    return rec, cb


# ------------------------------------------------------------------ typical section
def typical_section(k, n, pitch=0.0, plunge=0.0, steps=100, periods=None):
    """Complex lift (N/m) and moment about the elastic axis (N·m/m) amplitudes (time factor
    e^{iωt}) of a wing in motion α = pitch sin ωt, h = plunge sin ωt (h down)."""
    w = k * U / B
    period = 2 * np.pi / w
    y = np.array([0.0, 1.0, 0.0])

    def motion(t):
        s, c = np.sin(w * t), np.cos(w * t)
        r = rotation_about(y, pitch * s) @ WING
        return (np.array([0, 0, -plunge * s]), r, np.array([0, 0, -plunge * w * c]),
                pitch * w * c * y, np.array([0, 0, plunge * w * w * s]), -pitch * w * w * s * y)

    wing = PrescribedBody("wing", motion)
    line = LiftingLine("aero", wing, FlightCondition(U, 0.0, RHO), chord=2 * B,
                       span=(-0.5, 0.5), quarter_chord=B * (0.5 + A_EA), wake_states=n,
                       points=1)
    model = Model()
    model.add(wing, line)
    system = System(model)
    o = system.offset[wing]

    def loads(q, v, a, t):
        f = system.applied(q, v, t, a)[o : o + 12]
        d, fd = q[o + 3 : o + 12].reshape(3, 3), f[3:].reshape(3, 3)
        return t, f[2], np.cross(d, fd).sum(axis=0)[1]  # lift (z), nose-up moment (about y)

    if periods is None:  # let the slowest wake mode (time b/U · max eig A) die out
        tau = B / U * (np.abs(np.linalg.eigvals(peters_matrices(n)[0])).max() if n else 0.0)
        periods = int(max(3, np.ceil(10 * tau / period) + 1))
    rec, cb = _midpoint_recorder(system, loads)
    sim = simulate(model, periods * period, period / steps, reactions=False,
                   record_every=10**9, callback=cb, system=system, record_initial=True)
    assert sim.converged, sim.message
    r = np.array(rec)[-steps:]
    basis = np.column_stack([np.ones(steps), np.cos(w * r[:, 0]), np.sin(w * r[:, 0])])
    cl, cm = (np.linalg.lstsq(basis, r[:, j], rcond=None)[0] for j in (1, 2))
    return w, cl[1] - 1j * cl[2], cm[1] - 1j * cm[2]


def _reference(w, n, pitch, plunge, deficiency=None):
    kw = {} if deficiency is None else {"deficiency": deficiency}
    return harmonic_airloads(B, A_EA, U, RHO, w, -1j * plunge, -1j * pitch, **kw)


# The finite-state model's own error against Theodorsen (max over k ∈ [0.01, 2] of |C_N − C|,
# from tests/solver/test_airfoil.py) bounds the load error relative to the circulatory part.
MODEL_ERROR = {2: 0.144, 4: 0.034, 6: 0.015, 8: 0.0096, 10: 0.0082}


@pytest.mark.parametrize("k", [0.1, 0.5])
@pytest.mark.parametrize("motion", ["pitch", "plunge"])
def test_harmonic_response_matches_finite_state_theory_and_theodorsen(k, motion):
    n = DEFAULT_STATES
    pitch, plunge = (1e-3, 0.0) if motion == "pitch" else (0.0, 2.5e-4)
    w, lift, moment = typical_section(k, n, pitch, plunge)
    lm, mm = _reference(w, n, pitch, plunge, lambda kk: lift_deficiency(kk, n))
    lt, _ = _reference(w, n, pitch, plunge)
    # against the model's own closed form: time-step error (ωh)²/12 ≈ 3e-4 at 100 steps per
    # period plus the last wake transient; measured 2.0e-4…5.3e-4 (k = 0.1, 0.5)
    assert abs(lift - lm) < 1e-3 * abs(lm), (lift, lm)
    assert abs(moment - mm) < 1e-3 * abs(mm), (moment, mm)
    # against Theodorsen: the difference is the finite-state model's C_N(k) − C(k) (≤ 0.0096
    # at N = 8) times the quasi-steady circulatory lift 2πρUb w̄, plus the time-step error
    circ = abs(_reference(w, n, pitch, plunge, lambda kk: 1.0 + 0.0 * kk)[0]
               - _reference(w, n, pitch, plunge, lambda kk: 0.0 * kk)[0])
    kk = w * B / U
    model_error = abs(lift_deficiency(kk, n) - theodorsen(kk)) * circ
    assert model_error < MODEL_ERROR[n] * circ
    assert abs(abs(lift - lt) - model_error) < 1e-3 * abs(lt), (lift, lt, model_error)


def test_indicial_response_is_wagner():
    """A wing at rest suddenly plunging down at ḣ (start="rest": no wake yet, μ = 0) has
    circulatory lift L(s)/L(∞) = φ(s), s = U t / b."""
    n, hdot = DEFAULT_STATES, 0.05

    def motion(t):
        return (np.array([0, 0, -hdot * t]), WING, np.array([0, 0, -hdot]), np.zeros(3),
                np.zeros(3), np.zeros(3))

    wing = PrescribedBody("wing", motion)
    line = LiftingLine("aero", wing, FlightCondition(U, 0.0, RHO), chord=2 * B,
                       span=(-0.5, 0.5), wake_states=n, points=1, start="rest")
    model = Model()
    model.add(wing, line)
    system = System(model)
    st = _set(system, line)
    rec, cb = _midpoint_recorder(
        system, lambda q, v, a, t: (t, st.airloads(q, v, a)["lift"][0]))
    h = 0.02 * B / U
    simulate(model, 50 * B / U, h, reactions=False, record_every=10**9, callback=cb,
             system=system, record_initial=True)
    r = np.array(rec)
    s = r[:, 0] * U / B
    phi = r[:, 1] / (2 * np.pi * RHO * U * B * hdot)
    pick = [np.argmin(np.abs(s - x)) for x in (1.0, 2.0, 5.0, 10.0, 20.0, 49.0)]
    # the finite-state step response (closed form): midpoint rule, error O((h U/b)²), measured
    # 2e-5
    assert np.abs(phi[pick] - peters_step_response(s[pick], n)).max() < 1e-4
    # Wagner's function: the N = 8 model's own error, ≤ 3.6e-3 on this table
    assert np.abs(phi[pick] - wagner(s[pick])).max() < 4e-3


# ------------------------------------------------------------------ hover


def run_rotor(model, inflow, lines, t_end, steps_per_rev):
    system = System(model)
    st = _set(system, lines[0])
    o = system.offset[inflow]

    def fn(q, v, a, t):
        out = st.airloads(q, v, a)
        thrust = float(np.sum(out["force"][:, 2] * out["ds"]))
        return t, thrust / (RHO * np.pi * R_ROTOR**2 * (OMEGA * R_ROTOR) ** 2), \
            *q[o : o + inflow.n_states]

    rec, cb = _midpoint_recorder(system, fn)
    sim = simulate(model, t_end, 2 * np.pi / OMEGA / steps_per_rev, reactions=False,
                   record_every=10**9, callback=cb, system=system, record_initial=True)
    assert sim.converged, sim.message
    return np.array(rec)


@pytest.mark.parametrize("collective_deg", [4.0, 12.0])
def test_hover_inflow_is_momentum_theory_and_thrust_is_blade_element(collective_deg):
    theta = np.radians(collective_deg)
    lam, ct = hover_closed_form(theta)
    got = []
    for spr in (48, 96):
        r = run_rotor(*rotor(theta), t_end=1.5, steps_per_rev=spr)[-spr:]
        ct_sim, lam_sim = r[:, 1].mean(), r[:, 2].mean()
        # the Pitt–Peters steady state holds with the thrust the midpoint rule sees (measured
        # 6e-10 at 4°, the tail of the inflow transient, 2e-14 at 12°)
        assert abs(lam_sim - np.sqrt(ct_sim / 2)) < 1e-9, (lam_sim, ct_sim)
        assert np.abs(r[:, 3:]).max() < 1e-12  # no cyclic inflow in hover
        got.append((ct_sim, lam_sim))
    # thrust against the closed form: the chord of a turning director lies inside the circle,
    # an O((Ωh)²) error (measured −0.57 % → −0.14 % at 48 → 96 steps per revolution); the
    # Richardson extrapolation of the two agrees to 3.3e-6 (C_T) and 6e-7 (λ)
    (c1, l1), (c2, l2) = got
    assert abs((4 * c2 - c1) / 3 / ct - 1) < 1e-4, ((4 * c2 - c1) / 3, ct)
    assert abs((4 * l2 - l1) / 3 / lam - 1) < 1e-4, ((4 * l2 - l1) / 3, lam)
    assert abs(c2 / ct - 1) < 2e-3


# ------------------------------------------------------------------ beam, energy, Jacobians
def test_beam_line_gives_consistent_lift_and_root_moment():
    """A straight beam along +y (d2 = −x: the leading edge faces the wind U x̂) pitched by α:
    with w34 = U sin α, u = U cos α and Γ = a b w34, the force ρ Γ (u e_n + w34 e_c) has the
    vertical component ρ a b U² sin α per length exactly; the consistent nodal loads must sum
    to it and give the root moment lift · L/2 about x."""
    alpha, length, slope = 0.05, 2.0, 6.0
    beam = wing_beam(length=length)
    assert np.allclose(beam.frames[0][:, 1], (-1, 0, 0))
    line = LiftingLine("aero", beam, FlightCondition(U, 0.0, RHO), chord=2 * B, pitch=alpha,
                       lift_slope=slope, wake_states=4)
    model = Model()
    model.add(beam, line)
    system = System(model)
    q, v = system.q0_raw, np.zeros(system.n)
    f = system.applied(q, v, 0.0)
    o = system.offset[beam]
    fx = f[o : o + 12 * len(beam.nodes)].reshape(-1, 4, 3)
    lift = fx[:, 0, 2].sum()
    exact = RHO * slope * B * U**2 * np.sin(alpha) * length
    assert abs(lift / exact - 1) < 1e-12, (lift, exact)
    # root moment about x of the consistent loads: Σ y_a F_z,a + director moments = lift L/2
    d = q[o : o + 12 * len(beam.nodes)].reshape(-1, 4, 3)
    mom = (np.cross(d[:, 0], fx[:, 0]) + np.cross(d[:, 1:], fx[:, 1:]).sum(axis=1)).sum(axis=0)
    assert abs(mom[0] / (lift * length / 2) - 1) < 1e-12


def test_ep_books_the_air_work_exactly():
    """A wing pitching freely on a torsion spring in the stream (elastic axis behind the
    quarter chord: statically stable): E − W of ``ep`` stays constant to roundoff."""
    g = ground()
    wing = RigidBody("wing", 5.0, inertia=(0.2, 0.02, 0.2),
                     orientation=rotation_about((0, 1, 0), 0.05) @ WING)
    line = LiftingLine("aero", wing, FlightCondition(20.0, 0.0, RHO), chord=2 * B,
                       span=(-0.5, 0.5), quarter_chord=0.1, drag=0.01)
    hinge = Revolute("hinge", g, wing, point=(0, 0, 0), axis=(0, 1, 0))
    spring = RelativeRotation("spring", g, wing, axis=(0, 1, 0), stiffness=200.0)
    model = Model()
    model.add(g, wing, hinge, spring, line)
    rec = []
    sim = simulate(model, 0.5, 1e-3, reactions=False, record_every=10**9,
                   callback=lambda i: rec.append(i.energy() - i.work), record_initial=True)
    assert sim.converged, sim.message
    rec = np.array(rec)
    assert np.ptp(rec) < 1e-10 * 200.0 * 0.05**2, np.ptp(rec)


def _dense(n: int, vals, rows, cols):
    """The n × n matrix with ``vals`` summed at (rows, cols)."""
    m = np.zeros((n, n))
    np.add.at(m, (rows, cols), vals)
    return m


def test_complex_step_jacobians_match_finite_differences():
    """∂f/∂q, ∂f/∂v, ∂f/∂a of a twisted, moving beam line in forward flight with a Peters–He
    inflow, against central differences of the forces."""
    model, line = beam_line()
    system = System(model)
    rng = np.random.default_rng(3)
    q = system.q0_raw + 1e-2 * rng.standard_normal(system.n)
    v = rng.standard_normal(system.n)
    a = rng.standard_normal(system.n)
    v[system.first_order] = 0.0
    st = _set(system, line)
    jq, jv = st.force_jacobians(q, v, 0.0, a)
    ja = st.acceleration_jacobian(q, v, 0.0, a)

    def dense(vals, rows, cols):
        return _dense(system.n, vals, rows, cols)

    idx = st.force_idx

    def f(qq, vv, aa):
        return np.bincount(idx, st.force(qq, vv, 0.0, aa), minlength=system.n)

    eps = 1e-6
    for jac, which in ((dense(jq, st.fq_rows, st.fq_cols), 0),
                       (dense(jv, st.fv_rows, st.fv_cols), 1),
                       (dense(ja, st.fa_rows, st.fa_cols), 2)):
        fd = np.zeros_like(jac)
        for j in range(system.n):
            e = np.zeros(system.n)
            e[j] = eps
            args_p, args_m = [q, v, a], [q, v, a]
            args_p[which] = args_p[which] + e
            args_m[which] = args_m[which] - e
            fd[:, j] = (f(*args_p) - f(*args_m)) / (2 * eps)
        scale = np.abs(fd).max()
        assert np.abs(jac - fd).max() < 1e-6 * scale, (which, np.abs(jac - fd).max(), scale)


def test_summed_tangent_equals_the_three_weighted_jacobians():
    """``force_tangent`` (the three local Jacobians summed before the map to the support's
    coordinates) against wq ∂f/∂q + ∂f/∂v diag(wv) + wa ∂f/∂a summed from the global blocks,
    and the Newton matrix the system assembles with it against the blockwise sum; a velocity
    weight that differs inside one section's support is refused (None: the system then sums
    the three global blocks)."""
    model, line = beam_line()
    system = System(model)
    rng = np.random.default_rng(5)
    q = system.q0_raw + 1e-2 * rng.standard_normal(system.n)
    v, a = rng.standard_normal(system.n), rng.standard_normal(system.n)
    st = _set(system, line)
    wq, wa = -0.7, 2.3e-5
    wv = np.full(system.n, 31.0)
    wv[system.first_order] = 5.0  # the states' own weight: not a column of ∂f/∂v
    jq, jv = st.force_jacobians(q, v, 0.0, a)
    ja = st.acceleration_jacobian(q, v, 0.0, a)

    def dense(vals, rows, cols):
        return _dense(system.n, vals, rows, cols)

    want = (wq * dense(jq, st.fq_rows, st.fq_cols) + dense(jv * wv[st.fv_cols], st.fv_rows,
                                                            st.fv_cols)
            + wa * dense(ja, st.fa_rows, st.fa_cols))
    got = dense(st.force_tangent(q, v, 0.0, a, wq, wv, wa), st.fq_rows, st.fq_cols)
    # measured 1.6e-17 of the largest entry (the same sums in another order)
    assert np.abs(got - want).max() <= 1e-14 * np.abs(want).max()
    uneven = wv.copy()
    uneven[st.idx48[0, 5]] *= 1.5
    assert st.force_tangent(q, v, 0.0, a, wq, uneven, wa) is None
    # the whole model's force blocks (the inflow's too), summed by the system either way
    jq, jv = system.applied_jacobians(q, v, 0.0, a)
    ja = system.acceleration_jacobian(q, v, 0.0, a)
    for w in (wv, uneven):
        blocks = system.kkt({"Dq": wq * jq, "Dv": jv * w[system.Dv_cols], "Da": wa * ja})
        kkt = system.kkt({}, forces=(q, v, 0.0, a, wq, w, wa))
        assert np.abs((kkt - blocks).toarray()).max() <= 1e-14 * np.abs(want).max()


def test_bad_input_is_refused_with_the_parameter_named():
    wing = PrescribedBody("wing", lambda t: (np.zeros(3), WING, *[np.zeros(3)] * 4))
    fl = FlightCondition(10.0)
    with pytest.raises(ValueError, match="chord"):
        LiftingLine("a", wing, fl, chord=-1.0, span=(0, 1))
    with pytest.raises(ValueError, match="wake_states"):
        LiftingLine("a", wing, fl, chord=1.0, span=(0, 1), wake_states=12)
    with pytest.raises(ValueError, match="span"):
        LiftingLine("a", wing, fl, chord=1.0)
    with pytest.raises(ValueError, match="lift_end"):
        LiftingLine("a", wing, fl, chord=1.0, span=(0, 1), lift_end=2.0)
    with pytest.raises(ValueError, match="flight speed"):
        FlightCondition(-1.0)


def test_forward_flight_inflow_follows_the_blade_loads():
    """Rigid rotor at μ = 0.2 with the shaft 3° forward: the mean Pitt–Peters states over a
    revolution are the model's steady states for the mean load forcing the lifting lines
    computed (C_T, C_s, C_c through ``load_weights``), and those follow the closed-form L
    matrix λ = L V⁻¹ (C_T, C_s, C_c) — Glauert's λ0 = C_T/(2V_T) plus the skew coupling of
    the pitch moment, the gradients (15π/64) X C_T/V_T + 2(1 − X²) C_c/V_m and
    2(1 + X²) C_s/V_m; the inflow is larger at the rear and on the advancing side."""
    mu = 0.2
    flight = FlightCondition(mu * OMEGA * R_ROTOR, np.radians(3.0), RHO)
    model, inflow, lines = rotor(np.radians(8.0), flight=flight)
    system = System(model)
    st = _set(system, lines[0])
    o = system.offset[inflow]
    scale = 1.0 / (RHO * OMEGA**2 * R_ROTOR**4)

    def fn(q, v, a, t):
        out = st.airloads(q, v, a)
        w = inflow.load_weights(*inflow.disk_coordinates(out["position"]))
        forcing = (w * (out["force"][:, 2] * out["ds"] * scale)[:, None]).sum(axis=0)
        return np.concatenate([forcing, q[o : o + 3]])

    spr = 96
    rec, cb = _midpoint_recorder(system, fn)
    sim = simulate(model, 1.5, 2 * np.pi / OMEGA / spr, reactions=False, record_every=10**9,
                   callback=cb, system=system, record_initial=True)
    assert sim.converged, sim.message
    r = np.array(rec)[-spr:]
    forcing, states = r[:, :3].mean(axis=0), r[:, 3:].mean(axis=0)
    steady = inflow.steady_states(forcing)
    # the forcing carries a 4/rev ripple (rigid blades); the mean states differ from the
    # steady states of the mean forcing only at second order in it: measured 1.9e-10 relative
    assert np.abs(states - steady).max() < 1e-8 * abs(steady[0]), (states, steady)
    lam0 = states[0]
    ct, cs, cc = forcing
    mu_p = mu * np.cos(np.radians(3.0))
    lam = mu * np.sin(np.radians(3.0)) + lam0
    vt = np.hypot(mu_p, lam)
    vm = (mu_p**2 + lam * (lam + lam0)) / vt
    x = mu_p / (vt + lam)  # tan(χ/2), χ = atan(μ/λ)
    k = 15 * np.pi / 64 * x
    closed = np.array([0.5 * ct / vt - k * cc / vm, 2 * (1 + x * x) * cs / vm,
                       k * ct / vt + 2 * (1 - x * x) * cc / vm])
    assert np.abs(states - closed).max() < 1e-8 * lam0, (states, closed)  # measured 2.0e-10
    assert states[2] > 0 and states[1] > 0  # more inflow at the rear and on the advancing side


@pytest.mark.slow
@pytest.mark.parametrize("n", [2, 4, 6, 8, 10])
def test_harmonic_pitch_error_against_theodorsen_for_every_supported_n(n):
    """k from 0.02 to 2: the simulated lift follows the finite-state model's closed form, and
    its error against Theodorsen is that model's own C_N − C (the table of
    tests/solver/test_airfoil.py)."""
    worst = 0.0
    for k in (0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0):
        w, lift, _ = typical_section(k, n, 1e-3, 0.0)
        lm, _ = _reference(w, n, 1e-3, 0.0, lambda kk: lift_deficiency(kk, n))
        lt, _ = _reference(w, n, 1e-3, 0.0)
        assert abs(lift - lm) < 1.5e-3 * abs(lm), (k, lift, lm)
        worst = max(worst, abs(lift - lt) / abs(lt))
    print(f"N = {n}: max relative lift error against Theodorsen {worst:.4f}")
    assert worst < MODEL_ERROR[n] * 1.5 + 2e-3
