"""`bifilar fanplot`: natural frequencies of the articulated UH-60A blade against rotor speed.

::

    bifilar fanplot [--speeds RAD_PER_S ...] [--elements N] [--control-system KIND]
                    [--pitch-link-stiffness N_PER_M] [--pitch-horn-length M] --out FILE.nc

Writes ``frequency`` (Hz) over (``hub_speed`` (rad s-1), ``mode``) with the ``mode_label``
coordinate, and draws the Campbell diagram next to FILE (``.png`` and ``.pdf``): the computed
modes, the 1P…8P lines, the digitized Bowen-Davies points and the bifilar tuning line.
"""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np
import xarray as xr

from pipelines.options import OutPath
from pipelines.single import check_writable, fail, finish_figure, run_single
from studies.bifilar import HARDWARE
from studies.fanplot import MAX_SPEED, PARAMETERS, SPEC
from studies.uh60a import UH60A, bowen_davies_fanplot

# How the case's worker finds the model (it is not in the sweep registry).
MODEL_REF = "studies.fanplot:SPEC"
# the control system's parameters, as the rotor declares them (studies.swashplate)
_CONTROL = PARAMETERS["control_system"]
_STIFFNESS = PARAMETERS["pitch_link_stiffness"]
_HORN = PARAMETERS["pitch_horn_length"]


def fanplot_figure(ds: xr.Dataset, stem: Path, tuning_order: float) -> list[Path]:
    """Campbell diagram of a fan-plot dataset; returns the PNG and PDF paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref = bowen_davies_fanplot()
    omega = ds.hub_speed.values
    top = 1.1 * float(np.nanmax(ds.frequency.values)) if np.isfinite(ds.frequency).any() else 40
    fig, ax = plt.subplots(figsize=(7.5, 6.0))
    span = np.array([0.0, max(omega.max(), UH60A.omega_ref) * 1.05])
    for n in range(1, 9):
        f = n * span / (2 * np.pi)
        ax.plot(span, f, color="0.75", lw=0.8, zorder=0)
        x_end = min(span[1], top * 2 * np.pi / n)
        ax.text(x_end, n * x_end / (2 * np.pi), f"{n}P", fontsize=7, color="0.45",
                ha="right", va="bottom")
    ax.plot(span, tuning_order * span / (2 * np.pi), color="tab:red", ls="--", lw=1.2,
            label=f"bifilar tuning, {tuning_order:g}P")
    colors = plt.get_cmap("tab10")
    for j, label in enumerate(ds.mode_label.values):
        c = colors(j % 10)
        ax.plot(omega, ds.frequency.values[:, j], "-", color=c, lw=1.5, label=str(label))
        sel = ref.mode_label.values == label
        if sel.any():
            ax.plot(ref.rotor_speed.values, ref.frequency.values[:, sel][:, 0], "o", ms=4,
                    mfc="none", color=c)
    ax.plot([], [], "o", mfc="none", color="0.3", label="Bowen-Davies (digitized)")
    ax.axvline(UH60A.omega_ref, color="0.5", lw=0.8, ls=":")
    ax.set_xlim(span)
    ax.set_ylim(0, top)
    ax.set_xlabel("rotor speed Ω (rad/s)")
    ax.set_ylabel("natural frequency (Hz)")
    ax.set_title("UH-60A articulated blade, rotating frame", fontsize=10)
    return finish_figure(fig, ax, stem)


class _SpeedList(click.ParamType):
    name = "RAD_PER_S"

    def convert(self, value, param, ctx):
        try:
            v = float(value)
        except (TypeError, ValueError):
            self.fail(f"rotor speed {value!r} is not a number (rad/s)", param, ctx)
        if not (np.isfinite(v) and 0.0 <= v <= MAX_SPEED):
            self.fail(f"rotor speed {v:g} rad/s must be in 0 … {MAX_SPEED:g} rad/s", param, ctx)
        return v


@click.command()
@click.option("--speeds", "speeds", multiple=True, type=_SpeedList(),
              help="rotor speeds (rad/s, 0 … 60), e.g. --speeds 0 13.5 27; default 0 … 1.2 "
                   "Ω_ref in steps of 0.1 Ω_ref (Ω_ref = 27 rad/s)")
@click.argument("more_speeds", nargs=-1, type=_SpeedList())
@click.option("--elements", default=6, show_default=True, type=click.IntRange(1, 60),
              help="cubic beam elements from the hinge to the tip")
@click.option("--control-system", default=_CONTROL.default, show_default=True,
              type=click.Choice(_CONTROL.choices), help="pitch restraint: prescribed (a rigid "
              "pitch link) or swashplate (an elastic pitch link on the horn)")
@click.option("--pitch-link-stiffness", default=_STIFFNESS.default, show_default=True,
              type=click.FloatRange(_STIFFNESS.minimum, _STIFFNESS.maximum, min_open=True),
              help=f"{_STIFFNESS.long_name} ({_STIFFNESS.units})")
@click.option("--pitch-horn-length", default=_HORN.default, show_default=True,
              type=click.FloatRange(_HORN.minimum, _HORN.maximum, min_open=True),
              help=f"{_HORN.long_name} ({_HORN.units})")
@click.option("--tuning-order", default=HARDWARE["tuning_order"].default, show_default=True,
              type=click.FloatRange(0.5, 10.0), help="bifilar tuning order drawn as a line")
@click.option("--out", required=True, type=OutPath(dir_okay=False, path_type=Path),
              help="netCDF file; the figure is written beside it (.png, .pdf)")
def fanplot(speeds: tuple[float, ...], more_speeds: tuple[float, ...], elements: int,
            control_system: str, pitch_link_stiffness: float, pitch_horn_length: float,
            tuning_order: float, out: Path) -> None:
    """Fan plot (Campbell diagram) of one articulated UH-60A blade.

    Natural frequencies about the steady spin at each rotor speed, from the linearized
    multibody model: coincident flap/lag hinges at 0.381 m, lag hinge free (no damper), a rigid
    pitch link (prescribed) or an elastic one on the pitch horn (swashplate: the torsion
    branch moves with the link's stiffness), Yeo section properties with the Davis cuff and the
    structural twist.
    """
    if more_speeds and not speeds:
        fail(f"unexpected argument {more_speeds[0]:g}: rotor speeds go after --speeds")
    check_writable(out)
    given = sorted(set(speeds + more_speeds))
    ds = run_single(SPEC, MODEL_REF, {"speeds": " ".join(map(repr, given)),
                                      "elements": elements, "control_system": control_system,
                                      "pitch_link_stiffness": pitch_link_stiffness,
                                      "pitch_horn_length": pitch_horn_length}, out)
    click.echo(str(out))
    for path in fanplot_figure(ds, out.with_suffix(""), tuning_order):
        click.echo(str(path))
    at_ref = ds.sel(hub_speed=UH60A.omega_ref, method="nearest")
    ref = bowen_davies_fanplot().sel(speed_ratio=float(at_ref.hub_speed) / UH60A.omega_ref,
                                     method="nearest")
    click.echo(f"at {float(at_ref.hub_speed):g} rad/s:  mode  computed  Bowen-Davies (Hz)")
    for label, f in zip(at_ref.mode_label.values, at_ref.frequency.values, strict=True):
        sel = ref.mode_label.values == label
        pub = f"{float(ref.frequency.values[sel][0]):9.3f}" if sel.any() else "        -"
        click.echo(f"  {label:>10}  {f:8.3f}  {pub}")
