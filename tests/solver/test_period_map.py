"""Floquet multipliers of a multibody model's period map (:mod:`solver.period_map`) against
closed forms: Arnoldi's Ritz values of a matrix with a known spectrum, and a disc rolling in a
hole of a spinning hub — a centrifugal pendulum with rolling resistance, linear time-invariant
in the hub's frame, whose multipliers over a revolution are e^{λT}. The rolling relations'
arc length, the disc's spin and the contact's integral must not show up as multipliers 1.
Newton–Picard's correction from the Arnoldi run's slow subspace against the fixed point of an
affine map, and on the disc against marching; shooting by it against shooting by extrapolation."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

from solver.integrators import make_integrator
from solver.period_map import (
    SlowSubspace,
    arnoldi,
    kinetic_metric,
    map_multipliers,
    perturbed,
)
from solver.system import System
from tests.solver.models import hub_rolling_disc

OMEGA, ARM, R, R_PIN, MASS = 27.0, 0.4, 0.05, 0.015, 1.0  # hub_rolling_disc's defaults
DAMPING = 5e-4  # N m s/rad: about 2 % of critical on the swing


def test_arnoldi_finds_the_dominant_eigenvalues_of_a_known_spectrum():
    rng = np.random.default_rng(3)
    n = 60
    # a non-normal matrix with eigenvalues 0.95 e^{±0.4i}, 0.9, 0.5 and the rest below 0.3
    lead = np.array([0.95 * np.exp(0.4j), 0.95 * np.exp(-0.4j), 0.9, 0.5])
    rest = 0.3 * rng.uniform(-1, 1, n - 4)
    d = np.zeros((n, n))
    d[0:2, 0:2] = [[lead[0].real, -lead[0].imag], [lead[0].imag, lead[0].real]]
    d[2, 2], d[3, 3] = 0.9, 0.5
    d[4:, 4:] = np.diag(rest)
    s = rng.standard_normal((n, n))
    a = s @ d @ np.linalg.inv(s)
    vals, res = arnoldi(lambda v: a @ v, rng.standard_normal(n), 40, min_steps=8, tol=1e-10)
    assert sorted(np.abs(vals[:3])) == pytest.approx([0.9, 0.95, 0.95], abs=1e-9)
    assert min(abs(vals[0] - lead[0]), abs(vals[0] - lead[1])) < 1e-9
    assert res[0] <= 1e-10 * abs(vals[0])


def _disc_exact() -> np.ndarray:
    # 1.5 m ρ² φ'' + c (R/r)² φ' + m Ω² a ρ φ = 0 (ρ = R − r): the disc's translation and its
    # rolling spin ρ φ'/r add a half to the inertia, the centrifugal field's potential is
    # −½ m Ω² |x|², and the rolling resistance acts on the disc's rate relative to the
    # contact's Frenet triad, −(R/r) φ'; the gyroscopic terms of a one-degree-of-freedom
    # motion vanish
    rho = R - R_PIN
    lam = np.roots([1.5 * MASS * rho**2, DAMPING * (R / R_PIN) ** 2, MASS * OMEGA**2 * ARM * rho])
    return np.exp(lam * 2 * np.pi / OMEGA)


def _disc_multipliers(scheme: str, steps: int) -> np.ndarray:
    model = hub_rolling_disc(0.0, damping=DAMPING)[0]  # at rest in the hub's frame
    integ = make_integrator(System(model), scheme, 2 * np.pi / OMEGA / steps,
                            rho_inf=0.8 if scheme == "galpha" else None, tol=1e-10)
    # a perturbation of 1e-4 (m, and m/s over Ω): the energy-conserving steps' discrete
    # gradients carry a roundoff that perturbations below about 1e-5 meet (measured on ep:
    # the error at 200 steps 0.012 with 1e-4 and 1e-5, 0.005–0.016 with 1e-6 at Newton
    # tolerances 1e-10–1e-14; generalized-α 0.0124 from 1e-4 to 1e-7)
    mm = map_multipliers(integ, steps, rate=OMEGA, vectors=12, min_vectors=4, eps=1e-4)
    assert mm.largest == pytest.approx(abs(mm.values[0]))
    return mm.values


@pytest.mark.parametrize("scheme", ["ep", "galpha", "ed"])
def test_rolling_disc_multipliers_converge_at_second_order_to_its_pendulum(scheme):
    exact = _disc_exact()
    errors = []
    for steps in (100, 200):
        mu = _disc_multipliers(scheme, steps)
        # the swing's pair; every other direction decays within the revolution: no multiplier
        # 1 from the arc length, the spin or the contact's integral (measured below 1e-4)
        assert np.abs(mu[2:]).max() < 1e-3
        assert mu[0] == pytest.approx(np.conj(mu[1]))
        errors.append(min(abs(mu[0] - exact[0]), abs(mu[0] - exact[1])))
    # measured: 0.048 and 0.012 (ep), 0.050 and 0.012 (galpha, ρ∞ 0.8), 0.053 and 0.014 (ed):
    # the swing's phase error of a second-order step, ratio 3.7–4.1 (the modulus is right to
    # 2e-3 at 100 steps)
    assert errors[1] < 0.015
    assert 3.5 < errors[0] / errors[1] < 4.5


def _known_map(n: int, fast: float, seed: int = 3) -> np.ndarray:
    # a non-normal matrix with the slow eigenvalues 0.95 e^{±0.4i}, 0.9, 0.85 and the rest
    # uniformly within ±fast
    rng = np.random.default_rng(seed)
    d = np.zeros((n, n))
    lead = 0.95 * np.exp(0.4j)
    d[0:2, 0:2] = [[lead.real, -lead.imag], [lead.imag, lead.real]]
    d[2, 2], d[3, 3] = 0.9, 0.85
    d[4:, 4:] = np.diag(fast * rng.uniform(-1, 1, n - 4))
    s = rng.standard_normal((n, n))
    return s @ d @ np.linalg.inv(s)


@pytest.mark.parametrize("fast", [0.0, 0.3])
def test_newton_picard_correction_removes_the_slow_error_of_a_linear_map(fast):
    # iterates x_{j+1} = A x_j + b of an affine map, observed through C (fewer rows than
    # unknowns): from two successive iterates' observations the correction removes the slow
    # modes' error from the next iterate; what is left is the fast modes' (none with fast = 0)
    n, rows = 60, 30
    rng = np.random.default_rng(5)
    a = _known_map(n, fast)
    b = rng.standard_normal(n)
    c = rng.standard_normal((rows, n))
    fixed = np.linalg.solve(np.eye(n) - a, b)
    vals, _, _, basis, hess = arnoldi(lambda v: a @ v, rng.standard_normal(n), 40, krylov=True)
    assert sorted(np.abs(vals[:4])) == pytest.approx([0.85, 0.9, 0.95, 0.95], abs=1e-9)
    slow = SlowSubspace(["q"], np.ones(n), basis, hess, c @ basis)
    x = [fixed + rng.standard_normal(n)]
    for _ in range(8):  # the fast modes decay (0.3⁸ = 7e-5 of their start)
        x.append(a @ x[-1] + b)
    (delta,), unexplained = slow.correction(c @ x[-1] - c @ x[-2], np.ones(rows))
    corrected = a @ x[-1] + b + delta
    before = np.linalg.norm(a @ x[-1] + b - fixed)
    after = np.linalg.norm(corrected - fixed)
    # measured: 2.3e-14 of the error left without fast modes, 4.5e-4 with them (their
    # rest, and their part of the change taken for slow modes: 1.7e-3 of it unexplained);
    # marched, the slow modes' error decays by 0.95 an iterate
    assert after <= (1e-12 if fast == 0.0 else 1e-3) * before
    assert unexplained <= (1e-12 if fast == 0.0 else 1e-2)


def test_slow_subspace_pairs_are_the_jacobians_images_of_the_probes_rows():
    # the probe's rows of each Krylov vector (C v_j, with a time column) and Arnoldi's
    # Hessenberg matrix give C A v_j for the first k − 1 vectors without another march
    n, steps, cols = 60, 5, 4
    rng = np.random.default_rng(7)
    a = _known_map(n, 0.3)
    c = rng.standard_normal((steps * cols, n))
    _, _, _, basis, hess = arnoldi(lambda v: a @ v, rng.standard_normal(n), 20, krylov=True)
    times = np.arange(1, steps + 1) / steps

    def rows(x: np.ndarray) -> np.ndarray:  # the probe's rows of a state x, time first
        return np.column_stack([times, (c @ x).reshape(steps, cols)])

    slow = SlowSubspace(["q"], np.ones(n), basis, hess, c @ basis,
                        np.array([rows(v) for v in basis.T]), 0.0)
    u, ju = slow.pairs()
    k = basis.shape[1]
    assert u.shape == ju.shape == (k - 1, steps, cols + 1)
    expect = np.array([rows(a @ v) for v in basis.T[: k - 1]])
    np.testing.assert_array_equal(ju[:, :, 0], expect[:, :, 0])
    # measured 3.8e-16 of the largest image
    assert np.abs(ju - expect).max() <= 1e-13 * np.abs(expect).max()
    np.testing.assert_array_equal(u, slow.rows[: k - 1])


STEPS = 200  # the disc's steps a revolution


def _disc_off_its_rest(damping: float, amplitude: float):
    """The rolling disc at rest on the spinning hub (``damping`` its rolling resistance), the
    Arnoldi run on its revolution map that probes the disc's centre, and a start off the rest
    along the swing's mode (``amplitude`` of its largest position, m): (system, integrator,
    probe, multipliers, the start's state arrays in the subspace's keys)."""
    model, _, disc = hub_rolling_disc(0.0, damping=damping)
    system = System(model)
    integ = make_integrator(system, "galpha", 2 * np.pi / OMEGA / STEPS, rho_inf=0.8, tol=1e-10)
    o = system.offset[disc]

    def probe() -> np.ndarray:
        return integ.q[o : o + 3].copy()

    mm = map_multipliers(integ, STEPS, rate=OMEGA, vectors=12, min_vectors=4, eps=1e-4,
                         probe=probe)
    rest = integ.state()
    swing = np.real(mm.modes[:, :, 0])  # the swing's mode, in the state's units
    start = perturbed(system, [rest[k] for k in mm.subspace.keys],
                      list(amplitude * swing / np.abs(swing[0]).max()), rest["t"],
                      kinetic_metric(system))
    return system, integ, probe, mm, start


def test_newton_picard_restart_of_the_rolling_disc():
    # the disc swinging about the hole's outermost point decays by 0.70 a revolution; one
    # Newton–Picard correction from two revolutions' observations of the disc's centre (the
    # probe, through the multipliers' Arnoldi run) leaves a small fraction of the swing
    system, integ, probe, mm, start = _disc_off_its_rest(DAMPING, 1e-3)
    steps = STEPS
    sub = mm.subspace
    assert sub is not None and sub.observed.shape == (3 * steps, sub.basis.shape[1])
    rest = integ.state()
    state = dict(rest)
    state.update(zip(sub.keys, start, strict=True))

    def revolutions(count: int) -> list[np.ndarray]:
        out = []
        for _ in range(count):
            out.append(np.array([(integ.step(), probe())[1] for _ in range(steps)]))
        return out

    integ.restore(state)
    blocks = revolutions(3)
    change = blocks[-1] - blocks[-2]
    (dq, dv, *more), unexplained = sub.correction(change, np.ones(3))
    here = integ.state()
    arrays = perturbed(system, [here[k] for k in sub.keys], [dq, dv, *more], here["t"],
                       kinetic_metric(system))
    picard = np.abs(np.diff(revolutions(2), axis=0)).max()  # marched on, uncorrected
    here.update(zip(sub.keys, arrays, strict=True))
    integ.restore(here)
    newton = np.abs(np.diff(revolutions(2), axis=0)).max()
    # measured: the next revolutions' change 3.6e-9 m corrected against 6.9e-6 m marched
    # (5e-4 of it), 1.7e-4 of the change unexplained
    assert unexplained < 1e-2
    assert newton < 0.02 * picard


def _shoot_disc(disc, **options) -> tuple[object, list[str]]:
    """studies.periodic.shoot on the disc of :func:`_disc_off_its_rest` (its tuple ``disc``)
    from its start, its centre observed; the record and the progress lines."""
    from studies.periodic import shoot
    from studies.progress import reporting

    system, integ, probe, mm, start, rest = disc
    state = dict(rest)
    state.update(zip(mm.subspace.keys, start, strict=True))
    integ.restore(state)
    lines: list[str] = []
    with reporting(lines.append):
        rec = shoot(integ, lambda: np.concatenate([[integ.t], probe()]),
                    lambda block: block[:, 1:3], observe=lambda block, j: block[:, 1:4],
                    symmetry=None, system=system, steps_per_rev=STEPS, revolutions=1,
                    max_revolutions=60, **options)
    return rec, lines


def _slower_disc():
    # less rolling resistance than above: the swing decays by 0.87 a revolution, above the
    # slow modes' threshold SLOW_MODULUS; with the rest state to start from
    system, integ, probe, mm, start = _disc_off_its_rest(0.4 * DAMPING, 1e-2)
    return system, integ, probe, mm, start, integ.state()


def test_shooting_restarts_by_newton_picard_alone_with_the_slow_subspace():
    # studies.periodic.shoot given the multipliers' subspace: the disc started off its swing's
    # rest reaches the periodic response (the rest, turning with the hub) by Newton–Picard's
    # restarts only, never the extrapolation's, and in fewer revolutions than shooting by
    # extrapolation, whose response it matches
    disc = _slower_disc()
    rec, lines = _shoot_disc(disc, tolerance=1e-6, subspace=disc[3].subspace)
    restarts = [x for x in lines if "restart" in x]
    assert restarts and all("Newton–Picard restart" in x for x in restarts)
    # the recorded revolution is the rest orbit (the disc's centre, m), measured 0 m
    extrapolated, _ = _shoot_disc(disc, tolerance=1e-6)
    # measured: one restart, periodic (1e-6 of the centre's 0.435 m excursion) after 4
    # revolutions against 6 by the extrapolation; the recorded revolutions (the disc's centre)
    # 4.9e-8 m apart, both periodic to 1e-6
    assert rec.transient < extrapolated.transient
    assert np.abs(rec.samples[:, 1:4] - extrapolated.samples[:, 1:4]).max() < 2e-7


def _excursion_error(rec, exact) -> float:
    """The largest distance of ``rec``'s disc centre from ``exact``'s, over the latter's
    excursion."""
    scale = np.abs(exact.samples[:, 1:3] - exact.samples[:, 1:3].mean(axis=0)).max()
    return float(np.abs(rec.samples[:, 1:3] - exact.samples[:, 1:3]).max() / scale)


def test_a_trusted_restart_ends_the_search_one_revolution_on():
    # studies.periodic.shoot(trust_estimate=True): the disc off its rest, shot by extrapolation
    # to 1e-4, returns the revolution marched from the first restart whose estimate was within
    # the tolerance, without the test's two revolutions; it is as close to the periodic
    # response (the rest orbit, found to 1e-8) as the tolerance
    disc = _slower_disc()
    trusted, _ = _shoot_disc(disc, tolerance=1e-4, trust_estimate=True)
    tested, _ = _shoot_disc(disc, tolerance=1e-4)
    exact, _ = _shoot_disc(disc, tolerance=1e-8)
    # measured: restarted after 5 revolutions, recorded the 6th (the test records the 7th),
    # the estimate's unexplained part 7.7e-8, both records 3.3e-8 and 2.8e-8 of the centre's
    # 0.435 m excursion from the rest orbit
    assert trusted.restarts == 1 and trusted.transient + 1 == tested.transient
    assert trusted.change <= 0.5e-4
    assert _excursion_error(trusted, exact) <= 1e-4


def test_a_newton_picard_restart_that_grows_the_change_is_undone():
    # a subspace whose Jacobian is wrong (the swing's multiplier μ mirrored to 2 − μ: its
    # correction pushes the slow error the wrong way, 3.4 times over): the first test after
    # the restart finds the change grown, the march goes on from the state before it without
    # Newton–Picard, and the response is the rest orbit all the same
    disc = _slower_disc()
    sub = disc[3].subspace
    n = sub.hessenberg.shape[0]
    wrong = SlowSubspace(sub.keys, sub.weight, sub.basis, 2 * np.eye(n) - sub.hessenberg,
                         sub.observed)
    rec, lines = _shoot_disc(disc, tolerance=1e-6, subspace=wrong)
    exact, _ = _shoot_disc(disc, tolerance=1e-9)
    assert any("grew" in x and "marching on from the state before it" in x for x in lines)
    assert "after a Newton–Picard restart, found without it" in rec.note
    # measured: the change grew from 1.9e-4 to 7.5e-4; from the state before the restart the
    # extrapolation's restart found the response at revolution 10, 1.2e-8 of the centre's
    # excursion from the rest orbit
    assert _excursion_error(rec, exact) <= 1e-6


@pytest.mark.parametrize("scheme", ["galpha", "ed", "ep"])
def test_a_march_following_a_recorded_newton_path_is_the_march_on_its_own(scheme):
    # the disc swinging 0.3 rad round its hole, one revolution recorded; a march from a start
    # 1e-5 of its velocity off it that follows the recording reaches the state of that march
    # solved to roundoff, within Newton's tolerance, in fewer iterations and with no
    # factorization (at the Floquet multipliers' tight tolerance, confirmed by an update)
    model, _, _ = hub_rolling_disc(0.3, damping=DAMPING)
    system = System(model)
    integ = make_integrator(system, scheme, 2 * np.pi / OMEGA / STEPS,
                            rho_inf=0.8 if scheme == "galpha" else None, tol=1e-10)
    start = integ.state()
    with integ.tightened(1e-10), integ.recording() as path:
        for _ in range(STEPS):
            assert integ.step().converged
    assert len(path.x) == STEPS and all(lu is not None for lu in path.lu)
    base = integ.q.copy()
    off = dict(start)
    off["q"], off["v"] = perturbed(system, [start["q"], start["v"]],
                                   [np.zeros(system.n), 1e-5 * start["v"]], start["t"],
                                   kinetic_metric(system))

    def march(tol: float, follow: bool = False) -> tuple[np.ndarray, int, int]:
        integ.restore(off)
        integ.forget_factors()
        iterations = factorizations = 0
        with (integ.tightened(tol),
              integ.following(path) if follow else contextlib.nullcontext()):
            for _ in range(STEPS):
                info = integ.step()
                assert info.converged
                iterations += info.iterations
                factorizations += info.factorizations
        return integ.q.copy(), iterations, factorizations

    exact = march(1e-14)[0]
    own, own_iterations, _ = march(1e-10)
    followed, iterations, factorizations = march(1e-10, follow=True)
    change = np.abs(exact - base).max()
    # measured (galpha, ed, ep): change 3.8e-5–4.2e-5 m; the followed march's error
    # 1.7e-13–8.8e-12 m, the march's on its own 1.5e-12–8e-12 m; 2.0–2.18 iterations a step
    # against 3.06–3.12, and no factorization against 200
    assert np.abs(followed - exact).max() < 2.5e-6 * change
    assert np.abs(own - exact).max() < 2.5e-6 * change
    assert factorizations == 0
    assert iterations <= 2.5 * STEPS < own_iterations
