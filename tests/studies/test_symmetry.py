"""Cyclic symmetry of a model and affine combinations of states (solver/symmetry.py), and the
shooting that uses them (studies/periodic.py: shoot), on the hub with four bifilars.

* The turn-and-permute map is exact: its N-th power is the identity, it and its inverse
  compose to the identity, and a turned state satisfies every constraint at the earlier time
  (a rigid turn of the rotating parts about the moving shaft head, driven rotation included).
* The steady response of the hub is symmetric: the state a quarter revolution later, mapped
  back, is the state now, to the periodicity the run was accepted at.
* Combinations of triads on the rotation group: rotations by angles θ_j about one axis combine
  to the rotation by Σ w_j θ_j exactly, with the angular velocity Σ w_j ω_j (closed form).
* Shooting gives the periodic response that a long march gives, in at most 8 revolutions.
"""

from __future__ import annotations

import numpy as np
import pytest

from solver.bodies import RigidBody
from solver.integrators import make_integrator
from solver.model import Model
from solver.rotations import rotation_about
from solver.symmetry import CyclicSymmetry, affine_combination, director_triads
from solver.system import System
from studies import hub
from studies.periodic import referred_harmonics


@pytest.fixture(scope="module")
def free_hub():
    p = hub.SPEC.validate({})
    model, hb, shaft, parts = hub.build(p)
    s = System(model)
    return p, s, hub.symmetry(s, hb, shaft, parts)


def _marched_state(p, s, steps):
    h = 2 * np.pi / p.hub_speed / p.steps_per_rev
    integ = make_integrator(s, "ep", h, tol=hub.NEWTON_TOL)
    for _ in range(steps):
        integ.step()
    return integ


def test_turn_and_permute_is_exact_and_keeps_the_constraints(free_hub):
    p, s, sym = free_hub
    quarter = p.steps_per_rev // 4
    integ = _marched_state(p, s, 3 * quarter + 7)  # a generic state with swinging pins
    q, v, t = integ.q, integ.v, integ.t
    q4, v4 = q, v
    for _ in range(4):
        q4, v4 = sym.back(q4, v4, k=1)
    assert np.abs(q4 - q).max() < 1e-14 and np.abs(v4 - v).max() < 1e-12
    qb, vb = sym.back(*sym.back(q, v, k=3), k=-3)
    assert np.abs(qb - q).max() < 1e-14 and np.abs(vb - v).max() < 1e-12
    # the turned state is a state of the model a quarter revolution earlier: the position
    # constraints (driven rotation included) hold there to the integrator's tolerance
    t_back = t - 2 * np.pi / p.hub_speed / 4
    q1, _v1 = sym.back(q, v, k=1)
    c_now = np.abs(s.constraint(q, t)).max()
    c_back = np.abs(s.constraint(q1, t_back)).max()
    assert c_back <= 10 * c_now + 1e-12, (c_now, c_back)
    # ... and not at the same time (the map does turn the hub)
    assert np.abs(s.constraint(q1, t)).max() > 0.1
    # the velocities too (the scheme's end velocities are off the velocity constraints by
    # O(h²): the turned ones are off by as much, a quarter revolution earlier)
    q1, v1 = sym.back(q, v, k=1)
    now = np.abs(_velocity_residual(s, q, v, t)).max()
    back = np.abs(_velocity_residual(s, q1, v1, t_back)).max()
    assert back <= 1.0001 * now + 1e-12, (now, back)


def _velocity_residual(s, q, v, t):
    import scipy.sparse as sp

    g = sp.csr_matrix((s.jacobian_values(q, t), (s.G_rows, s.G_cols)), shape=(s.mh, s.n))
    return g @ v + s.constraint_rate(q, t)


