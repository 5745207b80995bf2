"""The compiled beam strain-energy kernels (solver/beam_kernels.py) against independent
computations: the dense strain matrices h_k (e_k = ½ Qᵀ h_k Q, built from the shape functions
by ``strain_matrices``), central finite differences of the energy and of the gradient, and the
exact identity of the discrete gradient.

The beams are chosen to exercise what the kernels' bookkeeping could get wrong: a fully
coupled, non-diagonal section (every C_kl), a curved reference (Jacobian varying along the
element), pre-twist, and section stations inside elements, so that elements have different
numbers of quadrature points and the padded slots are used.
"""

from __future__ import annotations

import numpy as np
import pytest

from solver.beams import (
    CONDENSED_POINTS,
    BeamSet,
    arc_beam,
    section_loads,
    straight_beam,
    strain_matrices,
)
from solver.model import Model
from solver.sections import SectionTable
from solver.system import System


def coupled_stiffness(rng, scale: float = 1.0) -> np.ndarray:
    a = rng.normal(size=(6, 6))
    return scale * (a @ a.T + 6 * np.eye(6))


def stepped_beam() -> Model:
    """Straight (3 m), pre-twisted, 3 elements; a coupled section that changes at stations
    inside the first and last elements: 6, 3 and 9 stiffness points per element."""
    rng = np.random.default_rng(3)
    c = np.stack([coupled_stiffness(rng, f) for f in (1.0, 1.0, 2.0, 2.0, 0.5, 0.5, 3.0, 3.0)])
    sec = SectionTable([0.0, 0.7, 0.7, 2.2, 2.2, 2.6, 2.6, 3.0], c, mass=1.0)
    return Model([straight_beam("b", (0.2, -0.1, 0.3), (2.2, 1.9, 1.3), sec, n_elements=3,
                                e3=(0.0, 0.2, 1.0), twist=lambda s: 0.3 * s)])


def curved_beam() -> Model:
    rng = np.random.default_rng(0)
    sec = SectionTable([0.0], coupled_stiffness(rng), mass=2.0, cg=(0.1, 0.05),
                       inertia=(0.3, 0.2, 0.01))
    return Model([arc_beam("b", (0, 1, 0), 1.0, (0, 0, 0), 1.0, sec, n_elements=2)])


MODELS = {"stepped": stepped_beam, "curved": curved_beam}


def setup(name):
    s = System(MODELS[name]())
    (bs,) = [x for x in s.sets if isinstance(x, BeamSet)]
    return s, bs


def condensed(beam) -> list[int]:
    """The elements BeamSet condenses: those with more than CONDENSED_POINTS points of the
    segmented 3-point rule (all straight here: the arc's elements have 3)."""
    quad = beam.quadrature(beam.stiffness_points)
    counts = np.bincount(quad["element"], minlength=beam.n_elements)
    return [e for e in range(beam.n_elements) if counts[e] > CONDENSED_POINTS]


