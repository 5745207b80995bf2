"""Branches of the hub model's periodic response, with their Floquet stability.

A branch (:mod:`studies.branches`) follows the hub's periodic response in one numeric
parameter by pseudo-arclength continuation (:func:`solver.continuation.continue_branch`), so
that it turns around the folds of a softening or hardening absorber, by either of two methods:

``harmonic_balance`` (free bifilars)
    The exact equations on swing coordinates (:mod:`studies.reduced_hub`) solved for σ_0's
    harmonics 0…24 on 128 samples a revolution (their residual ~1e-10 of the swing's
    accelerations, where the start's 12 on 64 leave 6e-5). Stability from the linearization
    of all 2 + N coordinates (:func:`studies.reduced_hub.linearization`: the perturbations
    need not share the response's sector symmetry), integrated over a sector
    (:func:`studies.reduced_hub.floquet_multipliers`). Hill's method
    (:func:`solver.floquet.hill_multipliers`) on the same linearization gives the same
    largest multiplier (to 1e-9; 4e-6 at a fold, tests), but its 300 × 300 eigenproblem
    takes 0.15–7 s a point where the sector's integration takes 0.03 s.
``shooting`` (any ``bifilar``)
    The multibody model itself, on the quarter-revolution map in minimal coordinates: the
    hub centre's position and velocity and each bifilar's pin angle and rate (12 numbers) give
    a consistent multibody state (:func:`studies.hub.build`), a quarter revolution is marched,
    the bifilars are renumbered (bifilar k + 1 takes bifilar k's place) and the same 12
    numbers read back. Its Jacobian, by finite differences, is the Newton matrix of the
    corrector and, at the solution, the quarter-revolution monodromy matrix in coordinates
    that satisfy the constraints by construction: its eigenvalues to the fourth power are the
    revolution's Floquet multipliers with the constraint directions removed.

Each point carries the outputs ``simulate`` would archive for that periodic response (from the
exact solution or one recorded revolution of the multibody model), so a branch archives the
same harmonics as a case.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import xarray as xr

from solver.continuation import continue_branch
from solver.floquet import multipliers
from solver.system import System
from studies import hub
from studies.absorbers import N_BIFILARS, AbsorberProbe, AbsorberStart
from studies.backbones import backbone
from studies.bifilar import pin_angle
from studies.branches import BranchPoint, BranchResult, Continuation
from studies.holes import MAX_TANGENT_ANGLE
from studies.parameters import ParameterError, Parameters
from studies.periodic import stepper
from studies.reduced_hub import (
    HarmonicBalance,
    PeriodicSwing,
    floquet_multipliers,
    tangent_angle,
)

BALANCE_HARMONICS = 24  # σ_0's harmonics on a branch (module docstring)
BALANCE_SAMPLES = 128
SWING_SCALE = np.radians(20.0)  # rad: the swing's scale in the arclength (balance_branch)
OUTPUT_SAMPLES = 64  # samples of the revolution a harmonic-balance point archives
# the backbone's swing amplitudes (degree): the holes cover the path to 70°
BACKBONE_AMPLITUDES = np.arange(2.0, 70.1, 2.0)
# a multiplier this far outside the unit circle, or closer, counts as on it (stable): the
# sector monodromy's multipliers are right to 2e-8, the shooting Jacobian's to ~1e-5 (tests)
STABILITY_MARGIN = 1e-6
# The shooting map's Newton matrix by forward differences of this step in the scaled
# coordinates (1e-5 of 1° of swing): its truncation error, ~1e-5 relative, is also the
# multipliers' accuracy; the map itself is evaluated with the time step's Newton solved to
# MAP_NEWTON_TOL, so that its roundoff (~1e-12) stays far below the differences.
SHOOTING_STEP = 1e-5
MAP_NEWTON_TOL = 1e-12
SHOOTING_TOLERANCE = 1e-7  # the corrector's last update over the unknowns' scales


def branch(p: Parameters, c: Continuation) -> BranchResult:
    """The hub's branch of periodic responses from ``p`` (the continued parameter at
    ``c.start``) as ``c`` says: harmonic balance for free bifilars (``method = "auto"``),
    shooting otherwise; with free bifilars also their backbone (:func:`backbone_dataset`).

    Raises
    ------
    ParameterError
        For a method the case's absorber has no equations for.
    RuntimeError
        If the first point is not found.
    """
    method = c.method
    if method == "auto":
        method = "harmonic_balance" if p.bifilar == "free" else "shooting"
    if method == "harmonic_balance":
        if p.bifilar != "free":
            raise ParameterError(f"method = 'harmonic_balance' needs bifilar = 'free' (its "
                                 f"swing coordinates); got {p.bifilar!r}: use 'shooting'")
        return BranchResult(balance_branch(p, c), backbone_dataset(p))
    if p.bifilar == "equivalent":
        raise ParameterError("bifilar = 'equivalent' has no branches: its response is linear "
                             "(studies.equivalent gives it in closed form)")
    extras = backbone_dataset(p) if p.bifilar == "free" else xr.Dataset()
    return BranchResult(shooting_branch(p, c), extras)


def backbone_dataset(p: Parameters) -> xr.Dataset:
    """The case's backbone (:func:`studies.backbones.backbone`) at
    :data:`BACKBONE_AMPLITUDES`: ``backbone_order`` along ``backbone_amplitude``."""
    order = backbone(hub.design(p).holes, p.hub_speed, np.radians(BACKBONE_AMPLITUDES))
    return xr.Dataset(
        {"backbone_order": ("backbone_amplitude", order,
                            {"units": "1", "long_name": "free-vibration tuning order of the "
                             "bifilar (unforced, undamped, hub centre fixed) against its "
                             "swing amplitude"})},
        coords={"backbone_amplitude": ("backbone_amplitude", BACKBONE_AMPLITUDES,
                                       {"units": "degree",
                                        "long_name": "largest pin angle of the free swing"})})


def _varied(p: Parameters, name: str) -> Callable[[float], Parameters | None]:
    """p with parameter ``name`` set to a value, or None where that value is invalid (the
    branch stops there)."""
    def at(value: float) -> Parameters | None:
        try:
            return p.replace(**{name: float(value)})
        except ParameterError:
            return None
    return at


def _swing_limit_exceeded(sol: PeriodicSwing) -> bool:
    """Whether the swing turns the path's tangent beyond the holes' extent."""
    t = 2 * np.pi / sol.model.hub_speed * np.arange(BALANCE_SAMPLES) / BALANCE_SAMPLES
    return bool(np.abs(tangent_angle(sol.model.holes, sol.sigma(t))[0]).max()
                > MAX_TANGENT_ANGLE)


def balance_branch(p: Parameters, c: Continuation) -> list[BranchPoint]:
    """The branch by harmonic balance on swing coordinates (module docstring)."""
    at = _varied(p, c.parameter)
    cache: dict[float, HarmonicBalance | None] = {}

    def balance(value: float) -> HarmonicBalance | None:
        if value not in cache:
            if len(cache) > 8:
                cache.clear()
            q = at(value)
            cache[value] = (None if q is None else HarmonicBalance(
                hub.reduced_model(q, hub.design(q)), BALANCE_HARMONICS, BALANCE_SAMPLES))
        return cache[value]

    def residual(x: np.ndarray, value: float) -> np.ndarray:
        b = balance(value)
        return np.full(len(x), np.nan) if b is None else b.residual(x)

    p0 = at(c.start)
    d0 = hub.design(p0)
    guess = hub.reduced_response(p0, d0)  # the start's solve (from the linear response)
    b0 = balance(c.start)
    x0 = b0.unknowns(guess.sigma(b0.t))
    t0 = time.perf_counter()
    # arclength: a change of the swing's harmonics by SWING_SCALE counts as much as crossing
    # the parameter's range (at the small-swing start the default, its harmonics' size, would
    # make the large swing's steps tiny)
    found = continue_branch(residual, x0, c.start, c.stop, step=c.step, min_step=c.min_step,
                            max_step=c.max_step, max_points=c.max_points,
                            x_scale=max(float(np.abs(x0).max()), SWING_SCALE))
    points = []
    note = "" if found.complete else f"branch ended early: {found.reason}"
    for pt in found.points:
        q = at(pt.parameter)
        sol = balance(pt.parameter).solution(pt.x)
        if _swing_limit_exceeded(sol):
            note = (f"branch ended at {c.parameter} = {pt.parameter:g}: the swing turns the "
                    f"path beyond the holes' {np.degrees(MAX_TANGENT_ANGLE):g}°")
            break
        mult = floquet_multipliers(sol)
        d = hub.design(q)
        facts = _facts(q, d, iterations=pt.iterations, change=sol.residual,
                       seconds=time.perf_counter() - t0, samples=OUTPUT_SAMPLES)
        t = 2 * np.pi / q.hub_speed * np.arange(OUTPUT_SAMPLES) / OUTPUT_SAMPLES
        result = _point_result(q.hub_speed, hub.solution_rows(q, d, sol, t), facts)
        points.append(BranchPoint(pt.parameter, result, mult, _stable(mult), pt.fold))
    return _noted(points, note)


def _noted(points: list[BranchPoint], note: str) -> list[BranchPoint]:
    """``points`` with why the branch ended early (if it did) as their results' message."""
    for pt in points:
        pt.result.attrs["message"] = note
    return points


