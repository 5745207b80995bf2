"""Geometrically exact beams in director form, with 4-node (cubic) elements.

Each beam node carries, like a rigid body, a position x and three orthonormal directors
(d1, d2, d3): 12 coordinates and six orthonormality rows at the node (Betsch & Steinmann 2002,
IJNME 54:1775; Romero & Armero 2002, IJNME 54:1683). All 12 components are interpolated with
the same cubic Lagrange functions N_a(ξ), nodes at ξ = −1, −1/3, 1/3, 1. The material strains
of the Reissner–Simo beam at a point, with ' = d/ds along the reference arc length,

    Γ_i = d_i · x'                          (axial, shear 2, shear 3)
    K_1 = ½(d3·d2' − d2·d3'),  K_2 = ½(d1·d3' − d3·d1'),  K_3 = ½(d2·d1' − d1·d2')

are *quadratic* in the nodal coordinates, e_k = ½ Qᵀ h_k Q − e0_k with constant matrices h_k
(16 × 16 over the 16 nodal 3-vectors of an element, times I3). Three consequences drive this
module:

* the strain energy W = ½ ∫ (e − e0)ᵀ C (e − e0) ds has the exact discrete gradient
  ∫ B(q_m)ᵀ C (ē − e0) ds with ē the mean of the end-point strains, because e_f − e_i =
  B(q_m)(q_f − q_i) holds exactly for a quadratic e — so ``ep`` conserves energy (and linear
  and angular momentum, the strains being objective) exactly;
* the stiffness is Bᵀ C B + Σ_k S_k h_k with S = C (e − e0): no further derivative to code;
* the section kinetic energy ½ ∫ρ |ẋ + ξ2 ḋ2 + ξ3 ḋ3|² dA gives a *constant* mass matrix.

The strain-energy arithmetic (strains, stresses, force, material and geometric stiffness) is
compiled in :mod:`solver.beam_kernels`, loops over elements and points that use the sparse
structure of h_k (each strain a sum of terms c u_i·u_j' of the interpolated x, d_i).

Reference strains e0 are computed from the interpolated reference configuration itself, so a
curved or pre-twisted beam carries exactly zero force there. Joints and loads attach to a
beam's :class:`BeamNode` exactly as to a rigid body (its centre = the node, its frame = the
section frame).

Quadrature is segmented: the element is split at every section-property station it contains
(a root cuff, a hinge lump), each segment integrated with Gauss points. Stiffness uses 3 points
per segment — reduced integration for a uniform cubic element, which removes the membrane
locking of curved elements (at 6 elements the 45° bend's out-of-plane tip error is +0.01 %
against −0.10 % with full integration; Bathe & Bolourchi 1979) — mass 4 points per segment
(exact for piecewise-linear properties on a straight element). A straight element with more
than two segments is *condensed* (:class:`BeamSet`): its strain energy integrated exactly on 6
points coupled by precomputed weights, the exact value of what its segments' points
approximate (on the UH-60A blade 6 points an element instead of 24–36).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver import beam_kernels as kernels
from solver.beam_kernels import STRAIN_TERMS
from solver.bodies import orthonormality_rows
from solver.element import Element, ElementSet
from solver.quadratic import QuadraticSet
from solver.sections import SectionTable
from solver.state import SECOND, StateBlock

Array = NDArray[np.float64]
NODE_XI = np.array([-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0])
LOAD_NAMES = ("N", "V2", "V3", "T", "M2", "M3")
LOAD_UNITS = ("N", "N", "N", "N m", "N m", "N m")


def lagrange(xi: ArrayLike) -> tuple[Array, Array]:
    """Cubic Lagrange shape functions and their ξ-derivatives at ``xi``: (…, 4) each."""
    xi = np.asarray(xi, dtype=float)[..., None]
    n = np.ones((*xi.shape[:-1], 4))
    dn = np.zeros_like(n)
    for a in range(4):
        others = [b for b in range(4) if b != a]
        den = np.prod([NODE_XI[a] - NODE_XI[b] for b in others])
        fac = [(xi[..., 0] - NODE_XI[b]) for b in others]
        n[..., a] = fac[0] * fac[1] * fac[2] / den
        dn[..., a] = (fac[1] * fac[2] + fac[0] * fac[2] + fac[0] * fac[1]) / den
    return n, dn


def strain_matrices(n: Array, dn_ds: Array) -> Array:
    """The constant matrices h_k (…, 6, 16, 16) with e_k = ½ Σ h_k[α, β] Q_α·Q_β over the
    element's nodal 3-vectors Q_{4a+u} (node a, u = x, d1, d2, d3).

    The dense form of the strains, for analysis and as the tests' independent reference: the
    solver evaluates strains, forces and stiffness with the compiled kernels of
    :mod:`solver.beam_kernels`, which use the terms' structure instead of these matrices."""
    p = n[..., :, None] * dn_ds[..., None, :]  # P_ab = N_a N_b'
    h = np.zeros((*n.shape[:-1], 6, 4, 4, 4, 4))  # k, a, u, b, w
    for k, i, j, c in STRAIN_TERMS:
        h[..., k, :, i, :, j] += c * p
        h[..., k, :, j, :, i] += c * np.swapaxes(p, -1, -2)
    return h.reshape((*n.shape[:-1], 6, 16, 16))


