"""Unsteady 2-D thin-airfoil theory: Peters' finite-state inflow and the classical references.

Pure functions, no solver element. They give

* the constants of the Peters, Karunamoorthy & Cao (J. Aircraft 32(2), 1995) finite-state
  model (:func:`peters_matrices`), with the conventions of byuflowlab/Aeroelasticity.jl
  ``peters.jl``;
* the model's frequency response (:func:`lift_deficiency`) and indicial response
  (:func:`peters_step_response`);
* the exact references they approximate: Theodorsen's function (:func:`theodorsen`), Wagner's
  function (:func:`wagner`) and Theodorsen's airloads for harmonic plunge and pitch
  (:func:`harmonic_airloads`).

**The finite-state model.** The wake's induced downwash on the plate is represented by N inflow
states λ_n (m/s) whose weighted sum is the mean induced inflow λ0 (dots are d/dt):

    A λ̇ + (U/b) λ = c ẇ,        λ0 = ½ bᵀ λ,        L_circ = 2π ρ U b (w − λ0),

where w (m/s) is the normal velocity of the three-quarter-chord point relative to the air,
positive down (air meeting the plate from below, i.e. upward lift), w = ḣ + U α + b(½ − a) α̇.
Reduced time is s = U t / b (semichords travelled). For harmonic motion, w = w̄ e^{iωt}, the
circulatory lift is 2π ρ U b C_N(k) w̄ with the reduced frequency k = ω b / U and

    C_N(k) = 1 − ½ bᵀ (I + i k A)⁻¹ c (i k),

which must approach Theodorsen's C(k) as N grows. With the binomial b_n of the 1995 paper it does
so only up to N ≈ 10; from N = 11 on the error grows again, and at N = 16 the model is
unstable: two eigenvalues of A have negative real parts (a pole of C_N in the lower half
k-plane; N = 17 is unstable too). This is a property of the b_n, not of rounding: the same
happens in exact rational arithmetic (Routh count of the exact characteristic polynomial).

Measured convergence (max over k ∈ [0.01, 2] of |C_N − C|, refined with a bounded search; from
N = 4 on an odd N is worse than the even N below it):

====  =======  ====  =======
N     error    N     error
====  =======  ====  =======
1     0.196    7     0.0203
2     0.144    8     0.00965
3     0.0725   9     0.0125
4     0.0345   10    0.00853
5     0.0365   11    0.0146
6     0.0158   12    0.0316
====  =======  ====  =======

Hence the supported range 1 ≤ N ≤ :data:`MAX_STATES` = 10 (N = 11 is already worse than N = 9,
N = 12 worse than N = 6, and A's condition number passes 10⁸ at N = 11) and
:data:`DEFAULT_STATES` = 8: the smallest N whose frequency-response error is below 1 % of
C(0) = 1 over k ∈ [0.01, 2]; its indicial response is then within 0.0075 of Wagner's for
s ∈ [0, 1000]. N = 10 improves the frequency-response error by only 12 % for 25 % more states per
section, which over the ~100 sections of a rotor is 200 more first-order unknowns.

Measured max over s ∈ [0, 1000] of |φ_N(s) − φ(s)| (Wagner): 0.162, 0.120, 0.041, 0.029, 0.020,
0.013, 0.011, 0.0074, 0.0071, 0.0055 for N = 1 … 10 (R. T. Jones' two-exponential fit: 0.0096).

**Initial lift.** φ_N(0+) = 1 − ½ bᵀ A⁻¹ c (:func:`circulatory_fraction`) equals Wagner's ½ only
approximately: exactly for N = 2, and to 1.3e-2, 1.0e-3, 5.5e-5, 2.5e-6 for N = 4, 6, 8, 10
(exact rationals, e.g. ½ bᵀ A⁻¹ c = 19/39 for N = 4 and 4559/9119 for N = 8).

Sign conventions (Theodorsen, Bisplinghoff–Ashley–Halfman §5-6, Hodges & Pierce §5.4): plunge h
positive down, pitch α positive nose up, lift L positive up, moment M positive nose up about the
elastic axis, which lies a·b aft of mid-chord (a = −½ quarter chord, a = 0 mid-chord).
"""

from __future__ import annotations

import functools
import numbers
from collections.abc import Callable
from math import factorial

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import integrate
from scipy.linalg import expm
from scipy.special import hankel2

#: Largest number of Peters states accepted (the binomial b_n stop converging beyond it).
MAX_STATES = 10

