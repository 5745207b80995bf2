"""Time integrators for constrained multibody systems (index-3: positions exact every step).

The :class:`Integrator` template (scipy ``OdeSolver`` style) owns the state (t, q, v, λ, ν),
Newton with its fallback to full Newton, the factor reuse, the counters, the bookkeeping of
energy and work, and the failure message that names the element behind the worst residual.
A scheme supplies only its residual, its tangent weights, its start and its state update.
Each kind of unknown (:mod:`solver.state`) is treated consistently by every scheme:
second-order coordinates and algebraic scalars by the scheme's second-order rule, first-order
states A ẋ = f by the matching first-order rule, and only second-order coordinates carry
kinetic energy and mechanical work.

* ``ep`` — energy preserving. Midpoint kinematics q_f − q_i = h(v_i + v_f)/2, momentum balance
  with discrete-gradient forces M(v_f − v_i) = −h[∇̄V + Ḡᵀλ + A(q_m)ᵀν − f(q_m, v_m)], position
  constraints C(q_f) = 0 and nonholonomic A(q_m)(q_f − q_i) = 0. Because Ḡ·Δq = C_f − C_i = 0
  and A(q_m)Δq = 0, the constraint forces do no work and E_f − E_i equals exactly the work of
  the applied loads, dampers and drivers, at any step size. First-order states: the implicit
  midpoint rule A(x_f − x_i) = h f(q_m, v_m, x_m, t_m) (A-stable, second order).
* ``galpha`` — generalized-α (Chung & Hulbert 1993; index-3 form of Arnold & Brüls 2007) with a
  user spectral radius ρ∞; directors live in a vector space, so no Lie-group correction is needed.
  First-order states use the first-order generalized-α of Jansen, Whiting & Hulbert (2000) in
  the same form (equations at t_{n+1}, a filtered rate w): α_m = (3ρ∞ − 1)/(2(1 + ρ∞)),
  α_f = ρ∞/(1 + ρ∞), γ = ½ + α_f − α_m, second order with spectral radius ρ∞ at infinity.
* ``ed`` — energy decaying by construction: the DG(1) time-discontinuous Galerkin scheme (see
  :class:`EnergyDecaying`): E_f − E_i = W − (energy of the jump) with the jump energy ≥ 0 at
  any step size, third order and L-stable on linear systems (ρ∞ = 0), O(h³) energy loss per
  period on resolved motion. The most dissipative generalized-α is ``galpha`` with
  ``rho_inf=0``.

Multipliers are scaled as impulses (μ = c h² λ) so the Newton matrix stays well conditioned as
h → 0 (Bottasso, Bauchau & Cardona 2007).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from solver.jit import njit
from solver.newton import (
    STALE_ITERATIONS,
    STALE_RATE,
    LinearSolver,
    max_abs,
    max_abs_weighted,
    newton,
)
from solver.sparse_lu import RefactorLU
from solver.system import BLOCKS, System, _scatter_add, csc_pattern
from solver.turning import TurningParts

Array = NDArray[np.float64]

# Newton stops when the updates of q fall below this, relative to the scale of q. Energy
# conservation to 1e-10 over 1e4 steps needs the solve close to roundoff; studies that only
# need harmonics may pass a looser ``tol``.
CONSTRAINT_TOL = 3e-15
# From this tolerance up, Newton may stop on the error its contraction rate predicts instead of
# confirming with one more update. Not at the roundoff-level default: there the updates are
# roundoff noise, and stopping on the estimate let the chain's energy drift 170 times more
# (16 links, ep, 5000 steps: 8.6e-8 J against 4.9e-10 J).
ESTIMATE_TOL = 1e-12
PROJECTION_MAXITER = 50  # Iterations allowed for the initial projection onto C(q) = 0.
# Kept factors turned with the spinning parts (solver.turning) are refreshed above this
# contraction rate or at this many iterations. On the rotor a fresh Newton matrix and its
# factorization cost about six residuals and solves; turned factors contract by 0.025 – 0.15
# as they age from one to four steps.
TURNED_STALE_RATE = 0.2
TURNED_STALE_ITERATIONS = 8
# The most memory a recorded Newton path's factors may hold (NewtonPath): the rotor's
# quarter-revolution map keeps 60 factors of 2.4 MB each; a longer march keeps factors for its
# first steps only, and its later steps solve with their own
PATH_BYTES = 1e9


# ---------------------------------------------------------------------- compiled step algebra
# The vector formulas evaluated once per step or per Newton iteration on the whole state. On
# small models a dozen NumPy operations on short vectors cost more in calls than in arithmetic
# (16-link chain: a sixth of a step went to galpha's begin, finish and predictor), so each
# formula is one compiled pass. Each is written operation by operation in NumPy's order (numba
# neither fuses multiply-adds nor reassociates without fastmath): the same values to the bit.
@njit(cache=True)
def _extrapolate(x0: Array, x1: Array, x2: Array, nk: int, cubic: bool) -> Array:
    """2 x₂ − x₁ (a line through the last two), and in the first ``nk`` entries, if
    ``cubic``, 3 x₂ − 3 x₁ + x₀ (a parabola through the last three)."""
    out = np.empty(len(x2))
    for i in range(len(x2)):
        out[i] = 2.0 * x2[i] - x1[i]
    if cubic:
        for i in range(nk):
            out[i] = 3.0 * x2[i] - 3.0 * x1[i] + x0[i]
    return out


@njit(cache=True)
def _galpha_begin(h: float, beta: float, gamma: float, am: float, af: float, v: Array,
                  a: Array, qdd: Array) -> tuple[Array, Array, Array]:
    """What a generalized-α step keeps from the previous one (v_i, the α-acceleration a_i,
    q̈_i): Δq at a zero α-acceleration, base = h v_i + h²(½ − β) a_i; the vector
    −base + βh²(α_m a_i − α_f q̈_i)/(1 − α_m), whose product with M is the constant of the
    momentum rows; and v_i + h(1 − γ) a_i, the constant of v_f."""
    n = len(v)
    base = np.empty(n)
    m = np.empty(n)
    vc = np.empty(n)
    hb = h * h * (0.5 - beta)
    bhh = beta * h * h
    hg = h * (1 - gamma)
    for i in range(n):
        base[i] = h * v[i] + hb * a[i]
        m[i] = -base[i] + bhh * (am * a[i] - af * qdd[i]) / (1 - am)
        vc[i] = v[i] + hg * a[i]
    return base, m, vc


@njit(cache=True)
def _galpha_rates(dq: Array, base: Array, vconst: Array, bhh: float,
                  hg: float) -> tuple[Array, Array]:
    """(v_f, a_α) that the increment Δq implies: a_α = (Δq − base)/(βh²) and
    v_f = v_const + hγ a_α (``bhh`` = βh², ``hg`` = hγ)."""
    n = len(dq)
    vf = np.empty(n)
    anew = np.empty(n)
    for i in range(n):
        anew[i] = (dq[i] - base[i]) / bhh
        vf[i] = vconst[i] + hg * anew[i]
    return vf, anew


@njit(cache=True)
def _galpha_acceleration(am: float, af: float, anew: Array, a: Array, qdd: Array) -> Array:
    """q̈_{n+1} from the α-accelerations a_{n+1}, a_n and q̈_n:
    ((1 − α_m) a_{n+1} + α_m a_n − α_f q̈_n)/(1 − α_f)."""
    out = np.empty(len(anew))
    for i in range(len(anew)):
        out[i] = ((1 - am) * anew[i] + am * a[i] - af * qdd[i]) / (1 - af)
    return out


@dataclass
class StepInfo:
    converged: bool
    iterations: int
    factorizations: int
    message: str = ""


@dataclass
class NewtonPath:
    """A march's Newton solutions and the LU factors of the Newton matrix at each, recorded
    (:meth:`Integrator.recording`) for marches from nearby states to follow
    (:meth:`Integrator.following`): the finite differences of a map.

    Near a recorded step the solution is the recorded one plus a small difference, and the
    Newton matrix at the recorded solution is the one Newton needs: a following step starts
    from the recorded x plus its difference extrapolated from the steps before, and solves
    with the recorded factors. Newton then converges in about two iterations without a
    factorization, where a march on its own starts from a predictor of the whole state and
    keeps factors that age (the rotor's Floquet marches: six iterations a step at their tight
    tolerance).
    """

    x: list[Array]  # each step's Newton solution
    start: list[Array]  # each step's plain predictor (the difference's start on the first two)
    lu: list[RefactorLU | None]  # factors of the Newton matrix at x (None: singular there,
    # or beyond the memory budget)
    angle: list[float]  # the spin angle of each step's matrix (turned factors)
    budget: float = PATH_BYTES  # the most memory its factors may hold (bytes)
    nbytes: int = 0  # the memory they hold


@dataclass
class Tangent:
    """Weights of the Newton matrix blocks a scheme asks for (see :meth:`Integrator._tangent`).

    q, v, t: where forces and constraint curvatures are evaluated; mass, first: weights of the
    mass and first-order mass blocks; stiff: of the potential Hessian; force: of the force
    Jacobians, with dq_dx the derivative of the evaluation point q by the unknown Δq and dv_dx
    (per unknown) that of v; hess: of the constraint Hessian; gbar: Jacobian values for the
    Gᵀμ columns; g_rows: for the constraint rows; a_weight: weight of ∂(A·w)/∂q in the
    nonholonomic rows, w: the vector A multiplies there; acc: the accelerations the added
    masses see, da_dx: their derivative by the unknown Δq.
    """

    q: Array
    v: Array
    t: float
    mu: Array
    mass: float
    first: float
    stiff: float
    force: float
    dq_dx: float
    dv_dx: Array
    hess: float
    gbar: Array
    g_rows: Array
    a_weight: float
    w: Array
    acc: Array | None = None
    da_dx: float = 0.0
    k_vals: Array | None = None  # stiffness block values, if not the Hessian at q


def _error_weights(scale: ArrayLike | None, n: int) -> Array | None:
    """1/``tolerance_scale`` per unknown (None: all ones, the plain maximum norm)."""
    if scale is None:
        return None
    s = np.asarray(scale, dtype=float)
    if s.shape != (n,):
        raise ValueError(f"tolerance_scale must be {n} numbers (one per unknown of q), got "
                         f"shape {s.shape}")
    bad = np.nonzero(~(np.isfinite(s) & (s > 0)))[0]
    if bad.size:
        raise ValueError(f"tolerance_scale[{bad[0]}] = {float(s[bad[0]])!r} must be finite and > 0")
    return 1.0 / s


class Integrator:
    """Template: state (t, q, v, λ, ν), Newton, counters and energy bookkeeping.

    Schemes implement ``_begin`` (constants of the step), ``_start`` (the plain predictor of
    x = (Δq, μ, ν)), ``_residual(x)``, ``_tangent_weights(x)`` and ``_finish(x)``.

    ``tol`` is Newton's tolerance on the updates of q relative to q's scale;
    ``tolerance_scale`` (n,), if given, multiplies that tolerance per unknown of q (> 0: a
    state judged in other units than the scale's, e.g. a stiff first-order state that the
    loads see beside velocities); ``book_work``
    false leaves the work of loads and drivers unbooked (``work`` is then NaN);
    ``turning`` (:class:`solver.turning.TurningParts`) names the parts that spin at a known
    rate, with which LU factors kept from step to step are turned.
    """

    name = "base"
    # the scheme equals its own adjoint (Φ_{−h} = Φ_h⁻¹): its error has odd powers of h per
    # step only, so symmetric compositions raise its order (solver.composition)
    symmetric = False

    def __init__(self, system: System, h: float, t0: float = 0.0, q0: Array | None = None,
                 v0: Array | None = None, reuse_jacobian: bool = True,
                 tol: float = CONSTRAINT_TOL, book_work: bool = True,
                 turning: TurningParts | None = None,
                 tolerance_scale: ArrayLike | None = None) -> None:
        if not (np.isfinite(h) and h > 0):
            raise ValueError(f"time step h = {h!r} s must be > 0")
        if not (0 < tol < 1e-3):
            raise ValueError(f"Newton tolerance tol = {tol!r} must be in (0, 1e-3)")
        self.tol = float(tol)
        self._weights = _error_weights(tolerance_scale, system.n)
        self.sys = system
        self.h = float(h)
        self.t = float(t0)
        self.reuse = reuse_jacobian
        # spinning parts: kept factors are turned with them (solver.turning), and then pay
        # at slower contraction rates (fewer Newton matrices and factorizations)
        self.turning = turning
        self.lin = LinearSolver(turning)
        if turning is not None:
            self.stale_rate, self.stale_iterations = TURNED_STALE_RATE, TURNED_STALE_ITERATIONS
        self.first = system.first_order
        self.mech = np.ones(system.n, dtype=bool)  # unknowns that carry mechanical work
        self.mech[self.first] = False
        q = system.q0_raw.copy() if q0 is None else np.asarray(q0, dtype=float).copy()
        self.q = project_positions(system, q, self.t)
        v = system.initial_velocity_guess() if v0 is None else np.asarray(v0, dtype=float)
        self.v = project_velocities(system, self.q, v, self.t)
        self.lam = np.zeros(system.mh)
        self.nu = np.zeros(system.mn)
        self._qdd0 = None
        try:  # consistent initial accelerations, state rates and multipliers (reactions at t0)
            self._qdd0, self.lam, self.nu = initial_accelerations(system, self.q, self.v,
                                                                  self.t, multipliers=True)
            self.v[self.first] = self._qdd0[self.first]  # ẋ from A ẋ = f
        except ValueError:
            pass
        # the work of loads, dampers and drivers (J), for energy balances; a run that reads
        # none (the rotor's) saves the midpoint force evaluation that ep and galpha spend on
        # it every step, and its work is NaN (never a silently wrong number)
        self.book_work = bool(book_work)
        self.work = 0.0 if book_work else float("nan")
        self.energy0 = self.energy()
        self.n_steps = 0
        self.n_iterations = 0
        self.n_factorizations = 0
        self.scale = max(1.0, float(np.abs(self.q).max()))
        self.conservative = not system.has_nonconservative
        self._nk = system.n  # kinematic unknowns leading the Newton vector (ed: two stages)

    # what a step starts from; schemes with more history extend it
    STATE: tuple[str, ...] = ("t", "q", "v", "lam", "nu")

    def state(self) -> dict[str, Any]:
        """A copy of what the next step starts from (time, positions, velocities, multipliers
        and the scheme's own history), for :meth:`restore`."""
        return {k: np.copy(getattr(self, k)) if k != "t" else self.t for k in self.STATE}

    def restore(self, state: dict[str, Any]) -> None:
        """Continue from :meth:`state` of an integrator of the same scheme on a system of the
        same layout (e.g. the same model with other damper values): the next step is the one
        the other integrator would have taken, with this system's forces."""
        missing = set(self.STATE) - set(state)
        if missing:
            raise ValueError(f"restore: state lacks {sorted(missing)} (a {self.name!r} state "
                             "is needed)")
        if np.shape(state["q"]) != self.q.shape:
            raise ValueError(f"restore: state has {np.size(state['q'])} unknowns, the system "
                             f"{self.q.size}")
        for k in self.STATE:
            setattr(self, k, float(state[k]) if k == "t" else np.array(state[k], dtype=float))
        self._x_hist = ()

    def forget_factors(self) -> None:
        """Drop the kept Newton factors and the record of how well they paid: the next step
        factors its own matrix, as a fresh integrator's first step does. Steps from one state
        then follow the same Newton path whatever ran before (kept factors of another state
        stop Newton at another point within its tolerance, or, at a stale matrix's slow
        contraction, on an error estimate far from it)."""
        self.lin.lu = None
        self._stale_failures = self._skip_reuse = 0
        self._retry = self.REUSE_RETRY

    @contextmanager
    def recording(self) -> Iterator[NewtonPath]:
        """While the block runs, keep each step's Newton solution and the LU factors of the
        Newton matrix there (a fresh factorization per step): a :class:`NewtonPath` for
        :meth:`following`."""
        path = NewtonPath([], [], [], [])
        self._recording = path
        try:
            yield path
        finally:
            self._recording = None

    @contextmanager
    def following(self, path: NewtonPath) -> Iterator[Integrator]:
        """While the block runs, step k starts from the recorded step k's solution plus the
        difference from it extrapolated over the previous steps, and solves with its
        factors (see :class:`NewtonPath`); beyond the path's length, as usual. For marches
        from states near the recorded march's start, at the same times."""
        self._following, self._path_step, self._path_hist = path, 0, ()
        try:
            yield self
        finally:
            self._following = None

    def _record(self, x: Array) -> None:
        """Keep step x and the factors of the Newton matrix at it in the recording path."""
        path = self._recording
        lu: RefactorLU | None = None  # (then followed with the step's own factors)
        last = next((f.nbytes for f in reversed(path.lu) if f is not None), 0)
        if path.nbytes + last <= path.budget:  # (the next factors about the last's size)
            lu = RefactorLU()
            try:
                lu.factor(self._jacobian(x))
                path.nbytes += lu.nbytes
            except (RuntimeError, ArithmeticError, spla.MatrixRankWarning):
                lu = None
        path.x.append(x.copy())
        path.start.append(self._recorded_start)
        path.lu.append(lu)
        path.angle.append(self.lin.angle)

    def _follow(self) -> Array | None:
        """The Newton start of a step that follows the path (its factors put in place), or
        None beyond its end."""
        path, k = self._following, self._path_step
        if k >= len(path.x):
            return None
        hist = self._path_hist
        if len(hist) < 2:  # the plain predictors' difference
            d = self._start() - path.start[k]
        else:
            d = _extrapolate(hist[0], hist[-2], hist[-1], self._nk, len(hist) == 3)
        if path.lu[k] is not None and not self._full:
            self.lin.use(path.lu[k], path.angle[k])
        return path.x[k] + d

    @contextmanager
    def tightened(self, tol: float) -> Iterator[Integrator]:
        """Newton's relative tolerance ``tol`` for every unknown alike (a per-unknown
        ``tolerance_scale`` suspended), confirmed by an update (never stopped on the error
        its contraction rate predicts, which a stale matrix's erratic rate can put far from
        the tolerance) while the block runs: for finite differences of the steps, whose noise
        is Newton's error over the perturbation."""
        saved = self.tol, self._weights, self._confirm
        self.tol, self._weights, self._confirm = float(tol), None, True
        try:
            yield self
        finally:
            self.tol, self._weights, self._confirm = saved

    def energy(self, q: Array | None = None, v: Array | None = None) -> float:
        q = self.q if q is None else q
        v = self.v if v is None else v
        return self.sys.kinetic(v) + self.sys.potential(q)

    def _error(self, dx: Array) -> float:
        """Size of a Newton update of x: the largest change of the kinematic unknowns, each
        divided by its ``tolerance_scale`` (Newton stops when it is at most ``tol`` times the
        scale of q)."""
        if self._weights is None:
            return max_abs(dx[: self._nk])
        return max_abs_weighted(dx, self._weights, self._nk // self.sys.n)

    _full = False
    _confirm = False  # Newton confirms convergence by an update, never on its estimate
    _recording: NewtonPath | None = None
    _following: NewtonPath | None = None
    _stale_failures = 0
    _skip_reuse = 0
    # steps after which reusing factors is tried again once it stopped paying, doubled after
    # every retry that fails again, up to REUSE_RETRY_MAX (a failed retry costs two Newton
    # iterations: on the rotor, whose blades turn the Newton matrix 1.5° a step, the retries
    # every 16 steps paid off 2 times in 30)
    REUSE_RETRY = 16
    REUSE_RETRY_MAX = 256
    _retry = REUSE_RETRY

    def _reuse_now(self) -> bool:
        """Reuse the previous step's LU factors unless that kept failing lately (fast rotation
        changes the matrix too much between steps; then one fresh factorization per step is
        cheaper than the extra iterations)."""
        if not self.reuse or self._full:
            return False
        if self._skip_reuse > 0:
            self._skip_reuse -= 1
            return False
        return True

    def _reuse_outcome(self, res) -> None:
        if res.stale_refactored:
            self._stale_failures += 1
            if self._stale_failures >= 2:
                self._skip_reuse = self._retry
                self._retry = min(2 * self._retry, self.REUSE_RETRY_MAX)
                self._stale_failures = 0
        else:
            self._stale_failures = 0
            if res.converged and res.factorizations == 0:  # the kept factors paid
                self._retry = self.REUSE_RETRY

    def step(self) -> StepInfo:
        """Advance one step of size h; on failure the state is left unchanged.

        A step whose fast (modified) Newton iteration fails is retried once with full Newton
        from the plain predictor, refactoring at every iteration.
        """
        info = self._solve()
        if not info.converged:
            hist, self._x_hist = getattr(self, "_x_hist", ()), ()
            self._full = True
            try:
                retry = self._solve()
            finally:
                self._full = False
            info = StepInfo(retry.converged, info.iterations + retry.iterations,
                            info.factorizations + retry.factorizations,
                            retry.message if not retry.converged else "")
            if not info.converged:
                self._x_hist = hist
        self.n_iterations += info.iterations
        self.n_factorizations += info.factorizations
        if info.converged:
            self.n_steps += 1
            self.sys.accept(self.q, self.v, self.t)
        return info

    # ------------------------------------------------------------------ the template
    # when kept factors are refreshed (newton)
    stale_rate, stale_iterations = STALE_RATE, STALE_ITERATIONS

    def _solve(self) -> StepInfo:
        """One step: Newton on the scheme's residual with the scheme's tangent."""
        self._begin()
        if self.turning is not None:  # the spin angle of this step's matrices
            self.lin.angle = self.turning.rate * (self.t + self.h)
            self.lin.stages = self._nk // self.sys.n
        x0 = None if self._following is None else self._follow()
        following = x0 is not None
        if not following:
            if self._recording is not None:
                self._recorded_start = self._start()
            x0 = self._predict()
        # a followed path's factors are of the matrix at the recorded solution: a slow
        # contraction is the Newton matrix's own approximation, which refactoring at the
        # iterate would not improve, so they are kept as long as turned factors are
        res = newton(self._residual, self._jacobian, x0, self._error, self.tol * self.scale,
                     self.lin, not self._full if following else self._reuse_now(),
                     full=self._full, estimate=self.tol >= ESTIMATE_TOL and not self._confirm,
                     stale_rate=TURNED_STALE_RATE if following else self.stale_rate,
                     stale_iterations=(TURNED_STALE_ITERATIONS if following
                                       else self.stale_iterations))
        if not following:
            self._reuse_outcome(res)
        if not res.converged:
            return StepInfo(False, res.iterations, res.factorizations,
                            res.message + self._culprit(res))
        if following:
            d = res.x - self._following.x[self._path_step]
            self._path_hist = (*self._path_hist[-2:], d)
            self._path_step += 1
        elif self._recording is not None:
            self._record(res.x)
        self._finish(res.x)
        self._history(res.x)
        return StepInfo(True, res.iterations, res.factorizations)

    def _jacobian(self, x: Array) -> sp.csc_matrix:
        return self._tangent(self._tangent_weights(x))

    def _tangent(self, w: Tangent) -> sp.csc_matrix:
        """The Newton matrix from a scheme's weights (one assembly for every scheme)."""
        s = self.sys
        blocks = {"M": (w.mass, s.M_vals), "A1": (w.first, s.A1_vals)}
        if s.block_sizes["K"]:
            blocks["K"] = (w.stiff,
                           s.stiffness_values(w.q) if w.k_vals is None else w.k_vals)
        if s.block_sizes["H"]:
            blocks["H"] = (w.hess, s.hessian_values(w.q, w.t, w.mu))
        blocks["GT"], blocks["G"] = w.gbar, w.g_rows
        if s.mn:
            a = s.nonholonomic_values(w.q)
            blocks["AT"] = a
            blocks["A"] = a + w.a_weight * s.nonholonomic_derivative(w.q, w.w)
        forces = None
        if s.block_sizes["Dq"] or s.block_sizes["Dv"] or s.block_sizes["Da"]:
            forces = (w.q, w.v, w.t, w.acc, -w.force * w.dq_dx, -w.force * w.dv_dx,
                      -w.force * w.da_dx)
        return s.kkt(blocks, shared=True, forces=forces)  # only factored, never kept

    def _culprit(self, res) -> str:
        """Which element owns the largest residual of a failed Newton iteration."""
        r = res.residual
        if r is None:
            try:
                r = self._residual(res.x)
            except (ValueError, FloatingPointError, ZeroDivisionError):
                return ""
        if r is None or not len(r):
            return ""
        a = np.abs(np.where(np.isfinite(r), r, np.inf))
        i = int(np.argmax(a))
        s = self.sys
        if i < self._nk:
            return f" (largest residual in the dynamics of {s.unknown_owner(i % s.n)})"
        return f" (largest residual in the constraint rows of {s.row_owner(i - self._nk)!r})"

    def _begin(self) -> None: ...

    def _start(self) -> Array:
        raise NotImplementedError

    def _residual(self, x: Array) -> Array:
        raise NotImplementedError

    def _tangent_weights(self, x: Array) -> Tangent:
        raise NotImplementedError

    def _finish(self, x: Array) -> None:
        raise NotImplementedError

    def _predict(self) -> Array:
        """Newton start for x = (Δq, μ, ν): Δq extrapolated quadratically from the last three
        increments (a cubic in q, error O(h⁴)); the multipliers linearly from the last two
        (they can carry the midpoint rule's two-step mode, which higher orders amplify).
        The scheme's plain predictor (:meth:`_start`) until two increments are known (only
        then: it costs a dozen vector operations that the extrapolation would discard)."""
        hist = getattr(self, "_x_hist", ())
        if len(hist) < 2:
            return self._start()
        return _extrapolate(hist[0], hist[-2], hist[-1], self._nk, len(hist) == 3)

    def _history(self, x: Array) -> None:
        hist = getattr(self, "_x_hist", ())
        self._x_hist = (*hist[-2:], x.copy())

    def _book_work(self, lam: Array, gv: Array, dq: Array, f: Array) -> None:
        """Work of the drivers (constraint forces of prescribed motions, −λ·GΔq) and of the
        applied loads and dampers on the mechanical coordinates over the step."""
        self.work += -float(lam @ self.sys.gmul(gv, dq)) + float(f[self.mech] @ dq[self.mech])

    def violation(self) -> float:
        """max |C(q, t)| over the holonomic rows."""
        c = self.sys.constraint(self.q, self.t)
        return max_abs(c)


class EnergyPreserving(Integrator):
    """Midpoint kinematics Δq = h(v_i + v_f)/2 with MΔv = −h F̄ (discrete-gradient forces):
    E_f − E_i is exactly the work done. First-order states: A Δx = h f at the midpoint.
    (``alpha`` is the midpoint weight ½ in Δq = h[(1−α)v_i + αv_f].)"""

    name = "ep"
    symmetric = True  # midpoint kinematics, midpoint forces, discrete gradients
    alpha = 0.5

    def _begin(self) -> None:
        h = self.h
        self._tf, self._tm = self.t + h, self.t + 0.5 * h
        self._c = self.alpha * h * h
        self._hMv = h * self.sys.mass_mul(self.v)

    def _start(self) -> Array:
        return np.concatenate([self.h * self.v, self._c * self.lam, self._c * self.nu])

    def _unpack(self, x):
        n, mh = self.sys.n, self.sys.mh
        dq = x[:n]
        return dq, self.q + dq, self.q + 0.5 * dq, x[n : n + mh], x[n + mh :]

    def _acc(self, dq):
        """(v_f − v_i)/h, the acceleration of the step (for added masses), or None."""
        if not self.sys.accel_sets:
            return None
        return (dq / self.h - self.v) / (self.alpha * self.h)

    def _residual(self, x):
        s, h, c = self.sys, self.h, self._c
        qi = self.q
        dq, qf, qm, mu, nu = self._unpack(x)
        gbar = s.discrete_jacobian_values(qi, qf, self.t, self._tf)
        r1 = s.mass_mul(dq) - self._hMv
        if len(self.first):
            r1 += (self.alpha * h) * s.first_mass_mul(dq)
        load = s.discrete_gradient(qi, qf)
        if s.force_sets:  # else f = 0, and ∇̄V − 0 is ∇̄V to the bit
            load = load - s.applied(qm, dq / h, self._tm, self._acc(dq))
        r1 += c * load
        r1 += s.gmul_T(gbar, mu)
        parts = [r1, s.constraint(qf, self._tf)]
        if s.mn:
            am = s.nonholonomic_values(qm)
            r1 += s.amul_T(am, nu)
            parts.append(s.amul(am, dq))
        return np.concatenate(parts)

    def _tangent_weights(self, x):
        s, h, c = self.sys, self.h, self._c
        dq, qf, qm, mu, _nu = self._unpack(x)
        return Tangent(q=qm, v=dq / h, t=self._tm, mu=mu, mass=1.0, first=self.alpha * h,
                       stiff=c, k_vals=s.discrete_stiffness_values(self.q, qf), force=c,
                       dq_dx=0.5, dv_dx=np.full(s.n, 1.0 / h),
                       hess=0.5, gbar=s.discrete_jacobian_values(self.q, qf, self.t, self._tf),
                       g_rows=s.jacobian_values(qf, self._tf), a_weight=0.5, w=dq,
                       acc=self._acc(dq), da_dx=1.0 / c)

    def _finish(self, x):
        s, h, c = self.sys, self.h, self._c
        dq, qf, qm, mu, nu = self._unpack(x)
        vi = self.v
        vf = vi + (dq / h - vi) / self.alpha
        vf[self.first] = dq[self.first] / h  # the mean rate of the midpoint rule
        lam = mu / c
        if self.book_work:
            gbar = s.discrete_jacobian_values(self.q, qf, self.t, self._tf)
            self._book_work(lam, gbar, dq, s.applied(qm, dq / h, self._tm, self._acc(dq)))
        self.q, self.v, self.t, self.lam, self.nu = qf, vf, self._tf, lam, nu / c


class GeneralizedAlpha(Integrator):
    """Generalized-α with spectral radius at infinite frequency ρ∞ ∈ [0, 1]."""

    name = "galpha"
    STATE = (*Integrator.STATE, "acc", "qdd")  # the acceleration history of the α method

    def __init__(self, system: System, h: float, rho_inf: float = 0.8, **kw) -> None:
        if not (0.0 <= rho_inf <= 1.0):
            raise ValueError(f"rho_inf = {rho_inf!r} must be in [0, 1]")
        super().__init__(system, h, **kw)
        r = rho_inf
        self.am = (2 * r - 1) / (r + 1)
        self.af = r / (r + 1)
        self.gamma = 0.5 + self.af - self.am
        self.beta = 0.25 * (self.gamma + 0.5) ** 2
        # first-order states (Jansen, Whiting & Hulbert 2000, weights on the old values)
        self.am1 = (3 * r - 1) / (2 * (1 + r))
        self.af1 = r / (1 + r)
        self.gamma1 = 0.5 + self.af1 - self.am1
        self.qdd = (self._qdd0 if self._qdd0 is not None
                    else initial_accelerations(system, self.q, self.v, self.t))
        self.acc = self.qdd.copy()
        # constants of every step: ∂v_f/∂Δq, with ẋ_f = k1 Δx + k0 for first-order states
        self._k1 = (1 - self.am1) / ((1 - self.af1) * self.gamma1 * self.h)
        self._dv_dx = np.full(system.n, self.gamma / (self.beta * self.h))
        self._dv_dx[self.first] = self._k1
        self._has_first = bool(len(self.first))
        self._rates_used = self._has_first or bool(system.force_sets) or system.mn > 0

    def _begin(self) -> None:
        s, h = self.sys, self.h
        am, af, g, b = self.am, self.af, self.gamma, self.beta
        vi, ai, qddi = self.v, self.acc, self.qdd
        self._tf = self.t + h
        self._sc = b * h * h * (1 - af) / (1 - am)
        self._base, m, self._vconst = _galpha_begin(h, b, g, am, af, vi, ai, qddi)
        self._mconst = s.mass_mul(m)
        f = self.first
        g1 = self.gamma1
        # ẋ_f = k1 Δx + k0: from w_f = (Δx − h(1−γ)w_i)/(γh) and the α-filter of the rates
        # (first-order states only; a purely mechanical model skips the empty index work)
        if self._has_first:
            self._k0 = ((1 - self.am1) * (-(1 - g1) * ai[f] / g1) + self.am1 * ai[f]
                        - self.af1 * qddi[f]) / (1 - self.af1)

    def _start(self) -> Array:
        h = self.h
        dq = h * self.v + 0.5 * h * h * self.acc
        if self._has_first:
            dq[self.first] = h * self.v[self.first]
        return np.concatenate([dq, self._sc * self.lam, self._sc * self.nu])

    def _rates(self, dq):
        """(v_f, a_α) that the increment Δq implies: the end velocity and the α-acceleration."""
        h = self.h
        vf, anew = _galpha_rates(dq, self._base, self._vconst, self.beta * h * h, h * self.gamma)
        if self._has_first:
            f = self.first
            vf[f] = self._k1 * dq[f] + self._k0
        return vf, anew

    def _unpack(self, x):
        n, mh = self.sys.n, self.sys.mh
        dq = x[:n]
        vf, anew = self._rates(dq)
        return dq, self.q + dq, vf, anew, x[n : n + mh], x[n + mh :]

    def _residual(self, x):
        s, b, h, g, sc = self.sys, self.beta, self.h, self.gamma, self._sc
        n, mh = s.n, s.mh
        dq, mu, nu = x[:n], x[n : n + mh], x[n + mh :]
        qf = self.q + dq
        # the rates enter only through loads, first-order states and nonholonomic rows (a
        # chain has none of them: its residual skips their vector operations)
        vf, anew = self._rates(dq) if self._rates_used else (None, None)
        c, gf = s.constraint_and_jacobian(qf, self._tf)
        r1 = s.mass_mul(dq) + self._mconst
        if len(self.first):  # A has only the first-order states' columns: A v_f is A ẋ_f
            r1 += sc * s.first_mass_mul(vf)
        load = s.gradient(qf)
        if s.force_sets:  # else f = 0, and ∇V − 0 is ∇V to the bit
            load = load - s.applied(qf, vf, self._tf, self._acc(anew))
        r1 += sc * load
        r1 += s.gmul_T(gf, mu)
        parts = [r1, c]
        if s.mn:
            af_ = s.nonholonomic_values(qf)
            r1 += s.amul_T(af_, nu)
            parts.append(s.amul(af_, vf) * (b * h / g))
        return np.concatenate(parts)

    def _tangent_weights(self, x):
        s, sc = self.sys, self._sc
        _dq, qf, vf, anew, mu, _nu = self._unpack(x)
        gf = s.jacobian_values(qf, self._tf)
        return Tangent(q=qf, v=vf, t=self._tf, mu=mu, mass=1.0, first=sc * self._k1,
                       stiff=sc, force=sc, dq_dx=1.0, dv_dx=self._dv_dx, hess=1.0, gbar=gf,
                       g_rows=gf, a_weight=self.beta * self.h / self.gamma, w=vf,
                       acc=self._acc(anew), da_dx=1.0 / sc)

    def _acc(self, anew):
        """q̈_{n+1} from the α-acceleration (what added masses see), or None."""
        if not self.sys.accel_sets:
            return None
        return _galpha_acceleration(self.am, self.af, anew, self.acc, self.qdd)

    def _finish(self, x):
        s, h = self.sys, self.h
        am, af = self.am, self.af
        dq, qf, vf, anew, mu, nu = self._unpack(x)
        ai, qddi = self.acc, self.qdd
        qdd = _galpha_acceleration(am, af, anew, ai, qddi)
        if self._has_first:
            f = self.first
            anew[f] = (dq[f] - h * (1 - self.gamma1) * ai[f]) / (self.gamma1 * h)  # w_f
            qdd[f] = vf[f]
        lam, nuv = mu / self._sc, nu / self._sc
        if self.book_work and not self.conservative:  # else no work to book
            qm, vm = self.q + 0.5 * dq, 0.5 * (self.v + vf)
            gm = s.jacobian_values(qm, self.t + 0.5 * h)
            # work booked with midpoint values (the scheme has no exact discrete energy balance)
            am_ = 0.5 * (self.qdd + qdd) if s.accel_sets else None
            self._book_work(0.5 * (self.lam + lam), gm, dq,
                            s.applied(qm, vm, self.t + 0.5 * h, am_))
        self.q, self.v, self.t, self.lam, self.nu = qf, vf, self._tf, lam, nuv
        self.acc, self.qdd = anew, qdd


class EnergyDecaying(Integrator):
    """Energy decaying by construction: the time-discontinuous Galerkin scheme of Bauchau &
    Theron (1996) with linear interpolation in time, in a form whose energy balance holds for
    any nonlinear potential, constraint and step size.

    Each step has two stages: *a* just after the start (the solution may jump there) and *b*
    at the end; the velocities v_a, v_b are the unknowns (with x = h v), linear in between:

        q_b = q_i + h (v_a + v_b)/2,      q_a = q_i − h (v_b − v_a)/6,
        h F_a = M (3 v_a + v_b − 4 v_i),  h F_b = M (v_b − 3 v_a + 2 v_i),

    i.e. M(v_b − v_i) = h(F_a + F_b)/2 and M(v_a − v_i) = h(F_a − F_b)/6: the DG(1) weak form
    with the jump at t_i⁺. The stage forces are F = f(q, v, t) + potential force + constraint
    forces, with the potential force split around the exact discrete gradient ∇̄V and a
    positive semidefinite stiffness K̄ (the material stiffness at the predicted midpoint, frozen
    over the step):

        P_a = −∇̄V + K̄(q_b − q_i)/2 + K̄ h(v_b − v_a)/6,   P_b = −∇̄V − K̄(q_b − q_i)/2.

    For a linear system with K̄ = K these are −K q_a and −K q_b, and the scheme is the DG(1)
    method: third order, L-stable, its amplification the (1, 2) Padé approximant of e^z. The
    constraint forces −Ḡᵀλ (one multiplier vector for both stages, C(q_b) = 0) and −A(q_m)ᵀν
    (A(q_m)(q_b − q_i) = 0) do no work, and the energy balance over a step is exactly

        E_b − E_i = W − ½ (v_a − v_i)ᵀ M (v_a − v_i) − (h²/72) (v_b − v_a)ᵀ K̄ (v_b − v_a),

    where W = (h/6)[f_a·(2v_a + v_b) + f_b·(v_a + 2v_b)] − λ·Ḡ(q_b − q_i) is the work of the
    applied loads, dampers and drivers (the exact integral of f·v for f and v linear over the
    step; −h/6 ∫(…) ≤ 0 for a linear damper). The last two terms, the energy of the jump,
    are the numerical dissipation: ≥ 0 for any step, O(h⁴) per step on smooth motion (so
    O(h³) per period), and they remove motion with ωh ≫ 1 within a few steps. With
    constraints, the end-velocity projection below adds ½|Δv|²_M ≥ 0 to it (also O(h⁴) per
    step) and the work of a prescribed motion's impulse to W. First-order states A ẋ = f
    follow the same DG(1) rule (A ẋ_a = f_a, A ẋ_b = f_b). Massless unknowns
    (joint scalars, prescribed bodies) have no inertia to jump: their stage-a row is
    v_a = v_b, and the stage-a force left on them (on a prescribed body: the driver's) is
    booked in W.

    The one multiplier vector is what keeps the constraint forces workless (a second one,
    for the stage-a velocities, would have to make them tangent to this step's chord, which
    the previous step's end velocity is not: an O(h) jump; constraining q_a as well makes
    v_b − v_a tangent at q_i, against the centripetal change of v, and drains 33 % of the
    energy of a free particle on a circle per revolution at 80 steps). Because that force
    acts through the chord only, the rows leave the end velocity's component normal to the
    constraints undamped: it alternates in sign from step to step, and loads can feed it
    (the rotor in forward flight failed that way). So the end velocity is projected,
    M-closest, onto the velocity constraints at q_b (:meth:`_tangent_velocity`): an impulse
    along the constraint normals, which only takes kinetic energy away and is booked with
    the jump. Rigid systems with no elastic potential and no force that varies within a step
    have no jump, and this projection is their only numerical dissipation (a pendulum: O(h³)
    per period).

    A price of the one multiplier vector: a stiff element loaded through a constraint force
    that changes over the step cannot follow the change between the stages and loses about
    ½k(Δs)² per step (Δs its quasi-static stretch per step), an O(h) loss per period with a
    small constant (rod on a 1e8 N/m elastic pivot: 1e-7 to 1e-6 of the energy per period
    at 25-200 steps per period).
    """

    name = "ed"

    def __init__(self, system: System, h: float, **kw) -> None:
        super().__init__(system, h, **kw)
        s = self.sys
        n = s.n
        self._nk = 2 * n
        weight = abs(s.M).sum(axis=1).A1 + abs(s.A1).sum(axis=1).A1
        self._massless = np.nonzero(weight == 0.0)[0]
        # the entries each block puts in the stage-a rows: all but the massless unknowns'
        # rows (which hold v_a = v_b instead); "GT" and "AT" are the constraint forces' blocks
        keep = weight != 0.0
        self._kept_entries = {name: np.nonzero(keep[s.block_pattern(name)[0]])[0]
                              for name in BLOCKS if name not in ("G", "A")}
        self._scatter = None  # the Newton matrix's CSC pattern, from the first assembly
        self.dissipation = 0.0  # numerical dissipation booked so far (J)
        self._proj: LinearSolver | bool = LinearSolver()  # for the end-velocity projection
        self.qdd = self._qdd0 if self._qdd0 is not None else np.zeros(system.n)

    def _begin(self) -> None:
        s, h = self.sys, self.h
        self._tf = self.t + h
        self._Mhv = s.mass_mul(h * self.v)
        qm = self.q + 0.5 * h * self.v  # predicted midpoint: where K̄ is frozen for the step
        self._Kbar_vals = s.material_stiffness_values(qm)
        self._Kbar = (s.block_matrix("K", self._Kbar_vals) if s.block_sizes["K"]
                      else sp.csr_matrix((s.n, s.n)))

    def _start(self) -> Array:
        hv, c = self.h * self.v, self.h * self.h
        return np.concatenate([hv, hv, c * self.lam, c * self.nu])

    def _unpack(self, x):
        s, h = self.sys, self.h
        n, mh = s.n, s.mh
        xa, xb = x[:n], x[n : 2 * n]
        dq, d = 0.5 * (xa + xb), xb - xa
        acc = None
        if s.accel_sets:  # the stage accelerations the rows' inertia terms imply
            hv = h * self.v
            acc = ((3.0 * xa + xb - 4.0 * hv) / (h * h), (xb - 3.0 * xa + 2.0 * hv) / (h * h))
        return (xa, xb, dq, d, self.q + dq, self.q - d / 6.0, self.q + 0.5 * dq,
                x[2 * n : 2 * n + mh], x[2 * n + mh :], acc or (None, None))

    def _rows(self, x):
        """The momentum rows of both stages (h² times force units) and the constraint rows;
        the stage-a rows of the massless unknowns as the momentum balance would have them;
        the applied forces f_a, f_b and the discrete constraint Jacobian Ḡ."""
        s, h = self.sys, self.h
        xa, xb, dq, d, qb, qa, qm, mu, nu, acc = self._unpack(x)
        # stage forces without the constraints: applied, and the split elastic force
        g = s.discrete_gradient(self.q, qb)
        kd, kdd = self._Kbar @ dq, self._Kbar @ d
        fa = s.applied(qa, xa / h, self.t, acc[0])
        fb = s.applied(qb, xb / h, self._tf, acc[1])
        gbar = s.discrete_jacobian_values(self.q, qb, self.t, self._tf)
        h2 = h * h
        cf = s.gmul_T(gbar, mu)
        ra = s.mass_mul(3.0 * xa + xb) - 4.0 * self._Mhv - h2 * (fa - g + 0.5 * kd + kdd / 6.0) + cf
        rb = s.mass_mul(xb - 3.0 * xa) + 2.0 * self._Mhv - h2 * (fb - g - 0.5 * kd) + cf
        if len(self.first):
            ra += h * s.first_mass_mul(xa)
            rb += h * s.first_mass_mul(xb)
        parts = [ra, rb, s.constraint(qb, self._tf)]
        if s.mn:
            am = s.nonholonomic_values(qm)
            an = s.amul_T(am, nu)
            ra += an
            rb += an
            parts.append(s.amul(am, dq))
        # a massless unknown has no inertia to jump: its stage-a row is v_a = v_b (the
        # force balance there would repeat stage b's, or, for a prescribed body, is the
        # driver's business)
        unbalanced = ra[self._massless].copy()
        ra[self._massless] = d[self._massless]
        return parts, unbalanced, (fa, fb, gbar)

    def _residual(self, x):
        return np.concatenate(self._rows(x)[0])

    def _jacobian(self, x) -> sp.csc_matrix:
        """The Newton matrix in one sparse assembly: every block's values, weighted for each
        of its places (rows a, b × columns x_a, x_b; the multiplier columns; the constraint
        rows), as one list of triplets. Stage-a rows of massless unknowns are v_a = v_b."""
        s, h = self.sys, self.h
        n, mh = s.n, s.mh
        xa, xb, dq, _d, qb, qa, qm, mu, _nu, acc = self._unpack(x)
        h2 = h * h
        kept = self._kept_entries
        first = self._scatter is None  # the pattern is the same at every call: built once
        parts: list[tuple[float, Array]] = []  # (weight, values) of each part
        where: list[tuple[Array, Array]] = []  # (rows, columns) of each part, first call only

        def part(w: float, vals: Array, rows: Array, cols: Array, r0: int, c0: int) -> None:
            """Add ``w * vals`` at (rows + r0, cols + c0); the indices only at the first call
            (the pattern is kept: the later calls need the values alone)."""
            parts.append((w, vals))
            if first:
                where.append((rows + r0, cols + c0))

        def put(name: str, vals: Array, places) -> None:
            """Add block ``name`` with ``vals`` at (row offset, column offset, weight) places;
            in the stage-a rows (offset 0) the massless unknowns' rows are left out."""
            rows, cols = s.block_pattern(name)
            for r0, c0, w in places:
                k = kept[name] if r0 == 0 else slice(None)
                part(w, vals[k], rows[k], cols[k], r0, c0)

        # ∂∇̄V/∂x_a = ∂∇̄V/∂x_b = ½ ∂∇̄V/∂q_b; q_a = q_i − (x_b − x_a)/6, q_b = q_i + (x_a + x_b)/2
        put("M", s.M_vals, [(0, 0, 3.0), (0, n, 1.0), (n, 0, -3.0), (n, n, 1.0)])
        if len(self.first):
            put("A1", s.A1_vals, [(0, 0, h), (n, n, h)])
        if s.block_sizes["K"]:
            put("K", s.discrete_stiffness_values(self.q, qb),
                [(0, 0, 0.5 * h2), (0, n, 0.5 * h2), (n, 0, 0.5 * h2), (n, n, 0.5 * h2)])
            put("K", self._Kbar_vals, [(0, 0, -h2 / 12.0), (0, n, -5.0 * h2 / 12.0),
                                       (n, 0, 0.25 * h2), (n, n, 0.25 * h2)])
        if s.block_sizes["Dq"] or s.block_sizes["Dv"]:
            jq, jv = s.applied_jacobians(qa, xa / h, self.t, acc[0])
            put("Dq", jq, [(0, 0, -h2 / 6.0), (0, n, h2 / 6.0)])
            put("Dv", jv, [(0, 0, -h)])
            jq, jv = s.applied_jacobians(qb, xb / h, self._tf, acc[1])
            put("Dq", jq, [(n, 0, -0.5 * h2), (n, n, -0.5 * h2)])
            put("Dv", jv, [(n, n, -h)])
        if s.block_sizes["Da"]:  # added masses: inertia like M in each stage's row
            put("Da", s.acceleration_jacobian(qa, xa / h, self.t, acc[0]),
                [(0, 0, -3.0), (0, n, -1.0)])
            put("Da", s.acceleration_jacobian(qb, xb / h, self._tf, acc[1]),
                [(n, 0, 3.0), (n, n, -1.0)])
        if s.block_sizes["H"]:
            put("H", s.hessian_values(qm, self.t + 0.5 * h, mu),
                [(0, 0, 0.25), (0, n, 0.25), (n, 0, 0.25), (n, n, 0.25)])
        if mh:
            gbar = s.discrete_jacobian_values(self.q, qb, self.t, self._tf)
            g_rows, g_cols = s.block_pattern("G")
            k = kept["GT"]  # Ḡᵀμ in both stages' rows
            part(1.0, gbar[k], g_cols[k], g_rows[k], 0, 2 * n)
            part(1.0, gbar, g_cols, g_rows, n, 2 * n)
            put("G", s.jacobian_values(qb, self._tf), [(2 * n, 0, 0.5), (2 * n, n, 0.5)])
        if s.mn:
            am = s.nonholonomic_values(qm)
            a_rows, a_cols = s.block_pattern("A")
            k = kept["AT"]
            part(1.0, am[k], a_cols[k], a_rows[k], 0, 2 * n + mh)
            part(1.0, am, a_cols, a_rows, n, 2 * n + mh)
            o = 2 * n + mh
            put("A", am, [(o, 0, 0.5), (o, n, 0.5)])
            put("A", s.nonholonomic_derivative(qm, dq), [(o, 0, 0.25), (o, n, 0.25)])
        w = self._massless  # their stage-a rows: x_b − x_a = 0
        ones = np.ones(len(w))
        part(-1.0, ones, w, w, 0, 0)
        part(1.0, ones, w, w, 0, n)
        size = 2 * n + mh + s.mn
        if first:
            self._scatter = csc_pattern([r for r, _ in where], [c for _, c in where], size)
        places, indices, indptr = self._scatter
        # each part added in place where its entries go (no triplet list of the rotor's
        # million entries, no sort): the sums of np.bincount over them, in the same order
        data = np.zeros(len(indices))
        for idx, (wt, vals) in zip(places, parts, strict=True):
            _scatter_add(data, idx, np.ascontiguousarray(vals, dtype=float), wt)
        # one pattern at every call, whatever values come out zero: the LU refactors with the
        # pivot order of the first matrix only while the pattern stays (dropping the zeros
        # gave a new pattern, and a fresh SuperLU factorization, at every step of the rotor)
        return sp.csc_matrix((data, indices, indptr), shape=(size, size))

    def _finish(self, x):
        s, h = self.sys, self.h
        xa, xb, dq, d, qb, _qa, _qm, mu, nu, _acc = self._unpack(x)
        _, unbalanced, (fa, fb, gbar) = self._rows(x)
        va, vb = xa / h, xb / h
        lam = mu / (h * h)
        mech = self.mech
        applied = (h / 6.0) * float(fa[mech] @ (2.0 * va + vb)[mech]
                                    + fb[mech] @ (va + 2.0 * vb)[mech])
        # the stage-a force left on massless unknowns (a prescribed body's: the driver's)
        # works on them; the momentum rows that hold elsewhere account for all the rest
        w = self._massless
        massless = float(unbalanced @ (2.0 * xa[w] + xb[w])) / (6.0 * h * h)
        self.work += applied - float(lam @ s.gmul(gbar, dq)) + massless
        jump = va - self.v
        jump[~mech] = 0.0
        self.dissipation += 0.5 * float(jump @ (s.M @ jump)) + float(d @ (self._Kbar @ d)) / 72.0
        # the stage-b acceleration the rows' inertia implies (what added masses see)
        self.qdd = (xb - 3.0 * xa + 2.0 * h * self.v) / (h * h)
        vb = self._tangent_velocity(qb, vb, self.qdd)
        self.q, self.v, self.t, self.lam, self.nu = qb, vb, self._tf, lam, nu / (h * h)

    def _tangent_velocity(self, q: Array, v: Array, a: Array) -> Array:
        """The end velocity made tangent to the constraints at the end of the step: the
        closest v' in the inertia's metric (M and the added masses −∂f/∂a) with
        G(q)v' + ∂C/∂t = 0 and A(q)v' = 0 (massless unknowns take what the constraints
        imply). The step's constraint force acts through the chord only (Ḡ, the same in both
        stages), so nothing in the rows damps a velocity component normal to the
        constraints: it would alternate in sign from step to step, undamped, and work from
        loads and drivers can feed it. The projection removes it. It is an impulse along the
        constraint normals in the inertia's metric, so it leaves the momentum of the motion
        the constraints allow, and with it the reduced dynamics, unchanged (in the bare M
        metric an added mass would see its velocity changed by O(h²) per step: a first-order
        error). It takes kinetic energy ½|Δv|²_M away, booked as numerical dissipation (O(h⁴)
        per step on smooth motion, v_b being off the constraints by O(h²)); the rest of the
        change of ½vᵀMv, v'·MΔv, is the work of the prescribed motions' and added masses'
        impulses, booked in W."""
        s = self.sys
        if s.mh + s.mn == 0 or self._proj is False:
            return v
        mat, g, an = inertia_kkt(s, q, v, self._tf, a)
        rhs = [np.zeros(s.n), -(s.gmul(g, v) + s.constraint_rate(q, self._tf))]
        if s.mn:
            rhs.append(-s.amul(an, v))
        if self._proj.factor(mat):
            # a massless unknown no constraint determines (its velocity is set by forces
            # alone): no M-projection exists; the scheme runs without it
            self._proj = False
            return v
        dv = self._proj.lu.solve(np.concatenate(rhs))[: s.n]
        dv[self.first] = 0.0
        vt = v + dv
        mdv = s.M @ dv
        self.dissipation += 0.5 * float(dv @ mdv)
        self.work += float(vt @ mdv)
        return vt


SCHEMES = {"ep": EnergyPreserving, "ed": EnergyDecaying, "galpha": GeneralizedAlpha}


def make_integrator(system: System, scheme: str, h: float, rho_inf: float | None = None,
                    **kw) -> Integrator:
    """Integrator by name: ``ep``, ``ed`` or ``galpha`` (ρ∞ default 0.8; ρ∞ = 0 is the most
    dissipative generalized-α)."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme = {scheme!r}: must be one of {', '.join(SCHEMES)}")
    cls = SCHEMES[scheme]
    if scheme != "galpha":
        if rho_inf is not None:
            raise ValueError(f"rho_inf = {rho_inf!r} applies to the galpha scheme only ({scheme} "
                             "has no free spectral radius)")
        return cls(system, h, **kw)
    if rho_inf is None:
        return cls(system, h, **kw)
    return cls(system, h, rho_inf=rho_inf, **kw)


# ---------------------------------------------------------------------- consistent start
def project_positions(s: System, q: Array, t: float) -> Array:
    """Closest q (least squares) with C(q, t) = 0, by Gauss–Newton on [[I, Gᵀ], [G, 0]]."""
    q = q.copy()
    lin = LinearSolver()
    q_ref = q.copy()
    for _ in range(PROJECTION_MAXITER):
        c, g = s.constraint_and_jacobian(q, t)
        if c.size == 0 or np.abs(c).max() < 1e-14 * max(1.0, np.abs(q).max()):
            return q
        n = s.n
        mat = _kkt_identity(s, np.ones(n), g)
        rhs = np.concatenate([q_ref - q, -c, np.zeros(s.mn)])
        msg = lin.factor(mat)
        if msg:
            raise ValueError(f"cannot assemble the initial configuration: {msg}")
        dx = lin.lu.solve(rhs)
        q += dx[:n]
    c = s.constraint(q, t)
    worst = s.row_owner(int(np.argmax(np.abs(c))))
    raise ValueError(f"initial configuration cannot satisfy the constraints (max |C| = "
                     f"{np.abs(c).max():.3g}, in {worst!r}): check joint locations and axes")


def _kkt_identity(s: System, diag: Array, g: Array):
    """[[diag(w), Gᵀ, 0], [G, 0, 0], [0, 0, I]] in the system's pattern (A rows neutralized)."""
    n = s.n
    top = sp.diags(diag)
    gm = sp.csr_matrix((g, (s.G_rows, s.G_cols)), shape=(s.mh, n))
    blocks = [[top, gm.T, None], [gm, None, None], [None, None, sp.identity(s.mn)]]
    if s.mn == 0:
        blocks = [[top, gm.T], [gm, None]]
    return sp.bmat(blocks, format="csc")


def constraint_rows(s: System, q: Array, t: float) -> sp.csr_matrix:
    """[G; A] at (q, t): the holonomic constraints' Jacobian over the velocity-level
    relations' rows, (mh + mn) × n."""
    g = s.jacobian_values(q, t)
    rows = [sp.csr_matrix((g, (s.G_rows, s.G_cols)), shape=(s.mh, s.n))]
    if s.mn:
        a = s.nonholonomic_values(q)
        rows.append(sp.csr_matrix((a, (s.A_rows - s.mh, s.A_cols)), shape=(s.mn, s.n)))
    return sp.vstack(rows).tocsr()


def project_velocities(s: System, q: Array, v: Array, t: float,
                       weights: Array | None = None) -> Array:
    """Closest v (weighted least squares) with G v + ∂C/∂t = 0 and A(q) v = 0; ``weights``
    (n,) > 0 replace the default ones (see below)."""
    if s.mh + s.mn == 0:
        return v.copy()
    big = constraint_rows(s, q, t)
    rhs = np.concatenate([-s.constraint_rate(q, t), np.zeros(s.mn)])
    # body coordinates keep their given rates as far as the constraints allow; the massless
    # joint scalars (η, s) take whatever rates the constraints imply (tiny weight)
    if weights is None:
        w = np.ones(s.n)
        w[s.layout.algebraic] = 1e-8
    else:
        w = np.asarray(weights, dtype=float)
    mat = sp.bmat([[sp.diags(w), big.T], [big, None]], format="csc")
    lin = LinearSolver()
    msg = lin.factor(mat)
    if msg:
        raise ValueError(f"cannot project the initial velocities: {msg}")
    sol = lin.lu.solve(np.concatenate([w * v, rhs]))
    return sol[: s.n]


def inertia_kkt(s: System, q: Array, v: Array, t: float, a: Array | None = None):
    """[[M + A − ∂f/∂a, Gᵀ, Aₙᵀ], [G, 0, 0], [Aₙ, 0, 0]] at (q, v, t) (added masses seen at
    accelerations ``a``): the matrix of the consistent accelerations and of ``ed``'s
    end-velocity projection. Returns it with the G and Aₙ values."""
    g = s.jacobian_values(q, t)
    blocks = {"M": s.M_vals, "A1": s.A1_vals, "GT": g, "G": g}
    if s.block_sizes["Da"]:  # added masses: f = f(a = 0) + (∂f/∂a) a, affine in a
        blocks["Da"] = -s.acceleration_jacobian(q, v, t, a)
    an = s.nonholonomic_values(q) if s.mn else np.zeros(0)
    if s.mn:
        blocks["AT"] = blocks["A"] = an
    return s.kkt(blocks), g, an


def initial_accelerations(s: System, q: Array, v: Array, t: float, multipliers: bool = False):
    """q̈ (and ẋ of the first-order states) from
    [[M + A − ∂f/∂a, Gᵀ, Aₙᵀ], [G, 0, 0], [Aₙ, 0, 0]] [q̈; λ; ν] = [f(a = 0) − ∇V; −γ; −γ_A]."""
    mat, _g, _an = inertia_kkt(s, q, v, t)
    rhs = np.concatenate([s.applied(q, v, t) - s.gradient(q), -s.constraint_curvature(q, v, t),
                          -s.nonholonomic_curvature(q, v) if s.mn else np.zeros(0)])
    lin = LinearSolver()
    msg = lin.factor(mat)
    if msg:
        raise ValueError(f"cannot compute consistent initial accelerations: {msg}")
    sol = lin.lu.solve(rhs)
    if multipliers:
        return sol[: s.n], sol[s.n : s.n + s.mh], sol[s.n + s.mh :]
    return sol[: s.n]
