"""Equilibria of beams whose axial stiffness dwarfs their bending stiffness (EA L²/EI up to
1e8, as in rotor blades), against closed forms: the Timoshenko cantilever, the elastica of a
cantilever under a tip load (Bisshopp & Drucker 1945), and the stretched string of a hinged
spinning blade. Failure messages tell a singular tangent from an ill-conditioned one.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

from solver.beams import section_loads, straight_beam
from solver.bodies import RigidBody, ground, spinning
from solver.equilibrium import Spin, equilibrium
from solver.forces import AppliedLoad
from solver.joints import Revolute, Rigid
from solver.model import Model
from solver.sections import isotropic_section
from solver.system import System

LENGTH, EI = 10.0, 1e6  # cantilever (m, N·m²)


def cantilever(ratio: float, load: float, *, clamp: bool = True, n_elements: int = 20):
    """A straight cantilever along x with EA L²/EI = ``ratio`` (GA = EA/2.6) and a dead tip
    load −``load``·t along z (N). Returns (model, beam, GA)."""
    ea = ratio * EI / LENGTH**2
    ga = ea / 2.6
    sec = isotropic_section(EA=ea, GA2=ga, GA3=ga, GJ=EI, EI2=EI, EI3=EI)
    b = straight_beam("b", (0, 0, 0), (LENGTH, 0, 0), sec, n_elements=n_elements)
    push = AppliedLoad("p", b.tip, force=lambda t: (0.0, 0.0, -load * t))
    if not clamp:
        return Model([b, push]), b, ga
    g = ground()
    return Model([g, b, Rigid("clamp", g, b.root, point=b.root.position), push]), b, ga


def tip(model, beam, res) -> np.ndarray:
    o = System(model).offset[beam.tip]
    return res.q[o : o + 3] - beam.tip.position


def elastica(alpha_l: float) -> tuple[float, float]:
    """Inextensible cantilever under a dead tip load P, αL = L √(P/EI): (horizontal shortening,
    deflection) of the tip over L. With θ₀ the tip slope, k² = (1 + sin θ₀)/2 and
    sin φ₁ = 1/(k√2): αL = K(k) − F(φ₁, k), x_tip = √(2 sin θ₀)/α,
    δ = L − 2 (E(k) − E(φ₁, k))/α."""

    def parts(theta0):
        m = (1 + np.sin(theta0)) / 2
        phi1 = np.arcsin(1 / np.sqrt(2 * m))
        return m, phi1, ellipk(m) - ellipkinc(phi1, m)

    theta0 = brentq(lambda th: parts(th)[2] - alpha_l, 1e-9, np.pi / 2 - 1e-12, xtol=1e-15)
    m, phi1, _ = parts(theta0)
    x_tip = np.sqrt(2 * np.sin(theta0)) / alpha_l
    delta = 1 - 2 * (ellipe(m) - ellipeinc(phi1, m)) / alpha_l
    return 1 - x_tip, delta


@pytest.mark.parametrize("ratio", [1e6, 1e7, 1e8])
def test_stiff_cantilever_small_load_is_timoshenkos(ratio):
    """Tip load P = 1e-4 EI/L²: deflection P L³/(3EI) + P L/GA (the shear term 8e-6 … 8e-8
    of it). Measured relative error −1.14e-9 at every EA L²/EI, the geometric nonlinearity
    ~(δ/L)² (20 cubic elements hold the cubic Timoshenko deflection exactly)."""
    p = 1e-4 * EI / LENGTH**2
    model, b, ga = cantilever(ratio, p)
    res = equilibrium(model, t=[1.0])
    assert res.converged, res.message
    exact = p * LENGTH**3 / (3 * EI) + p * LENGTH / ga
    assert -tip(model, b, res)[2] == pytest.approx(exact, rel=1e-8)


def test_stiff_cantilever_large_load_is_the_elastica():
    """Tip load P = 2 EI/L² in 20 load steps (tip deflection 0.49 L, slope 62°): every step
    converges for EA L²/EI = 1e4 … 1e8, and the tip tends to the inextensible elastica as
    the extension and shear strains, P/EA and P/GA = 2.6 P/EA, vanish. Measured tip errors
    over L: 3.8e-4 at EA L²/EI = 1e4, 3.8e-6 at 1e6, 4.4e-7 at 1e7, 1.0e-7 at 1e8 — falling
    as (EA L²/EI)⁻¹ down to the director interpolation's 1e-7 over 20 elements; the bound
    is 5 (EA L²/EI)⁻¹ + 2e-7. The moderate EA L²/EI = 1e4 differs from the stiff ones by its
    own extension and shear, 3.8e-4 L (bound 5e-4 L)."""
    p = 2 * EI / LENGTH**2
    steps = np.linspace(0.0, 1.0, 21)[1:]
    exact = np.array(elastica(np.sqrt(p / EI) * LENGTH))
    assert exact == pytest.approx([0.1606, 0.4934], abs=1e-4)  # Bisshopp & Drucker's table
    tips = {}
    for ratio in (1e4, 1e6, 1e7, 1e8):
        model, b, _ = cantilever(ratio, p)
        res = equilibrium(model, t=steps)
        assert res.converged, res.message
        tips[ratio] = tip(model, b, res)
    for ratio, u in tips.items():
        err = np.abs(np.array([-u[0], -u[2]]) / LENGTH - exact).max()
        assert err < 5 / ratio + 2e-7, (ratio, err)
        assert np.abs(u - tips[1e4]).max() < 5e-4 * LENGTH


def hinged_blade(ea: float, omega: float = 27.0, radius: float = 8.0, hinge: float = 0.4,
                 mass: float = 10.0, n_elements: int = 8, lag: bool = False):
    """A uniform blade from the flap hinge at r = ``hinge`` to ``radius`` (m) on a hub spinning
    at ``omega`` (rad/s) about z; EI = 1e6 N·m² flap, 1e7 lag, mass per length ``mass`` (kg/m),
    no rotary inertia. With ``lag``, a lag hinge at the same point follows the flap hinge
    through a massless link (as in :func:`studies.blade.articulated_blade`). Returns (model,
    blade, hub)."""
    sec = isotropic_section(EA=ea, GA2=ea / 2.6, GA3=ea / 2.6, GJ=1e6, EI2=1e6, EI3=1e7,
                            mass=mass)
    hub = spinning("hub", omega)
    b = straight_beam("blade", (hinge, 0, 0), (radius, 0, 0), sec, n_elements=n_elements,
                      angular_velocity=(0, 0, omega))
    point = (hinge, 0, 0)
    if not lag:
        return Model([hub, b, Revolute("flap", hub, b.root, point=point, axis=(0, 1, 0))]), b, hub
    link = RigidBody("link", 0.0, position=point, angular_velocity=(0, 0, omega))
    return Model([hub, link, b, Revolute("flap", hub, link, point=point, axis=(0, 1, 0)),
                  Revolute("lag", link, b.root, point=point, axis=(0, 0, 1))]), b, hub


def stretched_string(ea, omega, radius, hinge, mass) -> tuple[float, float]:
    """Axial force at the hinge (N) and tip elongation (m) of a uniform bar spinning about an
    axis through r = 0, pinned at r = e, free at R: w = r + u solves EA w'' + m Ω² w = 0 with
    w(e) = e, w'(R) = 1, so w = C cos β(r − R) + sin β(r − R)/β, β² = m Ω²/EA."""
    beta = omega * np.sqrt(mass / ea)
    a = beta * (hinge - radius)
    c = (hinge - np.sin(a) / beta) / np.cos(a)
    root_force = ea * (-c * beta * np.sin(a) + np.cos(a) - 1)
    return root_force, c - radius


