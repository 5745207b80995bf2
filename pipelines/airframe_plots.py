"""Figures of a rotor archive whose cases include a modal airframe (``fuselage = "modal"``,
e.g. ``studies/airframe_study.toml``), pairing it with the paper's model case by case.

Drawn by :func:`pipelines.plots.plot_archive` for any rotor archive with at least one ok case
on a modal airframe:

``airframe_hub_loads_4p``
    The 4P amplitudes of the in-plane hub force (x, y), the vertical hub force and the in-plane
    hub moments (x, y), fixed frame: one bar per ok case, coloured by the model: the paper's
    (fuselage-beam, prescribed pitch), the swashplate on the fuselage-beam, the modal airframe
    with the pitch prescribed, or both (:data:`MODELS`).
``airframe_cabin_vibration_4p``
    The 4P vibration at each response station of the modal cases, in g: the magnitude of the 4P
    harmonic of the station's acceleration vector, √(Σ over x, y, z of the 4P amplitude²), one
    bar per case and station.
``airframe_pin_amplitude``
    The pins' swing (half their peak-to-peak angle over the recorded revolution, the largest of
    the four bifilars), one bar per ok case with swinging pins.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from pipelines.archive import STATUS_OK
from pipelines.envelope_plots import HARMONIC, LOADS, SWING_LEVEL, _pin_swing, case_variable
from studies.airframe import G0

# The models a case may stand for, by (fuselage, control_system): legend text and bar colour.
MODELS = {
    ("beam", "prescribed"): ("paper's model (fuselage-beam, prescribed pitch)", "tab:blue"),
    ("beam", "swashplate"): ("fuselage-beam, swashplate", "tab:green"),
    ("modal", "prescribed"): ("modal airframe, prescribed pitch", "tab:purple"),
    ("modal", "swashplate"): ("modal airframe, swashplate", "tab:orange"),
}


def has_airframe(ds: xr.Dataset) -> bool:
    """Whether an archive holds an ok case on a modal airframe."""
    if "fuselage" not in ds or "status" not in ds:
        return False
    modal = np.asarray(ds["fuselage"].values == "modal")
    ok = np.asarray(ds["status"].values == STATUS_OK)
    return bool(np.any(np.broadcast_to(modal, ok.shape) & ok))


def _cases(ds: xr.Dataset) -> list[tuple[str, dict[str, int], tuple[str, str]]]:
    """The ok cases as (label, isel indexers, model: its key in :data:`MODELS`), labelled as
    every figure labels them (:func:`pipelines.plots._cases`)."""
    from pipelines.plots import _cases as archive_cases

    out = []
    for case in archive_cases(ds):
        if not case.ok:
            continue
        fuselage = str(case_variable(ds, "fuselage", case.sel).values.item())
        control = (str(case_variable(ds, "control_system", case.sel).values.item())
                   if "control_system" in ds else "prescribed")
        out.append((case.label, case.sel, (fuselage, control)))
    return out


def station_vibration(ds: xr.Dataset, sel: dict[str, int], harmonic: int = HARMONIC
                      ) -> np.ndarray:
    """The vibration (g) at each station of one case: the magnitude of the ``harmonic``-th
    harmonic of the station's acceleration vector, √(Σ over x, y, z of its amplitude²)."""
    amp = case_variable(ds, "station_acceleration_amplitude", sel).sel(harmonic=harmonic)
    return np.sqrt((amp.transpose("station", "direction").values ** 2).sum(axis=1)) / G0


def _bars(ax: Any, labels: Sequence[str], values: Sequence[float],
          models: Sequence[tuple[str, str]]) -> None:
    x = np.arange(len(labels))
    ax.bar(x, values, 0.7, color=[MODELS[m][1] for m in models], edgecolor="black",
           linewidth=0.5)
    ax.set_xticks(x, labels, rotation=30, ha="right", fontsize="small")
    ax.grid(True, axis="y", alpha=0.3)
    ax.set_ylim(bottom=0)


