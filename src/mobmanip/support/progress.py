"""Progress bars for long runs: one look for every command, on standard error, and only on a
terminal (a bar in piped or redirected output, or beside JSON, would be noise in a file)."""

from __future__ import annotations

import sys
from typing import Any


def on_terminal() -> bool:
    """Whether standard error is a terminal (where progress bars are shown)."""
    try:
        return bool(sys.stderr.isatty())
    except (AttributeError, ValueError):  # no isatty, or closed
        return False


def progress_bar(total: int, *, desc: str, unit: str, show: bool) -> Any:
    """A tqdm bar on standard error that disappears when done (``leave=False``), or one that
    shows nothing when ``show`` is false: callers update and close it either way.

    Args:
        total: the steps of the run.
        desc: what runs (``"carry qp"``).
        unit: what a step is (``"step"``, ``"sample"``).
        show: whether to show it (a command passes ``not --no-progress`` and :func:`on_terminal`).
    """
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=not show, leave=False, file=sys.stderr)
