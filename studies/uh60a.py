"""The public UH-60A main-rotor blade data as solver inputs.

Data (``studies/data/uh60a/``, copied unchanged from the public repository ``ptrbortolotti/SONATA``,
commit ``38c9c9cd65788fea378e86841d0881d43ad1e973``, folder ``jobs/VariSpeed/uh60a_data_blade/``;
see the README there):

* the Dymore blade deck ``dymore_uh60a_rotor_blade.dat``: H. Yeo's UH-60A section properties
  (beam property ``BLADE_BP_CD01``, 46 stations every 0.02R from r = 0.818 m to the tip), the
  structural and lifting-line twist, chord, airfoil tables and airstation positions;
* the piecewise-constant set after Davis (NASA, 1981), used here only inboard of r = 0.818 m,
  where the deck has nothing (root cuff and the ≈ 3.5 kg lump at the hinge);
* the digitized Bowen-Davies fan plot.

Frames and signs (read from the deck; those of Dymore, VABS and SONATA, whose section class says
"x1 along the beam, x2 towards the leading edge, x3 upwards"):

* blade frame — the deck's beam runs along +x of its frame ``BLADE_BF_BE01`` and its section triad
  is ``E2 = (0, 1, 0)``, ``E3 = (0, 0, 1)``. So d1 is spanwise outboard, d2 chordwise towards the
  leading edge, d3 normal to the chord, up (flap); for a rotor turning about +d3 (the UH-60A turns
  counter-clockwise seen from above) the leading edge advances along +d2. Check in the data: the
  swept tip's airstations and the Davis/Yeo tip centre of mass lie at negative d2 (the tip is
  swept aft), and the tip-weight region near 0.9R has its centre of mass at positive d2 (forward);
* twist — Dymore's 3-1-3 Euler angles (0, θ, 0) in degrees: a rotation θ about d1, positive
  nose up (d2, the leading edge, turning towards d3). Returned in rad;
* radius — the deck's arc length s starts at the blade attachment, r = s + (R − L) with the deck's
  beam length L = 7.36082856 m, i.e. the attachment at r = 0.8178714 m (SONATA's
  ``x_offset = 0.81786984``; the 1.6 µm difference puts the tip exactly at R = 8.1787 m).
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from importlib.resources.abc import Traversable
from typing import Literal

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from solver.sections import SectionTable

Array = NDArray[np.float64]
Value = str | dict  # a brace group of the deck: leaf text, or a nested block

DECK = "dymore_uh60a_rotor_blade.dat"
FANPLOT = "fanplot_bowen-davies.txt"
BEAM_PROPERTY = "BLADE_BP_CD01"  # Yeo's set
LIFTING_LINE = "BLADE_LL_CD01_BE01"
LIFTING_LINE_PROPERTY = "BLADE_LP_CD01"
TWIST_DISTRIBUTION = {"aero": "BLADE_OD_CD02", "structural": "BLADE_OD_CD01"}


@dataclass(frozen=True)
class UH60AData:
    """Global UH-60A rotor data (SI), with their public sources.

    GenHel = ``terragord7/J-GenHel`` ``H60_constants.jl`` after Howlett (NASA CR-166309, 1981);
    deck = the Dymore deck above; cross-checked against mscsim and SSCMTSVT.
    """

    n_blades: int = 4  # 1; all sources
    radius: float = 8.1787  # m; deck/SONATA (GenHel 26.83 ft = 8.178 m)
    hinge_radius: float = 0.381  # m; coincident flap/lag/pitch bearing, 15 in (GenHel);
    #                              SONATA/Dymore use 0.378
    beam_length: float = 7.36082856  # m; the deck's flexible beam (attachment to tip)
    omega_ref: float = 27.0  # rad/s; 258 rpm (GenHel; fan plot Ω_ref = 4.3 Hz)
    chord: float = 0.527  # m; nominal 1.73 ft (GenHel); deck 0.5273 inboard, 0.5325 outboard
    blade_mass: float = 116.5  # kg; 256.9 lb (GenHel, mscsim), hinge to tip
    blade_first_moment: float = 385.7  # kg·m; about the hinge, 86.7 slug·ft (GenHel)
    blade_flap_inertia: float = 2050.8  # kg·m²; about the hinge, 1512.6 slug·ft² (GenHel)
    lift_slope: float = 5.73  # 1/rad; linear lift-curve slope (GenHel, mscsim, SSCMTSVT)
    cd0: float = 0.008  # 1; profile drag coefficient (J-GenHel; 0.0087 in a UH-60 BET script)
    tip_loss: float = 0.95  # 1; deck TIP_LOSS_FACTOR (mscsim 0.97)
    shaft_tilt: float = math.radians(3.0)  # rad; forward (GenHel ITHSH = −3°)
    swashplate_phase: float = math.radians(-9.7)  # rad; GenHel DELSP
    delta3: float = 0.0  # rad; pitch-flap coupling (GenHel)
    lag_damper: float = 21.9e3  # N·s/m; linear, on the damper stroke (GenHel CLAG 1500 lb·s/ft)
    lag_damping: float = 1.07e3  # N·m·s/rad; its rotational equivalent at β = θ = 0 (derived)
    lag_spring: float = 20.4e3  # N·m/rad; lag spring (GenHel KLAG 15060 ft·lb/rad)

    @property
    def attachment_radius(self) -> float:
        """Radius where the deck's flexible blade (and Yeo's table) starts (m): R − L."""
        return self.radius - self.beam_length

    def thrust_unit(self, density: float, omega: float) -> float:
        """The thrust of C_T = 1, ρ π R² (ΩR)² (N), at air density ``density`` (kg/m³) and rotor
        speed ``omega`` (rad/s)."""
        return density * math.pi * self.radius**2 * (omega * self.radius) ** 2

    @property
    def solidity(self) -> float:
        """Thrust-weighted solidity N c / (π R) with the nominal chord (1): 0.0821."""
        return self.n_blades * self.chord / (math.pi * self.radius)


UH60A = UH60AData()

# Bowen-Davies fan plot: the file's column labels and the modes they are read as. The file calls
# its fifth frequency column "f4", but it is the 2nd lag mode: (i) SONATA's own Dymore runs order
# their modes l1, f1, f2, f3, l2, t1, f4, so "f4" sits where lag 2 falls; (ii) the column rises
# only from 17.5 to 21.0 Hz between Ω = 0 and Ω_ref, the weak centrifugal stiffening of a mode
# whose non-rotating frequency is set by the large lag stiffness, while the flap columns rise by
# 10 Hz and more; (iii) an uncoupled hinged-beam model of this blade puts lag 2 at 20.6 Hz and
# flap 4 at 33.9 Hz at Ω_ref, against 20.98 Hz for "f4" and 33.80 Hz for the last column "f5"
# (tests/studies/test_uh60a.py).
MODE_LABEL: dict[str, str] = {"l1": "lag 1", "f1": "flap 1", "f2": "flap 2", "f3": "flap 3",
                              "f4": "lag 2", "t1": "torsion 1", "f5": "flap 4"}


def data_file(name: str) -> Traversable:
    """A file of ``studies/data/uh60a/`` (shipped as package data)."""
    return resources.files("studies") / "data" / "uh60a" / name


# --------------------------------------------------------------------------------------------
# Dymore deck reader
# --------------------------------------------------------------------------------------------

_TOKEN = re.compile(r"@(\w+)|([{}])|([^@{}]+)")


def parse_dymore(text: str) -> dict[str, list[list[Value]]]:
    """Parse a Dymore input deck into nested dicts and lists.

    The deck is a sequence of ``@KEYWORD`` followed by zero or more brace groups; a group holds
    either plain text (numbers, names) or further keywords. ``!`` starts a comment to the end of
    the line.

    Parameters
    ----------
    text
        The deck's text.

    Returns
    -------
    dict
        ``{keyword: [occurrence, ...]}`` in file order, each occurrence the list of the brace
        groups that follow the keyword; a group is its stripped text (``str``) or, when it
        contains keywords, a dict of the same form. ``@NAME{X}{...}`` gives ``[["X", {...}]]``;
        pairs written on one line (``@CURVILINEAR_COORDINATE{s} @CHORD_LENGTH{c}``) give two
        equally long lists, to be zipped.

    Raises
    ------
    ValueError
        On unbalanced braces, a brace group without a keyword, or text mixed with keywords.
    """
    tokens = _TOKEN.findall(re.sub(r"![^\n]*", "", text))
    pos = 0

    def skip_blank() -> None:  # whitespace between a keyword and its groups
        nonlocal pos
        while pos < len(tokens) and tokens[pos][2] and not tokens[pos][2].strip():
            pos += 1

    def block(depth: int) -> tuple[dict[str, list[list[Value]]], str]:
        nonlocal pos
        out: dict[str, list[list[Value]]] = {}
        words: list[str] = []
        while pos < len(tokens):
            key, brace, txt = tokens[pos]
            pos += 1
            if key:
                groups: list[Value] = []
                skip_blank()
                while pos < len(tokens) and tokens[pos][1] == "{":
                    pos += 1
                    sub, words_in = block(depth + 1)
                    groups.append(sub if sub else words_in.strip())
                    skip_blank()
                out.setdefault(key, []).append(groups)
            elif brace == "}":
                if depth == 0:
                    raise ValueError("Dymore deck: '}' without a matching '{'")
                break
            elif brace == "{":
                raise ValueError(f"Dymore deck: a brace group without a keyword near token {pos}")
            else:
                words.append(txt)
        else:
            if depth:
                raise ValueError("Dymore deck: unclosed '{' at the end of the text")
        text_here = "".join(words)
        if out and text_here.strip():
            raise ValueError(f"Dymore deck: text {text_here.strip()[:40]!r} mixed with keywords")
        return out, text_here

    return block(0)[0]


def read_deck(path: Traversable | None = None) -> dict[str, list[list[Value]]]:
    """The parsed Dymore deck (:func:`parse_dymore`); by default the shipped UH-60A deck."""
    path = data_file(DECK) if path is None else path
    return parse_dymore(path.read_text(encoding="ascii"))


@lru_cache(maxsize=1)
def _deck() -> dict[str, list[list[Value]]]:
    return read_deck()


def _floats(text: Value) -> Array:
    if not isinstance(text, str):
        raise ValueError("Dymore deck: expected numbers, found a block")
    return np.array([float(x) for x in text.split(",")], dtype=float)


def _named(definition: str, name_key: str, name: str) -> dict[str, list[list[Value]]]:
    """The body of ``@<name_key>{name}{...}`` inside the deck's ``@<definition>{...}``."""
    for (section,) in _deck().get(definition, []):
        if isinstance(section, dict):
            for occ in section.get(name_key, []):
                if len(occ) == 2 and occ[0] == name and isinstance(occ[1], dict):
                    return occ[1]
    raise KeyError(f"Dymore deck: no {name_key} {name!r} in {definition}")


