"""The single-model commands (``bifilar collar``, ``pendulum``, ``fanplot``) run one case the
way a sweep runs each of its cases: through the model's ModelSpec, ``run_case`` and the
archive's case writer, with the same failure handling.
"""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path

import numpy as np
import xarray as xr
from click.testing import CliRunner

from pipelines import cli
from pipelines.archive import CONVENTIONS, STATUS_FAILED, STATUS_OK
from pipelines.studyfile import make_case_id, model_version
from studies.collar import SPEC as COLLAR

PIPELINES = Path(__file__).resolve().parents[2] / "pipelines"


def test_collar_writes_its_whole_result_through_the_case_writer(tmp_path):
    out = tmp_path / "c.nc"
    args = ["collar", "--curve", "circle", "--theta0", "30", "--steps-per-period", "100",
            "--out", str(out)]
    result = CliRunner().invoke(cli.main, args)
    assert result.exit_code == 0, result.output
    assert "measured period" in result.stdout
    with xr.open_dataset(out) as ds:
        assert ds.attrs["Conventions"] == CONVENTIONS and ds.attrs["status"] == STATUS_OK
        assert ds.attrs["model"] == "collar" and int(ds["run_converged"]) == 1
        params = COLLAR.complete({"curve": "circle", "theta0": 30.0,
                                  "steps_per_period": 100})
        assert ds.attrs["case_id"] == make_case_id("collar", params, model_version(COLLAR))
        # the model's variables, as the command always wrote them
        for name in ("theta", "s", "eta", "energy", "energy_error", "constraint_violation",
                     "period", "period_analytic", "period_error"):
            assert name in ds, name
        assert ds["theta"].dims == ("time",) and ds["theta"].encoding["zlib"]
        assert np.isfinite(float(ds["period"]))
    assert not list(tmp_path.glob(".c.*.tmp"))


def test_a_failed_single_case_exits_1_with_its_failure_recorded(tmp_path):
    out = tmp_path / "c.nc"
    # a cycloid released near the cusp with 8 steps per period: the integrator fails
    result = CliRunner().invoke(cli.main, ["collar", "--curve", "cycloid", "--theta0", "89",
                                           "--steps-per-period", "8", "--out", str(out)])
    assert result.exit_code == 1, result.output
    lines = result.stderr.strip().splitlines()
    assert lines[-1].startswith("error: the case failed: ") and str(out) in lines[-1]
    assert "Traceback" not in result.output
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == STATUS_FAILED and ds.attrs["message"]
        assert not ds.data_vars


def _imports(path: Path) -> list[tuple[str, str]]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [(node.module or "", alias.name) for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) for alias in node.names]


def test_commands_have_no_process_pool_or_writer_of_their_own():
    for name in ("study_commands.py", "fanplot_command.py", "single.py"):
        text = (PIPELINES / name).read_text(encoding="utf-8")
        assert "ProcessPoolExecutor" not in text and "to_netcdf" not in text, name
        private = [(m, n) for m, n in _imports(PIPELINES / name)
                   if m.startswith("pipelines") and n.startswith("_")]
        assert not private, (name, private)


def test_the_dead_harmonics_module_is_gone():
    assert importlib.util.find_spec("pipelines.harmonics") is None
