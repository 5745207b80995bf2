"""March a rotor model revolution by revolution until its response is periodic, then record.

A rotor in steady flight has a periodic response once its transients (the slow lag mode, the
bifilars' free swing, the fuselage modes) have decayed. The runs march whole revolutions and
compare the per-rev harmonics of chosen signals between successive revolutions; when the
largest change, relative to each signal's largest harmonic, is within the tolerance, the next
``revolutions`` whole revolutions are recorded (paper: "the simulations were run for several
main rotor revolutions until a periodic solution was reached"). With an extrapolation window
the periodic response is also estimated as the limit of the marched revolutions (reduced-rank
extrapolation), which settles the rotor's slow lag and pendulum modes in a handful of
revolutions instead of dozens (:func:`march`).

:func:`shoot` goes further for models with a cyclic symmetry (four blades, four bifilars): it
extrapolates the fixed point of the one-N-th-revolution map and restarts the model from it,
so that the recorded revolutions are marched from a periodic state. :func:`sector_response`
finds the periodic response of the same model at another time step from there, by
extrapolating a few iterates of its sector map, and :func:`richardson` compares the harmonics
of the two steps: the time-step error of the harmonics, and their extrapolation to zero step.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline

from solver.integrators import project_positions
from solver.period_map import kinetic_metric, perturbed
from solver.symmetry import affine_combination
from studies.parameters import Output, Param, ParameterError, Parameters
from studies.progress import report

Array = NDArray[np.float64]


def to_rotating(omega: float, t: ArrayLike, x: ArrayLike, y: ArrayLike) -> tuple[Array, Array]:
    """In-plane components (x, y) of the fixed frame in the hub frame at ψ = Ωt."""
    psi = omega * np.asarray(t)
    cs, sn = np.cos(psi), np.sin(psi)
    return cs * x + sn * y, -sn * x + cs * y


def stepper(integ, omega: float) -> Callable[[], None]:
    """One time step of ``integ``; raises RuntimeError naming the time and the revolution if
    Newton fails."""
    def step() -> None:
        info = integ.step()
        if not info.converged:
            raise RuntimeError(f"time step failed at t = {integ.t:.6g} s (revolution "
                               f"{integ.t * omega / (2 * np.pi):.2f}): {info.message}")
    return step


# The marching parameter every periodic model declares (studies.hub, studies.rotor).
PARAMETERS: dict[str, Param] = {
    "extrapolation_window": Param(
        8, "1", "revolutions whose changes estimate the periodic response by reduced-rank "
        "extrapolation of the marched revolutions (0: march only)", minimum=0, maximum=20),
}


# What every periodic model reports of its run, as declared scalar results (the archive keeps
# them under these names): the recording's time base, how the periodic response was reached
# and what it cost.
RUN_OUTPUTS: dict[str, Output] = {
    "run_hub_speed": Output("rad s-1", "rotor speed", dims=()),
    "run_revolutions": Output("1", "revolutions recorded", dims=()),
    "run_samples_per_rev": Output("1", "samples per revolution", dims=()),
    "run_transient_revolutions": Output("1", "revolutions simulated before recording",
                                        dims=()),
    "run_simulated_revolutions": Output(
        "1", "revolutions simulated in all: transient, recorded and those of the step-error "
        "estimate's coarser step", dims=()),
    "run_periodicity_change": Output(
        "1", "last change of the harmonics between successive revolutions (or iterates of "
        "the quarter-revolution map), relative to the largest", dims=()),
    "run_extrapolated": Output("1", "1 if the recorded revolutions are the extrapolated limit "
                               "of the marched ones, else 0", dims=()),
    "run_extrapolation_residual": Output("1", "unexplained part of that extrapolation",
                                         dims=()),
    "run_shooting_restarts": Output("1", "restarts from an extrapolated periodic state",
                                    dims=()),
    "run_steps": Output("1", "time steps taken", dims=()),
    "run_newton_iterations": Output("1", "Newton iterations taken", dims=()),
    "run_solver_seconds": Output("s", "time spent in the run", dims=()),
}


def run_facts(rec: PeriodicRecord, *, hub_speed: float, revolutions: int,
              samples_per_rev: int, transient: int, simulated: float, steps: int,
              iterations: int, seconds: float) -> dict[str, np.generic]:
    """The values of :data:`RUN_OUTPUTS` for a run that recorded ``rec`` (counts as int32,
    as the archive stores them)."""
    return {
        "run_hub_speed": np.float64(hub_speed),
        "run_revolutions": np.int32(revolutions),
        "run_samples_per_rev": np.int32(samples_per_rev),
        "run_transient_revolutions": np.int32(transient),
        "run_simulated_revolutions": np.float64(simulated),
        "run_periodicity_change": np.float64(rec.change),
        "run_extrapolated": np.int32(rec.extrapolated),
        "run_extrapolation_residual": np.float64(rec.residual),
        "run_shooting_restarts": np.int32(rec.restarts),
        "run_steps": np.int32(steps),
        "run_newton_iterations": np.int32(iterations),
        "run_solver_seconds": np.float64(seconds),
    }


def check(p: Parameters) -> None:
    """Cross-checks of the marching and shooting parameters (:data:`PARAMETERS`,
    :func:`shooting_parameters` and the model's own ``revolutions`` and ``max_revolutions``)."""
    if p.revolutions > p.max_revolutions:
        raise ParameterError(f"revolutions = {p.revolutions} must not exceed max_revolutions = "
                             f"{p.max_revolutions}")
    for name in ("extrapolation_window", "shooting_window"):
        if getattr(p, name, 0) == 1:
            raise ParameterError(f"{name} = 1: must be 0 (march only) or at least 2 (an "
                                 "extrapolation needs two changes)")


def rev_harmonics(block: Array, n_max: int = 8) -> NDArray[np.complex128]:
    """Complex per-rev harmonics 0..n_max of the columns of one revolution of samples."""
    f = np.fft.rfft(block, axis=0) / block.shape[0]
    return f[: n_max + 1]


def harmonic_scales(cur: NDArray[np.complex128], groups: Sequence[int] | None = None,
                    separate_mean: bool = False, floor: ArrayLike | None = None) -> Array:
    """The scale each harmonic of each column is judged against (same shape as ``cur``).

    The scale of a column is its largest harmonic, or with ``groups`` (``groups[j]`` labels
    column j) the largest of its group: the x and y of one vector share a scale, so that a
    component near zero is not held to its own tiny size. With ``separate_mean`` the
    vibratory harmonics (1 and up) are judged against the largest vibratory harmonic and the
    mean against the larger of itself and that: a steady force of kilonewtons does not hide a
    change of a vibratory harmonic of tens of newtons, and a mean near zero is not held to
    its own tiny size. All-zero scales (locked pins) stay zero: those columns are skipped.

    ``floor`` (one value per column, in its units) is the smallest scale a column is judged
    against: a response with no vibration of its own (a rotor in hover, axisymmetric: its
    fixed-frame hub loads steady, its pins at rest) has only the decaying transient in its
    vibratory harmonics, whose change between revolutions stays of the order of their own
    size however small they get; the floor says below which size a harmonic counts as zero.
    Floors below the scales a response has change nothing.
    """
    def group_max(a: Array) -> Array:
        a = a.copy()
        if groups is not None:
            labels = np.asarray(groups)
            for g in np.unique(labels):
                a[labels == g] = a[labels == g].max()
        return a

    mag = np.abs(cur)
    scale = np.empty(cur.shape)
    if separate_mean:
        vib = group_max(mag[1:].max(axis=0))
        scale[0] = np.maximum(group_max(mag[0]), vib)
        scale[1:] = vib
    else:
        scale[:] = group_max(mag.max(axis=0))
    if floor is not None:
        scale = np.where(scale > 0, np.maximum(scale, np.asarray(floor, dtype=float)), 0.0)
    return scale


def harmonic_change(cur: NDArray[np.complex128], prev: NDArray[np.complex128],
                    groups: Sequence[int] | None = None, separate_mean: bool = False,
                    floor: ArrayLike | None = None) -> float:
    """Largest change of a harmonic between two revolutions, relative to its scale
    (:func:`harmonic_scales` of ``cur``)."""
    scale = harmonic_scales(cur, groups, separate_mean, floor)
    live = scale > 0
    if not np.any(live):
        return 0.0
    return float(np.max(np.abs(cur - prev)[live] / scale[live]))


def rre_weights(seq: Sequence[Array], rcond: float = 1e-10) -> tuple[Array, float]:
    """Reduced-rank extrapolation (Sidi 2017, *Vector Extrapolation Methods*, ch. 1) of a
    sequence s_0 … s_k converging linearly to a fixed point: the weights γ_1 … γ_k with
    Σγ = 1 that minimize ‖Σ_j γ_j (s_j − s_{j−1})‖, so that s* ≈ Σ_j γ_j s_j.

    For a linear map s_{j+1} − s* = M (s_j − s*) whose transient lies in k − 1 eigenvectors
    the result is exact; the weights are those of the polynomial that annihilates the
    transient's eigenvalues, so they apply unchanged to any other linear observation of the
    same sequence (e.g. the whole state, when ``seq`` holds a few measured harmonics).

    Returns
    -------
    gamma : ndarray, shape (k,)
        The weights of s_1 … s_k.
    residual : float
        ‖Σ γ_j Δs_j‖ / ‖Δs_k‖: the part of the last change the extrapolation cannot explain
        (0 for an exact linear sequence, near 1 when it explains nothing).
    """
    s = np.array([np.concatenate([np.real(x).ravel(), np.imag(x).ravel()]) for x in seq])
    d = np.diff(s, axis=0).T  # (m, k): the changes Δs_1 … Δs_k
    k = d.shape[1]
    if k == 1:
        return np.ones(1), 1.0
    # γ_k = 1 − Σ_{j<k} γ_j: minimize ‖Δs_k + Σ_{j<k} γ_j (Δs_j − Δs_k)‖
    a = d[:, :-1] - d[:, -1:]
    g, *_ = np.linalg.lstsq(a, -d[:, -1], rcond=rcond)
    gamma = np.append(g, 1.0 - g.sum())
    last = np.linalg.norm(d[:, -1])
    residual = float(np.linalg.norm(d @ gamma) / last) if last > 0 else 0.0
    return gamma, residual


def secant_weights(windows: Sequence[Sequence[Array]], rcond: float = 1e-10
                   ) -> tuple[Array, float]:
    """Fixed point of a map by a secant (Anderson type II) step over the iterates it is known
    at: ``windows`` are runs of successive iterates x_0, x_1, … of the map (each the same
    linear observation, e.g. scaled samples), the last run ending at the current iterate x_k.

    Within each run, three successive iterates give a secant pair of the map's Jacobian J:
    u = x_i − x_{i−1} and Ju = x_{i+1} − x_i. With g = x_k − x_{k−1} the last change, c
    minimizes ‖g − (JU − U) c‖ and the fixed point is x* = x_k − (JU) c: Newton's step with
    J known on the pairs' span and the part of g outside it taken as decayed (fast modes).
    Runs from earlier starts (an earlier shooting window, the same map at another time step)
    add what they know of the slow modes to the current run's own pairs. For a linear map
    whose transient lies in the pairs' span the estimate is exact.

    Returns
    -------
    weights : ndarray
        Affine weights (sum 1) over the iterates of all runs in order, so that Σ w_j x_j is
        x* (and the same combination of any other linear observation of the iterates, e.g.
        the states, is its fixed point).
    residual : float
        ‖g − (JU − U) c‖ / ‖g‖: the part of the last change the pairs leave unexplained.
    """
    w, _, residual = secant_step(windows, rcond=rcond)
    return w, residual


def secant_step(windows: Sequence[Sequence[Array]], pairs: tuple[Array, Array] | None = None,
                rcond: float = 1e-10) -> tuple[Array, Array, float]:
    """:func:`secant_weights` with secant pairs known besides the runs': ``pairs`` (U, JU),
    each (p, …) in the iterates' layout, the map's Jacobian's images JU of the changes U
    (e.g. :meth:`solver.period_map.SlowSubspace.pairs`). The fixed point is then
    x* = Σ w_j x_j − Σ_i c_i (JU)_i.

    Returns
    -------
    weights : ndarray
        Affine weights over the runs' iterates, as :func:`secant_weights`'s.
    coefficients : ndarray, shape (p,)
        The c_i of the given pairs (empty without them).
    residual : float
        The part of the last change all pairs leave unexplained.
    """
    flat = [np.ravel(x) for run in windows for x in run]
    if len(windows[-1]) < 2:
        raise ValueError("secant_weights: the last run needs two iterates (a change)")
    ends = np.cumsum([len(run) for run in windows])
    triples = [(i - 1, i, i + 1) for start, end in zip(ends - np.diff(ends, prepend=0), ends,
                                                        strict=True)
               for i in range(start + 1, end - 1)]
    k = len(flat) - 1
    g = flat[k] - flat[k - 1]
    w = np.zeros(len(flat))
    w[k] = 1.0
    norm = np.linalg.norm(g)
    u, ju = (np.zeros((0, g.size)), np.zeros((0, g.size))) if pairs is None else (
        np.reshape(pairs[0], (len(pairs[0]), -1)), np.reshape(pairs[1], (len(pairs[1]), -1)))
    if not triples and not len(u):
        return w, np.zeros(0), 1.0
    y = np.column_stack([*(flat[c] - 2 * flat[b] + flat[a] for a, b, c in triples),
                         *(ju - u)])
    coef, *_ = np.linalg.lstsq(y, g, rcond=rcond)
    for (_, b, c), x in zip(triples, coef[: len(triples)], strict=True):
        # x* = x_k − Σ c (x_c − x_b)
        w[c] -= x
        w[b] += x
    residual = float(np.linalg.norm(g - y @ coef) / norm) if norm > 0 else 0.0
    return w, coef[len(triples) :], residual


@dataclass
class PeriodicRecord:
    """Whole revolutions of samples once periodic.

    ``samples`` (revolutions × steps_per_rev, columns of the sampler) with time in column 0;
    ``transient`` the revolutions marched before recording; ``change`` the last periodicity
    change; ``extrapolated`` whether the samples are the extrapolated limit of the marched
    revolutions (:func:`march`) rather than marched ones, and ``residual`` that
    extrapolation's unexplained part (:func:`rre_weights`); ``restarts`` how often
    :func:`shoot` restarted the model from an extrapolated state, and ``note`` what the case
    message should say (e.g. that shooting fell back to marching); ``iterates`` the blocks of
    samples of the iterates the last restart was extrapolated from, each with its phase (sector
    periods since t = 0 at its end), one list per window (the last restarts' with
    ``secant``), then the iterates marched since the last restart (near the periodic
    response, where the map is nearly linear) until they changed by at most the tolerance: a
    record of the slow modes for :func:`sector_response`.
    """

    samples: Array
    transient: int
    change: float
    extrapolated: bool = False
    residual: float = 0.0
    restarts: int = 0
    note: str = ""
    iterates: list[list[tuple[Array, int]]] = field(default_factory=list)


def march(step: Callable[[], None], sample: Callable[[], Array],
          signals: Callable[[Array], Array], *, steps_per_rev: int, revolutions: int,
          max_revolutions: int, tolerance: float, groups: Sequence[int] | None = None,
          separate_mean: bool = False, floor: ArrayLike | None = None,
          min_revolutions: int = 2, hint: str = "raise max_revolutions", window: int = 0,
          max_residual: float = 0.1,
          before_recording: Callable[[], None] | None = None) -> PeriodicRecord:
    """March until periodic, then record ``revolutions`` whole revolutions.

    With ``window`` ≥ 2 the periodic response is also estimated as the limit of the sequence
    of marched revolutions: after each revolution, reduced-rank extrapolation
    (:func:`rre_weights`) of the harmonics of the last ``window`` + 1 revolutions (scaled
    as the periodicity test scales them) gives weights γ, and Σ γ_j (revolution j) is the
    estimate — of every sampled column, since the weights annihilate the transient's
    eigenvalues whatever is observed. The estimate is accepted, and recorded (repeated over
    ``revolutions``, with the last marched revolution's times), when it changes by no more
    than ``tolerance`` from the previous revolution's estimate and the extrapolation leaves
    at most ``max_residual`` of the last change unexplained. The slow, lightly damped modes
    of a rotor (the lag mode, the fuselage, the pendulums) then cost a handful of
    revolutions instead of dozens. Whichever comes first, marched or extrapolated, ends the
    transient. The estimate is not a restart: the model's state is never altered (a linear
    combination of beam states is not a consistent state: its strains err at second order).

    Parameters
    ----------
    step
        Advances the model by one time step (raises on failure).
    sample
        The sampled row at the current state (time in s first).
    signals
        Maps one revolution of rows (steps_per_rev × columns) to the columns whose harmonics
        decide periodicity (e.g. hub motion in the rotating frame, pin angles).
    steps_per_rev, revolutions, max_revolutions, tolerance
        Steps per revolution; revolutions recorded; revolutions allowed for the transient;
        largest relative harmonic change between successive revolutions (or estimates)
        that counts as periodic.
    groups, separate_mean, floor
        How changes are measured (:func:`harmonic_change`): group labels of the signal
        columns that share a scale; the mean judged apart from the vibratory harmonics; the
        smallest scale of each signal column.
    min_revolutions
        Revolutions marched at least before periodicity is tested.
    hint
        Advice appended to the error when the response is not periodic in time.
    window, max_residual
        Revolutions whose changes the extrapolation uses (0: march only); largest
        unexplained part of an accepted extrapolation.
    before_recording
        Called once the marched response is periodic, before the recorded revolutions
        (e.g. to remove a settling device that vanishes on the periodic response).

    Raises
    ------
    RuntimeError
        If the response is not periodic after ``max_revolutions``.
    """
    def advance(n: int) -> Array:  # n steps, each sampled after it
        rows = []
        for _ in range(n):
            step()
            rows.append(sample())
        return np.array(rows)

    prev = prev_est = None
    change = float("inf")
    rev = 0
    blocks: list[Array] = []  # the last window + 1 revolutions
    harms: list[NDArray[np.complex128]] = []  # and their harmonics
    while True:
        block = advance(steps_per_rev)
        rev += 1
        cur = rev_harmonics(signals(block))
        if prev is not None:
            change = harmonic_change(cur, prev, groups, separate_mean, floor)
            done = rev >= min_revolutions and change <= tolerance
            report(f"revolution {rev} of at most {max_revolutions}: periodicity change "
                   f"{change:.2e}, tolerance {tolerance:g}" + (" (periodic: recording)"
                                                                 if done else ""))
            if done:
                break
        prev = cur
        if window >= 2:
            blocks = [*blocks[-window:], block]
            harms = [*harms[-window:], cur]
            if len(blocks) == window + 1:
                scale = harmonic_scales(cur, groups, separate_mean, floor)
                live = scale > 0
                gamma, residual = rre_weights([h[live] / scale[live] for h in harms])
                est = np.tensordot(gamma, np.array(harms[1:]), axes=1)
                if prev_est is not None:
                    est_change = harmonic_change(est, prev_est, groups, separate_mean,
                                                 floor)
                    done = est_change <= tolerance and residual <= max_residual
                    report(f"revolution {rev}: extrapolated periodic response changed by "
                           f"{est_change:.2e} (unexplained part of the last change "
                           f"{residual:.2f})" + (" (periodic: recording the estimate)"
                                                 if done else ""))
                    if done:
                        periodic = np.tensordot(gamma, np.array(blocks[1:]), axes=1)
                        periodic[:, 0] = block[:, 0]  # times (and azimuths) of the last one
                        return PeriodicRecord(_repeat(periodic, revolutions), rev, est_change,
                                              True, residual)
                prev_est = est
        if rev >= max_revolutions:
            raise RuntimeError(f"response not periodic after {max_revolutions} revolutions "
                               f"(last change {change:.2e} > tolerance {tolerance:g}); {hint}")
    if before_recording is not None:
        before_recording()
    return PeriodicRecord(advance(steps_per_rev * revolutions), rev, change)


def _repeat(one: Array, revolutions: int) -> Array:
    """``revolutions`` copies of one periodic revolution of samples, times advancing."""
    period = (one[-1, 0] - one[0, 0]) * one.shape[0] / (one.shape[0] - 1)
    reps = []
    for r in range(revolutions):
        block = one.copy()
        block[:, 0] += (r + 1) * period
        reps.append(block)
    return np.concatenate(reps)


def shooting_parameters(window: int) -> dict[str, Param]:
    """The shooting parameters of a model with a cyclic symmetry (:mod:`studies.hub`,
    :mod:`studies.rotor`), with that model's default ``window``: about two iterates per lightly
    damped mode of its sector map that a transient excites, as measured on the model."""
    return {
        "shooting_window": Param(
            window, "1", "iterates of the sector map (one N-th of a revolution each, N the "
            "symmetry's sectors) whose changes give the extrapolated restart state (0: march "
            "only)", minimum=0, maximum=40),
        "shooting_restarts": Param(
            4, "1", "restarts from an extrapolated state before shooting gives up and marches",
            minimum=0, maximum=50),
    }


# earlier windows whose secant pairs a restart of shoot(secant=True) keeps
SECANT_WINDOWS = 4
# Newton–Picard restarts (shoot's subspace): the slow modes are the map's Ritz values of
# modulus above SLOW_MODULUS, and their amplitudes are found by least squares that drop the
# directions whose singular values fall below SLOW_RCOND of the largest. Measured on Table 1's
# case 1 (the periodic response again after the wake's refinement, quarter-revolution map,
# 55 Arnoldi vectors): 24 modes above 0.8, observed through the loads, angles and pins of the
# rotor's samples with a condition number of 270; with 0.5 (52 modes) or without the cut the
# amplitudes took up the fast transient and the iterates diverged. With the subspace at hand
# the extrapolation's restarts are left out: on the same case's last periodic response (to
# 1e-3, from one periodic to 1e-2) they landed at a change of 1.2–2e-3 four times running and
# the response was found by marching, 15 revolutions, while the march alone decays at the
# slowest multiplier's rate (0.9165 a revolution measured, 0.9144 by Arnoldi) with no floor;
# Newton–Picard alone found it in 5.5 revolutions, at a change of 1.4e-4
SLOW_MODULUS = 0.8
SLOW_RCOND = 1e-3


def shoot(integ, sample: Callable[[], Array], signals: Callable[[Array], Array], *,
          observe: Callable[[Array, int], Array], symmetry, system, steps_per_rev: int,
          revolutions: int, max_revolutions: int, tolerance: float,
          groups: Sequence[int] | None = None, separate_mean: bool = False,
          floor: ArrayLike | None = None, observe_floor: ArrayLike | None = None,
          window: int = 12, max_restarts: int = 4, restart_fraction: float = 0.5,
          max_residual: float = 0.1, min_iterates: int = 4, secant: bool = False,
          subspace=None, observe_slow: Callable[[Array, int], Array] | None = None,
          trust_estimate: bool = False,
          hint: str = "raise max_revolutions") -> PeriodicRecord:
    """Periodic response by shooting: extrapolate the fixed point of the sector map and
    restart the model from it, until two successive marched revolutions agree.

    The map is one N-th of a revolution of the time integration followed by the symmetry's
    turn-and-permute back to the starting phase (:meth:`solver.symmetry.CyclicSymmetry.back`;
    N = 1 without symmetry: the one-revolution map), so a revolution gives N iterates
    x_0, x_1, … . After each iterate, reduced-rank extrapolation (:func:`rre_weights`) of the
    observed blocks (``observe``) since the last restart gives weights γ whose combination of
    the iterates, Σ γ_j x_j, is the estimated fixed point. Once the estimate is good enough —
    it leaves at most ``max_residual`` of the last change unexplained, and that part,
    relative to the signals' scale, is within ``restart_fraction`` × ``tolerance`` (with at
    least ``min_iterates`` iterates) or the ``window`` is full — the model restarts from
    that state at the next whole revolution (directors combined on the rotation group,
    :func:`solver.symmetry.affine_combination`; positions projected onto the constraints).
    For a linear map this is GMRES on (Φ − I)x = 0 in the Krylov space of the iterates
    (Sidi 2017, ch. 1; Smith, Ford & Sidi 1987), i.e. Newton–Krylov shooting with the
    iterates themselves as the Jacobian–vector products: no extra perturbed revolutions, and
    convergence is quadratic in the cycles once the window spans the lightly damped modes.
    The restart keeps the combined velocities as they are (the scheme's end velocities need
    not lie on the velocity constraints, and projecting them would start an undamped
    two-step mode).

    A restart that misses (the map is nonlinear: far from the fixed point its Jacobian
    differs) starts a new window. With ``secant`` the windows of the last
    :data:`SECANT_WINDOWS` restarts stay known: their successive iterates are secant pairs of
    the map's Jacobian, and the estimate is a secant step over them and the new window's own
    pairs (:func:`secant_weights`, a quasi-Newton shooting), from one revolution of new
    iterates on (at least two), instead of a new extrapolation that must span the slow modes
    again; and a change within the periodicity tolerance is left to the test.

    The periodicity test is :func:`march`'s: the harmonics of two successive whole revolutions
    marched since the last restart change by at most ``tolerance``; the recorded revolutions
    are the last ``revolutions`` of those (all marched from one state, none extrapolated).
    Before the first restart the test waits while a restart may still come — until the
    iterates' changes settle below a tenth of the tolerance (where no restart is tried) or a
    whole ``window`` has gone by — since from a start near the periodic response the change
    between revolutions shows only the decay of the start's error, not the error.
    After ``max_restarts`` restarts without passing it, the model marches on from the last
    state (time marching as the fallback), and the record's note says so.

    With ``trust_estimate``, a restart whose estimate put the state within the tolerance (its
    unexplained part at most ``restart_fraction`` × ``tolerance``, not a full window's) is
    taken at its word: the ``revolutions`` marched from it are the record, without the test's
    two revolutions. For a response needed only as closely as the tolerance and never
    recorded itself, such as one a prescribed wake is updated from; the record's ``change``
    is then the estimate's unexplained part.

    Parameters
    ----------
    integ
        The integrator (its ``q``, ``v``, ``t``, ``state``/``restore`` are used).
    sample, signals, steps_per_rev, revolutions, max_revolutions, tolerance, groups,
    separate_mean, floor
        As for :func:`march`.
    observe
        ``observe(block, j)``: the observations of the j-th iterate's block of samples
        (steps_per_rev / N rows) at the starting phase, e.g. non-rotating signals as they are
        and per-sector signals rolled by j sectors.
    observe_floor
        The smallest scale of each observed column (its units), as ``floor`` is of the
        signals': what the restarts and the extrapolation judge changes against.
    symmetry
        :class:`solver.symmetry.CyclicSymmetry` or ``None`` (the one-revolution map).
    system
        The assembled model (for the director triads of the combination).
    window, max_restarts, restart_fraction, max_residual, min_iterates, secant
        Largest number of iterates extrapolated per restart (the window spans the lightly
        damped modes: two per mode), restarts allowed, when to restart (see above), and
        whether later restarts keep the earlier windows' secant pairs.
    subspace, observe_slow
        :class:`solver.period_map.SlowSubspace` of this map, whose probe saw what
        ``observe_slow`` (default ``observe``) sees of a block, or ``None``. Given, a restart
        is Newton–Picard's: from the third iterate after a start or restart on, the slow
        error the last two iterates' observations show is removed from the current state at
        once (:meth:`~solver.period_map.SlowSubspace.correction`, on the Ritz values of
        modulus above :data:`SLOW_MODULUS`), unless the iterates changed by at most a tenth of
        the tolerance or the subspace leaves more than ``max_residual`` of the change
        unexplained; then the model marches on. The extrapolation's restarts are not used
        then (see :data:`SLOW_MODULUS`).
    trust_estimate
        Whether a restart within the tolerance ends the search (see above).
    hint
        Advice appended to the error when the response is not periodic in time.

    Raises
    ------
    RuntimeError
        If the response is not periodic after ``max_revolutions``.
    """
    n_sec = 1 if symmetry is None else symmetry.n_sectors
    if steps_per_rev % n_sec:
        raise ValueError(f"steps_per_rev = {steps_per_rev} must be a multiple of the "
                         f"{n_sec} sectors of the symmetry")
    m = steps_per_rev // n_sec
    step_once = stepper(integ, 2 * np.pi / (steps_per_rev * integ.h))

    # what the scheme carries from step to step besides q and v (generalized-α: its
    # acceleration history), mapped and combined like the velocities
    extra = [key for key in integ.STATE if key not in ("t", "q", "v", "lam", "nu")]

    def snapshot() -> tuple[Array, ...]:  # the state at the phase of t = 0
        arrays = (integ.q, integ.v, *(getattr(integ, key) for key in extra))
        return arrays if symmetry is None else symmetry.back(*arrays, k=phase())

    blocks: list[Array] = []  # blocks since the last restart
    obs: list[Array] = []
    states: list[tuple[Array, ...]] = []  # end states of the blocks, at the phase of t = 0
    raw: list[tuple[Array, int]] = []  # the observed blocks as sampled, with their phases
    memory: list[tuple[list[Array], list[tuple[Array, ...]]]] = []  # earlier windows
    history: list[list[tuple[Array, int]]] = []  # those of the last restarts' windows
    done = restarts = 0  # iterates done
    quarter = steps_per_rev * integ.h / n_sec  # s

    def phase() -> int:  # sector periods since t = 0: the index of the sector roll
        return round(integ.t / quarter)

    def observed_scale(o: Array) -> Array:
        # each observed column on its own scale: its largest value, or with separate_mean its
        # largest excursion from its mean (a steady force of kilonewtons must not hide the
        # change of a vibratory one, as in the periodicity test), at least its floor
        scale = np.abs(o - o.mean(axis=0) if separate_mean else o).max(axis=0)
        if observe_floor is None:
            return scale
        return np.where(scale > 0, np.maximum(scale, np.asarray(observe_floor, dtype=float)),
                        0.0)

    def unsettled(run: list[tuple[Array, int]], seen: list[Array]) -> list[tuple[Array, int]]:
        # the run (``seen``: its blocks' observations) up to its first iterate that changed by
        # at most the tolerance (what a secant
        # restart leaves to the periodicity test, above): after a restart that hit, its pairs
        # describe the noise and the last percent of the transient, not the slow modes. On the
        # hub tuned to 3.19P with 1.25 times the fuselage stiffness, restarted to 6e-6, the
        # estimate at 2h takes 17 iterates with them, 4 without; over a 60-case sweep
        # (tuning 2.7–3.3P, 0.5–1.5 times the fuselage stiffness) from the nonlinear start, at
        # most 7.25 revolutions a case against 8.0 with those changing by more than a tenth of
        # the tolerance kept, the harmonics' largest error 2.2e-3 against 1.9e-3
        for i in range(1, len(seen)):
            scale = observed_scale(seen[i])
            live = scale > 0
            if np.max(np.abs(seen[i] - seen[i - 1])[:, live] / scale[live]) <= tolerance:
                return run[: i + 1]
        return run

    slow_obs: list[Array] = []  # the iterates' observations for Newton–Picard

    def newton_picard() -> bool:
        # Newton–Picard's restart from the last two iterates' observations (see subspace
        # above), from the third iterate after a start or restart on (the first carries the
        # fast transient of the jump): whether it restarted
        nonlocal restarts, residual, blocks, obs, states, raw, history, slow_obs, settled
        nonlocal undo
        if len(slow_obs) < 3:
            return False
        step = slow_obs[-1] - slow_obs[-2]  # the last iterate's change
        scale = np.abs(slow_obs[-1] - slow_obs[-1].mean(axis=0)).max(axis=0)
        live = scale > 0
        if float(np.max(np.abs(step)[:, live] / scale[live])) <= 0.1 * tolerance:
            settled = True
            return False  # periodic already: the test decides
        delta, unexplained = subspace.correction(step, scale, rho=SLOW_MODULUS,
                                                 rcond=SLOW_RCOND)
        if unexplained > max_residual:
            return False
        k_now = phase()
        # the correction is a state of the phase of t = 0: added to the current state turned
        # back there, as the map's Jacobian sees a perturbation, and turned forward again
        try:
            arrays = perturbed(system, list(snapshot()), delta,
                               integ.t - (k_now % n_sec) * quarter, kinetic_metric(system))
        except ValueError as exc:  # too far from the constraints
            report(f"revolution {done / n_sec:g}: Newton–Picard state unusable ({exc})")
            return False
        if symmetry is not None:
            arrays = list(symmetry.back(*arrays, k=-k_now))
        undo = (integ.state(), done, change)
        state = dict(undo[0])
        state.update(zip(["q", "v", *extra], arrays, strict=True))
        integ.restore(state)
        restarts += 1
        residual = unexplained
        report(f"revolution {done / n_sec:g}: Newton–Picard restart {restarts} (unexplained "
               f"part {unexplained:.3f})")
        history = [raw]
        blocks, obs, states, raw, slow_obs = [], [], [], [], []
        return True

    change = float("inf")
    residual = 0.0
    trusted: float | None = None  # a trusted restart's unexplained part (trust_estimate)
    gave_up = False
    # whether the iterates' changes settled below the level where a restart is tried, and
    # whether a window has filled: see `early` below
    settled = filled = False
    # the state before the last Newton–Picard restart, the iterates done then and the
    # periodicity change measured before it: a correction the map's linearization mispredicts
    # can make the response worse (the envelope's 100 kt free case, the refined wake's
    # response: each of four restarts grew the change, from 6.3e-3 to 2.8, and a step then
    # failed, a singular Newton matrix). If the first test after a restart finds the change
    # grown (and not periodic), or a step fails, the march goes on from the state before it
    # without Newton–Picard: by the extrapolation's restarts, then marching.
    undo: tuple[dict, int, float] | None = None
    fallen = ""  # the note if the march went on so

    def abandon(why: str) -> None:
        nonlocal done, undo, subspace, blocks, obs, states, raw, slow_obs, fallen
        integ.restore(undo[0])
        integ.forget_factors()
        done, undo, subspace = undo[1], None, None
        blocks, obs, states, raw, slow_obs = [], [], [], [], []
        report(f"revolution {done / n_sec:g}: {why} after a Newton–Picard restart: marching "
               f"on from the state before it")
        fallen = f"{why} after a Newton–Picard restart, found without it"

    while True:
        rows = []
        try:
            for _ in range(m):
                step_once()
                rows.append(sample())
        except RuntimeError as exc:
            if undo is None:
                raise
            abandon(f"a step failed ({exc})")
            continue
        block = np.array(rows)
        done += 1
        blocks.append(block)
        revs_done = done / n_sec
        if trusted is not None and len(blocks) == revolutions * n_sec:
            report(f"revolution {revs_done:g}: recorded as marched from the restart, whose "
                   f"estimate was within the tolerance (unexplained {trusted:.2e})")
            return PeriodicRecord(np.concatenate(blocks), int(np.ceil(revs_done - revolutions)),
                                  trusted, residual=residual, restarts=restarts,
                                  iterates=[*history])
        if len(blocks) >= 2 * n_sec and len(blocks) % n_sec == 0:
            cur = rev_harmonics(signals(np.concatenate(blocks[-n_sec:])))
            prev = rev_harmonics(signals(np.concatenate(blocks[-2 * n_sec : -n_sec])))
            change = harmonic_change(cur, prev, groups, separate_mean, floor)
            if (undo is not None and len(blocks) == 2 * n_sec
                    and change > max(undo[2], tolerance)):
                abandon(f"the periodicity change grew from {undo[2]:.2e} to {change:.2e}")
                continue
            # Before the first restart the test must wait while a restart may still come: from
            # a start within the tolerance of the periodic response (the reduced model's,
            # studies.reduced_hub) the change between revolutions shows only the decay of the
            # start's error, (1 − ρ) of it with ρ the slow modes' ratio per revolution (0.6–0.85
            # with the pins' 1 % damping), not the error itself: without this wait a 60-case
            # sweep passes the test without a restart in 27 of 60 cases, their harmonics up to
            # 0.61 % from the periodic ones (0.15 % at most once restarted). Unless the changes
            # have settled below the restart level or a whole window went by without a usable
            # estimate.
            early = (restarts == 0 < max_restarts and window >= 2
                     and not (settled or filled))
            ok = change <= tolerance and len(blocks) >= revolutions * n_sec and not early
            report(f"revolution {revs_done:g}: periodicity change {change:.2e}, tolerance "
                   f"{tolerance:g}" + (" (periodic)" if ok else ""))
            # not periodic after the last restart allowed: marching on, shooting gave up
            gave_up = gave_up or (not ok and window >= 2 and restarts == max_restarts)
            if ok:
                rec = np.concatenate(blocks[-revolutions * n_sec :])
                note = fallen or ("" if not gave_up else
                                  f"periodic by marching: {restarts} shooting restarts did not "
                                  "reach a periodic response")
                return PeriodicRecord(rec, int(np.ceil(revs_done - revolutions)), change,
                                      residual=residual, restarts=restarts, note=note,
                                      iterates=[*history, unsettled(raw, obs)])
        if revs_done >= max_revolutions:
            raise RuntimeError(f"response not periodic after {max_revolutions} revolutions "
                               f"({restarts} shooting restarts; last change {change:.2e} > "
                               f"tolerance {tolerance:g}); {hint}")
        if window < 2 or restarts == max_restarts:
            continue
        obs.append(observe(block, phase()))
        raw.append((block, phase()))
        k = len(obs) - 1
        filled = filled or k >= window
        if subspace is not None:
            # Newton–Picard's restarts alone: the extrapolation's, whose fit leaves a part of
            # the change unexplained that the slowest modes amplify by 1/(1 − μ) (45 for the
            # rotor's 0.978 a quarter revolution), would put the slow error back; its states
            # are not kept
            slow_obs.append((observe_slow or observe)(block, phase()))
            newton_picard()
            continue
        states.append(snapshot())
        if k < 2:
            continue
        scale = observed_scale(obs[-1])
        live = scale > 0
        if memory:  # a secant step over the earlier windows' pairs and this one's
            gamma, residual = secant_weights([[o[:, live] / scale[live] for o in run]
                                              for run in [*(w[0] for w in memory), obs]])
            pool = [*(x for w in memory for x in w[1]), *states]
            least = max(2, n_sec)
        else:
            gamma, residual = rre_weights([o[:, live] / scale[live] for o in obs])
            pool, least = states[1:], min_iterates
        # the part of the last change the extrapolation leaves unexplained, relative to the
        # signals' scale: the estimate's error, to first order
        last = float(np.max(np.abs(obs[-1] - obs[-2])[:, live] / scale[live]))
        # periodic already: let the test decide. Changes within the tolerance but above a tenth
        # of it are still removed when the extrapolation explains them (from the linear start
        # the locked hub passes the test at 7.5e-4 after 3 revolutions without a restart, its
        # harmonics that far from the periodic ones; restarted after one revolution, they are
        # within 1.3e-7 of a 400-revolution march to 1e-6)
        # (after a restart that passed the test's tolerance, with a secant step at hand, the
        # test decides: restarting again would only start its two revolutions over)
        settled = last <= 0.1 * tolerance
        if last <= (tolerance if memory else 0.1 * tolerance):
            continue
        unexplained = residual * last
        if residual > max_residual or not (
                k >= window or (k >= least
                                and unexplained <= restart_fraction * tolerance)):
            if k >= window:  # slide the window
                obs, states, raw = obs[1:], states[1:], raw[1:]
            continue
        q, v = affine_combination(system, gamma, [s[0] for s in pool], [s[1] for s in pool])
        more = {key: gamma @ np.array([s[2 + i] for s in pool]) for i, key in enumerate(extra)}
        # the estimate is a state of the phase of t = 0: restart at the next whole revolution
        # (the forcing and the driven rotation repeat), so that the revolutions recorded after
        # it start at ψ = 0 like a marched run's
        t_restart = np.ceil(integ.t / (n_sec * quarter) - 1e-9) * n_sec * quarter
        # the combination leaves the position constraints violated at second order in the
        # iterates' spread: the scheme's first step would close that gap in one chord and
        # leave a velocity jump of (gap)/h as an undamped two-step mode, which slows every
        # later Newton solve; projecting the positions (not the velocities, whose normal part
        # is the scheme's own) avoids it
        try:
            q = project_positions(system, q, t_restart)
        except ValueError as exc:  # too far from the constraints: not a usable estimate
            report(f"revolution {revs_done:g}: extrapolated state unusable ({exc}; weights up "
                   f"to {np.abs(gamma).max():.3g}); marching on")
            obs, states, raw = obs[1:], states[1:], raw[1:]
            continue
        state = integ.state()
        state.update(t=t_restart, q=q, v=v, **more)
        integ.restore(state)
        restarts += 1
        if trust_estimate and unexplained <= restart_fraction * tolerance:
            trusted = unexplained
        report(f"revolution {revs_done:g}: restarted from the extrapolated periodic state "
               f"(restart {restarts}, {k} iterates, unexplained part {residual:.3f}, weights up "
               f"to {np.abs(gamma).max():.3g})")
        if secant:  # what this window knows of the slow modes, for the next estimates
            memory = [*memory, (obs, states)][-SECANT_WINDOWS:]
        history = [*history, raw][-(SECANT_WINDOWS if secant else 1):]
        blocks, obs, states, raw, slow_obs = [], [], [], [], []


def referred_harmonics(rows: Array, omega: float, n_max: int) -> NDArray[np.complex128]:
    """Complex harmonics 0..n_max of one revolution of sampled rows (time in s in column 0,
    uniform samples), referred to the azimuth ψ = Ωt = 0: x(ψ) = c_0 + 2 Re Σ_k c_k e^{ikψ}."""
    psi0 = omega * float(rows[0, 0])
    return rev_harmonics(rows[:, 1:], n_max) * np.exp(-1j * np.arange(n_max + 1)
                                                      * psi0)[:, None]


def richardson(fine: Array, coarse: Array, omega: float, n_max: int,
               order: int = 2) -> tuple[Array, Array]:
    """Richardson extrapolation of the harmonics of a periodic response computed at two steps.

    The periodic response of a symmetric one-step scheme (the midpoint-type ``ep``, or its
    symmetric composition, :mod:`solver.composition`) has an error expansion in even powers of
    the step, so the harmonics c(h) = c + a hᵖ + O(hᵖ⁺²) of the response at h (``fine``) and
    H = rh (``coarse``, r > 1) give c ≈ c(h) + (c(h) − c(H))/(rᵖ − 1) with error O(hᵖ⁺²):
    p = 2 for ``ep`` (with r = 2 the factor 1/3), 4 for its fourth-order composition (1/15).
    The correction of harmonics 0..n_max, a band-limited periodic signal, is added to every
    sample of ``fine``; harmonics above n_max keep the fine step's error.

    Parameters
    ----------
    fine, coarse
        Whole periodic revolutions of samples (rows: time in s, then the signals), at h and
        H > h, one sample per step; the last revolution of each is used (at least
        2 n_max + 2 samples per revolution).
    omega
        Rotor speed (rad/s).
    n_max
        Highest harmonic corrected.
    order
        Order p of the leading error term (2 for ``ep``, 4 composed): the factor is
        1/(2^p − 1).

    Returns
    -------
    corrected : ndarray
        ``fine`` with the correction added (time column unchanged).
    estimate : ndarray, shape (signals,)
        The correction's largest harmonic, relative to the signal's largest harmonic: the
        estimated time-step error of the fine step's harmonics (the extrapolated ones carry
        the O(h⁴) remainder, much smaller).
    """
    period = 2 * np.pi / omega
    n_f = round(period / (fine[1, 0] - fine[0, 0]))
    n_c = round(period / (coarse[1, 0] - coarse[0, 0]))
    if (n_f <= n_c or n_c < 2 * n_max + 2 or fine.shape[0] % n_f
            or coarse.shape[0] % n_c):
        raise ValueError(f"richardson: need whole revolutions at h and at a coarser step with "
                         f"at least {2 * n_max + 2} samples per revolution (got {n_f} and {n_c} "
                         "samples per revolution)")
    c_f = referred_harmonics(fine[-n_f:], omega, n_max)
    c_c = referred_harmonics(coarse[-n_c:], omega, n_max)
    delta = (c_f - c_c) / ((n_f / n_c) ** order - 1)
    k = np.arange(n_max + 1)
    phase = np.exp(1j * omega * np.outer(fine[:, 0], k))  # (samples, harmonics)
    weight = np.where(k == 0, 1.0, 2.0)
    corrected = fine.copy()
    corrected[:, 1:] += np.real(phase @ (weight[:, None] * delta))
    scale = np.abs(c_f).max(axis=0)
    estimate = np.divide(np.abs(delta).max(axis=0), scale, out=np.zeros_like(scale),
                         where=scale > 0)
    return corrected, estimate


def coarser_steps(steps_per_rev: int, n_sectors: int, n_max: int,
                  ratio: float = 2.0) -> int | None:
    """Steps per revolution of the coarser companion of a run at ``steps_per_rev``: the largest
    multiple of the sectors at most 1/``ratio`` of it (``ratio`` times the step when it
    divides), or ``None`` when that leaves fewer than 2 n_max + 2 samples per revolution
    (harmonic n_max would not be resolved)."""
    if not ratio > 1.0:
        raise ValueError(f"ratio = {ratio!r}: the companion's step must be coarser (ratio > 1)")
    n_c = int(steps_per_rev / ratio + 1e-9) // n_sectors * n_sectors
    return n_c if n_c >= 2 * n_max + 2 else None


def sector_response(integ, sample: Callable[[], Array], align: Callable[[Array, int], Array],
                    *, n_sectors: int, steps_per_rev: int, reference: Array, omega: float,
                    n_max: int = 8, min_iterates: int = 6, max_iterates: int = 16,
                    accuracy: float = 0.1, max_residual: float = 0.1,
                    history: Sequence[Sequence[Array]] | None = None,
                    pairs: tuple[Array, Array] | None = None, separate_mean: bool = False
                    ) -> tuple[Array, float, int]:
    """The periodic response of ``integ`` near its state, by extrapolating its sector map.

    Started on (or near) the periodic response of the same model at another time step, e.g.
    at the end of :func:`shoot`'s record, the iterates of the one-N-th-revolution map at this
    step converge to this step's periodic response, along the model's slow modes. As in
    :func:`shoot`, reduced-rank extrapolation of the iterates' blocks of samples, each aligned
    to the phase of t = 0 (``align``), gives weights γ whose combination of the blocks is the
    fixed point's block (:func:`rre_weights`), here without restarting the model: the
    combination is the result. By the symmetry the fixed point's block, unaligned sector by
    sector, is the whole revolution. Iterates are marched until the harmonics 0..n_max of the
    last three extrapolations agree within ``accuracy`` of their largest change from
    ``reference`` (each relative to the signal's largest harmonic in ``reference``): the
    difference the caller needs, to that relative accuracy. (The extrapolation's residual is
    no measure of its error until the iterates span the slow modes.)

    With ``history``, the iterates of the same map at the other step that shooting
    extrapolated (:attr:`PeriodicRecord.iterates`), the slow modes are known before this
    step's iterates span them: their successive changes are secant pairs (u, Ju) of the map's
    Jacobian J, which differs from this step's by the step error only. With this step's own
    pairs added, the fixed point is estimated by a secant (Anderson type II) step from the
    last iterate y_k with change g = y_k − y_{k−1}: c minimizes ‖g − (JU − U) c‖ and
    y* = y_k − (JU) c; the part of g no pair explains is taken as decayed (the fast modes).
    For a linear map whose transient lies in the pairs' span this is exact after two
    iterates. Pairs taken far from this step's fixed point (a large, nonlinear transient at
    the other step) need not explain this step's changes: an estimate counts only when the
    pairs leave at most ``max_residual`` of the last change unexplained. (Measured on the hub
    tuned to 3.08P with 1.5 times the fuselage stiffness, started with amplitude detuning:
    0.35–0.39 unexplained, and the estimate 2.1e-3 against the 5.5e-3 measured; from the
    linear start 0.017–0.08, and 4.6e-3.)

    ``pairs`` adds secant pairs known otherwise (:func:`secant_step`): the map's Jacobian (at
    the other step, or with the other forcing) as the multipliers' Arnoldi run saw it
    (:meth:`solver.period_map.SlowSubspace.pairs`), each Krylov vector's response a clean
    linear one where a shooting iterate's change mixes the modes with the noise of its Newton
    steps. (Table 1's free rotor at 180 steps a revolution: the estimate to a tenth of its
    change in 14 quarter revolutions, where shooting's iterates alone left it uncertain by
    22 % after 24.)

    Parameters
    ----------
    integ
        The integrator, at a whole sector period; it is stepped.
    sample
        One row of samples after a step (time in s first), as for :func:`shoot`.
    align
        ``align(block, j)``: the block (rows of samples) ending j sector periods after t = 0,
        moved to the phase of t = 0 (per-sector columns rolled by j); ``align(block, -j)``
        undoes it. All columns but the time are combined.
    n_sectors, steps_per_rev
        Sectors of the symmetry (1: the one-revolution map) and steps per revolution of
        ``integ`` (a multiple of ``n_sectors``).
    reference
        Whole revolutions of samples of the other step's periodic response (the last one is
        used), for the stopping test.
    history
        Runs of blocks of samples of successive iterates of the sector map at the other step,
        aligned (``align``) and at this step's sample times, oldest first (runs of fewer than
        three are not used); ``None``: this step's iterates only.
    pairs
        (U, JU): changes of a block and their images under the map's Jacobian, each
        (p, steps_per_rev / n_sectors, columns) aligned and at this step's sample times like
        the blocks (column 0 not used), or ``None``.
    separate_mean
        Judge the harmonics as the periodicity test does with it (:func:`harmonic_scales`):
        the vibratory ones against each signal's largest vibratory harmonic, not its mean.
    omega
        Rotor speed (rad/s).
    n_max, min_iterates, max_iterates, accuracy, max_residual
        Highest harmonic compared, least and most iterates (with a usable ``history`` at
        least four, what three estimates to compare need), the stopping test's relative
        accuracy, and the largest unexplained part of a secant estimate over ``history``.

    Returns
    -------
    revolution : ndarray
        One revolution of samples (``steps_per_rev`` rows), times following the start.
    uncertainty : float
        The last three extrapolations' largest difference over their change from
        ``reference`` (above ``accuracy`` if ``max_iterates`` ran out).
    iterates : int
        Sector periods marched.
    """
    if steps_per_rev % n_sectors:
        raise ValueError(f"steps_per_rev = {steps_per_rev} must be a multiple of the "
                         f"{n_sectors} sectors")
    if max_iterates < 4:  # three extrapolations to compare need four iterates
        raise ValueError(f"max_iterates = {max_iterates}: must be at least 4")
    m = steps_per_rev // n_sectors
    sector = 2 * np.pi / omega / n_sectors  # s
    step_once = stepper(integ, omega)
    start = round(integ.t / sector)
    if abs(integ.t - start * sector) > 1e-9 * sector:
        raise ValueError(f"the integrator's time {integ.t:.9g} s is not a whole sector period "
                         f"({sector:.9g} s): the iterates' phases would not align")
    t0 = start * sector
    n_ref = round(2 * np.pi / omega / (reference[1, 0] - reference[0, 0]))
    c_ref = referred_harmonics(reference[-n_ref:], omega, n_max)
    scale_ref = harmonic_scales(c_ref, separate_mean=separate_mean)
    live_ref = scale_ref > 0

    def unfold(block: Array) -> Array:  # the fixed point's revolution from its aligned block
        rev = np.concatenate([align(block, -(start + k + 1)) for k in range(n_sectors)])
        rev[:, 0] = t0 + (np.arange(steps_per_rev) + 1) * (sector / m)
        return rev

    def relative(c: NDArray[np.complex128]) -> float:  # largest harmonic, relative to scale
        return float(np.max(np.abs(c)[live_ref] / scale_ref[live_ref])) if np.any(
            live_ref) else 0.0

    past = [np.array(run, dtype=float) for run in history or () if len(run) >= 3]
    for run in past:
        if run.shape[1:] != (m, len(reference[0])):
            raise ValueError(f"history blocks must be {m} samples of {len(reference[0])} "
                             f"columns, got {run.shape[1:]}")
    if pairs is not None and (np.shape(pairs[0]) != np.shape(pairs[1])
                              or np.shape(pairs[0])[1:] != (m, len(reference[0]))):
        raise ValueError(f"pairs must be two arrays of blocks of {m} samples of "
                         f"{len(reference[0])} columns, got {np.shape(pairs[0])} and "
                         f"{np.shape(pairs[1])}")
    known = bool(past) or pairs is not None  # secant pairs besides this step's own
    # with the slow modes known, the three estimates the test compares need only four iterates
    least = min(min_iterates, 4) if known else min_iterates
    blocks: list[Array] = []
    estimates: list[tuple[Array, NDArray[np.complex128]]] = []
    while True:
        rows = []
        for _ in range(m):
            step_once()
            rows.append(sample())
        blocks.append(align(np.array(rows), round(integ.t / sector)))
        if len(blocks) < 2:
            continue
        if known:
            # each column on the scale of its largest sample in the last iterate
            scale = np.abs(blocks[-1][:, 1:]).max(axis=0)
            live = np.nonzero(scale > 0)[0] + 1
            runs = [*past, np.array(blocks)]
            w, coef, unexplained = secant_step(
                [[b[:, live] / scale[live - 1] for b in run] for run in runs],
                None if pairs is None else tuple(z[:, :, live] / scale[live - 1]
                                                 for z in pairs))
            fixed = blocks[-1].copy()
            fixed[:, 1:] = np.tensordot(w, np.concatenate(runs)[:, :, 1:], axes=1)
            if pairs is not None:
                fixed[:, 1:] -= np.tensordot(coef, pairs[1][:, :, 1:], axes=1)
            rev = unfold(fixed)
        else:
            scale = np.abs(blocks[-1][:, 1:]).max(axis=0)
            live = scale > 0
            gamma, _ = rre_weights([b[:, 1:][:, live] / scale[live] for b in blocks])
            rev = unfold(np.tensordot(gamma, np.array(blocks[1:]), axes=1))
        estimates.append((rev, referred_harmonics(rev, omega, n_max)))
        if len(estimates) < 3 or (known and unexplained > max_residual
                                  and len(blocks) < max_iterates):
            continue
        # converged when the last three estimates agree: extrapolation's own residual is no
        # measure of its error before the iterates span the slow modes
        c = estimates[-1][1]
        change = relative(c - c_ref)
        spread = max(relative(c - estimates[-2][1]), relative(c - estimates[-3][1]))
        uncertainty = spread / change if change > 0 else 0.0
        if known and unexplained > max_residual:  # out of iterates, the pairs still at odds
            uncertainty = max(uncertainty, unexplained)
        if ((len(blocks) >= least and uncertainty <= accuracy)
                or len(blocks) >= max_iterates):
            return rev, uncertainty, len(blocks)


# The step-error estimate every periodic model offers (studies.hub, studies.rotor): its
# switches, and what it reports.
STEP_ERROR_PARAMETERS: dict[str, Param] = {
    "error_estimate": Param(True, "1", "estimate the time-step error of the harmonics 0-8 "
                            "from the periodic response at a coarser step (the hub's about "
                            "twice its step, the rotor's 4/3 of it; stored as "
                            "run_step_error_estimate; also made whenever richardson is true)"),
    "richardson": Param(True, "1", "extrapolate the harmonics 0-8 to zero step from the "
                        "periodic response at that coarser step (Richardson on the scheme's "
                        "leading error term), storing the error estimate"),
}

STEP_ERROR_OUTPUTS: dict[str, Output] = {
    "run_step_error_estimate": Output(
        "1", "estimated time-step error of the harmonics at the time step (Richardson: "
        "|c(h) - c(H)|/((H/h)^p - 1) from the periodic response at the coarser step H, "
        "run_estimate_samples_per_rev; largest over harmonics 0-8 and signals, relative to "
        "each signal's largest harmonic)", dims=(),
        optional=True),
    "run_richardson": Output("1", "1 if the archived harmonics 0-8 are extrapolated to zero "
                             "step (they then carry a fraction of run_step_error_estimate), 0 "
                             "if they are those of the time step", dims=()),
    "run_estimate_revolutions": Output("1", "revolutions simulated at the step-error "
                                       "estimate's coarser step", dims=()),
    "run_estimate_samples_per_rev": Output("1", "steps per revolution of the step-error "
                                           "estimate's coarser step (0: no estimate)", dims=()),
}


@dataclass
class StepError:
    """What :func:`step_error` found: the recorded ``samples`` (extrapolated to zero step when
    ``extrapolated``), the ``estimate`` (NaN if none), the coarser step's ``integrator`` and
    ``steps_per_rev`` (``None`` and 0 if it was not run) and what the case message should say
    (``note``)."""

    samples: Array
    estimate: float = float("nan")
    extrapolated: bool = False
    integrator: object | None = None
    steps_per_rev: int = 0
    note: str = ""

    def facts(self) -> dict[str, np.generic]:
        """The values of :data:`STEP_ERROR_OUTPUTS`."""
        coarse = self.integrator
        facts: dict[str, np.generic] = {
            "run_richardson": np.int32(self.extrapolated),
            "run_estimate_revolutions": np.float64(
                0.0 if coarse is None else coarse.n_steps / self.steps_per_rev),
            "run_estimate_samples_per_rev": np.int32(self.steps_per_rev),
        }
        if np.isfinite(self.estimate):
            facts["run_step_error_estimate"] = np.float64(self.estimate)
        return facts


def resample(block: Array, m: int) -> Array:
    """A block of samples one sector long (rows: time, then the signals; one per step, the
    first a step after the sector's start) at m < rows samples instead, likewise placed: the
    samples themselves where the new times are among the old (m divides the rows), else a
    cubic spline through the block's samples, between which the new times lie (error O(h⁴):
    5e-5 of an 8P harmonic at 240 steps a revolution, largest near the block's ends)."""
    n = len(block)
    if n % m == 0:
        return block[n // m - 1 :: n // m]
    h = block[1, 0] - block[0, 0]
    t = block[0, 0] - h + (np.arange(m) + 1) * (n * h / m)
    out = np.empty((m, block.shape[1]))
    out[:, 0] = t
    out[:, 1:] = CubicSpline(block[:, 0], block[:, 1:], axis=0, extrapolate=True)(t)
    return out


def aligned_pairs(pairs: tuple[Array, Array, int], align: Callable[[Array, int], Array],
                  m: int) -> tuple[Array, Array]:
    """Secant pairs (U, JU, j) of blocks of samples as sampled, ending j sector periods after
    t = 0, as :func:`sector_response` takes them: aligned (``align``) and at m samples a
    sector (:func:`resample`)."""
    return tuple(np.array([resample(align(b, pairs[2]), m) for b in z]) for z in pairs[:2])


def step_error(rec: PeriodicRecord, state: dict, coarse: Callable[[int], object],
               sampler: Callable[[object], Callable[[], Array]],
               align: Callable[[Array, int], Array], *, n_sectors: int, steps_per_rev: int,
               omega: float, order: int, extrapolate: bool, accuracy: float = 0.1,
               max_iterates: int = 12, n_max: int = 8, ratio: float = 2.0,
               usable: float | None = None,
               pairs: tuple[Array, Array, int] | None = None) -> StepError:
    """The time-step error of a periodic response's harmonics, and their Richardson
    extrapolation to zero step.

    From ``state``, the integrator's state at the end of the recorded response ``rec`` (at a
    whole sector period), the same model at the coarser step :func:`coarser_steps` gives for
    ``ratio`` (``coarse(n)``: an integrator at n steps a revolution) reaches its own periodic
    response by :func:`sector_response` (with ``rec``'s shooting iterates, resampled to the
    coarse step's sample times by :func:`resample`, as the slow modes' history, and with
    ``pairs`` (U, JU, j) the map's Jacobian at the recorded step as secant pairs of blocks of
    samples, as sampled, ending j sector periods after t = 0: e.g.
    :meth:`solver.period_map.SlowSubspace.pairs`); :func:`richardson` of order ``order`` then
    gives the estimate and, with ``extrapolate``, the extrapolated samples.
    ``sampler(integ)`` makes the row sampler of an integrator, ``align`` is
    :func:`sector_response`'s, ``accuracy`` the estimate's own relative accuracy and
    ``max_iterates`` the most sector periods marched at the coarse step. An estimate whose
    iterates ran out before ``accuracy`` is still applied up to an uncertainty of ``usable``
    (default ``accuracy``; the note says how uncertain), which leaves that fraction of the
    step's error. Failures are not raised: the result then keeps ``rec``'s samples and says
    why in ``note``.
    """
    unextrapolated = ", harmonics not extrapolated" if extrapolate else ""
    n_c = coarser_steps(steps_per_rev, n_sectors, n_max, ratio)
    if n_c is None:
        return StepError(rec.samples, note=f"no step-error estimate at steps_per_rev = "
                         f"{steps_per_rev}{unextrapolated}: a coarser step would not resolve "
                         f"harmonic {n_max}")
    integ = coarse(n_c)
    integ.restore(state)
    # the shooting iterates at the coarse step's sample times
    history = [[resample(align(b, j), n_c // n_sectors) for b, j in run]
               for run in rec.iterates]
    known = None if pairs is None else aligned_pairs(pairs, align, n_c // n_sectors)
    result = StepError(rec.samples, integrator=integ, steps_per_rev=n_c)
    try:
        rev, uncertainty, _ = sector_response(
            integ, sampler(integ), align, n_sectors=n_sectors, steps_per_rev=n_c,
            reference=rec.samples, omega=omega, n_max=n_max, accuracy=accuracy,
            max_iterates=max_iterates, history=history, pairs=known)
    except RuntimeError as exc:
        result.note = f"no step-error estimate{unextrapolated}: {exc}"
        return result
    corrected, est = richardson(rec.samples, rev, omega, n_max, order=order)
    result.estimate = float(est.max())
    usable = accuracy if usable is None else usable
    if uncertainty > accuracy:
        result.note = (f"step-error estimate uncertain by {uncertainty:.0%}"
                       f"{unextrapolated if uncertainty > usable else ''}")
    if extrapolate and uncertainty <= usable:
        result.samples, result.extrapolated = corrected, True
    return result
