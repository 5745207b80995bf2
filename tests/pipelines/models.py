"""A small physical model in the hub model's output layout, for the pipeline tests.

Hub (effective in-plane mass ``M``) on an isotropic fuselage spring ``K·scale`` with damping, and
the four bifilars lumped into one absorber mass ``m`` on a spring tuned, in the fixed frame, to
``(tuning_order + 1)·Ω``: a bifilar tuned to nP in the rotating frame acts on the (n+1)P
progressive whirl of the hub. The hub is driven by in-plane forces at 1P (a small progressive
imbalance) and 4P (elliptical: progressive and regressive whirl, which the rotating frame sees at
3P and 5P). The steady state is exact, in closed form per harmonic (complex amplitudes of the
2×2 dynamic stiffness), then sampled into the dataset layout of ``studies.hub``; the expected
Fourier harmonics are therefore known analytically (:func:`steady_state`).

Pin angle of bifilar ``b`` (at azimuth ψ + b·90°): the absorber's displacement relative to the
hub, tangential at that bifilar, over the bifilar's effective pendulum length ``D - d`` (hole
minus pin diameter). It is a kinematic stand-in, not bifilar dynamics.

Test hooks: ``delay`` sleeps (to interrupt a sweep mid-run), ``run_log`` appends one line per
run (to count computations across processes), ``fail`` raises or returns a result marked failed,
and a negative ``absorber_damping_ratio`` makes the system unstable, which :func:`run` detects.

Workers find this model as ``model = "tests.pipelines.models:SPEC"`` (the repository root must be
on their ``sys.path``).
"""

from __future__ import annotations

import dataclasses
import json
import time
from typing import Any

import numpy as np
import xarray as xr

from studies.parameters import ModelSpec, Output, Param, ParameterError
from studies.periodic import RUN_OUTPUTS
from studies.progress import report
from studies.registry import register

HUB_MASS = 500.0  # kg, hub and rotor in-plane effective mass
ABSORBER_MASS = 50.0  # kg, four bifilar tuning masses
FUSELAGE_FREQUENCY = 4.4  # per rev at the nominal stiffness and 27 rad/s (above the 4P forcing)
FUSELAGE_DAMPING_RATIO = 0.03
NOMINAL_SPEED = 27.0  # rad/s, sets the fuselage stiffness
IMBALANCE = 0.05  # 1P force relative to the 4P force
ELLIPTICITY = 0.6  # y/x ratio of the 4P force
N_BIFILARS = 4

PARAMETERS: dict[str, Param] = {
    "hub_speed": Param(27.0, "rad s-1", "rotor speed", minimum=0.0, exclusive_minimum=True),
    "bifilar": Param("free", "1", "bifilar absorbers free or locked to the hub",
                     choices=("free", "locked")),
    "tuning_order": Param(3.0, "1", "bifilar tuning order, rotating frame", minimum=1.0,
                          maximum=10.0),
    "fuselage_stiffness_scale": Param(1.0, "1", "fuselage stiffness relative to nominal",
                                      minimum=0.0, exclusive_minimum=True),
    "absorber_damping_ratio": Param(0.02, "1", "absorber damping ratio", minimum=-0.5,
                                    maximum=0.5),
    "force_amplitude": Param(2000.0, "N", "4P in-plane hub force amplitude", minimum=0.0),
    "pin_diameter": Param(0.02, "m", "bifilar pin diameter", minimum=0.0, exclusive_minimum=True),
    "hole_diameter": Param(0.03, "m", "bifilar tracking hole diameter", minimum=0.0,
                           exclusive_minimum=True),
    "samples_per_rev": Param(64, "1", "samples per revolution", minimum=20),
    "revolutions": Param(2, "1", "revolutions recorded", minimum=1),
    "transient_revolutions": Param(3, "1", "revolutions before recording", minimum=0),
    "delay": Param(0.0, "s", "wall-clock delay of a run (tests)", minimum=0.0, maximum=60.0),
    "run_log": Param("", "1", "file to which each run appends a line (tests)"),
    "fail": Param("none", "1", "test failure mode", choices=("none", "raise", "report")),
}


