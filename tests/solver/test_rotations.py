"""Finite-rotation utilities (solver.rotations) against closed forms.

References used here (none of them calls the code under test):
* Rodrigues: R = I + sin φ ñ + (1 − cos φ) ñ², and R = expm(φ ñ) (scipy.linalg.expm);
* unit quaternion of (φ, n): (cos φ/2, sin φ/2 n);
* Wiener–Milenkovic parameters c = 4 tan(φ/4) n; for φ ≤ π, |c| ≤ 4, and c and −16c/(c·c)
  describe the same rotation.
All tolerances are a few hundred ulps: the functions are closed-form algebra, so anything larger
than roundoff is a bug (the measured worst cases are quoted next to each tolerance).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from solver.rotations import (
    matrix_from_quaternion,
    matrix_from_wiener_milenkovic,
    quaternion_from_matrix,
    rotation_about,
    skew,
    wiener_milenkovic_from_matrix,
)

RNG_SEED = 20240611


def _hat(v):
    """Independent skew matrix (not solver.rotations.skew)."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _rodrigues(n, phi):
    k = _hat(n)
    return np.eye(3) + np.sin(phi) * k + (1.0 - np.cos(phi)) * (k @ k)


def _axis_angle_samples(count=200):
    """Unit axes and angles in [0, π], with clusters at 0 and near/at π."""
    rng = np.random.default_rng(RNG_SEED)
    n = rng.standard_normal((count, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    phi = rng.uniform(0.0, np.pi, count)
    special = [0.0, 1e-12, 1e-6, np.pi - 1e-3, np.pi - 1e-6, np.pi - 1e-9, np.pi - 1e-12, np.pi]
    phi[: len(special)] = special
    phi[len(special) : 2 * len(special)] = special  # same angles about other axes
    return n, phi


def test_skew_and_rotation_about_match_cross_product_and_expm():
    n, phi = _axis_angle_samples()
    a = np.random.default_rng(1).standard_normal((len(n), 3))
    # skew(v) w = v × w for a batch
    np.testing.assert_allclose(np.einsum("kij,kj->ki", skew(n), a), np.cross(n, a), atol=1e-15)
    for ni, p in zip(n, phi, strict=True):
        # rotation_about vs the matrix exponential; measured max error 1.1e-15
        np.testing.assert_allclose(rotation_about(3.7 * ni, p), expm(p * _hat(ni)), atol=1e-14)


def test_quaternion_against_closed_form_and_round_trips():
    n, phi = _axis_angle_samples()
    r = np.array([_rodrigues(ni, p) for ni, p in zip(n, phi, strict=True)])
    q = quaternion_from_matrix(r)
    q_ref = np.column_stack([np.cos(phi / 2), np.sin(phi / 2)[:, None] * n])
    # e0 ≥ 0 convention; at φ = π exactly both signs of e are the same rotation
    sign = np.where(np.sum(q * q_ref, axis=1) < 0, -1.0, 1.0)
    assert np.all(q[:, 0] >= 0.0)
    np.testing.assert_allclose(sign[:, None] * q, q_ref, atol=1e-12)  # measured 2.2e-16
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
    # matrix → quaternion → matrix (measured 7.8e-16)
    np.testing.assert_allclose(matrix_from_quaternion(q), r, atol=1e-14)
    # quaternion → matrix is the closed form (e0² − e·e) I + 2 e eᵀ + 2 e0 ẽ
    np.testing.assert_allclose(matrix_from_quaternion(q_ref), r, atol=1e-14)
    # quaternion → matrix → quaternion, for non-normalised input of either sign
    raw = np.random.default_rng(2).standard_normal((100, 4)) * 3.0
    back = quaternion_from_matrix(matrix_from_quaternion(raw))
    unit = raw / np.linalg.norm(raw, axis=1, keepdims=True)
    unit *= np.where(unit[:, :1] < 0, -1.0, 1.0)
    np.testing.assert_allclose(back, unit, atol=1e-14)


def test_wiener_milenkovic_closed_form_bound_and_round_trip():
    n, phi = _axis_angle_samples()
    r = np.array([_rodrigues(ni, p) for ni, p in zip(n, phi, strict=True)])
    c = wiener_milenkovic_from_matrix(r)
    c_ref = 4.0 * np.tan(phi / 4)[:, None] * n
    # |c| ≤ 4 (the rescaled branch is never needed for φ ≤ π): roundoff allowance only
    assert np.all(np.linalg.norm(c, axis=1) <= 4.0 + 1e-12)
    at_pi = phi == np.pi
    np.testing.assert_allclose(c[~at_pi], c_ref[~at_pi], atol=1e-12)  # measured 8.9e-16
    # exactly π: c = ±4 n are the same rotation
    for ci, cr in zip(c[at_pi], c_ref[at_pi], strict=True):
        assert min(np.abs(ci - cr).max(), np.abs(ci + cr).max()) < 1e-12
    # matrix → c → matrix round trip, including angles within 1e-12 of π (measured 7.8e-16)
    np.testing.assert_allclose(matrix_from_wiener_milenkovic(c), r, atol=1e-14)
    # c → matrix against Rodrigues directly
    np.testing.assert_allclose(matrix_from_wiener_milenkovic(c_ref), r, atol=1e-14)


@pytest.mark.parametrize("phi", [np.pi + 1e-6, 4.0, 5.5, 2 * np.pi - 1e-3])
def test_wiener_milenkovic_beyond_pi_and_rescaling(phi):
    """For π < φ < 2π, c = 4 tan(φ/4) n has |c| > 4; it and its rescaled image −16c/(c·c)
    give the same matrix, and the matrix → c map returns the rescaled (|c| ≤ 4) branch."""
    n = np.array([0.2, -0.6, 0.77])
    n /= np.linalg.norm(n)
    c_big = 4.0 * np.tan(phi / 4) * n
    assert np.linalg.norm(c_big) > 4.0
    c_small = -16.0 * c_big / (c_big @ c_big)
    r = _rodrigues(n, phi)
    np.testing.assert_allclose(matrix_from_wiener_milenkovic(c_big), r, atol=1e-13)
    np.testing.assert_allclose(matrix_from_wiener_milenkovic(c_small), r, atol=1e-13)
    np.testing.assert_allclose(wiener_milenkovic_from_matrix(r), c_small, atol=1e-12)


def test_vectorised_shapes():
    n, phi = _axis_angle_samples(24)
    r = np.array([_rodrigues(ni, p) for ni, p in zip(n, phi, strict=True)]).reshape(4, 6, 3, 3)
    c = wiener_milenkovic_from_matrix(r)
    q = quaternion_from_matrix(r)
    assert c.shape == (4, 6, 3) and q.shape == (4, 6, 4)
    np.testing.assert_allclose(matrix_from_wiener_milenkovic(c), r, atol=1e-14)
    np.testing.assert_allclose(matrix_from_quaternion(q), r, atol=1e-14)
