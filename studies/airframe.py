"""An airframe given by its normal modes: the modal file, its reader and writer, and the solver
elements that attach a body (the rotor's shaft head) to it.

A modal airframe is n modal coordinates η_i (:class:`solver.modal.ModalStructure`), each obeying

    m_i η̈_i + 2 ζ_i ω_i m_i η̇_i + m_i ω_i² η_i = Q_i,        ω_i = 2π f_i,

driven by the hub through its shapes at the hub attachment point (the joint
:class:`solver.modal.ModalAttachment`: the hub point moves by Φ_t η and turns by Φ_r η), and
read out at named response stations as Φ_s η, Φ_s η̇, Φ_s η̈ (cabin vibration:
:func:`station_accelerations`).

Axes and units
--------------
Every position and shape is in the rotor model's axes (:mod:`studies.rotor`; the
fuselage-beam's section axes d1 = z, d2 = x, d3 = y): **x aft, y starboard, z up**
(right-handed; the rotor turns counter-clockwise seen from above, about +z). These are the
directions of the airframe lofting coordinates (fuselage station FS aft, butt line BL to
starboard, water line WL up), so a station at (FS, BL, WL) inches lies at
0.0254 (FS − FS_0, BL − BL_0, WL − WL_0) m from an origin at (FS_0, BL_0, WL_0).

* positions: m, from any origin (the file's own datum; only differences matter to the
  airframe, and :meth:`Airframe.elements` attaches at the hub position unless told otherwise);
* ``frequency``: undamped natural frequency f_i, Hz, ≥ 0;
* ``damping_ratio``: modal damping ζ_i, fraction of critical, in [0, 1);
* ``generalized_mass``: m_i, kg, > 0, consistent with the shapes' scaling (below);
* ``hub``: 6 numbers, the shape at the hub attachment point: translation x, y, z in m per m
  of η, then rotation about x, y, z in rad per m of η (right-handed);
* station shapes: 3 numbers each, translation x, y, z in m per m of η.

A shape may be scaled freely: scaling mode i's shapes by s scales its generalized mass by s²
and its η by 1/s (the physics is unchanged). :func:`beam_airframe` and the shipped file
scale each elastic mode so that its largest hub translation component is +1 (η is then the
hub's displacement, m, in that direction), or, for a mode that only turns the hub, its
largest hub rotation component (1 rad per m of η); rigid-body rotation modes in the shipped
file are 1 rad per m of η (η is the rotation times 1 m; the generalized mass is then the
moment of inertia, kg·m² per m²).

The file format (TOML)
----------------------
::

    title = "Example airframe"              # required, a line of text
    source = "where the numbers come from"  # required, text (may span lines, '''...''')

    [hub]
    position = [0.0, 0.0, 0.0]              # m: the hub attachment point

    [centre_of_gravity]                      # optional: the centre of the rigid-body
    position = [0.43, 0.0, -1.70]            # rotations, m (see "Rigid-body modes")

    [[stations]]                             # response stations (any number, names unique)
    name = "pilot_seat"
    position = [-3.59, 0.53, -1.91]          # m

    [[stations]]
    name = "tail"
    position = [9.93, 0.0, 0.25]

    [[modes]]                                # one table per mode (at least one)
    name = "vertical_bending_1"              # unique
    frequency = 7.0                          # Hz
    damping_ratio = 0.02                     # fraction of critical
    generalized_mass = 12146.0               # kg
    hub = [-0.82, 0.0, 1.0, 0.0, -0.48, 0.0] # m/m (x, y, z), rad/m (about x, y, z)
    [modes.stations]                         # one 3-vector per declared station, m/m
    pilot_seat = [0.17, 0.0, -1.47]
    tail = [1.60, 0.0, -2.49]

Names (modes and stations) are bare TOML keys: letters, digits, ``_`` and ``-``. Every key
is checked when the file is read (:func:`read_airframe`): a missing or unknown key, a wrong
type or length, a non-finite number, a value outside its range, a duplicate name, a station
shape for an undeclared station or none for a declared one is answered with an
:class:`AirframeError` naming the file, the mode or station, the key, the value and the valid
range. :class:`AirframeError` is a :class:`~studies.parameters.ParameterError`: a bad file given
as a model parameter (``fuselage_modes = "path.toml"``) is a bad parameter value, reported in
one line like any other.

Rigid-body modes
----------------
A free airframe has six rigid-body modes (0 Hz). In the rotor model they would drift: the
model has no gravity, no fuselage aerodynamics and no tail rotor, so nothing reacts the
rotor's mean loads — its thrust (about 72 kN at the UH-60A's weight), its mean in-plane force
and the shaft torque (about 38 kN·m at 1 MW and 27 rad/s). A free airframe would accelerate
at T/M ≈ 11 m/s² (5 m after one second) and spin up in yaw: it would leave the small-motion
range of the linear airframe and of the attachment's small-rotation measure, and the
response would never become periodic. In flight gravity, fuselage drag and the tail rotor
balance these mean loads; the model stands in for them by giving each rigid-body mode a soft
"suspension": a frequency f_s well below N/rev (and a damping ratio so that its transient
dies out in a few revolutions). The mean loads are then reacted by the suspension (static
offsets F/(m ω_s²), :meth:`Airframe.static_displacement` gives them to start a run there)
while at the blade-passage frequency f the rigid-body response differs from the free body's
by the factor 1/(1 − (f_s/f)² − 2iζ_s f_s/f) (response ∝ e^{i2πft}): 0.3 % in magnitude and
1.3° in phase for f_s = 1 Hz, ζ_s = 0.2 against 4P = 17.2 Hz; the suspension's own
transient then decays by e in 1/(ζ_s ω_s) = 0.8 s (3.4 revolutions at 27 rad/s). A frequency
of 0 is accepted by the format (for a model that reacts the mean loads otherwise) but the
rotor should not be run on it.

The rotor's thrust is large and turns with the shaft: when the airframe rolls by φ about its
centre of gravity, h below the hub, the thrust T tilts by φ with it. On the modes' linear
shapes the hub moves along the tangent of its arc, and the tilted thrust then has the moment
T h φ about the centre, a negative roll (and pitch) stiffness: 1.2e5 N·m/rad on the shipped
file, half its roll suspension, and with the rotor's own response the suspended airframe
rolled over (measured: past 0.9 rad in 20 revolutions). On the arc, as for the rigid body it
stands for, the moment is zero. The optional ``[centre_of_gravity]`` table gives that centre:
:meth:`Airframe.elements` then attaches the hub on the arc to second order
(:class:`solver.modal.ModalAttachment`'s ``rotation_centre``), which carries the geometric
stiffness of the thrust exactly to the order of a linear model.

The shipped default is ``studies/data/uh60a/airframe.toml`` (:func:`default_airframe`), a
UH-60A-class airframe; its file documents which numbers are published and which assumed.
:func:`beam_airframe` makes a modal airframe from the rotor's own clamped fuselage-beam and
shaft head, so that the modal and the beam airframes can be compared on the same rotor.
"""

