"""The public UH-60A blade data as solver inputs (studies/uh60a.py).

Checks, with the margins measured:

* the deck reader on a synthetic deck (nesting, named blocks, pairs on one line, comments, errors);
* Yeo's 46 stations and their values against Yeo's published table;
* the Davis cuff and its meeting with Yeo's table (a jump at the attachment, mass continuous);
* blade mass 120.04 kg integrated exactly (116.5 kg published, +3.0 %; the hinge lump, 3.48 kg,
  is the whole difference: 116.56 kg without it), first moment 391.3 kg·m (385.7 published,
  +1.5 %) and flap inertia 2087.9 kg·m² (2050.8, +1.8 %) about the hinge;
* twist −0.14° at 0.7R, chord, airfoils, the fan-plot file (11 rows);
* an independent rotating Euler–Bernoulli beam (cubic Hermite elements, centrifugal stiffening,
  hinged at e, uncoupled flap and lag) built from the SectionTable, against a reference
  computation: flap 1.0350, 2.8394, lag 0.2669 /rev at 27 rad/s (1.035, 2.839, 0.267), and lag 2 /
  flap 4 against the fan plot's "f4" / "f5" columns (−1.6 %, +0.3 %), which is why "f4" is read
  as lag 2. This guards the reading of units, axes (which EI is flap) and the radius offset.
"""

from __future__ import annotations

import tomllib
from fnmatch import fnmatch
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import eigh

from solver.sections import SectionTable
from studies import uh60a
from studies.uh60a import UH60A, blade_sections, parse_dymore

REPO = Path(__file__).resolve().parents[2]
R, E, OMEGA = UH60A.radius, UH60A.hinge_radius, UH60A.omega_ref


# --------------------------------------------------------------------------------------------
# exact integrals of a piecewise-linear table
# --------------------------------------------------------------------------------------------

def moment(table: SectionTable, power: int, origin: float) -> float:
    """∫ m(s) (s + origin)^power ds, exact (Simpson on each interval: m linear, power ≤ 2)."""
    s, m = table.stations, table.mass
    a, b, ma, mb = s[:-1], s[1:], m[:-1], m[1:]

    def g(x):
        return (x + origin) ** power

    mid = 0.5 * (a + b)
    return float(np.sum((b - a) / 6 * (ma * g(a) + 2 * (ma + mb) * g(mid) + mb * g(b))))


# --------------------------------------------------------------------------------------------
# the deck reader
# --------------------------------------------------------------------------------------------

def test_parser_nesting_names_pairs_comments():
    deck = parse_dymore("""
    ! a comment {with braces} and @KEYWORDS
    @TOP{
        @NAME{A}{ @X{1.0, 2.0} @EMPTY{} }   ! trailing comment
        @NAME {B} {
            @S { +0.0} @V {1e+000}
            @S { +1.5} @V {2e+000}
        }
        @FLAG
    }
    """)
    (top,) = deck["TOP"]
    assert [occ[0] for occ in top[0]["NAME"]] == ["A", "B"]
    a = top[0]["NAME"][0][1]
    assert a == {"X": [["1.0, 2.0"]], "EMPTY": [[""]]}
    b = top[0]["NAME"][1][1]
    assert [o[0] for o in b["S"]] == ["+0.0", "+1.5"] and [o[0] for o in b["V"]] == [
        "1e+000", "2e+000"]
    assert top[0]["FLAG"] == [[]]
    for bad in ("@A{ @B{1}", "@A{1}}", "{1}", "@A{ text @B{1} }"):
        with pytest.raises(ValueError):
            parse_dymore(bad)


