"""The floor under a moving robot: where the zero-moment point is at every sample of a motion.

The floor's resultant wrench on the robot and the object it carries is fixed by their momenta,
whatever share each contact takes: with the robot's centroidal momentum from Pinocchio
(``d/dt h_G = A_G qdd + dA_G v``, qdd = S xdot + Sdot x) and the object's (m a_o, its rotational
inertia times its angular acceleration), the floor pushes with

    F = p_dot_robot + p_dot_object - (M + m) g,
    M_O = k_dot_O,robot + k_dot_O,object - c x M g - c_o x m g          (about the world origin)

and the zero-moment point is where the horizontal part of that moment vanishes, on the floor.
The robot does not tip while it stays inside the support polygon; its signed distance to the
polygon's nearest edge (positive inside) is the stability margin. Unlike the contacts' shares,
these do not depend on how a statically indeterminate support divides the load.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..engine.stacked_linalg import cross3
from ..errors import NumericalError
from ..robot.model import Robot
from ..robot.support import Support, polygon_margin, robot_support
from ..robot.tasks import get_task
from ..terms.constraints.floor_wrench import WrenchSharing
from ..terms.dynamics import placed_end_effectors
from ..terms.grasp import GRAVITY, HeldObject, object_mass_of, skew
from .trajectory import Trajectory


@dataclass(frozen=True)
class GroundAlong:
    """The floor along a motion.

    Attributes:
        zmp: the zero-moment point per sample, world x, y (m), (N, 2).
        margin: its signed distance to the support polygon's nearest edge (m), (N,).
        normal: the floor's total normal force (N), (N,) (0 or less: the robot leaves the floor).
        support: the contacts used.
        force: the floor's resultant force on the robot and its object (N, world), (N, 3).
        moment: its moment about the world origin (N m, world), (N, 3).
        sharing: how the robot's contacts share the floor's wrench (the floor of motion's one
            model, :class:`mobmanip.terms.constraints.floor_wrench.WrenchSharing`).
    """

    zmp: np.ndarray
    margin: np.ndarray
    normal: np.ndarray
    support: Support
    force: np.ndarray | None = None
    moment: np.ndarray | None = None
    sharing: WrenchSharing | None = None

    def worst(self) -> int:
        """The sample with the smallest margin."""
        return int(np.argmin(self.margin))


def floor_wrench(
    robot: Robot,
    q: np.ndarray,
    x: np.ndarray,
    object_mass: float,
    object_acceleration: np.ndarray,
    object_acceleration_rate: np.ndarray,
    *,
    gravity: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The floor's resultant wrench on the robot and its object, affine in the reduced
    accelerations: (offset (6,), linear (6, nx)) with [force; moment about the world origin] =
    offset + linear @ xdot (N, N m; world axes), the velocity terms at (q, x).

    Args:
        robot, q, x: the robot, its configuration (nq,) and reduced velocity (nx,).
        object_mass: the object's mass (kg), held between the hands.
        object_acceleration, object_acceleration_rate: the object's 6-D acceleration (linear, then
            angular; world) as ``object_acceleration + object_acceleration_rate @ xdot``, (6,) and (6, nx).
        gravity: gravity in the floor's axes (m/s^2), (3,); default straight down (a level floor).
            On a ramp the world's axes are the ramp's (z its normal) and gravity leans
            (:meth:`mobmanip.motion.carry_floor.CarryFloor.gravity`).
    """
    g = np.asarray(GRAVITY if gravity is None else gravity, dtype=float)
    model, data = robot.model, robot.data
    mass = float(pin.computeTotalMass(model))
    S = robot.null_space(q)
    v = S @ x
    A_G = pin.computeCentroidalMap(model, data, q).copy()
    dA_G = pin.computeCentroidalMapTimeVariation(model, data, q, v)
    c = data.com[0].copy()
    # d/dt of the momentum about the centre of mass: A_G qdd + dA_G v, qdd = S xdot + Sdot x
    rate0 = A_G @ (robot.null_space_rate(q, x) @ x) + dA_G @ v
    rate1 = A_G @ S
    pin.framesForwardKinematics(model, data, q)
    hands = placed_end_effectors(robot)
    c_o = hands.mean(axis=0)
    a0, a1 = np.asarray(object_acceleration, dtype=float), np.asarray(object_acceleration_rate, dtype=float)
    offset, linear = np.zeros(6), np.zeros((6, S.shape[1]))
    offset[:3] = rate0[:3] + object_mass * a0[:3] - (mass + object_mass) * g
    linear[:3] = rate1[:3] + object_mass * a1[:3]
    offset[3:] = rate0[3:] + cross3(c, rate0[:3]) + object_mass * cross3(c_o, a0[:3])
    offset[3:] -= cross3(c, mass * g) + cross3(c_o, object_mass * g)  # the weights' moments
    linear[3:] = rate1[3:] + skew(c) @ rate1[:3] + object_mass * skew(c_o) @ a1[:3]
    if object_mass > 0.0:
        inertia = HeldObject.between(hands, object_mass).inertia
        offset[3:] += inertia @ a0[3:]
        linear[3:] += inertia @ a1[3:]
    return offset, linear


