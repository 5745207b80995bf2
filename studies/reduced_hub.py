r"""The hub model reduced to its swing coordinates, and its periodic response by harmonic balance.

The multibody hub (:mod:`studies.hub`) is, for rigid bodies rolling without sliding, exactly a
system of 2 + N coordinates: the hub centre z (complex, in-plane, fixed frame) and each
bifilar's path parameter σ_k (:class:`studies.holes.Holes`: the tuning mass's centre of mass on
Γ(σ), σ = 0 at the vertex). This module writes that system down and finds its periodic response
directly, so that a run can start on it (``initial_state = "nonlinear"``) with only the
time step's error left to remove: the linearized start (:func:`studies.hub.linear_response`)
leaves out the amplitude detuning and the turn of the swing's forcing direction (at 2.864P
tuning with 0.75 times the fuselage stiffness its 3P swing is 13.3° instead of 16.4°). It is
also an independent check of the multibody model at large swing: both must give the same
periodic response.

Equations (complex notation of :mod:`studies.equivalent`; hub frame of bifilar k turned by
ψ_k = Ωt + α_k). The tuning mass (m_b) translates with its centre of mass at Γ(σ); the two pins
(m_p and polar inertia I_p each, diameter d) have their centres at π(σ) = π0 + (Γ − Γ0)/2 and
roll on the arm's hole, turning relative to the hub at −|Γ'| σ̇ / d (the contact point is at
rest on the hub: a pin centre speed |π'| σ̇ = |Γ'| σ̇ / 2 at the lever d/2). Each part at
x = z + e^{iψ_k} X(σ_k) has the kinetic energy ½ m |ż + e^{iψ}(iΩX + X'σ̇)|², in which the
terms linear in σ̇ alone are total derivatives. Lagrange's equations then give, per bifilar,

    J(σ) σ̈ + ½ J'(σ) σ̇² − Ω² Re(conj(m_b Γ + m_p π) Γ') + (m_b + m_p) Re(conj(z̈) e^{iψ} Γ')
        + c_pin (|Γ'|/d + φ')² σ̇ = 0,            J(σ) = (m_b + m_p/2 + 2 I_p/d²) |Γ'|²,

with φ(σ) the turn of Γ's tangent (the pin angle the outputs report) and c_pin the rolling
resistance on the pin's rotation relative to the arm-side link, which turns with the tangent.
For circles (Γ = ρ_c + r e^{iφ}) this is J φ̈ + K sin φ = −B τ(φ)·z̈ − c_φ φ̇ with the constants
of :mod:`studies.equivalent`: the stiffness's sin φ is the amplitude detuning, and the forcing
direction τ(φ) = i e^{i(ψ+φ)} turns with the swing. The hub, with all masses m_z riding on it,

    m_z z̈ + c ż + k z = f(t) − d²/dt² Σ_k e^{iψ_k} P(σ_k),      P = m_b Γ + 2 m_p π,

P being a bifilar's first mass moment (its constant part sums to zero over the N bifilars).

**Periodic response.** The forcing repeats every 1/N revolution in the fixed frame, so the
periodic response has bifilar k + 1 doing what bifilar k does a sector later:
σ_k(t) = σ_0(t + kT/N), and z is T/N-periodic. The unknowns are σ_0's harmonics 0…H; given
them, the hub's harmonics (multiples of N) follow in closed form from the reaction's, and the
swing equation's residual, evaluated on M samples per revolution and projected on harmonics
0…H, is solved for zero (Newton's method, from the linear response, by continuation in the
forcing amplitude if the direct solve fails; 0.034 s). Measured at that 16.6° swing: H = 12 and
H = 24 agree to 1.3e-9 rad, and the multibody hub's periodic response to 1.5e-4 of each
signal's largest harmonic (``tests/studies/test_reduced_hub.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from studies.holes import Holes

Array = NDArray[np.float64]
HARMONICS = 12  # harmonics of the swing resolved (see the module docstring)
SAMPLES = 64  # samples per revolution of the residual (a multiple of the N sectors)
TOLERANCE = 1e-11  # rad: a solution's residual harmonics over the swing's stiffness K
DERIVATIVE_STEP = 1e-5  # central-difference step of Γ'' in σ (its error ~1e-10 relative)
CONTINUATION = (0.25, 0.5, 0.75, 1.0)  # forcing fractions when the direct solve fails
NEWTON_ITERATIONS = 30
JACOBIAN_STEP = 1e-7  # rad: forward differences of the residual in σ's harmonics


@dataclass(frozen=True)
class ReducedHub:
    """The hub with N identical bifilars on swing coordinates (passive data, SI units).

    Attributes
    ----------
    holes
        The bifilars' holes: the tuning mass's path Γ(σ) and its derivative (m).
    hub_speed
        Ω (rad/s).
    azimuths
        α_k (rad): bifilar k's radial line at t = 0, equally spaced.
    hub_mass
        m_z (kg): everything the hub centre carries, bifilars included.
    stiffness, damping
        The fuselage restraint's isotropic k (N/m) and c (N·s/m).
    whirl, force
        The shears' tones f = Σ F_j e^{iω_j t}: ω_j (rad/s, multiples of NΩ) and F_j (N,
        complex).
    pin_damping
        c_pin (N·m·s/rad): rolling resistance on each pin's rotation relative to its link.
    """

    holes: Holes
    hub_speed: float
    azimuths: Array
    hub_mass: float
    stiffness: float
    damping: float
    whirl: Array
    force: NDArray[np.complex128]
    pin_damping: float


@dataclass(frozen=True)
class PeriodicSwing:
    """A periodic response of :class:`ReducedHub`: bifilar 0's path parameter σ_0 (harmonics
    0…H, complex, σ_0(t) = Σ_{|n|≤H} s_n e^{inΩt} with s_{−n} = conj(s_n)) and the hub
    centre's harmonics Z_n at n = 0, ±N, ±2N, … (m, complex, z(t) = Σ Z_n e^{inΩt})."""

    model: ReducedHub
    swing: NDArray[np.complex128]
    hub_orders: NDArray[np.int64]
    hub: NDArray[np.complex128]
    residual: float

    def sigma(self, t: float | Array, k: int = 0, derivative: int = 0) -> Array:
        """Bifilar k's path parameter σ_k = σ_0(t + kT/N) (or its ``derivative``-th time
        derivative) at times ``t`` (s)."""
        m = self.model
        n = np.arange(len(self.swing))
        tk = np.asarray(t, dtype=float) + 2 * np.pi * k / (len(m.azimuths) * m.hub_speed)
        terms = self.swing * (1j * n * m.hub_speed) ** derivative
        e = np.exp(1j * np.multiply.outer(tk, n * m.hub_speed))
        return 2 * np.real(e @ terms) - np.real(terms[0])

    def center(self, t: float | Array, derivative: int = 0) -> NDArray[np.complex128]:
        """The hub centre z (m, complex) or its ``derivative``-th time derivative at ``t``."""
        w = self.hub_orders * self.model.hub_speed
        e = np.exp(1j * np.multiply.outer(np.asarray(t, dtype=float), w))
        return e @ (self.hub * (1j * w) ** derivative)


