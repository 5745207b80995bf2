"""Flight-envelope figures of a rotor archive (``studies/envelope_study.toml``).

Drawn by :func:`pipelines.plots.plot_archive` for any archive, a case list or a Cartesian sweep,
whose ok cases hold the rotor's 4P hub loads:

``envelope_hub_loads_4p``
    When ``flight_speed`` takes two or more values and the cases are trimmed (``trim`` other
    than ``none``): the 4P amplitudes of the in-plane hub force (x, y), the vertical hub force
    and the in-plane hub moments (x, y), fixed frame, against airspeed, one line per absorber
    (``bifilar``, and any other parameter that varies).
``envelope_controls_power``
    The trimmed controls (collective, cyclics, shaft tilt) and the rotor power against airspeed
    (the power curve).
``envelope_pin_amplitude``
    The pins' swing, half their peak-to-peak angle over the recorded revolution (the largest of
    the four bifilars), against airspeed; absorbers whose pins do not swing are left out.
``reduction_4p_vs_hub_speed``
    When ``hub_speed`` takes two or more values at one flight speed: the 4P reduction of each
    absorber, 1 − (its 4P load) / (the locked case's at the same rotor speed and flight speed),
    against rotor speed, for the in-plane hub force (√(x² + y²) of the amplitudes), the
    vertical force and the in-plane hub moment.

The airspeed figures take the cases at the rotor speed with the most airspeeds (the nominal
one of the envelope study); the rotor-speed figure the cases at the flight speeds where the
rotor speed varies. Airspeed is drawn in m/s (the archive's units) with knots on the top axis.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from matplotlib.figure import Figure

from pipelines.archive import STATUS_OK

KNOT = 1852.0 / 3600.0  # m/s
HARMONIC = 4  # blade passage of the four-bladed rotor, fixed frame
# The loads whose 4P amplitude is drawn: column -> (archived harmonic variable, direction, title).
LOADS: dict[str, tuple[str, str | None, str]] = {
    "force_x": ("hub_force_fixed_amplitude", "x", "in-plane hub force, x"),
    "force_y": ("hub_force_fixed_amplitude", "y", "in-plane hub force, y"),
    "force_z": ("hub_force_z_fixed_amplitude", None, "vertical hub force"),
    "moment_x": ("hub_moment_fixed_amplitude", "x", "in-plane hub moment, about x"),
    "moment_y": ("hub_moment_fixed_amplitude", "y", "in-plane hub moment, about y"),
}
# Pins whose half peak-to-peak angle stays below this (degree) do not swing (locked bifilars).
SWING_LEVEL = 1e-6
CONTROLS: dict[str, str] = {
    "control_collective": "collective θ0",
    "control_cyclic_sine": "longitudinal cyclic θs",
    "control_cyclic_cosine": "lateral cyclic θc",
    "control_shaft_tilt": "shaft tilt α_s (forward)",
}
# Parameters that are the abscissae, not line labels.
AXES = ("flight_speed", "hub_speed")
# Columns of the case tables that are results, not parameters.
RESULTS = frozenset({*LOADS, *CONTROLS, "rotor_power", "pin_swing", "force", "moment",
                     "force_locked", "force_z_locked", "moment_locked"})


def case_variable(ds: xr.Dataset, name: str, sel: dict[str, int]) -> xr.DataArray:
    """Variable ``name`` of one case (``sel``: the case's indices along the archive's case
    dimensions; those the variable lacks are left out)."""
    var = ds[name]
    return var.isel({d: i for d, i in sel.items() if d in var.dims})


def _value(ds: xr.Dataset, name: str, sel: dict[str, int]) -> Any:
    """A variable's value for one case (scalars are common to every case)."""
    value = case_variable(ds, name, sel).values
    value = value.item() if value.ndim == 0 else value
    return value.decode() if isinstance(value, bytes) else value


def _pin_swing(ds: xr.Dataset, sel: dict[str, int]) -> float:
    """Half the peak-to-peak pin angle over the recorded revolution, largest bifilar (degree)."""
    if "pin_angle" not in ds:
        return np.nan
    var = case_variable(ds, "pin_angle", sel)
    time = [d for d in var.dims if d in ("time_in_rev", "sample")]
    if not time:
        return np.nan
    values = var.values if var.dims[-1] == time[0] else var.transpose(..., time[0]).values
    values = np.atleast_2d(values)
    return float(np.nanmax(np.ptp(values, axis=-1)) / 2.0)


