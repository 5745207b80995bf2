"""Reference numbers of the studies, to show that a refactor changes no result.

Runs the collar (both curves, both cases, all three schemes), the pendulum (circle, cycloid and
epicycloid holes), the chain (N = 4, all schemes) and one free hub case through their public
entry points, stores every numeric output in an ``.npz`` file and prints the CPU time of each
run. ``--compare OLD NEW`` prints the largest relative difference of each stored array.

    python benchmarks/reference.py --out /tmp/new.npz
    python benchmarks/reference.py --compare /tmp/old.npz /tmp/new.npz
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _numeric(prefix: str, ds, out: dict) -> None:
    for name, var in ds.data_vars.items():
        if var.dtype.kind in "fiu":
            out[f"{prefix}/{name}"] = np.asarray(var.values, dtype=float)


def collect(include_hub: bool = True) -> dict:
    from chain import chain  # benchmarks/ is on the path when run as a script

    from solver.simulation import simulate
    from studies import bifilar, collar, hub

    out: dict[str, np.ndarray] = {}
    cpu: dict[str, float] = {}

    def timed(key, fn):
        t0 = time.process_time()
        res = fn()
        cpu[key] = time.process_time() - t0
        return res

    for curve in ("circle", "cycloid"):
        for inertia in (0.0, 0.5):
            for scheme in ("ep", "ed", "galpha"):
                key = f"collar_{curve}_{inertia:g}_{scheme}"
                p = {"curve": curve, "theta0": 40.0, "inertia": inertia, "scheme": scheme,
                     "steps_per_period": 200, "periods": 2.0}
                _numeric(key, timed(key, lambda p=p: collar.run(p)), out)
    for hole in ("circle", "cycloid", "epicycloid"):
        for scheme in ("ep", "ed", "galpha"):
            key = f"pendulum_{hole}_{scheme}"
            p = {"hole": hole, "amplitude": 20.0, "scheme": scheme, "periods": 2.0,
                 "steps_per_period": 100, "pin_damping": 1e-3}
            _numeric(key, timed(key, lambda p=p: bifilar.run(p)), out)
    for scheme in ("ep", "ed", "galpha"):
        key = f"chain4_{scheme}"
        sim = timed(key, lambda s=scheme: simulate(chain(4), 0.5, 1e-3, scheme=s,
                                                   reactions=True, record_every=10))
        _numeric(key, sim.dataset, out)
    if include_hub:
        ds = timed("hub_free", lambda: hub.run({}))
        _numeric("hub_free", ds, out)
        out["hub_free/steps"] = np.array(float(ds["run_steps"].item()))
        out["hub_free/newton_iterations"] = np.array(float(ds["run_newton_iterations"].item()))
    for k, v in cpu.items():
        print(f"{k:>28}: {v:8.3f} s CPU")
    return out


def compare(a_path: str, b_path: str) -> float:
    """Print, per stored array, the largest difference relative to its largest value; arrays
    that are roundoff diagnostics (all below 1e-9: constraint violations, energy errors,
    rolling residuals) and iteration counts are shown but not counted in the verdict."""
    a, b = np.load(a_path), np.load(b_path)
    worst, worst_key = 0.0, ""
    for key in sorted(set(a.files) | set(b.files)):
        if key not in a.files or key not in b.files:
            print(f"{key:>50}: only in {'new' if key not in a.files else 'old'}")
            continue
        x, y = a[key], b[key]
        if x.shape != y.shape:
            print(f"{key:>50}: shapes differ {x.shape} vs {y.shape}")
            worst, worst_key = np.inf, key
            continue
        with np.errstate(all="ignore"):
            scale = float(np.nanmax(np.abs(x))) if x.size and np.isfinite(x).any() else 0.0
            diff = float(np.nanmax(np.abs(x - y))) if x.size and np.isfinite(x).any() else 0.0
        if scale < 1e-9 or key.endswith("newton_iterations"):
            with np.errstate(all="ignore"):
                other = float(np.nanmax(np.abs(y))) if np.isfinite(y).any() else 0.0
            print(f"{key:>50}: (diagnostic) old max {scale:.2e}, new max {other:.2e}")
            continue
        d = diff / scale
        if d > worst:
            worst, worst_key = d, key
        print(f"{key:>50}: {d:.2e}")
    print(f"largest relative difference: {worst:.2e} ({worst_key})")
    return worst


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", help="write the reference numbers to this .npz")
    p.add_argument("--no-hub", action="store_true", help="skip the hub case (~30 s)")
    p.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"))
    a = p.parse_args()
    if a.compare:
        compare(*a.compare)
        return
    out = collect(include_hub=not a.no_hub)
    if a.out:
        np.savez(a.out, **out)


if __name__ == "__main__":
    main()