def _column(body: dict, key: str) -> list[Value]:
    return [occ[0] for occ in body[key]]


def _one(body: dict, key: str) -> Value:
    return body[key][0][0]


# --------------------------------------------------------------------------------------------
# Section properties
# --------------------------------------------------------------------------------------------

def yeo_properties() -> dict[str, Array]:
    """Yeo's section table as the deck gives it (SI), one row per station.

    Returns
    -------
    dict
        ``s`` arc length from the attachment (m); ``r`` radius (m); ``EA`` (N); ``GA2``, ``GA3``,
        ``GA23`` shear stiffnesses (N) (``SHEARING_STIFFNESSES``, here 0.05 EA, uncoupled);
        ``GJ`` (N·m²); ``EI2`` flap, ``EI3`` lag, ``EI23`` coupling (N·m²)
        (``BENDING_STIFFNESSES {H22, H33, H23}``; H22 is the smaller, bending about the chord
        line d2); ``m`` (kg/m); ``I11``, ``I22``, ``I33`` (kg·m) (``MOMENTS_OF_INERTIA``:
        polar, about d2 = ∫ρ ξ3² dA (flapwise), about d3 = ∫ρ ξ2² dA (chordwise), about the
        centre of mass); ``cg2``, ``cg3`` centre of mass (m) (``CENTRE_OF_MASS_LOCATION``).

    Raises
    ------
    ValueError
        If the shear centre or the centroid is off the reference line (not represented here).
    """
    body = _named("BEAM_PROPERTY_DEFINITION", "BEAM_PROPERTY_NAME", BEAM_PROPERTY)
    if _one(body, "COORDINATE_TYPE") != "CURVILINEAR_COORDINATE":
        raise ValueError("Dymore deck: beam properties not given against arc length")
    rows = body["CURVILINEAR_COORDINATE"]
    s = np.array([float(occ[0]) for occ in rows])
    props = [occ[1] for occ in rows]

    def col(key: str) -> Array:
        return np.array([_floats(_one(p, key)) for p in props])

    out = {"s": s, "r": s + UH60A.attachment_radius, "EA": col("AXIAL_STIFFNESS")[:, 0],
           "GJ": col("TORSIONAL_STIFFNESS")[:, 0], "m": col("MASS_PER_UNIT_SPAN")[:, 0]}
    out.update(zip(("EI2", "EI3", "EI23"), col("BENDING_STIFFNESSES").T, strict=True))
    out.update(zip(("GA2", "GA3", "GA23"), col("SHEARING_STIFFNESSES").T, strict=True))
    out.update(zip(("I11", "I22", "I33"), col("MOMENTS_OF_INERTIA").T, strict=True))
    out.update(zip(("cg2", "cg3"), col("CENTRE_OF_MASS_LOCATION").T, strict=True))
    for key in ("SHEAR_CENTRE_LOCATION", "CENTROID_LOCATION"):
        if np.any(col(key) != 0.0):
            raise ValueError(f"Dymore deck: non-zero {key} is not supported")
    return out


