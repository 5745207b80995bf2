"""The figures pairing the paper's model with a modal airframe (pipelines.airframe_plots),
drawn from a small synthetic archive (no rotor is run)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from pipelines.airframe_plots import G0, airframe_figures, has_airframe, station_vibration
from pipelines.archive import STATUS_FAILED, STATUS_OK

CASES = [("0: locked", "beam", 0.0), ("1: free", "beam", 9.0), ("0: locked", "modal", 0.0),
         ("1: free", "modal", 1.5), ("1: free, cycloid", "modal", 2.0)]
STATIONS = ["pilot_seat", "cabin_centre", "tail"]


def synthetic_archive(failed: int | None = None) -> xr.Dataset:
    """A case list as :func:`pipelines.archive.open_archive` returns it: beam cases without
    stations (NaN), modal cases with 4P station accelerations 1, 2, 2 m s-2 along x, y, z
    times the case number."""
    n = len(CASES)
    psi = np.linspace(0.0, 360.0, 48, endpoint=False)
    force = np.full((n, 3, 9), np.nan)
    force[:, :2, 4] = [[1000.0 - 100 * i, 800.0] for i in range(n)]
    station = np.full((n, len(STATIONS), 3, 9), np.nan)
    pins = np.zeros((n, 4, psi.size))
    for i, (_, fuselage, swing) in enumerate(CASES):
        if fuselage == "modal":
            station[i, :, :, :] = 0.0
            station[i, :, :, 4] = (i + 1) * np.array([1.0, 2.0, 2.0])
        pins[i] = swing * np.sin(np.radians(3 * psi))[None, :]
    status = np.full(n, STATUS_OK, dtype=np.int8)
    if failed is not None:
        status[failed] = STATUS_FAILED
    return xr.Dataset(
        {"status": ("case", status),
         "case_name": ("case", [c[0] for c in CASES]),
         "fuselage": ("case", [c[1] for c in CASES]),
         "hub_force_fixed_amplitude": (("case", "direction", "harmonic"), force),
         "station_acceleration_amplitude": (("case", "station", "direction", "harmonic"),
                                            station),
         "pin_angle": (("case", "bifilar", "time_in_rev"), pins)},
        coords={"case": np.arange(n), "direction": ["x", "y", "z"], "harmonic": np.arange(9),
                "station": STATIONS, "psi": ("time_in_rev", psi)})


def test_station_vibration_is_the_acceleration_vector_magnitude_in_g():
    """√(1² + 2² + 2²) = 3 m s-2 times the case number, in g."""
    ds = synthetic_archive()
    np.testing.assert_allclose(station_vibration(ds, {"case": 3}), [4 * 3.0 / G0] * 3,
                               rtol=1e-14)


def test_airframe_figures_are_drawn_for_an_archive_with_a_modal_case(tmp_path):
    paths = airframe_figures(synthetic_archive(), tmp_path, ("png",))
    assert sorted(p.name for p in paths) == ["airframe_cabin_vibration_4p.png",
                                             "airframe_hub_loads_4p.png",
                                             "airframe_pin_amplitude.png"]
    assert all(p.stat().st_size > 0 for p in paths)


def test_no_airframe_figures_without_an_ok_modal_case(tmp_path):
    ds = synthetic_archive()
    beam = ds.isel(case=[0, 1])
    assert not has_airframe(beam)
    assert airframe_figures(beam, tmp_path, ("png",)) == []
    failed = synthetic_archive(failed=2)
    failed["status"].values[3:] = STATUS_FAILED
    assert not has_airframe(failed)


def test_run_study_airframe_is_the_rotors():
    """--study airframe runs airframe_study.toml on the rotor (Table 1's cases 0-2 on both
    models, the hole shapes, each change alone); the hub has none, and says why."""
    from click.testing import CliRunner

    from pipelines import cli
    from pipelines.studyfile import load_study
    from tests.pipelines.helpers import one_error_line

    study = cli.default_study(None, "airframe")
    assert study.name == "airframe_study.toml"
    cases = load_study(study).cases
    both = [c for c in cases if (c.params["fuselage"], c.params["control_system"])
            == ("modal", "swashplate")]
    paper = [c for c in cases if (c.params["fuselage"], c.params["control_system"])
             == ("beam", "prescribed")]
    assert len(cases) == 14 and len(both) == 5 and len(paper) == 5
    for model in (both, paper):
        assert {c.params["hole"] for c in model} == {"circle", "cycloid", "epicycloid"}
    # each change alone, locked and free
    for model in (("beam", "swashplate"), ("modal", "prescribed")):
        alone = [c for c in cases if (c.params["fuselage"], c.params["control_system"]) == model]
        assert sorted(c.params["bifilar"] for c in alone) == ["free", "locked"]
    line = one_error_line(CliRunner().invoke(cli.main, ["run", "--study", "airframe", "--model",
                                                        "hub", "--out", "unused"]))
    assert "--study airframe" in line and "rotor" in line and "airframe" in line
