"""The kernels' warm-up (pipelines.kernels): it runs, leaves the kernels compiled and says so;
no timing (benchmarks/first_run.py measures it)."""
from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

from pipelines.kernels import kernels, warm_up_part, warm_up_workers
from studies.registry import resolve_model

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:  # the workers import the test model (see test_pipeline.py)
    sys.path.insert(0, str(REPO))
importlib.import_module("tests.pipelines.models")
WARM_MODEL = "tests.pipelines.models:WARM_SPEC"


def test_kernels_lists_the_solvers_compiled_functions():
    found = kernels()
    assert "solver.curve_kernels.evaluate" in found
    assert "solver.bsplines.nurbs_eval" in found  # listed once, under its own module
    assert not any(name.startswith("solver.curve_kernels.nurbs_eval") for name in found)


def test_built_in_models_have_warm_up_parts():
    for name in ("hub", "pendulum", "rotor"):
        assert resolve_model(name).warm_up, name


def test_warm_up_leaves_the_bifilars_kernels_compiled():
    result = warm_up_part("pendulum", 0)
    assert result["error"] == "", result["error"]
    found = kernels()
    # the curve sliding and rolling joints, the B-splines and the sparse LU were called
    for name in ("solver.curve_kernels.evaluate", "solver.bsplines.nurbs_eval"):
        assert found[name].signatures, name
    compiled = [name for name, k in found.items() if k.signatures]
    assert len(compiled) >= 10, compiled


def test_warm_up_part_reports_a_failure_instead_of_raising():
    lines: list[str] = []
    result = warm_up_part(WARM_MODEL, 1, lines.append)
    assert result["error"] == "RuntimeError: warm-up part broken (test)"
    assert result["compiled"] == 1
    assert len(lines) == 1 and lines[0].startswith("compiling kernels (first run only")


def test_warm_up_on_the_workers_says_once_and_goes_on_after_a_failure(scheduler):
    distributed = pytest.importorskip("distributed")
    lines: list[str] = []
    with distributed.Client(scheduler) as client:
        warm_up_workers(client, WARM_MODEL, lines.append)
    compiling = [line for line in lines if line.startswith("compiling kernels")]
    assert len(compiling) == 1, lines
    assert any(line.startswith("warning: compiling kernels ahead failed (RuntimeError: "
                               "warm-up part broken (test))") for line in lines), lines
    assert any(line.startswith("kernels compiled in ") for line in lines), lines


def test_warm_up_of_a_model_without_parts_does_nothing(scheduler):
    distributed = pytest.importorskip("distributed")
    lines: list[str] = []
    with distributed.Client(scheduler) as client:
        warm_up_workers(client, "tests.pipelines.models:SPEC", lines.append)
    assert lines == []
