"""The rotor's control system: prescribed blade pitch, or a swashplate with elastic pitch links.

``control_system = "prescribed"`` drives each blade's pitch bearing through the commanded angle
θ_k(t) = θ0 + θc cos ψ_k + θs sin ψ_k (a rigid control system, no linkage kinematics).

``control_system = "swashplate"`` frees the pitch bearing and holds the blade by a linkage,
per blade k (the hub's frame; e_r the blade's span axis, e_t its lead direction, z the shaft
axis, C the coincident flap/lag/pitch hinge at radius e):

* a pitch horn on the blade's root section: the point H = C + h (cos θ e_t + sin θ z), a
  chordwise arm of length h = ``pitch_horn_length`` towards the leading edge at the hinge
  station, in the hub plane at zero pitch θ (measured in the controls' reference). At zero
  pitch H lies on the flap hinge's axis, so flapping does not stretch the link: δ3 = 0, as the
  UH-60A;
* a pitch link, a massless axial spring of stiffness k = ``pitch_link_stiffness``
  (:class:`solver.forces.AxialSpring`) and length L = :data:`PITCH_LINK_LENGTH` from H down
  to the point P of the rotating ring;
* the rotating ring, rigid and massless, turning with the hub: each blade's attachment point
  P = C + h e_t + (z_k(t) − L) z is a massless body on a prismatic joint along the shaft axis
  of the hub, its stroke z_k(t) prescribed (:class:`solver.joints.Prismatic` with ``driven``);
* the non-rotating ring, positioned by the controls: the heights z_k are those it gives the
  rotating ring's points. They come from the **exact inverse kinematics of the rigid
  linkage**, z = h sin θ + L − √(L² − h² (1 − cos θ)²) (:func:`ring_height`), at the commanded
  pitch θ_k(t) of the :class:`studies.trim.ControlSchedule`: the controls (θ0, θc, θs) keep
  their meaning as blade pitch commands (trim and Table 1's inputs stay comparable), and an
  infinitely stiff link with the blade's flap and lag at zero reproduces the commanded pitch
  exactly. With the blade flapping and lagging the linkage adds its kinematic couplings,
  which the prescribed control system leaves out: the pitch–lag coupling of a coned blade,
  of order ζβ (rad), and terms of order θβ²/2 and hζ²/(2L) (docs/models.md).

The swashplate phase: P is at the horn's azimuth, which leads the blade by Δ = atan(h/e)
(27.7° at the defaults); to first order z = h θ, so the non-rotating ring's height at the
azimuth ψ_P of a point on it is h [θ0 + θc cos(ψ_P − Δ) + θs sin(ψ_P − Δ)]: its tilt is the
cyclic commands rotated by Δ (:func:`swashplate_phase`). GenHel's swashplate phase of the
UH-60A (DELSP = −9.7°) is that angle of the real linkage in GenHel's mixing convention; the
blade pitch commands here do not depend on it, only the non-rotating ring's tilt does.

The servos', the rings' and the pitch link's own compliance are lumped into the one link
stiffness k; with the arm h the blade's root sees the torsional stiffness k h² about the pitch
axis. The UH-60A's control-system stiffness and horn length are not public: the defaults
(h = 0.2 m, about 40 % of the chord, and k = 3e6 N/m) give k h² = 1.2e5 N·m/rad, within the
1e5–2e5 N·m/rad that the published torsion frequencies suggest (docs/models.md). On the fan
plot's blade at 27 rad/s they move the torsion-dominated mode from 4.86/rev (rigid link) to
4.51/rev (5e4 N·m/rad: 4.17/rev; 2e5: 4.72/rev, then mixed with lag 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.bodies import RigidBody
from solver.forces import AxialSpring
from solver.joints import Prismatic
from solver.model import Model
from solver.rotations import rotation_about
from solver.timefunctions import TimeFunction
from studies.parameters import Param

Z = np.array([0.0, 0.0, 1.0])
# The pitch link's length (m): the rigid linkage's geometry (the stiffness the blade sees is
# k h² whatever the length; the length sets the link's inclination and the kinematics).
PITCH_LINK_LENGTH = 0.5

CONTROL_SYSTEMS = ("prescribed", "swashplate")

PARAMETERS: dict[str, Param] = {
    "control_system": Param(
        "prescribed", "1", "blade pitch control: prescribed (the pitch bearings driven through "
        "the commanded pitch, a rigid control system) or swashplate (free pitch bearings held "
        "by elastic pitch links from a rotating ring that the controls position)",
        choices=CONTROL_SYSTEMS),
    "pitch_link_stiffness": Param(
        3.0e6, "N m-1", "axial stiffness k of each pitch link, with the servos' and rings' "
        "compliance lumped in (swashplate only); the UH-60A's is not public: with the horn "
        "k h² = 1.2e5 N m rad-1 about the pitch axis, within the 1e5-2e5 that the UH-60A's "
        "torsion frequency suggests; it moves the blade's torsion-dominated mode at 27 rad/s "
        "from 4.86/rev (rigid link) to 4.51/rev",
        minimum=0.0, exclusive_minimum=True, maximum=1e15),
    "pitch_horn_length": Param(
        0.2, "m", "pitch horn arm h: chordwise distance from the pitch axis to the pitch "
        "link's upper end, towards the leading edge, at the hinge station (swashplate only; "
        "the UH-60A's is not public: 0.2 m, about 40 % of the chord)",
        minimum=0.0, exclusive_minimum=True, maximum=0.4),
}


def ring_height(theta: float, horn: float, length: float = PITCH_LINK_LENGTH
                ) -> tuple[float, float, float]:
    """The stroke z(θ) of the rotating ring's point that holds the blade at pitch θ (rad) with
    a rigid link, and its first two derivatives dz/dθ, d²z/dθ².

    The horn's end is at C + h (cos θ e_t + sin θ z), the ring's point at
    C + h e_t + (z − L) z (flap and lag at zero), and a link of length L between them gives
    (h sin θ + L − z)² + h² (1 − cos θ)² = L²: z = h sin θ + L − √(L² − h² (1 − cos θ)²),
    the root with the link below the horn (z = 0 at θ = 0)."""
    g, dg, ddg = 1.0 - math.cos(theta), math.sin(theta), math.cos(theta)
    s = math.sqrt(length**2 - horn**2 * g**2)
    ds = -horn**2 * g * dg / s
    dds = -horn**2 * (dg**2 + g * ddg) / s - horn**4 * g**2 * dg**2 / s**3
    return (horn * math.sin(theta) + length - s, horn * math.cos(theta) - ds,
            -horn * math.sin(theta) - dds)


def horn_arm(theta: float | np.ndarray, horn: float, length: float = PITCH_LINK_LENGTH
             ) -> float | np.ndarray:
    """The rigid linkage's moment arm about the pitch axis at pitch θ (rad; flap and lag at
    zero), m: a tension T in the link turns the blade nose down by T times it.

    The horn's end is at h (cos θ, sin θ) in the (e_t, z) plane from the hinge, the link's
    direction from the ring up to it n = (−h (1 − cos θ)/L, √(1 − n_t²)) (:func:`ring_height`),
    and the arm is h (cos θ n_z − sin θ n_t): h at θ = 0, h cos θ to first order in the link's
    inclination."""
    n_t = -horn * (1.0 - np.cos(theta)) / length
    return horn * (np.cos(theta) * np.sqrt(1.0 - n_t**2) - np.sin(theta) * n_t)


def ring_drive(pitch: TimeFunction, horn: float, start: float,
               length: float = PITCH_LINK_LENGTH) -> TimeFunction:
    """The ring point's stroke relative to its value ``start`` (m) as built, z(θ(t)) − start,
    for the commanded pitch θ(t) (``pitch``, rad, absolute), with the chain rule's rate and
    acceleration (the controls' own rates included)."""

    def joint(t: float) -> tuple[float, float, float]:
        theta, rate, accel = pitch(t)
        z, dz, ddz = ring_height(theta, horn, length)
        return z - start, dz * rate, ddz * rate**2 + dz * accel

    return TimeFunction.of(joint)


def swashplate_phase(horn: float, hinge_radius: float) -> float:
    """The azimuth (rad) by which each blade's ring point, below its horn, leads the blade:
    atan(h/e). The non-rotating ring's tilt is the cyclic commands rotated by it."""
    return math.atan2(horn, hinge_radius)


@dataclass
class PitchLink:
    """One blade's linkage: the ring point's massless body and its driven prismatic joint on
    the hub (None for a ring fixed to the hub), the link, and the link's two ends at t = 0
    (global, m)."""

    ring: RigidBody | None
    drive: Prismatic | None
    link: AxialSpring
    horn: np.ndarray
    lower: np.ndarray


def add_pitch_link(model: Model, hub, root, k: int, azimuth: float, hinge_radius: float,
                   omega: float, theta_start: float, pitch: TimeFunction | None,
                   stiffness: float, horn: float) -> PitchLink:
    """Blade ``k``'s pitch link, rotating-ring point and its drive, added to ``model``.

    Parameters
    ----------
    model
        The model to add them to.
    hub
        The body spinning with the rotor that carries the rotating ring (frame = global at
        t = 0, spinning at ``omega`` about +z).
    root
        The blade's root section (a beam node), free in pitch about the span axis.
    k
        Blade index (names ``ring{k}``, ``ring_drive{k}``, ``pitch_link{k}``).
    azimuth
        The blade's azimuth at t = 0 (rad).
    hinge_radius
        Radius e of the hinge C (m).
    omega
        Rotor speed (rad/s).
    theta_start
        The blade's pitch as built (rad, the controls' reference).
    pitch
        The commanded pitch θ(t) (rad, absolute), or None for fixed controls: the link's lower
        end is then a point of the hub itself (the fan plot's blade).
    stiffness
        The link's axial stiffness k (N/m), ``pitch_link_stiffness``.
    horn
        The horn's arm h (m), ``pitch_horn_length``.
    """
    h, length = horn, PITCH_LINK_LENGTH
    er = np.array([math.cos(azimuth), math.sin(azimuth), 0.0])
    et = np.array([-math.sin(azimuth), math.cos(azimuth), 0.0])
    hinge = hinge_radius * er
    z0 = ring_height(theta_start, h, length)[0]
    lower = hinge + h * et + (z0 - length) * Z
    end = hinge + h * (math.cos(theta_start) * et + math.sin(theta_start) * Z)
    ring = drive = None
    if pitch is not None:  # the link's lower end on the ring point the controls drive
        ring = RigidBody(f"ring{k}", 0.0, position=lower,
                         orientation=rotation_about(Z, azimuth),
                         velocity=np.cross(omega * Z, lower), angular_velocity=omega * Z)
        drive = Prismatic(f"ring_drive{k}", hub, ring, point=lower, axis=Z,
                          driven=ring_drive(pitch, h, z0, length))
        model.add(ring, drive)
    link = AxialSpring(f"pitch_link{k}", hub if ring is None else ring, lower, root, end,
                       stiffness=stiffness, rest_length=length)
    model.add(link)
    return PitchLink(ring, drive, link, end, lower)


def check(control_system: str, stiffness: float, horn: float) -> None:
    """Raise :class:`~studies.parameters.ParameterError` for a control system, link or horn
    its parameter (:data:`PARAMETERS`) rejects: the check the rotor's and the fan plot's
    validation make, for direct calls."""
    for name, value in (("control_system", control_system),
                        ("pitch_link_stiffness", stiffness), ("pitch_horn_length", horn)):
        PARAMETERS[name].check(name, value)
