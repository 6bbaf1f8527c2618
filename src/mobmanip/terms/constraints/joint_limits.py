"""The joint boxes, the first two constraints: every wheel and joint within its own limit.

``|x_i| <= xdot_max_i`` in the velocity problem and ``|tau_i| <= tau_max_i`` in the acceleration
problem, the limits being the robot's (:attr:`mobmanip.robot.model.Robot.velocity_limits` and
``effort_limits``, in the reduced velocity's order) as the terms carry them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Constraint, ConstraintRows, Terms


def _box(
    name: str, problem: str, variable: str, limits: np.ndarray, names: tuple[str, ...], kind: str
) -> ConstraintRows:
    n = len(limits)
    labels = tuple(f"{joint} {kind} limit (+)" for joint in names) + tuple(
        f"{joint} {kind} limit (-)" for joint in names
    )
    return ConstraintRows(
        name=name,
        problem=problem,
        G={variable: np.vstack([np.eye(n), -np.eye(n)])},
        h=np.r_[limits, limits],
        labels=labels,
        kinds=(kind,) * (2 * n),
    )


@dataclass(frozen=True)
class VelocityBox(Constraint):
    """Every reduced velocity within its speed limit (rad/s or m/s)."""

    name: str = "velocity_limits"
    problem: str = "velocity"
    joint_box: bool = True

    def rows(self, terms: Terms) -> ConstraintRows:
        return _box(self.name, self.problem, "x", terms.velocity_limits, terms.reduced_names, "velocity")


@dataclass(frozen=True)
class EffortBox(Constraint):
    """Every reduced effort within its limit (N m or N)."""

    name: str = "effort_limits"
    problem: str = "acceleration"
    joint_box: bool = True

    def rows(self, terms: Terms) -> ConstraintRows:
        return _box(self.name, self.problem, "tau", terms.effort_limits, terms.reduced_names, "effort")


#: The constraints every problem has.
JOINT_BOXES: tuple[Constraint, ...] = (VelocityBox(), EffortBox())
