"""Pipeline tests: harmonics against exact signals, sweeps on a real dask cluster, the archive's
CF layout, failure recording, resume after a kill, study validation, plots and the CLI.

The hub model is not used: ``tests/pipelines/models.py`` is a small model in the same layout with
a closed-form steady state, so the archived harmonics can be checked against analysis. Workers
import it as ``tests.pipelines.models:SPEC``, which needs the repository root on ``sys.path``
(added below for this process, inherited by the spawned workers, and put on ``PYTHONPATH`` for
subprocesses).
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from pipelines import cli
from pipelines.archive import (
    CONVENTIONS,
    FLAG_MEANINGS,
    STATUS_FAILED,
    STATUS_NOT_RUN,
    STATUS_OK,
    case_summary,
    read_case,
    write_case,
)
from pipelines.plots import plot_archive
from pipelines.studyfile import StudyError, load_study, make_case_id, model_version
from pipelines.sweep import consolidate_study, run_sweep
from pipelines.worker import run_case
from studies.harmonics import N_MAX, case_harmonics, harmonics

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))
models = importlib.import_module("tests.pipelines.models")
MODEL = "tests.pipelines.models:SPEC"

# Roundoff bound on harmonics of O(1) signals from an FFT of a few hundred samples.
EXACT = 1e-12


def write_study(path: Path, body: str, model: str = MODEL) -> Path:
    path.write_text(f'model = "{model}"\ntitle = "test study"\n{body}')
    return path


def expected_fixed(params: dict, quantity: str) -> tuple[np.ndarray, np.ndarray]:
    """Analytic (cos, sin) coefficients, shape (direction, harmonic), of a fixed-frame vector."""
    cos, sin = np.zeros((2, N_MAX + 1)), np.zeros((2, N_MAX + 1))
    for k, amp in models.steady_state(params).items():
        for d in range(2):
            # Re(X e^{ikψ}) = Re X cos kψ - Im X sin kψ
            cos[d, k], sin[d, k] = amp[quantity][d].real, -amp[quantity][d].imag
    return cos, sin


def expected_rotating(params: dict) -> tuple[np.ndarray, np.ndarray]:
    """Analytic (cos, sin) of the hub displacement in the rotating frame.

    x_r = x cos ψ + y sin ψ, y_r = -x sin ψ + y cos ψ: harmonic k of the fixed frame goes to
    k+1 with ½(X - iY) and to k-1 with ½(X + iY) (x_r), and likewise for y_r.
    """
    phasor = np.zeros((2, N_MAX + 2), dtype=complex)
    for k, amp in models.steady_state(params).items():
        x, y = amp["hub"]
        for comp, (up, down) in enumerate((((x - 1j * y) / 2, (x + 1j * y) / 2),
                                           ((y + 1j * x) / 2, (y - 1j * x) / 2))):
            phasor[comp, k + 1] += up
            # For k = 1 the down-shifted term is constant: only its real part (a mean) remains.
            if k - 1 > 0:
                phasor[comp, k - 1] += down
            else:
                phasor[comp, 0] += down.real
    return phasor.real[:, : N_MAX + 1], -phasor.imag[:, : N_MAX + 1]


# --- harmonics ----------------------------------------------------------------------------------


def test_harmonics_exact_on_synthetic_signal():
    n, revs, psi0 = 48, 3, 0.7
    psi = psi0 + 2 * np.pi * np.arange(n * revs) / n
    coef = {0: (0.25, 0.0), 1: (1.0, -2.0), 3: (0.0, 0.5), 4: (-3.0, 1.5), 8: (0.125, 0.25)}
    x = sum(c * np.cos(k * psi) + s * np.sin(k * psi) for k, (c, s) in coef.items())
    # a sub-harmonic (not per rev) must not leak into the per-rev bins
    x = x + 0.3 * np.cos(psi / revs)
    h = harmonics(x, n, revs, psi0=psi0)
    want_c = np.array([coef.get(k, (0, 0))[0] for k in range(N_MAX + 1)])
    want_s = np.array([coef.get(k, (0, 0))[1] for k in range(N_MAX + 1)])
    np.testing.assert_allclose(h.cos, want_c, atol=EXACT)
    np.testing.assert_allclose(h.sin, want_s, atol=EXACT)
    np.testing.assert_allclose(h.amplitude, np.hypot(want_c, want_s), atol=EXACT)
    assert h.cos.dtype == np.float64 and h.sin.dtype == np.float64

    # vectorized: several signals at once, time on axis 0
    stacked = harmonics(np.stack([x, 2 * x], axis=1), n, revs, psi0=psi0, axis=0)
    np.testing.assert_allclose(stacked.cos[1], 2 * want_c, atol=EXACT)


@pytest.mark.parametrize(
    ("length", "n", "revs", "n_max", "match"),
    [
        (100, 48, 2, 8, "expected revolutions"),
        (32, 16, 2, 8, "cannot resolve harmonic 8"),
    ],
)
def test_harmonics_refuses_bad_sampling(length, n, revs, n_max, match):
    with pytest.raises(ValueError, match=match):
        harmonics(np.zeros(length), n, revs, n_max)


def test_case_harmonics_and_summary_against_closed_form():
    params = models.SPEC.complete({"transient_revolutions": 2, "revolutions": 3})
    ds = models.SPEC.run(params)
    # Start the recording a quarter revolution plus a fraction of a sample late: harmonics are
    # still referred to psi = Ω t, and the one-revolution histories still start at psi = 0.
    shift = (0.25 + 0.3 / params["samples_per_rev"]) * 2 * np.pi / params["hub_speed"]
    later = models.SPEC.run(params).assign_coords(time=ds["time"] + shift)
    psi_late = params["hub_speed"] * later["time"].values
    for name in ("hub_x_fixed", "hub_y_fixed", "hub_force_x_fixed"):
        quantity = "force" if "force" in name else "hub"
        d = 0 if "_x_" in name else 1
        later[name].values[:] = sum(
            (amp[quantity][d] * np.exp(1j * k * psi_late)).real
            for k, amp in models.steady_state(params).items()
        )

    h = case_harmonics(ds, models.SPEC.outputs)
    assert dict(h.sizes) == {"harmonic": N_MAX + 1, "direction": 2, "bifilar": 4}
    for name, var in h.variables.items():
        assert var.attrs.get("units") and var.attrs.get("long_name"), name
    for quantity, name in (("hub", "hub_displacement_fixed"), ("force", "hub_force_fixed"),
                           ("absorber", "bifilar_cm_displacement")):
        cos, sin = expected_fixed(params, quantity)
        scale = np.abs(cos).max()
        np.testing.assert_allclose(h[f"{name}_cos"], cos, atol=EXACT * scale)
        np.testing.assert_allclose(h[f"{name}_sin"], sin, atol=EXACT * scale)
        np.testing.assert_allclose(h[f"{name}_amplitude"], np.hypot(cos, sin),
                                   atol=EXACT * scale)
    cos, sin = expected_rotating(params)
    np.testing.assert_allclose(h["hub_displacement_rotating_cos"], cos, atol=1e-15)
    np.testing.assert_allclose(h["hub_displacement_rotating_sin"], sin, atol=1e-15)
    # opposite bifilars swing in antiphase at 3P and 5P
    np.testing.assert_allclose(h["pin_angle_cos"][2], -h["pin_angle_cos"][0], atol=1e-12)
    assert h["pin_angle_amplitude"].sel(bifilar=0, harmonic=3) > 1.0

    h_late = case_harmonics(later, models.SPEC.outputs)
    for name in ("hub_displacement_fixed", "hub_force_fixed"):
        tol = EXACT * 1e3 * float(np.abs(h[f"{name}_cos"]).max())
        np.testing.assert_allclose(h_late[f"{name}_cos"].sel(direction="x"),
                                   h[f"{name}_cos"].sel(direction="x"), atol=tol)
        np.testing.assert_allclose(h_late[f"{name}_sin"].sel(direction="x"),
                                   h[f"{name}_sin"].sel(direction="x"), atol=tol)

    summary = case_summary(later, models.SPEC)
    n = params["samples_per_rev"]
    assert summary.sizes["time_in_rev"] == n
    np.testing.assert_allclose(summary["psi"], 360.0 * np.arange(n) / n)
    np.testing.assert_allclose(summary["hub_x_fixed"], ds["hub_x_fixed"].values[:n],
                               atol=1e-12 * float(np.abs(ds["hub_x_fixed"]).max()))
    assert summary["run_transient_revolutions"] == 2 and summary["run_revolutions"] == 3


def test_case_harmonics_refuses_non_uniform_time():
    ds = models.SPEC.run(models.SPEC.complete({}))
    t = ds["time"].values.copy()
    t[5] += 1e-4
    with pytest.raises(ValueError, match="not uniform"):
        case_harmonics(ds.assign_coords(time=t), models.SPEC.outputs)


# --- case files ---------------------------------------------------------------------------------


def test_write_case_is_atomic(tmp_path):
    ok = xr.Dataset({"a": ("x", np.arange(3.0), {"units": "m", "long_name": "a"})})
    target = write_case(ok, tmp_path / "c.nc")
    assert read_case(target)["a"].encoding["zlib"]
    # netCDF cannot store a dict attribute: the write fails, leaving neither a file nor a temp.
    bad = ok.assign_attrs(nested={"no": 1})
    with pytest.raises(TypeError):
        write_case(bad, tmp_path / "d.nc")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.nc"]


@pytest.mark.parametrize(
    ("fail", "match"),
    [("raise", "RuntimeError: failure requested"), ("report", "did not converge")],
)
def test_run_case_records_failure_as_a_value(tmp_path, fail, match):
    params = models.SPEC.complete({"fail": fail})
    out = run_case(MODEL, params, str(tmp_path / "x.nc"))
    assert out["status"] == STATUS_FAILED and match in out["message"]
    case = read_case(tmp_path / "x.nc")
    assert case.attrs["status"] == STATUS_FAILED and match in case.attrs["message"]
    assert json.loads(case.attrs["parameters"])["fail"] == fail
    assert not case.data_vars


# --- sweeps on a real cluster -------------------------------------------------------------------


# ``scheduler`` (tests/conftest.py): a local cluster of 2 worker processes on free ports.


def test_local_cluster_workers_start_with_the_solvers_malloc_thresholds(monkeypatch):
    """The local cluster's workers start with glibc malloc thresholds that keep the solver's
    per-step arrays in the heap, not dask's MALLOC_TRIM_THRESHOLD_ = 65536 (which made a
    rotor revolution 9.0 s instead of 4.7 s, measured; see ``pipelines.cluster``)."""
    from pipelines.cluster import MALLOC_ENVIRON, connect

    for key in MALLOC_ENVIRON:  # a variable already set (here or by an earlier cluster) wins
        monkeypatch.setenv(key, "0")
        monkeypatch.delenv(key)
    with connect(1, None) as client:
        seen = client.run(lambda: {k: os.environ.get(k) for k in MALLOC_ENVIRON})
    assert list(seen.values()) == [{k: str(v) for k, v in MALLOC_ENVIRON.items()}]


SWEEP_STUDY = """
[fixed]
hub_speed = 27.0
samples_per_rev = 48
[sweep]
tuning_order = [2.8, 3.0, 3.2]
fuselage_stiffness_scale = [0.5, 0.75, 1.0]
"""

CASES_STUDY = """
[[cases]]
name = "0: locked"
bifilar = "locked"
[[cases]]
name = "1: free, 3P"
bifilar = "free"
tuning_order = 3.0
[[cases]]
name = "2: unstable absorber"
absorber_damping_ratio = -0.2
[[cases]]
name = "3: free, 3.3P, coarse"
tuning_order = 3.3
samples_per_rev = 40
"""


@pytest.fixture(scope="module")
def sweep_archive(scheduler, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("sweep")
    study = write_study(tmp / "study.toml", SWEEP_STUDY)
    return study, run_sweep(study, tmp / "out", scheduler=scheduler, progress=False,
                            command="bifilar sweep study.toml --out out")


@pytest.fixture(scope="module")
def cases_archive(scheduler, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cases")
    study = write_study(tmp / "study.toml", CASES_STUDY)
    return study, run_sweep(study, tmp / "out", scheduler=scheduler, progress=False)


def assert_cf(ds: xr.Dataset, study: Path) -> None:
    assert ds.attrs["Conventions"] == CONVENTIONS
    assert ds.attrs["title"] == "test study"
    assert ds.attrs["source"].startswith("bifilar ")
    assert ds.attrs["study"] == study.read_text()
    stamp, _, command = ds.attrs["history"].partition(": ")
    assert stamp[:4].isdigit() and "T" in stamp and command
    for name, var in ds.variables.items():
        assert var.attrs.get("units"), f"{name} has no units"
        assert var.attrs.get("long_name"), f"{name} has no long_name"
    status = ds["status"]
    assert status.dtype == np.int8
    assert list(status.attrs["flag_values"]) == [0, 1, 2]
    assert status.attrs["flag_meanings"] == FLAG_MEANINGS
    for name, var in ds.data_vars.items():
        if np.issubdtype(var.encoding.get("dtype", var.dtype), np.floating) and var.ndim:
            assert var.encoding.get("zlib") and var.encoding.get("complevel") == 4, name


def test_cartesian_sweep_archive(sweep_archive):
    study, path = sweep_archive
    with xr.open_dataset(path) as ds:
        assert_cf(ds, study)
        assert ds.attrs["history"].endswith("bifilar sweep study.toml --out out")
        assert ds["status"].dims == ("tuning_order", "fuselage_stiffness_scale")
        assert ds["hub_force_fixed_amplitude"].dims == ("tuning_order", "fuselage_stiffness_scale",
                                              "direction", "harmonic")
        assert ds["pin_angle_amplitude"].dims[-2:] == ("bifilar_index", "harmonic")
        assert ds["pin_angle"].dims[-2:] == ("bifilar_index", "time_in_rev")
        assert ds["psi"].attrs["units"] == "degree"
        np.testing.assert_array_equal(ds["tuning_order"], [2.8, 3.0, 3.2])
        assert ds["tuning_order"].attrs["long_name"] == "bifilar tuning order, rotating frame"
        assert ds["hub_speed"].ndim == 0 and float(ds["hub_speed"]) == 27.0
        assert ds["hub_speed"].attrs["units"] == "rad s-1"
        assert (ds["status"] == STATUS_OK).all() and (ds["message"] == "").all()

        spec = models.SPEC
        for t, s in [(2.8, 0.5), (3.2, 1.0)]:
            params = spec.complete({"tuning_order": t, "fuselage_stiffness_scale": s,
                                    "samples_per_rev": 48})
            case = ds.sel(tuning_order=t, fuselage_stiffness_scale=s)
            cos, sin = expected_fixed(params, "force")
            np.testing.assert_allclose(case["hub_force_fixed_cos"], cos, atol=1e-9)
            np.testing.assert_allclose(case["hub_force_fixed_sin"], sin, atol=1e-9)
            cos, sin = expected_rotating(params)
            np.testing.assert_allclose(case["hub_displacement_rotating_cos"], cos, atol=1e-15)
            np.testing.assert_allclose(case["hub_displacement_rotating_sin"], sin, atol=1e-15)
            assert str(case["case_id"].values) == make_case_id(spec.name, params,
                                                               model_version(spec))
        # the tuned absorber removes most of the 4P force (3P/5P rotating)
        force4 = ds["hub_force_fixed_amplitude"].sel(harmonic=4, direction=0,
                                                     fuselage_stiffness_scale=1)
        assert force4.sel(tuning_order=3.0) < 0.5 * force4.sel(tuning_order=2.8)


def test_failed_case_is_recorded_and_others_finish(cases_archive):
    study, path = cases_archive
    with xr.open_dataset(path) as ds:
        assert_cf(ds, study)
        assert ds["status"].dims == ("case",)
        assert list(ds["case_name"].values) == ["0: locked", "1: free, 3P",
                                                "2: unstable absorber", "3: free, 3.3P, coarse"]
        np.testing.assert_array_equal(ds["status"], [0, 0, 1, 0])
        message = str(ds["message"].values[2])
        assert message.startswith("RuntimeError: unstable")
        assert ds["hub_force_fixed_amplitude"].isel(case=2).isnull().all()
        assert ds["run_revolutions"].isel(case=2).isnull()  # integer fill value decoded
        assert ds["hub_force_fixed_amplitude"].isel(case=[0, 1, 3]).notnull().all()
        # parameters that vary are coordinates on `case`; the others are scalars
        assert ds["bifilar"].dims == ("case",) and ds["tuning_order"].dims == ("case",)
        assert list(ds["bifilar"].values) == ["locked", "free", "free", "free"]
        assert ds["revolutions"].ndim == 0 and int(ds["revolutions"]) == 2
        assert ds["revolutions"].attrs["units"] == "1"
        # locked bifilars do not swing
        assert float(abs(ds["pin_angle"].isel(case=0)).max()) == 0.0
        # histories of the coarser case are re-sampled (exactly) onto the common azimuth grid
        assert list(ds["samples_per_rev"].values) == [64, 64, 64, 40]
        assert ds.sizes["time_in_rev"] == 64
        params = models.SPEC.complete({"tuning_order": 3.3})
        psi = np.radians(ds["psi"].values)
        hub_x = sum((amp["hub"][0] * np.exp(1j * k * psi)).real
                    for k, amp in models.steady_state(params).items())
        np.testing.assert_allclose(ds["hub_x_fixed"].isel(case=3), hub_x, atol=1e-15)


def test_retry_failed_recomputes_only_failed_cases(cases_archive, scheduler, capsys):
    study, path = cases_archive
    run_sweep(study, path.parent, scheduler=scheduler, retry_failed=True)
    err = capsys.readouterr().err
    assert "resuming: 3 of 4 case(s) already finished" in err
    assert "[4/4] case 2: unstable absorber failed" in err
    assert err.count("] case ") == 1


def test_sweep_resumes_after_kill(scheduler, tmp_path):
    log = tmp_path / "runs.log"
    study = write_study(tmp_path / "slow.toml", f"""