# The hub model's output layout (names, dimensions, harmonics, archived histories, figures).
OUTPUTS: dict[str, Output] = {
    "time": Output("s", "time", dims=("time",)),
    "bifilar": Output("1", "bifilar number", dims=("bifilar",)),
    "hub_x_fixed": Output("m", "hub x displacement, fixed frame", history=True),
    "hub_y_fixed": Output("m", "hub y displacement, fixed frame", history=True),
    "hub_x_rotating": Output("m", "hub x displacement, rotating frame"),
    "hub_y_rotating": Output("m", "hub y displacement, rotating frame"),
    "hub_force_x_fixed": Output("N", "hub force x, fixed frame", history=True,
                                figure="hub_force_history"),
    "hub_force_y_fixed": Output("N", "hub force y, fixed frame", history=True,
                                figure="hub_force_history"),
    "bifilar_cm_x_fixed": Output("m", "bifilar centre of mass x, fixed frame", history=True),
    "bifilar_cm_y_fixed": Output("m", "bifilar centre of mass y, fixed frame", history=True),
    "pin_angle": Output("degree", "bifilar pin angle", dims=("bifilar", "time"), history=True,
                        harmonics=True, figure="pin_angles"),
    "hub_displacement_rotating": Output("m", "hub in-plane displacement, rotating frame",
                                        components=("hub_x_rotating", "hub_y_rotating")),
    "hub_displacement_fixed": Output("m", "hub in-plane displacement, fixed frame",
                                     components=("hub_x_fixed", "hub_y_fixed"), figure="orbits"),
    "hub_force_fixed": Output("N", "in-plane hub force on the fuselage, fixed frame",
                              components=("hub_force_x_fixed", "hub_force_y_fixed")),
    "bifilar_cm_displacement": Output("m", "bifilar centre of mass displacement, fixed frame",
                                      components=("bifilar_cm_x_fixed", "bifilar_cm_y_fixed"),
                                      figure="orbits"),
    # the recording's time base and transient, as every periodic model reports them
    **{name: RUN_OUTPUTS[name] for name in ("run_hub_speed", "run_revolutions",
                                            "run_samples_per_rev", "run_transient_revolutions")},
}


def check(params: dict[str, Any]) -> None:
    """Reject a pin that does not fit in its hole (impossible geometry)."""
    if params["pin_diameter"] >= params["hole_diameter"]:
        raise ParameterError(
            f"pin_diameter = {params['pin_diameter']:g} m must be smaller than hole_diameter = "
            f"{params['hole_diameter']:g} m: the pin would not fit in its tracking hole"
        )


def forcing(params: dict[str, Any]) -> dict[int, tuple[complex, complex]]:
    """Complex amplitudes (N) of the hub force per harmonic: F_x(t) = Re(F e^{i k ψ})."""
    f = params["force_amplitude"]
    return {
        1: (IMBALANCE * f + 0j, -1j * IMBALANCE * f),
        4: (f + 0j, -1j * ELLIPTICITY * f),
    }