def test_deck_blocks():
    deck = uh60a.read_deck()
    assert {"BEAM_PROPERTY_DEFINITION", "ORIENTATION_DISTRIBUTION_DEFINITION",
            "LIFTING_LINE_DEFINITION", "LIFTING_LINE_PROPERTY_DEFINITION"} <= set(deck)
    # the deck's beam: straight along +x, section triad E2 = y, E3 = z
    (points,) = deck["POINT_DEFINITION"][0]
    tip = next(o[1] for o in points["POINT_NAME"] if o[0] == "BLADE_PT_D_BE01")
    assert tip["COORDINATES"] == [["7.36082856e+00, 0.0, 0.0"]]
    (triads,) = deck["TRIAD_DEFINITION"][0]
    triad = triads["TRIAD_NAME"][0][1]
    assert triad["ORIENTATION_E2"] == [["0.0, 1.0, 0.0"]]
    assert triad["ORIENTATION_E3"] == [["0.0, 0.0, 1.0"]]


def test_data_shipped_as_package_data():
    setup = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "studies.data.uh60a" in setup["packages"]
    patterns = setup["package-data"]["studies.data.uh60a"]
    files = sorted(p.name for p in (REPO / "studies" / "data" / "uh60a").iterdir())
    for name in files:
        assert any(fnmatch(name, pattern) for pattern in patterns), name
        assert uh60a.data_file(name).is_file()
    assert {uh60a.DECK, uh60a.FANPLOT, "mass.dat", "README.md"} <= set(files)


# --------------------------------------------------------------------------------------------
# section properties
# --------------------------------------------------------------------------------------------

def test_yeo_stations():
    y = uh60a.yeo_properties()
    assert len(y["s"]) == 46
    assert y["r"][0] == pytest.approx(0.81787, abs=2e-6) and y["r"][-1] == pytest.approx(R)
    np.testing.assert_allclose(np.diff(y["r"]), 0.02 * R, rtol=3e-4)  # rounded in the deck
    assert np.all(y["EI2"] <= y["EI3"])  # H22 is flap, the smaller
    # Yeo splits the polar inertia 25 % flapwise / 75 % chordwise, except at the first station
    np.testing.assert_allclose(y["I22"][1:] / y["I11"][1:], uh60a.FLAPWISE_SHARE, rtol=1e-6)
    np.testing.assert_allclose(y["I22"][1:] + y["I33"][1:], y["I11"][1:], rtol=1e-6)
    assert np.all(y["GA23"] == 0) and np.all(y["EI23"] == 0) and np.all(y["cg3"] == 0)
    np.testing.assert_allclose(y["GA2"], 0.05 * y["EA"], rtol=1e-5)


# (r [m]; EA, EI_flap, EI_lag, GJ [N, N·m²]; m [kg/m]; I22, I33 [kg·m]; x_cg [m]):
# rows of Yeo's table, to its printed digits
TABLE = [
    (1.636, 2.8e8, 7.92e4, 1.35e6, 7.43e4, 10.34, 0.0268, 0.0804, -0.0069),
    (3.272, 2.78e8, 6.37e4, 2.4e6, 6.98e4, 10.27, 0.0365, 0.1095, -0.0209),
    (5.725, 3.15e8, 6.74e4, 2.0e6, 7.11e4, 11.65, 0.0444, 0.1333, -0.0099),
    (7.361, 4.81e8, 5.69e4, 1.35e6, 6.98e4, 17.79, 0.0807, 0.2420, 0.0319),
    (8.179, 1.08e8, 2.12e4, 1.28e6, 6.98e4, 4.00, 0.0427, 0.1281, -0.1324),
]


@pytest.mark.parametrize("include_cuff", [True, False])
@pytest.mark.parametrize("row", TABLE, ids=[f"r={row[0]}" for row in TABLE])
def test_values_at_stations(row, include_cuff):
    r, ea, ei2, ei3, gj, m, i22, i33, cg2 = row
    table = blade_sections(include_cuff)
    s = min(r - uh60a.section_origin(include_cuff), table.length)
    p = table.at(s)
    c = np.diag(p["stiffness"])
    for got, want in zip((c[0], c[4], c[5], c[3], p["mass"]), (ea, ei2, ei3, gj, m),
                         strict=True):
        assert got == pytest.approx(want, rel=6e-3)
    assert p["inertia"] == pytest.approx([i22, i33, 0.0], rel=6e-3, abs=1e-9)
    assert p["cg"] == pytest.approx([cg2, 0.0], rel=1e-2, abs=6e-5)


