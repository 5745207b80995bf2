"""Progress of a running model, reported without knowing who listens.

A model's run function calls :func:`report` with a short line ("revolution 12: periodicity
change 3.1e-03, tolerance 1e-03"). Nobody listens by default, so a model run from a script or a
test prints nothing. The sweep pipeline listens while a case runs on a dask worker
(:func:`reporting`) and forwards the lines to the client that started the sweep, which prints
them under the case's name.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from contextvars import ContextVar

_LISTENER: ContextVar[Callable[[str], None] | None] = ContextVar("bifilar_progress",
                                                                  default=None)


def report(message: str) -> None:
    """Pass one progress line to the current listener, if any (never raises)."""
    listener = _LISTENER.get()
    if listener is None:
        return
    with contextlib.suppress(Exception):  # progress must never fail a run
        listener(message)


@contextlib.contextmanager
def reporting(listener: Callable[[str], None]) -> Iterator[None]:
    """Send the :func:`report` lines of the code run inside this block to ``listener``."""
    token = _LISTENER.set(listener)
    try:
        yield
    finally:
        _LISTENER.reset(token)
