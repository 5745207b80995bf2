"""Helpers shared by the study tests."""

from __future__ import annotations

import numpy as np


def hub_samples(ds) -> np.ndarray:
    """The run's recorded rows as the sampler gives them: time, hub x, y and force x, y (fixed
    frame), tuning-mass centre x, y, pin angles."""
    return np.column_stack([ds["time"].values, *(ds[k].values for k in (
        "hub_x_fixed", "hub_y_fixed", "hub_force_x_fixed", "hub_force_y_fixed",
        "bifilar_cm_x_fixed", "bifilar_cm_y_fixed")), ds["pin_angle"].values.T])


# The rotor with the Peters–He inflow alone and two aerodynamic sections per element: what the
# tests run that are about anything but the inflow (a third of the prescribed wake's
# revolutions, each cheaper). The inflow's convergence is tested in test_rotor_wake.py.
PETERS_HE = {"inflow": "peters_he", "aero_points": 2}

# The tests' coarse rotor case (Peters–He alone): 120 steps/rev, 3 elements, 3 settling
# revolutions, periodic to 5 %, harmonics as marched (no step-error estimate).
COARSE_ROTOR = {**PETERS_HE, "steps_per_rev": 120, "blade_elements": 3, "wake_states": 2,
                "settle_revolutions": 3, "periodic_tolerance": 0.05, "error_estimate": False,
                "richardson": False}
