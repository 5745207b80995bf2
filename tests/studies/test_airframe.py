"""The modal airframe file, its reader and writer, its solver elements (studies/airframe.py).

Every expected value is independent of the code under test: the shipped file against its own
documented idealization recomputed here (free-free Euler–Bernoulli beam, rigid-body modes from
the published centre of gravity and inertias); the attached airframe against the closed-form
single-degree-of-freedom frequency and frequency response with the body's mass added; the
fuselage-beam's modal file against the beam model's own linearization (frequencies, and the
6 × 6 hub receptance assembled here from its mass and stiffness matrices) and against the
closed-form Euler–Bernoulli cantilever carrying a tip mass. Each tolerance is commented with
the error measured when the test was written.

Runtime (2 cores): about 5 s.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from solver.beams import straight_beam
from solver.bodies import RigidBody, ground
from solver.equilibrium import equilibrium
from solver.forces import AppliedLoad
from solver.integrators import make_integrator
from solver.joints import Rigid
from solver.model import Model
from solver.modes import natural_frequencies
from solver.sections import isotropic_section
from solver.system import System
from studies import airframe as airframe_module
from studies import rotor
from studies.airframe import (
    Airframe,
    AirframeError,
    beam_airframe,
    default_airframe,
    default_airframe_path,
    read_airframe,
    station_accelerations,
    write_airframe,
)
from studies.parameters import ParameterError

TWO_PI = 2.0 * np.pi
IN = 0.0254  # m per inch
FOUR_P = 4.0 * 27.0  # rad/s: the UH-60A's blade passage at 27 rad/s


# ----------------------------------------------------------------------- the shipped file
def test_shipped_file_counts_units_and_ranges():
    """The default file reads, holds the required stations and modes, and its numbers are
    in plausible ranges and consistent with the model's axes (x aft, y starboard, z up)."""
    af = default_airframe()
    assert default_airframe_path().name == "airframe.toml"
    assert af.n_modes == 10 and af.n_stations == 4
    assert af.station_names == ("pilot_seat", "cabin_centre", "tail", "centre_of_gravity")
    rigid = ("surge_x", "sway_y", "heave_z", "roll_x", "pitch_y", "yaw_z")
    elastic = ("lateral_bending_1", "vertical_bending_1", "torsion_1", "vertical_bending_2")
    assert af.mode_names == rigid + elastic
    np.testing.assert_array_equal(af.hub_position, 0.0)
    # axes: the pilot forward of the hub (x < 0) in the right seat (y > 0), below it; the
    # tail aft; the cabin under the hub
    pilot, cabin, tail, cg = af.station_offsets
    assert pilot[0] < -3.0 and pilot[1] > 0.0 and pilot[2] < -1.0
    assert tail[0] > 9.0 and cabin[2] < -2.0 and abs(cabin[0]) < 0.1
    assert cg[0] > 0.0 and cg[2] < 0.0  # GenHel: CG 16.75 in aft of and 66.8 in below the hub
    # rigid-body modes: the 1 Hz, 20 % suspension; masses 6,659 kg and the published inertias
    np.testing.assert_array_equal(af.frequencies[:6], 1.0)
    np.testing.assert_array_equal(af.damping_ratios[:6], 0.2)
    np.testing.assert_array_equal(af.masses[:3], 7375.0 - 716.0)
    slug_ft2 = 14.59390294 * 0.3048**2
    np.testing.assert_allclose(af.masses[3:6], np.array([4659.0, 38512.0, 36796.0]) * slug_ft2,
                               rtol=1e-5)  # written to 6 digits
    # elastic modes: 5-20 Hz, none within 10 % of 4P (17.19 Hz), damping 2 %
    f = af.frequencies[6:]
    assert np.all((f > 5.0) & (f < 20.0))
    assert np.all(np.abs(f / (FOUR_P / TWO_PI) - 1.0) > 0.1)
    np.testing.assert_array_equal(af.damping_ratios[6:], 0.02)
    assert np.all(af.masses > 0.0)
    # scaling: translation modes and elastic modes to a largest hub translation of +1,
    # rotation modes to 1 rad per m of η
    t, r = af.hub_shapes[:3], af.hub_shapes[3:]
    np.testing.assert_array_equal(t[:, [0, 1, 2, 6, 7, 8, 9]].max(axis=0), 1.0)
    np.testing.assert_array_equal(r[:, 3:6], np.eye(3))
    assert "GenHel" in af.source and "https://" in af.source and "Assumed" in af.source


def _free_free(beta_l: float, s: np.ndarray, length: float):
    """A uniform free-free Euler–Bernoulli bending mode (mean square 1) and its slope (1/m)."""
    k = (math.cosh(beta_l) - math.cos(beta_l)) / (math.sinh(beta_l) - math.sin(beta_l))
    x = beta_l * s
    phi = np.cosh(x) + np.cos(x) - k * (np.sinh(x) + np.sin(x))
    slope = beta_l / length * (np.sinh(x) - np.sin(x) - k * (np.cosh(x) + np.cos(x)))
    return phi, slope


