"""Checks shared by the command-line tests."""

from __future__ import annotations

from typing import Any


def one_error_line(result: Any) -> str:
    """The single ``error:`` line of a refused command (exit status 2, no traceback)."""
    assert result.exit_code == 2, (result.exit_code, result.output, result.exception)
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]
