"""Newton's stopping tests (:func:`solver.newton.newton`) on linear systems whose answer is
known: the iteration stops on the tolerance, on the contraction-rate estimate, and at the
roundoff floor only where that floor is real."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from solver.newton import ROUNDOFF_FLOOR, LinearSolver, max_abs, max_abs_weighted, newton

A = sp.csc_matrix(np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]]))
B = np.array([1.0, -2.0, 0.5])
X = np.linalg.solve(A.toarray(), B)
TOL = 1e-10


def _kept_factors(scale: float) -> LinearSolver:
    """Factors of A/scale, as if kept from an earlier step: each update with them is scale
    times the exact one, so the error contracts by 1 − scale per iteration."""
    lin = LinearSolver()
    assert lin.factor(sp.csc_matrix(A / scale)) is None
    return lin


def test_slowly_contracting_kept_factors_are_refreshed_not_taken_for_roundoff():
    """Kept factors contracting by 0.7 per iteration give updates that stop shrinking (rate
    0.7 > 0.5) while still within 1/ROUNDOFF_FLOOR of the tolerance: that is stale factors,
    not roundoff. Newton must refresh them and reach the tolerance (taken for roundoff, a
    rotor's steps would be accepted with errors up to 5e4 times it)."""
    x0 = X + 1e3 * TOL * np.array([1.0, -1.0, 0.5])
    res = newton(lambda x: A @ x - B, lambda x: A, x0, max_abs, TOL, _kept_factors(0.3))
    assert res.converged and res.factorizations == 1, res
    # the exact matrix solves a linear system in one update: the error is roundoff
    assert max_abs(res.x - X) <= 1e-3 * TOL, max_abs(res.x - X)


def test_updates_stagnating_with_a_fresh_matrix_are_the_roundoff_floor():
    """With the current matrix, updates that stop shrinking near the tolerance are the noise
    of the residual's evaluation (here an added noise 100 times the tolerance in x, as
    roundoff in a badly conditioned residual would give): accepted as converged, not
    reported as divergence."""
    rng = np.random.default_rng(0)
    noise = 100 * TOL

    def residual(x):
        return A @ (x + noise * rng.uniform(-1.0, 1.0, 3)) - B

    x0 = X + 1e3 * TOL
    res = newton(residual, lambda x: A, x0, max_abs, TOL, LinearSolver(), reuse=False)
    assert res.converged and res.factorizations == 1, res
    assert max_abs(res.x - X) <= 3 * noise
    assert noise * ROUNDOFF_FLOOR <= TOL  # the floor this test relies on


def test_kept_factors_that_contract_fast_are_kept():
    """Factors within 1 % of the matrix (contraction 0.01) are kept, and the rate-based
    estimate stops the iteration once the error it predicts passes the tolerance."""
    x0 = X + 1e4 * TOL * np.array([1.0, 0.5, -1.0])
    res = newton(lambda x: A @ x - B, lambda x: A, x0, max_abs, TOL, _kept_factors(0.99),
                 estimate=True)
    assert res.converged and res.factorizations == 0, res
    # the estimate is the contraction measured from two updates of about 1e-8: its roundoff
    # (measured 2.3e-6 relative, with NumPy 2.4) may put the error a hair past the tolerance
    assert max_abs(res.x - X) <= TOL * (1.0 + 1e-4)


def test_weighted_error_is_the_weighted_maximum_norm():
    """max_abs_weighted is max |xᵢ wᵢ| over the stages' blocks (w repeated per stage), NaN
    when an entry is: Newton's size of an update with a tolerance per unknown."""
    rng = np.random.default_rng(3)
    w = rng.uniform(0.01, 1.0, 5)
    x = rng.standard_normal(13)  # two stages of 5 and three multipliers, which are not judged
    assert max_abs_weighted(x, w, 1) == np.abs(x[:5] * w).max()
    assert max_abs_weighted(x, w, 2) == np.abs(x[:10] * np.tile(w, 2)).max()
    x[7] = np.nan
    assert np.isnan(max_abs_weighted(x, w, 2)) and not np.isnan(max_abs_weighted(x, w, 1))


@pytest.mark.parametrize("scale, match", [
    (np.ones(2), r"3 numbers \(one per unknown of q\), got shape \(2,\)"),
    ([1.0, 0.0, 1.0], r"tolerance_scale\[1\] = 0.0"),
    ([1.0, 1.0, np.inf], r"tolerance_scale\[2\] = inf")])
def test_tolerance_scale_is_validated(scale, match):
    """A tolerance per unknown of q: one finite positive number each, else an error naming
    the entry."""
    from solver.bodies import PointMass
    from solver.forces import Spring
    from solver.integrators import make_integrator
    from solver.model import Model
    from solver.system import System

    mod = Model()
    p = PointMass("mass", 1.0, position=(1.0, 0.0, 0.0))
    mod.add(p, Spring("s", None, p, point=(1.0, 0.0, 0.0), stiffness=10.0))
    with pytest.raises(ValueError, match=match):
        make_integrator(System(mod), "galpha", 0.01, tolerance_scale=scale)
