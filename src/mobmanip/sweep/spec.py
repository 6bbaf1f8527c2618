"""What a sweep is asked: its grid (:class:`SweepGrid`, :func:`parse_grid`) and what to sweep on
it (:class:`SweepSpec`), in a form any worker process or machine can rebuild the robot from.

:mod:`mobmanip.sweep.runner` runs a spec over a grid; :mod:`mobmanip.sweep.results` holds what
comes back. Both read this module; it reads neither.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError, GridError
from ..robot.model import Robot, load_robot
from ..support.reading import decimal
from ..terms.constraints.base import Constraint
from .budget import check_axis_count, check_values

#: Grid axes in order: the result arrays have this shape (one entry per value).
AXES = ("angle_deg", "distance", "heading_deg", "wheel_velocity_scale", "wheel_effort_scale")
#: Where the arms' postures come from (see :mod:`mobmanip.sweep.runner`).
POSTURE_METHODS = ("auto", "planar", "ik")


def parse_grid(text: str, name: str = "grid", positive: bool = False) -> np.ndarray:
    """Values of one grid axis from ``START:STOP:COUNT``, ``V1,V2,...`` or a single value.

    ``START:STOP:COUNT`` gives COUNT evenly spaced values from START to STOP, both included
    (``0:360:37`` is every 10 degrees). Values must be finite; with ``positive``, above zero.

    Raises:
        GridError: the text does not parse, COUNT is not a positive integer, or a value is bad.
    """
    text = str(text).strip()
    hint = "use START:STOP:COUNT, V1,V2,... or V"
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise GridError(f"{name}: expected START:STOP:COUNT, got {text!r}")
        count_text = parts[2].strip()
        if not (count_text.isascii() and count_text.isdigit()) or int(count_text) < 1:
            raise GridError(f"{name}: COUNT must be a positive integer, got {parts[2]!r} in {text!r}")
        check_axis_count(int(count_text), name)
        try:
            start, stop = decimal(parts[0]), decimal(parts[1])
        except ValueError:
            raise GridError(f"{name}: not a number in {text!r} ({hint})") from None
        count = int(count_text)
        if count == 1 and start != stop:
            raise GridError(f"{name}: one value from {start:g} to {stop:g}? use COUNT >= 2 or a single value")
        values = np.linspace(start, stop, count)
    else:
        try:
            values = np.array([decimal(v) for v in text.split(",")])
        except ValueError:
            raise GridError(f"{name}: not a number in {text!r} ({hint})") from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise GridError(f"{name}: values must be finite numbers, got {text!r}")
    if positive and np.any(values <= 0.0):
        raise GridError(f"{name}: values must be positive, got {text!r}")
    return values


@dataclass(frozen=True)
class SweepGrid:
    """The grid of a sweep; every axis is a 1-D array of values.

    Attributes:
        angle_deg: object directions from the platform heading (deg).
        distance: horizontal distances of the object from the arms' reference point (m): their
            common first joint for the planar postures, the horizontal centroid of their first
            joints for the inverse-kinematics ones.
        heading_deg: platform headings in the world (deg).
        wheel_velocity_scale: factors on both wheels' velocity limit.
        wheel_effort_scale: factors on both wheels' effort limit.
    """

    angle_deg: np.ndarray
    distance: np.ndarray
    heading_deg: np.ndarray = field(default_factory=lambda: np.zeros(1))
    wheel_velocity_scale: np.ndarray = field(default_factory=lambda: np.ones(1))
    wheel_effort_scale: np.ndarray = field(default_factory=lambda: np.ones(1))

    def __post_init__(self):
        for name in AXES:
            values = np.atleast_1d(np.asarray(getattr(self, name), dtype=float))
            if values.ndim != 1 or values.size == 0 or not np.all(np.isfinite(values)):
                raise GridError(f"{name}: a non-empty list of finite numbers is needed")
            if name in ("distance", "wheel_velocity_scale", "wheel_effort_scale") and np.any(values <= 0.0):
                raise GridError(f"{name}: values must be positive")
            check_values(name, values)
            object.__setattr__(self, name, values)

    @classmethod
    def parse(
        cls,
        angle: str,
        distance: str,
        heading: str = "0",
        wheel_velocity_scale: str = "1",
        wheel_effort_scale: str = "1",
    ) -> SweepGrid:
        """Build a grid from the command line's texts (see :func:`parse_grid`)."""
        return cls(
            parse_grid(angle, "--angle"),
            parse_grid(distance, "--distance", positive=True),
            parse_grid(heading, "--heading"),
            parse_grid(wheel_velocity_scale, "--wheel-velocity-scale", positive=True),
            parse_grid(wheel_effort_scale, "--wheel-effort-scale", positive=True),
        )

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(getattr(self, name)) for name in AXES)

    @property
    def n_configurations(self) -> int:
        """Distinct configurations: angle x distance x heading (limits do not change q)."""
        a, d, h, _, _ = self.shape
        return a * d * h

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep, in a form any worker process or machine can rebuild the robot from.

    Attributes:
        robot: built-in robot name or spec path (workers load it themselves; for a cluster,
            the path must exist on every worker).
        task: task space; defaults to the spec's ``default_task``.
        platform: ``"own"`` or ``"fixed"`` (locked platform).
        object_mass: object mass (kg); defaults to the spec's.
        decoupled: decoupled dynamics (the paper's Sec. 4.3).
        wheel_velocity_limit: both wheels' qdot_max before scaling (rad/s); default: the spec's.
        wheel_effort_limit: both wheels' tau_max before scaling (N m); default: the spec's.
        direction: the capacity direction: ``"radial"`` (from the reference point towards the object,
            in the horizontal plane), ``"tangential"`` (90 deg to the left of it) or task
            coordinates, e.g. ``(1, 0)`` (world frame; normalised).
        postures: ``"auto"``, ``"planar"`` or ``"ik"`` (see :mod:`mobmanip.sweep.runner`).
        reference: the inverse kinematics' reference posture, joint positions by name (a
            mapping or (name, value) pairs; joints not named stay at home); ``None``: the spec's
            hold posture, else the home configuration. Stored as a tuple of pairs.
        measures: the measures to sweep, by name (each needs a batch form, see
            :mod:`mobmanip.measures`); ``None``: the default ones (``kinematic``, ``dynamic``).
            :func:`mobmanip.sweep.run_sweep` stores them resolved, in the registry's order.
        constraints: constraints beyond the joint boxes (:mod:`mobmanip.terms.constraints`):
            the polytope measures honour them (computed one configuration at a time); the
            ellipsoids ignore them, and the result says so (:meth:`mobmanip.sweep.SweepResult.ignored_constraints`).
    """

    robot: str
    task: str | None = None
    platform: str = "own"
    object_mass: float | None = None
    decoupled: bool = False
    wheel_velocity_limit: float | None = None
    wheel_effort_limit: float | None = None
    direction: str | tuple[float, ...] = "radial"
    postures: str = "auto"
    reference: tuple[tuple[str, float], ...] | None = None
    measures: tuple[str, ...] | None = None
    constraints: tuple[Constraint, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "constraints", tuple(self.constraints))
        for c in self.constraints:
            if not isinstance(c, Constraint):
                raise ArgumentError(f"constraints must be mobmanip Constraints, got {c!r}")
        if self.measures is not None:
            names = (self.measures,) if isinstance(self.measures, str) else self.measures
            try:
                object.__setattr__(self, "measures", tuple(names))
            except TypeError:
                raise ArgumentError(f"measures must be measure names, got {self.measures!r}") from None
        if self.reference is not None:
            pairs = self.reference.items() if isinstance(self.reference, Mapping) else self.reference
            try:
                pairs = tuple((str(name), value) for name, value in pairs)
            except (TypeError, ValueError):
                raise ArgumentError(f"reference must map joint names to positions, got {self.reference!r}") from None
            object.__setattr__(self, "reference", pairs)

    def load(self) -> Robot:
        """The robot with the platform and base wheel limits applied."""
        robot = load_robot(self.robot)
        if self.wheel_velocity_limit is not None or self.wheel_effort_limit is not None:
            robot = robot.with_wheel_limits(velocity=self.wheel_velocity_limit, effort=self.wheel_effort_limit)
        if self.platform in ("fixed", "locked"):
            robot = robot.with_platform("fixed")
        elif self.platform != "own":
            raise ArgumentError(f"platform must be 'own' or 'fixed', got {self.platform!r}")
        return robot
