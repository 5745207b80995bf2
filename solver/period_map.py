"""Floquet multipliers of a periodic response found by time integration: Arnoldi iteration on
the finite-difference Jacobian of the integrator's period (or sector) map.

A periodic response x*(t) of a multibody model is asymptotically stable when every Floquet
multiplier of its linearization lies inside the unit circle (:mod:`solver.floquet`). For a
large model (a rotor: thousands of unknowns) the monodromy matrix is never formed; its
dominant eigenvalues are found by Arnoldi iteration on its action, one perturbed integration
per Krylov vector (Lust, Roose, Spence & Champneys 1998, "An adaptive Newton–Picard algorithm
with subspace iteration for computing periodic solutions", SIAM J. Sci. Comput. 19; Seydel,
*Practical Bifurcation and Stability Analysis*, ch. 7). Five things make that action a clean
linear operator on a constrained model, and each is needed (without them the hub's largest
multiplier came out between 0.96 and 10⁶ instead of 0.83, the rotor's up to 175 instead of
0.91):

* **The scheme's whole state.** The map acts on everything a step starts from: positions,
  velocities and the scheme's history (generalized-α's acceleration variables).
* **Consistent perturbations.** Velocity perturbations are made consistent in the kinetic-
  energy metric (a massless coordinate — a fictitious link, a joint's scalar — takes the rate
  the constraints imply), as the difference of two projections: the base state keeps the
  velocity component across the constraints that the scheme's own steps leave, only the
  perturbation is made tangent. The map's outputs are projected the same way. A component
  across the constraints is the scheme's own business (the energy-preserving step carries it
  as an undamped two-step mode), not the motion's.
* **The velocity relations' integrals held.** A velocity-level relation that is integrable
  (a pin rolling without slip in a planar hole: the arc lengths, the pin's spin and the two
  contact points are tied by integrals, not by the positions) has a constant of integration
  for every row: perturbing it moves the model to a neighbouring family of motions (a pin
  that slipped once), and the map has the multiplier 1 on each, whatever the stability. The
  multipliers of the motion are those of the map on the invariant subspace where the
  integrals keep their values: position perturbations are projected orthogonally onto
  G δq = 0 and A δq = 0 (A the relations' rows), inputs and outputs alike.
* **The pins' spin turned back.** On a periodic response each rolling pin returns to its
  place but not to its spin angle; the map's outputs turn each pin's directors (and their
  rates) about its own axis back to the input's spin (a symmetry of the motion), so that
  outputs and inputs share one tangent space.
* **One Newton path.** The base integration is recorded (each step's solution and the LU
  factors of the Newton matrix there: :class:`solver.integrators.NewtonPath`), and every
  integration, the base's own again among them, follows it: each step starts from the
  recorded solution plus its difference extrapolated from the steps before and solves with
  the recorded factors, to one tight tolerance on every unknown, confirmed by an update. Each
  step then converges in about two iterations to well within that tolerance (the rotor's
  quarter revolution: 2.0 iterations a step and no factorization, against 6.0 and 0.28 from
  its own predictor and aging factors; the largest multiplier the same to eight digits). The
  base state is first projected onto the constraints as the perturbed ones are. Otherwise
  the differences carry Newton's error (or the projection's offset) divided by the
  perturbation, and Arnoldi converges on noise (a base march that did not follow its own
  path: the rotor's largest Ritz value 1.29 instead of 0.914); the largest Ritz pair is
  therefore checked by one more application of the map.

Arnoldi here is a short explicit iteration (:func:`arnoldi`) rather than ARPACK's implicitly
restarted one (:func:`solver.floquet.dominant_multipliers`): each application is an
integration, a few dozen are affordable, and its Ritz vectors and residual estimates are what
the checks need.

With a cyclic symmetry of N sectors (:class:`solver.symmetry.CyclicSymmetry`) the map is one
N-th of the period followed by the symmetry's turn-and-permute back; its eigenvalues to the
N-th power are the period's multipliers, at an N-th of the cost per Krylov vector.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray
from scipy.linalg import schur

from solver.curve_joints import Rolling
from solver.integrators import constraint_rows, project_positions, project_velocities

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
# The largest fresh residual of the largest Ritz pair that is the finite differences' own
# error (their noise, Newton's tolerance over the perturbation, and the projections' second
# order in it): measured 1.7e-4–3.1e-4 on the trimmed rotor at 120 kt, 9e-4–1.2e-3 on the
# rolling disc at a perturbation of 1e-4; beyond it the map is not the linear operator
# Arnoldi assumed (3e-2 to 0.55 where the marches followed different Newton paths).
FRESH_LIMIT = 1e-2
# The weight of a random direction in Arnoldi's start, beside the unit transient the run left.
# The transient holds the slowest modes only as far as the run left them: shooting removes
# the modes its extrapolation spans, and on Table 1's locked case shot to a periodicity of
# 1e-3 a start weighted 1e-3 found the neighbouring 0.885 and stopped there, missing the
# largest multiplier 0.912 (marched and fitted independently: 0.91199). Weighted 0.1 it finds
# 0.9121 in 45 vectors; weighted 1, the rotor's many lightly damped blade modes crowd the
# Krylov space, and two of the envelope's 33 trimmed cases ran out of vectors (64).
NOISE = 0.1


def arnoldi(action, v0: Array, steps: int, *, min_steps: int | None = None,
            tol: float = 0.0, ritz_vectors: bool = False, krylov: bool = False
            ) -> tuple:
    """Ritz values of a linear map by Arnoldi iteration from ``v0``, with the residual
    estimate of each (|h_{k+1,k}| |e_kᵀ y| for its unit eigenvector y of the Hessenberg
    matrix: ‖A V y − μ V y‖ for the Ritz pair). Largest modulus first.

    At most ``steps`` steps; from ``min_steps`` on (default ``steps``) it stops once the
    largest Ritz value's residual, relative to its modulus, is within ``tol``, and on an
    invariant subspace. Modified Gram–Schmidt with one reorthogonalization. With
    ``ritz_vectors`` the Ritz vectors V y are returned too (columns, same order); with
    ``krylov`` also the orthonormal Krylov basis V (columns, the k vectors the map was applied
    to) and the Hessenberg matrix H = Vᵀ A V (k × k).
    """
    n = v0.size
    basis = np.zeros((n, steps + 1))
    hess = np.zeros((steps + 1, steps))
    basis[:, 0] = v0 / np.linalg.norm(v0)
    first = steps if min_steps is None else max(1, min(min_steps, steps))

    def ritz(k: int) -> tuple[CArray, Array, CArray]:
        vals, vecs = np.linalg.eig(hess[:k, :k])
        res = np.abs(hess[k, k - 1] * vecs[-1, :])
        order = np.argsort(-np.abs(vals), kind="stable")
        return vals[order].astype(complex), res[order], vecs[:, order]

    k = steps
    for j in range(steps):
        w = np.asarray(action(basis[:, j]), dtype=float)
        for _ in range(2):  # twice is enough (Giraud et al. 2005)
            c = basis[:, : j + 1].T @ w
            w -= basis[:, : j + 1] @ c
            hess[: j + 1, j] += c
        hess[j + 1, j] = np.linalg.norm(w)
        if hess[j + 1, j] <= 1e-14 * np.abs(hess[: j + 1, j]).max():
            hess[j + 1, j] = 0.0
            k = j + 1
            break
        basis[:, j + 1] = w / hess[j + 1, j]
        if j + 1 >= first and j + 1 < steps:
            vals, res, _ = ritz(j + 1)
            if res[0] <= tol * abs(vals[0]):
                k = j + 1
                break
    vals, res, vecs = ritz(k)
    if krylov:
        return vals, res, basis[:, :k] @ vecs, basis[:, :k], hess[:k, :k]
    if ritz_vectors:
        return vals, res, basis[:, :k] @ vecs
    return vals, res


def rolling_pins(system) -> NDArray[np.int64]:
    """The offsets in q of the bodies that roll (:class:`solver.curve_joints.Rolling`'s pins),
    each once."""
    return np.array(sorted({system.offset[e.pin] for e in system.elements
                            if isinstance(e, Rolling)}), dtype=np.int64)


def spin_alignment(pins: NDArray[np.int64], before: Array, after: Array) -> Array:
    """Per rolling pin (offsets ``pins``), the rotation R = D D'ᵀ that takes its triad D' in
    the positions ``after`` back to its triad D in ``before``: on a periodic response the
    pins return to their places but not to their spin angles, and turning each pin's directors
    (and their rates) by R moves the map's output back onto the input's spin (a symmetry of
    the motion), so that outputs and inputs share one tangent space. (k, 3, 3)."""
    out = np.empty((pins.size, 3, 3))
    for j, o in enumerate(pins):
        d = before[o + 3 : o + 12].reshape(3, 3).T  # columns d1, d2, d3
        d1 = after[o + 3 : o + 12].reshape(3, 3).T
        out[j] = d @ d1.T
    return out


def turn_pins(pins: NDArray[np.int64], rot: Array, arrays: list[Array]) -> list[Array]:
    """``arrays`` (positions, rates, …) with each pin's directors turned by its ``rot``."""
    out = [np.copy(x) for x in arrays]
    for o, r in zip(pins, rot, strict=True):
        for x in out:
            x[o + 3 : o + 12] = (x[o + 3 : o + 12].reshape(3, 3) @ r.T).ravel()
    return out


def position_tangent(system, q: Array, t: float):
    """The orthogonal projection of position perturbations δq onto the tangent of the
    holonomic constraints and of the integrals of the velocity-level relations at ``q``:
    G δq = 0 and A δq = 0. Returns δq ↦ projected δq (one factorization, many solves)."""
    n = system.n
    j = constraint_rows(system, q, t).tocsc()
    m = j.shape[0]
    if m == 0:
        return lambda dq: np.array(dq, dtype=float)
    lu = spla.splu(sp.bmat([[sp.identity(n), j.T], [j, None]], format="csc"))

    def project(dq: Array) -> Array:
        return lu.solve(np.concatenate([dq, np.zeros(m)]))[:n]
    return project


def kinetic_metric(system) -> Array:
    """The diagonal metric the map's velocities are made consistent in (see
    :func:`map_multipliers`): the mass matrix's diagonal, a tiny weight on a massless
    coordinate, 1 on a first-order state."""
    mass = np.asarray(system.M.diagonal(), dtype=float)
    metric = np.where(mass > 0, mass, 1e-8 * max(float(mass.max()), 1e-300))
    metric[system.first_order] = 1.0
    return metric


def perturbed(system, arrays: list[Array], delta: list[Array], t: float, metric: Array,
              v_consistent: Array | None = None) -> list[Array]:
    """The state ``arrays`` (positions, velocities, a scheme's history) moved by ``delta`` as
    the map's Jacobian sees a perturbation: positions projected onto the constraints at time
    ``t``, and the velocities' change made consistent with them in the ``metric`` — the
    difference of two projections, so that the velocities keep the component across the
    constraints the scheme's own steps left (``v_consistent``: the projection of the
    unperturbed velocities, if known). The rest is added as it is."""
    out = [a + d for a, d in zip(arrays, delta, strict=True)]
    out[0] = project_positions(system, out[0], t)
    if v_consistent is None:
        v_consistent = project_velocities(system, arrays[0], arrays[1], t, metric)
    out[1] = arrays[1] + (project_velocities(system, out[0], out[1], t, metric)
                          - v_consistent)
    return out


@dataclass
class SlowSubspace:
    """What an Arnoldi run on the map knows of its slow modes, for Newton–Picard shooting.

    ``basis`` holds the Krylov vectors V (columns, in the scaled state of
    :func:`map_multipliers`: the arrays ``keys`` concatenated and divided by ``weight``),
    ``hessenberg`` the map's Jacobian on them, H = Vᵀ M V, and ``observed`` what the caller's
    probe saw of each: C V, C the linear map from a state to the observations of the march
    that starts from it (rows: the observations flattened; columns: the vectors).

    Newton–Picard (Lust, Roose, Spence & Champneys 1998; Shroff & Keller 1993, the recursive
    projection method): on the slow subspace V_p of the Ritz values above a modulus ρ (a
    Schur basis of H), the map's error e_j of iterate j obeys e_{j+1} = H_p e_j; the fast
    rest decays by marching. Two successive iterates' observations differ by
    C V_p (H_p − I) e_{j−1}, which gives the slow error by least squares, and the error two
    iterates on is H_p² e_{j−1}: the correction removes it. The error is measured on
    observations rather than on the state because the state's own change over a map carries
    a floor the motion does not (the rates of fast first-order states, a scheme's history),
    whose projection on V_p, amplified by (I − H_p)⁻¹, would drive the iterates away.

    ``rows`` keeps the probe's rows themselves for each vector (k, steps, columns: the
    perturbed march's rows less the unperturbed one's, over the perturbation; column 0 the
    unperturbed march's, the time), and ``t0`` the time the marches start at: with
    :meth:`pairs`, what a march at another time step (:func:`studies.periodic.step_error`)
    needs of the slow modes.
    """

    keys: list[str]
    weight: Array
    basis: Array
    hessenberg: Array
    observed: Array
    rows: Array | None = None
    t0: float = 0.0

    def pairs(self) -> tuple[Array, Array]:
        """Secant pairs of the map's Jacobian J as the probe's rows see them: (C v_j, C J v_j)
        for the first k − 1 Krylov vectors, each (k − 1, steps, columns) with the time in
        column 0. Arnoldi's relation J V_{k−1} = V_k H_{k,k−1} makes the second exact from
        the k marches: C J v_j = Σ_i h_ij C v_i."""
        if self.rows is None or len(self.rows) < 2:
            raise ValueError("SlowSubspace.pairs: the probe's rows of two vectors at least "
                             "are needed")
        k = len(self.rows)
        u = self.rows[: k - 1].copy()
        ju = np.tensordot(self.hessenberg[:k, : k - 1].T, self.rows, axes=1)
        ju[:, :, 0] = u[:, :, 0]
        return u, ju

    def correction(self, change: Array, scale: Array, rho: float = 0.5,
                   rcond: float = 1e-6) -> tuple[list[Array], float]:
        """The state correction that removes the slow error from the iterate that follows
        the two whose observations differ by ``change`` (the probe's layout, any leading
        shape whose last axis matches ``scale``, each observed column's scale), and the
        part of ``change`` the slow subspace leaves unexplained (relative). The slow modes
        are the Ritz values of modulus above ``rho``; the least squares drop the directions
        whose singular values fall below ``rcond`` of the largest (poorly observed modes).

        Returns the correction as arrays in the order of :attr:`keys` (to be added to the
        iterate, in the phase the map's iterates share) and that residual."""
        t, u, p = schur(self.hessenberg, output="real",
                        sort=lambda re, im: re * re + im * im > rho * rho)
        if p == 0:
            return [np.zeros_like(self.weight[: self.weight.size // len(self.keys)])
                    for _ in self.keys], 1.0
        h = t[:p, :p]
        units = np.broadcast_to(np.asarray(scale, dtype=float), np.shape(change)).ravel()
        live = units > 0
        b = np.ravel(change)[live] / units[live]
        a = (self.observed @ u[:, :p])[live] / units[live, None]
        c, *_ = np.linalg.lstsq(a, b, rcond=rcond)
        norm = np.linalg.norm(b)
        unexplained = float(np.linalg.norm(b - a @ c) / norm) if norm > 0 else 0.0
        e = h @ h @ np.linalg.solve(h - np.eye(p), c)
        x = -(self.basis @ (u[:, :p] @ e)) * self.weight
        n = x.size // len(self.keys)
        return [x[i * n : (i + 1) * n] for i in range(len(self.keys))], unexplained


@dataclass
class MapMultipliers:
    """The dominant Floquet multipliers of a periodic response (:func:`map_multipliers`).

    ``values`` the period's multipliers (the map's Ritz values to the N-th power), largest
    modulus first; ``residuals`` each Ritz pair's residual estimate relative to the largest
    Ritz value's modulus (within the ``accuracy`` asked: converged); ``evaluations`` the
    perturbed integrations of the map spent; ``modes`` the Ritz vectors in the state's units:
    ``modes[i, :, k]`` is the part in the i-th state array (q, v, then the scheme's history)
    of the k-th multiplier's mode (its positions on the constraints' tangent);
    ``fresh_residual`` the largest pair's residual from one more application of the map,
    relative to its Ritz value (the noise of the finite differences shows here, not in
    Arnoldi's estimate); ``subspace`` what the run knows of the slow modes, with a probe
    (:class:`SlowSubspace`)."""

    values: CArray
    residuals: Array
    accuracy: float
    evaluations: int
    modes: CArray
    fresh_residual: float = 0.0
    subspace: SlowSubspace | None = None

    @property
    def failure(self) -> str:
        """Why :attr:`largest` is NaN ("" if it is not), for a case message."""
        if np.isfinite(self.largest):
            return ""
        return (f"no Floquet multipliers: the largest Ritz value {abs(self.values[0]):.4f} "
                f"not converged (residual {self.residuals[0]:.1e}, on a fresh application "
                f"of the map {self.fresh_residual:.1e})")

    @property
    def largest(self) -> float:
        """Modulus of the largest multiplier, NaN unless its Ritz value converged and a fresh
        application of the map confirms it (within :data:`FRESH_LIMIT`)."""
        ok = (self.values.size and self.residuals[0] <= self.accuracy
              and self.fresh_residual <= FRESH_LIMIT)
        return float(np.abs(self.values[0])) if ok else float("nan")


def map_multipliers(integ, steps: int, *, symmetry=None, rate: float = 1.0,
                    vectors: int = 64, min_vectors: int = 24, eps: float = 1e-5,
                    tol: float = 1e-10, accuracy: float = 1e-4, seed: int = 0,
                    probe: Callable[[], Array] | None = None,
                    observe: Callable[[Array], Array] | None = None) -> MapMultipliers:
    """Dominant Floquet multipliers of the periodic response ``integ`` is on.

    Parameters
    ----------
    integ
        An integrator at a state of the periodic response (at the start of a sector when
        ``symmetry`` is given); its state and its step counts are restored on return.
    steps
        Time steps of the map: a period, or one sector of it with ``symmetry``.
    symmetry
        :class:`solver.symmetry.CyclicSymmetry` or ``None``.
    rate
        The motion's frequency unit (rad/s, e.g. the rotor speed): a unit of velocity is
        ``rate`` times one of position and a unit of the scheme's accelerations ``rate``²
        times, so that the Arnoldi vectors, orthonormal in that norm, and the perturbation
        ``eps`` measured in it weigh a mode's position and rates alike.
    vectors, min_vectors
        Most and fewest Arnoldi steps (perturbed integrations of the map).
    eps
        Size of each perturbation in the scaled norm: above Newton's noise (``tol`` times q's
        scale) and below the response's nonlinearity. Generalized-α maps are linear from 1e-3
        to 1e-7 on the rotor; the energy-conserving steps (ep, ed) carry a roundoff in their
        discrete gradients that perturbations below about 1e-5 meet, so 1e-5–1e-4 there.
    tol
        Newton's relative tolerance during the perturbed integrations, well above its
        roundoff floor: there Newton accepts an iteration that stagnates, and that noise over
        ``eps`` swamps the differences.
    accuracy
        Arnoldi stops once the largest Ritz value's residual estimate, relative to its
        modulus, is within this; :attr:`MapMultipliers.largest` is NaN if it is not.
    seed
        Of the random start vector.
    probe, observe
        With ``probe`` (a row of observations of the integrator's state, called after each
        step of every march), the result's :attr:`MapMultipliers.subspace` holds what it saw
        of each Krylov vector: ``observe`` (default: as they are) of the march's rows stacked,
        its difference from the unperturbed march's over the perturbation.
    """
    keys = ["q", "v", *[k for k in integ.STATE if k not in ("t", "q", "v", "lam", "nu")]]
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"map_multipliers: rate = {rate!r} must be finite and > 0")
    w = np.array([rate ** min(i, 2) for i in range(len(keys))])
    base = integ.state()
    # the run's own counts: the perturbed integrations are not its steps
    # (a composed step keeps its own step count beside its wrapped step's)
    owners = [integ, *([integ._inner] if hasattr(integ, "_inner") else [])]
    counters = [(obj, name, getattr(obj, name)) for obj in owners
                for name in ("n_steps", "n_iterations", "n_factorizations") if name in vars(obj)]
    # every unknown to the one tolerance: a looser one on some (a rotor's wake states) lets
    # their Newton error over the perturbation into the differences
    with integ.tightened(tol):
        try:
            return _arnoldi_on_map(integ, steps, keys, np.repeat(w, integ.sys.n), symmetry,
                                   vectors, min_vectors, eps, accuracy, seed, probe,
                                   observe)
        finally:
            integ.restore(base)
            for obj, name, value in counters:
                setattr(obj, name, value)


def _arnoldi_on_map(integ, steps: int, keys: list[str], weight: Array, symmetry,
                    vectors: int, min_vectors: int, eps: float, accuracy: float,
                    seed: int, probe: Callable[[], Array] | None = None,
                    observe: Callable[[Array], Array] | None = None) -> MapMultipliers:
    """:func:`map_multipliers` from ``integ``'s state, ``weight`` the size of a unit of each
    coordinate of the concatenated state arrays ``keys``."""
    system = integ.sys
    n = system.n
    base = integ.state()
    t0 = base["t"]
    count = 0
    pins = rolling_pins(system)
    align: Array | None = None
    # velocities made consistent in the kinetic-energy metric: a massless coordinate (a
    # fictitious link, a joint's scalar) takes whatever rate the constraints imply, so the
    # map acts on the motion of the masses (a massless coordinate's own rate is a state of
    # the scheme only, undamped in an energy-preserving step)
    metric = kinetic_metric(system)

    def consistent(q: Array, v: Array) -> Array:
        return project_velocities(system, q, v, t0, metric)

    seen: list[Array] = []  # the probe's rows of each march
    # the base march's Newton path (an integrator that records one:
    # solver.integrators.NewtonPath), which every march then follows: each step converges in
    # about two iterations on the path's factors, and to well within Newton's tolerance, the
    # base march's own included, so that the differences carry no Newton error
    path = None

    def integrate(arrays: list[Array], record: bool = False) -> list[Array]:
        nonlocal count, path  # the map's raw output
        state = dict(base)
        state.update(zip(keys, arrays, strict=True))
        integ.restore(state)
        integ.forget_factors()  # every march on one Newton path
        mode = (integ.recording() if record else
                contextlib.nullcontext() if path is None else integ.following(path))
        rows = []
        with mode as recorded:
            for _ in range(steps):
                info = integ.step()
                if not info.converged:
                    raise RuntimeError(f"Floquet multipliers: a perturbed step failed at t = "
                                       f"{integ.t:.6g} s: {info.message}")
                if probe is not None:
                    rows.append(np.asarray(probe(), dtype=float))
        if record:
            path = recorded
        if probe is not None:
            seen.append(np.array(rows, dtype=float))
        count += 1
        out = [np.copy(getattr(integ, k)) for k in keys]
        return out if symmetry is None else list(symmetry.back(*out, k=1))

    def finish(out: list[Array]) -> Array:  # in the input's tangent space, scaled
        if align is not None:
            out = turn_pins(pins, align, out)
        # the velocities' component across the constraints is the scheme's own (its two-step
        # mode): the map's state is the tangent part
        out[1] = consistent(out[0], out[1])
        return np.concatenate(out) / weight

    def march(arrays: list[Array]) -> Array:
        return finish(integrate(arrays))

    start = [np.copy(base[k]) for k in keys]
    # the base state on the constraints as the perturbed ones will be (a run's Newton
    # tolerance leaves them violated by more than the projection's: that offset, divided by
    # eps, would swamp the differences)
    start[0] = project_positions(system, start[0], t0)
    v_base = consistent(start[0], start[1])
    if hasattr(integ, "recording"):
        integrate(start, record=True)
        seen.clear()
    raw = integrate(start)
    if pins.size:  # the pins' spin back to the input's, the same turn for every output
        align = spin_alignment(pins, start[0], raw[0])
    x0 = finish(raw)
    tangent = position_tangent(system, start[0], t0)

    def restrict(x: Array) -> Array:  # positions on the constraints' tangent
        x = np.array(x)
        x[:n] = tangent(x[:n] * weight[:n]) / weight[:n]
        return x

    def action(u: Array) -> Array:
        d = restrict(u) * eps * weight
        parts = perturbed(system, start, [d[i * n : (i + 1) * n] for i in range(len(keys))],
                          t0, metric, v_base)
        return restrict((march(parts) - x0) / eps)

    # the start: the map's change of the base state, the transient the run left, which holds
    # the slowest modes (so that a few vectors find them), with a little of every direction
    # so that none is missed
    rng = np.random.default_rng(seed)
    noise = restrict(rng.standard_normal(n * len(keys)))
    change = restrict(x0 - np.concatenate(start) / weight)
    size = np.linalg.norm(change)
    u0 = noise / np.linalg.norm(noise) * NOISE + (change / size if size > 0 else 0.0)
    vals, res, ritz, basis, hess = arnoldi(action, u0, vectors, min_steps=min_vectors,
                                           tol=accuracy, krylov=True)
    subspace = None
    if probe is not None:
        # seen[0] is the base march, seen[1 + j] the march from Krylov vector j
        def observed(block: Array) -> Array:
            return np.asarray(observe(block) if observe is not None else block, dtype=float)

        base_rows, base_observed = seen[0], observed(seen[0])
        k = basis.shape[1]
        cols = [((observed(r) - base_observed) / eps).ravel() for r in seen[1 : 1 + k]]
        rows = np.array([(r - base_rows) / eps for r in seen[1 : 1 + k]])
        rows[:, :, 0] = base_rows[:, 0]
        subspace = SlowSubspace(keys, weight, basis, hess, np.column_stack(cols), rows, t0)
    # the largest pair checked by a fresh application of the map: Arnoldi's residual estimate
    # holds for an exactly linear operator only, and a map whose finite differences carry
    # noise (a Newton stopped at its roundoff floor) can show tiny estimates for a wrong Ritz
    # pair; a fresh residual of that pair measures the noise
    y = ritz[:, 0] / np.linalg.norm(ritz[:, 0])
    image = np.zeros(y.size, dtype=complex)
    for part, unit in ((y.real, 1.0), (y.imag, 1j)):
        size = np.linalg.norm(part)
        if size > 1e-8:  # (the imaginary part of a real pair's vector is roundoff)
            image += unit * size * action(part / size)
    fresh = float(np.linalg.norm(image - vals[0] * y) / max(abs(vals[0]), 1e-300))
    sectors = 1 if symmetry is None else symmetry.n_sectors
    rel = res / max(float(np.abs(vals).max()), 1e-300)
    mult = vals**sectors
    order = np.argsort(-np.abs(mult), kind="stable")
    return MapMultipliers(mult[order], rel[order], accuracy, count,
                          (ritz[:, order] * weight[:, None]).reshape(len(keys), n, -1), fresh,
                          subspace)