def test_cuff_and_junction():
    table = blade_sections()
    yeo = blade_sections(include_cuff=False)
    assert table.stations[0] == 0.0 and table.length == pytest.approx(R - E)
    assert yeo.length == pytest.approx(UH60A.beam_length) and len(yeo.stations) == 46
    # the hinge lump: 1338 kg/m over 382.9-385.5 mm
    lump = table.at(0.0032)
    assert lump["mass"] == 1338.0 and lump["cg"] == pytest.approx([0.0, 0.0])
    cuff = table.at(0.2)  # r = 0.581 m: Davis
    c = np.diag(cuff["stiffness"])
    assert (cuff["mass"], c[4], c[5], c[3]) == (47.92, 3.68e5, 3.71e5, 2.87e5)
    # where Davis meets Yeo: a repeated station, Davis inboard, Yeo's first station outboard
    s_att = UH60A.attachment_radius - E
    assert np.count_nonzero(np.isclose(table.stations, s_att)) == 2
    left, right = table.at(s_att, side="left"), table.at(s_att, side="right")
    assert left["mass"] == pytest.approx(right["mass"], rel=1e-4)
    assert left["mass"] == 47.92
    assert np.diag(left["stiffness"])[[3, 4, 5]] == pytest.approx([2.87e5, 3.68e5, 3.71e5])
    assert np.diag(right["stiffness"])[[3, 4, 5]] == pytest.approx([2.018e5, 2.538e5, 2.558e5],
                                                                   rel=1e-3)
    # Yeo's stations, shifted by the attachment radius
    np.testing.assert_allclose(table.stations[-46:], yeo.stations + s_att)


def test_blade_mass_and_moments():
    table = blade_sections()
    mass = moment(table, 0, 0.0)
    first = moment(table, 1, 0.0)  # the table's arc length starts at the hinge
    flap_inertia = moment(table, 2, 0.0)
    lump = 1338.0 * (0.3855 - 0.3829)
    assert mass == pytest.approx(120.04, abs=0.01)
    # the published blade weight (116.5 kg, GenHel) is matched to 0.05 % without the hinge lump
    assert mass == pytest.approx(UH60A.blade_mass, rel=0.035)
    assert mass - lump == pytest.approx(UH60A.blade_mass, rel=5e-3)
    # about the hinge (the Yeo part alone gives 386.7 and 2086.5)
    assert first == pytest.approx(UH60A.blade_first_moment, rel=0.025)
    assert flap_inertia == pytest.approx(UH60A.blade_flap_inertia, rel=0.025)
    yeo = blade_sections(include_cuff=False)
    off = UH60A.attachment_radius
    assert moment(yeo, 1, off - E) == pytest.approx(386.8, abs=0.2)
    assert moment(yeo, 2, off - E) == pytest.approx(2088.5, rel=2e-3)
    # the table's own director mass matrix agrees with its mass per length
    assert table.director_inertia(3.0)[0, 0] == pytest.approx(table.at(3.0)["mass"])


# --------------------------------------------------------------------------------------------
# lifting line
# --------------------------------------------------------------------------------------------

def test_twist():
    r, twist = uh60a.blade_twist()
    assert len(r) == 83 and np.all(np.diff(r) > 0)
    assert r[0] == pytest.approx(UH60A.attachment_radius) and r[-1] == pytest.approx(R)
    at = np.degrees(np.interp(np.array([0.15, 0.5, 0.7, 0.93, 1.0]) * R, r, twist))
    # the deck's reference: ≈ 0 at 0.7R (9.67, 3.59, −0.14, −3.63, −1.62)
    assert at == pytest.approx([9.67, 3.59, -0.14, -3.63, -1.62], abs=0.06)
    assert abs(at[2]) < 0.2
    rs, ts = uh60a.blade_twist("structural")
    assert np.degrees(np.interp(0.25 * R, rs, ts)) == pytest.approx(8.8, abs=0.1)


