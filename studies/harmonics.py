"""Per-revolution Fourier harmonics of periodic rotor responses.

A steady rotor response recorded over ``R`` whole revolutions of ``N`` samples each (endpoint
excluded) is periodic in the recording window, so ``numpy.fft.rfft`` over all ``R·N`` samples is
exact: harmonic ``k`` of the rotor (``k`` cycles per revolution, "kP") sits in bin ``k·R``, with
no leakage and no window. Every other bin holds sub-harmonic or non-periodic content (a transient
that has not died out), which the per-rev harmonics deliberately ignore.

Convention (the paper's Figs. 17–19)::

    x(psi) = c_0 + sum_{k>=1} [c_k cos(k psi) + s_k sin(k psi)],   psi = Omega t,
    amplitude_k = hypot(c_k, s_k),   c_0 = mean,  s_0 = 0.

Coefficients are stored as real floats (cosine and sine), never complex, so they go into netCDF
unchanged.

Which signals get harmonics, under which names and units, is declared by each model
(:class:`studies.parameters.Output`): :func:`case_harmonics` follows the declarations. Every
harmonic output ``<name>``, a single history or an in-plane vector, is archived as
``<name>_amplitude``, ``<name>_cos`` and ``<name>_sin``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from studies.parameters import Output

# Highest harmonic stored in the archive: a 4-bladed rotor's fixed-frame loads are at 4P and 8P,
# and 8P is where the rotating-frame 7P and 9P meet.
N_MAX = 8

# Relative tolerance on the time step against 2π/(Ω·N): samples must be uniform and span whole
# revolutions, otherwise the per-rev bins of the FFT do not hold the per-rev harmonics.
TIME_STEP_RTOL = 1e-6

# The harmonic variables of an output <name>: <name>_amplitude, <name>_cos and <name>_sin.
SUFFIXES = ("_amplitude", "_cos", "_sin")

# The scalar results of a per-rev periodic model that give its recording's time base.
LAYOUT = ("run_hub_speed", "run_samples_per_rev", "run_revolutions")


class Harmonics(NamedTuple):
    """Per-rev Fourier coefficients; the last axis is the harmonic number ``0..n_max``.

    Attributes
    ----------
    cos, sin
        Cosine and sine coefficients ``c_k``, ``s_k`` (units of the signal); ``sin[..., 0] = 0``.
    amplitude
        ``hypot(c_k, s_k)`` (units of the signal); ``amplitude[..., 0] = |mean|``.
    """

    cos: NDArray[np.float64]
    sin: NDArray[np.float64]
    amplitude: NDArray[np.float64]


def harmonics(
    signal: ArrayLike,
    samples_per_rev: int,
    revolutions: int,
    n_max: int = N_MAX,
    *,
    psi0: float = 0.0,
    axis: int = -1,
) -> Harmonics:
    """Per-rev harmonics ``0..n_max`` of a signal sampled over whole rotor revolutions.

    Parameters
    ----------
    signal
        Samples, uniformly spaced in azimuth, ``revolutions * samples_per_rev`` of them along
        ``axis`` (endpoint excluded: the sample at ``psi0 + 2π·revolutions`` is not included).
        Any unit; the coefficients have the same unit. Other axes are transformed independently.
    samples_per_rev
        Samples per rotor revolution ``N``; must exceed ``2 * n_max`` (Nyquist).
    revolutions
        Number of whole revolutions ``R`` recorded (at least 1).
    n_max
        Highest harmonic returned.
    psi0
        Rotor azimuth of the first sample (rad). The coefficients refer to ``psi = Omega t``, so
        a recording that does not start at a whole revolution is rotated back to ``psi = 0``.
    axis
        The time axis of ``signal``.

    Returns
    -------
    Harmonics
        ``cos``, ``sin`` and ``amplitude``, each of shape ``signal.shape`` with ``axis`` removed
        and a trailing axis of length ``n_max + 1``.

    Raises
    ------
    ValueError
        If the number of samples is not ``revolutions * samples_per_rev`` or the sampling is too
        coarse for ``n_max``.
    """
    x = np.moveaxis(np.asarray(signal, dtype=float), axis, -1)
    if samples_per_rev < 1 or revolutions < 1 or n_max < 0:
        raise ValueError(
            f"need samples_per_rev >= 1, revolutions >= 1 and n_max >= 0; got "
            f"{samples_per_rev}, {revolutions}, {n_max}"
        )
    n_samples = samples_per_rev * revolutions
    if x.shape[-1] != n_samples:
        raise ValueError(
            f"signal has {x.shape[-1]} samples along its time axis, expected "
            f"revolutions * samples_per_rev = {revolutions} * {samples_per_rev} = {n_samples}"
        )
    # Strictly below Nyquist: at k = N/2 the sine term is sampled at its zeros and is lost.
    if 2 * n_max >= samples_per_rev:
        raise ValueError(
            f"{samples_per_rev} samples per revolution cannot resolve harmonic {n_max}: "
            f"need more than {2 * n_max} samples per revolution"
        )
    spectrum = np.fft.rfft(x, axis=-1)[..., revolutions * np.arange(n_max + 1)]
    # x = Re(X_m)·2/M cos - Im(X_m)·2/M sin for 0 < m < M/2; the mean is X_0/M.
    scale = np.full(n_max + 1, 2.0 / n_samples)
    scale[0] = 1.0 / n_samples
    cos = spectrum.real * scale
    sin = -spectrum.imag * scale
    sin[..., 0] = 0.0
    if psi0 != 0.0:
        # The FFT measured a cos(kφ) + b sin(kφ) with φ = psi - psi0; express in psi.
        k_psi0 = np.arange(n_max + 1) * psi0
        cos, sin = (
            cos * np.cos(k_psi0) - sin * np.sin(k_psi0),
            cos * np.sin(k_psi0) + sin * np.cos(k_psi0),
        )
    return Harmonics(cos=cos, sin=sin, amplitude=np.hypot(cos, sin))


def vector_quantities(outputs: Mapping[str, Output]) -> dict[str, tuple[tuple[str, str], str, str]]:
    """The declared in-plane vectors: name -> ((x, y) source histories, units, long_name)."""
    return {name: (out.components, out.units, out.long_name)
            for name, out in outputs.items() if out.components is not None}


def harmonic_signals(outputs: Mapping[str, Output]) -> dict[str, Output]:
    """The declared single time histories whose harmonics are archived (name -> declaration)."""
    return {name: out for name, out in outputs.items()
            if out.harmonics and out.components is None}


def required_variables(outputs: Mapping[str, Output]) -> tuple[str, ...]:
    """The histories a model result needs for its declared harmonics."""
    names: list[str] = []
    for (vx, vy), _, _ in vector_quantities(outputs).values():
        names += [vx, vy]
    names += list(harmonic_signals(outputs))
    return tuple(dict.fromkeys(names))


def harmonic_names(outputs: Mapping[str, Output]) -> list[str]:
    """Names of the harmonic variables :func:`case_harmonics` makes from ``outputs``."""
    return [f"{v}{s}" for v in (*vector_quantities(outputs), *harmonic_signals(outputs))
            for s in SUFFIXES]


def recording_layout(ds: xr.Dataset) -> tuple[float, int, int, float]:
    """Check the time base of a model result and return ``(hub_speed, N, R, psi0)``.

    Parameters
    ----------
    ds
        Model output with coordinate ``time`` (s) and the scalar results ``run_hub_speed``
        (rad/s), ``run_samples_per_rev`` and ``run_revolutions``
        (:data:`studies.periodic.RUN_OUTPUTS`).

    Returns
    -------
    hub_speed : float
        Rotor speed Ω (rad/s).
    samples_per_rev, revolutions : int
        Samples per revolution and number of whole revolutions recorded.
    psi0 : float
        Azimuth ``Ω·time[0]`` of the first sample (rad).

    Raises
    ------
    ValueError
        If a variable is missing, or the time samples are not uniform over whole revolutions.
    """
    missing = [a for a in LAYOUT if a not in ds]
    if missing or "time" not in ds.coords:
        what = ", ".join([f"variable {a!r}" for a in missing]
                         + ([] if "time" in ds.coords else ["coordinate 'time'"]))
        raise ValueError(f"model result lacks {what}; see studies.harmonics for the layout")
    omega = float(ds["run_hub_speed"])
    n = int(ds["run_samples_per_rev"])
    revs = int(ds["run_revolutions"])
    if not omega > 0:
        raise ValueError(f"hub_speed = {omega:g} rad/s: must be positive for per-rev harmonics")
    t = np.asarray(ds["time"].values, dtype=float)
    if t.size != n * revs:
        raise ValueError(
            f"time has {t.size} samples, expected revolutions * samples_per_rev = "
            f"{revs} * {n} = {n * revs} (whole revolutions, endpoint excluded)"
        )
    dt = 2.0 * np.pi / (omega * n)
    if t.size > 1 and not np.allclose(np.diff(t), dt, rtol=TIME_STEP_RTOL, atol=0.0):
        raise ValueError(
            f"time samples are not uniform at one revolution / samples_per_rev = {dt:.6g} s "
            f"(found steps from {np.diff(t).min():.6g} to {np.diff(t).max():.6g} s)"
        )
    return omega, n, revs, omega * float(t[0])


def case_harmonics(ds: xr.Dataset, outputs: Mapping[str, Output],
                   n_max: int = N_MAX) -> xr.Dataset:
    """Per-rev harmonics of the declared outputs of one case.

    Parameters
    ----------
    ds
        A per-rev periodic model result: ``time`` (s), ``run_hub_speed`` (rad/s),
        ``run_samples_per_rev``, ``run_revolutions`` (see :func:`recording_layout`), and the
        time histories that ``outputs`` name for harmonics.
    outputs
        The model's declarations (:attr:`studies.parameters.ModelSpec.outputs`). Each gives
        ``<name>_amplitude``, ``<name>_cos`` and ``<name>_sin``: an in-plane vector
        (``components``) with dims ``(direction, harmonic)``, a history declared with
        ``harmonics=True`` with its other dimensions in front of ``harmonic`` (e.g.
        ``(bifilar, harmonic)``). Units are
        those of the declaration; every variable has ``units`` and ``long_name``.
    n_max
        Highest harmonic.

    Returns
    -------
    xarray.Dataset
        Dimension ``harmonic`` (0..n_max), ``direction`` (``"x"``, ``"y"``) if there is a vector,
        and the other dimensions of the harmonic histories with their coordinates.

    Raises
    ------
    ValueError
        If the time base is inconsistent, a vector has only one of its components, or the result
        holds none of the declared harmonic outputs.
    """
    _, n, revs, psi0 = recording_layout(ds)
    vectors = vector_quantities(outputs)
    signals = harmonic_signals(outputs)
    partial = [f"{vx}/{vy}" for (vx, vy), _, _ in vectors.values() if (vx in ds) != (vy in ds)]
    if partial:
        raise ValueError(f"model result has only one component of {', '.join(partial)}")
    present = [v for v in required_variables(outputs) if v in ds]
    if not present:
        raise ValueError("model result lacks variable(s) "
                         f"{', '.join(required_variables(outputs)) or '(none declared)'}")

    def transform(values: ArrayLike) -> Harmonics:
        return harmonics(values, n, revs, n_max, psi0=psi0, axis=-1)

    out = xr.Dataset(
        coords={
            "harmonic": (
                "harmonic",
                np.arange(n_max + 1),
                {"units": "1", "long_name": "harmonic number (cycles per rotor revolution)"},
            ),
        }
    )
    # the in-plane vectors' directions x, y; a model whose outputs have a direction dimension
    # of their own (e.g. x, y, z) sets the labels, and the vectors are NaN along the others
    labels = (ds["direction"].values.astype(str) if "direction" in ds.coords
              else np.array(["x", "y"]))
    if vectors or "direction" in ds.coords:
        out = out.assign_coords(direction=(
            "direction",
            labels,
            {"units": "1", "long_name": "direction of the frame (in-plane vectors: x, y)"},
        ))
    where = [list(labels).index(d) if d in labels else -1 for d in ("x", "y")]
    if vectors and min(where) < 0:
        raise ValueError(f"the model's direction labels {list(labels)} lack x or y, which "
                         "its in-plane vectors need")
    for name, ((vx, vy), units, long_name) in vectors.items():
        if vx not in ds or vy not in ds:
            continue
        h2 = transform(np.stack([ds[vx].values, ds[vy].values]))
        h = Harmonics(*(_placed(part, where, len(labels)) for part in h2))
        for suffix, values, what in (
            ("_amplitude", h.amplitude, "harmonic amplitude"),
            ("_cos", h.cos, "cosine coefficient"),
            ("_sin", h.sin, "sine coefficient"),
        ):
            out[name + suffix] = (
                ("direction", "harmonic"),
                values,
                {"units": units, "long_name": f"{long_name}, {what}"},
            )
    for name, decl in signals.items():
        if name not in ds:
            continue
        other = tuple(d for d in ds[name].dims if d != "time")
        var = ds[name].transpose(*other, "time")
        h = transform(var.values)
        for suffix, values, what in (
            ("_amplitude", h.amplitude, "harmonic amplitude"),
            ("_cos", h.cos, "cosine coefficient"),
            ("_sin", h.sin, "sine coefficient"),
        ):
            out[name + suffix] = (
                (*other, "harmonic"),
                values,
                {"units": decl.units, "long_name": f"{decl.long_name}, {what}"},
            )
        out = copy_coords(out, ds, other)
    return out


def _placed(values: NDArray[np.float64], rows: list[int], n: int) -> NDArray[np.float64]:
    """``values`` (2, …) put at rows ``rows`` of an (n, …) array of NaN."""
    out = np.full((n, *values.shape[1:]), np.nan)
    out[rows] = values
    return out


def copy_coords(out: xr.Dataset, ds: xr.Dataset, dims: tuple[str, ...]) -> xr.Dataset:
    """Coordinates of the extra output dimensions ``dims`` taken from ``ds`` (an index with
    units "1" if the model gave none)."""
    for dim in dims:
        if dim in out.coords:
            continue
        if dim in ds.coords:
            coord = ds[dim].variable.copy()
            coord.attrs = {"units": "1", "long_name": f"{dim} index", **coord.attrs}
        else:
            coord = xr.Variable(dim, np.arange(ds.sizes[dim]),
                                {"units": "1", "long_name": f"{dim} index"})
        out = out.assign_coords({dim: coord})
    return out