#: Default number of Peters states: smallest N with max_k∈[0.01,2] |C_N(k) − C(k)| < 0.01.
DEFAULT_STATES = 8


def _check_states(n: object) -> int:
    """Validate a number of inflow states; return it as a Python int."""
    if isinstance(n, bool) or not isinstance(n, numbers.Integral):
        raise TypeError(f"n (number of Peters inflow states) must be an integer, got {n!r}")
    n = int(n)
    if not 1 <= n <= MAX_STATES:
        raise ValueError(
            f"n = {n} Peters inflow states is outside the supported range 1 <= n <= {MAX_STATES}:"
            " the binomial coefficients b_n stop converging to Theodorsen's C(k) beyond"
            f" n = {MAX_STATES} (the error grows from n = 11 and the model is unstable for"
            " n >= 16, even in exact arithmetic)"
        )
    return n


@functools.cache
def _constants(n: int) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Cached, read-only (A, b, c) for a validated n."""
    idx = np.arange(1, n + 1)
    # Induced-inflow weights: a truncated binomial series (integers, exact in float64 for
    # n <= MAX_STATES), with the last weight fixed to ±1.
    b = np.empty(n)
    for m in range(1, n):
        b[m - 1] = (-1) ** (m - 1) * (
            factorial(n + m - 1) // (factorial(n - m - 1) * factorial(m) ** 2)
        )
    b[n - 1] = (-1) ** (n - 1)
    # Forcing weights: the downwash rate enters state m as 2/m.
    c = 2.0 / idx
    d = np.zeros(n)
    d[0] = 0.5
    # Bidiagonal coupling from the recurrence of the Glauert expansion of the wake vorticity.
    D = np.zeros((n, n))
    D[idx[1:] - 1, idx[1:] - 2] = 1.0 / (2.0 * idx[1:])
    D[idx[:-1] - 1, idx[:-1]] = -1.0 / (2.0 * idx[:-1])
    A = D + np.outer(d, b) + np.outer(c, d) + 0.5 * np.outer(c, b)
    for arr in (A, b, c):
        arr.setflags(write=False)
    return A, b, c


def peters_matrices(
    n: int = DEFAULT_STATES,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Constants of the Peters–Karunamoorthy–Cao finite-state inflow model.

    The model is ``A λ̇ + (U/b) λ = c ẇ`` with the mean induced inflow ``λ0 = ½ bᵀ λ`` and the
    circulatory lift proportional to ``w − λ0``, ``w`` the normal velocity at the 3/4 chord.

    Parameters
    ----------
    n : int
        Number of inflow states N, 1 ≤ N ≤ :data:`MAX_STATES`.

    Returns
    -------
    A : ndarray, shape (N, N)
        Dimensionless "mass" matrix, ``A = D + d bᵀ + c dᵀ + ½ c bᵀ`` with
        ``D[m, m−1] = 1/(2m)``, ``D[m, m+1] = −1/(2m)`` (1-based m) and ``d = (½, 0, …)``.
    b : ndarray, shape (N,)
        Inflow weights, ``b_m = (−1)^{m−1} (N+m−1)! / [(N−m−1)! (m!)²]`` for m < N and
        ``b_N = (−1)^{N−1}``.
    c : ndarray, shape (N,)
        Forcing weights ``c_m = 2/m``.

    Raises
    ------
    TypeError
        If ``n`` is not an integer.
    ValueError
        If ``n`` is outside ``1 … MAX_STATES``.

    Notes
    -----
    Fresh, writable copies are returned on every call.
    """
    A, b, c = _constants(_check_states(n))
    return A.copy(), b.copy(), c.copy()


def circulatory_fraction(n: int = DEFAULT_STATES) -> float:
    """Fraction ``½ bᵀ A⁻¹ c`` of a downwash step taken up at once by the induced inflow.

    Immediately after a unit step in ``w`` the states jump to ``λ(0+) = A⁻¹ c`` (integrate the
    state equation across the step), so the finite-state indicial lift starts at
    ``φ_N(0+) = 1 − ½ bᵀ A⁻¹ c`` and equals ``1 − C_N(∞)``. Wagner's (and Theodorsen's
    ``C(∞)``) value is ½.

    Parameters
    ----------
    n : int
        Number of inflow states, 1 ≤ N ≤ :data:`MAX_STATES`.

    Returns
    -------
    float
        ``½ bᵀ A⁻¹ c`` (dimensionless). It is exactly ½ only for N = 2; otherwise it approaches
        ½ geometrically with N (19/39 at N = 4, 4559/9119 at N = 8).
    """
    A, b, c = _constants(_check_states(n))
    return float(0.5 * b @ np.linalg.solve(A, c))


