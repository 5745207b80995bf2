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
    other harmonics. A Cartesian sweep with a numeric dimension gets response curves instead:
    ``harmonics_<vector>_vs_<parameter>``, those harmonics' amplitudes against the first numeric
    swept parameter, one line per value of the others. Categories (a case list, a string
    parameter such as ``hole``) are always bars. A harmonic whose amplitude stays below
    :data:`NOISE_LEVEL` of the figure's largest is roundoff: its bars or panel are left out.
``<figure>`` of the declarations, over one revolution
    Vectors as smooth orbits about their mean (``orbits``: hub and bifilar centre of mass,
    Fig. 15; the mean, the static deflection, is given in the legend); a history with an extra
    dimension as one panel per case (``pin_angles``, Fig. 14: pins A and B, the bifilars 180°
    apart; cases where it is zero throughout, e.g. locked bifilars, are left out); other
    histories as one panel each with one line per case (``hub_force_history``, Fig. 16).
    Periodic histories are drawn smooth (Fourier interpolation of the archived revolution).

A rotor archive that sweeps airspeed with trim, or rotor speed, also gets the flight-envelope
figures of :mod:`pipelines.envelope_plots` (4P hub loads, trimmed controls and power, pin
amplitude against airspeed; 4P reduction against rotor speed).

For any other model (collar, pendulum): ``results`` (or ``results_vs_<parameter>`` for a
sweep), the declared scalar results against the first numeric swept parameter, or as grouped
bars over categories, and the declared histories against time (``<figure>``).

For a branch archive (a study with a ``[continuation]`` table: a ``point`` dimension), response
curves against the continued parameter instead, one curve per case (branch) in its colour,
stable parts solid, unstable parts dashed and folds marked ``x``:

``harmonics_<output>_vs_<parameter>``
    For every harmonic output (a history or an in-plane vector), the amplitude of its dominant
    harmonics (:func:`_dominant_harmonics`, or those asked for), one panel per harmonic (and
    per direction or other index of the output).
``results_vs_<parameter>``
    The declared scalar results that vary along a branch, one panel each.
``floquet_multiplier_max_vs_<parameter>``
    The largest Floquet multiplier modulus, with the unit circle's level 1.

Each case has one colour, line style and marker in every figure (by its position in the
archive), so that coinciding curves stay distinguishable and a case is recognised across
figures.

Time-history figures hold at most :data:`CASES_PER_PAGE` cases; more go on further pages
(``pin_angles_p2`` …).
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from pipelines.archive import (
    POINT,
    STATUS_OK,
    ArchiveError,
    _upsample,
    open_archive,
    status_counts,
)
from studies.harmonics import SUFFIXES, harmonic_names
from studies.parameters import ModelSpec, Output


class Case(NamedTuple):
    """One case of an archive as drawn: legend label, ``isel`` indexers, whether it finished
    ok, and its style (``color``, ``linestyle``, ``marker``), the same in every figure."""

    label: str
    sel: dict[str, int]
    ok: bool
    style: dict[str, Any]


Cases = list[Case]

# Harmonics drawn for a four-bladed rotor: either side of 4P in the rotating frame, 4P and its
# double in the fixed frame (the others are summarized in a line of text).
ROTATING_HARMONICS = (3, 5)
FIXED_HARMONICS = (4, 8)
# Points of a drawn orbit (Fourier interpolation of the archived revolution: smooth, exact for
# the band-limited periodic signal).
ORBIT_POINTS = 720
# Cases per time-history figure (one panel each for pin angles, one line each otherwise).
CASES_PER_PAGE = 8
# A branch archive's backbone (studies.backbones): free-vibration order per swing amplitude.
BACKBONE = "backbone_order"
# A harmonic whose amplitude stays below this share of the figure's largest is numerical noise
# (roundoff of the Fourier analysis, about 1e-14 relative): its panel or bar group is left out.
NOISE_LEVEL = 1e-6
# Line styles and markers cycled with the colours, so that cases whose curves coincide (a
# detuned case over the tuned one) stay distinguishable; markers spaced by this share of the
# axes' diagonal along each curve.
LINE_STYLES = ("-", "--", "-.", ":")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
MARKER_SPACING = 0.12
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


