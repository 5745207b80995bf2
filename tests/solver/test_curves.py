"""Tests of solver.curves: exact NURBS geometry, frames, arc length and constructors.

Tolerances are a few times the errors measured when the tests were written (noted inline).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from solver import curves
from solver.curves import NurbsCurve

RNG_SEED = 20240611


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------
def fd4(f, x: np.ndarray, h: float) -> np.ndarray:
    """Fourth-order central difference of ``f`` (values stacked along a new axis 0 of x)."""
    return (-f(x + 2 * h) + 8 * f(x + h) - 8 * f(x - h) + f(x - 2 * h)) / (12 * h)


def assert_rotation(r: np.ndarray, tol: float = 1e-13) -> None:
    """Columns orthonormal and right-handed (det +1), no NaN."""
    assert np.all(np.isfinite(r))
    eye = np.broadcast_to(np.eye(3), r.shape)
    np.testing.assert_allclose(np.swapaxes(r, -1, -2) @ r, eye, atol=tol)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=tol)


def assert_frame_derivative_fd(curve: NurbsCurve, eta: np.ndarray, rtol: float) -> float:
    """dR/deta from frame() against a 4th-order central difference of R; returns the error."""
    _, dr = curve.frame(eta)
    fd = fd4(lambda e: curve.frame(e)[0], eta, 1e-4)
    err = float(np.max(np.abs(dr - fd)) / np.max(np.abs(dr)))
    assert err < rtol, err
    return err


@pytest.fixture(scope="module")
def cyc() -> NurbsCurve:
    return curves.cycloid(0.7)


@pytest.fixture(scope="module")
def hel() -> NurbsCurve:
    return curves.helix(0.8, 0.5, 3.0)


@pytest.fixture(scope="module")
def epi() -> NurbsCurve:
    return curves.epicycloid(3.0, 1.0, 0.3, 1.8)


# --------------------------------------------------------------------------------------------
# circle and arcs (exact rational quadratics)
# --------------------------------------------------------------------------------------------
def test_circle_points_tangent_curvature_and_frame_closed_form() -> None:
    radius, center, start = 1.7, np.array([0.3, -2.0, 0.5]), 0.4
    c = curves.circle(radius, center, start_angle=start)
    assert c.degree == 2 and c.control_points.shape == (9, 3)
    np.testing.assert_array_equal(c.plane_normal, [0.0, 0.0, 1.0])
    eta = np.linspace(0.0, 1.0, 2001)
    p = c.point(eta)
    rel = p - center
    np.testing.assert_allclose(np.linalg.norm(rel, axis=-1), radius, rtol=1e-14)  # 1e-15
    np.testing.assert_allclose(rel[:, 2], 0.0, atol=1e-15)
    np.testing.assert_allclose(p[0], center + radius * np.array([np.cos(start), np.sin(start), 0]))
    np.testing.assert_allclose(p[-1], p[0], atol=1e-15)
    theta = np.arctan2(rel[:, 1], rel[:, 0])
    # counter-clockwise: the angle increases monotonically (unwrapped) by 2 pi
    unwrapped = np.unwrap(theta)
    assert np.all(np.diff(unwrapped) > 0)
    assert unwrapped[-1] - unwrapped[0] == pytest.approx(2 * np.pi, abs=1e-13)

    r, dr = c.frame(eta)
    assert_rotation(r)
    t_exact = np.stack([-np.sin(theta), np.cos(theta), 0 * theta], axis=-1)
    n_exact = np.stack([-np.cos(theta), -np.sin(theta), 0 * theta], axis=-1)  # to the centre
    np.testing.assert_allclose(r[..., 0], t_exact, atol=1e-14)
    np.testing.assert_allclose(r[..., 1], n_exact, atol=1e-14)
    np.testing.assert_allclose(r[..., 2], np.broadcast_to([0, 0, 1.0], t_exact.shape), atol=0)
    np.testing.assert_allclose(c.curvature(eta), 1.0 / radius, rtol=1e-13)  # 1e-15
    np.testing.assert_array_equal(c.torsion(eta), 0.0)
    # dR/deta = theta' [[-cos, sin, 0], [-sin, -cos, 0], [0, 0, 0]] with theta' = speed / R
    dtheta = c.speed(eta) / radius
    dt = dtheta[:, None] * np.stack([-np.cos(theta), -np.sin(theta), 0 * theta], axis=-1)
    dn = dtheta[:, None] * np.stack([np.sin(theta), -np.cos(theta), 0 * theta], axis=-1)
    np.testing.assert_allclose(dr[..., 0], dt, atol=1e-13 * dtheta.max())
    np.testing.assert_allclose(dr[..., 1], dn, atol=1e-13 * dtheta.max())
    np.testing.assert_array_equal(dr[..., 2], 0.0)
    # exact speed check: d theta / d eta = speed / R integrates to 2 pi
    assert c.length == pytest.approx(2 * np.pi * radius, rel=1e-14)  # measured 1e-16


def test_circle_arc_length_and_eta_symmetry() -> None:
    for radius in (1e-3, 1.0, 250.0):
        c = curves.circle(radius)
        assert abs(c.length / (2 * np.pi * radius) - 1) < 1e-13  # measured <= 2e-16
        quarter = c.eta_at(np.array([0.25, 0.5, 0.75]) * c.length)
        np.testing.assert_allclose(quarter, [0.25, 0.5, 0.75], atol=1e-14)


@pytest.mark.parametrize(
    ("a0", "a1", "npieces"),
    [(0.0, 0.5, 1), (-0.3, np.pi / 2 - 0.3, 1), (0.2, 3.5, 3), (1.0, 1.0 + 2 * np.pi, 4)],
)
def test_circle_arc(a0: float, a1: float, npieces: int) -> None:
    radius, center = 2.5, np.array([1.0, 2.0])
    arc = curves.circle_arc(radius, a0, a1, center=center)
    assert len(arc.control_points) == 2 * npieces + 1
    eta = np.linspace(0, 1, 1001)
    rel = arc.point(eta) - np.append(center, 0.0)
    np.testing.assert_allclose(np.linalg.norm(rel, axis=-1), radius, rtol=1e-14)
    np.testing.assert_allclose(rel[0, :2], radius * np.array([np.cos(a0), np.sin(a0)]), atol=1e-14)
    np.testing.assert_allclose(rel[-1, :2], radius * np.array([np.cos(a1), np.sin(a1)]), atol=1e-14)
    ang = np.unwrap(np.arctan2(rel[:, 1], rel[:, 0]))
    assert np.all(np.diff(ang) > 0)
    np.testing.assert_allclose(arc.curvature(eta), 1 / radius, rtol=1e-13)
    assert arc.length == pytest.approx(radius * (a1 - a0), rel=1e-14)
    assert_frame_derivative_fd(arc, np.array([0.1, 0.37, 0.61, 0.9]) + 0.013, 1e-10)  # 1.8e-12


def test_right_turn_gives_negative_curvature_and_outward_normal() -> None:
    """A clockwise circle with plane_normal +z: n = b x t points away from the centre."""
    c = curves.circle(2.0)
    cw = NurbsCurve(2, 1 - c.knots[::-1], c.control_points[::-1], c.weights[::-1], (0, 0, 1))
    eta = np.linspace(0.01, 0.99, 57)
    p = cw.point(eta)
    r, dr = cw.frame(eta)
    np.testing.assert_allclose(cw.curvature(eta), -0.5, rtol=1e-13)
    np.testing.assert_allclose(r[..., 1], p / 2.0, atol=1e-14)  # outward
    # t' = |p'| kappa n holds with the signed curvature
    k = cw.curvature(eta) * cw.speed(eta)
    np.testing.assert_allclose(dr[..., 0], k[:, None] * r[..., 1], atol=1e-12)
    np.testing.assert_allclose(dr[..., 1], -k[:, None] * r[..., 0], atol=1e-12)


def test_tilted_planar_circle() -> None:
    """Control points in a tilted plane with the matching plane_normal."""
    c = curves.circle(1.5)
    ang = 0.7
    q = np.array([[1, 0, 0], [0, np.cos(ang), -np.sin(ang)], [0, np.sin(ang), np.cos(ang)]])
    tilted = NurbsCurve(2, c.knots, c.control_points @ q.T, c.weights, plane_normal=q[:, 2])
    eta = np.linspace(0, 1, 101)
    r, _ = tilted.frame(eta)
    assert_rotation(r)
    np.testing.assert_allclose(r[..., 2], np.broadcast_to(q[:, 2], (101, 3)), atol=1e-15)
    np.testing.assert_allclose(tilted.curvature(eta), 1 / 1.5, rtol=1e-13)
    # the same circle as a space curve: the Frenet binormal coincides
    space = NurbsCurve(2, c.knots, c.control_points @ q.T, c.weights)
    np.testing.assert_allclose(space.frame(eta)[0], r, atol=1e-13)
    np.testing.assert_allclose(space.curvature(eta), 1 / 1.5, rtol=1e-13)
    np.testing.assert_allclose(space.torsion(eta), 0.0, atol=1e-12)


# --------------------------------------------------------------------------------------------
# cycloid, epicycloid, helix (interpolated transcendental curves)
# --------------------------------------------------------------------------------------------
def test_cycloid_points_tangent_angle_curvature(cyc: NurbsCurve) -> None:
    a = 0.7
    eta = np.linspace(0.0, 1.0, 20001)
    t = -np.pi + 2 * np.pi * eta
    exact = np.stack([a * (t + np.sin(t)), -a * (1 + np.cos(t)), 0 * t], axis=-1)
    err = np.max(np.linalg.norm(cyc.point(eta) - exact, axis=-1))
    assert err < 1e-13 * a  # measured 3e-15 a, everywhere including the cusps
    inner = np.abs(t) < 0.95 * np.pi
    r, _ = cyc.frame(eta)
    assert_rotation(r)
    angle = np.arctan2(r[..., 1, 0], r[..., 0, 0])
    assert np.max(np.abs(angle - t / 2)[inner]) < 1e-11  # measured 3.0e-12
    # the end tangents at the cusps are vertical (limiting direction), never NaN
    np.testing.assert_allclose(angle[[0, -1]], [-np.pi / 2, np.pi / 2], atol=1e-8)  # 2e-9
    # left turn about +z everywhere: n points up, towards the centre of curvature
    kappa = cyc.curvature(eta[inner])
    exact_kappa = 1 / (4 * a * np.cos(t[inner] / 2))
    assert np.max(np.abs(kappa / exact_kappa - 1)) < 1e-8  # measured 2.9e-9
    assert r[len(eta) // 2, 1, 1] == pytest.approx(1.0, abs=1e-14)
    assert cyc.point(0.5)[1] == pytest.approx(-2 * a, abs=1e-14)


def test_cycloid_arc_length(cyc: NurbsCurve) -> None:
    a = 0.7
    assert abs(cyc.length / (8 * a) - 1) < 1e-10  # measured 6e-16
    eta = np.linspace(0, 1, 1001)
    t = -np.pi + 2 * np.pi * eta
    s_exact = 4 * a * (1 + np.sin(t / 2))
    np.testing.assert_allclose(cyc.arc_length(eta), s_exact, rtol=0, atol=1e-13 * a)  # 5e-15


def test_epicycloid_curvature_and_frame(epi: NurbsCurve) -> None:
    a, b = 3.0, 1.0
    eta = np.linspace(0, 1, 3001)
    phi = 0.3 + 1.5 * eta
    k = (a + b) / b
    exact = np.stack(
        [(a + b) * np.cos(phi) - b * np.cos(k * phi), (a + b) * np.sin(phi) - b * np.sin(k * phi)],
        axis=-1,
    )
    np.testing.assert_allclose(epi.point(eta)[:, :2], exact, atol=1e-13)
    kappa = (a + 2 * b) / (4 * b * (a + b) * np.abs(np.sin(a * phi / (2 * b))))
    np.testing.assert_allclose(epi.curvature(eta), kappa, rtol=5e-9)  # measured 8e-10
    assert_frame_derivative_fd(epi, np.linspace(0.02, 0.98, 25), 1e-10)  # 4.8e-13


def test_cycloid_frame_derivative_fd(cyc: NurbsCurve) -> None:
    assert_frame_derivative_fd(cyc, np.linspace(0.05, 0.95, 31), 1e-10)  # 5.9e-13


def test_helix_curvature_torsion_and_frame(hel: NurbsCurve) -> None:
    r0, pitch = 0.8, 0.5
    c = pitch / (2 * np.pi)
    assert hel.plane_normal is None
    eta = np.linspace(0, 1, 5001)
    u = eta * 2 * np.pi * 3
    exact = np.stack([r0 * np.cos(u), r0 * np.sin(u), c * u], axis=-1)
    np.testing.assert_allclose(hel.point(eta), exact, atol=1e-13)
    np.testing.assert_allclose(hel.curvature(eta), r0 / (r0**2 + c**2), rtol=2e-9)  # 4.2e-10
    np.testing.assert_allclose(hel.torsion(eta), c / (r0**2 + c**2), rtol=5e-8)  # 1.0e-8
    assert hel.length == pytest.approx(3 * 2 * np.pi * math.hypot(r0, c), rel=1e-13)
    r, _ = hel.frame(eta)
    assert_rotation(r)
    # Frenet normal of a helix points to the axis
    radial = -exact[:, :2] / r0
    np.testing.assert_allclose(r[:, :2, 1], radial, atol=1e-10)  # 2e-12
    np.testing.assert_allclose(r[:, 2, 1], 0.0, atol=1e-10)  # 1.3e-11
    # dR/deta includes the torsion terms n' = |p'|(-kappa t + tau b), b' = -|p'| tau n
    assert_frame_derivative_fd(hel, np.linspace(0.03, 0.97, 23), 1e-10)  # 5.8e-13
    _, dr = hel.frame(np.array([0.41]))
    tau_term = hel.speed(0.41) * c / (r0**2 + c**2)
    assert np.linalg.norm(dr[0, :, 2]) == pytest.approx(tau_term, rel=1e-10)  # 3.6e-12


# --------------------------------------------------------------------------------------------
# straight lines and straight stretches
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("end", [(1.0, 2.0, 3.0), (0.0, 0.0, -2.0), (1e-3, 0.0, 2e-3)])
def test_space_line_has_finite_frame(end: tuple[float, float, float]) -> None:
    ln = curves.line((0.5, 0.5, 0.5), np.add(end, 0.5))
    assert ln.degree == 1 and ln.plane_normal is None
    eta = np.linspace(0, 1, 11)
    r, dr = ln.frame(eta)
    assert_rotation(r)
    np.testing.assert_allclose(
        r[..., 0], np.broadcast_to(np.array(end) / np.linalg.norm(end), (11, 3))
    )
    np.testing.assert_array_equal(dr, 0.0)
    np.testing.assert_array_equal(ln.curvature(eta), 0.0)
    np.testing.assert_array_equal(ln.torsion(eta), 0.0)
    assert ln.length == pytest.approx(np.linalg.norm(end), rel=1e-15)


def test_planar_line() -> None:
    ln = curves.line((0.0, 0.0), (3.0, 4.0))
    assert ln.plane_normal is not None
    r, dr = ln.frame(0.3)
    np.testing.assert_allclose(r[:, 0], [0.6, 0.8, 0.0])
    np.testing.assert_allclose(r[:, 1], [-0.8, 0.6, 0.0])  # left normal
    np.testing.assert_array_equal(dr, 0.0)
    assert ln.curvature(0.3) == 0.0
    np.testing.assert_allclose(ln.point(0.5), [1.5, 2.0, 0.0])
    assert ln.eta_at(2.5) == pytest.approx(0.5, abs=1e-15)


def test_space_curve_with_straight_stretch() -> None:
    """Collinear first control points: the first span is straight, then it bends out of plane."""
    pts = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0), (4, 1, 1), (4, 2, 3)]
    crv = NurbsCurve(3, [0, 0, 0, 0, 0.4, 0.7, 1, 1, 1, 1], pts)
    eta = np.linspace(0.0, 0.4, 21)[:-1]
    r, dr = crv.frame(eta)
    assert_rotation(r)
    np.testing.assert_allclose(r[..., 0], np.broadcast_to([1.0, 0, 0], (20, 3)), atol=1e-15)
    assert np.all(np.isfinite(dr))
    np.testing.assert_allclose(dr, 0.0, atol=1e-14)
    np.testing.assert_array_equal(crv.torsion(eta), 0.0)
    np.testing.assert_allclose(crv.curvature(eta), 0.0, atol=1e-15)
    # the curved part is a regular Frenet frame
    bent = np.linspace(0.45, 0.95, 11)
    assert np.all(crv.curvature(bent) > 1e-3)
    assert_frame_derivative_fd(crv, bent + 0.007, 1e-10)  # 2.6e-11


def test_straight_stretch_frame_derivative_is_exact(
    hel: NurbsCurve, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Force the straight-stretch frame on a curved helix: its dR/deta must still be exact."""
    monkeypatch.setattr(curves, "_STRAIGHT_TOL", 1e30)
    eta = np.linspace(0.03, 0.97, 97)
    # the reference axis (least aligned with t) must not switch inside the FD stencil
    axes = [np.argmin(np.abs(hel.frame(eta + k * 1e-4)[0][..., 0]), axis=-1) for k in (-2, 2)]
    eta = eta[axes[0] == axes[1]]
    r, dr = hel.frame(eta)
    assert_rotation(r)
    np.testing.assert_array_equal(hel.torsion(eta), 0.0)
    # n = unit part of the least-aligned global axis orthogonal to t
    t = r[..., 0]
    e = np.eye(3)[np.argmin(np.abs(t), axis=-1)]
    m = e - t * np.sum(t * e, axis=-1)[:, None]
    np.testing.assert_allclose(r[..., 1], m / np.linalg.norm(m, axis=1)[:, None], atol=1e-15)
    assert np.max(np.abs(dr[..., 1])) > 1.0  # n really moves
    assert_frame_derivative_fd(hel, eta, 1e-10)  # measured 7e-13


