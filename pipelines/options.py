"""Click parameter types shared by the ``bifilar`` commands."""

from __future__ import annotations

from typing import Any

import click


class OutPath(click.Path):
    """A ``click.Path`` that refuses an empty value.

    ``--out ""`` would otherwise become ``Path("")``, which is the current directory: a sweep
    would write into wherever the user happens to be and exit 0.
    """

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        if isinstance(value, str) and not value.strip():
            self.fail("an empty path; give a directory or file name (use . for the current "
                      "directory)", param, ctx)
        return super().convert(value, param, ctx)
