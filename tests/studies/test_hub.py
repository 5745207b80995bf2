"""The hub with four bifilars, run as users run it (the overnight sweep).

The paper's Table 1 (cases 0-3) goes through the real pipeline: a LocalCluster of 2 worker
processes, one case file per case, the consolidated CF archive, the report plots. The physics
checks are the paper's reported trends, with the margins we measured:

* free and tuned to 3P, the rotating-frame 3P hub displacement falls by at least 90 % against
  locked (a tuned absorber leaves only what its damping lets through);
* tuned to 3.3P (10 % detuned) it absorbs clearly less;
* opposite bifilars 0 and 2 swing 180° out of phase at 3P, by several degrees;
* halving the fuselage stiffness changes the fixed-frame 4P hub force by tens of percent.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipelines.cli import default_study
from pipelines.sweep import run_sweep
from studies.hub import SPEC, build
from studies.parameters import ParameterError
from tests.studies.helpers import hub_samples


@pytest.fixture(scope="module")
def table1(tmp_path_factory):
    out = tmp_path_factory.mktemp("table1")
    study = out / "study.toml"
    study.write_text(default_study("hub").read_text())
    archive = run_sweep(study, out / "run", workers=2, progress=False)
    ds = xr.open_dataset(archive)
    yield ds, out / "run"
    ds.close()


def _case(ds, name_start):
    names = [str(n) for n in ds.case_name.values]
    return next(i for i, n in enumerate(names) if n.startswith(name_start))


def test_table1_all_cases_ok(table1):
    ds, _ = table1
    assert ds.sizes["case"] == 5  # Table 1 and the equivalent of case 1
    assert (ds.status.values == 0).all(), ds.message.values


def test_tuned_bifilars_remove_3p_hub_motion(table1):
    ds, _ = table1
    amp = ds.hub_displacement_rotating_amplitude.sel(harmonic=3)
    locked = float(amp.isel(case=_case(ds, "0")).max())
    tuned = float(amp.isel(case=_case(ds, "1")).max())
    detuned = float(amp.isel(case=_case(ds, "2")).max())
    # measured: tuned/locked = 0.081 (91.9 % reduction), detuned/locked = 0.46
    assert tuned <= 0.1 * locked
    assert detuned >= 3 * tuned


def test_opposite_pins_out_of_phase_at_3p(table1):
    ds, _ = table1
    i = _case(ds, "1")
    c = ds.pin_angle_cos.isel(case=i).sel(harmonic=3).values
    s = ds.pin_angle_sin.isel(case=i).sel(harmonic=3).values
    z = c - 1j * s  # complex 3P amplitude of each bifilar
    amp = np.abs(z)
    assert amp.min() > 2.0  # several degrees (measured 5.1°)
    # 0 and 2 swing in opposition, as do 1 and 3, to the accuracy the periodicity test asks
    # for: a response whose change between two marched revolutions is within the study's
    # tolerance 1e-3 is within a few tolerances of the periodic one (measured 1.3e-3, 1.4e-3)
    assert np.abs(z[0] + z[2]) <= 3e-3 * amp[0]
    assert np.abs(z[1] + z[3]) <= 3e-3 * amp[1]


def test_fuselage_stiffness_changes_hub_forces(table1):
    ds, _ = table1
    f = ds.hub_force_fixed_amplitude.sel(harmonic=4)
    nominal = float(f.isel(case=_case(ds, "1")).max())
    soft = float(f.isel(case=_case(ds, "3")).max())
    assert abs(soft / nominal - 1) >= 0.1  # "tens of percent"


def test_archive_is_cf_and_plots_exist(table1):
    ds, run_dir = table1
    from pipelines.plots import plot_archive

    paths = plot_archive(run_dir / "archive.nc", run_dir / "plots")
    assert any(p.suffix == ".png" for p in paths) and any(p.suffix == ".pdf" for p in paths)
    assert all(p.stat().st_size > 1000 for p in paths)
    assert ds.attrs["Conventions"] == "CF-1.8"
    for key in ("title", "source", "history", "study"):
        assert ds.attrs.get(key), key
    for name, var in ds.variables.items():
        if name in ds.dims and var.dtype.kind in "OUS":
            continue
        assert "long_name" in var.attrs, name
    assert ds.status.attrs["flag_meanings"] == "ok failed not_run"
    assert ds.hub_displacement_rotating_amplitude.attrs["units"] == "m"
    assert ds.hub_force_fixed_amplitude.attrs["units"] == "N"
    assert ds.pin_angle_amplitude.attrs["units"] == "degree"


def test_hub_parameters_validated_before_running():
    with pytest.raises(ParameterError, match="fuselage_stiffness_scale"):
        SPEC.complete({"fuselage_stiffness_scale": -1.0})
    with pytest.raises(ParameterError, match="bifilar"):
        SPEC.complete({"bifilar": "loose"})
    with pytest.raises(ParameterError, match="unknown parameter"):
        SPEC.complete({"tuning_ordr": 3.0})
    # shooting steps whole quarter revolutions; the coarser step of the estimate is the
    # largest multiple of 4 at most half of it (here 80)
    SPEC.complete({"steps_per_rev": 164, "richardson": True})
    # the plain second-order step needs the finer step the composed one does without
    with pytest.raises(ParameterError, match="steps_per_rev = 40: must be at least 64 with "
                                             "composition = 'none'"):
        SPEC.complete({"composition": "none"})
    with pytest.raises(ParameterError, match="composition"):
        SPEC.complete({"composition": "rk4"})
    with pytest.raises(ParameterError, match="initial_state"):
        SPEC.complete({"initial_state": "warm"})
    with pytest.raises(ParameterError, match="steps_per_rev = 162: must be a multiple of 4"):
        SPEC.complete({"steps_per_rev": 162})
    SPEC.complete({"steps_per_rev": 161, "shooting_window": 0})  # marching: any count
    with pytest.raises(ParameterError, match="shooting_window = 1"):
        SPEC.complete({"shooting_window": 1})


def test_hub_model_has_no_redundant_constraints():
    """One bifilar adds exactly one degree of freedom; the hub adds two (in-plane)."""
    from solver.system import System

    p = SPEC.validate({})
    model, *_ = build(p)
    s = System(model)
    # unknowns minus holonomic and nonholonomic rows = degrees of freedom
    assert s.n - s.mh - s.mn == 2 + 4 * 1


@pytest.mark.parametrize("bifilar", ["equivalent", "locked"])
def test_linear_response_is_the_linear_models_periodic_response(bifilar):
    """The closed-form periodic response (``linear_response``: the hub's whirl under each 4P
    tone of the shears against the fuselage spring and damper and the absorbers' apparent
    mass, and the bifilars' swing) against the multibody hub model's periodic response for the
    linear absorbers: the fixed-frame equivalent (particle, gyroscopic coupling, rigid
    remainder) and the locked bifilars. The run's harmonics, extrapolated to zero step, agree
    to the periodicity test and the O(h⁶) remainder: measured 4.2e-4 of the largest harmonic
    (equivalent hub), 5.5e-4 (its swing), 1.5e-4 (locked hub)."""
    from studies.absorbers import AZIMUTHS
    from studies.equivalent import whirl_amplitude
    from studies.hub import design, linear_response, run

    p = SPEC.validate({"bifilar": bifilar})
    whirl, zz, aa = linear_response(p, design(p))
    assert whirl == pytest.approx(p.hub_speed * np.array([4.0, -4.0]))
    ds = run({"bifilar": bifilar})
    assert ds["run_richardson"].item() == 1 and ds.attrs["message"] == ""
    n = ds["run_samples_per_rev"].item()
    t = ds.time.values[-n:]
    z = (ds.hub_x_fixed.values + 1j * ds.hub_y_fixed.values)[-n:]
    phi = np.radians(ds.pin_angle.values[:, -n:])
    a = np.array([whirl_amplitude(phi[:, j], p.hub_speed * t[j] + AZIMUTHS)
                  for j in range(n)])
    tones = np.exp(-1j * np.outer(whirl, t))  # (tone, sample)
    np.testing.assert_allclose(tones @ z / n, zz, rtol=0, atol=1e-3 * np.abs(zz).max())
    np.testing.assert_allclose(tones @ a / n, aa, rtol=0, atol=1e-3 * np.abs(aa).max())


def test_undamped_tuned_bifilars_cancel_their_tone_in_the_linear_response():
    """Without damping, bifilars tuned to the rotating 3P (the fixed-frame progressive 4P
    whirl) have an infinite apparent mass at it: the closed form, written with the swing's
    denominator cleared, gives the exact limit — no hub motion at that tone and the swing
    whose force cancels the shear, Â = 2iF/(ω² N B) — and is continuous in the damping."""
    from studies.equivalent import equivalent_absorber
    from studies.hub import design, linear_response

    p = SPEC.validate({"pin_damping_ratio": 0.0})
    d = design(p)
    whirl, zz, aa = linear_response(p, d)
    force = d.force
    b = equivalent_absorber(d.holes, 4, 0.0).coupling
    assert abs(zz[0]) <= 1e-12 * abs(zz[1])
    assert aa[0] == pytest.approx(2j * force[0] / (whirl[0] ** 2 * 4 * b), rel=1e-12)
    damped = p.replace(pin_damping_ratio=1e-7)
    _, zz_d, aa_d = linear_response(damped, design(damped))
    np.testing.assert_allclose(aa_d, aa, rtol=1e-5)
    assert abs(zz_d[0]) < 1e-5 * abs(zz[1])


def test_linear_start_only_where_the_linearization_holds(monkeypatch):
    """A linear response that swings the pins beyond 30° (the amplitude detuning the
    linearization drops is 1.7 % there) is not used: the run starts at rest and its case
    message says why."""
    from studies import hub

    linear = {"initial_state": "linear"}
    p = SPEC.validate({**linear, "excitation_3p": 3e4})  # 20 times the default: 77° of swing
    start, note = hub.initial_start(p, hub.design(p))
    assert not np.any(start.angles) and not np.any(start.center)
    assert note == ("started at rest: the linear response swings the pins to 77.2°, beyond "
                    "the 30° where the linearization holds")
    monkeypatch.setattr(hub, "LINEAR_START_LIMIT", np.radians(1.0))
    ds = hub.run({**linear, "error_estimate": False, "richardson": False})
    assert ds.attrs["message"].startswith("started at rest: the linear response swings the "
                                          "pins to 3.42°, beyond the 1° where")


def test_nonlinear_start_falls_back_with_its_reason(monkeypatch):
    """Where the harmonic balance finds no periodic response (20 times the default shears:
    the linear one swings the pins to 77°) or finds one beyond the holes, the run takes the
    linear start where that holds, else rest, and the case message says both."""
    from studies import hub

    p = SPEC.validate({"excitation_3p": 3e4})
    start, note = hub.initial_start(p, hub.design(p))
    assert not np.any(start.angles)
    assert note.startswith("nonlinear start not found (the harmonic balance did not converge")
    assert note.endswith("; started at rest: the linear response swings the pins to 77.2°, "
                         "beyond the 30° where the linearization holds")
    p = SPEC.validate({})
    monkeypatch.setattr(hub, "NONLINEAR_START_LIMIT", np.radians(1.0))
    start, note = hub.initial_start(p, hub.design(p))
    linear, _ = hub._linear_start_checked(p, hub.design(p))
    np.testing.assert_array_equal(start.angles, linear.angles)
    assert note == ("nonlinear start not used: it swings the pins to 5.61°, beyond the 1° the "
                    "holes cover; started from the linear response")
    for other in ({"bifilar": "locked"}, {"bifilar": "equivalent"}):  # linear models: exact
        q = SPEC.validate(other)
        start, note = hub.initial_start(q, hub.design(q))
        assert note == ""
        np.testing.assert_array_equal(start.center,
                                      hub._linear_start_checked(q, hub.design(q))[0].center)


def test_nonlinear_and_linear_starts_are_nearly_periodic():
    """Started from the reduced model's periodic response (nonlinear, the default), the
    bifilars' first two marched revolutions differ by 0.14 % of the largest harmonics (the
    time step's error alone: the start is the exact equations' periodic response); from the
    linear response by 0.86 % (what the linearization leaves out); from rest by 81 %: the
    shooting then has only a small transient to remove."""
    from studies.hub import run

    given = {"shooting_window": 0, "extrapolation_window": 0, "max_revolutions": 2,
             "error_estimate": False, "richardson": False}
    for start, passes, fails in (("nonlinear", 2e-3, 1e-3), ("linear", 0.01, 5e-3),
                                 ("rest", None, 0.02)):
        if passes is not None:
            ds = run({**given, "initial_state": start, "periodic_tolerance": passes})
            assert ds["run_transient_revolutions"].item() == 2
        with pytest.raises(RuntimeError, match="not periodic after 2 revolutions"):
            run({**given, "initial_state": start, "periodic_tolerance": fails})


def test_default_run_stores_the_step_error_of_its_harmonics():
    """Each run estimates its harmonics' time-step error from the periodic response at twice
    the step, extrapolated from a few quarter-revolution iterates started on its own periodic
    state. Against the same Richardson estimate from an independent run at twice the step
    (shot from rest, to the periodicity test's tolerance) it agrees within 3 % (measured
    1.711e-3 against 1.709e-3), after one revolution at twice the step (the slow modes taken
    from shooting's iterates). By default the
    recorded harmonics are then extrapolated to zero step, exactly by the correction the
    estimate measures; with ``richardson = false`` they are the step's own."""
    from studies.hub import run
    from studies.periodic import referred_harmonics, richardson

    own = run({"richardson": False})
    assert own.attrs["message"] == "" and own["run_estimate_samples_per_rev"].item() == 20
    # at most 8 revolutions per case, the coarser step's included (measured 6.5)
    assert own["run_simulated_revolutions"].item() <= 8
    assert 1.0 <= own["run_estimate_revolutions"].item() <= 4.0
    assert own["run_richardson"].item() == 0
    coarse = run({"steps_per_rev": 20, "richardson": False, "error_estimate": False})
    assert "run_step_error_estimate" not in coarse
    assert coarse["run_estimate_revolutions"].item() == 0
    omega = own["run_hub_speed"].item()
    _, est = richardson(hub_samples(own), hub_samples(coarse), omega, 8, order=4)
    assert 1e-3 < est.max() < 3e-3
    assert own["run_step_error_estimate"].item() == pytest.approx(est.max(), rel=0.03)
    # the default: the same run and estimate, its harmonics 0-8 moved by c(h) - c(2h) over 15.
    # The same to roundoff, not to the bit: the secant step over shooting's nearly parallel
    # iterates amplifies roundoff, and two runs in one process need not round alike (measured
    # 2e-8 apart in this test under pytest, identical in a standalone process)
    ds = run({})
    assert ds["run_richardson"].item() == 1 and ds.attrs["message"] == ""
    assert ds["run_step_error_estimate"].item() == pytest.approx(
        own["run_step_error_estimate"].item(), rel=1e-6)
    c_own, c_ex = (referred_harmonics(hub_samples(d)[-40:], omega, 8) for d in (own, ds))
    scale = np.abs(c_own).max(axis=0)
    moved = np.max(np.abs(c_ex - c_own) / scale)
    assert moved == pytest.approx(ds["run_step_error_estimate"].item(), rel=1e-6)
    # harmonic 8 needs 18 samples per revolution at the coarser step: none below 40 steps/rev
    low = run({"bifilar": "locked", "steps_per_rev": 32})
    assert "run_step_error_estimate" not in low and low["run_richardson"].item() == 0
    assert ("no step-error estimate at steps_per_rev = 32, harmonics not extrapolated"
            in low.attrs["message"])


def _exact_error(given: dict):
    """The largest error of a run's harmonics 0–8 (last revolution, every sampled signal),
    relative to each signal's largest, against the exact equations' periodic response
    (``reduced_samples``: harmonic balance, no time step; it and the multibody agree to
    1.5e-4 when the multibody's step is refined, tests/studies/test_reduced_hub.py)."""
    from studies import hub
    from studies.periodic import referred_harmonics

    p = SPEC.validate(given)
    d = hub.design(p)

    def error(ds) -> float:
        rows = hub_samples(ds)[-ds["run_samples_per_rev"].item():]
        a, b = (referred_harmonics(r, p.hub_speed, 8)
                for r in (rows, hub.reduced_samples(p, d, rows[:, 0])))
        return float(np.max(np.abs(a - b) / np.abs(b).max(axis=0)))
    return error


@pytest.mark.slow
def test_default_step_gives_the_exact_harmonics_in_at_most_8_revolutions():
    """The default run's accuracy (0.5 % of each signal's largest harmonic) and revolutions
    (at most 8) against the exact equations' periodic response.

    Free case: the step (Suzuki's composition of ep, 40 steps/rev) errs by 0.19 % of each
    signal's largest harmonic (the plain ep at 160 steps/rev: 3.3 %) after 6.5 revolutions
    (5.5 at the step, recorded ones included, and 1.0 at twice the step for the estimate); the
    stored estimate is that error within 25 % (measured 1.71e-3 against 1.92e-3), and the
    default's extrapolated harmonics err by 2.3e-4. The composed step is of order 4 on the
    harmonics: 24 → 48 steps/rev take the error from 1.4e-2 to 9.4e-4 (log2 ratio 3.88).
    Tuned to 3.3P with 1.5 times the fuselage stiffness (a corner of the 60-case sweep, its
    largest swing, 24°) the step errs by 0.90 %, which the estimate flags (8.0e-3), and the
    default's extrapolated harmonics by 0.12 %, after 7.25 revolutions in all (6.25 and 1.0)."""
    from studies.hub import run

    error = _exact_error({})
    own = run({"richardson": False})
    assert error(own) < 5e-3
    assert own["run_step_error_estimate"].item() == pytest.approx(error(own), rel=0.25)
    assert own["run_simulated_revolutions"].item() <= 8
    assert own.attrs["message"] == ""
    assert error(run({})) < 5e-4
    e24, e48 = (error(run({"steps_per_rev": n, "richardson": False})) for n in (24, 48))
    assert 3.5 < np.log2(e24 / e48) < 4.5
    corner = {"tuning_order": 3.3, "fuselage_stiffness_scale": 1.5}
    error = _exact_error(corner)
    own = run({**corner, "richardson": False})
    assert error(own) > 5e-3 and own["run_step_error_estimate"].item() > 5e-3
    assert own["run_step_error_estimate"].item() == pytest.approx(error(own), rel=0.25)
    assert own["run_simulated_revolutions"].item() <= 8
    assert error(run(corner)) < 3e-3


@pytest.mark.slow
def test_sixty_case_sweep_takes_at_most_8_revolutions_per_case_at_the_exact_harmonics():
    """At most 8 revolutions per hub case, recorded ones included, over a 60-case sweep
    (tuning 2.7–3.3P in 12 steps, 0.5–1.5 times the fuselage stiffness, swings 2–24°, the
    fuselage mode at the 4P tone at 1.25 times), with the default run's accuracy against the
    exact equations' periodic response. Measured: 6.4 revolutions on
    average, at most 7.25; every case restarts once or twice; the extrapolated harmonics
    within 2.2e-3 of the exact ones (median 4.1e-4; the goal is 5e-3)."""
    from studies.hub import run

    worst = {}
    for order in np.round(np.linspace(2.7, 3.3, 12), 3):
        for scale in (0.5, 0.75, 1.0, 1.25, 1.5):
            given = {"tuning_order": float(order), "fuselage_stiffness_scale": scale}
            ds = run(given)
            assert ds.attrs["message"] == "" and ds["run_richardson"].item() == 1, given
            assert ds["run_shooting_restarts"].item() >= 1, given
            worst[(order, scale)] = (ds["run_simulated_revolutions"].item(),
                                     _exact_error(given)(ds))
    revolutions, errors = np.array(list(worst.values())).T
    assert revolutions.max() <= 8, max(worst.items(), key=lambda kv: kv[1][0])
    assert revolutions.mean() < 7
    assert errors.max() < 3e-3, max(worst.items(), key=lambda kv: kv[1][1])