def _unit(v: Array, what: str) -> Array:
    nv = np.linalg.norm(v)
    if not np.isfinite(nv) or nv < 1e-12:
        raise ValueError(f"{what} must be a non-zero finite vector, got {np.round(v, 9).tolist()}")
    return v / nv


@dataclass(eq=False)
class BeamNode(Element):
    """A node of a beam: joints and loads attach to it as to a rigid body (point = the node,
    frame = the section frame d1, d2, d3). Created by :class:`Beam`, not by users."""

    name: str
    beam: Beam
    index: int
    position: Array
    orientation: Array

    set_class = QuadraticSet
    quadratic_priority = 0  # orthonormality rows, like a rigid body's

    def quadratic_rows(self, qb, lay):
        return orthonormality_rows(qb, lay.offset[self]), {}


@dataclass(eq=False)
class Beam(Element):
    """A geometrically exact beam of cubic (4-node) elements.

    Use :func:`straight_beam` or :func:`arc_beam` to build one; this constructor takes the
    nodes directly.

    Parameters
    ----------
    name
        Unique name; the nodes are named ``name[k]``.
    points
        Reference (and initial) node positions (m), shape (3 n_elements + 1, 3); element e
        has nodes 3e … 3e + 3, the two inner ones equally spaced in arc length.
    frames
        Reference section frames at the nodes, (3 n_elements + 1, 3, 3), columns d1 (along
        the beam), d2, d3 (section axes); each a proper rotation.
    sections
        Section properties along the arc length (:class:`~solver.sections.SectionTable`); a
        table with stations must span the beam's length.
    velocity, angular_velocity, about
        Initial rigid motion (m/s, rad/s, m): ẋ = v + ω × (x − about), ḋ_i = ω × d_i.
        Projected onto the constraints before the first step.
    node_velocities, node_angular_velocities
        Optional extra initial velocities (m/s) and angular velocities (rad/s) of the nodes,
        (n_nodes, 3) each, e.g. to start a bending vibration with consistent section
        rotation rates.
    stiffness_points, mass_points
        Gauss points per segment for the internal force (3: reduced, recommended) and for
        the mass matrix (4).
    """

    name: str
    points: ArrayLike
    frames: ArrayLike
    sections: SectionTable
    velocity: ArrayLike = (0.0, 0.0, 0.0)
    angular_velocity: ArrayLike = (0.0, 0.0, 0.0)
    about: ArrayLike = (0.0, 0.0, 0.0)
    node_velocities: ArrayLike | None = None
    node_angular_velocities: ArrayLike | None = None
    stiffness_points: int = 3
    mass_points: int = 4
    nodes: list[BeamNode] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        owner = f"beam {self.name!r}"
        x = np.asarray(self.points, dtype=float)
        if x.ndim != 2 or x.shape[1] != 3 or len(x) < 4 or (len(x) - 1) % 3:
            raise ValueError(f"{owner}: points must have shape (3 n_elements + 1, 3), "
                             f"got {x.shape}")
        r = np.asarray(self.frames, dtype=float)
        if r.shape != (len(x), 3, 3):
            raise ValueError(f"{owner}: frames must have shape {(len(x), 3, 3)}, got {r.shape}")
        err = np.abs(np.einsum("nji,njk->nik", r, r) - np.eye(3)).max()
        if not np.all(np.isfinite(x)) or err > 1e-9 or np.any(np.linalg.det(r) < 0):
            raise ValueError(f"{owner}: frames must be proper rotations and points finite")
        if not isinstance(self.sections, SectionTable):
            raise TypeError(f"{owner}: sections must be a SectionTable")
        for k, n in (("stiffness_points", self.stiffness_points),
                     ("mass_points", self.mass_points)):
            if not (isinstance(n, int | np.integer) and 1 <= n <= 10):
                raise ValueError(f"{owner}: {k} = {n!r} must be an integer in 1…10")
        self.points, self.frames = x, r
        self.n_elements = (len(x) - 1) // 3
        # arc length of each element from its interpolated reference (8-point Gauss)
        xg, wg = np.polynomial.legendre.leggauss(8)
        _, dn = lagrange(xg)
        ell = np.array([wg @ np.linalg.norm(dn @ x[3 * e : 3 * e + 4], axis=1)
                        for e in range(self.n_elements)])
        self.element_ends = np.concatenate([[0.0], np.cumsum(ell)])
        self.length = float(self.element_ends[-1])
        tab = self.sections.length
        if np.isfinite(tab) and abs(tab - self.length) > 1e-6 * self.length:
            raise ValueError(f"{owner}: section stations end at {tab:.9g} m but the beam is "
                             f"{self.length:.9g} m long")
        self.node_s = np.concatenate([
            self.element_ends[e] + (NODE_XI[: 3 if e < self.n_elements - 1 else 4] + 1) / 2
            * ell[e] for e in range(self.n_elements)])
        self.nodes = [BeamNode(f"{self.name}[{k}]", self, k, x[k], r[k])
                      for k in range(len(x))]
        for k, v in (("velocity", self.velocity), ("angular_velocity", self.angular_velocity),
                     ("about", self.about)):
            a = np.asarray(v, dtype=float)
            if a.shape != (3,) or not np.all(np.isfinite(a)):
                raise ValueError(f"{owner}: {k} must be 3 finite numbers, got {v!r}")
            setattr(self, k, a)
        for k in ("node_velocities", "node_angular_velocities"):
            if getattr(self, k) is not None:
                nv = np.asarray(getattr(self, k), dtype=float)
                if nv.shape != x.shape or not np.all(np.isfinite(nv)):
                    raise ValueError(f"{owner}: {k} must be finite, shape {x.shape}")
                setattr(self, k, nv)

    # -- declarations -----------------------------------------------------------------------
    def parts(self) -> list[Element]:
        return list(self.nodes)

    @property
    def root(self) -> BeamNode:
        """First node (s = 0)."""
        return self.nodes[0]

    @property
    def tip(self) -> BeamNode:
        """Last node (s = length)."""
        return self.nodes[-1]

    def node_at(self, s: float) -> BeamNode:
        """The node at arc length ``s`` (m), which must be a node's position to 1e-9 L."""
        k = int(np.argmin(np.abs(self.node_s - s)))
        if abs(self.node_s[k] - s) > 1e-9 * self.length:
            raise ValueError(f"beam {self.name!r}: no node at s = {s!r} m; nodes at "
                             f"{np.round(self.node_s, 6).tolist()}")
        return self.nodes[k]

    def quadrature(self, points: int) -> dict[str, Array]:
        """Segmented Gauss quadrature: per point its element, ξ, arc length s (m) and the
        weight dξ (multiply by J = |dX/dξ| for ds). Segments split every element at the
        section-property stations inside it."""
        xg, wg = np.polynomial.legendre.leggauss(points)
        br = self.sections.breaks()
        el, xi, s, w = [], [], [], []
        for e in range(self.n_elements):
            s0, s1 = self.element_ends[e], self.element_ends[e + 1]
            cuts = br[(br > s0 + 1e-12 * self.length) & (br < s1 - 1e-12 * self.length)]
            edges = np.concatenate([[s0], cuts, [s1]])
            for a, b in itertools.pairwise(edges):
                sg = 0.5 * (a + b) + 0.5 * (b - a) * xg
                el.append(np.full(points, e))
                s.append(sg)
                xi.append(-1.0 + 2.0 * (sg - s0) / (s1 - s0))
                w.append(wg * (b - a) / (s1 - s0))
        return {"element": np.concatenate(el), "xi": np.concatenate(xi),
                "s": np.concatenate(s), "w": np.concatenate(w)}

    def _geometry(self, quad: dict[str, Array]) -> tuple[Array, Array, Array]:
        """Shape functions, their s-derivatives and ds weights at quadrature points."""
        n, dn = lagrange(quad["xi"])
        xe = self.points[3 * quad["element"][:, None] + np.arange(4)]  # (G, 4, 3)
        jac = np.linalg.norm(np.einsum("ga,gac->gc", dn, xe), axis=1)
        return n, dn / jac[:, None], quad["w"] * jac

    def mass_matrix(self) -> Array:
        """Consistent mass matrix of the 12 (n_nodes) coordinates, kg and kg·m units."""
        quad = self.quadrature(self.mass_points)
        n, _, wds = self._geometry(quad)
        mu = self.sections.director_inertia(quad["s"])  # (G, 4, 4)
        nn = len(self.nodes)
        m = np.zeros((nn, 4, nn, 4))
        for g, e in enumerate(quad["element"]):
            sl = slice(3 * e, 3 * e + 4)
            m[sl, :, sl, :] += wds[g] * np.einsum("a,b,uw->aubw", n[g], n[g], mu[g])
        m = m.reshape(4 * nn, 4 * nn)
        return np.kron(m, np.eye(3))

    def reference_coordinates(self) -> Array:
        """Reference nodal coordinates (n_nodes, 4, 3): x, d1, d2, d3 of each node (m, 1)."""
        return np.concatenate([self.points[:, None, :], np.swapaxes(self.frames, 1, 2)], axis=1)

    def states(self) -> list[StateBlock]:
        nn = len(self.nodes)
        q = self.reference_coordinates()
        w = self.angular_velocity
        rate = np.cross(w, q)
        rate[:, 0] = self.velocity + np.cross(w, self.points - self.about)
        if self.node_velocities is not None:
            rate[:, 0] += self.node_velocities
        if self.node_angular_velocities is not None:
            rate[:, 1:] += np.cross(self.node_angular_velocities[:, None, :], q[:, 1:])
        return [StateBlock(self, SECOND, 12 * nn, initial=q.ravel(), rate=rate.ravel(),
                           mass=self.mass_matrix(), units="m",
                           long_name=f"node positions and directors of beam {self.name}",
                           parts={node: 12 * k for k, node in enumerate(self.nodes)})]


