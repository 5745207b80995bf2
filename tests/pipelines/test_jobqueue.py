"""Sweeps on a batch system (``--cluster slurm|pbs``): the job script dask-jobqueue generates
carries the study file's ``[cluster]`` resources; nothing is submitted. Without dask-jobqueue,
``--cluster`` is refused in one line before any work.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from pipelines import cli
from pipelines import sweep as sweep_module
from pipelines.checks import InputError
from pipelines.cluster import MALLOC_ENVIRON, jobqueue_cluster
from pipelines.studyfile import StudyError, load_study

MODEL = "tests.pipelines.models:SPEC"
RESOURCES = """
[cluster]
cores = 4
memory = "8GB"
walltime = "02:00:00"
queue = "short"
account = "rotorlab"
jobs = 3
"""
# The scheduler of these tests: loopback only, no dashboard.
QUIET = {"scheduler_options": {"dashboard_address": None, "host": "127.0.0.1"}}


def study_file(path: Path, extra: str = RESOURCES) -> Path:
    path.write_text(f'model = "{MODEL}"\n[sweep]\ntuning_order = [2.9, 3.1]\n{extra}')
    return path


@pytest.mark.parametrize(("kind", "lines"), [
    ("slurm", ["#SBATCH -p short", "#SBATCH -A rotorlab", "#SBATCH --cpus-per-task=4",
               "#SBATCH --mem=8G", "#SBATCH -t 02:00:00"]),
    ("pbs", ["#PBS -q short", "#PBS -A rotorlab", "ncpus=4", "#PBS -l walltime=02:00:00"]),
])
def test_job_script_carries_the_study_resources(tmp_path, kind, lines):
    pytest.importorskip("dask_jobqueue")
    study = load_study(study_file(tmp_path / "s.toml"))
    assert study.cluster["jobs"] == 3
    with jobqueue_cluster(kind, study.cluster, **QUIET) as cluster:
        script = cluster.job_script()
        assert not cluster.workers  # nothing submitted
    for line in lines:
        assert line in script, (line, script)
    # one single-threaded worker process per core, the solver's malloc thresholds
    assert "--nworkers 4" in script and "--nthreads 1" in script
    for key, value in MALLOC_ENVIRON.items():
        assert f"export {key}={value}" in script
    assert sys.executable in script


def test_missing_resources_are_one_line():
    pytest.importorskip("dask_jobqueue")
    import dask

    with dask.config.set({"jobqueue.slurm.cores": None, "jobqueue.slurm.memory": None}), \
            pytest.raises(InputError) as info:
        jobqueue_cluster("slurm", {}, **QUIET)
    assert "cores and memory" in str(info.value) and "[cluster]" in str(info.value)


@pytest.mark.parametrize(("table", "match"), [
    ("[cluster]\ncores = 0\n", "cores = 0 must be a whole number"),
    ("[cluster]\nmemory = 8\n", "memory = 8 must be a non-empty string"),
    ("[cluster]\nnodes = 2\n", "unknown key 'nodes'"),
])
def test_bad_cluster_table_is_refused(tmp_path, table, match):
    with pytest.raises(StudyError, match=match):
        load_study(study_file(tmp_path / "s.toml", table))


def test_cluster_without_dask_jobqueue_is_refused_before_any_work(tmp_path, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "dask_jobqueue" else real(name, *a))
    ran: list[Any] = []
    monkeypatch.setattr(sweep_module, "_run_cases", lambda *a, **k: ran.append(a))
    result = CliRunner().invoke(cli.main, ["sweep", str(study_file(tmp_path / "s.toml")),
                                           "--out", str(tmp_path / "out"), "--cluster", "slurm"])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --cluster slurm needs dask-jobqueue")
    assert "bifilar[cluster]" in lines[0]
    assert not ran and not (tmp_path / "out").exists()


def test_cluster_is_exclusive_with_workers_and_scheduler(tmp_path):
    for extra in (["--workers", "2"], ["--scheduler", "tcp://127.0.0.1:8786"]):
        result = CliRunner().invoke(cli.main, ["sweep", str(study_file(tmp_path / "s.toml")),
                                               "--out", str(tmp_path / "out"), "--cluster",
                                               "pbs", *extra])
        assert result.exit_code == 2 and "exclusive" in result.stderr, result.output


# the local runner kills its job processes at the end without waiting for them
@pytest.mark.filterwarnings("ignore:subprocess .* is still running:ResourceWarning")
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_sweep_runs_on_worker_jobs(tmp_path, monkeypatch):
    """The whole path of --cluster (jobs scaled to the [cluster] table, the wait for them,
    one worker process per core) on dask-jobqueue's local job runner, which starts each job
    as a subprocess of this machine instead of submitting it."""
    pytest.importorskip("dask_jobqueue")
    import dask_jobqueue
    import dask_jobqueue.local

    from pipelines import cluster
    from pipelines.archive import STATUS_OK, open_archive
    from pipelines.sweep import run_sweep

    repo = Path(__file__).resolve().parents[2]
    monkeypatch.setenv("PYTHONPATH", str(repo))  # the jobs import the test model
    monkeypatch.setitem(cluster.JOBQUEUE_CLUSTERS, "local", "LocalCluster")
    monkeypatch.setattr(dask_jobqueue, "LocalCluster", dask_jobqueue.local.LocalCluster,
                        raising=False)
    # the local runner executes the job's command without a shell: no exports before it
    monkeypatch.setattr(cluster, "MALLOC_ENVIRON", {})
    study = study_file(tmp_path / "s.toml", '[cluster]\ncores = 2\nmemory = "2GB"\njobs = 1\n')
    archive = run_sweep(study, tmp_path / "out", cluster="local", worker_timeout=120,
                        progress=False)
    ds = open_archive(archive)
    assert (ds["status"] == STATUS_OK).all(), ds["message"].values
