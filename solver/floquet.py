"""Floquet multipliers of linear periodic systems ẏ = A(t) y, A(t + T) = A(t).

Every fundamental matrix satisfies Φ(t + T) = Φ(t) Φ(T) (Φ(0) = I), so the solutions grow per
period by the eigenvalues μ of the monodromy matrix Φ(T), the Floquet multipliers; a periodic
solution of a nonlinear system whose linearization this is is asymptotically stable when all
|μ| < 1 (apart from the multiplier 1 of an autonomous system's phase). The multipliers are
μ = exp(ρ T) for the Floquet exponents ρ, which are defined modulo iω, ω = 2π/T.

Three ways to them, for different callers:

* :func:`monodromy` integrates Φ(T) (scipy's DOP853) and :func:`multipliers` takes its
  eigenvalues: the reference, for any A(t) one can evaluate.
* :func:`hill_exponents` / :func:`hill_multipliers` use Hill's method, for a response known
  by its samples over a period (harmonic balance): a Floquet solution y = e^{ρt} p(t), p
  T-periodic with Fourier coefficients c_k, turns ẏ = A y into the eigenproblem

      Σ_j Â_{k−j} c_j − i k ω c_k = ρ c_k,   k = −H … H,

  with Â_p the Fourier coefficients of A, a block-Toeplitz matrix minus i k ω on the diagonal
  (the "Hill matrix"). Its (2H + 1) n eigenvalues approximate each exponent ρ together with
  its copies ρ + i k ω; n of them are kept. Following Lazarus & Thomas (2010, "A harmonic-
  based method for computing the stability of periodic solutions of dynamical systems",
  C. R. Mécanique 338, 510–517) the kept ones are those whose eigenvectors are most
  concentrated on the central block k = 0: the copy shifted by k ω has its coefficients
  shifted by k blocks, so the copy centred on k = 0 is the one the truncation resolves best.
  Two copies of one exponent (differing by i k ω, k ≠ 0) are not both kept: inside a
  parametric resonance the copies −σ ± iω/2 of one exponent are as central as each other and
  would outrank the other exponent σ + iω/2, which would hide the instability.
  The alternative criterion, the n eigenvalues with imaginary parts in (−ω/2, ω/2] closest
  to the real axis, is available as ``selection="strip"``; it fails when exponents lie near
  ±ω/2 (the edge of the strip, e.g. the boundaries of a parametric resonance) and when the
  truncation's spurious eigenvalues fall in the strip.
* :func:`dominant_multipliers` gives the largest multipliers of a linear map known only by
  its action (a shooting method's finite-difference Jacobian of the period map) by Arnoldi
  iteration, optionally restricted to a subspace (e.g. the state space with constraint
  directions removed).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.integrate
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

# Two Hill eigenvalues that differ by i k ω (k ≠ 0) to within CONGRUENT · ω are copies of one
# Floquet exponent (the central copies of a truncated Hill matrix agree to far better; genuine
# exponents that close are a double exponent at a stability boundary, within ~1e-14 of it in
# the parameter since they split as its square root).
CONGRUENT = 1e-7


def multipliers(matrix: ArrayLike) -> CArray:
    """Eigenvalues of ``matrix`` sorted by modulus, largest first (complex)."""
    mu = np.linalg.eigvals(np.asarray(matrix, dtype=float)).astype(complex)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def monodromy(a_of_t: Callable[[float], ArrayLike], n: int, period: float, *,
              rtol: float = 1e-11, atol: float = 1e-13) -> Array:
    """Monodromy matrix Φ(T) of ẏ = A(t) y: Φ' = A(t) Φ from Φ(0) = I to t = T.

    Parameters
    ----------
    a_of_t
        t -> A(t), (n, n).
    n
        The dimension.
    period
        T.
    rtol, atol
        Tolerances of scipy's DOP853 (8th order, suited to the tight tolerances that
        multipliers near 1 need).
    """

    def rhs(t: float, phi: Array) -> Array:
        return (np.asarray(a_of_t(t), dtype=float) @ phi.reshape(n, n)).reshape(-1)

    sol = scipy.integrate.solve_ivp(rhs, (0.0, period), np.eye(n).reshape(-1), method="DOP853",
                                    rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"monodromy: integration failed: {sol.message}")
    return sol.y[:, -1].reshape(n, n)


def _fourier_coefficients(a_samples: Array, order: int) -> dict[int, CArray]:
    """Â_p, |p| ≤ order, of A sampled at m equally spaced times t_s = s T/m.

    Coefficients with |p| > m/2 are not resolved by the samples and are zero; at p = ±m/2
    (m even) the Nyquist coefficient is split evenly between +p and −p, as in the real
    trigonometric interpolant.
    """
    m = a_samples.shape[0]
    c = np.fft.fft(a_samples, axis=0) / m
    out: dict[int, CArray] = {}
    for p in range(-order, order + 1):
        if 2 * abs(p) < m:
            out[p] = c[p % m]
        elif 2 * abs(p) == m:
            out[p] = 0.5 * c[m // 2]
        else:
            out[p] = np.zeros_like(c[0])
    return out


def hill_matrix(a_samples: ArrayLike, omega: float, harmonics: int) -> CArray:
    """The Hill matrix of ẏ = A(t) y over harmonics −H … H (blocks ordered by k).

    Block (k, j) is Â_{k−j} − i k ω δ_kj I (see the module docstring).
    """
    a = np.asarray(a_samples, dtype=float)
    n = a.shape[1]
    h = int(harmonics)
    coef = _fourier_coefficients(a, 2 * h)
    size = 2 * h + 1
    mat = np.zeros((size * n, size * n), dtype=complex)
    for bk, k in enumerate(range(-h, h + 1)):
        for bj, j in enumerate(range(-h, h + 1)):
            mat[bk * n:(bk + 1) * n, bj * n:(bj + 1) * n] = coef[k - j]
        mat[bk * n:(bk + 1) * n, bk * n:(bk + 1) * n] -= 1j * k * omega * np.eye(n)
    return mat


def hill_exponents(a_samples: ArrayLike, omega: float, harmonics: int, *,
                   selection: str = "weight") -> CArray:
    """Floquet exponents of ẏ = A(t) y by Hill's method.

    Parameters
    ----------
    a_samples
        A at m equally spaced times t_s = s T/m, s = 0 … m − 1, over one period T = 2π/ω,
        shape (m, n, n). Its harmonics up to 2H enter the Hill matrix, so m > 4H resolves
        them all (fewer samples drop the unresolved ones, see :func:`hill_matrix`).
    omega
        The fundamental frequency ω = 2π/T.
    harmonics
        H: the Floquet solution's periodic factor is truncated to harmonics −H … H.
    selection
        "weight" (default): the n eigenvalues whose eigenvectors have the largest share of
        their norm on the central block k = 0 (Lazarus & Thomas 2010), at most one copy
        ρ + i k ω of each exponent; "strip": the n
        eigenvalues with imaginary part in (−ω/2, ω/2] with the smallest |Im|.

    Returns
    -------
    (n,) complex exponents ρ (defined modulo iω).
    """
    a = np.asarray(a_samples, dtype=float)
    n = a.shape[1]
    h = int(harmonics)
    vals, vecs = np.linalg.eig(hill_matrix(a, omega, h))
    if selection == "weight":
        central = vecs[h * n:(h + 1) * n, :]
        weight = np.sum(np.abs(central) ** 2, axis=0) / np.sum(np.abs(vecs) ** 2, axis=0)
        keep = _one_per_family(vals, np.argsort(-weight, kind="stable"), omega, n)
    elif selection == "strip":
        im = vals.imag
        inside = np.flatnonzero((im > -0.5 * omega) & (im <= 0.5 * omega))
        keep = inside[np.argsort(np.abs(im[inside]), kind="stable")][:n]
        if keep.size < n:
            raise RuntimeError(f"hill_exponents: only {keep.size} of {n} exponents in the "
                               "strip (−ω/2, ω/2]")
    else:
        raise ValueError(f"hill_exponents: unknown selection {selection!r}")
    return vals[keep]


def _one_per_family(vals: CArray, order: NDArray[np.int64], omega: float, n: int
                    ) -> NDArray[np.int64]:
    """The first n of ``order`` (indices into vals) no two of which are copies ρ, ρ + i k ω,
    k ≠ 0, of one exponent (to CONGRUENT · ω).

    By weight alone, two copies of one exponent can outrank the other exponent's best copy:
    in a parametric resonance at ω/2 (or ω) the exponents ±σ + i ω/2 have copies −σ ± i ω/2
    that are both about as central, and taking both gives the multiplier −e^{−σT} twice
    instead of −e^{±σT}. Copies are skipped; if fewer than n indices remain (exponents that
    genuinely coincide modulo iω, at the boundary itself), the skipped ones fill up, in order.
    """
    chosen: list[int] = []
    skipped: list[int] = []
    tol = CONGRUENT * omega
    for i in order:
        copy = False
        for j in chosen:
            d = vals[i] - vals[j]
            k = round(d.imag / omega)
            if k != 0 and abs(d.real) <= tol and abs(d.imag - k * omega) <= tol:
                copy = True
                break
        (skipped if copy else chosen).append(int(i))
        if len(chosen) == n:
            break
    return np.array((chosen + skipped)[:n], dtype=np.int64)


def hill_multipliers(a_samples: ArrayLike, omega: float, harmonics: int, *,
                     selection: str = "weight") -> CArray:
    """Floquet multipliers exp(ρ · 2π/ω) of :func:`hill_exponents`' ρ, sorted by modulus,
    largest first."""
    rho = hill_exponents(a_samples, omega, harmonics, selection=selection)
    mu = np.exp(rho * (2.0 * np.pi / omega))
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def dominant_multipliers(action: Callable[[Array], ArrayLike], n: int, count: int, *,
                         basis: ArrayLike | None = None, tol: float = 0) -> CArray:
    """The ``count`` largest-modulus eigenvalues of the linear map v ↦ action(v).

    Parameters
    ----------
    action
        v (n,) -> M v (n,), e.g. a finite-difference Jacobian of a period map.
    n
        The dimension of v.
    count
        How many eigenvalues.
    basis
        (n, r) with orthonormal columns B: the eigenvalues of Bᵀ M B, the map restricted to
        the subspace range(B) (exactly M's eigenvalues on it when range(B) is invariant under
        M, e.g. when the removed directions are constraint directions the map leaves).
    tol
        Relative accuracy for ARPACK (0: machine precision).

    Returns
    -------
    (count,) complex, sorted by modulus, largest first.

    Notes
    -----
    Implicitly restarted Arnoldi (ARPACK through :func:`scipy.sparse.linalg.eigs`) with the
    map as a LinearOperator; ARPACK needs count < r − 1 (r = n without a basis), so for larger
    counts the r × r matrix is formed column by column and all its eigenvalues taken.
    """
    if basis is None:
        b = None
        r = n

        def matvec(v: Array) -> Array:
            return np.asarray(action(np.asarray(v, dtype=float).reshape(-1)), dtype=float)
    else:
        b = np.asarray(basis, dtype=float)
        if b.shape[0] != n:
            raise ValueError(f"dominant_multipliers: basis has {b.shape[0]} rows, need {n}")
        r = b.shape[1]

        def matvec(v: Array) -> Array:
            w = np.asarray(action(b @ np.asarray(v, dtype=float).reshape(-1)), dtype=float)
            return b.T @ w

    if not 0 < count <= r:
        raise ValueError(f"dominant_multipliers: need 0 < count <= {r}, got {count}")
    if count >= r - 1:
        mat = np.column_stack([matvec(e) for e in np.eye(r)])
        return multipliers(mat)[:count]
    op = spla.LinearOperator((r, r), matvec=matvec, dtype=float)
    # a fixed start vector makes the result reproducible
    v0 = np.ones(r) / np.sqrt(r)
    mu = spla.eigs(op, k=count, which="LM", tol=tol, v0=v0, return_eigenvectors=False)
    mu = np.asarray(mu, dtype=complex)
    return mu[np.argsort(-np.abs(mu), kind="stable")]