def _stable(mult: np.ndarray) -> bool:
    return bool(np.max(np.abs(mult)) <= 1.0 + STABILITY_MARGIN)


def _facts(p: Parameters, d: hub.HubDesign, *, iterations: int, change: float,
           seconds: float, samples: int, revolutions: float = 0.0, steps: int = 0
           ) -> dict[str, np.generic]:
    """The hub's declared run facts for a branch point: one revolution recorded at
    ``samples`` a revolution; ``revolutions`` and ``steps`` those the branch had simulated
    up to this point (0 for the harmonic balance); ``change`` the solution's residual."""
    return {
        "run_hub_speed": np.float64(p.hub_speed),
        "run_revolutions": np.int32(1),
        "run_samples_per_rev": np.int32(samples),
        "run_transient_revolutions": np.int32(0),
        "run_simulated_revolutions": np.float64(revolutions),
        "run_periodicity_change": np.float64(change),
        "run_extrapolated": np.int32(0),
        "run_extrapolation_residual": np.float64(0.0),
        "run_shooting_restarts": np.int32(0),
        "run_steps": np.int32(steps),
        "run_newton_iterations": np.int32(iterations),
        "run_solver_seconds": np.float64(seconds),
        "run_richardson": np.int32(0),
        "run_estimate_revolutions": np.float64(0.0),
        "run_estimate_samples_per_rev": np.int32(0),
        "run_substeps": np.int32(0),
        "tuning_order_linear": np.float64(d.holes.order_linear),
        "pin_damping": np.float64(d.pin_damping),
        "effective_fuselage_stiffness": np.float64(d.fuselage_stiffness),
        "fuselage_damping": np.float64(d.fuselage_damping),
    }