# Points of a condensed element (BeamSet): on a straight element the strains are polynomials
# of degree 5 in ξ (cubic directors times the quadratic derivatives of cubic positions), fixed
# by their values at 6 points
CONDENSED_POINTS = 6


def _interpolating(nodes: Array, x: Array) -> Array:
    """The Lagrange polynomials of ``nodes`` at ``x``: (len(x), len(nodes))."""
    out = np.ones((len(x), len(nodes)))
    for m, xm in enumerate(nodes):
        for j, xj in enumerate(nodes):
            if j != m:
                out[:, m] *= (x - xj) / (xm - xj)
    return out


class BeamSet(ElementSet):
    """Strain energy of all beams of a model, by compiled loops over their quadrature points.

    The quadrature data sit in a padded stack per element (``width`` slots, the most points of
    any element; unused slots have zero shape functions and weights and are skipped), so the
    strains and weighted stresses of a point keep one slot. The arithmetic is in
    :mod:`solver.beam_kernels`: per point the interpolated x, d_i and their s-derivatives, the
    strains and the strain gradient B from the one strain-term table; the weighted stresses
    T_g = Σ_h (w C)_gh (e_h − e0_h), force Σ_g B_gᵀ T_g, material stiffness
    Σ_gh B_gᵀ (w C)_gh B_h (three nonzero strains per row of B), geometric stiffness
    (Σ_g T_g,k h_k) ⊗ I3.

    The weights (w C)_gh are block-diagonal, w_g C(s_g), on the segmented Gauss points of
    :meth:`Beam.quadrature`, except on a *condensed* element: a straight one whose segments
    (the section stations inside it) would give it more than :data:`CONDENSED_POINTS` points,
    at ``stiffness_points`` ≥ 3 a segment. Its strains, polynomials of degree 5 in ξ, are
    e(ξ) = Σ_g L_g(ξ) e_g through their values at 6 Gauss points, so that its energy is
    exactly ½ Σ_gh e_gᵀ W_gh e_h with W_gh = ∫ L_g L_h C ds over the element (integrated once,
    with 6 Gauss points a segment: exact for piecewise-linear properties): the exact integral
    of the segmented rule's integrand, on 6 points instead of 3 a segment (on the rotor's
    blades 6 instead of 24–36).
    """

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        idx: list[Array] = []
        # per element: N, N', (w C)_gh and whether it couples the points (condensed)
        points: list[tuple[Array, Array, Array, bool]] = []
        for b in elements:
            o = system.offset[b]
            idx.append(o + 36 * np.arange(b.n_elements)[:, None] + np.arange(48))
            quad = b.quadrature(b.stiffness_points)
            nb, dnb, wb = b._geometry(quad)
            cb = b.sections.at(quad["s"])["stiffness"]
            fine = None
            for e in range(b.n_elements):
                at = quad["element"] == e
                m = int(at.sum())
                if b.stiffness_points >= 3 and m > CONDENSED_POINTS:
                    if fine is None:
                        fine = b.quadrature(CONDENSED_POINTS)
                    cond = self._condensed(b, e, fine)
                    if cond is not None:
                        points.append((*cond, True))
                        continue
                wc = np.zeros((m, m, 6, 6))
                wc[np.arange(m), np.arange(m)] = wb[at, None, None] * cb[at]
                points.append((nb[at], dnb[at], wc, False))
        self.idx = np.concatenate(idx)  # (E, 48) global coordinates of each element
        n_el = len(points)
        self._count = np.array([len(p[0]) for p in points], dtype=np.int64)
        width = int(self._count.max())
        self._n = np.zeros((n_el, width, 4))  # shape functions
        self._dn = np.zeros((n_el, width, 4))  # their s-derivatives (1/m)
        self._wc = np.zeros((n_el, width, width, 6, 6))  # (w C)_gh (N m, N m2, N m3)
        for el, (n, dn, wc, _) in enumerate(points):
            c = len(n)
            self._n[el, :c], self._dn[el, :c], self._wc[el, :c, :c] = n, dn, wc
        self._dense = np.array([p[3] for p in points])
        self._e0 = np.zeros((n_el, width, 6))
        # reference strains: zero force there
        self._e0 = self._strains(system.q0_raw)[1].reshape(n_el, width, 6)
        self.grad_idx = self.idx.ravel()
        self.stiff_rows = np.repeat(self.idx, 48, axis=1).ravel()
        self.stiff_cols = np.tile(self.idx, (1, 48)).ravel()

    @staticmethod
    def _condensed(b: Beam, e: int, fine: dict[str, Array]
                   ) -> tuple[Array, Array, Array] | None:
        """Element ``e`` of beam ``b`` condensed (see the class docstring): its N and N' at the
        6 Gauss points and W_gh (6, 6, 6, 6), from ``fine``, ``b``'s quadrature at 6 points a
        segment; None if the element is not straight (its |dX/dξ| not constant, so that its
        strains are not polynomials)."""
        xg, _ = np.polynomial.legendre.leggauss(CONDENSED_POINTS)
        at = fine["element"] == e
        sub = {k: v[at] for k, v in fine.items()}
        _, _, wds = b._geometry(sub)
        jac = wds / sub["w"]
        if np.ptp(jac) > 1e-12 * jac.max():
            return None
        n, dn, _ = b._geometry({"element": np.full(CONDENSED_POINTS, e), "xi": xg,
                                "s": np.zeros(CONDENSED_POINTS),
                                "w": np.zeros(CONDENSED_POINTS)})
        lag = _interpolating(xg, sub["xi"])  # (F, 6)
        c = b.sections.at(sub["s"])["stiffness"]
        wc = np.einsum("f,fg,fh,fkl->ghkl", wds, lag, lag, c)
        return n, dn, wc

    def _element_vectors(self, q: Array) -> Array:
        """The nodal 3-vectors Q (E, 16, 3) of every element."""
        return q[self.idx].reshape(-1, 16, 3)

    def _strains(self, q: Array) -> tuple[Array, Array]:
        """Element vectors Q (E, 16, 3) and strains e − e0 in the padded point slots
        (E · width, 6)."""
        qe = self._element_vectors(q)
        e = kernels.strains(qe, self._n, self._dn, self._count, self._e0)
        return qe, e.reshape(-1, 6)

    def _stress(self, e: Array) -> Array:
        """Weighted stresses T_g = Σ_h (w C)_gh (e_h − e0_h) in the padded slots
        (E · width, 6)."""
        t = kernels.weighted_stresses(self._wc, self._dense, e.reshape(self._e0.shape),
                                      self._count)
        return t.reshape(-1, 6)

    def _stress_matrices(self, stress: Array) -> Array:
        """Σ over each element's points of Σ_k T_k h_k: (E, 16, 16)."""
        return kernels.stress_matrices(stress.reshape(self._e0.shape), self._n, self._dn,
                                       self._count)

    def _force(self, qe: Array, stress: Array) -> Array:
        """Σ_g B_gᵀ T_g per element, flattened on ``grad_idx``: B_k = h_k Q."""
        return kernels.force(qe, stress.reshape(self._e0.shape), self._n, self._dn,
                             self._count).ravel()

    def potential(self, q):
        _, e = self._strains(q)
        return 0.5 * float(np.sum(e * self._stress(e)))

    def gradient(self, q):
        # _force(qe, _stress(e)) of _strains(q), fused into one compiled pass
        return kernels.internal_force(self._element_vectors(q), self._n, self._dn, self._wc,
                                      self._dense, self._count, self._e0).ravel()

    def discrete_gradient(self, qi, qf):
        # e is quadratic in q: e_f − e_i = B(q_m)(q_f − q_i) exactly, so the midpoint B
        # with the mean stress is the exact discrete gradient of ½ eᵀCe.
        _, ei = self._strains(qi)
        _, ef = self._strains(qf)
        qm = self._element_vectors(0.5 * (qi + qf))
        return self._force(qm, self._stress(0.5 * (ei + ef)))

    def _material(self, qe: Array, qe_right: Array | None = None) -> Array:
        """Material stiffness Σ_gh B_gᵀ (w C)_gh B_h per element (E, 48, 48): positive
        semidefinite. With ``qe_right``, Σ_gh B_g(Q)ᵀ (w C)_gh B_h(Q_right)."""
        same = qe_right is None
        return kernels.material(qe, qe if same else qe_right, same, self._n, self._dn,
                                self._wc, self._dense, self._count)

    def _with_geometric(self, k: Array, stress: Array) -> Array:
        """k (E, 48, 48) plus the geometric stiffness of the weighted stresses:
        (Σ_g T_g,k h_k) ⊗ I3."""
        kernels.add_geometric(k, self._stress_matrices(stress))
        return k.ravel()

    def material_stiffness(self, q):
        return self._material(self._element_vectors(q)).ravel()

    def stiffness(self, q):
        qe, e = self._strains(q)
        return self._with_geometric(self._material(qe), self._stress(e))

    def discrete_stiffness(self, qi, qf):
        # ∂/∂q_f of B(q_m)ᵀ C (e_i + e_f)/2: ½ the geometric stiffness of the mean stress plus
        # ½ B(q_m)ᵀ C B(q_f). The midpoint Hessian instead would take the stress at q_m, which
        # differs by C times the strain's second difference: for a blade turning a few degrees
        # per step, more than the centrifugal tension itself.
        _, ei = self._strains(qi)
        _, ef = self._strains(qf)
        qm = self._element_vectors(0.5 * (qi + qf))
        k = 0.5 * self._material(qm, self._element_vectors(qf))
        return self._with_geometric(k, 0.25 * self._stress(ei + ef))


