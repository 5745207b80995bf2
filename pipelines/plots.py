"""Report figures of a consolidated archive (the paper's Figs. 14–19), as PNG and PDF.

Figures are built on :class:`matplotlib.figure.Figure` directly, rendered by the Agg (PNG) and
PDF backends at ``savefig``: no pyplot state, so importing this module never changes the
interactive backend of a notebook, and a figure is freed as soon as it goes out of scope (the
memory ``plt.close(fig)`` would release is never registered with pyplot in the first place).

Figures written by :func:`plot_archive`:

``harmonics_<quantity>``
    Grouped bars of the per-rev harmonic amplitudes 0..8, one bar per case, for the hub
    displacement in the rotating frame (Fig. 17), the hub in-plane force in the fixed frame
    (Figs. 18–19) and the hub displacement in the fixed frame. For a Cartesian sweep of more than
    :data:`MAX_BAR_CASES` cases: ``harmonics_<quantity>_vs_<parameter>``, the dominant harmonic
    amplitudes against the first swept parameter, one line per value of the others.
``pin_angles``
    Pin angles of the opposite bifilars 0 and 2 over one revolution, one panel per free case
    (Fig. 14).
``orbits``
    In-plane orbits of the hub and of the bifilar tuning masses' centre of mass (Fig. 15).
``hub_force_history``
    Transmitted in-plane hub force over one revolution (Fig. 16).

Time-history figures hold at most :data:`CASES_PER_PAGE` cases; more go on further pages
(``pin_angles_p2`` …).
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from pipelines.archive import STATUS_OK, open_archive

# More bars than this per harmonic group are unreadable: a sweep switches to line plots.
MAX_BAR_CASES = 8
# Cases per time-history figure (one panel each for pin angles, one line each otherwise).
CASES_PER_PAGE = 8
FORMATS = ("png", "pdf")
DPI = 150

# Harmonic bar charts: variable -> figure title.
HARMONIC_FIGURES = {
    "hub_displacement_rotating": "Hub displacement harmonics, rotating frame",
    "hub_force_fixed": "Hub in-plane force harmonics, fixed frame",
    "hub_displacement_fixed": "Hub displacement harmonics, fixed frame",
}


def _save(fig: Figure, out_dir: Path, stem: str, formats: Sequence[str]) -> list[Path]:
    paths = []
    for fmt in formats:
        path = out_dir / f"{stem}.{fmt}"
        fig.savefig(path, dpi=DPI)
        paths.append(path)
    return paths


def _display_units(units: str, values: np.ndarray) -> tuple[float, str]:
    """Scale factor and unit label that make hub-size numbers readable (mm, kN)."""
    peak = float(np.nanmax(np.abs(values))) if np.isfinite(values).any() else 0.0
    if units == "m" and peak < 0.1:
        return 1e3, "mm"
    if units == "N" and peak >= 1e4:
        return 1e-3, "kN"
    return 1.0, units


def _case_dims(ds: xr.Dataset) -> tuple[str, ...]:
    return tuple(ds["status"].dims)


def _format(value: Any) -> str:
    if isinstance(value, float | np.floating):
        return f"{value:g}"
    return str(value.item() if isinstance(value, np.generic) else value)


def _cases(ds: xr.Dataset) -> list[tuple[str, dict[str, int], bool]]:
    """Every case of the archive as ``(legend label, isel indexers, finished ok)``."""
    dims = _case_dims(ds)
    out = []
    for index in np.ndindex(*ds["status"].shape):
        sel = dict(zip(dims, index, strict=True))
        if dims == ("case",):
            label = str(ds["case_name"].values[index[0]]) if "case_name" in ds else str(index[0])
        else:
            label = ", ".join(f"{d}={_format(ds[d].values[i])}" for d, i in sel.items())
        ok = int(ds["status"].values[index]) == STATUS_OK
        out.append((label if ok else f"{label} (failed)", sel, ok))
    return out


def _is_free(ds: xr.Dataset, sel: dict[str, int]) -> bool:
    """Whether a case's bifilars are free to swing (a locked case has nothing to plot)."""
    if "bifilar" in ds.variables and ds["bifilar"].dtype.kind in "OUS":
        setting = ds["bifilar"].isel({k: v for k, v in sel.items() if k in ds["bifilar"].dims})
        if str(setting.values) == "locked":
            return False
    pins = ds["pin_angle"].isel(sel).values
    return bool(np.isfinite(pins).all() and np.abs(pins).max() > 0)