def _matrices(params: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, damping and stiffness of one in-plane direction (hub, absorber)."""
    omega_f = FUSELAGE_FREQUENCY * NOMINAL_SPEED
    k_f = HUB_MASS * omega_f**2 * params["fuselage_stiffness_scale"]
    c_f = 2 * FUSELAGE_DAMPING_RATIO * np.sqrt(k_f * HUB_MASS)
    if params["bifilar"] == "locked":
        m = np.array([[HUB_MASS + ABSORBER_MASS]])
        return m, np.array([[c_f]]), np.array([[k_f]])
    omega_a = (params["tuning_order"] + 1) * params["hub_speed"]
    k_a = ABSORBER_MASS * omega_a**2
    c_a = 2 * params["absorber_damping_ratio"] * np.sqrt(k_a * ABSORBER_MASS)
    m = np.diag([HUB_MASS, ABSORBER_MASS])
    c = np.array([[c_f + c_a, -c_a], [-c_a, c_a]])
    k = np.array([[k_f + k_a, -k_a], [-k_a, k_a]])
    return m, c, k


def growth_rate(params: dict[str, Any]) -> float:
    """Largest real part of the free-vibration eigenvalues (1/s); > 0 means unstable."""
    m, c, k = _matrices(params)
    n = m.shape[0]
    minv = np.linalg.inv(m)
    state = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ c]])
    return float(np.linalg.eigvals(state).real.max())


def steady_state(params: dict[str, Any]) -> dict[int, dict[str, tuple[complex, complex]]]:
    """Exact steady state per harmonic k: complex (x, y) amplitudes, ``x(t) = Re(X e^{ikψ})``.

    Keys: ``hub`` and ``absorber`` (m, fixed frame), ``force`` (N, transmitted to the
    fuselage: fuselage spring and damper force).
    """
    m, c, k = _matrices(params)
    # The fuselage spring and damper are what remains of the hub row when the hub and the
    # absorber move together.
    k_f, c_f = k[0].sum(), c[0].sum()
    out: dict[int, dict[str, tuple[complex, complex]]] = {}
    for h, (fx, fy) in forcing(params).items():
        w = h * params["hub_speed"]
        z = k - w**2 * m + 1j * w * c
        rhs = np.zeros((k.shape[0], 2), dtype=complex)
        rhs[0] = fx, fy
        sol = np.linalg.solve(z, rhs)
        hub = sol[0]
        absorber = sol[-1]
        force = (k_f + 1j * w * c_f) * hub
        out[h] = {
            "hub": (complex(hub[0]), complex(hub[1])),
            "absorber": (complex(absorber[0]), complex(absorber[1])),
            "force": (complex(force[0]), complex(force[1])),
        }
    return out


def run(params: dict[str, Any]) -> xr.Dataset:
    """Sample the exact steady state into the hub model's dataset layout."""
    if params["run_log"]:
        with open(params["run_log"], "a") as log:
            values = params.as_dict() if hasattr(params, "as_dict") else dict(params)
            log.write(json.dumps(values, sort_keys=True) + "\n")
    time.sleep(params["delay"])
    report(f"steady state of {params['revolutions']} revolution(s) in closed form")
    if params["fail"] == "raise":
        raise RuntimeError("failure requested by the test (fail = 'raise')")
    rate = growth_rate(params)
    if rate > 0:
        raise RuntimeError(
            f"unstable: free vibrations grow at {rate:.3g} 1/s (absorber_damping_ratio = "
            f"{params['absorber_damping_ratio']:g}), so there is no steady periodic response"
        )
    omega = params["hub_speed"]
    n, revs = params["samples_per_rev"], params["revolutions"]
    skip = params["transient_revolutions"]
    period = 2 * np.pi / omega
    t = (skip + np.arange(revs * n) / n) * period
    psi = omega * t

    def signal(amplitudes: dict[int, complex]) -> np.ndarray:
        return sum((a * np.exp(1j * h * psi)).real for h, a in amplitudes.items())

    state = steady_state(params)
    series = {
        f"{name}_{axis}": signal({h: s[name][i] for h, s in state.items()})
        for name in ("hub", "absorber", "force")
        for i, axis in enumerate("xy")
    }
    hx, hy = series["hub_x"], series["hub_y"]
    rx, ry = series["absorber_x"] - hx, series["absorber_y"] - hy
    length = params["hole_diameter"] - params["pin_diameter"]
    bifilar_psi = psi[None, :] + np.arange(N_BIFILARS)[:, None] * np.pi / 2
    pins = np.degrees((-rx * np.sin(bifilar_psi) + ry * np.cos(bifilar_psi)) / length)

    ds = SPEC.dataset(
        {
            "time": t,
            "bifilar": np.arange(N_BIFILARS),
            "hub_x_fixed": hx,
            "hub_y_fixed": hy,
            "hub_x_rotating": hx * np.cos(psi) + hy * np.sin(psi),
            "hub_y_rotating": -hx * np.sin(psi) + hy * np.cos(psi),
            "hub_force_x_fixed": series["force_x"],
            "hub_force_y_fixed": series["force_y"],
            "bifilar_cm_x_fixed": series["absorber_x"],
            "bifilar_cm_y_fixed": series["absorber_y"],
            "pin_angle": pins,
            "run_hub_speed": np.float64(omega),
            "run_revolutions": np.int32(revs),
            "run_samples_per_rev": np.int32(n),
            "run_transient_revolutions": np.int32(skip),
        },
    )
    if params["fail"] == "report":
        ds.attrs.update(status="failed", message="solver did not converge (test report)")
    return ds


SPEC = ModelSpec(
    name="pipeline-test-2dof",
    parameters=PARAMETERS,
    simulate=run,
    check=check,
    description="hub on a fuselage spring with a tuned absorber, exact steady state",
    outputs=OUTPUTS,
)
register(SPEC)


# --- a model with warm-up parts (pipelines.kernels) ------------------------------------------


def _warm_kernel(scale: float) -> Any:
    """A new numba kernel (not cached on disk), so that every call of a warm-up part in a
    fresh process compiles one kernel."""
    import numba

    @numba.njit(cache=False)
    def kernel(x: float) -> float:
        return scale * x

    return kernel


def warm_up_double() -> None:
    """Warm-up part: compiles one kernel."""
    assert _warm_kernel(2.0)(1.0) == 2.0


def warm_up_fails() -> None:
    """Warm-up part that fails after compiling one kernel."""
    _warm_kernel(3.0)(1.0)
    raise RuntimeError("warm-up part broken (test)")


# Workers find it as "tests.pipelines.models:WARM_SPEC": the test model with two warm-up parts.
WARM_SPEC = dataclasses.replace(SPEC, name="pipeline-test-warm-up",
                                warm_up=(warm_up_double, warm_up_fails))
register(WARM_SPEC)


# --- a model with branches (studies.branches): the Duffing oscillator ------------------------
#
# x'' + 2ζx' + x + γx³ = F cos(Ωt) in dimensionless time, recorded "per rev": one revolution is
# one forcing period (ψ = Ωt, so the response is at 1P). Its one-harmonic balance
# x = A cos(Ωt - φ) has the frequency-response curve [(k - Ω²)² + (2ζΩ)²]A² = F² with
# k = 1 + ¾γA², solved in closed form for Ω² along the curve parametrized by the amplitude:
#
#     Ω² = k - 2ζ² ± sqrt(D),   D = 4ζ⁴ - 4ζ²k + F²/A²,
#
# the minus root from the static response (Ω = 0) up to the peak amplitude A_max (D = 0), the
# plus root beyond it down to A → 0 (Ω → ∞). With A = A_max(1 - u²) and the root's sign that
# of u the curve is smooth in u. For a hardening spring (γ > 0) strong enough it has two folds
# (dΩ/du = 0), and the middle branch between them is unstable (the saddle-node rule).

DUFFING_PARAMETERS: dict[str, Param] = {
    "forcing_frequency": Param(1.0, "1", "forcing frequency over the linear natural frequency",
                               minimum=0.0, exclusive_minimum=True, maximum=10.0),
    "damping_ratio": Param(0.05, "1", "damping ratio", minimum=0.0, exclusive_minimum=True,
                           maximum=0.5),
    "cubic_stiffness": Param(0.1, "1", "cubic stiffness over the linear stiffness", minimum=0.0,
                             maximum=10.0),
    "forcing_amplitude": Param(0.3, "1", "forcing amplitude over the linear stiffness",
                               minimum=0.0, exclusive_minimum=True),
    "samples_per_rev": Param(32, "1", "samples per forcing period", minimum=20),
    "revolutions": Param(1, "1", "forcing periods recorded", minimum=1),
    "run_log": Param("", "1", "file to which each run appends a line (tests)"),
    "branch_fail": Param("none", "1", "test failure mode of the branch",
                         choices=("none", "raise", "empty")),
}

DUFFING_OUTPUTS: dict[str, Output] = {
    "time": Output("s", "time", dims=("time",)),
    "displacement": Output("1", "displacement x", history=True, harmonics=True),
    "velocity": Output("1", "velocity dx/dt", harmonics=True),
    "response_amplitude": Output("1", "one-harmonic response amplitude A", dims=()),
    **{name: RUN_OUTPUTS[name] for name in ("run_hub_speed", "run_revolutions",
                                            "run_samples_per_rev", "run_transient_revolutions")},
}
# Points of the dense curve from which a branch's points are taken.
DENSE_POINTS = 20_001


def _peak_amplitude(zeta: float, gamma: float, force: float) -> float:
    """A_max, where D = 0: F²/A² = 4ζ²(k - ζ²), the left side falling and the right rising
    in A (bisection: both monotonic)."""
    low, high = 1e-12, force / (2 * zeta * np.sqrt(1 - zeta**2)) + 1.0
    for _ in range(200):
        mid = 0.5 * (low + high)
        k = 1 + 0.75 * gamma * mid**2
        if force**2 / mid**2 - 4 * zeta**2 * (k - zeta**2) > 0:
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


def duffing_curve(p: Any, omega_cap: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frequency-response curve from Ω = 0 to beyond ``omega_cap``, densely: (Ω, A, φ)."""
    zeta, gamma, force = p.damping_ratio, p.cubic_stiffness, p.forcing_amplitude
    a_max = _peak_amplitude(zeta, gamma, force)
    # static amplitude: A(1 + ¾γA²) = F, the real root of the cubic
    roots = np.roots([0.75 * gamma, 0.0, 1.0, -force]) if gamma > 0 else np.array([force])
    a_static = float(max(r.real for r in roots if abs(r.imag) < 1e-9 and r.real > 0))
    # far enough down the plus root that Ω > omega_cap (there Ω² ≈ F/A)
    a_end = min(force / (2.0 * omega_cap**2 + 2.0), 0.5 * a_max)
    u = np.linspace(-np.sqrt(1 - a_static / a_max), np.sqrt(1 - a_end / a_max), DENSE_POINTS)
    amplitude = a_max * (1 - u**2)
    k = 1 + 0.75 * gamma * amplitude**2
    disc = np.maximum(4 * zeta**4 - 4 * zeta**2 * k + force**2 / amplitude**2, 0.0)
    omega = np.sqrt(np.maximum(k - 2 * zeta**2 + np.sign(u) * np.sqrt(disc), 0.0))
    phase = np.arctan2(2 * zeta * omega, k - omega**2)
    return omega, amplitude, phase


def duffing_response(p: Any, omega: float, amplitude: float, phase: float,
                     message: str = "") -> xr.Dataset:
    """The one-harmonic periodic response sampled over whole forcing periods, in the layout
    the model's ``simulate`` returns."""
    n, revs = p.samples_per_rev, p.revolutions
    t = np.arange(revs * n) / n * (2 * np.pi / omega)
    angle = omega * t - phase
    return DUFFING_SPEC.dataset({
        "time": t,
        "displacement": amplitude * np.cos(angle),
        "velocity": -amplitude * omega * np.sin(angle),
        "response_amplitude": np.float64(amplitude),
        "run_hub_speed": np.float64(omega),
        "run_revolutions": np.int32(revs),
        "run_samples_per_rev": np.int32(n),
        "run_transient_revolutions": np.int32(0),
    }, {"message": message} if message else None)


def duffing_simulate(p: Any) -> xr.Dataset:
    """The response at ``forcing_frequency`` reached from rest at low frequency (the first
    crossing of the curve: the resonant branch)."""
    omega, amplitude, phase = duffing_curve(p, p.forcing_frequency + 1.0)
    i = int(np.argmax(omega >= p.forcing_frequency))
    return duffing_response(p, p.forcing_frequency, amplitude[i], phase[i])


def duffing_branch(p: Any, c: Any) -> list[Any]:
    """The frequency-response curve from ``c.start`` to ``c.stop``: points every ``c.step`` of
    arclength in (Ω, A), the folds among them; at most ``c.max_points`` (then the branch ends
    early and says so in its results' message).

    Floquet multipliers are a stand-in with the right product (Liouville: exp(-2ζT) over a
    period T): a complex pair of modulus exp(-ζT) on the stable branches, 1 at a fold, a real
    multiplier above 1 on the middle branch between the folds.
    """
    from studies.branches import BranchPoint

    if p.run_log:
        with open(p.run_log, "a") as log:
            log.write(json.dumps(p.as_dict(), sort_keys=True) + "\n")
    if p.branch_fail == "raise":
        raise RuntimeError("branch failure requested by the test (branch_fail = 'raise')")
    if p.branch_fail == "empty":
        return []
    omega, amplitude, phase = duffing_curve(p, max(c.start, c.stop) + 1.0)
    slope = np.diff(omega)
    folds = [i for i in range(1, len(omega) - 1) if slope[i - 1] * slope[i] < 0]
    order = np.arange(len(omega)) if c.stop > c.start else np.arange(len(omega))[::-1]
    sign = 1.0 if c.stop > c.start else -1.0
    first = int(np.argmax(sign * (omega[order] - c.start) >= 0))
    last = first + int(np.argmax(sign * (omega[order[first:]] - c.stop) >= 0))
    path = order[first:last + 1]
    arclength = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(omega[path]),
                                                          np.diff(amplitude[path])))])
    step = min(c.step, c.max_step)
    wanted = np.searchsorted(arclength, np.arange(0.0, arclength[-1], step))
    chosen = sorted({*wanted.tolist(), len(path) - 1,
                     *(int(np.flatnonzero(path == f)[0]) for f in folds if f in path)})
    message = ""
    if len(chosen) > c.max_points:
        chosen = chosen[:c.max_points]
        message = (f"branch ended at {c.max_points} points (max_points), forcing_frequency = "
                   f"{omega[path[chosen[-1]]]:g} before stop = {c.stop:g}")
    points = []
    for j in chosen:
        i = int(path[j])
        period = 2 * np.pi / omega[i]
        decay = np.exp(-p.damping_ratio * period)
        passed = sum(f < i for f in folds)
        if i in folds:
            multipliers, stable = np.array([1.0, decay**2], complex), True
        elif passed % 2:
            lo, hi = folds[passed - 1], folds[passed]
            grow = 1.0 + 0.5 * np.sin(np.pi * (i - lo) / (hi - lo))
            multipliers, stable = np.array([grow, decay**2 / grow], complex), False
        else:
            multipliers = decay * np.exp(np.array([1j, -1j]) * period)
            stable = True
        result = duffing_response(p, float(omega[i]), float(amplitude[i]), float(phase[i]),
                                  message)
        points.append(BranchPoint(float(omega[i]), result, multipliers, stable, i in folds))
    return points


DUFFING_SPEC = ModelSpec(
    name="pipeline-test-duffing",
    parameters=DUFFING_PARAMETERS,
    simulate=duffing_simulate,
    description="Duffing oscillator, one-harmonic balance in closed form along its branch",
    outputs=DUFFING_OUTPUTS,
    branch=duffing_branch,
)
register(DUFFING_SPEC)
