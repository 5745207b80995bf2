"""Branches of periodic responses through the pipeline: the study file's ``[continuation]``
table, branch cases on a dask cluster, the archive's ``point`` dimension (NaN-padded), resume,
and the response-curve figures (stable solid, unstable dashed, folds marked).

The model is the Duffing oscillator of ``tests/pipelines/models.py`` (``DUFFING_SPEC``): its
one-harmonic balance is in closed form along the frequency-response curve, so the branch's
folds and its unstable middle part are known exactly.
"""

from __future__ import annotations

import importlib
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

import pipelines.plots as plots
from pipelines import cli
from pipelines.archive import STATUS_FAILED, STATUS_OK, open_archive, read_case
from pipelines.studyfile import StudyError, load_study, make_case_id, model_version
from pipelines.sweep import run_sweep
from pipelines.worker import run_case

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))
models = importlib.import_module("tests.pipelines.models")
MODEL = "tests.pipelines.models:DUFFING_SPEC"
PARAMETER = "forcing_frequency"

CONTINUATION = """
[continuation]
parameter = "forcing_frequency"
start = 0.5
stop = 2.0
step = 0.05
"""
# a hardening branch with two folds, and a linear one (no fold) of another length
CASES = """
[[cases]]
name = "hardening"
cubic_stiffness = 0.1
[[cases]]
name = "linear"
cubic_stiffness = 0.0
"""


def write_study(path: Path, body: str, model: str = MODEL) -> Path:
    path.write_text(f'model = "{model}"\ntitle = "branches"\n{body}')
    return path


@pytest.fixture(scope="module")
def branches(scheduler, tmp_path_factory) -> tuple[Path, Path, Path]:
    """Two branch cases swept on the cluster: (study, archive, run log)."""
    tmp = tmp_path_factory.mktemp("branches")
    log = tmp / "runs.log"
    study = write_study(tmp / "study.toml",
                        f'[fixed]\nrun_log = "{log}"\n{CONTINUATION}{CASES}')
    archive = run_sweep(study, tmp / "out", scheduler=scheduler, progress=False)
    return study, archive, log


# --- study files --------------------------------------------------------------------------------


BAD = {
    "model without branch": (
        CONTINUATION + "[sweep]\ntuning_order = [3.0]\n", "tests.pipelines.models:SPEC",
        r"\[continuation\]: model 'pipeline-test-2dof' cannot follow a branch.*models that can"),
    "not a table": ("continuation = 3\n[sweep]\ncubic_stiffness = [0.1]\n", MODEL,
                    r"\[continuation\] must be a table"),
    "unknown key": (CONTINUATION + "stepp = 0.1\n" + CASES, MODEL,
                    r"\[continuation\]: unknown key\(s\) stepp"),
    "missing stop": ('[continuation]\nparameter = "forcing_frequency"\nstart = 0.5\n' + CASES,
                     MODEL, r"\[continuation\]: stop is required"),
    "string parameter": (
        '[continuation]\nparameter = "run_log"\nstart = 0.5\nstop = 1.0\n' + CASES, MODEL,
        r"parameter = 'run_log' is not a numeric \(float\) parameter.*numeric ones: "),
    "start out of range": (CONTINUATION.replace("start = 0.5", "start = 20.0") + CASES, MODEL,
                           r"start of forcing_frequency = 20: outside the valid range"),
    "start is stop": (CONTINUATION.replace("stop = 2.0", "stop = 0.5") + CASES, MODEL,
                      r"start = stop = 0.5"),
    "too few points": (CONTINUATION + "max_points = 1\n" + CASES, MODEL,
                       r"max_points = 1 must be in \[2, 10000\]"),
    "unknown method": (CONTINUATION + 'method = "newton"\n' + CASES, MODEL,
                       r"method = 'newton' must be one of auto, harmonic_balance, shooting"),
    "step above max_step": (CONTINUATION.replace("step = 0.05", "step = 0.5\nmax_step = 0.1")
                            + CASES, MODEL, r"min_step <= step <= max_step"),
    "continued parameter swept": (
        CONTINUATION + "[sweep]\nforcing_frequency = [1.0, 1.5]\n", MODEL,
        r"\[sweep\]: 'forcing_frequency' is the continued parameter of \[continuation\]"),
    "continued parameter in a case": (
        CONTINUATION + '[[cases]]\nname = "a"\nforcing_frequency = 1.0\n', MODEL,
        r"case 'a': 'forcing_frequency' is the continued parameter"),
    "continued parameter fixed": (
        "[fixed]\nforcing_frequency = 0.5\n" + CONTINUATION + CASES, MODEL,
        r"parameter = 'forcing_frequency' is also in \[fixed\]"),
}