Beam.set_class = BeamSet


# ------------------------------------------------------------------------------- loads
class SectionProbe:
    """Stress resultants (N, V2, V3, T, M2, M3) of ``beam`` at fixed arc lengths ``s`` (m).

    Components are in the section frame (d1, d2, d3): axial force N, shear forces V2, V3 (N),
    torsion T and bending moments M2, M3 (N·m) — the material stress resultants
    S = C (e − e0). They are evaluated at the three Gauss points of each element, where the
    strains of the cubic interpolation are superconvergent (exact for a linear shear and a
    quadratic moment), and interpolated by the quadratic through them to ``s``, element ends
    included. At a constrained end the joint reaction is the exact load. The geometry is set
    up once; calling the probe with (system, q) costs one small batched product.
    """

    def __init__(self, beam: Beam, s: ArrayLike) -> None:
        s = np.atleast_1d(np.asarray(s, dtype=float))
        if np.any(s < -1e-12 * beam.length) or np.any(s > beam.length * (1 + 1e-12)):
            raise ValueError(f"beam {beam.name!r}: section positions must lie in 0 … "
                             f"{beam.length:.6g} m, got {s.tolist()}")
        e = np.clip(np.searchsorted(beam.element_ends, s, side="right") - 1, 0,
                    beam.n_elements - 1)
        s0, s1 = beam.element_ends[e], beam.element_ends[e + 1]
        xg = np.polynomial.legendre.leggauss(3)[0]
        el = np.repeat(e, 3)
        xi_g = np.tile(xg, len(s))
        quad = {"element": el, "xi": xi_g,
                "s": np.repeat(s0, 3) + (xi_g + 1) / 2 * np.repeat(s1 - s0, 3),
                "w": np.zeros(3 * len(s))}
        n, dn, _ = beam._geometry(quad)
        self.beam = beam
        # one point per slot for the compiled strain kernel (the same as BeamSet's)
        self.n, self.dn = n[:, None, :], dn[:, None, :]
        self.count = np.ones(len(n), dtype=np.int64)
        self.local = 36 * el[:, None] + np.arange(48)
        # C at each point, as the weighted-stress kernel's one-point blocks
        self.wc = beam.sections.at(quad["s"])["stiffness"][:, None, None]
        self.dense = np.zeros(len(n), dtype=bool)
        self.e0 = np.zeros((len(n), 1, 6))
        self.e0 = self._strains(beam.reference_coordinates().ravel()[self.local])
        # quadratic Lagrange interpolation through the Gauss points
        self.lag = _interpolating(xg, -1.0 + 2.0 * (s - s0) / (s1 - s0))

    def _strains(self, qloc: Array) -> Array:
        """Strains minus the reference ones (3 len(s), 1, 6) from the element vectors."""
        return kernels.strains(qloc.reshape(-1, 16, 3), self.n, self.dn, self.count, self.e0)

    def __call__(self, system, q: Array) -> Array:
        """(len(s), 6) resultants at the configuration q of ``system``."""
        e = self._strains(q[system.offset[self.beam] + self.local])
        stress = kernels.weighted_stresses(self.wc, self.dense, e, self.count)
        stress = stress.reshape(len(self.lag), 3, 6)
        return np.einsum("ga,gak->gk", self.lag, stress)