def _point_result(omega: float, rows: np.ndarray, facts: dict[str, np.generic]
                  ) -> xr.Dataset:
    return hub.SPEC.dataset({**hub.recorded_outputs(omega, rows), **facts},
                            {"message": ""})


class QuarterMap:
    """The multibody hub's quarter-revolution map in minimal coordinates (module docstring):
    y = (x, y, ẋ, ẏ of the hub centre (m, m/s), the pin angles φ_k, their rates φ̇_k (rad,
    rad/s)) at t = 0 → the same a quarter revolution later, bifilars renumbered. ``spent``
    (shared by the maps of one branch) counts the revolutions and time steps simulated."""

    def __init__(self, p: Parameters, spent: dict[str, float] | None = None) -> None:
        self.p, self.d = p, hub.design(p)
        self.steps = p.steps_per_rev // N_BIFILARS
        self.spent = {"revolutions": 0.0, "steps": 0} if spent is None else spent

    def start(self, y: np.ndarray) -> AbsorberStart:
        n = N_BIFILARS
        return AbsorberStart(angles=y[4: 4 + n], rates=y[4 + n:],
                             center=np.array([y[0], y[1], 0.0]),
                             velocity=np.array([y[2], y[3], 0.0]))

    def integrator(self, y: np.ndarray):
        """The composed ep integrator of the model built at state ``y``, and its handles."""
        p = self.p
        model, hub_body, shaft, parts = hub.build(p, self.d, self.start(y))
        sysm = System(model)
        return (hub.time_integration(p, sysm, tol=MAP_NEWTON_TOL), sysm, hub_body, shaft,
                parts)

    def read(self, sysm: System, hub_body, shaft, parts, q: np.ndarray,
             v: np.ndarray) -> np.ndarray:
        """The minimal coordinates of the multibody state (q, v), in the bifilars' order."""
        o = sysm.offset[shaft]
        if self.p.bifilar == "free":
            w_hub = sysm.angular_velocity(q, v, hub_body)[2]
            phis = [pin_angle(sysm, b, hub_body, q) for b in parts]
            rates = [sysm.angular_velocity(q, v, b.link1)[2] - w_hub for b in parts]
        else:  # locked and equivalent: the swing is not a coordinate of the map
            phis = rates = [0.0] * N_BIFILARS
        return np.concatenate([q[o: o + 2], v[o: o + 2], phis, rates])

    def __call__(self, y: np.ndarray) -> np.ndarray:
        integ, sysm, hub_body, shaft, parts = self.integrator(y)
        step = stepper(integ, self.p.hub_speed)
        for _ in range(self.steps):
            step()
        self.spent["revolutions"] += 1 / N_BIFILARS
        self.spent["steps"] += self.steps
        # bifilar k's place a quarter revolution on is bifilar k + 1's at t = 0
        return _renumbered(self.read(sysm, hub_body, shaft, parts, integ.q, integ.v), 1)


