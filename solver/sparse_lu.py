"""Sparse LU that reuses its pivot order: factor once with SuperLU, refactor compiled.

A Newton matrix of a multibody model keeps its sparsity pattern for the whole run and changes
its values slowly, so the pivot sequence that partial pivoting chose for one matrix is almost
always good for the next. This is the idea of KLU's ``klu_refactor`` (Davis & Palamadai
Natarajan 2010, *ACM TOMS* 37): keep the row and column permutations and the symbolic
structure of L and U, and recompute only the numbers. scipy's ``splu`` cannot reuse anything
and carries a large fixed cost per call on the small, very sparse KKT matrices of this solver
(measured on the 16-link chain's 392 × 392 matrix: 865 µs to factor, 67 µs to solve, for
3044 nonzeros in L + U).

How it works:

- The first matrix of a pattern is factored by SuperLU (COLAMD column order, partial
  pivoting). Its permutations ``perm_r`` and ``perm_c`` give B = P_r A P_c.
- The structure of B = LU without pivoting is then computed once (the symbolic step of the
  left-looking Gilbert–Peierls algorithm).
- Every later matrix of the same pattern is refactored by the compiled left-looking numeric
  step with those pivots (:func:`_numeric`).
- A pivot is accepted if it is at least ``PIVOT_THRESHOLD`` times the largest entry below
  it in its column (threshold partial pivoting's test). If one is not, that matrix is
  factored afresh by SuperLU, and its pivots are kept for the next ones.

The factors keep only their entries that come out nonzero (:func:`_numeric`): on the planar
chain's Newton matrix two thirds of the structural ones are exact zeros. The solves are
compiled triangular sweeps over them.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray
from scipy.sparse.csgraph import reverse_cuthill_mckee

from solver.jit import njit

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

# A kept pivot must be at least this fraction of the largest entry below it in its column;
# else the matrix is refactored with fresh partial pivoting. (SuperLU's own threshold is 1:
# strict partial pivoting; 0.001 is KLU's default tolerance, and bounds the growth per column
# to 1000, which the Newton iteration around the solves absorbs. On the hub model 0.1 sent
# 14 % of the factorizations back to SuperLU, 0.01 about 6 %, 0.001 hardly fewer; on the
# rotor 0.01 sent 9 of 240 per revolution back, each costing about 60 ms, and 0.001 none,
# 6.27 → 5.67 s per revolution with the same Newton iterations and states to 1e-13.)
PIVOT_THRESHOLD = 0.001
ORDERINGS_FROM = 500  # unknowns from which several column orderings are tried
DENSE_LINE = 10.0  # a row or column is dense above this many times √n entries (COLAMD's rule)
DENSE_LAST = "DENSE_LAST+"  # prefix of an ordering that puts the dense lines last
# reverse Cuthill–McKee on the symmetric pattern |A| + |A|ᵀ: a column order of our own, for
# matrices made of long chains (beams) that minimum degree orders with more fill
RCM = "RCM"


@njit(cache=True)
def _symbolic(n: int, bp: IntArray, bi: IntArray) -> tuple:
    """Structure of L (strictly lower, unit diagonal) and U (strictly upper) of B = LU
    without pivoting, B in CSC (bp, bi). Column j of U holds the rows i < j reached from
    B(:, j) through the columns of L; they are listed in increasing order, the order in which
    the left-looking numeric step applies them. Returns (Lp, Li, Up, Ui, ok); ok is false if a
    diagonal entry is structurally zero.

    The rows above the diagonal are taken from a heap, smallest first: L(:, i) only adds rows
    > i, so once row i is popped every row it reaches is still to come. The cost is the
    reach's size times its logarithm, not n per column (which made this step 31 ms on the
    rotor's 2424-unknown matrix).
    """
    mark = np.full(n, -1, dtype=np.int64)
    cap = max(4 * len(bi), 16)
    li = np.empty(cap, dtype=np.int64)
    ui = np.empty(cap, dtype=np.int64)
    lp = np.zeros(n + 1, dtype=np.int64)
    up = np.zeros(n + 1, dtype=np.int64)
    heap = np.empty(n, dtype=np.int64)
    below = np.empty(n, dtype=np.int64)
    nl = 0
    nu = 0
    ok = True
    # the visit of a reached row (marked once, onto the heap above the diagonal or the list
    # below it) is written out twice, for B's entries and for L's: as a compiled helper, even
    # with inline="always", it made this step six times slower
    for j in range(n):
        nh = 0
        nb = 0
        for p in range(bp[j], bp[j + 1]):
            r = bi[p]
            if mark[r] == j:
                continue
            mark[r] = j
            if r < j:
                nh = _heap_push(heap, nh, r)
            elif r > j:
                below[nb] = r
                nb += 1
        while nh:
            i = heap[0]
            nh = _heap_pop(heap, nh)
            if nu == len(ui):
                ui = np.concatenate((ui, np.empty(len(ui), dtype=np.int64)))
            ui[nu] = i
            nu += 1
            for q in range(lp[i], lp[i + 1]):
                r = li[q]
                if mark[r] == j:
                    continue
                mark[r] = j
                if r < j:
                    nh = _heap_push(heap, nh, r)
                elif r > j:
                    below[nb] = r
                    nb += 1
        up[j + 1] = nu
        if mark[j] != j:
            ok = False
        if nl + nb > len(li):
            li = np.concatenate((li, np.empty(max(len(li), nb), dtype=np.int64)))
        li[nl : nl + nb] = np.sort(below[:nb])  # rows below the diagonal, increasing
        nl += nb
        lp[j + 1] = nl
    return lp, li[:nl].copy(), up, ui[:nu].copy(), ok


@njit(cache=True)
def _heap_push(heap: IntArray, size: int, value: int) -> int:
    """Push onto the binary min-heap heap[:size]; returns the new size."""
    k = size
    heap[k] = value
    while k:
        parent = (k - 1) // 2
        if heap[parent] <= value:
            break
        heap[k] = heap[parent]
        k = parent
    heap[k] = value
    return size + 1


@njit(cache=True)
def _heap_pop(heap: IntArray, size: int) -> int:
    """Remove the smallest entry, heap[0], from the min-heap heap[:size]; returns the new
    size."""
    size -= 1
    last = heap[size]
    k = 0
    while True:
        child = 2 * k + 1
        if child >= size:
            break
        if child + 1 < size and heap[child + 1] < heap[child]:
            child += 1
        if heap[child] >= last:
            break
        heap[k] = heap[child]
        k = child
    if size:
        heap[k] = last
    return size


@njit(cache=True)
def _numeric(n: int, bp: IntArray, bi: IntArray, bx: Array, lp: IntArray, li: IntArray,
             up: IntArray, ui: IntArray, fp: IntArray, fi: IntArray, fx: Array, gp: IntArray,
             gi: IntArray, gx: Array, d: Array, x: Array, threshold: float) -> int:
    """Left-looking LU of B with the given structure (lp, li; up, ui) and no pivoting.

    Only the entries that come out nonzero are stored: L strictly below the diagonal (unit
    diagonal) in (fp, fi, fx), U strictly above it in (gp, gi, gx), both CSC with the
    structure's capacity, and U's diagonal in d. Many structural entries are exact zeros (on
    the planar chain's Newton matrix 4631 of 6774, the out-of-plane couplings), and an exact
    zero changes nothing where it would be applied (x − 0·y = x), so leaving them out gives
    the same values as the full structure, in the later columns of this step and in
    :func:`_solve`, for less work. x is an all-zero work vector of length n, left all zero.
    Returns −1, or the first column whose pivot fails the threshold test."""
    nl = 0
    nu = 0
    fp[0] = 0
    gp[0] = 0
    for j in range(n):
        for p in range(bp[j], bp[j + 1]):
            x[bi[p]] = bx[p]
        for p in range(up[j], up[j + 1]):
            i = ui[p]
            xi = x[i]
            x[i] = 0.0
            if xi != 0.0:
                gi[nu] = i
                gx[nu] = xi
                nu += 1
                for q in range(fp[i], fp[i + 1]):
                    x[fi[q]] -= fx[q] * xi
        gp[j + 1] = nu
        piv = x[j]
        x[j] = 0.0
        big = 0.0
        for q in range(lp[j], lp[j + 1]):
            big = max(big, abs(x[li[q]]))
        if piv == 0.0 or abs(piv) < threshold * big:
            for q in range(lp[j], lp[j + 1]):
                x[li[q]] = 0.0
            return j
        d[j] = piv
        for q in range(lp[j], lp[j + 1]):
            r = li[q]
            lv = x[r] / piv
            x[r] = 0.0
            if lv != 0.0:
                fi[nl] = r
                fx[nl] = lv
                nl += 1
        fp[j + 1] = nl
    return -1


@njit(cache=True)
def _solve(n: int, perm_r: IntArray, perm_c: IntArray, lp: IntArray, li: IntArray,
           lx: Array, up: IntArray, ui: IntArray, ux: Array, d: Array, b: Array) -> Array:
    """x with A x = b, where P_r A P_c = L U: c = P_r b, L U y = c, x = P_c y."""
    c = np.empty(n)
    for i in range(n):
        c[perm_r[i]] = b[i]
    for j in range(n):  # L y = c, L unit lower, by columns
        cj = c[j]
        if cj != 0.0:
            for q in range(lp[j], lp[j + 1]):
                c[li[q]] -= lx[q] * cj
    for j in range(n - 1, -1, -1):  # U y = c, by columns
        cj = c[j] / d[j]
        c[j] = cj
        if cj != 0.0:
            for p in range(up[j], up[j + 1]):
                c[ui[p]] -= ux[p] * cj
    out = np.empty(n)
    for i in range(n):
        out[i] = c[perm_c[i]]
    return out


class _Analysis:
    """What a pattern's factorizations share: permutations (and the name of the column
    ordering, ``spec``), the map from A's stored entries to B's, the structure of L and U."""

    def __init__(self, a: sp.csc_matrix, perm_r: IntArray, perm_c: IntArray,
                 spec: str = "COLAMD") -> None:
        self.spec = spec
        n = self.n = a.shape[0]
        # B[perm_r[i], perm_c[j]] = A[i, j]; tag each stored entry to find where it goes
        tag = sp.csc_matrix((np.arange(1, a.nnz + 1, dtype=float), a.indices, a.indptr),
                            shape=a.shape).tocoo()
        b = sp.csc_matrix((tag.data, (perm_r[tag.row], perm_c[tag.col])), shape=a.shape)
        b.sort_indices()
        self.bp, self.bi = b.indptr.astype(np.int64), b.indices.astype(np.int64)
        self.src = b.data.astype(np.int64) - 1  # A.data index of each entry of B
        self.perm_r, self.perm_c = perm_r.astype(np.int64), perm_c.astype(np.int64)
        self.lp, self.li, self.up, self.ui, self.ok = _symbolic(n, self.bp, self.bi)
        # multiply-adds of a refactorization: column j is updated by L(:, i) for each i in
        # U(:, j), so every entry of U costs the length of its row's column of L
        self.flops = int(np.diff(self.lp)[self.ui].sum())


# Pivot orders by pattern, shared by every factorization object (a new integrator or projection
# on the same model finds its pattern's pivot orders here), the most recently used first; the
# patterns most recently used last. A few orders are kept per pattern because a turning model
# cycles through a few: on the hub, whose Newton matrix changes its best pivots as the hub
# turns, keeping 4 instead of 1 cut the fresh SuperLU factorizations of a case from 120 to 11.
_ANALYSES: dict[tuple, list[_Analysis]] = {}
_PATTERNS_KEPT = 16
_ORDERS_KEPT = 4


def _dense_lines(a: sp.csc_matrix) -> IntArray:
    """Indices i whose row or column i has more than ``DENSE_LINE`` × √n entries (on the
    rotor: the 8 global inflow states, 1144 entries each of 2424, every blade section's load
    feeding them and each of them acting on every section)."""
    n = a.shape[0]
    limit = DENSE_LINE * np.sqrt(n)
    counts = np.maximum(np.diff(a.indptr), np.bincount(a.indices, minlength=n))
    return np.nonzero(counts > limit)[0]


def _splu_order(a: sp.csc_matrix, spec: str,
                dense: IntArray | None = None) -> tuple[IntArray, IntArray]:
    """SuperLU's (perm_r, perm_c) for ``a`` in the column order ``spec``: one of SuperLU's
    orderings, or ``DENSE_LAST + <one of them>``: that ordering of the matrix without its
    dense lines (:func:`_dense_lines`), and those last. Minimum degree on the whole matrix
    sees every column that touches a dense row as adjacent to every other and orders the
    rest poorly: on the rotor's Newton matrix, minimum degree on AᵀA without the 8 inflow
    lines and those last costs 2.8 million multiply-adds per refactorization against 4.7 to
    9.3 million for the three orderings on the whole matrix. Raises RuntimeError (or
    ``MatrixRankWarning``) where SuperLU finds a matrix singular. ``dense``: the dense
    lines, if the caller has them already."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", spla.MatrixRankWarning)
        if spec == RCM:
            cols = _rcm(a)
        elif not spec.startswith(DENSE_LAST):
            lu = spla.splu(a, permc_spec=spec)
            return lu.perm_r.astype(np.int64), lu.perm_c.astype(np.int64)
        else:
            dense = _dense_lines(a) if dense is None else dense
            rest = np.setdiff1d(np.arange(a.shape[0]), dense)
            part = a[rest][:, rest].tocsc()
            inner = spec[len(DENSE_LAST):]
            order = (_rcm(part) if inner == RCM
                     else np.argsort(spla.splu(part, permc_spec=inner).perm_c))
            cols = np.concatenate([rest[order], dense])  # new column k: cols[k]
        lu = spla.splu(a[:, cols].tocsc(), permc_spec="NATURAL")
    perm_c = np.empty(a.shape[0], dtype=np.int64)
    perm_c[cols] = lu.perm_c  # B[:, perm_c[j]] holds A[:, j]
    return lu.perm_r.astype(np.int64), perm_c


