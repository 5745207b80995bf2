"""The state registry: the unknowns of a model, declared by its elements as typed blocks.

Three kinds of unknowns, each integrated consistently by every scheme:

``SECOND``
    Coordinates of second-order dynamics with a constant mass matrix: rigid-body and beam-node
    positions and directors, point masses. Their rates are velocities, M q̈ = forces.
``FIRST``
    First-order states with their own constant "mass" matrix A: A ẋ = f(q, v, x, t)
    (aerodynamic and inflow states, lags). They carry no kinetic energy.
``ALGEBRAIC``
    Massless scalars fixed by constraints (the curve parameter η, the arc length s).

An element declares its blocks with :class:`StateBlock`; :class:`Layout` numbers them: second-
order blocks first (in declaration order, so body coordinates form consecutive 3-vectors),
then algebraic scalars, then first-order states. Nothing is written into the declarations.

Second-order blocks are consecutive 3-vectors of two geometric types, which a rigid motion of
the whole model moves differently: *positions* (a body's centre, a point mass, a beam node)
rotate about a point and translate, *directors* (a body's or a beam node's d1, d2, d3) only
rotate. :attr:`StateBlock.positions` says which is which (used by relative equilibria and
linearization in a rotating frame, :mod:`solver.equilibrium`, :mod:`solver.modes`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
SECOND, ALGEBRAIC, FIRST = "second", "algebraic", "first"
KINDS = (SECOND, ALGEBRAIC, FIRST)


@dataclass(eq=False)
class StateBlock:
    """A block of unknowns declared by an element.

    Parameters
    ----------
    owner
        The declaring element (a body, a joint's scalar, a first-order element); the layout is
        looked up by it.
    kind
        ``"second"``, ``"first"`` or ``"algebraic"``.
    size
        Number of unknowns.
    initial, rate
        Initial values and rates (units of the unknowns, per second for rates).
    mass
        Constant mass matrix (second order) or A matrix (first order) as a dense
        ``size × size`` array; ``None`` is zero (algebraic blocks must leave it ``None``).
    units, long_name
        Of the unknowns, for results.
    parts
        Sub-owners addressed inside this block, with their local offsets (a beam's nodes, each
        12 coordinates x, d1, d2, d3 that joints and loads attach to like a rigid body's).
    positions
        Second-order blocks only: per coordinate (or per 3-vector), whether it belongs to a
        position 3-vector (True) or to a director (False). Default: all positions for a
        block of 3 (a point mass); for a block of 12·k coordinates, k groups laid out as
        (x, d1, d2, d3), so the first 3 of every 12 are positions (rigid bodies, beam nodes);
        other sizes must set it. Stored as a boolean array of length ``size`` (``None`` if
        not known); all False for first-order and algebraic blocks.
    """

    owner: object
    kind: str
    size: int
    initial: ArrayLike = 0.0
    rate: ArrayLike = 0.0
    mass: Array | None = None
    units: str = "1"
    long_name: str = ""
    parts: dict | None = None
    positions: ArrayLike | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"state kind {self.kind!r} must be one of {', '.join(KINDS)}")
        if self.kind == ALGEBRAIC and self.mass is not None:
            raise ValueError("algebraic states are massless (mass must be None)")
        self.initial = np.broadcast_to(np.asarray(self.initial, dtype=float),
                                       (self.size,)).copy()
        self.rate = np.broadcast_to(np.asarray(self.rate, dtype=float), (self.size,)).copy()
        self.positions = _position_mask(self.kind, self.size, self.positions)


class Layout:
    """Numbering of the declared state blocks.

    Attributes
    ----------
    n
        Number of unknowns.
    offset
        ``owner → index`` of the first unknown of the owner's (first) block.
    kind
        Per unknown, the index into :data:`KINDS` (0 second, 1 algebraic, 2 first order).
    second, algebraic, first
        Index arrays of the unknowns of each kind.
    is_position
        Per unknown, whether it is a component of a position 3-vector (see
        :attr:`StateBlock.positions`); second-order unknowns that are not are directors.
    unclassified
        Second-order blocks whose :attr:`StateBlock.positions` is unknown (their owners).
    """

    def __init__(self, blocks: list[StateBlock]) -> None:
        owners = [b.owner for b in blocks]
        if len({id(o) for o in owners}) != len(owners):
            raise ValueError("an element declared two state blocks under the same owner")
        ordered = [b for k in KINDS for b in blocks if b.kind == k]
        self.blocks = ordered
        self.offset: dict = {}
        n = 0
        kinds = []
        for b in ordered:
            self.offset[b.owner] = n
            for part, local in (b.parts or {}).items():
                self.offset[part] = n + local
            n += b.size
            kinds += [KINDS.index(b.kind)] * b.size
        self.n = n
        self.kind = np.array(kinds, dtype=np.int8)
        self.second = np.nonzero(self.kind == 0)[0]
        self.algebraic = np.nonzero(self.kind == 1)[0]
        self.first = np.nonzero(self.kind == 2)[0]
        self.n_second_coordinates = len(self.second)
        self.is_position = np.zeros(n, dtype=bool)
        self.unclassified = []
        for b in ordered:
            if b.positions is None:
                self.unclassified.append(b.owner)
            else:
                o = self.offset[b.owner]
                self.is_position[o : o + b.size] = b.positions

    def initial(self) -> tuple[Array, Array]:
        """Declared initial values and rates."""
        q = np.zeros(self.n)
        v = np.zeros(self.n)
        for b in self.blocks:
            o = self.offset[b.owner]
            q[o : o + b.size] = b.initial
            v[o : o + b.size] = b.rate
        return q, v

    def mass_matrices(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """(M, A): the second-order mass matrix and the first-order A matrix, both n × n,
        structural non-zeros only."""
        out = []
        for kind in (SECOND, FIRST):
            rows, cols, vals = [], [], []
            for b in self.blocks:
                if b.kind != kind or b.mass is None:
                    continue
                o = self.offset[b.owner]
                r, c = np.nonzero(b.mass)
                rows.append(o + r)
                cols.append(o + c)
                vals.append(b.mass[r, c])
            out.append(sp.csr_matrix((_cat(vals, float), (_cat(rows, np.int64),
                                                           _cat(cols, np.int64))),
                                     shape=(self.n, self.n)))
        return out[0], out[1]


def _position_mask(kind: str, size: int, given: ArrayLike | None) -> NDArray[np.bool_] | None:
    """The per-coordinate position mask of a block (see :attr:`StateBlock.positions`)."""
    if kind != SECOND:
        if given is not None and np.any(given):
            raise ValueError(f"only second-order blocks hold positions (kind {kind!r})")
        return np.zeros(size, dtype=bool)
    if given is None:
        if size == 3:
            return np.ones(3, dtype=bool)
        if size % 12 == 0:  # (x, d1, d2, d3) groups: rigid bodies, beam nodes
            return np.tile(np.repeat([True, False, False, False], 3), size // 12)
        return None
    m = np.asarray(given, dtype=bool).reshape(-1)
    if size % 3 == 0 and m.shape == (size // 3,):
        m = np.repeat(m, 3)
    if size % 3 or m.shape != (size,) or np.any(m.reshape(-1, 3) != m.reshape(-1, 3)[:, :1]):
        raise ValueError(f"positions must flag whole 3-vectors of a second-order block of "
                         f"{size} coordinates (length {size} or {size // 3})")
    return m


def _cat(parts: list, dtype) -> np.ndarray:
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)
