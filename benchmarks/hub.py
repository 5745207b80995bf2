"""Cases per hour of the hub model's built-in study (the paper's Table 1 on the hub model).

    python benchmarks/hub.py --workers 1 2 [--profile]
    python benchmarks/hub.py --case [--repeat 3]

Runs the built-in study with a LocalCluster of 1 and of 2 worker processes (fresh output
directories, nothing resumed) and prints one JSON object per run with the wall time, the cases
per hour and each case's solver time and steps per second. ``--profile`` also profiles one case
in this process (pyinstrument if installed, else cProfile) and prints where the time goes.

``--case`` measures the cost of one case side by side in one process: one free case at the
defaults (the composed fourth-order step, its step-error estimate and the harmonics extrapolated
to zero step), without the extrapolation (``richardson = false``) and without either
(``error_estimate = false`` too), alternately, each ``--repeat`` times after a warm-up run
(which loads the compiled kernels); it prints the best CPU time, the revolutions simulated
(those at the coarser step of the estimate also apart), the stored step-error estimate and each
one's error against the exact equations' periodic response (``studies.hub.reduced_samples``:
the hub on its swing coordinates by harmonic balance, no time step): the largest over harmonics
0–8 of every sampled signal, relative to that signal's largest harmonic.
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
    steps = ds["run_steps"].item()
    print(json.dumps({"profiled_steps": steps,
                      "steps_per_second": round(steps / ds["run_solver_seconds"].item(), 1),
                      "newton_iterations_per_step": round(
                          ds["run_newton_iterations"].item() / steps, 2)}))


CASE_SETTINGS = {
    "default (extrapolated)": {},
    "not extrapolated": {"richardson": False},
    "neither estimated nor extrapolated": {"richardson": False, "error_estimate": False},
}


def one_case(repeat: int) -> None:
    import numpy as np

    from studies.hub import SPEC, design, reduced_samples, run
    from studies.periodic import referred_harmonics

    p = SPEC.validate({})
    d = design(p)

    def error(ds) -> float:  # harmonics 0–8 of the last revolution against the exact ones
        n = ds["run_samples_per_rev"].item()
        rows = np.column_stack([ds["time"].values[-n:], *(ds[k].values[..., -n:].T for k in (
            "hub_x_fixed", "hub_y_fixed", "hub_force_x_fixed", "hub_force_y_fixed",
            "bifilar_cm_x_fixed", "bifilar_cm_y_fixed", "pin_angle"))])
        a, b = (referred_harmonics(r, p.hub_speed, 8)
                for r in (rows, reduced_samples(p, d, rows[:, 0])))
        return float(np.max(np.abs(a - b) / np.abs(b).max(axis=0)))

    run({})  # loads the compiled kernels
    cpu: dict[str, list[float]] = {k: [] for k in CASE_SETTINGS}
    last = {}
    for _ in range(repeat):
        for name, given in CASE_SETTINGS.items():
            t0 = time.process_time()
            last[name] = run(given)
            cpu[name].append(time.process_time() - t0)
    def optional(ds, name):  # a run without the estimate has none of its outputs
        return float(f"{ds[name].item():.3g}") if name in ds else None

    for name, ds in last.items():
        print(json.dumps({
            "case": name, "cpu_seconds_best": round(min(cpu[name]), 2),
            "cpu_seconds": [round(c, 2) for c in cpu[name]],
            "revolutions": ds["run_simulated_revolutions"].item(),
            "of_which_at_the_coarser_step": optional(ds, "run_estimate_revolutions"),
            "step_error_estimate": optional(ds, "run_step_error_estimate"),
            "steps": ds["run_steps"].item(), "substeps": ds["run_substeps"].item(),
            "newton_iterations": ds["run_newton_iterations"].item(),
            "harmonics_error": float(f"{error(ds):.3g}")}))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    p.add_argument("--profile", action="store_true")
    p.add_argument("--case", action="store_true",
                   help="one free case, default and previous default side by side")
    p.add_argument("--repeat", type=int, default=3)
    a = p.parse_args()
    if a.repeat < 1:
        p.error(f"--repeat {a.repeat}: must be at least 1")
    if a.case:
        one_case(a.repeat)
        return
    if a.profile:
        profile_case()
    for w in a.workers:
        print(json.dumps(sweep_once(w)), flush=True)


if __name__ == "__main__":
    main()
