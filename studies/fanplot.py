"""The fan plot of the articulated UH-60A blade as a model: one case is the whole diagram.

The modes are followed by their shapes from speed to speed (:func:`studies.blade.fanplot`), so
the rotor speeds are one parameter of one case, a blank-separated list, not a sweep of
independent cases.
"""

from __future__ import annotations

import math

import xarray as xr

from studies import swashplate
from studies.parameters import ModelSpec, Output, Param, ParameterError, Parameters

# Highest rotor speed (rad/s): well past any rotor's overspeed; the data set is for 27 rad/s.
MAX_SPEED = 60.0

PARAMETERS: dict[str, Param] = {
    "speeds": Param("", "rad s-1", "rotor speeds, separated by blanks (empty: 0 to 1.2 times "
                    "the reference speed in steps of 0.1 times it)"),
    "elements": Param(6, "1", "cubic beam elements from the hinge to the tip", minimum=1,
                      maximum=60),
    # the rotor's control system (the same parameters): prescribed = a rigid pitch link
    **swashplate.PARAMETERS,
}

OUTPUTS: dict[str, Output] = {
    "hub_speed": Output("rad s-1", "rotor speed", dims=("hub_speed",)),
    "mode": Output("1", "mode index", dims=("mode",)),
    "mode_label": Output("1", "dominant motion of the mode", dims=("mode",)),
    "frequency": Output("Hz", "natural frequency in the rotating frame",
                        dims=("hub_speed", "mode")),
}


def speeds_of(text: str) -> list[float]:
    """The rotor speeds of the ``speeds`` parameter (rad/s); raises ParameterError."""
    speeds = []
    for item in text.replace(",", " ").split():
        try:
            value = float(item)
        except ValueError:
            raise ParameterError(f"speeds: {item!r} is not a number (rad/s)") from None
        if not (math.isfinite(value) and 0.0 <= value <= MAX_SPEED):
            raise ParameterError(f"speeds: {value:g} rad/s is outside the valid range "
                                 f"[0, {MAX_SPEED:g}] rad s-1")
        speeds.append(value)
    return speeds


def check(p: Parameters) -> None:
    """The speeds parse as rotor speeds in range (raises ParameterError)."""
    speeds_of(p.speeds)


def simulate(p: Parameters) -> xr.Dataset:
    """Natural frequencies over (hub_speed, mode), as :func:`studies.blade.fanplot`."""
    from studies.blade import fanplot

    return fanplot(speeds_of(p.speeds) or None, n_elements=p.elements,
                   control_system=p.control_system,
                   pitch_link_stiffness=p.pitch_link_stiffness,
                   pitch_horn_length=p.pitch_horn_length)


SPEC = ModelSpec("fanplot", PARAMETERS, simulate, check,
                 description="natural frequencies of the articulated UH-60A blade against "
                             "rotor speed", outputs=OUTPUTS, version="2")