def _renumbered(y: np.ndarray, sectors: int) -> np.ndarray:
    """Minimal coordinates read ``sectors`` sector periods after t = 0, with each bifilar's
    angle and rate moved to the place its bifilar had at t = 0."""
    n = N_BIFILARS
    out = y.copy()
    out[4: 4 + n] = np.roll(y[4: 4 + n], sectors)
    out[4 + n:] = np.roll(y[4 + n:], sectors)
    return out


def _live(p: Parameters) -> np.ndarray:
    """Which minimal coordinates the map has: all with free bifilars, the hub's alone with
    locked ones."""
    return np.arange(4 + 2 * N_BIFILARS) < (4 + 2 * N_BIFILARS if p.bifilar == "free" else 4)


def _forward_columns(residual: Callable[[np.ndarray], np.ndarray], u: np.ndarray,
                     f0: np.ndarray) -> np.ndarray:
    """∂residual/∂u at u (where it is f0) by forward differences of :data:`SHOOTING_STEP`:
    one quarter revolution a column."""
    return np.column_stack([(residual(u + SHOOTING_STEP * e) - f0) / SHOOTING_STEP
                            for e in np.eye(len(u))])


def _revolution_multipliers(jac: np.ndarray) -> np.ndarray:
    """The revolution's multipliers, largest modulus first, of the quarter map's Jacobian
    minus the identity (``jac``): the N-th powers of the quarter map's eigenvalues."""
    mult = multipliers(jac + np.eye(len(jac))) ** N_BIFILARS
    return mult[np.argsort(-np.abs(mult))]


def _scales(p: Parameters) -> np.ndarray:
    """Scales of the minimal coordinates: the hub's static deflection under the 3P shear,
    1° of swing, times Ω for the rates."""
    k, _ = hub.fuselage(p)
    z = max(p.excitation_3p, p.excitation_5p, 1.0) / k
    s = np.array([z, z, z * p.hub_speed * 4, z * p.hub_speed * 4,
                  *[np.radians(1.0)] * N_BIFILARS, *[np.radians(1.0) * p.hub_speed * 3]
                  * N_BIFILARS])
    return s


def run_multipliers(p: Parameters, integ, sysm: System, hub_body, shaft, parts
                    ) -> np.ndarray:
    """The revolution's Floquet multipliers of a run's periodic response from its integrator
    at the end of the recording (a whole number of quarter revolutions): the quarter map's
    Jacobian (:class:`QuarterMap`) at the state read there, bifilars renumbered to the
    start's places. Largest modulus first."""
    qm = QuarterMap(p)
    sectors = round(integ.t * p.hub_speed * N_BIFILARS / (2 * np.pi))
    y = _renumbered(qm.read(sysm, hub_body, shaft, parts, integ.q, integ.v), sectors)
    scale, live = _scales(p), _live(p)

    def residual(u: np.ndarray) -> np.ndarray:
        z = y.copy()
        z[live] = u * scale[live]
        return (qm(z) - z)[live] / scale[live]

    u0 = y[live] / scale[live]
    return _revolution_multipliers(_forward_columns(residual, u0, residual(u0)))


