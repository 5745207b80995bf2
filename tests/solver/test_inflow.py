"""Finite-state rotor inflow (solver/inflow.py): Peters–He and Pitt–Peters.

References, each independent of the code under test:

* closed forms of the lowest Peters–He member, evaluated by hand from the Γ, H and φ formulas
  of Peters & He (1995) (their 4-digit tabulated values are checked too);
* the orthonormality of the Peters–He shapes with weight ν = √(1 − r̄²) (Gauss–Jacobi);
* the hover convergence table of Peters & He (1995) and linear actuator-disk theory in hover
  (λ = ΔC_p / (2V) point by point: the disturbance pressure is odd in z, so the disk sees half
  the pressure jump), reached through the blade-load weights a lifting line will use;
* momentum theory and Glauert's formula (solved here with brentq), the Pitt–Peters skew
  gradient (15π/32) X, the Peters–He one (2π/3) X, and the UH-60A flight condition's numbers;
* the exact (Riccati) hover response and its linearized time constant, against the solver's
  integrators;
* central finite differences for the Jacobian, complex steps for the section functions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import gammaln, hyp2f1, lpmv, roots_jacobi

from solver.air import FlightCondition
from solver.element import Element, ElementSet
from solver.inflow import (
    DynamicInflow,
    peters_he_matrices,
    peters_he_shape_coefficients,
    peters_he_states,
)
from solver.integrators import make_integrator
from solver.model import Model
from solver.system import System

OMEGA = 27.0  # rad/s, UH-60A
RADIUS = 8.178  # m
TIP_SPEED = OMEGA * RADIUS  # 220.8 m/s
HOVER = FlightCondition()


def cruise(mu: float = 0.2071, tilt_deg: float = 3.0) -> FlightCondition:
    """U = μ ΩR with the shaft tilted forward by tilt_deg (the UH-60A case: U = 150 ft/s)."""
    return FlightCondition(mu * TIP_SPEED, math.radians(tilt_deg))


def inflow(flight=HOVER, **kw) -> DynamicInflow:
    return DynamicInflow("rotor", flight, RADIUS, OMEGA, **kw)


def glauert(ct: float, mu: float, lam_f: float) -> float:
    """λ_i with λ_i = C_T / (2 √(μ² + (λ_f + λ_i)²)), independently of the element."""
    return brentq(lambda li: 2.0 * li * math.hypot(mu, lam_f + li) - ct, 0.0, 1.0,
                  xtol=1e-300, rtol=4 * np.finfo(float).eps)


def uniform_disk_forcing(e: DynamicInflow, dcp, n_blades: int = 4, n_radial: int = 24,
                         n_turns: int = 1):
    """F = Σ W_k T_k for a disk pressure ΔC_p(ξ, η) (on ρ(ΩR)²) carried by n_blades blades at
    n_turns × n_blades azimuths (Gauss–Legendre along the blade): each blade carries the
    pressure of its 1/N share of the annulus, L = Δp 2π r / N (N/m), so
    T_k = L w / (ρΩ²R⁴) = 2π ΔC_p r̄ w̄ / N."""
    x, w = np.polynomial.legendre.leggauss(n_radial)
    rb, wb = 0.5 * (x + 1.0), 0.5 * w
    n = n_blades * n_turns
    psi = 2.0 * np.pi * np.arange(n) / n
    r, p = np.meshgrid(rb, psi)
    xi, eta = r * np.cos(p), r * np.sin(p)
    t = dcp(xi, eta) * 2.0 * np.pi * r * wb / n
    return np.einsum("ab,abn->n", t, e.load_weights(xi, eta)), (xi, eta, r, wb, n)


# ---------------------------------------------------------------- 1. lowest Peters–He member
@pytest.mark.parametrize("x", [0.0, 0.25, 0.8887, 1.0, 1.6])
def test_peters_he_lowest_member_closed_form(x):
    # By hand from Γ (Peters & He 1995), H_1^0 = 1, H_2^1 = 2/3, H_3^2 = 8/15:
    # Γ_11^00 = (−1)·2·3/(1·2·4·(−1)) = 3/4; Γ_12^01 = −π/(2√(H_2^1 H_1^0)·√15) = −π/(2√10)
    # (r+m odd, sgn(0−1) = −1) with the row factor X^m = X; Γ_21^10 = +π/(2√10) with
    # X^1 + X^1 = 2X; Γ_22^11 = (−1)·2·5/((2/3)·4·6·(−1)) = 5/8 with 1 ∓ X²; K = (2/π) H.
    k, lc, ls, states = peters_he_matrices(1, 1, x)
    assert states == [("c", 0, 1), ("c", 1, 2), ("s", 1, 2)]
    g = math.pi / (2.0 * math.sqrt(10.0))
    np.testing.assert_allclose(lc, [[0.75, -g * x], [2 * g * x, 0.625 * (1 - x * x)]],
                               rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(ls, [[0.625 * (1 + x * x)]], rtol=1e-15)
    np.testing.assert_allclose(k, np.diag([2 / math.pi, 4 / (3 * math.pi), 4 / (3 * math.pi)]),
                               rtol=1e-15)
    # the 4-digit tabulated values (π/√10 = 0.99346 is truncated to 0.9934 there)
    np.testing.assert_allclose([-g, 2 * g], [-0.4967, 0.9934], atol=1e-4)
    np.testing.assert_allclose(np.diag(k), [0.6366, 0.4244, 0.4244], atol=5e-5)


def test_peters_he_second_harmonic_mass_and_shapes():
    k, _, _, states = peters_he_matrices(2, 2, 0.3)
    assert k[states.index(("c", 2, 3)), states.index(("c", 2, 3))] == pytest.approx(
        16 / (15 * math.pi), rel=1e-15)  # (2/π)(8/15) = 0.3395
    assert 16 / (15 * math.pi) == pytest.approx(0.3395, abs=5e-5)
    e = inflow(harmonics=1)
    assert e.labels == ["alpha_1^0", "alpha_2^1", "beta_2^1"]
    rng = np.random.default_rng(1)
    xi, eta = rng.uniform(-0.7, 0.7, (2, 9))
    phi = e.shape(xi, eta)  # φ_1^0 = √3, φ_2^1 = √(15/2) r̄ = 2.7386 r̄ (cos ψ, sin ψ)
    np.testing.assert_allclose(phi, np.column_stack(
        [np.full(9, math.sqrt(3)), math.sqrt(7.5) * xi, math.sqrt(7.5) * eta]), rtol=1e-15)
    assert math.sqrt(7.5) == pytest.approx(2.7386, abs=5e-5)


@pytest.mark.parametrize("r", [0, 1, 2, 3])
def test_peters_he_shapes_are_orthonormal_with_weight_nu(r):
    # ∫_0^1 φ_j^r φ_n^r ν r̄ dr̄ = δ_jn, ν = √(1 − r̄²): with u = r̄², ½∫ f(u) √(1 − u) du, a
    # Gauss–Jacobi rule (weight (1 − s)^½ on [−1, 1], u = (1 + s)/2) exact for polynomials.
    s, w = roots_jacobi(30, 0.5, 0.0)
    u = 0.5 * (1.0 + s)
    js = range(r + 1, r + 12, 2)
    phi = np.array([np.polyval(peters_he_shape_coefficients(r, j)[::-1], u) * u ** (r / 2)
                    for j in js])
    gram = 0.5 * (phi * w) @ phi.T / 2**1.5  # du = ds/2 and √(1 − u) = √((1 − s)/2)
    # measured ≤ 1.4e-13 (r = 3, j up to 14: cancellation in the alternating coefficients)
    np.testing.assert_allclose(gram, np.eye(len(js)), atol=1e-12)


def test_shape_matches_polar_form_and_is_complex_step_safe():
    e = inflow(harmonics=3, power=5)
    rng = np.random.default_rng(2)
    rb, psi = rng.uniform(0.05, 1.0, 7), rng.uniform(0, 2 * np.pi, 7)
    xi, eta = rb * np.cos(psi), rb * np.sin(psi)
    polar = np.column_stack([
        np.polyval(peters_he_shape_coefficients(r, j)[::-1], rb * rb) * rb**r
        * (np.cos(r * psi) if kind == "c" else np.sin(r * psi))
        for kind, r, j in peters_he_states(3, 5)])
    np.testing.assert_allclose(e.shape(xi, eta), polar, rtol=1e-13, atol=1e-14)
    # complex step along ξ (and through disk_coordinates) against central differences
    for f in (e.shape, e.load_weights, inflow(model="pitt-peters").load_weights):
        cs = f(xi + 1e-30j, eta).imag / 1e-30
        fd = (f(xi + 1e-6, eta) - f(xi - 1e-6, eta)) / 2e-6
        np.testing.assert_allclose(cs, fd, rtol=1e-7, atol=1e-8)  # measured 8e-11
    pts = np.column_stack([RADIUS * xi + 1.0, RADIUS * eta - 2.0, np.full(7, 0.3)])
    moved = DynamicInflow("r", HOVER, RADIUS, OMEGA, harmonics=3, power=5,
                          centre=(1.0, -2.0, 0.5))
    cx, ce = moved.disk_coordinates(pts + np.array([1e-30j * RADIUS, 0, 0]))
    np.testing.assert_allclose(cx.real, xi, rtol=1e-14)
    np.testing.assert_allclose(ce.real, eta, rtol=1e-14)
    np.testing.assert_allclose(cx.imag, 1e-30, rtol=1e-14)
    lam = moved.shape(cx, ce) @ np.arange(1.0, moved.n_states + 1)
    assert np.iscomplexobj(lam) and np.all(lam.imag != 0.0)
    vel = moved.induced_velocity(pts, np.arange(1.0, moved.n_states + 1))
    np.testing.assert_allclose(vel[:, 2], -lam.real * TIP_SPEED, rtol=1e-13)
    assert np.all(vel[:, :2] == 0.0)


# ---------------------------------------------------------------- 2. hover, uniform loading
@pytest.mark.parametrize("power,n_states,table", [
    (0, 1, 0.5625), (2, 2, 0.5249), (4, 3, 0.5137), (8, 5, 0.5061), (14, 8, 0.5028)])
def test_hover_uniform_loading_converges_to_momentum(power, n_states, table):
    e = inflow(harmonics=0, power=power)
    assert e.n_states == n_states
    ct = 0.0063
    f, (xi, eta, r, wb, n) = uniform_disk_forcing(e, lambda x, y: ct + 0.0 * x, n_blades=4)
    # cancellation in the degree-14 shapes: measured 2.3e-14 of the largest entry
    np.testing.assert_allclose(f, e.uniform_forcing(ct), atol=1e-13 * np.abs(f).max())
    v = 0.037  # one mass-flow parameter for all states (linear problem: α = L V⁻¹ F)
    alpha = e.l_matrix(0.0) @ f / v
    ratio = e.mean_inflow(alpha) * v / ct
    assert ratio == pytest.approx(table, abs=5e-5)
    if n_states == 1:
        assert ratio == pytest.approx(9 / 16, rel=1e-14)
    # the disk-area average, by quadrature of the shapes (4 blades × 8 azimuths each)
    _, (xi, eta, r, wb, n) = uniform_disk_forcing(e, lambda x, y: x, n_turns=8)
    avg = np.sum((e.shape(xi, eta) @ alpha) * r * wb) * 2 * np.pi / n / np.pi
    assert e.mean_inflow(alpha) == pytest.approx(avg, rel=1e-13)


@pytest.mark.parametrize("r,lowest", [(1, 75 / 128), (2, None)])
def test_hover_harmonic_loading_converges_to_actuator_disk(r, lowest):
    # ΔC_p = r̄^r cos rψ: linear actuator-disk theory in hover gives λ = ΔC_p/(2V) at every
    # point, so the area projection of λ V on the load shape, over that of the load itself,
    # tends to ½. The lowest member (r = 1, P = 1) gives (75/32)(1/4) = 75/128 (module
    # docstring). Measured: r = 1: 0.5859, 0.5383, 0.5223, 0.5106, 0.5051; r = 2: 0.5981,
    # 0.5467, 0.5283, 0.5141, 0.5070.
    out = []
    for extra in (0, 2, 4, 8, 14):
        e = inflow(harmonics=r, power=r + extra)
        dcp = lambda x, y: ((x + 1j * y) ** r).real  # noqa: E731
        f, (xi, eta, rr, wb, _) = uniform_disk_forcing(e, dcp, n_blades=16)
        lam = e.shape(xi, eta) @ (e.l_matrix(0.0) @ f)  # V = 1
        out.append(np.sum(lam * dcp(xi, eta) * rr * wb) / np.sum(dcp(xi, eta) ** 2 * rr * wb))
    if lowest is not None:
        assert out[0] == pytest.approx(lowest, rel=1e-13)
    assert np.all(np.diff(out) < 0) and 0.5 < out[-1] < 0.508, out


def _disk_quadrature(n_radial: int = 120, n_azimuth: int = 64):
    """Points (r̄, ψ) and area weights r̄ dr̄ dψ on the unit disk, exact for the Peters–He
    integrands: r̄ = sin θ turns ν = √(1 − r̄²) = cos θ and r̄ dr̄ into trigonometric
    polynomials in θ (Gauss–Legendre), and the azimuth is a trigonometric polynomial."""
    x, w = np.polynomial.legendre.leggauss(n_radial)
    theta = (x + 1.0) * math.pi / 4.0
    rb = np.sin(theta)
    wr = w * math.pi / 4.0 * rb * np.cos(theta)
    psi = 2.0 * math.pi * np.arange(n_azimuth) / n_azimuth
    rr, pp = np.meshgrid(rb, psi, indexing="ij")
    return rr, pp, np.outer(wr, np.full(n_azimuth, 2.0 * math.pi / n_azimuth))


@pytest.mark.parametrize("r,power", [(1, 7), (2, 8), (3, 9), (5, 9)])
def test_hover_pressure_modes_give_the_exact_galerkin_inflow(r, power):
    # A disk loading built from the Peters–He pressure modes P̄_n^r(ν) cos rψ = ν φ_n^r cos rψ
    # (n ≤ P + 1), on top of a uniform thrust. Linear actuator-disk theory in hover: the
    # perturbation inflow is ΔC_p / (2 V_m) at every point (the disturbance pressure is odd in
    # z: the disk sees half the jump, carried by the perturbation mass flow V_m = 2 λ_m). That
    # inflow is not a finite sum of the shapes φ_j^r (it carries the factor ν), but a
    # truncated Peters–He set whose pressure modes hold the loading gives exactly its
    # Galerkin coefficients: α_j = ∫ λ φ_j^r ν dA / ∫ (φ_j^r)² ν dA, evaluated here by
    # quadrature. This checks the in-harmonic coupling Γ_jn^rr, the ½τ normalization of the
    # load weights and the shapes of every radial order at once. Measured: 4e-13.
    e = inflow(harmonics=max(r, 3), power=power)
    rr, pp, w = _disk_quadrature()
    nu = np.sqrt(1.0 - rr**2)

    def radial(x):  # a loading of the pressure modes n = r+1, r+3, r+5
        return 0.004 * x**r * (1.0 - 0.6 * x**2 + 0.25 * x**4)

    ct = 0.0063
    dcp = ct + nu * radial(rr) * np.cos(r * pp)
    xi, eta = rr * np.cos(pp), rr * np.sin(pp)
    f = np.einsum("ijk,ij->k", e.load_weights(xi, eta), dcp * w)
    alpha = e.steady_states(f)
    flow = e.flow(alpha)
    assert flow.v_m == pytest.approx(2.0 * flow.lambda_m, rel=1e-14)  # hover
    rb, wr = rr[:, 0], w[:, 0]  # r̄ dr̄ (times a constant that cancels)
    nu1 = np.sqrt(1.0 - rb**2)
    lam = nu1 * radial(rb) / (2.0 * flow.v_m)
    checked = 0
    for i, (kind, rs, j) in enumerate(e.harmonic_indices):
        if kind == "c" and rs == r:
            phi = rb**r * np.polyval(peters_he_shape_coefficients(r, j)[::-1], rb**2)
            exact = np.sum(wr * nu1 * lam * phi) / np.sum(wr * nu1 * phi**2)
            assert alpha[i] == pytest.approx(exact, rel=1e-11, abs=1e-13 * abs(lam).max())
            checked += 1
        elif rs != 0:  # no other harmonic is loaded, and in hover none couples
            assert abs(alpha[i]) < 1e-15
    assert checked == len(range(r + 1, power + 2, 2))


# ---------------------------------------------------------------- 3. Pitt–Peters steady state
@pytest.mark.parametrize("ct", [1e-4, 1e-3, 0.00567, 0.02, 0.1, -0.004])
def test_pitt_peters_hover_is_momentum_theory(ct):
    e = inflow(model="pitt-peters")
    lam = e.steady_states(e.uniform_forcing(ct))
    expected = math.copysign(math.sqrt(abs(ct) / 2), ct)
    assert lam[0] == pytest.approx(expected, rel=1e-10)  # measured ≤ 2e-16
    assert lam[1] == 0.0 and lam[2] == 0.0


def test_pitt_peters_forward_flight_is_glauert_with_skew_gradient():
    ct = 0.00567
    e = inflow(cruise(), model="pitt-peters", initial_thrust=ct)
    lam = e.states()[0].initial
    mu, lam_f = e.free_stream
    assert mu == pytest.approx(0.2071 * math.cos(math.radians(3)), rel=1e-14)
    assert lam_f == pytest.approx(0.2071 * math.sin(math.radians(3)), rel=1e-14)
    assert lam[0] == pytest.approx(glauert(ct, mu, lam_f), rel=1e-10)  # measured 1e-16
    fl = e.flow(lam)
    # the UH-60A case (W = 16 000 lb, α_TPP = −3°): λ ≈ 0.02446, χ ≈ 83.3°; with C_T rounded
    # to 0.00567 we get 0.024452 and 83.256° (the table used C_T = 0.005672: 0.02446)
    assert fl.lambda_total == pytest.approx(0.02446, rel=5e-4)
    assert math.degrees(fl.chi) == pytest.approx(83.3, abs=0.05)
    x = math.tan(fl.chi / 2)
    assert fl.skew == pytest.approx(x, rel=1e-14)
    assert x == pytest.approx(0.889, abs=1e-3)  # Coleman's k_x
    assert lam[2] / lam[0] == pytest.approx(15 * math.pi / 32 * x, rel=1e-12)
    assert lam[2] / lam[0] == pytest.approx(1.309, abs=1e-3)  # Pitt–Peters' k_x
    assert lam[2] > 0 and lam[1] == 0.0  # more inflow at the rear (ψ = 0, +x)
    gr = e.gradients(lam)
    assert gr == (lam[0], lam[1], lam[2])
    # more load on one side gives more inflow there than the same thrust spread uniformly
    base = e.uniform_forcing(ct)
    for i, (xi, eta) in ((1, (0.0, 0.7)), (1, (0.0, -0.7)), (2, (0.7, 0.0)), (2, (-0.7, 0.0))):
        w = e.load_weights(np.array([xi]), np.array([eta]))[0]
        more = e.steady_states(base + 1e-4 * w)
        spread = e.steady_states(base + 1e-4 * w[0] * np.array([1.0, 0.0, 0.0]))
        assert np.sign(more[i] - spread[i]) == np.sign(xi + eta)


# ---------------------------------------------------------------- 4. Peters–He skew
@pytest.mark.parametrize("mu", [0.0, 0.01, 0.1, 0.2071, 0.35])
def test_peters_he_three_state_skew_gradient(mu):
    ct = 0.0063
    e = inflow(cruise(mu), initial_thrust=ct)
    a = e.states()[0].initial
    fl = e.flow(a)
    lam0, lam_s, lam_c = e.gradients(a)
    assert lam0 == pytest.approx(math.sqrt(3) * a[0], rel=1e-15)
    assert lam_c == pytest.approx(math.sqrt(7.5) * a[1], rel=1e-15)
    assert lam_s == 0.0 and a[2] == 0.0
    assert lam_c == pytest.approx(2 * math.pi / 3 * fl.skew * lam0, rel=1e-12, abs=1e-18)
    # λ_c(r̄ = 1) from the shapes themselves; more inflow at the rear (ψ = 0) for X > 0
    rear, front = e.shape(np.array([1.0, -1.0]), np.array([0.0, 0.0])) @ a
    assert (rear - front) / 2 == pytest.approx(lam_c, rel=1e-12, abs=1e-18)
    if mu == 0.0:
        assert fl.skew == 0.0 and rear == front  # axisymmetric
    else:
        assert rear > front
    # the 1-state momentum: C_T = 2 λ_m V_T with 9/8 of the Glauert λ_i (L_11 = 9/16)
    assert 2 * fl.lambda_m * fl.v_t == pytest.approx(9 / 8 * ct, rel=1e-12)


# ---------------------------------------------------------------- skewed wake: L(X) from the flow
# The linearized Euler equations carry the pressure disturbance Φ along the free stream: the
# inflow at a disk point is the integral of ∂Φ/∂z along the streamline that reaches it from
# upstream, λ(x) = −(1/2V) ∫_0^∞ ∂Φ/∂z (x + s ê) ds, ê = (−sin χ, 0, cos χ), with Φ the potential
# whose value on the disk's upper face is the loading Δp (in hover λ = Δp/(2V), the exact
# result above). A unit τ_n^m is the loading P̄_n^m(ν) cos mψ (or sin), whose potential in
# ellipsoidal coordinates (x² + y² = (1 − ν²)(1 + η²), z = νη) is P̄_n^m(ν) Q̄_n^m(iη) cos mψ
# with Q̄_n^m(i0) = 1 (Peters & He 1995). The Galerkin coefficients of λ on the shapes
# φ_j^r = P̄_j^r/ν with weight ν are then ½ L(X)_jn / V: every entry of L, the r + m odd
# couplings with their signs and the powers of X included, computed here from the flow by
# quadrature with SciPy's Legendre and hypergeometric functions, independently of the
# closed forms in the code.
def _legendre_bar(m: int, n: int, nu):
    """P̄_n^m(ν), normalized to ∫_0^1 P̄² dν = 1, without the Condon–Shortley phase."""
    scale = math.sqrt((2 * n + 1) * math.exp(gammaln(n - m + 1) - gammaln(n + m + 1)))
    return (-1) ** m * lpmv(m, n, nu) * scale


def _q_bar(m: int, n: int, eta):
    """Q̄_n^m(iη) = Q_n^m(iη)/Q_n^m(i0) from the hypergeometric form of Q_n^m (the constant
    phase cancels; the limit η → 0 by Richardson from η = 1e-7, 2e-7)."""
    def raw(e):
        return ((1.0 + e**2) ** (m / 2) * e ** (-n - m - 1.0)
                * hyp2f1((n + m + 1) / 2, (n + m + 2) / 2, n + 1.5, -1.0 / e**2))
    return raw(eta) / (2.0 * raw(1e-7) - raw(2e-7))


def _pressure_potential(kind: str, m: int, n: int, x, y, z):
    a = x * x + y * y + z * z - 1.0
    root = np.sqrt(a * a + 4.0 * z * z)
    eta = np.sqrt(np.where(a > 0.0, (a + root) / 2.0, 2.0 * z * z / (root - a)))  # no cancellation
    nu = np.minimum(1.0, z / eta)
    azimuth = np.arctan2(y, x)
    trig = np.cos(m * azimuth) if kind == "c" else np.sin(m * azimuth)
    return _legendre_bar(m, n, nu) * _q_bar(m, n, eta) * trig


def _l_matrix_from_the_flow(states, skew: float, n_radial: int, n_path: int,
                            h: float = 1e-5) -> np.ndarray:
    chi = 2.0 * math.atan(skew)
    x, w = np.polynomial.legendre.leggauss(n_radial)
    theta = (x + 1.0) * math.pi / 4.0  # r̄ = sin θ, ν = cos θ
    rb, nu = np.sin(theta), np.cos(theta)
    w_area = w * math.pi / 4.0 * rb * nu
    psi = 2.0 * math.pi * (np.arange(n_radial) + 0.5) / n_radial
    xs, ws = np.polynomial.legendre.leggauss(n_path)
    u = (xs + 1.0) * math.pi / 4.0  # s = tan²u: dense near the disk
    s = np.tan(u) ** 2
    ds = 2.0 * np.tan(u) / np.cos(u) ** 2 * ws * math.pi / 4.0
    px = (rb[:, None] * np.cos(psi))[..., None] - s * math.sin(chi)
    py = (rb[:, None] * np.sin(psi))[..., None] + 0.0 * s
    pz = s * math.cos(chi)

    def galerkin(step):
        # ∂Φ/∂z by a difference over [z, z + 2 step] (the path must not cross the disk):
        # first order in the step, hence the Richardson pair below
        out = np.zeros((len(states), len(states)))
        for col, (kind, m, n) in enumerate(states):
            dphi = (_pressure_potential(kind, m, n, px, py, pz + 2.0 * step)
                    - _pressure_potential(kind, m, n, px, py, pz)) / (2.0 * step)
            lam = -np.sum(dphi * ds, axis=-1)  # × 2V λ
            for row, (k2, r, j) in enumerate(states):
                if k2 != kind:
                    continue
                shape = np.outer(_legendre_bar(r, j, nu) / nu,
                                 np.cos(r * psi) if k2 == "c" else np.sin(r * psi))
                wn = (w_area * nu)[:, None]
                out[row, col] = np.sum(wn * lam * shape) / np.sum(wn * shape**2)
        return out

    return 2.0 * galerkin(h / 2.0) - galerkin(h)


@pytest.mark.parametrize("harmonics,power,skew,n_radial,n_path,tol", [
    # measured: 5.8e-9, 7.3e-9 (the quadrature's resolution, not the closed forms)
    (2, 3, 0.6, 32, 160, 2e-8),
    pytest.param(3, 4, 0.8, 48, 240, 2e-8, marks=pytest.mark.slow),
])
def test_skewed_l_matrix_is_the_flow_of_the_pressure_modes(harmonics, power, skew, n_radial,
                                                          n_path, tol):
    _, lc, ls, states = peters_he_matrices(harmonics, power, skew)
    nc = lc.shape[0]
    expected = np.zeros((len(states), len(states)))
    expected[:nc, :nc], expected[nc:, nc:] = lc, ls
    with np.errstate(divide="ignore", invalid="ignore"):
        from_flow = _l_matrix_from_the_flow(states, skew, n_radial, n_path)
    np.testing.assert_allclose(from_flow, expected, rtol=0.0, atol=tol)
    # the entries checked include the cross-harmonic, skew-dependent ones
    assert np.count_nonzero(np.abs(expected[:nc, :nc]) > 1e-3) > 2 * nc


def test_peters_he_higher_order_steady_state():
    # M = 4, P = 6 (24 states) at the UH-60A cruise point: the momentum inflow √3 α_1^0 is
    # near Glauert (measured 0.3 % above) and the inflow grows from front to rear; in hover
    # every harmonic state stays zero (axisymmetric).
    ct = 0.00567
    e = inflow(cruise(), harmonics=4, power=6, initial_thrust=ct)
    a = e.states()[0].initial
    fl = e.flow(a)
    assert fl.lambda_m == pytest.approx(glauert(ct, fl.mu, fl.lambda_f), rel=5e-3)
    np.testing.assert_allclose(e.rhs(a), -e.uniform_forcing(ct), atol=1e-17)
    lam = e.shape(np.linspace(-0.9, 0.9, 7), np.zeros(7)) @ a
    assert np.all(np.diff(lam) > 0)
    h = inflow(harmonics=4, power=6, initial_thrust=ct).states()[0].initial
    harmonic = np.array([r > 0 for _, r, _ in peters_he_states(4, 6)])
    assert np.all(h[harmonic] == 0.0) and np.all(h[~harmonic] != 0.0)


# ---------------------------------------------------------------- 5. time domain
@dataclass(eq=False)
class Forcing(Element):
    """Constant forcing F on an inflow element's state rows (stands in for a lifting line)."""

    name: str
    inflow: DynamicInflow
    values: np.ndarray