def _davis(name: str) -> tuple[Array, Array]:
    """A Davis step table: radius (m) and value (SI), two rows per constant piece."""
    rv = np.loadtxt(str(data_file(name)), comments="#", ndmin=2)
    return rv[:, 0] * 1e-3, rv[:, 1]


def _davis_on(name: str, a: float, b: float) -> float:
    """The Davis value over the piece (a, b) (m), which must lie inside one constant piece."""
    r, v = _davis(name)
    mid = 0.5 * (a + b)
    k = int(np.searchsorted(r, mid, side="right")) - 1
    if not (0 <= k < len(r) - 1 and r[k] <= a + 1e-9 and b <= r[k + 1] + 1e-9
            and v[k] == v[k + 1]):
        raise ValueError(f"{name}: ({a:g}, {b:g}) m is not inside one constant piece")
    return float(v[k])


# Davis files used for the cuff, and the share of the polar inertia that is flapwise (Yeo's
# table splits its polar inertia I11 into I22 = 0.25 I11 and I33 = 0.75 I11 at every station but
# the first; the same split is applied to Davis' polar inertia).
_CUFF_FILES = {"m": "mass.dat", "EI2": "flapping_stiffness.dat", "EI3": "edgewise_stiffness2.dat",
               "GJ": "torsional_stiffness.dat", "J": "torsional_inertia.dat"}