from __future__ import annotations

import difflib
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.modal import ModalAttachment, ModalStructure
from solver.rotations import skew
from studies.parameters import ParameterError, read_toml

if TYPE_CHECKING:
    from solver.beams import BeamNode
    from solver.bodies import PointMass, PrescribedBody, RigidBody

Array = NDArray[np.float64]

DIRECTIONS = ("x", "y", "z")  # the station outputs' direction labels (model axes)
G0 = 9.80665  # m s-2, standard gravity: the unit g of the stations' vibration
HUB_COMPONENTS = ("translation x", "translation y", "translation z", "rotation x",
                  "rotation y", "rotation z")
TOP_KEYS = ("title", "source", "hub", "centre_of_gravity", "stations", "modes")
HUB_KEYS = ("position",)
STATION_KEYS = ("name", "position")
MODE_KEYS = ("name", "frequency", "damping_ratio", "generalized_mass", "hub", "stations")
NAME = re.compile(r"[A-Za-z0-9_-]+\Z")
DEFAULT_FILE = "airframe.toml"
# A degenerate cluster of beam modes (equal frequencies to this relative spread) is made
# mass-orthogonal before its shapes are written.
CLUSTER_TOL = 1e-7


class AirframeError(ParameterError):
    """A modal airframe (file or arrays) is unusable; the message names the file, the mode or
    station, the key, the value and the valid range."""


# ---------------------------------------------------------------------------- the airframe
def _mode_label(i: int, names: Sequence[str]) -> str:
    return f"mode {names[i]!r} (modes[{i}])" if i < len(names) else f"modes[{i}]"


def _frozen(a: ArrayLike, shape: tuple[int, ...], what: str) -> Array:
    out = np.array(a, dtype=float)
    if out.shape != shape:
        raise AirframeError(f"{what} has shape {out.shape}; expected {shape}")
    out.flags.writeable = False
    return out


def _check_name(name: Any, what: str) -> None:
    if not isinstance(name, str) or not NAME.match(name):
        raise AirframeError(f"{what}: name = {name!r} must be a non-empty bare TOML key "
                            "(letters, digits, _ and -)")


