"""March a rotor model revolution by revolution until its response is periodic, then record.

A rotor in steady flight has a periodic response once its transients (the slow lag mode, the
bifilars' free swing, the fuselage modes) have decayed. The runs march whole revolutions and
compare the per-rev harmonics of chosen signals between successive revolutions; when the
largest change, relative to each signal's largest harmonic, is within the tolerance, the next
``revolutions`` whole revolutions are recorded (paper: "the simulations were run for several
main rotor revolutions until a periodic solution was reached").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

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


def rev_harmonics(block: Array, n_max: int = 8) -> NDArray[np.complex128]:
    """Complex per-rev harmonics 0..n_max of the columns of one revolution of samples."""
    f = np.fft.rfft(block, axis=0) / block.shape[0]
    return f[: n_max + 1]


def harmonic_change(cur: NDArray[np.complex128], prev: NDArray[np.complex128],
                    groups: Sequence[int] | None = None, separate_mean: bool = False) -> float:
    """Largest change of a harmonic between two revolutions, relative to a scale.

    The scale of a column is its largest harmonic, or with ``groups`` (``groups[j]`` labels
    column j) the largest of its group: the x and y of one vector share a scale, so that a
    component near zero is not held to its own tiny size. With ``separate_mean`` the
    vibratory harmonics (1 and up) are judged against the largest vibratory harmonic and the
    mean against the larger of itself and that: a steady force of kilonewtons does not hide a
    change of a vibratory harmonic of tens of newtons, and a mean near zero is not held to
    its own tiny size. All-zero scales (locked pins) are skipped.
    """
    def group_max(a: NDArray[np.float64]) -> NDArray[np.float64]:
        a = a.copy()
        if groups is not None:
            labels = np.asarray(groups)
            for g in np.unique(labels):
                a[labels == g] = a[labels == g].max()
        return a

    change = np.abs(cur - prev)
    if separate_mean:
        vib = group_max(np.abs(cur[1:]).max(axis=0))
        mean = np.maximum(group_max(np.abs(cur[0])), vib)
        parts = [(change[:1], mean), (change[1:], vib)]
    else:
        parts = [(change, group_max(np.abs(cur).max(axis=0)))]
    worst = 0.0
    for c, scale in parts:
        live = scale > 0
        if np.any(live):
            worst = max(worst, float(np.max(c[:, live] / scale[live])))
    return worst


@dataclass
class PeriodicRecord:
    """Whole revolutions of samples once periodic.

    ``samples`` (revolutions × steps_per_rev, columns of the sampler) with time in column 0;
    ``transient`` the revolutions marched before recording; ``change`` the last periodicity
    change.
    """

    samples: Array
    transient: int
    change: float


def march(step: Callable[[], None], sample: Callable[[], Array],
          signals: Callable[[Array], Array], *, steps_per_rev: int, revolutions: int,
          max_revolutions: int, tolerance: float, groups: Sequence[int] | None = None,
          separate_mean: bool = False, min_revolutions: int = 2,
          hint: str = "raise max_revolutions") -> PeriodicRecord:
    """March until periodic, then record ``revolutions`` whole revolutions.

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
        largest relative harmonic change between successive revolutions that counts as
        periodic.
    groups, separate_mean
        How changes are measured (:func:`harmonic_change`): group labels of the signal
        columns that share a scale; the mean judged apart from the vibratory harmonics.
    min_revolutions
        Revolutions marched at least before periodicity is tested.
    hint
        Advice appended to the error when the response is not periodic in time.

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

    prev = None
    change = float("inf")
    rev = 0
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
        if rev >= max_revolutions:
            raise RuntimeError(f"response not periodic after {max_revolutions} revolutions "
                               f"(last change {change:.2e} > tolerance {tolerance:g}); {hint}")
    return PeriodicRecord(advance(steps_per_rev * revolutions), rev, change)