def _styles(n: int) -> list[dict[str, Any]]:
    """A colour, line style and marker for each of ``n`` curves, all distinct pairs."""
    colors = _colors(n)
    return [{"color": colors[i], "linestyle": LINE_STYLES[i % len(LINE_STYLES)],
             "marker": MARKERS[i % len(MARKERS)]} for i in range(n)]


def _markevery(i: int, n: int) -> tuple[float, float]:
    """Markers every :data:`MARKER_SPACING` of the axes' diagonal along the drawn path (evenly
    spread whatever the sampling, also on an orbit that loops four times a revolution),
    shifted for curve ``i`` of ``n`` so that coinciding curves show each other's markers."""
    return MARKER_SPACING * i / max(n, 1), MARKER_SPACING


def _line(ax: Any, x: np.ndarray, y: np.ndarray, style: dict[str, Any], index: int, count: int,
          **kwargs: Any) -> None:
    """A curve in a case's (or a group's) style, markers spread along it."""
    ax.plot(x, y, **style, markevery=_markevery(index, count), markersize=4,
            mfc="none", **kwargs)


def _cases(ds: xr.Dataset) -> Cases:
    """Every case of the archive, each with its fixed style (by its position in the archive,
    so a case looks the same in every figure whichever cases a figure draws)."""
    dims = _case_dims(ds)
    styles = _styles(int(np.prod(ds["status"].shape)))
    out = []
    for number, index in enumerate(np.ndindex(*ds["status"].shape)):
        sel = dict(zip(dims, index, strict=True))
        if dims == ("case",):
            label = str(ds["case_name"].values[index[0]]) if "case_name" in ds else str(index[0])
        else:
            label = ", ".join(f"{d}={_format(ds[d].values[i])}" for d, i in sel.items())
        ok = int(ds["status"].values[index]) == STATUS_OK
        out.append(Case(label if ok else f"{label} (failed)", sel, ok, styles[number]))
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
    return f"{name} ({_units_label(units)})"


def _units_label(units: str) -> str:
    """Units as an axis shows them: a ratio (units "1" or none) reads "dimensionless"."""
    return "dimensionless" if units in ("", "1") else units


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


def _significant(var: xr.DataArray, harmonics: Sequence[int]) -> list[int]:
    """Those of ``harmonics`` whose largest amplitude (over every case and direction) reaches
    :data:`NOISE_LEVEL` of the largest among them: the others are roundoff, not response."""
    if not harmonics:
        return []
    values = np.abs(var.sel(harmonic=list(harmonics)).transpose(..., "harmonic").values)
    peak = np.where(np.isfinite(values), values, 0.0).reshape(-1, len(harmonics)).max(axis=0)
    return [h for h, p in zip(harmonics, peak, strict=True) if p >= NOISE_LEVEL * peak.max()]


def _frame_harmonics(ds: xr.Dataset, var: xr.DataArray, name: str) -> list[int]:
    """The frame's harmonics (:func:`frame_harmonics`) archived and above noise level."""
    return _significant(var, [h for h in frame_harmonics(name) if h in ds["harmonic"].values])


def _bar_panel(ax: Any, ds: xr.Dataset, name: str, cases: Cases, shown: Sequence[int],
               scale: float) -> None:
    """Grouped bars: one group per (harmonic, direction), one bar per case in its colour."""
    var = ds[name]
    # (a direction the vector lacks, e.g. z beside a station's x, y, z, is NaN throughout)
    groups = [(h, d) for h in shown for d in _directions(var)]
    width = 0.8 / len(cases)
    x = np.arange(len(groups))
    for i, case in enumerate(cases):
        amp = [float(var.isel(case.sel).sel(direction=d, harmonic=h)) * scale for h, d in groups]
        ax.bar(x - 0.4 + (i + 0.5) * width, amp, width, label=case.label,
               color=case.style["color"], edgecolor="black", linewidth=0.5)
    ax.set_xticks(x, [f"{h}P {d}" for h, d in groups])
    ax.grid(True, axis="y", alpha=0.3)
    ax.set_ylim(bottom=0)


def _directions(var: xr.DataArray) -> list[str]:
    """The directions along which ``var`` has a value somewhere."""
    other = [d for d in var.dims if d != "direction"]
    held = np.isfinite(var.values).any(axis=tuple(var.dims.index(d) for d in other))
    return [str(d) for d, ok in zip(var["direction"].values, held, strict=True) if ok]


