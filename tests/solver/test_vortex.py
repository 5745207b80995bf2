"""Biot–Savart velocity of straight vortex segments (solver/vortex_kernels.py).

References, independent of the kernel:

* the Biot–Savart line integral v = Γ/(4π) ∫ dl × (P − x)/|P − x|³ along each segment, by
  adaptive quadrature (scipy.integrate.quad);
* the infinite line vortex, Γ/(2π h);
* the vortex ring's velocity field in closed form with complete elliptic integrals (Lamb,
  *Hydrodynamics*, §161; on the axis Γa²/[2(a² + z²)^{3/2}]), against polygons of N and 2N
  segments extrapolated in N (the inscribed polygon's error is a series in N⁻²);
* the Vatistas n = 2 core profile h/√(h⁴ + r_c⁴) (Vatistas, Kozel & Mih 1991) at h = r_c and far
  from the core.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from solver.vortex_kernels import induced_velocity
from solver.vortex_wake import TipVortexWake


def _line_integral(p, a, b, gamma):
    d = b - a

    def comp(i):
        def f(t):
            r = p - (a + t * d)
            return np.cross(d, r)[i] / np.linalg.norm(r) ** 3
        return quad(f, 0.0, 1.0, epsabs=0.0, epsrel=1e-13, limit=200)[0]

    return gamma / (4.0 * math.pi) * np.array([comp(i) for i in range(3)])


def test_segment_against_the_biot_savart_integral():
    rng = np.random.default_rng(7)
    a = rng.normal(size=(6, 3))
    b = a + rng.normal(size=(6, 3))
    gamma = rng.uniform(-3.0, 3.0, 6)
    pts = rng.normal(size=(5, 3)) * 1.5
    v = induced_velocity(pts, a, b, gamma)
    ref = np.array([sum(_line_integral(p, a[k], b[k], gamma[k]) for k in range(6)) for p in pts])
    # measured 3.4e-16 of the largest component
    np.testing.assert_allclose(v, ref, rtol=0.0, atol=1e-12 * np.abs(ref).max())


def test_long_segment_is_the_line_vortex_and_the_core_profile():
    gamma, h, rc = 2.5, 0.3, 0.05
    a, b = np.array([[0.0, 0.0, -1e7]]), np.array([[0.0, 0.0, 1e7]])
    p = np.array([[h, 0.0, 0.0]])
    v = induced_velocity(p, a, b, gamma)[0]
    # circulation right-handed about +z: at +x the swirl is +y
    assert v[1] == pytest.approx(gamma / (2 * math.pi * h), rel=1e-12)
    assert v[0] == 0.0 and v[2] == 0.0
    at_core = induced_velocity(np.array([[rc, 0.0, 0.0]]), a, b, gamma, core=rc)[0, 1]
    assert at_core == pytest.approx(gamma / (2 * math.pi * rc) / math.sqrt(2.0), rel=1e-12)
    far = induced_velocity(np.array([[100 * rc, 0.0, 0.0]]), a, b, gamma, core=rc)[0, 1]
    assert far == pytest.approx(gamma / (2 * math.pi * 100 * rc), rel=6e-9)  # (1 + 1e-8)^-½
    on_axis = induced_velocity(np.array([[0.0, 0.0, 0.3]]), a, b, gamma)
    assert np.all(on_axis == 0.0)  # on the line: no velocity, no NaN


def _ring_exact(gamma, a, rho, z):
    """(u_ρ, u_z) of a ring of radius a in z = 0, circulation right-handed about the
    counterclockwise tangent (velocity +z through the ring)."""
    if rho == 0.0:
        return 0.0, gamma * a * a / (2.0 * (a * a + z * z) ** 1.5)
    big = (rho + a) ** 2 + z * z
    small = (a - rho) ** 2 + z * z
    m = 4.0 * a * rho / big
    k, e = ellipk(m), ellipe(m)
    uz = gamma / (2 * math.pi * math.sqrt(big)) * (k + (a * a - rho * rho - z * z) / small * e)
    ur = gamma * z / (2 * math.pi * rho * math.sqrt(big)) * (-k + (a * a + rho * rho + z * z)
                                                             / small * e)
    return ur, uz


def _ring_polygon(n, a, gamma, pts):
    th = 2.0 * math.pi * np.arange(n + 1) / n
    verts = np.stack([a * np.cos(th), a * np.sin(th), np.zeros_like(th)], axis=1)
    return induced_velocity(pts, verts[:-1], verts[1:], gamma)


@pytest.mark.parametrize("rho,z", [(0.0, 0.0), (0.0, 0.7), (0.5, 0.0), (0.5, 0.3), (0.9, 0.1),
                                   (1.5, -0.4), (0.3, -2.0)])
def test_polygon_rings_converge_to_the_elliptic_closed_form(rho, z):
    a, gamma = 1.0, 1.7
    azimuth = 0.37  # off a vertex
    p = np.array([[rho * math.cos(azimuth), rho * math.sin(azimuth), z]])
    ur, uz = _ring_exact(gamma, a, rho, z)
    exact = np.array([ur * math.cos(azimuth), ur * math.sin(azimuth), uz])
    scale = gamma / (2 * a)  # the velocity at the centre
    n = 2048
    coarse, fine = _ring_polygon(n, a, gamma, p)[0], _ring_polygon(2 * n, a, gamma, p)[0]
    # second order in the number of segments (ratio 4.000), the extrapolation of the pair to
    # 1e-10 (measured at most 1.5e-11, beside the ring at ρ = 0.9a)
    assert np.abs(coarse - exact).max() / np.abs(fine - exact).max() == pytest.approx(4.0,
                                                                                     rel=2e-2)
    extrapolated = (4.0 * fine - coarse) / 3.0
    np.testing.assert_allclose(extrapolated, exact, rtol=0.0, atol=1e-10 * scale)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="core radius"):
        induced_velocity([[0, 0, 0]], [[1, 0, 0]], [[2, 0, 0]], 1.0, core=-0.1)
    with pytest.raises(ValueError, match="finite"):
        induced_velocity([[0, 0, np.nan]], [[1, 0, 0]], [[2, 0, 0]], 1.0)
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        induced_velocity([[0, 0]], [[1, 0, 0]], [[2, 0, 0]], 1.0)


# ------------------------------------------------------------------ prescribed tip-vortex wakes
R, OMEGA, BLADES = 8.18, 27.0, 4  # a UH-60A-sized rotor (m, rad/s)


def _disk_mean_and_centre(wake, gamma, core):
    """Disk-area mean and centre value of the induced inflow (on ΩR, positive down)."""
    x, w = np.polynomial.legendre.leggauss(40)
    r, wr = (x + 1.0) / 2.0, w / 2.0 * (x + 1.0) / 2.0
    psi = 2.0 * math.pi * (np.arange(64) + 0.5) / 64
    pts = np.stack([np.outer(r, np.cos(psi)).ravel(), np.outer(r, np.sin(psi)).ravel(),
                    np.zeros(r.size * psi.size)], axis=1) * R
    a, b, _ = wake.segments(0.0)
    lam = -induced_velocity(pts, a, b, gamma, core=core)[:, 2].reshape(r.size, psi.size)
    mean = np.sum(wr[:, None] * lam) / (psi.size * np.sum(wr))
    centre = -induced_velocity(np.zeros((1, 3)), a, b, gamma, core=core)[0, 2]
    return mean / (OMEGA * R), centre / (OMEGA * R)


def test_hover_helical_wake_gives_momentum_inflow():
    # Q tip helices of constant circulation Γ descending at the disk's inflow v: a vortex
    # cylinder of strength QΓΩ/(2πv) per unit length, whose end plane sees half of it; with the
    # thrust ρQΓΩR²/2 of the bound vortices, that is momentum theory, v² = T/(2ρA) = QΓΩ/(4π).
    lam0 = 0.06
    v = lam0 * OMEGA * R
    gamma = 4.0 * math.pi * v * v / (BLADES * OMEGA)
    wake = TipVortexWake(R, BLADES, 0.0, 0.0, lam0, turns=60, segments_per_turn=72)
    mean, centre = _disk_mean_and_centre(wake, gamma, core=0.025 * R)
    # measured 0.985 and 0.9990: the disk mean loses the flux that passes inside the cores
    # and beside the discrete vortices at the rim
    assert mean / lam0 == pytest.approx(1.0, abs=0.02)
    assert centre / lam0 == pytest.approx(1.0, abs=2e-3)


@pytest.mark.parametrize("mu,lam_f", [(0.1, 0.0), (0.2, 0.01), (0.3, 0.02)])
def test_skewed_wake_centre_is_glauert_and_gradient_is_colemans(mu, lam_f):
    # Coleman, Feingold & Stempin (NACA ARR L5E10, 1945): a skewed vortex cylinder gives the
    # momentum (Glauert) inflow at the disk centre, λ0 √(μ² + λ²) = QΓ/(4πΩR²), and a
    # longitudinal gradient λ = λ0 (1 + tan(χ/2) x/R) near it.
    gamma = 40.0
    lam0 = brentq(lambda lam: lam * math.hypot(mu, lam_f + lam)
                  - BLADES * gamma / (4 * math.pi * OMEGA * R * R), 1e-6, 1.0)
    wake = TipVortexWake(R, BLADES, mu, lam_f, lam0, turns=40, segments_per_turn=72)
    xs = np.linspace(-0.25, 0.25, 11)
    pts = np.stack([xs, 0 * xs, 0 * xs], axis=1) * R
    lam = np.mean([-induced_velocity(pts, *wake.segments(az)[:2], gamma,
                                     core=0.02 * R)[:, 2] / (OMEGA * R)
                   for az in np.linspace(0.0, math.pi / 2, 4, endpoint=False)], axis=0)
    slope, centre = np.polyfit(xs, lam, 1)
    # measured: centre 6e-5, 8e-5, 3.4e-4 from Glauert; slope 1.6 %, 1.4 %, 0.9 % above
    # tan(χ/2) (a line fitted over |x| ≤ R/4 of a curve)
    assert centre / lam0 == pytest.approx(1.0, abs=1e-3)
    assert slope / centre / math.tan(wake.skew_angle / 2) == pytest.approx(1.01, abs=0.01)


def test_beddoes_wake_descends_slowly_in_front_and_at_twice_the_inflow_behind():
    mu, lam_f, lam0 = 0.2, 0.01, 0.0344
    rigid = TipVortexWake(R, BLADES, mu, lam_f, lam0, turns=3, descent="rigid")
    bed = TipVortexWake(R, BLADES, mu, lam_f, lam0, turns=3, descent="beddoes")
    e = bed.skew_angle / 2.0
    # the vortex trailed at ψ = 180° (front of the disk) starts at x = −1, y = 0
    pts = bed.filament(math.pi) / R
    phi = bed.ages()
    rate = -np.gradient(pts[:, 2], phi)
    # (a one-sided difference over 5° of age, in which x moves by the wake's own advance)
    assert rate[0] == pytest.approx(lam_f + lam0 * (1.0 - e), rel=2e-2)
    assert rate[0] < lam_f + lam0 < rate[far_index := int(np.argmax(pts[:, 0] > 1.05))]
    assert far_index > 0
    far = pts[:, 0] > 1.05  # downstream of the disk
    expected = lam_f + 2.0 * lam0 * (1.0 - e * np.abs(pts[far, 1]) ** 3)
    # (the trapezoidal descent differentiated back over 5° of age: measured 0.8 %)
    np.testing.assert_allclose(rate[far], expected, rtol=1e-2)
    np.testing.assert_allclose(rigid.filament(0.3)[:, :2], bed.filament(0.3)[:, :2], rtol=1e-14)


@pytest.mark.parametrize("kw,match", [
    ({"radius": -1.0}, "radius"), ({"blades": 0}, "blades"), ({"turns": 0.0}, "turns"),
    ({"mean_induced_inflow": 0.0}, "mean_induced_inflow"), ({"descent": "free"}, "descent"),
    ({"release_radius": 1.2}, "release_radius"), ({"segments_per_turn": 4}, "segments")])
def test_wake_parameters_are_checked(kw, match):
    args = {"radius": R, "blades": BLADES, "advance_ratio": 0.2, "free_stream_inflow": 0.0,
            "mean_induced_inflow": 0.05, **kw}
    with pytest.raises(ValueError, match=match):
        TipVortexWake(**args)


def test_blade_velocities_trail_each_segment_with_its_blades_circulation_then():
    # Γ(ψ) = Γ0 (1 + 0.5 cos ψ + 0.2 sin 2ψ) on the azimuth grid, the tip released from a
    # flapping circle; every segment summed by hand: its blade's Γ when the blade was at
    # ψ_b − φ (the segment's mid age φ), plus the other blades' bound vortices
    n_psi, q = 24, 3
    wake = TipVortexWake(R, q, 0.15, 0.01, 0.04, turns=2, segments_per_turn=36,
                         release_radius=0.95)
    psi = 2 * math.pi * np.arange(n_psi) / n_psi
    gamma = 30.0 * (1 + 0.5 * np.cos(psi) + 0.2 * np.sin(2 * psi))
    release = 0.95 * R * np.stack([np.cos(psi), np.sin(psi), 0.05 * np.cos(psi)], axis=1)
    root = 0.2 * release
    rng = np.random.default_rng(4)
    points = np.einsum("jab,kb->jka", _turn(psi), np.column_stack(
        [np.linspace(0.3, 0.9, 5) * R, rng.normal(0, 0.02, 5), rng.normal(0, 0.05, 5)]))
    core = 0.03
    got = wake.blade_velocities(points, gamma, release, np.stack([root, release], axis=1), core)
    for j in (0, 5, 17):
        expect = np.zeros((5, 3))
        for k in range(q):
            psi_k = psi[j] + 2 * math.pi * k / q
            pts = wake.filament(psi_k, release)
            phi = wake.ages()
            mid = 0.5 * (phi[1:] + phi[:-1])
            trailed = np.interp(np.mod(psi_k - mid, 2 * math.pi),
                                np.append(psi, 2 * math.pi), np.append(gamma, gamma[0]))
            expect += induced_velocity(points[j], pts[:-1], pts[1:], trailed, core)
            if k:
                i = (j + k * n_psi // q) % n_psi
                expect += induced_velocity(points[j], root[i:i + 1], release[i:i + 1],
                                           gamma[i], core)
        np.testing.assert_allclose(got[j], expect, rtol=0, atol=1e-12 * np.abs(expect).max())
    # the filament leaves from the release history: age 0 at the blade's own release point
    np.testing.assert_allclose(wake.filament(psi[7], release)[0], release[7], atol=1e-12)


def _turn(psi):
    c, s = np.cos(psi), np.sin(psi)
    rot = np.zeros((len(psi), 3, 3))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 1, 0], rot[:, 1, 1], rot[:, 2, 2] = c, -s, s, c, 1.0
    return rot