def dense_reference(system, beam, q, qr=None):
    """Energy, strains at the kernels' points (G, 6), gradient (E, 48), material stiffness
    Σ B(Q)ᵀ wC B(Q_r) and geometric stiffness (Σ w S_k h_k) ⊗ I3 (E, 48, 48) from the dense
    h_k, point by point in plain NumPy (no padding, no kernels): on the segmented 3-point
    rule, and on a condensed element by 8 Gauss points a segment (exact for its strain energy's
    integrand, of degree 11 with piecewise-linear properties), the strains there at the 6
    Gauss points of the element."""
    quad = beam.quadrature(beam.stiffness_points)
    fine = beam.quadrature(8)
    dense = condensed(beam)
    keep = ~np.isin(quad["element"], dense)
    take = np.isin(fine["element"], dense)
    quad = {k: np.concatenate([quad[k][keep], fine[k][take]]) for k in quad}
    order = np.argsort(quad["element"], kind="stable")
    quad = {k: v[order] for k, v in quad.items()}
    n, dn, wds = beam._geometry(quad)
    h = strain_matrices(n, dn)  # (G, 6, 16, 16)
    c = beam.sections.at(quad["s"])["stiffness"]
    idx = system.offset[beam] + 36 * quad["element"][:, None] + np.arange(48)

    def vectors(qq, ix=idx):
        return qq[ix].reshape(-1, 16, 3)

    def strain(v, hh=h):
        return 0.5 * np.einsum("gkab,gac,gbc->gk", hh, v, v)

    v = vectors(q)
    e = strain(v) - strain(vectors(system.q0_raw))
    stress = np.einsum("gkl,gl->gk", c, e)
    b = np.einsum("gkab,gbc->gkac", h, v).reshape(-1, 6, 48)  # B_k = h_k Q
    br = b if qr is None else np.einsum("gkab,gbc->gkac", h, vectors(qr)).reshape(-1, 6, 48)
    energy = 0.5 * np.einsum("g,gk,gk->", wds, e, stress)
    grad = np.zeros((beam.n_elements, 48))
    mat = np.zeros((beam.n_elements, 48, 48))
    geo = np.zeros((beam.n_elements, 48, 48))
    for g, el in enumerate(quad["element"]):
        grad[el] += wds[g] * b[g].T @ stress[g]
        mat[el] += wds[g] * b[g].T @ c[g] @ br[g]
        geo[el] += np.kron(np.einsum("k,kab->ab", wds[g] * stress[g], h[g]), np.eye(3))
    # the strains at the kernels' points: the 3-point rule's, and on a condensed element its
    # 6 Gauss points
    pts = {k: v[keep] for k, v in beam.quadrature(beam.stiffness_points).items()}
    xg = np.polynomial.legendre.leggauss(CONDENSED_POINTS)[0]
    for el in dense:
        add = {"element": np.full(len(xg), el), "xi": xg, "s": np.zeros(len(xg)),
               "w": np.zeros(len(xg))}
        pts = {k: np.concatenate([pts[k], add[k]]) for k in pts}
    order = np.argsort(pts["element"], kind="stable")
    pts = {k: v[order] for k, v in pts.items()}
    hp = strain_matrices(*beam._geometry(pts)[:2])
    ip = system.offset[beam] + 36 * pts["element"][:, None] + np.arange(48)
    e_points = strain(vectors(q, ip), hp) - strain(vectors(system.q0_raw, ip), hp)
    return energy, e_points, grad, mat, geo


@pytest.mark.parametrize("name", MODELS)
def test_kernels_match_dense_strain_matrices(name):
    """Energy, strains, gradient, stiffness (material + geometric) and the mixed material
    stiffness B(Q)ᵀ C B(Q_r) against the dense h_k products: measured ≤ 6e-15 relative (the
    strains of the stepped beam; the rest ≤ 4e-15)."""
    s, bs = setup(name)
    (beam,) = bs.elements
    rng = np.random.default_rng(7)
    q = s.q0_raw + 0.05 * rng.normal(size=s.n)
    qr = q + 0.05 * rng.normal(size=s.n)
    energy, e, grad, mat, geo = dense_reference(s, beam, q)
    # the stepped beam's last element (9 points of the 3-point rule) is condensed
    assert list(np.flatnonzero(bs._dense)) == condensed(beam) == ([2] if name == "stepped"
                                                                  else [])
    assert bs.potential(q) == pytest.approx(energy, rel=1e-13)
    # strains: the kernel's real slots, in the order of the quadrature; padding stays zero
    _, ek = bs._strains(q)
    width = bs._e0.shape[1]
    real = np.concatenate([np.arange(c) + i * width for i, c in enumerate(bs._count)])
    assert (len(real) < len(ek)) == (name == "stepped")  # stepped: padding used
    assert np.abs(ek[real] - e).max() <= 1e-13 * np.abs(e).max()
    assert np.abs(np.delete(ek, real, axis=0)).max(initial=0.0) == 0.0
    g = bs.gradient(q).reshape(-1, 48)
    assert np.abs(g - grad).max() <= 1e-13 * np.abs(grad).max()
    k = bs.stiffness(q).reshape(-1, 48, 48)
    assert np.abs(k - (mat + geo)).max() <= 1e-13 * np.abs(mat + geo).max()
    mixed = dense_reference(s, beam, q, qr)[3]
    km = bs._material(bs._element_vectors(q), bs._element_vectors(qr))
    assert np.abs(km - mixed).max() <= 1e-13 * np.abs(mixed).max()