[fixed]
delay = 1.0
run_log = "{log}"
[sweep]
tuning_order = [2.5, 2.75, 3.0, 3.25, 3.5, 3.75]
""")
    out = tmp_path / "out"
    cases_dir = out / "cases"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH")) if p)}
    with open(tmp_path / "first.err", "wb") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "pipelines.sweep", str(study), "--out", str(out),
             "--workers", "2"],
            cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=err,
            start_new_session=True,  # its own process group: the kill takes the workers too
        )
        try:
            deadline = time.monotonic() + 60
            while len(list(cases_dir.glob("*.nc"))) < 2:
                assert proc.poll() is None, (tmp_path / "first.err").read_text()
                assert time.monotonic() < deadline, "no case finished within 60 s"
                time.sleep(0.05)
        finally:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    before = {p.name: p.stat().st_mtime_ns for p in cases_dir.glob("*.nc")}
    assert 2 <= len(before) < 6
    assert not (out / "archive.nc").exists()
    runs_before = len(log.read_text().splitlines())
    # what has finished can be archived without running anything: the rest is flagged not_run
    with xr.open_dataset(consolidate_study(study, out)) as partial:
        assert int((partial["status"] == STATUS_OK).sum()) == len(before)
        assert int((partial["status"] == STATUS_NOT_RUN).sum()) == 6 - len(before)
        force = partial["hub_force_fixed_amplitude"]
        assert force.where(partial["status"] == STATUS_NOT_RUN).isnull().all()

    path = run_sweep(study, out, scheduler=scheduler)
    after = {p.name: p.stat().st_mtime_ns for p in cases_dir.glob("*.nc")}
    assert len(after) == 6
    assert {k: after[k] for k in before} == before  # finished cases untouched
    reruns = [json.loads(line)["tuning_order"] for line in log.read_text().splitlines()
              [runs_before:]]
    spec = models.SPEC
    recomputed = sorted(make_case_id(spec.name, spec.complete(
        {"delay": 1.0, "run_log": str(log), "tuning_order": t}), model_version(spec)) + ".nc"
        for t in reruns)
    assert recomputed == sorted(set(after) - set(before))  # each missing case exactly once
    with xr.open_dataset(path) as ds:
        assert (ds["status"] == STATUS_OK).all()
        assert ds.sizes["tuning_order"] == 6


# --- study validation ---------------------------------------------------------------------------


BAD_STUDIES = {
    "toml syntax": ('model = "x"\n[fixed\n', "not valid TOML.*line 2"),
    "no model": ('title = "t"\n[sweep]\ntuning_order = [3.0]\n', "no model given"),
    "unknown model": (
        'model = "no-such-model"\n[sweep]\ntuning_order = [3.0]\n', "unknown model 'no-such"
    ),
    "unimportable plug-in": (
        'model = "no_such_module:SPEC"\n[sweep]\ntuning_order = [3.0]\n', "cannot load model"
    ),
    "unknown parameter": (
        f'model = "{MODEL}"\n[fixed]\ntunning_order = 3.0\n[sweep]\nhub_speed = [27.0]\n',
        "unknown parameter 'tunning_order'.*did you mean 'tuning_order'",
    ),
    "wrong type": (
        f'model = "{MODEL}"\n[sweep]\ntuning_order = ["three"]\n', "expected a number"
    ),
    "out of range": (
        f'model = "{MODEL}"\n[sweep]\ntuning_order = [30.0]\n', "outside the valid range"
    ),
    "empty list": (f'model = "{MODEL}"\n[sweep]\ntuning_order = []\n', "empty list"),
    "both sweep and cases": (
        f'model = "{MODEL}"\n[sweep]\ntuning_order = [3.0]\n[[cases]]\nname = "a"\n',
        "not both",
    ),
    "neither sweep nor cases": (f'model = "{MODEL}"\n[fixed]\nhub_speed = 27.0\n', "neither"),
    "swept and fixed": (
        f'model = "{MODEL}"\n[fixed]\ntuning_order = 3.0\n[sweep]\ntuning_order = [3.0]\n',
        "both swept and in \\[fixed\\]",
    ),
    "sweep value not a list": (
        f'model = "{MODEL}"\n[sweep]\ntuning_order = 3.0\n', "must be a list of values"
    ),
    "impossible geometry": (
        f'model = "{MODEL}"\n[[cases]]\nname = "fat pin"\npin_diameter = 0.04\n',
        "case 'fat pin': pin_diameter = 0.04 m must be smaller than hole_diameter",
    ),
    "duplicate cases": (
        f'model = "{MODEL}"\n[[cases]]\nname = "a"\n[[cases]]\nname = "b"\n',
        "identical parameters",
    ),
    "unknown top-level key": (
        f'model = "{MODEL}"\n[fixd]\nhub_speed = 27.0\n', "unknown top-level key"
    ),
}


@pytest.mark.parametrize(("text", "match"), BAD_STUDIES.values(), ids=BAD_STUDIES.keys())
def test_bad_study_is_refused_with_a_clear_message(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(StudyError, match=match) as info:
        load_study(path)
    assert "\n" not in str(info.value)
    assert str(path) in str(info.value)


def test_registry_name_resolves_in_process(tmp_path):
    study = load_study(write_study(tmp_path / "s.toml", "[sweep]\nbifilar = ['free']\n",
                                   model=models.SPEC.name))
    assert study.spec is models.SPEC and len(study.cases) == 1


# --- command line -------------------------------------------------------------------------------


def error_line(result) -> str:
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2, result.output
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert "Traceback" not in result.output
    return lines[0]


def test_cli_bad_study_prints_one_error_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(f'model = "{MODEL}"\n[sweep]\ntuning_order = []\n')
    runner = CliRunner()
    line = error_line(runner.invoke(cli.main, ["sweep", str(bad), "--out", str(tmp_path)]))
    assert "empty list" in line
    line = error_line(runner.invoke(cli.main, ["sweep", str(tmp_path / "none.toml"), "--out",
                                               str(tmp_path)]))
    assert "not found" in line
    line = error_line(runner.invoke(cli.main, ["sweep", str(bad), "--out", str(tmp_path),
                                               "--workers", "2", "--scheduler", "tcp://x:1"]))
    assert "mutually exclusive" in line
    line = error_line(runner.invoke(cli.main, ["plot", str(tmp_path / "none.nc"), "--out",
                                               str(tmp_path)]))
    assert "archive not found" in line


def test_cli_run_sweeps_and_plots(scheduler, tmp_path, monkeypatch):
    study = write_study(tmp_path / "default.toml", CASES_STUDY)
    monkeypatch.setattr(cli, "default_study",
                        lambda model="hub", study_name="table1": study)
    result = CliRunner().invoke(cli.main, ["run", "--out", str(tmp_path / "res"),
                                           "--scheduler", scheduler])
    # one case of four fails: exit status 1, the last line says how many and where to look
    assert result.exit_code == 1, result.output
    assert "[4/4] case" in result.stderr and "failed" in result.stderr
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("error: 1 of 4 case(s) not ok (1 failed, 0 not run)"), last
    assert "'message' variable" in last and "archive.nc" in last
    assert "Traceback" not in result.output
    assert (tmp_path / "res" / "archive.nc").exists()
    # the figures of a case list (bars, Figs. 14-19), as PNG and PDF
    paths = [Path(line) for line in result.stdout.splitlines()[1:]]
    names = {p.name for p in paths}
    for stem in ("harmonics_hub_displacement_rotating", "harmonics_hub_force_fixed",
                 "harmonics_hub_displacement_fixed", "pin_angles", "orbits",
                 "hub_force_history"):
        assert {f"{stem}.png", f"{stem}.pdf"} <= names
    assert all(p.parent == tmp_path / "res" / "plots" and p.stat().st_size > 1000
               for p in paths)
    # the paired comparisons (reference case 1 against each other case; case 2 failed)
    assert {"compare_case0_vs_case1.png", "compare_case1_vs_case3.png"} <= names
    assert "compare_case1_vs_case2.png" not in names


def test_large_sweep_plots_lines_against_first_parameter(sweep_archive, tmp_path):
    names = {p.name for p in plot_archive(sweep_archive[1], tmp_path, formats=("png",))}
    assert "harmonics_hub_force_fixed_vs_tuning_order.png" in names
    assert "harmonics_hub_force_fixed.png" not in names
    assert {"pin_angles_p1.png", "pin_angles_p2.png"} <= names  # 9 free cases, 8 per page


# --- the built-in study -------------------------------------------------------------------------

DEFAULT_STUDY = REPO / "studies" / "hub_study.toml"
ROTOR_STUDY = REPO / "studies" / "rotor_study.toml"


def test_default_study_is_table_1(tmp_path):
    doc = tomllib.loads(DEFAULT_STUDY.read_text())
    assert doc["model"] == "hub"
    rows = [(c["bifilar"], c["tuning_order"], c["fuselage_stiffness_scale"])
            for c in doc["cases"]]
    assert rows == [("locked", 3.0, 1.0), ("free", 3.0, 1.0), ("free", 3.3, 1.0),
                    ("free", 3.0, 0.5), ("equivalent", 3.0, 1.0)]
    # the rotor's built-in study is the same table, its fuselage scaled by its beam's EI
    rotor = tomllib.loads(ROTOR_STUDY.read_text())
    renamed = [{("fuselage_bending_stiffness_scale" if k == "fuselage_stiffness_scale" else k): v
                for k, v in c.items()} for c in doc["cases"]]
    assert rotor["model"] == "rotor" and rotor["cases"] == renamed
    # Same file on the stand-in model (same parameter names): it validates.
    copy = tmp_path / "default.toml"
    text = DEFAULT_STUDY.read_text().replace('model = "hub"', f'model = "{MODEL}"')
    copy.write_text(text[: text.index('[[cases]]\nname = "4:')])  # it has no equivalent
    study = load_study(copy)
    assert [c.label for c in study.cases] == ["0: locked", "1: free, 3P", "2: free, 3.3P",
                                              "3: free, 3P, half fuselage stiffness"]


def test_built_in_studies_validate_on_their_models():
    assert len(load_study(DEFAULT_STUDY).cases) == 5
    assert len(load_study(ROTOR_STUDY).cases) == 5


# --- outputs declared once: every registered model sweeps end to end ---------------------------

PENDULUM_STUDY = """model = "pendulum"
title = "pendulum amplitude sweep"
[fixed]
periods = 2.0
steps_per_period = 40
[sweep]
amplitude = [5.0, 20.0]
"""

COLLAR_STUDY = """model = "collar"
title = "collar release sweep"
[fixed]
periods = 2.0
steps_per_period = 100
[sweep]
theta0 = [20.0, 60.0]
"""


def assert_declared(ds: xr.Dataset, spec) -> None:
    """Every archive variable carries units and long_name; declared ones carry their own."""
    for name, var in ds.variables.items():
        assert var.attrs.get("units"), f"{name} has no units"
        assert var.attrs.get("long_name"), f"{name} has no long_name"
    for name, out in spec.outputs.items():
        if name in ds:
            assert ds[name].attrs["units"] == out.units, name
            assert ds[name].attrs["long_name"] == out.long_name, name


def test_pendulum_study_sweeps_end_to_end(scheduler, tmp_path):
    from studies.bifilar import SPEC

    study = tmp_path / "pendulum.toml"
    study.write_text(PENDULUM_STUDY)
    result = CliRunner().invoke(cli.main, ["sweep", str(study), "--out", str(tmp_path / "out"),
                                           "--scheduler", scheduler])
    assert result.exit_code == 0, result.output
    with xr.open_dataset(result.stdout.strip()) as ds:
        assert (ds["status"] == STATUS_OK).all(), ds["message"].values
        assert ds.attrs["model"] == "pendulum"
        assert_declared(ds, SPEC)
        assert ds["frequency_order"].dims == ("amplitude",)
        assert ds["frequency_order_linear"].attrs["units"] == "1"
        for name in ("pin_angle", "mass_x", "mass_y", "time"):
            assert ds[name].dims == ("amplitude", "sample"), name
        assert ds["time"].attrs["units"] == "s"
        # nothing of the hub layout
        assert "harmonic" not in ds.dims and "run_samples_per_rev" not in ds
        order = ds["frequency_order"].values
        lin = float(ds["frequency_order_linear"].isel(amplitude=0))
        # circular holes soften with amplitude (π/(2K(sin A/2)): -0.05 % at 5°, -0.8 % at 20°)
        assert order[1] < order[0] and abs(order[0] / lin - 1) < 5e-3
        np.testing.assert_allclose(ds["pin_angle"].isel(sample=0), [5.0, 20.0], rtol=1e-9)
    paths = plot_archive(tmp_path / "out" / "archive.nc", tmp_path / "plots", formats=("png",))
    assert {p.name for p in paths} == {"results_vs_amplitude.png", "pin_angle_history.png"}


def test_collar_study_sweeps_end_to_end(scheduler, tmp_path):
    from studies.collar import SPEC

    study = tmp_path / "collar.toml"
    study.write_text(COLLAR_STUDY)
    result = CliRunner().invoke(cli.main, ["sweep", str(study), "--out", str(tmp_path / "out"),
                                           "--scheduler", scheduler, "--quiet"])
    assert result.exit_code == 0, result.output
    with xr.open_dataset(result.stdout.strip()) as ds:
        assert (ds["status"] == STATUS_OK).all(), ds["message"].values
        assert_declared(ds, SPEC)
        for name in ("period", "period_analytic", "period_error"):
            assert ds[name].dims == ("theta0",), name
        assert ds["period"].attrs["units"] == "s"
        assert ds["theta"].dims == ("theta0", "sample")
        # 100 steps per period: the period within the scheme's phase error, (2π/100)²/12 ≈ 3e-4
        assert float(abs(ds["period_error"]).max()) < 1e-3
        # the longer period of the larger release gives the same number of samples
        assert int(ds["time"].notnull().sum()) == 2 * ds.sizes["sample"]
    paths = plot_archive(tmp_path / "out" / "archive.nc", tmp_path / "plots", formats=("png",))
    assert {p.name for p in paths} == {"results_vs_theta0.png", "collar_angle.png"}


@pytest.mark.parametrize("name", ["pendulum_study.toml", "collar_study.toml"])
def test_example_studies_validate(name):
    study = load_study(REPO / "studies" / name)
    assert study.cases and study.spec.outputs


def test_sweep_with_failed_cases_exits_1(scheduler, tmp_path):
    study = write_study(tmp_path / "s.toml", CASES_STUDY)
    result = CliRunner().invoke(cli.main, ["sweep", str(study), "--out", str(tmp_path / "out"),
                                           "--scheduler", scheduler])
    assert result.exit_code == 1, result.output
    assert Path(result.stdout.strip()).name == "archive.nc"
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("error: 1 of 4 case(s) not ok (1 failed, 0 not run)"), last
    assert str(tmp_path / "out" / "archive.nc") in last and "cases" in last


def test_plot_refuses_archive_without_ok_case(scheduler, tmp_path):
    study = write_study(tmp_path / "s.toml", '[sweep]\nfail = ["raise"]\n')
    runner = CliRunner()
    result = runner.invoke(cli.main, ["sweep", str(study), "--out", str(tmp_path / "out"),
                                      "--scheduler", scheduler, "--quiet"])
    assert result.exit_code == 1, result.output
    line = error_line(runner.invoke(cli.main, ["plot", str(tmp_path / "out" / "archive.nc"),
                                               "--out", str(tmp_path / "plots")]))
    assert "no case" in line and "1 failed" in line
    # a case file is not an archive
    case = next((tmp_path / "out" / "cases").glob("*.nc"))
    line = error_line(runner.invoke(cli.main, ["plot", str(case), "--out",
                                               str(tmp_path / "plots")]))
    assert "not a sweep archive" in line


def test_outputs_are_filled_only_through_declarations():
    from studies.parameters import ModelSpec, Output, OutputError, output_dataset

    outputs = {"time": Output("s", "time", dims=("time",)),
               "x": Output("m", "position"),
               "peak": Output("m", "largest position", dims=())}
    ds = output_dataset(outputs, {"time": [0.0, 1.0], "x": [0.0, 2.0], "peak": 2.0})
    assert ds["x"].attrs == {"units": "m", "long_name": "position"}
    assert "time" in ds.coords and ds["peak"].ndim == 0
    with pytest.raises(OutputError, match="undeclared output"):
        output_dataset(outputs, {"time": [0.0], "x": [0.0], "peak": 0.0, "y": [1.0]})
    with pytest.raises(OutputError, match="not filled: peak"):
        output_dataset(outputs, {"time": [0.0], "x": [0.0]})
    with pytest.raises(OutputError, match="dimension"):
        output_dataset(outputs, {"time": [0.0], "x": [[0.0]], "peak": 0.0})
    with pytest.raises(OutputError, match="units"):
        ModelSpec("bad", {}, lambda p: xr.Dataset(), outputs={
            **outputs, "v": Output("N", "vector", components=("x", "x"))})


def test_shared_hardware_and_generated_options():
    from pipelines.study_commands import collar, pendulum
    from studies import bifilar, hub
    from studies import collar as collar_study

    for name, param in bifilar.HARDWARE.items():
        assert hub.PARAMETERS[name] is param and bifilar.PARAMETERS[name] is param, name
    assert hub.SPEC.complete({})["tuning_order"] == 3.0
    for command, params in ((collar, collar_study.PARAMETERS), (pendulum, bifilar.PARAMETERS)):
        options = {o.name: o for o in command.params}
        for name, param in params.items():
            option = options[name]
            assert option.opts == ["--" + name.replace("_", "-")]
            assert option.default in (param.default, None), name
            assert param.long_name in option.help, name
            if param.units != "1":
                assert param.units in option.help, name