def _pages(items: list[Any]) -> list[list[Any]]:
    return [items[i:i + CASES_PER_PAGE] for i in range(0, len(items), CASES_PER_PAGE)]


def _page_stem(stem: str, page: int, pages: int) -> str:
    return stem if pages == 1 else f"{stem}_p{page + 1}"


def _legend(fig: Figure, ax: Any) -> None:
    """Legend under the axes, in as many columns as the labels' length allows."""
    handles, labels = ax.get_legend_handles_labels()
    if not labels:
        return
    # About 110 characters of small text fit across a 9-10 inch figure.
    ncols = max(1, min(len(labels), 4, 110 // (max(map(len, labels)) + 6)))
    fig.legend(handles, labels, loc="outside lower center", ncols=ncols, fontsize="small")


def _axis_label(attrs: dict[str, Any], fallback: str) -> str:
    units = attrs.get("units", "")
    name = attrs.get("long_name") or fallback
    return name if units in ("", "1") else f"{name} ({units})"


def _psi_axis(ax: Any) -> None:
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 90))
    ax.grid(True, alpha=0.3)


def _colors(n: int) -> list[Any]:
    from matplotlib import colormaps

    cmap = colormaps["tab10"] if n <= 10 else colormaps["viridis"]
    return [cmap(i if n <= 10 else i / max(n - 1, 1)) for i in range(n)]


def _harmonic_bars(ds: xr.Dataset, name: str, title: str, out_dir: Path,
                   formats: Sequence[str]) -> list[Path]:
    cases = _cases(ds)
    var = ds[name]
    scale, units = _display_units(var.attrs.get("units", ""), var.values)
    harmonic = ds["harmonic"].values
    width = 0.8 / len(cases)
    fig = Figure(figsize=(9, 6.5), layout="constrained")
    axes = fig.subplots(ds.sizes["direction"], 1, sharex=True, squeeze=False)[:, 0]
    colors = _colors(len(cases))
    for ax, direction in zip(axes, ds["direction"].values, strict=True):
        for i, (label, sel, _ok) in enumerate(cases):
            amp = var.isel(sel).sel(direction=direction).values * scale
            ax.bar(harmonic - 0.4 + (i + 0.5) * width, amp, width, label=label,
                   color=colors[i], edgecolor="black", linewidth=0.5)
        ax.set_ylabel(f"{direction} amplitude ({units})")
        ax.grid(True, axis="y", alpha=0.3)
    axes[-1].set_xticks(harmonic)
    axes[-1].set_xlabel("harmonic (cycles per rotor revolution)")
    fig.suptitle(title)
    _legend(fig, axes[0])
    return _save(fig, out_dir, f"harmonics_{name}", formats)


def _dominant_harmonics(values: np.ndarray, harmonic: np.ndarray, count: int = 2) -> list[int]:
    """The ``count`` non-zero harmonics with the largest amplitude over all cases."""
    flat = np.abs(values).reshape(-1, values.shape[-1])
    peak = np.where(np.isfinite(flat), flat, 0.0).max(axis=0)
    order = [int(harmonic[i]) for i in np.argsort(-peak) if harmonic[i] != 0]
    return sorted(order[:count])


