"""Newton's method on the sparse KKT system, with optional reuse of the factorization.

Failure is a value: :func:`newton` returns a :class:`NewtonResult` with ``converged``,
``iterations`` and a message; non-finite residuals, a singular matrix or a contraction rate ≥ 1
with a fresh Jacobian mean divergence (scipy ``radau.py::solve_collocation_system`` does the
same). Reusing the LU factors of an earlier Jacobian (modified Newton) costs a few more, much
cheaper, iterations; the factors are refreshed as soon as the contraction slows down. A
refreshed factorization keeps an earlier pivot order of the same pattern when it still passes
the pivot test (:mod:`solver.sparse_lu`), which makes it about ten times cheaper than SuperLU's
on these matrices. Above roundoff-level tolerances the iteration stops on the error its
contraction rate predicts, rate/(1 − rate)·|Δx|, instead of confirming with one more update.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from solver.jit import njit
from solver.sparse_lu import RefactorLU
from solver.turning import TurningParts

NEWTON_MAXITER = 30  # Maximum number of Newton iterations per step.
SLOW_RATE = 0.25  # Contraction rate above which the LU factors are refreshed.
STALE_RATE = 0.02  # Rate above which factors from an earlier step are not worth keeping.
STALE_ITERATIONS = 4  # Iterations after which factors from an earlier step are refreshed.
# Updates that stop shrinking, with a Newton matrix of the current iterate, while within
# 1/ROUNDOFF_FLOOR of the tolerance are roundoff noise (the KKT matrix's condition number times
# machine precision), not divergence. With factors kept from an earlier matrix, slow shrinking
# only means the factors are stale: those are refreshed instead (see newton()).
ROUNDOFF_FLOOR = 1e-5
# LU pivots smaller than this times the largest are zero: a singular matrix (measured: the
# rotor's Newton matrices 1.7e-9, a rotation with no inertia and no joint 7e-18)
PIVOT_RATIO = 1e-13
ERROR_RATE = 0.1  # contraction rate below which the rate-based error estimate is trusted


@dataclass
class NewtonResult:
    x: NDArray[np.float64]
    converged: bool
    iterations: int
    factorizations: int
    message: str = ""
    stale_refactored: bool = False  # factors reused from an earlier call failed at once
    residual: NDArray[np.float64] | None = None  # last residual evaluated (for diagnostics)


class LinearSolver:
    """Holds LU factors between calls so a later solve can reuse them.

    ``lu`` has ``solve(b)`` after a successful :meth:`factor`, and is None after a failed one.
    Matrices of one sparsity pattern are refactored with the pivot order of the first
    (:class:`solver.sparse_lu.RefactorLU`).

    With ``turning`` (:class:`solver.turning.TurningParts`), factors kept from a matrix
    factored at an earlier spin angle solve as that matrix turned to the current ``angle``
    (rad; the caller sets it): T lu⁻¹ Tᵀ b, T turning the spinning parts' 3-vectors in the
    first ``stages`` blocks of n unknowns.
    """

    def __init__(self, turning: TurningParts | None = None, stages: int = 1) -> None:
        self.lu: RefactorLU | None = None
        self._factors = RefactorLU()
        self.turning = turning
        self.stages = stages
        self.angle = 0.0  # the spin angle of the matrices now being solved
        self._angle_lu = 0.0  # the spin angle of the factored matrix

    def factor(self, mat) -> str | None:
        self.lu = None
        try:
            self._factors.factor(mat)
        except (RuntimeError, spla.MatrixRankWarning) as exc:
            return _singular(str(exc))
        # a zero pivot that roundoff left at 1e-16 is still a zero pivot (whether it comes
        # out exactly zero depends on the order of the sums that built the matrix)
        d = np.abs(self._factors.diagonal)
        if d.size and d.min() <= PIVOT_RATIO * d.max():
            return _singular(f"pivot {d.min():.1e} against {d.max():.1e}")
        self.lu = self._factors
        self._angle_lu = self.angle
        return None

    def use(self, lu: RefactorLU, angle: float) -> None:
        """Keep factors made elsewhere (of a matrix at spin ``angle``, rad), as if factored
        here: a recorded Newton path's (:class:`solver.integrators.NewtonPath`)."""
        self.lu, self._angle_lu = lu, angle

    def solve(self, b: NDArray) -> NDArray:
        """x with J x = b for the current matrix J, by the kept factors (turned, if they were
        factored at another spin angle)."""
        turn = self.angle - self._angle_lu
        if self.turning is None or turn == 0.0:
            return self.lu.solve(b)
        b = np.array(b, dtype=float)
        self.turning.turn(b, -turn, self.stages)
        x = self.lu.solve(b)
        self.turning.turn(x, turn, self.stages)
        return x


def _singular(why: str) -> str:
    return (f"singular Newton matrix ({why}); redundant or insufficient constraints, "
            "or a body with zero inertia whose rotation no joint fixes")


def _factor(solver, jacobian, x) -> str:
    """Factor the Newton matrix at x; a message if it is singular or cannot be evaluated (an
    iterate so far from the solution that a term divides by zero is a diverged Newton)."""
    try:
        return solver.factor(jacobian(x))
    except ArithmeticError as exc:
        return f"Newton diverged (the Newton matrix is not finite: {exc})"


