"""Per-rev harmonics: moved to :mod:`studies.harmonics` (studies use them too); re-exported."""

from studies.harmonics import (
    N_MAX,
    TIME_STEP_RTOL,
    Harmonics,
    case_harmonics,
    harmonic_names,
    harmonic_signals,
    harmonics,
    recording_layout,
    required_variables,
    vector_quantities,
)

__all__ = [
    "N_MAX",
    "TIME_STEP_RTOL",
    "Harmonics",
    "case_harmonics",
    "harmonic_names",
    "harmonic_signals",
    "harmonics",
    "recording_layout",
    "required_variables",
    "vector_quantities",
]
