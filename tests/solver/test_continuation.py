"""Pseudo-arclength continuation (:mod:`solver.continuation`) on the forced Duffing oscillator
x'' + 2ζx' + x + γx³ = F cos ωt, whose one-harmonic response has a closed-form
amplitude–frequency relation and closed-form folds, and whose multi-harmonic response changes
stability (:func:`solver.floquet.hill_multipliers`) exactly at its folds."""

from __future__ import annotations

import numpy as np
import pytest

from solver.continuation import Branch, BranchPoint, continue_branch
from solver.floquet import hill_multipliers

ZETA, GAMMA, FORCE = 0.02, 0.1, 0.05  # hardening, lightly damped: two folds near ω = 1.05
START, STOP = 0.5, 2.0
K = 0.75 * GAMMA  # the cubic's one-harmonic coefficient: x³ → ¾ A² x


def one_harmonic(x: np.ndarray, w: float) -> np.ndarray:
    """Harmonic balance of x ≈ a cos ωt + b sin ωt: the cos and sin balances."""
    a, b = x
    k = 1.0 - w * w + K * (a * a + b * b)
    return np.array([k * a + 2 * ZETA * w * b - FORCE, k * b - 2 * ZETA * w * a])


def one_harmonic_jacobian(x: np.ndarray, w: float) -> tuple[np.ndarray, np.ndarray]:
    a, b = x
    k = 1.0 - w * w + K * (a * a + b * b)
    jx = np.array([[k + 2 * K * a * a, 2 * ZETA * w + 2 * K * a * b],
                   [2 * K * a * b - 2 * ZETA * w, k + 2 * K * b * b]])
    jl = np.array([-2 * w * a + 2 * ZETA * b, -2 * w * b - 2 * ZETA * a])
    return jx, jl


def amplitude_relation(amplitude2: float, w: float) -> float:
    """[(1 − ω² + ¾γA²)² + (2ζω)²] A² − F², zero on the one-harmonic branch."""
    return ((1 - w * w + K * amplitude2) ** 2 + (2 * ZETA * w) ** 2) * amplitude2 - FORCE**2


def closed_form_folds() -> list[tuple[float, float]]:
    """(ω, A) of the folds, dω/dA = 0 on the amplitude relation G(P, ω) = 0, P = A².

    With c = 1 − ω² + kP (k = ¾γ): G = (c² + 4ζ²ω²) P − F² and ∂G/∂P = c² + 4ζ²ω² + 2kPc = 0.
    The second turns the first into −2kP²c = F², so c = −F²/(2kP²) and ω² = 1 + kP − c;
    back in ∂G/∂P = 0, times 4k²P⁴:
        16ζ²k³P⁵ + 16ζ²k²P⁴ − 4k²F²P³ + 8ζ²kF²P² + F⁴ = 0,
    whose positive roots (polished by Newton on the polynomial) are the folds.
    """
    coeffs = [16 * ZETA**2 * K**3, 16 * ZETA**2 * K**2, -4 * K**2 * FORCE**2,
              8 * ZETA**2 * K * FORCE**2, 0.0, FORCE**4]
    poly = np.poly1d(coeffs)
    folds = []
    for root in np.roots(coeffs):
        if abs(root.imag) > 1e-8 * abs(root) or root.real <= 0:
            continue
        p = root.real
        for _ in range(5):
            p -= poly(p) / poly.deriv()(p)
        c = -FORCE**2 / (2 * K * p * p)
        w2 = 1 + K * p - c
        if w2 > 0:
            folds.append((float(np.sqrt(w2)), float(np.sqrt(p))))
    return sorted(folds)


def _continue(jacobian) -> Branch:
    return continue_branch(one_harmonic, [FORCE / (1 - START**2), 0.0], START, STOP,
                           jacobian=jacobian, step=0.02, min_step=1e-6, max_step=0.05,
                           x_scale=1.0, max_points=500)


