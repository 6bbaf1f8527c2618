"""Named postures of a robot: ``home``, ``hold`` and the spec's ``[postures.NAME]``.

Every command that takes a configuration takes ``--posture NAME`` instead of ``--q Q.json``:

* ``home``: the home configuration (:meth:`mobmanip.robot.model.Robot.neutral`: joints at zero or at
  their ``[reference]`` positions);
* ``hold``: the spec's ``[hold]`` posture, in which the hands hold the default object;
* any ``[postures.NAME]`` table of the spec: arm and torso joint positions, the others at home
  (``init-spec`` writes one for each keyframe of an MJCF file, ``keyframe_home`` and
  ``keyframe_hold`` for keys named like the two above).

The platform stands at the origin with heading 0 unless a pose is given.

:func:`hand_spread_warnings` compares how far apart the hands of a held object are with how far
apart the object's declared grasp points are (an explicit object's offsets, else the spec's
``[object] grasp_offsets``): two "holding" hands a metre apart hold nothing.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol

import numpy as np

from ..errors import UnknownPostureError
from ..robot.model import Robot
from ..robot.spec import RobotSpec

HOME, HOLD = "home", "hold"

#: Slack on the declared distance between two grasp points before a wider spread of the hands
#: is warned about: a tenth of that distance, and at least this many metres (a hand's width).
SPREAD_SLACK = 0.05


class GraspPoints(Protocol):
    """An object with grasp points, such as :class:`mobmanip.terms.grasp.HeldObject` (declared
    here by what is read from it: the terms layer sits above the postures)."""

    @property
    def offsets(self) -> np.ndarray:
        """The grasp points from the object's centre, (k, 3) (m)."""
        ...


def posture_names(spec: RobotSpec) -> tuple[str, ...]:
    """The names ``--posture`` accepts for this spec: ``home``, ``hold`` if the spec gives one,
    then the spec's ``[postures.*]`` in file order."""
    return (HOME,) + ((HOLD,) if spec.hold else ()) + tuple(spec.postures)


def posture_joints(spec: RobotSpec, name: str) -> Mapping[str, float]:
    """Joint positions of the posture ``name`` (joints not named stay at home).

    Raises:
        UnknownPostureError: the spec defines no such posture (the message lists them).
    """
    if name == HOME:
        return {}
    if name == HOLD and spec.hold:
        return spec.hold
    if name in spec.postures:
        return spec.postures[name]
    raise UnknownPostureError(spec.name, name, posture_names(spec))


def named_configuration(robot: Robot, name: str, platform: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """The configuration (nq,) of posture ``name`` with the platform at ``platform`` (x m, y m,
    yaw rad).

    Raises:
        UnknownPostureError: the spec defines no such posture.
    """
    return robot.configuration(platform, dict(posture_joints(robot.spec, name)))


def declared_grasp_offsets(robot: Robot, held_object: GraspPoints | None = None) -> np.ndarray | None:
    """The grasp offsets (k, 3) an object declares: an explicit object's, else the spec's
    ``[object] grasp_offsets``; ``None`` when neither declares any (or with one arm)."""
    if len(robot.arms) < 2:
        return None
    if held_object is not None:
        return np.asarray(held_object.offsets, dtype=float)
    if robot.spec.grasp_offsets:
        return np.asarray(robot.spec.grasp_offsets, dtype=float)
    return None


def hand_spread_warnings(robot: Robot, positions: np.ndarray, held_object: GraspPoints | None = None) -> list[str]:
    """Warnings for pairs of hands further apart than the object's grasp points allow.

    Args:
        robot: the robot.
        positions: world positions of the end effectors, (k, 3).
        held_object: an explicit object (its offsets are its grasp points), or ``None`` for the
            default one (the spec's ``[object] grasp_offsets``).

    Returns:
        One message per pair of hands whose distance exceeds the distance of their declared
        grasp points by more than a tenth of it and at least :data:`SPREAD_SLACK`; empty when
        nothing is declared.
    """
    offsets = declared_grasp_offsets(robot, held_object)
    if offsets is None:
        return []
    out = []
    k = len(robot.arms)
    for a in range(k):
        for b in range(a + 1, k):
            apart = float(np.linalg.norm(positions[a] - positions[b]))
            allowed = float(np.linalg.norm(offsets[a] - offsets[b]))
            if apart > allowed + max(SPREAD_SLACK, 0.1 * allowed):
                source = "the object's grasp offsets" if held_object is not None else "[object] grasp_offsets"
                out.append(
                    f"the hands {robot.arms[a].end_effector} and {robot.arms[b].end_effector} are {apart:.3f} m apart, "
                    f"but {source} put their grasp points {allowed:.3f} m apart: they do not hold that object "
                    f"(try a posture that holds it, e.g. --posture {HOLD})"
                )
    return out
