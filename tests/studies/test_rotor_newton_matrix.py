"""The sparse LU's ordering on the rotor's Newton matrix (dense inflow lines ordered last)."""

from __future__ import annotations

import numpy as np

import studies.rotor as rotor
from solver import sparse_lu
from solver.sparse_lu import RefactorLU
from solver.system import System
from tests.studies.helpers import PETERS_HE


def test_dense_lines_are_ordered_last():
    """The rotor's Newton matrix has 8 dense rows and columns (the global inflow states: every
    blade section's load feeds them, each acts on every section): minimum degree on the
    whole matrix sees the unknowns they touch as adjacent and orders the rest poorly. The
    ordering of the rest without them, and those last, is chosen, and costs 2.8 million
    multiply-adds per refactorization against 4.7 million for the best of the three orderings
    on the whole matrix (measured); it solves as accurately as they do. Of the orderings of
    the rest, reverse Cuthill–McKee (the blades are long chains) wins: on this early step's
    matrix 2.51 million against 2.79 for minimum degree on AᵀA (on a settled step's, 2.34
    against 2.75). Measured with two aerodynamic sections per element; with three, minimum
    degree on A + Aᵀ over the whole matrix is the cheapest (2.77 million against 3.10) and
    is chosen."""
    p = rotor.SPEC.validate(PETERS_HE)
    integ = rotor.integrator(System(rotor.build(p)[0]), p, 2 * np.pi / p.hub_speed / 240)
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
