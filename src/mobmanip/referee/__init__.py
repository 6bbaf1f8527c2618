"""The physics referee: mobmanip's grounded capacity replayed in MuJoCo, a physics engine it does
not contain (``pip install 'mobmanip[referee]'``; the command is ``mobmanip referee``).

:func:`build` makes MuJoCo's model of a loaded robot standing on the floor with the object held
(:mod:`mobmanip.referee.model`); :func:`referee_for` builds it for a grounded analysis, with the
floor constraint's own contacts; :func:`replay_maxima` replays each axis maximum and says whether
MuJoCo agrees at t = 0 and whether the robot holds (:mod:`mobmanip.referee.check`);
:meth:`Referee.follow` replays a whole timed motion, its planned efforts with a joint feedback
(:class:`MotionReplay`).
"""

from __future__ import annotations

from .check import (
    ACCELERATION_TOLERANCE,
    NORMAL_TOLERANCE,
    POINT_OBJECT_RADIUS,
    RISE,
    SLIDE,
    AxisReplay,
    axis_directions,
    object_for_referee,
    replay_axis,
    replay_maxima,
)
from .model import (
    ContactForce,
    MotionReplay,
    NotRepresentable,
    Referee,
    Rollout,
    Support,
    build,
    check_representable,
    contacts_of_floor,
    urdf_casters,
)


def referee_for(robot, q, grounded, held_object, *, grasp: str | None = None) -> Referee:
    """MuJoCo's model for a grounded set: the robot at ``q`` on the floor the set was computed on
    (its contacts, friction and gravity, from ``grounded.model["floor"]``), holding
    ``held_object`` (the analysis's own; see :func:`object_for_referee`)."""
    info = grounded.model["floor"]
    gravity = info.get("gravity")
    return build(robot, q, contacts=contacts_of_floor(info), object=held_object, grasp=grasp,
                 mu=float(info["mu"] or 0.0), gravity=gravity)  # fmt: skip


__all__ = [
    "ACCELERATION_TOLERANCE",
    "NORMAL_TOLERANCE",
    "POINT_OBJECT_RADIUS",
    "RISE",
    "SLIDE",
    "AxisReplay",
    "ContactForce",
    "MotionReplay",
    "NotRepresentable",
    "Referee",
    "Rollout",
    "Support",
    "axis_directions",
    "build",
    "check_representable",
    "contacts_of_floor",
    "object_for_referee",
    "referee_for",
    "replay_axis",
    "replay_maxima",
    "urdf_casters",
]
