"""The paper's validation example (Figs. 10–12): a collar sliding on a circle or a cycloid.

The collar is released at rest at tangent angle θ0 and slides without friction under gravity,
held on the curve by a curve sliding joint. Case 1 (Ip = 0) is a point mass; case 2 (Ip > 0) is
a rigid collar whose orientation the joint's rotation constraints lock to the Frenet triad, so
it spins at κ·ṡ. The period is measured from the simulated motion (zero crossings of the tangent
angle over every simulated period) and compared with Eq. (8), (26) or (27) as corrected by the
errata.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from solver.bodies import PointMass, RigidBody, ground
from solver.curve_joints import ArcLength, CurveSliding
from solver.curves import circle, cycloid
from solver.forces import Gravity
from solver.model import Model
from solver.rotations import rotation_about
from solver.simulation import simulate as simulate_model
from studies.analytic import collar_circle_period, collar_cycloid_period
from studies.measure import period_from_crossings
from studies.parameters import (
    RUN_OUTPUTS,
    ModelSpec,
    Output,
    Param,
    ParameterError,
    Parameters,
    run_facts,
)

PARAMETERS: dict[str, Param] = {
    "curve": Param("circle", "1", "curve the collar slides on", choices=("circle", "cycloid")),
    "theta0": Param(30.0, "degree", "release tangent angle", minimum=0.0, exclusive_minimum=True,
                    maximum=179.0),
    "mass": Param(2.0, "kg", "collar mass", minimum=1e-3, maximum=1e4),
    "radius": Param(1.0, "m", "circle radius R", minimum=1e-3, maximum=1e3),
    "cycloid_a": Param(0.25, "m", "cycloid constant a", minimum=1e-3,
                      maximum=1e3),
    "inertia": Param(0.0, "kg m2", "collar polar moment of inertia Ip (> 0: case 2)",
                     minimum=0.0, maximum=1e4),
    "gravity": Param(9.81, "m s-2", "acceleration of gravity", minimum=0.01,
                     maximum=100.0),
    "scheme": Param("ep", "1", "time integration scheme", choices=("ep", "ed", "galpha")),
    "steps_per_period": Param(1000, "1", "time steps per analytic period", minimum=8,
                              maximum=100000),
    "periods": Param(2.0, "1", "simulated duration in analytic periods", minimum=2.0,
                     maximum=1000.0),
}


# What a run returns; the sweep archive keeps the scalar results and the histories marked
# ``history`` (whole, per case).
OUTPUTS: dict[str, Output] = {
    "time": Output("s", "time", dims=("time",)),
    "theta": Output("degree", "tangent angle of the curve at the collar (from the lowest point)",
                    history=True, figure="collar_angle"),
    "s": Output("m", "arc length travelled (Eq. 25)"),
    "eta": Output("1", "curve parameter"),
    "energy": Output("J", "total energy"),
    "energy_error": Output("1", "relative energy change"),
    "constraint_violation": Output("1", "max |C| (m)"),
    "period": Output("s", "period measured from the motion", dims=()),
    "period_analytic": Output("s", "analytic period (Eqs. 8, 26, 27 with errata)", dims=()),
    "period_error": Output("1", "relative period error", dims=()),
    **RUN_OUTPUTS,
}


def check(p: Parameters) -> None:
    """Cross-parameter validity: the release point must lie on the curve."""
    if p.curve == "cycloid" and not p.theta0 < 90.0:
        raise ParameterError(f"theta0 = {p.theta0:g} degree: on the cycloid the tangent "
                             "angle must be in (0, 90) degree (90 is the cusp)")


def analytic_period(p: Parameters) -> float:
    th = np.radians(p.theta0)
    if p.curve == "circle":
        return collar_circle_period(p.radius, p.gravity, th, p.mass, p.inertia)
    return collar_cycloid_period(p.cycloid_a, p.gravity, th, p.mass, p.inertia)


def build(p: Parameters) -> tuple[Model, CurveSliding, RigidBody | PointMass]:
    """The collar model: ground carrying the curve, the collar, the joint, gravity (−y)."""
    th = np.radians(p.theta0)
    g0 = ground()
    if p.curve == "circle":
        r = p.radius
        # seam of the closed NURBS circle at the top, lowest point at η = 1/2
        curve = circle(r, start_angle=0.5 * np.pi)
        pos = np.array([r * np.sin(th), -r * np.cos(th), 0.0])
    else:
        a = p.cycloid_a
        curve = cycloid(a)
        t = 2.0 * th  # tangent angle φ = t/2 on the paper's cycloid
        pos = np.array([a * (t + np.sin(t)), -a * (1.0 + np.cos(t)), 0.0])
    if p.inertia > 0.0:
        ip = p.inertia
        collar = RigidBody("collar", p.mass, inertia=(0.5 * ip, 0.5 * ip, ip), position=pos,
                           orientation=rotation_about((0, 0, 1), th))
        joint = CurveSliding("slide", g0, curve, collar, rotation=True)
    else:
        collar = PointMass("collar", p.mass, position=pos)
        joint = CurveSliding("slide", g0, curve, collar)
    model = Model()
    model.add(g0, collar, joint, ArcLength(joint), Gravity((0.0, -p.gravity, 0.0)))
    return model, joint, collar


def run(given: Mapping[str, Any] | Parameters = ()) -> xr.Dataset:
    """One collar case from its parameters (validated here unless they are the collar's
    :class:`~studies.parameters.Parameters` already): see :func:`simulate`."""
    return simulate(SPEC.validate(given))


def simulate(p: Parameters) -> xr.Dataset:
    """Simulate one release and return its time histories and the measured period."""
    model, joint, _ = build(p)
    t_ref = analytic_period(p)
    h = t_ref / p.steps_per_period
    sim = simulate_model(model, p.periods * t_ref, h, scheme=p.scheme, reactions=False)
    ds = sim.dataset
    eta = ds.scalar_value.sel(scalar="slide.eta").values
    s_arc = ds.scalar_value.sel(scalar="slide.s").values
    tang = joint.curve.frame(eta)[0][:, :, 0]
    theta = np.degrees(np.arctan2(tang[:, 1], tang[:, 0]))
    t = ds.time.values
    period = period_from_crossings(t, theta, center=0.0) if sim.converged else float("nan")
    e = ds.energy.values
    return SPEC.dataset({
        **run_facts(sim, h),
        "time": t,
        "theta": theta,
        "s": s_arc - s_arc[0] * 0,
        "eta": eta,
        "energy": e,
        "energy_error": (e - e[0]) / abs(e[0]) if e[0] else e - e[0],
        "constraint_violation": ds.constraint_violation.values,
        "period": period,
        "period_analytic": t_ref,
        "period_error": period / t_ref - 1.0,
    }, {"message": sim.message})


SPEC = ModelSpec("collar", PARAMETERS, simulate, check,
                 description="collar sliding on a circle or cycloid (paper Figs. 10-12)",
                 outputs=OUTPUTS, version="2")
