"""Drivers' rates and accelerations against central differences of their values."""

import numpy as np
import pytest

from solver.timefunctions import cos_of, harmonic, sin_of
from studies.trim import ControlSchedule


def _differenced(f, t: float, h: float = 1e-4) -> tuple[float, float]:
    """Rate and acceleration of ``f.value`` by central differences (error O(h²) of the
    derivatives: about 1e-8 of their scale here)."""
    up, mid, down = f.value(t + h), f.value(t), f.value(t - h)
    return (up - down) / (2 * h), (up - 2 * mid + down) / h**2


@pytest.mark.parametrize("compose", [sin_of, cos_of])
def test_composed_drivers_rate_and_acceleration(compose):
    f = compose(harmonic(0.4, 3.0, 0.2))
    for t in (0.0, 0.37, 1.9):
        value, rate, accel = f(t)
        assert value == f.value(t) and rate == f.rate(t) and accel == f.accel(t)
        d1, d2 = _differenced(f, t)
        assert rate == pytest.approx(d1, abs=1e-7)
        assert accel == pytest.approx(d2, abs=1e-5)


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
        assert rate == pytest.approx(d1, rel=1e-6, abs=1e-8)
        assert accel == pytest.approx(d2, rel=1e-4, abs=1e-4)
        # and composed as the pitch bearing's constraint takes it
        s = sin_of(blade)
        d1, d2 = _differenced(s, t, h=1e-5)
        assert s(t)[1] == pytest.approx(d1, rel=1e-6, abs=1e-8)
        assert s(t)[2] == pytest.approx(d2, rel=1e-4, abs=1e-4)