def _bar_width(bars: int) -> float:
    """Figure width (inches) that keeps ``bars`` bars readable."""
    return max(9.0, 1.5 + 0.2 * bars)


def _harmonic_bars(ds: xr.Dataset, name: str, title: str, out_dir: Path,
                   formats: Sequence[str]) -> list[Path]:
    cases = _cases(ds)
    var = ds[name]
    scale, units = _display_units(var.attrs.get("units", ""), var.values)
    shown = _frame_harmonics(ds, var, name)
    fig = Figure(figsize=(_bar_width(len(cases) * len(shown) * len(_directions(var))), 5.5),
                 layout="constrained")
    ax = fig.subplots()
    _bar_panel(ax, ds, name, cases, shown, scale)
    ax.set_ylabel(f"amplitude ({units})")
    ax.set_xlabel("harmonic (cycles per rotor revolution) and in-plane direction\n"
                  + _rest_summary(var, shown, scale, units), fontsize="small")
    fig.suptitle(title, wrap=True)
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
    if not names or not all(case.ok for case in chosen):
        return []
    cols = 2 if len(names) > 1 else 1
    rows = -(-len(names) // cols)
    fig = Figure(figsize=(5.6 * cols, 1.6 + 3.3 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax, name in zip(axes, names, strict=False):
        var = ds[name]
        scale, units = _display_units(var.attrs.get("units", ""), var.values)
        sub = var.isel(case=list(pair))
        shown = _frame_harmonics(ds, sub, name)
        _bar_panel(ax, ds, name, chosen, shown, scale)
        ax.set_ylabel(f"amplitude ({units})")
        ax.set_title(spec.outputs[name].long_name, fontsize="medium", wrap=True)
        ax.set_xlabel(_rest_summary(sub, shown, scale, units).replace("; ", "\n", 1),
                      fontsize="x-small", color="0.3")
    for ax in axes[len(names):]:
        ax.set_visible(False)
    fig.suptitle(f"Case {chosen[0].label} against case {chosen[1].label}", wrap=True)
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
    picks = _significant(values, [h for h in chosen if h in ds["harmonic"].values]) if chosen \
        else _frame_harmonics(ds, values, name)
    if not picks:
        return []
    x = ds[first].values
    xattrs = dict(ds[first].attrs)
    combos = list(itertools.product(*(range(ds.sizes[d]) for d in others)))
    colors = _colors(len(combos))
    # x and y of one harmonic share a panel (solid and dashed): for a circular whirl they
    # coincide, and two identical panels would say nothing more
    fig = Figure(figsize=(max(8.0, 6 * len(picks)), 5.2), layout="constrained")
    axes = fig.subplots(1, len(picks), squeeze=False)[0]
    styles = ("-", "--", ":", "-.")
    for ax, k in zip(axes, picks, strict=True):
        for d, direction in enumerate(_directions(var)):
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
    fig.suptitle(f"{title} against {first}", wrap=True)
    _legend(fig, axes[0])
    return _save(fig, out_dir, f"harmonics_{name}_vs_{first}", formats)


def _time_axis(ds: xr.Dataset, sel: dict[str, int]) -> tuple[np.ndarray, str]:
    """Abscissa of a case's archived history: azimuth (periodic) or its time (s)."""
    if "psi" in ds.coords:
        return ds["psi"].values, "rotor azimuth psi (degree)"
    return ds["time"].isel(sel).values, "time (s)"


def _revolution(ds: xr.Dataset, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A history drawn: over one revolution (periodic, on the archive's uniform azimuth grid)
    smooth and closed, by Fourier interpolation (exact for the band-limited periodic signal)
    with the first sample repeated at 360°; against time, as archived."""
    if "psi" not in ds.coords or not np.isfinite(y).all():
        return x, y
    points = max(ORBIT_POINTS, y.size)
    fine = _upsample(y, points)
    psi = x[0] + 360.0 * np.arange(points + 1) / points
    return psi, np.append(fine, fine[0])


def _finish_axis(ax: Any, ds: xr.Dataset) -> None:
    if "psi" in ds.coords:
        _psi_axis(ax)
    else:
        ax.grid(True, alpha=0.3)


def _over(ds: xr.Dataset) -> str:
    return "over one revolution" if "psi" in ds.coords else "against time"


def _pin_pair(ds: xr.Dataset, index: str) -> list[tuple[int, str, str]]:
    """The entries of an indexed history drawn, as ``(position, label, line style)``.

    For the bifilars (an even number, evenly spaced), the paper's Fig. 14: pin A, the first
    bifilar, solid, and pin B, the bifilar 180° from it, dash-dotted; their angles are in
    antiphase for a response at 3P. Otherwise every entry, one line style each.
    """
    n = ds.sizes[index]
    if index.startswith("bifilar") and n >= 2 and n % 2 == 0:
        values = ds[index].values
        return [(0, f"pin A (bifilar {_format(values[0])})", "-"),
                (n // 2, f"pin B (bifilar {_format(values[n // 2])}, 180° from A)", "-.")]
    return [(k, f"{index} {_format(v)}", LINE_STYLES[k % len(LINE_STYLES)])
            for k, v in enumerate(ds[index].values)]


def _indexed_history(ds: xr.Dataset, name: str, stem: str, cases: Cases, out_dir: Path,
                     formats: Sequence[str]) -> list[Path]:
    """A history with an extra dimension (e.g. one per bifilar): one panel per case, in the
    case's colour, one line style per entry drawn (:func:`_pin_pair`)."""
    var = ds[name]
    inner = [d for d in var.dims if d not in _case_dims(ds) and d not in ("time_in_rev",
                                                                          "sample")]
    index = inner[0]
    entries = _pin_pair(ds, index)
    shown = [c for c in cases if c.ok and _swings(var.isel(c.sel).values)]
    units = var.attrs.get("units", "")
    paths: list[Path] = []
    pages = _pages(shown)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(8, 1.0 + 2.2 * len(chunk)), layout="constrained")
        axes = fig.subplots(len(chunk), 1, sharex=True, squeeze=False)[:, 0]
        for ax, case in zip(axes, chunk, strict=True):
            x, xlabel = _time_axis(ds, case.sel)
            values = var.isel(case.sel)
            for k, label, linestyle in entries:
                ax.plot(*_revolution(ds, x, values.isel({index: k}).values),
                        linestyle=linestyle, color=case.style["color"], label=label)
            ax.set_title(case.label, fontsize="medium")
            ax.set_ylabel(units or name)
            _finish_axis(ax, ds)
        axes[-1].set_xlabel(xlabel)
        # one legend for every panel: the entries by line style (the colour is the case's)
        handles = [Line2D([], [], color="0.25", linestyle=ls) for _k, _l, ls in entries]
        fig.legend(handles, [lab for _k, lab, _ls in entries], loc="outside lower center",
                   ncols=len(entries), fontsize="small")
        fig.suptitle(f"{var.attrs.get('long_name', name)} {_over(ds)}", wrap=True)
        paths += _save(fig, out_dir, _page_stem(stem, page, len(pages)), formats)
    return paths


def _round_to(value: float, quantum: float) -> float:
    """``value`` rounded to a multiple of ``quantum`` (unchanged if ``quantum`` is 0); 0, not
    -0."""
    if not quantum > 0 or not np.isfinite(value):
        return value
    return float(np.round(value / quantum) * quantum) + 0.0


def _time_dims(ds: xr.Dataset, name: str) -> list[str]:
    """The dimensions of a history other than the case dimensions (its samples in time)."""
    return [d for d in ds[name].dims if d not in _case_dims(ds)]


def _orbits(ds: xr.Dataset, vectors: dict[str, Output], stem: str, cases: Cases,
            out_dir: Path, formats: Sequence[str]) -> list[Path]:
    """In-plane vectors as orbits about their mean: one panel per vector, one line per case.

    The mean (the static deflection, e.g. the hub's sag under the rotor's steady load) is
    taken out and written in the legend: the orbit is the vibration, drawn at its own scale.
    """
    ok = [c for c in cases if c.ok]
    by_units: dict[str, tuple[float, str]] = {}
    for units in {v.units for v in vectors.values()}:
        by_units[units] = _display_units(units, np.concatenate(
            [(ds[c] - ds[c].mean(_time_dims(ds, c))).values.ravel() for v in vectors.values()
             if v.units == units for c in v.components or ()]))
    paths: list[Path] = []
    pages = _pages(ok)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(5.2 * len(vectors), 5.8), layout="constrained")
        axes = fig.subplots(1, len(vectors), squeeze=False)[0]
        for ax, vector in zip(axes, vectors.values(), strict=True):
            cx, cy = vector.components or ("", "")
            scale, units = by_units[vector.units]
            for i, case in enumerate(chunk):
                x = ds[cx].isel(case.sel).values * scale
                y = ds[cy].isel(case.sel).values * scale
                mean = (np.nanmean(x), np.nanmean(y))
                x, y = x - mean[0], y - mean[1]
                # the mean to a thousandth of the orbit's size (its roundoff is not news)
                size = float(np.nanmax(np.hypot(x, y))) if np.isfinite(x).any() else 0.0
                shown = [_round_to(m, 1e-3 * size) for m in mean]
                if "psi" in ds.coords and np.isfinite(x).all() and np.isfinite(y).all():
                    # Smooth and closed: Fourier interpolation of the periodic revolution.
                    x = _upsample(x, max(ORBIT_POINTS, x.size))
                    y = _upsample(y, max(ORBIT_POINTS, y.size))
                    x, y = np.append(x, x[0]), np.append(y, y[0])
                _line(ax, x, y, case.style, i, len(chunk),
                      label=f"{case.label}; mean ({shown[0]:.3g}, {shown[1]:.3g}) {units}")
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(vector.long_name, fontsize="medium", wrap=True)
            ax.set_xlabel(f"x about the mean ({units})")
            ax.set_ylabel(f"y about the mean ({units})")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.12))
        fig.suptitle(f"In-plane orbits about their mean {_over(ds)}", wrap=True)
        paths += _save(fig, out_dir, _page_stem(stem, page, len(pages)), formats)
    return paths


def _histories(ds: xr.Dataset, names: list[str], stem: str, cases: Cases, out_dir: Path,
               formats: Sequence[str]) -> list[Path]:
    """Histories without an extra dimension: one panel per history (its name as the panel's
    title, its units on the axis: long names as axis labels collide), one line per case."""
    ok = [c for c in cases if c.ok]
    # one display unit per physical unit in the figure (x and y of a force both in kN)
    by_units: dict[str, tuple[float, str]] = {}
    for units in {ds[n].attrs.get("units", "") for n in names}:
        by_units[units] = _display_units(units, np.concatenate(
            [ds[n].values.ravel() for n in names if ds[n].attrs.get("units", "") == units]))
    paths: list[Path] = []
    pages = _pages(ok)
    for page, chunk in enumerate(pages):
        fig = Figure(figsize=(9, 1.5 + 2.5 * len(names)), layout="constrained")
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
        for ax, name in zip(axes, names, strict=True):
            var = ds[name]
            scale, units = by_units[var.attrs.get("units", "")]
            for i, case in enumerate(chunk):
                x, xlabel = _time_axis(ds, case.sel)
                y = var.isel(case.sel).values * scale
                if not np.isfinite(y).any():
                    continue  # a history this case's model has not (an optional output)
                _line(ax, *_revolution(ds, x, y), case.style, i, len(chunk), label=case.label)
            ax.set_title(var.attrs.get("long_name", name), fontsize="medium")
            ax.set_ylabel(_units_label(units))
            _finish_axis(ax, ds)
        fig.align_ylabels(axes)
        axes[-1].set_xlabel(xlabel)
        _legend(fig, axes[0])
        long_names = [ds[n].attrs.get("long_name", n) for n in names]
        fig.suptitle(f"{long_names[0] if len(names) == 1 else stem.replace('_', ' ')} "
                     f"{_over(ds)}", wrap=True)
        paths += _save(fig, out_dir, _page_stem(stem, page, len(pages)), formats)
    return paths


def _results(ds: xr.Dataset, names: list[str], cases: Cases, out_dir: Path,
             formats: Sequence[str]) -> list[Path]:
    """Scalar results, one panel each: against the first numeric swept parameter (one line per
    value of the others), or, when the cases are categories (a case list, string parameters),
    as grouped bars: one group per category of the first dimension, one bar per value of the
    others (for a case list, one bar per case in its colour)."""
    dims = _case_dims(ds)
    first = _response_dim(ds) or dims[0]
    others = tuple(d for d in dims if d != first)
    numeric = first != "case" and np.issubdtype(ds[first].dtype, np.number)
    if first == "case":
        ticks = [c.label for c in cases]
    else:
        ticks = [_format(v) for v in ds[first].values]
    combos = list(itertools.product(*(range(ds.sizes[d]) for d in others)))
    styles = [c.style for c in cases] if first == "case" else _styles(len(combos))
    width = 8.0 if numeric else _bar_width(len(ticks) * len(combos))
    fig = Figure(figsize=(width, 1.5 + 2.6 * len(names)), layout="constrained")
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    x = ds[first].values if numeric else np.arange(len(ticks))
    for ax, name in zip(axes, names, strict=True):
        var = ds[name].where(ds["status"] == STATUS_OK)
        for j, combo in enumerate(combos):
            sel = dict(zip(others, combo, strict=True))
            y = var.isel(sel).transpose(first).values
            label = ", ".join(f"{d}={_format(ds[d].values[i])}" for d, i in sel.items())
            if numeric:
                _line(ax, x, y, styles[j], j, len(combos), label=label or None)
                continue
            bar = 0.8 / len(combos)
            colors = [st["color"] for st in styles] if first == "case" else styles[j]["color"]
            ax.bar(x - 0.4 + (j + 0.5) * bar, np.nan_to_num(y), bar, color=colors,
                   edgecolor="black", linewidth=0.5, label=label or None)
        units = ds[name].attrs.get("units", "")
        ax.set_title(ds[name].attrs.get("long_name", name), fontsize="medium")
        ax.set_ylabel(_units_label(units))
        ax.grid(True, axis="both" if numeric else "y", alpha=0.3)
    fig.align_ylabels(axes)
    if not numeric:
        axes[-1].set_xticks(x, ticks, rotation=30 if first == "case" else 0,
                            ha="right" if first == "case" else "center")
    axes[-1].set_xlabel("case" if first == "case" else _axis_label(dict(ds[first].attrs),
                                                                   first))
    if others:
        _legend(fig, axes[0])
    fig.suptitle("Results" + ("" if first == "case" else f" against {first}"), wrap=True)
    stem = "results" if first == "case" else f"results_vs_{first}"
    return _save(fig, out_dir, stem, formats)


def _branch_curve(ax: Any, x: np.ndarray, y: np.ndarray, stable: np.ndarray, fold: np.ndarray,
                  color: Any, label: str | None) -> None:
    """One branch: runs of stable segments solid, of unstable ones dashed, folds marked.

    A segment between two points is stable if both ends are (a fold, a multiplier on the unit
    circle, counts as stable: the segments on its unstable side are dashed). Padding (NaN)
    and points without a value are left out.
    """
    keep = np.isfinite(x) & np.isfinite(y) & np.isfinite(stable)
    x, y = x[keep], y[keep]
    stable, fold = stable[keep] == 1, np.nan_to_num(fold[keep]) == 1
    if x.size == 1:
        ax.plot(x, y, "o" if stable[0] else "s", color=color, mfc="none", label=label)
    segments = stable[:-1] & stable[1:]
    start = 0
    for end in range(1, segments.size + 1):
        if end == segments.size or segments[end] != segments[start]:
            ax.plot(x[start:end + 1], y[start:end + 1], "-" if segments[start] else "--",
                    color=color, label=label)
            label = None
            start = end
    if fold.any():
        ax.plot(x[fold], y[fold], "x", linestyle="none", color=color, markersize=8, mew=2)


def _branch_legend(fig: Figure, ax: Any) -> None:
    """The branches (cases) by colour, and the line styles and fold marker they share."""
    handles, labels = ax.get_legend_handles_labels()
    handles += [Line2D([], [], color="0.3", linestyle="-"),
                Line2D([], [], color="0.3", linestyle="--"),
                Line2D([], [], color="0.3", marker="x", linestyle="none", mew=2)]
    labels += ["stable", "unstable", "fold"]
    ncols = max(1, min(len(labels), 4, 110 // (max(map(len, labels)) + 6)))
    fig.legend(handles, labels, loc="outside lower center", ncols=ncols, fontsize="small")


def _branch_panels(ds: xr.Dataset, panels: list[tuple[str, xr.DataArray, dict[str, Any]]],
                   parameter: str, cases: Cases, title: str, stem: str, out_dir: Path,
                   formats: Sequence[str], level: float | None = None,
                   quantity: str = "") -> list[Path]:
    """A figure of branch curves: one panel per ``(title, values, attrs)``, one curve per ok
    case against ``parameter`` (``level``: a horizontal line drawn in every panel;
    ``quantity``: what the vertical axes show, before their units)."""
    ok = [c for c in cases if c.ok]
    cols = 2 if len(panels) > 1 else 1
    rows = -(-len(panels) // cols)
    fig = Figure(figsize=(6.0 * cols if cols > 1 else 8.0, 1.8 + 3.4 * rows),
                 layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax, (name, values, attrs) in zip(axes, panels, strict=False):
        scale, units = _display_units(attrs.get("units", ""), values.values)
        for case in ok:
            _branch_curve(ax, ds[parameter].isel(case.sel).values,
                          values.isel(case.sel).values * scale,
                          ds["stable"].isel(case.sel).values, ds["fold"].isel(case.sel).values,
                          case.style["color"], case.label)
        if level is not None:
            ax.axhline(level, color="black", linewidth=0.8, linestyle=":")
        ax.set_title(name, fontsize="medium", wrap=True)
        ax.set_ylabel(f"{quantity} ({_units_label(units)})" if quantity
                      else _units_label(units))
        ax.set_xlabel(_axis_label(dict(ds[parameter].attrs), parameter))
        ax.grid(True, alpha=0.3)
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    fig.suptitle(title, wrap=True)
    _branch_legend(fig, axes[0])
    return _save(fig, out_dir, stem, formats)


def _branch_figures(ds: xr.Dataset, spec: ModelSpec, cases: Cases, out_dir: Path,
                    formats: Sequence[str], chosen: Sequence[int] | None) -> list[Path]:
    """The response curves of a branch archive (see the module documentation)."""
    parameter = next((n for n in spec.parameters if n in ds and POINT in ds[n].dims), None)
    if parameter is None:
        raise ArchiveError("the archive has branches (a point dimension) but no variable of "
                           "the continued parameter per point")
    ok = ds["status"] == STATUS_OK
    along = f"against {ds[parameter].attrs.get('long_name') or parameter}"
    paths: list[Path] = []
    signals = sorted({n[:-len(s)] for n in harmonic_names(spec.outputs) for s in SUFFIXES
                      if n.endswith(s)}, key=list(spec.outputs).index)
    for name in signals:
        if f"{name}_amplitude" not in ds:
            continue
        var = ds[f"{name}_amplitude"].where(ok)
        inner = [d for d in var.dims if d not in _case_dims(ds) and d not in (POINT, "harmonic")]
        harmonic = ds["harmonic"].values
        picks = [h for h in chosen if h in harmonic] if chosen else _dominant_harmonics(
            var.transpose(..., "harmonic").values, harmonic)
        picks = _significant(var, picks)
        panels = []
        for k in picks:
            for entry in itertools.product(*(range(ds.sizes[d]) for d in inner)):
                sel = dict(zip(inner, entry, strict=True))
                where = ", ".join(f"{_format(ds[d].values[i])}" for d, i in sel.items())
                panels.append((f"{k}P" + (f", {where}" if where else ""),
                               var.isel(sel).sel(harmonic=k), dict(var.attrs)))
        if panels:
            paths += _branch_panels(
                ds, panels, parameter, cases,
                f"Harmonics of the {spec.outputs[name].long_name} {along}",
                f"harmonics_{name}_vs_{parameter}", out_dir, formats, quantity="amplitude")
    # the scalar results that change along a branch (the run facts, run_*, are not drawn)
    scalars = []
    for name, decl in spec.outputs.items():
        if not decl.is_scalar or name.startswith("run_") or name not in ds:
            continue
        values = ds[name].where(ok)
        if POINT in values.dims and bool((values.max(POINT) > values.min(POINT)).any()):
            scalars.append((decl.long_name or name, values, dict(ds[name].attrs)))
    if scalars:
        paths += _branch_panels(ds, scalars, parameter, cases, f"Results {along}",
                                f"results_vs_{parameter}", out_dir, formats)
    multiplier = ds["floquet_multiplier_max"]
    paths += _branch_panels(
        ds, [("largest Floquet multiplier modulus (above 1: unstable)", multiplier.where(ok),
              dict(multiplier.attrs))],
        parameter, cases, f"Stability {along}", f"floquet_multiplier_max_vs_{parameter}",
        out_dir, formats, level=1.0)
    if BACKBONE in ds:
        paths += _backbones(ds, cases, out_dir, formats)
    return paths


def _backbones(ds: xr.Dataset, cases: Cases, out_dir: Path,
               formats: Sequence[str]) -> list[Path]:
    """The absorbers' backbones of a branch archive: free-vibration order against swing
    amplitude, one curve per ok case (its hole shape in the legend)."""
    var = ds[BACKBONE]
    (dim,) = [d for d in var.dims if d not in _case_dims(ds)]
    fig = Figure(figsize=(8.0, 5.2), layout="constrained")
    ax = fig.subplots()
    for case in (c for c in cases if c.ok):
        ax.plot(ds[dim].values, var.isel(case.sel).values, color=case.style["color"],
                label=case.label)
    ax.set_xlabel(_axis_label(dict(ds[dim].attrs), dim))
    ax.set_ylabel(f"tuning order ({_units_label(var.attrs.get('units', '1'))})")
    ax.set_title(var.attrs.get("long_name", BACKBONE), fontsize="medium", wrap=True)
    ax.grid(True, alpha=0.3)
    _legend(fig, ax)
    return _save(fig, out_dir, "backbones", formats)


def archive_model(ds: xr.Dataset, path: str | os.PathLike[str] = "archive") -> ModelSpec:
    """The model of an archive (its ``model`` attribute), for its output declarations.

    Raises
    ------
    pipelines.archive.ArchiveError
        If the file is not a sweep archive or its model cannot be loaded.
    """
    from studies.parameters import ParameterError
    from studies.registry import resolve_model

    if "status" not in ds or "model" not in ds.attrs:
        raise ArchiveError(f"{path} is not a sweep archive (no 'status' variable or 'model' "
                           "attribute); bifilar plot draws the archive.nc of bifilar sweep or "
                           "bifilar run")
    try:
        return resolve_model(str(ds.attrs["model"]))
    except ParameterError as exc:
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
        large for bar charts, or against the continued parameter of a branch archive;
        default: the two largest non-zero harmonics of each quantity.
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
    archived = ds
    # the charts below address an in-plane vector's harmonic amplitudes (archived as
    # <name>_amplitude) by the vector's name
    ds = ds.rename({f"{n}_amplitude": n for n, d in spec.outputs.items()
                    if d.is_vector and f"{n}_amplitude" in ds})
    cases = _cases(ds)
    if not any(case.ok for case in cases):
        counts = status_counts(ds)
        raise ArchiveError(
            f"no case of {archive_path} finished ok ({counts['failed']} failed, "
            f"{counts['not_run']} not run), nothing to plot; its 'message' variable says why"
        )
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if POINT in archived.dims:
        # branches: response curves against the continued parameter, nothing per revolution
        return _branch_figures(archived, spec, _cases(archived), out, formats, harmonics)
    paths: list[Path] = []
    if spec.periodic:
        # response curves need a numeric abscissa; categories (a case list, a string
        # parameter such as ``hole``) are grouped bars
        lines = _response_dim(ds) is not None
        from pipelines.envelope_plots import sweeps_envelope

        # Table 1's paired comparisons; an envelope's cases get the envelope figures instead
        for pair in [] if sweeps_envelope(archived) else comparison_pairs(ds):
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
        # (the run facts, run_*, are archived but are not results to draw)
        scalars = [n for n, o in spec.outputs.items()
                   if o.is_scalar and n in ds and not n.startswith("run_")]
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
    if spec.periodic:
        from pipelines.airframe_plots import airframe_figures
        from pipelines.envelope_plots import envelope_figures

        # (the rotor's, when it sweeps airspeed with trim or rotor speed)
        paths += envelope_figures(archived, list(spec.parameters), out, formats)
        # (the rotor's, when a case stands on a modal airframe)
        paths += airframe_figures(archived, out, formats)
    return paths
