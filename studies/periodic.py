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
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from studies.parameters import Param, ParameterError
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


def check(p: dict[str, Any]) -> None:
    """Cross-checks of the marching parameters (:data:`PARAMETERS` and the model's own
    ``revolutions`` and ``max_revolutions``)."""
    if p["revolutions"] > p["max_revolutions"]:
        raise ParameterError("revolutions must not exceed max_revolutions")
    if p["extrapolation_window"] == 1:
        raise ParameterError("extrapolation_window = 1: must be 0 (march only) or at least 2 "
                             "(an extrapolation needs two changes)")


def rev_harmonics(block: Array, n_max: int = 8) -> NDArray[np.complex128]:
    """Complex per-rev harmonics 0..n_max of the columns of one revolution of samples."""
    f = np.fft.rfft(block, axis=0) / block.shape[0]
    return f[: n_max + 1]


def harmonic_scales(cur: NDArray[np.complex128], groups: Sequence[int] | None = None,
                    separate_mean: bool = False) -> Array:
    """The scale each harmonic of each column is judged against (same shape as ``cur``).

    The scale of a column is its largest harmonic, or with ``groups`` (``groups[j]`` labels
    column j) the largest of its group: the x and y of one vector share a scale, so that a
    component near zero is not held to its own tiny size. With ``separate_mean`` the
    vibratory harmonics (1 and up) are judged against the largest vibratory harmonic and the
    mean against the larger of itself and that: a steady force of kilonewtons does not hide a
    change of a vibratory harmonic of tens of newtons, and a mean near zero is not held to
    its own tiny size. All-zero scales (locked pins) stay zero: those columns are skipped.
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
    return scale


def harmonic_change(cur: NDArray[np.complex128], prev: NDArray[np.complex128],
                    groups: Sequence[int] | None = None, separate_mean: bool = False) -> float:
    """Largest change of a harmonic between two revolutions, relative to its scale
    (:func:`harmonic_scales` of ``cur``)."""
    scale = harmonic_scales(cur, groups, separate_mean)
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


@dataclass
class PeriodicRecord:
    """Whole revolutions of samples once periodic.

    ``samples`` (revolutions × steps_per_rev, columns of the sampler) with time in column 0;
    ``transient`` the revolutions marched before recording; ``change`` the last periodicity
    change; ``extrapolated`` whether the samples are the extrapolated limit of the marched
    revolutions (:func:`march`) rather than marched ones, and ``residual`` that
    extrapolation's unexplained part (:func:`rre_weights`).
    """

    samples: Array
    transient: int
    change: float
    extrapolated: bool = False
    residual: float = 0.0


def march(step: Callable[[], None], sample: Callable[[], Array],
          signals: Callable[[Array], Array], *, steps_per_rev: int, revolutions: int,
          max_revolutions: int, tolerance: float, groups: Sequence[int] | None = None,
          separate_mean: bool = False, min_revolutions: int = 2,
          hint: str = "raise max_revolutions", window: int = 0,
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
    groups, separate_mean
        How changes are measured (:func:`harmonic_change`): group labels of the signal
        columns that share a scale; the mean judged apart from the vibratory harmonics.
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
            change = harmonic_change(cur, prev, groups, separate_mean)
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
                scale = harmonic_scales(cur, groups, separate_mean)
                live = scale > 0
                gamma, residual = rre_weights([h[live] / scale[live] for h in harms])
                est = np.tensordot(gamma, np.array(harms[1:]), axes=1)
                if prev_est is not None:
                    est_change = harmonic_change(est, prev_est, groups, separate_mean)
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