# --------------------------------------------------------------------------------------------
# general NURBS: exact derivatives against finite differences
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("degree", [2, 3, 4, 5])
def test_rational_derivatives_against_finite_differences(degree: int) -> None:
    rng = np.random.default_rng(RNG_SEED + degree)
    n = degree + 4
    pts = rng.uniform(-1.0, 1.0, size=(n, 3))
    w = rng.uniform(0.4, 2.5, size=n)
    inner = np.sort(rng.uniform(0.1, 0.9, size=n - degree - 1))
    knots = np.concatenate([[0.0] * (degree + 1), inner, [1.0] * (degree + 1)])
    crv = NurbsCurve(degree, knots * 3.0 - 1.0, pts, w)  # any knot range is rescaled
    np.testing.assert_allclose(crv.knots, knots, atol=1e-15)
    # test points at least 0.01 away from every knot (the stencil spans 4e-4)
    eta = np.linspace(0.02, 0.98, 200)
    eta = eta[np.min(np.abs(eta[:, None] - knots[None, :]), axis=1) > 0.01]
    d = crv.derivatives(eta, order=4)
    assert d.shape == (5, len(eta), 3)
    np.testing.assert_allclose(d[0], crv.point(eta))
    for k in range(1, 5):
        fd = fd4(lambda e, k=k: crv.derivatives(e, order=k - 1)[k - 1], eta, 1e-4)
        scale = np.max(np.abs(d[k]))
        err = np.max(np.abs(d[k] - fd)) / scale
        assert err < 1e-8, (k, err)  # measured <= 1.6e-9 (truncation error of the stencil)
    # the homogeneous formula: p = sum N w P / sum N w, checked on one point by hand
    from scipy.interpolate import BSpline

    num = BSpline(knots, pts * w[:, None], degree)(0.5)
    den = BSpline(knots, w, degree)(0.5)
    np.testing.assert_allclose(crv.point(0.5), num / den, rtol=1e-14)


