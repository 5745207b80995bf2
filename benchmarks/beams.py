"""Geometrically exact beam benchmark: a rotating blade and a cantilever under a step load.

* ``blade`` — 6 cubic elements, a uniform section roughly like a UH-60A blade (EA 3e8 N,
  GA 1.4e7 N both shears, GJ 7e4, EI flap 7.9e4, EI lag 1.35e6 N·m², 10.3 kg/m,
  i22 0.027, i33 0.080 kg·m), 7.8 m long from radius 0.38 m, clamped to a hub spinning at
  27 rad/s about z and started with the rigid rotation; 360 steps per revolution;
* ``cantilever`` — 24 elements, the same section, 10 m, clamped to ground, a 200 N flap
  (z) tip force applied as a step at t = 0; h = 2 ms.

    PYTHONPATH=. python benchmarks/beams.py --revolutions 2 --cantilever-steps 500 [--json]

Prints per case the steps per second of the time loop, the Newton iterations per step, the
loop and set-up wall times (s) and a sanity figure: the blade's tip radial stretch
over the last revolution (mean and range, m, against the static centrifugal stretch, a few
mm: started unstretched, the blade oscillates axially about it) and its largest lag and flap
tip excursions; the cantilever's tip deflection at the end and its largest (m).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from solver.beams import straight_beam
from solver.bodies import ground, spinning
from solver.forces import AppliedLoad
from solver.joints import Rigid
from solver.model import Model
from solver.sections import isotropic_section
from solver.simulation import simulate
from solver.system import System

OMEGA = 27.0  # rad/s
ROOT, LENGTH = 0.38, 7.8  # m
SECTION = dict(EA=3e8, GA2=1.4e7, GA3=1.4e7, GJ=7e4, EI2=7.9e4, EI3=1.35e6, mass=10.3,
               i22=0.027, i33=0.080)
TIP_LOAD = 200.0  # N, flap


def blade_model() -> tuple[Model, object]:
    """The rotating blade: d1 radial, d2 = z × d1 in the plane of rotation (lag), d3 = z
    (flap), so EI2 is the flap and EI3 the lag stiffness."""
    hub = spinning("hub", OMEGA)
    b = straight_beam("blade", (ROOT, 0, 0), (ROOT + LENGTH, 0, 0), isotropic_section(**SECTION),
                      n_elements=6, angular_velocity=(0.0, 0.0, OMEGA), about=(0.0, 0.0, 0.0))
    return Model([hub, b, Rigid("clamp", hub, b.root, point=b.root.position)]), b


def cantilever_model() -> tuple[Model, object]:
    g = ground()
    b = straight_beam("beam", (0, 0, 0), (10.0, 0, 0), isotropic_section(**SECTION),
                      n_elements=24)
    return Model([g, b, Rigid("clamp", g, b.root, point=b.root.position),
                  AppliedLoad("tip", b.tip, force=lambda t: (0.0, 0.0, TIP_LOAD))]), b


def centrifugal_stretch() -> float:
    """Static radial stretch of the tip from N(r) = m Ω² (R² − r²)/2 alone (m)."""
    r = np.linspace(ROOT, ROOT + LENGTH, 2001)
    n = SECTION["mass"] * OMEGA**2 * ((ROOT + LENGTH) ** 2 - r**2) / 2
    return float(np.trapezoid(n / SECTION["EA"], r))


def run(case: str, scheme: str, steps: int, h: float) -> dict:
    t0 = time.perf_counter()
    model, beam = blade_model() if case == "blade" else cantilever_model()
    s = System(model)
    setup = time.perf_counter() - t0
    o = s.offset[beam.tip]
    tips = []
    sim = simulate(model, steps * h, h, scheme=scheme, system=s, record_every=steps,
                   reactions=False, callback=lambda i: tips.append((i.t, i.q[o : o + 3].copy())))
    ds = sim.dataset
    n = int(len(ds.newton_iterations) - 1)
    out = {"case": case, "scheme": scheme, "steps": n, "h": h,
           "seconds": round(sim.seconds, 3), "setup_seconds": round(setup, 3),
           "steps_per_second": round(n / sim.seconds, 1),
           "newton_per_step": round(float(ds.newton_iterations.values[1:].mean()), 3),
           "converged": sim.converged}
    t = np.array([a for a, _ in tips])
    x = np.array([b for _, b in tips])
    if case == "blade":
        # into the hub frame (rotation by −Ωt about z)
        c, sn = np.cos(OMEGA * t), np.sin(OMEGA * t)
        radial = c * x[:, 0] + sn * x[:, 1]
        lag = -sn * x[:, 0] + c * x[:, 1]
        last = t > t[-1] - 2 * np.pi / OMEGA + 0.5 * h  # the last revolution
        stretch = radial[last] - ROOT - LENGTH
        out.update(tip_radial_stretch=float(stretch.mean()),
                   tip_radial_stretch_range=[float(stretch.min()), float(stretch.max())],
                   static_stretch=centrifugal_stretch(),
                   max_abs_flap=float(np.abs(x[:, 2]).max()),
                   max_abs_lag=float(np.abs(lag).max()))
    else:
        out.update(tip_deflection=float(x[-1, 2]), max_tip_deflection=float(x[:, 2].max()))
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--revolutions", type=float, default=2.0)
    p.add_argument("--steps-per-rev", type=int, default=360)
    p.add_argument("--cantilever-steps", type=int, default=500)
    p.add_argument("--cantilever-h", type=float, default=2e-3)
    p.add_argument("--schemes", nargs="+", choices=["ep", "ed", "galpha"],
                   default=["ep", "galpha"])
    p.add_argument("--cases", nargs="+", choices=["blade", "cantilever"],
                   default=["blade", "cantilever"])
    p.add_argument("--repeat", type=int, default=1,
                   help="run each case this many times and keep the fastest")
    p.add_argument("--json", action="store_true", help="print one JSON object per run")
    a = p.parse_args()
    h_blade = 2 * np.pi / OMEGA / a.steps_per_rev
    runs = []
    for case in a.cases:
        for scheme in a.schemes:
            if case == "blade":
                args = (round(a.revolutions * a.steps_per_rev), h_blade)
            else:
                args = (a.cantilever_steps, a.cantilever_h)
            r = min((run(case, scheme, *args) for _ in range(max(1, a.repeat))),
                    key=lambda x: x["seconds"])
            runs.append(r)
            if a.json:
                print(json.dumps(r), flush=True)
    if a.json:
        return
    print(f"{'case':>10} {'scheme':>6} {'steps':>6} {'steps/s':>9} {'newton/step':>11} "
          f"{'loop s':>8} {'setup s':>8}  check")
    for r in runs:
        if r["case"] == "blade":
            lo, hi = r["tip_radial_stretch_range"]
            check = (f"tip stretch {1e3 * r['tip_radial_stretch']:.2f} mm ({1e3 * lo:.2f}…"
                     f"{1e3 * hi:.2f}; static {1e3 * r['static_stretch']:.2f}), "
                     f"|lag| ≤ {1e3 * r['max_abs_lag']:.3g} mm, "
                     f"|flap| ≤ {1e3 * r['max_abs_flap']:.2g} mm")
        else:
            check = (f"tip w {r['tip_deflection']:.4f} m (max {r['max_tip_deflection']:.4f}; "
                     f"static {TIP_LOAD * 1e3 / (3 * SECTION['EI2']):.4f})")
        if not r["converged"]:
            check += "  NOT CONVERGED"
        print(f"{r['case']:>10} {r['scheme']:>6} {r['steps']:>6} {r['steps_per_second']:>9.1f} "
              f"{r['newton_per_step']:>11.2f} {r['seconds']:>8.2f} {r['setup_seconds']:>8.2f}  "
              f"{check}")


if __name__ == "__main__":
    main()
