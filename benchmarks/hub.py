"""Cases per hour of the hub model's built-in study (the paper's Table 1 on the hub model).

    python benchmarks/hub.py --workers 1 2 [--profile]

Runs the built-in study with a LocalCluster of 1 and of 2 worker processes (fresh output
directories, nothing resumed) and prints one JSON object per run with the wall time, the cases
per hour and each case's solver time and steps per second. ``--profile`` also profiles one case
in this process (pyinstrument if installed, else cProfile) and prints where the time goes.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from pipelines.cli import default_study
from pipelines.sweep import run_sweep


def sweep_once(workers: int) -> dict:
    import xarray as xr

    with tempfile.TemporaryDirectory() as tmp:
        study = Path(tmp) / "study.toml"
        study.write_text(default_study("hub").read_text())
        t0 = time.perf_counter()
        archive = run_sweep(study, Path(tmp) / "out", workers=workers, progress=False)
        wall = time.perf_counter() - t0
        ds = xr.open_dataset(archive)
        n = int(ds.sizes["case"])
        out = {"workers": workers, "cases": n, "wall_seconds": round(wall, 1),
               "cases_per_hour": round(3600 * n / wall, 1),
               "case_wall_seconds": [round(float(x), 1) for x in ds["run_wall_time"].values]}
        ds.close()
    return out


def profile_case() -> None:
    from studies.hub import run

    params = {"bifilar": "free", "max_revolutions": 4, "revolutions": 1,
              "periodic_tolerance": 1.0}
    try:
        from pyinstrument import Profiler

        prof = Profiler()
        prof.start()
        ds = run(params)
        prof.stop()
        print(prof.output_text(unicode=True, color=False, show_all=False))
    except ImportError:
        import cProfile
        import pstats

        pr = cProfile.Profile()
        pr.enable()
        ds = run(params)
        pr.disable()
        pstats.Stats(pr).sort_stats("tottime").print_stats(15)
    steps = ds.attrs["steps"]
    print(json.dumps({"profiled_steps": steps,
                      "steps_per_second": round(steps / ds.attrs["solver_seconds"], 1),
                      "newton_iterations_per_step": round(ds.attrs["newton_iterations"] / steps,
                                                          2)}))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    p.add_argument("--profile", action="store_true")
    a = p.parse_args()
    if a.profile:
        profile_case()
    for w in a.workers:
        print(json.dumps(sweep_once(w)), flush=True)


if __name__ == "__main__":
    main()
