"""Pseudo-arclength continuation of the solutions of F(x, λ) = 0 in one parameter λ.

A branch of solutions x(λ) is followed as a curve y(s) = (x, λ)(s) parameterized by its
arclength s, so that it goes around turning points (folds) in λ where x(λ) has no
continuation. Each step is Keller's predictor–corrector (Keller 1977; Allgower & Georg,
*Introduction to Numerical Continuation Methods*, 2003, ch. 2–6; Seydel, *Practical
Bifurcation and Stability Analysis*, 2010, §4.4–4.5):

* the tangent t is the null vector of the n × (n + 1) matrix [F_x F_λ] (in scaled
  coordinates, below), found from the bordered system [F_x F_λ; t_prevᵀ] t = (0, 1) and
  normalized; its sign is kept continuous (t · t_prev > 0), so that the branch is traversed
  in one direction through folds, and the first one points towards ``stop``;
* the predictor is y_pred = y + h t;
* the corrector is Newton's method on F(y) = 0, t · (y − y_pred) = 0, whose Jacobian
  [F_x F_λ; tᵀ] stays regular at simple folds (where F_x alone is singular).

The step h adapts: it grows after a corrector that converged in few iterations, shrinks after
one that needed many, and is halved when the corrector fails or the tangent turns by more
than :data:`MAX_TURN` (a sign that the step jumped to another part of the branch). Below
``min_step`` the continuation gives up and returns the points found so far.

A fold (turning point in λ) lies where the λ-component of the tangent changes sign. It is
located between the two points that bracket it by Brent's method on s ↦ t_λ(y(s)), y(s) the
fully corrected point at arclength s along the earlier point's tangent: near a simple fold λ
is quadratic in s, so an error δs in s gives an error of order κ δs² in λ (κ the curvature),
and the fold's λ comes out at roundoff level.

Scaling. λ and x usually have different units, so arclength is measured in the scaled space

    ds² = (span² / n) · |dx / x_scale|² + dλ²,    span = |stop − start|,

in which a change of every state component by its scale counts as much as crossing the whole
requested λ range, and the state's share does not grow with n (the 1/n makes it a mean
square). Steps are then arclengths in λ's units: on a part of the branch where x hardly
changes a step of h advances λ by h, and on a steep part (near a resonance, a fold) by less.
The default ``x_scale`` is the scalar max|x| of the corrected starting point (1 if that is
zero): one scale for all components keeps components that are zero at the start (a phase, an
out-of-plane motion) from getting an arbitrary tiny scale.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
Residual = Callable[[Array, float], Array]
Jacobian = Callable[[Array, float], tuple[Array, Array]]

# Step control. A corrector that converges in at most FAST_ITERATIONS Newton iterations (three
# is what a quadratically convergent Newton needs from a predictor error of 1e-3 to 1e-10)
# lets the step grow by GROW; one that needs SLOW_ITERATIONS or more shrinks it by SHRINK.
FAST_ITERATIONS = 3
SLOW_ITERATIONS = 6
GROW = 1.5
SHRINK = 0.7
# The largest angle between successive tangents accepted (rad): a larger one is a step that
# went around a fold in one go or jumped to another branch.
MAX_TURN = math.radians(30.0)
# A corrector whose update grows after its second iteration is diverging.
DIVERGING_RATE = 1.0
# Finite-difference steps: central differences with h = FD_STEP · max(|xᵢ|, x_scaleᵢ), whose
# truncation (h²) and roundoff (eps/h) errors balance at eps^(1/3) ≈ 6e-6, leaving about
# eps^(2/3) ≈ 4e-11 relative error in the Jacobian.
FD_STEP = np.finfo(float).eps ** (1.0 / 3.0)
# The start's Newton at fixed λ gets at least this many iterations (its guess may be poor).
START_ITERATIONS = 25


@dataclass(frozen=True)
class BranchPoint:
    """A solved point of a branch.

    Attributes
    ----------
    x
        The state (n,).
    parameter
        λ.
    tangent
        Unit tangent (n + 1,) in the scaled (x, λ) space (see the module docstring), oriented
        along the branch's travel; its last component is dλ/ds.
    jacobian
        dF/dx at the solution (n, n), for the caller's stability analysis.
    fold
        True at a located turning point in λ.
    iterations
        Newton iterations of the corrector that found the point.
    """

    x: Array
    parameter: float
    tangent: Array
    jacobian: Array
    fold: bool
    iterations: int


@dataclass(frozen=True)
class Branch:
    """A continued branch: its points in the order of travel, why it ended, and whether it
    reached ``stop``."""

    points: list[BranchPoint]
    reason: str
    complete: bool


def _name(residual: Callable) -> str:
    return getattr(residual, "__qualname__", None) or repr(residual)


def finite_difference_jacobian(residual: Residual, x: Array, lam: float, x_scale: Array,
                               lam_scale: float) -> tuple[Array, Array]:
    """(F_x, F_λ) at (x, λ) by central differences.

    The step of component i is h = eps^(1/3) · max(|xᵢ|, x_scaleᵢ) (and eps^(1/3) ·
    max(|λ|, lam_scale) for λ): 2n + 2 residual evaluations, an error of about eps^(2/3)
    relative to the derivatives' size.
    """
    n = x.size
    jx = np.empty((n, n))
    for i in range(n):
        h = FD_STEP * max(abs(x[i]), x_scale[i])
        xp = x.copy()
        xm = x.copy()
        xp[i] += h
        xm[i] -= h
        jx[:, i] = (np.asarray(residual(xp, lam)) - np.asarray(residual(xm, lam))) / (2.0 * h)
    h = FD_STEP * max(abs(lam), lam_scale)
    jl = (np.asarray(residual(x, lam + h)) - np.asarray(residual(x, lam - h))) / (2.0 * h)
    return jx, jl


class _Problem:
    """F in the scaled coordinates y = (D x, λ), D = span/(√n · x_scale) elementwise."""

    def __init__(self, residual: Residual, jacobian: Jacobian | None, x_scale: Array,
                 span: float, tolerance: float, max_iterations: int) -> None:
        self.residual = residual
        self.jacobian_x = jacobian
        self.x_scale = x_scale
        self.span = span
        self.d = span / (math.sqrt(x_scale.size) * x_scale)
        self.tolerance = tolerance
        self.max_iterations = max_iterations

    def state(self, y: Array) -> tuple[Array, float]:
        return y[:-1] / self.d, float(y[-1])

    def scaled(self, x: Array, lam: float) -> Array:
        return np.append(self.d * x, lam)

    def f(self, y: Array) -> Array:
        x, lam = self.state(y)
        return np.asarray(self.residual(x, lam), dtype=float)

    def jacobians(self, y: Array) -> tuple[Array, Array]:
        """(F_x, [F_x D⁻¹ F_λ]): the unscaled state Jacobian and the scaled n × (n+1) one."""
        x, lam = self.state(y)
        if self.jacobian_x is None:
            jx, jl = finite_difference_jacobian(self.residual, x, lam, self.x_scale, self.span)
        else:
            jx, jl = self.jacobian_x(x, lam)
            jx = np.asarray(jx, dtype=float)
            jl = np.asarray(jl, dtype=float).reshape(-1)
        return jx, np.column_stack([jx / self.d, jl])

    def converged(self, dy: Array) -> bool:
        """The update is below the tolerance: |Δx/x_scale| and |Δλ|/span."""
        dx = dy[:-1] / self.d / self.x_scale
        return (np.max(np.abs(dx), initial=0.0) <= self.tolerance
                and abs(dy[-1]) <= self.tolerance * self.span)

    def tangent(self, jy: Array, previous: Array) -> Array:
        """Unit null vector of jy with t · previous > 0."""
        n = jy.shape[0]
        rhs = np.zeros(n + 1)
        rhs[-1] = 1.0
        try:
            t = np.linalg.solve(np.vstack([jy, previous]), rhs)
        except np.linalg.LinAlgError:
            t = np.full(n + 1, np.nan)
        if not np.all(np.isfinite(t)):
            # previous ⟂ null space (only at a degenerate start): the SVD's null vector
            t = np.linalg.svd(jy)[2][-1]
        t /= np.linalg.norm(t)
        return t if t @ previous >= 0.0 else -t

    def correct(self, y0: Array, row: Array, target: float
                ) -> tuple[Array | None, Array | None, Array | None, int, str]:
        """Newton on F(y) = 0, row · y = target from y0.

        Returns (y, F_x, jy, iterations, message); y is None on failure, and the Jacobians
        are those at the converged y.
        """
        y = y0.copy()
        previous = math.inf
        for it in range(1, self.max_iterations + 1):
            try:
                r = self.f(y)
                jx, jy = self.jacobians(y)
                dy = np.linalg.solve(np.vstack([jy, row]), -np.append(r, row @ y - target))
            except (np.linalg.LinAlgError, ArithmeticError) as exc:
                return None, None, None, it, f"singular or failed corrector ({exc})"
            if not np.all(np.isfinite(dy)):
                return None, None, None, it, "non-finite corrector update"
            y += dy
            size = float(np.linalg.norm(dy))
            if self.converged(dy):
                jx, jy = self.jacobians(y)
                if not (np.all(np.isfinite(jy)) and np.all(np.isfinite(self.f(y)))):
                    return None, None, None, it, "non-finite residual at the corrected point"
                return y, jx, jy, it, ""
            if it > 2 and size > DIVERGING_RATE * previous:
                return None, None, None, it, (
                    f"corrector diverging (|F| = {np.linalg.norm(r):.3e})")
            previous = size
        return None, None, None, self.max_iterations, (
            f"corrector not converged in {self.max_iterations} iterations "
            f"(|F| = {np.linalg.norm(r):.3e})")


def _newton_fixed(problem: _Problem, x0: Array, lam: float, iterations: int
                  ) -> tuple[Array | None, int, str]:
    """Newton on F(x, λ) = 0 at fixed λ (the start's correction)."""
    x = np.array(x0, dtype=float)
    r = np.full(x.size, np.nan)
    for it in range(1, iterations + 1):
        try:
            r = np.asarray(problem.residual(x, lam), dtype=float)
            jx, _ = problem.jacobians(problem.scaled(x, lam))
            dx = np.linalg.solve(jx, -r)
        except (np.linalg.LinAlgError, ArithmeticError) as exc:
            return None, it, f"singular or failed Newton ({exc})"
        if not np.all(np.isfinite(dx)):
            return None, it, f"non-finite Newton update (|F| = {np.linalg.norm(r):.3e})"
        x = x + dx
        if np.max(np.abs(dx / problem.x_scale), initial=0.0) <= problem.tolerance:
            return x, it, ""
    return None, iterations, (f"no convergence in {iterations} iterations "
                              f"(|F| = {np.linalg.norm(r):.3e})")


def _point(problem: _Problem, y: Array, jx: Array, tangent: Array, fold: bool,
           iterations: int) -> BranchPoint:
    x, lam = problem.state(y)
    return BranchPoint(x=x, parameter=lam, tangent=tangent, jacobian=jx, fold=fold,
                       iterations=iterations)


def continue_branch(residual: Residual, x0: ArrayLike, start: float, stop: float, *,
                    jacobian: Jacobian | None = None, step: float, min_step: float,
                    max_step: float, max_points: int = 200, tolerance: float = 1e-10,
                    x_scale: ArrayLike | float | None = None, max_iterations: int = 10,
                    callback: Callable[[BranchPoint], None] | None = None) -> Branch:
    """Follow the solutions of F(x, λ) = 0 from λ = ``start`` to λ = ``stop``.

    Parameters
    ----------
    residual
        F(x, λ) -> (n,).
    x0
        A guess of the solution at λ = ``start``; it is corrected by Newton at fixed λ first.
    start, stop
        The parameter range (``stop`` may be below ``start``; they must differ).
    jacobian
        (x, λ) -> (F_x (n, n), F_λ (n,)); by default central finite differences with step
        eps^(1/3) · max(|xᵢ|, x_scaleᵢ) (2n + 2 residual evaluations per Jacobian, see
        :func:`finite_difference_jacobian`).
    step, min_step, max_step
        First, smallest and largest arclength step, in λ's units (see the module docstring
        for the scaled arclength).
    max_points
        Most points returned (fold points included).
    tolerance
        The corrector has converged when its update is below ``tolerance`` in
        max|Δx/x_scale| and in |Δλ|/|stop − start| (Newton converges quadratically, so the
        error left is far below that).
    x_scale
        Scale of the state, scalar or (n,); default max|x| of the corrected start (1 if 0).
    max_iterations
        Newton iterations per corrector.
    callback
        Called with each accepted point, in order.

    Returns
    -------
    Branch
        ``complete`` if λ = ``stop`` was reached (the last point then lies at exactly
        λ = ``stop``); otherwise ``reason`` tells why not: "max_points", "step below
        min_step: ..." (with the corrector's last failure), or "left the parameter range
        ..." after the branch turned back past ``start`` by more than the span.

    Raises
    ------
    RuntimeError
        If the start cannot be corrected.
    ValueError
        If ``start == stop`` or the steps are inconsistent.
    """
    start, stop = float(start), float(stop)
    span = abs(stop - start)
    if not span > 0.0:
        raise ValueError("continue_branch: start and stop must differ")
    if not 0.0 < min_step <= step <= max_step:
        raise ValueError(f"continue_branch: need 0 < min_step <= step <= max_step, got "
                         f"{min_step}, {step}, {max_step}")
    x0 = np.array(x0, dtype=float).reshape(-1)
    n = x0.size
    direction = math.copysign(1.0, stop - start)
    low, high = min(start, stop) - span, max(start, stop) + span

    def scale_of(x: Array) -> Array:
        if x_scale is not None:
            return np.broadcast_to(np.asarray(x_scale, dtype=float), (n,)).copy()
        m = float(np.max(np.abs(x), initial=0.0))
        return np.full(n, m if m > 0.0 else 1.0)

    # the start, with a provisional scale from the guess, then the final scale from it
    problem = _Problem(residual, jacobian, scale_of(x0), span, tolerance, max_iterations)
    xs, its, msg = _newton_fixed(problem, x0, start, max(max_iterations, START_ITERATIONS))
    if xs is None:
        raise RuntimeError(f"continue_branch: Newton on the residual {_name(residual)} at "
                           f"λ = start = {start:g} failed: {msg}")
    problem = _Problem(residual, jacobian, scale_of(xs), span, tolerance, max_iterations)

    y = problem.scaled(xs, start)
    jx, jy = problem.jacobians(y)
    towards = np.zeros(n + 1)
    towards[-1] = direction
    t = problem.tangent(jy, towards)
    points = [_point(problem, y, jx, t, False, its)]
    if callback is not None:
        callback(points[0])

    def accept(p: BranchPoint) -> None:
        points.append(p)
        if callback is not None:
            callback(p)

    h = step
    failure = ""
    while True:
        if len(points) >= max_points:
            return Branch(points, "max_points", False)
        if h < min_step:
            return Branch(points, f"step below min_step: {failure} at λ = {y[-1]:.10g}",
                          False)
        y_pred = y + h * t
        y_new, jx_new, jy_new, its, failure = problem.correct(y_pred, t, t @ y_pred)
        if y_new is None:
            h *= 0.5
            continue
        t_new = problem.tangent(jy_new, t)
        if t_new @ t < math.cos(MAX_TURN) and h > min_step:
            failure = f"tangent turned by {math.degrees(math.acos(min(1.0, t_new @ t))):.0f}°"
            h = max(0.5 * h, min_step)
            continue

        # the step's pieces in order of travel: y → (fold →) y_new; the branch ends on the
        # first piece that reaches λ = stop (with a fold beyond stop, that is the first)
        pieces = [(y, t, None)]
        if t[-1] * t_new[-1] < 0.0:
            fold = _locate_fold(problem, y, t, h)
            if fold is not None:
                pieces.append((fold[0], fold[2], fold))
        pieces.append((y_new, t_new, None))
        new: list[BranchPoint] = []  # accepted only once the whole step has succeeded
        finished = failed = False
        for (ya, ta, _), (yb, _, fold) in itertools.pairwise(pieces):
            la, lb = float(ya[-1]), float(yb[-1])
            if (lb - stop) * (la - stop) <= 0.0 and la != lb:
                end = _end_at_stop(problem, ya, yb, ta, stop)
                if isinstance(end, str):
                    failure = f"correction at λ = stop failed: {end}"
                    failed = True
                else:
                    new.append(end)
                    finished = True
                break
            if fold is not None:
                new.append(_point(problem, fold[0], fold[1], fold[2], True, fold[3]))
        if failed:
            h *= 0.5
            continue
        if not finished:
            new.append(_point(problem, y_new, jx_new, t_new, False, its))
        for p in new:
            if len(points) >= max_points:
                return Branch(points, "max_points", False)
            accept(p)
        if finished:
            return Branch(points, "reached stop", True)
        lam_new = float(y_new[-1])
        if not low <= lam_new <= high:
            return Branch(points, f"left the parameter range [{low:g}, {high:g}] (the "
                          f"branch turned back) at λ = {lam_new:.10g}", False)
        if its <= FAST_ITERATIONS:
            h = min(GROW * h, max_step)
        elif its >= SLOW_ITERATIONS:
            h = max(SHRINK * h, min_step)
        y, t = y_new, t_new


def _end_at_stop(problem: _Problem, ya: Array, yb: Array, ta: Array, stop: float
                 ) -> BranchPoint | str:
    """The point at exactly λ = stop between ya and yb (λ = stop between theirs), by Newton
    with the constraint λ = stop (a natural-parameter correction) from the chord's point at
    λ = stop; the failure's message if it fails."""
    frac = (stop - ya[-1]) / (yb[-1] - ya[-1])
    guess = ya + frac * (yb - ya)
    row = np.zeros(ya.size)
    row[-1] = 1.0
    y_end, jx_end, jy_end, its, why = problem.correct(guess, row, stop)
    if y_end is None:
        return why
    y_end[-1] = stop
    return _point(problem, y_end, jx_end, problem.tangent(jy_end, ta), False, its)


def _locate_fold(problem: _Problem, y: Array, t: Array, h: float
                 ) -> tuple[Array, Array, Array, int] | None:
    """The fold between y and its corrected successor at arclength h along t: (y, F_x,
    tangent, iterations) of the fold, or None if a correction inside the bracket failed (the
    branch is still right; only the fold's point is missing).

    y(s) is the corrected point on the hyperplane t · (y − (y + s t)) = 0; Brent's method
    finds the s where its tangent's λ-component vanishes.
    """
    cache: dict[float, tuple[Array, Array, Array, int]] = {}

    def t_lam(s: float) -> float:
        y_pred = y + s * t
        ys, jx, jy, its, why = problem.correct(y_pred, t, t @ y_pred)
        if ys is None:
            raise ArithmeticError(why)
        ts = problem.tangent(jy, t)
        cache[s] = (ys, jx, ts, its)
        return float(ts[-1])

    try:
        # without raising at maxiter: with a finite-difference Jacobian the tangent's
        # λ-component is known to ~1e-6 only (measured on the hub's harmonic balance), and the
        # last bracket's point is then the fold to that accuracy
        s = scipy.optimize.brentq(t_lam, 0.0, h, xtol=1e-14 * h, rtol=4 * np.finfo(float).eps,
                                  maxiter=60, disp=False)
        if s not in cache:
            t_lam(s)
    except (ArithmeticError, ValueError, RuntimeError):
        return None
    return cache[s]
