"""The UH-60A blade fan plot against the published (Bowen-Davies) frequencies, and the
``bifilar fanplot`` command."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from pipelines.cli import main
from studies.blade import fanplot
from studies.uh60a import bowen_davies_fanplot


@pytest.fixture(scope="module")
def at_27():
    return fanplot([27.0])


def published(label: str) -> float:
    ref = bowen_davies_fanplot().sel(speed_ratio=1.0)
    return float(ref.frequency.values[list(ref.mode_label.values).index(label)])


@pytest.mark.parametrize("label, tol", [("flap 1", 0.03), ("flap 2", 0.03), ("flap 3", 0.03),
                                        ("flap 4", 0.03), ("lag 2", 0.03), ("torsion 1", 0.03),
                                        ("lag 1", 0.06)])
def test_fanplot_at_27_rad_s_against_bowen_davies(at_27, label, tol):
    """Measured relative differences at 27 rad/s (6 elements, converged to 0.2 % against 12):
    flap 1 −0.9 %, flap 2 −0.2 %, flap 3 −1.8 %, flap 4 +0.4 %, lag 2 −0.4 %, torsion 1
    +0.6 %. Lag 1 is −4.7 %: this arrangement has a free lag hinge, while the published
    model has lag stiffness — its lag 1 is 0.28 Hz at Ω = 0 (checked below), ours 0."""
    f = at_27.frequency.sel(hub_speed=27.0).values[list(at_27.mode_label.values).index(label)]
    assert f == pytest.approx(published(label), rel=tol)


@pytest.mark.slow
def test_fanplot_branches_follow_bowen_davies():
    """The whole fan plot, 0 … Ω_ref, branch by branch (eleven speeds; the default tier checks
    27 rad/s and 0 above): the modes named at 0.1 Ω_ref and
    followed by their shapes land on the digitized branches through the flap 3 / lag 2 /
    torsion veerings. Measured worst differences: flap 2 −4.8 % (at 0.1 Ω_ref, 3.4 Hz), flap 3
    −2.1 %, flap 4 +3.8 % (Ω = 0), lag 2 −1.2 %, torsion −3.0 % (Ω = 0). Flap 1 and lag 1
    differ at low speed because the published model has hinge stiffness: at Ω = 0 its lag 1
    and flap 1 are 0.28 and 0.31 Hz, a free hinge's 0."""
    ref = bowen_davies_fanplot()
    ds = fanplot(ref.rotor_speed.values)
    labels = list(ds.mode_label.values)
    for k, label in enumerate(ref.mode_label.values):
        if label in ("flap 1", "lag 1"):
            continue
        ours = ds.frequency.values[:, labels.index(label)]
        assert np.abs(ours / ref.frequency.values[:, k] - 1).max() < 0.05, label
    at_rest = ref.frequency.sel(speed_ratio=0.0)
    assert at_rest.values[list(ref.mode_label.values).index("lag 1")] > 0.25


def test_fanplot_labels_and_zero_speed():
    """At Ω = 0 the hinged blade's rigid flap and lag modes are 0 Hz; the elastic modes
    are ordered by frequency within each family."""
    ds = fanplot([0.0])
    f = dict(zip(ds.mode_label.values, ds.frequency.values[0], strict=True))
    assert f["flap 1"] < 1e-3 and f["lag 1"] < 1e-3
    assert 0 < f["flap 2"] < f["flap 3"] < f["flap 4"]
    assert ds.frequency.attrs["units"] == "Hz" and ds.hub_speed.attrs["units"] == "rad s-1"


def test_fanplot_command_writes_archive_and_figure(tmp_path):
    """The command's archive and figure (two beam elements: the layout, not the accuracy,
    which the tests above check at the default six)."""
    out = tmp_path / "fan.nc"
    res = CliRunner().invoke(main, ["fanplot", "--speeds", "10", "27", "--elements", "2",
                                    "--out", str(out)])
    assert res.exit_code == 0, res.output
    ds = xr.open_dataset(out)
    assert ds.frequency.dims == ("hub_speed", "mode")
    assert list(ds.hub_speed.values) == [10.0, 27.0]
    assert "lag 2" in list(ds.mode_label.values)
    assert np.isfinite(ds.frequency.values).all()
    assert (tmp_path / "fan.png").exists() and (tmp_path / "fan.pdf").exists()


@pytest.mark.parametrize("args, message", [
    (["--speeds", "-5"], "must be in 0"),
    (["--speeds", "fast"], "not a number"),
    (["--elements", "0"], "0"),
    (["5"], "rotor speeds go after --speeds"),
])
def test_fanplot_bad_input_is_one_line(tmp_path, args, message):
    res = CliRunner().invoke(main, ["fanplot", *args, "--out", str(tmp_path / "f.nc")])
    assert res.exit_code == 2 and message in res.output
    assert "Traceback" not in res.output


def test_blade_steady_spin_at_every_default_speed():
    """The twisted blade's relative equilibrium converges at each default fan-plot speed
    (from the straight blade Newton sees no centrifugal flap stiffness at first: the solver
    damps large director turns and, failing that, ramps the spin rate)."""
    from solver.equilibrium import Spin, equilibrium
    from studies.blade import DEFAULT_SPEED_RATIOS, articulated_blade
    from studies.uh60a import UH60A

    for omega in UH60A.omega_ref * DEFAULT_SPEED_RATIOS[1:]:
        model, _ = articulated_blade(float(omega))
        eq = equilibrium(model, spin=Spin(float(omega), (0.0, 0.0, 1.0)))
        assert eq.converged, (omega, eq.message)


@pytest.mark.slow
def test_fanplot_command_takes_the_control_system(tmp_path):
    """``--control-system swashplate`` with a soft pitch link (k h² = 1.2e4 N·m/rad, below
    the blade's GJ/L ≈ 1e4 N·m/rad) lowers the torsion branch below the rigid link's (two
    elements, one speed: the parameters' path, not the accuracy, which
    tests/studies/test_swashplate.py checks); a negative stiffness is one line."""
    runner = CliRunner()
    freq = {}
    for name, extra in (("rigid", []), ("link", ["--control-system", "swashplate",
                                                 "--pitch-link-stiffness", "3e5"])):
        out = tmp_path / f"{name}.nc"
        res = runner.invoke(main, ["fanplot", "--speeds", "2.7", "--elements", "2", *extra,
                                   "--out", str(out)])
        assert res.exit_code == 0, res.output
        ds = xr.open_dataset(out)
        freq[name] = float(ds.frequency.values[0, list(ds.mode_label.values).index(
            "torsion 1")])
    assert freq["link"] < 0.9 * freq["rigid"]
    res = runner.invoke(main, ["fanplot", "--pitch-link-stiffness", "-1", "--out",
                               str(tmp_path / "bad.nc")])
    assert res.exit_code == 2 and "Traceback" not in res.output