@dataclass(frozen=True, eq=False)
class Airframe:
    """A modal airframe: n modes, their shapes at the hub point and at named stations.

    All arrays are read-only, in the rotor model's axes (x aft, y starboard, z up) and the
    units of the module docstring. Built by :func:`read_airframe` or :func:`beam_airframe`;
    the constructor checks everything (:class:`AirframeError`).

    Parameters
    ----------
    title, source
        A line of text; where the numbers come from (published, assumed).
    hub_position
        The hub attachment point (3,), m.
    station_names, station_positions
        Response stations: unique names and positions (n_stations, 3), m.
    mode_names
        Unique mode names (n,).
    frequencies
        Undamped natural frequencies f_i (n,), Hz, ≥ 0.
    damping_ratios
        Modal damping ratios ζ_i (n,), in [0, 1).
    masses
        Generalized masses m_i (n,), kg, > 0.
    hub_shapes
        Shapes at the hub point (6, n): rows translation x, y, z (m per m of η), rotation
        about x, y, z (rad per m of η).
    station_shapes
        Translation shapes at the stations (n_stations, 3, n), m per m of η.
    centre_of_gravity
        The centre of the rigid-body rotation modes (3,), m, or ``None`` (the hub then
        follows the linear shapes alone: see the module docstring's "Rigid-body modes").
    """

    title: str
    source: str
    hub_position: Array
    station_names: tuple[str, ...]
    station_positions: Array
    mode_names: tuple[str, ...]
    frequencies: Array
    damping_ratios: Array
    masses: Array
    hub_shapes: Array
    station_shapes: Array
    centre_of_gravity: Array | None = None

    def __post_init__(self) -> None:
        for key in ("title", "source"):
            if not isinstance(getattr(self, key), str):
                raise AirframeError(f"{key} = {getattr(self, key)!r} must be a string")
        names, stations = tuple(self.mode_names), tuple(self.station_names)
        object.__setattr__(self, "mode_names", names)
        object.__setattr__(self, "station_names", stations)
        n, ns = len(names), len(stations)
        if n == 0:
            raise AirframeError("no modes: give at least one [[modes]] table")
        for kind, seq in (("modes", names), ("stations", stations)):
            for i, name in enumerate(seq):
                _check_name(name, f"{kind}[{i}]")
                if name in seq[:i]:
                    raise AirframeError(f"{kind}[{i}]: duplicate name {name!r}; names must be "
                                        "unique")
        arrays = {
            "hub_position": (3,), "station_positions": (ns, 3), "frequencies": (n,),
            "damping_ratios": (n,), "masses": (n,), "hub_shapes": (6, n),
            "station_shapes": (ns, 3, n),
        }
        for key, shape in arrays.items():
            object.__setattr__(self, key, _frozen(getattr(self, key), shape, key))
        if self.centre_of_gravity is not None:
            object.__setattr__(self, "centre_of_gravity",
                               _frozen(self.centre_of_gravity, (3,), "centre_of_gravity"))
            if not np.all(np.isfinite(self.centre_of_gravity)):
                raise AirframeError("centre_of_gravity: position = "
                                    f"{self.centre_of_gravity.tolist()} m must be finite")
        if not np.all(np.isfinite(self.hub_position)):
            raise AirframeError(f"hub: position = {self.hub_position.tolist()} m must be "
                                "finite")
        for i, name in enumerate(stations):
            p = self.station_positions[i]
            if not np.all(np.isfinite(p)):
                raise AirframeError(f"station {name!r} (stations[{i}]): position = "
                                    f"{p.tolist()} m must be finite")
        # per mode, in the file's terms: key = value: the valid range
        checks = (
            ("frequency", self.frequencies, " Hz", lambda v: v >= 0.0, "[0, inf) Hz"),
            ("damping_ratio", self.damping_ratios, "", lambda v: 0.0 <= v < 1.0,
             "[0, 1) (fraction of critical damping)"),
            ("generalized_mass", self.masses, " kg", lambda v: v > 0.0,
             "(0, inf) kg"),
        )
        for i in range(n):
            where = _mode_label(i, names)
            for key, values, unit, ok, valid in checks:
                v = float(values[i])
                if not math.isfinite(v):
                    raise AirframeError(f"{where}: {key} = {v!r}{unit} must be finite, in "
                                        f"{valid}")
                if not ok(v):
                    raise AirframeError(f"{where}: {key} = {v!r}{unit}: outside the valid "
                                        f"range {valid}")
            bad = np.flatnonzero(~np.isfinite(self.hub_shapes[:, i]))
            if bad.size:
                k = int(bad[0])
                raise AirframeError(f"{where}: hub[{k}] ({HUB_COMPONENTS[k]}) = "
                                    f"{float(self.hub_shapes[k, i])!r} must be finite")
            for j, station in enumerate(stations):
                s = self.station_shapes[j, :, i]
                if not np.all(np.isfinite(s)):
                    raise AirframeError(f"{where}: stations.{station} = {s.tolist()} must be "
                                        "finite")

    # -- sizes and views -----------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of modes n."""
        return len(self.mode_names)

    @property
    def n_stations(self) -> int:
        """Number of response stations."""
        return len(self.station_names)

    @property
    def station_offsets(self) -> Array:
        """Station positions relative to the hub point (n_stations, 3), m."""
        return self.station_positions - self.hub_position

    def station_index(self, name: str) -> int:
        """Index of a station by name (``KeyError`` naming the declared ones)."""
        try:
            return self.station_names.index(name)
        except ValueError:
            raise KeyError(f"no station {name!r}; declared: "
                           f"{', '.join(self.station_names) or 'none'}") from None

    # -- solver elements -----------------------------------------------------------------
    def elements(self, body: RigidBody | PrescribedBody | BeamNode | PointMass,
                 point: ArrayLike | None = None, name: str = "airframe", *,
                 displacement: ArrayLike | None = None,
                 velocity: ArrayLike | None = None) -> tuple[ModalStructure, ModalAttachment]:
        """The modal structure and the joint attaching ``body`` at the hub point.

        Parameters
        ----------
        body
            The body the hub loads come through (e.g. the rotor's shaft head): its material
            point at ``point`` follows Φ_t η and its small rotation Φ_r η (both hub shape
            blocks are used, so ``body`` must have an orientation: a rigid body, a beam node
            or a prescribed body).
        point
            Global position (m) of the attachment at t = 0 (default: the file's hub
            position). The model's origin need not be the file's: only the shapes enter the
            attachment, so the rotor passes its own hub centre here.
        name
            Name of the modal structure; the joint is ``name + "_hub"``.
        displacement, velocity
            Initial η (m) and η̇ (m/s), e.g. :meth:`static_displacement`; the body must be
            declared where that deflection carries it (see
            :class:`solver.modal.ModalAttachment`).

        Returns
        -------
        (ModalStructure, ModalAttachment)
            Add both to the model (after ``body``).
        """
        modal = ModalStructure(name, self.frequencies, self.damping_ratios, self.masses,
                               displacement=displacement, velocity=velocity)
        p = self.hub_position if point is None else np.asarray(point, dtype=float)
        # the centre of gravity, where the attachment point puts the hub
        centre = (None if self.centre_of_gravity is None
                  else p + self.centre_of_gravity - self.hub_position)
        joint = ModalAttachment(f"{name}_hub", body, modal, p, self.hub_shapes[:3],
                                self.hub_shapes[3:], rotation_centre=centre)
        return modal, joint

    def station_accelerations(self, eta_ddot: ArrayLike) -> Array:
        """Φ_s η̈: see :func:`station_accelerations`."""
        return station_accelerations(self, eta_ddot)

    def static_displacement(self, force: ArrayLike = (0.0, 0.0, 0.0),
                            moment: ArrayLike = (0.0, 0.0, 0.0)) -> Array:
        """η (m) of the airframe held by a constant hub force (N) and moment (N·m, about the
        hub point), both global: η_i = (Φ_t,iᵀ F + Φ_r,iᵀ M) / (m_i ω_i²), the start of a run
        on the mean deflection. Linear: the attached model's own equilibrium differs at second
        order in the load (on the shipped file under the UH-60A's mean thrust and shaft
        torque by 7e-3 of the largest η: the torque, tilted with the deflected hub, loads
        roll and torsion, and the thrust stiffens roll and pitch on the arc about the centre
        of gravity). Raises :class:`AirframeError` if a loaded mode has no stiffness
        (0 Hz: no static deflection exists)."""
        load = np.concatenate([np.asarray(force, dtype=float).reshape(3),
                               np.asarray(moment, dtype=float).reshape(3)])
        q = self.hub_shapes.T @ load
        k = self.masses * (2.0 * np.pi * self.frequencies) ** 2
        free = (k == 0.0) & (q != 0.0)
        if free.any():
            i = int(np.flatnonzero(free)[0])
            raise AirframeError(f"{_mode_label(i, self.mode_names)} has frequency 0 Hz and "
                                f"the load drives it (Q = {q[i]:g} N): no static deflection "
                                "exists; give the rigid-body modes a suspension frequency")
        return np.divide(q, k, out=np.zeros_like(q), where=k > 0.0)


