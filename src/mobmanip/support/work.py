"""What a command may cost: an estimate made before the work starts and a stated bound on it.

Every command whose work grows with its input (a carried path's duration over its step, a
trajectory's samples, a placement map's cells, a team's robots and headings) counts its units
of work before starting, refuses a count above its bound unless asked for more (``--max-work
N``), and says what it is about to do when that will take more than a few seconds.
:mod:`mobmanip.sweep.budget` does the same for sweeps with a grid of its own.
"""

from __future__ import annotations

import logging
import math
import sys
from dataclasses import dataclass

from ..errors import ArgumentError

#: An estimate above this many seconds is announced on standard error before the work starts.
ANNOUNCE_SECONDS = 30.0
#: Grid points (angle x distance x heading x velocity scale x effort scale) a sweep runs without
#: being asked for more: about a minute and a few gigabytes on one core (:mod:`mobmanip.sweep.budget`).
MAX_GRID_POINTS = 10_000_000

_log = logging.getLogger("mobmanip")


@dataclass(frozen=True)
class WorkEstimate:
    """The work a command is about to do.

    Attributes:
        command: the command (``"carry"``).
        units: what is counted (``"QP steps"``).
        count: how many.
        seconds_each: measured wall time of one unit on the paper's robot (s), rounded up.
        detail: how the count follows from the input (``"path 1e+05 s / step 0.02 s"``).
    """

    command: str
    units: str
    count: float
    seconds_each: float
    detail: str = ""

    @property
    def seconds(self) -> float:
        try:
            return self.count * self.seconds_each
        except OverflowError:  # a count of hundreds of digits, typed on the command line
            return math.inf

    def describe(self) -> str:
        if self.count < 1e15:
            count = f"{self.count:,.0f}"
        elif self.count <= sys.float_info.max:
            count = f"{self.count:.3g}"
        elif isinstance(self.count, int):  # an integer no float holds
            count = f"a number of {len(str(abs(self.count)))} digits of"
        else:  # e.g. --prepare 1e308 s over a step of 0.02 s
            count = "more than any float counts of"
        detail = f" ({self.detail})" if self.detail else ""
        return f"{count} {self.units}{detail}, about {duration(self.seconds)}"


def duration(seconds: float) -> str:
    """A duration for people: ``0.4 s``, ``12 min``, ``3.1 h``, ``40 days``."""
    if not math.isfinite(seconds):
        return "forever"
    if seconds < 90:
        return f"{max(seconds, 0.1):.1f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    if seconds < 3 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.3g} days"


def bound(override: int | None, default: int) -> int:
    """The bound in force: the ``--max-work`` given, else the command's default."""
    return default if override is None else override


def check_work(estimate: WorkEstimate, limit: int | None, option: str = "--max-work") -> WorkEstimate:
    """Refuse ``estimate`` above ``limit`` units (naming the estimate and the option that raises
    the limit); announce it on standard error when it exceeds :data:`ANNOUNCE_SECONDS`.

    Raises:
        ArgumentError: more work than ``limit``, or a ``limit`` below 1.
    """
    if limit is not None and limit < 1:
        raise ArgumentError(f"{option} must be at least 1, got {limit}")
    if limit is not None and not estimate.count <= limit:
        raise ArgumentError(
            f"{estimate.command}: {estimate.describe()}; more than the {limit:,} {estimate.units} it runs without "
            f"being asked (raise the bound with {option} N, or ask for less)"
        )
    _log.info("%s: %s", estimate.command, estimate.describe())
    if estimate.seconds > ANNOUNCE_SECONDS:
        print(f"mobmanip: {estimate.command}: {estimate.describe()}", file=sys.stderr, flush=True)
    return estimate


@dataclass(frozen=True)
class WorkBound:
    """A command's bound on one kind of work, for code that learns the count only as it reads
    (a recording's messages, a site file's positions): :meth:`check` refuses a count above
    ``limit`` as :func:`check_work` does, before the work starts.

    Attributes:
        command: the command (``"trajectory"``).
        units: what is counted (``"samples"``).
        seconds_each: measured wall time of one unit (s).
        limit: the bound in force (see :func:`bound`).
        option: the option that raises it.
    """

    command: str
    units: str
    seconds_each: float
    limit: int
    option: str = "--max-work"

    def check(self, count: float, detail: str = "") -> WorkEstimate:
        """Refuse ``count`` units above the limit (see :func:`check_work`)."""
        return check_work(WorkEstimate(self.command, self.units, count, self.seconds_each, detail), self.limit,
                          self.option)  # fmt: skip