class ForcingSet(ElementSet):
    nonconservative = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        self.force_idx = np.concatenate([system.offset[e.inflow] + np.arange(e.inflow.n_states)
                                         for e in elements])
        self._f = np.concatenate([e.values for e in elements])

    def force(self, q, v, t):
        return self._f.copy()


Forcing.set_class = ForcingSet


def stepped(e: DynamicInflow, forcing, h: float, n: int, scheme: str = "ep") -> np.ndarray:
    """States after each of n steps of size h (s), first row the initial states."""
    m = Model()
    m.add(e, Forcing("load", e, np.asarray(forcing, dtype=float)))
    s = System(m)
    it = make_integrator(s, scheme, h)
    i = s.offset[e] + np.arange(e.n_states)
    out = [it.q[i]]
    for _ in range(n):
        assert it.step().converged
        out.append(it.q[i])
    return np.array(out)


# single-state hover models: (mass m, dλ/dstate, rhs f = −c state², forcing per unit C_T);
# linearized time constant τ = m / (Ω |∂f/∂x|):
#   pitt-peters: (128/(75π)/Ω) λ̇ = C_T − 2λ²             → τ = 128/(75π) / (4 λ Ω)
#   peters-he, one state: ((2/π)/Ω) α̇ = (√3/4) C_T − (4/√3) α²   (λ = √3 α, V_T = λ, L = 3/4)
#                                                        → τ = 3 / (4π λ Ω)
MODELS_1 = {"pitt-peters": dict(model="pitt-peters"),
            "peters-he": dict(model="peters-he", harmonics=0, power=0)}


