"""NURBS curves of any degree with exact derivatives, moving frames and arc length.

A NURBS curve of degree ``p`` with control points ``P_i`` (length units, e.g. m), positive
weights ``w_i`` and a clamped knot vector on ``[0, 1]`` is

.. math::

    \\mathbf p(\\eta) = \\frac{\\sum_i N_{i,p}(\\eta)\\, w_i \\mathbf P_i}
                           {\\sum_i N_{i,p}(\\eta)\\, w_i}
                     = \\frac{\\mathbf A(\\eta)}{w(\\eta)},

with the B-spline basis functions ``N_{i,p}``.  The numerator ``A`` and the denominator ``w`` are
ordinary (polynomial) B-splines: they are evaluated together, by one compiled kernel
(:mod:`solver.bsplines`: the basis functions on the knot span, Piegl & Tiller A2.2, with the
derivatives as splines of the coefficients' differences, eq. 3.4), from the homogeneous
control points ``(w_i P_i, w_i)``, and the
derivatives of the rational curve follow from differentiating ``A = w p`` with Leibniz's rule
(Piegl & Tiller, *The NURBS Book*, eq. 4.8)::

    p^(k) = ( A^(k) - sum_{i=1..k} C(k, i) w^(i) p^(k-i) ) / w .

Non-rational curves (all weights equal) skip the division.

Units and parameter
-------------------
The parameter ``eta`` is dimensionless and runs over ``[0, 1]`` (any knot range given to the
constructor is rescaled).  Points are in the length unit of the control points, ``p^(k)`` in
length units per unit ``eta^k``, curvature and torsion in 1/length, arc length in length units.
Every evaluation method clips ``eta`` to ``[0, 1]`` silently: a trial point of a Newton iteration
may overshoot the ends slightly, and it then sees the curve (and its derivatives) at the end
point.  The curve is never extrapolated.

Frame conventions
-----------------
``frame(eta)`` returns ``R`` whose COLUMNS are the unit vectors ``t, n, b`` (a proper rotation,
``b = t x n``) and its exact derivative ``dR/deta``, computed from ``p', p'', p'''``.

*Planar curves* (``plane_normal`` set): ``t = p'/|p'|``, ``b = plane_normal``, ``n = b x t``, the
LEFT normal.  This never produces NaN on straight stretches.  It coincides with the Frenet triad
where the curve turns left (counter-clockwise about ``plane_normal``); where the curve turns right
``n`` points away from the centre of curvature.  Derivatives::

    t' = (p'' - t (t . p'')) / |p'| ,   n' = b x t' ,   b' = 0 .

The curvature of a planar curve is SIGNED, ``kappa = ((p' x p'') . b) / |p'|^3`` (positive for
a left turn), so that ``t' = |p'| kappa n`` and ``n' = -|p'| kappa t`` hold everywhere; the
torsion is 0.

*Space curves* (``plane_normal`` is None): the Frenet triad ``t = p'/|p'|``,
``b = (p' x p'') / |p' x p''|``, ``n = b x t``, with ``kappa = |p' x p''| / |p'|^3 >= 0`` and
``tau = ((p' x p'') . p''') / |p' x p''|^2``, and the Frenet-Serret formulas times ``|p'|``::

    t' = |p'| kappa n ,   n' = |p'| (-kappa t + tau b) ,   b' = -|p'| tau n .

On a straight stretch the Frenet normal is undefined.  The stretch is detected by the
dimensionless test ``|p' x p''| <= 1e-12 |p'| max(|p'|, |p''|)``, i.e. the turning rate
``kappa |p'|`` (rad per unit ``eta``) is below ``1e-12 max(1, |p''|/|p'|)``.  (A bare
``|p' x p''| <= 1e-12 |p'|^3`` would compare a curvature with a number and so depend on the
length unit; the roundoff of ``p' x p''`` itself is of order ``eps |p'| |p''|``, which the test
above always classifies as straight.)  There the frame is instead: ``n`` = the unit component,
orthogonal to ``t``, of the global axis least aligned with ``t``; ``b = t x n``; torsion 0; and
``dR/deta`` is the exact derivative of that construction driven by
``t' = (p'' - t (t . p'')) / |p'|`` only (``m = e - t (t.e)``, ``n = m/|m|``,
``n' = (m' - n (n.m'))/|m|`` with ``m' = -t' (t.e) - t (t'.e)``, ``b' = t' x n + t x n'``).
This frame is not continuous with the Frenet frame where a space curve passes from curved to
straight; a planar curve should be given a ``plane_normal`` instead.

Where the parametric speed is below ``1e-10`` times the size of the control polygon (a cusp of
the parametrization, e.g. the ends of :func:`cycloid`), ``t`` is taken along the first
nonvanishing higher derivative, with the sign of its one-sided limit (from the right, from the
left at ``eta = 1``); ``dR/deta`` is not meaningful there.  Nothing here returns NaN for a
finite ``eta``.

Arc length
----------
``s(eta) = int_0^eta |p'(u)| du`` is integrated by 16-point Gauss-Legendre quadrature on a table
of sub-intervals built at construction: the knot spans, split evenly into at least 64 pieces in
all, then halved adaptively until halving changes a piece's integral by less than ``1e-14``
relative (``1e-16`` of the total length absolute).  The cumulative lengths are cached, so
``arc_length`` costs one vectorized 16-point rule per query point.  ``eta_at`` starts from a
cubic Hermite interpolation of the inverse ``eta(s)`` in the bracketing sub-interval and
refines by Newton's method (``ds/deta = |p'|``) safeguarded by bisection: 1-2 iterations.

Performance
-----------
A point with its derivatives costs one compiled call (~5 us for a few parameters, against
~60 us for scipy ``BSpline`` calls per derivative order and the quotient rule in NumPy); a
frame adds a few tens of small NumPy operations.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import make_interp_spline

from solver.bsplines import nurbs_derivatives

__all__ = [
    "NurbsCurve",
    "circle",
    "circle_arc",
    "cycloid",
    "epicycloid",
    "from_function",
    "helix",
    "interpolate",
    "line",
]

FloatArray = NDArray[np.float64]

# Gauss-Legendre rule used for the arc length (nodes on [-1, 1]).
_GL_ORDER = 16
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(_GL_ORDER)
_GL_U = 0.5 * (_GL_NODES + 1.0)  # nodes mapped to [0, 1]
_GL_W = 0.5 * _GL_WEIGHTS  # weights for [0, 1]
# Arc-length table: at least this many sub-intervals in all (knot spans split evenly) ...
_GL_MIN_INTERVALS = 64
# ... then halved adaptively until the halves change the integral by < rel * I + abs * length.
_GL_REL_TOL = 1e-14
_GL_ABS_TOL = 1e-16
_GL_MAX_LEVELS = 30

# Dimensionless threshold of the straight-stretch test of space curves.
_STRAIGHT_TOL = 1e-12
# Relative (to the curve's size) planarity tolerance of control points and interpolated points.
_PLANAR_TOL = 1e-9
# Parametric speed below this fraction of the curve's size counts as zero (cusp).
_ZERO_SPEED = 1e-10
_EPS = float(np.finfo(float).eps)

_Z_AXIS = np.array([0.0, 0.0, 1.0])
_Z_AXIS.setflags(write=False)
_EYE = np.eye(3)
_ROLL = np.array([1, 2, 0])


# --------------------------------------------------------------------------------------------
# small helpers (written for low per-call overhead on tiny arrays)
# --------------------------------------------------------------------------------------------
def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross product along the last axis (several times cheaper than ``np.cross`` here).

    With the cyclic shift ``S(v) = (v_y, v_z, v_x)``: ``a * S(b) - S(a) * b`` is
    ``(c_z, c_x, c_y)`` for ``c = a x b``, and one more shift puts it in order.
    """
    return (a * b.take(_ROLL, axis=-1) - a.take(_ROLL, axis=-1) * b).take(_ROLL, axis=-1)