def rest_wrench(robot: Robot, q: np.ndarray, object_mass: float, *, gravity: np.ndarray | None = None) -> np.ndarray:
    """The floor's wrench at rest, (6,): :func:`floor_wrench`'s offset with the robot still and
    the object not accelerating, the robot's and the object's weights alone (N, N m; world axes,
    moment about the world origin)."""
    zero = np.zeros(robot.nx)
    return floor_wrench(robot, q, zero, object_mass, np.zeros(6), np.zeros((6, robot.nx)), gravity=gravity)[0]


def ground_along(
    robot: Robot,
    trajectory: Trajectory,
    object_acceleration: np.ndarray,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    support: Support | None = None,
    gravity: np.ndarray | None = None,
) -> GroundAlong:
    """The zero-moment point and stability margin at every sample (see the module's docstring).

    Args:
        robot: a robot with a wheeled platform.
        trajectory: the motion.
        object_acceleration: the object's acceleration in the task's rows per sample, (N, m)
            (:attr:`mobmanip.motion.trajectory_analysis.TrajectoryAnalysis.object_acceleration`); its
            rows outside the task are taken as zero (a planar task's object stays level).
        task: task-space name (default: the spec's).
        object_mass: the object held between the hands (kg; default: the spec's).
        support: the contacts (default: the robot's own, :func:`mobmanip.robot.support.robot_support`).
        gravity: gravity in the floor's axes, (3,) (default: a level floor), as :func:`floor_wrench`.
    """
    task = get_task(task or robot.spec.default_task)
    support = robot_support(robot) if support is None else support
    mass_o = object_mass_of(robot, object_mass)
    n = len(trajectory)
    zmp, margin, normal = np.zeros((n, 2)), np.zeros(n), np.zeros(n)
    forces, moments = np.zeros((n, 3)), np.zeros((n, 3))
    full = np.zeros((n, 6))
    full[:, list(task.rows)] = np.asarray(object_acceleration, dtype=float)
    z_floor = support.floor_z
    for i in range(n):
        q, x, xdot = trajectory.q[i], trajectory.x[i], trajectory.xdot[i]
        offset, linear = floor_wrench(robot, q, x, mass_o, full[i], np.zeros((6, robot.nx)), gravity=gravity)
        wrench = offset + linear @ xdot
        force, moment = wrench[:3], wrench[3:]
        normal[i] = force[2]
        forces[i], moments[i] = force, moment
        if force[2] <= 1e-9:
            raise NumericalError(
                f"at sample {i} (t = {trajectory.t[i]:.6g} s) the floor's normal force is {force[2]:.6g} N: "
                "the motion lifts the whole robot off the floor"
            )
        zmp[i] = ((z_floor * force[0] - moment[1]) / force[2], (moment[0] + z_floor * force[1]) / force[2])
        x0, y0, c0, s0 = q[0], q[1], q[2], q[3]
        pose = (float(x0), float(y0), math.atan2(float(s0), float(c0)))
        margin[i] = polygon_margin(support.polygon(pose), zmp[i])
    return GroundAlong(zmp, margin, normal, support, forces, moments, WrenchSharing.build(robot, support))