@njit(cache=True)
def max_abs(x: NDArray) -> float:
    """max |xᵢ| as ``np.abs(x).max()`` gives it, NaN if an entry is NaN (so it is finite
    exactly when every entry is), in one compiled pass: Newton takes three per iteration, and
    the NumPy form costs two calls and a temporary. 0 for an empty x."""
    m = 0.0
    for v in x:
        a = abs(v)
        if a != a:
            return a
        if a > m:
            m = a
    return m


@njit(cache=True)
def max_abs_weighted(x: NDArray, w: NDArray, stages: int) -> float:
    """max |xᵢ wᵢ| over the first ``stages`` blocks of len(w) entries of x (w repeated in
    each), NaN if one of them is NaN: :func:`max_abs` with a weight per unknown."""
    n = len(w)
    m = 0.0
    for s in range(stages):
        for i in range(n):
            a = abs(x[s * n + i]) * w[i]
            if a != a:
                return a
            if a > m:
                m = a
    return m


def newton(residual: Callable[[NDArray], NDArray], jacobian: Callable[[NDArray], object],
           x0: NDArray, error: Callable[[NDArray], float], tol: float, solver: LinearSolver,
           reuse: bool = True, full: bool = False, estimate: bool = False,
           stale_rate: float = STALE_RATE,
           stale_iterations: int = STALE_ITERATIONS) -> NewtonResult:
    """Solve residual(x) = 0 from x0.

    An update dx has converged when ``error(dx) <= tol``; ``error`` must be a maximum norm
    (of dx or of some of its entries), so that the scaled tests below, of c·dx for a c > 0,
    are c·error(dx) without a second evaluation (exactly: rounding is monotone, so
    max|fl(c·dxᵢ)| = fl(c·max|dxᵢ|)). ``solver`` keeps LU factors that are reused across
    calls when ``reuse`` is true. ``full`` refactors at every iteration and only gives up on
    non-finite values or the iteration limit (the robust retry). ``estimate`` also accepts an
    update whose error estimate from the contraction rate, rate/(1 − rate)·dx, passes the
    test (for tolerances well above roundoff, where that estimate means something). Factors
    kept from an earlier call are refreshed once the contraction rate exceeds ``stale_rate``
    or the iteration count reaches ``stale_iterations``.
    """
    x = x0.copy()
    nfact = 0
    fresh = False
    started_stale = reuse and solver.lu is not None
    stale_bad = False
    if not reuse or solver.lu is None:
        msg = _factor(solver, jacobian, x)
        nfact += 1
        fresh = True
        if msg:
            return NewtonResult(x, False, 0, nfact, msg)
    prev = np.inf
    for it in range(1, NEWTON_MAXITER + 1):
        try:
            r = residual(x)
        except ArithmeticError:  # e.g. a division by zero far from the solution
            r = np.full_like(x, np.nan)
        if not math.isfinite(max_abs(r)):
            return NewtonResult(x, False, it, nfact, "non-finite residual (Newton diverged)",
                                residual=r)
        dx = solver.solve(-r)
        size = max_abs(dx)  # NaN or infinite exactly when an entry is
        if not math.isfinite(size):
            return NewtonResult(x, False, it, nfact, "non-finite Newton update", residual=r)
        x += dx
        err = error(dx)
        rate = size / prev if math.isfinite(prev) and prev > 0 else 0.0
        # converged, or stagnating at the roundoff floor: updates that no longer shrink
        # although the factors are of a matrix from this call. Kept factors that contract
        # slowly are stale, and their update says nothing of roundoff: accepting it stopped
        # the rotor's steps with errors up to 5e4 times the tolerance, a few steps per
        # revolution (noise that made its shooting fail at looser tolerances)
        done = err <= tol or (fresh and rate > 0.5 and err * ROUNDOFF_FLOOR <= tol)
        if full:
            if done:
                return NewtonResult(x, True, it, nfact)
            msg = _factor(solver, jacobian, x)
            nfact += 1
            if msg:
                return NewtonResult(x, False, it, nfact, msg)
            prev = size
            continue
        if done:
            return NewtonResult(x, True, it, nfact, stale_refactored=stale_bad)
        # the error left after this update, from the contraction rate: rate/(1 − rate)·|dx|
        # (scipy radau.py's test); it saves the update that would only confirm convergence
        if estimate and 0.0 < rate < ERROR_RATE and err * (rate / (1.0 - rate)) <= tol:
            return NewtonResult(x, True, it, nfact, stale_refactored=stale_bad)
        if rate > SLOW_RATE or (not fresh and (it >= stale_iterations or rate > stale_rate)):
            stale_bad = stale_bad or (started_stale and not fresh and it <= 2)
            if fresh and rate >= 1.0 and it > 3:
                return NewtonResult(x, False, it, nfact,
                                    f"Newton diverged (contraction rate {rate:.2f} ≥ 1)",
                                    residual=r)
            fresh = True
            msg = _factor(solver, jacobian, x)
            nfact += 1
            if msg:
                return NewtonResult(x, False, it, nfact, msg)
            prev = np.inf  # rates are only compared within one factorization
            continue
        prev = size
    return NewtonResult(x, False, NEWTON_MAXITER, nfact,
                        f"Newton did not converge in {NEWTON_MAXITER} iterations", residual=r)