@pytest.mark.parametrize("jacobian", [one_harmonic_jacobian, None], ids=["exact", "fd"])
def test_duffing_one_harmonic_branch_through_both_folds(jacobian):
    """From ω = 0.5 to 2 across the resonance's two folds. Every point satisfies the amplitude
    relation (measured |G| ≤ 3e-17 against F² = 2.5e-3; asserted 1e-9 relative); the folds
    come out at the closed form's ω and A: measured 2e-16 and 7e-16 with the exact Jacobian,
    2e-16 and 1.8e-11 with finite differences (asserted 1e-10 and 1e-9); their tangents'
    λ-components vanish to 7e-13 (asserted 1e-9)."""
    branch = _continue(jacobian)
    assert branch.complete, branch.reason
    assert branch.reason == "reached stop"
    assert branch.points[0].parameter == START
    assert branch.points[-1].parameter == STOP
    for p in branch.points:
        assert abs(amplitude_relation(p.x @ p.x, p.parameter)) <= 1e-9 * FORCE**2
        assert abs(np.linalg.norm(p.tangent) - 1) < 1e-12
        assert p.jacobian.shape == (2, 2)
    folds = [p for p in branch.points if p.fold]
    expected = closed_form_folds()
    assert len(expected) == 2 and len(folds) == 2
    # the upper fold (larger ω, the jump down) comes first along the branch
    for p, (w, a) in zip(folds, expected[::-1], strict=True):
        assert abs(p.parameter - w) < 1e-10
        assert abs(np.sqrt(p.x @ p.x) - a) < 1e-9
        assert abs(p.tangent[-1]) < 1e-9
    # λ increases, decreases between the folds, increases again: each fold crossed once
    lam = np.array([p.parameter for p in branch.points])
    i1, i2 = (i for i, p in enumerate(branch.points) if p.fold)
    assert np.all(np.diff(lam[: i1 + 1]) > 0)
    assert np.all(np.diff(lam[i1 : i2 + 1]) < 0)
    assert np.all(np.diff(lam[i2:]) > 0)
    # tangent orientation continuous
    for p, q in zip(branch.points, branch.points[1:], strict=False):
        assert p.tangent @ q.tangent > 0


# Multi-harmonic balance: x(τ) = Σ aⱼ cos hⱼτ + bⱼ sin hⱼτ, τ = ωt, odd harmonics only (the
# Duffing's symmetric response has no even ones), residual projected on the same harmonics
# from SAMPLES collocation points by the FFT (exact Galerkin for the cubic: 3·9 = 27 < 32).
HARMONICS = np.array([1, 3, 5, 7, 9])
SAMPLES = 64
TAU = 2 * np.pi * np.arange(SAMPLES) / SAMPLES
COS = np.cos(np.outer(TAU, HARMONICS))
SIN = np.sin(np.outer(TAU, HARMONICS))