def _harmonic_lines(ds: xr.Dataset, name: str, title: str, out_dir: Path,
                    formats: Sequence[str], chosen: Sequence[int] | None) -> list[Path]:
    dims = _case_dims(ds)
    first, others = dims[0], dims[1:]
    var = ds[name]
    scale, units = _display_units(var.attrs.get("units", ""), var.values)
    # NaN where a case failed; the line then has a gap rather than a false value.
    values = var.where(ds["status"] == STATUS_OK)
    picks = list(chosen) if chosen else _dominant_harmonics(
        var.transpose(..., "harmonic").values, ds["harmonic"].values)
    x = ds[first].values
    xattrs = dict(ds[first].attrs)
    combos = list(itertools.product(*(range(ds.sizes[d]) for d in others)))
    colors = _colors(len(combos))
    fig = Figure(figsize=(10, 3.2 * len(picks) + 1.2), layout="constrained")
    axes = fig.subplots(len(picks), ds.sizes["direction"], squeeze=False, sharex=True)
    for row, k in enumerate(picks):
        for col, direction in enumerate(ds["direction"].values):
            ax = axes[row, col]
            for combo, color in zip(combos, colors, strict=True):
                sel = dict(zip(others, combo, strict=True))
                y = values.isel(sel).sel(direction=direction, harmonic=k).transpose(first).values
                label = ", ".join(f"{d}={_format(ds[d].values[i])}" for d, i in sel.items())
                if label and not np.isfinite(y).any():
                    label += " (failed)"
                ax.plot(x, y * scale, marker="o", color=color, label=label or None)
            ax.set_title(f"{k}P, {direction}", fontsize="medium")
            ax.set_ylabel(f"amplitude ({units})")
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(_axis_label(xattrs, first))
    fig.suptitle(f"{title} against {first}")
    _legend(fig, axes[0, 0])
    return _save(fig, out_dir, f"harmonics_{name}_vs_{first}", formats)


def _pin_angles(ds: xr.Dataset, cases: list[tuple[str, dict[str, int], bool]],
                out_dir: Path, formats: Sequence[str]) -> list[Path]:
    free = [c for c in cases if c[2] and _is_free(ds, c[1])]
    psi = ds["psi"].values
    units = ds["pin_angle"].attrs.get("units", "degree")
    paths: list[Path] = []
    pages = _pages(free)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(8, 1.0 + 2.2 * len(chunk)), layout="constrained")
        axes = fig.subplots(len(chunk), 1, sharex=True, squeeze=False)[:, 0]
        for ax, (label, sel, _ok) in zip(axes, chunk, strict=True):
            pins = ds["pin_angle"].isel(sel)
            for pin, style in ((0, "-"), (2, "-.")):
                ax.plot(psi, pins.sel(bifilar_index=pin).values, style, color="black",
                        label=f"bifilar {pin}")
            ax.set_title(label, fontsize="medium")
            ax.set_ylabel(f"pin angle ({units})")
            _psi_axis(ax)
            ax.legend(fontsize="small", loc="upper right")
        axes[-1].set_xlabel("rotor azimuth psi (degree)")
        fig.suptitle("Pin angles of opposite bifilars 0 and 2 over one revolution")
        paths += _save(fig, out_dir, _page_stem("pin_angles", page, len(pages)), formats)
    return paths


