"""Every input checked before any work, and archives that pass the CF checker.

* property-based (hypothesis): random study files through :func:`load_study`, random command
  lines through ``bifilar collar``, ``bifilar pendulum`` and ``bifilar sweep`` (with the model
  runs and the cluster replaced by recorders, so nothing is computed): the answer is exit status
  2 with one ``error:`` line naming the parameter or option, or a run with exactly the values
  given; never a traceback, never silently other values;
* plausibility ranges on every declared parameter, cross-parameter geometry, output paths,
  scheduler addresses;
* archives and case files: ``cfchecks`` finds no error and no warning; files get the umask's
  permissions; case ids change with the model version.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import math
import os
import re
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pipelines import cli, study_commands
from pipelines import sweep as sweep_module
from pipelines.archive import open_archive, write_case
from pipelines.checks import InputError, check_scheduler_address
from pipelines.cluster import dashboard_works
from pipelines.single import fail
from pipelines.studyfile import StudyError, load_study, make_case_id, model_version
from pipelines.sweep import consolidate_study
from pipelines.worker import run_case
from studies import bifilar, collar, hub
from studies.parameters import Param, ParameterError
from tests.pipelines.helpers import one_error_line

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))
models = importlib.import_module("tests.pipelines.models")
MODEL = "tests.pipelines.models:SPEC"
CF_TABLES = Path(__file__).parent / "data" / "cf"

SPECS = {"hub": hub.SPEC, "pendulum": bifilar.SPEC, "collar": collar.SPEC}
FAST = settings(max_examples=100, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])


# --- declarations -------------------------------------------------------------------------------


@pytest.mark.parametrize("model", SPECS)
def test_every_numeric_parameter_has_a_plausible_range(model):
    for name, param in SPECS[model].parameters.items():
        if param.kind in (int, float):
            assert param.minimum is not None and param.maximum is not None, name
            assert param.minimum <= param.default <= param.maximum, name


@pytest.mark.parametrize(("model", "given", "names"), [
    ("hub", {"tuning_mass": 1e300}, ["tuning_mass"]),
    ("hub", {"hub_speed": 1e300}, ["hub_speed"]),
    ("hub", {"steps_per_rev": math.nan}, ["steps_per_rev"]),
    ("hub", {"steps_per_rev": math.inf}, ["steps_per_rev"]),
    ("hub", {"fuselage_stiffness": 1e300}, ["fuselage_stiffness"]),
    ("hub", {"pin_diameter": 0.5}, ["pin_diameter", "arm_radius"]),
    ("pendulum", {"pin_diameter": 0.5, "arm_radius": 0.4}, ["pin_diameter", "arm_radius"]),
    ("pendulum", {"hole_diameter": 0.6}, ["hole_diameter", "arm_radius"]),
    ("pendulum", {"pin_mass": 0.0, "pin_inertia": 1e-3}, ["pin_inertia", "pin_mass"]),
    ("hub", {"tuning_order": 0.6}, ["tuning_order", "arm_radius"]),
    ("collar", {"curve": "cycloid", "theta0": 95.0}, ["theta0"]),
    ("collar", {"periods": 1e300}, ["periods"]),
])
def test_implausible_values_and_geometry_are_refused(model, given, names):
    with pytest.raises(ParameterError) as info:
        SPECS[model].complete(given)
    message = str(info.value)
    assert "\n" not in message
    for name in names:
        assert name in message, (name, message)


def test_empty_case_table_is_refused(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('model = "hub"\n[[cases]]\nname = "a"\ntuning_order = 3.0\n[[cases]]\n')
    with pytest.raises(StudyError, match=r"\[\[cases\]\] number 2 is empty"):
        load_study(path)


@pytest.mark.parametrize("address", ["foo", "tcp://x:abc", "tcp://:8786", "udp://h:1",
                                     "tcp://h:0", "tcp://h:99999", "tcp://h h:1", ""])
def test_malformed_scheduler_address_is_refused(address):
    with pytest.raises(InputError, match="--scheduler"):
        check_scheduler_address(address)


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "node12:8786", "tls://[::1]:1",
                                     "tcp://node-3.cluster.local:40000"])
def test_scheduler_address_forms(address):
    assert check_scheduler_address(address) == address


# --- output paths: refused before any work ------------------------------------------------------


def _no_work(*args: Any, **kwargs: Any) -> Any:
    raise AssertionError("work started before the output path was checked")


@pytest.fixture
def nothing_runs(monkeypatch):
    monkeypatch.setattr(sweep_module, "_run_cases", _no_work)
    monkeypatch.setattr(study_commands, "_run_and_write", _no_work)
    monkeypatch.setattr(study_commands, "collar_figures", _no_work)
    monkeypatch.setattr(study_commands, "pendulum_figures", _no_work)
    import pipelines.plots

    monkeypatch.setattr(pipelines.plots, "plot_archive", _no_work)


@pytest.mark.parametrize("where", ["below_file", "proc"])
@pytest.mark.parametrize("command", ["run", "sweep", "plot", "collar", "pendulum"])
def test_unwritable_out_fails_before_any_work(tmp_path, nothing_runs, command, where):
    afile = tmp_path / "afile"
    afile.write_text("x")
    study = tmp_path / "s.toml"
    study.write_text(f'model = "{MODEL}"\n[sweep]\ntuning_order = [3.0]\n')
    archive = tmp_path / "archive.nc"
    archive.write_text("not read")
    file_like = command in ("collar", "pendulum")
    out = (afile / "x.nc" if file_like else afile / "x") if where == "below_file" else (
        Path("/proc/bifilar-test.nc") if file_like else Path("/proc/bifilar-test"))
    args = {
        "run": ["run", "--out", str(out)],
        "sweep": ["sweep", str(study), "--out", str(out)],
        "plot": ["plot", str(archive), "--out", str(out)],
        "collar": ["collar", "--curve", "circle", "--theta0", "20", "--out", str(out)],
        "pendulum": ["pendulum", "--amplitude", "5", "--out", str(out)],
    }[command]
    line = one_error_line(CliRunner().invoke(cli.main, args))
    assert "--out" in line and str(out) in line
    assert not out.exists()


# --- property-based: study files ----------------------------------------------------------------

UNKNOWN_NAMES = ("tunning_order", "speed", "name2")
STRUCTURAL = ("[sweep]", "[[cases]]", "cases", "identical parameters", "empty", "both swept",
              "also in [fixed]", "repeats a value", "must be a list", "must be a string",
              "neither", "not both", "must be a table")


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(value)


def _param_value(param: Param | None) -> st.SearchStrategy[Any]:
    """Valid values of ``param`` mixed with every kind of invalid one."""
    wild = st.one_of(
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(min_value=-(2**63), max_value=2**63 - 1),
        st.sampled_from(["", "free", "circle", "cycloid", "three", "ep"]),
        st.booleans(),
    )
    if param is None:
        return wild
    if param.choices is not None:
        return st.one_of(st.sampled_from(param.choices), wild)
    if param.kind is bool:
        return st.one_of(st.booleans(), wild)
    lo = param.minimum if param.minimum is not None else -1e6
    hi = param.maximum if param.maximum is not None else 1e6
    if param.kind is int:
        valid = st.integers(min_value=math.ceil(lo), max_value=int(min(hi, lo + 400)))
    else:
        valid = st.floats(min_value=lo, max_value=hi, allow_nan=False)
    # the default and valid values most of the time, anything now and then
    return st.one_of(st.just(param.default), valid, valid, wild)


@st.composite
def study_files(draw: Any) -> tuple[str, str, dict[str, Any]]:
    """(model, TOML text, what the file says: fixed, sweep or cases)."""
    model = draw(st.sampled_from(sorted(SPECS)))
    spec = SPECS[model]
    names = st.one_of(st.sampled_from(sorted(spec.parameters)), st.sampled_from(UNKNOWN_NAMES))

    def entries(max_size: int) -> st.SearchStrategy[dict[str, Any]]:
        return st.dictionaries(names, st.deferred(lambda: st.just(None)), max_size=max_size)

    fixed_names = draw(entries(3))
    fixed = {n: draw(_param_value(spec.parameters.get(n))) for n in fixed_names}
    lines = [f'model = "{model}"', 'title = "hypothesis"', "[fixed]"]
    lines += [f"{n} = {_toml_value(v)}" for n, v in fixed.items()]
    layout: dict[str, Any] = {"fixed": fixed}
    if draw(st.booleans()):
        sweep: dict[str, list[Any]] = {}
        for n in draw(entries(2)):
            sweep[n] = draw(st.lists(_param_value(spec.parameters.get(n)), min_size=0,
                                     max_size=3))
        lines.append("[sweep]")
        lines += [f"{n} = {_toml_value(v)}" for n, v in sweep.items()]
        layout["sweep"] = sweep
    else:
        cases = []
        for i in range(draw(st.integers(min_value=0, max_value=3))):
            case = {n: draw(_param_value(spec.parameters.get(n))) for n in draw(entries(2))}
            lines.append("[[cases]]")
            if draw(st.booleans()):
                lines.append(f'name = "case {i}"')
            lines += [f"{n} = {_toml_value(v)}" for n, v in case.items()]
            cases.append(case)
        layout["cases"] = cases
    return model, "\n".join(lines) + "\n", layout


def _same(a: Any, b: Any) -> bool:
    return type(a) is type(b) and a == b


@FAST
@given(study=study_files())
def test_random_study_files_are_refused_in_one_line_or_taken_as_written(tmp_path, study):
    model, text, layout = study
    spec = SPECS[model]
    path = tmp_path / "study.toml"
    path.write_text(text)
    named = set(layout["fixed"]) | set(layout.get("sweep", {}))
    for case in layout.get("cases", []):
        named |= set(case)
    try:
        loaded = load_study(path)
    except StudyError as exc:
        message = str(exc)
        assert "\n" not in message and str(path) in message
        assert any(n in message for n in named) or any(s in message for s in STRUCTURAL), (
            message)
        return
    # accepted: every case holds exactly the file's values, the rest are defaults, all valid
    assert loaded.cases
    for case in loaded.cases:
        assert set(case.params) == set(spec.parameters)
        for name, value in case.params.items():
            assert _same(spec.parameters[name].check(name, value), value), name
        spec.complete(case.params)
    for name, value in layout["fixed"].items():
        for case in loaded.cases:
            checked = spec.parameters[name].check(name, value)
            assert _same(case.params[name], checked), name
    for name, values in layout.get("sweep", {}).items():
        got = sorted({repr(c.params[name]) for c in loaded.cases})
        want = sorted({repr(spec.parameters[name].check(name, v)) for v in values})
        assert got == want, name
    for case, given_case in zip(loaded.cases, layout.get("cases", []), strict=False):
        for name, value in given_case.items():
            assert _same(case.params[name], spec.parameters[name].check(name, value)), name


# --- property-based: command lines --------------------------------------------------------------


def _option_text(value: Any) -> str:
    return str(value) if not isinstance(value, float) else repr(value)


@st.composite
def command_lines(draw: Any) -> tuple[str, list[str], dict[str, str]]:
    command = draw(st.sampled_from(["collar", "pendulum"]))
    params = collar.PARAMETERS if command == "collar" else bifilar.PARAMETERS
    chosen = draw(st.lists(st.sampled_from(sorted(params)), max_size=4, unique=True))
    options: dict[str, str] = {}
    for name in chosen:
        value = draw(st.one_of(
            _param_value(params[name]).map(_option_text),
            st.sampled_from(["abc", "nan", "inf", "-inf", "1e300", "-1", "0", ""]),
        ))
        options[name] = value
    if command == "collar":
        options.setdefault("curve", "circle")
        options.setdefault("theta0", "20")
    else:
        options.setdefault("amplitude", "5")
    out = draw(st.sampled_from(["ok.nc", "afile/x.nc", "/proc/x.nc", "adir"]))
    args = [command]
    for name, value in options.items():
        args += ["--" + name.replace("_", "-"), value]
    return command, [*args, "--out", out], options


@FAST
@given(line=command_lines())
def test_random_command_lines_are_refused_in_one_line_or_run_as_given(tmp_path, line):
    command, args, options = line
    spec = collar.SPEC if command == "collar" else bifilar.SPEC
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir(exist_ok=True)
    runs: list[dict[str, Any]] = []

    def record(spec_: Any, given_: dict[str, Any], out: Path) -> xr.Dataset:
        try:
            params = spec_.complete(given_)
        except ParameterError as exc:
            fail(str(exc))
        runs.append(params)
        return xr.Dataset({k: ((), 1.0) for k in (
            "period", "period_analytic", "period_error", "frequency_order",
            "frequency_order_linear")}, {"jacobi": ("time", [1.0, 1.0])})

    cwd = os.getcwd()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(study_commands, "_run_and_write", record)
        os.chdir(tmp_path)
        try:
            result = CliRunner().invoke(cli.main, args)
        finally:
            os.chdir(cwd)
    if result.exit_code == 0:
        assert len(runs) == 1 and result.exception is None
        for name, text in options.items():
            param = spec.parameters[name]
            want = param.check(name, param.kind(text) if param.kind is not str else text)
            assert _same(runs[0][name], want), (name, text, runs[0][name])
        return
    line = one_error_line(result)
    assert not runs
    assert any(n in line or "--" + n.replace("_", "-") in line for n in options) or (
        "--out" in line), line


@FAST
@given(scheduler=st.one_of(st.none(), st.text(max_size=20),
                           st.sampled_from(["tcp://127.0.0.1:8786", "h:1", "tcp://h:x"])),
       out=st.sampled_from(["out", "afile/x", "/proc/x"]),
       workers=st.sampled_from([None, "0", "1", "two"]))
def test_random_sweep_command_lines(tmp_path, scheduler, out, workers):
    (tmp_path / "afile").write_text("x")
    study = tmp_path / "s.toml"
    study.write_text(f'model = "{MODEL}"\n[sweep]\ntuning_order = [3.0]\n')
    ran: list[Any] = []
    args = ["sweep", str(study), "--out", str(tmp_path / out) if not out.startswith("/") else out]
    if scheduler is not None:
        args += ["--scheduler", scheduler]
    if workers is not None:
        args += ["--workers", workers]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sweep_module, "_run_cases", lambda *a, **k: ran.append(a))
        result = CliRunner().invoke(cli.main, args)
    if result.exit_code == 1:  # ran (nothing computed: the cases are archived as not run)
        assert ran
        assert result.exception is None or isinstance(result.exception, SystemExit)
        assert "not ok" in result.stderr.strip().splitlines()[-1]
        return
    line = one_error_line(result)
    assert not ran
    assert any(s in line for s in ("--scheduler", "--out", "--workers")), line


# --- archives: the CF checker, permissions, case ids --------------------------------------------


def _cf_checker() -> list[str]:
    """The ``cfchecks`` command, or skip with the reason it cannot run."""
    exe = shutil.which("cfchecks")
    if exe is None:
        pytest.skip("cfchecks not installed (pip install cfchecker)")
    try:
        import cfchecker.cfchecks  # noqa: F401  (loads udunits2 through cfunits)
    except Exception as exc:  # OSError, or cfunits' own error when libudunits2 is missing
        pytest.skip(f"the CF checker cannot run here: {type(exc).__name__}: {exc} (it needs the "
                    "udunits2 C library: apt-get install libudunits2-0)")
    return [exe, "-v", "auto", "-s", str(CF_TABLES / "standard-name-table.xml"),
            "-a", str(CF_TABLES / "area-type-table.xml"),
            "-r", str(CF_TABLES / "region-list.xml")]


def _sweep_in_process(tmp_path: Path, text: str) -> Path:
    """A study run case by case in this process (no cluster), consolidated."""
    path = tmp_path / "study.toml"
    path.write_text(text)
    study = load_study(path)
    out = tmp_path / "out"
    for case in study.cases:
        run_case(study.model_ref, case.params, str(case.path(out / "cases")))
    return consolidate_study(study, out, command="test")


CF_STUDIES = {
    "hub layout, string dimension": f"""model = "{MODEL}"