def path_terms(holes: Holes, sigma: Array) -> tuple[NDArray[np.complex128], ...]:
    """Γ, Γ', Γ'' (m, complex: x + iy in the bifilar's hub frame) at ``sigma``; Γ'' by central
    differences of Γ' (:data:`DERIVATIVE_STEP`)."""
    def c(xy: Array) -> NDArray[np.complex128]:
        return xy[..., 0] + 1j * xy[..., 1]
    s = np.asarray(sigma, dtype=float)
    e = DERIVATIVE_STEP
    return (c(holes.path(s)), c(holes.dpath(s)),
            (c(holes.dpath(s + e)) - c(holes.dpath(s - e))) / (2 * e))


def _turn_rate(d1: NDArray[np.complex128], d2: NDArray[np.complex128]) -> Array:
    """dφ/dσ, the rate at which Γ's tangent turns, from Γ' and Γ''."""
    return np.imag(np.conj(d1) * d2) / np.abs(d1) ** 2


def tangent_angle(holes: Holes, sigma: Array) -> tuple[Array, Array]:
    """φ(σ), the turn of Γ's tangent from the vertex's (rad: the pin angle), and dφ/dσ."""
    _, d1, d2 = path_terms(holes, sigma)
    return np.angle(-1j * d1), _turn_rate(d1, d2)


