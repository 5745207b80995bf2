"""Sparse LU on the Newton matrices: solver/sparse_lu.py against SuiteSparse's KLU (kvxopt).

    PYTHONPATH=. python benchmarks/sparse_lu_klu.py [--repeats 20] [--models chain hub rotor]

For each model (the 16-link chain of benchmarks/chain.py, the hub model and the UH-60 rotor at
their defaults) the integrator marches a few steps and every matrix its Newton iteration
factors is kept; the matrices of the pattern factored most often (the Newton matrix; the
start's projection has another) are the test set. Per model it prints the unknowns n, the
stored entries nnz, the entries of L + U, and the median wall time over ``--repeats`` repeats
of

- ``factor``: the first factorization of the pattern (ours: the column orderings tried, the
  pivots by SuperLU, the symbolic step and the numeric one, with the cache of pivot orders
  emptied before each repeat; KLU: the matrix handed to kvxopt, ``klu.symbolic`` (BTF and
  AMD) and ``klu.numeric``),
- ``refactor``: a later matrix of the same pattern (ours: the compiled numeric step with the
  kept pivots; KLU: the new values handed over and ``klu.numeric`` with the kept symbolic
  analysis, which pivots afresh: kvxopt does not expose ``klu_refactor``),
- ``solve``: one right-hand side with the factors of a refactored matrix (the conversions to
  and from kvxopt's matrix type included for KLU),

and the largest relative residual ‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞) of each over the test
set (both solve the same systems). The row ``KLU-r`` is KLU's own refactorization with the
kept pivots (``klu_refactor``, which kvxopt's Python interface leaves out) called through
ctypes on the KLU library that kvxopt's wheel ships: what a binding that exposed it would
cost. The machine may be shared: the medians over the repeats damp the interference. kvxopt
is in the ``bench`` extra.
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

import solver.sparse_lu as slu
from solver.system import System

MIN_MATRICES = 4  # of the Newton pattern: the first and at least three to refactor
MAX_STEPS = 400


def _integrator(name: str):
    """The model's system and its integrator as its study makes it."""
    from solver.integrators import make_integrator

    if name == "chain":
        from benchmarks.chain import chain

        return make_integrator(System(chain(16)), "ep", 1e-3)
    if name == "hub":
        from studies import hub

        p = hub.SPEC.validate({})
        d = hub.design(p)
        start, _ = hub.initial_start(p, d)
        model = hub.build(p, d, start)[0]
        return make_integrator(System(model), "ep", 2 * np.pi / p.hub_speed / p.steps_per_rev,
                               tol=hub.NEWTON_TOL)
    from studies import rotor

    p = rotor.SPEC.validate({})
    model, parts = rotor.build(p)
    return rotor.integrator(System(model), p, 2 * np.pi / p.hub_speed / p.steps_per_rev, parts)


def newton_matrices(name: str) -> list[sp.csc_matrix]:
    """Copies of the Newton matrices the model's integrator factors in its first steps (at
    least ``MIN_MATRICES`` of the pattern factored most often, or those of ``MAX_STEPS``
    steps)."""
    kept: list[sp.csc_matrix] = []
    factor = slu.RefactorLU.factor

    def keep(self, mat) -> None:
        a = sp.csc_matrix(mat, copy=True)
        a.sum_duplicates()
        kept.append(a)
        factor(self, mat)

    slu.RefactorLU.factor = keep
    try:
        integ = _integrator(name)
        for _ in range(MAX_STEPS):
            integ.step()
            counts = Counter(_key(a) for a in kept)
            if counts and counts.most_common(1)[0][1] >= MIN_MATRICES:
                break
    finally:
        slu.RefactorLU.factor = factor
    key = Counter(_key(a) for a in kept).most_common(1)[0][0]
    return [a for a in kept if _key(a) == key]


def _key(a: sp.csc_matrix) -> tuple:
    return (a.shape[0], a.indptr.tobytes(), a.indices.tobytes())


