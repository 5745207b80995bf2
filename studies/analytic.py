"""Closed-form and quadrature results the studies are validated against.

Each formula cites the paper (Bauchau, Rodriguez & Chen, JAHS 2003) as corrected by its errata.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import quad
from scipy.special import ellipk


def pendulum_period(omega0: float, amplitude: float) -> float:
    """Eq. (8) corrected (errata 1): T = 4 K(k)/ω0, k = sin(θ0/2) (s; ω0 in rad/s, θ0 in rad)."""
    k = np.sin(0.5 * amplitude)
    return 4.0 * float(ellipk(k * k)) / omega0


def collar_circle_period(radius: float, gravity: float, theta0: float, mass: float,
                         inertia: float = 0.0) -> float:
    """Collar on a circle (cases 1 and 2): Eq. (8) with ω² = (g/R)/(1 + ρ²/R²), ρ² = Ip/m
    (errata 2: the paper prints the factor inverted)."""
    rho2 = inertia / mass
    omega = np.sqrt(gravity / radius / (1.0 + rho2 / radius**2))
    return pendulum_period(omega, theta0)


def collar_cycloid_period(a: float, gravity: float, theta0: float, mass: float,
                          inertia: float = 0.0) -> float:
    """Collar on the cycloid p(t) = a(t + sin t) i1 − a(1 + cos t) i2 released at tangent
    angle θ0 (rad). Case 1 (Ip = 0): Eq. (26), T = 4π√(a/g), the tautochrone. Case 2: Eq. (27)
    with y0 the release height above the lowest point, y0 = 2a sin²θ0 (errata 3)."""
    if inertia == 0.0:
        return 4.0 * np.pi * np.sqrt(a / gravity)
    rho2 = inertia / mass
    y0 = 2.0 * a * np.sin(theta0) ** 2

    def f(u: float) -> float:  # Eq. (27) integrand times √(u − u²) (the algebraic weight)
        return np.sqrt(0.5 + rho2 / (16.0 * a * a) / (2.0 - (y0 / a) * u))

    val, _ = quad(f, 0.0, 1.0, weight="alg", wvar=(-0.5, -0.5), epsabs=1e-14, epsrel=1e-13,
                  limit=200)
    return 4.0 * np.sqrt(2.0 * a / gravity) * val


def collar_cycloid_period_energy(a: float, gravity: float, theta0: float, mass: float,
                                 inertia: float = 0.0) -> float:
    """The same period derived independently from the energy integral in the tangent angle φ:
    ½(16 m a² cos²φ + Ip) φ̇² = 2 m g a (sin²θ0 − sin²φ), with sin φ = sin θ0 sin ψ,
    T = 4 ∫₀^{π/2} √(4a/g + ρ²/(4 g a cos²φ)) dψ. Used to cross-check Eq. (27)."""
    rho2 = inertia / mass
    s0 = np.sin(theta0)

    def f(psi: float) -> float:
        c2 = 1.0 - (s0 * np.sin(psi)) ** 2
        return np.sqrt(4.0 * a / gravity + rho2 / (4.0 * gravity * a * c2))

    val, _ = quad(f, 0.0, 0.5 * np.pi, epsabs=1e-14, epsrel=1e-13, limit=200)
    return 4.0 * val


def bifilar_order_circular(hub_speed: float, arm_radius: float, cm_offset: float,
                           hole_diameter: float, pin_diameter: float, tuning_mass: float,
                           pin_mass: float = 0.0, pin_inertia: float = 0.0) -> float:
    """Eq. (7) (errata 5: m_p, I_p per pin, two pins): the tuning order ω/Ω of a bifilar with
    equal circular holes of diameter D and pins of diameter d; R = R0 + Rm."""
    r_cm = arm_radius + cm_offset
    num = tuning_mass + pin_mass * arm_radius / r_cm
    den = tuning_mass + 0.5 * pin_mass + 2.0 * pin_inertia / pin_diameter**2
    return float(np.sqrt(num / den * r_cm / (hole_diameter - pin_diameter)))


def hole_diameter_for_order(order: float, arm_radius: float, cm_offset: float,
                            pin_diameter: float, tuning_mass: float, pin_mass: float = 0.0,
                            pin_inertia: float = 0.0) -> float:
    """Eq. (7) solved for the hole diameter D (m) that tunes the bifilar to ``order``."""
    r_cm = arm_radius + cm_offset
    num = tuning_mass + pin_mass * arm_radius / r_cm
    den = tuning_mass + 0.5 * pin_mass + 2.0 * pin_inertia / pin_diameter**2
    return float(pin_diameter + num / den * r_cm / order**2)


def amplitude_frequency_ratio(amplitude: float) -> float:
    """ω(A)/ω(0) = π / (2 K(sin(A/2))) of a simple pendulum of amplitude A (rad)."""
    k = np.sin(0.5 * amplitude)
    return float(np.pi / (2.0 * ellipk(k * k)))