def _rcm(a: sp.csc_matrix) -> IntArray:
    """Reverse Cuthill–McKee order of the symmetric pattern |A| + |A|ᵀ (new column k:
    ``order[k]``)."""
    at = sp.csr_matrix((np.ones(a.nnz), a.indices, a.indptr), shape=a.shape)  # Aᵀ's pattern
    return reverse_cuthill_mckee((at + at.T).tocsr(), symmetric_mode=True).astype(np.int64)


def _fresh_analysis(a: sp.csc_matrix, spec: str | None = None) -> _Analysis:
    """Pivots by SuperLU's partial pivoting, in the column order ``spec`` or, if None, the
    cheapest to refactor of COLAMD, minimum degree on AᵀA + A and on AᵀA and reverse
    Cuthill–McKee on |A| + |A|ᵀ, on the whole matrix and, where it has dense lines, with those
    last (all tried from ``ORDERINGS_FROM`` unknowns up; see :func:`_splu_order`). On the
    rotor's Newton matrix RCM with the inflow lines last wins: 2.34 million multiply-adds per
    refactorization against 2.75 for minimum degree on AᵀA, 150 000 nonzeros in L + U against
    171 000."""
    dense = None
    if spec is not None:
        specs: tuple[str, ...] = (spec,)
    elif a.shape[0] >= ORDERINGS_FROM:
        specs = ("COLAMD", "MMD_AT_PLUS_A", "MMD_ATA", RCM)
        dense = _dense_lines(a)
        if len(dense):
            specs += tuple(DENSE_LAST + s for s in specs)
    else:
        specs = ("COLAMD",)
    best = None
    failure: Exception | None = None
    for spec in specs:
        try:
            perm_r, perm_c = _splu_order(a, spec, dense)
        except (RuntimeError, spla.MatrixRankWarning) as exc:
            # the whole matrix singular, or only the part without the dense lines (which
            # may need them for its rank): try the next ordering
            failure = exc
            continue
        an = _Analysis(a, perm_r, perm_c, spec)
        if an.ok and (best is None or an.flops < best.flops):
            best = an
    if best is None:
        if failure is not None:
            raise failure
        raise RuntimeError("structurally zero pivot in the order partial pivoting chose")
    return best