def median_time(fn: Callable[[int], object], repeats: int) -> float:
    """Median wall time (s) of fn(r), r = 0 … repeats − 1, after one call not timed."""
    fn(0)
    times = []
    for r in range(repeats):
        t0 = time.perf_counter()
        fn(r)
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def residual(a: sp.csc_matrix, x: np.ndarray, b: np.ndarray) -> float:
    """‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)."""
    norm_a = abs(a).sum(axis=1).max()
    return float(np.abs(a @ x - b).max()
                 / (norm_a * np.abs(x).max() + np.abs(b).max()))


class Klu:
    """KLU through kvxopt on one sparsity pattern: ``factor`` (symbolic and numeric),
    ``refactor`` (numeric with the kept symbolic analysis), ``solve``."""

    def __init__(self) -> None:
        from kvxopt import klu, matrix, spmatrix

        self.klu, self.matrix, self.spmatrix = klu, matrix, spmatrix

    def _values(self, a: sp.csc_matrix):
        return self.matrix(a.data)

    def factor(self, a: sp.csc_matrix) -> None:
        cols = np.repeat(np.arange(a.shape[0]), np.diff(a.indptr))
        self.a = self.spmatrix(self._values(a), self.matrix(a.indices.astype(np.int64)),
                               self.matrix(cols), a.shape)
        self.symbolic = self.klu.symbolic(self.a)
        self.numeric = self.klu.numeric(self.a, self.symbolic)

    def refactor(self, a: sp.csc_matrix) -> None:
        # a canonical CSC matrix's values are in the order kvxopt keeps them (by column,
        # rows increasing): checked once in check_order()
        self.a.V = self._values(a)
        self.numeric = self.klu.numeric(self.a, self.symbolic)

    def check_order(self, a: sp.csc_matrix) -> None:
        ptr, ind, _ = self.a.CCS
        if not (np.array_equal(np.asarray(ptr).ravel(), a.indptr)
                and np.array_equal(np.asarray(ind).ravel(), a.indices)):
            raise RuntimeError("kvxopt stores the pattern in another order than scipy")

    def kept_pivots(self) -> Callable[[sp.csc_matrix], None] | None:
        """``klu_l_refactor`` (the kept pivots, new values) called through ctypes on the KLU
        library kvxopt ships, on the current factors; None where that library is not found.
        """
        import ctypes
        import glob
        import os

        import kvxopt

        found = glob.glob(os.path.join(os.path.dirname(kvxopt.__file__), os.pardir,
                                       "kvxopt.libs", "libklu*.so*"))
        if not found:
            return None
        lib = ctypes.CDLL(found[0])
        pointer = ctypes.pythonapi.PyCapsule_GetPointer
        pointer.restype = ctypes.c_void_p
        pointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
        common = ctypes.create_string_buffer(4096)  # klu_l_common, with room to spare
        lib.klu_l_defaults(common)
        lib.klu_l_refactor.argtypes = [ctypes.c_void_p] * 6
        lib.klu_l_refactor.restype = ctypes.c_long
        ptr, ind, _ = self.a.CCS
        ap, ai = np.asarray(ptr).ravel().copy(), np.asarray(ind).ravel().copy()
        sym = pointer(self.symbolic, b"KLU SYM D FACTOR")
        num = pointer(self.numeric, b"KLU NUM D FACTOR")

        def refactor(a: sp.csc_matrix) -> None:
            if not lib.klu_l_refactor(ap.ctypes.data, ai.ctypes.data, a.data.ctypes.data,
                                      sym, num, common):
                raise ArithmeticError("klu_refactor failed")

        return refactor

    def solve(self, b: np.ndarray) -> np.ndarray:
        x = self.matrix(b)
        self.klu.solve(self.a, self.symbolic, self.numeric, x)
        return np.asarray(x).ravel()

    def lu_entries(self) -> int:
        # L and U with their diagonals, and F, the entries above BTF's diagonal blocks
        low, up, *_, off, _ = self.klu.get_numeric(self.a, self.symbolic, self.numeric)
        return len(low.V) + len(up.V) + len(off.V) - self.a.size[0]


