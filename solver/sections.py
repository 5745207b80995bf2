"""Cross-section properties of beams, tabulated along the reference arc length.

A :class:`SectionTable` holds the stiffness and inertia of a beam's cross-sections at stations
along its reference line and interpolates linearly between them; a repeated station makes a
jump (a root cuff, a hinge lump), which the beam's segmented quadrature integrates exactly.

Conventions (those of BeamDyn, Kynema and Dymore): the section frame is (d1, d2, d3), d1 along
the reference line (the beam axis of a straight beam), d2 and d3 the section axes. The 6 × 6
stiffness acts on the material strains ordered (axial, shear 2, shear 3, torsion, bending 2,
bending 3) and gives the stress resultants (N, V2, V3, T, M2, M3) in the same order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


@dataclass(eq=False)
class SectionTable:
    """Section properties at stations, linearly interpolated between them.

    Parameters
    ----------
    stations
        Arc length from the beam's first node (m), non-decreasing, from 0 to the beam length; a
        station given twice marks a jump of the properties there.
    stiffness
        6 × 6 symmetric positive semi-definite stiffness per station, (n, 6, 6), in N (axial,
        shears), N·m (couplings) and N·m² (torsion, bendings); order (axial, shear 2, shear 3,
        torsion, bending 2, bending 3). A single 6 × 6 matrix is broadcast to all stations.
    mass
        Mass per unit length (kg/m), (n,) or scalar.
    cg
        Centre-of-mass offset (ξ2, ξ3) in the section frame (m), (n, 2) or (2,).
    inertia
        Mass moments of inertia per unit length about the centre of mass (kg·m):
        (i22, i33, i23) with i22 = ∫ρ (ξ3 − c3)² dA (bending about d2, flap for a blade),
        i33 = ∫ρ (ξ2 − c2)² dA (about d3, lag) and i23 = ∫ρ (ξ2 − c2)(ξ3 − c3) dA; (n, 3) or
        (3,). The polar moment is i22 + i33.
    """

    stations: ArrayLike
    stiffness: ArrayLike
    mass: ArrayLike = 0.0
    cg: ArrayLike = (0.0, 0.0)
    inertia: ArrayLike = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        s = np.asarray(self.stations, dtype=float).reshape(-1)
        n = len(s)
        if n < 1 or not np.all(np.isfinite(s)) or s[0] != 0.0 or np.any(np.diff(s) < 0):
            raise ValueError("section stations must be finite, start at 0 m and not decrease; "
                             f"got {np.round(s, 6).tolist()}")
        if n == 1:  # one station: uniform beam; the beam stretches it over its length
            s = np.array([0.0, np.inf])
        self.stations = s
        m = len(s)

        def table(x, shape, what, units):
            a = np.asarray(x, dtype=float)
            try:
                a = np.broadcast_to(a, (m, *shape)) if a.shape in (shape, ()) else a
                if a.shape == (n, *shape) and n == 1:
                    a = np.broadcast_to(a, (m, *shape))
                if a.shape != (m, *shape):
                    raise ValueError
            except ValueError:
                raise ValueError(f"section {what} must have shape {(n, *shape)} (one per "
                                 f"station) or {shape}; got {np.shape(x)}") from None
            if not np.all(np.isfinite(a)):
                raise ValueError(f"section {what} ({units}) must be finite")
            return np.array(a)

        c = table(self.stiffness, (6, 6), "stiffness", "N, N m, N m2")
        if np.abs(c - np.swapaxes(c, 1, 2)).max() > 1e-9 * max(1.0, np.abs(c).max()):
            raise ValueError("section stiffness matrices must be symmetric")
        # exactly symmetric from here on (the beams' material stiffness sums half of itself)
        c = 0.5 * (c + np.swapaxes(c, 1, 2))
        for k, ck in enumerate(c):
            ev = np.linalg.eigvalsh(ck)
            if ev.min() < -1e-9 * max(1.0, ev.max()):
                raise ValueError(f"section stiffness at station {k} (s = {s[k]:g} m) is not "
                                 f"positive semi-definite (eigenvalue {ev.min():.4g})")
        self.stiffness = c
        self.mass = table(self.mass, (), "mass", "kg/m")
        if np.any(self.mass < 0):
            raise ValueError("section mass per length (kg/m) must be ≥ 0")
        self.cg = table(self.cg, (2,), "cg", "m")
        self.inertia = table(self.inertia, (3,), "inertia", "kg m")
        i22, i33, i23 = self.inertia.T
        if np.any(i22 < 0) or np.any(i33 < 0) or np.any(i23**2 > i22 * i33 * (1 + 1e-9) + 1e-300):
            raise ValueError("section inertia (i22, i33, i23) (kg m) must be a positive "
                             "semi-definite second moment: i22, i33 ≥ 0 and i23² ≤ i22 i33")

    @property
    def length(self) -> float:
        """Last station (m); infinite for a uniform table given at one station."""
        return float(self.stations[-1])

    def breaks(self) -> Array:
        """Distinct finite stations (m): where the properties may have kinks or jumps."""
        s = self.stations[np.isfinite(self.stations)]
        return np.unique(s)

    def _interp(self, table: Array, s: Array, side: str) -> Array:
        """Linear interpolation at arc lengths ``s``; at a jump, ``side`` picks the value on
        the 'left' or 'right' of it."""
        st = self.stations
        s = np.asarray(s, dtype=float)
        if np.isinf(st[-1]):
            return np.broadcast_to(table[0], (*s.shape, *table.shape[1:])).copy()
        # 'right': st[k] ≤ s < st[k+1]; 'left': st[k] < s ≤ st[k+1] — never a zero-length
        # interval inside the table, so a repeated station is a clean jump
        k = np.clip(np.searchsorted(st, s, side=side) - 1, 0, len(st) - 2)
        ds = st[k + 1] - st[k]
        t = np.clip((s - st[k]) / np.where(ds > 0, ds, 1.0), 0.0, 1.0)
        t = t.reshape(t.shape + (1,) * (table.ndim - 1))
        return (1 - t) * table[k] + t * table[k + 1]

    def at(self, s: ArrayLike, side: str = "right") -> dict[str, Array]:
        """Properties at arc lengths ``s`` (m): ``stiffness`` (…, 6, 6), ``mass`` (…),
        ``cg`` (…, 2), ``inertia`` (…, 3)."""
        return {k: self._interp(getattr(self, k), np.asarray(s, dtype=float), side)
                for k in ("stiffness", "mass", "cg", "inertia")}

    def director_inertia(self, s: ArrayLike, side: str = "right") -> Array:
        """The 4 × 4 section mass density per length of (x, d1, d2, d3) at ``s`` (kg/m, kg,
        kg·m): [[m, 0, S2, S3], [0, 0, 0, 0], [S2, 0, J22, J23], [S3, 0, J23, J33]] with
        S_α = m c_α and J_αβ = ∫ρ ξ_α ξ_β dA about the reference line. The section kinetic
        energy is ½ Σ μ_ij ẏ_i·ẏ_j over y = (x, d1, d2, d3)."""
        p = self.at(s, side)
        m, c, i = p["mass"], p["cg"], p["inertia"]
        out = np.zeros((*np.shape(m), 4, 4))
        out[..., 0, 0] = m
        out[..., 0, 2] = out[..., 2, 0] = m * c[..., 0]
        out[..., 0, 3] = out[..., 3, 0] = m * c[..., 1]
        out[..., 2, 2] = i[..., 1] + m * c[..., 0] ** 2
        out[..., 3, 3] = i[..., 0] + m * c[..., 1] ** 2
        out[..., 2, 3] = out[..., 3, 2] = i[..., 2] + m * c[..., 0] * c[..., 1]
        return out


def isotropic_section(*, EA: float, GA2: float, GA3: float, GJ: float, EI2: float, EI3: float,
                      mass: float = 0.0, i22: float = 0.0, i33: float = 0.0) -> SectionTable:
    """A uniform, uncoupled section (N, N·m², kg/m, kg·m): diagonal stiffness
    (EA, GA2, GA3, GJ, EI2, EI3), centre of mass on the reference line."""
    vals = dict(EA=EA, GA2=GA2, GA3=GA3, GJ=GJ, EI2=EI2, EI3=EI3, mass=mass, i22=i22, i33=i33)
    for k, v in vals.items():
        if not (np.isfinite(v) and v >= 0):
            raise ValueError(f"isotropic_section: {k} = {v!r} must be ≥ 0 and finite")
    return SectionTable([0.0], np.diag([EA, GA2, GA3, GJ, EI2, EI3]), mass=mass,
                        inertia=(i22, i33, 0.0))
