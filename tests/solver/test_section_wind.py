"""Prescribed periodic wind at lifting-line sections (solver/section_wind.py)."""

from __future__ import annotations

import numpy as np
import pytest

from solver.section_wind import PeriodicWind


def test_wind_interpolates_its_samples_linearly_and_periodically():
    rng = np.random.default_rng(3)
    period, n = 0.25, 12
    table = rng.standard_normal((n, 5, 3))
    wind = PeriodicWind(period, table, delay=0.031)
    times = rng.uniform(-1.0, 1.0, 40)
    for t in times:
        # np.interp on the periodic extension of each component, an independent reading
        tt = np.arange(n + 1) * period / n
        ext = np.concatenate([table, table[:1]])
        phase = (t + 0.031) % period
        expect = np.array([[np.interp(phase, tt, ext[:, i, c]) for c in range(3)]
                           for i in range(5)])
        assert np.allclose(wind(t), expect, rtol=0, atol=1e-13)
    # on a sample it is the sample, and the table is kept by reference
    assert np.array_equal(wind(3 * period / n - 0.031), table[3])
    table[3] = 7.0
    assert np.all(wind(3 * period / n - 0.031) == 7.0)


@pytest.mark.parametrize(("period", "table", "delay", "what"), [
    (0.0, np.zeros((4, 2, 3)), 0.0, "period"),
    (1.0, np.zeros((1, 2, 3)), 0.0, "table"),
    (1.0, np.zeros((4, 2, 2)), 0.0, "table"),
    (1.0, np.zeros((4, 2, 3)), np.nan, "delay"),
])
def test_bad_wind_is_named(period, table, delay, what):
    with pytest.raises(ValueError, match=what):
        PeriodicWind(period, table, delay)