def test_shipped_file_follows_its_documented_idealization():
    """Every shape and generalized mass of the shipped file recomputed from the text at the
    head of the file: lofting coordinates → model axes, rigid-body modes about the published
    centre of gravity, the uniform free-free beam (nose at FS 141, 601 in long, axis at WL
    248.2, rigid sections) for the elastic modes, hub-normalized. The file holds 6
    significant digits: measured at most 2.4e-6 relative (of each mode's largest entry)."""
    af = default_airframe()

    def at(fs, bl, wl):
        return IN * np.array([fs - 341.25, bl, wl - 315.0])

    np.testing.assert_allclose(af.station_positions, [at(200.0, 21.0, 240.0),
                                                      at(343.5, 0.0, 225.0),
                                                      at(732.0, 0.0, 324.7),
                                                      at(358.0, 0.0, 248.2)], atol=1e-12)
    points = np.vstack([af.hub_position, af.station_positions])  # hub first
    cg = at(358.0, 0.0, 248.2)
    mass = 7375.0 - 716.0
    inertia = np.array([4659.0, 38512.0, 36796.0]) * 14.59390294 * 0.3048**2
    shapes = np.concatenate([af.hub_shapes[:3][None], af.station_shapes])  # (points, 3, n)
    expect = np.zeros_like(shapes)
    rot = np.zeros((3, af.n_modes))
    masses = np.zeros(af.n_modes)
    for k in range(3):
        e = np.eye(3)[k]
        expect[:, :, k] = e
        masses[k] = mass
        expect[:, :, 3 + k] = np.cross(e, points - cg)
        rot[:, 3 + k] = e
        masses[3 + k] = inertia[k]
    length = 601.0 * IN
    s = (points[:, 0] / IN + 341.25 - 141.0) / 601.0  # fraction of the length from the nose
    r = points - np.array([0.0, 0.0, IN * (248.2 - 315.0)])  # offsets from the beam axis
    r[:, 0] = 0.0
    b1 = brentq(lambda b: math.cos(b) * math.cosh(b) - 1.0, 4.6, 4.8, xtol=1e-14)
    b2 = brentq(lambda b: math.cos(b) * math.cosh(b) - 1.0, 7.8, 7.9, xtol=1e-14)
    elastic = []
    phi, slope = _free_free(b1, s, length)  # lateral: v, θ_z = v'
    elastic.append((np.outer(phi, [0, 1, 0]), np.outer(slope, [0, 0, 1]), mass))
    elastic.append((np.outer(phi, [0, 0, 1]), np.outer(-slope, [0, 1, 0]), mass))  # θ_y = -w'
    twist = np.cos(np.pi * s)
    elastic.append((np.zeros((len(s), 3)), np.outer(twist, [1, 0, 0]), inertia[0] / 2))
    phi, slope = _free_free(b2, s, length)
    elastic.append((np.outer(phi, [0, 0, 1]), np.outer(-slope, [0, 1, 0]), mass))
    for j, (u, theta, m) in enumerate(elastic, start=6):
        moved = u + np.cross(theta, r)
        scale = 1.0 / moved[0, np.argmax(np.abs(moved[0]))]
        expect[:, :, j] = moved * scale
        rot[:, j] = theta[0] * scale
        masses[j] = m * scale**2
    for j in range(af.n_modes):
        big = np.abs(expect[:, :, j]).max()
        np.testing.assert_allclose(shapes[:, :, j], expect[:, :, j], rtol=0, atol=5e-6 * big,
                                   err_msg=af.mode_names[j])
        np.testing.assert_allclose(af.hub_shapes[3:, j], rot[:, j], rtol=0, atol=5e-6,
                                   err_msg=af.mode_names[j])
    np.testing.assert_allclose(af.masses, masses, rtol=5e-6)
    # the second vertical bending at the beam's frequency ratio to the first
    assert af.frequencies[9] == pytest.approx(7.0 * (b2 / b1) ** 2, rel=5e-6)


def test_documented_example_is_a_valid_file(tmp_path):
    """The format example of the module docstring is a file the reader accepts."""
    doc = airframe_module.__doc__
    block = doc.split("::\n\n", 1)[1].split("\nNames (modes", 1)[0]
    text = "\n".join(line[4:] for line in block.splitlines())
    path = tmp_path / "example.toml"
    path.write_text(text, encoding="utf-8")
    af = read_airframe(path)
    assert af.mode_names == ("vertical_bending_1",)
    assert af.station_names == ("pilot_seat", "tail")
    np.testing.assert_array_equal(af.station_shapes[:, :, 0], [[0.17, 0.0, -1.47],
                                                               [1.60, 0.0, -2.49]])


# ------------------------------------------------------------------------- bad files
BASE = """\
title = "test"
source = "made up"
[hub]
position = [0.0, 0.0, 0.0]
[[stations]]
name = "pilot_seat"
position = [-3.0, 0.5, -1.9]
[[stations]]
name = "tail"
position = [9.9, 0.0, 0.2]
[[modes]]
name = "bend"
frequency = 7.0
damping_ratio = 0.02
generalized_mass = 1200.0
hub = [0.0, 0.0, 1.0, 0.0, 0.5, 0.0]
[modes.stations]
pilot_seat = [0.0, 0.0, -1.5]
tail = [0.0, 0.0, -2.5]
[[modes]]
name = "twist"
frequency = 10.0
damping_ratio = 0.02
generalized_mass = 400.0
hub = [0.0, 1.0, 0.0, -0.6, 0.0, 0.0]
[modes.stations]
pilot_seat = [0.0, -0.2, -0.6]
tail = [0.0, -2.3, 0.0]
"""