def case_table(ds: xr.Dataset, parameters: Sequence[str]) -> pd.DataFrame:
    """The ok cases of an archive as rows: the given parameters (those archived), the 4P loads
    (:data:`LOADS`), the controls, the rotor power and the pin swing (``pin_swing``)."""
    dims = tuple(ds["status"].dims)
    names = [p for p in parameters if p in ds]
    rows = []
    for index in np.ndindex(*ds["status"].shape):
        if int(ds["status"].values[index]) != STATUS_OK:
            continue
        sel = dict(zip(dims, index, strict=True))
        row: dict[str, Any] = {p: _value(ds, p, sel) for p in names}
        for column, (var, direction, _title) in LOADS.items():
            if var not in ds:
                continue
            amp = case_variable(ds, var, sel).sel(harmonic=HARMONIC)
            row[column] = float(amp.sel(direction=direction) if direction else amp)
        for name in (*CONTROLS, "rotor_power"):
            if name in ds:
                row[name] = float(_value(ds, name, sel))
        row["pin_swing"] = _pin_swing(ds, sel)
        rows.append(row)
    return pd.DataFrame(rows)


def _varying(table: pd.DataFrame, exclude: Sequence[str]) -> list[str]:
    """Parameters of the table that take more than one value, other than ``exclude``."""
    return [c for c in table.columns
            if c not in RESULTS and c not in exclude and table[c].nunique() > 1]


def _label(keys: Sequence[str], values: Any) -> str:
    values = values if isinstance(values, tuple) else (values,)
    parts = []
    for key, value in zip(keys, values, strict=True):
        text = f"{value:g}" if isinstance(value, float) else str(value)
        parts.append(text if key == "bifilar" else f"{key}={text}")
    return ", ".join(parts) or "all cases"


def _keys(table: pd.DataFrame, exclude: Sequence[str]) -> list[str]:
    """The varying parameters other than ``exclude``, ``bifilar`` first: a curve's label."""
    return sorted(_varying(table, exclude), key=lambda k: k != "bifilar")


def _groups(table: pd.DataFrame, x: str, keys: Sequence[str]) -> list[tuple[str, pd.DataFrame]]:
    """One curve per combination of the parameters ``keys``, sorted along ``x``."""
    keys = list(keys)
    if not keys:
        return [(_label([], ()), table.sort_values(x))]
    return [(_label(keys, values), group.sort_values(x))
            for values, group in table.groupby(keys if len(keys) > 1 else keys[0], sort=False)]


def _nominal(table: pd.DataFrame, along: str, at: str) -> pd.DataFrame:
    """The cases at the value of ``at`` that has the most distinct values of ``along``."""
    if at not in table or table[at].nunique() < 2:
        return table
    counts = table.groupby(at)[along].nunique()
    return table[table[at] == counts.idxmax()]


def _knots_axis(ax: Any) -> None:
    """Airspeed in m/s below, knots on a top axis."""
    top = ax.secondary_xaxis("top", functions=(lambda v: v / KNOT, lambda v: v * KNOT))
    top.set_xlabel("airspeed (kt)", fontsize="small")
    top.tick_params(labelsize="small")


def _style_map(table: pd.DataFrame, keys: Sequence[str]) -> dict[str, dict[str, Any]]:
    """One style per curve label of the whole archive, the same in every envelope figure."""
    from pipelines.plots import _styles

    labels = [label for label, _ in _groups(table, table.columns[0], keys)]
    return dict(zip(labels, _styles(len(labels)), strict=True))