def test_derivatives_beyond_degree_and_shapes() -> None:
    c = curves.circle(1.0)
    d = c.derivatives(np.full((2, 3), 0.1), order=5)  # rational: p'''' etc. are not zero
    assert d.shape == (6, 2, 3, 3)
    fd = fd4(lambda e: c.derivatives(e, 4)[4], np.array([0.1]), 1e-4)
    np.testing.assert_allclose(d[5, 0, 0], fd[0], rtol=1e-5)
    ln = curves.line((0, 0, 0), (1, 1, 1))
    np.testing.assert_array_equal(ln.derivatives(0.3, order=3)[2:], 0.0)
    assert c.point(0.2).shape == (3,)
    assert c.speed(0.2).shape == ()
    assert c.curvature(0.2).shape == ()
    assert c.arc_length(0.2).shape == ()
    assert c.eta_at(0.2).shape == ()
    assert c.frame(0.2)[0].shape == (3, 3)
    assert c.frame(np.zeros((4, 5)))[1].shape == (4, 5, 3, 3)
    assert c.derivatives(0.2).shape == (4, 3)


def test_eta_is_clipped_to_unit_interval() -> None:
    c = curves.circle(1.0, start_angle=0.3)
    np.testing.assert_array_equal(c.point(1.0 + 1e-12), c.point(1.0))
    np.testing.assert_array_equal(c.point(-0.25), c.point(0.0))
    np.testing.assert_array_equal(c.frame(7.0)[0], c.frame(1.0)[0])
    assert c.arc_length(1.5) == c.length
    assert c.eta_at(-1.0) == 0.0
    assert c.eta_at(10.0) == 1.0


