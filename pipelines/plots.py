"""Report figures of a consolidated archive (the paper's Figs. 14–19), as PNG and PDF.

Figures are built on :class:`matplotlib.figure.Figure` directly, rendered by the Agg (PNG) and
PDF backends at ``savefig``: no pyplot state, so importing this module never changes the
interactive backend of a notebook, and a figure is freed as soon as it goes out of scope (the
memory ``plt.close(fig)`` would release is never registered with pyplot in the first place).

Which figures are drawn is generated from the model's output declarations
(:class:`studies.parameters.Output`; the archive's ``model`` attribute names the model). Figures
written by :func:`plot_archive` for a per-rev periodic model (the hub):

``compare_case<i>_vs_case<j>``
    For a case list, the paired comparisons (:func:`comparison_pairs`: the reference case 1
    against each other case, Table 1's 0 vs 1, 1 vs 2, 1 vs 3): one panel per in-plane vector,
    the two cases' bars side by side.
``harmonics_<vector>``
    Grouped bars of the harmonics that matter for the vector's frame (:func:`frame_harmonics`:
    3P and 5P rotating, 4P and 8P fixed; x and y as groups), one bar per case, for every
    declared in-plane vector (the hub displacement in the rotating frame, Fig. 17; the hub
    in-plane force in the fixed frame, Figs. 18–19; …); a line of text gives the largest of the
    other harmonics. A Cartesian sweep with a numeric dimension (or of more than
    :data:`MAX_BAR_CASES` cases) gets response curves instead:
    ``harmonics_<vector>_vs_<parameter>``, those harmonics' amplitudes against the first numeric
    swept parameter, one line per value of the others.
``<figure>`` of the declarations, over one revolution
    Vectors as smooth orbits (``orbits``: hub and bifilar centre of mass, Fig. 15; Fourier
    interpolation of the archived revolution); a history with an
    extra dimension as one panel per case (``pin_angles``, Fig. 14; cases where it is zero
    throughout, e.g. locked bifilars, are left out); other histories as one panel each with one
    line per case (``hub_force_history``, Fig. 16).

For any other model (collar, pendulum): ``results`` (or ``results_vs_<parameter>`` for a
sweep), the declared scalar results against the cases, and the declared histories against time
(``<figure>``).

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

from pipelines.archive import STATUS_OK, ArchiveError, _upsample, open_archive, status_counts
from studies.parameters import ModelSpec, Output

Cases = list[tuple[str, dict[str, int], bool]]

# More bars than this per harmonic group are unreadable: a sweep switches to line plots.
MAX_BAR_CASES = 8
# Harmonics drawn for a four-bladed rotor: either side of 4P in the rotating frame, 4P and its
# double in the fixed frame (the others are summarized in a line of text).
ROTATING_HARMONICS = (3, 5)
FIXED_HARMONICS = (4, 8)
# Points of a drawn orbit (Fourier interpolation of the archived revolution: smooth, exact for
# the band-limited periodic signal).
ORBIT_POINTS = 720
# Cases per time-history figure (one panel each for pin angles, one line each otherwise).
CASES_PER_PAGE = 8
FORMATS = ("png", "pdf")
DPI = 150

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


def _swings(values: np.ndarray) -> bool:
    """Whether a case's history is worth a panel: finite and not zero throughout (a locked
    bifilar does not swing)."""
    return bool(np.isfinite(values).all() and np.abs(values).max() > 0)


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


def frame_harmonics(name: str) -> tuple[int, ...]:
    """The harmonics that matter for a quantity of a four-bladed rotor: 3P and 5P in the
    rotating frame (either side of 4P), 4P and 8P in the fixed frame."""
    return ROTATING_HARMONICS if "rotating" in name or name.startswith("pin_angle") else (
        FIXED_HARMONICS)


def _rest_summary(var: xr.DataArray, shown: Sequence[int], scale: float, units: str) -> str:
    """One line on the harmonics left out of a chart: the largest of them, against the shown."""
    harmonic = list(var["harmonic"].values)
    rest = [h for h in harmonic if h not in shown]
    if not rest:
        return ""
    values = np.abs(var.transpose(..., "harmonic").values)
    finite = np.where(np.isfinite(values), values, 0.0).reshape(-1, len(harmonic))
    peak_shown = max(finite[:, harmonic.index(h)].max() for h in shown)
    peaks = {h: finite[:, harmonic.index(h)].max() for h in rest}
    worst = max(peaks, key=lambda h: peaks[h])
    share = peaks[worst] / peak_shown if peak_shown > 0 else np.inf
    return (f"not shown: harmonics {', '.join(map(str, rest))}; largest {worst}P "
            f"{peaks[worst] * scale:.3g} {units}"
            + (f" ({100 * share:.2g} % of the largest shown)" if np.isfinite(share) else ""))


def _bar_panel(ax: Any, ds: xr.Dataset, name: str, cases: Cases, shown: Sequence[int],
               scale: float, colors: Sequence[Any]) -> None:
    """Grouped bars: one group per (harmonic, direction), one bar per case."""
    var = ds[name]
    groups = [(h, d) for h in shown for d in ds["direction"].values]
    width = 0.8 / len(cases)
    x = np.arange(len(groups))
    for i, (label, sel, _ok) in enumerate(cases):
        amp = [float(var.isel(sel).sel(direction=d, harmonic=h)) * scale for h, d in groups]
        ax.bar(x - 0.4 + (i + 0.5) * width, amp, width, label=label, color=colors[i],
               edgecolor="black", linewidth=0.5)
    ax.set_xticks(x, [f"{h}P {d}" for h, d in groups])
    ax.grid(True, axis="y", alpha=0.3)
    ax.set_ylim(bottom=0)


def _harmonic_bars(ds: xr.Dataset, name: str, title: str, out_dir: Path,
                   formats: Sequence[str]) -> list[Path]:
    cases = _cases(ds)
    var = ds[name]
    scale, units = _display_units(var.attrs.get("units", ""), var.values)
    shown = [h for h in frame_harmonics(name) if h in ds["harmonic"].values]
    fig = Figure(figsize=(9, 5.5), layout="constrained")
    ax = fig.subplots()
    _bar_panel(ax, ds, name, cases, shown, scale, _colors(len(cases)))
    ax.set_ylabel(f"amplitude ({units})")
    ax.set_xlabel("harmonic (cycles per rotor revolution) and in-plane direction\n"
                  + _rest_summary(var, shown, scale, units), fontsize="small")
    fig.suptitle(title)
    _legend(fig, ax)
    return _save(fig, out_dir, f"harmonics_{name}", formats)


def comparison_pairs(ds: xr.Dataset) -> list[tuple[int, int]]:
    """The paired comparisons of a case list: the reference case (the second, e.g. Table 1's
    case 1, free and tuned) against every other case: (0, 1), (1, 2), (1, 3), ..."""
    if _case_dims(ds) != ("case",) or ds.sizes["case"] < 2:
        return []
    return [(min(i, 1), max(i, 1)) for i in range(ds.sizes["case"]) if i != 1]


def _comparison(ds: xr.Dataset, spec: ModelSpec, pair: tuple[int, int], out_dir: Path,
                formats: Sequence[str]) -> list[Path]:
    """One figure per pair: the frame harmonics of every vector, the two cases side by side."""
    cases = _cases(ds)
    chosen = [cases[i] for i in pair]
    names = [n for n, d in spec.outputs.items() if d.is_vector and n in ds]
    if not names or not all(ok for *_, ok in chosen):
        return []
    cols = 2 if len(names) > 1 else 1
    rows = -(-len(names) // cols)
    fig = Figure(figsize=(5.6 * cols, 1.6 + 3.3 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    colors = _colors(2)
    for ax, name in zip(axes, names, strict=False):
        var = ds[name]
        scale, units = _display_units(var.attrs.get("units", ""), var.values)
        shown = [h for h in frame_harmonics(name) if h in ds["harmonic"].values]
        _bar_panel(ax, ds, name, chosen, shown, scale, colors)
        ax.set_ylabel(f"amplitude ({units})")
        ax.set_title(spec.outputs[name].long_name, fontsize="medium", wrap=True)
        sub = var.isel(case=list(pair))
        ax.set_xlabel(_rest_summary(sub, shown, scale, units).replace("; ", "\n", 1),
                      fontsize="x-small", color="0.3")
    for ax in axes[len(names):]:
        ax.set_visible(False)
    fig.suptitle(f"Case {chosen[0][0]} against case {chosen[1][0]}")
    _legend(fig, axes[0])
    return _save(fig, out_dir, f"compare_case{pair[0]}_vs_case{pair[1]}", formats)


def _response_dim(ds: xr.Dataset) -> str | None:
    """The first numeric swept dimension of a Cartesian sweep (drawn as response curves)."""
    dims = _case_dims(ds)
    if dims == ("case",):
        return None
    for dim in dims:
        if np.issubdtype(ds[dim].dtype, np.number) and ds.sizes[dim] > 1:
            return dim
    return None


def _dominant_harmonics(values: np.ndarray, harmonic: np.ndarray, count: int = 2) -> list[int]:
    """The ``count`` non-zero harmonics with the largest amplitude over all cases."""
    flat = np.abs(values).reshape(-1, values.shape[-1])
    peak = np.where(np.isfinite(flat), flat, 0.0).max(axis=0)
    order = [int(harmonic[i]) for i in np.argsort(-peak) if harmonic[i] != 0]
    return sorted(order[:count])


def _harmonic_lines(ds: xr.Dataset, name: str, title: str, out_dir: Path,
                    formats: Sequence[str], chosen: Sequence[int] | None) -> list[Path]:
    dims = _case_dims(ds)
    first = _response_dim(ds) or dims[0]
    others = tuple(d for d in dims if d != first)
    var = ds[name]
    scale, units = _display_units(var.attrs.get("units", ""), var.values)
    # NaN where a case failed; the line then has a gap rather than a false value.
    values = var.where(ds["status"] == STATUS_OK)
    picks = list(chosen) if chosen else [h for h in frame_harmonics(name)
                                         if h in ds["harmonic"].values]
    x = ds[first].values
    xattrs = dict(ds[first].attrs)
    combos = list(itertools.product(*(range(ds.sizes[d]) for d in others)))
    colors = _colors(len(combos))
    # x and y of one harmonic share a panel (solid and dashed): for a circular whirl they
    # coincide, and two identical panels would say nothing more
    fig = Figure(figsize=(6 * len(picks), 5.2), layout="constrained")
    axes = fig.subplots(1, len(picks), squeeze=False)[0]
    styles = ("-", "--", ":", "-.")
    for ax, k in zip(axes, picks, strict=True):
        for d, direction in enumerate(ds["direction"].values):
            for combo, color in zip(combos, colors, strict=True):
                sel = dict(zip(others, combo, strict=True))
                y = values.isel(sel).sel(direction=direction, harmonic=k).transpose(first).values
                label = ", ".join([f"{dd}={_format(ds[dd].values[i])}" for dd, i in sel.items()]
                                  + [str(direction)])
                if not np.isfinite(y).any():
                    label += " (failed)"
                ax.plot(x, y * scale, styles[d % len(styles)], marker="o" if d == 0 else "s",
                        mfc="none" if d else color, color=color, label=label)
        ax.set_title(f"{k}P", fontsize="medium")
        ax.set_ylabel(f"amplitude ({units})")
        ax.set_xlabel(_axis_label(xattrs, first))
        ax.grid(True, alpha=0.3)
        ax.set_ylim(bottom=0)
    fig.suptitle(f"{title} against {first}")
    _legend(fig, axes[0])
    return _save(fig, out_dir, f"harmonics_{name}_vs_{first}", formats)


def _time_axis(ds: xr.Dataset, sel: dict[str, int]) -> tuple[np.ndarray, str]:
    """Abscissa of a case's archived history: azimuth (periodic) or its time (s)."""
    if "psi" in ds.coords:
        return ds["psi"].values, "rotor azimuth psi (degree)"
    return ds["time"].isel(sel).values, "time (s)"


