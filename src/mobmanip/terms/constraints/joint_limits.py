"""The joint boxes, the first two constraints: every wheel and joint within its own limit.

``|x_i| <= xdot_max_i`` in the velocity problem and ``|tau_i| <= tau_max_i`` in the acceleration
problem, the limits being the robot's (:attr:`mobmanip.robot.model.Robot.velocity_limits` and
``effort_limits``, in the reduced velocity's order) as the terms carry them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import ArgumentError
from .base import Constraint, ConstraintRows, Terms

#: Per problem, the variable its joint box bounds and what that variable's limits are (the rows'
#: kind, and the terms' ``<kind>_limits`` they read): the velocities x, the efforts tau.
BOXED: dict[str, tuple[str, str]] = {"velocity": ("x", "velocity"), "acceleration": ("tau", "effort")}


@dataclass(frozen=True)
class JointBox(Constraint):
    """A problem's joint box: ``|z_i| <= limit_i`` on its variable z of :data:`BOXED`, one ``(+)``
    and one ``(-)`` row per reduced velocity, labelled by the joint's name."""

    name: str
    problem: str
    joint_box: bool = True

    def __post_init__(self) -> None:
        if self.problem not in BOXED:
            raise ArgumentError(f"joint box {self.name!r}: its problem is one of {sorted(BOXED)}, got {self.problem!r}")

    def rows(self, terms: Terms) -> ConstraintRows:
        variable, kind = BOXED[self.problem]
        limits = terms.velocity_limits if kind == "velocity" else terms.effort_limits
        n = len(limits)
        labels = tuple(f"{joint} {kind} limit (+)" for joint in terms.reduced_names) + tuple(
            f"{joint} {kind} limit (-)" for joint in terms.reduced_names
        )
        return ConstraintRows(
            name=self.name,
            problem=self.problem,
            G={variable: np.vstack([np.eye(n), -np.eye(n)])},
            h=np.r_[limits, limits],
            labels=labels,
            kinds=(kind,) * (2 * n),
        )


@dataclass(frozen=True)
class VelocityBox(JointBox):
    """Every reduced velocity within its speed limit (rad/s or m/s)."""

    name: str = "velocity_limits"
    problem: str = "velocity"


@dataclass(frozen=True)
class EffortBox(JointBox):
    """Every reduced effort within its limit (N m or N)."""

    name: str = "effort_limits"
    problem: str = "acceleration"


#: The constraints every problem has.
JOINT_BOXES: tuple[Constraint, ...] = (VelocityBox(), EffortBox())