def section_loads(system, beam: Beam, q: Array, s: ArrayLike) -> Array:
    """Stress resultants (N, V2, V3, T, M2, M3) at arc lengths ``s`` (m) of ``beam``, section
    frame; see :class:`SectionProbe` (use one directly to sample the same points often).

    Returns
    -------
    array (len(s), 6)
    """
    return SectionProbe(beam, s)(system, q)


# ---------------------------------------------------------------------------- factories
def _frames_along(tangents: Array, e3: ArrayLike, twist: Array, owner: str) -> Array:
    """Section frames: d1 = tangent, d3 = the hint e3 made normal to it, d2 = d3 × d1, then
    both rotated by the twist angle (rad) about d1."""
    out = np.zeros((len(tangents), 3, 3))
    hint = _unit(np.asarray(e3, dtype=float), f"{owner}: e3")
    for k, t in enumerate(tangents):
        d1 = _unit(t, f"{owner}: tangent")
        d3 = hint - (hint @ d1) * d1
        if np.linalg.norm(d3) < 1e-8:
            raise ValueError(f"{owner}: e3 {hint.tolist()} is parallel to the beam axis")
        d3 /= np.linalg.norm(d3)
        d2 = np.cross(d3, d1)
        c, s = np.cos(twist[k]), np.sin(twist[k])
        out[k] = np.column_stack([d1, c * d2 + s * d3, -s * d2 + c * d3])
    return out


