"""The sweep's inputs and its surroundings, each refused with one line before any work or made
to work: empty and occupied output paths, worker counts, study sizes and the cost of their
validation, results that come out NaN, parameter ranges whose minimum must run, the output
directory's lock, a scheduler without workers, leftovers of killed writers, the compile notice
and the command-line help.

Nothing here computes more than a few cheap cases: the test model of ``models.py`` and the
collar and pendulum at their smallest settings.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
import os
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import xarray as xr
from click.testing import CliRunner

from pipelines import cli, studyfile
from pipelines import sweep as sweep_module
from pipelines.archive import _WRITER, STATUS_FAILED, STATUS_OK, read_case, stale_temporaries
from pipelines.checks import InputError, max_workers
from pipelines.cluster import SweepError
from pipelines.lock import LOCK_NAME
from pipelines.studyfile import MAX_CASES, StudyError, load_study
from pipelines.sweep import run_sweep
from pipelines.worker import compile_notice, run_case
from studies.parameters import ModelSpec, Output, Param
from studies.registry import register
from tests.pipelines.helpers import one_error_line

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))
models = importlib.import_module("tests.pipelines.models")
MODEL = "tests.pipelines.models:SPEC"


def study_file(path: Path, body: str = "[sweep]\ntuning_order = [2.9, 3.1]\n",
               model: str = MODEL) -> Path:
    path.write_text(f'model = "{model}"\ntitle = "test"\n{body}')
    return path


@pytest.fixture
def no_cases(monkeypatch):
    """Replace the cluster and its cases by a recorder: the sweep computes nothing."""
    ran: list[Any] = []
    monkeypatch.setattr(sweep_module, "_run_cases", lambda *a, **k: ran.append(a))
    return ran


def _refuses_before_work(args: list[str], ran: list[Any]) -> str:
    line = one_error_line(CliRunner().invoke(cli.main, args))
    assert not ran
    return line


# --- output paths -------------------------------------------------------------------------------


@pytest.mark.parametrize("command", ["sweep", "run", "plot", "collar", "pendulum", "fanplot"])
def test_empty_out_is_refused(tmp_path, monkeypatch, no_cases, command):
    monkeypatch.chdir(tmp_path)
    study = study_file(tmp_path / "s.toml")
    args = {"sweep": ["sweep", str(study)], "run": ["run"], "plot": ["plot", "a.nc"],
            "collar": ["collar", "--curve", "circle", "--theta0", "20"],
            "pendulum": ["pendulum", "--amplitude", "5"], "fanplot": ["fanplot"]}[command]
    line = _refuses_before_work([*args, "--out", ""], no_cases)
    assert "--out" in line and "empty path" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_empty_out_is_refused_by_the_api(tmp_path, no_cases):
    with pytest.raises(InputError, match="--out '': an empty path"):
        run_sweep(study_file(tmp_path / "s.toml"), "", progress=False)


@pytest.mark.parametrize("blocker", ["archive.nc", "cases"])
def test_occupied_archive_or_cases_path_is_refused_before_any_case(tmp_path, no_cases,
                                                                    blocker):
    out = tmp_path / "out"
    out.mkdir()
    if blocker == "archive.nc":
        (out / blocker).mkdir()  # a folder where the archive goes
    else:
        (out / blocker).write_text("a file where the case files go")
    line = _refuses_before_work(["sweep", str(study_file(tmp_path / "s.toml")), "--out",
                                 str(out)], no_cases)
    assert blocker in line and "--out" in line
    assert not (out / LOCK_NAME).exists()


# --- workers and the size of a study ----------------------------------------------------------


@pytest.mark.parametrize("workers", ["100000", str(max_workers() + 1), "0"])
def test_too_many_or_no_workers_are_refused(tmp_path, no_cases, workers):
    line = _refuses_before_work(["sweep", str(study_file(tmp_path / "s.toml")), "--out",
                                 str(tmp_path / "out"), "--workers", workers], no_cases)
    assert "--workers" in line and workers in line
    if workers != "0":
        assert f"[1, {max_workers()}]" in line and "per CPU core" in line
    assert not (tmp_path / "out").exists()


def test_too_many_workers_are_refused_by_the_api(tmp_path, no_cases):
    with pytest.raises(InputError, match="--workers 100000: outside the valid range"):
        run_sweep(study_file(tmp_path / "s.toml"), tmp_path / "out", workers=100000)


def test_a_study_above_the_case_limit_is_refused_before_expanding(tmp_path, monkeypatch):
    values = ", ".join(f"{2.0 + 0.001 * i:.3f}" for i in range(1000))
    scales = ", ".join(f"{0.5 + 0.001 * i:.3f}" for i in range(1000))
    path = study_file(tmp_path / "big.toml",
                      f"[sweep]\ntuning_order = [{values}]\nfuselage_stiffness_scale = "
                      f"[{scales}]\n")

    def no_cases_made(*args: Any) -> Any:
        raise AssertionError("cases were expanded")

    monkeypatch.setattr(studyfile, "make_case_id", no_cases_made)
    with pytest.raises(StudyError) as info:
        load_study(path)
    message = str(info.value)
    assert "1000000 cases" in message and f"limit of {MAX_CASES}" in message
    assert "1000 tuning_order x 1000 fuselage_stiffness_scale" in message


def test_ten_thousand_cases_validate_each_value_once(tmp_path, monkeypatch):
    """10^4 cases: every swept value is type- and range-checked once, and the model's
    cross-check (here: the pin fits its hole) runs once per combination of the values it
    reads, not once per case."""
    cross_checks: list[Any] = []

    def counted_check(p: Any) -> None:
        cross_checks.append(1)
        models.check(p)

    spec = dataclasses.replace(models.SPEC, name="pipeline-test-counted", check=counted_check)
    register(spec)
    value_checks: list[str] = []
    original = Param.check

    def counted(self: Param, name: str, value: Any) -> Any:
        value_checks.append(name)
        return original(self, name, value)

    monkeypatch.setattr(Param, "check", counted)
    orders = ", ".join(f"{2.0 + 0.01 * i:.2f}" for i in range(100))
    scales = ", ".join(f"{0.5 + 0.01 * i:.2f}" for i in range(100))
    study = load_study(study_file(
        tmp_path / "s.toml", f"[fixed]\nhub_speed = 27.0\n[sweep]\ntuning_order = [{orders}]\n"
        f"fuselage_stiffness_scale = [{scales}]\n", model=spec.name))
    assert len(study.cases) == 10_000
    assert sorted(set(value_checks)) == ["fuselage_stiffness_scale", "hub_speed",
                                         "tuning_order"]
    assert len(value_checks) <= 201
    assert len(cross_checks) == 1
    assert study.cases[-1].params["tuning_order"] == 2.99


def test_a_cross_check_still_refuses_each_bad_combination(tmp_path):
    path = study_file(tmp_path / "s.toml", "[fixed]\nhole_diameter = 0.03\n[sweep]\n"
                      "tuning_order = [2.9, 3.0, 3.1]\npin_diameter = [0.01, 0.02, 0.04]\n")
    with pytest.raises(StudyError, match=r"pin_diameter = 0\.04 m must be smaller than "
                                         r"hole_diameter = 0\.03 m"):
        load_study(path)


# --- results that come out NaN, and ranges whose minimum runs ---------------------------------


def _nan_run(p: Any) -> xr.Dataset:
    value = math.nan if p["broken"] else 1.0
    return NAN_SPEC.dataset({"value": value, "fine": 2.0})


NAN_SPEC = ModelSpec("pipeline-test-nan", {"broken": Param(True, "1", "return NaN")}, _nan_run,
                     outputs={"value": Output("m", "a result", dims=()),
                              "fine": Output("m", "another result", dims=())})


def test_a_nan_output_makes_the_case_failed_and_names_it(tmp_path):
    model = "tests.pipelines.test_sweep_inputs:NAN_SPEC"
    out = run_case(model, {"broken": True}, str(tmp_path / "a.nc"))
    assert out["status"] == STATUS_FAILED
    assert "value" in out["message"] and "NaN" in out["message"]
    assert "fine" not in out["message"]
    assert read_case(tmp_path / "a.nc").attrs["status"] == STATUS_FAILED
    assert run_case(model, {"broken": False}, str(tmp_path / "b.nc"))["status"] == STATUS_OK


@pytest.mark.parametrize(("model", "given"), [
    ("collar", {"curve": "circle", "theta0": 20.0}),
    ("collar", {"curve": "cycloid", "theta0": 60.0}),
    ("pendulum", {"hole": "circle"}),
    ("pendulum", {"hole": "epicycloid"}),
])
def test_the_smallest_valid_run_gives_finite_results(tmp_path, model, given):
    """``periods`` and ``steps_per_period`` at their minimum (and the smallest amplitude
    above the excluded 0): the period is measured, nothing is NaN."""
    from studies.registry import get_model

    spec = get_model(model)
    lows = {name: spec.parameters[name].minimum for name in ("periods", "steps_per_period")}
    if model == "pendulum":
        lows["amplitude"] = 1.0
    params = spec.complete({**given, **lows})
    out = run_case(model, params, str(tmp_path / "c.nc"))
    assert out["status"] == STATUS_OK, out["message"]


def test_zero_amplitude_is_outside_the_pendulums_range():
    from studies.bifilar import SPEC
    from studies.parameters import ParameterError

    with pytest.raises(ParameterError, match=r"amplitude = 0 degree: outside the valid range "
                                             r"\(0, 60\]"):
        SPEC.complete({"amplitude": 0.0})


def test_the_hub_runs_at_its_fewest_steps_per_revolution(tmp_path):
    from studies.hub import SPEC

    low = SPEC.parameters["steps_per_rev"].minimum
    out = run_case("hub", SPEC.complete({"steps_per_rev": low}), str(tmp_path / "h.nc"))
    assert out["status"] == STATUS_OK, out["message"]


# --- the output directory's lock ----------------------------------------------------------------


def _lock(out: Path, pid: int, host: str | None = None) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    path = out / LOCK_NAME
    path.write_text(json.dumps({"pid": pid, "host": host or socket.gethostname(),
                                "started": "2026-01-01T00:00:00+00:00",
                                "command": "bifilar sweep other.toml --out out"}))
    return path


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_a_running_sweep_holds_the_lock(tmp_path, monkeypatch):
    seen: list[dict[str, Any]] = []

    def look(*args: Any, **kwargs: Any) -> None:
        seen.append(json.loads((tmp_path / "out" / LOCK_NAME).read_text()))

    monkeypatch.setattr(sweep_module, "_run_cases", look)
    run_sweep(study_file(tmp_path / "s.toml"), tmp_path / "out", progress=False,
              command="bifilar sweep s.toml --out out")
    assert seen and seen[0]["pid"] == os.getpid()
    assert seen[0]["command"] == "bifilar sweep s.toml --out out"
    assert not (tmp_path / "out" / LOCK_NAME).exists()  # released at the end


def test_a_live_lock_refuses_a_second_sweep(tmp_path, no_cases):
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        lock = _lock(tmp_path / "out", other.pid)
        line = _refuses_before_work(["sweep", str(study_file(tmp_path / "s.toml")), "--out",
                                     str(tmp_path / "out")], no_cases)
    finally:
        other.kill()
        other.wait()
    assert "another sweep" in line and f"process {other.pid}" in line and str(lock) in line
    assert lock.exists()  # not ours to remove


def test_another_hosts_lock_is_not_taken(tmp_path, no_cases):
    _lock(tmp_path / "out", 1, host="some-other-node")
    line = _refuses_before_work(["sweep", str(study_file(tmp_path / "s.toml")), "--out",
                                 str(tmp_path / "out")], no_cases)
    assert "some-other-node" in line


def test_a_stale_lock_is_taken_over_with_a_line(tmp_path, no_cases):
    pid = _dead_pid()
    _lock(tmp_path / "out", pid)
    result = CliRunner().invoke(cli.main, ["sweep", str(study_file(tmp_path / "s.toml")),
                                           "--out", str(tmp_path / "out")])
    assert result.exit_code == 1, result.output  # ran (nothing computed: cases not run)
    assert no_cases
    assert f"taking over the stale lock {tmp_path / 'out' / LOCK_NAME}" in result.stderr
    assert f"process {pid} on {socket.gethostname()} no longer runs" in result.stderr
    assert not (tmp_path / "out" / LOCK_NAME).exists()


def test_an_empty_lock_is_being_written_unless_it_is_old(tmp_path, no_cases):
    """A lock file without its owner: one being created right now is respected, one older
    than a writer needs (its writer died between creating and filling it) is taken over."""
    out = tmp_path / "out"
    out.mkdir()
    lock = out / LOCK_NAME
    lock.touch()
    study = str(study_file(tmp_path / "s.toml"))
    line = _refuses_before_work(["sweep", study, "--out", str(out)], no_cases)
    assert "creating the lock file now" in line
    old = lock.stat().st_mtime - 3600
    os.utime(lock, (old, old))
    result = CliRunner().invoke(cli.main, ["sweep", study, "--out", str(out)])
    assert result.exit_code == 1, result.output  # ran (nothing computed)
    assert "an unfinished lock file" in result.stderr and not lock.exists()


# --- a scheduler without workers ----------------------------------------------------------------


def test_a_scheduler_without_workers_is_announced_then_times_out(tmp_path):
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=True, dashboard_address=None,
                      host="127.0.0.1", scheduler_port=0) as cluster:
        result = CliRunner().invoke(cli.main, [
            "sweep", str(study_file(tmp_path / "s.toml")), "--out", str(tmp_path / "out"),
            "--scheduler", cluster.scheduler_address, "--worker-timeout", "1"])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert any("has no workers yet; waiting up to 1 s" in line for line in lines), lines
    assert lines[-1].startswith("error: no dask worker joined the scheduler at "), lines
    assert "Traceback" not in result.output
    assert not list((tmp_path / "out" / "cases").glob("*.nc"))
    assert not (tmp_path / "out" / LOCK_NAME).exists()


def test_worker_timeout_must_be_positive(tmp_path, no_cases):
    line = _refuses_before_work(["sweep", str(study_file(tmp_path / "s.toml")), "--out",
                                 str(tmp_path / "out"), "--worker-timeout", "0"], no_cases)
    assert "--worker-timeout" in line


def test_sweep_waits_for_workers_in_the_api(tmp_path):
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=True, dashboard_address=None,
                      host="127.0.0.1", scheduler_port=0) as cluster, \
            pytest.raises(SweepError, match=r"within 0\.5 s"):
        run_sweep(study_file(tmp_path / "s.toml"), tmp_path / "out",
                  scheduler=cluster.scheduler_address, worker_timeout=0.5, progress=False)


# --- leftovers of killed writers ----------------------------------------------------------------


def test_stale_archive_temporaries_are_removed_at_the_next_write(tmp_path, no_cases):
    out = tmp_path / "out"
    out.mkdir()
    dead = out / f".archive.{_WRITER}.{_dead_pid()}.abc123.tmp"
    unnamed = out / ".archive.k2j3h4.tmp"  # a writer that did not name itself
    mine = out / f".archive.{_WRITER}.{os.getpid()}.zzz999.tmp"
    live_proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    live = out / f".archive.{_WRITER}.{live_proc.pid}.def456.tmp"
    remote = out / ".archive.other-node.1234.ghi789.tmp"
    try:
        for path in (dead, unnamed, mine, live, remote):
            path.write_bytes(b"half a netCDF file")
        assert stale_temporaries(out, "archive") == sorted([dead, unnamed, mine])
        run_sweep(study_file(tmp_path / "s.toml"), out, progress=False)
    finally:
        live_proc.kill()
        live_proc.wait()
    assert (out / "archive.nc").exists()
    left = sorted(p.name for p in out.glob(".archive.*"))
    assert left == sorted([live.name, remote.name])


# --- the compile notice -------------------------------------------------------------------------


def test_compiling_kernels_is_announced_once():
    numba = pytest.importorskip("numba")

    @numba.njit(cache=False)
    def twice(x: float) -> float:
        return 2.0 * x

    @numba.njit(cache=False)
    def thrice(x: float) -> float:
        return 3.0 * x

    lines: list[str] = []
    with compile_notice(lines.append):
        assert twice(1.0) == 2.0 and thrice(1.0) == 3.0
    assert len(lines) == 1 and lines[0].startswith("compiling kernels (first run only")
    lines.clear()
    with compile_notice(lines.append):
        twice(2.0)  # compiled already: nothing to say
    assert lines == []


def test_run_case_passes_the_compile_notice_to_its_progress(tmp_path, monkeypatch):
    numba = pytest.importorskip("numba")

    @numba.njit(cache=False)
    def kernel(x: float) -> float:
        return x + 1.0

    def run(p: Any) -> xr.Dataset:
        return NAN_SPEC.dataset({"value": kernel(1.0), "fine": 2.0})

    spec = ModelSpec("pipeline-test-compiles", NAN_SPEC.parameters, run,
                     outputs=NAN_SPEC.outputs)
    register(spec)
    lines: list[str] = []
    out = run_case(spec.name, {"broken": False}, str(tmp_path / "k.nc"), progress=lines.append)
    assert out["status"] == STATUS_OK, out["message"]
    assert any(line.startswith("compiling kernels") for line in lines), lines


# --- command-line help --------------------------------------------------------------------------


@pytest.mark.parametrize(("command", "choices"), [
    ("collar", ["[circle|cycloid]", "[ep|ed|galpha]"]),
    ("pendulum", ["[circle|cycloid|epicycloid]", "[ep|ed|galpha]"]),
])
def test_help_lists_choices_and_says_dimensionless(command, choices):
    result = CliRunner().invoke(cli.main, [command, "--help"], terminal_width=200)
    assert result.exit_code == 0
    text = " ".join(result.output.split())
    for choice in choices:
        assert choice in text, choice
    assert "(dimensionless)" in text and "(1)" not in text


def test_a_range_message_says_dimensionless(tmp_path):
    line = one_error_line(CliRunner().invoke(cli.main, [
        "collar", "--curve", "circle", "--theta0", "20", "--periods", "1.5",
        "--out", str(tmp_path / "c.nc")]))
    assert "periods = 1.5: outside the valid range [2, 1000] (dimensionless)" in line


def test_a_choice_outside_the_list_is_one_line(tmp_path):
    line = one_error_line(CliRunner().invoke(cli.main, [
        "collar", "--curve", "ellipse", "--theta0", "20", "--out", str(tmp_path / "c.nc")]))
    assert "--curve" in line and "ellipse" in line and "circle" in line



@pytest.mark.slow
def test_the_rotor_runs_at_its_fewest_steps_per_revolution(tmp_path):
    """Fewer steps than the minimum make the rotor's Newton matrix singular within its first
    revolution (64-112 measured); the minimum itself runs the free case."""
    from studies.rotor import SPEC

    low = SPEC.parameters["steps_per_rev"].minimum
    out = run_case("rotor", SPEC.complete({"steps_per_rev": low}), str(tmp_path / "r.nc"))
    assert out["status"] == STATUS_OK, out["message"]
