"""Aerodynamics benchmark: a hovering rigid rotor with lifting lines and a dynamic inflow.

Four rigid blades (prescribed spin at 30 rad/s about z, collective 8°, radius 5 m, chord
0.3 m, root cut-out 0.2R), four Gauss sections per blade, Peters finite-state wake states per
section (``--states``, default 8) and the Pitt–Peters inflow (or ``--inflow peters-he`` with
M = P = 4); 96 steps per revolution with ``ep``.

    PYTHONPATH=. python benchmarks/aero.py --revolutions 4 [--states 8] [--inflow pitt-peters]

Prints the unknowns, the steps per second of the time loop, the Newton iterations per step,
the set-up and loop wall times (s) and the thrust coefficient at the end against the
closed-form blade-element/momentum value (tests/solver/lifting_line_models.py).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

# the hovering rotor is the lifting-line tests' model: the repository root on the path
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from solver.simulation import simulate
from solver.system import System
from tests.solver.lifting_line_models import OMEGA, hover_closed_form, rotor


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--revolutions", type=float, default=4.0)
    p.add_argument("--states", type=int, default=8)
    p.add_argument("--inflow", default="pitt-peters", choices=["pitt-peters", "peters-he"])
    p.add_argument("--json", action="store_true")
    a = p.parse_args()
    theta = np.radians(8.0)
    kw = {"harmonics": 4, "power": 4} if a.inflow == "peters-he" else {}
    t0 = time.perf_counter()
    model, inflow, _ = rotor(theta, inflow_model=a.inflow, n=a.states, **kw)
    system = System(model)
    setup = time.perf_counter() - t0
    spr = 96
    t1 = time.perf_counter()
    sim = simulate(model, a.revolutions * 2 * np.pi / OMEGA, 2 * np.pi / OMEGA / spr,
                   reactions=False, system=system, record_every=10**9)
    loop = time.perf_counter() - t1
    steps = round(a.revolutions * spr)
    o = system.offset[inflow]
    res = {"unknowns": system.n, "steps": steps, "steps_per_s": steps / loop,
           "newton_per_step": float(sim.dataset["newton_iterations"].mean()),
           "setup_s": setup, "loop_s": loop, "converged": bool(sim.converged),
           "lambda0": float(sim.integrator.q[o]),
           "lambda0_closed_form": hover_closed_form(theta)[0]}
    if a.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k:>22}: {v}")


if __name__ == "__main__":
    main()