def theodorsen(k: ArrayLike) -> NDArray[np.complex128] | complex:
    """Theodorsen's lift-deficiency function ``C(k) = F(k) + i G(k)``.

    ``C(k) = H1⁽²⁾(k) / (H1⁽²⁾(k) + i H0⁽²⁾(k))`` with the Hankel functions of the second kind
    (time factor ``e^{iωt}``): the ratio of the circulatory lift of a harmonically oscillating
    plate to its quasi-steady value, the wake's lag and attenuation.

    Parameters
    ----------
    k : array_like
        Reduced frequency ``k = ω b / U`` (dimensionless), ``k ≥ 0``. ``C(0) = 1`` (steady
        flow) and ``C(∞) = ½``.

    Returns
    -------
    complex or ndarray of complex
        ``C(k)``, same shape as ``k`` (a Python complex for scalar input).

    Raises
    ------
    ValueError
        If any ``k`` is negative or NaN.
    """
    kk = np.asarray(k, dtype=float)
    if np.any(np.isnan(kk)) or np.any(kk < 0.0):
        raise ValueError("theodorsen: the reduced frequency k must be >= 0 (and not NaN)")
    out = np.empty(kk.shape, dtype=complex)
    # C = 1 / (1 + i H0/H1): H1 ~ 2i/(πk) dominates as k → 0, so C → 1; for very small k the
    # Hankel functions overflow, and there C = 1 to far below double precision anyway
    # (C − 1 = O(k ln k)).
    tiny = kk < 1e-250
    big = np.isinf(kk)
    mid = ~(tiny | big)
    km = kk[mid]
    out[mid] = 1.0 / (1.0 + 1j * hankel2(0, km) / hankel2(1, km))
    out[tiny] = 1.0
    out[big] = 0.5
    return complex(out[()]) if out.ndim == 0 else out


def lift_deficiency(k: ArrayLike, n: int = DEFAULT_STATES) -> NDArray[np.complex128] | complex:
    """Lift-deficiency function of the N-state Peters model, its approximation of ``C(k)``.

    For ``w = w̄ e^{iωt}`` the states respond as ``λ̄ = (I + i k A)⁻¹ c (i k) w̄`` and the
    circulatory lift is proportional to ``w̄ − λ̄0``, so

        C_N(k) = 1 − ½ bᵀ (I + i k A)⁻¹ c (i k).

    Parameters
    ----------
    k : array_like
        Reduced frequency ``k = ω b / U`` (dimensionless), ``k ≥ 0``.
    n : int
        Number of inflow states, 1 ≤ N ≤ :data:`MAX_STATES`.

    Returns
    -------
    complex or ndarray of complex
        ``C_N(k)``, same shape as ``k``. ``C_N(0) = 1`` exactly.

    Raises
    ------
    ValueError
        If ``n`` is out of range or any ``k`` is negative, infinite or NaN.
    """
    A, b, c = _constants(_check_states(n))
    kk = np.asarray(k, dtype=float)
    if not np.all(np.isfinite(kk)) or np.any(kk < 0.0):
        raise ValueError("lift_deficiency: the reduced frequency k must be finite and >= 0")
    flat = kk.reshape(-1)
    eye = np.eye(A.shape[0])
    # One small complex solve per frequency, batched: (I + i k A) x = c i k.
    mats = eye[None, :, :] + 1j * flat[:, None, None] * A[None, :, :]
    rhs = (1j * flat[:, None] * c[None, :])[:, :, None]
    lam = np.linalg.solve(mats, rhs)[:, :, 0]
    out = (1.0 - 0.5 * lam @ b).reshape(kk.shape)
    return complex(out[()]) if out.ndim == 0 else out


def _real_theodorsen(k: float) -> float:
    """F(k) = Re C(k) for one k > 0 (scalar fast path for the quadrature)."""
    return (1.0 / (1.0 + 1j * hankel2(0, k) / hankel2(1, k))).real