FLAPWISE_SHARE = 0.25


def davis_cuff() -> dict[str, Array]:
    """Davis' root values between the hinge and the attachment, piece by piece (SI).

    Returns
    -------
    dict
        ``r0``, ``r1`` piece ends (m) and, per piece, ``m`` (kg/m), ``EI2`` flap, ``EI3`` lag,
        ``GJ`` (N·m²), ``J`` polar mass inertia about the centre of mass (kg·m). The pieces are
        cut at every Davis break in (e, r_att): the hinge lump 1338 kg/m over 0.3829–0.3855 m
        (3.48 kg), the cuff 47.92 kg/m, EI 3.68e5 / 3.71e5 N·m² from 0.3855 m, GJ 2.87e5 N·m²,
        and the polar inertia steps at 0.5918, 0.6629 and 0.762 m. Davis gives no bending
        stiffness inboard of the lump (0.381–0.3829 m); the lump's 2.29e5 N·m² is extended to
        the hinge there (a beam needs a finite stiffness, and the piece is 1.9 mm long).
    """
    e, r_att = UH60A.hinge_radius, UH60A.attachment_radius
    cuts = {e, r_att}
    for name in _CUFF_FILES.values():
        r, _ = _davis(name)
        cuts.update(float(x) for x in r if e + 1e-9 < x < r_att - 1e-9)
    edges = np.array(sorted(cuts))
    out = {"r0": edges[:-1], "r1": edges[1:]}
    for key, name in _CUFF_FILES.items():
        out[key] = np.array([_davis_on(name, a, b) for a, b in itertools.pairwise(edges)])
    for key in ("EI2", "EI3", "GJ"):  # extend the first non-zero stiffness inwards to the hinge
        v = out[key]
        for k in range(len(v) - 2, -1, -1):
            if v[k] == 0.0:
                v[k] = v[k + 1]
    return out


