"""Trim of the rotor model, solved together with its periodic response.

``trim = "none"`` flies the parameters' controls (the paper's). The other two find controls:

* ``wind_tunnel`` — collective θ0 and the cyclics θc, θs such that the blade loading C_T/σ
  equals ``thrust_coefficient`` and blade 0's first-harmonic flapping relative to the
  shaft is zero (β1c = β1s = 0: the tip-path plane perpendicular to the shaft), at the given
  ``shaft_tilt``; the achieved C_T/σ is ``thrust_coefficient_achieved``.
* ``propulsive`` — θ0, θc, θs and the shaft tilt α_s such that the rotor's mean force carries
  ``gross_weight`` W and overcomes the parasite drag D = ½ ρ U² ``flat_plate_area``, with zero
  mean hub pitch and roll moments. A simplification of a whole aircraft: the rotor alone
  balances the weight and the drag of a point-mass fuselage (no tail rotor, no fuselage or
  tail moments, no side force), so the trimmed rotor flies with zero hub moments.

How (no outer loop of whole runs): the controls are held by a :class:`ControlSchedule` that
the swashplate drives read at every time step. During the settling revolutions, after each
revolution the trim residuals measured on it give a Newton step on the controls, with the
Jacobian of a rigid articulated rotor with uniform inflow in closed form (:class:`RigidRotor`:
∂(C_T/σ, β1c, β1s)/∂(θ0, θc, θs), and the shaft tilt's effect through the inflow and the
force's direction); the new controls ramp in smoothly over the next quarter revolution (a jump
would violate the driven pitch bearings). Once settled, the model shoots to its periodic
response at the controls reached; its residuals are checked, and if they exceed the
tolerances (:data:`THRUST_TOLERANCE`, :data:`FLAPPING_TOLERANCE`), a Broyden-corrected step
(the Jacobian updated from the periodic responses' secant pairs) changes the controls, a
quarter revolution ramps them in, and the model shoots again from where it is. A case that
does not trim within :data:`MAX_CORRECTIONS` corrections fails with its residuals.

The measured quantities: C_T/σ from the mean aerodynamic force along the shaft over the
revolution; β1c, β1s from blade 0's flap hinge angle; the rotor force and hub moments from the
fuselage-beam's top section, whose means over a revolution are the rotor's mean force and
moment on the airframe (no gravity, periodic motion).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from solver.inflow import glauert_inflow
from solver.timefunctions import TimeFunction
from studies.parameters import Output, Param, ParameterError, Parameters
from studies.progress import report

Array = NDArray[np.float64]
TRIMS = ("none", "wind_tunnel", "propulsive")
LBF = 4.4482216152605  # N
FT2 = 0.09290304  # m²

PARAMETERS: dict[str, Param] = {
    "trim": Param("none", "1", "trim: none (fly the controls given), wind_tunnel (collective "
                  "and cyclics for the C_T/σ of thrust_coefficient and zero "
                  "first-harmonic flapping at the given shaft_tilt) or propulsive (collective, "
                  "cyclics and shaft tilt for a rotor carrying gross_weight against the "
                  "parasite drag of flat_plate_area with zero hub moments; no tail rotor, no "
                  "fuselage moments)",
                  choices=TRIMS),
    "thrust_coefficient": Param(
        0.08, "1", "wind_tunnel trim's target blade loading C_T/σ (thrust coefficient over "
        "solidity; the UH-60A Airloads counters fly about 0.08); unused otherwise",
        minimum=0.02, maximum=0.14),
    # UH-60A "loaded" weight 7,375 kg (16,260 lb): the Black Hawk's published general
    # characteristics (max take-off 24,500 lb); 9.80665 m/s² → 72.3 kN
    "gross_weight": Param(72.3e3, "N", "propulsive trim's gross weight W the rotor carries "
                          "(default the UH-60A's loaded weight, 16,260 lb); unused otherwise",
                          minimum=1e3, maximum=5e5),
    # an estimate: 26 ft² inside the 25–35 ft² range the project's notes give for the UH-60A
    # (no primary source retrieved); D/W = 0.051 at 150 ft/s with the default weight
    "flat_plate_area": Param(2.4, "m2", "propulsive trim's equivalent flat-plate area f of the "
                             "airframe: parasite drag ½ρU²f (default 26 ft², an estimate for "
                             "a UH-60A-class airframe); unused otherwise",
                             minimum=0.0, maximum=50.0),
}

OUTPUTS: dict[str, Output] = {
    "thrust_coefficient_achieved": Output("1", "blade loading C_T/σ the case reached (the "
                                          "trim's thrust measure)", dims=()),
    "trim_residual_thrust": Output(
        "1", "trim thrust residual: C_T/σ over its target less 1 (wind_tunnel), or the rotor's "
        "vertical force over the gross weight less 1 (propulsive); 0 untrimmed", dims=()),
    "trim_residual_flapping": Output(
        "degree", "trim flapping residual: magnitude of blade 0's first-harmonic flapping "
        "√(β1c² + β1s²) (wind_tunnel); 0 otherwise", dims=()),
    "trim_residual_propulsive_force": Output(
        "1", "trim propulsive residual: the rotor's forward force less the parasite drag, over "
        "the gross weight (propulsive); 0 otherwise", dims=()),
    "trim_residual_hub_moment": Output(
        "N m", "trim moment residual: magnitude of the mean in-plane hub moment (propulsive); "
        "0 otherwise", dims=()),
    "trim_iterations": Output("1", "control updates of the trim (during settling and after "
                              "shooting); 0 untrimmed", dims=()),
}

# Trim tolerances on the periodic response: half the accuracy promised (C_T/σ within 0.5 %,
# first-harmonic flapping below 0.05°), so that a case passing them meets it with margin.
THRUST_TOLERANCE = 2.5e-3  # relative (C_T/σ or the vertical force; the propulsive force on W)
FLAPPING_TOLERANCE = 0.025  # degree (propulsive: its hub moment's equivalent flapping)
MAX_CORRECTIONS = 4  # control corrections after the first periodic response
RAMP = 0.25  # of a revolution: the control change's ramp
SETTLE_RELAXATION = 0.6  # of a Newton step from a settling revolution
SETTLE_WINDOW = 0.5  # of a settling revolution, measured (its end)
MAX_STEP = math.radians(3.0)  # rad: largest change of a control in one update


def check(p: Parameters) -> None:
    """Cross-checks of the trim parameters."""
    if p.trim == "propulsive":
        if p.flight_speed <= 0.0:
            raise ParameterError(f"flight_speed = {p.flight_speed:g} m s-1: propulsive trim "
                                 "needs forward flight (> 0)")


def smoothstep(tau: float) -> tuple[float, float, float]:
    """Quintic ramp s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ on [0, 1] (0 before, 1 after) and its first two
    derivatives: value, slope and curvature continuous at both ends (C²)."""
    if tau <= 0.0:
        return 0.0, 0.0, 0.0
    if tau >= 1.0:
        return 1.0, 0.0, 0.0
    t2 = tau * tau
    return (t2 * tau * (10 - 15 * tau + 6 * t2), 30 * t2 * (1 - tau) ** 2,
            60 * tau * (1 - tau) * (1 - 2 * tau))


class ControlSchedule:
    """The rotor's controls as functions of time, read by the swashplate drives at each step.

    Holds (θ0, θc, θs) (rad) that ramp smoothly (:func:`smoothstep`) from their values at
    ``t0`` to new ones over ``duration`` seconds when :meth:`set` is called, and the shaft
    tilt α_s (rad), which the model takes when it is rebuilt (the free stream's direction).

    Parameters
    ----------
    pitch
        Initial (θ0, θc, θs), rad.
    shaft_tilt
        Initial forward shaft tilt, rad.
    omega
        Rotor speed Ω, rad/s.
    """

    def __init__(self, pitch: Array, shaft_tilt: float, omega: float) -> None:
        self.old = np.array(pitch, dtype=float)
        self.new = self.old.copy()
        self.t0, self.duration = 0.0, 1e-12  # no ramp
        self.shaft_tilt = float(shaft_tilt)
        self.omega = float(omega)

    def values(self, t: float) -> tuple[Array, Array, Array]:
        """(θ0, θc, θs) at ``t`` and their first and second time derivatives."""
        s, ds, dds = smoothstep((t - self.t0) / self.duration)
        d = self.new - self.old
        return self.old + s * d, d * (ds / self.duration), d * (dds / self.duration**2)

    @property
    def controls(self) -> Array:
        """The controls at the end of the current ramp: (θ0, θc, θs, α_s), rad."""
        return np.append(self.new, self.shaft_tilt)

    def set(self, controls: Array, t0: float, duration: float) -> None:
        """Ramp (θ0, θc, θs) to ``controls[:3]`` over [t0, t0 + duration] (s); the shaft tilt
        becomes ``controls[3]`` (if given) at the next rebuild."""
        self.old = self.values(t0)[0]
        self.new = np.array(controls[:3], dtype=float)
        self.t0, self.duration = float(t0), float(duration)
        if len(controls) > 3:
            self.shaft_tilt = float(controls[3])

    def pitch(self, azimuth: float, reference: float) -> TimeFunction:
        """The driven pitch angle of the blade at ``azimuth`` (rad at t = 0) relative to
        ``reference`` (its pitch as built): θ0 + θc cos ψ + θs sin ψ − reference, ψ = Ωt +
        azimuth, with exact rate and acceleration (the controls' own rates included)."""
        om = self.omega

        def joint(t: float) -> tuple[float, float, float]:
            psi = om * t + azimuth
            (c, dc, ddc), cs, sn = self.values(t), math.cos(psi), math.sin(psi)
            return (c[0] + c[1] * cs + c[2] * sn - reference,
                    dc[0] + dc[1] * cs + dc[2] * sn + om * (-c[1] * sn + c[2] * cs),
                    ddc[0] + ddc[1] * cs + ddc[2] * sn + 2 * om * (-dc[1] * sn + dc[2] * cs)
                    - om * om * (c[1] * cs + c[2] * sn))

        return TimeFunction.of(joint)


@dataclass(frozen=True)
class RigidRotor:
    """A rigid articulated rotor with uniform inflow, in closed form (Johnson, *Helicopter
    Theory*, ch. 5; Bramwell, *Helicopter Dynamics*, ch. 4): the trim's Jacobian.

    Blades flap rigidly about a hinge with rotating flap frequency ν (per rev); the airloads
    are blade-element strip theory with small angles, lift slope a, no stall, no reversed-flow
    correction, U_T = r + μ sin ψ, U_P = λ + r β' + μ β cos ψ (r on R, ψ = 0 aft, the blade
    advancing at 90°), pitch θ = θ0 + θtw r + θc cos ψ + θs sin ψ, lift between the root
    cut-out x0 and the tip-loss station B. The flap equation β'' + ν² β = γ M_F with
    M_F = ½ ∫ r (U_T² θ − U_P U_T) dr (the aerodynamic flap moment on I_β Ω², γ the Lock
    number) is balanced on its mean and first ``harmonics`` harmonics, and
    C_T/σ = (a/2) ⟨∫ (U_T² θ − U_P U_T) dr⟩. The integrals are evaluated by quadrature that is
    exact for these polynomials (Gauss in r, 4K + 12 azimuths), so the result is the closed
    form's:
    with ν = 1, x0 = 0, B = 1 and zero flapping, e.g. C_T/σ = (a/2)[θ0(1/3 + μ²/2) +
    θtw(1 + μ²)/4 + μθs/2 − λ/2].

    Parameters
    ----------
    lift_slope
        a, 1/rad.
    solidity
        σ = N c / (π R).
    lock
        Lock number γ = ρ a c R⁴ / I_β.
    flap_frequency
        ν, per rev (1 for a hinge at the centre).
    root, tip
        Root cut-out x0 and tip-loss factor B, on R.
    twist
        Linear twist θtw, rad (tip less root).
    harmonics
        Flapping harmonics kept (1: the classical closed form's truncation; more: the same
        equations without it, the higher harmonics of β feeding back through μ β cos ψ).
    """

    lift_slope: float
    solidity: float
    lock: float
    flap_frequency: float = 1.0
    root: float = 0.0
    tip: float = 1.0
    twist: float = 0.0
    harmonics: int = 1

    def _loads(self, theta: Array, beta: Array, mu: float, lam: float
               ) -> tuple[Array, Array, Array]:
        """M_F(ψ) and the thrust integrand ∫(U_T²θ − U_P U_T)dr at the azimuths ψ (also
        returned) for flapping coefficients ``beta`` (β0, β1c, β1s, β2c, …)."""
        xg, wg = np.polynomial.legendre.leggauss(4)
        r = 0.5 * (self.tip + self.root) + 0.5 * (self.tip - self.root) * xg
        w = 0.5 * (self.tip - self.root) * wg
        k = self.harmonics
        psi = 2 * np.pi * np.arange(4 * k + 12) / (4 * k + 12)  # exact for these products
        cs, sn = np.cos(psi)[:, None], np.sin(psi)[:, None]
        th = theta[0] + self.twist * r + theta[1] * cs + theta[2] * sn
        n = np.arange(1, k + 1)
        c_n, s_n = np.cos(np.outer(psi, n)), np.sin(np.outer(psi, n))
        b = (beta[0] + c_n @ beta[1::2] + s_n @ beta[2::2])[:, None]
        db = (-s_n @ (n * beta[1::2]) + c_n @ (n * beta[2::2]))[:, None]  # dβ/dψ
        ut = r + mu * sn
        up = lam + r * db + mu * b * cs
        f = ut * ut * th - up * ut
        return 0.5 * (f * r) @ w, f @ w, psi

    def response(self, theta: Array, mu: float, lam: float) -> tuple[float, Array]:
        """C_T/σ and the flapping (β0, β1c, β1s, then the higher harmonics kept) (rad) at
        controls ``theta`` = (θ0, θc, θs) (rad), advance ratio ``mu`` and uniform inflow
        ``lam`` (down through the disk, on ΩR)."""
        theta = np.asarray(theta, dtype=float)
        k = self.harmonics
        psi = self._loads(theta, np.zeros(2 * k + 1), mu, lam)[2]
        n = np.arange(1, k + 1)
        proj = np.vstack([np.full(len(psi), 1 / len(psi)),
                          *[row for j in n for row in (2 * np.cos(j * psi) / len(psi),
                                                       2 * np.sin(j * psi) / len(psi))]])
        nu2 = self.flap_frequency**2
        lhs = np.diag([nu2, *np.repeat(nu2 - n**2, 2)])

        def balance(beta: Array) -> Array:  # (ν² − n²) β_n − γ (its harmonic of M_F)
            return lhs @ beta - self.lock * (proj @ self._loads(theta, beta, mu, lam)[0])

        r0 = balance(np.zeros(2 * k + 1))
        jac = np.column_stack([balance(e) - r0 for e in np.eye(2 * k + 1)])
        beta = np.linalg.solve(jac, -r0)
        ct = 0.5 * self.lift_slope * float(np.mean(self._loads(theta, beta, mu, lam)[1]))
        return ct, beta

    def trimmed_response(self, controls: Array, speed: float, tip_speed: float,
                         induced: bool = True) -> tuple[float, Array, float]:
        """C_T/σ, flapping and total inflow λ at ``controls`` (θ0, θc, θs, α_s) (rad), flight
        ``speed`` and ``tip_speed`` ΩR (m/s): μ = U cos α_s/ΩR, λ = U sin α_s/ΩR + λ_i with
        λ_i Glauert's momentum inflow for the thrust (``induced``), found by fixed-point
        iteration (its rate, about σa/(8μ), is below 1 in forward flight)."""
        alpha = controls[3]
        mu = speed * math.cos(alpha) / tip_speed
        lam_f = speed * math.sin(alpha) / tip_speed
        lam, ct = lam_f, 0.0
        for _ in range(60):
            ct, beta = self.response(controls[:3], mu, lam)
            if not induced:
                break
            new = lam_f + glauert_inflow(ct * self.solidity, mu, lam_f)
            if abs(new - lam) < 1e-12:
                break
            lam = 0.5 * (lam + new)
        return ct, beta, lam


@dataclass
class Measured:
    """What the trim reads of one revolution: C_T/σ, blade 0's β1c, β1s (rad), the rotor's
    mean force (N) and in-plane hub moment (N·m) in model axes."""

    ct_sigma: float
    beta1c: float
    beta1s: float
    force: Array
    moment: Array


class Trimmer:
    """Newton steps on the trim residuals, with the closed-form Jacobian of a
    :class:`RigidRotor` and Broyden updates from periodic responses.

    Parameters
    ----------
    kind
        ``wind_tunnel`` (unknowns θ0, θc, θs) or ``propulsive`` (and α_s).
    rigid
        The rigid rotor whose derivatives start the Jacobian.
    speed, tip_speed
        Flight speed U and ΩR (m/s).
    target
        ``wind_tunnel``: the target C_T/σ. ``propulsive``: (W, D) in N.
    thrust_scale
        ρ π R² (ΩR)² σ: thrust (N) per unit C_T/σ (the measured thrust's scale, and the
        propulsive trim's force rows).
    moment_scale
        ``propulsive``: the hub moment (N·m) per radian of first-harmonic flapping,
        (N_b/2) e C for hinge offset e and blade centrifugal force C (the in-plane moment the
        tilted centrifugal forces pass to the hub): the moment residuals are measured as
        equivalent flapping, M = moment_scale (β1s, −β1c).
    induced
        Whether the rigid rotor's inflow follows the thrust (Glauert) or is prescribed.
    """

    def __init__(self, kind: str, rigid: RigidRotor, speed: float, tip_speed: float,
                 target: float | tuple[float, float], thrust_scale: float = 1.0,
                 moment_scale: float = 1.0, induced: bool = True) -> None:
        if kind not in TRIMS[1:]:
            raise ValueError(f"trim = {kind!r}: must be one of {TRIMS[1:]}")
        self.kind, self.rigid, self.speed, self.tip_speed = kind, rigid, speed, tip_speed
        self.target = target
        self.thrust_scale, self.moment_scale, self.induced = thrust_scale, moment_scale, induced
        self.n = 3 if kind == "wind_tunnel" else 4
        self.updates = 0
        self._tilt = 0.0  # the shaft tilt of the wind-tunnel trim's Jacobian (rad)
        self.jacobian: Array | None = None  # the Broyden-updated one, once periodic
        self.last: tuple[Array, Array] | None = None  # (controls, residual) of the last periodic

    # -- residuals ------------------------------------------------------------------------
    def residual(self, m: Measured, controls: Array) -> Array:
        """The trim residuals (dimensionless; flapping and moments in rad of flapping):
        wind tunnel (C_T/σ / target − 1, β1c, β1s); propulsive ((L − W)/W, (P − D)/W,
        equivalent β1c, β1s of the hub moment), L and P the rotor force's components up and
        forward (the flight direction is (−cos α_s, 0, sin α_s) in model axes)."""
        if self.kind == "wind_tunnel":
            return np.array([m.ct_sigma / self.target - 1.0, m.beta1c, m.beta1s])
        w, d = self.target
        a = controls[3]
        lift = m.force[0] * math.sin(a) + m.force[2] * math.cos(a)
        prop = -m.force[0] * math.cos(a) + m.force[2] * math.sin(a)
        return np.array([lift / w - 1.0, (prop - d) / w, -m.moment[1] / self.moment_scale,
                         m.moment[0] / self.moment_scale])

    def converged(self, r: Array) -> bool:
        """Whether residuals ``r`` are within the tolerances."""
        flap = math.radians(FLAPPING_TOLERANCE)
        return bool(np.all(np.abs(r[:-2]) <= THRUST_TOLERANCE)
                    and np.all(np.abs(r[-2:]) <= flap))

    # -- the rigid rotor's Jacobian -------------------------------------------------------
    def _model(self, x: Array) -> Array:
        """The rigid rotor's residual-like quantities at controls ``x``."""
        full = x if self.n == 4 else np.append(x, self._tilt)
        ct, beta, _ = self.rigid.trimmed_response(full, self.speed, self.tip_speed,
                                                  self.induced)
        if self.kind == "wind_tunnel":
            return np.array([ct / self.target, beta[1], beta[2]])
        # the rigid rotor's force is its thrust along the shaft (the H-force left out): up
        # T cos α_s, forward T sin α_s
        w, _ = self.target
        t = ct * self.thrust_scale
        return np.array([t * math.cos(x[3]) / w, t * math.sin(x[3]) / w, beta[1], beta[2]])

    def model_jacobian(self, x: Array) -> Array:
        """∂(residuals)/∂(controls) of the rigid rotor at ``x`` (central differences; the
        closed form is linear in the pitch controls at fixed inflow)."""
        eps = 1e-4
        cols = [(self._model(x + eps * e) - self._model(x - eps * e)) / (2 * eps)
                for e in np.eye(self.n)]
        return np.column_stack(cols)

    # -- steps ----------------------------------------------------------------------------
    def step(self, controls: Array, r: Array, periodic: bool) -> Array:
        """New controls (θ0, θc, θs[, α_s]) from the residuals ``r`` at ``controls`` (the first
        n of them are the unknowns). ``periodic``: ``r`` is of a periodic response, so that
        successive ones form secant pairs for Broyden's update of the Jacobian; otherwise
        (a settling revolution, still in its transient) the rigid rotor's Jacobian is used
        as it is."""
        self._tilt = controls[3]
        x = np.array(controls[: self.n], dtype=float)
        if periodic:
            if self.jacobian is None:
                self.jacobian = self.model_jacobian(x)
            elif self.last is not None:  # Broyden's good update from the secant pair
                dx, dr = x - self.last[0], r - self.last[1]
                if dx @ dx > 0:
                    self.jacobian = self.jacobian + np.outer(dr - self.jacobian @ dx, dx) / (
                        dx @ dx)
            self.last = (x, r)
            jac = self.jacobian
        else:
            jac = self.model_jacobian(x)
        # a settling revolution's residuals still carry the transient of the last change
        # (the inflow's lag above all), which a full step would chase: it is relaxed
        dx = -np.linalg.solve(jac, r) * (1.0 if periodic else SETTLE_RELAXATION)
        biggest = np.max(np.abs(dx))
        if biggest > MAX_STEP:  # a bounded step: the closed form is a linear guide
            dx *= MAX_STEP / biggest
        self.updates += 1
        new = np.array(controls, dtype=float)
        new[: self.n] = x + dx
        return new


def measure(rows: Array, columns: tuple[str, ...], omega: float, steps_per_rev: int,
            thrust_per_ct_sigma: float, window: float = 1.0) -> Measured:
    """What the trim reads of the last ``window`` of a revolution (a whole number of quarter
    revolutions, so that the 4P loads average out) of sampled ``rows`` (columns named by
    ``columns``: time ``t``, ``thrust``, ``flap`` in degree, the top section's force ``fx``,
    ``fy``, ``fz`` and moments ``mhx``, ``mhy``): the means, and blade 0's flapping
    β0 + β1c cos ψ + β1s sin ψ fitted by least squares (its first harmonics over a whole
    revolution)."""
    block = rows[-round(window * steps_per_rev):]
    col = {c: block[:, i] for i, c in enumerate(columns)}
    psi = omega * col["t"]
    basis = np.column_stack([np.ones_like(psi), np.cos(psi), np.sin(psi)])
    flap = np.linalg.lstsq(basis, np.radians(col["flap"]), rcond=None)[0]
    # the top section's force and moment are what the rotor and shaft head pass down to the
    # airframe: over a revolution their means are the rotor's mean force and moment on it
    force = np.array([col["fx"].mean(), col["fy"].mean(), col["fz"].mean()])
    moment = np.array([col["mhx"].mean(), col["mhy"].mean()])
    return Measured(float(col["thrust"].mean()) / thrust_per_ct_sigma, float(flap[1]),
                    float(flap[2]), force, moment)


def facts(trimmer: Trimmer | None, ct_sigma: float, m: Measured | None,
          controls: Array) -> dict[str, np.generic]:
    """The trim's archived scalars (:data:`OUTPUTS`): ``ct_sigma`` the recorded C_T/σ, ``m``
    the recorded revolution's measures (needed with a ``trimmer``), ``controls`` flown."""
    out = {"thrust_coefficient_achieved": np.float64(ct_sigma),
           "trim_residual_thrust": np.float64(0.0),
           "trim_residual_flapping": np.float64(0.0),
           "trim_residual_propulsive_force": np.float64(0.0),
           "trim_residual_hub_moment": np.float64(0.0),
           "trim_iterations": np.int32(0)}
    if trimmer is None or m is None:
        return out
    r = trimmer.residual(m, controls)
    out["trim_residual_thrust"] = np.float64(r[0])
    out["trim_iterations"] = np.int32(trimmer.updates)
    if trimmer.kind == "wind_tunnel":
        out["trim_residual_flapping"] = np.float64(math.degrees(math.hypot(r[1], r[2])))
    else:
        out["trim_residual_propulsive_force"] = np.float64(r[1])
        out["trim_residual_hub_moment"] = np.float64(math.hypot(*m.moment))
    return out


def update(trimmer: Trimmer, controls: ControlSchedule, rows: Array,
           columns: tuple[str, ...], steps_per_rev: int, t: float, periodic: bool
           ) -> tuple[Array, bool]:
    """Measure the last revolution of ``rows`` and, unless its residuals are within the
    tolerances (only a ``periodic`` response counts as trimmed), step the controls: they
    ramp to the new values over :data:`RAMP` of a revolution from time ``t`` (s).
    Returns (residuals, trimmed)."""
    omega = controls.omega
    # a settling revolution: its second half, after the quarter revolution of the last ramp
    # and a quarter for the flap response to it (flap damping γ/16: 0.2 of it left)
    m = measure(rows, columns, omega, steps_per_rev, trimmer.thrust_scale,
                1.0 if periodic else SETTLE_WINDOW)
    x = controls.controls
    r = trimmer.residual(m, x)
    if periodic and trimmer.converged(r):
        report(f"trimmed: {describe(trimmer, r)}; {controls_degrees(x)}")
        return r, True
    new = trimmer.step(x, r, periodic)
    controls.set(new, t, RAMP * 2 * math.pi / omega)
    report(f"trim update {trimmer.updates}: {describe(trimmer, r)}; next "
           f"{controls_degrees(new)}")
    return r, False


def describe(trimmer: Trimmer, r: Array) -> str:
    """The residuals ``r`` in words, for messages."""
    if trimmer.kind == "wind_tunnel":
        return (f"C_T/σ off its target {trimmer.target:g} by {100 * r[0]:+.3g} % (tolerance "
                f"{100 * THRUST_TOLERANCE:g} %), flapping β1c = {math.degrees(r[1]):+.3g}°, "
                f"β1s = {math.degrees(r[2]):+.3g}° (tolerance {FLAPPING_TOLERANCE:g}°)")
    return (f"vertical force off the gross weight by {100 * r[0]:+.3g} %, propulsive force "
            f"less drag {100 * r[1]:+.3g} % of the weight (tolerance "
            f"{100 * THRUST_TOLERANCE:g} %), hub moments as flapping β1c = "
            f"{math.degrees(r[2]):+.3g}°, β1s = {math.degrees(r[3]):+.3g}° (tolerance "
            f"{FLAPPING_TOLERANCE:g}°)")


def controls_degrees(controls: Array) -> str:
    """The controls in words, for messages."""
    th0, thc, ths, a = np.degrees(controls)
    return f"θ0 = {th0:.3f}°, θc = {thc:.3f}°, θs = {ths:.3f}°, shaft tilt {a:.3f}°"


def schedule(p: Parameters) -> ControlSchedule:
    """The rotor case's control schedule, starting at its parameters' controls."""
    return ControlSchedule(np.radians([p.collective, p.cyclic_cosine, p.cyclic_sine]),
                           math.radians(p.shaft_tilt), p.hub_speed)


def for_rotor(p: Parameters, blades: int = 4) -> Trimmer | None:
    """The trimmer of a UH-60 rotor case (``None`` for ``trim = "none"``): the rigid rotor of
    the UH-60A's global data (:class:`studies.uh60a.UH60A`: lift slope, solidity, Lock number
    γ = ρ a c R⁴/I_β, flap frequency ν² = 1 + e S_β/I_β, the first airstation as root cut-out,
    the tip loss) and the targets of ``p``."""
    if p.trim == "none":
        return None
    from studies.uh60a import UH60A, blade_airstations

    r, omega = UH60A.radius, p.hub_speed
    lock = p.air_density * UH60A.lift_slope * UH60A.chord * r**4 / UH60A.blade_flap_inertia
    nu = math.sqrt(1 + UH60A.hinge_radius * UH60A.blade_first_moment
                   / UH60A.blade_flap_inertia)
    rigid = RigidRotor(UH60A.lift_slope, UH60A.solidity, lock, nu,
                       root=float(blade_airstations()[0][0]) / r, tip=UH60A.tip_loss)
    tip_speed = omega * r
    per_ct_sigma = UH60A.thrust_unit(p.air_density, omega) * UH60A.solidity
    # each blade's centrifugal force C = Ω² (S_β + e m_b), at the hinge offset e
    pull = omega**2 * (UH60A.blade_first_moment + UH60A.hinge_radius * UH60A.blade_mass)
    if p.trim == "wind_tunnel":
        target: float | tuple[float, float] = p.thrust_coefficient
    else:
        target = (p.gross_weight,
                  0.5 * p.air_density * p.flight_speed**2 * p.flat_plate_area)
    return Trimmer(p.trim, rigid, p.flight_speed, tip_speed, target,
                   thrust_scale=per_ct_sigma,
                   moment_scale=0.5 * blades * UH60A.hinge_radius * pull)
