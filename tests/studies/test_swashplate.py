"""The swashplate control system (studies/swashplate.py, the rotor's and the fan plot's
``control_system = "swashplate"``) against independent answers.

* the ring's stroke closes the rigid linkage (its length computed here from the two ends) and
  its derivatives are those of finite differences; the linkage's arm is the link length's rate
  with the pitch;
* with a very stiff link, and the blades' flap and lag hinges locked (where the linkage has no
  kinematic coupling), the rotor's blades follow the commanded pitch history to 1e-8 rad, and
  the pitch-link load is the root torsion over the linkage's arm (static balance of the root);
* the fan plot's blade on its pitch link has the natural frequencies of the same blade on a
  free pitch bearing with a root torsion spring k h² (the link's restraint in closed form), and
  a very stiff link those of the locked bearing;
* the parameters are validated at their bounds.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import pytest

from solver.equilibrium import Spin
from solver.forces import RelativeRotation
from solver.joints import Orientation, Revolute
from solver.model import Model
from solver.modes import natural_frequencies
from solver.system import System
from studies import fanplot as fanplot_model
from studies import rotor, swashplate, trim
from studies.blade import articulated_blade
from studies.parameters import ParameterError
from tests.studies.helpers import COARSE_ROTOR
from tests.studies.test_rotor_outputs import _Probe as _PowerProbe

H, L = swashplate.PARAMETERS["pitch_horn_length"].default, swashplate.PITCH_LINK_LENGTH


@pytest.mark.parametrize("theta", [-0.3, -0.05, 0.0, 0.1, 0.35])
def test_ring_height_closes_the_linkage(theta):
    """The horn's end at h (cos θ, sin θ) and the ring's point at (h, z − L) in the blade's
    (e_t, z) plane are L apart (measured 1.1e-16 m); dz/dθ, d²z/dθ² are z's central
    differences (measured 5.4e-12 m/rad, and 1.2e-6 m/rad² from the second difference's
    roundoff); the arm is ∂ℓ/∂θ of the link's length at a fixed ring point (measured
    5.6e-12 m)."""
    z, dz, ddz = swashplate.ring_height(theta, H, L)

    def length(th, zz):
        return math.hypot(H * math.cos(th) - H, H * math.sin(th) - (zz - L))

    assert length(theta, z) == pytest.approx(L, abs=1e-14)
    eps = 1e-5
    zp, zm = (swashplate.ring_height(theta + s, H, L)[0] for s in (eps, -eps))
    assert dz == pytest.approx((zp - zm) / (2 * eps), abs=1e-9)
    assert ddz == pytest.approx((zp - 2 * z + zm) / eps**2, abs=1e-4)
    arm = (length(theta + eps, z) - length(theta - eps, z)) / (2 * eps)
    assert swashplate.horn_arm(theta, H, L) == pytest.approx(arm, abs=1e-9)


@pytest.mark.parametrize("given, match", [
    ({"pitch_link_stiffness": -1.0}, "pitch_link_stiffness = -1 N m-1: outside"),
    ({"pitch_link_stiffness": 0.0}, "pitch_link_stiffness = 0 N m-1: outside"),
    ({"pitch_horn_length": 0.0}, "pitch_horn_length = 0 m: outside"),
    ({"pitch_horn_length": 0.5}, "pitch_horn_length = 0.5 m: outside"),
    ({"control_system": "cyclic"}, "control_system"),
])
def test_parameters_validated(given, match):
    """The rotor and the fan plot share the parameters and their ranges: a clear
    ParameterError naming the parameter, its value and the range; the blade model checks a
    direct call the same way."""
    with pytest.raises(ParameterError, match=match):
        rotor.SPEC.validate(given)
    with pytest.raises(ParameterError, match=match):
        fanplot_model.SPEC.validate(given)
    kw = {"control_system": "swashplate", **given}
    with pytest.raises(ParameterError, match=match.split(" = ")[0]):
        articulated_blade(27.0, **kw)


def _locked_rotor(stiffness: float):
    """The coarse rotor with pitch links of ``stiffness``, its flap and lag hinges locked (an
    Orientation joint about each hinge's axis): the linkage then holds the pitch alone."""
    p = rotor.SPEC.validate({**COARSE_ROTOR, "control_system": "swashplate",
                             "pitch_link_stiffness": stiffness})
    model, parts = rotor.build(p)
    named = {getattr(e, "name", None): e for e in model.elements}
    z = np.array([0.0, 0.0, 1.0])
    for k in range(rotor.N_BLADES):
        psi = k * math.pi / 2
        et = np.array([-math.sin(psi), math.cos(psi), 0.0])
        model.add(Orientation(f"flap_lock{k}", parts.hub, named[f"flap_link{k}"], axis=et,
                              axes=(2,)),
                  Orientation(f"lag_lock{k}", named[f"flap_link{k}"], named[f"lag_link{k}"],
                              axis=z, axes=(2,)))
    return p, model, parts, named


def test_stiff_pitch_links_give_the_commanded_pitch():
    """k = 1e13 N/m, flap and lag locked, half a revolution from the start (the forward-flight
    airloads, 120 steps/rev, Newton to 1e-12): every blade's pitch (its bearing's angle plus
    the built pitch) is the commanded θ0 + θc cos ψ + θs sin ψ. Measured 2.5e-9 rad, the
    link's stretch T/(k h) for the loads of up to 3.4 kN (5e-10 rad per kN; at 1e12 N/m
    2.5e-8 rad). Blade 0's link load is its root torsion over the linkage's arm at that pitch:
    measured 3e-10 relative (the root section's d1 is the pitch axis, the bearing carries no
    pitch moment)."""
    p, model, parts, named = _locked_rotor(1e13)
    system = System(model)
    h = 2 * math.pi / p.hub_speed / p.steps_per_rev
    integ = rotor.integrator(system, p, h, parts, tol=1e-12)
    sampler = rotor._Sampler(system, parts)
    schedule = trim.schedule(p)
    commands = [schedule.pitch(k * math.pi / 2, 0.0) for k in range(rotor.N_BLADES)]
    built = [c.value(0.0) for c in commands]
    worst = balance = 0.0
    col = rotor._Sampler.COLUMNS.index
    for _ in range(p.steps_per_rev // 2):
        integ.step()
        for k in range(rotor.N_BLADES):
            theta = built[k] + system.joint_angle(named[f"pitch{k}"], integ.q)
            worst = max(worst, abs(theta - commands[k].value(integ.t)))
        row = sampler(integ)
        arm = swashplate.horn_arm(commands[0].value(integ.t), p.pitch_horn_length)
        balance = max(balance, abs(row[col("link")] - row[col("t1")] / arm)
                      / abs(row[col("link")]))
    assert worst <= 1e-8
    assert balance <= 1e-7


# ------------------------------------------------------------------------------ fan plot
OMEGA = 27.0


def _frequencies(model: Model) -> np.ndarray:
    """The ten lowest natural frequencies (Hz) about the steady spin at 27 rad/s."""
    md = natural_frequencies(System(model), spin=Spin(OMEGA, (0.0, 0.0, 1.0)))
    return np.sort(md.frequency)[:10]


@pytest.mark.slow
def test_pitch_link_frequencies_against_a_root_torsion_spring():
    """The blade on its pitch link (k = 3e6 N/m on h = 0.2 m) against the same blade with the
    link replaced by a rotational spring k h² = 1.2e5 N·m/rad on the free pitch bearing
    (solver.forces.RelativeRotation): the link's restraint to first order, its pull along the
    link adding nothing at zero pitch, where the horn lies on the flap axis and across the lag
    motion. The ten lowest modes (flap, lag and the coupled torsion modes; the
    torsion-dominated one at 4.505/rev, 4.863/rev with a rigid link): measured within 3.6e-5
    relative. A stiff link (1e9 N/m) gives the locked bearing's frequencies: measured within
    1.7e-4 (its k h² = 4e7 N·m/rad against the blade's GJ/L ≈ 1e4 N·m/rad)."""
    k = 3e6
    linked, beam = articulated_blade(OMEGA, control_system="swashplate",
                                     pitch_link_stiffness=k, pitch_horn_length=H)
    kept = [e for e in linked.elements if getattr(e, "name", "") != "pitch_link0"]
    lag_link = next(e for e in kept if getattr(e, "name", "") == "lag_link")
    sprung = Model([*kept, RelativeRotation("pitch_spring", lag_link, beam.root,
                                            axis=(1.0, 0.0, 0.0), stiffness=k * H**2)])
    f_link, f_spring = _frequencies(linked), _frequencies(sprung)
    np.testing.assert_allclose(f_link, f_spring, rtol=1e-2)
    # the restraint matters: the modes near 4.5-5.2/rev moved from the rigid link's
    f_rigid = _frequencies(articulated_blade(OMEGA)[0])
    assert np.abs(f_link / f_rigid - 1).max() > 0.02
    stiff = articulated_blade(OMEGA, control_system="swashplate", pitch_link_stiffness=1e9,
                              pitch_horn_length=H)[0]
    np.testing.assert_allclose(_frequencies(stiff), f_rigid, rtol=1e-3)


# --------------------------------------------------------------------------- flying rotor
class _SwashProbe(rotor._Sampler):
    """The case's sampler, also booking the power balance's terms (test_rotor_outputs's
    probe) with the swashplate's power, and blade 0's pitch against its command."""

    booked: ClassVar[list[tuple[float, ...]]] = []

    def __init__(self, system, parts) -> None:
        super().__init__(system, parts)
        self.base = _PowerProbe(system, parts)
        # the bearings' power (zero: free bearings), not the links' (forces, not joints)
        self.base.pitches = [j for j in self.base.pitches if isinstance(j, Revolute)]
        named = {getattr(e, "name", None): e for e in system.model.elements}
        self.drives = [named[f"ring_drive{k}"] for k in range(rotor.N_BLADES)]
        self.pitch0 = named["pitch0"]

    def __call__(self, integ) -> np.ndarray:
        row = super().__call__(integ)
        self.base(integ)
        s, q, v = self.s, integ.q, integ.v
        hub = self.parts.hub
        o_hub = s.offset[hub]
        w_hub = s.angular_velocity(q, v, hub)
        # the swashplate's power: each ring drive's force on its ring point times the point's
        # velocity relative to the hub (their rotations are locked together)
        swash = 0.0
        for j in self.drives:
            f, _ = s.reaction(j, q, integ.lam, integ.t)
            o = s.offset[j.body_b]
            rel = v[o : o + 3] - v[o_hub : o_hub + 3] - np.cross(w_hub, q[o : o + 3]
                                                                 - q[o_hub : o_hub + 3])
            swash += float(f @ rel)
        theta = s.joint_angle(self.pitch0, q)
        self.booked.append((*_PowerProbe.booked[-1], swash, theta))
        return row


@pytest.fixture(scope="module")
def flying():
    """The coarse forward-flight case with the default pitch links, and its booked rows."""
    _SwashProbe.booked, _PowerProbe.booked = [], []
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(rotor, "_Sampler", _SwashProbe)
        ds = rotor.run({**COARSE_ROTOR, "control_system": "swashplate"})
    n = ds.sizes["time"]
    booked = np.array(_SwashProbe.booked[-n - 1 :])
    np.testing.assert_allclose(booked[1:, 0], ds.time.values, rtol=0, atol=1e-12)
    return ds, booked


@pytest.mark.slow
def test_swashplate_power_balance(flying):
    """The shaft's and the swashplate's power go into the air, the dampers and the change of
    the model's energy (the prescribed motion of the rings does the work the driven pitch
    bearings do otherwise); the free bearings take none. Measured: 1.011 MW of shaft power,
    0.49 kW from the swashplate, balanced to 6.7e-4 of the shaft power (the prescribed case:
    6.6e-4; what is left is generalized-α's numerical dissipation at 120 steps/rev)."""
    ds, b = flying
    air, dampers, fuselage, pitch, energy = b[1:, 1:6].T
    swash = b[1:, 7]
    power = float(ds.rotor_power)
    period = 2 * math.pi / float(ds.run_hub_speed)
    change = (energy[-1] - b[0, 5]) / period
    assert power > 5e5 and air.mean() > 5e5
    assert np.abs(pitch).max() <= 1e-6 * power  # the free bearings do no work
    assert 0 < swash.mean() < 2e-3 * power
    balance = power + swash.mean() - air.mean() - dampers.mean() - fuselage.mean() - change
    assert abs(balance) <= 2e-3 * power, balance / power


@pytest.mark.slow
def test_swashplate_link_load_and_pitch_in_flight(flying):
    """In forward flight: the pitch-link load against blade 0's root torsion over the rigid
    linkage's arm at the commanded pitch, and the pitch against its command.

    The static balance is not exact here: the flapped and lagged blade turns the root's axis
    d1 out of the hub plane the link works in, and the link leans with the lag (the arm about
    d1 changes by about 1 − cos β and ζ h/L): measured within 0.55 % of the load's peak to
    peak (−846 … 333 N). The pitch differs from the command by the link's stretch (−T/(k h),
    at most 1.4e-3 rad here) and the linkage's kinematic pitch–lag coupling of the coned blade
    (of order ζβ, 0.68° here once the stretch is taken out): measured at most 0.64°."""
    ds, b = flying
    p = rotor.SPEC.validate({**COARSE_ROTOR, "control_system": "swashplate"})
    command = trim.schedule(p).pitch(0.0, 0.0)
    t = ds.time.values
    theta_cmd = np.array([command.value(x) for x in t])
    load = ds.pitch_link_load.values
    balance = ds.blade_root_torsion.values / swashplate.horn_arm(theta_cmd, H)
    assert np.abs(load - balance).max() <= 0.015 * np.ptp(load)
    theta = command.value(0.0) + b[1:, 8]
    assert np.abs(theta - theta_cmd).max() <= math.radians(0.75)
