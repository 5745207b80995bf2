"""A 60-case sweep of the hub model, with 1 and with 2 workers.

    python benchmarks/sweep60.py --workers 1 2                        # the full 60 cases
    python benchmarks/sweep60.py --workers 1 2 --cases 6 --steps-per-rev 64 --max-revolutions 6

The study sweeps ``tuning_order`` (12 values, 2.7-3.3) against ``fuselage_stiffness_scale``
(5 values, 0.5-1.5); ``--cases N`` keeps the first N cases in that order (a reduced run), and
``--steps-per-rev``, ``--max-revolutions``, ``--periodic-tolerance`` make each case cheaper (a
default hub case costs about 2 s of CPU, 1.5 s without its step-error estimate). Each run starts
from an empty output directory (nothing resumed) and prints one JSON object: workers, cases,
wall time, cases per hour, the driver's peak resident memory (this process, which holds the dask
client and, for a local cluster, the scheduler; measured as the growth of ``ru_maxrss`` over the
run and as the absolute peak), and the cases' status counts.
"""

from __future__ import annotations

import argparse
import itertools
import json
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

TUNING_ORDERS = [round(x, 3) for x in np.linspace(2.7, 3.3, 12)]
STIFFNESS_SCALES = [0.5, 0.75, 1.0, 1.25, 1.5]


def study_text(cases: int, fixed: dict[str, float | int]) -> str:
    """A [[cases]] study of the first ``cases`` points of the 12 x 5 grid."""
    lines = ['model = "hub"', f'title = "60-case hub benchmark ({cases} cases)"', "[fixed]"]
    lines += [f"{k} = {v}" for k, v in fixed.items()]
    grid = list(itertools.product(TUNING_ORDERS, STIFFNESS_SCALES))[:cases]
    for order, scale in grid:
        lines += ["[[cases]]", f'name = "n={order:g}, k={scale:g}"',
                  f"tuning_order = {order}", f"fuselage_stiffness_scale = {scale}"]
    return "\n".join(lines) + "\n"


def peak_rss_mib() -> float:
    """Peak resident memory of this process (MiB; ru_maxrss is in KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def sweep_once(workers: int, cases: int, fixed: dict[str, float | int]) -> dict:
    from pipelines.archive import open_archive, status_counts
    from pipelines.sweep import run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        study = Path(tmp) / "study.toml"
        study.write_text(study_text(cases, fixed))
        before = peak_rss_mib()
        t0 = time.perf_counter()
        archive = run_sweep(study, Path(tmp) / "out", workers=workers, progress=False)
        wall = time.perf_counter() - t0
        counts = status_counts(open_archive(archive))
    return {"workers": workers, "cases": cases, "fixed": fixed, "wall_seconds": round(wall, 1),
            "cases_per_hour": round(3600 * cases / wall, 1),
            "driver_peak_rss_mib": round(peak_rss_mib(), 1),
            "driver_peak_rss_growth_mib": round(peak_rss_mib() - before, 1),
            "status": counts}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--cases", type=int, default=60, choices=range(1, 61),
                        metavar="N (1-60)")
    parser.add_argument("--steps-per-rev", type=int, default=None)
    parser.add_argument("--max-revolutions", type=int, default=None)
    parser.add_argument("--periodic-tolerance", type=float, default=None)
    args = parser.parse_args()
    fixed = {k: v for k, v in (("steps_per_rev", args.steps_per_rev),
                               ("max_revolutions", args.max_revolutions),
                               ("periodic_tolerance", args.periodic_tolerance)) if v is not None}
    for workers in args.workers:
        print(json.dumps(sweep_once(workers, args.cases, fixed)), flush=True)


if __name__ == "__main__":
    main()