def station_accelerations(airframe: Airframe, eta_ddot: ArrayLike) -> Array:
    """Station accelerations Φ_s η̈ (m s-2): (n_stations, 3, ...) for η̈ of shape (n, ...)
    (m s-2 of η: one modal state, or one per trailing index, e.g. per time sample)."""
    acc = np.asarray(eta_ddot, dtype=float)
    if acc.ndim == 0 or acc.shape[0] != airframe.n_modes:
        raise ValueError(f"eta_ddot has shape {acc.shape}; its first axis must hold the "
                         f"{airframe.n_modes} modes")
    return np.tensordot(airframe.station_shapes, acc, axes=([2], [0]))


# ------------------------------------------------------------------------------ reading
def default_airframe_path() -> Path:
    """The shipped UH-60A-class airframe file (``studies/data/uh60a/airframe.toml``)."""
    return Path(str(resources.files("studies.data.uh60a") / DEFAULT_FILE))


def default_airframe() -> Airframe:
    """The shipped UH-60A-class airframe (:func:`default_airframe_path`)."""
    return read_airframe(default_airframe_path())


def _suggest(key: str, allowed: Sequence[str]) -> str:
    close = difflib.get_close_matches(key, list(allowed), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _table(value: Any, where: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise AirframeError(f"{where} must be a table, not {type(value).__name__}")
    return value


def _keys(table: Mapping[str, Any], where: str, allowed: Sequence[str],
          required: Sequence[str], hints: Mapping[str, str]) -> None:
    for key in table:
        if key not in allowed:
            raise AirframeError(f"{where}: unknown key {key!r}{_suggest(key, allowed)}; "
                                f"allowed: {', '.join(allowed)}")
    for key in required:
        if key not in table:
            raise AirframeError(f"{where}: missing key {key!r} ({hints[key]})")


def _number(value: Any, where: str, key: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise AirframeError(f"{where}: {key} = {value!r}: expected a number ({unit})")
    try:
        return float(value)
    except OverflowError:  # an integer too large for a float
        return math.inf


def _vector(value: Any, where: str, key: str, n: int, meaning: str) -> list[float]:
    if not isinstance(value, list):
        raise AirframeError(f"{where}: {key} = {value!r}: expected a list of {n} numbers "
                            f"({meaning})")
    if len(value) != n:
        raise AirframeError(f"{where}: {key} has {len(value)} values; expected {n} "
                            f"({meaning})")
    out = [_number(v, where, f"{key}[{k}]", meaning) for k, v in enumerate(value)]
    for k, v in enumerate(out):
        if not math.isfinite(v):
            raise AirframeError(f"{where}: {key}[{k}] = {v!r} must be finite ({meaning})")
    return out


HINTS = {
    "title": "a line of text", "source": "text: where the numbers come from",
    "hub": "a [hub] table with position = [x, y, z] in m", "modes": "[[modes]] tables",
    "centre_of_gravity": "a [centre_of_gravity] table with position = [x, y, z] in m",
    "position": "[x, y, z] in m", "name": "a bare TOML key",
    "frequency": "Hz, >= 0", "damping_ratio": "fraction of critical damping, in [0, 1)",
    "generalized_mass": "kg, > 0",
    "hub_shape": "6 numbers: translation x, y, z in m per m of η, rotation x, y, z in rad "
                 "per m of η",
    "stations": "a [modes.stations] table: one [x, y, z] in m per m of η per declared station",
}
MODE_HINTS = {**HINTS, "hub": HINTS["hub_shape"]}


def read_airframe(path: str | Path) -> Airframe:
    """Read and check a modal airframe file (the TOML format of the module docstring).

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    Airframe

    Raises
    ------
    AirframeError
        For a missing or unreadable file, invalid TOML, or any bad entry (the message names
        the file, the mode or station, the key, the value and the valid range).
    """
    path = Path(path)
    doc = read_toml(path, AirframeError, "airframe file")[1]
    try:
        return _parse(doc)
    except AirframeError as exc:
        raise AirframeError(f"{path}: {exc}") from None


def _named_entry(entry: Any, kind: str, index: int, allowed: Sequence[str],
                 required: Sequence[str], hints: Mapping[str, str],
                 seen: list[str]) -> tuple[dict[str, Any], str]:
    """The ``index``-th ``[[stations]]`` or ``[[modes]]`` table (``kind`` "station" or "mode")
    checked for its keys and a unique name, which is appended to ``seen``; returns it and the
    place name the messages use."""
    where = f"{kind}s[{index}]"
    entry = _table(entry, where)
    if isinstance(entry.get("name"), str):
        where = f"{kind} {entry['name']!r} ({where})"
    _keys(entry, where, allowed, required, hints)
    _check_name(entry["name"], where)
    if entry["name"] in seen:
        raise AirframeError(f"{where}: duplicate name {entry['name']!r}; {kind} names must be "
                            "unique")
    seen.append(entry["name"])
    return entry, where


def _parse(doc: dict[str, Any]) -> Airframe:
    _keys(doc, "top level", TOP_KEYS, ("title", "source", "hub", "modes"), HINTS)
    for key in ("title", "source"):
        if not isinstance(doc[key], str):
            raise AirframeError(f"{key} = {doc[key]!r}: expected a string ({HINTS[key]})")
    hub = _table(doc["hub"], "[hub]")
    _keys(hub, "[hub]", HUB_KEYS, HUB_KEYS, HINTS)
    hub_position = _vector(hub["position"], "[hub]", "position", 3, "x, y, z in m")
    centre = None
    if "centre_of_gravity" in doc:
        table = _table(doc["centre_of_gravity"], "[centre_of_gravity]")
        _keys(table, "[centre_of_gravity]", HUB_KEYS, HUB_KEYS, HINTS)
        centre = _vector(table["position"], "[centre_of_gravity]", "position", 3,
                         "x, y, z in m")

    raw_stations = doc.get("stations", [])
    if not isinstance(raw_stations, list):
        raise AirframeError("stations must be a list of [[stations]] tables")
    station_names: list[str] = []
    station_positions: list[list[float]] = []
    for j, entry in enumerate(raw_stations):
        entry, where = _named_entry(entry, "station", j, STATION_KEYS, STATION_KEYS, HINTS,
                                    station_names)
        station_positions.append(_vector(entry["position"], where, "position", 3,
                                         "x, y, z in m"))

    raw_modes = doc["modes"]
    if not isinstance(raw_modes, list) or not raw_modes:
        raise AirframeError("modes must be a non-empty list of [[modes]] tables")
    names: list[str] = []
    values: dict[str, list[float]] = {"frequency": [], "damping_ratio": [],
                                      "generalized_mass": []}
    units = {"frequency": "Hz", "damping_ratio": "fraction of critical damping",
             "generalized_mass": "kg"}
    hub_shapes: list[list[float]] = []
    station_shapes = np.zeros((len(station_names), 3, len(raw_modes)))
    required = ("name", "frequency", "damping_ratio", "generalized_mass", "hub")
    for i, entry in enumerate(raw_modes):
        entry, where = _named_entry(entry, "mode", i, MODE_KEYS, required, MODE_HINTS, names)
        for key in values:
            values[key].append(_number(entry[key], where, key, units[key]))
        hub_shapes.append(_vector(entry["hub"], where, "hub", 6, HINTS["hub_shape"]))
        shapes = entry.get("stations", {})
        if station_names and "stations" not in entry:
            raise AirframeError(f"{where}: missing key 'stations' ({HINTS['stations']}: "
                                f"{', '.join(station_names)})")
        shapes = _table(shapes, f"{where}: stations")
        for key in shapes:
            if key not in station_names:
                raise AirframeError(
                    f"{where}: stations.{key}: a shape for {key!r}, which is not a declared "
                    f"station{_suggest(key, station_names)}; declared: "
                    f"{', '.join(station_names) or 'none'}")
        for j, station in enumerate(station_names):
            if station not in shapes:
                raise AirframeError(f"{where}: stations: no shape for the declared station "
                                    f"{station!r} (x, y, z in m per m of η)")
            station_shapes[j, :, i] = _vector(shapes[station], where, f"stations.{station}",
                                              3, "x, y, z in m per m of η")
    return Airframe(
        title=doc["title"], source=doc["source"], hub_position=hub_position,
        station_names=tuple(station_names),
        station_positions=np.reshape(station_positions, (len(station_names), 3)),
        mode_names=tuple(names), frequencies=values["frequency"],
        damping_ratios=values["damping_ratio"], masses=values["generalized_mass"],
        hub_shapes=np.array(hub_shapes).T.reshape(6, len(names)),
        station_shapes=station_shapes, centre_of_gravity=centre)


# ------------------------------------------------------------------------------ writing
def _string(text: str) -> str:
    """A TOML string for ``text``: a multi-line literal string when that can hold it, else
    a basic string (JSON's escapes are TOML's)."""
    literal = ("\n" in text and "'''" not in text and not text.endswith("'")
               and not re.search(r"[\x00-\x08\x0b-\x1f\x7f]", text))  # \r included
    if literal:
        return "'''\n" + text + "'''"
    return json.dumps(text, ensure_ascii=False)


def _floats(values: ArrayLike) -> str:
    # repr: the shortest text that reads back to the same double (an exact round trip)
    return "[" + ", ".join(repr(float(v)) for v in np.asarray(values).ravel()) + "]"


def write_airframe(airframe: Airframe, path: str | Path) -> Path:
    """Write ``airframe`` as a modal file (the module docstring's format) that
    :func:`read_airframe` reads back exactly (every number to the last bit).

    Returns
    -------
    Path
        The file written.
    """
    path = Path(path)
    lines = [
        "# Modal airframe (format: studies/airframe.py). Axes: x aft, y starboard, z up.",
        "# Units: m, Hz, kg; shapes in m (translation) and rad (rotation) per m of η.",
        f"title = {_string(airframe.title)}",
        f"source = {_string(airframe.source)}",
        "",
        "[hub]",
        f"position = {_floats(airframe.hub_position)}",
    ]
    if airframe.centre_of_gravity is not None:
        lines += ["", "[centre_of_gravity]",
                  f"position = {_floats(airframe.centre_of_gravity)}"]
    for name, p in zip(airframe.station_names, airframe.station_positions, strict=True):
        lines += ["", "[[stations]]", f"name = {json.dumps(name)}", f"position = {_floats(p)}"]
    for i, name in enumerate(airframe.mode_names):
        lines += [
            "", "[[modes]]", f"name = {json.dumps(name)}",
            f"frequency = {float(airframe.frequencies[i])!r}",
            f"damping_ratio = {float(airframe.damping_ratios[i])!r}",
            f"generalized_mass = {float(airframe.masses[i])!r}",
            f"hub = {_floats(airframe.hub_shapes[:, i])}",
        ]
        if airframe.n_stations:
            lines.append("[modes.stations]")
            lines += [f"{s} = {_floats(airframe.station_shapes[j, :, i])}"
                      for j, s in enumerate(airframe.station_names)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


# ------------------------------------------------------------- the fuselage-beam's modes
def _clamped_beam(length: float, bending_stiffness: float, tip_mass: float,
                  tip_inertia: ArrayLike, elements: int, axial_stiffness: float,
                  shear_stiffness: float, torsional_stiffness: float, mass_per_length: float,
                  section_inertia: float):
    """The rotor's fuselage-beam with its shaft head welded to its top, clamped to the ground
    (:func:`studies.rotor.fuselage_beam`), with the section constants given. Returns (model,
    tip body)."""
    from solver.bodies import ground
    from solver.model import Model
    from studies.rotor import fuselage_beam, fuselage_section

    section = fuselage_section(bending_stiffness, axial=axial_stiffness,
                               shear=shear_stiffness, torsion=torsional_stiffness,
                               mass=mass_per_length, inertia=section_inertia)
    g0 = ground()
    beam, tip, mounts = fuselage_beam(g0, length, section, tip_mass, elements,
                                      tuple(np.asarray(tip_inertia, dtype=float)))
    model = Model()
    model.add(g0, beam, tip, *mounts)
    return model, tip


def _rotation_rows(o: int, n: int) -> Array:
    """The rows (3 × n) mapping a body's perturbed coordinates (position at o, directors d_k
    at o + 3 + 3k, initially e_k) to its small rotation δθ = ½ Σ_k e_k × δd_k (the measure
    :class:`solver.modal.ModalAttachment` uses)."""
    t = np.zeros((3, n))
    for k in range(3):
        t[:, o + 3 + 3 * k : o + 6 + 3 * k] = 0.5 * skew(np.eye(3)[k])
    return t


def _m_orthogonal(phi: Array, mass: Array, freq: Array) -> Array:
    """Shapes made mass-orthogonal within clusters of equal frequency (Gram–Schmidt in the
    mass inner product, in order: an already orthogonal cluster is left unchanged)."""
    phi = phi.copy()
    i = 0
    while i < len(freq):
        j = i + 1
        while j < len(freq) and abs(freq[j] - freq[i]) <= CLUSTER_TOL * freq[i]:
            j += 1
        for a in range(i + 1, j):
            for b in range(i, a):
                mb = phi[:, b] @ mass @ phi[:, b]
                phi[:, a] -= (phi[:, b] @ mass @ phi[:, a]) / mb * phi[:, b]
        i = j
    return phi


def beam_airframe(*, length: float | None = None, bending_stiffness: float | None = None,
                  tip_mass: float | None = None, tip_inertia: ArrayLike | None = None,
                  n_modes: int | None = None, max_frequency: float = 3000.0,
                  elements: int | None = None,
                  axial_stiffness: float | None = None, shear_stiffness: float | None = None,
                  torsional_stiffness: float | None = None,
                  mass_per_length: float | None = None,
                  section_inertia: float | None = None,
                  damping_ratio: float = 0.02, title: str | None = None) -> Airframe:
    """The modal airframe of the rotor's clamped fuselage-beam carrying its shaft head.

    The beam and tip body are built as :func:`studies.rotor.fuselage_beam` builds them (the
    defaults are the rotor's: ``fuselage_length``, the nominal
    ``fuselage_bending_stiffness``, ``shaft_mass`` and its inertia, the section constants
    ``FUSELAGE_*``), its modes computed by :func:`solver.modes.natural_frequencies`, and each
    mode written as the module docstring describes: the frequency, the given damping ratio,
    the hub shape (translation and small rotation ½ Σ e_k × δd_k of the tip body, the
    :class:`solver.modal.ModalAttachment` measure) scaled so its largest translation component
    is +1 m per m of η (its largest rotation component +1 rad per m of η for a mode that only
    turns the hub, torsion), and the generalized mass φᵀ M φ of that scaled shape in the
    linearization's mass matrix (consistent with the solver's kinetic energy). Within a
    cluster of equal frequencies (bending in x and y of the isotropic beam) the shapes are
    made mass-orthogonal first. The hub point is the beam's top, the origin; no stations.

    The tip body is part of the airframe: a rotor attached to this airframe should carry its
    own shaft head with no mass of its own (or this function called with ``tip_mass`` 0 and
    the shaft head kept in the rotor, at the cost of more modes for the same accuracy).

    Only the modes up to ``max_frequency`` are kept. The discretized beam's top modes (shear
    and extension of its elements, up to 240 kHz with m ω² ≈ 1e22 N/m for the rotor's beam)
    are not physics worth keeping and ruin a modal model: with stiffnesses m_i ω_i² spanning
    more than about 1e15, the low modes of the model a body is attached to are lost to
    roundoff (measured on the rotor's beam with a massless shaft head attached: its first
    bending frequency off by 2.7 % with all 36 modes, by 2.1e-11 with the 10 up to 3 kHz).

    Parameters
    ----------
    length, bending_stiffness, tip_mass, tip_inertia
        Beam length (m, clamp to hub centre), EI (N·m², both planes), tip body mass (kg) and
        principal inertia (kg·m², body axes = global).
    n_modes, max_frequency
        Keep the n lowest modes (default: all) of those up to ``max_frequency`` (Hz; default
        3 kHz, 10 modes of the rotor's beam, 175 × 4P).
    elements, axial_stiffness, shear_stiffness, torsional_stiffness, mass_per_length,
    section_inertia
        Cubic elements, EA (N), GA (N, both), GJ (N·m²), mass (kg/m) and i22 = i33 (kg·m).
    damping_ratio
        ζ given to every mode (the beam itself is undamped).
    title
        Default: one naming the beam.

    Returns
    -------
    Airframe
    """
    from solver.modes import natural_frequencies
    from studies import rotor

    p = rotor.PARAMETERS
    length = p["fuselage_length"].default if length is None else length
    ei = p["fuselage_bending_stiffness"].default if bending_stiffness is None else bending_stiffness
    tip_mass = p["shaft_mass"].default if tip_mass is None else tip_mass
    elements = rotor.FUSELAGE_ELEMENTS if elements is None else elements
    ea = rotor.FUSELAGE_EA if axial_stiffness is None else axial_stiffness
    ga = rotor.FUSELAGE_GA if shear_stiffness is None else shear_stiffness
    gj = rotor.FUSELAGE_GJ if torsional_stiffness is None else torsional_stiffness
    mu = rotor.FUSELAGE_MASS if mass_per_length is None else mass_per_length
    tip_inertia = rotor.SHAFT_INERTIA if tip_inertia is None else tip_inertia
    if section_inertia is None:
        section_inertia = rotor.FUSELAGE_SECTION_INERTIA
    model, tip = _clamped_beam(length, ei, tip_mass, tip_inertia, elements, ea, ga, gj, mu,
                               section_inertia)
    md = natural_frequencies(model)
    available = int(np.count_nonzero(md.frequency <= max_frequency))
    if n_modes is None:
        n_modes = available
    if not 1 <= n_modes <= available:
        raise ValueError(f"n_modes = {n_modes!r}: the beam has {available} modes up to "
                         f"max_frequency = {max_frequency:g} Hz (its lowest at "
                         f"{md.frequency[0]:g} Hz); give 1 to {available} (or None for all "
                         "of them), or raise max_frequency")
    lin = md.linearization
    phi = md.shapes[:, :n_modes]
    if np.abs(phi.imag).max() > 1e-9 * np.abs(phi.real).max():
        raise RuntimeError("the beam's undamped modes came out complex")
    freq = md.frequency[:n_modes]
    phi = _m_orthogonal(phi.real, lin.M, freq)
    o = lin.system.offset[tip]
    hub = np.vstack([phi[o : o + 3], _rotation_rows(o, phi.shape[0]) @ phi])
    names = []
    for j in range(n_modes):
        t, r = hub[:3, j], hub[3:, j]
        # a mode that only turns the hub (torsion): its translation is roundoff
        turns = np.abs(t).max() <= 1e-8 * length * np.abs(r).max()
        block = r if turns else t
        k = int(np.argmax(np.abs(block)))
        pivot = block[k]  # divided by itself: exactly 1
        hub[:, j] /= pivot
        phi[:, j] /= pivot
        names.append(f"mode_{j + 1}_{'r' if turns else ''}{DIRECTIONS[k]}")
    masses = np.einsum("ij,ik,kj->j", phi, lin.M, phi)
    return Airframe(
        title=title or (f"clamped fuselage-beam, {length:g} m, EI {ei:g} N m2, tip mass "
                        f"{tip_mass:g} kg: its {n_modes} lowest modes"),
        source=(f"studies.airframe.beam_airframe: solver.modes of the rotor's fuselage-beam "
                f"({elements} cubic elements, EA {ea:g} N, GA {ga:g} N, GJ {gj:g} N m2, "
                f"{mu:g} kg/m, i22 = i33 {section_inertia:g} kg m) clamped at z = "
                f"{-length:g} m, its top at the origin carrying a rigid body of {tip_mass:g} "
                f"kg and inertia {np.asarray(tip_inertia, dtype=float).tolist()} kg m2; "
                f"damping ratio {damping_ratio:g} given to every mode"),
        hub_position=np.zeros(3), station_names=(), station_positions=np.zeros((0, 3)),
        mode_names=tuple(names), frequencies=freq, damping_ratios=np.full(n_modes,
                                                                         damping_ratio),
        masses=masses, hub_shapes=hub, station_shapes=np.zeros((0, 3, n_modes)))