BAD_FILES = [
    # (replace this, by this), message after "<path>: "
    (("generalized_mass = 1200.0\n", ""),
     r"mode 'bend' \(modes\[0\]\): missing key 'generalized_mass' \(kg, > 0\)"),
    (("generalized_mass = 1200.0", "mass = 1200.0"),
     r"mode 'bend' \(modes\[0\]\): unknown key 'mass'; allowed: name, frequency"),
    (("frequency = 7.0", "frequency = -1.0"),
     r"mode 'bend' \(modes\[0\]\): frequency = -1\.0 Hz: outside the valid range \[0, inf\) Hz"),
    (("frequency = 7.0", "frequency = inf"),
     r"mode 'bend' \(modes\[0\]\): frequency = inf Hz must be finite"),
    (("frequency = 7.0", "frequency = \"seven\""),
     r"mode 'bend' \(modes\[0\]\): frequency = 'seven': expected a number \(Hz\)"),
    (("damping_ratio = 0.02\ngeneralized_mass = 400.0", "damping_ratio = 1.0\n"
      "generalized_mass = 400.0"),
     r"mode 'twist' \(modes\[1\]\): damping_ratio = 1\.0: outside the valid range \[0, 1\) "
     r"\(fraction of critical damping\)"),
    (("damping_ratio = 0.02\ngeneralized_mass = 1200.0", "damping_ratio = -0.01\n"
      "generalized_mass = 1200.0"),
     r"mode 'bend' \(modes\[0\]\): damping_ratio = -0\.01: outside the valid range \[0, 1\)"),
    (("damping_ratio = 0.02\ngeneralized_mass = 1200.0", "damping_ratio = true\n"
      "generalized_mass = 1200.0"),
     r"mode 'bend' \(modes\[0\]\): damping_ratio = True: expected a number"),
    (("generalized_mass = 400.0", "generalized_mass = 0.0"),
     r"mode 'twist' \(modes\[1\]\): generalized_mass = 0\.0 kg: outside the valid range "
     r"\(0, inf\) kg"),
    (("hub = [0.0, 0.0, 1.0, 0.0, 0.5, 0.0]", "hub = [0.0, 0.0, 1.0, 0.0, 0.5]"),
     r"mode 'bend' \(modes\[0\]\): hub has 5 values; expected 6 \(6 numbers: translation x, "
     r"y, z in m per m of η, rotation x, y, z in rad per m of η\)"),
    (("hub = [0.0, 0.0, 1.0, 0.0, 0.5, 0.0]", "hub = [0.0, 0.0, nan, 0.0, 0.5, 0.0]"),
     r"mode 'bend' \(modes\[0\]\): hub\[2\] = nan must be finite"),
    (("pilot_seat = [0.0, 0.0, -1.5]", "pilot = [0.0, 0.0, -1.5]"),
     r"mode 'bend' \(modes\[0\]\): stations\.pilot: a shape for 'pilot', which is not a "
     r"declared station \(did you mean 'pilot_seat'\?\); declared: pilot_seat, tail"),
    (("tail = [0.0, -2.3, 0.0]\n", ""),
     r"mode 'twist' \(modes\[1\]\): stations: no shape for the declared station 'tail'"),
    (("tail = [0.0, -2.3, 0.0]", "tail = [0.0, -2.3]"),
     r"mode 'twist' \(modes\[1\]\): stations\.tail has 2 values; expected 3"),
    (("tail = [0.0, -2.3, 0.0]", "tail = [0.0, -inf, 0.0]"),
     r"mode 'twist' \(modes\[1\]\): stations\.tail\[1\] = -inf must be finite"),
    (("name = \"twist\"", "name = \"bend\""),
     r"mode 'bend' \(modes\[1\]\): duplicate name 'bend'; mode names must be unique"),
    (("name = \"tail\"", "name = \"pilot_seat\""),
     r"station 'pilot_seat' \(stations\[1\]\): duplicate name 'pilot_seat'; station names "
     r"must be unique"),
    (("name = \"tail\"", "name = \"the tail\""),
     r"station 'the tail' \(stations\[1\]\): name = 'the tail' must be a non-empty bare TOML "
     r"key"),
    (("position = [9.9, 0.0, 0.2]", "position = [9.9, 0.0]"),
     r"station 'tail' \(stations\[1\]\): position has 2 values; expected 3 \(x, y, z in m\)"),
    (("position = [9.9, 0.0, 0.2]", "position = [9.9, nan, 0.2]"),
     r"station 'tail' \(stations\[1\]\): position\[1\] = nan must be finite"),
    (("position = [0.0, 0.0, 0.0]", "position = [0.0, 0.0, 0.0]\nheight = 1.0"),
     r"\[hub\]: unknown key 'height'; allowed: position"),
    (("[hub]\nposition = [0.0, 0.0, 0.0]\n", ""),
     r"top level: missing key 'hub' \(a \[hub\] table with position = \[x, y, z\] in m\)"),
    (("title = \"test\"", "titel = \"test\""),
     r"top level: unknown key 'titel' \(did you mean 'title'\?\)"),
    (("source = \"made up\"", "source = 3"),
     r"source = 3: expected a string"),
    (("[modes.stations]\npilot_seat = [0.0, 0.0, -1.5]\ntail = [0.0, 0.0, -2.5]\n", ""),
     r"mode 'bend' \(modes\[0\]\): missing key 'stations' \(a \[modes\.stations\] table: one "
     r"\[x, y, z\] in m per m of η per declared station: pilot_seat, tail\)"),
    (("position = [0.0, 0.0, 0.0]", "position = [0.0, 0.0, 0.0"), r"not valid TOML"),
]


