"""The rotor's flight outputs (studies/rotor.py) against independent answers, on one case.

* ``rotor_power`` (mean drive torque × Ω, from the drive's Lagrange multipliers) against the
  power the air takes from the blades, computed from the lifting lines' airloads and the
  sections' velocities, plus what the dampers dissipate and the pitch links put in;
* ``flap_angle`` (the flap hinge's relative rotation) against blade 0's root slope above the
  hub plane, and ``flapping_cosine``/``flapping_sine`` against the archive's harmonics;
* ``hub_moment_*_fixed`` (the fuselage-beam's top section) against the beam's statics from its
  root moments and the transmitted force;
* the controls are the parameters.

One coarse case serves every test (120 steps/rev, 3 elements and 2 wake states per blade, 3
settling revolutions, periodic to 5 %: 15.5 revolutions, 10–15 s).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import pytest

from solver.forces import RelativeRotation
from studies import rotor
from studies.harmonics import case_harmonics
from tests.studies.helpers import COARSE_ROTOR

# (the recorded revolutions as marched: the step-error estimate's coarser run would also be
# booked, and its extrapolation would move the outputs off the booked rows)
COARSE = COARSE_ROTOR


class _Probe(rotor._Sampler):
    """The case's sampler, also booking at each sample what the outputs are checked
    against (kept beside the rows; the last rows are the recorded revolutions)."""

    booked: ClassVar[list[tuple[float, ...]]] = []

    def __init__(self, system, parts) -> None:
        super().__init__(system, parts)
        els = system.model.elements
        self.dampers = [e for e in els if isinstance(e, RelativeRotation) and e.damping > 0]
        self.pitches = [e for e in els if getattr(e, "name", "").startswith("pitch")]
        self.line_sets = [s for s in system.sets
                          if any(line in s.elements for line in parts.lines)]
        self.o_root0 = system.offset[parts.blades[0].root]

    def __call__(self, integ) -> np.ndarray:
        row = super().__call__(integ)
        s, q, v, parts = self.s, integ.q, integ.v, self.parts
        # the power the air takes from the blades: −Σ g·ẋ ds over the sections, g the
        # generalized airload per span on the section's position and directors (a force at
        # the quarter and mid chord and a pitching moment), ẋ their rates
        air = 0.0
        for ls in self.line_sets:
            x, xd, xa, mu, al = ls._inputs(q, v, integ.qdd)
            g, *_ = ls._kernel(x, xd, xa, mu, al, integ.t)
            air -= float(np.sum(np.einsum("ki,ki->k", g, xd) * ls.ds))
        # the lag dampers and the pins' rolling resistance: c φ̇², φ̇ the relative rate
        dampers = 0.0
        for e in self.dampers:
            axis = s.directors(q, e.body_a) @ s.to_local_vector(e.body_a, e.axis)
            rate = (s.angular_velocity(q, v, e.body_b) - s.angular_velocity(q, v, e.body_a))
            dampers += e.damping * float(rate @ axis) ** 2
        o = s.offset[parts.shaft]
        fuselage = parts.fuselage_damping * float(v[o] ** 2 + v[o + 1] ** 2)
        # the swashplate's power into the blades through the driven pitch bearings: the
        # bearing's moment on the blade times the blade's rate relative to the lag link
        pitch = 0.0
        for j in self.pitches:
            _, m = s.reaction(j, q, integ.lam, integ.t)
            pitch += float(m @ (s.angular_velocity(q, v, j.body_b)
                                - s.angular_velocity(q, v, j.body_a)))
        # blade 0's span axis at its root (d1) in the hub's axes: the root's slope above the
        # hub plane is the flap angle whatever the lag angle (flap, then lag about the flapped
        # shaft axis, then pitch about the span)
        hub = s.directors(q, parts.hub)
        d1 = q[self.o_root0 + 3 : self.o_root0 + 6] @ hub
        slope = math.degrees(math.atan2(d1[2], d1[0]))
        self.booked.append((integ.t, air, dampers, fuselage, pitch, integ.energy(), slope))
        return row


@pytest.fixture(scope="module")
def case():
    """The coarse case's result and its booked rows: the recorded revolutions and the sample
    before them (the energy at the start of the record)."""
    _Probe.booked = []
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(rotor, "_Sampler", _Probe)
        ds = rotor.run(COARSE)
    n = ds.sizes["time"]
    booked = np.array(_Probe.booked[-n - 1 :])
    np.testing.assert_allclose(booked[1:, 0], ds.time.values, rtol=0, atol=1e-12)
    return ds, booked


def test_rotor_power_is_what_the_air_and_the_dampers_take(case):
    """Over the recorded revolutions the shaft power and the pitch links' power go into the
    air, the lag, pin and fuselage dampers and the change of the model's energy; what is left
    is the scheme's numerical dissipation and the rectangle rule."""
    ds, b = case
    air, dampers, fuselage, pitch, energy = b[1:, 1:6].T
    power = float(ds.rotor_power)
    period = 2 * math.pi / float(ds.run_hub_speed)
    change = (energy[-1] - b[0, 5]) / period
    # signs: the rotor absorbs power from the shaft, the air takes it (measured 1.05 MW,
    # 112 kN of thrust at 150 ft/s); the pitch links put in 0.5 kW, the dampers take 20 W
    assert power > 5e5 and air.mean() > 5e5
    assert 0 < pitch.mean() < 2e-3 * power
    balance = power + pitch.mean() - air.mean() - dampers.mean() - fuselage.mean() - change
    # measured: 6.6e-4 of the power here (at the defaults, 240 steps/rev, 4.4e-5); without
    # the energy change 1.2e-3 (defaults: 8.9e-5), and the shaft power alone against the
    # air's 5.6e-4 at the defaults
    assert abs(balance) <= 2e-3 * power, balance / power