def test_combination_of_rotations_about_one_axis_is_exact():
    model = Model()
    body = RigidBody("b", 1.0, inertia=(1.0, 2.0, 3.0))
    model.add(body)
    s = System(model)
    assert director_triads(s.layout).shape == (1, 3, 3)
    o = s.offset[body]
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    base = rotation_about([0.0, 1.0, 0.0], 0.3)
    angles, rates = np.array([0.2, 1.4, -0.9]), np.array([5.0, -2.0, 7.0])
    w = np.array([-1.5, 2.0, 0.5])
    qs, vs = [], []
    for th, om in zip(angles, rates, strict=True):
        q, v = np.zeros(s.n), np.zeros(s.n)
        r = rotation_about(axis, th) @ base
        q[o : o + 3] = [th, 0.0, 1.0]
        v[o : o + 3] = [om, 0.0, 0.0]
        # d_i = columns of R, ḋ_i = ω × d_i with ω = om · axis (global)
        for i in range(3):
            q[o + 3 + 3 * i : o + 6 + 3 * i] = r[:, i]
            v[o + 3 + 3 * i : o + 6 + 3 * i] = np.cross(om * axis, r[:, i])
        qs.append(q)
        vs.append(v)
    qc, vc = affine_combination(s, w, qs, vs)
    r = rotation_about(axis, w @ angles) @ base
    om = (w @ rates) * axis
    assert np.allclose(qc[o : o + 3], [w @ angles, 0.0, 1.0], atol=1e-15)
    for i in range(3):
        assert np.abs(qc[o + 3 + 3 * i : o + 6 + 3 * i] - r[:, i]).max() < 1e-14
        assert np.abs(vc[o + 3 + 3 * i : o + 6 + 3 * i] - np.cross(om, r[:, i])).max() < 1e-13
    with pytest.raises(ValueError, match="sum to"):
        affine_combination(s, [0.5, 0.4, 0.0], qs, vs)


def test_symmetry_rejects_mismatched_sectors(free_hub):
    _p, s, _sym = free_hub
    owners = [b.owner for b in s.layout.blocks]
    names = {getattr(o, "name", ""): o for o in owners}
    with pytest.raises(ValueError, match="at least 2 sectors"):
        CyclicSymmetry(s, [[names["b0_mass"]]])
    with pytest.raises(ValueError, match="does not match"):
        CyclicSymmetry(s, [[names["b0_mass"]], [names["b1_slide1.eta"]]])


def test_turning_parts_turn_positions_and_directors_only(free_hub):
    """solver.turning: the spinning owners' position and director 3-vectors turn by R(ψ) about
    the axis, in every stage block of a Newton vector; scalars (the curve parameters η), the
    other owners and the multipliers after the stages stay; −ψ undoes ψ."""
    from solver.turning import TurningParts

    _p, s, _sym = free_hub
    names = {getattr(b.owner, "name", ""): b.owner for b in s.layout.blocks}
    owners = [o for n, o in names.items() if n == "hub" or n.startswith("b0_")]
    axis = np.array([0.2, -0.1, 1.0])
    parts = TurningParts(s, owners, axis, rate=27.0)
    eta = s.offset[names["b0_slide1.eta"]]
    hub = s.offset[names["hub"]]
    assert eta not in parts.vectors and np.isin(hub + np.arange(12), parts.vectors).all()
    assert np.all(np.diff(parts.vectors, axis=1) == 1)
    x = np.random.default_rng(4).standard_normal(2 * s.n + 5)
    y = x.copy()
    parts.turn(y, 0.7, stages=2)
    r = rotation_about(axis, 0.7)
    for k in (0, s.n):
        v = parts.vectors + k
        assert np.abs(y[v] - x[v] @ r.T).max() < 1e-15
    still = np.ones(len(x), dtype=bool)
    still[parts.vectors.ravel()] = still[parts.vectors.ravel() + s.n] = False
    assert np.array_equal(y[still], x[still])
    parts.turn(y, -0.7, stages=2)
    assert np.abs(y - x).max() < 1e-15
    with pytest.raises(ValueError, match="axis"):
        TurningParts(s, owners, (0.0, 0.0, 0.0), 1.0)
    with pytest.raises(ValueError, match="declares no state block"):
        TurningParts(s, [object()], axis, 1.0)


def _harmonics(ds, n):
    """Harmonics 0..8 of the last revolution, referred to the azimuth ψ = 0 (a shooting run
    records from a quarter revolution)."""
    rows = np.column_stack([ds["time"].values[-n:], *(ds[k].values[..., -n:].T for k in (
        "hub_x_rotating", "hub_y_rotating", "hub_force_x_fixed", "hub_force_y_fixed",
        "pin_angle"))])
    return referred_harmonics(rows, ds["run_hub_speed"].item(), 8)