def section_origin(include_cuff: bool = True) -> float:
    """Radius (m) of arc length 0 of :func:`blade_sections`: the hinge, or the attachment."""
    return UH60A.hinge_radius if include_cuff else UH60A.attachment_radius


def blade_sections(include_cuff: bool = True) -> SectionTable:
    """The UH-60A blade's section table, hinge (or attachment) to tip.

    Parameters
    ----------
    include_cuff
        True: the flexible blade from the flap/lag hinge at e = 0.381 m (arc length 0) to the tip
        R = 8.1787 m, with Davis' cuff and hinge lump inboard of the attachment r_att = 0.81787 m.
        False: Yeo's 46 stations only, arc length 0 at r_att (the deck's beam).

    Returns
    -------
    SectionTable
        Arc length s = r − :func:`section_origin` (m), straight reference line along d1.

    Notes
    -----
    Mapping of the deck (Yeo) to :class:`~solver.sections.SectionTable`, station by station:

    * stiffness = diag(EA, GA2, GA3, GJ, H22, H33) in the order (axial, shear 2, shear 3,
      torsion, bending 2, bending 3). ``BENDING_STIFFNESSES {H22, H33, H23}``: H22 is bending
      about d2, the chord line — flap, the smaller value (6.4e4 against 2.4e6 N·m² mid-span) —
      and H33 about d3, lag; H23 = 0. ``SHEARING_STIFFNESSES {K22, K33, K23}`` are in the deck
      (GA = 0.05 EA, uncoupled) and are used as given. The reference line is the deck's beam
      axis, which is the elastic axis and shear centre (``SHEAR_CENTRE_LOCATION`` and
      ``CENTROID_LOCATION`` are zero), the pitch axis near the quarter chord;
    * mass = ``MASS_PER_UNIT_SPAN``;
    * cg = ``CENTRE_OF_MASS_LOCATION`` (ξ2, ξ3) as given: ξ2 chordwise, positive towards the
      leading edge (mid-span −0.021 m, i.e. aft of the reference line; the swept tip −0.13 m),
      ξ3 = 0. Davis' ``cg.dat`` has the same values and signs;
    * inertia = (i22, i33, i23) = (I22, I33, 0) from ``MOMENTS_OF_INERTIA {I11, I22, I33}``:
      I22 = ∫ρ ξ3² dA (about d2, flapwise) is our i22, I33 = ∫ρ ξ2² dA (about d3, chordwise) is
      our i33, and I11 = I22 + I33 the polar one (so the director form's M22 = i33,
      M33 = i22 plus the cg terms). They are taken about the centre of mass: Dymore's
      convention as SONATA reads it (it plots I11 and I33 against its own mass-centre values and
      against Davis' "inertia about C.G."), and the data agree — Yeo's I11 follows Davis' polar
      inertia about the cg (0.146 against 0.141 kg·m mid-span, 0.171 against 0.169 at the tip,
      where m ξ2² would add 0.07). The first station's I11 (0.0819) is not I22 + I33 (0.0668);
      I22 and I33 are used as given.

    Inboard of r_att (``include_cuff``; :func:`davis_cuff`): Davis' piecewise-constant mass,
    EI2, EI3, GJ and polar inertia J (split i22 = 0.25 J, i33 = 0.75 J as Yeo splits I11),
    cg = 0, and EA, GA2, GA3 of Yeo's first station (Davis gives none). Davis' ``cg.dat`` puts
    the hinge lump's centre of mass 184.2 mm forward; not used (the value equals the lump's
    mid-radius 384.2 mm minus 200, which looks like a transcription slip, and the lump sits at
    the hinge, where an offset barely matters). Where Davis meets Yeo, at r_att: a repeated
    station, Davis' values on the inboard side, Yeo's first station on the outboard side. The
    mass is continuous there (47.92 kg/m in both); EI2, EI3 and GJ drop from Davis' 3.68e5,
    3.71e5, 2.87e5 to Yeo's 2.54e5, 2.56e5, 2.02e5 N·m². Outboard, Yeo's values are linearly
    interpolated between his stations, as in the Dymore model (Davis' steps at 0.8255 and
    1.270 m are smoothed into Yeo's 0.02R ramps).
    """
    y = yeo_properties()
    n = len(y["s"])
    stiff = np.zeros((n, 6, 6))
    for k, key in enumerate(("EA", "GA2", "GA3", "GJ", "EI2", "EI3")):
        stiff[:, k, k] = y[key]
    stiff[:, 1, 2] = stiff[:, 2, 1] = y["GA23"]
    stiff[:, 4, 5] = stiff[:, 5, 4] = y["EI23"]
    mass = y["m"]
    cg = np.column_stack([y["cg2"], y["cg3"]])
    inertia = np.column_stack([y["I22"], y["I33"], np.zeros(n)])
    s = y["s"]
    if include_cuff:
        c = davis_cuff()
        r = np.column_stack([c["r0"], c["r1"]]).reshape(-1)  # both ends of each piece
        k_c = np.repeat(np.arange(len(c["r0"])), 2)
        cs = np.zeros((len(r), 6, 6))
        cs[:, 0, 0], cs[:, 1, 1], cs[:, 2, 2] = y["EA"][0], y["GA2"][0], y["GA3"][0]
        cs[:, 3, 3], cs[:, 4, 4], cs[:, 5, 5] = c["GJ"][k_c], c["EI2"][k_c], c["EI3"][k_c]
        j = c["J"][k_c]
        s = np.concatenate([r - UH60A.hinge_radius, s + (UH60A.attachment_radius
                                                         - UH60A.hinge_radius)])
        s[0] = 0.0
        stiff = np.concatenate([cs, stiff])
        mass = np.concatenate([c["m"][k_c], mass])
        cg = np.concatenate([np.zeros((len(r), 2)), cg])
        inertia = np.concatenate([np.column_stack([FLAPWISE_SHARE * j,
                                                   (1 - FLAPWISE_SHARE) * j,
                                                   np.zeros(len(r))]), inertia])
    return SectionTable(s, stiff, mass=mass, cg=cg, inertia=inertia)