# --------------------------------------------------------------------------------------------
# interpolation
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("degree", [1, 2, 3, 5])
def test_interpolate_reproduces_points(degree: int) -> None:
    rng = np.random.default_rng(RNG_SEED)
    pts = np.cumsum(rng.uniform(0.1, 1.0, size=(12, 3)), axis=0)
    crv = curves.interpolate(pts, degree=degree)
    chord = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    u = chord / chord[-1]
    np.testing.assert_allclose(crv.point(u), pts, atol=1e-12)
    assert crv.plane_normal is None and crv.degree == degree
    # given parameters, any range
    par = np.linspace(-2.0, 5.0, 12) ** 3
    crv2 = curves.interpolate(pts, degree=degree, parameters=par)
    np.testing.assert_allclose(crv2.point((par - par[0]) / (par[-1] - par[0])), pts, atol=1e-12)


def test_interpolate_planarity() -> None:
    xy = np.array([[0, 0], [1, 0.5], [2, 0.2], [3, -1], [4, 0]], dtype=float)
    assert curves.interpolate(xy).plane_normal is not None
    flat = np.column_stack([xy, np.full(5, 0.25)])
    crv = curves.interpolate(flat)
    np.testing.assert_array_equal(crv.plane_normal, [0, 0, 1])
    np.testing.assert_array_equal(crv.control_points[:, 2], 0.25)
    # a tilted plane given explicitly
    normal = np.array([0.0, -np.sin(0.4), np.cos(0.4)])
    q = np.array([[1, 0, 0], [0, np.cos(0.4), -np.sin(0.4)], [0, np.sin(0.4), np.cos(0.4)]])
    tilted_pts = flat @ q.T
    tilted = curves.interpolate(tilted_pts, plane_normal=normal * 3.0)
    np.testing.assert_allclose(tilted.plane_normal, normal)
    r, _ = tilted.frame(np.linspace(0, 1, 9))
    np.testing.assert_allclose(r[..., 2], np.broadcast_to(normal, (9, 3)), atol=1e-15)
    assert_rotation(r)