def _model_legend(fig: Figure, models: Sequence[tuple[str, str]]) -> None:
    from matplotlib.patches import Patch

    shown = [m for m in MODELS if m in models]
    fig.legend([Patch(facecolor=MODELS[m][1], edgecolor="black") for m in shown],
               [MODELS[m][0] for m in shown], loc="outside lower center", ncols=len(shown),
               fontsize="small")


def airframe_figures(ds: xr.Dataset, out_dir: Path, formats: Sequence[str]) -> list[Path]:
    """The figures of the module docstring for an archive (none without a modal case)."""
    from pipelines.plots import _save

    if not has_airframe(ds):
        return []
    cases = _cases(ds)
    labels = [c[0] for c in cases]
    models = [c[2] for c in cases]
    paths: list[Path] = []

    # ---- 4P hub loads
    loads = {k: v for k, v in LOADS.items() if v[0] in ds}
    if loads:
        # two panels abreast, half an inch a bar
        fig = Figure(figsize=(max(10.0, 2 * (1.5 + 0.5 * len(cases))),
                              3.4 * -(-len(loads) // 2) + 1.5), layout="constrained")
        axes = fig.subplots(-(-len(loads) // 2), 2, squeeze=False).ravel()
        for ax in axes[len(loads):]:
            ax.set_visible(False)
        for ax, (var, direction, title) in zip(axes, loads.values(), strict=False):
            values = []
            for _, sel, _ in cases:
                amp = case_variable(ds, var, sel).sel(harmonic=HARMONIC)
                values.append(float(amp.sel(direction=direction) if direction else amp))
            unit = "N m" if "moment" in var else "N"
            _bars(ax, labels, values, models)
            ax.set_title(f"4P {title}", fontsize="medium")
            ax.set_ylabel(f"amplitude ({unit})")
        _model_legend(fig, models)
        fig.suptitle("4P hub loads, fixed frame: the paper's model and the modal airframe")
        paths += _save(fig, out_dir, "airframe_hub_loads_4p", formats)

    # ---- cabin vibration per station
    if "station_acceleration_amplitude" in ds and "station" in ds.coords:
        modal = [(label, sel) for label, sel, model in cases if model[0] == "modal"]
        stations = [str(s) for s in ds["station"].values]
        fig = Figure(figsize=(max(9.0, 1.0 + 0.5 * len(modal) * len(stations)), 5.0),
                     layout="constrained")
        ax = fig.subplots()
        width = 0.8 / max(len(modal), 1)
        x = np.arange(len(stations))
        from pipelines.plots import _styles

        for i, ((label, sel), style) in enumerate(zip(modal, _styles(len(modal)),
                                                      strict=True)):
            g = station_vibration(ds, sel)
            ax.bar(x - 0.4 + (i + 0.5) * width, g, width, label=label, color=style["color"],
                   edgecolor="black", linewidth=0.5)
        ax.set_xticks(x, stations)
        ax.set_ylabel("4P vibration (g)")
        ax.grid(True, axis="y", alpha=0.3)
        ax.set_ylim(bottom=0)
        ax.legend(fontsize="small")
        fig.suptitle("4P vibration at the airframe's stations, √(Σ x, y, z amplitude²)")
        paths += _save(fig, out_dir, "airframe_cabin_vibration_4p", formats)

    # ---- pins
    swing = [(label, _pin_swing(ds, sel), model) for label, sel, model in cases]
    swing = [s for s in swing if np.isfinite(s[1]) and s[1] > SWING_LEVEL]
    if swing:
        fig = Figure(figsize=(max(8.0, 1.5 + 0.6 * len(swing)), 5.0), layout="constrained")
        ax = fig.subplots()
        _bars(ax, [s[0] for s in swing], [s[1] for s in swing], [s[2] for s in swing])
        ax.set_ylabel("pin swing, half peak-to-peak (degree)")
        _model_legend(fig, [s[2] for s in swing])
        fig.suptitle("Pin amplitude: the paper's model and the modal airframe")
        paths += _save(fig, out_dir, "airframe_pin_amplitude", formats)
    return paths