def _panels(fig: Figure, n: int, cols: int) -> list[Any]:
    rows = -(-n // cols)
    axes = list(fig.subplots(rows, cols, squeeze=False, sharex=True).ravel())
    for ax in axes[n:]:
        ax.set_visible(False)
    return axes[:n]


def _against(table: pd.DataFrame, x: str, columns: dict[str, str], ylabels: dict[str, str],
             scales: dict[str, float], title: str, xlabel: str, stem: str, out_dir: Path,
             formats: Sequence[str], styles: dict[str, dict[str, Any]],
             keys: Sequence[str], cols: int = 2) -> list[Path]:
    """A figure of ``columns`` (one panel each) against ``x``, one line per combination of
    ``keys`` in its style of ``styles``."""
    from pipelines.plots import _legend, _line, _save

    curves = [(label, group, styles[label]) for label, group in _groups(table, x, keys)]
    fig = Figure(figsize=(5.0 * cols, 1.6 + 2.8 * -(-len(columns) // cols)),
                 layout="constrained")
    axes = _panels(fig, len(columns), cols)
    for ax, (column, panel_title) in zip(axes, columns.items(), strict=True):
        for i, (label, group, style) in enumerate(curves):
            _line(ax, group[x].to_numpy(float), group[column].to_numpy(float) * scales[column],
                  style, i, len(curves), label=label)
        ax.set_title(panel_title, fontsize="medium")
        ax.set_ylabel(ylabels[column])
        ax.grid(True, alpha=0.3)
        if x == "flight_speed":
            _knots_axis(ax)
    for ax in axes[-cols:]:
        ax.set_xlabel(xlabel)
        ax.xaxis.set_tick_params(labelbottom=True)
    fig.align_ylabels(axes)
    fig.suptitle(title, wrap=True)
    _legend(fig, axes[0])
    return _save(fig, out_dir, stem, formats)


def _load_units(table: pd.DataFrame) -> tuple[dict[str, float], dict[str, str]]:
    """kN and kN m when the loads reach 10 kN (m), N and N m otherwise."""
    scales, labels = {}, {}
    for column in LOADS:
        if column not in table:
            continue
        big = float(np.nanmax(np.abs(table[column].to_numpy(float)))) >= 1e4
        unit = "N m" if column.startswith("moment") else "N"
        scales[column] = 1e-3 if big else 1.0
        labels[column] = f"4P amplitude ({'k' if big else ''}{unit})"
    return scales, labels


def _airspeed_figures(table: pd.DataFrame, out_dir: Path, formats: Sequence[str],
                      styles: dict[str, dict[str, Any]], keys: Sequence[str]) -> list[Path]:
    table = _nominal(table, "flight_speed", "hub_speed")
    xlabel = "airspeed (m s-1)"
    where = ""
    if "hub_speed" in table and table["hub_speed"].nunique() == 1:
        where = f" at Ω = {float(table['hub_speed'].iloc[0]):g} rad/s"
    paths: list[Path] = []
    loads = {c: LOADS[c][2] for c in LOADS if c in table}
    if loads:
        scales, labels = _load_units(table)
        paths += _against(table, "flight_speed", loads, labels, scales,
                          f"4P vibratory hub loads (fixed frame) against airspeed{where}",
                          xlabel, "envelope_hub_loads_4p", out_dir, formats, styles, keys)
    controls = {c: t for c, t in CONTROLS.items() if c in table}
    if "rotor_power" in table:
        controls["rotor_power"] = "rotor power (the power curve)"
    if controls:
        labels = {c: "degree" for c in CONTROLS} | {"rotor_power": "kW"}
        scales = {c: 1.0 for c in CONTROLS} | {"rotor_power": 1e-3}
        paths += _against(table, "flight_speed", controls, labels, scales,
                          f"Trimmed controls and rotor power against airspeed{where}",
                          xlabel, "envelope_controls_power", out_dir, formats, styles, keys)
    swings = table["pin_swing"].fillna(0.0) > SWING_LEVEL
    if keys:  # every case of an absorber whose pins swing somewhere
        swings = swings.groupby([table[k] for k in keys]).transform("any")
    swinging = table[swings.to_numpy(bool)]
    if len(swinging):
        paths += _against(swinging, "flight_speed", {"pin_swing": "bifilar pin swing"},
                          {"pin_swing": "half peak-to-peak pin angle, largest bifilar (degree)"},
                          {"pin_swing": 1.0}, f"Pin amplitude against airspeed{where}",
                          xlabel, "envelope_pin_amplitude", out_dir, formats, styles, keys,
                          cols=1)
    return paths


def reduction_table(table: pd.DataFrame) -> pd.DataFrame:
    """Each absorber's 4P reduction against the locked case with otherwise equal parameters:
    ``force`` (in-plane, √(x² + y²)), ``force_z`` and ``moment`` (in-plane), as
    1 − absorber / locked; absorbers without a locked partner are left out."""
    keys = [c for c in table.columns if c not in RESULTS and c != "bifilar"]
    magnitude = pd.DataFrame({
        "force": np.hypot(table["force_x"], table["force_y"]),
        "force_z": table["force_z"],
        "moment": np.hypot(table["moment_x"], table["moment_y"]),
    })
    data = pd.concat([table[[*keys, "bifilar"]], magnitude], axis=1)
    locked = data[data["bifilar"] == "locked"]
    others = data[data["bifilar"] != "locked"]
    merged = others.merge(locked.drop(columns="bifilar"), on=keys, suffixes=("", "_locked"))
    for column in ("force", "force_z", "moment"):
        merged[column] = 1.0 - merged[column] / merged[f"{column}_locked"]
    return merged[[*keys, "bifilar", "force", "force_z", "moment"]]


def _rotor_speed_figure(table: pd.DataFrame, out_dir: Path, formats: Sequence[str],
                        styles: dict[str, dict[str, Any]], keys: Sequence[str]) -> list[Path]:
    table = _nominal(table, "hub_speed", "flight_speed")
    if not all(c in table for c in ("force_x", "force_y", "force_z", "moment_x", "moment_y")):
        return []
    reduction = reduction_table(table)
    if reduction.empty or reduction["hub_speed"].nunique() < 2:
        return []
    where = ""
    if "flight_speed" in table and table["flight_speed"].nunique() == 1:
        speed = float(table["flight_speed"].iloc[0])
        where = f" at {speed:.3g} m/s ({speed / KNOT:.0f} kt)"
    columns = {"force": "in-plane hub force √(x² + y²)", "force_z": "vertical hub force",
               "moment": "in-plane hub moment √(x² + y²)"}
    ylabel = "4P reduction over locked (%)"
    return _against(reduction, "hub_speed", columns, dict.fromkeys(columns, ylabel),
                    dict.fromkeys(columns, 100.0),
                    f"4P hub-load reduction against rotor speed{where}", "rotor speed Ω (rad s-1)",
                    "reduction_4p_vs_hub_speed", out_dir, formats, styles, keys, cols=3)


def sweeps_envelope(ds: xr.Dataset) -> bool:
    """Whether an archive's cases vary the airspeed or the rotor speed of the rotor (and hold
    its 4P hub loads): its figures are then this module's, not Table 1's paired comparisons."""
    if "hub_force_fixed_amplitude" not in ds:
        return False
    return any(name in ds and np.unique(ds[name].values).size > 1 for name in AXES)


def envelope_figures(ds: xr.Dataset, parameters: Sequence[str], out_dir: Path,
                     formats: Sequence[str]) -> list[Path]:
    """The flight-envelope figures of an archive (see the module documentation).

    Parameters
    ----------
    ds
        The archive as :func:`pipelines.archive.open_archive` returns it (harmonic variables
        under their archived names, ``<name>_amplitude``).
    parameters
        The model's parameter names (the candidates for abscissae and line labels).
    out_dir
        Directory for the figures.
    formats
        File formats.

    Returns
    -------
    list of pathlib.Path
        The files written; none if the archive sweeps neither airspeed (trimmed) nor rotor
        speed, or lacks the rotor's 4P hub loads.
    """
    if "flight_speed" not in ds or "hub_force_fixed_amplitude" not in ds:
        return []
    table = case_table(ds, parameters)
    if table.empty:
        return []
    paths: list[Path] = []
    keys = _keys(table, AXES)
    styles = _style_map(table, keys)
    trimmed = "trim" in table and (table["trim"] != "none").all()
    if trimmed and table["flight_speed"].nunique() > 1:
        paths += _airspeed_figures(table, out_dir, formats, styles, keys)
    if "hub_speed" in table and "bifilar" in table and table["hub_speed"].nunique() > 1:
        paths += _rotor_speed_figure(table, out_dir, formats, styles, keys)
    return paths