def _swing_residual(model: ReducedHub, terms: tuple[NDArray[np.complex128], ...], sig_d: Array,
                    sig_dd: Array, zdd: NDArray[np.complex128], psi: Array) -> Array:
    """The swing equation's residual (N·m) of one bifilar (see the module docstring), with
    ``terms`` Γ, Γ', Γ'' at its path parameter (:func:`path_terms`)."""
    g = model.holes.geometry
    gam, d1, d2 = terms
    pi = _pin_center(model.holes, gam)
    c_j = g.tuning_mass + 0.5 * g.pin_mass + 2 * g.pin_inertia / g.pin_diameter**2
    speed2 = np.abs(d1) ** 2
    rel = np.sqrt(speed2) / g.pin_diameter + _turn_rate(d1, d2)  # pin turn relative to link
    return (c_j * speed2 * sig_dd + c_j * np.real(np.conj(d1) * d2) * sig_d**2
            - model.hub_speed**2 * np.real(np.conj(g.tuning_mass * gam + g.pin_mass * pi) * d1)
            + (g.tuning_mass + g.pin_mass) * np.real(np.conj(zdd) * np.exp(1j * psi) * d1)
            + model.pin_damping * rel**2 * sig_d)


def _pin_center(holes: Holes, gam: NDArray[np.complex128]) -> NDArray[np.complex128]:
    """π = π0 + (Γ − Γ0)/2 (m, complex): the pin centre midway between the holes
    (:meth:`studies.holes.Holes.pin_center`, here from Γ already evaluated)."""
    (p0x, p0y), (vx, vy) = holes.pin_center(0.0), holes.vertex
    return p0x + 1j * p0y + 0.5 * (gam - (vx + 1j * vy))