def test_from_function_parameter_is_affine_in_t() -> None:
    def f(t: np.ndarray) -> np.ndarray:
        return np.stack([np.cos(t), np.sin(2 * t), 0.1 * t])  # (3, n) is accepted too

    crv = curves.from_function(f, -1.0, 2.0, n_points=200)
    eta = np.linspace(0, 1, 777)
    np.testing.assert_allclose(crv.point(eta), f(-1.0 + 3.0 * eta).T, atol=1e-12)
    # derivatives scale with (t1 - t0)
    t = -1.0 + 3.0 * eta
    dexact = 3.0 * np.stack([-np.sin(t), 2 * np.cos(2 * t), 0.1 + 0 * t], axis=-1)
    np.testing.assert_allclose(crv.derivatives(eta, 1)[1], dexact, atol=1e-9)


# --------------------------------------------------------------------------------------------
# arc length inversion and closest point
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["circle", "cycloid", "helix", "rational"])
def test_eta_at_inverts_arc_length(name: str, cyc: NurbsCurve, hel: NurbsCurve) -> None:
    if name == "circle":
        crv = curves.circle(0.3)
    elif name == "cycloid":
        crv = cyc
    elif name == "helix":
        crv = hel
    else:
        rng = np.random.default_rng(RNG_SEED)
        crv = NurbsCurve(
            3, [0, 0, 0, 0, 0.2, 0.5, 1, 1, 1, 1], rng.normal(size=(6, 3)), rng.uniform(0.3, 3, 6)
        )
    s = np.linspace(0.0, crv.length, 501)
    eta = crv.eta_at(s)
    assert np.all(np.diff(eta) > 0)
    np.testing.assert_allclose(crv.arc_length(eta), s, rtol=0, atol=1e-14 * crv.length)  # 8e-16
    # the other way round, where the speed is not small
    e = np.linspace(0.05, 0.95, 101)
    np.testing.assert_allclose(crv.eta_at(crv.arc_length(e)), e, atol=1e-14)  # 8e-16
    # arc length against an independent composite 24-point Gauss rule split at the knots
    end = 0.37
    cuts = np.unique(np.concatenate([[0.0, end], crv.knots[crv.knots < end]]))
    edges = np.unique(np.concatenate([np.linspace(a, b, 41) for a, b in itertools.pairwise(cuts)]))
    x, w = np.polynomial.legendre.leggauss(24)
    half = 0.5 * np.diff(edges)
    nodes = (edges[:-1] + half)[:, None] + half[:, None] * x
    ref = float(np.sum(half * (crv.speed(nodes) @ w)))
    assert float(crv.arc_length(end)) == pytest.approx(ref, rel=1e-13)


