"""The compiler of the solver's kernels: numba's ``njit``, or a clear error if numba is missing.

Every compiled kernel module imports ``njit`` from here, so the dependency and its message are
stated once.
"""

from __future__ import annotations

try:
    from numba import njit
except ImportError as exc:  # a hard dependency: say how to get it
    raise ImportError("bifilar's compiled kernels need numba: pip install 'numba>=0.59' "
                      "(a wheel for every supported platform is on PyPI)") from exc

__all__ = ["njit"]
