"""Newton factors carried along with the parts of a model that spin at a known rate.

The Newton matrix of a spinning part (a rotor's hub, hinges and blades) turns with it: its
rows and columns of the part's position and director 3-vectors are, a few steps later and to
first order in everything but the spin, the earlier ones rotated by the angle turned in
between. With T(ψ) the rotation of those 3-vectors by ψ about the spin axis (identity on every
other unknown and on the constraint rows),

    J(t + Δt) ≈ T(ΩΔt) J(t) T(ΩΔt)ᵀ,   so   J(t + Δt)⁻¹ ≈ T(ΩΔt) J(t)⁻¹ T(ΩΔt)ᵀ,

and the LU factors of J(t) still drive a modified Newton iteration at t + Δt once the
right-hand side is turned back and the update turned forward. The iteration converges to the
same solution as with fresh factors (the residual is exact); only its rate depends on how good
the turned matrix is. Measured on the rotor model (blades turning 1.5° per step): factors
from the step before contract Newton's updates by 0.44 as they are and by 0.03–0.09 turned
(0.05 two steps old, 0.15 four; the rate varies along the revolution in forward flight).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver.jit import njit
from solver.rotations import rotation_about

Array = NDArray[np.float64]


class TurningParts:
    """The position and director 3-vectors of the parts that spin at ``rate`` about ``axis``.

    Parameters
    ----------
    system
        The assembled model (:class:`solver.system.System`).
    owners
        State owners that spin (bodies, beams, links, the elements on them); their position
        and director 3-vectors are turned, their other unknowns (second-order scalars such as
        a curve parameter, first-order states) left as they are.
    axis
        The spin axis (global; normalized here).
    rate
        Spin rate Ω (rad/s): the parts turn by Ω Δt in Δt.
    """

    def __init__(self, system, owners: Sequence[object], axis: ArrayLike,
                 rate: float) -> None:
        lay = system.layout
        axis = np.asarray(axis, dtype=float)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)) or not np.any(axis):
            raise ValueError(f"axis = {axis.tolist()} must be a finite nonzero 3-vector")
        if not np.isfinite(rate):
            raise ValueError(f"rate = {rate!r} rad/s must be finite")
        blocks = {id(b.owner): b for b in lay.blocks}
        scalars = {id(o) for o in lay.unclassified}  # second-order, neither x nor d
        vec = []
        for o in owners:
            if id(o) not in blocks:
                raise ValueError(f"{getattr(o, 'name', o)!r} declares no state block")
            b = blocks[id(o)]
            if b.kind == "second" and id(o) not in scalars:  # whole 3-vectors (state.py)
                start = lay.offset[o]
                vec.append(np.arange(start, start + b.size).reshape(-1, 3))
        # (m, 3) indices of the turned 3-vectors
        self.vectors = (np.concatenate(vec).astype(np.int64) if vec
                        else np.zeros((0, 3), dtype=np.int64))
        self.axis = axis / np.linalg.norm(axis)
        self.rate = float(rate)
        self.n = system.n
        self._angle, self._rot, self._back = 0.0, np.eye(3), np.eye(3)  # R(ψ), R(−ψ)

    def turn(self, x: Array, angle: float, stages: int = 1) -> None:
        """Rotate the parts' 3-vectors in ``x`` by ``angle`` (rad) about the axis, in place:
        in each of the first ``stages`` blocks of n entries (a Newton vector's increments,
        one block per stage of the scheme); the entries after them (multipliers) stay."""
        # Newton turns by the same ± angle a dozen times a step: R(ψ) and R(−ψ) = R(ψ)ᵀ kept
        if angle == -self._angle:
            self._angle, self._rot, self._back = angle, self._back, self._rot
        elif angle != self._angle:
            self._angle, self._rot = angle, rotation_about(self.axis, angle)
            self._back = np.ascontiguousarray(self._rot.T)
        _turn(x, self.vectors, self._rot, stages, self.n)


@njit(cache=True)
def _turn(x: Array, vectors: NDArray[np.int64], rot: Array, stages: int, n: int) -> None:
    """x[v] ← rot x[v] for each 3-vector v of ``vectors`` in each stage block, in place (one
    compiled pass: twice per Newton iteration on the rotor, where NumPy's fancy indexing of
    404 vectors cost 70 µs a call)."""
    for k in range(stages):
        for i in range(vectors.shape[0]):
            a, b, c = vectors[i, 0] + k * n, vectors[i, 1] + k * n, vectors[i, 2] + k * n
            x0, x1, x2 = x[a], x[b], x[c]
            x[a] = rot[0, 0] * x0 + rot[0, 1] * x1 + rot[0, 2] * x2
            x[b] = rot[1, 0] * x0 + rot[1, 1] * x1 + rot[1, 2] * x2
            x[c] = rot[2, 0] * x0 + rot[2, 1] * x1 + rot[2, 2] * x2
