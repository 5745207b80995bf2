"""The report figures, drawn from small archives of the pipeline test model (a case list like
the paper's Table 1, a sweep of a string parameter, a numeric sweep): pins A and B (Fig. 14),
orbits about their mean (Fig. 15), one style per case in every figure, categorical sweeps as
grouped bars, harmonics at noise level left out, no clipped or colliding text.

The figures are taken at :func:`pipelines.plots._save`, before they are written, so that their
artists can be inspected; writing PNG and PDF is tested with the CLI (test_pipeline.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.container import BarContainer
from matplotlib.figure import Figure

import pipelines.plots as plots
from pipelines.archive import open_archive
from pipelines.sweep import run_sweep

HEADER = 'model = "tests.pipelines.models:SPEC"\ntitle = "figures"\n'
CASES = HEADER + """
[[cases]]
name = "0: locked"
bifilar = "locked"
[[cases]]
name = "1: free, 3P"
[[cases]]
name = "2: free, 3.3P"
tuning_order = 3.3
[[cases]]
name = "3: free, 3P, soft fuselage"
fuselage_stiffness_scale = 0.5
"""
CATEGORICAL = HEADER + """
[sweep]
bifilar = ["free", "locked"]
"""
NUMERIC = HEADER + """
[sweep]
tuning_order = [2.8, 3.0, 3.2]
bifilar = ["free", "locked"]
"""
# a model without per-rev harmonics, swept over a string parameter: its scalar results
COLLAR_CURVES = """model = "collar"
title = "collar on both curves"
[fixed]
steps_per_period = 100
[sweep]
curve = ["circle", "cycloid"]
"""


@pytest.fixture(scope="module")
def archives(scheduler, tmp_path_factory) -> dict[str, Path]:
    out = {}
    for name, body in (("cases", CASES), ("categorical", CATEGORICAL), ("numeric", NUMERIC),
                       ("collar", COLLAR_CURVES)):
        tmp = tmp_path_factory.mktemp(name)
        (tmp / "study.toml").write_text(body)
        out[name] = run_sweep(tmp / "study.toml", tmp / "out", scheduler=scheduler,
                              progress=False)
    return out


def figures(archive: Path, monkeypatch, tmp_path) -> dict[str, Figure]:
    """The figures of an archive, by stem, as drawn (not written)."""
    drawn: dict[str, Figure] = {}

    def keep(fig: Figure, out_dir: Path, stem: str, formats) -> list[Path]:
        drawn[stem] = fig
        return [out_dir / f"{stem}.png"]

    monkeypatch.setattr(plots, "_save", keep)
    plots.plot_archive(archive, tmp_path)
    return drawn


def _texts(fig: Figure) -> list:
    """Every text drawn: titles, axis and tick labels (of the ticks in view), legends."""
    out = [fig._suptitle, *fig.texts]
    for legend in fig.legends:
        out += legend.get_texts()
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        out += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label,
                ax.xaxis.offsetText, ax.yaxis.offsetText]
        for axis in (ax.xaxis, ax.yaxis):
            out += [tick.label1 for tick in axis._update_ticks()]
        if ax.get_legend() is not None:
            out += ax.get_legend().get_texts()
    unique = {id(t): t for t in out if t is not None and t.get_visible() and t.get_text().strip()}
    return list(unique.values())


def layout_faults(fig: Figure) -> list[str]:
    """Texts outside the figure (clipped) and pairs of texts that overlap (beyond 1 pixel)."""
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    page = fig.bbox
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in _texts(fig)]
    faults = [f"clipped: {text!r}" for text, b in boxes
              if b.x0 < page.x0 - 1 or b.y0 < page.y0 - 1 or b.x1 > page.x1 + 1
              or b.y1 > page.y1 + 1]
    for i, (ta, a) in enumerate(boxes):
        for tb, b in boxes[i + 1:]:
            if min(a.x1, b.x1) - max(a.x0, b.x0) > 1 and min(a.y1, b.y1) - max(a.y0, b.y0) > 1:
                faults.append(f"overlap: {ta!r} / {tb!r}")
    return faults


def test_pin_angles_show_pins_a_and_b(archives, monkeypatch, tmp_path):
    """Fig. 14: per case, pin A (bifilar 0, solid) and pin B (bifilar 2, 180° away,
    dash-dotted), in antiphase at 3P; the locked case, which does not swing, has no panel."""
    fig = figures(archives["cases"], monkeypatch, tmp_path)["pin_angles"]
    ds = open_archive(archives["cases"])
    panels = [ax for ax in fig.axes if ax.lines]
    assert [ax.get_title() for ax in panels] == list(ds["case_name"].values[1:])
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["pin A (bifilar 0)", "pin B (bifilar 2, 180° from A)"]
    for case, ax in enumerate(panels, start=1):
        a, b = ax.lines
        assert (a.get_linestyle(), b.get_linestyle()) == ("-", "-.")
        pins = ds["pin_angle"].isel(case=case).transpose("bifilar_index", ...).values
        psi = ds["psi"].values
        # drawn smooth through the archived samples (Fourier interpolation, read back here
        # linearly between its 720 points: 0.3 % of the swing)
        for line, pin in ((a, pins[0]), (b, pins[2])):
            drawn = np.interp(psi, line.get_xdata(), line.get_ydata())
            np.testing.assert_allclose(drawn, pin, atol=3e-3 * np.abs(pin).max())
        # antiphase (the 3P swing seen from bifilars half a revolution apart)
        assert np.corrcoef(a.get_ydata(), b.get_ydata())[0, 1] < -0.99


def test_orbits_are_drawn_about_their_mean(archives, monkeypatch, tmp_path):
    """Fig. 15: a static deflection (here 5 mm added to every hub position) moves no orbit;
    each is drawn about its own mean, which the legend states."""
    ds = open_archive(archives["cases"])
    sagged = ds.assign(hub_x_fixed=ds["hub_x_fixed"] + 0.005)
    path = tmp_path / "sagged.nc"
    sagged.to_netcdf(path)
    fig = figures(path, monkeypatch, tmp_path)["orbits"]
    hub = fig.axes[0]
    assert "hub" in hub.get_title()
    for line in hub.lines:
        x, y = line.get_xdata()[:-1], line.get_ydata()[:-1]  # closed: the first point repeats
        size = np.hypot(x, y).max()
        assert abs(x.mean()) < 1e-9 * size and abs(y.mean()) < 1e-9 * size
    labels = [t.get_text() for t in hub.get_legend().get_texts()]
    assert all("mean (5, 0) mm" in label for label in labels), labels


def _styles(fig: Figure) -> dict[str, set]:
    """Legend label -> the set of (colour, line style, marker) it is drawn with."""
    out: dict[str, set] = {}
    for ax in fig.axes:
        for line in ax.lines:
            label = line.get_label()
            if not label.startswith("_"):
                out.setdefault(label.split(";")[0], set()).add(
                    (line.get_color() if isinstance(line.get_color(), str)
                     else tuple(line.get_color()), line.get_linestyle(), line.get_marker()))
        for bars in ax.containers:
            if isinstance(bars, BarContainer) and not bars.get_label().startswith("_"):
                color = tuple(bars.patches[0].get_facecolor())
                out.setdefault(bars.get_label(), set()).add((color, None, None))
    return out


def test_one_style_per_case_in_every_figure(archives, monkeypatch, tmp_path):
    """Each case keeps its colour in every figure, bars and lines alike, and no two cases
    share both colour and line style (case 1 stays visible under a coinciding case)."""
    drawn = figures(archives["cases"], monkeypatch, tmp_path)
    ds = open_archive(archives["cases"])
    colors: dict[str, set] = {}
    lines: dict[str, set] = {}
    for fig in drawn.values():
        for label, styles in _styles(fig).items():
            colors.setdefault(label, set()).update(s[0][:3] for s in styles)
            lines.setdefault(label, set()).update(s[1:] for s in styles if s[1] is not None)
    names = list(ds["case_name"].values)
    assert set(names) <= set(colors)
    assert all(len(colors[n]) == 1 for n in names), {n: colors[n] for n in names}
    assert all(len(lines[n]) == 1 for n in names), {n: lines[n] for n in names}
    looks = [(*colors[n], *lines[n]) for n in names]
    assert len(set(looks)) == len(names)
    assert len({c for n in names for c in colors[n]}) == len(names)


def test_categorical_sweep_is_drawn_as_grouped_bars(archives, monkeypatch, tmp_path):
    drawn = figures(archives["categorical"], monkeypatch, tmp_path)
    assert not any("_vs_" in stem for stem in drawn)
    fig = drawn["harmonics_hub_force_fixed"]
    (ax,) = [a for a in fig.axes if a.get_visible()]
    bars = [c for c in ax.containers if isinstance(c, BarContainer)]
    assert [b.get_label() for b in bars] == ["bifilar=free", "bifilar=locked"]
    assert not ax.lines


def test_categorical_results_are_grouped_bars(archives, monkeypatch, tmp_path):
    """A non-periodic model's results against a string parameter: one bar per curve in every
    panel, no lines joining the categories."""
    fig = figures(archives["collar"], monkeypatch, tmp_path)["results_vs_curve"]
    for ax in fig.axes:
        assert not ax.lines
        (bars,) = [c for c in ax.containers if isinstance(c, BarContainer)]
        assert len(bars.patches) == 2
    assert [t.get_text() for t in fig.axes[-1].get_xticklabels()] == ["circle", "cycloid"]


def test_harmonics_at_noise_level_are_left_out(archives, monkeypatch, tmp_path):
    """The model's fixed-frame response has no 8P: its amplitude is roundoff (about 1e-14 of
    the 4P), so the 8P panel of the response curves and the 8P bars are left out."""
    ds = open_archive(archives["numeric"])
    force = np.abs(ds["hub_force_fixed_amplitude"])
    assert float(force.sel(harmonic=8).max()) < 1e-10 * float(force.sel(harmonic=4).max())
    drawn = figures(archives["numeric"], monkeypatch, tmp_path)
    fig = drawn["harmonics_hub_force_fixed_vs_tuning_order"]
    assert [ax.get_title() for ax in fig.axes] == ["4P"]
    rotating = drawn["harmonics_hub_displacement_rotating_vs_tuning_order"]
    assert [ax.get_title() for ax in rotating.axes] == ["3P", "5P"]
    bars = figures(archives["cases"], monkeypatch, tmp_path)["harmonics_hub_force_fixed"]
    ticks = [t.get_text() for t in bars.axes[0].get_xticklabels()]
    assert ticks == ["4P x", "4P y"]


@pytest.mark.parametrize("archive", ["cases", "categorical", "numeric", "collar"])
def test_no_text_is_clipped_or_collides(archives, archive, monkeypatch, tmp_path):
    drawn = figures(archives[archive], monkeypatch, tmp_path)
    assert drawn
    faults = {stem: layout_faults(fig) for stem, fig in drawn.items()}
    assert not any(faults.values()), {k: v for k, v in faults.items() if v}
