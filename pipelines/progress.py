"""Progress of a sweep on the driver's stderr: one line per finished case, and the lines the
models report while their cases run.

A worker sends its case's lines (:func:`studies.progress.report`, and the compile notice) as
dask events on the sweep's own topic (:func:`pipelines.worker.run_case`); the driver subscribes
to that topic and prints each line under its case's label.
"""

from __future__ import annotations

import sys
import uuid
from collections.abc import Callable, Mapping
from typing import Any

# Dask event topic prefix of the progress lines; one topic per sweep.
PROGRESS_TOPIC = "bifilar-progress"


def printer(enabled: bool = True) -> Callable[[str], None]:
    """A ``say(line)`` that prints to stderr at once, or does nothing."""

    def say(line: str) -> None:
        if enabled:
            print(line, file=sys.stderr, flush=True)

    return say


def new_topic() -> str:
    """A topic of its own for one sweep (two sweeps on one scheduler do not mix lines)."""
    return f"{PROGRESS_TOPIC}-{uuid.uuid4().hex[:12]}"


def forward(say: Callable[[str], None],
            labels: Mapping[str, str]) -> Callable[[tuple[float, Any]], None]:
    """The handler of the topic's events: each line printed under its case's label."""

    def handle(event: tuple[float, Any]) -> None:
        msg = event[1]
        if isinstance(msg, dict) and msg.get("case_id") in labels:
            say(f"  case {labels[msg['case_id']]}: {msg.get('message', '')}")

    return handle


def finished_line(done: int, total: int, label: str, result: Mapping[str, Any],
                  ok: bool) -> str:
    """``[k/N] case <label> ok (12.3 s)``, or ``failed (…): <message>``."""
    return (f"[{done}/{total}] case {label} {'ok' if ok else 'failed'} "
            f"({result['wall_time']:.1f} s)" + ("" if ok else f": {result['message']}"))