def _twist_values(twist, s: Array, owner: str) -> Array:
    if twist is None:
        return np.zeros_like(s)
    tw = np.asarray(twist(s) if callable(twist) else np.broadcast_to(twist, s.shape), float)
    if tw.shape != s.shape or not np.all(np.isfinite(tw)):
        raise ValueError(f"{owner}: twist must be a number or a function of arc length s (m) "
                         "giving finite angles (rad)")
    return tw


def _element_ends(length: float, n_elements: int | None, breaks: ArrayLike | None,
                  owner: str) -> Array:
    if breaks is not None:
        b = np.asarray(breaks, dtype=float)
        if (b.ndim != 1 or len(b) < 2 or abs(b[0]) > 1e-12 or abs(b[-1] - length) > 1e-9 * length
                or np.any(np.diff(b) <= 0)):
            raise ValueError(f"{owner}: breaks must increase from 0 to the length {length:g} m")
        return b
    if n_elements is None or not (isinstance(n_elements, int | np.integer) and n_elements >= 1):
        raise ValueError(f"{owner}: n_elements = {n_elements!r} must be an integer ≥ 1")
    return np.linspace(0.0, length, n_elements + 1)


def _node_arc(ends: Array) -> Array:
    return np.concatenate([e0 + (NODE_XI[:3] + 1) / 2 * (e1 - e0)
                           for e0, e1 in itertools.pairwise(ends)] + [ends[-1:]])