def _finish_axis(ax: Any, ds: xr.Dataset) -> None:
    if "psi" in ds.coords:
        _psi_axis(ax)
    else:
        ax.grid(True, alpha=0.3)


def _over(ds: xr.Dataset) -> str:
    return "over one revolution" if "psi" in ds.coords else "against time"


def _indexed_history(ds: xr.Dataset, name: str, stem: str, cases: Cases, out_dir: Path,
                     formats: Sequence[str]) -> list[Path]:
    """A history with an extra dimension (e.g. one per bifilar): one panel per case."""
    var = ds[name]
    inner = [d for d in var.dims if d not in _case_dims(ds) and d not in ("time_in_rev",
                                                                          "sample")]
    index = inner[0]
    shown = [c for c in cases if c[2] and _swings(var.isel(c[1]).values)]
    units = var.attrs.get("units", "")
    styles = ("-", "-.", "--", ":")
    paths: list[Path] = []
    pages = _pages(shown)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(8, 1.0 + 2.2 * len(chunk)), layout="constrained")
        axes = fig.subplots(len(chunk), 1, sharex=True, squeeze=False)[:, 0]
        for ax, (label, sel, _ok) in zip(axes, chunk, strict=True):
            x, xlabel = _time_axis(ds, sel)
            values = var.isel(sel)
            for k, item in enumerate(ds[index].values):
                ax.plot(x, values.sel({index: item}).values, styles[k % len(styles)],
                        color=_colors(ds.sizes[index])[k], label=f"{index} {_format(item)}")
            ax.set_title(label, fontsize="medium")
            ax.set_ylabel(units or name)
            _finish_axis(ax, ds)
        axes[-1].set_xlabel(xlabel)
        _legend(fig, axes[0])
        fig.suptitle(f"{var.attrs.get('long_name', name)} {_over(ds)}")
        paths += _save(fig, out_dir, _page_stem(stem, page, len(pages)), formats)
    return paths


