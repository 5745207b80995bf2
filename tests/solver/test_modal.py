"""The modal structure and its attachment joint (:mod:`solver.modal`) against analysis.

Every expected value is independent of the code under test: the closed-form frequency response
of a single-degree-of-freedom oscillator, the damped free response's frequency and decay, a
generalized eigenproblem of the reduced linear system assembled here with numpy from the body's
mass and inertia and the shapes, and energy sums recomputed from the recorded modal motion.
Each tolerance is commented with the error measured when the test was written.

Forced responses start on the exact periodic solution; the small transient left by the
discretization is fitted together with the steady harmonic (the linear response's exact form:
a harmonic at the forcing frequency plus the damped free mode), so three forcing periods do.

Runtime (2 cores): about 3 s.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from solver.bodies import PointMass, RigidBody
from solver.equilibrium import Spin, equilibrium
from solver.forces import AppliedLoad
from solver.integrators import initial_accelerations, make_integrator
from solver.modal import ModalAttachment, ModalStructure
from solver.model import Model
from solver.modes import natural_frequencies
from solver.system import System
from tests.solver.models import rodrigues

TWO_PI = 2.0 * np.pi

# one airframe mode, a light body at the attachment point, a harmonic load there
FN, ZETA, M_MODE = 2.0, 0.05, 10.0  # Hz, 1, kg
W_FORCE = TWO_PI * 2.6  # rad/s, above resonance
T_END = 1.2  # s: 3.1 forcing periods, a whole number of every step used


def _skew(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def sdof(m_eff: float, force: float):
    """Closed form of m_eff η̈ + c η̇ + k η = force cos Ωt (k, c of the mode alone): the complex
    amplitude H (η = Re H e^{iΩt}), and the free mode's decay rate σ and damped frequency ω_d."""
    wn = TWO_PI * FN
    k, c = M_MODE * wn**2, 2.0 * ZETA * wn * M_MODE
    h = force / (k - m_eff * W_FORCE**2 + 1j * c * W_FORCE)
    sigma = c / (2.0 * m_eff)
    return h, sigma, np.sqrt(k / m_eff - sigma**2)


def fit_harmonic(t, y, sigma, wd):
    """Complex amplitude Y of y ≈ Re Y e^{iΩt} + e^{−σt}(a cos ω_d t + b sin ω_d t), least
    squares (y: samples × signals)."""
    basis = np.column_stack([np.cos(W_FORCE * t), np.sin(W_FORCE * t),
                             np.exp(-sigma * t) * np.cos(wd * t),
                             np.exp(-sigma * t) * np.sin(wd * t)])
    coef = np.linalg.lstsq(basis, y, rcond=None)[0]
    return coef[0] - 1j * coef[1]


def march(model, h, signals, rho_inf=0.8):
    """Generalized-α to T_END; samples of ``signals(integ)`` at every step (with t = 0).
    Returns (t, samples, integrator)."""
    integ = make_integrator(System(model), "galpha", h, rho_inf=rho_inf)
    n = round(T_END / h)
    t, y = [integ.t], [signals(integ)]
    for _ in range(n):
        info = integ.step()
        assert info.converged, info.message
        t.append(integ.t)
        y.append(signals(integ))
    return np.array(t), np.array(y), integ


def richardson(coarse, fine):
    """Second-order Richardson extrapolation from steps 2h and h."""
    return (4.0 * fine - coarse) / 3.0


# ------------------------------------------------------------ translational SDOF, forced
PHI_T, M_BODY, F0 = 0.5, 1.0, 3.0  # m per m of η, kg, N


def translational_model(h_c, load=True):
    """The mode carrying a point mass at its attachment point, pushed by F0 cos Ωt along x;
    started on the exact periodic solution η = Re H e^{iΩt} (H = ``h_c``): the point mass sits
    at Φ η(0) (the undeformed structure's point is the origin). ``load`` False: unloaded."""
    eta0, rate0 = h_c.real, (1j * W_FORCE * h_c).real
    model = Model()
    af = model.add(ModalStructure("airframe", [FN], [ZETA], [M_MODE], displacement=[eta0],
                                  velocity=[rate0]))
    p0 = (PHI_T * eta0, 0.0, 0.0)
    mass = model.add(PointMass("mass", M_BODY, position=p0, velocity=(PHI_T * rate0, 0, 0)))
    att = model.add(ModalAttachment("mount", mass, af, p0, [[PHI_T], [0.0], [0.0]]))
    if load:
        model.add(AppliedLoad("shaker", mass,
                              force=lambda t: (F0 * np.cos(W_FORCE * t), 0.0, 0.0)))
    return model, af, mass, att


