"""The articulated UH-60A blade as a multibody model, and its fan plot.

The blade (``studies.uh60a``: Yeo's section properties with the Davis cuff) is a
geometrically exact beam of cubic elements from the hinge to the tip, on a hub spinning about
+z (counter-clockwise seen from above, as the UH-60A). The hinge arrangement: flap and lag
revolutes at one point e = 0.381 m, flap first going outboard, joined by a massless link; the
pitch bearing is locked (``control_system = "prescribed"``: a rigid pitch link, the reference
arrangement for the published frequencies) or free and held by an elastic pitch link on a horn
(``"swashplate"``: :mod:`studies.swashplate` at fixed controls, the link's lower end on the
hub), and the lag hinge has neither damper nor spring (undamped frequencies). The pitch link's
stiffness k on the horn's arm h restrains the root's pitch by k h² (N·m/rad): the torsion
branch falls with it.

The fan plot (Campbell diagram) is the set of natural frequencies of the linearized model about
its steady spin at each rotor speed (:func:`solver.modes.natural_frequencies`, rotating frame).
Each mode is named by its dominant motion — flap (out of the rotor plane), lag (in the plane),
torsion (section rotation about the blade axis) or axial — measured by the share of its
kinetic energy, and numbered by frequency within its family.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment

from solver.beams import Beam, straight_beam
from solver.bodies import RigidBody, spinning
from solver.equilibrium import Spin
from solver.joints import Revolute
from solver.model import Model
from solver.modes import Modes, natural_frequencies
from solver.system import System
from studies import swashplate
from studies.uh60a import UH60A, blade_sections, blade_twist, section_origin

Array = NDArray[np.float64]
FAMILIES = ("flap", "lag", "torsion", "axial")
FANPLOT_MODES = ("flap 1", "flap 2", "flap 3", "flap 4", "lag 1", "lag 2", "torsion 1")
TRACK_STEP = 0.1  # of Ω_ref: modes are named at this speed and followed in such steps
TRACKED_EXTRA = 6  # modes followed beyond the reported ones (room for branches to cross)
DEFAULT_SPEED_RATIOS = np.round(np.arange(0.0, 1.21, 0.1), 10)  # of Ω_ref = 27 rad/s
# the control system's defaults (studies.swashplate.PARAMETERS)
CONTROL_SYSTEM = swashplate.PARAMETERS["control_system"].default
PITCH_LINK_STIFFNESS = swashplate.PARAMETERS["pitch_link_stiffness"].default
PITCH_HORN_LENGTH = swashplate.PARAMETERS["pitch_horn_length"].default


def articulated_blade(speed: float, *, n_elements: int = 6, twist: bool = True,
                      control_system: str = CONTROL_SYSTEM,
                      pitch_link_stiffness: float = PITCH_LINK_STIFFNESS,
                      pitch_horn_length: float = PITCH_HORN_LENGTH) -> tuple[Model, Beam]:
    """One articulated UH-60A blade on a hub spinning at ``speed`` (rad/s) about +z.

    Parameters
    ----------
    speed
        Rotor speed Ω (rad/s), ≥ 0.
    n_elements
        Cubic beam elements from the hinge to the tip (the paper uses 6).
    twist
        Include the built-in structural twist of the section axes (couples flap, lag and
        torsion); without it the blade's section axes are those of the rotor plane.
    control_system
        ``"prescribed"``: the pitch bearing locked (rigid pitch link); ``"swashplate"``: the
        pitch bearing free, a pitch link from the horn to the hub (at zero collective).
    pitch_link_stiffness
        The pitch link's axial stiffness k (N/m), with ``"swashplate"``.
    pitch_horn_length
        The pitch horn's arm h (m), with ``"swashplate"``.

    Returns
    -------
    (model, beam)
    """
    if not (np.isfinite(speed) and speed >= 0):
        raise ValueError(f"rotor speed = {speed!r} rad/s must be ≥ 0")
    if not (isinstance(n_elements, int | np.integer) and 1 <= n_elements <= 60):
        raise ValueError(f"n_elements = {n_elements!r} must be an integer in 1…60")
    swashplate.check(control_system, pitch_link_stiffness, pitch_horn_length)
    e = section_origin(include_cuff=True)  # hinge radius (m): the beam starts there
    hinge = np.array([e, 0.0, 0.0])
    if twist:
        r_tw, tw = blade_twist("structural")

        def twist_of(s):
            return np.interp(np.asarray(s) + e, r_tw, tw)
    else:
        twist_of = None
    hub = spinning("hub", float(speed))
    blade = straight_beam("blade", hinge, (UH60A.radius, 0.0, 0.0), blade_sections(),
                          n_elements=n_elements, e3=(0.0, 0.0, 1.0), twist=twist_of,
                          angular_velocity=(0.0, 0.0, speed))
    # flap hinge about the chordwise axis (y at azimuth 0), then the lag hinge about z,
    # joined by a massless link whose rotation both hinges fix
    link = RigidBody("flap_link", 0.0, position=hinge, angular_velocity=(0.0, 0.0, speed))
    if control_system == "prescribed":
        model = Model([
            hub, link, blade,
            Revolute("flap", hub, link, point=hinge, axis=(0.0, 1.0, 0.0)),
            Revolute("lag", link, blade.root, point=hinge, axis=(0.0, 0.0, 1.0)),
        ])
        return model, blade
    # the free pitch bearing outboard of the lag hinge (a second massless link between them),
    # the blade held in pitch by the link from its horn down to the hub
    lag_link = RigidBody("lag_link", 0.0, position=hinge, angular_velocity=(0.0, 0.0, speed))
    model = Model([
        hub, link, lag_link, blade,
        Revolute("flap", hub, link, point=hinge, axis=(0.0, 1.0, 0.0)),
        Revolute("lag", link, lag_link, point=hinge, axis=(0.0, 0.0, 1.0)),
        Revolute("pitch", lag_link, blade.root, point=hinge, axis=(1.0, 0.0, 0.0)),
    ])
    swashplate.add_pitch_link(model, hub, blade.root, 0, 0.0, e, float(speed), 0.0, None,
                              pitch_link_stiffness, pitch_horn_length)
    return model, blade


def classify(modes: Modes, system: System, beam: Beam) -> list[str]:
    """Label each mode of ``modes`` ('flap 1', 'lag 2', 'torsion 1', …) by its dominant
    motion on ``beam``: the share of kinetic energy in out-of-plane (z), in-plane (y) and
    axial (x) node translation and in section rotation about the blade axis."""
    o = system.offset[beam]
    nb = 12 * len(beam.nodes)
    m = system.M[o : o + nb, o : o + nb].toarray()
    phi = modes.shapes[o : o + nb]  # (12 n, modes)
    comp = np.arange(nb).reshape(-1, 4, 3)  # node, (x, d1, d2, d3), xyz
    # kinetic energy of each family, in FAMILIES order: node z (flap), node y (lag), the
    # directors (section rotation: torsion, plus the small rotary inertia of bending slopes),
    # node x (axial)
    groups = (comp[:, 0, 2], comp[:, 0, 1], comp[:, 1:, :].ravel(), comp[:, 0, 0])
    energies = [np.real(np.einsum("im,ij,jm->m", phi[g].conj(), m[np.ix_(g, g)], phi[g]))
                for g in groups]
    family = np.argmax(np.array(energies), axis=0)
    count = dict.fromkeys(FAMILIES, 0)
    labels = [""] * len(family)
    for k in np.argsort(modes.frequency, kind="stable"):
        fam = FAMILIES[family[k]]
        count[fam] += 1
        labels[k] = f"{fam} {count[fam]}"
    return labels

def fanplot(speeds: ArrayLike | None = None, *, n_elements: int = 6,
            modes: tuple[str, ...] = FANPLOT_MODES, control_system: str = CONTROL_SYSTEM,
            pitch_link_stiffness: float = PITCH_LINK_STIFFNESS,
            pitch_horn_length: float = PITCH_HORN_LENGTH) -> xr.Dataset:
    """Natural frequencies of the articulated UH-60A blade against rotor speed.

    Parameters
    ----------
    speeds
        Rotor speeds Ω (rad/s), each ≥ 0; default 0 … 1.2 Ω_ref in steps of 0.1 Ω_ref.
    n_elements
        Beam elements, hinge to tip.
    modes
        Mode labels to report.
    control_system, pitch_link_stiffness, pitch_horn_length
        The pitch restraint (:func:`articulated_blade`): a rigid pitch link, or an elastic
        one of stiffness k (N/m) on a horn of arm h (m).

    Returns
    -------
    xarray.Dataset
        ``frequency`` (Hz) over (``hub_speed`` (rad s-1), ``mode``) with the coordinate
        ``mode_label``; NaN where a mode was not found among the computed ones. Speeds are
        sorted. Each mode is named by its dominant motion at 0.1 Ω_ref and followed by its
        shape (modal assurance criterion) through steps of 0.1 Ω_ref to the requested
        speeds, so a branch keeps its name through veerings.
    """
    sp = (UH60A.omega_ref * DEFAULT_SPEED_RATIOS if speeds is None
          else np.atleast_1d(np.asarray(speeds, dtype=float)))
    if sp.ndim != 1 or not len(sp) or not np.all(np.isfinite(sp)) or np.any(sp < 0):
        raise ValueError(f"speeds = {speeds!r} must be rotor speeds ≥ 0 rad/s")
    sp = np.unique(sp)
    swashplate.check(control_system, pitch_link_stiffness, pitch_horn_length)
    restraint = {"control_system": control_system,
                 "pitch_link_stiffness": pitch_link_stiffness,
                 "pitch_horn_length": pitch_horn_length}
    # modes are named at a low speed, where they keep the character of the non-rotating
    # blade's modes, and followed by their shapes in steps of at most TRACK_STEP: the
    # conventional branches of a fan plot, which keep their names through veerings
    step = TRACK_STEP * UH60A.omega_ref
    path = np.unique(np.concatenate([sp, np.arange(1, int(np.ceil(sp.max() / step)) + 1) * step]))
    runs = []
    for omega in path:
        model, beam = articulated_blade(float(omega), n_elements=n_elements, **restraint)
        s = System(model)
        spin = Spin(float(omega), (0.0, 0.0, 1.0)) if omega else None
        md = natural_frequencies(s, spin=spin)
        keep = np.argsort(md.frequency, kind="stable")[: len(modes) + TRACKED_EXTRA]
        o, nb = s.offset[beam], 12 * len(beam.nodes)
        runs.append((md, s, beam, keep, md.shapes[o : o + nb, keep],
                     s.M[o : o + nb, o : o + nb]))
    anchor = int(np.argmin(np.abs(path - step)))
    md, s, beam, keep, _, _ = runs[anchor]
    names = np.array(classify(md, s, beam), dtype=object)[keep]
    labels: list = [None] * len(path)
    labels[anchor] = names
    for order in (range(anchor + 1, len(path)), range(anchor - 1, -1, -1)):
        prev = anchor
        for i in order:
            labels[i] = _follow(runs[prev], labels[prev], runs[i])
            prev = i
    freq = np.full((len(sp), len(modes)), np.nan)
    for i, k in enumerate(np.searchsorted(path, sp)):
        md, keep = runs[k][0], runs[k][3]
        for j, name in enumerate(modes):
            hit = np.nonzero(labels[k] == name)[0]
            if len(hit):
                freq[i, j] = md.frequency[keep[hit[0]]]
    ds = xr.Dataset(coords={
        "hub_speed": ("hub_speed", sp, {"units": "rad s-1", "long_name": "rotor speed"}),
        "mode": ("mode", np.arange(len(modes)), {"long_name": "mode index"}),
        "mode_label": ("mode", list(modes), {"long_name": "dominant motion of the mode"}),
    })
    ds["frequency"] = (("hub_speed", "mode"), freq, {
        "units": "Hz", "long_name": "natural frequency in the rotating frame"})
    ds.attrs.update(
        title="UH-60A articulated blade fan plot",
        model=(f"{n_elements} cubic geometrically exact beam elements, hinge to tip; coincident "
               "flap/lag hinges at the hinge radius, lag hinge free, "
               + ("pitch link rigid" if control_system == "prescribed" else
                  f"pitch bearing free, pitch link of {pitch_link_stiffness:g} N/m on a "
                  f"{pitch_horn_length:g} m horn")
               + "; Yeo section properties with the Davis cuff; structural twist"),
        reference_speed=UH60A.omega_ref,
    )
    return ds


def _follow(prev_run, prev_labels, run) -> NDArray[np.object_]:
    """Labels at one speed from those at the neighbouring one: each mode takes the label of
    the previous mode its shape resembles most (mass-weighted modal assurance criterion,
    one-to-one by the assignment of largest total resemblance)."""
    phi0, m0 = prev_run[4], prev_run[5]
    phi1 = run[4]

    def inner(a, b):
        return a.conj().T @ (m0 @ b)

    mac = np.abs(inner(phi0, phi1)) ** 2 / np.outer(
        np.real(np.diag(inner(phi0, phi0))), np.real(np.diag(inner(phi1, phi1))))
    rows, cols = linear_sum_assignment(-mac)
    out = np.array([None] * phi1.shape[1], dtype=object)
    out[cols] = prev_labels[rows]
    return out
