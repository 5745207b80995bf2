"""The element/state framework: passive models, structural patterns, failures that name elements."""

from __future__ import annotations

import copy

import numpy as np

from solver.bodies import RigidBody, ground
from solver.forces import AppliedLoad, Gravity
from solver.integrators import make_integrator
from solver.joints import Revolute
from solver.model import Model
from solver.simulation import simulate
from solver.system import System
from tests.solver.models import hub_rolling_disc


def _pendulum_model():
    """A disc rolling in a hole of a spinning hub, with rolling resistance: curve joint,
    rolling, damper and driver."""
    return hub_rolling_disc(np.radians(20.0), damping=1e-4)[0]


def test_assembly_does_not_write_into_the_model():
    """A model with curve joints, rolling, dampers and a driver assembles twice to the same
    system, and no declaration gains or changes an attribute."""
    model = _pendulum_model()
    before = [copy.copy(vars(e)) for e in model.elements]
    s1 = System(model)
    s2 = System(model)
    for e, b in zip(model.elements, before, strict=True):
        assert set(vars(e)) == set(b), type(e).__name__
        for k, v in b.items():
            assert vars(e)[k] is v or np.array_equal(vars(e)[k], v), (type(e).__name__, k)
    assert s1.n == s2.n and s1.m == s2.m
    assert np.array_equal(s1.q0_raw, s2.q0_raw)
    # the same model simulated on both systems gives the same numbers
    a = simulate(model, 0.02, 1e-3, system=s1, reactions=False).dataset.position.values
    b = simulate(model, 0.02, 1e-3, system=s2, reactions=False).dataset.position.values
    assert np.array_equal(a, b)


def test_newton_matrix_holds_structural_nonzeros_only():
    """At a generic state, few stored entries of the KKT matrix are exact zeros."""
    model = _pendulum_model()
    s = System(model)
    integ = make_integrator(s, "ep", 1e-3)
    rng = np.random.default_rng(1)
    x = np.concatenate([1e-4 * rng.standard_normal(s.n), 1e-3 * rng.standard_normal(s.m)])
    integ._begin()
    mat = integ._jacobian(x)
    zeros = np.count_nonzero(mat.data == 0.0)
    # measured: 52 exact zeros of 682 stored entries (7.6 %): the hole is planar, so the
    # out-of-plane components of its derivatives are zero by geometry, not by structure
    assert zeros <= 0.1 * mat.nnz, (zeros, mat.nnz)


def test_failed_step_names_the_element():
    """A load that turns non-finite makes the step fail; the message says whose row."""
    g = ground()
    rod = RigidBody("rod", 1.0, inertia=(0.0, 0.1, 0.1), position=(0.5, 0.0, 0.0))
    model = Model()
    model.add(g, rod, Revolute("pin", g, rod, point=(0, 0, 0), axis=(0, 0, 1)),
              Gravity((0.0, -9.81, 0.0)),
              AppliedLoad("bad", rod, force=lambda t: np.array([np.nan if t > 0.005 else 0.0,
                                                                0.0, 0.0])))
    sim = simulate(model, 0.02, 1e-3, reactions=False)
    assert not sim.converged
    assert "'rod'" in sim.message, sim.message
