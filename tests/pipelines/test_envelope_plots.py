"""The flight-envelope figures (pipelines.envelope_plots), drawn from a small synthetic archive
shaped like ``studies/envelope_study.toml``'s (a case list over airspeed, rotor speed and
absorber; no rotor is run), and the ``--study`` option of ``bifilar run``."""

from __future__ import annotations

import itertools
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner
from matplotlib.figure import Figure

import pipelines.plots as plots
from pipelines import cli
from pipelines.archive import STATUS_FAILED, STATUS_OK
from pipelines.envelope_plots import KNOT, envelope_figures
from pipelines.studyfile import load_study
from tests.pipelines.helpers import one_error_line
from tests.pipelines.test_plots import layout_faults

REPO = Path(__file__).resolve().parents[2]
SPEEDS = [40.0, 100.0, 160.0]  # kt
ROTOR_SPEEDS = [25.65, 28.35]  # rad/s, besides the nominal 27
ABSORBERS = ["locked", "free", "equivalent"]
PARAMETERS = ["bifilar", "hub_speed", "flight_speed", "trim", "gross_weight"]


def _case(kt: float, omega: float, bifilar: str) -> dict:
    """Synthetic results: locked 4P loads growing with airspeed; free bifilars cut them to
    10 % at any rotor speed, the equivalent absorber to 15 % at 27 rad/s, less away from it."""
    locked = 1e4 * (1.0 + (kt / 100.0) ** 2) * (omega / 27.0) ** 2
    share = {"locked": 1.0, "free": 0.1, "equivalent": 0.15 + 5.0 * abs(omega / 27.0 - 1)}
    amp = locked * share[bifilar]
    return {"force": (amp, 0.6 * amp), "force_z": 0.3 * amp, "moment": (0.2 * amp, 0.1 * amp),
            "power": 1e6 * (0.6 + 0.4 * (kt / 100.0 - 0.8) ** 2), "collective": 9.0 + kt / 100,
            "swing": 4.0 + kt / 40 if bifilar == "free" else 0.0}


def synthetic_archive(failed: int | None = None) -> xr.Dataset:
    """An archive as :func:`pipelines.archive.open_archive` returns it: airspeeds at 27 rad/s
    and rotor speeds at 100 kt, every absorber."""
    rows = [(kt, 27.0, b) for kt in SPEEDS for b in ABSORBERS]
    rows += [(100.0, om, b) for om in ROTOR_SPEEDS for b in ABSORBERS]
    n, harmonics = len(rows), np.arange(9)
    force = np.zeros((n, 9, 2))
    moment = np.zeros((n, 9, 2))
    force_z = np.zeros((n, 9))
    psi = np.linspace(0.0, 360.0, 48, endpoint=False)
    pins = np.zeros((n, 4, psi.size))
    scalars = {k: np.zeros(n) for k in ("rotor_power", "control_collective",
                                         "control_cyclic_sine", "control_cyclic_cosine",
                                         "control_shaft_tilt")}
    for i, (kt, omega, bifilar) in enumerate(rows):
        r = _case(kt, omega, bifilar)
        force[i, 4], moment[i, 4], force_z[i, 4] = r["force"], r["moment"], r["force_z"]
        pins[i] = r["swing"] * np.sin(np.radians(3 * psi))[None, :]
        scalars["rotor_power"][i] = r["power"]
        scalars["control_collective"][i] = r["collective"]
        scalars["control_cyclic_sine"][i] = -kt / 25.0
        scalars["control_shaft_tilt"][i] = kt / 20.0
    status = np.full(n, STATUS_OK, dtype=np.int8)
    if failed is not None:
        status[failed] = STATUS_FAILED
    case = ("case",)
    return xr.Dataset(
        {"status": (case, status),
         "hub_force_fixed_amplitude": (("case", "harmonic", "direction"), force, {"units": "N"}),
         "hub_moment_fixed_amplitude": (("case", "harmonic", "direction"), moment,
                                        {"units": "N m"}),
         "hub_force_z_fixed_amplitude": (("case", "harmonic"), force_z, {"units": "N"}),
         "pin_angle": (("case", "bifilar_index", "time_in_rev"), pins, {"units": "degree"}),
         **{k: (case, v) for k, v in scalars.items()},
         "trim": ((), "propulsive"), "gross_weight": ((), 72.3e3)},
        coords={"case": np.arange(n), "harmonic": harmonics, "direction": ["x", "y"],
                "flight_speed": (case, [kt * KNOT for kt, _, _ in rows], {"units": "m s-1"}),
                "hub_speed": (case, [om for _, om, _ in rows], {"units": "rad s-1"}),
                "bifilar": (case, [b for _, _, b in rows]),
                "case_name": (case, [f"{kt:g} kt, {om:g} rad/s, {b}" for kt, om, b in rows])},
        attrs={"model": "rotor"})


