"""Analyse one configuration: reduced dynamics, unified Jacobian and (later) ellipsoids.

:func:`analyze` is the single entry point behind ``mobmanip analyze`` and the Python API;
:meth:`Analysis.to_dict` gives the JSON document the command writes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .dynamics import decouple, end_effector_positions, reduced_dynamics, unified_jacobian
from .model import Robot
from .tasks import get_task


@dataclass(frozen=True)
class Analysis:
    """Everything computed at one configuration.

    Attributes:
        robot: the robot analysed (with its platform and limits).
        q: configuration, (nq,).
        task: task-space name.
        unified_jacobian: J_u, (m * n_arms, nx).
        reduced_inertia: P (coupled), (nx, nx).
        reduced_inertia_decoupled: P with platform-arm blocks zeroed, (nx, nx).
        input_matrix: Q, (nx, nx).
        bias: xi at rest (= -S^T g), (nx,).
        end_effector_positions: world positions of the end effectors, (n_arms, 3).
    """

    robot: Robot
    q: np.ndarray
    task: str
    unified_jacobian: np.ndarray
    reduced_inertia: np.ndarray
    reduced_inertia_decoupled: np.ndarray
    input_matrix: np.ndarray
    bias: np.ndarray
    end_effector_positions: np.ndarray

    def to_dict(self) -> dict:
        """A JSON-ready dictionary (matrices as lists of rows)."""
        robot = self.robot
        return {
            "robot": robot.name,
            "platform": robot.platform.kind,
            "task": self.task,
            "q": robot.configuration_dict(self.q),
            "reduced_velocity_names": list(robot.reduced_velocity_names),
            "arms": [
                {"name": arm.name, "end_effector": arm.end_effector, "position": pos.tolist()}
                for arm, pos in zip(robot.arms, self.end_effector_positions)
            ],
            "unified_jacobian": self.unified_jacobian.tolist(),
            "reduced_inertia": self.reduced_inertia.tolist(),
            "reduced_inertia_decoupled": self.reduced_inertia_decoupled.tolist(),
            "input_matrix": self.input_matrix.tolist(),
            "bias": self.bias.tolist(),
            "velocity_limits": robot.velocity_limits.tolist(),
            "effort_limits": robot.effort_limits.tolist(),
        }


def analyze(robot: Robot, q: np.ndarray, task: str | None = None) -> Analysis:
    """Analyse the robot at configuration q (robot and object at rest).

    Args:
        robot: the loaded robot (use ``robot.with_platform("fixed")`` for locked wheels).
        q: configuration, (nq,); see :meth:`Robot.configuration`.
        task: task space name; defaults to the spec's ``default_task``.
    """
    q = robot.check_configuration(q)
    task = get_task(task or robot.spec.default_task)
    dyn = reduced_dynamics(robot, q)
    J_u = unified_jacobian(robot, q, task)
    return Analysis(
        robot=robot,
        q=q,
        task=task.name,
        unified_jacobian=J_u,
        reduced_inertia=dyn.P,
        reduced_inertia_decoupled=decouple(robot, dyn.P),
        input_matrix=dyn.Q,
        bias=dyn.xi,
        end_effector_positions=end_effector_positions(robot, q),
    )
