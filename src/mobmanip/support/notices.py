"""Warnings for the user, each said once.

A warning that holds for a whole command (a vendor flaw repaired when the robot was loaded, say)
may be met again by every result that carries it (an analysis lists it in its ``"warnings"``).
Inside :func:`notice_session` (the ``mobmanip`` command opens one per run) :func:`notice` prints
each distinct text once, ``warning: TEXT`` on standard error, when it is first met; outside one
(the Python API) it goes to the ``mobmanip`` logger at WARNING level, and the objects that carry
the warnings (``Robot.warnings``, ``Analysis.warnings``) are where a program reads them.
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import sys
from collections.abc import Iterator
from typing import TextIO

_SEEN: contextvars.ContextVar[set[str] | None] = contextvars.ContextVar("mobmanip_notices", default=None)
_log = logging.getLogger("mobmanip")


@contextlib.contextmanager
def notice_session() -> Iterator[None]:
    """While active, :func:`notice` prints each distinct warning once on standard error."""
    token = _SEEN.set(set())
    try:
        yield
    finally:
        _SEEN.reset(token)


def notice(text: str, stream: TextIO | None = None) -> None:
    """Say ``text`` to the user once (see the module docstring)."""
    seen = _SEEN.get()
    if seen is None:
        if stream is not None:
            print(f"warning: {text}", file=stream)
        else:
            _log.warning("%s", text)
        return
    if text in seen:
        return
    seen.add(text)
    print(f"warning: {text}", file=stream or sys.stderr)