def test_forced_translational_mode_matches_closed_form_frequency_response():
    """Steady displacement, velocity and acceleration of the attachment point (station outputs
    Φ η, Φ η̇, Φ η̈) against |H| = F0 φ² / √((k − m_eff Ω²)² + (cΩ)²) and its phase, with
    m_eff = m + m_body φ² (the point mass moves with the structure).

    Generalized-α (ρ∞ = 0.8) at h = 8e-4 and 4e-4 s (Ωh = 0.013, 0.0065): the displacement
    errs by 7.0e-5 and 1.75e-5 relative (order 2.00), and by 1.9e-9 after Richardson
    extrapolation; velocity and acceleration (the scheme's q̈) alike. The station motion at
    the end from the equations of motion errs by 1.6e-5 at 4e-4 s, 2.1e-9 after Richardson.
    The modal frequency and damping ratio of the unloaded model (``solver.modes``) match
    ω_n √(m/m_eff) and c/(2√(k m_eff)) to 2.2e-16."""
    h_c, sigma, wd = sdof(M_MODE + M_BODY * PHI_T**2, PHI_T * F0)
    u_exact = PHI_T * h_c * np.array([1.0, 1j * W_FORCE, -W_FORCE**2])
    station = {"mount": [[PHI_T], [0.0], [0.0]]}
    amps, ends = [], []
    for h in (8e-4, 4e-4):
        model, af, mass, _ = translational_model(h_c)

        def signals(integ, af=af, mass=mass):
            st = af.station_motion(station, integ, acceleration="scheme")["mount"]
            o = integ.sys.offset[mass]
            # the point mass's own position against the station's displacement: same motion
            assert integ.q[o] == pytest.approx(st.displacement[0], abs=1e-15)
            return [st.displacement[0], st.velocity[0], st.acceleration[0]]

        t, y, integ = march(model, h, signals)
        amps.append(fit_harmonic(t, y, sigma, wd))
        # station outputs at the end from the equations of motion (any scheme)
        end = af.station_motion(station, integ)["mount"]
        ends.append(np.array([end.displacement[0], end.velocity[0], end.acceleration[0]]))
    err = [np.abs(a / u_exact - 1.0) for a in amps]
    # measured 7.0e-5, 5.5e-5, 4.0e-5 (u, u̇, ü) at 8e-4 s, a quarter of that at 4e-4 s
    assert np.all(err[0] < 1e-4) and np.all(err[1] < 2.5e-5)
    order = np.log2(err[0] / err[1])
    assert np.all(np.abs(order - 2.0) < 0.05)  # measured 2.000
    rich = richardson(*amps)
    # measured 1.9e-9, 1.6e-9, 1.1e-9 (amplitude and phase together: the complex ratio's
    # distance from 1)
    np.testing.assert_array_less(np.abs(rich / u_exact - 1.0), 1e-8)
    # the end-time station motion from the equations of motion: Richardson at the same t
    t_end = t[-1]
    exact_end = (u_exact * np.exp(1j * W_FORCE * t_end)).real
    scale = np.abs(u_exact)
    # measured 1.6e-5, 9.5e-6, 8.4e-6 at 4e-4 s (order 2.00), 2.1e-9 at most after
    # Richardson (relative to each amplitude)
    assert np.all(np.abs(ends[1] - exact_end) < 2.5e-5 * scale)
    assert np.all(np.abs(richardson(*ends) - exact_end) < 1e-8 * scale)

    # natural frequency and damping of the assembled linear model
    md = natural_frequencies(translational_model(0.0j, load=False)[0])
    m_eff = M_MODE + M_BODY * PHI_T**2
    wn = TWO_PI * FN
    assert md.omega[0] == pytest.approx(wn * np.sqrt(M_MODE / m_eff), rel=1e-12)
    assert md.damping_ratio[0] == pytest.approx(ZETA * wn * M_MODE
                                                / np.sqrt(M_MODE * wn**2 * m_eff), rel=1e-12)