@pytest.mark.parametrize(("edit", "message"), BAD_FILES,
                         ids=[f"{i}:{m[:40]}" for i, (_, m) in enumerate(BAD_FILES)])
def test_bad_file_is_answered_with_what_is_wrong(tmp_path, edit, message):
    """Each bad entry is refused by an AirframeError (a ParameterError: one line at the
    command line) naming the file, the mode or station, the key, the value and the range."""
    before, after = edit
    assert before in BASE
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace(before, after, 1), encoding="utf-8")
    with pytest.raises(AirframeError, match=re.escape(str(path)) + ": " + message) as info:
        read_airframe(path)
    assert isinstance(info.value, ParameterError)


def test_base_file_is_valid_and_missing_file_is_named(tmp_path):
    path = tmp_path / "ok.toml"
    path.write_text(BASE, encoding="utf-8")
    af = read_airframe(path)
    assert af.mode_names == ("bend", "twist") and af.n_stations == 2
    np.testing.assert_array_equal(af.station_shapes[1, :, 1], [0.0, -2.3, 0.0])
    np.testing.assert_array_equal(af.hub_shapes[:, 0], [0.0, 0.0, 1.0, 0.0, 0.5, 0.0])
    with pytest.raises(AirframeError, match=r"airframe file not found: .*nowhere\.toml"):
        read_airframe(tmp_path / "nowhere.toml")
    path.write_text("modes = []\n" + BASE.split("[[modes]]")[0], encoding="utf-8")
    with pytest.raises(AirframeError, match=r"modes must be a non-empty list"):
        read_airframe(path)


# -------------------------------------------------------------------------- round trip
def _fields(a: Airframe) -> dict:
    return {k: getattr(a, k) for k in (
        "title", "source", "hub_position", "station_names", "station_positions", "mode_names",
        "frequencies", "damping_ratios", "masses", "hub_shapes", "station_shapes")}


def _same(a: Airframe, b: Airframe) -> None:
    assert (a.title, a.source, a.mode_names, a.station_names) == (
        b.title, b.source, b.mode_names, b.station_names)
    for key in ("hub_position", "station_positions", "frequencies", "damping_ratios", "masses",
                "hub_shapes", "station_shapes"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key), err_msg=key)


def test_write_then_read_is_exact(tmp_path):
    """write → read gives every number back to the last bit (the shipped file, a title with
    quotes and a multi-line source, and a beam airframe with roundoff-sized shape entries);
    writing what was read writes the same text."""
    af = default_airframe()
    first = write_airframe(af, tmp_path / "a.toml")
    back = read_airframe(first)
    _same(af, back)
    second = write_airframe(back, tmp_path / "b.toml")
    assert first.read_text() == second.read_text()
    odd = Airframe(title='a "quoted" title\r', source="line 1\n\tline 2 with 'quotes'\n",
                   hub_position=[1.0, -2.0, 3.5], station_names=("s-1",),
                   station_positions=[[0.1, 0.2, 0.3]], mode_names=("m_0",),
                   frequencies=[0.0], damping_ratios=[0.0], masses=[1e-300],
                   hub_shapes=[[1e-17], [-0.0], [1.0], [np.pi], [-1e300], [2.0]],
                   station_shapes=[[[1.0], [2.0], [-3.0]]])
    _same(odd, read_airframe(write_airframe(odd, tmp_path / "odd.toml")))
    beam = beam_airframe(n_modes=6)
    _same(beam, read_airframe(write_airframe(beam, tmp_path / "beam.toml")))
    for source in ("ends with a quote '\n", "crlf\r\nline", "three ''' quotes\n"):
        text = Airframe(**{**_fields(odd), "source": source})
        _same(text, read_airframe(write_airframe(text, tmp_path / "text.toml")))


# --------------------------------------------------------------- the attached airframe
FN = np.array([3.0, 5.0])  # Hz
ZETA = np.array([0.03, 0.02])
M_MODE = np.array([80.0, 40.0])  # kg
PHI_Z, PSI_X = 0.6, 1.5  # m per m of η (mode 0, along z), rad per m of η (mode 1, about x)
BODY_MASS, BODY_J = 25.0, np.array([4.0, 5.0, 6.0])  # kg, kg·m² (principal, global axes)
HUB = np.array([0.3, -0.2, 1.1])  # m
STATION = np.array([[0.0, 0.0], [0.4, -1.2], [2.0, 0.3]])  # one station's 3 × 2 shapes
F0, W_FORCE = 50.0, TWO_PI * 2.2  # N, rad/s (below mode 0's loaded frequency)
T_END = 1.5  # s


def two_mode_airframe() -> Airframe:
    """Mode 0 moves the hub along z, mode 1 turns it about x (uncoupled through a body whose
    centre of mass is at the hub point)."""
    hub = np.zeros((6, 2))
    hub[2, 0], hub[3, 1] = PHI_Z, PSI_X
    return Airframe(title="two modes", source="test", hub_position=HUB,
                    station_names=("cabin",), station_positions=[[1.0, 0.0, -1.0]],
                    mode_names=("heave", "roll"), frequencies=FN, damping_ratios=ZETA,
                    masses=M_MODE, hub_shapes=hub, station_shapes=STATION[None])