def periodic_swing(model: ReducedHub, guess: Array, harmonics: int = HARMONICS,
                   samples: int = SAMPLES) -> PeriodicSwing:
    """The periodic response of ``model`` by harmonic balance (module docstring), from
    ``guess``: σ_0 at ``samples`` equally spaced times over one revolution from t = 0.

    Raises
    ------
    ValueError
        For ``samples`` not a multiple of the N sectors or not above 2 ``harmonics``.
    RuntimeError
        If no solution is found (the message says how far it got).
    """
    n_sec = len(model.azimuths)
    if samples % n_sec or samples <= 2 * harmonics:
        raise ValueError(f"samples = {samples} must be a multiple of the {n_sec} sectors and "
                         f"exceed 2 × harmonics = {2 * harmonics}")
    if np.shape(guess) != (samples,):
        raise ValueError(f"guess has shape {np.shape(guess)}: must be ({samples},), σ_0 at the "
                         "samples")
    omega = model.hub_speed
    m = samples
    t = 2 * np.pi / omega * np.arange(m) / m
    n = np.arange(harmonics + 1)
    full = np.fft.fftfreq(m, 1.0 / m).round().astype(int)  # signed orders of the samples
    hub_live = (full % n_sec == 0) & (full != 0) & (np.abs(full) < m // 2)
    w = full * omega
    hub_gain = np.zeros(m, dtype=complex)
    hub_gain[hub_live] = 1.0 / (model.stiffness + 1j * w[hub_live] * model.damping
                                - w[hub_live] ** 2 * model.hub_mass)
    tones = np.zeros(m, dtype=complex)
    for wj, fj in zip(model.whirl, model.force, strict=True):
        order = round(wj / omega)
        if abs(wj / omega - order) > 1e-9 or order % n_sec or not 0 < abs(order) < m // 2:
            raise ValueError(f"whirl {wj!r} rad/s must be a multiple of {n_sec}Ω below "
                             f"{m // 2}Ω")
        tones[order % m] += fj
    g = model.holes.geometry
    shift = m // n_sec
    psis = [omega * t + a for a in model.azimuths]
    stiff = model.hub_speed**2 * model.holes.rho_v * (
        g.tuning_mass * (g.arm_radius + g.cm_offset) + g.pin_mass * g.arm_radius)

    def spectrum(x: Array) -> NDArray[np.complex128]:
        return np.concatenate([x[:1], x[1::2] + 1j * x[2::2]])

    def hub_of(gam: NDArray[np.complex128], fraction: float = 1.0) -> NDArray[np.complex128]:
        # z's harmonics (signed orders of the samples) under a fraction of the shears, from
        # bifilar 0's Γ at the samples: bifilar k's is the same a sector later (rolled)
        moment = g.tuning_mass * gam + 2 * g.pin_mass * _pin_center(model.holes, gam)
        reaction = sum(np.exp(1j * psi) * np.roll(moment, -k * shift)
                       for k, psi in enumerate(psis))
        return hub_gain * (fraction * tones + w**2 * np.fft.fft(reaction) / m)

    def fields(x: Array) -> tuple[Array, Array, Array]:  # σ_0, σ̇_0, σ̈_0 at the samples
        s = spectrum(x)
        spec = np.zeros(m // 2 + 1, dtype=complex)
        spec[: harmonics + 1] = s * m
        spec[0] = s[0].real * m
        iw = 1j * omega * np.arange(m // 2 + 1)
        return tuple(np.fft.irfft(spec * iw**j, m) for j in range(3))

    def residual(x: Array, fraction: float) -> Array:
        sig, sig_d, sig_dd = fields(x)
        terms = path_terms(model.holes, sig)
        zdd = np.fft.ifft(-(w**2) * hub_of(terms[0], fraction)) * m
        r = np.fft.rfft(_swing_residual(model, terms, sig_d, sig_dd, zdd, psis[0]))[n] / (m * stiff)
        return np.concatenate([r[:1].real, np.column_stack([r[1:].real, r[1:].imag]).ravel()])

    s0 = np.fft.rfft(np.asarray(guess, dtype=float))[n] / m
    x0 = np.concatenate([s0[:1].real, np.column_stack([s0[1:].real, s0[1:].imag]).ravel()])
    sol = _solve(residual, x0)
    zz = hub_of(path_terms(model.holes, fields(sol)[0])[0])
    orders = full[hub_live | (full == 0)]
    keep = np.argsort(orders)
    idx = np.nonzero(hub_live | (full == 0))[0][keep]
    return PeriodicSwing(model, spectrum(sol), full[idx], zz[idx],
                         float(np.max(np.abs(residual(sol, 1.0)))))


def _newton(residual, x: Array, fraction: float) -> tuple[Array, float]:
    """Newton's method on ``residual(x, fraction)`` with a forward-difference Jacobian (step
    :data:`JACOBIAN_STEP` rad, the unknowns being angles), each step halved until the residual
    decreases; returns the last iterate and its largest residual."""
    f = residual(x, fraction)
    err = float(np.max(np.abs(f)))
    for _ in range(NEWTON_ITERATIONS):
        if not np.isfinite(err) or err <= TOLERANCE:
            break
        jac = np.column_stack([(residual(x + JACOBIAN_STEP * e, fraction) - f) / JACOBIAN_STEP
                               for e in np.eye(len(x))])
        try:
            dx = np.linalg.solve(jac, f)
        except np.linalg.LinAlgError:
            break
        for _ in range(20):  # halve the step until the residual decreases
            trial = x - dx
            ft = residual(trial, fraction)
            et = float(np.max(np.abs(ft)))
            if et < err:
                break
            dx = 0.5 * dx
        else:
            break
        x, f, err = trial, ft, et
    return x, err


def _solve(residual, x0: Array) -> Array:
    """Zero of ``residual(x, fraction)`` at fraction 1: directly, else by continuation in the
    forcing fraction (:data:`CONTINUATION`)."""
    best = np.inf
    for path in ((1.0,), CONTINUATION):
        x = x0
        for fraction in path:
            x, err = _newton(residual, x, fraction)
            if not err <= TOLERANCE:
                best = min(best, err)
                break
        else:
            return x
    raise RuntimeError(f"the harmonic balance did not converge (residual {best:.2e} rad > "
                       f"{TOLERANCE:g})")
