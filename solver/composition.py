"""Fourth-order time integration by symmetric composition of a symmetric one-step scheme.

A symmetric (time-reversible) one-step method Φ_h of order 2, such as the energy-preserving
midpoint-type ``ep`` scheme, has an error expansion in odd powers of h per step, so a
palindromic product of its steps with suitably chosen sizes,

    Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h},   γ_i = γ_{s+1−i},   Σ γ_i = 1,   Σ γ_i³ = 0,

cancels the h³ term and is of order 4 (Yoshida 1990; Suzuki 1990; Hairer, Lubich & Wanner,
*Geometric Numerical Integration*, 2nd ed., §II.4 and §V.3). One substep must go backwards
in time (Σ γ³ = 0 needs a negative γ). Every property of Φ that survives composition is
kept: Ψ is symmetric, and with ``ep`` the energy balance E_f − E_i = W holds exactly over
each substep, hence over each step. Constraints hold at every substep end.

Two sets of weights are offered (:data:`COMPOSITIONS`):

- ``yoshida``: the triple jump, γ = (γ₁, 1 − 2γ₁, γ₁), γ₁ = 1/(2 − 2^{1/3}); 3 substeps,
  the middle one −1.70 h.
- ``suzuki``: Suzuki's fractal, γ = (γ₁, γ₁, 1 − 4γ₁, γ₁, γ₁), γ₁ = 1/(4 − 4^{1/3}); 5
  substeps, the middle one −0.66 h. Its error constant is far smaller: on the bifilar hub's
  periodic harmonics the triple jump at 96 steps per revolution (288 substeps) leaves 0.39 %,
  Suzuki's at 40 (200 substeps) 0.18 % (:mod:`studies.hub`).

The composed integrator keeps a separate Newton history (the predictor's extrapolation) and a
separate set of LU factors for each substep size, so that each substep is predicted from and
solved with the same substep of the steps before, which changes smoothly, rather than from
the previous substep, whose size and direction differ.
"""

from __future__ import annotations

from typing import Any

from solver.newton import LinearSolver

_G3 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_G5 = 1.0 / (4.0 - 4.0 ** (1.0 / 3.0))
# substep sizes per step, in units of the step (palindromic, sum 1, cubes sum 0)
COMPOSITIONS: dict[str, tuple[float, ...]] = {
    "yoshida": (_G3, 1.0 - 2.0 * _G3, _G3),
    "suzuki": (_G5, _G5, 1.0 - 4.0 * _G5, _G5, _G5),
}


class Composed:
    """A symmetric scheme's steps composed into a fourth-order step.

    Wraps an integrator whose scheme is symmetric (``ep``); exposes what the periodic solvers
    and the studies use of an integrator: :meth:`step`, ``q``, ``v``, ``t``, ``h`` (the
    composed step, s), :meth:`state` / :meth:`restore`, and the counters ``n_steps``
    (composed steps), ``n_substeps``, ``n_iterations`` and ``n_factorizations`` (over all
    substeps). Any other attribute is the wrapped integrator's.

    Parameters
    ----------
    integrator
        The symmetric one-step integrator, built with the composed step as its ``h``.
    method
        A key of :data:`COMPOSITIONS`.

    Raises
    ------
    ValueError
        If the scheme is not symmetric (generalized-α and ``ed`` damp, so their error has
        even powers too and composition would not raise their order) or ``method`` is
        unknown.
    """

    def __init__(self, integrator, method: str = "suzuki") -> None:
        if method not in COMPOSITIONS:
            raise ValueError(f"composition = {method!r}: must be one of "
                             f"{', '.join(COMPOSITIONS)}")
        if not getattr(integrator, "symmetric", False):
            raise ValueError(f"composition = {method!r} needs a symmetric scheme (ep); "
                             f"{integrator.name!r} is not")
        delayed = [type(s).__name__ for s in integrator.sys.sets if s.step_history]
        if delayed:
            raise ValueError(f"composition = {method!r} steps backwards within a step, which "
                             f"the step history of {', '.join(delayed)} (delayed feedback) "
                             "cannot follow")
        self._inner = integrator
        self.method = method
        self.gammas = COMPOSITIONS[method]
        self.h = float(integrator.h)
        self.n_steps = 0
        # one LU-factor holder per distinct substep size, one predictor history per substep
        sizes = sorted(set(self.gammas))
        self._solvers = {g: (integrator.lin if g == self.gammas[0] else LinearSolver())
                         for g in sizes}
        self._histories: list[tuple] = [() for _ in self.gammas]

    # the wrapped integrator's state and everything not defined here
    def __getattr__(self, name: str) -> Any:
        if name == "_inner":  # not set yet (copy, unpickling): no recursion
            raise AttributeError(name)
        return getattr(self._inner, name)

    @property
    def q(self):
        return self._inner.q

    @property
    def v(self):
        return self._inner.v

    @property
    def t(self) -> float:
        return self._inner.t

    @property
    def n_substeps(self) -> int:
        return self._inner.n_steps

    def state(self) -> dict[str, Any]:
        return self._inner.state()

    def forget_factors(self) -> None:
        """Drop every substep size's kept Newton factors (see the wrapped integrator's)."""
        for solver in self._solvers.values():
            solver.lu = None
        self._inner.forget_factors()

    def restore(self, state: dict[str, Any]) -> None:
        self._inner.restore(state)
        self._histories = [() for _ in self.gammas]

    def step(self):
        """One composed step of size ``h``; on failure the state is left unchanged and the
        failed substep's :class:`solver.integrators.StepInfo` is returned (its message says
        which substep)."""
        inner, h = self._inner, self.h
        start, work = inner.state(), inner.work
        lin0 = inner.lin
        iterations = factorizations = 0
        info = None
        try:
            for k, g in enumerate(self.gammas):
                inner.h = g * h
                inner.lin = self._solvers[g]
                inner._x_hist = self._histories[k]
                info = inner.step()
                self._histories[k] = inner._x_hist
                iterations += info.iterations
                factorizations += info.factorizations
                if not info.converged:  # back to the step's start, its work unbooked
                    inner.restore(start)
                    inner.work = work
                    self._histories = [() for _ in self.gammas]
                    info.message = (f"substep {k + 1} of {len(self.gammas)} ({g:+.3f} h) of "
                                    f"the {self.method} composition: {info.message}")
                    info.iterations, info.factorizations = iterations, factorizations
                    return info
        finally:
            inner.h = h
            inner.lin = lin0
        self.n_steps += 1
        info.iterations, info.factorizations = iterations, factorizations
        return info
