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


def swing_stiffness(holes: Holes, hub_speed: float) -> float:
    """K (N·m): the swing equation's stiffness at the vertex, Ω² ρ_v (m_b (R0 + Rm) + m_p R0),
    the scale of its residuals."""
    g = holes.geometry
    return hub_speed**2 * holes.rho_v * (g.tuning_mass * (g.arm_radius + g.cm_offset)
                                         + g.pin_mass * g.arm_radius)


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


class HarmonicBalance:
    """The periodic-response equations of ``model`` on σ_0's harmonics 0…``harmonics``
    (module docstring), sampled at ``samples`` times a revolution.

    The unknowns are real: x = (s_0, Re s_1, Im s_1, …, Re s_H, Im s_H) (rad, σ_0's
    harmonics); :meth:`residual` is the swing equation's residual projected on the same
    harmonics, over the swing's stiffness K (rad).

    Raises
    ------
    ValueError
        For ``samples`` not a multiple of the N sectors or not above 2 ``harmonics``, or a
        shear tone that is not a multiple of NΩ below the samples' Nyquist order.
    """

    def __init__(self, model: ReducedHub, harmonics: int = HARMONICS,
                 samples: int = SAMPLES) -> None:
        n_sec = len(model.azimuths)
        if samples % n_sec or samples <= 2 * harmonics:
            raise ValueError(f"samples = {samples} must be a multiple of the {n_sec} sectors "
                             f"and exceed 2 × harmonics = {2 * harmonics}")
        self.model, self.harmonics, self.samples = model, harmonics, samples
        omega, m = model.hub_speed, samples
        self.t = 2 * np.pi / omega * np.arange(m) / m
        self.full = np.fft.fftfreq(m, 1.0 / m).round().astype(int)  # signed sample orders
        self.hub_live = ((self.full % n_sec == 0) & (self.full != 0)
                         & (np.abs(self.full) < m // 2))
        live = self.hub_live
        self.w = w = self.full * omega
        self.hub_gain = np.zeros(m, dtype=complex)
        self.hub_gain[live] = 1.0 / (model.stiffness + 1j * w[live] * model.damping
                                     - w[live] ** 2 * model.hub_mass)
        self.tones = np.zeros(m, dtype=complex)
        for wj, fj in zip(model.whirl, model.force, strict=True):
            order = round(wj / omega)
            if abs(wj / omega - order) > 1e-9 or order % n_sec or not 0 < abs(order) < m // 2:
                raise ValueError(f"whirl {wj!r} rad/s must be a multiple of {n_sec}Ω below "
                                 f"{m // 2}Ω")
            self.tones[order % m] += fj
        self.shift = m // n_sec
        self.psis = [omega * self.t + a for a in model.azimuths]
        self.stiff = swing_stiffness(model.holes, model.hub_speed)

    def unknowns(self, guess: Array) -> Array:
        """x of σ_0 given at the samples (``guess``, shape (samples,))."""
        if np.shape(guess) != (self.samples,):
            raise ValueError(f"guess has shape {np.shape(guess)}: must be ({self.samples},), "
                             "σ_0 at the samples")
        s0 = np.fft.rfft(np.asarray(guess, dtype=float))[: self.harmonics + 1] / self.samples
        return np.concatenate([s0[:1].real, np.column_stack([s0[1:].real, s0[1:].imag]).ravel()])

    def hub_of(self, gam: NDArray[np.complex128], fraction: float = 1.0
               ) -> NDArray[np.complex128]:
        """z's harmonics (signed orders of the samples) under a fraction of the shears, from
        bifilar 0's Γ at the samples: bifilar k's is the same a sector later (rolled)."""
        g, m = self.model.holes.geometry, self.samples
        moment = g.tuning_mass * gam + 2 * g.pin_mass * _pin_center(self.model.holes, gam)
        reaction = sum(np.exp(1j * psi) * np.roll(moment, -k * self.shift)
                       for k, psi in enumerate(self.psis))
        return self.hub_gain * (fraction * self.tones + self.w**2 * np.fft.fft(reaction) / m)

    def fields(self, x: Array) -> tuple[Array, Array, Array]:
        """σ_0, σ̇_0, σ̈_0 at the samples."""
        m = self.samples
        s = _spectrum(x)
        spec = np.zeros(m // 2 + 1, dtype=complex)
        spec[: self.harmonics + 1] = s * m
        spec[0] = s[0].real * m
        iw = 1j * self.model.hub_speed * np.arange(m // 2 + 1)
        return tuple(np.fft.irfft(spec * iw**j, m) for j in range(3))

    def residual(self, x: Array, fraction: float = 1.0) -> Array:
        """The swing equation's residual harmonics over K (rad), same layout as x, with a
        ``fraction`` of the shears."""
        m = self.samples
        sig, sig_d, sig_dd = self.fields(x)
        terms = path_terms(self.model.holes, sig)
        zdd = np.fft.ifft(-(self.w**2) * self.hub_of(terms[0], fraction)) * m
        r = (np.fft.rfft(_swing_residual(self.model, terms, sig_d, sig_dd, zdd, self.psis[0]))
             [: self.harmonics + 1] / (m * self.stiff))
        return np.concatenate([r[:1].real, np.column_stack([r[1:].real, r[1:].imag]).ravel()])

    def solution(self, x: Array) -> PeriodicSwing:
        """The :class:`PeriodicSwing` of the unknowns ``x``."""
        full, live = self.full, self.hub_live
        zz = self.hub_of(path_terms(self.model.holes, self.fields(x)[0])[0])
        kept = live | (full == 0)
        idx = np.nonzero(kept)[0][np.argsort(full[kept])]
        return PeriodicSwing(self.model, _spectrum(x), full[idx], zz[idx],
                             float(np.max(np.abs(self.residual(x)))))


def _spectrum(x: Array) -> NDArray[np.complex128]:
    """σ_0's complex harmonics 0…H of the real unknowns x."""
    return np.concatenate([x[:1], x[1::2] + 1j * x[2::2]])


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
    balance = HarmonicBalance(model, harmonics, samples)
    return balance.solution(_solve(balance.residual, balance.unknowns(guess)))


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


# The equations of motion of all 2 + N coordinates, for the stability of a periodic response:
# its perturbations need not share the response's sector symmetry.
STATE_STEP = 1e-7  # central-difference step of the linearization (m, rad; m/s, rad/s)


def accelerations(model: ReducedHub, t: float | Array, y: Array) -> Array:
    """ẏ of the state y = (x, y, σ_0…σ_{N−1}, ẋ, ẏ, σ̇_0…σ̇_{N−1}) (m, rad, m/s, rad/s) at time
    ``t`` (s): the module docstring's equations solved for the accelerations. ``y`` may hold
    several states (shape (..., 2 (2 + N)), times ``t`` broadcast against its leading axes).

    The hub's equation with d²/dt²(e^{iψ}P) written out (P' = (m_b + m_p)Γ', the pins' centres
    moving at half the mass's rate) and the swing equations share the accelerations through
    the symmetric mass matrix [[m_z I, B], [Bᵀ, diag J(σ_k)]], B's column k being
    (m_b + m_p)(Re, Im) e^{iψ_k}Γ'_k.
    """
    g = model.holes.geometry
    n = len(model.azimuths)
    omega = model.hub_speed
    y = np.asarray(y, dtype=float)
    t = np.asarray(t, dtype=float)[..., None]
    sig, sig_d = y[..., 2: 2 + n], y[..., 4 + n:]
    z, zd = y[..., :1] + 1j * y[..., 1:2], y[..., 2 + n: 3 + n] + 1j * y[..., 3 + n: 4 + n]
    psi = omega * t + model.azimuths
    terms = path_terms(model.holes, sig)
    gam, d1, d2 = terms
    rot = np.exp(1j * psi)
    mbp = g.tuning_mass + g.pin_mass
    moment = g.tuning_mass * gam + 2 * g.pin_mass * _pin_center(model.holes, gam)
    force = np.sum(model.force * np.exp(1j * model.whirl * t), axis=-1)
    hub_rhs = (force - model.damping * zd[..., 0] - model.stiffness * z[..., 0]
               - np.sum(rot * (-omega**2 * moment + 2j * omega * mbp * d1 * sig_d
                               + mbp * d2 * sig_d**2), axis=-1))
    # the swing equations' terms other than the accelerations' (σ̈ = 0, z̈ = 0)
    zero = np.zeros_like(sig)
    swing_rhs = -_swing_residual(model, terms, sig_d, zero, zero, psi)
    c_j = g.tuning_mass + 0.5 * g.pin_mass + 2 * g.pin_inertia / g.pin_diameter**2
    coupling = mbp * rot * d1
    mass = np.zeros((*sig.shape[:-1], 2 + n, 2 + n))
    mass[..., 0, 0] = mass[..., 1, 1] = model.hub_mass
    mass[..., 0, 2:] = mass[..., 2:, 0] = coupling.real
    mass[..., 1, 2:] = mass[..., 2:, 1] = coupling.imag
    idx = np.arange(2, 2 + n)
    mass[..., idx, idx] = c_j * np.abs(d1) ** 2
    rhs = np.concatenate([hub_rhs.real[..., None], hub_rhs.imag[..., None], swing_rhs], axis=-1)
    acc = np.linalg.solve(mass, rhs[..., None])[..., 0]
    return np.concatenate([y[..., 2 + n:], acc], axis=-1)


def periodic_state(sol: PeriodicSwing, t: float | Array) -> Array:
    """The state of :func:`accelerations` on the periodic response ``sol`` at ``t`` (s):
    shape (len(t), 2 (2 + N)), or (2 (2 + N),) for a scalar ``t``."""
    tt = np.atleast_1d(np.asarray(t, dtype=float))
    n = len(sol.model.azimuths)
    z, zd = sol.center(tt), sol.center(tt, derivative=1)
    cols = [z.real, z.imag, *(sol.sigma(tt, k) for k in range(n)),
            zd.real, zd.imag, *(sol.sigma(tt, k, derivative=1) for k in range(n))]
    y = np.column_stack(cols)
    return y[0] if np.ndim(t) == 0 else y


def linearization(model: ReducedHub, t: float | Array, y: Array,
                  step: float = STATE_STEP) -> Array:
    """∂ẏ/∂y of :func:`accelerations` at (t, y) (shape (..., n, n) for states (..., n)), by
    central differences (``step``; the truncation error ~ step² relative, the roundoff
    ~ 1e-16/step)."""
    y = np.asarray(y, dtype=float)
    cols = [(accelerations(model, t, y + step * e) - accelerations(model, t, y - step * e))
            / (2 * step) for e in np.eye(y.shape[-1])]
    return np.stack(cols, axis=-1)


# RK4 steps of the variational equation over a sector: the multipliers then agree with a
# whole revolution's monodromy at 16 times the steps to 2e-8 (a fold's 0.977: 1.6e-7)
SECTOR_STEPS = 250


def sector_monodromy(sol: PeriodicSwing, steps: int = SECTOR_STEPS) -> Array:
    """The linearized sector map of the periodic response ``sol``: the variational equation
    δẏ = A(t) δy (:func:`linearization`) integrated over one N-th of a revolution (classical
    Runge–Kutta, ``steps`` steps, A evaluated at once at every stage time), then the
    bifilars renumbered as the response repeats, σ_k(T/N) = σ_{k+1}(0): bifilar k − 1's
    state a sector on is bifilar k's at the start. Its N-th power is the revolution's
    monodromy matrix."""
    model = sol.model
    n = len(model.azimuths)
    h = 2 * np.pi / model.hub_speed / n / steps
    t = 0.5 * h * np.arange(2 * steps + 1)
    a = linearization(model, t, periodic_state(sol, t))
    phi = np.eye(2 * (2 + n))
    for j in range(steps):
        a0, am, a1 = a[2 * j], a[2 * j + 1], a[2 * j + 2]
        k1 = a0 @ phi
        k2 = am @ (phi + 0.5 * h * k1)
        k3 = am @ (phi + 0.5 * h * k2)
        k4 = a1 @ (phi + h * k3)
        phi = phi + (h / 6) * (k1 + 2 * k2 + 2 * k3 + k4)
    # renumber: the new bifilar k is the old k − 1 (positions and rates)
    order = np.arange(2 * (2 + n))
    for base in (2, 4 + n):
        order[base: base + n] = base + np.roll(np.arange(n), 1)
    return phi[order]


def floquet_multipliers(sol: PeriodicSwing, steps: int = SECTOR_STEPS) -> NDArray[np.complex128]:
    """The revolution's Floquet multipliers of ``sol``, largest modulus first: the N-th
    powers of the eigenvalues of :func:`sector_monodromy` (each of the revolution's
    multipliers once per sector-map eigenvalue)."""
    mu = np.linalg.eigvals(sector_monodromy(sol, steps)) ** len(sol.model.azimuths)
    return mu[np.argsort(-np.abs(mu))]
