"""Finite rotations: skew matrices, axis-angle, quaternions and Wiener–Milenkovic parameters.

The solver itself carries orientation as three orthonormal directors (the columns of the
rotation matrix), so it needs no rotation parameters inside Newton; the parameters here are for
input (initial orientations) and output (what Dymore users read: Wiener–Milenkovic parameters
c = 4 tan(φ/4) n, rescaled c → −16c/(c·c) when |c| > 4 so that |c| ≤ 4 stays singularity free).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def skew(v: ArrayLike) -> NDArray[np.float64]:
    """Skew-symmetric matrix ``ṽ`` with ``ṽ w = v × w``; ``v`` of shape (..., 3)."""
    v = np.asarray(v, dtype=float)
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def rotation_about(axis: ArrayLike, angle: float) -> NDArray[np.float64]:
    """Rotation matrix of ``angle`` (rad) about the unit vector ``axis`` (Rodrigues)."""
    n = np.asarray(axis, dtype=float)
    n = n / np.linalg.norm(n)
    k = skew(n)
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def quaternion_from_matrix(r: ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion (e0, e1, e2, e3) with e0 ≥ 0 from rotation matrices (..., 3, 3)."""
    r = np.asarray(r, dtype=float)
    tr = np.trace(r, axis1=-2, axis2=-1)
    # Shepperd's method: pick the largest of 4 candidate squares for numerical robustness.
    cand = np.stack(
        [1 + tr, 1 + 2 * r[..., 0, 0] - tr, 1 + 2 * r[..., 1, 1] - tr, 1 + 2 * r[..., 2, 2] - tr],
        axis=-1,
    )
    k = np.argmax(cand, axis=-1)
    q = np.empty((*r.shape[:-2], 4))
    s = np.sqrt(np.maximum(np.take_along_axis(cand, k[..., None], -1)[..., 0], 1e-300))
    r32, r23 = r[..., 2, 1], r[..., 1, 2]
    r13, r31 = r[..., 0, 2], r[..., 2, 0]
    r21, r12 = r[..., 1, 0], r[..., 0, 1]
    opts = [
        (s, (r32 - r23) / s, (r13 - r31) / s, (r21 - r12) / s),
        ((r32 - r23) / s, s, (r12 + r21) / s, (r13 + r31) / s),
        ((r13 - r31) / s, (r12 + r21) / s, s, (r23 + r32) / s),
        ((r21 - r12) / s, (r13 + r31) / s, (r23 + r32) / s, s),
    ]
    for i, comps in enumerate(opts):
        mask = k == i
        for j in range(4):
            q[..., j] = np.where(mask, comps[j], q[..., j] if i else comps[j])
    q *= 0.5
    q *= np.where(q[..., :1] < 0, -1.0, 1.0)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def matrix_from_quaternion(q: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrices (..., 3, 3) from unit quaternions (..., 4) = (e0, e)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    e0, e = q[..., 0], q[..., 1:]
    ee = np.einsum("...i,...j->...ij", e, e)
    return (
        (e0**2 - np.sum(e * e, -1))[..., None, None] * np.eye(3)
        + 2 * ee
        + 2 * e0[..., None, None] * skew(e)
    )


def wiener_milenkovic_from_matrix(r: ArrayLike) -> NDArray[np.float64]:
    """Wiener–Milenkovic parameters c = 4 tan(φ/4) n of rotation matrices (..., 3, 3).

    With the quaternion's scalar part e0 ≥ 0 the rotation angle is ≤ π, so |c| ≤ 4: the
    rescaled (singularity-free) branch is chosen automatically.
    """
    q = quaternion_from_matrix(r)
    return 4.0 * q[..., 1:] / (1.0 + q[..., :1])


def matrix_from_wiener_milenkovic(c: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrices from Wiener–Milenkovic parameters (..., 3) (any magnitude)."""
    c = np.asarray(c, dtype=float)
    cc = np.sum(c * c, axis=-1)
    c0 = 2.0 - cc / 8.0
    # quaternion: e0 = c0 / (4 - c0), e = c / (4 - c0) · ... ; normalize for safety
    q = np.concatenate([c0[..., None], c], axis=-1)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    q[..., 0] = c0 / np.sqrt(c0**2 + cc)
    return matrix_from_quaternion(q)