# --------------------------------------------------------------------------------------------
# Lifting line: twist, chord, airfoils, airstations
# --------------------------------------------------------------------------------------------

def blade_twist(line: Literal["aero", "structural"] = "aero") -> tuple[Array, Array]:
    """Built-in twist against radius.

    Parameters
    ----------
    line
        ``"aero"``: the lifting line's orientation distribution ``BLADE_OD_CD02`` (81 airstation
        points plus the ends); ``"structural"``: the beam's ``BLADE_OD_CD01``.

    Returns
    -------
    r, twist
        Radius (m) and twist (rad), positive nose up (a rotation about d1 turning the leading
        edge d2 towards d3), piecewise linear between points. The reference is the deck's,
        not the root: the aero twist is 9.67° on the inboard blade (0.135–0.17R), crosses zero
        at 0.69R (−0.14° at 0.7R), reaches −3.63° at 0.93R and −1.62° at the tip — so a
        collective θ0 in this frame is the pitch near 0.7R.
    """
    body = _named("ORIENTATION_DISTRIBUTION_DEFINITION", "ORIENTATION_DISTRIBUTION_NAME",
                  TWIST_DISTRIBUTION[line])
    if (_one(body, "ORIENTATION_DEFINITION_TYPE"), _one(body, "COORDINATE_TYPE")) != \
            ("EULER_ANGLES_313", "CURVILINEAR_COORDINATE"):
        raise ValueError("Dymore deck: twist not given as 3-1-3 angles against arc length")
    s = np.array([_floats(v)[0] for v in _column(body, "CURVILINEAR_COORDINATE")])
    angles = np.array([_floats(v) for v in _column(body, "EULER_ANGLES_313")])
    if np.any(angles[:, [0, 2]] != 0.0):
        raise ValueError("Dymore deck: orientation is not a pure twist about d1")
    return s + UH60A.attachment_radius, np.radians(angles[:, 1])