def test_chord_airfoils_airstations():
    r, chord = uh60a.blade_chord()
    assert len(r) == 83 and chord[0] == 0.0
    assert np.interp(0.3 * R, r, chord) == pytest.approx(UH60A.chord, abs=1e-3)
    assert np.interp(0.55 * R, r, chord) == pytest.approx(0.5325, abs=1e-4)
    foils = uh60a.blade_airfoil()
    assert foils.at([0.3 * R, 0.6 * R, 0.9 * R]) == ["SC1095", "SC1094R8", "SC1095"]
    assert foils.lift_slope == 5.73
    ra, offset = uh60a.blade_airstations()
    assert len(ra) == 81 and offset.shape == (81, 2)
    assert offset[-1, 0] == pytest.approx(-0.162, abs=1e-3)  # the tip is swept aft (−d2)


def test_fanplot():
    fan = uh60a.bowen_davies_fanplot()
    assert fan.sizes == {"speed_ratio": 11, "mode": 7}
    assert list(fan["mode"].values) == ["l1", "f1", "f2", "f3", "f4", "t1", "f5"]
    labels = dict(zip(fan["mode"].values, fan["mode_label"].values, strict=True))
    assert labels == uh60a.MODE_LABEL and labels["f4"] == "lag 2"
    at_ref = fan["frequency"].sel(speed_ratio=1.0)
    assert at_ref.sel(mode="f1") == pytest.approx(4.48634)
    assert at_ref.sel(mode="l1") * 2 * np.pi / OMEGA == pytest.approx(0.280, abs=1e-3)
    assert fan["rotor_speed"].values[-1] == OMEGA and fan["frequency"].attrs["units"] == "Hz"


# --------------------------------------------------------------------------------------------
# independent check: a hinged rotating Euler–Bernoulli beam
# --------------------------------------------------------------------------------------------

GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(4)