def _orbits(ds: xr.Dataset, vectors: dict[str, Output], stem: str, cases: Cases,
            out_dir: Path, formats: Sequence[str]) -> list[Path]:
    """In-plane vectors as orbits: one panel per vector, one line per case."""
    ok = [c for c in cases if c[2]]
    by_units: dict[str, tuple[float, str]] = {}
    for units in {v.units for v in vectors.values()}:
        by_units[units] = _display_units(units, np.concatenate(
            [ds[c].values.ravel() for v in vectors.values() if v.units == units
             for c in v.components or ()]))
    paths: list[Path] = []
    pages = _pages(ok)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(5.2 * len(vectors), 5.8), layout="constrained")
        axes = fig.subplots(1, len(vectors), squeeze=False)[0]
        colors = _colors(len(chunk))
        for ax, vector in zip(axes, vectors.values(), strict=True):
            cx, cy = vector.components or ("", "")
            scale, units = by_units[vector.units]
            for (label, sel, _ok), color in zip(chunk, colors, strict=True):
                x = ds[cx].isel(sel).values * scale
                y = ds[cy].isel(sel).values * scale
                if "psi" in ds.coords and np.isfinite(x).all() and np.isfinite(y).all():
                    # Smooth and closed: Fourier interpolation of the periodic revolution.
                    x = _upsample(x, max(ORBIT_POINTS, x.size))
                    y = _upsample(y, max(ORBIT_POINTS, y.size))
                    x, y = np.append(x, x[0]), np.append(y, y[0])
                ax.plot(x, y, color=color, label=label)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(vector.long_name, fontsize="medium", wrap=True)
            ax.set_xlabel(f"x ({units})")
            ax.set_ylabel(f"y ({units})")
            ax.grid(True, alpha=0.3)
        _legend(fig, axes[0])
        fig.suptitle(f"In-plane orbits {_over(ds)}")
        paths += _save(fig, out_dir, _page_stem(stem, page, len(pages)), formats)
    return paths


