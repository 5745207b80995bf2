r"""Backbones: a bifilar's free-vibration tuning order against its swing amplitude.

The backbone is the unforced, undamped branch of periodic responses of one bifilar on a hub
spinning at Ω about a fixed centre: the swing equation of :mod:`studies.reduced_hub` with
z̈ = 0 and no rolling resistance,

    J(σ) σ̈ + ½ J'(σ) σ̇² = Ω² Re(conj(m_b Γ + m_p π) Γ'),

a conservative, time-reversible oscillator. Its free oscillation through the vertex is even
in time, σ(t) = Σ_{k=0…H} a_k cos kωt, and the harmonic balance solves the cosine
projections of the residual for a_0, a_2…a_H and ω with the amplitude fixed by σ(0) (the
turning point, where the pin angle is largest). The tuning order is ω/Ω: constant for the
epicycloid (the tautochrone of the centrifugal field), falling as the pendulum's law
π/(2K(sin(φ/2))) for a circle, as the classical result for a circular-path centrifugal
pendulum.

:func:`order_by_quadrature` gives the same order independently, from the energy integral
T = 2 ∫ √(J / 2(V(σ_a) − V(σ))) dσ between the turning points (Gauss–Legendre after a sine
substitution that removes the endpoints' square-root singularities).
"""

from __future__ import annotations

import numpy as np
import scipy.optimize
from numpy.typing import NDArray

from studies.holes import Holes
from studies.reduced_hub import (
    ReducedHub,
    _newton,
    _swing_residual,
    path_terms,
    swing_stiffness,
)

Array = NDArray[np.float64]
HARMONICS = 24  # cosine harmonics of the swing (the 60° circle's 24th is ~1e-14 rad)
SAMPLES = 128
TOLERANCE = 1e-11  # rad: the residual's harmonics over the swing's stiffness
QUADRATURE_NODES = 64


def _free_model(holes: Holes, hub_speed: float) -> ReducedHub:
    """One bifilar on a fixed, unforced hub without rolling resistance."""
    return ReducedHub(holes, hub_speed, np.zeros(1), 1.0, 0.0, 0.0, np.zeros(0),
                      np.zeros(0, dtype=complex), 0.0)


def _residual(model: ReducedHub, coeffs: Array, order: float, samples: int) -> Array:
    """The swing equation's cosine projections (over K) for σ = Σ a_k cos(k ν Ω t)."""
    h = len(coeffs) - 1
    nu = order * model.hub_speed
    theta = 2 * np.pi * np.arange(samples) / samples
    k = np.arange(h + 1)
    c, s = np.cos(np.outer(theta, k)), np.sin(np.outer(theta, k))
    sig = c @ coeffs
    sig_d = -(s * (k * nu)) @ coeffs
    sig_dd = -(c * (k * nu) ** 2) @ coeffs
    zero = np.zeros(samples)
    r = _swing_residual(model, path_terms(model.holes, sig), sig_d, sig_dd,
                        zero.astype(complex), zero)
    proj = (c.T @ r) * (2.0 / samples)
    proj[0] *= 0.5
    return proj / swing_stiffness(model.holes, model.hub_speed)


def backbone(holes: Holes, hub_speed: float, amplitudes: Array,
             harmonics: int = HARMONICS, samples: int = SAMPLES) -> Array:
    """The free-vibration tuning order ω/Ω at each pin-angle amplitude (rad, increasing, > 0),
    NaN beyond the holes' extent or where the balance fails.

    Each amplitude is solved by Newton's method from the previous one's solution (the first
    from the linear order), the amplitude fixed by σ(0) = σ(φ_a).
    """
    model = _free_model(holes, hub_speed)
    a = np.zeros(harmonics + 1)
    order = holes.order_linear
    out = np.full(len(amplitudes), np.nan)
    last = 0.0
    for i, amp in enumerate(amplitudes):
        try:
            sigma_a = float(holes.sigma_of_angle(float(amp)))
        except (ValueError, RuntimeError):
            break
        if a[1] == 0.0:
            a[1] = sigma_a
        else:  # scale the previous shape to the new turning point
            a *= sigma_a / last
        last = sigma_a

        def equations(u: Array, sigma_a: float = sigma_a) -> Array:
            # unknowns a_0, a_2…a_H, ω/Ω; a_1 from σ(0) = Σ a_k = σ_a
            coeffs = np.concatenate([u[:1], [sigma_a - u[0] - u[1:-1].sum()], u[1:-1]])
            return _residual(model, coeffs, u[-1], samples)

        u0 = np.concatenate([a[:1], a[2:], [order]])
        # Newton with a fixed difference step (the unknowns are angles; MINPACK's steps
        # relative to |u| fail on the harmonics that are zero for a symmetric hole)
        u, err = _newton(lambda v, _: equations(v), u0, 1.0)
        if not err <= TOLERANCE:
            break
        a = np.concatenate([u[:1], [sigma_a - u[0] - u[1:-1].sum()], u[1:-1]])
        order = float(u[-1])
        out[i] = order
    return out


def order_by_quadrature(holes: Holes, hub_speed: float, amplitude: float,
                        nodes: int = QUADRATURE_NODES) -> float:
    """The free-vibration tuning order at pin-angle ``amplitude`` (rad) from the energy
    integral (module docstring): an independent check of :func:`backbone`."""
    model = _free_model(holes, hub_speed)
    g = holes.geometry
    c_j = g.tuning_mass + 0.5 * g.pin_mass + 2 * g.pin_inertia / g.pin_diameter**2
    xg, wg = np.polynomial.legendre.leggauss(nodes)

    def force(s: Array) -> Array:  # Ω² Re(conj(m_b Γ + m_p π) Γ'): the swing's restoring force
        zero = np.zeros(np.shape(s))
        return -_swing_residual(model, path_terms(holes, s), zero, zero, zero.astype(complex),
                                zero)

    def potential(s: float) -> float:  # V(σ) = −∫_0^σ force
        return float(-0.5 * s * np.sum(wg * force(0.5 * s * (xg + 1))))

    def half(sigma_a: float) -> float:  # ∫_0^{σ_a} dσ/σ̇ with σ = σ_a sin θ
        theta = 0.25 * np.pi * (xg + 1)
        s = sigma_a * np.sin(theta)
        v_a = potential(sigma_a)
        dv = np.array([v_a - potential(si) for si in s])
        jac = c_j * np.abs(path_terms(holes, s)[1]) ** 2
        integrand = np.sqrt(jac / (2 * dv)) * sigma_a * np.cos(theta)
        return abs(float(0.25 * np.pi * np.sum(wg * integrand)))  # a time, either side

    sigma_a = float(holes.sigma_of_angle(amplitude))
    v_a = potential(sigma_a)
    # the other turning point: the same potential on the other side of the vertex
    sigma_b = scipy.optimize.brentq(lambda s: potential(s) - v_a, -1.5 * sigma_a,
                                    -0.5 * sigma_a, xtol=1e-15)
    period = 2 * (half(sigma_a) + half(sigma_b))
    return 2 * np.pi / period / hub_speed

