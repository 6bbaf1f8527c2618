"""How hard a robot can brake from a straight run, holding its object, without tipping or slipping.

The robot drives straight along its heading at speed v with its arms still and the object held
(level: the hands carry its weight). Braking, it keeps that posture: the platform decelerates
along its heading, nothing turns and no joint moves. The whole robot then only translates, so the
velocity terms vanish (a translation has no Coriolis or centrifugal forces, and wheels spinning
about axles that do not turn have no gyroscopic ones): the efforts, contact forces and
deceleration of every instant of the stop are those of the robot at rest, the same from the
first instant to the last. The hardest stop is one linear program: the floor's grounded set of
the object's accelerations (:class:`~mobmanip.terms.constraints.floor.Floor`: no tip-over, the
driven wheels within friction, the reserve, the ramp) with the arms' and the turn's reduced
accelerations held at zero, and its straight-line reach against the motion. A constant
deceleration d stops the robot from v in ``v / d`` seconds over ``v^2 / (2 d)`` metres; it is the
shortest stop with the arms held (moving them could shift the load, and is not looked for here).

The highest speed from which it stops within a distance D is ``sqrt(2 d D)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ArgumentError
from ..robot.model import Robot, platform_pose
from ..sets.lifted import LiftedPolytope
from ..terms.constraints.floor import CONTACT_FORCES, Floor, ground_reaction
from .reaches import tip_over_reading

#: The task the stop is read in: the object's motion in the floor plane (x, y), held level by the hands.
TASK = "planar"


@dataclass(frozen=True)
class Stop:
    """The hardest stop from a straight run (see the module's docstring).

    Attributes:
        sense: +1 driving forward (along the heading), -1 backward.
        speed: the speed braked from (m/s).
        deceleration: the largest constant deceleration (m/s^2), 0 when the robot cannot brake.
        distance, time: the stop's length (m) and duration (s); inf when it cannot brake.
        binding: what stops a harder stop (the limits at the maximum).
        tau: the efforts that brake it (N m or N), in the robot's reduced velocity order.
        contact_forces: the floor's force at each contact, name -> (normal N, tangential N).
        zmp_margin: the zero-moment point's distance inside the support polygon (m).
    """

    sense: int
    speed: float
    deceleration: float
    distance: float
    time: float
    binding: tuple[str, ...]
    tau: np.ndarray
    contact_forces: dict[str, tuple[float, float]]
    zmp_margin: float | None

    def speed_for(self, distance: float) -> float:
        """The highest speed (m/s) from which this deceleration stops within ``distance`` (m)."""
        return math.sqrt(2.0 * self.deceleration * max(float(distance), 0.0))

    def to_dict(self) -> dict:
        return {
            "sense": "forward" if self.sense > 0 else "backward",
            "speed": self.speed,
            "deceleration": self.deceleration,
            "distance": None if math.isinf(self.distance) else self.distance,
            "time": None if math.isinf(self.time) else self.time,
            "binding": list(self.binding),
            "tau": self.tau.tolist(),
            "contact_forces": {k: {"normal": n, "tangential": t} for k, (n, t) in self.contact_forces.items()},
            "zmp_margin": self.zmp_margin,
        }


def braking_set(
    robot: Robot, q: np.ndarray, object_mass: float | None = None, floor: Floor | None = None
) -> LiftedPolytope:
    """The grounded set of the object's planar accelerations with the arms still and the platform
    not turning (a :class:`~mobmanip.sets.lifted.LiftedPolytope`): what a rigid robot translating
    along its heading can do (see the module's docstring).

    Raises:
        ArgumentError: a robot without a platform on the floor.
    """
    from .single import analyze

    if robot.wheel_platform is None and robot.platform.kind != "omnidirectional":
        raise ArgumentError(f"{robot.name!r} has a fixed base: it does not drive, so it does not brake")
    floor = replace(Floor(level=True), mu="spec") if floor is None else replace(floor, level=True)
    analysis = analyze(robot, q, TASK, object_mass=object_mass, measures=("dynamic_polytope",), constraints=(floor,))
    grounded = analysis.measures["dynamic_polytope"]
    assert isinstance(grounded, LiftedPolytope)  # a set on the floor is a lifted polytope
    S = robot.null_space(q)
    n_platform = robot.platform.n_reduced
    arms = np.eye(S.shape[1])[n_platform:]  # every joint's reduced acceleration held at zero
    turn = S[2:3] / max(float(np.linalg.norm(S[2])), 1e-300)  # the base's yaw acceleration
    side = S[1:2]  # its sideways acceleration (zero by construction on wheels; an omnidirectional base's row)
    rows = [arms, turn] + ([side / np.linalg.norm(side)] if np.linalg.norm(side) > 0.0 else [])
    return grounded.restricted("xdot", np.vstack(rows))


def hardest_stop(
    robot: Robot,
    q: np.ndarray,
    sense: int = 1,
    speed: float = 1.0,
    object_mass: float | None = None,
    floor: Floor | None = None,
) -> Stop:
    """The hardest stop from ``speed`` (m/s) driving forward (``sense`` +1) or backward (-1) at
    configuration ``q``, with the arms held and the object held level, on ``floor`` (default: the
    spec's friction).

    Raises:
        ArgumentError: a bad sense or speed, a robot that does not drive.
    """
    if sense not in (1, -1):
        raise ArgumentError(f"the sense of the run must be +1 (forward) or -1 (backward), got {sense!r}")
    if isinstance(speed, bool) or not (isinstance(speed, (int, float)) and math.isfinite(speed) and speed >= 0.0):
        raise ArgumentError(f"the speed braked from must be a finite number of m/s >= 0, got {speed!r}")
    if robot.platform.n_reduced == 0:
        raise ArgumentError(f"{robot.name} has a {robot.platform.kind} platform: it does not drive, so it has no stop")
    S = robot.null_space(q)[:3, : robot.platform.n_reduced]
    run = np.linalg.lstsq(S, [1.0, 0.0, 0.0], rcond=None)[0]
    if np.linalg.norm(S @ run - [1.0, 0.0, 0.0]) > 1e-9:
        raise ArgumentError(
            f"{robot.name}'s {robot.platform.kind.replace('_', ' ')} base cannot drive straight in this configuration "
            "(a steered base turns as it drives unless its steering is at 0): the stop is for a straight run"
        )
    braking = braking_set(robot, q, object_mass, floor)
    heading = platform_pose(q)[2]
    against = -sense * np.array([math.cos(heading), math.sin(heading)])  # the deceleration's direction
    deceleration = 0.0 if braking.empty else float(braking.straight_line_reach(against))
    if deceleration <= 0.0:
        return Stop(sense, float(speed), 0.0, math.inf, math.inf, (), np.zeros(robot.nx), {}, None)
    witness = braking.straight_line_witness(against)
    info = braking.model["floor"]
    reaction = ground_reaction(info, witness.variables[CONTACT_FORCES])
    contacts = {name: (float(c["normal"]), float(c["tangential"])) for name, c in reaction["contacts"].items()}
    binding = tuple(tip_over_reading(list(witness.binding), info, reaction))
    return Stop(
        sense=sense,
        speed=float(speed),
        deceleration=deceleration,
        distance=speed**2 / (2.0 * deceleration),
        time=speed / deceleration,
        binding=binding,
        tau=witness.variables["tau"].copy(),
        contact_forces=contacts,
        zmp_margin=reaction.get("margin"),
    )