def _reactions_after(model, att, scheme: str, h: float, steps: int):
    """The integrator after ``steps`` steps of ``scheme`` at ``h``, and there, with the
    multipliers consistent with the state's accelerations, the attachment's force and moment
    on its body (``System.reaction``) and its generalized force on the modes."""
    integ = make_integrator(System(model), scheme, h)
    for _ in range(steps):
        integ.step()
    s = integ.sys
    _, lam, _ = initial_accelerations(s, integ.q, integ.v, integ.t, multipliers=True)
    force, moment = s.reaction(att, integ.q, lam, integ.t)
    return integ, force, moment, att.modal_force(s, integ.q, lam, integ.t)


def test_attachment_reaction_is_the_generalized_force_on_the_mode():
    """The attachment's force on the body F (``System.reaction``) and on the mode Q
    (``ModalAttachment.modal_force``, ``ModalStructure.generalized_force``) are action and
    reaction through the shape, Q = −Φ_tᵀ F, and with the multipliers consistent with the
    state's accelerations Q = m η̈ + c η̇ + k η (the mode's own equation), at a state of the
    forced run: measured 0 and 3e-16 relative. The scheme's own q̈ (generalized-α) agrees with
    the equations of motion's to 2.8e-14."""
    h_c, _, _ = sdof(M_MODE + M_BODY * PHI_T**2, PHI_T * F0)
    model, af, _, att = translational_model(h_c)
    integ, force, moment, q_mode = _reactions_after(model, att, "galpha", 1e-3, 37)
    assert np.all(moment == 0.0)
    assert q_mode[0] == pytest.approx(-PHI_T * force[0], rel=1e-14)
    eta, rate, acc = af.modal_state(integ)
    wn = TWO_PI * FN
    own = M_MODE * (acc + 2 * ZETA * wn * rate + wn**2 * eta)
    q_total = af.generalized_force(integ)
    assert q_total[0] == pytest.approx(q_mode[0], rel=1e-14)
    assert q_total[0] == pytest.approx(own[0], rel=1e-12)
    assert af.modal_state(integ, acceleration="scheme")[2][0] == pytest.approx(acc[0], rel=1e-11)


def test_attachment_moment_enters_the_modes_through_the_rotation_shapes():
    """Three modes and a rigid body: the generalized force of the attachment on the modes is
    Q = −Φ_tᵀ F − Φ_rᵀ M, F and M the force and moment (about the point) the attachment
    applies to the body (``System.reaction``), to first order in the rotation: measured
    3.8e-10 relative at |Φ_r η| ≈ 3e-9 rad (3.8e-11 at a tenth of the amplitude)."""
    model, af, _ = three_mode_model(rate=(5e-6, -4e-6, 3e-6))
    att = model.elements[-1]
    integ, force, moment, q_mode = _reactions_after(model, att, "ep", 2e-3, 10)
    scale = np.abs(q_mode).max()
    assert np.abs(q_mode + PHI_T3.T @ force + PHI_R3.T @ moment).max() < 2e-9 * scale
    np.testing.assert_array_equal(af.generalized_force(integ), q_mode)  # the only attachment


# ---------------------------------------------------------------- torsional SDOF, forced
PHI_R, M0 = 2.0, 0.05  # rad per m of η, N·m: J_z φ_r² is a third of m
J_BODY = np.array([0.4, 0.6, 0.8])  # kg·m², principal, body axes = global at rest


def torsional_model(h_c, load=True):
    """A mode with a rotational shape only (about z, φ_r per m of η; the point held fixed,
    Φ_t = 0) carrying a rigid body at its centre of mass, turned by M0 cos Ωt about z; started
    on the periodic solution (the body turned by φ_r η(0) about z). ``load`` False: unloaded."""
    eta0, rate0 = h_c.real, (1j * W_FORCE * h_c).real
    model = Model()
    af = model.add(ModalStructure("airframe", [FN], [ZETA], [M_MODE], displacement=[eta0],
                                  velocity=[rate0]))
    centre = np.array([0.3, -0.2, 0.1])
    body = model.add(RigidBody("disc", 4.0, J_BODY, position=centre,
                               orientation=rodrigues((0, 0, 1), PHI_R * eta0),
                               angular_velocity=(0.0, 0.0, PHI_R * rate0)))
    model.add(ModalAttachment("mount", body, af, centre, np.zeros((3, 1)),
                              [[0.0], [0.0], [PHI_R]]))
    if load:
        model.add(AppliedLoad("torque", body,
                              moment=lambda t: (0.0, 0.0, M0 * np.cos(W_FORCE * t))))
    return model, af, body