def _pattern_key(a: sp.csc_matrix) -> tuple:
    return (a.shape[0], a.indptr.tobytes(), a.indices.tobytes())


class RefactorLU:
    """LU factors of square sparse matrices, refactored with the pivot order of an earlier
    matrix of the same pattern.

    :meth:`factor` takes a matrix (any scipy sparse format); :meth:`solve` solves with the
    last factors, for one right-hand side or the columns of a 2-D array; :attr:`diagonal` is
    U's diagonal (the pivots). ``refactored`` and ``fresh`` count the two kinds of
    factorization.
    """

    def __init__(self) -> None:
        self._an: _Analysis | None = None
        self._ptr = self._ind = None
        self._key: tuple | None = None
        self.diagonal = np.zeros(0)
        self.refactored = 0
        self.fresh = 0

    def _use(self, an: _Analysis, a: sp.csc_matrix) -> None:
        self._an = an
        self._ptr, self._ind = a.indptr, a.indices
        # the nonzero entries of L and U (CSC, at most the structure's), see _numeric
        # (row indices as int32: a solve streams every entry of L and U, and on the rotor's
        # 3.2 MB of factors the narrower indices make them 2.4 MB, and a solve 8–13 % faster)
        self._l = (np.zeros(an.n + 1, dtype=np.int64), np.empty(len(an.li), dtype=np.int32),
                   np.empty(len(an.li)))
        self._u = (np.zeros(an.n + 1, dtype=np.int64), np.empty(len(an.ui), dtype=np.int32),
                   np.empty(len(an.ui)))
        self.diagonal = np.empty(an.n)
        self._work = np.zeros(an.n)
        # what every solve passes on but the right-hand side (Newton solves twice a step)
        self._solve_args = (an.n, an.perm_r, an.perm_c, *self._l, *self._u, self.diagonal)

    def _refactor(self, a: sp.csc_matrix) -> bool:
        an = self._an
        return _numeric(an.n, an.bp, an.bi, a.data[an.src], an.lp, an.li, an.up, an.ui,
                        *self._l, *self._u, self.diagonal, self._work, PIVOT_THRESHOLD) < 0

    def factor(self, mat) -> None:
        """Factor ``mat``. Raises RuntimeError or ``MatrixRankWarning`` (as SuperLU does) if
        it is exactly singular."""
        a = mat if isinstance(mat, sp.csc_matrix) else sp.csc_matrix(mat)
        if a.shape[0] != a.shape[1]:
            raise ValueError(f"the matrix to factor is {a.shape[0]} × {a.shape[1]}: not square")
        if not a.has_canonical_format:
            a = a.copy()
            a.sum_duplicates()
        same = self._an is not None and (
            (a.indptr is self._ptr and a.indices is self._ind)
            or (a.shape[0] == self._an.n and np.array_equal(a.indptr, self._ptr)
                and np.array_equal(a.indices, self._ind)))
        if same and self._refactor(a):
            self.refactored += 1
            return
        if not same:
            self._key = _pattern_key(a)
        orders = _ANALYSES.pop(self._key, [])
        _ANALYSES[self._key] = orders  # the most recently used pattern last
        while len(_ANALYSES) > _PATTERNS_KEPT:
            del _ANALYSES[next(iter(_ANALYSES))]
        for k, an in enumerate(orders):  # another pivot order that suited this pattern
            if same and an is self._an:
                continue
            self._use(an, a)
            if self._refactor(a):
                orders.insert(0, orders.pop(k))
                self.refactored += 1
                return
        # a pattern seen before keeps the column ordering that won there (only the pivots
        # need renewing)
        an = _fresh_analysis(a, orders[0].spec if orders else None)
        self.fresh += 1
        self._use(an, a)
        if not self._refactor(a):
            raise RuntimeError("the pivot order of partial pivoting failed its own threshold "
                               "test (a matrix too badly scaled to factor)")
        orders.insert(0, an)
        del orders[_ORDERS_KEPT:]

    @property
    def nbytes(self) -> int:
        """Memory the factors hold (L's and U's entries and row indices, U's diagonal)."""
        if self._an is None:
            return 0
        return sum(a.nbytes for a in (*self._l, *self._u, self.diagonal))

    def solve(self, b: Array) -> Array:
        """x with A x = b for the last factored A; b of shape (n,) or (n, k)."""
        an = self._an
        if an is None:
            raise RuntimeError("solve before a successful factor")
        b = np.asarray(b, dtype=float)
        args = self._solve_args
        if b.ndim == 1:
            return _solve(*args, np.ascontiguousarray(b))
        return np.column_stack([_solve(*args, np.ascontiguousarray(b[:, k]))
                                for k in range(b.shape[1])])
