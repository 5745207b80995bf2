"""The compiled B-spline kernel (solver.bsplines) against scipy's independent evaluation.

scipy's ``BSpline.__call__(x, nu)`` runs de Boor's recurrence for the derivative of order nu
directly on the basis functions; ours differentiates the coefficients (Piegl & Tiller eq.
3.4) and sums them with the lower-degree basis. Random clamped knot vectors with repeated
interior knots, degrees 0-5, points at and between the knots, both ends.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import BSpline

from solver.bsplines import bspline_derivatives, nurbs_derivatives


def random_spline(rng, p: int, repeat: bool):
    n = p + 1 + int(rng.integers(0, 8))
    inner = np.sort(rng.random(n - p - 1))
    if repeat and len(inner) >= 2:  # a knot of multiplicity up to p (C0 at most)
        m = min(p, len(inner))
        inner[:m] = inner[0]
    t = np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])
    return t, rng.standard_normal((n, 3))


@pytest.mark.parametrize("p", range(6))
def test_derivatives_match_scipy(p):
    rng = np.random.default_rng(p)
    worst = 0.0
    for trial in range(30):
        t, c = random_spline(rng, p, repeat=trial % 2 == 1)
        x = np.concatenate([rng.random(40), t])  # the knots themselves: one-sided values
        d = bspline_derivatives(t, c, p, x, p + 1)
        spl = BSpline(t, c, p, extrapolate=True)
        for k in range(p + 1):
            ref = spl(x, nu=k)
            worst = max(worst, np.abs(d[k] - ref).max() / max(1.0, np.abs(ref).max()))
        assert np.all(d[p + 1] == 0.0)  # above the degree
    # measured ≤ 6e-16 of the scale
    assert worst <= 1e-12, worst


def test_rational_curve_against_its_closed_form():
    """A NURBS quarter circle (degree 2, weights 1, 1/√2, 1) lies exactly on the unit circle:
    the point to roundoff, the tangent from the quotient rule perpendicular to the radius,
    and against central differences of the point."""
    w = np.array([1.0, np.sqrt(0.5), 1.0])
    pts = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    t = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    hom = np.column_stack([pts * w[:, None], w])
    x = np.linspace(0.0, 1.0, 11)
    d = nurbs_derivatives(t, hom, 2, x, 2, rational=True)
    np.testing.assert_allclose(np.linalg.norm(d[0], axis=1), 1.0, atol=1e-15)
    # tangent ⟂ radius, and the rational first derivative against central differences
    np.testing.assert_allclose(np.sum(d[0] * d[1], axis=1), 0.0, atol=1e-14)
    h = 1e-6
    xi = x[1:-1]
    fd = (nurbs_derivatives(t, hom, 2, xi + h, 0, True)[0]
          - nurbs_derivatives(t, hom, 2, xi - h, 0, True)[0]) / (2 * h)
    np.testing.assert_allclose(d[1][1:-1], fd, atol=1e-8)  # measured 1.3e-10 (the FD error)