@pytest.mark.parametrize("name", list(MODELS_1))
def test_hover_time_constant_after_a_small_step(name):
    ct1, eps = 0.006, 1e-4
    e = inflow(initial_thrust=ct1, **MODELS_1[name])
    target = e.steady_states(e.uniform_forcing(ct1 * (1 + eps)))
    lam = e.mean_inflow(target)
    tau = (128 / (75 * math.pi) / (4 * lam * OMEGA) if name == "pitt-peters"
           else 3 / (4 * math.pi * lam * OMEGA))
    h = tau / 20
    x = stepped(e, e.uniform_forcing(ct1 * (1 + eps)), h, 50)[:, 0]
    d = target[0] - x
    ratio = d[1:] / d[:-1]
    # the implicit midpoint rule multiplies a mode of time constant τ by (1 − a)/(1 + a),
    # a = h/(2τ), per step: invert it to measure τ free of the time-step error
    a = (1 - ratio) / (1 + ratio)
    measured = h / (2 * a)
    # the linearization point moves from the old to the new steady state: relative ε/4 =
    # 2.5e-5 at the first step, measured 2.4e-5 (first) and 3e-6 (steps 40–50)
    np.testing.assert_allclose(measured[40:], tau, rtol=1e-5)
    np.testing.assert_allclose(measured[0], tau, rtol=5e-5)