def straight_beam(name: str, start: ArrayLike, end: ArrayLike, sections: SectionTable, *,
                  n_elements: int | None = None, breaks: ArrayLike | None = None,
                  e3: ArrayLike = (0.0, 0.0, 1.0),
                  twist: float | Callable[[Array], Array] | None = None, **kw) -> Beam:
    """A straight beam from ``start`` to ``end`` (m).

    Parameters
    ----------
    n_elements, breaks
        Either the number of equal elements or the element ends as arc lengths (m) from 0 to
        the length (align them with property jumps and attachment points).
    e3
        Direction for the section axis d3 (made normal to the axis); d2 = d3 × d1.
    twist
        Pre-twist of the section axes about d1 (rad), a number or a function of s (m).
    **kw
        Passed to :class:`Beam` (initial motion, quadrature).
    """
    owner = f"beam {name!r}"
    a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    axis = _unit(b - a, f"{owner}: end − start")
    length = float(np.linalg.norm(b - a))
    s = _node_arc(_element_ends(length, n_elements, breaks, owner))
    frames = _frames_along(np.tile(axis, (len(s), 1)), e3, _twist_values(twist, s, owner), owner)
    return Beam(name, a + s[:, None] * axis, frames, sections, **kw)


def arc_beam(name: str, center: ArrayLike, radius: float, start: ArrayLike, angle: float,
             sections: SectionTable, *, n_elements: int | None = None,
             normal: ArrayLike = (0.0, 0.0, 1.0), **kw) -> Beam:
    """A circular arc of ``radius`` (m) about ``center`` (m), from the point ``start`` (m),
    turning by ``angle`` (rad, right-handed about ``normal``). Section axes: d1 the tangent,
    d3 = ``normal``, d2 = d3 × d1 (towards the centre for a positive angle)."""
    owner = f"beam {name!r}"
    if not (np.isfinite(radius) and radius > 0 and np.isfinite(angle) and angle != 0):
        raise ValueError(f"{owner}: radius {radius!r} m must be > 0 and angle {angle!r} rad ≠ 0")
    c, p0 = np.asarray(center, dtype=float), np.asarray(start, dtype=float)
    nrm = _unit(np.asarray(normal, dtype=float), f"{owner}: normal")
    r0 = p0 - c
    if abs(np.linalg.norm(r0) - radius) > 1e-9 * radius or abs(r0 @ nrm) > 1e-9 * radius:
        raise ValueError(f"{owner}: start must lie on the circle of radius {radius:g} m about "
                         "center, in the plane normal to normal")
    u = r0 / radius
    w = np.cross(nrm, u)
    length = abs(angle) * radius
    s = _node_arc(_element_ends(length, n_elements, None, owner))
    th = np.sign(angle) * s / radius
    pts = c + radius * (np.cos(th)[:, None] * u + np.sin(th)[:, None] * w)
    tan = np.sign(angle) * (-np.sin(th)[:, None] * u + np.cos(th)[:, None] * w)
    frames = _frames_along(tan, nrm, np.zeros_like(s), owner)
    return Beam(name, pts, frames, sections, **kw)


