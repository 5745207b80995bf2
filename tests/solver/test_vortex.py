"""Biot–Savart velocity of straight vortex segments (solver/vortex_kernels.py).

References, independent of the kernel:

* the Biot–Savart line integral v = Γ/(4π) ∫ dl × (P − x)/|P − x|³ along each segment, by
  adaptive quadrature (scipy.integrate.quad);
* the infinite line vortex, Γ/(2π h);
* the vortex ring's velocity field in closed form with complete elliptic integrals (Lamb,
  *Hydrodynamics*, §161; on the axis Γa²/[2(a² + z²)^{3/2}]), against polygons of N and 2N
  segments extrapolated in N (the inscribed polygon's error is a series in N⁻²);
* the Vatistas n = 2 core profile h/√(h⁴ + r_c⁴) (Bagai & Leishman 1993) at h = r_c and far
  from the core.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ellipe, ellipk

from solver.vortex_kernels import induced_velocity


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