def _response(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x, dx/dτ and d²x/dτ² at the collocation points from c = (a₁ … a₅, b₁ … b₅)."""
    a, b = c[: len(HARMONICS)], c[len(HARMONICS):]
    x = COS @ a + SIN @ b
    xt = SIN @ (-HARMONICS * a) + COS @ (HARMONICS * b)
    xtt = -(COS @ (HARMONICS**2 * a) + SIN @ (HARMONICS**2 * b))
    return x, xt, xtt


def multi_harmonic(c: np.ndarray, w: float) -> np.ndarray:
    x, xt, xtt = _response(c)
    r = w * w * xtt + 2 * ZETA * w * xt + x + GAMMA * x**3 - FORCE * np.cos(TAU)
    rf = np.fft.rfft(r) * (2.0 / SAMPLES)
    return np.concatenate([rf[HARMONICS].real, -rf[HARMONICS].imag])


def largest_multiplier(point: BranchPoint) -> float:
    """max |μ| of the linearization y' = [[0, 1], [−1 − 3γx(t)², −2ζ]] y about the response."""
    x, _, _ = _response(point.x)
    a = np.zeros((SAMPLES, 2, 2))
    a[:, 0, 1] = 1.0
    a[:, 1, 0] = -1.0 - 3 * GAMMA * x**2
    a[:, 1, 1] = -2 * ZETA
    return float(abs(hill_multipliers(a, point.parameter, 15)[0]))


def test_duffing_multi_harmonic_stability_changes_at_the_folds():
    """Five odd harmonics, finite-difference Jacobians. Hill's largest multiplier is < 1 on the
    lower and upper branches and > 1 on the middle one, between the two folds, and 1 at the
    folds themselves (measured |max|μ| − 1| ≤ 3e-12 there, asserted 1e-6; the nearest other
    point is 9.9e-4 from 1, asserted 1e-4). The folds lie within 1.6e-4 of the one-harmonic
    ones (the higher harmonics' share; asserted 1e-3)."""
    c0 = np.zeros(2 * len(HARMONICS))
    c0[0] = FORCE / (1 - START**2)
    branch = continue_branch(multi_harmonic, c0, START, STOP, step=0.02, min_step=1e-6,
                             max_step=0.05, x_scale=1.0, max_points=500)
    assert branch.complete, branch.reason
    folds = [i for i, p in enumerate(branch.points) if p.fold]
    assert len(folds) == 2
    i1, i2 = folds
    for i, p in enumerate(branch.points):
        mu = largest_multiplier(p)
        if p.fold:
            assert abs(mu - 1) < 1e-6
        elif i1 < i < i2:
            assert mu > 1 + 1e-4, (i, p.parameter, mu)
        else:
            assert mu < 1 - 1e-4, (i, p.parameter, mu)
    for i, (w, _) in zip(folds, closed_form_folds()[::-1], strict=True):
        assert abs(branch.points[i].parameter - w) < 1e-3


def test_decreasing_parameter_and_the_ends_of_a_branch():
    """Continuation downwards (stop < start) ends at exactly λ = stop; max_points and a
    min_step that cannot be met end it early, with the points found so far."""
    x0 = [FORCE / (1 - STOP**2), 0.0]
    down = continue_branch(one_harmonic, x0, STOP, START, jacobian=one_harmonic_jacobian,
                           step=0.02, min_step=1e-6, max_step=0.05, x_scale=1.0,
                           max_points=500)
    assert down.complete and down.points[-1].parameter == START
    # downwards the branch crosses the same two folds, the lower one first
    assert [p.fold for p in down.points].count(True) == 2
    short = continue_branch(one_harmonic, x0, STOP, START, jacobian=one_harmonic_jacobian,
                            step=0.02, min_step=1e-6, max_step=0.05, max_points=5)
    assert not short.complete and short.reason == "max_points" and len(short.points) == 5
    seen: list[BranchPoint] = []
    continue_branch(one_harmonic, x0, STOP, START, jacobian=one_harmonic_jacobian, step=0.02,
                    min_step=1e-6, max_step=0.05, max_points=5, callback=seen.append)
    assert len(seen) == 5

    def half_parabola(x, lam):
        # x = √(1 − λ) has a vertical tangent at λ = 1 and no continuation beyond it (this
        # residual only knows the upper half): the step shrinks below min_step there
        with np.errstate(invalid="ignore"):
            return np.array([x[0] - np.sqrt(1.0 - lam)])

    stuck = continue_branch(half_parabola, [1.0], 0.0, 2.0, step=0.1, min_step=1e-3,
                            max_step=0.2)
    assert not stuck.complete
    assert stuck.reason.startswith("step below min_step"), stuck.reason
    assert stuck.points and all(p.parameter < 1.0 for p in stuck.points)

    def parabola(x, lam):
        return np.array([lam + x[0] ** 2 - 1.0])

    # past the fold at λ = 1 the branch heads away from stop = 1.5 and leaves [−0.5, 2.5]
    away = continue_branch(parabola, [-np.sqrt(0.5)], 0.5, 1.5, step=0.05, min_step=1e-6,
                           max_step=0.2)
    assert not away.complete
    assert away.reason.startswith("left the parameter range"), away.reason
    folds = [p for p in away.points if p.fold]
    assert len(folds) == 1 and abs(folds[0].parameter - 1.0) < 1e-12
    assert abs(folds[0].x[0]) < 1e-6

    # a stop just short of the fold: a long step passes stop, turns at the fold and comes back
    # below stop; the branch still ends at the first crossing of λ = stop, before the fold
    for step in (0.05, 0.5):
        near = continue_branch(parabola, [-np.sqrt(0.5)], 0.5, 1.0 - 1e-8, step=step,
                               min_step=1e-6, max_step=step)
        assert near.complete and near.points[-1].parameter == 1.0 - 1e-8
        assert not any(p.fold for p in near.points)
        assert abs(near.points[-1].x[0] + 1e-4) < 1e-8

    def circle(x, lam):
        return np.array([x[0] ** 2 + lam**2 - 1.0])

    # a closed branch that never reaches stop = 2: around and around until max_points, with
    # folds alternately at λ = 1 and λ = −1
    loop = continue_branch(circle, [1.0], 0.0, 2.0, step=0.1, min_step=1e-6, max_step=0.3,
                           max_points=120)
    assert not loop.complete and loop.reason == "max_points" and len(loop.points) == 120
    lam_folds = [p.parameter for p in loop.points if p.fold]
    assert len(lam_folds) >= 4
    assert np.allclose(lam_folds, [(-1.0) ** i for i in range(len(lam_folds))], atol=1e-12)


def test_a_start_that_does_not_converge_names_the_residual():
    def no_root(x, lam):
        return np.array([x[0] ** 2 + 1.0])

    with pytest.raises(RuntimeError, match="no_root"):
        continue_branch(no_root, [0.5], 0.0, 1.0, step=0.1, min_step=1e-3, max_step=0.2)
