"""Floquet multipliers (:mod:`solver.floquet`) against closed forms: the transition curves of
Mathieu's equation from their perturbation series, a constant system's e^{λT}, and the
dominant eigenvalues of a matrix with a known spectrum."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import scipy.special

from solver.floquet import (
    dominant_multipliers,
    hill_exponents,
    hill_multipliers,
    monodromy,
    multipliers,
)

EPS = 0.1  # ε of x'' + (δ + ε cos t) x = 0
HARMONICS = 12  # Hill's truncation for Mathieu: the transitions do not change beyond H = 8
SAMPLES = 64  # samples of A per period (> 4H resolves the Hill matrix's harmonics)


def _distance(mu: np.ndarray, ref: np.ndarray) -> float:
    """Largest distance from an element of one set to the nearest of the other (sets of equal
    size; sorting complex numbers would pair conjugates by roundoff)."""
    d = np.abs(np.asarray(mu)[:, None] - np.asarray(ref)[None, :])
    assert len(mu) == len(ref)
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def _mathieu_a(delta: float) -> np.ndarray:
    t = np.arange(SAMPLES) * 2.0 * np.pi / SAMPLES
    a = np.zeros((SAMPLES, 2, 2))
    a[:, 0, 1] = 1.0
    a[:, 1, 0] = -(delta + EPS * np.cos(t))
    return a


def _half_trace_monodromy(delta: float) -> float:
    phi = monodromy(lambda t: np.array([[0.0, 1.0], [-(delta + EPS * np.cos(t)), 0.0]]), 2,
                    2.0 * np.pi)
    return 0.5 * np.trace(phi)


def _half_trace_hill(delta: float) -> float:
    return 0.5 * float(hill_multipliers(_mathieu_a(delta), 1.0, HARMONICS).sum().real)


# Transition curves of x'' + (δ + ε cos t) x = 0 from the series of the Mathieu characteristic
# values, NIST DLMF §28.6(i), eqs. 28.6.1–28.6.5, for w'' + (a − 2q cos 2z) w = 0:
#   a₀ = −q²/2 + 7q⁴/128 − …,          a₁ = 1 + q − q²/8 − q³/64 − q⁴/1536 + …,
#   b₁ = 1 − q − q²/8 + q³/64 − q⁴/1536 + …,   a₂ = 4 + 5q²/12 − 763q⁴/13824 + …,
#   b₂ = 4 − q²/12 + 5q⁴/13824 + ….
# With t = 2z, d²/dt² = ¼ d²/dz², so x'' + (δ + ε cos t) x = 0 is w'' + (4δ + 4ε cos 2z) w = 0:
# a = 4δ and −2q = 4ε, q = −2ε. The set {aₙ(q), bₙ(q)} is the same for −q (DLMF 28.2.26:
# a₂ₙ(−q) = a₂ₙ(q), a₂ₙ₊₁(−q) = b₂ₙ₊₁(q), b₂ₙ₊₂(−q) = b₂ₙ₊₂(q)), so δ = a(2ε)/4:
#   δ = −ε²/2 + 7ε⁴/32,
#   δ = 1/4 ± ε/2 − ε²/8 ∓ ε³/32 − ε⁴/384,
#   δ = 1 − ε²/12 + 5ε⁴/3456,   δ = 1 + 5ε²/12 − 763ε⁴/3456
# (the Nayfeh & Mook, Nonlinear Oscillations, §5.2 forms). The next terms are
# −29ε⁶/144 ≈ 2.0e-7, ±11ε⁵/4608 ≈ 2.4e-8 and O(ε⁶) ≈ 2e-7 at ε = 0.1; scipy's
# mathieu_a/mathieu_b (an independent algorithm) check the mapping below.
E = EPS
TRANSITIONS = [
    # (name, series δ, half trace at the boundary, bracket, scipy's characteristic value)
    ("a0", -E**2 / 2 + 7 * E**4 / 32, 1.0, (-0.05, 0.05), scipy.special.mathieu_a(0, 2 * E)),
    ("b1", 0.25 - E / 2 - E**2 / 8 + E**3 / 32 - E**4 / 384, -1.0, (0.15, 0.25),
     scipy.special.mathieu_b(1, 2 * E)),
    ("a1", 0.25 + E / 2 - E**2 / 8 - E**3 / 32 - E**4 / 384, -1.0, (0.25, 0.35),
     scipy.special.mathieu_a(1, 2 * E)),
    ("b2", 1 - E**2 / 12 + 5 * E**4 / 3456, 1.0, (0.95, 1.0), scipy.special.mathieu_b(2, 2 * E)),
    ("a2", 1 + 5 * E**2 / 12 - 763 * E**4 / 3456, 1.0, (1.0, 1.05),
     scipy.special.mathieu_a(2, 2 * E)),
]


@pytest.mark.parametrize(("name", "series", "trace", "bracket", "char"), TRANSITIONS,
                         ids=[t[0] for t in TRANSITIONS])
def test_mathieu_transition_curves_match_the_perturbation_series(name, series, trace, bracket,
                                                                 char):
    """The boundaries of the parametric-resonance tongues, where the multipliers meet at ±1 and
    max|μ| leaves 1 (the system conserves phase volume, μ₁μ₂ = 1, so |½ tr Φ(T)| = 1 there),
    found by Brent's method on ½ tr Φ(T) ∓ 1 from the integrated monodromy and from Hill's
    multipliers. Measured against the series: a0 1.99e-7, b1 2.26e-8, a1 2.52e-8,
    b2 2.7e-11, a2 1.99e-7 (the series' next terms; asserted to 3e-7, the brief's bound was
    1e-4); Hill against monodromy ≤ 2.5e-10 (the double multiplier at the boundary is
    sensitive; asserted 1e-9); scipy's values against the monodromy's ≤ 3.2e-11 (asserted
    1e-9)."""
    d_mono = scipy.optimize.brentq(lambda d: _half_trace_monodromy(d) - trace, *bracket,
                                   xtol=1e-14)
    d_hill = scipy.optimize.brentq(lambda d: _half_trace_hill(d) - trace, *bracket, xtol=1e-14)
    assert abs(d_mono - series) < 3e-7
    assert abs(d_hill - series) < 3e-7
    assert abs(d_hill - d_mono) < 1e-9
    assert abs(char / 4 - d_mono) < 1e-9
    # inside the tongue (past the boundary, away from the stable side) max|μ| > 1, outside = 1
    inside = bracket[1] if trace * (_half_trace_monodromy(bracket[1]) - trace) > 0 else bracket[0]
    outside = bracket[0] if inside == bracket[1] else bracket[1]
    mu_in = hill_multipliers(_mathieu_a(inside), 1.0, HARMONICS)
    mu_out = hill_multipliers(_mathieu_a(outside), 1.0, HARMONICS)
    assert abs(mu_in[0]) > 1.0 + 1e-3
    assert abs(abs(mu_out[0]) - 1.0) < 1e-10


def test_hill_selections_agree_away_from_the_strip_edges():
    """The central-weight selection and the strip (−ω/2, ω/2] give the same multipliers where
    no exponent lies near ±ω/2 (δ = 0.6, between the tongues at 1/4 and 1): measured 2e-14,
    and against the integrated monodromy 8e-13."""
    a = _mathieu_a(0.6)
    by_weight = hill_multipliers(a, 1.0, HARMONICS)
    by_strip = hill_multipliers(a, 1.0, HARMONICS, selection="strip")
    assert _distance(by_weight, by_strip) < 1e-12
    phi = monodromy(lambda t: np.array([[0.0, 1.0], [-(0.6 + EPS * np.cos(t)), 0.0]]), 2,
                    2.0 * np.pi)
    assert _distance(by_weight, multipliers(phi)) < 1e-10


def _damped_two_dof() -> np.ndarray:
    """First-order form of M q'' + C q' + K q = 0, 2 DOF (complex modes, unequal damping)."""
    m = np.diag([1.0, 2.0])
    k = np.array([[3.0, -1.0], [-1.0, 2.0]])
    c = np.array([[0.1, -0.02], [-0.02, 0.05]])
    minv = np.linalg.inv(m)
    return np.block([[np.zeros((2, 2)), np.eye(2)], [-minv @ k, -minv @ c]])