def test_forced_torsional_mode_matches_closed_form():
    """The body's rotation ψ about z (from its directors, atan2(d1_y, d1_x)) against the
    torsional SDOF (m + J_z φ_r²) η̈ + c η̇ + k η = φ_r M0 cos Ωt, ψ = φ_r η (J_z φ_r² is a
    third of m, so the body's inertia matters at the percent level).

    Generalized-α at h = 8e-4 and 4e-4 s: measured 5.4e-5 and 1.35e-5 relative (order
    2.00), 8.4e-9 after Richardson extrapolation. That remainder is the finite rotation, not
    the step: the attachment's measure sin ψ and the body's kinetic energy are exact to first
    order, and at |ψ| = 1.0e-4 rad their relative effects are of order ψ² (with half the
    torque the remainder falls fourfold, to 2.1e-9). Natural frequency (``solver.modes``,
    unloaded) against ω_n √(m/(m + J_z φ_r²)): measured 2e-16."""
    j_eff = M_MODE + J_BODY[2] * PHI_R**2
    h_c, sigma, wd = sdof(j_eff, PHI_R * M0)
    psi_exact = PHI_R * h_c
    amps = []
    for h in (8e-4, 4e-4):
        model, _, body = torsional_model(h_c)

        def signals(integ, body=body):
            d = integ.sys.directors(integ.q, body)
            return np.arctan2(d[1, 0], d[0, 0])

        t, y, integ = march(model, h, signals)
        # the point stays where it was (Φ_t = 0 holds it): measured 0 m
        o = integ.sys.offset[body]
        assert np.abs(integ.q[o : o + 3] - [0.3, -0.2, 0.1]).max() < 1e-12
        amps.append(fit_harmonic(t, y, sigma, wd))
    err = [abs(a / psi_exact - 1.0) for a in amps]
    assert err[0] < 7e-5 and err[1] < 2e-5  # measured 5.4e-5, 1.35e-5
    assert abs(np.log2(err[0] / err[1]) - 2.0) < 0.05  # measured 2.0006
    assert abs(richardson(*amps) / psi_exact - 1.0) < 2e-8  # measured 8.4e-9

    md = natural_frequencies(torsional_model(0.0j, load=False)[0])
    assert md.omega[0] == pytest.approx(TWO_PI * FN * np.sqrt(M_MODE / j_eff), rel=1e-12)


# ------------------------------------------------------------- three modes, rigid body
FREQS = np.array([3.0, 5.5, 9.0])  # Hz
ZETAS = np.array([0.02, 0.03, 0.05])
MASSES = np.array([50.0, 30.0, 20.0])  # kg
PHI_T3 = np.array([[0.8, 0.1, -0.3], [0.2, -0.6, 0.4], [0.1, 0.3, 0.7]])
PHI_R3 = np.array([[0.05, -0.2, 0.1], [0.3, 0.1, -0.15], [-0.1, 0.25, 0.2]])  # rad/m
BODY_MASS = 12.0
BODY_J = np.array([[1.5, 0.1, -0.2], [0.1, 2.0, 0.05], [-0.2, 0.05, 2.5]])  # body axes
BODY_R = rodrigues((1.0, -2.0, 0.5), 0.7)
BODY_X = np.array([1.0, 0.5, -0.3])
MOUNT = np.array([1.2, 0.2, -0.5])


def three_mode_model(damping=ZETAS, rate=(0.0, 0.0, 0.0)):
    """Three modes carrying a rigid body (full inertia, tilted) at a point off its centre of
    mass, translation and rotation attached; ``rate`` the initial η̇ (the body's velocity
    made consistent with it)."""
    rate = np.asarray(rate, dtype=float)
    omega = PHI_R3 @ rate
    model = Model()
    af = model.add(ModalStructure("airframe", FREQS, damping, MASSES, velocity=rate))
    body = model.add(RigidBody("gearbox", BODY_MASS, BODY_J, position=BODY_X,
                               orientation=BODY_R,
                               velocity=PHI_T3 @ rate + np.cross(omega, BODY_X - MOUNT),
                               angular_velocity=omega))
    model.add(ModalAttachment("mount", body, af, MOUNT, PHI_T3, PHI_R3))
    return model, af, body