@pytest.mark.parametrize(("body", "model", "match"), BAD.values(), ids=BAD.keys())
def test_bad_continuation_is_refused_with_one_line(tmp_path, body, model, match):
    path = write_study(tmp_path / "bad.toml", body, model)
    with pytest.raises(StudyError, match=match) as info:
        load_study(path)
    assert "\n" not in str(info.value)
    assert str(path) in str(info.value)


def test_continuation_is_part_of_the_case_id(tmp_path):
    """Each case starts its branch at ``start``; the settings are in its id, so a changed
    table computes the branches again, and the settings travel with the study."""
    study = load_study(write_study(tmp_path / "a.toml", CONTINUATION + CASES))
    longer = load_study(write_study(tmp_path / "b.toml",
                                    CONTINUATION.replace("stop = 2.0", "stop = 2.5") + CASES))
    assert all(c.params[PARAMETER] == 0.5 for c in study.cases)
    assert [c.params for c in study.cases] == [c.params for c in longer.cases]
    assert not {c.case_id for c in study.cases} & {c.case_id for c in longer.cases}
    version = model_version(study.spec)
    # the same parameters without a [continuation] are another case
    assert study.cases[0].case_id != make_case_id(study.spec.name, study.cases[0].params,
                                                  version)
    assert study.continuation_dict == {
        "parameter": PARAMETER, "start": 0.5, "stop": 2.0, "step": 0.05,
        "min_step": pytest.approx(1.5e-5), "max_step": pytest.approx(0.15), "max_points": 200,
        "method": "auto"}
    coords, constants = study.archive_coords()
    assert PARAMETER not in coords and PARAMETER not in constants


@settings(max_examples=40, deadline=None)
@given(start=st.floats(-20, 20, allow_nan=False), stop=st.floats(-20, 20, allow_nan=False))
def test_continuation_range_loads_or_says_why(start, stop):
    """Any start and stop: a valid pair loads with every case at start; any other is refused
    with one line naming the key and the valid range."""
    body = (f'[continuation]\nparameter = "forcing_frequency"\nstart = {start!r}\n'
            f"stop = {stop!r}\n" + CASES)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_study(Path(tmp) / "s.toml", body)
        valid = all(0.0 < v <= 10.0 for v in (start, stop)) and start != stop
        if valid:
            study = load_study(path)
            assert all(c.params[PARAMETER] == start for c in study.cases)
            return
        with pytest.raises(StudyError) as info:
            load_study(path)
    message = str(info.value)
    assert "\n" not in message and "[continuation]" in message
    assert "valid range" in message or "start = stop" in message


# --- the worker ---------------------------------------------------------------------------------


def _continuation(**changes) -> dict:
    study_settings = {"parameter": PARAMETER, "start": 0.5, "stop": 2.0, "step": 0.05,
                      "min_step": 1e-5, "max_step": 0.15, "max_points": 200, "method": "auto"}
    return {**study_settings, **changes}


@pytest.mark.parametrize(("fail", "match"), [
    ("raise", "RuntimeError: branch failure requested by the test"),
    ("empty", "has no points"),
])
def test_failed_branch_is_a_failed_case(tmp_path, fail, match):
    params = models.DUFFING_SPEC.complete({PARAMETER: 0.5, "branch_fail": fail})
    result = run_case(MODEL, params, str(tmp_path / "c.nc"), continuation=_continuation())
    assert result["status"] == STATUS_FAILED
    assert match in result["message"]
    assert read_case(tmp_path / "c.nc").attrs["message"] == result["message"]


