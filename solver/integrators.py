"""Time integrators for constrained multibody systems (index-3: positions exact every step).

Three schemes share one template (scipy ``OdeSolver`` style): :meth:`Integrator.step` owns the
status, the counters and the bookkeeping of energy and work; each scheme implements
``_solve`` for one step.

* ``ep`` — energy preserving. Midpoint kinematics q_f − q_i = h(v_i + v_f)/2, momentum balance
  with discrete-gradient forces M(v_f − v_i) = −h[∇̄V + Ḡᵀλ + A(q_m)ᵀν − f(q_m, v_m)], position
  constraints C(q_f) = 0 and nonholonomic A(q_m)(q_f − q_i) = 0. Because Ḡ·Δq = C_f − C_i = 0
  and A(q_m)Δq = 0, the constraint forces do no work and E_f − E_i equals exactly the work of
  the applied loads, dampers and drivers, at any step size.
* ``galpha`` — generalized-α (Chung & Hulbert 1993; index-3 form of Arnold & Brüls 2007) with a
  user spectral radius ρ∞; directors live in a vector space, so no Lie-group correction is needed.
* ``ed`` — energy decaying: a generalized-α step (second order, high frequencies damped to ρ∞,
  default 0: annihilated) guarded so that, for conservative systems, the energy never grows:
  if a step would increase it, the velocities are scaled back to the previous energy (the
  velocity constraints are homogeneous, so they stay satisfied), and if even the potential
  energy exceeds it, the step is recomputed with the provably decaying scheme
  Δq = h v_f, MΔv = −h[∇̄V + Ḡᵀλ + …] (E_f − E_i = −½ΔvᵀMΔv ≤ 0). For smooth motion the
  guard changes the solution by the scheme's own O(h³) local energy error, so second order is
  kept. (Bauchau's time-discontinuous Galerkin ED scheme is third order; this one is simpler and
  its decay does not depend on special element discretizations. See the closing note.)

Multipliers are scaled as impulses (μ = c h² λ) so the Newton matrix stays well conditioned as
h → 0 (Bottasso, Bauchau & Cardona 2007).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from solver.newton import LinearSolver, newton
from solver.system import System

Array = NDArray[np.float64]

# Newton stops when the updates of q fall below this, relative to the scale of q. Energy
# conservation to 1e-10 over 1e4 steps needs the solve close to roundoff; studies that only
# need harmonics may pass a looser ``tol``.
CONSTRAINT_TOL = 3e-15
PROJECTION_MAXITER = 50  # Iterations allowed for the initial projection onto C(q) = 0.


@dataclass
class StepInfo:
    converged: bool
    iterations: int
    factorizations: int
    message: str = ""


class Integrator:
    """Template: state (t, q, v, λ), counters and energy bookkeeping; schemes give ``_solve``."""

    name = "base"

    def __init__(self, system: System, h: float, t0: float = 0.0, q0: Array | None = None,
                 v0: Array | None = None, reuse_jacobian: bool = True,
                 tol: float = CONSTRAINT_TOL) -> None:
        if not (np.isfinite(h) and h > 0):
            raise ValueError(f"time step h = {h!r} s must be > 0")
        if not (0 < tol < 1e-3):
            raise ValueError(f"Newton tolerance tol = {tol!r} must be in (0, 1e-3)")
        self.tol = float(tol)
        self.sys = system
        self.h = float(h)
        self.t = float(t0)
        self.reuse = reuse_jacobian
        self.lin = LinearSolver()
        q = system.q0_raw.copy() if q0 is None else np.asarray(q0, dtype=float).copy()
        self.q = project_positions(system, q, self.t)
        v = system.initial_velocity_guess() if v0 is None else np.asarray(v0, dtype=float)
        self.v = project_velocities(system, self.q, v, self.t)
        self.lam = np.zeros(system.mh)
        self.nu = np.zeros(system.mn)
        try:  # multipliers of the consistent initial accelerations (reactions at t = 0)
            _, self.lam, self.nu = initial_accelerations(system, self.q, self.v, self.t,
                                                         multipliers=True)
        except ValueError:
            pass
        self.work = 0.0
        self.energy0 = self.energy()
        self.n_steps = 0
        self.n_iterations = 0
        self.n_factorizations = 0
        self.scale = max(1.0, float(np.abs(self.q).max()))
        self.conservative = not system.has_nonconservative

    def energy(self, q: Array | None = None, v: Array | None = None) -> float:
        q = self.q if q is None else q
        v = self.v if v is None else v
        return self.sys.kinetic(v) + self.sys.potential(q)

    def _converged(self, x: Array, dx: Array) -> bool:
        n = self.sys.n
        return float(np.abs(dx[:n]).max()) <= self.tol * self.scale

    _full = False
    _stale_failures = 0
    _skip_reuse = 0
    REUSE_RETRY = 16  # steps after which reusing factors is tried again once it stopped paying

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
                self._skip_reuse = self.REUSE_RETRY
                self._stale_failures = 0
        else:
            self._stale_failures = 0

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
            for f in self.sys.forces:
                f.accept(self.q)
        return info

    def _solve(self) -> StepInfo:
        raise NotImplementedError

    def _predict(self, default: Array) -> Array:
        """Newton start for x = (Δq, μ, ν): Δq extrapolated quadratically from the last three
        increments (a cubic in q, error O(h⁴)); the multipliers linearly from the last two
        (they can carry the midpoint rule's two-step mode, which higher orders amplify)."""
        hist = getattr(self, "_x_hist", ())
        if len(hist) < 2:
            return default
        x = 2.0 * hist[-1] - hist[-2]
        if len(hist) == 3:
            n = self.sys.n
            x[:n] = 3.0 * hist[2][:n] - 3.0 * hist[1][:n] + hist[0][:n]
        return x

    def _history(self, x: Array) -> None:
        hist = getattr(self, "_x_hist", ())
        self._x_hist = (*hist[-2:], x.copy())

    def violation(self) -> float:
        """max |C(q, t)| over the holonomic rows."""
        c = self.sys.constraint(self.q, self.t)
        return float(np.abs(c).max()) if c.size else 0.0


class Midpoint(Integrator):
    """The α-family Δq = h[(1−α)v_i + αv_f], MΔv = −h F̄: α = ½ is the EP scheme, α = 1 the
    provably decaying fallback of the ED scheme (E_f − E_i = −(α − ½)ΔvᵀMΔv)."""

    name = "ep"
    alpha = 0.5

    def _solve(self) -> StepInfo:
        s, h, a = self.sys, self.h, self.alpha
        n, mh = s.n, s.mh
        qi, vi, ti = self.q, self.v, self.t
        tf, tm = ti + h, ti + 0.5 * h
        c = a * h * h
        Mvi = s.M @ vi

        def unpack(x):
            dq = x[:n]
            return dq, qi + dq, qi + 0.5 * dq, x[n : n + mh], x[n + mh :]

        def residual(x):
            dq, qf, qm, mu, nu = unpack(x)
            gbar = s.discrete_jacobian_values(qi, qf, ti, tf)
            r1 = s.M @ dq - h * Mvi + c * (s.discrete_gradient(qi, qf)
                                           - s.applied(qm, dq / h, tm))
            r1 += s.gmul_T(gbar, mu)
            parts = [r1, s.constraint(qf, tf)]
            if s.mn:
                am = s.nonholonomic_values(qm)
                r1 += s.amul_T(am, nu)
                parts.append(s.amul(am, dq))
            return np.concatenate(parts)

        def jacobian(x):
            dq, qf, qm, mu, _nu = unpack(x)
            k = 0.5 * c * s.stiffness_values(qm)
            jq, jv = s.applied_jacobians(qm, dq / h, tm)
            d = -c * (0.5 * jq + jv / h)
            hq, hg = s.hessian_values(qm, tm, mu)
            gbar = s.discrete_jacobian_values(qi, qf, ti, tf)
            gf = s.jacobian_values(qf, tf)
            am = s.nonholonomic_values(qm) if s.mn else np.zeros(0)
            a31 = am + 0.5 * s.nonholonomic_derivative(qm, dq) if s.mn else am
            return s.kkt(1.0, k, d, 0.5 * hq, 0.5 * hg, gbar, gf, am, a31)

        x0 = self._predict(np.concatenate([h * vi, c * self.lam, c * self.nu]))
        res = newton(residual, jacobian, x0, self._converged, self.lin,
                     self._reuse_now(), full=self._full)
        self._reuse_outcome(res)
        if not res.converged:
            return StepInfo(False, res.iterations, res.factorizations, res.message)
        dq, qf, qm, mu, nu = unpack(res.x)
        vf = vi + (dq / h - vi) / a
        gbar = s.discrete_jacobian_values(qi, qf, ti, tf)
        lam, nuv = mu / c, nu / c
        # work of drivers (constraint forces of prescribed motions) and of applied loads
        self.work += -float(lam @ s.gmul(gbar, dq)) + float(s.applied(qm, dq / h, tm) @ dq)
        self.q, self.v, self.t, self.lam, self.nu = qf, vf, tf, lam, nuv
        self._history(res.x)
        return StepInfo(True, res.iterations, res.factorizations)


class EnergyPreserving(Midpoint):
    name = "ep"
    alpha = 0.5


class _Decaying(Midpoint):
    name = "ed-fallback"
    alpha = 1.0


class GeneralizedAlpha(Integrator):
    """Generalized-α with spectral radius at infinite frequency ρ∞ ∈ [0, 1]."""

    name = "galpha"

    def __init__(self, system: System, h: float, rho_inf: float = 0.8, **kw) -> None:
        if not (0.0 <= rho_inf <= 1.0):
            raise ValueError(f"rho_inf = {rho_inf!r} must be in [0, 1]")
        super().__init__(system, h, **kw)
        r = rho_inf
        self.am = (2 * r - 1) / (r + 1)
        self.af = r / (r + 1)
        self.gamma = 0.5 + self.af - self.am
        self.beta = 0.25 * (self.gamma + 0.5) ** 2
        self.qdd = initial_accelerations(system, self.q, self.v, self.t)
        self.acc = self.qdd.copy()

    def _solve(self) -> StepInfo:
        s, h = self.sys, self.h
        n, mh = s.n, s.mh
        am, af, g, b = self.am, self.af, self.gamma, self.beta
        qi, vi, ti, ai, qddi = self.q, self.v, self.t, self.acc, self.qdd
        tf = ti + h
        sc = b * h * h * (1 - af) / (1 - am)
        base = h * vi + h * h * (0.5 - b) * ai
        mconst = s.M @ (-base + b * h * h * (am * ai - af * qddi) / (1 - am))
        vconst = vi + h * (1 - g) * ai

        def unpack(x):
            dq = x[:n]
            anew = (dq - base) / (b * h * h)
            return dq, qi + dq, vconst + h * g * anew, anew, x[n : n + mh], x[n + mh :]

        def residual(x):
            dq, qf, vf, _anew, mu, nu = unpack(x)
            c, gf = s.constraint_and_jacobian(qf, tf)
            r1 = s.M @ dq + mconst + sc * (s.gradient(qf) - s.applied(qf, vf, tf))
            r1 += s.gmul_T(gf, mu)
            parts = [r1, c]
            if s.mn:
                af_ = s.nonholonomic_values(qf)
                r1 += s.amul_T(af_, nu)
                parts.append(s.amul(af_, vf) * (b * h / g))
            return np.concatenate(parts)

        def jacobian(x):
            _dq, qf, vf, _anew, mu, _nu = unpack(x)
            k = sc * s.stiffness_values(qf)
            jq, jv = s.applied_jacobians(qf, vf, tf)
            d = -sc * (jq + jv * g / (b * h))
            hq, hg = s.hessian_values(qf, tf, mu)
            gf = s.jacobian_values(qf, tf)
            a_ = s.nonholonomic_values(qf) if s.mn else np.zeros(0)
            a31 = a_ + (b * h / g) * s.nonholonomic_derivative(qf, vf) if s.mn else a_
            return s.kkt(1.0, k, d, hq, hg, gf, gf, a_, a31)

        x0 = self._predict(np.concatenate([h * vi + 0.5 * h * h * ai, sc * self.lam,
                                           sc * self.nu]))
        res = newton(residual, jacobian, x0, self._converged, self.lin,
                     self._reuse_now(), full=self._full)
        self._reuse_outcome(res)
        if not res.converged:
            return StepInfo(False, res.iterations, res.factorizations, res.message)
        dq, qf, vf, anew, mu, nu = unpack(res.x)
        qdd = ((1 - am) * anew + am * ai - af * qddi) / (1 - af)
        lam, nuv = mu / sc, nu / sc
        qm, vm = qi + 0.5 * dq, 0.5 * (vi + vf)
        gm = s.jacobian_values(qm, ti + 0.5 * h)
        # work booked with midpoint values (the scheme has no exact discrete energy balance)
        lam_m = 0.5 * (self.lam + lam)
        self.work += -float(lam_m @ s.gmul(gm, dq)) + float(s.applied(qm, vm, ti + 0.5 * h) @ dq)
        self.q, self.v, self.t, self.lam, self.nu = qf, vf, tf, lam, nuv
        self.acc, self.qdd = anew, qdd
        self._history(res.x)
        return StepInfo(True, res.iterations, res.factorizations)


class EnergyDecaying(GeneralizedAlpha):
    """Generalized-α (default ρ∞ = 0) with an energy-decay guard for conservative systems."""

    name = "ed"

    def __init__(self, system: System, h: float, rho_inf: float = 0.0, **kw) -> None:
        super().__init__(system, h, rho_inf=rho_inf, **kw)
        self._fallback: _Decaying | None = None
        self.n_scaled = 0
        self.n_fallback = 0

    def _solve(self) -> StepInfo:
        if not self.conservative:
            return super()._solve()
        e_i = self.energy()
        saved = (self.q, self.v, self.t, self.lam, self.nu, self.acc, self.qdd)
        info = super()._solve()
        if not info.converged:
            return info
        t_f = self.sys.kinetic(self.v)
        v_f = self.sys.potential(self.q)
        if t_f + v_f <= e_i:
            return info
        if v_f <= e_i and t_f > 0:
            self.v = self.v * np.sqrt((e_i - v_f) / t_f)
            self.n_scaled += 1
            return info
        # potential alone exceeds the previous energy: redo with the decaying α = 1 scheme
        self.q, self.v, self.t, self.lam, self.nu, self.acc, self.qdd = saved
        fb = self._fallback_integrator()
        fb.q, fb.v, fb.t, fb.lam, fb.nu = self.q, self.v, self.t, self.lam, self.nu
        info2 = fb._solve()
        if info2.converged:
            self.q, self.v, self.t, self.lam, self.nu = fb.q, fb.v, fb.t, fb.lam, fb.nu
            self.acc = self.qdd = initial_accelerations(self.sys, self.q, self.v, self.t)
            self.n_fallback += 1
        return StepInfo(info2.converged, info.iterations + info2.iterations,
                        info.factorizations + info2.factorizations, info2.message)

    def _fallback_integrator(self) -> _Decaying:
        if self._fallback is None:
            fb = _Decaying.__new__(_Decaying)
            fb.sys, fb.h, fb.reuse, fb.lin = self.sys, self.h, self.reuse, LinearSolver()
            fb.scale, fb.work, fb.conservative = self.scale, 0.0, True
            self._fallback = fb
        return self._fallback


SCHEMES = {"ep": EnergyPreserving, "ed": EnergyDecaying, "galpha": GeneralizedAlpha}


def make_integrator(system: System, scheme: str, h: float, rho_inf: float | None = None,
                    **kw) -> Integrator:
    """Integrator by name: ``ep``, ``ed`` (ρ∞ default 0) or ``galpha`` (ρ∞ default 0.8)."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme = {scheme!r}: must be one of {', '.join(SCHEMES)}")
    cls = SCHEMES[scheme]
    if scheme == "ep":
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
        ident = np.ones(n)
        mat = _kkt_identity(s, ident, g)
        rhs = np.concatenate([q_ref - q, -c, np.zeros(s.mn)])
        msg = lin.factor(mat)
        if msg:
            raise ValueError(f"cannot assemble the initial configuration: {msg}")
        dx = lin.lu.solve(rhs)
        q += dx[:n]
    c = s.constraint(q, t)
    raise ValueError(f"initial configuration cannot satisfy the constraints (max |C| = "
                     f"{np.abs(c).max():.3g}): check joint locations and axes")


def _kkt_identity(s: System, diag: Array, g: Array):
    """[[diag(w), Gᵀ, 0], [G, 0, 0], [0, 0, I]] in the system's pattern (A rows neutralized)."""
    import scipy.sparse as sp

    n = s.n
    top = sp.diags(diag)
    gm = sp.csr_matrix((g, (s.G_rows, s.G_cols)), shape=(s.mh, n))
    blocks = [[top, gm.T, None], [gm, None, None], [None, None, sp.identity(s.mn)]]
    if s.mn == 0:
        blocks = [[top, gm.T], [gm, None]]
    return sp.bmat(blocks, format="csc")


def project_velocities(s: System, q: Array, v: Array, t: float) -> Array:
    """Closest v (weighted least squares) with G v + ∂C/∂t = 0 and A(q) v = 0."""
    import scipy.sparse as sp

    if s.mh + s.mn == 0:
        return v.copy()
    g = s.jacobian_values(q, t)
    gm = sp.csr_matrix((g, (s.G_rows, s.G_cols)), shape=(s.mh, s.n))
    rows = [gm]
    rhs = [-s.constraint_rate(q, t)]
    if s.mn:
        a = s.nonholonomic_values(q)
        rows.append(sp.csr_matrix((a, (s.A_rows - s.mh, s.A_cols)), shape=(s.mn, s.n)))
        rhs.append(np.zeros(s.mn))
    big = sp.vstack(rows).tocsr()
    # body coordinates keep their given rates as far as the constraints allow; the massless
    # joint scalars (η, s) take whatever rates the constraints imply (tiny weight)
    w = np.ones(s.n)
    w[list(s.scalar_index.values())] = 1e-8
    mat = sp.bmat([[sp.diags(w), big.T], [big, None]], format="csc")
    lin = LinearSolver()
    msg = lin.factor(mat)
    if msg:
        raise ValueError(f"cannot project the initial velocities: {msg}")
    sol = lin.lu.solve(np.concatenate([w * v, np.concatenate(rhs)]))
    return sol[: s.n]


def initial_accelerations(s: System, q: Array, v: Array, t: float, multipliers: bool = False):
    """q̈ from [[M, Gᵀ, Aᵀ], [G, 0, 0], [A, 0, 0]] [q̈; λ; ν] = [f − ∇V; −γ; −γ_A]."""
    g = s.jacobian_values(q, t)
    a = s.nonholonomic_values(q) if s.mn else np.zeros(0)
    z = np.zeros  # no stiffness, damping or curvature blocks: the matrix is [[M, Gᵀ], [G, 0]]
    mat = s.kkt(1.0, z(len(s.stiffness_values(q))), z(len(s.applied_jacobians(q, v, t)[0])),
                z(len(s.quad.hess_rows)), z(sum(len(gr.hess_rows) for gr in s.groups)),
                g, g, a, a)
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