def _lifting_line_property() -> dict:
    return _named("LIFTING_LINE_PROPERTY_DEFINITION", "LIFTING_LINE_PROPERTY_NAME",
                  LIFTING_LINE_PROPERTY)


def blade_chord() -> tuple[Array, Array]:
    """Chord against radius: r (m), chord (m), piecewise linear.

    From ``CHORD_LENGTH_DEFINITION``: zero at the attachment, rising to 0.5273 m at 0.135R,
    0.5325 m from 0.51R, 0.5706 m over 0.72–0.82R, 0.5273 m again over 0.86–0.92R and
    0.53–0.56 m on the swept tip (the wider values appear to include the trim tabs). The deck's
    quarter-chord offsets are all zero (the tip's sweep is in the airstation positions,
    :func:`blade_airstations`).
    """
    body = _one(_lifting_line_property(), "CHORD_LENGTH_DEFINITION")
    s = np.array([_floats(v)[0] for v in _column(body, "CURVILINEAR_COORDINATE")])
    chord = np.array([_floats(v)[0] for v in _column(body, "CHORD_LENGTH")])
    offset = np.array([_floats(v)[0] for v in _column(body, "QUARTER_CHORD_OFFSET")])
    if np.any(offset != 0.0):
        raise ValueError("Dymore deck: non-zero quarter-chord offsets are not supported")
    return s + UH60A.attachment_radius, chord


@dataclass(frozen=True)
class Airfoils:
    """Airfoil sections along the blade, with the rotor's global 2-D coefficients.

    Attributes
    ----------
    r
        Radii (m) of the deck's ``AIRTABLE_DEFINITION`` points; a change of section is given by
        two points 0.03 mm apart.
    name
        Section names at those points (``BLADE_AT_`` prefix removed): SC1095 inboard, SC1094R8
        from r = 4.008 m (0.49R) to 6.707 m (0.82R), SC1095 outboard.
    lift_slope
        Lift-curve slope (1/rad), the same for all sections: the deck's air tables are not
        public, so the global value :attr:`UH60AData.lift_slope`.
    cd0
        Profile drag coefficient (1), likewise global.
    """

    r: Array
    name: tuple[str, ...]
    lift_slope: float = UH60A.lift_slope
    cd0: float = UH60A.cd0

    def at(self, r: ArrayLike) -> list[str]:
        """Section name at radii ``r`` (m), from the nearest definition point inboard."""
        k = np.clip(np.searchsorted(self.r, np.atleast_1d(r), side="right") - 1,
                    0, len(self.r) - 1)
        return [self.name[i] for i in k]