def test_closest_eta() -> None:
    c = curves.circle(2.0, center=(1.0, 1.0))
    for ang in (0.0, 0.3, 2.0, 4.0, 6.0):
        q = np.array([1.0, 1.0]) + 3.5 * np.array([np.cos(ang), np.sin(ang)])
        e = c.closest_eta(q)
        rel = c.point(e)[:2] - [1.0, 1.0]
        assert math.atan2(rel[1], rel[0]) % (2 * np.pi) == pytest.approx(ang, abs=1e-12)
    cyc = curves.cycloid(1.0)
    for eta0 in (0.2, 0.5, 0.77):
        r, _ = cyc.frame(eta0)
        q = cyc.point(eta0) + 0.05 * r[:, 1]  # off the curve along the normal (inside)
        assert cyc.closest_eta(q) == pytest.approx(eta0, abs=1e-12)
        assert cyc.closest_eta(cyc.point(eta0)) == pytest.approx(eta0, abs=1e-12)
    assert cyc.closest_eta((-10.0, 1.0)) == 0.0
    assert cyc.closest_eta((10.0, 1.0, 0.0)) == 1.0


# --------------------------------------------------------------------------------------------
# input validation
# --------------------------------------------------------------------------------------------
GOOD_KNOTS = [0, 0, 0, 0, 0.5, 1, 1, 1, 1]
GOOD_PTS = [(0, 0), (1, 1), (2, 0), (3, 1), (4, 0)]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"weights": [1, 1, 0, 1, 1]}, r"weights must be finite and > 0"),
        ({"weights": [1, 1, 1]}, r"weights must have shape \(5,\)"),
        (
            {"knots": [0, 0, 0, 0, 1, 1, 1, 1]},
            r"knot vector length must be n\+degree\+1 = 9, got 8",
        ),
        ({"knots": [0, 0, 0, 0.1, 0.5, 1, 1, 1, 1]}, r"knots must be clamped"),
        ({"knots": [0, 0, 0, 0, 0.5, 0.4, 1, 1, 1]}, r"knots must be nondecreasing"),
        ({"knots": [1, 1, 1, 1, 1, 1, 1, 1, 1]}, r"knots must span a nonzero range"),
        ({"degree": 0}, r"degree must be an integer >= 1, got 0"),
        ({"degree": 2.5}, r"degree must be an integer"),
        ({"control_points": [(0, 0), (1, 1), (2, 0)]}, r"need at least degree\+1 = 4 control"),
        ({"control_points": [(0, 0, 0, 0)] * 5}, r"control_points must have shape"),
        ({"control_points": [(1, 1)] * 5}, r"control_points must not all coincide"),
        ({"plane_normal": (0, 0, 0)}, r"plane_normal must be a finite nonzero 3-vector"),
        ({"plane_normal": (1, 0, 0)}, r"control_points must lie in a plane orthogonal"),
    ],
)
def test_bad_nurbs_input(kwargs: dict, match: str) -> None:
    args = {"degree": 3, "knots": GOOD_KNOTS, "control_points": GOOD_PTS} | kwargs
    with pytest.raises(ValueError, match=match):
        NurbsCurve(**args)


