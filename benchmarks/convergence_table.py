"""Markdown tables of the rotor's vibratory outputs from a sweep archive.

    bifilar sweep studies/inflow_convergence_study.toml --out /tmp/inflow
    python benchmarks/convergence_table.py /tmp/inflow/archive.nc

One row per case (or per value of the last swept parameter, one table per combination of the
others): the 4P hub forces and fuselage moments in the fixed frame, the 3P and 5P rotating hub
motion, blade 0's 3P and 5P root flap shear, the largest 3P pin amplitude, the mean thrust, the
archived step-error and wake error estimates (the step's in brackets where the harmonics are
the step's own, not extrapolated), the revolutions simulated and the case's wall time.
"""

from __future__ import annotations

import argparse
import itertools

import numpy as np

from pipelines.archive import open_archive

HEADER = ("| {key} | 4P Fx, Fy (N) | 4P Fz (N) | 4P Mx, My (N m) | 3P, 5P rotating hub (µm) "
          "| 3P, 5P root flap shear (N) | pins 3P (deg) | thrust (kN) | step, wake error "
          "estimates (%) | revolutions | wall (s) |")


def _estimate(case, name: str) -> str:
    """An archived error estimate in percent ("–" where the case has none, "(x)" where the
    step's was not applied: the harmonics are the step's own)."""
    if name not in case or not np.isfinite(float(case[name])):
        return "–"
    text = f"{100 * float(case[name]):.1f}"
    if name == "run_step_error_estimate" and not int(case.get("run_richardson", 1)):
        text = f"({text})"
    return text


def _row(case) -> str:
    if int(case["status"]) != 0:
        message = str(case["message"].values).split(" (")[0]
        return f"failed: {message} |" + " |" * 9

    def amp(name, k, d=None):
        a = case[name + "_amplitude"].sel(harmonic=k)
        return float(a if d is None else a.sel(direction=d))

    def hub(k):
        return 1e6 * np.hypot(amp("hub_displacement_rotating", k, "x"),
                              amp("hub_displacement_rotating", k, "y"))

    pins = float(case["pin_angle_amplitude"].sel(harmonic=3).max())
    pins_text = f"{pins:.2f}" if pins > 0.0 else "–"  # locked bifilars
    return (f"{amp('hub_force_fixed', 4, 'x'):.0f}, {amp('hub_force_fixed', 4, 'y'):.0f} | "
            f"{amp('hub_force_z_fixed', 4):.0f} | "
            f"{amp('fuselage_moment_fixed', 4, 'x'):.0f}, "
            f"{amp('fuselage_moment_fixed', 4, 'y'):.0f} | {hub(3):.0f}, {hub(5):.1f} | "
            f"{amp('blade_root_shear_flap', 3):.0f}, {amp('blade_root_shear_flap', 5):.0f} | "
            f"{pins_text} | {amp('thrust', 0) / 1e3:.1f} | "
            f"{_estimate(case, 'run_step_error_estimate')}, "
            f"{_estimate(case, 'run_wake_error_estimate')} | "
            f"{float(case['run_simulated_revolutions']):.2f} | "
            f"{float(case['run_wall_time']):.0f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("archive")
    ds = open_archive(parser.parse_args().archive)
    dims = [d for d in ds["status"].dims]
    *outer, last = dims
    for combo in itertools.product(*(ds[d].values for d in outer)):
        if outer:
            print("**" + ", ".join(f"{d} = {v}" for d, v in zip(outer, combo, strict=True))
                  + "**\n")
        print(HEADER.format(key=last))
        print("|" + "---|" * 11)
        sub = ds.sel(dict(zip(outer, combo, strict=True)))
        for value in sub[last].values:
            label = (str(sub["case_name"].sel({last: value}).values)
                     if "case_name" in sub else value)
            print(f"| {label} | " + _row(sub.sel({last: value})))
        print()


if __name__ == "__main__":
    main()
