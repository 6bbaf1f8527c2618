"""The paper's Section 4 case study: two mirrored 3R arms holding an object at the platform.

Each arm takes the posture that maximises its own kinematic manipulability sqrt(det(J J^T))
(2 x 3 translational Jacobian in the horizontal plane), found numerically on the model's own
Jacobian; the arms mirror each other about the line from P_o to the object, and q1 of each arm
points its end effector at the object. The object direction alpha is measured from the platform
heading (0 deg in front, 90 deg to the left). Both end effectors grasp the object at its centre.
The posture and its configurations (:func:`optimal_posture`, :func:`configuration_at`,
:class:`ArmPosture`, :func:`arm_measure`) live with the other postures, in
:mod:`mobmanip.postures.planar`, and are re-exported here.

Sweeps: Fig. 3 varies the platform's maximum rim speed (wheel qdot_max = v / r) and adds the
locked platform; Fig. 4 varies the wheels' maximum torque, with decoupled dynamics as in the
paper and coupled dynamics as the paper did not.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from .analysis.single import Analysis, analyze
from .errors import SpecError
from .measures import DYNAMIC, KINEMATIC, get_measure
from .platforms import DifferentialDrive
from .postures.planar import ArmPosture, arm_measure, configuration_at, optimal_posture
from .robot.model import Robot

__all__ = [
    "ANGLES_DEG",
    "PLATFORM_SPEEDS",
    "WHEEL_TORQUES",
    "ArmPosture",
    "CaseStudy",
    "DynamicCase",
    "KinematicCase",
    "arm_measure",
    "configuration_at",
    "optimal_posture",
    "run_case_study",
]

ANGLES_DEG = (0.0, 45.0, 90.0)
PLATFORM_SPEEDS = (0.001, 0.5, 1.0)  # m/s, maximum rim speed of the wheels (Fig. 3)
WHEEL_TORQUES = (200.0, 50.0, 10.0)  # N m (Fig. 4)


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

    Raises:
        SpecError: not a differential drive with two 3-joint arms with vertical axes.
    """
    if not isinstance(robot.platform, DifferentialDrive):  # the sweeps vary its wheels' limits
        raise SpecError(f"the case study needs a differential drive with two arms; {robot.name!r} does not fit")
    note = progress or (lambda message: None)
    if measures is not None:
        measures = (KINEMATIC.name, DYNAMIC.name, *measures)
    posture = optimal_posture(robot)
    note(
        f"optimal arm posture q2 = {posture.q[1]:.4f}, q3 = {posture.q[2]:.4f} rad, "
        f"manipulability {posture.manipulability:.4f} m^2, reach {posture.reach:.4f} m"
    )
    radius = robot.platform.radius
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
