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


def test_dense_lines_are_ordered_last():
    """The rotor's Newton matrix has 8 dense rows and columns (the global inflow states: every
    blade section's load feeds them, each acts on every section): minimum degree on the
    whole matrix sees the unknowns they touch as adjacent and orders the rest poorly. The
    ordering of the rest without them, and those last, is chosen, and costs 2.8 million
    multiply-adds per refactorization against 4.7 million for the best of the three orderings
    on the whole matrix (measured); it solves as accurately as they do. Of the orderings of
    the rest, reverse Cuthill–McKee (the blades are long chains) wins: on this early step's
    matrix 2.51 million against 2.79 for minimum degree on AᵀA (on a settled step's, 2.34
    against 2.75)."""
    import studies.rotor as rotor
    from solver.system import System

    p = rotor.SPEC.complete({})
    integ = rotor.integrator(System(rotor.build(p)[0]), p, 2 * np.pi / p["hub_speed"] / 240)
    for _ in range(3):
        assert integ.step().converged
    integ._begin()
    a = integ._jacobian(integ._predict())
    assert len(sparse_lu._dense_lines(a)) == 8
    whole = min(sparse_lu._fresh_analysis(a, spec).flops
                for spec in ("COLAMD", "MMD_AT_PLUS_A", "MMD_ATA"))
    an = sparse_lu._fresh_analysis(a)
    assert an.spec == sparse_lu.DENSE_LAST + sparse_lu.RCM
    assert an.flops < 0.7 * whole, (an.flops, whole)
    mmd = sparse_lu._fresh_analysis(a, sparse_lu.DENSE_LAST + "MMD_ATA").flops
    assert an.flops < 0.95 * mmd, (an.flops, mmd)
    lu = RefactorLU()
    lu.factor(a)
    b = np.random.default_rng(1).standard_normal(a.shape[0])
    x = lu.solve(b)
    # componentwise backward error max |Ax − b| / (|A||x| + |b|): measured 3.5e-12 (4.4e-13
    # with minimum degree on AᵀA, 3.8e-13 – 6.4e-13 on the whole matrix: the 0.001 pivot
    # threshold allows some growth; 1e-11 is still 1e4 below the rotor's Newton tolerance)
    berr = np.abs(a @ x - b) / (abs(a) @ np.abs(x) + np.abs(b))
    assert berr.max() <= 1e-11, berr.max()