def drawn(ds: xr.Dataset, monkeypatch, tmp_path) -> dict[str, Figure]:
    figures: dict[str, Figure] = {}

    def keep(fig: Figure, out_dir: Path, stem: str, formats) -> list[Path]:
        figures[stem] = fig
        return [out_dir / f"{stem}.png"]

    monkeypatch.setattr(plots, "_save", keep)
    envelope_figures(ds, PARAMETERS, tmp_path, ("png",))
    return figures


def _lines(fig: Figure, panel: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    ax = [a for a in fig.axes if a.lines][panel]
    return {line.get_label(): (line.get_xdata(), line.get_ydata()) for line in ax.lines}


def test_envelope_figures_are_drawn_from_the_archive(monkeypatch, tmp_path):
    figures = drawn(synthetic_archive(), monkeypatch, tmp_path)
    assert set(figures) == {"envelope_hub_loads_4p", "envelope_controls_power",
                            "envelope_pin_amplitude", "reduction_4p_vs_hub_speed"}
    # 4P loads against airspeed: the nominal rotor speed's cases only, one line per absorber
    loads = _lines(figures["envelope_hub_loads_4p"], 0)
    assert list(loads) == ABSORBERS
    x, y = loads["locked"]
    np.testing.assert_allclose(x, np.array(SPEEDS) * KNOT)
    np.testing.assert_allclose(y, [_case(kt, 27.0, "locked")["force"][0] / 1e3 for kt in SPEEDS])
    # power curve in kW
    power = _lines(figures["envelope_controls_power"], 4)
    np.testing.assert_allclose(power["free"][1], [_case(kt, 27.0, "free")["power"] / 1e3
                                                  for kt in SPEEDS])
    # only the free bifilars' pins swing
    pins = _lines(figures["envelope_pin_amplitude"], 0)
    assert list(pins) == ["free"]
    np.testing.assert_allclose(pins["free"][1], [4.0 + kt / 40 for kt in SPEEDS], rtol=1e-6)


def test_reduction_is_over_the_locked_case_at_the_same_rotor_speed(monkeypatch, tmp_path):
    figures = drawn(synthetic_archive(), monkeypatch, tmp_path)
    curves = _lines(figures["reduction_4p_vs_hub_speed"], 0)
    assert list(curves) == ["free", "equivalent"]
    x, y = curves["free"]
    np.testing.assert_allclose(x, [25.65, 27.0, 28.35])
    np.testing.assert_allclose(y, 90.0)
    x, y = curves["equivalent"]
    np.testing.assert_allclose(y[1], 85.0)
    assert y[0] < 85.0 and y[2] < 85.0


def test_envelope_figures_skip_failed_cases_and_fit_their_text(monkeypatch, tmp_path):
    figures = drawn(synthetic_archive(failed=3), monkeypatch, tmp_path)  # 100 kt, locked
    x, _ = _lines(figures["envelope_hub_loads_4p"], 0)["locked"]
    np.testing.assert_allclose(x, np.array([40.0, 160.0]) * KNOT)
    faults = {stem: layout_faults(fig) for stem, fig in figures.items()}
    assert not any(faults.values()), faults


def test_no_envelope_figures_without_trim_or_sweep(monkeypatch, tmp_path):
    ds = synthetic_archive().assign(trim=((), "none"))
    ds = ds.isel(case=ds["hub_speed"] == 27.0)  # no rotor-speed sweep either
    assert drawn(ds, monkeypatch, tmp_path) == {}


def test_envelope_study_file_holds_both_sweeps():
    study = load_study(REPO / "studies" / "envelope_study.toml")
    params = [c.params for c in study.cases]
    assert all(p["trim"] == "propulsive" for p in params)
    nominal = {(p["flight_speed"], p["bifilar"]) for p in params if p["hub_speed"] == 27.0}
    speeds = sorted({v for v, _ in nominal})
    assert len(speeds) >= 7 and speeds[0] / KNOT == pytest.approx(40, abs=0.01)
    assert speeds[-1] / KNOT == pytest.approx(160, abs=0.01)
    assert {b for _, b in nominal} == set(ABSORBERS)
    omegas = {p["hub_speed"] for p in params}
    assert min(omegas) == pytest.approx(0.95 * 27.0) and max(omegas) == pytest.approx(1.05 * 27)


def test_run_study_option(monkeypatch, tmp_path):
    """--study envelope runs envelope_study.toml; it has no hub version; an unknown study is
    refused naming the valid ones."""
    assert cli.default_study("rotor", "envelope").name == "envelope_study.toml"
    assert cli.default_study("hub").name == "hub_study.toml"
    runner = CliRunner()
    line = one_error_line(runner.invoke(cli.main, ["run", "--study", "envelope", "--model",
                                                   "hub", "--out", str(tmp_path)]))
    assert "--study envelope" in line and "rotor" in line and "trim" in line
    line = one_error_line(runner.invoke(cli.main, ["run", "--study", "table2",
                                                   "--out", str(tmp_path)]))
    assert "--study" in line and "table1" in line and "envelope" in line
    assert not (tmp_path / "archive.nc").exists()
    # the jump study is the hub's only: without --model it runs there
    assert cli.default_study(None, "jump").name == "jump_study.toml"
    line = one_error_line(runner.invoke(cli.main, ["run", "--study", "jump", "--model",
                                                   "rotor", "--out", str(tmp_path)]))
    assert "--study jump" in line and "hub" in line



def test_cartesian_sweep_with_another_parameter(monkeypatch, tmp_path):
    """A [sweep] of flight_speed × bifilar × gross_weight: one line per absorber and weight."""
    weights = [60e3, 72.3e3]
    shape = (len(SPEEDS), len(ABSORBERS), len(weights))
    dims = ("flight_speed", "bifilar", "gross_weight")
    force = np.zeros((*shape, 9, 2))
    power = np.zeros(shape)
    for (i, kt), (j, b), (k, w) in itertools.product(enumerate(SPEEDS), enumerate(ABSORBERS),
                                                      enumerate(weights)):
        force[i, j, k, 4] = _case(kt, 27.0, b)["force"]
        power[i, j, k] = _case(kt, 27.0, b)["power"] * w / 72.3e3
    sweep = xr.Dataset(
        {"status": (dims, np.full(shape, STATUS_OK, dtype=np.int8)),
         "hub_force_fixed_amplitude": ((*dims, "harmonic", "direction"), force),
         "rotor_power": (dims, power), "trim": ((), "propulsive"), "hub_speed": ((), 27.0)},
        coords={"flight_speed": np.array(SPEEDS) * KNOT, "bifilar": ABSORBERS,
                "gross_weight": weights, "harmonic": np.arange(9), "direction": ["x", "y"]})
    figures = drawn(sweep, monkeypatch, tmp_path)
    assert set(figures) == {"envelope_hub_loads_4p", "envelope_controls_power"}
    curves = _lines(figures["envelope_controls_power"], 0)
    assert len(curves) == 6
    np.testing.assert_allclose(curves["free, gross_weight=60000"][1],
                               [_case(kt, 27.0, "free")["power"] * 60 / 72.3e3
                                for kt in SPEEDS])


def test_plot_archive_draws_the_envelope_figures_without_paired_comparisons(monkeypatch,
                                                                           tmp_path):
    """bifilar plot on the envelope's archive: its figures, and no Table 1 comparisons."""
    from pipelines.envelope_plots import sweeps_envelope

    ds = synthetic_archive()
    assert sweeps_envelope(ds)
    assert not sweeps_envelope(ds.isel(case=[0, 1, 2]))  # one airspeed, one rotor speed
    # the rotor's declarations are not needed for these figures: a model with none
    spec = SimpleNamespace(parameters=dict.fromkeys(PARAMETERS), outputs={}, periodic=True)
    monkeypatch.setattr(plots, "open_archive", lambda path: ds)
    monkeypatch.setattr(plots, "archive_model", lambda ds, path: spec)
    drawn_stems: list[str] = []
    monkeypatch.setattr(plots, "_save", lambda fig, out, stem, formats: drawn_stems.append(stem)
                        or [out / f"{stem}.png"])
    plots.plot_archive(tmp_path / "archive.nc", tmp_path)
    assert "envelope_hub_loads_4p" in drawn_stems and "reduction_4p_vs_hub_speed" in drawn_stems
    assert not any(stem.startswith("compare_") for stem in drawn_stems)
