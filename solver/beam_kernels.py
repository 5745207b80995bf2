"""Compiled strain-energy kernels of the geometrically exact beam (:mod:`solver.beams`).

The strains of the director beam are quadratic in the nodal coordinates: at a point of an
element with cubic shape functions N_a and their arc-length derivatives N_a' (1/m), the
interpolated vectors

    u_i = Σ_a N_a Q_{4a+i},   v_i = u_i' = Σ_a N_a' Q_{4a+i}      (i = 0: x, 1…3: d1…d3)

give every strain as a sum of terms c u_i·v_j (the table :data:`STRAIN_TERMS`):

    Γ_i = d_i·x',  K_1 = ½(d3·d2' − d2·d3'),  K_2 = ½(d1·d3' − d3·d1'),  K_3 = ½(d2·d1' − d1·d2').

Written with the element's constant 16 × 16 matrices h_k (``solver.beams.strain_matrices``),
e_k = ½ Qᵀ h_k Q; the NumPy implementation this module replaced evaluated exactly that, as
batched products of the dense 256-long h_k with the element Gram matrix Q Qᵀ over padded
quadrature slots: most of a rotor step's time. Here each quantity is one compiled loop over
elements and their points that uses the structure instead, every formula derived from the one
term table:

* strain e_k: 2 × 48 multiply-adds to interpolate u, v, then 9 dot products;
* strain gradient B_k = ∂e_k/∂Q (6 × 48): term (k, i, j, c) puts c N_a v_j on node a's
  vector i and c N_a' u_i on its vector j — half of B's entries are structurally zero;
* force ∫ Bᵀ S ds without forming B; material stiffness ∫ Bᵀ C B_r ds, where each row of B
  has only three nonzero strains (3 × 48² multiply-adds a point instead of 6 × 48²); the
  geometric stiffness Σ_k S_k h_k ⊗ I3 with the points summed first, per strain, and spread
  over h_k's terms once per element.

Layout (that of :class:`solver.beams.BeamSet`): element vectors Q are (E, 16, 3), node a's
vector u at row 4a + u; a 48-long coordinate index is 3(4a + u) + component. Quadrature data
are padded per element to W slots: ``n``, ``dn`` (E, W, 4) the shape functions and their
s-derivatives (1/m), ``wc`` (E, W, W, 6, 6) the weighted section stiffness (w C)_gh coupling
the points g and h (block-diagonal, w_g C_g, unless the element is ``dense``: condensed),
``count`` (E,) the number of real points of each element (the rest are left zero in every
output). The kernels take the weighted stresses T_g = Σ_h (w C)_gh (e_h − e0_h) where a
point's stress resultants times its weight would go.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from solver.jit import njit

Array = NDArray[np.float64]
IArray = NDArray[np.int64]
BArray = NDArray[np.bool_]

# (strain k, vector i, vector j, coefficient c): e_k gets c·(u_i · u_j') where u_0 = x and
# u_1..3 = d1..3.  Γ_i = d_i·x';  K_1 = ½(d3·d2' − d2·d3') etc. The one definition of the
# strains: the kernels below and ``solver.beams.strain_matrices`` all read it.
STRAIN_TERMS = (
    (0, 1, 0, 1.0), (1, 2, 0, 1.0), (2, 3, 0, 1.0),
    (3, 3, 2, 0.5), (3, 2, 3, -0.5),
    (4, 1, 3, 0.5), (4, 3, 1, -0.5),
    (5, 2, 1, 0.5), (5, 1, 2, -0.5),
)
# the table as arrays (numba freezes module-level arrays into the compiled code)
_TK = np.array([t[0] for t in STRAIN_TERMS], dtype=np.int64)
_TI = np.array([t[1] for t in STRAIN_TERMS], dtype=np.int64)
_TJ = np.array([t[2] for t in STRAIN_TERMS], dtype=np.int64)
_TC = np.array([t[3] for t in STRAIN_TERMS], dtype=np.float64)


def _strains_of() -> IArray:
    """(4, 3): for each nodal vector u (x, d1, d2, d3) the strains whose terms contain it.

    x is in the three Γ_i (through x'), d_i in Γ_i and the two curvatures about the other
    axes: three each, which :func:`material` unrolls."""
    sets = [sorted({t[0] for t in STRAIN_TERMS if u in (t[1], t[2])}) for u in range(4)]
    if any(len(x) != 3 for x in sets):
        raise ValueError(f"material() assumes three strains per nodal vector, got {sets}")
    return np.array(sets, dtype=np.int64)


# the nonzero rows of B: the derivative of e_k by node a's vector u vanishes unless k is here
_STRAINS_OF = _strains_of()


@njit(cache=True)
def _interpolate(qe: Array, n: Array, dn: Array, u: Array, v: Array) -> None:
    """u_i = Σ_a N_a Q_{4a+i} (m, 1) and v_i = Σ_a N_a' Q_{4a+i} (1, 1/m) into (4, 3) each."""
    for i in range(4):
        for c in range(3):
            su = 0.0
            sv = 0.0
            for a in range(4):
                qa = qe[4 * a + i, c]
                su += n[a] * qa
                sv += dn[a] * qa
            u[i, c] = su
            v[i, c] = sv


@njit(cache=True)
def _point_strains(u: Array, v: Array, e0: Array, out: Array) -> None:
    """out = e − e0 (6,) at a point: e_k = Σ_terms c u_i·v_j (1 and 1/m)."""
    for k in range(6):
        out[k] = 0.0
    for t in range(_TK.shape[0]):
        i, j = _TI[t], _TJ[t]
        out[_TK[t]] += _TC[t] * (u[i, 0] * v[j, 0] + u[i, 1] * v[j, 1] + u[i, 2] * v[j, 2])
    for k in range(6):
        out[k] -= e0[k]


@njit(cache=True)
def _strain_gradient(n: Array, dn: Array, u: Array, v: Array, ab: Array, b: Array) -> None:
    """B = ∂e/∂Q (6, 48) at a point: B_k[node a, vector w] = N_a α_kw + N_a' β_kw, where term
    (k, i, j, c) of e_k = c u_i·v_j adds c v_j to α_ki and c u_i to β_kj. ``ab`` (2, 6, 4, 3)
    is scratch for α, β; B's entries for vectors outside e_k come out as exact zeros."""
    ab[:, :, :, :] = 0.0
    for t in range(_TK.shape[0]):
        k, i, j, c = _TK[t], _TI[t], _TJ[t], _TC[t]
        for comp in range(3):
            ab[0, k, i, comp] += c * v[j, comp]
            ab[1, k, j, comp] += c * u[i, comp]
    for k in range(6):
        for a in range(4):
            for w in range(4):
                r = 3 * (4 * a + w)
                for comp in range(3):
                    b[k, r + comp] = n[a] * ab[0, k, w, comp] + dn[a] * ab[1, k, w, comp]


@njit(cache=True)
def strains(qe: Array, n: Array, dn: Array, count: IArray, e0: Array) -> Array:
    """Strains minus the reference strains, e − e0 (E, W, 6), at every element's points.

    Parameters
    ----------
    qe : (E, 16, 3) element vectors (m for x, 1 for the directors).
    n, dn, count : shape functions, their s-derivatives (1/m), real points per element.
    e0 : (E, W, 6) reference strains (zero for a configuration measured from nothing).
    """
    ne, nw = n.shape[0], n.shape[1]
    e = np.zeros((ne, nw, 6))
    u = np.empty((4, 3))
    v = np.empty((4, 3))
    for el in range(ne):
        for g in range(count[el]):
            _interpolate(qe[el], n[el, g], dn[el, g], u, v)
            _point_strains(u, v, e0[el, g], e[el, g])
    return e


@njit(cache=True)
def _point_weighted_stress(wc: Array, dense: bool, e: Array, c: int, g: int,
                           out: Array) -> None:
    """out (6,) = T_g = Σ_h (w C)_gh (e_h − e0_h) of one element (``wc`` its (W, W, 6, 6)
    weights, ``e`` its (W, 6) strains, ``c`` its real points): over every h on a ``dense``
    element, over h = g alone otherwise."""
    lo, hi = (0, c) if dense else (g, g + 1)
    for k in range(6):
        acc = 0.0
        for h in range(lo, hi):
            for m in range(6):
                acc += wc[g, h, k, m] * e[h, m]
        out[k] = acc


@njit(cache=True)
def weighted_stresses(wc: Array, dense: BArray, e: Array, count: IArray) -> Array:
    """T_g = Σ_h (w C)_gh (e_h − e0_h) (E, W, 6), N·m and N·m² (the stress resultants times
    their ds weight): on an element that is not ``dense`` (w C) is block-diagonal over its
    points, T_g = w_g C_g (e_g − e0_g); on a dense one (condensed, see
    :class:`solver.beams.BeamSet`) it couples them."""
    t = np.zeros(e.shape)
    for el in range(e.shape[0]):
        for g in range(count[el]):
            _point_weighted_stress(wc[el], dense[el], e[el], count[el], g, t[el, g])
    return t


@njit(cache=True)
def _add_point_force(n: Array, dn: Array, u: Array, v: Array, ws: Array, fg: Array,
                     f: Array) -> None:
    """f (48,) += Bᵀ T at a point (T its weighted stress), without forming B: node a's vector
    x gets N_a F_x + N_a' G_x, where term (k, i, j, c) adds c T_k v_j to F_i and c T_k u_i to
    G_j (:func:`_strain_gradient`'s α and β contracted with T). ``fg`` (2, 4, 3) scratch."""
    fg[:, :, :] = 0.0
    for t in range(_TK.shape[0]):
        i, j = _TI[t], _TJ[t]
        cs = _TC[t] * ws[_TK[t]]
        for comp in range(3):
            fg[0, i, comp] += cs * v[j, comp]
            fg[1, j, comp] += cs * u[i, comp]
    for a in range(4):
        for x in range(4):
            r = 3 * (4 * a + x)
            for comp in range(3):
                f[r + comp] += n[a] * fg[0, x, comp] + dn[a] * fg[1, x, comp]


@njit(cache=True)
def force(qe: Array, t: Array, n: Array, dn: Array, count: IArray) -> Array:
    """Internal force Σ_g B_g(Q)ᵀ T_g per element (E, 48), T the weighted stresses
    (:func:`weighted_stresses`): N on x, N·m on the directors.

    With T of the mean of two end-point strains and Q the midpoint this is the exact discrete
    gradient (the strains are quadratic: e_f − e_i = B(Q_m)(Q_f − Q_i))."""
    ne = qe.shape[0]
    f = np.zeros((ne, 48))
    u = np.empty((4, 3))
    v = np.empty((4, 3))
    fg = np.empty((2, 4, 3))
    for el in range(ne):
        for g in range(count[el]):
            _interpolate(qe[el], n[el, g], dn[el, g], u, v)
            _add_point_force(n[el, g], dn[el, g], u, v, t[el, g], fg, f[el])
    return f


@njit(cache=True)
def internal_force(qe: Array, n: Array, dn: Array, wc: Array, dense: BArray, count: IArray,
                   e0: Array) -> Array:
    """The gradient of the strain energy, Σ_g B_gᵀ T_g per element (E, 48), in one pass:
    :func:`strains`, :func:`weighted_stresses` and :func:`force` fused (one interpolation a
    point)."""
    ne, nw = qe.shape[0], n.shape[1]
    f = np.zeros((ne, 48))
    u = np.empty((nw, 4, 3))
    v = np.empty((nw, 4, 3))
    fg = np.empty((2, 4, 3))
    e = np.empty((nw, 6))
    ws = np.empty(6)
    for el in range(ne):
        c = count[el]
        for g in range(c):
            _interpolate(qe[el], n[el, g], dn[el, g], u[g], v[g])
            _point_strains(u[g], v[g], e0[el, g], e[g])
        for g in range(c):
            _point_weighted_stress(wc[el], dense[el], e, c, g, ws)
            _add_point_force(n[el, g], dn[el, g], u[g], v[g], ws, fg, f[el])
    return f


@njit(cache=True)
def stress_matrices(t: Array, n: Array, dn: Array, count: IArray) -> Array:
    """Σ over each element's points of Σ_k T_k h_k (E, 16, 16), T the weighted stresses
    (:func:`weighted_stresses`), N and N·m: the geometric stiffness is this times I3.

    Term (k, i, j, c) of h_k holds c N_a N_b' at (4a + i, 4b + j) and c N_a' N_b at
    (4a + j, 4b + i) (the second derivative of c u_i·v_j). The points' sum is taken first,
    A_k[a, b] = Σ_g T_k N_a N_b', and spread over the terms once per element."""
    ne = t.shape[0]
    hs = np.zeros((ne, 16, 16))
    acc = np.empty((6, 4, 4))
    for el in range(ne):
        acc[:, :, :] = 0.0
        for g in range(count[el]):
            na, da = n[el, g], dn[el, g]
            for k in range(6):
                ws = t[el, g, k]
                for a in range(4):
                    wn = ws * na[a]
                    for bb in range(4):
                        acc[k, a, bb] += wn * da[bb]
        for tt in range(_TK.shape[0]):
            k, i, j, c = _TK[tt], _TI[tt], _TJ[tt], _TC[tt]
            for a in range(4):
                for bb in range(4):
                    hs[el, 4 * a + i, 4 * bb + j] += c * acc[k, a, bb]
                    hs[el, 4 * a + j, 4 * bb + i] += c * acc[k, bb, a]
    return hs


@njit(cache=True)
def material(qe: Array, qr: Array, same: bool, n: Array, dn: Array, wc: Array,
             dense: BArray, count: IArray) -> Array:
    """Material stiffness Σ_gh B_g(Q)ᵀ (w C)_gh B_h(Q_r) per element (E, 48, 48) ((w C)
    block-diagonal over the points of an element that is not ``dense``).

    ``same`` says Q_r is Q: B is built once, and the matrix is symmetric (as every section
    stiffness is, :class:`~solver.sections.SectionTable`), so only its entries on and right
    of each row triplet's diagonal block are summed and the rest mirrored, about half the
    multiply-adds. B is sparse by structure: the three rows of node a's vector u (its
    components) are nonzero only for the three strains that contain u (``_STRAINS_OF``), so
    (w C) B_r needs three products per entry and each point adds, to those three rows of the
    element matrix at once, three rank-1 terms: 3 × 48² multiply-adds a point instead of the
    dense 6 × 48², with each (w C) B_r entry loaded once for the three rows."""
    ne, nw = qe.shape[0], n.shape[1]
    k = np.zeros((ne, 48, 48))
    u = np.empty((4, 3))
    v = np.empty((4, 3))
    ab = np.empty((2, 6, 4, 3))
    b = np.empty((nw, 6, 48))
    br = np.empty((nw, 6, 48))
    cb = np.empty((6, 48))
    for el in range(ne):
        ke = k[el]
        c = count[el]
        for g in range(c):
            na, da = n[el, g], dn[el, g]
            _interpolate(qe[el], na, da, u, v)
            _strain_gradient(na, da, u, v, ab, b[g])
            if not same:
                _interpolate(qr[el], na, da, u, v)
                _strain_gradient(na, da, u, v, ab, br[g])
        right = b if same else br
        for g in range(c):
            lo, hi = (0, c) if dense[el] else (g, g + 1)
            cb[:, :] = 0.0
            for h in range(lo, hi):  # cb = Σ_h (w C)_gh B_r,h over B_r,h's nonzero rows
                wgh = wc[el, g, h]
                bh = right[h]
                for col in range(48):
                    sk = _STRAINS_OF[(col // 3) % 4]
                    x0, x1, x2 = bh[sk[0], col], bh[sk[1], col], bh[sk[2], col]
                    for p in range(6):
                        cb[p, col] += wgh[p, sk[0]] * x0 + wgh[p, sk[1]] * x1 + wgh[p, sk[2]] * x2
            bg = b[g]
            for al in range(16):  # node a's vector u = al % 4: rows r, r + 1, r + 2
                sk = _STRAINS_OF[al % 4]
                p0, p1, p2 = sk[0], sk[1], sk[2]
                r = 3 * al
                b00, b01, b02 = bg[p0, r], bg[p1, r], bg[p2, r]
                b10, b11, b12 = bg[p0, r + 1], bg[p1, r + 1], bg[p2, r + 1]
                b20, b21, b22 = bg[p0, r + 2], bg[p1, r + 2], bg[p2, r + 2]
                for col in range(r if same else 0, 48):
                    c0, c1, c2 = cb[p0, col], cb[p1, col], cb[p2, col]
                    ke[r, col] += b00 * c0 + b01 * c1 + b02 * c2
                    ke[r + 1, col] += b10 * c0 + b11 * c1 + b12 * c2
                    ke[r + 2, col] += b20 * c0 + b21 * c1 + b22 * c2
        if same:  # entry (i, j) left of row i's triplet is entry (j, i), summed above
            for i in range(3, 48):
                for j in range(3 * (i // 3)):
                    ke[i, j] = ke[j, i]
    return k


@njit(cache=True)
def add_geometric(k: Array, hs: Array) -> None:
    """k[e, 3α + c, 3β + c] += hs[e, α, β] for c = 0, 1, 2: the geometric stiffness hs ⊗ I3
    added in place to the (E, 48, 48) element matrices."""
    for el in range(k.shape[0]):
        for al in range(16):
            for be in range(16):
                x = hs[el, al, be]
                for c in range(3):
                    k[el, 3 * al + c, 3 * be + c] += x
