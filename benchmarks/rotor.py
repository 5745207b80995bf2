"""Rotor benchmark: the UH-60 rotor model (studies/rotor.py) per revolution and per case.

    PYTHONPATH=. python benchmarks/rotor.py --revolutions 2 [--bifilar free] [--scheme ed]
                                             [--inflow peters_he] [--aero-points 2] [--profile]
                                             [--control-system swashplate]
                                             [--fuselage modal] [--fuselage-modes FILE]
    PYTHONPATH=. python benchmarks/rotor.py --case [--bifilar free]     # one whole case
    PYTHONPATH=. python benchmarks/rotor.py --case --no-floquet         # without its multipliers
    PYTHONPATH=. python benchmarks/rotor.py --case --no-estimate        # without its step error
    PYTHONPATH=. python benchmarks/rotor.py --case --trim wind_tunnel   # trimmed, and untrimmed
    PYTHONPATH=. python benchmarks/rotor.py --case --progress           # its stages, timed
    PYTHONPATH=. python benchmarks/rotor.py --wake-update               # one wake update

The first form builds the model with its defaults (``--steps-per-rev`` to change them), marches
``--revolutions`` revolutions and prints the unknowns, the set-up time, the wall time per
revolution, steps per second and Newton iterations per step; ``--profile`` runs the loop under
pyinstrument and prints the profile (the modules that take the time). The second runs one case
as the sweep does (settling, marching until periodic, recording) and prints its wall time,
revolutions (those of the step-error estimate's coarser step among them) and Newton iterations
per step, its step-error estimate (``--no-estimate``: none, and no extrapolation), its largest
Floquet multiplier (``--no-floquet``: none) and, with the prescribed wake, its updates
(``--progress``: the case's progress lines on stderr, each after the seconds since the case
began: where its revolutions and time go); with
``--trim`` it runs the case trimmed and untrimmed and prints both, the trim's control updates,
its residuals and the revolutions' ratio (``--coarse``: the coarse case of the tests, 120
steps/rev, 3 elements, 3 settling revolutions, periodic to 5 %, Peters–He alone unless
``--inflow`` says otherwise). The third times one update
of the prescribed wake (Biot–Savart over the revolution's azimuths at blade 0's sections) at
the model's wake parameters. ``--control-system swashplate`` runs any of them with the
swashplate's pitch links instead of the driven pitch bearings (``prescribed``, the default);
``--fuselage modal`` on the modal airframe (``--fuselage-modes``: its file, default the shipped
UH-60A-class one) instead of the fuselage-beam.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time

import numpy as np

from solver.system import System
from studies.parameters import Parameters
from studies.progress import reporting
from studies.rotor import SPEC, build, integrator, run


def per_revolution(p: Parameters, revolutions: int, profile: bool) -> dict:
    t0 = time.perf_counter()
    model, parts = build(p)
    system = System(model)
    integ = integrator(system, p, 2 * np.pi / p.hub_speed / p.steps_per_rev, parts)
    setup = time.perf_counter() - t0
    profiler = None
    if profile:
        from pyinstrument import Profiler

        profiler = Profiler()
        profiler.start()
    t1 = time.perf_counter()
    for _ in range(revolutions * p.steps_per_rev):
        info = integ.step()
        if not info.converged:
            raise SystemExit(f"step failed at t = {integ.t:.4g} s: {info.message}")
    loop = time.perf_counter() - t1
    if profiler is not None:
        profiler.stop()
        print(profiler.output_text(unicode=True, color=False, show_all=False))
    return {"bifilar": p.bifilar, "inflow": p.inflow, "control_system": p.control_system,
            "fuselage": p.fuselage, "unknowns": system.n, "steps_per_rev": p.steps_per_rev,
            "setup_s": round(setup, 2), "seconds_per_rev": round(loop / revolutions, 2),
            "steps_per_s": round(integ.n_steps / loop, 2),
            "newton_per_step": round(integ.n_iterations / integ.n_steps, 2)}


def per_case(p: Parameters, progress: bool = False) -> dict:
    t0 = time.perf_counter()

    def say(line: str) -> None:
        print(f"{time.perf_counter() - t0:7.1f} s  {line}", file=sys.stderr, flush=True)

    with reporting(say) if progress else contextlib.nullcontext():
        ds = run(p)
    wall = time.perf_counter() - t0
    revs = ds["run_simulated_revolutions"].item()
    return {"bifilar": p.bifilar, "inflow": p.inflow, "trim": p.trim, "wall_s": round(wall, 1),
            "revolutions": revs, "wake_updates": int(ds["run_wake_updates"].item()),
            "estimate_revolutions": ds["run_estimate_revolutions"].item(),
            "step_error_estimate": round(float(ds.get("run_step_error_estimate", np.nan)), 4),
            "floquet_multiplier_max": round(float(ds.get("floquet_multiplier_max", np.nan)), 4),
            "seconds_per_rev": round(wall / revs, 2),
            "newton_per_step": round(
                ds["run_newton_iterations"].item() / ds["run_steps"].item(), 2),
            "thrust_coefficient_over_solidity": round(
                ds["thrust_coefficient_over_solidity"].item(), 4),
            "trim_iterations": int(ds["trim_iterations"].item()),
            "trim_residual_thrust": float(f"{ds['trim_residual_thrust'].item():.3g}"),
            "flapping_deg": [round(ds["flapping_cosine"].item(), 4),
                             round(ds["flapping_sine"].item(), 4)],
            "hub_moment_mean": [round(float(ds[f"hub_moment_{c}_fixed"].mean()), 1)
                                for c in "xy"],
            "controls_deg": [round(ds[f"control_{c}"].item(), 3) for c in (
                "collective", "cyclic_cosine", "cyclic_sine", "shaft_tilt")]}


def wake_update(p: Parameters) -> dict:
    wake = build(p)[1].wake
    wake.filled[:] = True  # the started wake's histories stand for a recorded revolution
    wake.thrust[:] = 90e3
    t0 = time.perf_counter()
    wake.update()
    seconds = time.perf_counter() - t0
    segments = round(p.wake_turns * p.wake_segments_per_turn) * 4
    return {"azimuths": p.steps_per_rev, "sections": wake.table.shape[1],
            "segments": segments, "seconds_per_update": round(seconds, 3)}


def main() -> None:
    a = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    a.add_argument("--revolutions", type=int, default=2)
    a.add_argument("--bifilar", default="free", choices=["free", "locked", "equivalent"])
    a.add_argument("--steps-per-rev", type=int, default=None)
    a.add_argument("--scheme", default=None, choices=["galpha", "ed", "ep"],
                   help="time integration scheme (default: the model's, galpha)")
    a.add_argument("--profile", action="store_true")
    a.add_argument("--inflow", default=None, choices=["peters_he", "prescribed_wake"],
                   help="the rotor's inflow model (default: the model's, the prescribed wake)")
    a.add_argument("--aero-points", type=int, default=None,
                   help="aerodynamic sections per blade element (default: the model's, 3)")
    a.add_argument("--case", action="store_true", help="run one whole case")
    a.add_argument("--progress", action="store_true",
                   help="with --case: print its progress lines, timed, on stderr")
    a.add_argument("--trim", default=None, choices=["wind_tunnel", "propulsive"],
                   help="with --case: run it trimmed and untrimmed")
    a.add_argument("--coarse", action="store_true",
                   help="the coarse case of the tests (120 steps/rev, 3 elements)")
    a.add_argument("--no-floquet", action="store_true",
                   help="with --case: without the Floquet multipliers")
    a.add_argument("--no-estimate", action="store_true",
                   help="with --case: without the step-error estimate and extrapolation")
    a.add_argument("--wake-update", action="store_true",
                   help="time one update of the prescribed wake")
    a.add_argument("--control-system", default="prescribed",
                   choices=list(SPEC.parameters["control_system"].choices),
                   help="driven pitch bearings (prescribed) or the swashplate's pitch links")
    a.add_argument("--fuselage", default="beam", choices=list(SPEC.parameters["fuselage"].choices),
                   help="the fuselage-beam (beam) or a modal airframe (modal)")
    a.add_argument("--fuselage-modes", default="",
                   help="the modal airframe file (default: the shipped UH-60A-class one)")
    args = a.parse_args()
    given = {"bifilar": args.bifilar, "floquet": not args.no_floquet,
             "error_estimate": not args.no_estimate, "richardson": not args.no_estimate,
             "control_system": args.control_system, "fuselage": args.fuselage,
             "fuselage_modes": args.fuselage_modes}
    if args.inflow:
        given["inflow"] = args.inflow
    if args.aero_points:
        given["aero_points"] = args.aero_points
    if args.steps_per_rev:
        given["steps_per_rev"] = args.steps_per_rev
    if args.scheme:
        given["scheme"] = args.scheme
    if args.coarse:
        given = {"inflow": "peters_he", "aero_points": 2, **given, "steps_per_rev": 120,
                 "blade_elements": 3, "wake_states": 2, "settle_revolutions": 3,
                 "periodic_tolerance": 0.05}
    p = SPEC.validate(given)
    if args.wake_update:
        res = wake_update(SPEC.validate({**given, "inflow": "prescribed_wake"}))
    elif args.case and args.trim:
        plain = per_case(p, args.progress)
        print(json.dumps(plain))
        res = per_case(SPEC.validate({**given, "trim": args.trim}), args.progress)
        res["revolutions_ratio"] = round(res["revolutions"] / plain["revolutions"], 2)
    elif args.case:
        res = per_case(p, args.progress)
    else:
        res = per_revolution(p, args.revolutions, args.profile)
    print(json.dumps(res))


if __name__ == "__main__":
    main()