def test_pitt_peters_hover_large_step_follows_the_riccati_solution():
    # (M/Ω) λ̇ = C_T − 2λ² → λ(t) = a tanh(k a t + atanh(λ(0)/a)), a = √(C_T/2), k = 2Ω/M
    e = inflow(model="pitt-peters", initial_thrust=0.003)
    ct = 0.006
    a, k = math.sqrt(ct / 2), 2 * OMEGA / (128 / (75 * math.pi))
    tau = 1 / (2 * k * a)
    errors = []
    for h in (tau / 10, tau / 20):
        x = stepped(e, e.uniform_forcing(ct), h, round(5 * tau / h))
        t = h * np.arange(len(x))
        exact = a * np.tanh(k * a * t + math.atanh(math.sqrt(0.0015) / a))
        errors.append(np.abs(x[:, 0] - exact).max() / a)
        assert np.all(x[:, 1:] == 0.0)
    # second order: measured 7.08e-5 → 1.77e-5 (ratio 4.00)
    assert errors[1] < 2e-5 and 3.9 < errors[0] / errors[1] < 4.1, errors
    # the final state: large steps (the midpoint factor 1/3 per step at h = τ)
    x = stepped(e, e.uniform_forcing(ct), tau, 40)
    np.testing.assert_allclose(x[-1], e.steady_states(e.uniform_forcing(ct)), rtol=1e-13,
                               atol=1e-17)


