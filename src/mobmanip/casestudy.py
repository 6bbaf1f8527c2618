"""The paper's Section 4 case study: two mirrored 3R arms holding an object at the platform.

Each arm takes the posture that maximises its own kinematic manipulability sqrt(det(J J^T))
(2 x 3 translational Jacobian in the horizontal plane), found numerically on the model's own
Jacobian; the arms mirror each other about the line from P_o to the object, and q1 of each arm
points its end effector at the object. The object direction alpha is measured from the platform
heading (0 deg in front, 90 deg to the left). Both end effectors grasp the object at its centre.

Sweeps: Fig. 3 varies the platform's maximum rim speed (wheel qdot_max = v / r) and adds the
locked platform; Fig. 4 varies the wheels' maximum torque, with decoupled dynamics as in the
paper and coupled dynamics as the paper did not.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .analysis.single import Analysis, analyze
from .errors import SpecError
from .measures import DYNAMIC, KINEMATIC, get_measure
from .platforms import DifferentialDrive
from .robot.model import Arm, Robot

ANGLES_DEG = (0.0, 45.0, 90.0)
PLATFORM_SPEEDS = (0.001, 0.5, 1.0)  # m/s, maximum rim speed of the wheels (Fig. 3)
WHEEL_TORQUES = (200.0, 50.0, 10.0)  # N m (Fig. 4)


@dataclass(frozen=True)
class ArmPosture:
    """The globally optimal posture of one arm.

    Attributes:
        q: joint angles (q1 = 0, q2, q3) (rad).
        manipulability: sqrt(det(J J^T)) of the arm's horizontal translational Jacobian (m^2).
        reach: horizontal distance from the arm's first joint to its end effector (m).
        bearing: direction of the end effector seen from the first joint at q1 = 0 (rad).
    """

    q: tuple[float, ...]
    manipulability: float
    reach: float
    bearing: float


def _check_paper_like(robot: Robot) -> None:
    if not isinstance(robot.platform, DifferentialDrive) or len(robot.arms) != 2:  # the paper's own platform
        raise SpecError(f"the case study needs a differential drive with two arms; {robot.name!r} does not fit")
    if any(len(arm.joint_names) != 3 for arm in robot.arms):
        raise SpecError(f"the case study needs two 3-joint arms; {robot.name!r} has other arms")


def arm_measure(robot: Robot, arm: Arm, q2: float, q3: float) -> tuple[float, np.ndarray, np.ndarray]:
    """An arm's own manipulability sqrt(det(J J^T)) of its planar 2 x 3 translational Jacobian,
    its end-effector position and its first joint's position (m), at joints (0, q2, q3) (rad)."""
    model, data = robot.model, robot.data
    q = robot.configuration(joints=dict(zip(arm.joint_names, (0.0, q2, q3))))
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)[:2, list(arm.v_indices)]
    w = math.sqrt(max(np.linalg.det(J @ J.T), 0.0))
    base = data.oMi[model.getJointId(arm.joint_names[0])].translation
    return w, data.oMf[arm.frame_id].translation.copy(), base.copy()


def optimal_posture(robot: Robot, arm_index: int = 0, grid: int = 73, refinements: int = 6) -> ArmPosture:
    """Maximise an arm's own manipulability over (q2, q3) by grid search with zooming.

    The search starts on a ``grid`` x ``grid`` lattice over [-pi, pi]^2 and zooms in around the
    best point ``refinements`` times (each time to a cell of the previous lattice); the result is
    accurate to about 2 pi / grid / (grid / 4)^refinements rad. Among the two mirror-image optima
    (q2, q3) and (-q2, -q3), the one that bends to the right (positive bearing) is returned.
    """
    _check_paper_like(robot)
    arm = robot.arms[arm_index]
    center, half = np.zeros(2), math.pi
    best = (-1.0, 0.0, 0.0)
    for _ in range(refinements + 1):
        values = np.linspace(-half, half, grid)
        for dq2 in values:
            for dq3 in values:
                q2, q3 = center[0] + dq2, center[1] + dq3
                w = arm_measure(robot, arm, q2, q3)[0]
                if w > best[0]:
                    best = (w, q2, q3)
        center = np.array(best[1:])
        half = 2.0 * half / (grid - 1)
    w, q2, q3 = best
    _, tip, base = arm_measure(robot, arm, q2, q3)
    bearing = math.atan2(tip[1] - base[1], tip[0] - base[0])
    if bearing < 0:  # take the mirror image so that the arm's elbow is on its right
        q2, q3 = -q2, -q3
        _, tip, base = arm_measure(robot, arm, q2, q3)
        bearing = math.atan2(tip[1] - base[1], tip[0] - base[0])
    reach = float(np.hypot(*(tip - base)[:2]))
    return ArmPosture((0.0, float(q2), float(q3)), float(w), reach, float(bearing))


def configuration_at(robot: Robot, posture: ArmPosture, angle_deg: float, heading: float = 0.0) -> np.ndarray:
    """q with both arms in the mirrored optimal posture pointing at an object at ``angle_deg``.

    Arm 1 (right) takes (q2, q3) and arm 2 (left) the mirror image (-q2, -q3); each q1 turns its
    end effector onto the direction alpha from the platform heading. ``heading`` rotates the
    whole robot (rad).
    """
    _check_paper_like(robot)
    alpha = math.radians(angle_deg)
    _, q2, q3 = posture.q
    right, left = robot.arms
    joints = dict(zip(right.joint_names, (alpha - posture.bearing, q2, q3)))
    joints.update(zip(left.joint_names, (alpha + posture.bearing, -q2, -q3)))
    return robot.configuration((0.0, 0.0, heading), joints)


