"""Compiled arithmetic of the rotational springs and dampers (:mod:`solver.forces`).

:class:`solver.forces.RelativeRotationSet` measures the relative rotation φ of two bodies about
a joint axis from the joint triads e_i^a, e_i^b that the bodies carry (e_i = Σ_α c_α d_α, fixed
coefficients on the body's directors; a grounded element has a constant e^a):

    c = e1ᵃ·e1ᵇ = cos φ,   s = −e1ᵃ·e2ᵇ = sin φ   (times the same factor off the manifold),
    φ = atan2(s, c),   ∇φ = (c ∇s − s ∇c)/r²,   r² = c² + s²,

with c and s bilinear in the two bodies' directors. In NumPy its moment, gradient and the
tangent of a damper are some tens of einsum/concatenate calls on (J, k) and (J, k, k) arrays
per call (J the number of elements, k ≤ 18 the director columns they touch), called several
times per Newton iteration: interpreter overhead, not arithmetic. Here each is one compiled
loop over the elements (numba, like :mod:`solver.curve_kernels`).

Column layout of one element (``RelativeRotationSet.idx``): first body a's active directors
(those with a non-zero coefficient in some member; none if grounded), 3 columns each, then
body b's. ``na`` is the number of body a's columns.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from solver.jit import njit

Array = NDArray[np.float64]
IArray = NDArray[np.int64]


@njit(cache=True)
def _bilinear(q: Array, idx: IArray, na: int, cb1: Array, cb2: Array, ca1: Array, ea: Array,
              grounded: bool, j: int, e_a: Array, dc: Array, ds: Array) -> tuple[float, float]:
    """c = e1ᵃ·e1ᵇ and s = −e1ᵃ·e2ᵇ of element j, and their gradients dc, ds (k,) over
    ``idx[j]``: ∂c/∂d_α^b = cb1_α e1ᵃ, ∂s/∂d_α^b = −cb2_α e1ᵃ, and for a body a
    ∂c/∂d_α^a = ca1_α e1ᵇ, ∂s/∂d_α^a = −ca1_α e2ᵇ. ``e_a`` (3,) receives e1ᵃ."""
    nb = cb1.shape[1]
    eb1 = np.zeros(3)
    eb2 = np.zeros(3)
    for a in range(nb):
        o = idx[j, na + 3 * a]
        for i in range(3):
            eb1[i] += cb1[j, a] * q[o + i]
            eb2[i] += cb2[j, a] * q[o + i]
    if grounded:
        for i in range(3):
            e_a[i] = ea[j, i]
    else:
        e_a[:] = 0.0
        for a in range(ca1.shape[1]):
            o = idx[j, 3 * a]
            for i in range(3):
                e_a[i] += ca1[j, a] * q[o + i]
    c = e_a[0] * eb1[0] + e_a[1] * eb1[1] + e_a[2] * eb1[2]
    s = -(e_a[0] * eb2[0] + e_a[1] * eb2[1] + e_a[2] * eb2[2])
    for a in range(nb):
        for i in range(3):
            dc[na + 3 * a + i] = cb1[j, a] * e_a[i]
            ds[na + 3 * a + i] = -cb2[j, a] * e_a[i]
    for a in range(na // 3):
        for i in range(3):
            dc[3 * a + i] = ca1[j, a] * eb1[i]
            ds[3 * a + i] = -ca1[j, a] * eb2[i]
    return c, s


@njit(cache=True)
def phi_grad(q: Array, idx: IArray, na: int, cb1: Array, cb2: Array, ca1: Array, ea: Array,
             grounded: bool) -> tuple[Array, Array, Array]:
    """c, s (J,) and ∇φ = (c ∇s − s ∇c)/(c² + s²) (J, k, rad per unit director) of J
    rotational springs over their columns ``idx`` (J, k).

    Parameters
    ----------
    q : (n,) coordinates; idx : (J, k) columns (body a's active directors, then body b's);
    na : number of body a's columns (0 if grounded); cb1, cb2 : (J, nb) coefficients of e1ᵇ,
    e2ᵇ on body b's active directors; ca1 : (J, na/3) those of e1ᵃ on body a's (unused if
    grounded); ea : (J, 3) the constant e1ᵃ of grounded elements (unused otherwise).
    """
    nj, k = idx.shape
    c = np.empty(nj)
    s = np.empty(nj)
    g = np.empty((nj, k))
    e_a = np.empty(3)
    dc = np.empty(k)
    ds = np.empty(k)
    for j in range(nj):
        cj, sj = _bilinear(q, idx, na, cb1, cb2, ca1, ea, grounded, j, e_a, dc, ds)
        r2 = cj * cj + sj * sj
        for m in range(k):
            g[j, m] = (cj * ds[m] - sj * dc[m]) / r2
        c[j] = cj
        s[j] = sj
    return c, s, g


@njit(cache=True)
def phi_hessian(q: Array, idx: IArray, na: int, cb1: Array, cb2: Array, ca1: Array,
                ea: Array, grounded: bool) -> tuple[Array, Array, Array, Array]:
    """c, s (J,), ∇φ (J, k) and the Hessian ∇²φ (J, k, k) (arguments as :func:`phi_grad`).

    c and s are bilinear: their only second derivatives couple a director of body a with one
    of body b, ∂²c/∂d_α^a∂d_β^b = ca1_α cb1_β I3 and ∂²s/∂d_α^a∂d_β^b = −ca1_α cb2_β I3 (none
    if grounded). Differentiating ∇φ = (c∇s − s∇c)/r² once more:
        ∇²φ = [∇s∇cᵀ − ∇c∇sᵀ + c∇²s − s∇²c − 2∇φ(c∇c + s∇s)ᵀ]/r²,   r² = c² + s².
    """
    nj, k = idx.shape
    c = np.empty(nj)
    s = np.empty(nj)
    g = np.empty((nj, k))
    hess = np.empty((nj, k, k))
    e_a = np.empty(3)
    dc = np.empty(k)
    ds = np.empty(k)
    w = np.empty(k)
    hc = np.zeros((k, k))
    hs = np.zeros((k, k))
    for j in range(nj):
        cj, sj = _bilinear(q, idx, na, cb1, cb2, ca1, ea, grounded, j, e_a, dc, ds)
        r2 = cj * cj + sj * sj
        for m in range(k):
            g[j, m] = (cj * ds[m] - sj * dc[m]) / r2
            w[m] = cj * dc[m] + sj * ds[m]
        if not grounded:  # the a–b blocks of ∇²c, ∇²s (the rest of hc, hs stays zero)
            for a in range(na // 3):
                for b in range(cb1.shape[1]):
                    xc = ca1[j, a] * cb1[j, b]
                    xs = ca1[j, a] * -cb2[j, b]
                    for i in range(3):
                        hc[3 * a + i, na + 3 * b + i] = xc
                        hc[na + 3 * b + i, 3 * a + i] = xc
                        hs[3 * a + i, na + 3 * b + i] = xs
                        hs[na + 3 * b + i, 3 * a + i] = xs
        for m in range(k):
            for n in range(k):
                outer = ds[m] * dc[n] - dc[m] * ds[n]
                hess[j, m, n] = ((outer + cj * hs[m, n] - sj * hc[m, n])
                                 - 2.0 * g[j, m] * w[n]) / r2
        c[j] = cj
        s[j] = sj
    return c, s, g, hess


@njit(cache=True)
def damper_jacobians(g: Array, hess: Array, v: Array, damp: Array, stiff: Array,
                     moment: Array) -> tuple[Array, Array]:
    """∂f/∂q and ∂f/∂v (flat, J·k·k, row-major per element) of f = m ∇φ, m = −(c + b) φ̇ − a φ
    + … (a damper, with the stiffness a and damping b of delayed feedback where it acts).

    With φ̇ = ∇φ·v: ∂f/∂v = −(c + b) ∇φ∇φᵀ and ∂f/∂q = ∇φ (∂m/∂q)ᵀ + m ∇²φ with
    ∂m/∂q = −(c + b) ∇²φ v − a ∇φ — the moment turns with the bodies (m ∇²φ) and the rate with
    the configuration (∇²φ v).

    Parameters
    ----------
    g, hess : (J, k), (J, k, k) ∇φ and ∇²φ; v : (J, k) the velocities at the columns;
    damp, stiff : (J,) c + b (N·m·s/rad) and a (N·m/rad); moment : (J,) m (N·m).
    """
    nj, k = g.shape
    fq = np.empty((nj, k, k))
    fv = np.empty((nj, k, k))
    hv = np.empty(k)
    for j in range(nj):
        for m in range(k):
            x = 0.0
            for n in range(k):
                x += hess[j, m, n] * v[j, n]
            hv[m] = x
        for m in range(k):
            for n in range(k):
                ggt = g[j, m] * g[j, n]
                fq[j, m, n] = (-damp[j] * g[j, m] * hv[n] - stiff[j] * ggt
                               + moment[j] * hess[j, m, n])
                fv[j, m, n] = -damp[j] * ggt
    return fq.ravel(), fv.ravel()