def _histories(ds: xr.Dataset, names: list[str], stem: str, cases: Cases, out_dir: Path,
               formats: Sequence[str]) -> list[Path]:
    """Histories without an extra dimension: one panel per history, one line per case."""
    ok = [c for c in cases if c[2]]
    paths: list[Path] = []
    pages = _pages(ok)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(9, 1.5 + 2.5 * len(names)), layout="constrained")
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
        colors = _colors(len(chunk))
        for ax, name in zip(axes, names, strict=True):
            var = ds[name]
            scale, units = _display_units(var.attrs.get("units", ""), var.values)
            for (label, sel, _ok), color in zip(chunk, colors, strict=True):
                x, xlabel = _time_axis(ds, sel)
                ax.plot(x, var.isel(sel).values * scale, color=color, label=label)
            ax.set_ylabel(_axis_label({**var.attrs, "units": units}, name), wrap=True)
            _finish_axis(ax, ds)
        axes[-1].set_xlabel(xlabel)
        _legend(fig, axes[0])
        long_names = [ds[n].attrs.get("long_name", n) for n in names]
        fig.suptitle(f"{long_names[0] if len(names) == 1 else stem.replace('_', ' ')} "
                     f"{_over(ds)}")
        paths += _save(fig, out_dir, _page_stem(stem, page, len(pages)), formats)
    return paths


