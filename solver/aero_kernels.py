"""Compiled airloads of the lifting-line sections (:mod:`solver.lifting_line`).

:class:`~solver.lifting_line.LiftingLineSet` evaluates, per section, the Peters finite-state
airfoil in the section's frame (circulatory lift at the quarter chord, profile drag, apparent
mass) and its share of the rotor inflow forcing; the formulas and their derivation are in the
docstring of :mod:`solver.lifting_line`. The force Jacobians are complex steps of the same
formula by each of the section's 36 + N + n_i local inputs. As a vectorized NumPy kernel this
is some eighty array operations on arrays of a few dozen sections per call (and one call on a
36 + N + n_i times larger complex batch for the Jacobians): interpreter overhead, not
arithmetic. Here :func:`section_loads` is the one implementation of the formula, compiled by
numba for float64 (the forces and the ``details`` of
:meth:`~solver.lifting_line.LiftingLineSet.airloads`, from the same call) and for complex128
(:func:`local_jacobian`'s complex steps), so both come from one source.

The rotor inflow enters through its shape functions Φ (λ = Φ·α at the section) and the load
weights W = Φ * factors (the section's share of the forcing), evaluated by
:meth:`~solver.inflow.DynamicInflow.shape` at the sections' disk coordinates and passed in
(for Peters–He that method runs :func:`peters_he_shapes`, compiled here as well, for real and
complex points; it stays the inflow model's one definition of Φ):
they depend on the section's position only, so the complex-step Jacobian needs them at the
real positions and at the three positions stepped by i h along x, y and z (two NumPy calls
per Jacobian instead of a shape evaluation per perturbed input).

The support maps S (12 × 48 per section: x = S q, loads Sᵀ g ds) are mostly zeros (48 of 576
on a beam: one shape function per node and component); :func:`section_inputs`,
:func:`support_forces` and :func:`expand_jacobian` use their nonzeros only.

Layout. Section k's inputs are x (12: position, d1, d2, d3, m), their rates xd (m/s) and
accelerations xa (m/s²), the wake states mu (N, m/s) and the inflow states al (n_i, −).
``props[k]`` holds (b semichord m, cos(θ − α0), sin(θ − α0), ξ_qc m, lift slope × lifting
1/rad, c_d0, ds m). Outputs: g (12) the generalized force per unit span on (x, d1, d2, d3)
(N/m), the wake-state rates (N, m/s²), the inflow forcing (n_i, −), and the details (``DETAILS``
columns, see :data:`DETAIL_COLUMNS`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from solver.jit import njit

Array = NDArray[np.float64]

# columns of the details row of a section: name → (first column, width)
DETAIL_COLUMNS = {"force": (0, 3), "circulatory": (3, 3), "u": (6, 1), "w0": (7, 1),
                  "w34": (8, 1), "lam0": (9, 1), "lift": (10, 1), "apparent_lift": (11, 1),
                  "apparent_moment": (12, 1), "position": (13, 3), "air": (16, 3)}
DETAILS = 19
N_PROPS = 7  # b, cos, sin, ξ_qc, a, c_d0, ds
_WORK = 11  # rows of 3-vectors in the work buffer


@njit(cache=True)
def section_loads(x, xd, xa, mu, al, phi, wts, props, rho, vinf, omega_r, load_scale,
                  u_floor2, kappa, pb, ainv_c, wk, g, rates, forcing, det):
    """Airloads of one section (real or complex: every operation is analytic).

    Parameters
    ----------
    x, xd, xa
        (12,) coordinates (position m, directors d1, d2, d3), rates, accelerations.
    mu
        (N,) wake states μ = λ − A⁻¹c w34 (m/s).
    al
        (n_i,) inflow states (on ΩR).
    phi, wts
        (n_i,) inflow shapes Φ (λ = Φ·al) and load weights W at the section's position.
    props
        (7,) the section's constants: b (m), cos(θ − α0), sin(θ − α0), ξ_qc (m), lift slope
        times the lifting flag (1/rad), c_d0, quadrature weight ds (m).
    rho, vinf
        Air density (kg/m³) and the air's velocity at the section (3,) (m/s): the free
        stream plus any prescribed wind (:mod:`solver.section_wind`).
    omega_r, load_scale
        ΩR (m/s) and 1/(ρΩ²R⁴) of the inflow (unused without inflow states).
    u_floor2
        Floor u_f² (m²/s²) of the wake decay speed √(u² + u_f²).
    kappa, pb, ainv_c
        κ = ½bᵀA⁻¹c, ½b (N,) and A⁻¹c (N,) of Peters' model.
    wk
        (11, 3) work buffer of the inputs' dtype.
    g, rates, forcing, det
        Outputs (12,), (N,), (n_i,), (19,) (N/m, m/s², −, see ``DETAIL_COLUMNS``).
    """
    b, ct, st, xq, a_lift, cd0, ds = (props[0], props[1], props[2], props[3], props[4],
                                      props[5], props[6])
    n, ni = mu.shape[0], al.shape[0]
    # induced inflow λ = Φ·α at the section: −λΩR ẑ adds to the free stream
    lam = 0.0 * x[0]
    for i in range(ni):
        lam += phi[i] * al[i]
    xm, x34 = xq - 0.5 * b, xq - b  # mid-chord and three-quarter chord
    ec, en, dec, den, aec = wk[0], wk[1], wk[2], wk[3], wk[4]
    vair, w_mid, w_34, w_qc, f_qc, f_mid = wk[5], wk[6], wk[7], wk[8], wk[9], wk[10]
    for i in range(3):
        # chordwise (towards the leading edge) and normal unit vectors of the zero-lift line,
        # their rates and the acceleration of e_c
        ec[i] = ct * x[6 + i] + st * x[9 + i]
        en[i] = -st * x[6 + i] + ct * x[9 + i]
        dec[i] = ct * xd[6 + i] + st * xd[9 + i]
        den[i] = -st * xd[6 + i] + ct * xd[9 + i]
        aec[i] = ct * xa[6 + i] + st * xa[9 + i]
        vair[i] = vinf[i]
    vair[2] = vair[2] - lam * omega_r
    u = 0.0 * x[0]
    w0 = 0.0 * x[0]
    w34 = 0.0 * x[0]
    w1 = 0.0 * x[0]
    for i in range(3):
        # air velocity relative to the chord points P(ξ) = x + ξ e_c
        w_mid[i] = vair[i] - xd[i] - xm * dec[i]
        w_34[i] = vair[i] - xd[i] - x34 * dec[i]
        w_qc[i] = vair[i] - xd[i] - xq * dec[i]
        u -= w_mid[i] * ec[i]
        w0 += w_mid[i] * en[i]
        w34 += w_34[i] * en[i]
        w1 += dec[i] * en[i]
    w1 = b * w1
    if n:
        lam0 = kappa * w34
        for j in range(n):
            lam0 += mu[j] * pb[j]
        ueff = np.sqrt(u * u + u_floor2)
        for j in range(n):
            rates[j] = -(ueff / b) * (mu[j] + w34 * ainv_c[j])
    else:
        lam0 = 0.0 * w34
    # Kutta–Joukowski at the quarter chord: F = ρΓ (u e_n + (w34 − λ0) e_c)
    wc = w34 - lam0
    gam = a_lift * b * wc
    # profile drag ½ρ c c_d0 |W⊥| W⊥, W⊥ the part of W(ξ_qc) normal to the span (d1)
    wd1 = 0.0 * x[0]
    d11 = 0.0 * x[0]
    for i in range(3):
        wd1 += w_qc[i] * x[3 + i]
        d11 += x[3 + i] * x[3 + i]
    r = wd1 / d11
    wpp = 0.0 * x[0]
    for i in range(3):
        w_qc[i] = w_qc[i] - r * x[3 + i]  # now W⊥
        wpp += w_qc[i] * w_qc[i]
    drag = rho * b * cd0 * np.sqrt(wpp)
    # apparent mass: rates of w0 and w1 along the motion (the inflow's rate left out)
    w0dot = 0.0 * x[0]
    w1dot = 0.0 * x[0]
    for i in range(3):
        f_qc[i] = (rho * gam) * (u * en[i] + wc * ec[i]) + drag * w_qc[i]
        w0dot += -(xa[i] + xm * aec[i]) * en[i] + w_mid[i] * den[i]
        w1dot += aec[i] * en[i] + dec[i] * den[i]
    w1dot = b * w1dot
    pib2 = math.pi * rho * b * b
    l_nc = pib2 * w0dot
    m_nc = -pib2 * (0.5 * u * w1 + 0.125 * b * w1dot)
    for i in range(3):
        f_mid[i] = l_nc * en[i]
    # a force F at P(ξ) works on x and, through ξ e_c = ξ (cos d2 + sin d3), on d2 and d3
    for i in range(3):
        g[i] = f_qc[i] + f_mid[i]
        g[3 + i] = 0.0
        g[6 + i] = (xq * ct) * f_qc[i] + (xm * ct) * f_mid[i]
        g[9 + i] = (xq * st) * f_qc[i] + (xm * st) * f_mid[i]
    # the pure moment m_nc e_s (e_s = d1) as director forces ½ (m e_s) × d_i
    m0, m1, m2 = m_nc * x[3], m_nc * x[4], m_nc * x[5]
    for d in range(3):
        o = 3 + 3 * d
        g[o] += 0.5 * (m1 * x[o + 2] - m2 * x[o + 1])
        g[o + 1] += 0.5 * (m2 * x[o] - m0 * x[o + 2])
        g[o + 2] += 0.5 * (m0 * x[o + 1] - m1 * x[o])
    # the section's share of the rotor load on the inflow states: W (F·ẑ) ds / (ρΩ²R⁴)
    fz = g[2] * ds * load_scale
    for i in range(ni):
        forcing[i] = wts[i] * fz
    for i in range(3):
        det[i] = g[i]
        det[3 + i] = f_qc[i]
        det[13 + i] = x[i]
        det[16 + i] = vair[i]
    det[6], det[7], det[8], det[9] = u, w0, w34, lam0
    det[10], det[11], det[12] = rho * gam * u, l_nc, m_nc


@njit(cache=True)
def airloads(x, xd, xa, mu, al, phi, wts, props, rho, air, omega_r, load_scale, u_floor2,
             kappa, pb, ainv_c, g, rates, forcing, det):
    """:func:`section_loads` of every section k (real): inputs (K, ·), the air's velocity at
    each section ``air`` (K, 3) (free stream and any prescribed wind), outputs g (K, 12),
    rates (K, N), forcing (K, n_i), det (K, 19)."""
    wk = np.empty((_WORK, 3))
    for k in range(x.shape[0]):
        section_loads(x[k], xd[k], xa[k], mu[k], al[k], phi[k], wts[k], props[k], rho, air[k],
                      omega_r, load_scale, u_floor2, kappa, pb, ainv_c, wk, g[k], rates[k],
                      forcing[k], det[k])


@njit(cache=True)
def local_jacobian(x, xd, xa, mu, al, phi, wts, phi_p, wts_p, props, rho, air, omega_r,
                   load_scale, u_floor2, kappa, pb, ainv_c, h, wq, wv, wa, combined, jac):
    """∂(g, rates, forcing)/∂(x, μ, α, ẋ, ẍ) of every section by complex steps i h of
    :func:`section_loads`, one input at a time; the inflow states α enter only through the
    section's λ = Φ·α, so one step along Φ/(Φ·Φ) gives ∂/∂λ, and column j is ∂/∂λ Φ_j.

    ``phi_p``, ``wts_p`` (3, K, n_i, complex) are Φ and W at the positions perturbed by
    i h wq along x, y, z (the only inputs they depend on); ``air`` (K, 3) the air's velocity
    at each section, as in :func:`airloads`. Without ``combined`` (and with ``wq`` = 1),
    ``jac`` (K, 12 + N + n_i, 36 + N + n_i) receives the derivatives, columns in the order
    x (12), μ (N), α (n_i), ẋ (12), ẍ (12). With ``combined`` it receives the Newton
    matrix's weighted sum (K, 12 + N + n_i, 12 + N + n_i): wq ∂/∂x + wv[k] ∂/∂ẋ + wa ∂/∂ẍ
    by the 12 coordinates, then wq ∂/∂μ and wq ∂/∂α. One complex step then moves a
    coordinate by i h wq, its rate by i h wv[k] and its acceleration by i h wa together (the
    derivative along that direction is the weighted sum): 12 + N + 1 evaluations a section
    instead of 36 + N + 1.
    """
    n, ni = mu.shape[1], al.shape[1]
    m = 12 + n + ni
    wk = np.empty((_WORK, 3), np.complex128)
    cx = np.empty(12, np.complex128)
    cxd = np.empty(12, np.complex128)
    cxa = np.empty(12, np.complex128)
    cmu = np.empty(n, np.complex128)
    cal = np.empty(ni, np.complex128)
    cph = np.empty(ni, np.complex128)
    cwt = np.empty(ni, np.complex128)
    out = np.empty(m, np.complex128)
    det = np.empty(DETAILS, np.complex128)
    step = 1j * h
    for k in range(x.shape[0]):
        for i in range(12):
            cx[i], cxd[i], cxa[i] = x[k, i], xd[k, i], xa[k, i]
        for i in range(n):
            cmu[i] = mu[k, i]
        for i in range(ni):
            cal[i], cph[i], cwt[i] = al[k, i], phi[k, i], wts[k, i]
        pp = 0.0
        for i in range(ni):
            pp += phi[k, i] * phi[k, i]
        col = 0
        for block in range(3 if combined else 5):
            if block == 2:  # α: one step of λ (no column if Φ = 0 here: λ takes no α)
                if pp > 0.0:
                    for i in range(ni):
                        cal[i] = al[k, i] + (step * wq) * (phi[k, i] / pp)
                    section_loads(cx, cxd, cxa, cmu, cal, cph, cwt, props[k], rho, air[k],
                                  omega_r, load_scale, u_floor2, kappa, pb, ainv_c, wk,
                                  out[:12], out[12 : 12 + n], out[12 + n :], det)
                    for i in range(ni):
                        cal[i] = al[k, i]
                for i in range(m):
                    d = out[i].imag / h if pp > 0.0 else 0.0  # ∂/∂λ
                    for c in range(ni):
                        jac[k, i, col + c] = d * phi[k, c]
                col += ni
                continue
            size = 12 if block in (0, 3, 4) else n
            arr = cx if block == 0 else (cmu if block == 1 else (cxd if block == 3 else cxa))
            for c in range(size):
                base = arr[c]
                arr[c] = base + step * (wq if block < 3 else 1.0)
                if combined and block == 0:  # the rate and the acceleration move with it
                    cxd[c] = xd[k, c] + step * wv[k]
                    cxa[c] = xa[k, c] + step * wa
                if block == 0 and c < 3:  # a position step moves the inflow shapes
                    ph, wt = phi_p[c, k], wts_p[c, k]
                else:
                    ph, wt = cph, cwt
                section_loads(cx, cxd, cxa, cmu, cal, ph, wt, props[k], rho, air[k], omega_r,
                              load_scale, u_floor2, kappa, pb, ainv_c, wk, out[:12],
                              out[12 : 12 + n], out[12 + n :], det)
                arr[c] = base
                if combined and block == 0:
                    cxd[c], cxa[c] = xd[k, c], xa[k, c]
                for i in range(m):
                    jac[k, i, col] = out[i].imag / h
                col += 1


@njit(cache=True)
def section_inputs(q, v, a, idx48, nnz, nz_r, nz_c, nz_s, x, xd, xa):
    """The sections' coordinates x, rates xd and accelerations xa (K, 12) from the support's
    48 global coordinates ``idx48`` (K, 48): x = S q with the map S (12 × 48: the beam's shape
    functions or a body's rigid offset) given by its ``nnz[k]`` nonzeros S[r, c] = s per
    section (``nz_r``, ``nz_c``, ``nz_s``, (K, L))."""
    for k in range(idx48.shape[0]):
        for r in range(12):
            x[k, r] = xd[k, r] = xa[k, r] = 0.0
        for e in range(nnz[k]):
            r, j, s = nz_r[k, e], idx48[k, nz_c[k, e]], nz_s[k, e]
            x[k, r] += s * q[j]
            xd[k, r] += s * v[j]
            xa[k, r] += s * a[j]


@njit(cache=True)
def support_forces(g, ds, nnz, nz_r, nz_c, nz_s, out):
    """Consistent loads on the support's 48 coordinates, out[k, :48] = Sᵀ g ds (N), S as in
    :func:`section_inputs`."""
    for k in range(g.shape[0]):
        for c in range(48):
            out[k, c] = 0.0
        for e in range(nnz[k]):
            out[k, nz_c[k, e]] += nz_s[k, e] * (g[k, nz_r[k, e]] * ds[k])


@njit(cache=True)
def expand_jacobian(jac, c0, nraw, ds, nnz, nz_r, nz_c, nz_s, out):
    """Global blocks of the local Jacobian ``jac`` (K, 12 + N + n_i, ·): its columns c0…c0+11
    (by the section's 12 coordinates, rates or accelerations) and the ``nraw`` after them (by
    the section's own states), rows and columns mapped to the support's coordinates,

        out[k] = [[Sᵀ ds J_xx S, Sᵀ ds J_xs],
                  [J_sx S,       J_ss     ]],

    out (K, 48 + N + n_i, 48 + nraw); S as in :func:`section_inputs`."""
    m = jac.shape[1]
    ncol = 12 + nraw
    rows = np.empty((48 + m - 12, ncol))
    for k in range(jac.shape[0]):
        # rows: the 12 force components to the 48 support coordinates through Sᵀ ds
        rows[:48, :] = 0.0
        for e in range(nnz[k]):
            r, c, s = nz_r[k, e], nz_c[k, e], nz_s[k, e] * ds[k]
            for j in range(ncol):
                rows[c, j] += s * jac[k, r, c0 + j]
        for i in range(m - 12):
            for j in range(ncol):
                rows[48 + i, j] = jac[k, 12 + i, c0 + j]
        # columns: by the 12 section inputs to by the 48 support coordinates through S
        for i in range(48 + m - 12):
            for c in range(48):
                out[k, i, c] = 0.0
            for e in range(nnz[k]):
                out[k, i, nz_c[k, e]] += rows[i, nz_r[k, e]] * nz_s[k, e]
            for j in range(nraw):
                out[k, i, 48 + j] = rows[i, 12 + j]


@njit(cache=True)
def peters_he_shapes(xi, eta, sine, harmonic, coef, ncoef, cr, sr, out):
    """Peters–He inflow shapes Φ_i = φ_j^r(r̄) (r̄^r cos rψ or r̄^r sin rψ) at disk points
    (real or complex: polynomials in ξ, η; :meth:`solver.inflow.DynamicInflow.shape`).

    Parameters
    ----------
    xi, eta
        (P,) disk coordinates ξ = r̄ cos ψ, η = r̄ sin ψ.
    sine, harmonic
        (n,) per state: 1 for a sine state (β), 0 for a cosine one (α); its harmonic r.
    coef, ncoef
        (n, L) coefficients c_k of φ_j^r = r̄^r Σ_k c_k r̄^{2k} (padded) and their counts (n,).
    cr, sr
        (M + 1,) work arrays of the points' dtype.
    out
        (P, n) the shapes (dimensionless).
    """
    nh = cr.shape[0]
    for p in range(xi.shape[0]):
        x, e = xi[p], eta[p]
        # r̄^r cos rψ and r̄^r sin rψ: real and imaginary parts of (ξ + iη)^r, by recursion
        cr[0], sr[0] = 1.0 + 0.0 * x, 0.0 * x
        for r in range(1, nh):
            cr[r] = cr[r - 1] * x - sr[r - 1] * e
            sr[r] = sr[r - 1] * x + cr[r - 1] * e
        rho2 = x * x + e * e
        for i in range(sine.shape[0]):
            poly = coef[i, ncoef[i] - 1] + 0.0 * x  # Horner in r̄²
            for c in range(ncoef[i] - 2, -1, -1):
                poly = poly * rho2 + coef[i, c]
            out[p, i] = poly * (sr[harmonic[i]] if sine[i] else cr[harmonic[i]])


@njit(cache=True)
def flow_terms(mu: float, lam_f: float, lam_m: float) -> tuple:
    """Finite-state inflow's flow parameters: V_T, V_m, X and their derivatives by λ_m.

    ``mu`` the in-plane and ``lam_f`` the through-disk free stream on ΩR, ``lam_m`` the
    momentum inflow (:class:`solver.inflow.DynamicInflow`): λ = λ_f + λ_m,
    V_T = √(μ² + λ²), V_m = (μ² + λ(λ + λ_m))/V_T, X = tan(χ/2) = μ/(V_T + λ); all zero with
    no flow at all (a hover start: f = 0 and ∂f/∂α = 0 there), X = 0 in axial flow."""
    lam = lam_f + lam_m
    vt = math.hypot(mu, lam)
    if vt == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    dvt = lam / vt
    num = mu * mu + lam * (lam + lam_m)
    vm = num / vt
    dvm = (3.0 * lam + lam_m - vm * dvt) / vt  # d num/dλ_m = 2λ + (λ + λ_m)
    if mu == 0.0:  # axial flow: no skew, whatever the sign of λ
        return vt, vm, 0.0, dvt, dvm, 0.0
    den = vt + lam  # > 0 when μ ≠ 0; tan(χ/2) = sin χ/(1 + cos χ)
    return vt, vm, mu / den, dvt, dvm, -mu * (dvt + 1.0) / (den * den)


@njit(cache=True)
def inflow_rhs(a: Array, mom: Array, lp: Array, mu: float, lam_f: float, jacobian: bool,
               jac: Array) -> Array:
    """f = −V L(X)⁻¹ α of a finite-state inflow (dimensionless), with V = (V_T, V_m, …, V_m)
    and L(X) = Σ_p X^p L_p (``lp`` (P, n, n)); with ``jacobian`` also ∂f/∂α into ``jac``
    (n × n): d(L⁻¹α) = L⁻¹dα − L⁻¹ (dL/dX) L⁻¹α dX, dX = (dX/dλ_m) m·dα, dV = (dV/dλ_m) m·dα,
    λ_m = m·α (``mom``)."""
    n = a.shape[0]
    lam_m = 0.0
    for i in range(n):
        lam_m += mom[i] * a[i]
    vt, vm, x, dvt, dvm, dx = flow_terms(mu, lam_f, lam_m)
    big = lp[lp.shape[0] - 1].copy()  # Horner in X
    for p in range(lp.shape[0] - 2, -1, -1):
        big = big * x + lp[p]
    u = np.linalg.solve(big, a)  # L⁻¹α
    f = np.empty(n)
    for i in range(n):
        f[i] = -(vt if i == 0 else vm) * u[i]  # the thrust state sees the total flow
    if jacobian:
        dbig = np.zeros((n, n))  # dL/dX = Σ_p p X^(p−1) L_p
        for p in range(lp.shape[0] - 1, 0, -1):
            dbig = dbig * x + p * lp[p]
        inv = np.linalg.inv(big)
        w = inv @ (dbig @ u)
        for i in range(n):
            v = vt if i == 0 else vm
            dv = dvt if i == 0 else dvm
            for j in range(n):
                jac[i, j] = -v * (inv[i, j] - w[i] * dx * mom[j]) - dv * u[i] * mom[j]
    return f