def test_branch_ended_early_keeps_its_message(tmp_path):
    params = models.DUFFING_SPEC.complete({PARAMETER: 0.5})
    result = run_case(MODEL, params, str(tmp_path / "c.nc"),
                      continuation=_continuation(max_points=20))
    assert result["status"] == STATUS_OK
    assert result["message"].startswith("branch ended at 20 points (max_points)")
    case = read_case(tmp_path / "c.nc")
    assert case.sizes["point"] == 20
    assert case[PARAMETER].attrs["units"] == "1"
    assert case["stable"].dtype == np.int8


# --- sweep and archive --------------------------------------------------------------------------


def test_branch_archive_layout(branches):
    _, path, _ = branches
    ds = open_archive(path)
    assert ds["status"].dims == ("case",) and (ds["status"] == STATUS_OK).all()
    assert list(ds["case_name"].values) == ["hardening", "linear"]
    # the continued parameter per point (with its declaration), never a case coordinate
    param = models.DUFFING_PARAMETERS[PARAMETER]
    assert ds[PARAMETER].dims == ("case", "point")
    assert ds[PARAMETER].attrs["units"] == param.units
    assert ds[PARAMETER].attrs["long_name"] == param.long_name
    for name in ("stable", "fold", "floquet_multiplier_max", "displacement_amplitude",
                 "response_amplitude"):
        assert ds[name].dims[:2] == ("case", "point"), name
    for name, var in ds.variables.items():
        assert var.attrs.get("units") and var.attrs.get("long_name"), name

    lengths = [int(np.isfinite(ds[PARAMETER].isel(case=i)).sum()) for i in range(2)]
    assert ds.sizes["point"] == max(lengths) and lengths[0] != lengths[1]
    short = int(np.argmin(lengths))
    tail = ds.isel(case=short, point=slice(lengths[short], None))
    for name in (PARAMETER, "stable", "fold", "floquet_multiplier_max",
                 "displacement_amplitude"):
        assert np.isnan(tail[name].values).all(), name
    # stored as int8 flags with the fill value -1 in the padding
    with xr.open_dataset(path, mask_and_scale=False) as raw:
        assert raw["stable"].dtype == np.int8 and raw["stable"].attrs["_FillValue"] == -1
        assert raw["fold"].dtype == np.int8
        assert list(raw["stable"].attrs["flag_values"]) == [0, 1]
        assert (raw["stable"].values[short, lengths[short]:] == -1).all()

    for i, label in enumerate(ds["case_name"].values):
        case = ds.isel(case=i, point=slice(0, lengths[i]))
        omega = case[PARAMETER].values
        assert omega[0] == pytest.approx(0.5, abs=1e-3)
        assert omega[-1] == pytest.approx(2.0, abs=1e-2)
        # the 1P amplitude of the recorded response is the balance's amplitude
        np.testing.assert_allclose(case["displacement_amplitude"].sel(harmonic=1),
                                   case["response_amplitude"], rtol=1e-12)
        stable = case["stable"].values == 1
        folds = np.flatnonzero(case["fold"].values == 1)
        multiplier = case["floquet_multiplier_max"].values
        assert ((multiplier > 1) == ~stable).all()
        if label == "linear":
            assert stable.all() and folds.size == 0
            continue
        # hardening: two folds, the first at the larger frequency; unstable between them
        assert folds.size == 2 and omega[folds[0]] > omega[folds[1]]
        assert multiplier[folds] == pytest.approx(1.0)
        assert (~stable[folds[0] + 1:folds[1]]).all()
        assert stable[:folds[0] + 1].all() and stable[folds[1]:].all()