def blade_airfoil() -> Airfoils:
    """Airfoil distribution of the lifting line (:class:`Airfoils`)."""
    body = _one(_lifting_line_property(), "AIRTABLE_DEFINITION")
    s = np.array([_floats(v)[0] for v in _column(body, "CURVILINEAR_COORDINATE")])
    names = tuple(str(v).strip().removeprefix("BLADE_AT_") for v in
                  _column(body, "AIRTABLE_NAME"))
    return Airfoils(s + UH60A.attachment_radius, names)


def blade_airstations() -> tuple[Array, Array]:
    """Airstation positions of the lifting line.

    Returns
    -------
    r, offset
        Radius (m) of the 81 airstations, and their (d2, d3) offsets from the beam reference
        line (m), (81, 2): −0.9 mm chordwise over most of the span, the aft sweep of the tip
        (−0.16 m at the last station, r = 8.108 m), and −7 to +11 mm along d3; d2 positive
        towards the leading edge.
    """
    ll = _named("LIFTING_LINE_DEFINITION", "LIFTING_LINE_NAME", LIFTING_LINE)
    xyz = np.array([_floats(v) for v in _column(_one(ll, "AIRSTATION_POSITION"),
                                                  "COORDINATES")])
    return xyz[:, 0] + UH60A.attachment_radius, xyz[:, 1:]


# --------------------------------------------------------------------------------------------
# Fan plot
# --------------------------------------------------------------------------------------------

def bowen_davies_fanplot() -> xr.Dataset:
    """The digitized Bowen-Davies UH-60A fan plot.

    Returns
    -------
    xarray.Dataset
        ``frequency`` (Hz) over (``speed_ratio``, ``mode``): ``speed_ratio`` is Ω/Ω_ref
        (0, 0.1, …, 1; Ω_ref = 27 rad/s), ``rotor_speed`` the same in rad/s; ``mode`` holds the
        file's column labels (l1, f1, f2, f3, f4, t1, f5) and ``mode_label`` the modes they are
        read as (:data:`MODE_LABEL`; the column "f4" is lag 2, see there). Coupled modes of the
        real blade (twist, cg offsets), so flap 3 and torsion 1 veer apart near Ω_ref.
    """
    lines = [ln.strip() for ln in data_file(FANPLOT).read_text().splitlines() if ln.strip()]
    head = [h.strip() for h in lines[0].split(",")]
    values = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    if head[0] != "x" or values.shape[1] != len(head):
        raise ValueError(f"{FANPLOT}: unexpected layout {head}")
    modes = head[1:]
    return xr.Dataset(
        {"frequency": (("speed_ratio", "mode"), values[:, 1:],
                       {"units": "Hz", "long_name": "natural frequency"})},
        coords={
            "speed_ratio": ("speed_ratio", values[:, 0],
                            {"units": "1", "long_name": "rotor speed / reference speed"}),
            "rotor_speed": ("speed_ratio", values[:, 0] * UH60A.omega_ref,
                            {"units": "rad s-1", "long_name": "rotor speed"}),
            "mode": ("mode", modes, {"long_name": "column label of the digitized file"}),
            "mode_label": ("mode", [MODE_LABEL.get(m, m) for m in modes],
                           {"long_name": "mode the column is read as"}),
        },
        attrs={"source": "Bowen-Davies PhD (University of Maryland), digitized in "
                         "ptrbortolotti/SONATA jobs/VariSpeed/uh60a_data_blade/"
                         "fanplot_uh60a_bowen-davies-PhD.txt",
               "omega_ref": UH60A.omega_ref, "omega_ref_units": "rad s-1"},
    )


__all__ = ["FLAPWISE_SHARE", "MODE_LABEL", "UH60A", "Airfoils", "UH60AData", "blade_airfoil",
           "blade_airstations", "blade_chord", "blade_sections", "blade_twist",
           "bowen_davies_fanplot", "data_file", "davis_cuff", "parse_dymore", "read_deck",
           "section_origin", "yeo_properties"]
