"""A sweep of a team's object heading: the object turns about its centre, the robots stay where
they are and reach for the moved grasp points (see :mod:`mobmanip.team`).

At each heading the grasping arms' joints are solved by inverse kinematics (``reach = true`` for
every robot), starting from the solution at the neighbouring heading: the sweep starts at the
heading nearest the description's own and goes outwards both ways, so the postures vary
continuously. A heading at which some hand cannot meet its grasp point within the tolerance is
marked unreachable (its values are absent, never NaN).
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, MobmanipError, TeamError
from ..measures import resolve_measures
from ..robot.tasks import get_task
from ..support.progress import progress_bar
from ..terms.constraints.base import Constraint
from .analysis import analyze_team, ray_radius
from .members import Team, team_from_dict

__all__ = ["HeadingPoint", "TeamSweep", "sweep_heading"]


@dataclass(frozen=True)
class HeadingPoint:
    """The team at one object heading.

    Attributes:
        offset_deg: the heading's change from the description's (deg).
        reachable: every hand meets its grasp point.
        reach: per measure, the reach along each task axis, positive way (task units), (m,).
        limiting: per measure, the name of the robot limiting the team along each task axis.
        volume: per measure, the set's volume (absent when it cannot be computed).
        worst_torque: the load-sharing worst normalised torque holding the object still.
        overload: no internal forces hold the object still within the limits.
        joints: each robot's joint positions at this heading, by robot name.
    """

    offset_deg: float
    reachable: bool
    reach: Mapping[str, np.ndarray]
    limiting: Mapping[str, tuple[str, ...]]
    volume: Mapping[str, float]
    worst_torque: float | None
    overload: bool | None
    joints: Mapping[str, Mapping[str, float]]

    def to_dict(self) -> dict:
        """JSON-ready."""
        return {
            "offset_deg": self.offset_deg,
            "reachable": self.reachable,
            "reach": {k: v.tolist() for k, v in self.reach.items()},
            "limiting_robot": {k: list(v) for k, v in self.limiting.items()},
            "volume": dict(self.volume),
            "worst_normalised_torque": self.worst_torque,
            "overload": self.overload,
            "joints": {k: dict(v) for k, v in self.joints.items()},
        }


@dataclass(frozen=True)
class TeamSweep:
    """A sweep of the object heading.

    Attributes:
        task: the task-space name.
        measures: the measures computed, in order.
        points: one per heading, in the order of the offsets asked for.
    """

    task: str
    measures: tuple[str, ...]
    points: tuple[HeadingPoint, ...]

    @property
    def offsets_deg(self) -> np.ndarray:
        """The heading offsets (deg), (n,)."""
        return np.array([p.offset_deg for p in self.points])

    @property
    def reachable(self) -> np.ndarray:
        """Which headings are reachable, (n,) bool."""
        return np.array([p.reachable for p in self.points])

    def to_dict(self) -> dict:
        """JSON-ready."""
        return {
            "task": self.task,
            "task_axes": list(get_task(self.task).labels),
            "measures": list(self.measures),
            "points": [p.to_dict() for p in self.points],
        }


def sweep_heading(
    data: Mapping,
    offsets_deg: Sequence[float] | np.ndarray,
    *,
    base_dir: Path | str = ".",
    measures: Iterable[str] | str | None = None,
    where: str = "team",
    progress: bool = False,
    constraints: Iterable[Constraint] = (),
) -> TeamSweep:
    """Turn the object of a team description through ``offsets_deg`` (deg, added to its
    ``yaw_deg``) and analyse the team at each heading.

    Args:
        data: a parsed team description (see :mod:`mobmanip.team`).
        offsets_deg: the heading changes (deg), finite.
        base_dir: where relative robot spec paths are found.
        measures: the measures (default: the default ones).
        where: the description's name in messages.
        progress: show a progress bar over the headings on standard error.
        constraints: constraints beyond the joint boxes (e.g. the floor), as :func:`analyze_team`'s.

    Raises:
        ArgumentError: no offsets, or a non-finite one; TeamError: the description is wrong
            (checked at its own heading first).
    """
    offsets = checked_offsets(offsets_deg)
    constraints = tuple(constraints)
    names = measure_names(measures)
    team_from_dict(data, base_dir, where=where)  # the description itself must hold
    points: dict[int, HeadingPoint] = {}
    with progress_bar(len(offsets), desc="team headings", unit="heading", show=progress) as bar:

        def visit(k: int, seed: dict | None) -> dict | None:
            bar.update(1)
            points[k], solved = _one(data, offsets[k], seed, base_dir, names, where, constraints)
            return solved

        walk_headings(offsets, visit)
    task = team_from_dict(data, base_dir, where=where).task
    return TeamSweep(task, names, tuple(points[k] for k in range(len(offsets))))


def checked_offsets(offsets_deg: Sequence[float] | np.ndarray) -> np.ndarray:
    """The heading offsets as a flat float array (deg).

    Raises:
        ArgumentError: no offsets, or a non-finite one.
    """
    offsets = np.asarray(offsets_deg, dtype=float).ravel()
    if offsets.size == 0 or not np.all(np.isfinite(offsets)):
        raise ArgumentError(f"heading offsets must be finite numbers of degrees, got {offsets_deg!r}")
    return offsets


def measure_names(measures: Iterable[str] | str | None) -> tuple[str, ...]:
    """The names of the measures asked for (default: the default ones), in order."""
    return tuple(m.name for m in resolve_measures(measures))


def walk_headings(offsets: np.ndarray, visit: Callable[[int, dict | None], dict | None]) -> None:
    """Visit every heading in the sweep's order, each with the joints its inverse kinematics
    starts from: from the heading nearest the description's own outwards, up then down.

    ``visit(k, seed)`` handles heading ``k`` starting from ``seed`` and returns the joints solved
    there (robot name -> joint -> value), or None where some hand cannot meet its grasp point. A
    heading starts from the joints solved at its neighbour towards the start (the neighbour's own
    seed if it was unreachable; the start from the description's joints, None). The seeds make the
    postures continuous, and they are all a heading's point depends on besides its offset: given
    its seed, a heading can be analysed anywhere, in any order, with the same result.
    """
    start = int(np.argmin(np.abs(offsets)))
    order = list(range(start, len(offsets))) + list(range(start - 1, -1, -1))
    seeds: dict[int, dict] = {}
    for k in order:
        neighbour = k - 1 if k > start else (k + 1 if k < start else None)
        seed = seeds.get(neighbour) if neighbour is not None else None
        solved = visit(k, seed)
        seeds[k] = solved if solved is not None else (seed or {})


def _moved(data, offset, joints, reach: bool) -> dict:
    """The description with the object turned by ``offset`` (deg) and each robot's joints updated
    from ``joints`` (robot name -> joint -> value; None: none), its arms reaching or not."""
    moved = copy.deepcopy(dict(data))
    obj = dict(moved.get("object", {}))
    obj["yaw_deg"] = float(obj.get("yaw_deg", 0.0)) + float(offset)
    moved["object"] = obj
    robots = []
    for entry in moved.get("robots", []):
        entry = dict(entry)
        entry["reach"] = reach
        name = entry.get("name", entry.get("robot"))
        if joints and name in joints:
            entry["joints"] = {**entry.get("joints", {}), **joints[name]}
        robots.append(entry)
    moved["robots"] = robots
    return moved


def solve_heading(
    data: Mapping, offset: float, seed: Mapping | None, base_dir: Path | str, where: str
) -> tuple[Team, dict] | tuple[None, None]:
    """The team at one heading, its hands reaching from ``seed``, and the grasping arms' joints
    solved there (robot name -> joint -> value); (None, None) where some hand cannot meet its grasp
    point."""
    try:
        team = team_from_dict(_moved(data, offset, seed, reach=True), base_dir, where=where)
    except TeamError:
        return None, None
    joints = {
        member.name: {
            joint: value
            for joint, value in member.robot.configuration_dict(member.q)["joints"].items()
            if any(joint in member.robot.arms[i].joint_names for i in member.arms)
        }
        for member in team.members
    }
    return team, joints


def point_with_joints(
    data: Mapping,
    offset: float,
    joints: Mapping,
    base_dir: Path | str,
    names: tuple[str, ...],
    where: str,
    constraints: tuple[Constraint, ...] = (),
) -> HeadingPoint:
    """The point at a reachable heading whose grasping arms' joints ``joints`` were solved (by
    :func:`solve_heading`): the team is built with them in place, no inverse kinematics, the same team
    to the last bit (the arms' one-degree-of-freedom joints go into the configuration as they are).

    Raises:
        TeamError: a hand is not at its grasp point with these joints.
    """
    team = team_from_dict(_moved(data, offset, joints, reach=False), base_dir, where=where)
    return _analyse(team, offset, names, joints, constraints)


def _one(data, offset, seed, base_dir, names, where, constraints=()) -> tuple[HeadingPoint, dict | None]:
    """The point at one heading, the hands reaching from ``seed`` (see :func:`walk_headings`),
    and the joints solved there (None where unreachable)."""
    team, joints = solve_heading(data, offset, seed, base_dir, where)
    if team is None:
        return unreachable(offset), None
    return _analyse(team, offset, names, joints, constraints), joints


def unreachable(offset: float) -> HeadingPoint:
    """The point at a heading where some hand cannot meet its grasp point."""
    return HeadingPoint(float(offset), False, {}, {}, {}, None, None, {})


def _analyse(team, offset, names, joints, constraints=()) -> HeadingPoint:
    """The point of a team at the heading ``offset``, its grasping arms at ``joints``."""
    analysis = analyze_team(team, names, constraints=constraints)
    m = analysis.terms.W.shape[0]
    axes = np.eye(m)
    reach, limiting, volume = {}, {}, {}
    for name in names:
        task_set = analysis.measure(name)
        reach[name] = np.array([ray_radius(task_set, e) for e in axes])
        limiting[name] = tuple(analysis.limiting_robots(name, axes))
        try:
            volume[name] = float(task_set.volume)
        except MobmanipError:  # a set whose volume is not available
            pass
    sharing = analysis.load_sharing()
    return HeadingPoint(float(offset), True, reach, limiting, volume, sharing.worst, sharing.empty, joints)