@pytest.mark.parametrize("scheme", ["ep", "galpha", "ed"])
def test_peters_he_forward_flight_settles_on_the_steady_state(scheme):
    # M = 2, P = 4 (11 states), UH-60A cruise, uniform thrust plus two point loads; time
    # constants 0.014–0.091 s; from zero states, 150 steps of 0.05 s: measured 3e-16 (ep)
    e = inflow(cruise(), harmonics=2, power=4)
    f = e.uniform_forcing(0.006) + 0.01 * e.load_weights(np.array([0.3, 0.7]),
                                                         np.array([0.5, -0.2])).sum(axis=0)
    x = stepped(e, f, 0.05, 150, scheme)
    steady = e.steady_states(f)
    np.testing.assert_allclose(x[-1], steady, atol=1e-12 * np.abs(steady).max())
    np.testing.assert_allclose(e.rhs(steady), -f, atol=1e-17)


# ---------------------------------------------------------------- 6. Jacobian, validation
@pytest.mark.parametrize("kw,flight", [
    (dict(model="pitt-peters"), cruise()), (dict(model="pitt-peters"), HOVER),
    (dict(harmonics=1), cruise(0.1, -4.0)), (dict(harmonics=2, power=4), cruise()),
    (dict(harmonics=3, power=3), HOVER)])
