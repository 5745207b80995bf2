"""Linearization about a (relative) equilibrium and its eigen-analysis, for any model.

**Linearization.** About an equilibrium (q*, λ*) at time t (:mod:`solver.equilibrium`), the
integrators' equations M q̈ + A ẋ + ∇V − f + Gᵀλ = 0, C = 0 (A the first-order mass, acting on
the rates of the first-order states) perturb to

    M δq̈ + (A + D) δq̇ + K0 δq + G0ᵀ δλ = 0,      G0 δq = 0,

with D = −∂f/∂v and K0 = ∇²V + Σ λ*_r ∇²C_r − ∂f/∂q (the KKT blocks K, H, Dq), all at
(q*, v*, t). At a **relative equilibrium** (the model spinning rigidly at Ω about a fixed axis)
the perturbations are written in the rotating frame, δq = R(Ωt) δξ, with R turning every
second-order 3-vector (positions and directors alike; algebraic and first-order unknowns are
scalars and do not turn). Then δq̇ = R(δξ̇ + Ω̂δξ), δq̈ = R(δξ̈ + 2Ω̂δξ̇ + Ω̂²δξ), where Ω̂ applies
the skew matrix of Ω to each 3-vector. Every body and beam has a mass matrix E ⊗ I3, which
commutes with R, and the steady model is invariant under the spin (checked by
:func:`solver.equilibrium.equilibrium`), so multiplying by Rᵀ leaves constant coefficients:

    M δξ̈ + C δξ̇ + K δξ + G0ᵀ δμ = 0,      G0 δξ = 0,
    C = D + A + 2 M Ω̂                      (damping, first-order mass, gyroscopic),
    K = K0 + M Ω̂² + D Ω̂                    (stiffness, centrifugal softening, damping in
                                             rotation).

Nonholonomic rows A_n(q) q̇ = 0 perturb to A_n (δξ̇ + Ω̂δξ) + ∂(A_n v*)/∂q δξ = 0 and enter
with their own multipliers.

**Eigen-analysis.** The holonomic rows are eliminated with a basis Z of the null space of G0,
δξ = Z η (QR of G0ᵀ). The reduced matrices Zᵀ M Z etc. may be singular (the massless director
d1 of a beam, bodies of zero inertia whose rotation follows from joints, massless nodes), and
stiffness and inertia may be strongly graded (a beam's EA against its EI), so the eigenvalues
are computed through the spectral transformation θ = 1/(s − s0) with a small negative shift
s0: the low modes become the largest θ and keep full relative accuracy, missing inertia maps to
θ = 0 (dropped as infinite), and no inverse of the mass matrix is formed. Undamped,
non-gyroscopic symmetric problems use the symmetric form (Cholesky of K + δ² M, ``eigh``);
all others the first-order descriptor pencil (η, η̇, ν), densely, or by shift-invert Arnoldi
when only a few modes of a large model are asked for. Rigid-body modes at the shift would
dominate the transformed problem, so the shift is moved next to the lowest moving mode in a
second pass. A pencil that is singular at every shift has directions that appear in no
equation (massless *and* unrestrained): they are removed and counted first, then QZ.
Eigenvalues s are reported once per complex-conjugate pair (Im s > 0) and once per real root;
|s| below ``zero_tol`` times the reference frequency √(‖ZᵀKZ‖/‖ZᵀMZ‖) are rigid-body
(neutral) modes, reported as 0 Hz once per independent shape. Mode shapes are returned in the
full coordinates δξ (rotating frame), so a mode can be classified by which unknowns move
(:meth:`Modes.fractions`); within a cluster of equal eigenvalues (flap and lag of a round beam
at rest) the basis is aligned with the coordinates, so it is reproducible.

Models are assumed small (dense matrices, up to a few thousand unknowns: a spinning cantilever
of 2184 unknowns takes about 8 s for all its 1080 modes, 3 s for the lowest ten, on 2 cores).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from solver.bodies import PrescribedBody
from solver.equilibrium import Equilibrium, Spin, SpinField, equilibrium, static_blocks
from solver.system import System

Array = NDArray[np.float64]
SHIFT = 1e-3  # |σ0|: shift of the spectral transformation (units of the reference frequency)
INFINITE_TOL = 1e-13  # |θ| (relative to the largest) below which an eigenvalue is infinite
SINGULAR_TOL = 1e-15  # reciprocal condition of a shifted pencil taken as singular
UNDETERMINED_TOL = 1e-12  # relative singular value of a direction that enters no equation
DEGENERATE_TOL = 1e-7  # relative spread of eigenvalues taken as one (degenerate) cluster
ARNOLDI_MIN = 600  # companion size from which a few lowest modes are found by Arnoldi


@dataclass
class Linearization:
    """Constant-coefficient linear model about a (relative) equilibrium (rotating frame).

    M δξ̈ + C δξ̇ + K δξ + Gᵀ δμ + A_nᵀ δν = 0,  G δξ = 0,  A_n δξ̇ + B_n δξ = 0.

    Attributes
    ----------
    M
        Mass matrix (n × n; kg, kg·m², per unknown units).
    C
        Damping (−∂f/∂v), first-order mass and gyroscopic 2MΩ̂ (n × n; N·s/m and alike).
    K
        Stiffness: potential Hessian, λ-weighted constraint Hessian, −∂f/∂q, and the rotating
        frame terms MΩ̂² + DΩ̂ (n × n; N/m and alike).
    G
        Holonomic constraint Jacobian (m_h × n).
    Z
        Orthonormal basis of the null space of G (n × k): the admissible perturbations.
    A_n, B_n
        Nonholonomic rows: coefficients of δξ̇ and δξ (m_n × n).
    q, lam, t, spin, system
        The equilibrium linearized about.
    """

    M: Array
    C: Array
    K: Array
    G: Array
    Z: Array
    A_n: Array
    B_n: Array
    q: Array
    lam: Array
    t: float
    spin: Spin | None
    system: System = field(repr=False)


def linearize(system: System, q: ArrayLike, lam: ArrayLike, t: float = 0.0,
              spin: Spin | None = None, *, fd_step: float | None = None) -> Linearization:
    """Linearize a system about an equilibrium (see the module docstring).

    Parameters
    ----------
    system
        Assembled system.
    q, lam
        Equilibrium configuration and holonomic multipliers (from
        :func:`solver.equilibrium.equilibrium`).
    t
        Time of the equilibrium (s).
    spin
        Spin of a relative equilibrium (rotating-frame perturbations), or ``None``.
    fd_step
        If given, K0 and D are central differences of ∇V − f + Gᵀλ with this step (units of
        the unknowns) instead of the elements' analytic Jacobians — a check for elements whose
        tangent is approximate (e.g. a rotational spring's Gauss–Newton stiffness away from
        its rest angle).

    Returns
    -------
    Linearization
        Dense matrices.
    """
    s = system
    n = s.n
    q = np.asarray(q, dtype=float).reshape(-1)
    lam = np.asarray(lam, dtype=float).reshape(-1)
    if q.shape != (n,) or lam.shape != (s.mh,):
        raise ValueError(f"q must have {n} entries and lam {s.mh} (got {q.size}, {lam.size})")
    fld = SpinField(s, spin)
    v = fld.velocity(q)
    g = s.jacobian_values(q, t)
    if fd_step is None:
        blocks, jv = static_blocks(s, q, v, lam, t, fld.acceleration(q))
        k0 = s.kkt(blocks)[:n, :n].toarray()
        d = -s.kkt({"Dv": jv})[:n, :n].toarray()
    else:
        k0, d = _finite_difference(s, q, v, lam, t, g, fd_step)
    # added masses (fluid apparent mass) join the mass matrix: M_eff = M − ∂f/∂a
    m_eff = s.M
    if s.block_sizes["Da"]:
        fa = s.acceleration_jacobian(q, v, t, fld.acceleration(q))
        m_eff = (s.M - s.kkt({"Da": fa})[:n, :n]).tocsr()
    mw = m_eff @ fld.W  # sparse products: M and Ω̂ are block diagonal
    gm = sp.csr_matrix((g, (s.G_rows, s.G_cols)), shape=(s.mh, n)).toarray()
    c = d + s.A1.toarray() + 2.0 * mw.toarray()
    k = k0 + (mw @ fld.W).toarray() + (fld.W.T @ d.T).T
    w = fld.W.toarray() if s.mn else None
    if s.mn:
        a_vals = s.nonholonomic_values(q)
        rows, cols = s.A_rows - s.mh, s.A_cols
        a_n = sp.csr_matrix((a_vals, (rows, cols)), shape=(s.mn, n)).toarray()
        da = sp.csr_matrix((s.nonholonomic_derivative(q, v), (rows, cols)),
                           shape=(s.mn, n)).toarray()
        b_n = a_n @ w + da
    else:
        a_n = b_n = np.zeros((0, n))
    return Linearization(M=m_eff.toarray(), C=c, K=k, G=gm, Z=_null_space(gm, n), A_n=a_n, B_n=b_n,
                         q=q.copy(), lam=lam.copy(), t=float(t), spin=spin, system=s)


def _null_space(g: Array, n: int) -> Array:
    """Orthonormal basis of {x : G x = 0} (rows scaled to unit norm first, so the rank
    decision does not depend on the units of the rows)."""
    if g.shape[0] == 0:
        return np.eye(n)
    nrm = np.linalg.norm(g, axis=1)
    gs = g[nrm > 0] / nrm[nrm > 0, None]
    if gs.shape[0] == 0:
        return np.eye(n)
    # QR of Gᵀ (cheaper than the SVD); the constraints of a model that integrates are
    # independent, so plain QR suffices unless R shows a (near) dependent row, then the
    # rank-revealing pivoted QR decides
    m = gs.shape[0]
    if m <= n:
        q, r = sla.qr(gs.T, mode="full", check_finite=False)
        d = np.abs(np.diag(r))
        if d.min(initial=np.inf) > 1e-8 * d.max(initial=0.0):
            return np.ascontiguousarray(q[:, m:])
    q, r, _ = sla.qr(gs.T, mode="full", pivoting=True, check_finite=False)
    d = np.abs(np.diag(r))
    rank = int(np.count_nonzero(d > 1e-10 * d.max(initial=0.0)))
    return np.ascontiguousarray(q[:, rank:])


def _finite_difference(s: System, q: Array, v: Array, lam: Array, t: float, g: Array,
                       h: float) -> tuple[Array, Array]:
    """(∂r/∂q, ∂r/∂v) of r = ∇V − f + Gᵀλ by central differences (λ fixed)."""
    n = s.n

    def r(qq: Array, vv: Array) -> Array:
        return s.gradient(qq) - s.applied(qq, vv, t) + s.gmul_T(s.jacobian_values(qq, t), lam)

    k0 = np.zeros((n, n))
    d = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        k0[:, j] = (r(q + e, v) - r(q - e, v)) / (2 * h)
        d[:, j] = (r(q, v + e) - r(q, v - e)) / (2 * h)
    return k0, d


# ---------------------------------------------------------------------- eigen-analysis
@dataclass
class Modes:
    """Eigen-analysis of a :class:`Linearization`, sorted by undamped natural frequency.

    Attributes
    ----------
    eigenvalues
        s (1/s, complex): one per complex pair (Im s > 0) or real root; exactly 0 for
        rigid-body modes.
    frequency
        Undamped natural frequency |s| / 2π (Hz).
    damped_frequency
        |Im s| / 2π (Hz).
    damping_ratio
        −Re s / |s| (0 for rigid-body modes; negative: unstable).
    shapes
        Mode shapes δξ in the full coordinates (n × number of modes, complex), largest
        component 1. Within a cluster of equal eigenvalues the basis is made reproducible
        and aligned with the coordinates (see ``_canonical``).
    n_infinite
        Eigenvalues dropped as infinite (missing inertia: massless directions, and in the
        first-order form one more per constraint-like row); ``None`` when only the lowest
        ``n`` modes were computed.
    n_undetermined
        Directions removed because no equation involves them (massless and unrestrained).
    linearization, equilibrium
        What the modes were computed from (``equilibrium`` only from
        :func:`natural_frequencies`).
    """

    eigenvalues: NDArray[np.complex128]
    frequency: Array
    damped_frequency: Array
    damping_ratio: Array
    shapes: NDArray[np.complex128]
    n_infinite: int | None
    n_undetermined: int
    linearization: Linearization = field(repr=False)
    equilibrium: Equilibrium | None = field(default=None, repr=False)

    def __len__(self) -> int:
        return len(self.eigenvalues)

    @property
    def omega(self) -> Array:
        """Undamped natural circular frequencies |s| (rad/s)."""
        return np.abs(self.eigenvalues)

    def fractions(self, j: int, kinetic: bool = True) -> dict[str, float]:
        """Share of mode ``j`` carried by each owner of unknowns (bodies, beams, scalars,
        first-order elements): of the kinetic energy ½ φᴴ M φ by default, or of the squared
        amplitude |φ|² (every unknown, massless ones too) with ``kinetic=False``."""
        s = self.linearization.system
        phi = self.shapes[:, j]
        if kinetic:
            mphi = self.linearization.M @ phi
            weight = np.real(np.conj(phi) * mphi)
        else:
            weight = np.abs(phi) ** 2
        out: dict[str, float] = {}
        for b in s.layout.blocks:
            o = s.offset[b.owner]
            name = getattr(b.owner, "name", "?")
            out[name] = out.get(name, 0.0) + float(weight[o : o + b.size].sum())
        total = sum(out.values())
        return {k: (v / total if total > 0 else 0.0) for k, v in out.items()}


def modes(lin: Linearization, n: int | None = None, *, zero_tol: float = 1e-6) -> Modes:
    """Eigenvalues and mode shapes of a linearization (see the module docstring).

    Parameters
    ----------
    lin
        From :func:`linearize`.
    n
        Return only the ``n`` lowest modes (all by default; for large models a given ``n``
        is much cheaper: a partial symmetric eigensolver or shift-invert Arnoldi).
    zero_tol
        |s| below ``zero_tol`` times the reference frequency √(‖ZᵀKZ‖/‖ZᵀMZ‖) is a rigid-body
        mode (0 Hz).

    Returns
    -------
    Modes
    """
    if n is not None and n < 1:
        raise ValueError(f"n = {n!r} must be ≥ 1 (or None for all modes)")
    z = lin.Z
    nfull = lin.M.shape[0]
    if z.shape[1] == 0:
        return _empty(lin, nfull)
    mt, ct, kt = (_sandwich(z, x) for x in (lin.M, lin.C, lin.K))
    at, bt = lin.A_n @ z, lin.B_n @ z
    nm, nc, nk = (float(np.abs(x).max(initial=0.0)) for x in (mt, ct, kt))
    # reference circular frequency: time is scaled by it so the pencil is O(1)
    if nk > 0 and nm > 0:
        w_ref = np.sqrt(nk / nm)
    elif nc > 0 and nm > 0:
        w_ref = nc / nm
    elif nk > 0 and nc > 0:
        w_ref = nk / nc
    else:
        w_ref = 1.0
    fscale = max(nk, nc * w_ref, nm * w_ref**2) or 1.0
    mh, ch, kh = mt * (w_ref**2 / fscale), ct * (w_ref / fscale), kt / fscale
    nhs = max(float(np.abs(bt).max(initial=0.0)), w_ref * float(np.abs(at).max(initial=0.0)))
    nhs = nhs or 1.0
    ah, bh = at * (w_ref / nhs), bt / nhs
    solved = _shift_invert(mh, ch, kh, ah, ah.T, bh, n, zero_tol)
    n_undet = 0
    if solved is None:
        # the pencil is singular: remove the directions no equation involves (massless and
        # unrestrained), then QZ
        basis, rows, n_undet = _determined(mh, ch, kh, ah, bh)
        aht = ah.T  # the nonholonomic forces in the η-equations
        if basis is not None:
            mh, ch, kh = (rows.T @ x @ basis for x in (mh, ch, kh))
            aht = rows.T @ aht
            ah, bh = ah @ basis, bh @ basis
            z = z @ basis
        solved = _shift_invert(mh, ch, kh, ah, aht, bh, n, zero_tol)
        if solved is None:
            solved = _qz(*_descriptor(mh, ch, kh, ah, aht, bh), z.shape[1])
    sig, vec, n_inf = solved
    s_all = sig * w_ref
    shapes = z @ vec
    return _assemble(lin, s_all, shapes, n_inf, n_undet, zero_tol * w_ref, n)


def _sandwich(z: Array, x: Array) -> Array:
    """Zᵀ X Z, through a sparse X when X is mostly zeros (mass and gyroscopic matrices)."""
    if np.count_nonzero(x) < 0.05 * x.size:
        return z.T @ np.asarray(sp.csr_matrix(x) @ z)
    return z.T @ x @ z


def _determined(mh, ch, kh, ah, bh):
    """Bases of the determined directions (columns) and equations (rows), or ``None`` if
    every direction enters some equation. Returns (basis, rows, number removed)."""
    k = mh.shape[0]
    cols = np.vstack([mh, ch, kh, ah, bh])
    rows = np.hstack([mh, ch, kh, ah.T])
    _, sc, vt = sla.svd(cols, full_matrices=False)
    u, sr, _ = sla.svd(rows, full_matrices=False)
    rc = int(np.count_nonzero(sc > UNDETERMINED_TOL * max(sc.max(initial=0.0), 1e-300)))
    rr = int(np.count_nonzero(sr > UNDETERMINED_TOL * max(sr.max(initial=0.0), 1e-300)))
    if rc == k and rr == k:
        return None, None, 0
    if rc != rr:
        raise ValueError(f"the linearized model is singular: {k - rc} directions enter no "
                         f"equation but {k - rr} equations are empty")
    return vt[:rc].T, u[:, :rr], k - rc


def _shift_invert(mh, ch, kh, ah, aht, bh, n, zero):
    """Eigenvalues by the spectral transformation θ = 1/(σ − σ0) with a small shift σ0 < 0
    (normalized units): the low modes become the largest θ and keep full relative accuracy
    even when stiffness or inertia are strongly graded (a beam's EA against its EI, tiny
    rotary inertia) — unlike an inverse of the mass matrix; missing inertia maps to θ = 0
    (dropped as infinite). Undamped symmetric problems use K + δ² M = L Lᵀ and ``eigh`` of
    L⁻¹ M L⁻ᵀ; all others the descriptor pencil. Returns (σ, shapes in η, number dropped as
    infinite, or None when only some modes were computed) or ``None`` if the pencil is
    singular at the shifts."""
    k = mh.shape[0]
    symmetric = (not len(ah) and np.abs(ch).max(initial=0.0) <= 1e-13
                 and np.abs(kh - kh.T).max(initial=0.0) <= 1e-11
                 and np.abs(mh - mh.T).max(initial=0.0) <= 1e-11)
    ab = None if symmetric else _descriptor(mh, ch, kh, ah, aht, bh)

    def solve(shift: float):
        if symmetric:
            out = _symmetric(0.5 * (mh + mh.T), 0.5 * (kh + kh.T), shift, n)
            if out is not None:
                return out
        pencil = ab if ab is not None else _descriptor(mh, ch, kh, ah, aht, bh)
        for sigma0 in (-shift, -shift * 1.6180339887):
            out = _general(*pencil, sigma0, k, n)
            if out is not None:
                return out
        return None

    out = solve(SHIFT)
    if out is None:
        return None
    # rigid-body modes (σ = 0) at distance δ from the shift dominate the transformed problem,
    # costing the other modes a relative accuracy of about ε/δ²: shift again, to half the
    # lowest nonzero |σ|, when it is far above δ
    mag = np.abs(out[0])
    moving = mag[mag > zero]
    if np.any(mag <= zero) and len(moving) and moving.min() > 10 * SHIFT:
        again = solve(0.5 * float(moving.min()))
        if again is not None:
            out = again
    return out


def _symmetric(mh: Array, kh: Array, shift: float, n: int | None):
    """Undamped symmetric K φ = σ² M φ with K + δ² M positive definite (δ = ``shift``)."""
    d2 = shift**2
    try:
        low = np.linalg.cholesky(kh + d2 * mh)
    except np.linalg.LinAlgError:
        return None  # unstable (K indefinite) or massless and unrestrained: general path
    piv = np.diag(low) ** 2
    if piv.min() <= SINGULAR_TOL * piv.max():
        return None
    x = sla.solve_triangular(low, mh, lower=True, check_finite=False)
    smat = sla.solve_triangular(low, x.T, lower=True, check_finite=False)  # L⁻¹ M L⁻ᵀ
    smat = 0.5 * (smat + smat.T)
    k = mh.shape[0]
    partial = n is not None and n < k
    if partial:  # the largest θ are the lowest modes
        theta, u = sla.eigh(smat, subset_by_index=[k - n, k - 1], check_finite=False)
    else:
        theta, u = np.linalg.eigh(smat)
    finite = theta > INFINITE_TOL * max(float(np.abs(theta).max(initial=0.0)), 1e-300)
    n_inf = None if partial else int(np.count_nonzero(~finite))
    mu = 1.0 / theta[finite] - d2  # σ²
    phi = sla.solve_triangular(low.T, u[:, finite], lower=False, check_finite=False)
    sig = np.where(mu < 0, np.sqrt(np.abs(mu)) + 0j, 1j * np.sqrt(np.abs(mu)))
    return sig, phi, n_inf


def _descriptor(mh, ch, kh, ah, aht, bh) -> tuple[Array, Array]:
    """First-order descriptor pencil σ B y = A y for y = (η, u = η', ν)."""
    k, mn = mh.shape[0], ah.shape[0]
    eye, zk = np.eye(k), np.zeros((k, k))
    zn, znn = np.zeros((k, mn)), np.zeros((mn, mn))
    a = np.block([[zk, eye, zn], [-kh, -ch, -aht], [-bh, -ah, znn]])
    b = np.block([[eye, zk, zn], [zk, mh, zn], [zn.T, zn.T, znn]])
    return a, b


def _general(a: Array, b: Array, sigma0: float, k: int, n: int | None):
    """Shift-invert of the descriptor pencil: eigenvalues θ of (A − σ0 B)⁻¹ B, densely or,
    for a few modes of a large model, by Arnoldi (ARPACK)."""
    size = a.shape[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error", sla.LinAlgWarning)
        try:
            shifted = a - sigma0 * b
            lu = sla.lu_factor(shifted, check_finite=False)
        except (sla.LinAlgWarning, ValueError, sla.LinAlgError):
            return None
    rcond, info = _gecon(lu[0], float(np.abs(shifted).sum(axis=0).max()))
    if info or not rcond > SINGULAR_TOL:
        return None
    if n is not None and size > ARNOLDI_MIN:
        op = spla.LinearOperator((size, size), dtype=float,
                                 matvec=lambda x: sla.lu_solve(lu, b @ x, check_finite=False))
        nev = min(2 * n + 8, size - 2)
        try:
            theta, y = spla.eigs(op, k=nev, which="LM", tol=1e-13)
        except (spla.ArpackError, spla.ArpackNoConvergence):
            theta = None
        if theta is not None:
            big = np.abs(theta) > INFINITE_TOL * np.abs(theta).max()
            sig = sigma0 + 1.0 / theta[big]
            reach = 1.0 / np.abs(theta).min()  # every σ not found is at least this far
            mag = np.sort(np.abs(sig))
            if len(mag) and mag[min(2 * n, len(mag)) - 1] + abs(sigma0) < reach:
                return sig, y[:k, big], None
    theta, y = np.linalg.eig(sla.lu_solve(lu, b, check_finite=False))
    finite = np.abs(theta) > INFINITE_TOL * max(float(np.abs(theta).max(initial=0.0)), 1e-300)
    sig = sigma0 + 1.0 / theta[finite]
    if np.abs(sig - sigma0).min(initial=np.inf) < 1e-6 * abs(sigma0):
        return None  # the shift sits on an eigenvalue: try another
    return sig, y[:k, finite], int(np.count_nonzero(~finite))


def _gecon(lu_matrix: Array, anorm: float) -> tuple[float, int]:
    """Reciprocal condition number (1-norm) of a matrix from its LU factors (LAPACK gecon)."""
    gecon = sla.get_lapack_funcs("gecon", (lu_matrix,))
    rcond, info = gecon(lu_matrix, anorm, norm="1")
    return float(rcond), int(info)


def _qz(a: Array, b: Array, k: int):
    """The descriptor pencil by QZ (last resort, for singular pencils). Returns (σ, shapes in
    η, number dropped)."""
    ab, vec = sla.eig(a, b, homogeneous_eigvals=True)
    alpha, beta = ab
    big = np.maximum(np.abs(alpha), np.abs(beta))
    finite = (np.abs(beta) > INFINITE_TOL * np.maximum(np.abs(alpha), 1e-300)) & (
        big > INFINITE_TOL)
    sig = alpha[finite] / beta[finite]
    return sig, vec[:k, finite], int(np.count_nonzero(~finite))


def _assemble(lin: Linearization, s_all, shapes, n_inf: int | None, n_undet: int, zero: float,
              n: int | None) -> Modes:
    """One entry per complex pair or real root, rigid-body modes merged by shape, sorted."""
    s_all = np.asarray(s_all, dtype=complex)
    mag = np.abs(s_all)
    is_zero = mag <= zero
    im_tol = 1e-9 * np.maximum(mag, zero)
    keep = ~is_zero & ((s_all.imag > im_tol) | (np.abs(s_all.imag) <= im_tol))
    eig = [s_all[keep]]
    shp = [shapes[:, keep]]
    if np.any(is_zero):  # rigid-body modes: one per independent shape (Jordan pairs merged)
        zs = shapes[:, is_zero]
        zs = zs / np.maximum(np.linalg.norm(zs, axis=0), 1e-300)
        u, sv, _ = np.linalg.svd(zs, full_matrices=False)
        r = int(np.count_nonzero(sv > 1e-4 * sv.max()))
        eig.append(np.zeros(r, dtype=complex))
        shp.append(u[:, :r])
    s_out = np.concatenate(eig)
    shapes = np.concatenate(shp, axis=1)
    s_out = np.where(np.abs(s_out.imag) <= 1e-9 * np.maximum(np.abs(s_out), zero),
                     s_out.real + 0j, s_out)
    order = np.lexsort((np.abs(s_out.imag), np.abs(s_out)))
    s_out, shapes = s_out[order], shapes[:, order]
    shapes = _canonical(s_out, shapes, zero)
    if n is not None:
        s_out, shapes = s_out[:n], shapes[:, :n]
    shapes = _normalized(shapes)
    mag = np.abs(s_out)
    zeta = np.where(mag > 0, -s_out.real / np.where(mag > 0, mag, 1.0), 0.0) + 0.0
    return Modes(eigenvalues=s_out, frequency=mag / (2 * np.pi),
                 damped_frequency=np.abs(s_out.imag) / (2 * np.pi), damping_ratio=zeta,
                 shapes=shapes, n_infinite=n_inf, n_undetermined=n_undet, linearization=lin)


def _canonical(s: NDArray[np.complex128], shapes: NDArray, zero: float) -> NDArray:
    """A reproducible basis for each cluster of (numerically) equal eigenvalues — flap and lag
    of a round beam at rest, the x, y, z of an isotropic spring, rigid-body modes — whose
    eigenvectors are otherwise an arbitrary mix: the c coordinates that move most (QR with
    column pivoting) each get one vector that is 1 there and 0 at the others, so the shapes
    align with the coordinates whenever the modes can be told apart by them."""
    out = np.array(shapes, dtype=complex)
    i = 0
    while i < len(s):
        j = i + 1
        tol = DEGENERATE_TOL * max(abs(s[i]), zero)
        while j < len(s) and abs(s[j] - s[i]) <= tol:
            j += 1
        if j - i > 1:
            phi = out[:, i:j]
            sub = phi[_pivot_rows(phi), :]
            if np.linalg.cond(sub) < 1e8:
                out[:, i:j] = phi @ np.linalg.inv(sub)
        i = j
    return out


def _pivot_rows(phi: NDArray) -> list[int]:
    """The rows (coordinates) QR with column pivoting of φᵀ would pick: greedily the row of
    largest norm, then the largest after removing its direction."""
    a = np.array(phi, dtype=complex)
    rows = []
    for _ in range(phi.shape[1]):
        i = int(np.argmax(np.einsum("ij,ij->i", a, a.conj()).real))
        rows.append(i)
        v = a[i] / max(np.linalg.norm(a[i]), 1e-300)
        a -= np.outer(a @ v.conj(), v)
    return rows


def _normalized(shapes: NDArray) -> NDArray[np.complex128]:
    """Scale each shape so its largest component is 1 (real)."""
    shapes = np.asarray(shapes, dtype=complex)
    if shapes.size == 0:
        return shapes
    i = np.argmax(np.abs(shapes), axis=0)
    piv = shapes[i, np.arange(shapes.shape[1])]
    return shapes / np.where(np.abs(piv) > 0, piv, 1.0)[None, :]


def _empty(lin: Linearization, nfull: int) -> Modes:
    e = np.zeros(0)
    return Modes(eigenvalues=e.astype(complex), frequency=e, damped_frequency=e,
                 damping_ratio=e, shapes=np.zeros((nfull, 0), dtype=complex), n_infinite=0,
                 n_undetermined=0, linearization=lin)


# ---------------------------------------------------------------------- one call
def natural_frequencies(model, spin: Spin | None = None, *, t: float = 0.0,
                        q0: ArrayLike | None = None, n: int | None = None, tol: float = 1e-10,
                        max_iter: int = 50, zero_tol: float = 1e-6,
                        fd_step: float | None = None) -> Modes:
    """Equilibrium, linearization and modes of a model in one call.

    Parameters
    ----------
    model
        A :class:`solver.model.Model` or an assembled :class:`solver.system.System`.
    spin
        Steady spin (rotating-frame modes of a relative equilibrium); required when the model
        has a moving prescribed body (e.g. ``Spin.from_body(hub)``).
    t, q0, tol, max_iter
        Passed to :func:`solver.equilibrium.equilibrium` (``t`` may be a continuation
        sequence; the modes are those at its last time).
    n, zero_tol
        Passed to :func:`modes`.
    fd_step
        Passed to :func:`linearize`.

    Returns
    -------
    Modes
        With ``equilibrium`` set.

    Raises
    ------
    RuntimeError
        If the equilibrium does not converge (the message names the culprit).
    """
    s = model if isinstance(model, System) else System(model)
    if spin is None:
        moving = [b.name for b in s.bodies if isinstance(b, PrescribedBody) and b.moves()]
        if moving:
            raise ValueError(f"prescribed bod{'ies' if len(moving) > 1 else 'y'} "
                             f"{', '.join(map(repr, moving))} move: modes need a steady "
                             "spin, pass spin=Spin(rate, axis, origin) or Spin.from_body(hub)")
    eq = equilibrium(s, t=t, q0=q0, spin=spin, tol=tol, max_iter=max_iter)
    if not eq.converged:
        raise RuntimeError(f"no equilibrium to linearize about: {eq.message}")
    lin = linearize(s, eq.q, eq.lam, eq.t, spin, fd_step=fd_step)
    out = modes(lin, n, zero_tol=zero_tol)
    out.equilibrium = eq
    return out