def reduced_matrices():
    """M, C, K of the three modes with the body riding on them, from the body's kinetic energy
    ½ m |v_c|² + ½ ωᵀ J_g ω with ω = Φ_r η̇ and v_c = (Φ_t − [r×] Φ_r) η̇, r = x_c − point."""
    r = BODY_X - MOUNT
    tc = PHI_T3 - _skew(r) @ PHI_R3
    jg = BODY_R @ BODY_J @ BODY_R.T
    m = np.diag(MASSES) + BODY_MASS * tc.T @ tc + PHI_R3.T @ jg @ PHI_R3
    w = TWO_PI * FREQS
    return m, np.diag(2 * ZETAS * w * MASSES), np.diag(MASSES * w**2)


def test_three_modes_with_rigid_body_natural_frequencies():
    """Natural frequencies of the assembled model (``solver.modes``) against the generalized
    eigenproblem K φ = ω² M φ of the reduced system (scipy ``eigh``), and with damping the
    eigenvalues of the first-order state matrix [[0, I], [−M⁻¹K, −M⁻¹C]] (numpy).
    Measured 2.2e-16 (undamped) and 4.7e-16 (damped) relative: roundoff."""
    m, c, k = reduced_matrices()
    md = natural_frequencies(three_mode_model(damping=np.zeros(3))[0])
    w2 = sla.eigh(k, m, eigvals_only=True)
    np.testing.assert_allclose(md.omega, np.sqrt(w2), rtol=1e-12)

    md = natural_frequencies(three_mode_model()[0])
    a = np.block([[np.zeros((3, 3)), np.eye(3)],
                  [-np.linalg.solve(m, k), -np.linalg.solve(m, c)]])
    ev = np.linalg.eigvals(a)
    ev = ev[ev.imag > 0]
    ev = ev[np.argsort(np.abs(ev))]
    np.testing.assert_allclose(md.eigenvalues, ev, rtol=1e-12)


@pytest.mark.parametrize("damped", [False, True])
def test_energy_preserving_scheme_books_modal_energy_and_damping(damped):
    """``ep``, free vibration of the three modes and the body (400 steps of 2e-3 s, about 7
    periods of the top mode): with no damping the energy ½ Σ m η̇² + ½ Σ mω² η² + the body's
    is conserved (measured 8.5e-14 relative, roundoff accumulated at the Newton tolerance);
    with damping E − E0 equals the booked work (measured 1.5e-14 of E0), that work is
    negative and equals −Σ c_i (Δη_i)²/h over the steps recomputed from the recorded modal
    motion (the midpoint damper force times the step, measured 1.6e-13 relative), and 55 % of
    the energy is lost."""
    zeta = ZETAS if damped else np.zeros(3)
    model, af, _ = three_mode_model(damping=zeta, rate=(0.05, -0.04, 0.03))
    integ = make_integrator(System(model), "ep", 2e-3)
    idx = af.indices(integ.sys)
    e0 = integ.energy()
    etas, energy, work = [integ.q[idx].copy()], [e0], [0.0]
    for _ in range(400):
        assert integ.step().converged
        etas.append(integ.q[idx].copy())
        energy.append(integ.energy())
        work.append(integ.work)
    energy, work = np.array(energy), np.array(work)
    balance = np.abs(energy - e0 - work).max() / e0
    assert balance < 1e-12
    if not damped:
        # the constraint forces' work, booked too: roundoff (measured 8e-14 of E0)
        assert np.abs(work).max() < 1e-12 * e0
        assert np.abs(energy - e0).max() < 1e-12 * e0
        return
    c = 2 * zeta * TWO_PI * FREQS * MASSES
    deta = np.diff(np.array(etas), axis=0)
    dissipated = float(np.sum(c * deta**2) / integ.h)
    assert -work[-1] == pytest.approx(dissipated, rel=1e-11)
    assert 0.5 < 1.0 - energy[-1] / e0 < 0.6  # measured 0.552


