"""Frames for the viewer's animations (``mobmanip view --sweep NAME``).

``object-angle``
    The paper's robot (a differential drive with two 3-joint arms): both arms in their globally
    optimal, mirrored posture (:func:`mobmanip.postures.planar.optimal_posture`) aim at an object whose
    direction from the platform heading goes from 0 to 90 deg in 3 deg steps (pausing at the
    paper's 0, 45 and 90 deg). Any other robot keeps its configuration and turns its platform
    heading through the same 0 .. 90 deg: the object's direction in the world turns with it and
    the world-axes ellipsoids turn rigidly with the robot (their shape does not depend on the
    heading).
``fig3``
    Paper Fig. 3: at each object direction 0, 45 and 90 deg, the wheels' maximum rim speed
    steps through 0.001, 0.5 and 1.0 m/s (and back, alternately), with the locked-platform pair
    drawn throughout; between directions the arms re-aim at the current speed.
``fig4``
    Paper Fig. 4: the same with the wheels' maximum torque 200, 50 and 10 N m, decoupled
    dynamics as in the paper (unless ``decoupled=False`` is passed).

Between the paper's values the frames are computed at intermediate speeds, torques and angles,
so the animation morphs through real ellipsoids rather than interpolating shapes. Every frame
carries a caption (:attr:`mobmanip.viz.scene.Frame.caption`) that the page shows while it plays:
the object's direction and the wheels' limit of that frame, the paper's values held, the others
marked as between them or turning.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..casestudy import ANGLES_DEG, PLATFORM_SPEEDS, WHEEL_TORQUES, configuration_at, optimal_posture
from ..errors import ArgumentError, SpecError
from ..robot.model import Robot, platform_pose
from .scene import Frame, analyze_pair

SWEEPS = ("object-angle", "fig3", "fig4")
HOLD = 1.0  # s: pause on each of the paper's values
_SUBSTEPS = 8  # computed frames between two of the paper's values


def _check_moving(robot: Robot, sweep: str) -> None:
    if robot.wheel_platform is None or robot.platform_locked:
        raise ArgumentError(f"--sweep {sweep} varies the wheels' limits; it needs the robot's own moving platform")


def _paper_like(robot: Robot):
    """(robot on its own moving platform, the arms' optimal posture), or (None, None) when its
    arms are not the paper's (two 3-joint arms with vertical axes, on any base). A paper-like
    robot with its platform locked still qualifies."""
    own = robot
    if robot.platform_locked and robot.wheel_platform is not None:
        own = robot.with_platform(robot.wheel_platform.kind)
    try:
        return own, optimal_posture(own)
    except SpecError:
        return None, None


def object_angle_frames(
    robot: Robot,
    q: np.ndarray | None = None,
    task: str | None = None,
    *,
    angles_deg: Sequence[float] = tuple(range(0, 91, 3)),
    locked: bool = True,
    **options: Any,
) -> list[Frame]:
    """Frames over the object direction (paper's robot) or the platform heading (any other).

    Args:
        robot: the robot.
        q: base configuration (other robots only; default the home pose).
        task: task space (default the spec's).
        angles_deg: the directions (deg).
        locked: also draw the locked-platform pair.
        **options: passed to :func:`mobmanip.analysis.analyze` (``object_mass``, ``decoupled``,
            ``measures``).
    """
    paper, posture = _paper_like(robot)
    if posture is not None and q is not None:
        raise ArgumentError(
            f"the object-angle sweep places {robot.name!r} itself (arms aimed at the object); leave out --q"
        )
    frames = []
    for angle in angles_deg:
        if posture is not None:
            q_at = configuration_at(paper, posture, angle)
            label = f"object at {angle:g} deg from the platform heading"
        else:
            q_at = np.array(robot.neutral() if q is None else q, dtype=float)
            yaw = platform_pose(q_at)[2] + math.radians(angle)
            q_at[2:4] = (math.cos(yaw), math.sin(yaw))
            label = f"platform heading turned by {angle:g} deg"
        analysis, fixed = analyze_pair(robot, q_at, task, locked=locked, **options)
        hold = HOLD if any(abs(angle - a) < 1e-9 for a in ANGLES_DEG) else 0.0
        frames.append(Frame(q_at, analysis, fixed, hold=hold, label=label if hold else "", caption=label))
    return frames


def _limit_sweep(
    robot: Robot,
    task: str | None,
    values: Sequence[float],
    make_robot,
    describe,
    locked: bool,
    angles_deg: Sequence[float],
    **options: Any,
) -> list[Frame]:
    posture = optimal_posture(robot)  # raises SpecError for a robot unlike the paper's
    frames: list[Frame] = []
    order = list(values)
    previous_angle = None
    for n, angle in enumerate(angles_deg):
        # Re-aim the arms at the current limit, through intermediate directions.
        if previous_angle is not None:
            variant = make_robot(order[0])
            for s in range(1, _SUBSTEPS):
                between = previous_angle + (angle - previous_angle) * s / _SUBSTEPS
                q_between = configuration_at(robot, posture, between)
                analysis, fixed = analyze_pair(variant, q_between, task, locked=locked, **options)
                caption = f"object at {between:.3g} deg, {describe(order[0])} (turning to {angle:g} deg)"
                frames.append(Frame(q_between, analysis, fixed, caption=caption))
        q = configuration_at(robot, posture, angle)
        for i, value in enumerate(order):
            if i > 0:  # morph from the previous value through computed intermediate ones
                for s in range(1, _SUBSTEPS):
                    between = order[i - 1] + (value - order[i - 1]) * s / _SUBSTEPS
                    analysis, fixed = analyze_pair(make_robot(between), q, task, locked=locked, **options)
                    caption = (
                        f"object at {angle:g} deg, {describe(float(f'{between:.3g}'))} (between the paper's values)"
                    )
                    frames.append(Frame(q, analysis, fixed, caption=caption))
            analysis, fixed = analyze_pair(make_robot(value), q, task, locked=locked, **options)
            frames.append(Frame(q, analysis, fixed, hold=HOLD, label=f"object at {angle:g} deg, {describe(value)}"))
        previous_angle = angle
        if n + 1 < len(angles_deg):
            order = order[::-1]  # continue from the value we ended on
    return frames


def fig3_frames(
    robot: Robot,
    task: str | None = "planar",
    *,
    speeds: Sequence[float] = PLATFORM_SPEEDS,
    angles_deg: Sequence[float] = ANGLES_DEG,
    locked: bool = True,
    **options: Any,
) -> list[Frame]:
    """Paper Fig. 3: the wheels' maximum rim speed (m/s) at each object direction."""
    _check_moving(robot, "fig3")
    radius = getattr(robot.wheel_platform, "radius", None)
    if radius is None:
        raise SpecError(f"the Fig. 3 sweep needs wheels (a differential drive); {robot.name!r} has none")
    return _limit_sweep(
        robot,
        task,
        speeds,
        lambda v: robot.with_wheel_limits(velocity=v / radius),
        lambda v: f"platform speed <= {v:g} m/s",
        locked,
        angles_deg,
        **options,
    )


def fig4_frames(
    robot: Robot,
    task: str | None = "planar",
    *,
    torques: Sequence[float] = WHEEL_TORQUES,
    angles_deg: Sequence[float] = ANGLES_DEG,
    locked: bool = True,
    decoupled: bool = True,
    **options: Any,
) -> list[Frame]:
    """Paper Fig. 4: the wheels' maximum torque (N m) at each object direction (decoupled
    dynamics by default, as in the paper)."""
    _check_moving(robot, "fig4")
    return _limit_sweep(
        robot,
        task,
        torques,
        lambda t: robot.with_wheel_limits(effort=t),
        lambda t: f"wheel torque <= {t:g} N m",
        locked,
        angles_deg,
        decoupled=decoupled,
        **options,
    )


def sweep_frames(
    name: str,
    robot: Robot,
    q: np.ndarray | None = None,
    task: str | None = None,
    *,
    locked: bool = True,
    **options: Any,
) -> list[Frame]:
    """The frames of the sweep ``name`` (one of :data:`SWEEPS`).

    Raises:
        ArgumentError: unknown sweep, or fig3/fig4 on a locked platform.
        SpecError: fig3/fig4 on a robot unlike the paper's.
    """
    if name == "object-angle":
        return object_angle_frames(robot, q, task, locked=locked, **options)
    if name == "fig3":
        return fig3_frames(robot, task or "planar", locked=locked, **options)
    if name == "fig4":
        options.pop("decoupled", None)  # decoupled, as in the paper
        return fig4_frames(robot, task or "planar", locked=locked, **options)
    raise ArgumentError(f"unknown sweep {name!r}; expected one of {', '.join(SWEEPS)}")