def test_jacobian_against_central_differences(kw, flight):
    e = inflow(flight, initial_thrust=0.006, **kw)
    rng = np.random.default_rng(3)
    a = e.states()[0].initial * (1 + 0.3 * rng.standard_normal(e.n_states)) \
        + 0.003 * rng.standard_normal(e.n_states)
    f, jac = e.rhs(a, jacobian=True)
    np.testing.assert_array_equal(f, e.rhs(a))
    step = 1e-6
    fd = np.column_stack([(e.rhs(a + step * d) - e.rhs(a - step * d)) / (2 * step)
                          for d in np.eye(e.n_states)])
    # truncation (step²/6 f''') and roundoff (1e-16/1e-6): measured ≤ 1.5e-10 of max |∂f/∂α|
    np.testing.assert_allclose(jac, fd, atol=1e-7 * np.abs(fd).max())


def test_assembled_force_and_jacobian_of_two_rotors():
    # two rotors (one of each model) in one set, with a forcing set on both: the pattern
    # (fq_rows, fq_cols) and values against central differences of System.applied
    r1 = DynamicInflow("main", cruise(), RADIUS, OMEGA, harmonics=2, power=2,
                       initial_thrust=0.006)
    r2 = DynamicInflow("tail", cruise(), 1.7, 124.0, model="pitt-peters", centre=(9, 0, 1),
                       initial_thrust=0.004)
    m = Model()
    m.add(r1, r2, Forcing("l1", r1, r1.uniform_forcing(0.007)),
          Forcing("l2", r2, r2.uniform_forcing(0.003)))
    s = System(m)
    assert len(s.first_order) == r1.n_states + r2.n_states == s.n
    q = s.q0_raw + 1e-3 * np.random.default_rng(4).standard_normal(s.n)
    v = np.zeros(s.n)
    dense = np.zeros((s.n, s.n))
    for st in s.fjac_sets:
        np.add.at(dense, (st.fq_rows, st.fq_cols), st.force_jacobians(q, v, 0.0)[0])
    fd = np.column_stack([(s.applied(q + 1e-7 * d, v, 0) - s.applied(q - 1e-7 * d, v, 0))
                          / 2e-7 for d in np.eye(s.n)])
    np.testing.assert_allclose(dense, fd, atol=1e-7 * np.abs(fd).max())
    # mass K/Ω on the diagonal; the steady start is an equilibrium of the whole model
    np.testing.assert_allclose(s.A1.toarray()[: r1.n_states, : r1.n_states], r1.mass_matrix)
    s0 = System(Model([r1, Forcing("l", r1, r1.uniform_forcing(0.006))]))
    assert np.abs(s0.applied(s0.q0_raw, np.zeros(s0.n), 0.0)).max() < 1e-17


