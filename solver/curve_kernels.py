"""Compiled per-iteration arithmetic of the curve sliding joint (paper Eqs. 11 and 21–23).

:class:`solver.curve_joints.CurveSlidingSet` evaluates J joints that share one curve: the
constraint values and Jacobian, the exact discrete derivative of the energy-preserving scheme
and the λ-weighted Hessian of its Newton tangent, each once or twice per Newton iteration. In
vectorized NumPy every one of these is some tens of einsum/stack calls on (J, 3, 3) arrays
(J = 4 on the hub model), whose cost is interpreter and small-array overhead, not
arithmetic. Here each is one compiled loop over the joints
(numba, like :mod:`solver.bsplines`) that reads the directors straight from q and writes the
values in the set's sparse pattern order. The kernels evaluate the curve themselves (its
B-spline, ``NurbsCurve.spline``, through :func:`solver.bsplines.nurbs_eval`) and build a planar
curve's frame (:func:`_planar_frame`); only a space curve's Frenet frame comes from
``NurbsCurve.frame``.

The nonholonomic relations that go with the joint are here too, one compiled call per set
each: the arc length ṡ − |p*'(η)| η̇ = 0 (Eq. 25: :func:`arc_length_matrix`,
:func:`arc_length_derivative`) and rolling ṡ + σ r (ω_pin − ω_link)·n = 0 (Eq. 5:
:func:`rolling_matrix`, :func:`rolling_derivative`). In NumPy these are small-array calls
(a curve evaluation, norms, broadcast cross products) several times per Newton iteration;
compiled, with the planar frame of the joint's Hessian and the rotational springs
(:mod:`solver.rotation_kernels`), they about halve a free hub case's CPU time.

Layout of one joint (column indices within the joint's column block, as
``CurveSlidingSet._structure``): 0:3 x_k, 3:12 the directors d_1^k, d_2^k, d_3^k, 12:15 x_ℓ,
15:24 the directors of body ℓ (a rigid body ℓ only), then η (``nc − 1``). A director d_α of a
body with offset o is ``q[o + 3 + 3α : o + 6 + 3α]``. Rows: the three displacement rows, then
one row per locked rotation.

Rotation rows (Eq. 23): with R*(η) the Frenet triad of the curve in body k's frame (columns
t, n, b) and c the triad at η0 in body ℓ's frame, the row locking the rotation about axis x
of the pair (a, b) = ((2, 1), (0, 2), (1, 0))[x] is
    C = j_a^k·j_b^ℓ − j_b^k·j_a^ℓ = Σ_βγ W_βγ(η) X_βγ,  X_βγ = d_β^k·d_γ^ℓ,
    W_βγ = R*_βa c_γb − R*_βb c_γa,
a bilinear form in the two triads of directors whose coefficients depend on η alone. The
kernels take W and dW/dη per joint and row (arrays (J, r, 3, 3)) from :func:`curve_state`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from solver.bsplines import nurbs_eval
from solver.jit import njit

Array = NDArray[np.float64]
IArray = NDArray[np.int64]

# body ℓ's columns start at XL and its directors at DL within a joint's column block (see the
# module docstring; CurveSlidingSet builds its sparsity pattern with the same constants)
XL, DL = 12, 15


@njit(cache=True)
def _bilinear(r: Array, c: Array, ra: IArray, rb: IArray, out: Array) -> None:
    """W_βγ = r_βa c_γb − r_βb c_γa for every rotation row (a, b) = (ra, rb) (Eq. 23), from a
    triad r (R*, or a derivative of it) and c (3, 3); ``out`` is (r, 3, 3)."""
    for k in range(ra.shape[0]):
        a, b = ra[k], rb[k]
        for be in range(3):
            for ga in range(3):
                out[k, be, ga] = r[be, a] * c[ga, b] - r[be, b] * c[ga, a]


@njit(cache=True)
def _rotate(rot: Array, r: Array, out: Array) -> None:
    """out = rot @ r for 3 × 3 matrices (a triad from the curve's frame to body k's)."""
    for i in range(3):
        for k in range(3):
            out[i, k] = rot[i, 0] * r[0, k] + rot[i, 1] * r[1, k] + rot[i, 2] * r[2, k]


@njit(cache=True)
def _directors(q: Array, o: int, out: Array) -> None:
    """out[α] = d_α of the body with offset o (rows d_1, d_2, d_3)."""
    for a in range(3):
        for i in range(3):
            out[a, i] = q[o + 3 + 3 * a + i]


@njit(cache=True)
def _dot_rows(a: Array, b: Array, i: int, k: int) -> float:
    """a[i]·b[k] for 3 × 3 arrays (X_βγ = d_β^k·d_γ^ℓ for director rows)."""
    return a[i, 0] * b[k, 0] + a[i, 1] * b[k, 1] + a[i, 2] * b[k, 2]


@njit(cache=True)
def _cross_into(a: Array, b: Array, out: Array, col: int) -> None:
    """Column ``col`` of the 3 × 3 ``out`` = a × b."""
    out[0, col] = a[1] * b[2] - a[2] * b[1]
    out[1, col] = a[2] * b[0] - a[0] * b[2]
    out[2, col] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True)
def _curve(knots: Array, hom: Array, degree: int, rational: bool, eta: Array,
           order: int) -> Array:
    """p, p', …, p⁽ᵒʳᵈᵉʳ⁾ (order + 1, J, 3) of a curve (``NurbsCurve.spline``) at the
    parameters η clipped to [0, 1], as ``NurbsCurve.derivatives`` clips them: one compiled
    evaluation (:func:`solver.bsplines.nurbs_eval`), no trip through the interpreter."""
    x = np.empty(eta.shape[0])
    for j in range(eta.shape[0]):
        x[j] = min(max(eta[j], 0.0), 1.0)
    return nurbs_eval(knots, hom, degree, x, order, rational)


@njit(cache=True)
def _planar_frame(d: Array, j: int, normal: Array, r: Array, dr: Array) -> None:
    """The planar frame R (columns t, n, b) and dR/dη at point j of d = [p, p', p'', …]
    (the convention of ``NurbsCurve.frame`` for a planar curve, to roundoff):
        t = p'/|p'|,  b = plane normal,  n = b × t,
        t' = (p'' − t (t·p''))/|p'|  (the derivative of p'/|p'|),  n' = b × t',  b' = 0.
    The speed |p'| must not vanish (a cusp of the parametrization has no tangent here)."""
    sp = np.sqrt(d[1, j, 0] * d[1, j, 0] + d[1, j, 1] * d[1, j, 1] + d[1, j, 2] * d[1, j, 2])
    t = np.empty(3)
    tp = np.empty(3)
    for i in range(3):
        t[i] = d[1, j, i] / sp
    tdp = t[0] * d[2, j, 0] + t[1] * d[2, j, 1] + t[2] * d[2, j, 2]
    for i in range(3):
        tp[i] = (d[2, j, i] - t[i] * tdp) / sp
        r[i, 0] = t[i]
        r[i, 2] = normal[i]
        dr[i, 0] = tp[i]
        dr[i, 2] = 0.0
    _cross_into(normal, t, r, 1)
    _cross_into(normal, tp, dr, 1)


@njit(cache=True)
def planar_dframe(knots: Array, hom: Array, degree: int, rational: bool, eta: Array,
                  normal: Array) -> Array:
    """dR/dη (J, 3, 3) of a planar curve (``NurbsCurve.spline``, unit plane ``normal``) at η
    clipped to [0, 1]: what ``NurbsCurve.frame(eta)[1]`` gives, in one compiled call (the
    Hessian's central difference of dR/dη evaluates it at η ± h every Newton iteration)."""
    d = _curve(knots, hom, degree, rational, eta, 2)
    nj = eta.shape[0]
    r = np.empty((3, 3))
    out = np.empty((nj, 3, 3))
    for j in range(nj):
        _planar_frame(d, j, normal, r, out[j])
    return out


@njit(cache=True)
def curve_state(knots: Array, hom: Array, degree: int, rational: bool, eta: Array,
                frame: Array, dframe: Array, rot: Array, offset: Array, normal: Array,
                planar: bool, c: Array, ra: IArray,
                rb: IArray) -> tuple[Array, Array, Array, Array, Array]:
    """The curve at the joints' parameters in body k's frames: p*, p*', p*'' and W, dW/dη.

    Parameters
    ----------
    knots, hom, degree, rational : the curve (``NurbsCurve.spline``), points in m.
    eta : (J,) the joints' curve parameters (clipped to [0, 1] like ``curve.derivatives``).
    frame, dframe : (J, 3, 3) the curve's frame R and dR/dη (columns t, n, b) from
        ``curve.frame`` for a space curve; ignored (may be empty) if ``planar`` or without
        rotation rows.
    rot, offset : (J, 3, 3), (J, 3) placement of the curve in body k: p* = o + Q p, R* = Q R.
    normal : (3,) plane normal of a planar curve.
    planar : build R, dR/dη from the curve's p', p'' and ``normal`` (:func:`_planar_frame`,
        the planar convention of :mod:`solver.curves`) instead of ``frame``/``dframe``.
    c : (J, 3, 3) Frenet triad at η0 in body ℓ's frame; ra, rb : (r,) the rows' pairs (a, b).

    Returns
    -------
    p, p1, p2 : (J, 3) p* (m), p*' (m per η), p*'' (m per η²); w, dw : (J, r, 3, 3) the
    rotation rows' W(η) and dW/dη (Eq. 23).
    """
    d = _curve(knots, hom, degree, rational, eta, 2)
    nj, nr = d.shape[1], ra.shape[0]
    p = np.empty((nj, 3))
    p1 = np.empty((nj, 3))
    p2 = np.empty((nj, 3))
    w = np.empty((nj, nr, 3, 3))
    dw = np.empty((nj, nr, 3, 3))
    r = np.empty((3, 3))
    dr = np.empty((3, 3))
    rk = np.empty((3, 3))
    for j in range(nj):
        for i in range(3):
            s0 = 0.0
            s1 = 0.0
            s2 = 0.0
            for a in range(3):
                s0 += d[0, j, a] * rot[j, i, a]
                s1 += d[1, j, a] * rot[j, i, a]
                s2 += d[2, j, a] * rot[j, i, a]
            p[j, i] = offset[j, i] + s0
            p1[j, i] = s1
            p2[j, i] = s2
        if nr == 0:
            continue
        if planar:
            _planar_frame(d, j, normal, r, dr)
            _rotate(rot[j], r, rk)
            _bilinear(rk, c[j], ra, rb, w[j])
            _rotate(rot[j], dr, rk)
            _bilinear(rk, c[j], ra, rb, dw[j])
        else:
            _rotate(rot[j], frame[j], rk)
            _bilinear(rk, c[j], ra, rb, w[j])
            _rotate(rot[j], dframe[j], rk)
            _bilinear(rk, c[j], ra, rb, dw[j])
    return p, p1, p2, w, dw


@njit(cache=True)
def _fixed_entries(g: Array, b: Array, j: int, l_rigid: bool) -> None:
    """The displacement rows' entries that do not depend on q: ∂/∂x_k = I, ∂/∂x_ℓ = −I and
    ∂/∂d_α^ℓ = −b_α I (the point b of body ℓ in its frame)."""
    for i in range(3):
        g[i, i] = 1.0
        g[i, XL + i] = -1.0
        if l_rigid:
            for a in range(3):
                g[i, DL + 3 * a + i] = -b[j, a]


@njit(cache=True)
def _rotation_row(g: Array, row: int, w: Array, dk: Array, dl: Array) -> None:
    """The director columns of one rotation row Σ_βγ W_βγ d_β^k·d_γ^ℓ (Eq. 23): ∂/∂d_β^k =
    Σ_γ W_βγ d_γ^ℓ and ∂/∂d_γ^ℓ = Σ_β W_βγ d_β^k (with W, d^k, d^ℓ at a point, or their
    averages over a step for the discrete derivative)."""
    for be in range(3):
        for i in range(3):
            sk = 0.0
            sl = 0.0
            for ga in range(3):
                sk += w[be, ga] * dl[ga, i]
                sl += w[ga, be] * dk[ga, i]
            g[row, 3 + 3 * be + i] = sk
            g[row, DL + 3 * be + i] = sl


@njit(cache=True)
def _gather(g: Array, jr: IArray, jc: IArray, out: Array, start: int) -> None:
    """Copy the structural entries (jr, jc) of one joint's dense block into the flat values."""
    for k in range(jr.shape[0]):
        out[start + k] = g[jr[k], jc[k]]


@njit(cache=True)
def evaluate(q: Array, ok: IArray, ol: IArray, l_rigid: bool, b: Array, p: Array, p1: Array,
             w: Array, dw: Array, jr: IArray, jc: IArray, nc: int) -> tuple[Array, Array]:
    """Constraint values and Jacobian of J curve sliding joints.

    Displacement rows (Eq. 11), with R_k p* = Σ_α p*_α d_α^k:
        C = x_k + Σ_α p*_α(η) d_α^k − x_ℓ − Σ_α b_α d_α^ℓ,
        ∂C/∂d_α^k = p*_α I,  ∂C/∂η = Σ_α p*'_α d_α^k
    (the b terms for a rigid body ℓ only). Rotation rows (Eq. 23): C = Σ_βγ W_βγ X_βγ,
        ∂C/∂d_β^k = Σ_γ W_βγ d_γ^ℓ,  ∂C/∂d_γ^ℓ = Σ_β W_βγ d_β^k,  ∂C/∂η = Σ_βγ W'_βγ X_βγ.

    Parameters
    ----------
    q : (n,) coordinates; ok, ol : (J,) offsets of bodies k and ℓ; l_rigid : body ℓ rigid;
    b : (J, 3) contact point in body ℓ's frame (m); p, p1 (J, 3) and w, dw (J, r, 3, 3) from
    :func:`curve_state`; jr, jc : structural non-zeros of one joint's rows; nc : columns per
    joint.

    Returns
    -------
    c : (J·m,) constraint values; g : (J·len(jr),) Jacobian values in pattern order.
    """
    nj, nr = ok.shape[0], w.shape[1]
    mj, je, npj = 3 + nr, nc - 1, jr.shape[0]
    c = np.empty(nj * mj)
    vals = np.empty(nj * npj)
    g = np.zeros((mj, nc))
    dk = np.empty((3, 3))
    dl = np.empty((3, 3))
    x = np.empty((3, 3))
    for j in range(nj):
        _directors(q, ok[j], dk)
        if l_rigid:
            _directors(q, ol[j], dl)
        _fixed_entries(g, b, j, l_rigid)
        for i in range(3):
            s = 0.0
            s1 = 0.0
            for a in range(3):
                s += p[j, a] * dk[a, i]
                s1 += p1[j, a] * dk[a, i]
                g[i, 3 + 3 * a + i] = p[j, a]
            ci = q[ok[j] + i] + s - q[ol[j] + i]
            if l_rigid:
                sb = 0.0
                for a in range(3):
                    sb += b[j, a] * dl[a, i]
                ci -= sb
            c[j * mj + i] = ci
            g[i, je] = s1
        if nr:
            for be in range(3):
                for ga in range(3):
                    x[be, ga] = _dot_rows(dk, dl, be, ga)
            for k in range(nr):
                s = 0.0
                s1 = 0.0
                for be in range(3):
                    for ga in range(3):
                        s += w[j, k, be, ga] * x[be, ga]
                        s1 += dw[j, k, be, ga] * x[be, ga]
                c[j * mj + 3 + k] = s
                g[3 + k, je] = s1
                _rotation_row(g, 3 + k, w[j, k], dk, dl)
        _gather(g, jr, jc, vals, j * npj)
    return c, vals


@njit(cache=True)
def discrete_jacobian(qi: Array, qf: Array, ok: IArray, ol: IArray, ie: IArray, l_rigid: bool,
                      b: Array, pi: Array, p1i: Array, wi: Array, dwi: Array, pf: Array,
                      p1f: Array, wf: Array, dwf: Array, jr: IArray, jc: IArray,
                      nc: int) -> Array:
    """Exact discrete derivative Ḡ with Ḡ·(q_f − q_i) = C(q_f) − C(q_i), in pattern order.

    Product rule with averages and the secant of the curve (design note): Δ(p_α d_α) =
    p̄_α Δd_α + d̄_α p̄'_α Δη with p̄' = (p(η_f) − p(η_i))/Δη; the rotation rows are
    Σ W_βγ(η) d_β^k·d_γ^ℓ and use the secant of W likewise, with X̄ the mean of the end
    points' X_βγ = d_β^k·d_γ^ℓ (the mean of a product is not the product of means: that is
    what makes Δ(W X) = W̄ ΔX + ΔW X̄ exact). For |Δη| < 1e-9 the secants are replaced by the
    mean of the end derivatives (no 0/0; exact to the roundoff of C there).

    Parameters
    ----------
    qi, qf : (n,) start and end of the step; ok, ol, ie : (J,) offsets of bodies k, ℓ and the
    index of η; l_rigid, b, jr, jc, nc : as :func:`evaluate`; pi, p1i, wi, dwi and pf, p1f,
    wf, dwf : :func:`curve_state` at η_i and η_f.
    """
    nj, nr = ok.shape[0], wi.shape[1]
    mj, je, npj = 3 + nr, nc - 1, jr.shape[0]
    vals = np.empty(nj * npj)
    g = np.zeros((mj, nc))
    dki = np.empty((3, 3))
    dkf = np.empty((3, 3))
    dli = np.empty((3, 3))
    dlf = np.empty((3, 3))
    dkbar = np.empty((3, 3))
    dlbar = np.empty((3, 3))
    xbar = np.empty((3, 3))
    wbar = np.empty((3, 3))
    for j in range(nj):
        de = qf[ie[j]] - qi[ie[j]]
        small = abs(de) < 1e-9
        _directors(qi, ok[j], dki)
        _directors(qf, ok[j], dkf)
        for a in range(3):
            for i in range(3):
                dkbar[a, i] = 0.5 * (dki[a, i] + dkf[a, i])
        _fixed_entries(g, b, j, l_rigid)
        for i in range(3):
            s = 0.0
            for a in range(3):
                g[i, 3 + 3 * a + i] = 0.5 * (pi[j, a] + pf[j, a])
                if small:
                    sec = 0.5 * (p1i[j, a] + p1f[j, a])
                else:
                    sec = (pf[j, a] - pi[j, a]) / de
                s += sec * dkbar[a, i]
            g[i, je] = s
        if nr:
            _directors(qi, ol[j], dli)
            _directors(qf, ol[j], dlf)
            for a in range(3):
                for i in range(3):
                    dlbar[a, i] = 0.5 * (dli[a, i] + dlf[a, i])
            for be in range(3):
                for ga in range(3):
                    xbar[be, ga] = 0.5 * (_dot_rows(dki, dli, be, ga) + _dot_rows(dkf, dlf, be, ga))
            for k in range(nr):
                s = 0.0
                for be in range(3):
                    for ga in range(3):
                        if small:
                            dwk = 0.5 * (dwi[j, k, be, ga] + dwf[j, k, be, ga])
                        else:
                            dwk = (wf[j, k, be, ga] - wi[j, k, be, ga]) / de
                        s += dwk * xbar[be, ga]
                g[3 + k, je] = s
                for be in range(3):
                    for ga in range(3):
                        wbar[be, ga] = 0.5 * (wi[j, k, be, ga] + wf[j, k, be, ga])
                _rotation_row(g, 3 + k, wbar, dkbar, dlbar)
        _gather(g, jr, jc, vals, j * npj)
    return vals


@njit(cache=True)
def constraint_hessian(q: Array, ok: IArray, ol: IArray, lam: Array, p1: Array, p2: Array,
                       w: Array, dw: Array, rot: Array, dframe_plus: Array,
                       dframe_minus: Array, step: float, c: Array, ra: IArray, rb: IArray,
                       hr: IArray, hc: IArray, nc: int) -> Array:
    """Σ_r λ_r ∂²C_r/∂q² of J joints at the structural non-zeros (hr, hc) of one joint.

    Displacement rows: ∂²/∂η∂d_α^k = p*'_α I, ∂²/∂η² = Σ_α p*''_α d_α^k (C is linear in the
    coordinates otherwise). Rotation rows (Σ_βγ W_βγ X_βγ): ∂²/∂η∂d_β^k = Σ_γ W'_βγ d_γ^ℓ,
    ∂²/∂η∂d_γ^ℓ = Σ_β W'_βγ d_β^k, ∂²/∂d_β^k∂d_γ^ℓ = W_βγ I (only equal components couple),
    and ∂²/∂η² = Σ_βγ W''_βγ X_βγ with d²R*/dη² by a central difference of the exact first
    derivative (the curve gives R and dR/dη only): W'' is the bilinear form of
    Q (dR(η + h) − dR(η − h))/(2h), h = ``step``, dR(η ± h) = ``dframe_plus``/``_minus``.
    The Hessian only shapes the Newton matrix, so the O(h²) + O(eps/h) error of that
    difference costs no accuracy of the solution.

    Parameters
    ----------
    q : (n,) coordinates; ok, ol : (J,) offsets of bodies k and ℓ; lam : (J·m,) multipliers;
    p1, p2, w, dw : :func:`curve_state` at η; rot : (J, 3, 3) placements Q; dframe_plus,
    dframe_minus : (J, 3, 3) dR/dη of the curve at η ± h (empty without rotation rows);
    c, ra, rb : as :func:`curve_state`; hr, hc : structural non-zeros of the symmetric
    Hessian of one joint; nc : columns per joint.
    """
    nj, nr = ok.shape[0], w.shape[1]
    mj, je, nph = 3 + nr, nc - 1, hr.shape[0]
    vals = np.empty(nj * nph)
    h = np.empty((nc, nc))  # one side of the diagonal; symmetrized when gathered
    dk = np.empty((3, 3))
    dl = np.empty((3, 3))
    d2r = np.empty((3, 3))
    rp = np.empty((3, 3))
    rm = np.empty((3, 3))
    d2w = np.empty((nr, 3, 3))
    coef = np.empty((3, 3))
    for j in range(nj):
        h[:, :] = 0.0
        _directors(q, ok[j], dk)
        lj = lam[j * mj : (j + 1) * mj]
        s = 0.0
        for i in range(3):
            for a in range(3):
                h[je, 3 + 3 * a + i] = p1[j, a] * lj[i]
                s += lj[i] * p2[j, a] * dk[a, i]
        h[je, je] = s
        if nr:
            _directors(q, ol[j], dl)
            _rotate(rot[j], dframe_plus[j], rp)
            _rotate(rot[j], dframe_minus[j], rm)
            for i in range(3):
                for k in range(3):
                    d2r[i, k] = (rp[i, k] - rm[i, k]) / (2 * step)
            _bilinear(d2r, c[j], ra, rb, d2w)
            s = 0.0
            for be in range(3):
                for ga in range(3):
                    x = _dot_rows(dk, dl, be, ga)
                    cf = 0.0
                    for k in range(nr):
                        s += lj[3 + k] * d2w[k, be, ga] * x
                        cf += lj[3 + k] * w[j, k, be, ga]
                    coef[be, ga] = cf
            h[je, je] += s
            for be in range(3):
                for i in range(3):
                    sk = 0.0
                    sl = 0.0
                    for k in range(nr):
                        for ga in range(3):
                            sk += lj[3 + k] * dw[j, k, be, ga] * dl[ga, i]
                            sl += lj[3 + k] * dw[j, k, ga, be] * dk[ga, i]
                    h[je, 3 + 3 * be + i] += sk
                    h[je, DL + 3 * be + i] += sl
            for be in range(3):
                for ga in range(3):
                    for i in range(3):
                        h[3 + 3 * be + i, DL + 3 * ga + i] += coef[be, ga]
        for k in range(nph):
            r_, c_ = hr[k], hc[k]
            vals[j * nph + k] = h[r_, c_] if r_ == c_ else h[r_, c_] + h[c_, r_]
    return vals


# ----------------------------------------------------------------- nonholonomic relations
@njit(cache=True)
def arc_length_matrix(knots: Array, hom: Array, degree: int, rational: bool, q: Array,
                      ie: IArray) -> Array:
    """Rows A of the arc-length relations ṡ − |p*'(η)| η̇ = 0 (Eq. 25) over (s, η).

    The speed of the placed curve is the curve's own, |p*'| = |Q p'| = |p'| (Q a rotation).

    Parameters
    ----------
    knots, hom, degree, rational : the curve (``NurbsCurve.spline``), points in m.
    q : (n,) coordinates; ie : (J,) index of each relation's η (clipped to [0, 1]).

    Returns
    -------
    (J, 2): (1, −|p'(η)|) per relation (dimensionless, m per unit η).
    """
    d = _curve(knots, hom, degree, rational, q[ie], 1)
    out = np.empty((ie.shape[0], 2))
    for j in range(ie.shape[0]):
        out[j, 0] = 1.0
        out[j, 1] = -np.sqrt(d[1, j, 0] * d[1, j, 0] + d[1, j, 1] * d[1, j, 1]
                             + d[1, j, 2] * d[1, j, 2])
    return out


@njit(cache=True)
def arc_length_derivative(knots: Array, hom: Array, degree: int, rational: bool, q: Array,
                          dq: Array, ie: IArray) -> Array:
    """∂(A(q)·dq)/∂q of the arc-length rows (J, 2) over (s, η): A·dq = ds − |p'(η)| dη
    depends on η alone, with d|p'|/dη = p'·p''/|p'|, so the η entry is −(p'·p''/|p'|) dη
    (m per unit η, times dη) and the s entry 0."""
    d = _curve(knots, hom, degree, rational, q[ie], 2)
    out = np.zeros((ie.shape[0], 2))
    for j in range(ie.shape[0]):
        sp = np.sqrt(d[1, j, 0] * d[1, j, 0] + d[1, j, 1] * d[1, j, 1]
                     + d[1, j, 2] * d[1, j, 2])
        dot = d[1, j, 0] * d[2, j, 0] + d[1, j, 1] * d[2, j, 1] + d[1, j, 2] * d[2, j, 2]
        out[j, 1] = -dot / sp * dq[ie[j]]
    return out


@njit(cache=True)
def _axis_vector(q: Array, o: int, axis: Array, j: int, out: Array) -> None:
    """out = Σ_β axis_β d_β: the rolling axis n of joint j in the global frame, from the
    directors of the link (first director at q[o])."""
    for i in range(3):
        out[i] = (axis[j, 0] * q[o + i] + axis[j, 1] * q[o + 3 + i]) + axis[j, 2] * q[o + 6 + i]


@njit(cache=True)
def _cross_at(a: Array, ia: int, b: Array, ib: int, out: Array) -> None:
    """out = a[ia : ia + 3] × b[ib : ib + 3] (vectors stored in flat arrays)."""
    out[0] = a[ia + 1] * b[ib + 2] - a[ia + 2] * b[ib + 1]
    out[1] = a[ia + 2] * b[ib] - a[ia] * b[ib + 2]
    out[2] = a[ia] * b[ib + 1] - a[ia + 1] * b[ib]


@njit(cache=True)
def rolling_matrix(q: Array, op: IArray, ol: IArray, k: Array, axis: Array) -> Array:
    """Rows A of the rolling relations ṡ + σ r (ω_pin − ω_link)·n = 0 (Eq. 5).

    With directors, ω·n = ½ Σ_α ḋ_α·(n × d_α), so the row over (s, d_α^pin, d_α^link) is
        (1,  k n × d_α^pin,  −k n × d_α^link),   k = ½ σ r,
    n = Σ_β axis_β d_β^link the rolling axis (the curve binormal) carried by the link.

    Parameters
    ----------
    q : (n,) coordinates; op, ol : (J,) index of the first director of the pin and the link;
    k : (J,) ½ σ r (m); axis : (J, 3) rolling axis in the link's frame (unit).

    Returns
    -------
    (J, 19): the rows over (s, the pin's 9 director coordinates, the link's 9), in m for the
    director columns.
    """
    nj = op.shape[0]
    out = np.empty((nj, 19))
    n = np.empty(3)
    x = np.empty(3)
    for j in range(nj):
        _axis_vector(q, ol[j], axis, j, n)
        out[j, 0] = 1.0
        for a in range(3):
            _cross_at(n, 0, q, op[j] + 3 * a, x)
            for i in range(3):
                out[j, 1 + 3 * a + i] = k[j] * x[i]
            _cross_at(n, 0, q, ol[j] + 3 * a, x)
            for i in range(3):
                out[j, 10 + 3 * a + i] = -k[j] * x[i]
    return out


@njit(cache=True)
def rolling_derivative(q: Array, dq: Array, op: IArray, ol: IArray, k: Array,
                       axis: Array) -> Array:
    """∂(A(q)·dq)/∂q of the rolling rows (J, 19), over the columns of :func:`rolling_matrix`.

    With e_α the director components of dq, A·dq = de_s + k Σ_α [n·(d_α^pin × e_α^pin) −
    n·(d_α^link × e_α^link)] (a triple product), so
        ∂/∂d_α^pin = k e_α^pin × n,   ∂/∂d_α^link = −k e_α^link × n + k axis_α w,
    the last term through the rolling axis n = Σ_β axis_β d_β^link, with
    w = ∂(A·dq)/∂n / k = Σ_α (d_α^pin × e_α^pin − d_α^link × e_α^link).
    """
    nj = op.shape[0]
    out = np.zeros((nj, 19))
    n = np.empty(3)
    x = np.empty(3)
    y = np.empty(3)
    w = np.empty(3)
    for j in range(nj):
        _axis_vector(q, ol[j], axis, j, n)
        # w = Σ_α (d_α^pin × e_α^pin − d_α^link × e_α^link): ∂(row·v)/∂n along dq
        for a in range(3):
            _cross_at(q, op[j] + 3 * a, dq, op[j] + 3 * a, x)
            _cross_at(q, ol[j] + 3 * a, dq, ol[j] + 3 * a, y)
            for i in range(3):
                if a == 0:
                    w[i] = x[i] - y[i]
                else:
                    w[i] += x[i] - y[i]
        for a in range(3):
            _cross_at(dq, op[j] + 3 * a, n, 0, x)
            for i in range(3):
                out[j, 1 + 3 * a + i] = k[j] * x[i]
            _cross_at(dq, ol[j] + 3 * a, n, 0, x)
            for i in range(3):
                out[j, 10 + 3 * a + i] = -k[j] * x[i] + k[j] * (axis[j, a] * w[i])
    return out