[fixed]
samples_per_rev = 24
[sweep]
bifilar = ["free", "locked"]
tuning_order = [2.9, 3.1]
""",
    "case list with a failed case": f"""model = "{MODEL}"
[[cases]]
name = "0: locked, ü"
bifilar = "locked"
[[cases]]
name = "1: failing"
fail = "raise"
""",
    "pendulum histories": """model = "pendulum"
[fixed]
periods = 2.0
steps_per_period = 16
[sweep]
hole = ["circle", "cycloid"]
""",
}


@pytest.mark.parametrize("text", CF_STUDIES.values(), ids=CF_STUDIES.keys())
def test_archive_and_case_files_pass_the_cf_checker(tmp_path, text):
    checker = _cf_checker()
    archive = _sweep_in_process(tmp_path, text)
    files = [archive, *sorted((archive.parent / "cases").glob("*.nc"))]
    result = subprocess.run([*checker, *map(str, files)], capture_output=True, text=True,
                            timeout=300, cwd=tmp_path)
    report = result.stdout + result.stderr
    assert "Traceback" not in report, report
    assert re.findall(r"ERRORS detected: (\d+)", report) == ["0"] * len(files), report
    assert re.findall(r"WARNINGS given: (\d+)", report) == ["0"] * len(files), report
    # names come back as coordinates when read through the archive API
    ds = open_archive(archive)
    for dim in ds.dims:
        assert dim in ds.coords or dim.startswith("string"), dim
    if "direction" in ds.dims:
        assert list(ds["direction"].values) == ["x", "y"]
        assert "time_in_rev" in ds.coords and ds["time_in_rev"].dtype == np.int32
    if "hole" in ds.dims:
        assert list(ds["hole"].values) == ["circle", "cycloid"]
        assert ds["time"].attrs["standard_name"] == "time"


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o027, 0o640), (0o077, 0o600)])
def test_files_get_the_umask_permissions(tmp_path, umask, mode):
    old = os.umask(umask)
    try:
        path = write_case(xr.Dataset({"x": ((), 1.0)}), tmp_path / "c.nc")
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == mode


def test_case_ids_change_with_the_model_version(tmp_path):
    spec = models.SPEC
    params = spec.complete({})
    bumped = replace(spec, version="2")
    assert model_version(spec) != model_version(bumped)
    assert make_case_id(spec.name, params, model_version(spec)) != make_case_id(
        spec.name, params, model_version(bumped))
    assert "bifilar " in model_version(spec) and spec.name in model_version(spec)
    # the case file records the version it was computed with
    out = run_case(MODEL, params, str(tmp_path / "c.nc"))
    assert out["status"] == 0
    with xr.open_dataset(tmp_path / "c.nc") as ds:
        assert ds.attrs["model_version"] == model_version(spec)


# --- dashboard ----------------------------------------------------------------------------------


def test_dashboard_link_only_when_it_works():
    import urllib.parse
    import urllib.request

    from distributed import Client, LocalCluster

    with (LocalCluster(n_workers=0, processes=False, dashboard_address="127.0.0.1:0") as lc,
          Client(lc) as client):
        works = dashboard_works(client, client.scheduler_info())
        assert works == (importlib.util.find_spec("bokeh") is not None)
        if works:
            # the link names the host's address; the test reads it on the loopback
            port = urllib.parse.urlsplit(client.dashboard_link).port
            with contextlib.closing(urllib.request.urlopen(f"http://127.0.0.1:{port}/status",
                                                           timeout=30)) as page:
                body = page.read().decode(errors="replace")
            assert page.status == 200 and "needs bokeh" not in body
