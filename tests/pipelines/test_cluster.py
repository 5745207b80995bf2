"""The real cluster path: ``dask scheduler`` and two ``dask worker`` processes started here on the
loopback, the sweep pointed at them with ``--scheduler``, one worker killed mid-run; every case
finishes. Also: progress lines of running cases reach the driver.

Everything listens on 127.0.0.1 only, and every wait is bounded.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr

from pipelines.archive import STATUS_OK

REPO = Path(__file__).resolve().parents[2]
MODEL = "tests.pipelines.models:SPEC"
START_TIMEOUT = 60.0
RUN_TIMEOUT = 180.0


def _dask(*args: str) -> list[str]:
    """The ``dask`` command of this interpreter's environment."""
    return [sys.executable, "-m", "dask", *args]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH")) if p)}


def _wait_for(predicate, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


def _kill(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two single-threaded workers (no nanny) on 127.0.0.1; yields
    (address, {worker address: process})."""
    sched_file = tmp_path / "scheduler.json"
    logs = tmp_path / "logs"
    logs.mkdir()
    procs: list[subprocess.Popen] = []

    def start(name: str, args: list[str]) -> subprocess.Popen:
        with open(logs / f"{name}.log", "wb") as log:
            proc = subprocess.Popen(args, cwd=tmp_path, env=_env(), stdout=log, stderr=log,
                                    start_new_session=True)
        procs.append(proc)
        return proc

    try:
        start("scheduler", _dask("scheduler", "--host", "127.0.0.1", "--port", "0",
                                 "--no-dashboard", "--dashboard-address", "127.0.0.1:0",
                                 "--scheduler-file", str(sched_file)))
        _wait_for(lambda: sched_file.exists() and sched_file.stat().st_size > 0,
                  START_TIMEOUT, "the scheduler file")
        address = json.loads(sched_file.read_text())["address"]
        workers = {}
        for i in range(2):
            workers[f"w{i}"] = start(f"worker{i}", _dask(
                "worker", address, "--nthreads", "1", "--no-nanny", "--host", "127.0.0.1",
                "--name", f"w{i}", "--no-dashboard", "--death-timeout", "60"))
        from distributed import Client

        with Client(address, timeout=START_TIMEOUT) as client:
            client.wait_for_workers(2, timeout=START_TIMEOUT)
        yield address, workers
    finally:
        for proc in procs:
            _kill(proc)


def test_sweep_survives_a_killed_worker(cluster, tmp_path):
    address, workers = cluster
    study = tmp_path / "study.toml"
    study.write_text(f'''model = "{MODEL}"
title = "cluster test"
[fixed]
delay = 1.5
[sweep]
tuning_order = [2.6, 2.7, 2.8, 2.9, 3.0, 3.1, 3.2, 3.3]
''')
    out = tmp_path / "out"
    with open(tmp_path / "sweep.err", "wb") as err:
        sweep = subprocess.Popen(
            [sys.executable, "-m", "pipelines.sweep", str(study), "--out", str(out),
             "--scheduler", address],
            cwd=tmp_path, env=_env(), stdout=subprocess.PIPE, stderr=err,
            start_new_session=True)
    try:
        # kill one worker once the first case has finished (both workers are busy by then)
        _wait_for(lambda: len(list((out / "cases").glob("*.nc"))) >= 1 or sweep.poll() is not None,
                  RUN_TIMEOUT, "the first case")
        assert sweep.poll() is None, (tmp_path / "sweep.err").read_text()
        _kill(workers["w0"])
        stdout, _ = sweep.communicate(timeout=RUN_TIMEOUT)
    finally:
        _kill(sweep)
    log = (tmp_path / "sweep.err").read_text()
    assert sweep.returncode == 0, log
    assert "Traceback" not in log
    assert "on 2 dask worker(s)" in log
    assert "started on tcp://127.0.0.1:" in log  # progress lines from the workers
    with xr.open_dataset(stdout.decode().strip()) as ds:
        assert int((ds["status"] == STATUS_OK).sum()) == 8, ds["message"].values
    assert workers["w0"].poll() is not None and workers["w1"].poll() is None