if hasattr(np, "vecdot"):  # NumPy >= 2.0

    def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
        """Dot product along the last axis."""
        return np.vecdot(a, b)

else:  # pragma: no cover - NumPy 1.26

    def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
        """Dot product along the last axis."""
        return np.einsum("...i,...i->...", a, b)


def _norm(a: FloatArray) -> FloatArray:
    return np.sqrt(_dot(a, a))


def _skew(v: FloatArray) -> FloatArray:
    """Matrix ``S`` with ``S @ x = v x x``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _positive(name: str, value: Any) -> float:
    """``value`` as a finite float > 0, else ValueError naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}") from None
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def _finite(name: str, value: Any) -> float:
    """``value`` as a finite float, else ValueError naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return v


def _integer(name: str, value: Any, minimum: int) -> int:
    """``value`` as an int >= ``minimum``, else ValueError naming ``name``."""
    try:
        v = operator.index(value)
    except TypeError:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}") from None
    if v < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {v}")
    return v


def _vector3(name: str, value: Any) -> FloatArray:
    """A 2- or 3-vector as a finite 3-vector (z = 0 for 2-vectors)."""
    v = np.asarray(value, dtype=float)
    if v.shape not in ((2,), (3,)) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be a finite 2- or 3-vector, got {value!r}")
    return np.append(v, 0.0) if v.size == 2 else v.copy()


def _points3(name: str, value: Any) -> tuple[FloatArray, bool]:
    """Points ``(n, 2)`` or ``(n, 3)`` as ``(n, 3)``; also whether they were 2-D."""
    p = np.asarray(value, dtype=float)
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValueError(f"{name} must have shape (n, 2) or (n, 3), got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} must be finite, got non-finite entries")
    if p.shape[1] == 2:
        return np.column_stack((p, np.zeros(len(p)))), True
    return p.copy(), False


def _check_planar(name: str, points: FloatArray, normal: FloatArray) -> None:
    """Raise unless ``points`` lie in one plane orthogonal to the unit vector ``normal``."""
    rel = points - points[0]
    size = float(np.max(_norm(rel)))
    off = float(np.max(np.abs(rel @ normal)))
    if off > _PLANAR_TOL * max(size, np.finfo(float).tiny):
        raise ValueError(
            f"{name} must lie in a plane orthogonal to plane_normal={normal.tolist()}: largest "
            f"out-of-plane distance {off:.3g} exceeds {_PLANAR_TOL:g} x size {size:.3g}"
        )


def _unit_normal(value: Any) -> FloatArray:
    n = np.asarray(value, dtype=float)
    if n.shape != (3,) or not np.all(np.isfinite(n)) or not np.any(n):
        raise ValueError(f"plane_normal must be a finite nonzero 3-vector, got {value!r}")
    return n / np.linalg.norm(n)


# --------------------------------------------------------------------------------------------
# the curve
# --------------------------------------------------------------------------------------------
class NurbsCurve:
    """A NURBS curve of any degree in 3-D space, parametrized by ``eta`` in ``[0, 1]``.

    Parameters
    ----------
    degree
        Polynomial degree ``p >= 1``.
    knots
        Knot vector of length ``n + p + 1``: finite, nondecreasing, clamped (the first ``p + 1``
        and the last ``p + 1`` knots equal), interior multiplicities ``<= p``.  Any range is
        rescaled to ``[0, 1]`` (dimensionless).
    control_points
        ``(n, 2)`` or ``(n, 3)`` control points, length units (e.g. m).  2-D points get
        ``z = 0`` and ``plane_normal`` then defaults to ``(0, 0, 1)``.  ``n >= p + 1``.
    weights
        ``(n,)`` weights, all ``> 0`` (default 1: a non-rational B-spline).
    plane_normal
        Normal of the plane of a planar curve (normalized on input).  Setting it selects the
        planar frame convention (see the module docstring).  The control points must lie
        within ``1e-9 x size`` of a plane orthogonal to it and are projected onto that plane
        (through the first control point).  ``None`` for 3-D control points: a space curve
        with the Frenet frame (even if the points happen to be coplanar).

    Attributes
    ----------
    degree : int
    knots : ndarray, shape (n + degree + 1,)
        Rescaled to ``[0, 1]``.  Read-only.
    control_points : ndarray, shape (n, 3)
        Length units.  Read-only.
    weights : ndarray, shape (n,)
        Read-only.
    plane_normal : ndarray, shape (3,), or None
        Unit normal for planar curves.  Read-only.

    Raises
    ------
    ValueError
        On any invalid argument, with a one-line message naming it.

    Notes
    -----
    Evaluation costs one compiled call for the point and its derivatives plus some tens of
    small NumPy operations for a frame, for a scalar or an array of any shape alike.
    """

    def __init__(
        self,
        degree: int,
        knots: ArrayLike,
        control_points: ArrayLike,
        weights: ArrayLike | None = None,
        plane_normal: ArrayLike | None = None,
    ) -> None:
        p = _integer("degree", degree, 1)
        pts, was_2d = _points3("control_points", control_points)
        n = len(pts)
        if n < p + 1:
            raise ValueError(
                f"control_points: need at least degree+1 = {p + 1} control points, got {n}"
            )
        if weights is None:
            w = np.ones(n)
        else:
            w = np.asarray(weights, dtype=float).copy()
            if w.shape != (n,):
                raise ValueError(f"weights must have shape ({n},), got shape {w.shape}")
            if not np.all(np.isfinite(w)) or not np.all(w > 0.0):
                raise ValueError(f"weights must be finite and > 0, got min {np.min(w)!r}")
        k = np.asarray(knots, dtype=float).copy()
        if k.ndim != 1 or len(k) != n + p + 1:
            raise ValueError(f"knot vector length must be n+degree+1 = {n + p + 1}, got {k.size}")
        if not np.all(np.isfinite(k)):
            raise ValueError("knots must be finite, got non-finite entries")
        if np.any(np.diff(k) < 0.0):
            raise ValueError(f"knots must be nondecreasing, got {k.tolist()}")
        if not k[-1] > k[0]:
            raise ValueError(f"knots must span a nonzero range, got [{k[0]:g}, {k[-1]:g}]")
        if np.any(k[: p + 1] != k[0]) or np.any(k[-p - 1 :] != k[-1]):
            raise ValueError(
                f"knots must be clamped (first and last degree+1 = {p + 1} knots equal), "
                f"got {k.tolist()}"
            )
        interior = k[p + 1 : -p - 1]
        if interior.size:
            _, counts = np.unique(interior, return_counts=True)
            if counts.max() > p:
                raise ValueError(
                    f"knots: interior knot multiplicity must be <= degree = {p}, "
                    f"got {int(counts.max())}"
                )
        k = (k - k[0]) / (k[-1] - k[0])
        k[: p + 1] = 0.0
        k[-p - 1 :] = 1.0

        size = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
        if size == 0.0:
            raise ValueError("control_points must not all coincide (degenerate curve)")

        normal: FloatArray | None
        if plane_normal is not None:
            normal = _unit_normal(plane_normal)
            _check_planar("control_points", pts, normal)
            # Remove the (tolerated) out-of-plane part so that t, n, b are exactly orthogonal.
            pts -= np.outer((pts - pts[0]) @ normal, normal)
        elif was_2d:
            normal = _Z_AXIS.copy()
        else:
            normal = None

        for arr in (k, pts, w):
            arr.setflags(write=False)
        if normal is not None:
            normal.setflags(write=False)
        self.degree: int = p
        self.knots: FloatArray = k
        self.control_points: FloatArray = pts
        self.weights: FloatArray = w
        self.plane_normal: FloatArray | None = normal
        self._scale = size
        self._zero_speed = _ZERO_SPEED * size
        # n = b x t = t @ _bskew_t for planar curves.
        self._bskew_t = None if normal is None else _skew(normal).T

        # Homogeneous B-spline: coefficients (w P, w).  If all weights are equal the weights
        # cancel and the curve is the polynomial B-spline with coefficients P.
        self._rational = bool(np.any(w != w[0]))
        coef = np.column_stack((pts * w[:, None], w)) if self._rational else pts
        self._hom: FloatArray = np.ascontiguousarray(coef, dtype=float)

        self._build_arc_length_table()
        self._grid: FloatArray | None = None
        self._grid_points: FloatArray | None = None

    # ---------------------------------------------------------------------------------------
    def __repr__(self) -> str:
        kind = "planar" if self.plane_normal is not None else "space"
        rat = "rational" if self._rational else "non-rational"
        return (
            f"NurbsCurve(degree={self.degree}, n={len(self.control_points)}, {rat}, {kind}, "
            f"length={self.length:.6g})"
        )

    @property
    def is_planar(self) -> bool:
        """True if the curve has a ``plane_normal`` (planar frame convention)."""
        return self.plane_normal is not None

    @property
    def length(self) -> float:
        """Total arc length, length units."""
        return float(self._cum[-1])

    @property
    def spline(self) -> tuple[FloatArray, FloatArray, int, bool]:
        """``(knots, coefficients, degree, rational)``: the homogeneous B-spline that
        :func:`solver.bsplines.nurbs_eval` evaluates, for compiled kernels that evaluate the
        curve themselves (at parameters clipped to [0, 1], as :meth:`derivatives` does)."""
        return self.knots, self._hom, self.degree, self._rational

    # ---------------------------------------------------------------------------------------
    # evaluation
    # ---------------------------------------------------------------------------------------
    @staticmethod
    def _flat(eta: ArrayLike) -> tuple[FloatArray, tuple[int, ...]]:
        """``eta`` flattened and clipped to [0, 1], and its original shape."""
        x = np.asarray(eta, dtype=float)
        return np.minimum(np.maximum(x.ravel(), 0.0), 1.0), x.shape

    def _derivs(self, x: FloatArray, order: int, first: int = 0) -> list[FloatArray]:
        """Derivatives ``[p^(first), ..., p^(order)]`` at the flat parameters ``x``, each (N, 3)
        (one compiled call: :func:`solver.bsplines.nurbs_derivatives`)."""
        d = nurbs_derivatives(self.knots, self._hom, self.degree, x, order, self._rational)
        return list(d[first:])

    def derivatives(self, eta: ArrayLike, order: int = 3) -> FloatArray:
        """Point and derivatives with respect to ``eta``.

        Parameters
        ----------
        eta
            Parameter(s), dimensionless, any shape; clipped to [0, 1].
        order
            Highest derivative order (>= 0).

        Returns
        -------
        ndarray, shape (order + 1, *np.shape(eta), 3)
            ``[p, p', p'', ...]``; ``p^(k)`` in length units per unit ``eta^k``.  Exact up to
            roundoff.  Across a knot where a derivative jumps, the value from the right is
            returned (from the left at ``eta = 1``).
        """
        order = _integer("order", order, 0)
        x, shape = self._flat(eta)
        return np.stack(self._derivs(x, order)).reshape(order + 1, *shape, 3)

    def point(self, eta: ArrayLike) -> FloatArray:
        """Point(s) ``p(eta)``, shape ``(*np.shape(eta), 3)``, length units."""
        x, shape = self._flat(eta)
        return self._derivs(x, 0)[0].reshape(*shape, 3)

    def speed(self, eta: ArrayLike) -> FloatArray:
        """Parametric speed ``|p'(eta)| = ds/deta``, shape ``np.shape(eta)``, length units."""
        x, shape = self._flat(eta)
        return _norm(self._derivs(x, 1, 1)[0]).reshape(shape)

    def _tangent(
        self, x: FloatArray, d: list[FloatArray]
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Unit tangent, speed (floored) and 1/speed from ``d = [p', p'', ...]``.

        Where the speed vanishes (a cusp of the parametrization) the direction of the first
        nonvanishing higher derivative ``p^(j)`` is used: its one-sided limit, from the right,
        i.e. ``+p^(j)``, except at ``eta = 1`` (from the left, ``(-1)^(j-1) p^(j)``).
        """
        sp = _norm(d[0])
        if (sp > self._zero_speed).all():
            inv = 1.0 / sp
            return d[0] * inv[:, None], sp, inv
        vec = d[0].copy()
        zero = sp <= self._zero_speed
        sign = np.where(x >= 1.0, -1.0, 1.0)[:, None]
        for j in range(1, len(d)):
            vec[zero] = (sign**j * d[j])[zero]
            zero &= _norm(vec) <= self._zero_speed
        vec[zero] = _EYE[0]
        sp = np.maximum(sp, self._zero_speed)
        return vec / _norm(vec)[:, None], sp, 1.0 / sp

    def _planar(self, x: FloatArray) -> tuple[FloatArray, ...]:
        """Planar geometry at flat ``x``: t, n, t', n', signed curvature."""
        d = self._derivs(x, 2, 1)
        t, _, inv = self._tangent(x, d)
        d2 = d[1]
        n = t @ self._bskew_t  # n = b x t
        # t' = (p'' - t (t.p'')) / |p'|  (derivative of p'/|p'|), n' = b x t'.
        tp = (d2 - t * _dot(t, d2)[:, None]) * inv[:, None]
        npr = tp @ self._bskew_t
        kappa = _dot(tp, n) * inv  # signed: t' = |p'| kappa n
        return t, n, tp, npr, kappa

    def _space(self, x: FloatArray) -> tuple[FloatArray, ...]:
        """Space-curve geometry at flat ``x``: t, n, b, t', n', b', curvature, torsion."""
        d = self._derivs(x, 3, 1)
        d1, d2, d3 = d
        t, sp, inv = self._tangent(x, d)
        c = _cross(d1, d2)
        cn = _norm(c)
        kappa = cn * inv**3
        straight = cn <= _STRAIGHT_TOL * sp * np.maximum(sp, _norm(d2))
        any_straight = straight.any()
        cn_safe = np.where(straight, 1.0, cn) if any_straight else cn
        inv_c = 1.0 / cn_safe
        tau = _dot(c, d3) * inv_c**2
        if any_straight:
            tau[straight] = 0.0

        # Frenet triad and Frenet-Serret derivatives (times ds/deta = |p'|).
        b = c * inv_c[:, None]
        n = _cross(b, t)
        spk = (sp * kappa)[:, None]
        spt = (sp * tau)[:, None]
        tp = spk * n
        npr = spt * b - spk * t
        bp = -spt * n

        if any_straight:
            s = straight
            ts = t[s]
            # t' = (p'' - t (t.p'')) / |p'| drives the straight-stretch frame.
            tps = (d2[s] - ts * _dot(ts, d2[s])[:, None]) * inv[s][:, None]
            # n = unit part of e orthogonal to t, e = global axis least aligned with t.
            e = _EYE[np.argmin(np.abs(ts), axis=1)]
            te = _dot(ts, e)[:, None]
            m = e - ts * te
            mn = _norm(m)[:, None]
            ns = m / mn
            # m' = -t' (t.e) - t (t'.e);  n' = (m' - n (n.m')) / |m|;  b' = t' x n + t x n'.
            mp = -tps * te - ts * _dot(tps, e)[:, None]
            nps = (mp - ns * _dot(ns, mp)[:, None]) / mn
            n[s] = ns
            b[s] = _cross(ts, ns)
            tp[s] = tps
            npr[s] = nps
            bp[s] = _cross(tps, ns) + _cross(ts, nps)
        return t, n, b, tp, npr, bp, kappa, tau

    def frame(self, eta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Moving frame and its exact derivative (conventions in the module docstring).

        Parameters
        ----------
        eta
            Parameter(s), dimensionless, any shape; clipped to [0, 1].

        Returns
        -------
        R : ndarray, shape (*np.shape(eta), 3, 3)
            Rotation whose columns are ``t, n, b`` (dimensionless).
        dR : ndarray, shape (*np.shape(eta), 3, 3)
            ``dR/deta`` (per unit ``eta``); ``dR/ds = dR/deta / speed``.
        """
        x, shape = self._flat(eta)
        r = np.empty((len(x), 3, 3))
        dr = np.empty((len(x), 3, 3))
        if self.plane_normal is not None:
            t, n, tp, npr, _ = self._planar(x)
            r[:, :, 2] = self.plane_normal
            dr[:, :, 2] = 0.0
        else:
            t, n, b, tp, npr, bp, _, _ = self._space(x)
            r[:, :, 2] = b
            dr[:, :, 2] = bp
        r[:, :, 0] = t
        r[:, :, 1] = n
        dr[:, :, 0] = tp
        dr[:, :, 1] = npr
        return r.reshape(*shape, 3, 3), dr.reshape(*shape, 3, 3)

    def curvature(self, eta: ArrayLike) -> FloatArray:
        """Curvature, 1/length, shape ``np.shape(eta)``.

        Signed for planar curves (positive where the curve turns left about ``plane_normal``),
        ``>= 0`` for space curves.
        """
        x, shape = self._flat(eta)
        if self.plane_normal is not None:
            return self._planar(x)[4].reshape(shape)
        return self._space(x)[6].reshape(shape)

    def torsion(self, eta: ArrayLike) -> FloatArray:
        """Torsion, 1/length, shape ``np.shape(eta)``; 0 for planar curves and straight parts."""
        x, shape = self._flat(eta)
        if self.plane_normal is not None:
            return np.zeros(shape)
        return self._space(x)[7].reshape(shape)

    # ---------------------------------------------------------------------------------------
    # arc length
    # ---------------------------------------------------------------------------------------
    def _gl(self, lo: FloatArray, hi: FloatArray) -> FloatArray:
        """16-point Gauss-Legendre integral of the speed over each [lo, hi] (vectorized)."""
        h = hi - lo
        u = lo[:, None] + h[:, None] * _GL_U
        d1 = self._derivs(u.ravel(), 1, 1)[0]
        return h * (_norm(d1).reshape(u.shape) @ _GL_W)

    def _build_arc_length_table(self) -> None:
        """Cumulative arc length on an adaptive subdivision of the knot spans.

        Sets the sub-interval ends ``_s_lo``, ``_s_hi``, their lengths ``_s_val``, the cumulative
        lengths ``_cum`` (at the ``_s_lo`` and at 1) and the speeds ``_v_lo``, ``_v_hi`` at the
        ends (for the Hermite initial guess of :meth:`eta_at`).
        """
        br = np.unique(self.knots)
        per = max(1, math.ceil(_GL_MIN_INTERVALS / (len(br) - 1)))
        frac = np.arange(per) / per
        lo = (br[:-1, None] + np.diff(br)[:, None] * frac).ravel()
        hi = np.append(lo[1:], 1.0)
        whole = self._gl(lo, hi)
        total = float(whole.sum())
        acc_lo, acc_hi, acc_val = [], [], []
        for level in range(_GL_MAX_LEVELS + 1):
            mid = 0.5 * (lo + hi)
            left, right = self._gl(lo, mid), self._gl(mid, hi)
            err = np.abs(left + right - whole)
            ok = err <= _GL_REL_TOL * np.abs(whole) + _GL_ABS_TOL * total
            if level == _GL_MAX_LEVELS:
                ok[:] = True
            # Accepted intervals keep the (more accurate) two-half value.
            acc_lo.append(lo[ok])
            acc_hi.append(hi[ok])
            acc_val.append((left + right)[ok])
            bad = ~ok
            if not bad.any():
                break
            lo = np.concatenate((lo[bad], mid[bad]))
            hi = np.concatenate((mid[bad], hi[bad]))
            whole = np.concatenate((left[bad], right[bad]))
        s_lo = np.concatenate(acc_lo)
        order = np.argsort(s_lo)
        self._s_lo = s_lo[order]
        self._s_hi = np.concatenate(acc_hi)[order]
        self._s_val = np.concatenate(acc_val)[order]
        self._cum = np.concatenate(([0.0], np.cumsum(self._s_val)))
        self._v_lo = _norm(self._derivs(self._s_lo, 1, 1)[0])
        # Left-hand speed at the right ends (a knot may carry a jump of p').
        self._v_hi = _norm(self._derivs(self._s_hi * (1.0 - _EPS), 1, 1)[0])

    def _arc_flat(self, x: FloatArray) -> FloatArray:
        j = np.searchsorted(self._s_lo, x, side="right") - 1
        j = np.minimum(np.maximum(j, 0), len(self._s_lo) - 1)
        lo = self._s_lo[j]
        return self._cum[j] + self._gl(lo, x)

    def arc_length(self, eta: ArrayLike) -> FloatArray:
        """Arc length ``s(eta)`` from ``eta = 0``, length units, shape ``np.shape(eta)``.

        Gauss-Legendre quadrature on the cached adaptive subdivision of the knot spans;
        relative accuracy ~1e-14.
        """
        x, shape = self._flat(eta)
        return self._arc_flat(x).reshape(shape)

    def eta_at(self, s: ArrayLike) -> FloatArray:
        """Parameter at arc length ``s`` (inverse of :meth:`arc_length`).

        Parameters
        ----------
        s
            Arc length(s) from ``eta = 0``, length units, any shape; clipped to
            ``[0, length]`` silently (like ``eta`` elsewhere).

        Returns
        -------
        ndarray, shape ``np.shape(s)``
            Dimensionless ``eta``.  Initial guess: cubic Hermite interpolation of the inverse
            function ``eta(s)`` (slopes ``1/|p'|``) in the sub-interval of the arc-length table
            that brackets ``s``; then Newton's method on ``s(eta) - s`` with
            ``ds/deta = |p'|``, safeguarded by bisection inside that sub-interval, until
            ``|s(eta) - s| <= 4 eps length`` or the step is below ``4 eps``.
        """
        sa = np.asarray(s, dtype=float)
        shape = sa.shape
        target = np.minimum(np.maximum(sa.ravel(), 0.0), self.length)
        nint = len(self._s_lo)
        j = np.searchsorted(self._cum, target, side="right") - 1
        j = np.minimum(np.maximum(j, 0), nint - 1)
        lo = self._s_lo[j]
        hi = self._s_hi[j]
        base = self._cum[j]
        width = hi - lo
        # Hermite guess of eta(s) on [lo, hi]: theta in [0, 1], slopes h / v (in theta units).
        h_s = self._s_val[j]
        theta = np.clip((target - base) / np.where(h_s > 0.0, h_s, 1.0), 0.0, 1.0)
        v0, v1 = self._v_lo[j], self._v_hi[j]
        good = (v0 > 0.0) & (v1 > 0.0)
        m0 = np.where(good, h_s / np.where(good, v0, 1.0), width)
        m1 = np.where(good, h_s / np.where(good, v1, 1.0), width)
        th2, th3 = theta * theta, theta * theta * theta
        eta = (
            lo + (3.0 * th2 - 2.0 * th3) * width + (th3 - 2.0 * th2 + theta) * m0 + (th3 - th2) * m1
        )
        eta = np.minimum(np.maximum(eta, lo), hi)
        tol_s = 4.0 * _EPS * max(self.length, np.finfo(float).tiny)
        idx = np.arange(len(eta))
        lo = lo.copy()
        hi = hi.copy()
        for _ in range(100):
            e = eta[idx]
            a = self._s_lo[j[idx]]
            f = self._cum[j[idx]] + self._gl(a, e) - target[idx]
            sp = _norm(self._derivs(e, 1, 1)[0])
            conv = np.abs(f) <= tol_s
            lo[idx] = np.where(f < 0.0, e, lo[idx])
            hi[idx] = np.where(f > 0.0, e, hi[idx])
            new = e - f / np.where(sp > 0.0, sp, np.inf)
            out = ~((new > lo[idx]) & (new < hi[idx]))
            new = np.where(out, 0.5 * (lo[idx] + hi[idx]), new)
            tiny_step = np.abs(new - e) <= 4.0 * _EPS
            eta[idx] = np.where(conv, e, new)
            idx = idx[~(conv | tiny_step)]
            if idx.size == 0:
                break
        return eta.reshape(shape)

    # ---------------------------------------------------------------------------------------
    # projection
    # ---------------------------------------------------------------------------------------
    def closest_eta(self, point: ArrayLike) -> float:
        """Parameter of the curve point nearest to ``point``.

        Parameters
        ----------
        point
            2- or 3-vector, length units (a 2-vector gets z = 0).

        Returns
        -------
        float
            ``eta`` in [0, 1].  Global search on a cached sample grid (8 points per arc-length
            sub-interval, at least 513), then safeguarded Newton on ``g = p'.(p - q) = 0``
            around the 4 best sampled local minima of the distance; ties go to the smaller
            ``eta``.
        """
        q = _vector3("point", point)
        if self._grid is None or self._grid_points is None:
            sub = np.arange(8) / 8.0
            g = (self._s_lo[:, None] + (self._s_hi - self._s_lo)[:, None] * sub).ravel()
            g = np.union1d(np.append(g, 1.0), np.linspace(0.0, 1.0, 513))
            self._grid = g
            self._grid_points = self._derivs(g, 0)[0]
        grid = self._grid
        dist2 = np.sum((self._grid_points - q) ** 2, axis=-1)
        m = len(grid)
        padded = np.concatenate(([np.inf], dist2, [np.inf]))
        is_min = (dist2 <= padded[:-2]) & (dist2 <= padded[2:])
        cand = np.flatnonzero(is_min)
        cand = cand[np.argsort(dist2[cand], kind="stable")[:4]]
        best_eta, best_d = 0.0, np.inf
        for i in cand:
            e = self._refine_closest(q, grid[max(i - 1, 0)], grid[min(i + 1, m - 1)], grid[i])
            d = float(np.sum((self._derivs(np.array([e]), 0)[0][0] - q) ** 2))
            if d < best_d or (d == best_d and e < best_eta):
                best_eta, best_d = e, d
        return float(best_eta)

    def _refine_closest(self, q: FloatArray, lo: float, hi: float, eta: float) -> float:
        """Safeguarded Newton for g(eta) = p'.(p - q) = 0 in [lo, hi]."""

        def g_and_dg(e: float) -> tuple[float, float]:
            p0, p1, p2 = (v[0] for v in self._derivs(np.array([e]), 2))
            r = p0 - q
            return float(p1 @ r), float(p2 @ r + p1 @ p1)

        g_lo, _ = g_and_dg(lo)
        g_hi, _ = g_and_dg(hi)
        if g_lo >= 0.0:  # distance nondecreasing from lo: the bracket's minimum is at lo
            return lo
        if g_hi <= 0.0:  # distance nonincreasing up to hi
            return hi
        for _ in range(100):
            g, dg = g_and_dg(eta)
            if g == 0.0:
                return eta
            if g < 0.0:
                lo = eta
            else:
                hi = eta
            new = eta - g / dg if dg > 0.0 else 0.5 * (lo + hi)
            if not lo < new < hi:
                new = 0.5 * (lo + hi)
            if abs(new - eta) <= 2.0 * _EPS:
                return new
            eta = new
        return eta


# constructors
# --------------------------------------------------------------------------------------------
def circle(
    radius: float, center: ArrayLike = (0.0, 0.0, 0.0), start_angle: float = 0.0
) -> NurbsCurve:
    """Full circle, exact rational quadratic NURBS.

    Nine control points (four 90-degree arcs; weights 1 at the on-circle points and
    ``sqrt(2)/2`` at the corner points at distance ``sqrt(2) radius``), knots
    ``[0, 0, 0, 1/4, 1/4, 1/2, 1/2, 3/4, 3/4, 1, 1, 1]``.

    Parameters
    ----------
    radius
        Radius > 0, length units.
    center
        Centre (2- or 3-vector), length units.
    start_angle
        Angle of ``p(0)`` from the +x axis, rad.  The circle runs counter-clockwise about +z
        (``plane_normal = (0, 0, 1)``, so ``n`` points to the centre and the curvature is
        ``+1/radius``).
    """
    r = _positive("radius", radius)
    c = _vector3("center", center)
    a0 = _finite("start_angle", start_angle)
    ang = a0 + 0.25 * np.pi * np.arange(9)
    dist = np.where(np.arange(9) % 2 == 1, r * math.sqrt(2.0), r)
    pts = c + np.column_stack((dist * np.cos(ang), dist * np.sin(ang), np.zeros(9)))
    pts[8] = pts[0]  # closed exactly
    w = np.where(np.arange(9) % 2 == 1, math.sqrt(2.0) / 2.0, 1.0)
    knots = [0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0]
    return NurbsCurve(2, knots, pts, w, plane_normal=_Z_AXIS)


def circle_arc(
    radius: float,
    angle_start: float,
    angle_end: float,
    center: ArrayLike = (0.0, 0.0, 0.0),
) -> NurbsCurve:
    """Circular arc, exact rational quadratic NURBS, counter-clockwise about +z.

    The arc is split into ``ceil(span / 90 deg)`` equal pieces; a piece of opening ``theta``
    has its middle control point at distance ``radius / cos(theta/2)`` with weight
    ``cos(theta/2)``.

    Parameters
    ----------
    radius
        Radius > 0, length units.
    angle_start, angle_end
        Angles from +x, rad, with ``0 < angle_end - angle_start <= 2 pi``.
    center
        Centre (2- or 3-vector), length units.
    """
    r = _positive("radius", radius)
    a0 = _finite("angle_start", angle_start)
    a1 = _finite("angle_end", angle_end)
    c = _vector3("center", center)
    span = a1 - a0
    if not (0.0 < span <= 2.0 * np.pi * (1.0 + 1e-12)):
        raise ValueError(
            f"angle_end - angle_start must be in (0, 2 pi] rad, got {span!r} "
            f"(angle_start={a0!r}, angle_end={a1!r})"
        )
    nseg = max(1, math.ceil(span / (0.5 * np.pi) - 1e-9))
    theta = span / nseg
    ang = a0 + 0.5 * theta * np.arange(2 * nseg + 1)
    ang[-1] = a1
    odd = np.arange(2 * nseg + 1) % 2 == 1
    half_cos = math.cos(0.5 * theta)
    dist = np.where(odd, r / half_cos, r)
    pts = c + np.column_stack((dist * np.cos(ang), dist * np.sin(ang), np.zeros(len(ang))))
    w = np.where(odd, half_cos, 1.0)
    inner = np.repeat(np.arange(1, nseg) / nseg, 2)
    knots = np.concatenate(([0.0] * 3, inner, [1.0] * 3))
    return NurbsCurve(2, knots, pts, w, plane_normal=_Z_AXIS)


def line(p0: ArrayLike, p1: ArrayLike) -> NurbsCurve:
    """Straight segment from ``p0`` to ``p1`` (degree 1, constant speed ``|p1 - p0|``).

    2-D end points, or 3-D ones with equal z, give a planar curve (normal +z, left normal);
    otherwise a space curve whose frame is the straight-stretch frame of the module docstring.
    """
    a = _vector3("p0", p0)
    b = _vector3("p1", p1)
    if np.array_equal(a, b):
        raise ValueError(f"p0 and p1 must differ, got both {a.tolist()}")
    normal = _Z_AXIS if a[2] == b[2] else None
    return NurbsCurve(1, [0.0, 0.0, 1.0, 1.0], np.vstack((a, b)), plane_normal=normal)


def interpolate(
    points: ArrayLike,
    degree: int = 3,
    plane_normal: ArrayLike | None = None,
    parameters: ArrayLike | None = None,
) -> NurbsCurve:
    """B-spline (weights 1) through ``points`` (:func:`scipy.interpolate.make_interp_spline`).

    Parameters
    ----------
    points
        ``(m, 2)`` or ``(m, 3)`` points, length units, ``m >= degree + 1``.
    degree
        Spline degree >= 1 (odd degrees use not-a-knot end conditions).
    plane_normal
        Makes the curve planar (the points must lie in a plane orthogonal to it).  Without it
        the curve is planar with normal +z if the points are 2-D or all have the same z.
    parameters
        Strictly increasing parameters of the points (any range, rescaled to [0, 1]); default
        chord length (consecutive points must then be distinct).

    Returns
    -------
    NurbsCurve
        Clamped, with ``p(eta_i) = points[i]`` at the (rescaled) parameters.
    """
    p = _integer("degree", degree, 1)
    pts, was_2d = _points3("points", points)
    m = len(pts)
    if m < p + 1:
        raise ValueError(f"points: need at least degree+1 = {p + 1} points, got {m}")
    if parameters is None:
        chord = _norm(np.diff(pts, axis=0))
        if np.any(chord == 0.0):
            i = int(np.flatnonzero(chord == 0.0)[0])
            raise ValueError(
                f"points: consecutive points must be distinct for chord-length parameters "
                f"(points {i} and {i + 1} coincide)"
            )
        u = np.concatenate(([0.0], np.cumsum(chord)))
    else:
        u = np.asarray(parameters, dtype=float).copy()
        if u.shape != (m,):
            raise ValueError(f"parameters must have shape ({m},), got shape {u.shape}")
        if not np.all(np.isfinite(u)) or np.any(np.diff(u) <= 0.0):
            raise ValueError("parameters must be finite and strictly increasing")
    u = (u - u[0]) / (u[-1] - u[0])
    u[-1] = 1.0

    normal: FloatArray | None = None
    if plane_normal is not None:
        normal = _unit_normal(plane_normal)
        _check_planar("points", pts, normal)
    elif was_2d or np.all(pts[:, 2] == pts[0, 2]):
        normal = _Z_AXIS

    spl = make_interp_spline(u, pts, k=p)
    ctrl = np.array(spl.c, dtype=float)
    if normal is not None:
        # Remove the roundoff that the linear solve leaves off the plane of the points.
        ctrl -= np.outer((ctrl - pts[0]) @ normal, normal)
    return NurbsCurve(p, spl.t, ctrl, plane_normal=normal)


def _sample(f: Callable[[FloatArray], ArrayLike], t: FloatArray) -> FloatArray:
    """Call ``f`` on the parameter array and return the points as (len(t), 2|3)."""
    v = np.asarray(f(t), dtype=float)
    m = len(t)
    if v.ndim == 2 and v.shape[0] == m and v.shape[1] in (2, 3):
        pass
    elif v.ndim == 2 and v.shape[1] == m and v.shape[0] in (2, 3):
        v = v.T
    else:
        raise ValueError(
            f"f must return points of shape ({m}, 2|3) or (2|3, {m}) for {m} parameters, "
            f"got shape {v.shape}"
        )
    if not np.all(np.isfinite(v)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(v), axis=1))[0])
        raise ValueError(f"f must return finite points, got {v[bad].tolist()} at t = {t[bad]!r}")
    return v


# Blend between uniform (0) and Chebyshev-Lobatto (1) sampling used by from_function.
_CLUSTER = 0.5


def from_function(
    f: Callable[[FloatArray], ArrayLike],
    t0: float,
    t1: float,
    n_points: int = 400,
    degree: int = 5,
) -> NurbsCurve:
    """Interpolating B-spline of a parametric curve ``t -> f(t)``, ``t`` in ``[t0, t1]``.

    The curve is sampled at ``n_points`` parameters clustered toward the ends (the average of
    uniform and Chebyshev-Lobatto spacing) and interpolated with :func:`interpolate` using the
    samples' parameters, so that ``eta = (t - t0) / (t1 - t0)`` EXACTLY: ``p(eta)`` approximates
    ``f(t0 + eta (t1 - t0))`` and the derivatives scale with powers of ``t1 - t0``.

    Parameters
    ----------
    f
        Vectorized function: called once with a 1-D float array of parameters, returns the
        points as an array of shape ``(len(t), 2|3)`` or ``(2|3, len(t))``, length units.
        2-D points, or 3-D ones with equal z, give a planar curve with normal +z.
    t0, t1
        Parameter range, ``t1 > t0`` (units of ``f``'s argument).
    n_points
        Number of samples, ``>= degree + 1``.
    degree
        Spline degree (default quintic).
    """
    a = _finite("t0", t0)
    b = _finite("t1", t1)
    if not b > a:
        raise ValueError(f"t1 must be > t0, got t0={a!r}, t1={b!r}")
    p = _integer("degree", degree, 1)
    m = _integer("n_points", n_points, p + 1)
    u = np.linspace(0.0, 1.0, m)
    g = (1.0 - _CLUSTER) * u + _CLUSTER * 0.5 * (1.0 - np.cos(np.pi * u))
    g[0], g[-1] = 0.0, 1.0
    pts = _sample(f, a + (b - a) * g)
    return interpolate(pts, degree=p, parameters=g)


def cycloid(a: float, n_points: int = 801) -> NurbsCurve:
    """The hanging cycloid ``p(t) = a (t + sin t) i1 - a (1 + cos t) i2``, ``t`` in [-pi, pi].

    Lowest point ``(0, -2a)`` at ``t = 0`` (``eta = 1/2``), cusps at ``(+-pi a, 0)``; length
    ``8 a``.  ``eta = (t + pi) / (2 pi)``.  The curve runs in +x at the bottom and turns left
    about +z (``plane_normal = (0, 0, 1)``), so ``n`` points up, towards the centre of
    curvature; curvature ``1 / (4 a cos(t/2))`` and tangent angle ``t/2``.

    A cycloid is not a NURBS: this is the quintic interpolant of :func:`from_function`.  Since
    the parametrization in ``t`` is entire (the cusps are geometric only), the interpolant is
    accurate up to the cusps.  Measured with the default 801 samples (200 001 check points,
    a = 1 and a = 0.01): point error 3.5e-15 a everywhere, cusps included (required: 1e-9 a
    for ``|t| < 0.95 pi``); length error 6e-16 relative, ``s(eta)`` error 8e-15 a; for
    ``|t| < 0.95 pi`` tangent angle error 3e-12 rad and curvature relative error 2.5e-9 (the
    curvature needs ``p''``, interpolated to O(h^4)); tangent angle error 3e-8 rad closer to
    the cusps (the speed vanishes there).

    Parameters
    ----------
    a
        Generating-circle radius > 0, length units.
    n_points
        Number of interpolation samples (>= 6).
    """
    aa = _positive("a", a)

    def f(t: FloatArray) -> FloatArray:
        return np.column_stack((aa * (t + np.sin(t)), -aa * (1.0 + np.cos(t))))

    return from_function(f, -np.pi, np.pi, n_points=n_points, degree=5)


def epicycloid(a: float, b: float, phi0: float, phi1: float, n_points: int = 801) -> NurbsCurve:
    """Epicycloid: a point of a circle of radius ``b`` rolling OUTSIDE a fixed circle ``a``.

    ``x = (a+b) cos phi - b cos((a+b) phi / b)``, ``y = (a+b) sin phi - b sin((a+b) phi / b)``
    for ``phi`` in ``[phi0, phi1]`` (``eta = (phi - phi0) / (phi1 - phi0)``); planar, normal +z.
    The arches turn counter-clockwise (left) as ``phi`` increases: the signed curvature is
    positive, ``(a + 2b) / (4 b (a + b) |sin(a phi / (2b))|)``, and ``n`` points to the centre of
    curvature.  Cusps at ``phi = 2 pi k b / a``.  Quintic interpolant of :func:`from_function`
    (an entire function of ``phi``: accurate up to the cusps like :func:`cycloid`).

    Parameters
    ----------
    a, b
        Fixed and rolling radii > 0, length units.
    phi0, phi1
        Angle range of the rolling circle's centre, rad, ``phi1 > phi0``.
    n_points
        Number of interpolation samples (>= 6).
    """
    ra = _positive("a", a)
    rb = _positive("b", b)
    k = (ra + rb) / rb

    def f(phi: FloatArray) -> FloatArray:
        return np.column_stack(
            (
                (ra + rb) * np.cos(phi) - rb * np.cos(k * phi),
                (ra + rb) * np.sin(phi) - rb * np.sin(k * phi),
            )
        )

    return from_function(f, phi0, phi1, n_points=n_points, degree=5)


def helix(
    radius: float, pitch: float, turns: float, n_points: int | None = None, degree: int = 7
) -> NurbsCurve:
    """Circular helix ``(r cos u, r sin u, pitch u / (2 pi))``, ``u`` in ``[0, 2 pi turns]``.

    A space curve, the interpolant of :func:`from_function` (``eta = u / (2 pi turns)``), with
    curvature ``r / (r^2 + c^2)`` and torsion ``c / (r^2 + c^2)``, ``c = pitch / (2 pi)``.
    ``pitch = 0`` gives a planar circle.

    The torsion needs the third derivative, whose roundoff grows like ``eps / h^3`` with the
    sample spacing ``h``: a septic interpolant on ~100 samples per turn is more accurate than
    a denser quintic one.  Measured (r = 1, pitch = 0.5, 0.5 to 10 turns, defaults): point
    error < 1e-14 r, curvature relative error < 1e-9, torsion relative error < 5e-8
    (< 3e-9 away from the first and last 5 %), length relative error < 1e-14.

    Parameters
    ----------
    radius
        Radius > 0, length units.
    pitch
        Rise per turn, length units (negative: left-handed).
    turns
        Number of turns > 0.
    n_points
        Number of samples; default ``max(101, ceil(100 turns) + 1)``.
    degree
        Interpolation degree (default 7).
    """
    r = _positive("radius", radius)
    h = _finite("pitch", pitch)
    nt = _positive("turns", turns)
    if n_points is None:
        n_points = max(101, math.ceil(100.0 * nt) + 1)
    c = h / (2.0 * np.pi)

    def f(u: FloatArray) -> FloatArray:
        return np.column_stack((r * np.cos(u), r * np.sin(u), c * u))

    return from_function(f, 0.0, 2.0 * np.pi * nt, n_points=n_points, degree=degree)