def test_steady_state_without_mass_flow_is_an_error():
    e = inflow(model="pitt-peters")
    np.testing.assert_array_equal(e.steady_states(np.zeros(3)), np.zeros(3))
    with pytest.raises(RuntimeError, match="no steady inflow"):
        e.steady_states([0.0, 1e-3, 0.0])  # a moment without thrust in hover
    with pytest.raises(ValueError, match="forcing must be 3"):
        e.steady_states([1.0, 2.0])


@pytest.mark.parametrize("kw,match", [
    (dict(name=""), "name"),
    (dict(flight="hover"), "flight"),
    (dict(radius=0.0), "radius = 0.0 m must be finite and > 0"),
    (dict(radius=float("nan")), "radius"),
    (dict(radius="8"), "radius"),
    (dict(omega=-27.0), r"omega = -27.0 rad/s"),
    (dict(model="glauert"), "model = 'glauert' must be one of 'peters-he', 'pitt-peters'"),
    (dict(harmonics=-1), r"harmonics = -1 must be in \[0, 16\]"),
    (dict(harmonics=17), "harmonics = 17"),
    (dict(harmonics=1.0), "harmonics = 1.0 must be an integer"),
    (dict(harmonics=True), "harmonics"),
    (dict(harmonics=2, power=1), r"power = 1 must be in \[harmonics = 2, 32\]"),
    (dict(power=33), "power = 33"),
    (dict(model="pitt-peters", harmonics=2), "harmonics = 2: pitt-peters"),
    (dict(model="pitt-peters", power=3), "power = 3: pitt-peters"),
    (dict(centre=(0.0, 0.0)), "centre"),
    (dict(centre=(0.0, float("inf"), 0.0)), "centre"),
    (dict(initial_thrust=0.2), r"initial_thrust = 0.2 must be a thrust coefficient in"),
    (dict(initial_thrust=float("nan")), "initial_thrust"),
])
def test_parameter_validation(kw, match):
    args = dict(name="rotor", flight=HOVER, radius=RADIUS, omega=OMEGA) | kw
    with pytest.raises(ValueError, match=match):
        DynamicInflow(**args)