def attached_model(af: Airframe, eta0=(0.0, 0.0), rate0=(0.0, 0.0), load=False):
    """A rigid body (centre of mass at the hub point) on the airframe's elements; started on
    the deflection η0, η̇0 (the body placed and moving with the hub); ``load``: F0 cos Ωt
    along z at the hub."""
    eta0, rate0 = np.asarray(eta0, dtype=float), np.asarray(rate0, dtype=float)
    t, r = af.hub_shapes[:3], af.hub_shapes[3:]
    angle = float((r @ eta0)[0])
    c, s = math.cos(angle), math.sin(angle)
    body = RigidBody("gearbox", BODY_MASS, BODY_J, position=HUB + t @ eta0,
                     orientation=[[1, 0, 0], [0, c, -s], [0, s, c]], velocity=t @ rate0,
                     angular_velocity=r @ rate0)
    modal, joint = af.elements(body, displacement=eta0, velocity=rate0)
    model = Model()
    model.add(body, modal, joint)
    if load:
        model.add(AppliedLoad("rotor", body, force=lambda t: (0.0, 0.0, F0 * np.cos(W_FORCE * t))))
    return model, modal, joint, body


def test_attached_rigid_body_adds_its_mass_to_each_mode():
    """Natural frequencies of the airframe carrying the body (``solver.modes``) against
    ω_n √(m/(m + m_b φ²)) for the heave mode and ω_n √(m/(m + J_x ψ²)) for the roll mode
    (measured 3.3e-16 relative), damping ratios ζ √(m/m_eff) (measured 9.5e-15); the
    elements' names and the attachment point."""
    af = two_mode_airframe()
    model, modal, joint, _ = attached_model(af)
    assert (modal.name, joint.name) == ("airframe", "airframe_hub")
    np.testing.assert_array_equal(joint.point, HUB)
    md = natural_frequencies(model)
    m_eff = M_MODE + np.array([BODY_MASS * PHI_Z**2, BODY_J[0] * PSI_X**2])
    wn = TWO_PI * FN * np.sqrt(M_MODE / m_eff)
    order = np.argsort(wn)
    np.testing.assert_allclose(md.omega, wn[order], rtol=1e-13)
    np.testing.assert_allclose(md.damping_ratio, (ZETA * np.sqrt(M_MODE / m_eff))[order],
                               rtol=1e-12)


def sdof(force: float):
    """Closed form of the heave mode with the body riding on it, m_eff η̈ + c η̇ + k η =
    φ F cos Ωt: η's complex amplitude, and the free mode's decay rate and damped frequency."""
    wn = TWO_PI * FN[0]
    k, c = M_MODE[0] * wn**2, 2.0 * ZETA[0] * wn * M_MODE[0]
    m_eff = M_MODE[0] + BODY_MASS * PHI_Z**2
    h = PHI_Z * force / (k - m_eff * W_FORCE**2 + 1j * c * W_FORCE)
    sigma = c / (2.0 * m_eff)
    return h, sigma, math.sqrt(k / m_eff - sigma**2)


def test_forced_airframe_and_station_accelerations_match_closed_form():
    """A harmonic force F0 cos Ωt along z at the hub, integrated (generalized-α, ρ∞ = 0.8,
    h = 1e-3 s over 1.5 s, started on the periodic solution; the transient the step leaves is
    fitted with the damped free mode): the station acceleration's amplitude against
    Φ_s (−Ω² H) of the closed-form SDOF (measured 8.3e-5 relative at Ωh = 0.014, the
    scheme's O((Ωh)²) error: tests/solver/test_modal.py measures 1.75e-5 at Ωh = 0.0065);
    at every step the station accelerations are Φ_s η̈ of the modal state, equal to
    :meth:`ModalStructure.station_motion`'s, and the roll mode stays at rest."""
    af = two_mode_airframe()
    h_c, sigma, wd = sdof(F0)
    eta0 = (h_c.real, 0.0)
    rate0 = ((1j * W_FORCE * h_c).real, 0.0)
    model, modal, _, _ = attached_model(af, eta0, rate0, load=True)
    step = 1e-3
    integ = make_integrator(System(model), "galpha", step, rho_inf=0.8)
    shapes = {"cabin": af.station_shapes[0]}
    t, y = [], []
    for _ in range(round(T_END / step)):
        assert integ.step().converged
        eta, _, acc = modal.modal_state(integ, acceleration="scheme")
        a = af.station_accelerations(acc)
        np.testing.assert_array_equal(a, station_accelerations(af, acc))
        np.testing.assert_array_equal(a[0], af.station_shapes[0] @ acc)
        assert abs(eta[1]) < 1e-12
        t.append(integ.t)
        y.append(a[0])
    end = modal.station_motion(shapes, integ)["cabin"].acceleration
    np.testing.assert_allclose(af.station_accelerations(modal.modal_state(integ)[2])[0], end,
                               rtol=1e-15, atol=0)
    t, y = np.array(t), np.array(y)
    basis = np.column_stack([np.cos(W_FORCE * t), np.sin(W_FORCE * t),
                             np.exp(-sigma * t) * np.cos(wd * t),
                             np.exp(-sigma * t) * np.sin(wd * t)])
    coef = np.linalg.lstsq(basis, y, rcond=None)[0]
    amp = coef[0] - 1j * coef[1]  # per direction
    exact = STATION[:, 0] * (-W_FORCE**2 * h_c)  # mode 0's column of the station shapes
    big = np.abs(exact).max()
    assert np.abs(amp - exact).max() < 1.2e-4 * big  # measured 8.3e-5


