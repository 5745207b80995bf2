"""Seconds per branch point of the hub model, by harmonic balance and by shooting.

    python benchmarks/branches.py [--shooting-points 4]

Continues the jump study's circular-hole case (free bifilars tuned at 2.95P, the 3P shear
from 200 N to 8 kN; ``studies/jump_study.toml``) by harmonic balance on the swing
coordinates, and a short stretch of the same branch by shooting on the multibody model's
quarter-revolution map (``method = "shooting"``, 80 steps/rev), in this process, and prints one
JSON object per method: the points, folds, wall time, seconds per point, and for shooting the
revolutions simulated per point. It also times one plain hub run with and without its Floquet
multipliers (``floquet``).
"""

from __future__ import annotations

import argparse
import json
import time

from studies import hub
from studies.branches import continuation_settings
from studies.hub_branches import balance_branch, shooting_branch

JUMP = {"bifilar": "free", "tuning_order": 2.95, "hole": "circle"}


def timed_branch(method: str, points: int) -> dict:
    if method == "harmonic_balance":
        p = hub.SPEC.validate({**JUMP, "excitation_3p": 200.0})
        table = {"parameter": "excitation_3p", "start": 200.0, "stop": 8000.0}
        run = balance_branch
    else:
        p = hub.SPEC.validate({**JUMP, "excitation_3p": 3000.0, "steps_per_rev": 80})
        table = {"parameter": "excitation_3p", "start": 3000.0, "stop": 4000.0,
                 "max_points": points, "method": "shooting"}
        run = shooting_branch
    c = continuation_settings(table, hub.SPEC.parameters)
    t0 = time.perf_counter()
    found = run(p, c)
    wall = time.perf_counter() - t0
    out = {"method": method, "points": len(found), "folds": sum(pt.fold for pt in found),
           "wall_s": round(wall, 2), "s_per_point": round(wall / len(found), 3)}
    if method == "shooting":
        revs = max(float(pt.result.run_simulated_revolutions) for pt in found)
        out["revolutions_per_point"] = round(revs / len(found), 1)
    return out


def timed_run(floquet: bool) -> dict:
    p = hub.SPEC.validate({"floquet": floquet})
    hub.simulate(p)  # warm-up: the compiled kernels loaded
    t0 = time.perf_counter()
    hub.simulate(p)
    return {"hub_run_floquet": floquet, "wall_s": round(time.perf_counter() - t0, 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shooting-points", type=int, default=4)
    args = parser.parse_args()
    for result in (timed_branch("harmonic_balance", 0),
                   timed_branch("shooting", args.shooting_points),
                   timed_run(False), timed_run(True)):
        print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