def _wagner_scalar(s: float) -> float:
    """Wagner's function at one reduced time 0 < s < ∞ (see :func:`wagner`)."""

    def g(k: float) -> float:
        return (_real_theodorsen(k) - 0.5) / k

    # φ(s) = (2/π)∫₀^∞ F(k) sin(ks)/k dk. F(∞) = ½ and (2/π)∫₀^∞ ½ sin(ks)/k dk = ½ for s > 0,
    # so only the remainder (F − ½)/k, which decays like k⁻³, is integrated numerically, in
    # three pieces:
    # * [0, k1], k1 ≤ half a period of sin(ks): no oscillation; (F − ½)/k ~ 1/(2k) there, but
    #   (F − ½) sin(ks)/k is bounded, with a k ln k term in F that adaptive QAGS resolves;
    # * [k1, K]: QUADPACK's Clenshaw–Curtis rule for the weight sin(ks) (QAWO), any s;
    # * [K, ∞): QUADPACK's Fourier-integral rule (QAWF), cycle by cycle with extrapolation.
    k1 = min(1.0, np.pi / s)
    k_tail = 4.0
    tol = 1e-11
    head, _ = integrate.quad(
        lambda k: g(k) * np.sin(k * s), 0.0, k1, limit=200, epsabs=tol, epsrel=tol
    )
    mid, _ = integrate.quad(g, k1, k_tail, weight="sin", wvar=s, limit=400, epsabs=tol, epsrel=tol)
    tail, _ = integrate.quad(g, k_tail, np.inf, weight="sin", wvar=s, limlst=100, epsabs=tol)
    return 0.5 + 2.0 / np.pi * (head + mid + tail)


def wagner(s: ArrayLike) -> NDArray[np.float64] | float:
    """Wagner's indicial lift function φ(s), exact (by quadrature of Theodorsen's F).

    Circulatory lift after a unit step in the 3/4-chord downwash, as a fraction of its final
    value: ``L_circ(s) = 2π ρ U b w φ(s)``. Computed from

        φ(s) = (2/π) ∫₀^∞ F(k) sin(k s) / k dk,      F = Re C,

    to about 1e-11 (checked against mpmath's ``quadosc`` at 20 digits for s = 1, 10, 50). The
    apparent-mass impulse at s = 0 is not included.

    Parameters
    ----------
    s : array_like
        Reduced time ``s = U t / b`` (semichords travelled since the step).

    Returns
    -------
    float or ndarray
        φ(s): 0 for s < 0, ½ at s = 0 (the value just after the step), → 1 as s → ∞.
    """
    ss = np.asarray(s, dtype=float)
    if np.any(np.isnan(ss)):
        raise ValueError("wagner: s must not be NaN")
    out = np.empty(ss.shape)
    for i, si in np.ndenumerate(ss):
        if si < 0.0:
            out[i] = 0.0
        elif si == 0.0:
            out[i] = 0.5
        elif np.isinf(si):
            out[i] = 1.0
        else:
            out[i] = _wagner_scalar(float(si))
    return float(out[()]) if out.ndim == 0 else out


def peters_step_response(s: ArrayLike, n: int = DEFAULT_STATES) -> NDArray[np.float64] | float:
    """Indicial lift of the N-state Peters model, its approximation of Wagner's φ(s).

    A unit step in ``w`` at s = 0 makes the states jump to ``λ(0+) = A⁻¹ c`` (the state
    equation integrated across the step); afterwards ``dλ/ds = −A⁻¹ λ``, so
    ``λ(s) = exp(−A⁻¹ s) λ(0+)`` and ``φ_N(s) = 1 − ½ bᵀ λ(s)``.

    Parameters
    ----------
    s : array_like
        Reduced time ``s = U t / b``, s ≥ 0.
    n : int
        Number of inflow states, 1 ≤ N ≤ :data:`MAX_STATES`.

    Returns
    -------
    float or ndarray
        φ_N(s), same shape as ``s``; ``φ_N(0) = 1 −`` :func:`circulatory_fraction`.
    """
    A, b, c = _constants(_check_states(n))
    ss = np.asarray(s, dtype=float)
    if not np.all(np.isfinite(ss)) or np.any(ss < 0.0):
        raise ValueError("peters_step_response: s must be finite and >= 0")
    Ainv = np.linalg.inv(A)
    lam0 = np.linalg.solve(A, c)  # the jump across the step, as in circulatory_fraction
    # A is far from normal (eigenvector condition number ~1e4 at N = 8, ~2e5 at N = 10), so
    # the transition matrix is taken by scaling and squaring (one batched expm), not by
    # eigenvector expansion.
    flat = ss.reshape(-1)
    lam = expm(-Ainv[None, :, :] * flat[:, None, None]) @ lam0
    out = (1.0 - 0.5 * lam @ b).reshape(ss.shape)
    return float(out[()]) if out.ndim == 0 else out


