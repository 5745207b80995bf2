"""The refactoring sparse LU (solver/sparse_lu.py) against scipy's direct solver."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from solver import sparse_lu
from solver.newton import LinearSolver
from solver.sparse_lu import RefactorLU


@pytest.fixture(autouse=True)
def _no_shared_analyses():
    """Each test starts with no pivot order kept from another test's matrices."""
    sparse_lu._ANALYSES.clear()
    yield
    sparse_lu._ANALYSES.clear()


def _random_kkt(n: int, m: int, seed: int) -> sp.csc_matrix:
    """[[K, Gᵀ], [G, 0]]: K sparse nonsymmetric with a strong diagonal, G sparse full rank,
    the zero block that makes partial pivoting necessary."""
    rng = np.random.default_rng(seed)
    k = sp.random(n, n, density=3 / n, random_state=rng) + sp.diags(rng.uniform(1, 2, n))
    g = sp.random(m, n, density=2 / n, random_state=rng) + sp.eye(m, n, k=seed % (n - m))
    return sp.bmat([[k, g.T], [g, None]], format="csc")


@pytest.mark.parametrize("seed", range(6))
def test_solves_like_scipy_and_refactors(seed):
    """First factorization and a refactorization with other values of the same pattern both
    solve to roundoff (measured 6.7e-16 relative to |x| against spsolve); the second reuses
    the pivots."""
    a = _random_kkt(40, 12, seed)
    rng = np.random.default_rng(100 + seed)
    b = rng.standard_normal(a.shape[0])
    lu = RefactorLU()
    lu.factor(a)
    x = lu.solve(b)
    ref = spla.spsolve(a, b)
    assert np.abs(x - ref).max() <= 1e-12 * np.abs(ref).max()
    a2 = a.copy()
    a2.data *= 1 + 0.05 * rng.standard_normal(a2.nnz)
    lu.factor(a2)
    assert lu.refactored >= 1
    x2 = lu.solve(b)
    assert np.abs(a2 @ x2 - b).max() <= 1e-12 * np.abs(b).max()
    bb = rng.standard_normal((a.shape[0], 3))
    assert np.abs(a2 @ lu.solve(bb) - bb).max() <= 1e-12 * np.abs(bb).max()


def test_pivot_that_vanishes_is_replaced():
    """A matrix whose kept pivot becomes zero (a director component passing through zero)
    is factored again with fresh partial pivoting, and solved exactly."""
    a = sp.csc_matrix(np.array([[2.0, 1.0], [1.0, 1.0]]))
    lu = RefactorLU()
    lu.factor(a)
    fresh = lu.fresh
    b2 = sp.csc_matrix((np.array([0.0, 1.0, 1.0, 1.0]), a.indices, a.indptr), shape=(2, 2))
    lu.factor(b2)  # [[0, 1], [1, 1]]: the first pivot is now zero
    assert lu.fresh == fresh + 1
    np.testing.assert_allclose(b2 @ lu.solve(np.array([1.0, 2.0])), [1.0, 2.0], rtol=1e-15)


def test_threshold_test_sends_small_pivots_back():
    """With the pivot at 1e-4 of the entry below it (under the 1e-3 threshold) the refactor
    is refused and SuperLU pivots afresh."""
    assert sparse_lu.PIVOT_THRESHOLD == pytest.approx(1e-3)
    a = sp.csc_matrix(np.array([[4.0, 1.0], [1.0, 3.0]]))
    lu = RefactorLU()
    lu.factor(a)
    n0 = lu.fresh
    small = sp.csc_matrix((np.array([1e-4, 1.0, 1.0, 3.0]), a.indices, a.indptr), shape=(2, 2))
    lu.factor(small)
    assert lu.fresh == n0 + 1


def test_pattern_analysis_shared_between_objects():
    """A second factorization object on the same pattern starts from the first one's pivot
    order (a new integrator on the same model): no SuperLU call."""
    a = _random_kkt(30, 8, 7)
    RefactorLU().factor(a)
    lu = RefactorLU()
    lu.factor(a)
    assert (lu.fresh, lu.refactored) == (0, 1)


def test_singular_matrix_is_reported():
    a = sp.csc_matrix(np.array([[1.0, 2.0, 0.0], [2.0, 4.0, 0.0], [0.0, 0.0, 1.0]]))
    lin = LinearSolver()
    msg = lin.factor(a)
    assert msg is not None and "singular" in msg
    assert lin.lu is None
    with pytest.raises(ValueError, match="not square"):
        RefactorLU().factor(sp.csc_matrix(np.ones((2, 3))))


def test_earlier_pivot_order_is_tried_before_superlu():
    """A pattern whose values alternate between two states that need different pivots (a
    turning model) is refactored with the kept order of each: SuperLU runs twice, not at
    every switch."""
    a = sp.csc_matrix(np.array([[2.0, 1.0], [1.0, 1.0]]))
    b = sp.csc_matrix((np.array([1e-6, 1.0, 1.0, 1.0]), a.indices, a.indptr), shape=(2, 2))
    lu = RefactorLU()
    for k in range(6):
        m = a if k % 2 == 0 else b
        lu.factor(m)
        np.testing.assert_allclose(m @ lu.solve(np.array([1.0, 2.0])), [1.0, 2.0], rtol=1e-12)
    assert (lu.fresh, lu.refactored) == (2, 4)

