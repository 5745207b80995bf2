"""Compiled B-spline evaluation: a point and its derivatives at many parameters in one call.

The curve-joint kernels evaluate NURBS curves at a handful of parameters per Newton iteration
(one per pin); there scipy's ``BSpline`` costs a call per derivative order, and the rational
quotient rule in NumPy as much again: most of a curve evaluation's time on the hub model. This
kernel finds the knot span, the nonzero basis functions of every degree up to p (Piegl &
Tiller, *The NURBS Book*, algorithms A2.1 and A2.2) and the derivatives as lower-degree
splines of the coefficients' differences (eq. 3.4), compiled with numba.

Conventions (those of ``scipy.interpolate.BSpline`` with ``extrapolate=True``, which the tests
check against): the span of x is the last l with t[l] <= x, limited to degree <= l < n; so at
an interior knot every derivative is the one from the right, and at the right end of the
knot vector the one from the left. Derivatives above the degree are zero.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from solver.jit import njit

Array = NDArray[np.float64]


@njit(cache=True)
def _span(t: Array, degree: int, n: int, x: float) -> int:
    """Last l in [degree, n − 1] with t[l] <= x (binary search, A2.1 with scipy's ends)."""
    lo, hi = degree, n - 1
    if x >= t[hi]:
        return hi
    while hi - lo > 1:  # t[lo] <= x < t[hi] (or x below t[degree]: then lo = degree)
        mid = (lo + hi) // 2
        if t[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def _basis(t: Array, degree: int, span: int, x: float) -> Array:
    """Triangular table of the nonzero basis functions of every degree q <= p at x on
    ``span``: N_{span−q+r, q}(x) = ndu[r, q] (A2.2, keeping the lower degrees)."""
    p = degree
    ndu = np.zeros((p + 1, p + 1))
    left = np.zeros(p + 1)
    right = np.zeros(p + 1)
    ndu[0, 0] = 1.0
    for j in range(1, p + 1):
        left[j] = x - t[span + 1 - j]
        right[j] = t[span + j] - x
        saved = 0.0
        for r in range(j):
            tmp = ndu[r, j - 1] / (right[r + 1] + left[j - r])
            ndu[r, j] = saved + right[r + 1] * tmp
            saved = left[j - r] * tmp
        ndu[j, j] = saved
    return ndu


@njit(cache=True)
def _evaluate(t: Array, coef: Array, degree: int, x: Array, order: int) -> Array:
    """The k-th derivative as the degree p − k spline whose coefficients are the k-th
    differences of the active coefficients (the arithmetic of differentiating the spline):
    c⁽ʳ⁾_i = (p − r + 1)(c⁽ʳ⁻¹⁾_i − c⁽ʳ⁻¹⁾_{i−1}) / (t_{i+p−r+1} − t_i), and 0 across a
    zero-width interval (a basis function with empty support: a C0 knot)."""
    n = coef.shape[0]
    dim = coef.shape[1]
    p = degree
    out = np.zeros((order + 1, x.shape[0], dim))
    d = np.empty((p + 1, dim))
    for i in range(x.shape[0]):
        span = _span(t, p, n, x[i])
        ndu = _basis(t, p, span, x[i])
        for j in range(p + 1):
            for m in range(dim):
                d[j, m] = coef[span - p + j, m]
        for k in range(min(order, p) + 1):
            if k > 0:  # one more difference: then d[j] = c⁽ᵏ⁾_{span−p+j} for j >= k
                for j in range(p, k - 1, -1):
                    ii = span - p + j
                    den = t[ii + p - k + 1] - t[ii]
                    f = (p - k + 1) / den if den > 0.0 else 0.0
                    for m in range(dim):
                        d[j, m] = f * (d[j, m] - d[j - 1, m])
            q = p - k
            for jj in range(q + 1):
                c = ndu[jj, q]
                for m in range(dim):
                    out[k, i, m] += c * d[k + jj, m]
    return out


@njit(cache=True)
def _rational(hom: Array) -> Array:
    """Derivatives of p = A/w from those of the homogeneous (A, w) (last column w), by
    Leibniz's rule on A = w p: p^(k) = (A^(k) − Σ_{j=1..k} C(k, j) w^(j) p^(k−j)) / w."""
    order, npts, dim = hom.shape[0] - 1, hom.shape[1], hom.shape[2] - 1
    out = np.zeros((order + 1, npts, dim))
    for i in range(npts):
        inv_w = 1.0 / hom[0, i, dim]
        for k in range(order + 1):
            for m in range(dim):
                v = hom[k, i, m]
                binom = 1.0
                for j in range(1, k + 1):
                    binom = binom * (k - j + 1) / j  # C(k, j)
                    v -= binom * hom[j, i, dim] * out[k - j, i, m]
                out[k, i, m] = v * inv_w
    return out


def bspline_derivatives(knots: Array, coef: Array, degree: int, x: Array, order: int) -> Array:
    """Value and derivatives of a B-spline ``sum_i coef_i N_{i,degree}(x)``.

    Parameters
    ----------
    knots : (n + degree + 1,) nondecreasing knot vector.
    coef : (n, dim) coefficients (any units).
    degree : polynomial degree p >= 0.
    x : (N,) parameters (knot units).
    order : highest derivative order k >= 0.

    Returns
    -------
    (k + 1, N, dim) array: ``d^j/dx^j`` for j = 0..k (coefficient units per x^j).
    """
    return _evaluate(np.ascontiguousarray(knots, dtype=float),
                     np.ascontiguousarray(coef, dtype=float), int(degree),
                     np.ascontiguousarray(x, dtype=float), int(order))


@njit(cache=True)
def nurbs_eval(knots: Array, hom: Array, degree: int, x: Array, order: int,
               rational: bool) -> Array:
    """:func:`nurbs_derivatives` for contiguous float arrays, callable from other compiled
    kernels (which then evaluate a curve without a trip through the interpreter)."""
    d = _evaluate(knots, hom, degree, x, order)
    if rational:
        return _rational(d)
    return d


def nurbs_derivatives(knots: Array, hom: Array, degree: int, x: Array, order: int,
                      rational: bool) -> Array:
    """Point and derivatives of a NURBS curve from its homogeneous coefficients.

    ``hom`` is (n, dim + 1) with rows (w_i P_i, w_i) if ``rational``, else (n, dim) with the
    control points P_i. Returns (order + 1, N, dim): ``p^(j)`` for j = 0..order.
    """
    return nurbs_eval(np.ascontiguousarray(knots, dtype=float),
                      np.ascontiguousarray(hom, dtype=float), int(degree),
                      np.ascontiguousarray(x, dtype=float), int(order), bool(rational))