def harmonic_airloads(
    b: float,
    a: float,
    U: float,
    rho: float,
    omega: ArrayLike,
    h_amp: complex,
    alpha_amp: complex,
    deficiency: Callable[[ArrayLike], ArrayLike] = theodorsen,
) -> tuple[NDArray[np.complex128] | complex, NDArray[np.complex128] | complex]:
    """Theodorsen's lift and moment amplitudes for harmonic plunge and pitch.

    Motion ``h = h̄ e^{iωt}`` (plunge of the elastic axis, positive down) and
    ``α = ᾱ e^{iωt}`` (pitch, positive nose up) about an elastic axis ``a·b`` aft of mid-chord,
    in a free stream ``U``. With the 3/4-chord downwash ``w = ḣ + U α + b(½ − a) α̇``,

        L = π ρ b² (ḧ + U α̇ − b a α̈) + 2π ρ U b C(k) w,
        M = π ρ b² [b a ḧ − U b (½ − a) α̇ − b² (⅛ + a²) α̈] + 2π ρ U b² (a + ½) C(k) w.

    The first terms are the apparent-mass (non-circulatory) loads: the fluid mass π ρ b² of the
    circumscribed cylinder accelerating with the mid-chord, its rotary inertia π ρ b⁴/8 and the
    π ρ b² U α̇ lift acting at the 3/4 chord. The circulatory lift 2π ρ U b C(k) w acts at the
    quarter chord, a lever b(a + ½) ahead of the elastic axis.

    Parameters
    ----------
    b : float
        Semichord (m), > 0.
    a : float
        Elastic-axis position aft of mid-chord in semichords (dimensionless).
    U : float
        Free-stream speed (m/s), > 0.
    rho : float
        Air density (kg/m³).
    omega : array_like
        Circular frequency ω (rad/s), ≥ 0; the reduced frequency is ``k = ω b / U``.
    h_amp : complex
        Plunge amplitude h̄ (m), positive down.
    alpha_amp : complex
        Pitch amplitude ᾱ (rad), positive nose up.
    deficiency : callable, optional
        Lift-deficiency function of k; :func:`theodorsen` by default. For the finite-state
        model pass ``lambda k: lift_deficiency(k, n)``.

    Returns
    -------
    L : complex or ndarray of complex
        Lift amplitude per unit span (N/m), positive up.
    M : complex or ndarray of complex
        Pitching-moment amplitude per unit span about the elastic axis (N·m/m), positive nose
        up.

    Notes
    -----
    The physical loads are ``Re(L̄ e^{iωt})`` and ``Re(M̄ e^{iωt})`` for the physical motion
    ``Re(h̄ e^{iωt})``, ``Re(ᾱ e^{iωt})``.

    Checks of the formulas (signs and lever arms): the apparent-mass terms rebuilt from the
    cylinder mass at mid-chord (which moves down by h − a b α), its rotary inertia and the
    3/4-chord π ρ b² U α̇ force; the circulatory moment vanishing about the quarter chord
    (a = −½); the classical real form of the pure-plunge lift with F and G; the
    normal force and moment of Aeroelasticity.jl's ``peters_loads``, which, moved from its
    reference point to the elastic axis, expand to the same L and M; and a time integration of
    the Peters states against this function with ``deficiency = C_N``.
    """
    if not b > 0.0 or not U > 0.0:
        raise ValueError(f"harmonic_airloads: need b > 0 and U > 0, got b = {b!r}, U = {U!r}")
    w = np.asarray(omega, dtype=float)
    if np.any(w < 0.0):
        raise ValueError("harmonic_airloads: omega must be >= 0 (use the complex conjugate)")
    k = w * b / U
    C = np.asarray(deficiency(k), dtype=complex)
    iw = 1j * w
    # Time derivatives of e^{iωt} motions: d/dt → iω.
    hd, hdd = iw * h_amp, iw**2 * h_amp
    ad, add = iw * alpha_amp, iw**2 * alpha_amp
    w34 = hd + U * alpha_amp + b * (0.5 - a) * ad  # 3/4-chord downwash amplitude
    circ = 2.0 * np.pi * rho * U * b * C * w34  # circulatory lift, acting at the 1/4 chord
    lift = np.pi * rho * b**2 * (hdd + U * ad - b * a * add) + circ
    moment = (
        np.pi * rho * b**2 * (b * a * hdd - U * b * (0.5 - a) * ad - b**2 * (0.125 + a**2) * add)
        + b * (a + 0.5) * circ
    )
    if np.ndim(lift) == 0:
        return complex(lift), complex(moment)
    return lift, moment
