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
δξ = Z η. The reduced matrices Zᵀ M Z etc. may be singular (the massless director d1 of a
beam, bodies of zero inertia whose rotation follows from joints), so the problem is solved as a
generalized eigenproblem, which puts the missing inertia at infinite eigenvalues, dropped.
Undamped, non-gyroscopic symmetric problems are solved as K φ = ω² M φ (symmetric-definite if
Zᵀ M Z is positive definite); all others in first-order (descriptor) form with the QZ
algorithm. Directions that appear in no equation at all (massless *and* unrestrained) are
removed first and counted. Eigenvalues s are reported once per complex-conjugate pair
(Im s > 0) and once per real root; |s| below ``zero_tol`` times the reference frequency
√(‖K‖/‖M‖) are rigid-body (neutral) modes, reported as 0 Hz once per independent shape.
Mode shapes are returned in the full coordinates δξ (rotating frame), so a mode can be
classified by which unknowns move (:meth:`Modes.fractions`).

Models are assumed small (dense matrices, up to a few thousand unknowns).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from solver.bodies import PrescribedBody
from solver.equilibrium import Equilibrium, Spin, SpinField, equilibrium
from solver.system import System

Array = NDArray[np.float64]
INFINITE_TOL = 1e-11  # |β| of a normalized pencil below which an eigenvalue is infinite
UNDETERMINED_TOL = 1e-12  # relative singular value of a direction that enters no equation


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
        blocks = {}
        if s.block_sizes["K"]:
            blocks["K"] = s.stiffness_values(q)
        jq, jv = s.applied_jacobians(q, v, t)
        if s.block_sizes["Dq"]:
            blocks["Dq"] = -jq
        if s.block_sizes["H"]:
            blocks["H"] = s.hessian_values(q, t, lam)
        k0 = s.kkt(blocks)[:n, :n].toarray()
        d = -s.kkt({"Dv": jv})[:n, :n].toarray()
    else:
        k0, d = _finite_difference(s, q, v, lam, t, g, fd_step)
    mass = s.M.toarray()
    w = fld.W.toarray()
    gm = sp.csr_matrix((g, (s.G_rows, s.G_cols)), shape=(s.mh, n)).toarray()
    c = d + s.A1.toarray() + 2.0 * mass @ w
    k = k0 + mass @ w @ w + d @ w
    if s.mn:
        a_vals = s.nonholonomic_values(q)
        rows, cols = s.A_rows - s.mh, s.A_cols
        a_n = sp.csr_matrix((a_vals, (rows, cols)), shape=(s.mn, n)).toarray()
        da = sp.csr_matrix((s.nonholonomic_derivative(q, v), (rows, cols)),
                           shape=(s.mn, n)).toarray()
        b_n = a_n @ w + da
    else:
        a_n = b_n = np.zeros((0, n))
    return Linearization(M=mass, C=c, K=k, G=gm, Z=_null_space(gm, n), A_n=a_n, B_n=b_n,
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
    return sla.null_space(gs, rcond=1e-10)


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
        component 1.
    n_infinite
        Eigenvalues dropped as infinite (missing inertia).
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
    n_infinite: int
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
        Return only the ``n`` lowest modes (all by default).
    zero_tol
        |s| below ``zero_tol`` times the reference frequency √(‖ZᵀKZ‖/‖ZᵀMZ‖) is a rigid-body
        mode (0 Hz).

    Returns
    -------
    Modes
    """
    z = lin.Z
    nfull = lin.M.shape[0]
    if z.shape[1] == 0:
        return _empty(lin, nfull)
    mt, ct, kt = z.T @ lin.M @ z, z.T @ lin.C @ z, z.T @ lin.K @ z
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
    # directions no equation involves (massless and unrestrained) are removed
    basis, rows, n_undet = _determined(mh, ch, kh, ah, bh)
    aht = ah.T  # the nonholonomic forces in the η-equations
    if basis is not None:
        mh, ch, kh = (rows.T @ x @ basis for x in (mh, ch, kh))
        aht = rows.T @ aht
        ah, bh = ah @ basis, bh @ basis
        z = z @ basis
    k = z.shape[1]
    scale_c = float(np.abs(ch).max(initial=0.0))
    symmetric = (np.allclose(mh, mh.T, rtol=0, atol=1e-12)
                 and np.allclose(kh, kh.T, rtol=0, atol=1e-12))
    if scale_c <= 1e-13 and not len(ah) and symmetric:
        sig, vec, n_inf = _undamped(mh, kh)
    else:
        sig, vec, n_inf = _first_order(mh, ch, kh, ah, aht, bh, k)
    s_all = sig * w_ref
    shapes = z @ vec
    return _assemble(lin, s_all, shapes, n_inf, n_undet, zero_tol * w_ref, n)


def _determined(mh, ch, kh, ah, bh):
    """Bases of the determined directions (columns) and equations (rows), or ``None`` if
    every direction enters some equation. Returns (basis, rows, number removed)."""
    k = mh.shape[0]
    cols = np.vstack([mh, ch, kh, ah, bh])
    rows = np.hstack([mh, ch, kh, ah.T])
    _, sc, vt = np.linalg.svd(cols, full_matrices=True)
    u, sr, _ = np.linalg.svd(rows, full_matrices=True)
    rc = int(np.count_nonzero(sc > UNDETERMINED_TOL * max(sc.max(initial=0.0), 1e-300)))
    rr = int(np.count_nonzero(sr > UNDETERMINED_TOL * max(sr.max(initial=0.0), 1e-300)))
    if rc == k and rr == k:
        return None, None, 0
    if rc != rr:
        raise ValueError(f"the linearized model is singular: {k - rc} directions enter no "
                         f"equation but {k - rr} equations are empty")
    return vt[:rc].T, u[:, :rr], k - rc


def _undamped(mh: Array, kh: Array) -> tuple[NDArray[np.complex128], NDArray, int]:
    """K φ = σ² M φ (symmetric): s = i σ per mode. Returns (s, shapes in η, dropped)."""
    try:
        cho = np.linalg.cholesky(mh)
        ok = np.diag(cho).min() > 1e-7 * np.diag(cho).max()
    except np.linalg.LinAlgError:
        ok = False
    if ok:
        mu, vec = sla.eigh(kh, mh)
        n_inf = 0
    else:
        ab, vec = sla.eig(kh, mh, homogeneous_eigvals=True)
        alpha, beta = ab
        finite = np.abs(beta) > INFINITE_TOL * np.maximum(np.abs(alpha), 1e-300)
        finite &= np.maximum(np.abs(alpha), np.abs(beta)) > INFINITE_TOL
        n_inf = int(np.count_nonzero(~finite))
        mu = np.real_if_close(alpha[finite] / beta[finite], tol=1e6)
        vec = vec[:, finite]
    mu = np.asarray(mu)
    s = np.where(np.isreal(mu) & (np.real(mu) < 0), np.sqrt(np.abs(mu)) + 0j,
                 1j * np.sqrt(mu.astype(complex)))
    return s, vec, n_inf


def _first_order(mh, ch, kh, ah, aht, bh, k):
    """Descriptor form y = (η, u = η', ν): σ B y = A y. Returns (σ, shapes in η, dropped)."""
    mn = ah.shape[0]
    eye, zk = np.eye(k), np.zeros((k, k))
    zn, znn = np.zeros((k, mn)), np.zeros((mn, mn))
    a = np.block([[zk, eye, zn], [-kh, -ch, -aht], [-bh, -ah, znn]])
    b = np.block([[eye, zk, zn], [zk, mh, zn], [zn.T, zn.T, znn]])
    ab, vec = sla.eig(a, b, homogeneous_eigvals=True)
    alpha, beta = ab
    big = np.maximum(np.abs(alpha), np.abs(beta))
    finite = (np.abs(beta) > INFINITE_TOL * np.maximum(np.abs(alpha), 1e-300)) & (
        big > INFINITE_TOL)
    sig = alpha[finite] / beta[finite]
    return sig, vec[:k, finite], int(np.count_nonzero(~finite))


def _assemble(lin: Linearization, s_all, shapes, n_inf: int, n_undet: int, zero: float,
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
    if n is not None:
        s_out, shapes = s_out[:n], shapes[:, :n]
    shapes = _normalized(shapes)
    mag = np.abs(s_out)
    zeta = np.where(mag > 0, -s_out.real / np.where(mag > 0, mag, 1.0), 0.0) + 0.0
    return Modes(eigenvalues=s_out, frequency=mag / (2 * np.pi),
                 damped_frequency=np.abs(s_out.imag) / (2 * np.pi), damping_ratio=zeta,
                 shapes=shapes, n_infinite=n_inf, n_undetermined=n_undet, linearization=lin)


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
