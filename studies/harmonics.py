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
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

# Highest harmonic stored in the archive: a 4-bladed rotor's fixed-frame loads are at 4P and 8P,
# and 8P is where the rotating-frame 7P and 9P meet.
N_MAX = 8

# Relative tolerance on the time step against 2π/(Ω·N): samples must be uniform and span whole
# revolutions, otherwise the per-rev bins of the FFT do not hold the per-rev harmonics.
TIME_STEP_RTOL = 1e-6


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


# Harmonic outputs of one case: name -> (fixed-frame x and y source variables, units,
# long_name). The rotating-frame hub displacement is in the model output, so no frame rotation
# is done here.
VECTOR_QUANTITIES: dict[str, tuple[tuple[str, str], str, str]] = {
    "hub_displacement_rotating": (
        ("hub_x_rotating", "hub_y_rotating"),
        "m",
        "hub in-plane displacement in the rotating frame",
    ),
    "hub_displacement_fixed": (
        ("hub_x_fixed", "hub_y_fixed"),
        "m",
        "hub in-plane displacement in the fixed frame",
    ),
    "hub_force_fixed": (
        ("hub_force_x_fixed", "hub_force_y_fixed"),
        "N",
        "in-plane hub force transmitted to the fuselage, fixed frame",
    ),
    "bifilar_cm_displacement": (
        ("bifilar_cm_x_fixed", "bifilar_cm_y_fixed"),
        "m",
        "displacement of the centre of mass of the bifilar tuning masses, fixed frame",
    ),
}

# Variables a case must contain for its harmonics; the bifilar ones may be absent (a model
# without absorbers), in which case their harmonics are absent too.
REQUIRED_VARIABLES = (
    "hub_x_rotating", "hub_y_rotating", "hub_x_fixed", "hub_y_fixed",
    "hub_force_x_fixed", "hub_force_y_fixed",
)


def recording_layout(ds: xr.Dataset) -> tuple[float, int, int, float]:
    """Check the time base of a model result and return ``(hub_speed, N, R, psi0)``.

    Parameters
    ----------
    ds
        Model output with coordinate ``time`` (s) and attrs ``hub_speed`` (rad/s),
        ``samples_per_rev`` and ``revolutions``.

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
        If an attribute is missing, or the time samples are not uniform over whole revolutions.
    """
    missing = [a for a in ("hub_speed", "samples_per_rev", "revolutions") if a not in ds.attrs]
    if missing or "time" not in ds.coords:
        what = ", ".join([f"attribute {a!r}" for a in missing]
                         + ([] if "time" in ds.coords else ["coordinate 'time'"]))
        raise ValueError(f"model result lacks {what}; see pipelines.harmonics for the layout")
    omega = float(ds.attrs["hub_speed"])
    n = int(ds.attrs["samples_per_rev"])
    revs = int(ds.attrs["revolutions"])
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


def case_harmonics(ds: xr.Dataset, n_max: int = N_MAX) -> xr.Dataset:
    """Per-rev harmonics of the hub, force, bifilar and pin-angle responses of one case.

    Parameters
    ----------
    ds
        A model result in the hub layout (see :mod:`studies.registry`): ``time`` (s), attrs
        ``hub_speed`` (rad/s), ``samples_per_rev``, ``revolutions``, and the variables
        ``hub_{x,y}_rotating``, ``hub_{x,y}_fixed``, ``hub_force_{x,y}_fixed`` (and, when the
        model has bifilars, ``bifilar_cm_{x,y}_fixed`` and ``pin_angle(bifilar, time)``).
    n_max
        Highest harmonic.

    Returns
    -------
    xarray.Dataset
        Dimension ``harmonic`` (0..n_max) and ``direction`` (``"x"``, ``"y"``); for each of
        ``hub_displacement_rotating`` (m), ``hub_displacement_fixed`` (m), ``hub_force_fixed`` (N),
        ``bifilar_cm_displacement`` (m): the amplitude under that name and the coefficients as
        ``<name>_cos`` and ``<name>_sin``, dims ``(direction, harmonic)``; and
        ``pin_angle_amplitude``, ``pin_angle_cos``, ``pin_angle_sin`` (degree), dims
        ``(bifilar, harmonic)``. Every variable has ``units`` and ``long_name``.

    Raises
    ------
    ValueError
        If the time base is inconsistent or a required variable is missing.
    """
    _, n, revs, psi0 = recording_layout(ds)
    missing = [v for v in REQUIRED_VARIABLES if v not in ds]
    if missing:
        raise ValueError(f"model result lacks variable(s) {', '.join(missing)}")

    def transform(values: ArrayLike) -> Harmonics:
        return harmonics(values, n, revs, n_max, psi0=psi0, axis=-1)

    out = xr.Dataset(
        coords={
            "harmonic": (
                "harmonic",
                np.arange(n_max + 1),
                {"units": "1", "long_name": "harmonic number (cycles per rotor revolution)"},
            ),
            "direction": (
                "direction",
                np.array(["x", "y"]),
                {"units": "1", "long_name": "in-plane direction of the frame"},
            ),
        }
    )
    for name, ((vx, vy), units, long_name) in VECTOR_QUANTITIES.items():
        if vx not in ds or vy not in ds:
            continue
        h = transform(np.stack([ds[vx].values, ds[vy].values]))
        for suffix, values, what in (
            ("", h.amplitude, "harmonic amplitude"),
            ("_cos", h.cos, "cosine coefficient"),
            ("_sin", h.sin, "sine coefficient"),
        ):
            out[name + suffix] = (
                ("direction", "harmonic"),
                values,
                {"units": units, "long_name": f"{long_name}, {what}"},
            )
    if "pin_angle" in ds:
        pins = ds["pin_angle"].transpose("bifilar", "time")
        h = transform(pins.values)
        units = pins.attrs.get("units", "degree")
        for suffix, values, what in (
            ("_amplitude", h.amplitude, "harmonic amplitude"),
            ("_cos", h.cos, "cosine coefficient"),
            ("_sin", h.sin, "sine coefficient"),
        ):
            out["pin_angle" + suffix] = (
                ("bifilar", "harmonic"),
                values,
                {"units": units, "long_name": f"bifilar pin angle, {what}"},
            )
        out = out.assign_coords(
            bifilar=(
                "bifilar",
                np.asarray(pins["bifilar"].values) if "bifilar" in pins.coords
                else np.arange(pins.sizes["bifilar"]),
                {"units": "1", "long_name": "bifilar absorber number (0 and 2 are opposite)"},
            )
        )
    return out