def test_energy_decaying_scheme_balance_with_modes():
    """``ed`` on the damped three-mode model: E − E0 = W − D exactly (W the modal damping's
    booked work, D the scheme's numerical dissipation, ≥ 0): measured 8e-15 relative to E0
    over 200 steps of 2e-3 s; D is a small fraction of the damper's −W (measured 1.6e-4)."""
    model, _, _ = three_mode_model(rate=(0.05, -0.04, 0.03))
    integ = make_integrator(System(model), "ed", 2e-3)
    e0 = integ.energy()
    worst = 0.0
    for _ in range(200):
        assert integ.step().converged
        worst = max(worst, abs(integ.energy() - e0 - integ.work + integ.dissipation))
    assert worst < 1e-12 * e0
    assert integ.work < 0 and 0 <= integ.dissipation < 1e-3 * -integ.work


def test_station_motion_of_several_stations():
    """Station outputs are Φ_s η, Φ_s η̇, Φ_s η̈ of the modal state; η̈ from the equations of
    motion satisfies the reduced system M η̈ + C η̇ + K η = 0 of the test's own matrices
    (measured 3.2e-9 relative to Kη, the size of the neglected nonlinear terms: it falls
    tenfold with the amplitude); the scheme's own acceleration is refused by ``ep``."""
    # small motion (|η| ≈ 1e-8 m): the reduced system is the model's linearization, and its
    # nonlinear terms (of relative size |Φ_r η|) stay below 1e-8
    model, af, _ = three_mode_model(rate=(5e-6, -4e-6, 3e-6))
    integ = make_integrator(System(model), "ep", 2e-3)
    for _ in range(10):
        integ.step()
    stations = {"cockpit": np.arange(9.0).reshape(3, 3) / 9.0, "tail": PHI_R3}
    out = af.station_motion(stations, integ)
    eta, rate, acc = af.modal_state(integ)
    m, c, k = reduced_matrices()
    res = m @ acc + c @ rate + k @ eta
    assert np.abs(res).max() < 1e-8 * np.abs(k @ eta).max()
    for name, phi in stations.items():
        np.testing.assert_array_equal(out[name].displacement, phi @ eta)
        np.testing.assert_array_equal(out[name].velocity, phi @ rate)
        np.testing.assert_array_equal(out[name].acceleration, phi @ acc)
    with pytest.raises(ValueError, match="'ep' scheme keeps no end-of-step acceleration"):
        af.station_motion(stations, integ, acceleration="scheme")
    with pytest.raises(ValueError, match=r"acceleration = 'mean'"):
        af.modal_state(integ, acceleration="mean")
    with pytest.raises(ValueError, match=r"station 'tail' shapes must be a 3 x 3 array"):
        af.station_motion({"tail": np.ones((3, 2))}, integ)


def test_modal_coordinates_are_not_spun():
    """A spinning linearization cannot turn the modal coordinates (they are not 3-vectors):
    the error names the structure, also for a block of 3 modes."""
    with pytest.raises(ValueError, match=r"'airframe'.*StateBlock\.positions"):
        equilibrium(three_mode_model()[0], spin=Spin(1.0))


# --------------------------------------------------------------------------- bad inputs
@pytest.mark.parametrize(("kwargs", "message"), [
    ({"frequencies": [2.0, -1.0]}, r"frequencies\[1\] = -1\.0 Hz: outside the valid range "
                                   r"\[0, inf\) Hz"),
    ({"frequencies": [2.0, np.nan]}, r"frequencies\[1\] = nan Hz must be finite"),
    ({"frequencies": [[2.0, 3.0]]}, r"frequencies must be a 1-D sequence"),
    ({"damping_ratios": [0.1, 1.0]}, r"damping_ratios\[1\] = 1\.0: outside the valid range "
                                     r"\[0, 1\)"),
    ({"damping_ratios": [-0.1, 0.1]}, r"damping_ratios\[0\] = -0\.1: outside"),
    ({"masses": [1.0, 0.0]}, r"masses\[1\] = 0\.0 kg: outside the valid range \(0, inf\) kg"),
    ({"masses": [1.0, np.inf]}, r"masses\[1\] = inf kg must be finite"),
    ({"masses": [1.0]}, r"masses has 1 values but frequencies has 2"),
    ({"damping_ratios": [0.1, 0.1, 0.1]}, r"damping_ratios has 3 values but frequencies has 2"),
    ({"displacement": [0.0]}, r"displacement has 1 values"),
])
def test_modal_structure_rejects_bad_parameters(kwargs, message):
    args = {"frequencies": [2.0, 3.0], "damping_ratios": [0.01, 0.02], "masses": [1.0, 2.0]}
    args.update(kwargs)
    with pytest.raises(ValueError, match=r"modal structure 'af': " + message):
        ModalStructure("af", **args)


