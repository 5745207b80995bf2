"""Interfaces of the constraint groups that are not quadratic in the unknowns.

A :class:`HolonomicGroup` gives C(q) and its Jacobian rows over a fixed set of columns per row;
the integrators build the exact discrete derivative from them (Gonzalez's correction, design
note "Anything else"), so the energy-preserving scheme stays exact. A :class:`NonholonomicGroup`
gives the rows of A(q) in A(q)·q̇ = 0; the integrators discretize it as A(q_m)·(q_f − q_i) = 0
with the workless force A(q_m)ᵀλ.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


class _Group:
    """Rows over a fixed set of columns per row (``cols``, m × k, no repeats)."""

    name: str = ""
    cols: NDArray[np.int64]

    def scalars(self) -> list:
        """Extra scalar unknowns the group owns (η, s)."""
        return []

    def setup(self, system) -> None:
        """Resolve coordinate indices once the system is numbered."""
        raise NotImplementedError

    @property
    def m(self) -> int:
        return self.cols.shape[0]


class HolonomicGroup(_Group):
    """m rows C_r(q) = 0, each depending on the k coordinates ``cols[r]``."""

    hess_rows: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
    hess_cols: NDArray[np.int64] = np.zeros(0, dtype=np.int64)

    def evaluate(self, q: Array) -> tuple[Array, Array]:
        """(C (m,), ∂C/∂q values (m, k) at ``cols``)."""
        raise NotImplementedError

    def hessian(self, q: Array, lam: Array) -> Array:
        """Values of Σ_r λ_r ∂²C_r/∂q² at (hess_rows, hess_cols) (may be approximate)."""
        return np.zeros(0)


class NonholonomicGroup(_Group):
    """m rows A_r(q)·q̇ = 0, each over the k coordinates ``cols[r]``."""

    def matrix(self, q: Array) -> Array:
        """Values (m, k) of A(q) at ``cols``."""
        raise NotImplementedError

    def derivative(self, q: Array, dq: Array) -> Array:
        """Values (m, k) of ∂(A(q)·dq)/∂q at ``cols`` (for exact Newton tangents); ``dq`` is
        the full vector. Default: A independent of q."""
        return np.zeros(self.cols.shape)