def measure(name: str, repeats: int) -> list[dict]:
    mats = newton_matrices(name)
    a0, later = mats[0], mats[1:]
    n = a0.shape[0]
    rng = np.random.default_rng(0)
    rhs = [rng.standard_normal(n) for _ in later]
    rows = []

    # ours
    def first(_: int) -> slu.RefactorLU:
        slu._ANALYSES.clear()  # a pattern never seen: the orderings are tried again
        lu = slu.RefactorLU()
        lu.factor(a0)
        return lu

    t_factor = median_time(first, repeats)
    ours = first(0)
    fresh = ours.fresh
    t_refactor = median_time(lambda r: ours.factor(later[r % len(later)]), repeats)
    fallbacks = ours.fresh - fresh
    res = 0.0
    for a, b in zip(later, rhs, strict=True):
        ours.factor(a)
        res = max(res, residual(a, ours.solve(b), b))
    t_solve = median_time(lambda r: ours.solve(rhs[-1]), repeats)
    entries = int(ours._l[0][-1] + ours._u[0][-1]) + n
    rows.append({"model": name, "lu": "ours", "n": n, "nnz": a0.nnz, "lu_entries": entries,
                 "factor": t_factor, "refactor": t_refactor, "solve": t_solve,
                 "residual": res, "note": f"{fallbacks} of {repeats + 1} refactors pivoted "
                                           "afresh"})

    # KLU
    k = Klu()
    t_factor = median_time(lambda r: k.factor(a0), repeats)
    k.check_order(a0)
    t_refactor = median_time(lambda r: k.refactor(later[r % len(later)]), repeats)
    res = 0.0
    for a, b in zip(later, rhs, strict=True):
        k.refactor(a)
        res = max(res, residual(a, k.solve(b), b))
    t_solve = median_time(lambda r: k.solve(rhs[-1]), repeats)
    t_transfer = median_time(lambda r: k._values(later[r % len(later)]), repeats)
    rows.append({"model": name, "lu": "KLU", "n": n, "nnz": a0.nnz,
                 "lu_entries": k.lu_entries(), "factor": t_factor, "refactor": t_refactor,
                 "solve": t_solve, "residual": res,
                 "note": f"values handed over: {1e6 * t_transfer:.0f} µs of the refactor"})

    # KLU's refactorization with the kept pivots
    k.factor(a0)
    kept = k.kept_pivots()
    if kept is not None:
        t_refactor = median_time(lambda r: kept(later[r % len(later)]), repeats)
        res = 0.0
        for a, b in zip(later, rhs, strict=True):
            kept(a)
            res = max(res, residual(a, k.solve(b), b))
        rows.append({"model": name, "lu": "KLU-r", "n": n, "nnz": a0.nnz,
                     "lu_entries": k.lu_entries(), "factor": float("nan"),
                     "refactor": t_refactor, "solve": float("nan"), "residual": res,
                     "note": "klu_refactor through ctypes"})
    return rows


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=20)
    p.add_argument("--models", nargs="+", choices=["chain", "hub", "rotor"],
                   default=["chain", "hub", "rotor"])
    a = p.parse_args()
    print(f"median of {a.repeats} repeats, µs")
    print(f"{'model':<6} {'LU':<5} {'n':>5} {'nnz':>7} {'L+U':>7} {'factor':>9} "
          f"{'refactor':>9} {'solve':>7} {'residual':>9}  note")
    def us(t: float, width: int, digits: int) -> str:
        return f"{'-':>{width}}" if np.isnan(t) else f"{1e6 * t:>{width}.{digits}f}"

    for name in a.models:
        for r in measure(name, a.repeats):
            print(f"{r['model']:<6} {r['lu']:<5} {r['n']:>5} {r['nnz']:>7} "
                  f"{r['lu_entries']:>7} {us(r['factor'], 9, 0)} "
                  f"{us(r['refactor'], 9, 0)} {us(r['solve'], 7, 1)} "
                  f"{r['residual']:>9.1e}  {r['note']}", flush=True)


if __name__ == "__main__":
    main()