# ------------------------------------------------------------------------ distributed loads
@dataclass(eq=False)
class DistributedLoad(Element):
    """Dead distributed force (N/m) and moment (N·m/m) along a beam, global components.

    ``force`` and ``moment`` are functions ``(s, t) -> (len(s), 3)`` of the arc length s (m)
    and time t (s). They are integrated against the shape functions (consistent nodal loads)
    on the beam's mass quadrature; the moment acts as director forces ½ m × d_i, the virtual
    work of m·δφ with δφ = ½ Σ d_i × δd_i.
    """

    name: str
    beam: Beam
    force: Callable[[Array, float], ArrayLike] | None = None
    moment: Callable[[Array, float], ArrayLike] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.beam, Beam):
            raise TypeError(f"distributed load {self.name!r}: beam must be a Beam")
        if self.force is None and self.moment is None:
            raise ValueError(f"distributed load {self.name!r}: give a force or a moment")


class DistributedLoadSet(ElementSet):
    """Consistent nodal loads of distributed loads, vectorized over quadrature points."""

    nonconservative = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        self.parts = []
        idx, fq_r, fq_c = [], [], []
        for ld in elements:
            b = ld.beam
            quad = b.quadrature(b.mass_points)
            n, _, wds = b._geometry(quad)
            el_idx = (system.offset[b] + 36 * quad["element"][:, None, None]
                      + 12 * np.arange(4)[None, :, None] + np.arange(12))  # (G, 4, 12)
            self.parts.append((ld, quad["s"], n, n * wds[:, None], el_idx))
            idx.append(el_idx.ravel())
            if ld.moment is not None:
                d = el_idx[:, :, 3:].reshape(-1, 4, 3, 3)  # G, node a, director, comp
                # ∂f(d_i,a)/∂d_i,b: rows (a, i, comp r), cols (b, i, comp c)
                r = np.broadcast_to(d[:, :, None, :, :, None], (len(d), 4, 4, 3, 3, 3))
                c = np.broadcast_to(d[:, None, :, :, None, :], (len(d), 4, 4, 3, 3, 3))
                fq_r.append(r.ravel())
                fq_c.append(c.ravel())
        self.force_idx = np.concatenate(idx)
        self.fq_rows = np.concatenate(fq_r) if fq_r else self.fq_rows
        self.fq_cols = np.concatenate(fq_c) if fq_c else self.fq_cols

    @staticmethod
    def _field(fun, s, t, what, name) -> Array:
        a = np.asarray(fun(s, t), dtype=float)
        if a.shape != (len(s), 3) or not np.all(np.isfinite(a)):
            raise ValueError(f"distributed load {name!r}: {what}(s, t) must return finite "
                             f"values of shape {(len(s), 3)}, got {a.shape}")
        return a

    def force(self, q, v, t):
        out = []
        for ld, s, n, nw, el_idx in self.parts:
            f = np.zeros((*el_idx.shape[:2], 4, 3))  # G, node, (x, d1, d2, d3), comp
            if ld.force is not None:
                fd = self._field(ld.force, s, t, "force", ld.name)
                f[:, :, 0] = nw[:, :, None] * fd[:, None]
            if ld.moment is not None:
                m = self._field(ld.moment, s, t, "moment", ld.name)
                dq = q[el_idx[:, :, 3:]].reshape(-1, 4, 3, 3)
                d = np.einsum("ga,gaic->gic", n, dq)
                # director force density ½ m × d_i (d_i interpolated), times N_a w ds
                fd = 0.5 * np.cross(m[:, None, :], d)  # G, i, comp
                f[:, :, 1:] += nw[:, :, None, None] * fd[:, None]
            out.append(f.ravel())
        return np.concatenate(out)

    def force_jacobians(self, q, v, t):
        out = []
        for ld, s, n, nw, _ in self.parts:
            if ld.moment is None:
                continue
            m = self._field(ld.moment, s, t, "moment", ld.name)
            sk = np.zeros((len(m), 3, 3))
            sk[:, 0, 1], sk[:, 0, 2], sk[:, 1, 2] = -m[:, 2], m[:, 1], -m[:, 0]
            sk -= np.swapaxes(sk, 1, 2)
            # f(d_i,a) = ½ N_a w m × Σ_b N_b d_i,b: block (a, b) = ½ w N_a N_b skew(m)
            nn = nw[:, :, None] * n[:, None, :]
            blk = 0.5 * nn[:, :, :, None, None, None] * sk[:, None, None, None, :, :]
            out.append(np.broadcast_to(blk, (len(m), 4, 4, 3, 3, 3)).ravel())
        return (np.concatenate(out) if out else np.zeros(0)), np.zeros(0)


DistributedLoad.set_class = DistributedLoadSet