@pytest.mark.slow
def test_shooting_gives_the_long_march_periodic_response():
    # reference: plain marching (no extrapolation, no shooting) to a 100 times tighter
    # periodicity than the default, about 40 revolutions
    ref = hub.run({"shooting_window": 0, "extrapolation_window": 0, "richardson": False,
                   "error_estimate": False, "periodic_tolerance": 1e-5, "max_revolutions": 400})
    shot = hub.run({"richardson": False, "error_estimate": False})
    n = shot["run_samples_per_rev"].item()
    a, b = _harmonics(shot, n), _harmonics(ref, n)
    scale = np.abs(b).max(axis=0)
    # measured 1.7e-4 of each signal's largest harmonic (tolerance 1e-3), 7.5 revolutions
    # against 40 (transient_revolutions counts the started quarter revolutions, rounded up)
    assert np.max(np.abs(a - b) / scale) < 1e-3
    assert shot["run_transient_revolutions"].item() + shot["run_revolutions"].item() <= 8
    assert shot["run_shooting_restarts"].item() >= 1 and shot.attrs["message"] == ""
    # the steady response is symmetric: a quarter revolution later, bifilar j does what
    # bifilar j + 1 did (pin angles, degrees), within the periodicity (measured 2.2e-4)
    pins = shot["pin_angle"].values[:, -n:]
    quarter = n // 4
    earlier = np.roll(pins, -1, axis=0)[:, :-quarter]  # row j: bifilar j + 1, a quarter before
    assert np.abs(earlier - pins[:, quarter:]).max() < 2e-3 * np.abs(pins).max()


def test_locked_hub_shoots_in_a_few_revolutions():
    # the locked case's only free motion is the fuselage mode (2 % damped): one restart after
    # four quarter revolutions explains it (measured: 1.3e-7 from the 400-revolution march,
    # whose own tolerance is 1e-6, after 3.25 revolutions from the linear start or from rest)
    ds = hub.run({"bifilar": "locked", "richardson": False, "error_estimate": False})
    assert ds["run_shooting_restarts"].item() == 1
    assert ds["run_transient_revolutions"].item() + ds["run_revolutions"].item() <= 4
    marched = hub.run({"bifilar": "locked", "shooting_window": 0, "extrapolation_window": 0,
                       "richardson": False, "error_estimate": False,
                       "periodic_tolerance": 1e-6,
                       "max_revolutions": 400})
    n = ds["run_samples_per_rev"].item()
    a, b = _harmonics(ds, n), _harmonics(marched, n)
    live = np.abs(b).max(axis=0) > 0
    assert np.max(np.abs(a - b)[:, live] / np.abs(b).max(axis=0)[live]) < 1e-5


def test_rotor_quarter_turn_keeps_every_constraint():
    # the rotor's sectors are blade j's beam, hinge links and lifting-line states and bifilar j;
    # the hub turns about the shaft head's axis (which tilts with the fuselage-beam). A state
    # a quarter revolution on, mapped back, satisfies every constraint at the earlier time
    # (measured: 2.4e-13, the integrator's own level: the hinge links are built in frames
    # turned with their blade, so the quarter turn maps one blade's parts onto the next's)
    from studies import rotor

    p = rotor.SPEC.validate({})
    model, parts = rotor.build(p)
    s = System(model)
    sym = rotor.symmetry(s, parts)
    h = 2 * np.pi / p.hub_speed / p.steps_per_rev
    integ = rotor.integrator(s, p, h)
    for _ in range(70):
        integ.step()
    q, v, t = integ.q, integ.v, integ.t
    c_now = np.abs(s.constraint(q, t)).max()
    quarter = 2 * np.pi / p.hub_speed / 4
    for k in (1, 2, 3, -1):
        qk, vk = sym.back(q, v, k=k)
        assert np.abs(s.constraint(qk, t - k * quarter)).max() <= 10 * c_now + 1e-12, k
        now = np.abs(_velocity_residual(s, q, v, t)).max()
        back = np.abs(_velocity_residual(s, qk, vk, t - k * quarter)).max()
        # the scheme's own velocity-constraint residual (0.035 here) is carried over exactly
        assert back <= 1.0001 * now + 1e-12, (k, now, back)