def test_flap_angle_is_the_blade_roots_slope_and_its_harmonics(case):
    """β from the flap hinge is blade 0's root slope above the hub plane, positive up
    (coning 5.3° under 112 kN of thrust); β1c, β1s are the flap angle's first harmonics on
    ψ = Ωt as the archive computes them."""
    ds, b = case
    beta = ds.flap_angle.values
    # measured 1.4e-8° (the hinges' constraints hold to Newton's tolerance)
    np.testing.assert_allclose(beta, b[1:, 6], rtol=0, atol=1e-6)
    assert float(ds.thrust.mean()) > 0 and 2.0 < beta.mean() < 10.0
    h = case_harmonics(ds, rotor.SPEC.outputs)
    assert float(ds.flapping_cosine) == pytest.approx(float(h.flap_angle_cos.sel(harmonic=1)),
                                                      rel=1e-12)
    assert float(ds.flapping_sine) == pytest.approx(float(h.flap_angle_sin.sel(harmonic=1)),
                                                    rel=1e-12)
    # fitted directly on the samples' azimuth ψ = Ωt
    psi = float(ds.run_hub_speed) * ds.time.values
    a = np.column_stack([np.ones_like(psi), np.cos(psi), np.sin(psi)])
    coef, *_ = np.linalg.lstsq(a, beta, rcond=None)
    # (a least-squares fit over whole revolutions is the Fourier projection: equal to roundoff)
    np.testing.assert_allclose(coef[1:], [float(ds.flapping_cosine), float(ds.flapping_sine)],
                               rtol=1e-9)


def test_hub_moments_are_the_beams_statics(case):
    """Averaged over whole revolutions the fuselage-beam's inertia drops out (the mean of a
    periodic acceleration is zero), so the mean loads are a static beam's: the moment at the
    top is the root moment less the moment of the top force about the root,
    M_top = M_root − (x_top − x_root) × F."""
    ds, _ = case
    length = float(rotor.SPEC.parameters["fuselage_length"].default)
    force = np.column_stack([ds[f"hub_force_{c}_fixed"].values for c in "xyz"])
    # the top has moved with the hub centre (the beam's axial shortening, 0.1 mm, left out)
    arm = np.column_stack([ds.hub_x_fixed.values, ds.hub_y_fixed.values,
                           np.full(ds.sizes["time"], length)])
    root = np.column_stack([ds.fuselage_moment_x_fixed.values,
                            ds.fuselage_moment_y_fixed.values])
    top = np.column_stack([ds.hub_moment_x_fixed.values, ds.hub_moment_y_fixed.values])
    statics = (root - np.cross(arm, force)[:, :2]).mean(axis=0)
    scale = np.abs(top.mean(axis=0)).max()
    # measured 1.6e-4 of the largest mean (9.6 kN·m about x): 1.5 and 0.13 N·m. With the
    # undeflected arm L ẑ it is 2.8 % off: the 112 kN thrust times the top's 2.4 mm mean
    # deflection
    np.testing.assert_allclose(top.mean(axis=0), statics, rtol=0, atol=5e-4 * scale)
    straight = (root - np.cross([0.0, 0.0, length], force)[:, :2]).mean(axis=0)
    assert np.abs(top.mean(axis=0) - straight).max() > 1e-2 * scale
    # the in-plane vector is archived with its harmonics like the hub force
    h = case_harmonics(ds, rotor.SPEC.outputs)
    assert h.hub_moment_fixed_amplitude.dims == ("direction", "harmonic")
    assert h.hub_moment_fixed_amplitude.attrs["units"] == "N m"


def test_controls_are_the_parameters(case):
    ds, _ = case
    p = rotor.SPEC.validate(COARSE)
    for name in ("collective", "cyclic_sine", "cyclic_cosine", "shaft_tilt"):
        var = ds[f"control_{name}"]
        assert var.dims == () and var.attrs["units"] == "degree"
        assert float(var) == getattr(p, name)
