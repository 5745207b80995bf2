"""Static equilibria and relative equilibria (steady spin) of a model, by Newton's method.

A static equilibrium at time t solves, for the configuration q and the multipliers λ,

    ∇V(q) − f(q, 0, t) + G(q, t)ᵀλ = 0,      C(q, t) = 0,

the integrators' force balance (:mod:`solver.integrators`) with no motion: ∇V the gradient of
the potential (springs, gravity, beams), f the generalized forces (applied loads, dampers,
first-order right-hand sides), G = ∂C/∂q. Algebraic scalars (η, s) are ordinary unknowns, and
so are first-order states: a steady A ẋ = f has ẋ = 0, so their rows read f = 0 — the same
force-balance rows, with nothing to add.

A **relative equilibrium** is a motion in which the whole model turns rigidly at a constant
rate Ω about a fixed axis through a point o (:class:`Spin`): every second-order 3-vector of the
layout moves as a position, x(t) = o + R(Ωt)(x − o), or as a director, d(t) = R(Ωt) d
(:attr:`solver.state.StateBlock.positions` says which). At the instant t its velocities and
accelerations are

    v* = Ω̂ (x − o),  Ω̂ d;        a* = Ω̂ v*  (centripetal),

with Ω̂ the skew matrix of Ω n, and the balance gains the inertia term M a*:

    M a*(q) + ∇V(q) − f(q, v*(q), t) + G(q, t)ᵀλ = 0,      C(q, t) = 0.

Prescribed bodies that move (a hub made by :func:`solver.bodies.spinning`) must move with the
spin; those at rest (the ground) stay at rest, and whatever joins them to the rest of the model
must be symmetric about the axis. After convergence the steadiness is checked: the velocity
constraints G v* + ∂C/∂t = 0 must hold, and the whole model turned by one radian (and advanced
by the matching time) must still satisfy its constraints, with every potential gradient and
generalized force turned with it — gravity off the axis, a load fixed in space or a spring
with a rest vector fixed in space fail that test and are named in the error.

Newton's matrix is the integrators' KKT matrix (:meth:`solver.system.System.kkt`, blocks K,
Dq, H, Gᵀ, G) plus, with a spin, the exact derivative of the inertia and damping terms,
M Ω̂² − (∂f/∂v) Ω̂ (added as a sparse matrix: for a general axis Ω̂² is not in the mass
pattern). Its rows and columns are first equilibrated (Ruiz's scaling by powers of 2), so that
the LU's pivot test compares stiffnesses of one scale: unscaled, the EA-sized pivots of a stiff
beam section make its EI-sized ones look like zeros (pivot ratio 1e-14 at EA L²/EI = 1e6). A
neutral direction (a free rotor, a lag hinge at Ω = 0) makes the equilibrated matrix singular;
the step is then its minimum-norm least-squares step, dense, which converges to the
equilibrium nearest the start. Newton stops when the update of q has vanished and every force
row is below 1e-6 of the largest force term or below its roundoff level, a few ε times
|J| |(q, λ)| (J the tangent's force rows): the internal forces of a stiff section, EA times a
strain that cancels to about ε |x|/h, carry more roundoff than 1e-6 of a small load. A failure
message says whether the tangent is singular (a neutral direction, named) or ill-conditioned
but not singular (:func:`_diagnosis`).

Loads are ramped by passing a sequence of times (applied loads are functions of time): each
solve starts from the previous solution. If Newton fails straight at a spin, the spin rate
itself is ramped (Ω k/8, k = 1 … 8), since the centrifugal tension that
stiffens a rotating structure is missing at the start.

Nonholonomic rows A(q) q̇ = 0 (arc length, rolling) restrict velocities only; a static
configuration satisfies them trivially and their multipliers are taken as zero (the
equilibrium is that of the holonomic system). With a spin they must admit v*; that is checked.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from solver.bodies import PrescribedBody
from solver.jit import njit
from solver.newton import LinearSolver
from solver.rotations import rotation_about, skew
from solver.state import SECOND
from solver.system import System

Array = NDArray[np.float64]

DENSE_LIMIT = 6000  # largest Newton matrix solved densely (minimum norm) when it is singular
DIAGNOSE_LIMIT = 2500  # largest one whose neutral direction is named in a failure message
ILL_CONDITIONED = 1e10  # condition number (equilibrated) that a failure message reports
RESIDUAL_TOL = 1e-12  # relative force balance at which q is taken as converged at once
RESIDUAL_SETTLED = 1e-6  # relative force balance accepted once the update has vanished
# a force row's residual is roundoff below this many ε times its |J| |(q, λ)| (measured at rest
# on a cantilever with EA L²/EI = 1e8: at most 0.6)
ROUNDOFF_FLOOR = 16.0
SPIN_UP_STEPS = 8  # spin-rate continuation when Newton fails straight at the full rate
MAX_TURN = 0.3  # largest director change of one Newton step (≈ rad)
EQUILIBRATION_SWEEPS = 30  # most sweeps of Ruiz's scaling (:func:`_scaling`)
STEADY_TOL = 1e-8  # relative error allowed in the steadiness checks of a relative equilibrium


@dataclass(frozen=True)
class Spin:
    """A steady rigid rotation of the whole model.

    Parameters
    ----------
    rate
        Spin rate Ω (rad/s), positive counter-clockwise about ``axis``; 0 is a static problem.
    axis
        Direction of the spin axis (any nonzero vector, normalized on construction).
    origin
        A point of the axis (m), global frame.
    """

    rate: float
    axis: ArrayLike = (0.0, 0.0, 1.0)
    origin: ArrayLike = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not np.isfinite(self.rate):
            raise ValueError(f"spin rate = {self.rate!r} rad/s must be finite")
        a = np.asarray(self.axis, dtype=float).reshape(-1)
        nrm = float(np.linalg.norm(a)) if a.shape == (3,) else 0.0
        if a.shape != (3,) or not np.isfinite(nrm) or nrm == 0.0:
            raise ValueError(f"spin axis must be a nonzero 3-vector, got {self.axis!r}")
        o = np.asarray(self.origin, dtype=float).reshape(-1)
        if o.shape != (3,) or not np.all(np.isfinite(o)):
            raise ValueError(f"spin origin must be 3 finite numbers (m), got {self.origin!r}")
        object.__setattr__(self, "rate", float(self.rate))
        object.__setattr__(self, "axis", a / nrm)
        object.__setattr__(self, "origin", o)

    @property
    def omega(self) -> Array:
        """Angular velocity vector Ω n (rad/s)."""
        return self.rate * self.axis

    @classmethod
    def from_body(cls, body: PrescribedBody, t: float = 0.0) -> Spin:
        """The spin of a prescribed body (e.g. a hub from :func:`solver.bodies.spinning`) at
        time t (s): rate |ω|, axis ω/|ω|, origin its reference point."""
        x, _r, _v, w, *_ = (np.asarray(z, dtype=float) for z in body.motion(t))
        rate = float(np.linalg.norm(w))
        if rate == 0.0:
            raise ValueError(f"prescribed body {body.name!r} does not rotate at t = {t} s")
        return cls(rate, w / rate, x)


class SpinField:
    """The rigid spin applied to a system's unknowns.

    Attributes
    ----------
    spun
        Per unknown: True for the second-order coordinates that turn with the spin (every
        3-vector except those of prescribed bodies at rest); algebraic scalars and first-order
        states never turn.
    prescribed
        Per unknown: coordinates of prescribed bodies (their force rows are absorbed by their
        own multipliers and take no part in the steadiness checks).
    W
        Sparse n × n block-diagonal matrix applying Ω̂ to every spun 3-vector (1/s).
    """

    def __init__(self, system: System, spin: Spin | None) -> None:
        lay = system.layout
        n, n2 = system.n, lay.n_second_coordinates
        self.spin = spin
        self.rate = 0.0 if spin is None else spin.rate
        self._n2 = n2
        self.spun = np.zeros(n, dtype=bool)
        self.prescribed = np.zeros(n, dtype=bool)
        self._shift = np.zeros(n)  # o on the spun positions, 0 elsewhere: q − shift is turned
        for b in lay.blocks:
            if isinstance(b.owner, PrescribedBody):
                o = system.offset[b.owner]
                self.prescribed[o : o + b.size] = True
        if spin is None or spin.rate == 0.0:
            self.W = sp.csr_matrix((n, n))
            return
        if lay.unclassified:
            names = ", ".join(repr(getattr(o, "name", "?")) for o in lay.unclassified)
            raise ValueError(f"cannot spin the state blocks of {names}: their 3-vectors are "
                             "neither 12·k (x, d1, d2, d3) groups nor a single position; set "
                             "StateBlock.positions")
        if n2 % 3:
            raise ValueError(f"second-order coordinates ({n2}) are not a sequence of 3-vectors")
        self.spun[:n2] = True
        for b in lay.blocks:
            if isinstance(b.owner, PrescribedBody) and not b.owner.moves():
                o = system.offset[b.owner]
                self.spun[o : o + b.size] = False  # the ground stays where it is
        pos = self.spun & lay.is_position
        self._shift[pos] = np.tile(spin.origin, n2 // 3)[pos[:n2]]
        per_vector = self.spun[:n2:3].astype(float)
        w = sp.kron(sp.diags(per_vector), sp.csr_matrix(skew(spin.omega)))
        self.W = sp.block_diag([w, sp.csr_matrix((n - n2, n - n2))], format="csr")

    @property
    def active(self) -> bool:
        """Whether anything turns (a nonzero spin rate)."""
        return self.rate != 0.0

    def velocity(self, q: Array) -> Array:
        """v* = Ω̂ (x − o) on positions, Ω̂ d on directors, 0 elsewhere (m/s, 1/s)."""
        return self.W @ (q - self._shift)

    def acceleration(self, q: Array) -> Array:
        """a* = Ω̂ v* (centripetal; m/s², 1/s²)."""
        return self.W @ self.velocity(q)

    def turn(self, q: Array, angle: float, vector: bool = False) -> Array:
        """Turn the spun 3-vectors of ``q`` by ``angle`` (rad) about the spin axis: positions
        about the origin, directors (and every 3-vector if ``vector``, e.g. forces) as free
        vectors."""
        if not self.active or angle == 0.0:
            return q.copy()
        rot = rotation_about(self.spin.axis, angle)
        n2 = self._n2
        shift = np.zeros(n2) if vector else self._shift[:n2]
        turned = ((q[:n2] - shift).reshape(-1, 3) @ rot.T).reshape(-1) + shift
        out = np.array(q, dtype=float)
        mask = self.spun[:n2]
        out[:n2][mask] = turned[mask]
        return out


@dataclass
class Equilibrium:
    """Outcome of :func:`equilibrium` (failure is a value: ``converged`` false, ``message``).

    Attributes
    ----------
    q
        Configuration (units of the unknowns: m for positions, 1 for directors).
    lam
        Multipliers of the holonomic rows (N for position rows; N·m for rows of unit
        vectors; see :mod:`solver.joints`).
    residual
        max |M a* + ∇V − f + Gᵀλ| over the unknowns at q (N, or N·m per director).
    violation
        max |C(q, t)| (m, or 1).
    iterations
        Newton iterations, summed over the continuation times.
    converged, message
        Status; the message names the element behind the largest residual on failure.
    t
        Time of the solution (s): the last of the continuation times.
    spin
        The spin of a relative equilibrium (``None`` for a static one).
    velocity
        v* at q (zeros for a static equilibrium).
    system
        The assembled system the unknowns refer to.
    """

    q: Array
    lam: Array
    residual: float
    violation: float
    iterations: int
    converged: bool
    message: str
    t: float
    spin: Spin | None
    velocity: Array
    system: System = field(repr=False)


def equilibrium(model_or_system, *, t: float | Sequence[float] = 0.0, q0: ArrayLike | None = None,
                spin: Spin | None = None, tol: float = 1e-10, max_iter: int = 50) -> Equilibrium:
    """Static equilibrium, or relative equilibrium at a steady spin, by Newton's method.

    Parameters
    ----------
    model_or_system
        A :class:`solver.model.Model` or an assembled :class:`solver.system.System`.
    t
        Time (s) at which loads and prescribed motions are evaluated, or an increasing
        sequence of times for load continuation (each solve starts from the previous one).
    q0
        Starting configuration (default: the model's initial one; with a spin it is first
        turned by Ω t to follow a hub spinning from angle 0 at t = 0).
    spin
        Steady spin of the whole model (relative equilibrium); ``None`` for a static one
        (then prescribed motions are simply frozen at t).
    tol
        Newton stops when the update of q falls below ``tol`` relative to the scale of q.
    max_iter
        Newton iterations allowed per time.

    Returns
    -------
    Equilibrium
        With ``converged`` false and a message naming the culprit element if Newton failed.

    Raises
    ------
    ValueError
        For bad input, or a spin under which the model cannot be steady (the offending element
        is named).
    """
    s = model_or_system if isinstance(model_or_system, System) else System(model_or_system)
    times = np.atleast_1d(np.asarray(t, dtype=float))
    if times.ndim != 1 or not len(times) or not np.all(np.isfinite(times)):
        raise ValueError(f"t = {t!r} must be a finite time (s) or a non-empty sequence of them")
    if np.any(np.diff(times) < 0):
        raise ValueError("continuation times must not decrease")
    if not (0.0 < tol < 1e-2):
        raise ValueError(f"tol = {tol!r} must be in (0, 1e-2)")
    if max_iter < 1:
        raise ValueError(f"max_iter = {max_iter!r} must be ≥ 1")
    if spin is not None and not isinstance(spin, Spin):
        raise TypeError(f"spin must be a Spin(rate, axis, origin), got {type(spin).__name__}")
    fld = SpinField(s, spin)
    if q0 is None:
        q = fld.turn(s.q0_raw, fld.rate * times[0])
    else:
        q = np.asarray(q0, dtype=float).reshape(-1).copy()
        if q.shape != (s.n,) or not np.all(np.isfinite(q)):
            raise ValueError(f"q0 must be {s.n} finite numbers (the model's unknowns)")
    lam = None
    total = 0
    prev_t = times[0]
    for k, tk in enumerate(times):
        q = fld.turn(q, fld.rate * (tk - prev_t))
        prev_t = tk
        start = q
        q, lam, its, ok, msg = _newton(s, q, lam, float(tk), fld, tol, max_iter)
        total += its
        if not ok and k == 0 and fld.active:
            # the centrifugal load is the load to ramp: spin up in steps from the start
            q, lam, its, ok = _spin_up(s, start, float(tk), spin, tol, max_iter)
            total += its
        if not ok:
            where = f" at t = {tk:g} s (step {k + 1} of {len(times)})" if len(times) > 1 else ""
            msg += _diagnosis(s, q, lam, float(tk), fld) + where
            return _result(s, q, lam, float(tk), fld, total, False, msg)
    if spin is not None:
        check_steady(s, q, lam, float(times[-1]), fld)
    return _result(s, q, lam, float(times[-1]), fld, total, True, "")


def _spin_up(s: System, q: Array, t: float, spin: Spin, tol: float, max_iter: int,
             steps: int = SPIN_UP_STEPS):
    """Continuation in the spin rate, Ω k/steps for k = 1 … steps, each Newton starting from
    the previous solution. Straight from a start without centrifugal tension, Newton may
    wander (a twisted blade has no flap stiffness until it is stretched); at a fraction of
    the rate the tension of the previous solution is nearly right."""
    lam = None
    total = 0
    for k in range(1, steps + 1):
        part = SpinField(s, Spin(spin.rate * k / steps, spin.axis, spin.origin))
        q, lam, its, ok, _ = _newton(s, q, lam, t, part, tol, max_iter)
        total += its
        if not ok:
            return q, lam, total, False
    return q, lam, total, True


# ---------------------------------------------------------------------- residual and tangent
def _balance(s: System, q: Array, lam: Array, t: float, fld: SpinField):
    """Force balance r = M a* + ∇V − f(q, v*, t) + Gᵀλ, the constraints C, and the size of the
    largest force term (the scale r is judged against)."""
    v = fld.velocity(q)
    a = fld.acceleration(q)
    c, g = s.constraint_and_jacobian(q, t)
    terms = [s.gradient(q), -s.applied(q, v, t, a), s.gmul_T(g, lam)]
    if fld.active:
        terms.append(s.M @ a)
    r = np.sum(terms, axis=0)
    scale = max(float(np.abs(x).max()) if x.size else 0.0 for x in terms)
    return r, c, g, scale


def static_blocks(s: System, q: Array, v: Array, lam: Array, t: float,
                  a: Array | None = None) -> tuple[dict, Array]:
    """KKT blocks of ∂(∇V − f + Gᵀλ)/∂q at (q, v, a, λ, t) — stiffness K, −∂f/∂q, λ-Hessian
    H — and the values of ∂f/∂v (Dv pattern). Shared by the equilibrium Newton and the
    linearization."""
    blocks = {}
    if s.block_sizes["K"]:
        blocks["K"] = s.stiffness_values(q)
    jq, jv = s.applied_jacobians(q, v, t, a)
    if s.block_sizes["Dq"]:
        blocks["Dq"] = -jq
    if s.block_sizes["H"]:
        blocks["H"] = s.hessian_values(q, t, lam)
    return blocks, jv


def _tangent(s: System, q: Array, lam: Array, t: float, g: Array, fld: SpinField):
    """∂(r, C)/∂(q, λ): the KKT matrix without the nonholonomic rows."""
    v, a = fld.velocity(q), fld.acceleration(q)
    blocks, jv = static_blocks(s, q, v, lam, t, a)
    blocks.update(GT=g, G=g)
    nm = s.n + s.mh
    mat = s.kkt(blocks)[:nm, :nm]
    if fld.active:  # d(M a*)/dq = M Ω̂², d(−f(q, v*(q), a*(q)))/dq ∋ −(∂f/∂v) Ω̂ − (∂f/∂a) Ω̂²
        w = fld.W
        extra = s.M @ (w @ w)
        if s.block_sizes["Dv"]:
            extra = extra - s.kkt({"Dv": jv})[: s.n, : s.n] @ w
        if s.block_sizes["Da"]:
            fa = s.kkt({"Da": s.acceleration_jacobian(q, v, t, a)})[: s.n, : s.n]
            extra = extra - fa @ (w @ w)
        mat = mat + sp.block_diag([extra, sp.csr_matrix((s.mh, s.mh))], format="csc")
    return mat.tocsc()


def _solve(mat: sp.csc_matrix, rhs: Array, n: int, scale: float) -> Array:
    """Newton update from the sparse LU of the equilibrated matrix D_r A D_c (:func:`_scaling`),
    whose pivot test then compares stiffnesses of one scale; if that matrix is (numerically)
    singular, its minimum-norm least-squares update, dense."""
    dr, dc = _scaling(mat)
    a = _scaled(mat, dr, dc)
    lin = LinearSolver()
    if lin.factor(a) is None:
        dx = dc * lin.lu.solve(dr * rhs)
        if np.all(np.isfinite(dx)) and np.abs(dx[:n]).max(initial=0.0) <= 1e6 * scale:
            return dx
    if mat.shape[0] > DENSE_LIMIT:
        raise _Singular
    y, *_ = sla.lstsq(a.toarray(), dr * rhs, cond=1e-12, lapack_driver="gelsd")
    return dc * y


class _Singular(Exception):
    """The Newton matrix is singular and too large for the dense fallback."""


def _scaling(mat) -> tuple[Array, Array]:
    """Row and column scales D_r, D_c (powers of 2, so that scaling rounds nothing) that
    equilibrate D_r A D_c: every row and column of max-norm within a factor 2 of 1."""
    a = sp.csc_matrix(mat)
    return _ruiz(a.indptr.astype(np.int64), a.indices.astype(np.int64),
                 np.abs(a.data).astype(float), a.shape[0], EQUILIBRATION_SWEEPS)


@njit(cache=True)
def _ruiz(indptr, indices, data, nrows, sweeps):
    """Ruiz's equilibration of |A| (CSC): each sweep divides every row and column by the
    square root of its max-norm, until all lie within a factor 2 of 1 (the spread of the
    logarithms about halves per sweep)."""
    ncols = len(indptr) - 1
    dr = np.ones(nrows)
    dc = np.ones(ncols)
    r = np.zeros(nrows)
    c = np.zeros(ncols)
    for _ in range(sweeps):
        r[:] = 0.0
        c[:] = 0.0
        for j in range(ncols):
            for p in range(indptr[j], indptr[j + 1]):
                i = indices[p]
                v = data[p] * dr[i] * dc[j]
                if v > r[i]:
                    r[i] = v
                if v > c[j]:
                    c[j] = v
        worst = 0.0
        for i in range(nrows):
            if r[i] > 0.0:
                worst = max(worst, abs(np.log2(r[i])))
                dr[i] /= np.sqrt(r[i])
        for j in range(ncols):
            if c[j] > 0.0:
                worst = max(worst, abs(np.log2(c[j])))
                dc[j] /= np.sqrt(c[j])
        if worst < 1.0:
            break
    return np.exp2(np.round(np.log2(dr))), np.exp2(np.round(np.log2(dc)))


def _scaled(mat, dr: Array, dc: Array) -> sp.csc_matrix:
    """D_r A D_c as a CSC matrix."""
    a = sp.csc_matrix(mat, copy=True)
    a.data *= dr[a.indices] * np.repeat(dc, np.diff(a.indptr))
    return a


def _multiplier_estimate(s: System, q: Array, r0: Array, g: Array) -> Array:
    """λ minimizing |r0 + Gᵀλ| (r0 the balance without constraint forces): the start that
    makes a configuration already in equilibrium converge in zero iterations."""
    if s.mh == 0:
        return np.zeros(0)
    gm = sp.csr_matrix((g, (s.G_rows, s.G_cols)), shape=(s.mh, s.n))
    mat = sp.bmat([[sp.identity(s.n), gm.T], [gm, None]], format="csc")
    lin = LinearSolver()
    if lin.factor(mat) is not None:
        return np.zeros(s.mh)  # redundant rows: Newton's least-squares steps sort it out
    sol = lin.lu.solve(np.concatenate([-r0, np.zeros(s.mh)]))
    return sol[s.n :] if np.all(np.isfinite(sol)) else np.zeros(s.mh)


def _newton(s: System, q: Array, lam: Array | None, t: float, fld: SpinField, tol: float,
            max_iter: int):
    """Newton on (r, C) = 0 at one time; returns (q, λ, iterations, converged, message)."""
    n = s.n
    scale = max(1.0, float(np.abs(q).max(initial=0.0)))
    if lam is None:
        r0, _c, g, _ = _balance(s, q, np.zeros(s.mh), t, fld)
        lam = _multiplier_estimate(s, q, r0, g)
    lam = lam.copy()
    step = np.inf
    floor = np.zeros(n)
    directors = _director_mask(s)
    for it in range(max_iter + 1):
        r, c, g, fscale = _balance(s, q, lam, t, fld)
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(c))):
            return q, lam, it, False, "non-finite residual (Newton diverged)"
        rel = _relative(r, c, fscale, scale)
        if rel.max(initial=0.0) <= RESIDUAL_TOL or (step <= tol * scale and
                                                    _settled(r, c, fscale, scale, floor)):
            return q, lam, it, True, ""
        if it == max_iter:
            break
        mat = _tangent(s, q, lam, t, g, fld)
        floor = _roundoff(mat, q, lam)
        try:
            dx = _solve(mat, -np.concatenate([r, c]), n, scale)
        except _Singular:
            return q, lam, it, False, ("the equilibrium tangent has a zero pivot after "
                                       "equilibration and is too large for the dense "
                                       "least-squares fallback")
        # a damped step when directors would turn by more than MAX_TURN (rad, roughly):
        # far from the solution (a blade without centrifugal tension yet has no flap
        # stiffness) the full step of a linearized rotation is meaningless
        turn = float(np.abs(dx[:n][directors]).max(initial=0.0))
        if turn > MAX_TURN:
            dx = dx * (MAX_TURN / turn)
        q = q + dx[:n]
        lam = lam + dx[n:]
        step = float(np.abs(dx[:n]).max(initial=0.0))
    i = int(np.argmax(rel))
    where = (f"the force balance of {s.unknown_owner(i)}" if i < n
             else f"the constraint rows of {s.row_owner(i - n)!r}")
    msg = (f"equilibrium Newton did not converge in {max_iter} iterations (relative residual "
           f"{rel.max():.2g}, largest in {where})")
    return q, lam, max_iter, False, msg


def _director_mask(s: System) -> NDArray[np.bool_]:
    """Unknowns that are components of unit vectors (body and beam-node directors)."""
    mask = np.zeros(s.n, dtype=bool)
    for b in s.layout.blocks:
        if b.kind == SECOND and b.positions is not None:
            o = s.offset[b.owner]
            mask[o : o + b.size] = ~np.asarray(b.positions, dtype=bool)
    return mask


def _roundoff(mat: sp.csc_matrix, q: Array, lam: Array) -> Array:
    """Roundoff level of each force-balance row: ROUNDOFF_FLOOR·ε·(|J| |(q, λ)|), the size of
    the sums that make up the internal forces (a stiff beam's EA times its strain's
    cancellation error), J the force rows of the tangent (of the last iterate: near the
    solution it changes little)."""
    n = len(q)
    z = np.abs(np.concatenate([q, lam]))
    return ROUNDOFF_FLOOR * np.finfo(float).eps * (abs(mat[:n]) @ z)


def _settled(r: Array, c: Array, fscale: float, scale: float, floor: Array) -> bool:
    """Whether the residual is at rest after a vanishing update: every force row below
    RESIDUAL_SETTLED of the largest force term or its roundoff level ``floor``, every
    constraint below RESIDUAL_SETTLED of the size of the model."""
    return bool(np.all(np.abs(r) <= RESIDUAL_SETTLED * fscale + floor)
                and np.all(np.abs(c) <= RESIDUAL_SETTLED * scale))


def _relative(r: Array, c: Array, fscale: float, scale: float) -> Array:
    """Residuals relative to the largest force term and to the size of the model."""
    fr = np.abs(r) / fscale if fscale > 0 else np.where(r == 0, 0.0, np.inf)
    return np.concatenate([fr, np.abs(c) / scale])


def _diagnosis(s: System, q: Array, lam: Array, t: float, fld: SpinField) -> str:
    """What the conditioning of the tangent at (q, λ) says of a failed Newton (for messages):
    singular — its condition number after equilibration at least 1/ε, the smallest singular
    value below the roundoff of the largest: a neutral direction, named (by the dense SVD, up
    to DIAGNOSE_LIMIT unknowns); ill-conditioned — a condition number from ILL_CONDITIONED to
    1/ε; else nothing. The condition number is the 1-norm estimate (measured 1.9–5 times the
    2-norm one). Measured after equilibration (2-norm): an unrestrained beam 2e17–1e18, a flap
    hinge at rest 4e16–5e16; a clamped cantilever 3e7 · (EA L²/EI / 1e4), 3e13 at
    EA L²/EI = 1e10."""
    _, _, g, _ = _balance(s, q, lam, t, fld)
    mat = _tangent(s, q, lam, t, g, fld)
    dr, dc = _scaling(mat)
    a = _scaled(mat, dr, dc)
    cond = _condition_estimate(a)
    if cond * np.finfo(float).eps >= 1.0:
        where = ""
        if a.shape[0] <= DIAGNOSE_LIMIT:
            null = dc * np.linalg.svd(a.toarray())[2][-1]
            i = int(np.argmax(np.abs(null[: s.n])))
            where = f"; the null direction moves {s.unknown_owner(i)} most"
        return (f"; the tangent is singular (condition estimate {cond:.1e} after equilibration"
                f"{where}): "
                "no stiffness holds it and the loads push along it")
    if cond >= ILL_CONDITIONED:
        return (f"; the tangent is ill-conditioned (condition estimate {cond:.1e} after "
                "equilibration) but not singular: stiffnesses of very different sizes (a beam's "
                "EA L²/EI), whose roundoff may keep the residual from settling")
    return ""


def _condition_estimate(a: sp.csc_matrix) -> float:
    """1-norm condition estimate of a sparse matrix (Hager–Higham, on a SuperLU factorization);
    infinite if the factorization fails."""
    try:
        lu = spla.splu(a)
    except RuntimeError:
        return np.inf
    inv = spla.LinearOperator(a.shape, matvec=lu.solve, rmatvec=lambda b: lu.solve(b, "T"),
                              dtype=float)
    norm_inv = spla.onenormest(inv)
    return float(spla.norm(a, 1) * norm_inv) if np.isfinite(norm_inv) else np.inf


def _result(s: System, q: Array, lam: Array, t: float, fld: SpinField, its: int, ok: bool,
            msg: str) -> Equilibrium:
    r, c, _g, _ = _balance(s, q, lam, t, fld)
    return Equilibrium(q=q, lam=lam, residual=float(np.abs(r).max(initial=0.0)),
                       violation=float(np.abs(c).max(initial=0.0)), iterations=its,
                       converged=ok, message=msg, t=t, spin=fld.spin,
                       velocity=fld.velocity(q), system=s)


# ---------------------------------------------------------------------- steadiness
def check_steady(s: System, q: Array, lam: Array, t: float, fld: SpinField) -> None:
    """Raise ``ValueError`` naming the element that keeps (q, λ) at time t from being a
    relative equilibrium of the spin: the mass matrix must commute with the spin (E ⊗ I3
    blocks), the spin must satisfy the velocity constraints (G v* + ∂C/∂t = 0, A v* = 0), and
    the model turned by one radian at the matching later time must satisfy its constraints,
    with every potential gradient and generalized force turned with it."""
    n = s.n
    w = fld.W
    mscale = float(np.abs(s.M).max()) if s.M.nnz else 0.0
    comm = (s.M @ w - w @ s.M).tocoo()
    if comm.nnz and np.abs(comm.data).max() > 1e-12 * mscale * abs(fld.rate):
        i = int(comm.row[np.argmax(np.abs(comm.data))])
        raise ValueError(f"the mass matrix of {s.unknown_owner(i)} is not of the form E ⊗ I3, "
                         "so it does not commute with the spin")
    v = fld.velocity(q)
    length = max(1.0, float(np.abs((q - fld._shift)[fld.spun]).max(initial=0.0)))
    if s.mh:
        cv = s.gmul(s.jacobian_values(q, t), v) + s.constraint_rate(q, t)
        i = int(np.argmax(np.abs(cv)))
        if abs(cv[i]) > STEADY_TOL * max(abs(fld.rate), 1e-4) * length:
            raise ValueError(
                f"{s.row_owner(i)!r} does not move with the spin of {fld.rate:g} rad/s about "
                f"{fld.spin.axis.round(6).tolist()} (velocity constraint residual {cv[i]:.3g}): "
                "a prescribed body turning at another rate or about another axis, a driven "
                "joint, or a joint to the ground off the spin axis")
    if s.mn:
        av = s.amul(s.nonholonomic_values(q), v)
        i = int(np.argmax(np.abs(av)))
        if abs(av[i]) > STEADY_TOL * max(abs(fld.rate), 1e-4) * length:
            raise ValueError(f"relation {s.relation_names[i]!r} does not admit the rigid spin "
                             f"(A v* = {av[i]:.3g})")
    if not fld.active:
        return  # a zero spin: the prescribed motions must be at rest, nothing turns
    # one radian later: every term must have turned with the model
    tau = 1.0 / abs(fld.rate)
    angle = fld.rate * tau
    q1, t1 = fld.turn(q, angle), t + tau
    v1 = fld.velocity(q1)
    if s.mh:
        c1 = s.constraint(q1, t1)
        i = int(np.argmax(np.abs(c1)))
        if abs(c1[i]) > STEADY_TOL * length:
            raise ValueError(
                f"{s.row_owner(i)!r} is not symmetric about the spin axis: the model turned "
                f"by 1 rad violates its constraint by {c1[i]:.3g} (a prescribed body not "
                "spinning with the model, or a joint to the ground off the axis)")
    free = ~fld.prescribed
    pairs = [(st, st.grad_idx, lambda st, qq, vv, tt: st.gradient(qq))
             for st in s.potential_sets]
    pairs += [(st, st.force_idx, lambda st, qq, vv, tt: st.force(qq, vv, tt))
              for st in s.force_sets]
    vals = []
    for st, idx, fun in pairs:
        a = np.bincount(idx, fun(st, q, v, t), minlength=n)
        b = np.bincount(idx, fun(st, q1, v1, t1), minlength=n)
        vals.append((st, a, b))
    fscale = max([float(np.abs(a).max(initial=0.0)) for _, a, _ in vals]
                 + [float(np.abs(s.M @ fld.acceleration(q)).max(initial=0.0))])
    # roundoff of stiff internal forces (a beam's EA times the strain's cancellation error)
    kvals = s.stiffness_values(q)
    noise = 1e-12 * float(np.abs(kvals).max(initial=0.0)) * length
    for st, a, b in vals:
        err = np.abs(b - fld.turn(a, angle, vector=True))[free]
        if err.size and err.max() > STEADY_TOL * max(fscale, 1e-300) + noise:
            i = int(np.nonzero(free)[0][np.argmax(err)])
            raise ValueError(
                f"{st.name!r} is not symmetric about the spin axis: its force on "
                f"{s.unknown_owner(i)} does not turn with the model (e.g. gravity off the "
                "axis, a load or spring fixed in space); no steady spin exists")