def test_station_accelerations_of_histories_and_bad_shapes():
    af = default_airframe()
    rng = np.random.default_rng(1)
    acc = rng.normal(size=(af.n_modes, 7))  # 7 samples
    out = station_accelerations(af, acc)
    assert out.shape == (4, 3, 7)
    for k in range(7):
        np.testing.assert_allclose(out[:, :, k], af.station_shapes @ acc[:, k], rtol=1e-14)
    with pytest.raises(ValueError, match=r"first axis must hold the 10 modes"):
        station_accelerations(af, np.ones(3))
    assert af.station_index("tail") == 2
    with pytest.raises(KeyError, match=r"no station 'cockpit'; declared: pilot_seat"):
        af.station_index("cockpit")


def test_static_displacement_is_the_attached_equilibrium():
    """Constant hub loads on a body attached to the shipped airframe: the static equilibrium's
    η (``solver.equilibrium``, Newton on the nonlinear model) against the linear
    :meth:`Airframe.static_displacement`. Their difference is second order in the load:
    measured 7.0e-3 of the largest η at the UH-60A's mean loads (72.3 kN thrust, 38.3 kN·m
    shaft torque: the torque, tilted by the 0.01 rad pitch deflection, puts 380 N·m into roll
    and torsion, and the thrust, fixed in space here, stiffens roll and pitch by T h on the
    arc about the centre of gravity; the linear formula leaves both out), and at a
    thousandth of them (1.05e-5). Modes at 0 Hz are refused."""
    af = default_airframe()
    errors = []
    for scale in (1.0, 1e-3):
        force = scale * np.array([-3e3, 1e3, 72.3e3])
        moment = scale * np.array([2e3, -5e3, 38.3e3])
        body = RigidBody("shaft", 1.0, (1.0, 1.0, 1.0))
        modal, joint = af.elements(body)
        model = Model()
        model.add(body, modal, joint, AppliedLoad("mean", body, force=lambda t, f=force: f,
                                                  moment=lambda t, m=moment: m))
        eq = equilibrium(model)
        assert eq.converged
        eta = eq.q[modal.indices(System(model))]
        expect = af.static_displacement(force, moment)
        errors.append(np.abs(eta - expect).max() / np.abs(expect).max())
    assert errors[0] < 1e-2 and errors[1] < 2e-5  # measured 7.0e-3, 1.05e-5
    free = Airframe(title="t", source="s", hub_position=[0, 0, 0], station_names=(),
                    station_positions=np.zeros((0, 3)), mode_names=("drift",),
                    frequencies=[0.0], damping_ratios=[0.0], masses=[1.0],
                    hub_shapes=[[0.0], [0.0], [1.0], [0.0], [0.0], [0.0]],
                    station_shapes=np.zeros((0, 3, 1)))
    with pytest.raises(AirframeError, match=r"mode 'drift' \(modes\[0\]\) has frequency 0 Hz"):
        free.static_displacement((0.0, 0.0, 1.0))


# ------------------------------------------------------------- the fuselage-beam's modes
def rotor_fuselage_beam(elements=rotor.FUSELAGE_ELEMENTS, ga=rotor.FUSELAGE_GA, i_sec=1e-3,
                        tip_inertia=(10.0, 10.0, 10.0)):
    """The rotor's fuselage-beam and shaft head as studies.rotor.build_model builds them."""
    p = rotor.PARAMETERS
    length = p["fuselage_length"].default
    ei = p["fuselage_bending_stiffness"].default
    section = isotropic_section(EA=rotor.FUSELAGE_EA, GA2=ga, GA3=ga,
                                GJ=rotor.FUSELAGE_GJ, EI2=ei, EI3=ei, mass=rotor.FUSELAGE_MASS,
                                i22=i_sec, i33=i_sec)
    fus = straight_beam("fuselage", (0.0, 0.0, -length), (0.0, 0.0, 0.0), section,
                        n_elements=elements, e3=(0.0, 1.0, 0.0))
    g0 = ground()
    shaft = RigidBody("shaft", p["shaft_mass"].default, inertia=tip_inertia)
    model = Model()
    model.add(g0, fus, shaft, Rigid("fuselage_clamp", g0, fus.root),
              Rigid("shaft_mount", fus.tip, shaft))
    return model, shaft