def _results(ds: xr.Dataset, names: list[str], cases: Cases, out_dir: Path,
             formats: Sequence[str]) -> list[Path]:
    """Scalar results against the first case dimension, one line per value of the others."""
    dims = _case_dims(ds)
    first, others = dims[0], dims[1:]
    if first == "case":
        x = np.arange(ds.sizes["case"])
        ticks = [c[0] for c in cases]
    else:
        values = ds[first].values
        numeric = np.issubdtype(values.dtype, np.number)
        x = values if numeric else np.arange(values.size)
        ticks = None if numeric else [_format(v) for v in values]
    combos = list(itertools.product(*(range(ds.sizes[d]) for d in others)))
    colors = _colors(len(combos))
    fig = Figure(figsize=(8, 1.5 + 2.6 * len(names)), layout="constrained")
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    for ax, name in zip(axes, names, strict=True):
        var = ds[name].where(ds["status"] == STATUS_OK)
        for combo, color in zip(combos, colors, strict=True):
            sel = dict(zip(others, combo, strict=True))
            y = var.isel(sel).transpose(first).values
            label = ", ".join(f"{d}={_format(ds[d].values[i])}" for d, i in sel.items())
            ax.plot(x, y, marker="o", color=color, label=label or None)
        ax.set_ylabel(_axis_label(dict(ds[name].attrs), name), wrap=True)
        ax.grid(True, alpha=0.3)
    if ticks is not None:
        axes[-1].set_xticks(x, ticks, rotation=30 if first == "case" else 0, ha="right"
                            if first == "case" else "center")
    axes[-1].set_xlabel("case" if first == "case" else _axis_label(dict(ds[first].attrs),
                                                                   first))
    if others:
        _legend(fig, axes[0])
    fig.suptitle("Results" + ("" if first == "case" else f" against {first}"))
    stem = "results" if first == "case" else f"results_vs_{first}"
    return _save(fig, out_dir, stem, formats)


