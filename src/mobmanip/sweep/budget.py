"""What a sweep may cost: a stated limit on its grid, an estimate of time and memory made before
it starts, the ranges of grid values, and worker processes that end with their parent.

A grid of 10^9 points would allocate its index arrays (hundreds of gigabytes) or run for hours
before anything is reported; :func:`check_grid` refuses grids above :data:`MAX_GRID_POINTS`
points unless the caller raises the limit (``run_sweep(..., max_points=...)``,
``mobmanip sweep --max-points N``), and any grid whose estimated memory exceeds the machine's.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import signal
import threading
import time
from dataclasses import dataclass

import numpy as np

from ..errors import GridError
from ..support.work import MAX_GRID_POINTS

#: Measured on the paper's robot (docs/howto/batch.md, "How fast"): 3.85 s for 10^6 configurations in one
#: process, 440 MB peak; per point, rounded up.
SECONDS_PER_POINT = 4e-6
BYTES_PER_POINT = 450
#: Inverse kinematics per (angle, distance) point (TIAGo++: 1.3 s for 360 points), rounded up.
SECONDS_PER_IK_POSTURE = 4e-3
#: Magnitude of angles and headings (deg), range of distances (m) and of limit scale factors.
MAX_ANGLE_DEG = 1e6
DISTANCE_RANGE = (0.0, 1e3)
SCALE_RANGE = (1e-6, 1e6)


@dataclass(frozen=True)
class SweepEstimate:
    """Rough cost of a sweep, before it runs.

    Attributes:
        points: grid points.
        seconds: wall time (s) on the given workers.
        bytes: peak memory (bytes) of the main process.
    """

    points: int
    seconds: float
    bytes: int

    def describe(self) -> str:
        return f"{self.points:,} grid points, about {_duration(self.seconds)} and {_size(self.bytes)} of memory"


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{max(seconds, 0.1):.1f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _size(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if n < 1000 or unit == "TB":
            return f"{n:.0f} {unit}"
        n /= 1000
    return f"{n:.0f} TB"  # pragma: no cover


def estimate(shape: tuple[int, ...], workers: int = 1, inverse_kinematics: bool = False) -> SweepEstimate:
    """The cost of a grid of ``shape`` (angle, distance, heading, velocity scale, effort scale)."""
    points = math.prod(int(n) for n in shape)
    seconds = points * SECONDS_PER_POINT / max(1, workers)
    if inverse_kinematics:
        seconds += shape[0] * shape[1] * SECONDS_PER_IK_POSTURE / max(1, workers)
    return SweepEstimate(points, seconds, points * BYTES_PER_POINT)


def _physical_memory() -> int | None:
    with contextlib.suppress(ValueError, OSError, AttributeError):
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    return None


def check_grid(shape: tuple[int, ...], max_points: int | None = MAX_GRID_POINTS, workers: int = 1) -> SweepEstimate:
    """Refuse a grid above ``max_points`` points (``None``: no limit) or one whose estimated
    memory exceeds the machine's; return its estimate.

    Raises:
        GridError: naming the grid's size and estimated cost.
    """
    cost = estimate(shape, workers)
    if max_points is not None and cost.points > max_points:
        raise GridError(
            f"the grid, {' x '.join(str(n) for n in shape)} = {cost.describe()}, is more than the limit of "
            f"{max_points:,} points: use a coarser grid or raise the limit (--max-points, run_sweep(max_points=...))"
        )
    memory = _physical_memory()
    if memory is not None and cost.bytes > memory:
        raise GridError(f"the grid has {cost.describe()}, more than this machine's {_size(memory)}")
    return cost


def check_axis_count(count: int, name: str) -> None:
    """A grid axis of at most :data:`MAX_GRID_POINTS` values (before it is allocated)."""
    if count > MAX_GRID_POINTS:
        raise GridError(f"{name}: {count:,} values is more than a sweep can take (at most {MAX_GRID_POINTS:,} points)")


def check_values(name: str, values: np.ndarray) -> None:
    """Grid values within the supported ranges (angles, distances, scale factors).

    Raises:
        GridError: the first value outside, with the range.
    """
    if name in ("angle_deg", "heading_deg"):
        low, high = -MAX_ANGLE_DEG, MAX_ANGLE_DEG
    elif name == "distance":
        low, high = DISTANCE_RANGE
    else:
        low, high = SCALE_RANGE
    bad = values[(values < low) | (values > high)]
    if bad.size:
        raise GridError(f"{name}: {bad[0]:g} is outside the supported range [{low:g}, {high:g}]")


# ----- worker processes


def exit_with_parent(parent_pid: int) -> None:
    """Pool initializer: end this worker when the process that started it dies (even by SIGKILL).

    On Linux the kernel sends SIGKILL on the parent's death (``PR_SET_PDEATHSIG``); everywhere a
    daemon thread also checks every half second that the parent is still there.
    """
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG = 1
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)

    def watch():
        while True:
            time.sleep(0.5)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="mobmanip-parent-watch", daemon=True).start()


def check_scaled_limits(robot, grid) -> None:
    """The wheel limits at the grid's smallest and largest scale factors within the ranges of
    :mod:`mobmanip.support.ranges` (as :meth:`mobmanip.robot.model.Robot.with_limits` would check them).

    Raises:
        RangeError: naming the scale factor and the limit.
    """
    from ..errors import RangeError
    from ..support.ranges import check_limit, check_limit_ratio

    names = robot.reduced_velocity_names
    drives = [k for k, name in enumerate(robot.platform.reduced_names) if name in robot.platform.drive_names]
    if not drives:
        return
    for kind, base, scales in (
        ("velocity", robot.velocity_limits, grid.wheel_velocity_scale),
        ("effort", robot.effort_limits, grid.wheel_effort_scale),
    ):
        for scale in (float(np.min(scales)), float(np.max(scales))):
            limits = np.array(base, dtype=float)
            limits[drives] *= scale
            try:
                for k in drives:
                    check_limit(names[k], kind, float(limits[k]))
                check_limit_ratio(kind, dict(zip(names, limits.tolist())))
            except RangeError as exc:
                raise RangeError(
                    f"with wheel {kind} scale {scale:g}, {exc.what}", exc.value, exc.low, exc.high
                ) from None