def _orbits(ds: xr.Dataset, cases: list[tuple[str, dict[str, int], bool]],
            out_dir: Path, formats: Sequence[str]) -> list[Path]:
    panels = [(p, t) for p, t in (("hub", "hub centre"), ("bifilar_cm", "bifilar centre of mass"))
              if f"{p}_x_fixed" in ds and f"{p}_y_fixed" in ds]
    ok = [c for c in cases if c[2]]
    scale, units = _display_units("m", np.concatenate(
        [ds[f"{p}_{a}_fixed"].values.ravel() for p, _ in panels for a in "xy"]))
    paths: list[Path] = []
    pages = _pages(ok)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(5.2 * len(panels), 5.8), layout="constrained")
        axes = fig.subplots(1, len(panels), squeeze=False)[0]
        colors = _colors(len(chunk))
        for ax, (prefix, what) in zip(axes, panels, strict=True):
            for (label, sel, _ok), color in zip(chunk, colors, strict=True):
                x = ds[f"{prefix}_x_fixed"].isel(sel).values * scale
                y = ds[f"{prefix}_y_fixed"].isel(sel).values * scale
                # Close the periodic orbit: the last revolution ends where it began.
                ax.plot(np.append(x, x[0]), np.append(y, y[0]), color=color, label=label)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(what, fontsize="medium")
            ax.set_xlabel(f"x, fixed frame ({units})")
            ax.set_ylabel(f"y, fixed frame ({units})")
            ax.grid(True, alpha=0.3)
        _legend(fig, axes[0])
        fig.suptitle("In-plane orbits over one revolution")
        paths += _save(fig, out_dir, _page_stem("orbits", page, len(pages)), formats)
    return paths


def _force_history(ds: xr.Dataset, cases: list[tuple[str, dict[str, int], bool]],
                   out_dir: Path, formats: Sequence[str]) -> list[Path]:
    ok = [c for c in cases if c[2]]
    psi = ds["psi"].values
    scale, units = _display_units("N", np.concatenate(
        [ds[f"hub_force_{a}_fixed"].values.ravel() for a in "xy"]))
    paths: list[Path] = []
    pages = _pages(ok)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(9, 6.5), layout="constrained")
        axes = fig.subplots(2, 1, sharex=True)
        colors = _colors(len(chunk))
        for ax, axis in zip(axes, "xy", strict=True):
            for (label, sel, _ok), color in zip(chunk, colors, strict=True):
                ax.plot(psi, ds[f"hub_force_{axis}_fixed"].isel(sel).values * scale,
                        color=color, label=label)
            ax.set_ylabel(f"force {axis}, fixed frame ({units})")
            _psi_axis(ax)
        axes[-1].set_xlabel("rotor azimuth psi (degree)")
        _legend(fig, axes[0])
        fig.suptitle("In-plane hub force transmitted to the fuselage over one revolution")
        paths += _save(fig, out_dir, _page_stem("hub_force_history", page, len(pages)), formats)
    return paths


def plot_archive(
    archive_path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    harmonics: Sequence[int] | None = None,
    formats: Sequence[str] = FORMATS,
) -> list[Path]:
    """Write the report figures of an archive as PNG and PDF.

    Parameters
    ----------
    archive_path
        Consolidated archive written by :func:`pipelines.sweep.run_sweep`.
    out_dir
        Directory for the figures (created if needed).
    harmonics
        Harmonic numbers drawn against the first swept parameter when a Cartesian sweep is too
        large for bar charts; default: the two largest non-zero harmonics of each quantity.

    Returns
    -------
    list of pathlib.Path
        The files written (each figure in each format). Figures whose data are absent
        (e.g. no free bifilar, or every case failed) are skipped.

    Raises
    ------
    FileNotFoundError
        If the archive does not exist.
    pipelines.archive.ArchiveError
        If it cannot be read.
    """
    ds = open_archive(archive_path)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cases = _cases(ds)
    if not any(ok for *_, ok in cases):
        return []
    lines = _case_dims(ds) != ("case",) and len(cases) > MAX_BAR_CASES
    paths: list[Path] = []
    for name, title in HARMONIC_FIGURES.items():
        if name not in ds:
            continue
        if lines:
            paths += _harmonic_lines(ds, name, title, out, formats, harmonics)
        else:
            paths += _harmonic_bars(ds, name, title, out, formats)
    if "pin_angle" in ds:
        paths += _pin_angles(ds, cases, out, formats)
    if "hub_x_fixed" in ds and "hub_y_fixed" in ds:
        paths += _orbits(ds, cases, out, formats)
    if "hub_force_x_fixed" in ds and "hub_force_y_fixed" in ds:
        paths += _force_history(ds, cases, out, formats)
    return paths