@dataclass(frozen=True)
class KinematicCase:
    angle_deg: float
    platform_speed_max: float | None  # m/s; None for the locked platform
    analysis: Analysis


@dataclass(frozen=True)
class DynamicCase:
    angle_deg: float
    wheel_torque_max: float
    decoupled: bool
    analysis: Analysis


@dataclass(frozen=True)
class CaseStudy:
    """Results of the paper's Section 4: the posture and both sweeps."""

    robot: Robot
    posture: ArmPosture
    kinematic: tuple[KinematicCase, ...]
    dynamic: tuple[DynamicCase, ...]

    def __repr__(self) -> str:
        q = ", ".join(f"{v:.4f}" for v in self.posture.q)
        return (
            f"CaseStudy(robot={self.robot.name!r}, arm posture ({q}) rad, "
            f"{len(self.kinematic)} kinematic and {len(self.dynamic)} dynamic cases)"
        )

    def to_dict(self) -> dict:
        """JSON-ready: each case gives its figure's ellipsoid (``semi_axes``, ``axes``) and every
        other measure of the same quantity it was analysed with, under its JSON key (e.g. a
        velocity polytope beside Fig. 3's ellipses)."""

        def ell(e):
            return {"semi_axes": e.semi_axes.tolist(), "axes": e.axes.tolist()}

        def others(analysis: Analysis, figure: str) -> dict:
            quantity = get_measure(figure).quantity
            return {
                get_measure(name).json_key: s.to_dict()
                for name, s in analysis.measures.items()
                if name != figure and get_measure(name).quantity == quantity
            }

        return {
            "robot": self.robot.name,
            "arm_posture": {
                "q": list(self.posture.q),
                "manipulability": self.posture.manipulability,
                "reach": self.posture.reach,
            },
            "kinematic": [
                {
                    "object_angle_deg": c.angle_deg,
                    "platform_speed_max": c.platform_speed_max,
                    **ell(c.analysis.kinematic),
                    **others(c.analysis, KINEMATIC.name),
                }
                for c in self.kinematic
            ],
            "dynamic": [
                {
                    "object_angle_deg": c.angle_deg,
                    "wheel_torque_max": c.wheel_torque_max,
                    "decoupled": c.decoupled,
                    **ell(c.analysis.dynamic),
                    **others(c.analysis, DYNAMIC.name),
                }
                for c in self.dynamic
            ],
        }


def run_case_study(
    robot: Robot,
    angles_deg: Sequence[float] = ANGLES_DEG,
    platform_speeds: Sequence[float] = PLATFORM_SPEEDS,
    wheel_torques: Sequence[float] = WHEEL_TORQUES,
    task: str = "planar",
    progress: Callable[[str], None] | None = None,
    measures: Sequence[str] | None = None,
) -> CaseStudy:
    """Run the Fig. 3 and Fig. 4 sweeps on a paper-like robot.

    Args:
        robot: a differential drive with two 3-joint arms (e.g. ``planar_dual_arm``).
        angles_deg: object directions from the platform heading (deg).
        platform_speeds: maximum wheel rim speeds for Fig. 3 (m/s).
        wheel_torques: maximum wheel torques for Fig. 4 (N m).
        task: task space at the object.
        progress: called with a short message after each step.
        measures: measures to compute besides the kinematic and dynamic ellipsoids (names, see
            :mod:`mobmanip.measures`); ``None``: the default ones.
    """
    note = progress or (lambda message: None)
    if measures is not None:
        measures = (KINEMATIC.name, DYNAMIC.name, *measures)
    posture = optimal_posture(robot)
    note(
        f"optimal arm posture q2 = {posture.q[1]:.4f}, q3 = {posture.q[2]:.4f} rad, "
        f"manipulability {posture.manipulability:.4f} m^2, reach {posture.reach:.4f} m"
    )
    radius = robot.platform.radius  # type: ignore[attr-defined]  # a differential drive (checked)
    kinematic, dynamic = [], []
    for angle in angles_deg:
        q = configuration_at(robot, posture, angle)
        for speed in platform_speeds:
            variant = robot.with_wheel_limits(velocity=speed / radius)
            kinematic.append(KinematicCase(angle, speed, analyze(variant, q, task, measures=measures)))
        kinematic.append(KinematicCase(angle, None, analyze(robot.with_platform("fixed"), q, task, measures=measures)))
        for decoupled in (True, False):
            for torque in wheel_torques:
                variant = robot.with_wheel_limits(effort=torque)
                case = analyze(variant, q, task, decoupled=decoupled, measures=measures)
                dynamic.append(DynamicCase(angle, torque, decoupled, case))
        note(
            f"object at {angle:g} deg: {len(platform_speeds) + 1} kinematic and {2 * len(wheel_torques)} dynamic cases"
        )
    return CaseStudy(robot, posture, tuple(kinematic), tuple(dynamic))