def hub_receptance(model, shaft, omega: float) -> np.ndarray:
    """The 6 × 6 receptance at the shaft head (translation, small rotation ½ Σ e_k × δd_k per
    unit force and moment) of the beam's linearization: T Z (Zᵀ(K − ω²M)Z)⁻¹ Zᵀ Tᵀ."""
    lin = natural_frequencies(model).linearization
    o = lin.system.offset[shaft]
    n = lin.M.shape[0]
    t = np.zeros((6, n))
    t[:3, o : o + 3] = np.eye(3)
    for k in range(3):
        e = np.eye(3)[k]
        t[3:, o + 3 + 3 * k : o + 6 + 3 * k] = 0.5 * np.array(
            [[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
    z = lin.Z
    dyn = z.T @ (lin.K - omega**2 * lin.M) @ z
    return t @ z @ np.linalg.solve(dyn, z.T @ t.T)


def modal_receptance(af: Airframe, omega: float, n: int | None = None) -> np.ndarray:
    """Σ_j h_j h_jᵀ / (m_j (ω_j² − ω²)) over the n lowest modes (undamped)."""
    n = af.n_modes if n is None else n
    h = af.hub_shapes[:, :n]
    w2 = (TWO_PI * af.frequencies[:n]) ** 2
    return (h / (af.masses[:n] * (w2 - omega**2))) @ h.T


def test_beam_airframe_reproduces_the_fuselage_beam():
    """The rotor's fuselage-beam with its shaft head (2 cubic elements, 36 modes): the modal
    file's frequencies against the beam model's own (``solver.modes`` on a model built here
    as the rotor builds it; measured 0), and its hub receptance at 4P (17.19 Hz) against the
    beam linearization's (assembled here from M, K and the constraint null space): with all
    modes measured 9.0e-13 of the largest entry (shapes, rotation measure and generalized
    masses exact). Truncated, each entry's relative error (measured):

    ====== ========== ========== ========== ==========
    modes  x–x        x–θy       θy–θy      z–z
    ====== ========== ========== ========== ==========
    2      2.7e-5     1.8e-3     0.11       1 (axial)
    6      1.9e-6     3.3e-5     5.3e-4     9.5e-5
    10     2.7e-8     1.5e-7     7.7e-7     9.5e-5
    ====== ========== ========== ========== ==========

    so the in-plane 4P hub response of the beam is within 3e-5 with its first bending pair
    alone. Shapes are hub-normalized (largest translation, or rotation for torsion, is 1)."""
    af = beam_airframe(max_frequency=math.inf)
    model, shaft = rotor_fuselage_beam()
    md = natural_frequencies(model)
    assert af.n_modes == len(md) == 36
    np.testing.assert_allclose(af.frequencies, md.frequency, rtol=1e-10)
    np.testing.assert_array_equal(af.damping_ratios, 0.02)
    assert af.mode_names[:6] == ("mode_1_y", "mode_2_x", "mode_3_rz", "mode_4_y", "mode_5_x",
                                 "mode_6_z")
    t, r = af.hub_shapes[:3], af.hub_shapes[3:]
    np.testing.assert_array_equal(np.where(np.abs(t).max(axis=0) > 1e-6,
                                           np.abs(t).max(axis=0), np.abs(r).max(axis=0)), 1.0)
    # first bending: tip slope of a cantilever bent by a tip load, 3/(2L) (the shaft's mass
    # dominates the beam's): measured 0.745 against 0.75
    assert r[0, 0] == pytest.approx(-0.75, rel=0.01) and r[1, 1] == pytest.approx(0.75, rel=0.01)
    exact = hub_receptance(model, shaft, FOUR_P)
    full = modal_receptance(af, FOUR_P)
    assert np.abs(full - exact).max() < 1e-11 * np.abs(exact).max()  # measured 9.0e-13
    entries = ((0, 0), (0, 4), (4, 4), (2, 2))  # x–x, x–θy, θy–θy, z–z
    bounds = {2: (4e-5, 3e-3, 0.2), 6: (3e-6, 5e-5, 1e-3), 10: (5e-8, 3e-7, 1.5e-6)}
    for n, bound in bounds.items():
        part = modal_receptance(af, FOUR_P, n)
        err = [abs(part[e] / exact[e] - 1.0) for e in entries]
        assert np.all(np.array(err[:3]) < bound), (n, err)
    assert abs(modal_receptance(af, FOUR_P, 6)[2, 2] / exact[2, 2] - 1.0) < 2e-4


def cantilever_frequencies(length, ei, mu, tip_mass, count):
    """Roots of 1 + cos βL cosh βL + (M/(μL)) βL (cos βL sinh βL − sin βL cosh βL) = 0: the
    Euler–Bernoulli cantilever carrying a tip mass (no rotary inertia), f = β² √(EI/μ)/2π."""
    ratio = tip_mass / (mu * length)

    def f(x):
        return 1.0 + math.cos(x) * math.cosh(x) + ratio * x * (
            math.cos(x) * math.sinh(x) - math.sin(x) * math.cosh(x))

    grid = np.linspace(1e-3, 15.0, 30001)
    values = [f(x) for x in grid]
    roots = [brentq(f, a, b, xtol=1e-15) for a, b, fa, fb in
             zip(grid[:-1], grid[1:], values[:-1], values[1:], strict=True) if fa * fb < 0]
    beta = np.array(roots[:count]) / length
    return beta**2 * math.sqrt(ei / mu) / TWO_PI


def test_beam_airframe_against_the_euler_bernoulli_cantilever_with_tip_mass():
    """The fuselage-beam without rotary inertia (section and tip) and nearly without shear
    flexibility (GA = 1e14 N: its frequency effect ~ 3EI/(2GA L²) = 6e-8) against the
    closed-form cantilever with a 300 kg tip mass (M/(μL) = 15). First bending: measured
    5.7e-8 (2 elements) and 1.6e-7 (4), 7.8e-8 with 8: the residual shear flexibility and
    the stiff problem's roundoff, not the discretization. Second bending: measured 5.3e-4 and
    9.1e-6, a factor 58 (order 5.9) for twice the elements: the cubic elements' convergence
    (3.8e-7 with 8 elements, at the floor)."""
    p = rotor.PARAMETERS
    length, ei = p["fuselage_length"].default, p["fuselage_bending_stiffness"].default
    exact = cantilever_frequencies(length, ei, rotor.FUSELAGE_MASS, 300.0, 2)
    errors = {}
    for elements in (2, 4):
        af = beam_airframe(elements=elements, shear_stiffness=1e14, section_inertia=0.0,
                           tip_inertia=(0.0, 0.0, 0.0), tip_mass=300.0)
        # bending in x: the modes whose largest hub motion is a translation along x
        bending = np.sort(af.frequencies[[n.endswith("_x") and "_r" not in n
                                          for n in af.mode_names]])[:2]
        errors[elements] = np.abs(bending / exact - 1.0)
    assert errors[2][0] < 2e-7 and errors[4][0] < 3e-7  # measured 5.7e-8, 1.6e-7
    assert errors[2][1] < 7e-4 and errors[4][1] < 1.5e-5  # measured 5.3e-4, 9.1e-6
    assert errors[2][1] / errors[4][1] > 40.0  # measured 58


def test_beam_airframe_mode_count():
    """By default the modes up to 3 kHz (10 of the rotor's beam); fewer on request."""
    af = beam_airframe()
    assert af.n_modes == 10 and af.frequencies[-1] < 3000.0
    af = beam_airframe(n_modes=3)
    assert af.n_modes == 3 and af.mode_names == ("mode_1_y", "mode_2_x", "mode_3_rz")
    with pytest.raises(ValueError, match=r"n_modes = 11: the beam has 10 modes up to "
                                         r"max_frequency = 3000 Hz"):
        beam_airframe(n_modes=11)


def test_hub_on_the_modal_airframe_matches_the_hub_on_the_beam():
    """The rotor's hub (250 kg, tilt inertia 50 kg·m²) welded to the shaft head of the beam
    model, against the same body attached to the beam's modal airframe (``solver.modes`` on
    both): the first coupled bending pair (15.78 Hz, near 4P) within 2.9e-4 with the 2 first
    bending modes, 4.8e-7 with 6, 9.3e-10 with the default 10 (measured); with the default the
    first six coupled frequencies within 9.7e-6 (the axial one, 213 Hz, whose next axial mode
    is above 3 kHz, the last to converge). A massless body on the default airframe leaves its
    frequencies unchanged (measured 2.1e-11: roundoff amplified by the modal stiffnesses'
    range, 3e6 here; the beam's top modes, a range of 1e15, are left out for that reason)."""
    model, shaft = rotor_fuselage_beam()
    hub = RigidBody("hub", 250.0, inertia=(50.0, 50.0, 1.0))
    model.add(hub, Rigid("weld", shaft, hub))
    ref = natural_frequencies(model).frequency
    errors = {}
    for n in (2, 6, None):
        af = beam_airframe(damping_ratio=0.0, n_modes=n)
        body = RigidBody("hub", 250.0, inertia=(50.0, 50.0, 1.0))
        modal, joint = af.elements(body)
        coupled = Model()
        coupled.add(body, modal, joint)
        f = natural_frequencies(coupled).frequency
        k = min(6, af.n_modes)
        errors[n] = np.abs(f[:k] / ref[:k] - 1.0)
    assert errors[2].max() < 4e-4  # measured 2.9e-4
    assert errors[6][:2].max() < 7e-7  # measured 4.8e-7
    assert errors[None][:2].max() < 5e-9 and errors[None].max() < 2e-5  # 9.3e-10, 9.7e-6
    af = beam_airframe(damping_ratio=0.0)
    body = RigidBody("shaft", 0.0, inertia=(0.0, 0.0, 0.0))
    modal, joint = af.elements(body)
    alone = Model()
    alone.add(body, modal, joint)
    np.testing.assert_allclose(natural_frequencies(alone).frequency, af.frequencies, rtol=1e-10)


def test_airframe_constructor_checks_arrays():
    good = two_mode_airframe()
    kwargs = _fields(good)
    with pytest.raises(AirframeError, match=r"hub_shapes has shape \(3, 2\); expected \(6, 2\)"):
        Airframe(**{**kwargs, "hub_shapes": np.zeros((3, 2))})
    with pytest.raises(AirframeError, match=r"no modes"):
        Airframe(**{**kwargs, "mode_names": (), "frequencies": [], "damping_ratios": [],
                    "masses": [], "hub_shapes": np.zeros((6, 0)),
                    "station_shapes": np.zeros((1, 3, 0))})
    with pytest.raises(AirframeError, match=r"mode 'roll' \(modes\[1\]\): generalized_mass = "
                                            r"-1\.0 kg: outside the valid range"):
        Airframe(**{**kwargs, "masses": [1.0, -1.0]})
    assert not good.frequencies.flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        good.masses[0] = 2.0


def test_data_file_sits_beside_the_module():
    """The shipped file is where the reader looks (studies/data), and in the source tree."""
    here = Path(airframe_module.__file__).parent / "data" / "uh60a" / "airframe.toml"
    assert default_airframe_path().resolve() == here.resolve() and here.is_file()