def _gauss(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """4-point Gauss points and weights on each interval (a, b)."""
    x = 0.5 * (a + b)[..., None] + 0.5 * (b - a)[..., None] * GAUSS_X
    return x, 0.5 * (b - a)[..., None] * GAUSS_W


def rotating_beam(table: SectionTable, hinge: float, omega: float, n_el: int = 60):
    """Mass, flap and lag stiffness of a rotating beam hinged at radius ``hinge`` (root
    displacement fixed, slope free), cubic Hermite elements, uncoupled, with the properties
    integrated exactly piece by piece between the table's breaks.

    Flap: EI2 w'''' − (T w')' ; lag: EI3 v'''' − (T v')' − m Ω² v;
    T(s) = Ω² ∫_s^L m(ξ) (hinge + ξ) dξ."""
    L = table.length
    brk = table.breaks()
    # centrifugal tension at the breaks, exact (m (hinge + s) is quadratic between breaks)
    x, w = _gauss(brk[:-1], brk[1:])
    per = np.sum(w * table.at(x)["mass"] * (hinge + x), axis=-1)
    t_brk = omega**2 * np.concatenate([np.cumsum(per[::-1])[::-1], [0.0]])

    def tension(s):
        k = np.clip(np.searchsorted(brk, s, side="right") - 1, 0, len(brk) - 2)
        xi, wi = _gauss(s, brk[k + 1])
        return t_brk[k + 1] + omega**2 * np.sum(wi * table.at(xi)["mass"] * (hinge + xi), -1)

    nodes = np.linspace(0.0, L, n_el + 1)
    ndof = 2 * (n_el + 1)
    M, K2, K3, KT = (np.zeros((ndof, ndof)) for _ in range(4))
    for e in range(n_el):
        a, b = nodes[e], nodes[e + 1]
        h = b - a
        cuts = np.concatenate([[a], brk[(brk > a) & (brk < b)], [b]])
        xs, ws = _gauss(cuts[:-1], cuts[1:])
        xs, ws = xs.ravel(), ws.ravel()
        p = table.at(xs)
        t = (xs - a) / h
        N = np.stack([1 - 3 * t**2 + 2 * t**3, h * (t - 2 * t**2 + t**3), 3 * t**2 - 2 * t**3,
                      h * (-(t**2) + t**3)])
        dN = np.stack([-6 * t + 6 * t**2, h * (1 - 4 * t + 3 * t**2), 6 * t - 6 * t**2,
                       h * (-2 * t + 3 * t**2)]) / h
        d2N = np.stack([-6 + 12 * t, h * (-4 + 6 * t), 6 - 12 * t, h * (-2 + 6 * t)]) / h**2
        dofs = np.arange(2 * e, 2 * e + 4)
        ix = np.ix_(dofs, dofs)
        M[ix] += (N * ws * p["mass"]) @ N.T
        K2[ix] += (d2N * ws * p["stiffness"][:, 4, 4]) @ d2N.T
        K3[ix] += (d2N * ws * p["stiffness"][:, 5, 5]) @ d2N.T
        KT[ix] += (dN * ws * tension(xs)) @ dN.T
    free = np.arange(1, ndof)  # hinge: w(0) = 0, slope free
    sub = np.ix_(free, free)
    return M[sub], (K2 + KT)[sub], (K3 + KT - omega**2 * M)[sub]


def per_rev(M, K, omega, n):
    lam = eigh(K, M, eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(lam) / omega


def test_rotating_beam_frequencies_match_reference():
    M, Kf, Kl = rotating_beam(blade_sections(), E, OMEGA)
    flap = per_rev(M, Kf, OMEGA, 4)
    lag = per_rev(M, Kl, OMEGA, 2)
    # a reference computation (uncoupled, 120 elements): flap 1.035, 2.839, 5.035, 7.892; lag 0.267,
    # 4.801
    assert flap[:2] == pytest.approx([1.035, 2.839], rel=0.01)
    assert lag[0] == pytest.approx(0.267, rel=0.01)
    assert flap[:2] == pytest.approx([1.035, 2.839], rel=1e-3)
    assert lag[0] == pytest.approx(0.267, rel=2e-3)
    assert flap[2:] == pytest.approx([5.035, 7.892], rel=2e-3)
    assert lag[1] == pytest.approx(4.801, rel=2e-3)
    # rigid flap and lag from the table's own moments: ν² = 1 + e S/I and e S/I
    S, inertia = moment(blade_sections(), 1, 0.0), moment(blade_sections(), 2, 0.0)
    assert lag[0] == pytest.approx(np.sqrt(E * S / inertia), rel=5e-3)
    # against the digitized (coupled) fan plot at Ω_ref: lag 2 is the column "f4" and flap 4
    # the column "f5" (−1.6 % and +0.3 %); flap 1 and 2 within 1 %
    hz = uh60a.bowen_davies_fanplot()["frequency"].sel(speed_ratio=1.0)
    to_hz = OMEGA / (2 * np.pi)
    assert lag[1] * to_hz == pytest.approx(float(hz.sel(mode="f4")), rel=0.03)
    assert flap[3] * to_hz == pytest.approx(float(hz.sel(mode="f5")), rel=0.01)
    assert flap[:2] * to_hz == pytest.approx(hz.sel(mode=["f1", "f2"]).values, rel=0.01)


def test_flap_and_lag_are_not_swapped():
    # swapping the two bending stiffnesses (the reading error this guards against) moves
    # flap 2 far from the reference
    table = blade_sections()
    c = table.stiffness.copy()
    c[:, [4, 5], :] = c[:, [5, 4], :]
    c[:, :, [4, 5]] = c[:, :, [5, 4]]
    swapped = SectionTable(table.stations, c, mass=table.mass, cg=table.cg,
                           inertia=table.inertia)
    M, Kf, _ = rotating_beam(swapped, E, OMEGA, n_el=30)
    assert per_rev(M, Kf, OMEGA, 2)[1] > 1.3 * 2.839