@pytest.mark.parametrize("name", MODELS)
def test_gradient_and_stiffness_against_finite_differences(name):
    """Gradient against central differences of the energy (measured ≤ 1.9e-10 relative, the
    O(ε²) truncation and roundoff of ε = 1e-6), stiffness against central differences of the
    gradient (≤ 1.2e-10), the discrete stiffness against differences of the discrete gradient
    in q_f (≤ 1.3e-10); the material stiffness symmetric (1.3e-16) and semidefinite."""
    s, bs = setup(name)
    rng = np.random.default_rng(11)
    q = s.q0_raw + 0.05 * rng.normal(size=s.n)
    qf = q + 0.05 * rng.normal(size=s.n)
    eps = 1e-6
    eye = np.eye(s.n)
    rows, cols = bs.stiff_rows, bs.stiff_cols

    def dense(vals):
        k = np.zeros((s.n, s.n))
        np.add.at(k, (rows, cols), vals)
        return k

    def grad(x):
        out = np.zeros(s.n)
        np.add.at(out, bs.grad_idx, bs.gradient(x))
        return out

    def dgrad(x):
        out = np.zeros(s.n)
        np.add.at(out, bs.grad_idx, bs.discrete_gradient(q, x))
        return out

    gfd = np.array([(bs.potential(q + eps * d) - bs.potential(q - eps * d)) / (2 * eps)
                    for d in eye])
    g = grad(q)
    assert np.abs(g - gfd).max() < 3e-9 * np.abs(g).max()
    kfd = np.array([(grad(q + eps * d) - grad(q - eps * d)) / (2 * eps) for d in eye]).T
    k = dense(bs.stiffness(q))
    assert np.abs(k - kfd).max() < 3e-9 * np.abs(k).max()
    km = dense(bs.material_stiffness(q))
    assert np.abs(km - km.T).max() <= 1e-13 * np.abs(km).max()  # symmetric sections
    assert np.linalg.eigvalsh(0.5 * (km + km.T)).min() > -1e-13 * np.abs(km).max()
    dfd = np.array([(dgrad(qf + eps * d) - dgrad(qf - eps * d)) / (2 * eps) for d in eye]).T
    kd = dense(bs.discrete_stiffness(q, qf))
    assert np.abs(kd - dfd).max() < 3e-9 * np.abs(kd).max()


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("size", [1e-3, 0.3])
def test_discrete_gradient_identity(name, size):
    """dg(q_i, q_f)·(q_f − q_i) = V(q_f) − V(q_i) for small and large steps: measured
    ≤ 8e-16 relative to the larger energy."""
    s, bs = setup(name)
    rng = np.random.default_rng(5)
    qi = s.q0_raw + 0.1 * rng.normal(size=s.n)
    qf = qi + size * rng.normal(size=s.n)
    dq = (qf - qi)[bs.grad_idx]
    de = bs.discrete_gradient(qi, qf) @ dq
    vi, vf = bs.potential(qi), bs.potential(qf)
    assert abs(de - (vf - vi)) <= 1e-14 * max(abs(vi), abs(vf))
    # and at q_f = q_i it is the gradient
    assert np.array_equal(bs.discrete_gradient(qi, qi), bs.gradient(qi))


def test_reference_is_stress_free_and_section_loads_use_the_same_strains():
    """Zero force and energy in the reference; the section probe's resultants at the Gauss
    points equal C (e − e0) of the dense strain matrices (measured 2.5e-15 relative)."""
    s, bs = setup("stepped")
    (beam,) = bs.elements
    assert np.abs(bs.gradient(s.q0_raw)).max() == 0.0 and bs.potential(s.q0_raw) == 0.0
    rng = np.random.default_rng(2)
    q = s.q0_raw + 0.05 * rng.normal(size=s.n)
    # the three Gauss points of element 1 (a uniform piece of section: 1.0 … 2.0 m)
    ends = beam.element_ends
    xg = np.polynomial.legendre.leggauss(3)[0]
    sg = ends[1] + (xg + 1) / 2 * (ends[2] - ends[1])
    loads = section_loads(s, beam, q, sg)
    quad = {"element": np.ones(3, dtype=int), "xi": xg, "s": sg, "w": np.zeros(3)}
    n, dn, _ = beam._geometry(quad)
    h = strain_matrices(n, dn)
    idx = s.offset[beam] + 36 + np.arange(48)
    v, v0 = q[idx].reshape(16, 3), s.q0_raw[idx].reshape(16, 3)
    e = 0.5 * (np.einsum("gkab,ac,bc->gk", h, v, v) - np.einsum("gkab,ac,bc->gk", h, v0, v0))
    ref = np.einsum("gkl,gl->gk", beam.sections.at(sg)["stiffness"], e)
    assert np.abs(loads - ref).max() <= 1e-13 * np.abs(ref).max()
