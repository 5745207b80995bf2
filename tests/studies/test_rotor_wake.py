"""The rotor's prescribed wake iteration (studies/rotor_wake.py)."""

from __future__ import annotations

import numpy as np
import pytest

from studies.rotor_wake import anderson_step


def _iterate(a, b, beta, depth, steps):
    history: list = []
    x = np.zeros(len(b))
    errors = []
    exact = np.linalg.solve(np.eye(len(b)) - a, b)
    for _ in range(steps):
        f = a @ x + b - x
        x = x + anderson_step(history, x.copy(), f, beta, depth)
        errors.append(np.abs(x - exact).max() / np.abs(exact).max())
    return errors


def test_anderson_solves_a_linear_fixed_point_as_gmres_does():
    # G(x) = A x + b with eigenvalues 0.3 … 0.95 (a slow direction, as the wake's 0.7): the
    # relaxed iteration crawls at 1 − β(1 − 0.95) per step; Anderson with depth ≥ n is
    # GMRES on (I − A) x = b, exact after n + 1 steps (measured 2e-15 after 7 for n = 6)
    rng = np.random.default_rng(1)
    n = 6
    basis = np.linalg.qr(rng.normal(size=(n, n)))[0]
    a = basis @ np.diag(np.linspace(0.3, 0.95, n)) @ np.linalg.inv(basis)
    b = rng.normal(size=n)
    assert _iterate(a, b, 0.5, n, n + 2)[-1] < 1e-10
    relaxed = _iterate(a, b, 0.5, 0, 30)
    assert relaxed[-1] > 0.1  # (1 − 0.5 · 0.05)^30 = 0.47 of the slow part left
    assert relaxed[-1] / relaxed[-2] == pytest.approx(0.975, abs=2e-3)