def test_modal_structure_accepts_a_scalar_damping_ratio():
    af = ModalStructure("af", [2.0, 3.0], 0.02, [1.0, 2.0])
    np.testing.assert_array_equal(af.damping_ratio, [0.02, 0.02])


def test_modal_attachment_rejects_bad_inputs():
    af = ModalStructure("af", [2.0, 3.0], 0.02, [1.0, 2.0])
    body = RigidBody("b", 1.0, (1.0, 1.0, 1.0))
    pm = PointMass("p", 1.0)
    ok = np.zeros((3, 2))
    with pytest.raises(ValueError, match=r"modal attachment 'a': translation_shapes must be a "
                                         r"3 x 2 array .* got shape \(2, 3\)"):
        ModalAttachment("a", body, af, (0, 0, 0), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"'a': rotation_shapes must be finite"):
        ModalAttachment("a", body, af, (0, 0, 0), ok, np.full((3, 2), np.nan))
    with pytest.raises(ValueError, match=r"'a': rotation_shapes given but 'p' is a point mass"):
        ModalAttachment("a", pm, af, (0, 0, 0), ok, ok)
    with pytest.raises(ValueError, match=r"'a': translation_shapes and rotation_shapes are "
                                         "both None"):
        ModalAttachment("a", body, af, (0, 0, 0), None, None)
    with pytest.raises(ValueError, match=r"'a': point must be 3 finite numbers"):
        ModalAttachment("a", body, af, (0, 0), ok)
    with pytest.raises(ValueError, match=r"'a': modal must be a ModalStructure"):
        ModalAttachment("a", body, body, (0, 0, 0), ok)
    with pytest.raises(ValueError, match=r"'a': body must be a body"):
        ModalAttachment("a", af, af, (0, 0, 0), ok)


# ------------------------------------------- a steady load above the centre of rotation
ROLL_HZ, ROLL_INERTIA, ARM, THRUST = 1.0, 6000.0, 1.7, 7.0e4  # Hz, kg m2, m, N
HUB_MASS, HUB_INERTIA = 50.0, 8.0  # kg, kg m2


def roll_model(centre: bool):
    """One roll mode (1 rad about x per m of η, about the origin) carrying a rigid body ARM
    above the origin, pulled up by a steady force THRUST fixed in space; ``centre``: the
    attachment knows the origin as its rotation centre."""
    model = Model()
    af = model.add(ModalStructure("airframe", [ROLL_HZ], [0.0], [ROLL_INERTIA]))
    hub = model.add(RigidBody("hub", HUB_MASS, inertia=(HUB_INERTIA,) * 3,
                              position=(0.0, 0.0, ARM)))
    model.add(ModalAttachment("mount", hub, af, (0.0, 0.0, ARM), [[0.0], [-ARM], [0.0]],
                              [[1.0], [0.0], [0.0]],
                              rotation_centre=(0.0, 0.0, 0.0) if centre else None))
    model.add(AppliedLoad("thrust", hub, force=lambda t: (0.0, 0.0, THRUST)))
    return model


@pytest.mark.parametrize("centre", [True, False])
def test_steady_load_above_the_rotation_centre_stiffens_the_roll_mode(centre):
    """A roll mode carrying a body ARM above its centre, pulled up by a dead load T: on the
    arc the point drops by ARM φ²/2 as it turns, so the load adds the stiffness T·ARM, and
    ω² = (k + T·ARM) / (I + m ARM² + J) (k = I ω0², body mass m and inertia J), the pendulum's
    closed form; the linear rows (no centre) miss T·ARM. Measured: 1e-13 relative with the
    centre; without it the frequency is the unloaded one."""
    md = natural_frequencies(roll_model(centre))
    k = ROLL_INERTIA * (TWO_PI * ROLL_HZ) ** 2
    inertia = ROLL_INERTIA + HUB_MASS * ARM**2 + HUB_INERTIA
    geometric = THRUST * ARM if centre else 0.0
    expected = np.sqrt((k + geometric) / inertia)
    roll = md.omega[np.argmin(np.abs(md.omega - expected))]
    np.testing.assert_allclose(roll, expected, rtol=1e-10)