@pytest.mark.parametrize("ea", [4.6e9, 1e6 * EI / 7.6**2, 1e7 * EI / 7.6**2,
                                1e8 * EI / 7.6**2],
                         ids=["EA=4.6e9", "EAL2/EI=1e6", "EAL2/EI=1e7", "EAL2/EI=1e8"])
@pytest.mark.parametrize("lag", [False, True], ids=["flap", "flap+lag"])
def test_stiff_hinged_blade_spins_up(ea, lag):
    """Hinged blade (a flap hinge, or flap and lag hinges; 7.6 m from the hinge, EA = 4.6e9 N
    is EA L²/EI = 2.7e5) at 27 rad/s: the relative equilibrium converges; the flap and lag
    angles are zero with no out-of-plane or drag load; the hinge force is the stretched
    string's, which is m Ω² (R² − e²)/2 to within 0.75 of the strain (≤ 5e-5); the tip
    elongation ∫ N/EA ds is the string's (2.5e-4 m at EA = 4.6e9, 6.6e-7 m at 1.7e12).
    Measured relative errors, either hinge: force ≤ 6.5e-9, elongation ≤ 8e-9, both largest
    at EA L²/EI = 1e8 (roundoff of positions of 8 m against an elongation of 6.6e-7 m)."""
    omega, radius, hinge, mass = 27.0, 8.0, 0.4, 10.0
    model, b, hub = hinged_blade(ea, omega, radius, hinge, mass, lag=lag)
    s = System(model)
    res = equilibrium(s, spin=Spin.from_body(hub))
    assert res.converged, res.message
    o = s.offset[b]
    nodes = res.q[o : o + 12 * len(b.nodes)].reshape(-1, 4, 3)
    assert np.abs(nodes[:, 0, 1:]).max() < 1e-12 * radius  # no flap, lag or bending
    force, stretch = stretched_string(ea, omega, radius, hinge, mass)
    rigid = mass * omega**2 * (radius**2 - hinge**2) / 2
    assert force == pytest.approx(rigid, rel=rigid / ea)
    root = section_loads(s, b, res.q, [0.0])[0]
    assert root[0] == pytest.approx(force, rel=5e-8)
    assert nodes[-1, 0, 0] - radius == pytest.approx(stretch, rel=5e-8)


def test_singular_tangent_is_named():
    """A beam held by nothing under a tip load: no stiffness holds its rigid motions; the
    message says singular (condition ≥ 1/ε after equilibration; measured 4e18)."""
    model, _, _ = cantilever(1e8, 100.0, clamp=False, n_elements=4)
    res = equilibrium(model, t=[1.0], max_iter=2)
    assert not res.converged
    assert "the tangent is singular" in res.message, res.message
    assert "ill-conditioned" not in res.message


def test_ill_conditioned_tangent_is_named():
    """The clamped cantilever at EA L²/EI = 1e8 stopped after one Newton update: its tangent
    is ill-conditioned (condition estimate 2.7e11 after equilibration, 1.4e11 in the 2-norm:
    EA/h against 3EI/L³) but not singular, and the message says so. The load leaves the beam
    nearly straight: under 1e-2 EI/L² the linear update's spurious stretch, EA θ²/2, stiffens
    the tangent to a condition below ILL_CONDITIONED."""
    model, _, _ = cantilever(1e8, 1e-6 * EI / LENGTH**2)
    res = equilibrium(model, t=[1.0], max_iter=1)
    assert not res.converged
    assert "the tangent is ill-conditioned (condition estimate" in res.message, res.message
    assert "is singular" not in res.message