def test_bad_constructor_input() -> None:
    with pytest.raises(ValueError, match=r"radius must be a finite number > 0, got -1"):
        curves.circle(-1)
    with pytest.raises(ValueError, match=r"radius"):
        curves.circle_arc(0.0, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"angle_end - angle_start must be in \(0, 2 pi\]"):
        curves.circle_arc(1.0, 1.0, 0.5)
    with pytest.raises(ValueError, match=r"angle_end - angle_start"):
        curves.circle_arc(1.0, 0.0, 7.0)
    with pytest.raises(ValueError, match=r"center must be a finite 2- or 3-vector"):
        curves.circle(1.0, center=(0, 0, 0, 0))
    with pytest.raises(ValueError, match=r"p0 and p1 must differ"):
        curves.line((1, 2), (1, 2))
    with pytest.raises(ValueError, match=r"points: need at least degree\+1 = 4 points, got 3"):
        curves.interpolate([(0, 0), (1, 1), (2, 0)])
    with pytest.raises(ValueError, match=r"points 1 and 2 coincide"):
        curves.interpolate([(0, 0), (1, 1), (1, 1), (2, 0), (3, 3)])
    with pytest.raises(ValueError, match=r"parameters must be finite and strictly increasing"):
        curves.interpolate(GOOD_PTS, parameters=[0, 1, 1, 2, 3])
    with pytest.raises(ValueError, match=r"points must lie in a plane orthogonal"):
        curves.interpolate([(0, 0, 0), (1, 0, 1), (2, 1, 0), (3, 0, 0)], plane_normal=(0, 0, 1))
    with pytest.raises(ValueError, match=r"t1 must be > t0"):
        curves.from_function(lambda t: np.stack([t, t]), 1.0, 1.0)
    with pytest.raises(ValueError, match=r"n_points must be an integer >= 6, got 5"):
        curves.from_function(lambda t: np.stack([t, t]), 0.0, 1.0, n_points=5)
    with pytest.raises(ValueError, match=r"f must return points of shape"):
        curves.from_function(lambda t: t, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"f must return finite points"):
        curves.from_function(lambda t: np.stack([t, np.where(t > 0.5, np.nan, t)]), 0.0, 1.0)
    with pytest.raises(ValueError, match=r"a must be a finite number > 0"):
        curves.cycloid(-0.1)
    with pytest.raises(ValueError, match=r"b must be a finite number > 0"):
        curves.epicycloid(1.0, 0.0, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"turns must be a finite number > 0"):
        curves.helix(1.0, 0.1, 0.0)
    with pytest.raises(ValueError, match=r"pitch must be a finite number"):
        curves.helix(1.0, float("nan"), 1.0)
    with pytest.raises(ValueError, match=r"order must be an integer >= 0"):
        curves.circle(1.0).derivatives(0.5, order=-1)
    with pytest.raises(ValueError, match=r"point must be a finite 2- or 3-vector"):
        curves.circle(1.0).closest_eta((1.0, 2.0, 3.0, 4.0))
