"""Drivers' rates and accelerations against central differences of their values."""

import numpy as np
import pytest

from solver.timefunctions import cos_of, harmonic, sin_of
from studies.swashplate import ring_drive
from studies.trim import ControlSchedule


def _differenced(f, t: float, h: float = 1e-4) -> tuple[float, float]:
    """Rate and acceleration of ``f.value`` by central differences: their truncation and
    roundoff errors, measured against the closed forms below, are at most 2e-8 and 4e-8 for
    the harmonic's compositions (h = 1e-4) and 1.3e-8 and 1e-7 of the pitch's largest rate
    and acceleration (h = 1e-5); the tolerances are ten times that."""
    up, mid, down = f.value(t + h), f.value(t), f.value(t - h)
    return (up - down) / (2 * h), (up - 2 * mid + down) / h**2


@pytest.mark.parametrize("compose", [sin_of, cos_of])
def test_composed_drivers_rate_and_acceleration(compose):
    f = compose(harmonic(0.4, 3.0, 0.2))
    for t in (0.0, 0.37, 1.9):
        value, rate, accel = f(t)
        assert value == f.value(t) and rate == f.rate(t) and accel == f.accel(t)
        d1, d2 = _differenced(f, t)
        assert rate == pytest.approx(d1, abs=2e-7)
        assert accel == pytest.approx(d2, abs=4e-7)


def test_a_blade_pitch_during_a_control_ramp():
    # θ0 + θc cos ψ + θs sin ψ with the controls ramping: the rates carry both the azimuth's
    # and the controls' own rates
    schedule = ControlSchedule(np.radians([8.0, 1.5, -3.0]), 0.0, 27.0)
    schedule.set(np.radians([9.0, 2.0, -4.0]), 0.1, 0.5)
    blade = schedule.pitch(np.pi / 2, reference=0.1)
    for t in (0.05, 0.2, 0.35, 0.55, 0.8):
        value, rate, accel = blade(t)
        assert value == blade.value(t)
        d1, d2 = _differenced(blade, t, h=1e-5)
        assert rate == pytest.approx(d1, abs=2.5e-7)
        assert accel == pytest.approx(d2, abs=4.5e-5)
        # and composed as the pitch bearing's constraint and the swashplate's ring drive take
        # it (the ring's stroke for a 0.2 m horn: m, m/s, m/s²)
        for f in (sin_of(blade), ring_drive(blade, 0.2, 0.01)):
            d1, d2 = _differenced(f, t, h=1e-5)
            assert f(t)[1] == pytest.approx(d1, abs=2.5e-7)
            assert f(t)[2] == pytest.approx(d2, abs=4.5e-5)