def shooting_branch(p: Parameters, c: Continuation) -> list[BranchPoint]:
    """The branch by shooting on the multibody model's quarter-revolution map (module
    docstring)."""
    at = _varied(p, c.parameter)
    p0 = at(c.start)
    d0 = hub.design(p0)
    start, _ = hub.initial_start(p0, d0)
    scale, live = _scales(p0), _live(p)
    maps: dict[float, QuarterMap | None] = {}
    spent = {"revolutions": 0.0, "steps": 0}  # by every map of the branch

    def quarter(value: float) -> QuarterMap | None:
        if value not in maps:
            if len(maps) > 4:
                maps.clear()
            q = at(value)
            maps[value] = None if q is None else QuarterMap(q, spent)
        return maps[value]

    def full(u: np.ndarray) -> np.ndarray:
        y = np.zeros(len(scale))
        y[live] = u * scale[live]
        return y

    def residual(u: np.ndarray, value: float) -> np.ndarray:
        qm = quarter(value)
        if qm is None:
            return np.full(len(u), np.nan)
        try:
            y = full(u)
            return (qm(y) - y)[live] / scale[live]
        except RuntimeError:
            return np.full(len(u), np.nan)

    y0 = np.concatenate([start.center[:2], start.velocity[:2], start.angles, start.rates])
    u0 = y0[live] / scale[live]
    t0 = time.perf_counter()

    def jacobian(u: np.ndarray, value: float) -> tuple[np.ndarray, np.ndarray]:
        # forward differences: 1 + n + 1 quarter revolutions
        f0 = residual(u, value)
        dl = SHOOTING_STEP * max(abs(value), abs(c.stop - c.start))
        return (_forward_columns(lambda x: residual(x, value), u, f0),
                (residual(u, value + dl) - f0) / dl)

    found = continue_branch(residual, u0, c.start, c.stop, jacobian=jacobian, step=c.step,
                            min_step=c.min_step, max_step=c.max_step,
                            max_points=c.max_points, tolerance=SHOOTING_TOLERANCE,
                            x_scale=np.ones(len(u0)))
    note = "" if found.complete else f"branch ended early: {found.reason}"
    points = []
    for pt in found.points:
        q = at(pt.parameter)
        # the quarter-revolution monodromy in the scaled coordinates: J_x = M_s − I
        mult = _revolution_multipliers(pt.jacobian)
        qm = quarter(pt.parameter) or QuarterMap(q, spent)
        y = full(pt.x)
        rows, end = _record(qm, y)
        facts = _facts(q, qm.d, iterations=pt.iterations,
                       change=float(np.max(np.abs(end - y)[live] / scale[live])),
                       seconds=time.perf_counter() - t0, samples=q.steps_per_rev,
                       revolutions=spent["revolutions"], steps=int(spent["steps"]))
        points.append(BranchPoint(pt.parameter, _point_result(q.hub_speed, rows, facts),
                                  mult, _stable(mult), pt.fold))
    return _noted(points, note)


def _record(qm: QuarterMap, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One revolution of the multibody model from the periodic state ``y``, sampled after
    each step as :func:`studies.hub.simulate` samples it, and the minimal coordinates at its
    end (the bifilars back in their places: y again on a periodic response)."""
    integ, sysm, hub_body, shaft, parts = qm.integrator(y)
    sample = hub.recorder(integ, qm.d, AbsorberProbe(sysm, parts, hub_body), sysm.offset[shaft])
    step, rows = stepper(integ, qm.p.hub_speed), []
    for _ in range(qm.p.steps_per_rev):
        step()
        rows.append(sample())
    qm.spent["revolutions"] += 1
    qm.spent["steps"] += qm.p.steps_per_rev
    return np.array(rows), qm.read(sysm, hub_body, shaft, parts, integ.q, integ.v)
