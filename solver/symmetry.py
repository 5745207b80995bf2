"""Cyclic symmetry of a model: a rotation by 2π/N about an axis that permutes N identical sectors.

A rotor with N identical blades (or absorbers) spinning at Ω under loads that are periodic
with T/N in the non-rotating frame has a steady response with the same symmetry: at t + T/N
sector j stands where sector j + 1 stood at t and does what it did there (its global
coordinates are sector j + 1's at t), the hub has turned by 2π/N, and the non-rotating parts
(shaft head, fuselage, inflow) repeat with period T/N. The map from t to t + T/N followed by
the inverse, :meth:`CyclicSymmetry.back` (each sector's coordinates moved to the next sector's
slot, the hub turned back by 2π/N), is then a map of one N-th of a revolution whose fixed
point is the periodic response: a shooting or a marching on it sees N iterates per revolution
(Peters & Barwey; the "quarter-revolution map with blade permutation" of a four-bladed rotor).

The turn acts on the rotating parts that belong to no sector as a rigid rotation about the
axis through a centre that may move (the shaft head): positions p → c + R(p − c), directors
d → R d, and their rates ṗ → ċ + R(ṗ − ċ), ḋ → R ḋ (plus Ṙ terms when the axis tilts). It
preserves every constraint between the rotating parts and between them and the centre's body,
and, in a driven rotation ψ = Ωt, turns the state at t + T/N into one consistent at t.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.rotations import rotation_about

Array = NDArray[np.float64]


class CyclicSymmetry:
    """Turn-and-permute map of the states of a cyclically symmetric model.

    Parameters
    ----------
    system
        The assembled model (:class:`solver.system.System`).
    sectors
        ``N`` lists of state owners (bodies, joints' scalars, first-order elements), one per
        sector, in the sense of rotation (sector j + 1 is sector j turned by +2π/N); matching
        owners must declare blocks of the same kind and size. N ≥ 2.
    rotating
        Owners that turn with the rotor but belong to no sector (the hub); all other owners are
        non-rotating and left as they are.
    axis
        Rotor axis; the rotor turns positively about it. In the frame of ``centre`` when that
        is a rigid body (the shaft head, whose axis tilts with the fuselage), else global.
    centre
        The owner whose first three coordinates are the centre the rotor turns about (e.g. the
        shaft head), or ``None`` for the fixed point ``point``.
    point
        The centre when ``centre`` is ``None`` (m, global).
    """

    def __init__(self, system, sectors: Sequence[Sequence[object]],
                 rotating: Sequence[object] = (), axis: ArrayLike = (0.0, 0.0, 1.0),
                 centre: object | None = None, point: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        n_sec = len(sectors)
        if n_sec < 2:
            raise ValueError(f"a cyclic symmetry needs at least 2 sectors, got {n_sec}")
        lay = system.layout
        blocks = {id(b.owner): b for b in lay.blocks}

        def indices(owner) -> NDArray[np.int64]:
            if id(owner) not in blocks:
                raise ValueError(f"{getattr(owner, 'name', owner)!r} declares no state block")
            b = blocks[id(owner)]
            o = lay.offset[owner]
            return np.arange(o, o + b.size)

        sec_idx = []
        for j, sec in enumerate(sectors):
            if len(sec) != len(sectors[0]):
                raise ValueError(f"sector {j} has {len(sec)} owners, sector 0 {len(sectors[0])}")
            for o0, o in zip(sectors[0], sec, strict=True):
                b0, b = blocks.get(id(o0)), blocks.get(id(o))
                if b0 is not None and b is not None and (b.kind, b.size) != (b0.kind, b0.size):
                    raise ValueError(f"sector {j}: {getattr(o, 'name', o)!r} does not match "
                                     f"{getattr(o0, 'name', o0)!r} of sector 0")
            sec_idx.append(np.concatenate([indices(o) for o in sec]) if len(sec)
                           else np.zeros(0, np.int64))
        self.n_sectors = n_sec
        self.angle = 2 * np.pi / n_sec
        n = system.n
        # perm[i]: where coordinate i of the mapped state comes from, one sector back
        self._perm = np.arange(n)
        for j in range(n_sec):
            self._perm[sec_idx[j]] = sec_idx[j - 1]
        turned = np.zeros(n, dtype=bool)
        for o in rotating:
            turned[indices(o)] = True
        second = lay.kind == 0
        turned &= second
        if lay.unclassified and np.any(turned[np.concatenate(
                [indices(o) for o in lay.unclassified])]):
            raise ValueError("a turned owner has second-order coordinates that are neither "
                             "positions nor directors")
        # the turned 3-vectors: first index of each, and whether it is a position
        first = np.nonzero(turned)[0]
        if first.size % 3:
            raise ValueError("turned coordinates must come in whole 3-vectors")
        first = first.reshape(-1, 3)[:, 0]
        if np.any(np.diff(np.nonzero(turned)[0].reshape(-1, 3), axis=1) != 1):
            raise ValueError("turned coordinates must come in whole 3-vectors")
        self._vec = first[:, None] + np.arange(3)
        self._pos = lay.is_position[first]
        self.axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        self._centre = None if centre is None else lay.offset[centre]
        # the axis is fixed in the centre body when it is a rigid body (12 coordinates x, d1,
        # d2, d3): the shaft head carries the rotor axis
        self._centre_triad = centre is not None and blocks[id(centre)].size == 12 and bool(
            lay.is_position[self._centre]) and not lay.is_position[self._centre + 3 :
                                                                   self._centre + 12].any()
        self._point = np.asarray(point, dtype=float)

    def back(self, q: Array, *rates: Array, k: int = 1) -> tuple[Array, ...]:
        """The state k sector periods earlier on a symmetric response: the rotating parts
        turned by −k·2π/N about the axis and each sector's coordinates moved to the sector
        ahead of it.

        On the periodic symmetric response, ``back(q(t + kT/N), v(t + kT/N), k=k)`` equals
        ``(q(t), v(t))``; ``k`` may be negative (the state k sector periods later).
        ``rates`` are the velocities and, after them, any higher rates a scheme keeps
        (accelerations), each of the layout's length.

        With the axis fixed in a moving centre body (a shaft head on a bending fuselage) the
        turn is R = D R₀ Dᵀ with D the body's triad: positions x → c + R(x − c), directors
        d → R d, and the velocities follow exactly, ẋ → ċ + Ṙ(x − c) + R(ẋ − ċ),
        ḋ → Ṙd + Rḋ with Ṙ from the body's director rates. Higher rates are turned by R
        alone (they seed a scheme's history; the missing terms are of the order of the
        centre's angular velocity, zero for a non-tilting shaft).
        """
        k = int(k) % self.n_sectors
        q = np.array(q, dtype=float)
        rates = tuple(np.array(r, dtype=float) for r in rates)
        for _ in range(k):
            q = q[self._perm]
            rates = tuple(r[self._perm] for r in rates)
        r0 = rotation_about(self.axis, -k * self.angle)
        if self._centre is None:
            c = self._point
            rot, rot_dot = r0, np.zeros((3, 3))
        else:
            o = self._centre
            c = q[o : o + 3].copy()
            if self._centre_triad:
                d = q[o + 3 : o + 12].reshape(3, 3).T  # columns d1, d2, d3
                rot = d @ r0 @ d.T
                if rates:
                    dd = rates[0][o + 3 : o + 12].reshape(3, 3).T
                    rot_dot = dd @ r0 @ d.T + d @ r0 @ dd.T
                else:
                    rot_dot = np.zeros((3, 3))
            else:
                rot, rot_dot = r0, np.zeros((3, 3))
        pos = self._pos
        x0 = q[self._vec]  # (m, 3) the turned 3-vectors before the turn
        rel = x0 - np.where(pos[:, None], c, 0.0)  # x − c for positions, d for directors
        q[self._vec] = rel @ rot.T + np.where(pos[:, None], c, 0.0)
        for n, r in enumerate(rates):
            rc = (np.zeros(3) if self._centre is None
                  else r[self._centre : self._centre + 3].copy())
            shift = np.where(pos[:, None], rc, 0.0)
            turned = (r[self._vec] - shift) @ rot.T + shift
            if n == 0:
                turned += rel @ rot_dot.T
            r[self._vec] = turned
        return (q, *rates)


def director_triads(layout) -> NDArray[np.int64]:
    """Indices (m, 3, 3) of the director triads (d1, d2, d3) of the second-order blocks: the
    three director 3-vectors that follow each position 3-vector of a rigid body or beam node."""
    pos = layout.is_position
    kind = layout.kind
    out = []
    for b in layout.blocks:
        o = layout.offset[b.owner]
        if b.kind != "second" or b.size % 12:
            continue
        for g in range(o, o + b.size, 12):
            if pos[g] and not pos[g + 3 : g + 12].any() and np.all(kind[g : g + 12] == 0):
                out.append(np.arange(g + 3, g + 12).reshape(3, 3))
    return np.array(out, dtype=np.int64).reshape(-1, 3, 3)


def affine_combination(system, weights: ArrayLike, qs: Sequence[Array],
                       vs: Sequence[Array]) -> tuple[Array, Array]:
    """Σ_j w_j (q_j, v_j) with Σ w_j = 1, taken on the rotation group for director triads.

    Positions, scalars and their rates combine linearly. A triad D = [d1 d2 d3] combines as
    D* = D_k exp(Σ_j w_j log(D_kᵀ D_j)) about the last state's D_k, and its rate from the
    body-frame angular velocities, Ḋ* = D* skew(Σ_j w_j ω_j) with skew(ω_j) = D_jᵀ Ḋ_j: a
    linear combination of the directors themselves would leave the triads non-orthonormal at
    second order in their spread (a rolling pin turns by radians between states), and the
    projection back onto the constraints would then move the physical coordinates too.
    """
    from scipy.spatial.transform import Rotation

    w = np.asarray(weights, dtype=float)
    if w.ndim != 1 or w.size != len(qs) or len(qs) != len(vs) or not len(qs):
        raise ValueError("affine_combination: one weight per state, at least one state")
    if abs(w.sum() - 1.0) > 1e-9:
        raise ValueError(f"affine_combination: weights sum to {w.sum()!r}, not 1")
    qa, va = np.array(qs, dtype=float), np.array(vs, dtype=float)
    q, v = w @ qa, w @ va
    tri = director_triads(system.layout)
    if tri.size:
        # D[j, m] with columns d1, d2, d3 (rows of the index triad are the directors)
        d = np.swapaxes(qa[:, tri], -1, -2)  # (states, m, 3, 3)
        dd = np.swapaxes(va[:, tri], -1, -2)
        ref = d[-1]
        m = ref.shape[0]
        rel = np.einsum("mji,smjk->smik", ref, d).reshape(-1, 3, 3)
        theta = Rotation.from_matrix(rel).as_rotvec().reshape(len(qs), m, 3)
        new = ref @ Rotation.from_rotvec(np.tensordot(w, theta, axes=1)).as_matrix()
        om = np.einsum("smji,smjk->smik", d, dd)  # body-frame skew(ω_j), up to roundoff
        omega = 0.5 * np.stack([om[..., 2, 1] - om[..., 1, 2], om[..., 0, 2] - om[..., 2, 0],
                                om[..., 1, 0] - om[..., 0, 1]], axis=-1)
        ws = np.tensordot(w, omega, axes=1)  # (m, 3)
        sk = np.zeros((m, 3, 3))
        sk[:, 0, 1], sk[:, 0, 2], sk[:, 1, 2] = -ws[:, 2], ws[:, 1], -ws[:, 0]
        sk -= np.swapaxes(sk, -1, -2)
        q[tri] = np.swapaxes(new, -1, -2)
        v[tri] = np.swapaxes(new @ sk, -1, -2)
    return q, v