def test_resume_does_not_recompute_branches(branches, scheduler, capsys):
    study, path, log = branches
    before = log.read_text().count("\n")
    assert before == 2
    run_sweep(study, path.parent, scheduler=scheduler)
    assert log.read_text().count("\n") == before
    assert "2 of 2 case(s) already finished" in capsys.readouterr().err
    assert open_archive(path).sizes["point"] == open_archive(path)[PARAMETER].shape[1]


# --- figures ------------------------------------------------------------------------------------


def test_plot_draws_response_curves(branches, tmp_path):
    _, path, _ = branches
    result = CliRunner().invoke(cli.main, ["plot", str(path), "--out", str(tmp_path),
                                           "--format", "png"])
    assert result.exit_code == 0, result.output
    names = {Path(line).name for line in result.stdout.splitlines()}
    assert names == {f"{stem}_vs_{PARAMETER}.png" for stem in (
        "harmonics_displacement", "harmonics_velocity", "results",
        "floquet_multiplier_max")}
    assert all((tmp_path / name).stat().st_size > 1000 for name in names)


def test_unstable_parts_are_dashed_and_folds_marked(branches, monkeypatch, tmp_path):
    _, path, _ = branches
    drawn = {}

    def keep(fig, out_dir, stem, formats):
        drawn[stem] = fig
        return [out_dir / f"{stem}.png"]

    monkeypatch.setattr(plots, "_save", keep)
    plots.plot_archive(path, tmp_path)
    ds = open_archive(path)
    hard = ds.isel(case=0)
    omega = hard[PARAMETER].values
    folds = np.flatnonzero(hard["fold"].values == 1)
    low, high = sorted(omega[folds])
    for stem in (f"harmonics_displacement_vs_{PARAMETER}",
                 f"floquet_multiplier_max_vs_{PARAMETER}"):
        ax = drawn[stem].axes[0]
        # the dominant harmonic first: 1P
        assert ax.get_title().startswith("1P") or stem.startswith("floquet")
        dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
        # only the hardening branch has an unstable part: one dashed run between its folds
        assert len(dashed) == 1
        x = dashed[0].get_xdata()
        assert low - 1e-12 <= x.min() and x.max() <= high + 1e-12
        marks = [line for line in ax.get_lines() if line.get_marker() == "x"]
        assert len(marks) == 1 and sorted(marks[0].get_xdata()) == pytest.approx([low, high])
    floquet = drawn[f"floquet_multiplier_max_vs_{PARAMETER}"].axes[0]
    assert any(list(line.get_ydata()) == [1.0, 1.0] for line in floquet.get_lines())
    legend = [t.get_text() for t in drawn[f"results_vs_{PARAMETER}"].legends[0].get_texts()]
    assert legend == ["hardening", "linear", "stable", "unstable", "fold"]


@pytest.mark.slow
def test_the_jump_study(tmp_path):
    """`bifilar run --study jump`: the circle's branch folds twice, the cycloid's and the
    epicycloid's not; each case archives its backbone; the figures are drawn."""
    from click.testing import CliRunner

    from pipelines import cli
    from pipelines.archive import open_archive

    result = CliRunner().invoke(cli.main, ["run", "--study", "jump", "--out", str(tmp_path),
                                           "--workers", "2"])
    assert result.exit_code == 0, result.output
    ds = open_archive(tmp_path / "archive.nc")
    names = [str(n) for n in ds["case_name"].values] if "case_name" in ds else None
    folds = ds["fold"].fillna(0).sum("point").values
    assert list(folds) == [2, 0, 0], (names, folds)
    order = ds["backbone_order"]
    assert order.dims[-1] == "backbone_amplitude"
    # softening circle, hardening cycloid, isochronous epicycloid (2.95P tuning)
    last = order.isel(backbone_amplitude=-1).values
    assert last[0] < 2.7 and last[1] > 2.97 and abs(last[2] - 2.95) < 1e-3
    stems = {p.stem for p in (tmp_path / "plots").iterdir()}
    assert {"backbones", "floquet_multiplier_max_vs_excitation_3p",
            "harmonics_pin_angle_vs_excitation_3p"} <= stems