def test_constant_system_multipliers_are_exponentials_of_its_eigenvalues():
    """A constant A, regarded as periodic with T = 2π/ω: all three ways give e^{λᵢT} (λᵢ the
    eigenvalues of A) to 1e-8 (measured: Hill 6e-15, monodromy 6e-12, expm 5e-15); Hill's
    exponents are the λᵢ themselves (measured 2e-15), being in the central block."""
    a = _damped_two_dof()
    omega = 1.3
    period = 2.0 * np.pi / omega
    lam = np.linalg.eigvals(a)
    expected = np.exp(lam * period)
    expected = expected[np.argsort(-np.abs(expected))]
    samples = np.broadcast_to(a, (16, 4, 4))

    def close(mu):
        return _distance(mu, expected) < 1e-8

    assert close(hill_multipliers(samples, omega, 4))
    assert _distance(hill_exponents(samples, omega, 4), lam) < 1e-12
    assert close(multipliers(monodromy(lambda t: a, 4, period)))
    assert close(multipliers(scipy.linalg.expm(a * period)))
    # sorted by modulus, largest first
    mu = hill_multipliers(samples, omega, 4)
    assert np.all(np.diff(np.abs(mu)) <= 1e-15)


def _known_spectrum(rng: np.random.Generator, spectrum: np.ndarray) -> np.ndarray:
    """A real matrix V diag V⁻¹ with the given spectrum (complex pairs as 2×2 rotation
    blocks), V a well-conditioned random matrix."""
    blocks = []
    i = 0
    while i < len(spectrum):
        s = spectrum[i]
        if abs(s.imag) > 0:
            blocks.append(np.array([[s.real, s.imag], [-s.imag, s.real]]))
            i += 2
        else:
            blocks.append(np.array([[s.real]]))
            i += 1
    d = scipy.linalg.block_diag(*blocks)
    v = np.eye(len(d)) + 0.3 * rng.standard_normal((len(d), len(d))) / np.sqrt(len(d))
    return v @ d @ np.linalg.inv(v)