def archive_model(ds: xr.Dataset, path: str | os.PathLike[str] = "archive") -> ModelSpec:
    """The model of an archive (its ``model`` attribute), for its output declarations.

    Raises
    ------
    pipelines.archive.ArchiveError
        If the file is not a sweep archive or its model cannot be loaded.
    """
    from pipelines.sweep import StudyError, resolve_model

    if "status" not in ds or "model" not in ds.attrs:
        raise ArchiveError(f"{path} is not a sweep archive (no 'status' variable or 'model' "
                           "attribute); bifilar plot draws the archive.nc of bifilar sweep or "
                           "bifilar run")
    try:
        return resolve_model(str(ds.attrs["model"]))
    except StudyError as exc:
        raise ArchiveError(f"{path}: cannot load its model to plot it: {exc}") from exc


def _figures(spec: ModelSpec, ds: xr.Dataset) -> dict[str, list[str]]:
    """Declared figure stems -> the archived outputs drawn in them, in declaration order."""
    figures: dict[str, list[str]] = {}
    for name, out in spec.outputs.items():
        if out.figure is None:
            continue
        present = all(c in ds for c in out.components) if out.components else name in ds
        if present:
            figures.setdefault(out.figure, []).append(name)
    return figures


def plot_archive(
    archive_path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    harmonics: Sequence[int] | None = None,
    formats: Sequence[str] = FORMATS,
) -> list[Path]:
    """Write the report figures of an archive as PNG and PDF.

    Which figures are drawn follows the model's output declarations (see the module
    documentation).

    Parameters
    ----------
    archive_path
        Consolidated archive written by :func:`pipelines.sweep.run_sweep`.
    out_dir
        Directory for the figures (created if needed).
    harmonics
        Harmonic numbers drawn against the first swept parameter when a Cartesian sweep is too
        large for bar charts; default: the two largest non-zero harmonics of each quantity.
    formats
        File formats (matplotlib names: ``png``, ``pdf``, ``svg``).

    Returns
    -------
    list of pathlib.Path
        The files written (each figure in each format). Figures whose data are absent
        (e.g. no free bifilar) are skipped.

    Raises
    ------
    FileNotFoundError
        If the archive does not exist.
    pipelines.archive.ArchiveError
        If it cannot be read, is not a sweep archive, its model cannot be loaded, or no case
        finished ok (nothing to plot).
    """
    ds = open_archive(archive_path)
    spec = archive_model(ds, archive_path)
    cases = _cases(ds)
    if not any(ok for *_, ok in cases):
        counts = status_counts(ds)
        raise ArchiveError(
            f"no case of {archive_path} finished ok ({counts['failed']} failed, "
            f"{counts['not_run']} not run), nothing to plot; its 'message' variable says why"
        )
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    if spec.periodic:
        lines = _response_dim(ds) is not None or (
            _case_dims(ds) != ("case",) and len(cases) > MAX_BAR_CASES)
        for pair in comparison_pairs(ds):
            paths += _comparison(ds, spec, pair, out, formats)
        for name, decl in spec.outputs.items():
            if not decl.is_vector or name not in ds:
                continue
            title = f"Harmonics of the {decl.long_name}"
            if lines:
                paths += _harmonic_lines(ds, name, title, out, formats, harmonics)
            else:
                paths += _harmonic_bars(ds, name, title, out, formats)
    else:
        scalars = [n for n, o in spec.outputs.items() if o.is_scalar and n in ds]
        if scalars:
            paths += _results(ds, scalars, cases, out, formats)
    for stem, names in _figures(spec, ds).items():
        decls = {n: spec.outputs[n] for n in names}
        vectors = {n: d for n, d in decls.items() if d.is_vector}
        if vectors:
            paths += _orbits(ds, vectors, stem, cases, out, formats)
        indexed = [n for n, d in decls.items() if not d.is_vector and len(d.dims) > 1]
        for name in indexed:
            paths += _indexed_history(ds, name, stem, cases, out, formats)
        plain = [n for n, d in decls.items() if not d.is_vector and len(d.dims) == 1]
        if plain:
            paths += _histories(ds, plain, stem, cases, out, formats)
    return paths
