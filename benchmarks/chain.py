"""N-link pendulum chain benchmark.

Each link: 1 kg, a 1 m slender rod; revolute joints about the global z axis, the first to
ground; gravity 9.81 m/s² along −y; released horizontal (links along +x); h = 1e-3 s.

    python benchmarks/chain.py --links 16 --steps 2000 --scheme ep --json
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from solver.bodies import RigidBody, ground
from solver.forces import Gravity
from solver.joints import Revolute
from solver.model import Model
from solver.simulation import simulate


def chain(links: int) -> Model:
    """The benchmark chain as a model."""
    g = ground()
    model = Model()
    model.add(g, Gravity((0.0, -9.81, 0.0)))
    prev = g
    j_rod = 1.0 / 12.0  # slender rod about its centre, kg·m²
    for i in range(links):
        b = RigidBody(f"link{i}", 1.0, inertia=(0.0, j_rod, j_rod), position=(i + 0.5, 0.0, 0.0))
        model.add(b, Revolute(f"joint{i}", prev, b, point=(float(i), 0.0, 0.0), axis=(0, 0, 1)))
        prev = b
    return model


def run(links: int, steps: int, scheme: str, h: float = 1e-3) -> dict:
    sim = simulate(chain(links), steps * h, h, scheme=scheme, record_every=steps,
                   reactions=False)
    ds = sim.dataset
    e = ds.energy.values
    return {
        "links": links,
        "steps": int(len(e) - 1),
        "scheme": scheme,
        "seconds": round(sim.seconds, 4),
        "steps_per_second": round((len(e) - 1) / sim.seconds, 1),
        "newton_iterations": int(ds.newton_iterations.sum()),
        "factorizations": int(sim.integrator.n_factorizations),
        "energy_drift": float(np.abs(e - e[0]).max()),
        "max_constraint_violation": float(ds.constraint_violation.max()),
        "converged": sim.converged,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--links", type=int, default=16)
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--scheme", choices=["ep", "ed", "galpha"], default="ep")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    a = p.parse_args()
    out = run(a.links, a.steps, a.scheme)
    if a.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:>24}: {v}")


if __name__ == "__main__":
    main()