def test_dominant_multipliers_of_a_known_spectrum_and_on_a_subspace():
    """Arnoldi on a 30 × 30 matrix with known leading eigenvalues 0.95e^{±0.4i}, 0.9, −0.85
    (the rest ≤ 0.5 in modulus), also through an orthonormal basis Q₁ of an invariant
    subspace: M = Q [[M₁₁, M₁₂], [0, M₂₂]] Qᵀ with M₂₂'s eigenvalues 2 and 1.5 on the removed
    directions, so Q₁ᵀ M Q₁ = M₁₁. Measured errors 1.3e-15 restricted and 5e-15 on the whole
    map (to 1e-10)."""
    rng = np.random.default_rng(7)
    lead = np.array([0.95 * np.exp(0.4j), 0.95 * np.exp(-0.4j), 0.9, -0.85])
    rest = 0.5 * rng.uniform(-1, 1, 24)
    m11 = _known_spectrum(rng, np.concatenate([lead, rest.astype(complex)]))
    r = m11.shape[0]
    n = r + 2
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    top = np.block([[m11, rng.standard_normal((r, 2))],
                    [np.zeros((2, r)), np.array([[2.0, 0.3], [0.0, 1.5]])]])
    m = q @ top @ q.T
    expected = lead[np.argsort(-np.abs(lead), kind="stable")]

    def same(mu, ref):
        return _distance(mu, ref) < 1e-10

    restricted = dominant_multipliers(lambda v: m @ v, n, 4, basis=q[:, :r])
    assert same(restricted, expected)
    assert np.all(np.diff(np.abs(restricted)) <= 1e-12)
    full = dominant_multipliers(lambda v: m @ v, n, 4)
    assert same(full, np.array([2.0, 1.5, lead[0], lead[1]]))
    # count ≥ r − 1 forms the matrix: all its eigenvalues
    every = dominant_multipliers(lambda v: m @ v, n, n - 1)
    assert same(every, multipliers(m)[: n - 1])
