"""Lifting-line models shared by the lifting-line and aerodynamic-kernel tests.

* :func:`rotor` — rigid blades in prescribed spin with lifting lines and a dynamic inflow.
* :func:`hover_closed_form` — that rotor's hover inflow and thrust in closed form.
* :func:`wing_beam` — a straight elastic beam to carry a lifting line.
* :func:`beam_line` — a twisted beam line in forward flight with a Peters–He inflow (and a
  prescribed periodic wind).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import brentq

from solver.air import FlightCondition
from solver.beams import straight_beam
from solver.bodies import PrescribedBody
from solver.inflow import DynamicInflow
from solver.lifting_line import LiftingLine
from solver.model import Model
from solver.rotations import rotation_about
from solver.section_wind import PeriodicWind
from solver.sections import isotropic_section

RHO = 1.225  # air density, kg/m³
# rotor radius (m), speed (rad/s), chord (m), blade count, root cut-out (of R), lift slope (1/rad)
R_ROTOR, OMEGA, CHORD, NB, X0, SLOPE = 5.0, 30.0, 0.3, 4, 0.2, 5.7


def rotor(theta, inflow_model="pitt-peters", n=4, flight=None, **kw):
    """NB rigid blades (prescribed spin about z, pitch θ) with lifting lines and an inflow."""
    flight = flight or FlightCondition(0.0, 0.0, RHO)
    inflow = DynamicInflow("inflow", flight, R_ROTOR, OMEGA, model=inflow_model,
                           initial_thrust=0.005, **kw)
    model = Model()
    model.add(inflow)
    lines = []
    for k in range(NB):
        psi0 = 2 * np.pi * k / NB

        def motion(t, psi0=psi0):
            r = rotation_about((0, 0, 1), psi0 + OMEGA * t) @ rotation_about((1, 0, 0), theta)
            return np.zeros(3), r, np.zeros(3), np.array([0, 0, OMEGA]), np.zeros(3), np.zeros(3)

        blade = PrescribedBody(f"blade{k}", motion)
        lines.append(LiftingLine(f"line{k}", blade, flight, chord=CHORD, span=(X0 * R_ROTOR,
                                 R_ROTOR), lift_slope=SLOPE, wake_states=n, inflow=inflow))
        model.add(blade, lines[-1])
    return model, inflow, lines


def hover_closed_form(theta):
    """Hover's uniform inflow λ and C_T of :func:`rotor` at pitch θ: blade element
    (Kutta–Joukowski on sections of pitch θ) closed by momentum theory λ = √(C_T/2)."""
    sigma = NB * CHORD / (np.pi * R_ROTOR)

    def ct(lam):
        return sigma * SLOPE / 2 * ((1 - X0**3) * np.sin(theta) / 3
                                    - lam * (1 - X0**2) * np.cos(theta) / 2)

    lam = brentq(lambda x: 2 * x * x - ct(x), 1e-9, 0.5)
    return lam, ct(lam)


def wing_beam(n_el=2, length=2.0):
    """A straight isotropic beam along +y (d3 up), ``n_el`` elements of total ``length``."""
    sec = isotropic_section(EA=1e7, GA2=1e6, GA3=1e6, GJ=5e3, EI2=2e4, EI3=8e4, mass=2.0,
                            i22=1e-3, i33=4e-3)
    return straight_beam("wing", (0, 0, 0), (0, length, 0), sec, n_elements=n_el,
                         e3=(0, 0, 1))


def beam_line(zero_lift_angle: float = 0.0, wind: bool = False) -> tuple[Model, LiftingLine]:
    """A twisted two-element beam line in forward flight with a Peters–He inflow; with
    ``wind``, also a prescribed periodic wind of a few m/s at the sections (random samples)."""
    flight = FlightCondition(40.0, 0.05, RHO)
    beam = wing_beam(n_el=2, length=4.0)
    inflow = DynamicInflow("inflow", flight, 4.0, 20.0, model="peters-he", harmonics=2,
                           power=3, initial_thrust=0.004)
    line = LiftingLine("aero", beam, flight, chord=0.3, pitch=lambda s: 0.1 - 0.02 * s,
                       quarter_chord=0.02, drag=0.01, lift_slope=5.7, wake_states=4,
                       inflow=inflow, span=(0.5, 4.0), lift_end=3.8, points=3,
                       zero_lift_angle=zero_lift_angle)
    if wind:
        table = 3.0 * np.random.default_rng(5).standard_normal((16, line.n_sections, 3))
        line = dataclasses.replace(line, wind=PeriodicWind(0.3, table, delay=0.02))
    model = Model()
    model.add(beam, inflow, line)
    return model, line
