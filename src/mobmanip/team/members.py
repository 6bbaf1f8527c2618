"""Teams: several mobile manipulators holding one rigid object.

A team is k robots, each placed in one world frame (platform pose x, y, yaw) in a configuration,
some of whose hands grasp one rigid object. The paper's formulation extends to it block by
block (see :mod:`mobmanip.team.analysis`): with every robot's unified Jacobian J_i S_i,
reduced inertia P_i, input matrix Q_i and bias xi_i,

    J_u = blkdiag(J_i S_i),  P = blkdiag(P_i),  Q = blkdiag(Q_i),  xi = (xi_1, ..., xi_k),

and one grasp matrix W = [W_1 ... W_k] over all grasping hands, in the world frame about the
object's centre. A team of one robot holding the object with all its hands is that robot's own
analysis.

A team is described by a TOML file::

    name = "beam"
    task = "planar_rigid"          # default: the first robot's default_task
    tolerance = 0.01               # m: how far a hand may be from its grasp point (default 0.01)
    decoupled = false              # optional: neglect each robot's platform-arm interaction

    [object]
    mass = 4.0                     # kg
    position = [0.0, 0.0, 0.35]    # m, world: the object's centre (and centre of mass)
    yaw_deg = 90.0                 # its heading about the vertical (default 0)
    size = [1.5, 0.08, 0.08]       # optional: a uniform box (m) in the object frame, for the
                                   # inertia and the drawing
    # shape = "cylinder"           # or a uniform cylinder along the object's x axis:
    # length = 1.5                 # m
    # radius = 0.04                # m
    # inertia = [0.75, 0.01, 0.75] # or its principal moments (kg m^2) along the object axes,
                                   # or a 3 x 3 matrix; default: a solid sphere reaching the
                                   # farthest grasp point, as for one robot

    [[robots]]
    name = "south"                 # unique in the team
    robot = "planar_dual_arm"      # a built-in robot or a spec path (relative to this file)
    position = [0.0, -1.8226]      # m, world: the platform pose
    yaw_deg = 90.0
    posture = "home"               # "home" or "hold" (the spec's [hold]); default "hold" when
                                   # the spec has one
    reach = false                  # solve the grasping arms' joints so that each hand meets its
                                   # grasp point (inverse kinematics from the posture)
    platform = "own"               # or "fixed": this robot's platform does not move
    [robots.joints]                # optional joint positions (rad, m) over the posture
    arm_right_1_joint = -0.874
    [[robots.grasps]]              # the hands that hold the object, with their grasp points
    arm = "right"
    point = [-0.75, 0.0, 0.0]      # m, in the object frame (x along the object's heading)

Distances between hands and grasp points are measured in the task's linear coordinates: in the
horizontal plane for the planar tasks (whose robots may hold the object at different heights),
in 3-D otherwise. The grasp matrix uses the hands' actual positions (within the tolerance of
the grasp points), so that it agrees exactly with the Jacobians.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import MobmanipError, TeamError
from ..robot.model import Robot, load_robot
from ..robot.tasks import get_task
from ..terms.grasp import HeldObject

__all__ = [
    "DEFAULT_TOLERANCE",
    "Member",
    "ObjectShape",
    "Team",
    "box_inertia",
    "cylinder_inertia",
    "hand_positions",
    "load_team",
    "team_from_dict",
]

#: Default distance (m) a hand may be from its grasp point.
DEFAULT_TOLERANCE = 0.01


@dataclass(frozen=True)
class Member:
    """One robot of a team.

    Attributes:
        name: its name in the team (unique).
        robot: the loaded robot (its platform possibly locked).
        q: its configuration, platform pose in the world included, (nq,).
        arms: indices (into ``robot.arms``) of the arms that grasp the object, in grasp order.
    """

    name: str
    robot: Robot
    q: np.ndarray
    arms: tuple[int, ...]

    @property
    def nx(self) -> int:
        """Number of reduced velocities."""
        return self.robot.nx

    @property
    def arm_names(self) -> tuple[str, ...]:
        """Names of the grasping arms, in grasp order."""
        return tuple(self.robot.arms[i].name for i in self.arms)


@dataclass(frozen=True)
class ObjectShape:
    """The held object's solid, as its description gives it (``size``, or ``shape = "cylinder"``
    with ``length`` and ``radius``), in the object's own frame (x along its heading).

    Attributes:
        kind: ``"box"`` or ``"cylinder"`` (its axis along the object's x).
        size: the solid's extent along the object's x, y and z axes (m): a box's edges; a
            cylinder's length, then its diameter twice.
    """

    kind: str
    size: tuple[float, float, float]

    def __post_init__(self):
        if self.kind not in ("box", "cylinder"):
            raise TeamError(f"object shape must be 'box' or 'cylinder', got {self.kind!r}")
        size = tuple(float(v) for v in self.size)
        if len(size) != 3 or not all(math.isfinite(v) and v >= 0.0 for v in size):
            raise TeamError(f"object size must be three lengths (m), got {self.size!r}")
        if self.kind == "cylinder" and size[1] != size[2]:
            raise TeamError(f"a cylinder's extents across its axis must be equal (its diameter), got {size!r}")
        object.__setattr__(self, "size", size)

    def moments(self, mass: float) -> np.ndarray:
        """Principal moments of the uniform solid of ``mass`` (kg) along the object's axes (kg m^2), (3,)."""
        if self.kind == "box":
            return box_inertia(mass, self.size)
        return cylinder_inertia(mass, self.size[0], 0.5 * self.size[1])

    def corners(self, center: np.ndarray, yaw: float) -> np.ndarray:
        """The corners (8, 3) of the box around the solid, centred at ``center`` (m, world) and
        turned by ``yaw`` (rad) about the vertical: x, then y, then z from its lower side."""
        half = 0.5 * np.array(self.size)
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
        return np.asarray(center, dtype=float) + (signs * half) @ _rot_z(yaw).T

    def describe(self) -> str:
        """``box 1.5 x 0.08 x 0.08 m`` or ``cylinder 1.5 m long, 0.04 m radius``."""
        if self.kind == "box":
            return "box " + " x ".join(f"{v:g}" for v in self.size) + " m"
        return f"cylinder {self.size[0]:g} m long, {0.5 * self.size[1]:g} m radius"


@dataclass(frozen=True)
class Team:
    """Robots holding one rigid object.

    Attributes:
        name: the team's name.
        task: task-space name (one for all robots).
        members: the robots, in order; their reduced velocities stack in this order.
        held_object: the object, its ``offsets`` one row per grasping hand (members in order,
            each member's arms in its grasp order), from the hands' actual positions.
        grasp_points: the nominal grasp points in the world (m), (n_hands, 3).
        object_yaw: the object's heading (rad).
        decoupled: neglect each robot's platform-arm interaction in the dynamics.
        object_shape: the object's solid (drawn by the viewers), or ``None`` when its
            description gives none (the object is then drawn through its grasps only).
    """

    name: str
    task: str
    members: tuple[Member, ...]
    held_object: HeldObject
    grasp_points: np.ndarray
    object_yaw: float = 0.0
    decoupled: bool = False
    object_shape: ObjectShape | None = None
    hands: tuple[tuple[int, int], ...] = field(init=False)

    def __post_init__(self):
        get_task(self.task)
        if not self.members:
            raise TeamError(f"team {self.name!r}: no robots")
        names = [m.name for m in self.members]
        for name in names:
            if names.count(name) > 1:
                raise TeamError(f"team {self.name!r}: robot name {name!r} is used twice")
        hands = tuple((k, a) for k, m in enumerate(self.members) for a in m.arms)
        if not hands:
            raise TeamError(f"team {self.name!r}: no hand grasps the object")
        for m in self.members:
            if len(set(m.arms)) != len(m.arms):
                raise TeamError(f"team {self.name!r}, robot {m.name!r}: an arm grasps twice ({m.arm_names})")
        if self.held_object.offsets.shape != (len(hands), 3):
            raise TeamError(
                f"team {self.name!r}: the object needs one grasp offset per hand ({len(hands)}), "
                f"got {self.held_object.offsets.shape}"
            )
        object.__setattr__(self, "hands", hands)

    @property
    def hand_names(self) -> tuple[str, ...]:
        """``"robot/arm"`` for each grasping hand, in order."""
        return tuple(f"{self.members[k].name}/{self.members[k].robot.arms[a].name}" for k, a in self.hands)

    @property
    def nx(self) -> int:
        """Number of reduced velocities of the whole team."""
        return sum(m.nx for m in self.members)

    def member_slices(self) -> tuple[slice, ...]:
        """Where each member's reduced velocities sit in the team's, in order."""
        out, start = [], 0
        for m in self.members:
            out.append(slice(start, start + m.nx))
            start += m.nx
        return tuple(out)

    @classmethod
    def holding(
        cls,
        members: Sequence[Member],
        mass: float,
        *,
        task: str | None = None,
        center: np.ndarray | None = None,
        inertia: np.ndarray | None = None,
        name: str = "team",
        decoupled: bool = False,
    ) -> Team:
        """A team whose object is held where the hands are now.

        Args:
            members: the robots.
            mass: object mass (kg).
            task: task-space name (default: the first robot's default task).
            center: the object's centre in the world (m), (3,); default: the hands' centroid.
            inertia: rotational inertia about the centre, world axes (kg m^2), (3, 3); default:
                a solid sphere reaching the farthest hand (as :meth:`HeldObject.between`).
            name: the team's name.
            decoupled: neglect each robot's platform-arm interaction.
        """
        members = tuple(members)
        if not members:
            raise TeamError(f"team {name!r}: no robots")
        points = np.vstack([hand_positions(m) for m in members])
        obj = HeldObject.between(points, mass, inertia)
        if center is not None:
            center = _vector(center, 3, f"team {name!r}: object position")
            offsets = points - center
            obj = HeldObject(obj.mass, _sphere(obj.mass, offsets) if inertia is None else obj.inertia, center, offsets)
        return cls(name, task or members[0].robot.spec.default_task, members, obj, points, 0.0, decoupled)


def hand_positions(member: Member) -> np.ndarray:
    """World positions of a member's grasping hands (m), (len(member.arms), 3)."""
    robot = member.robot
    pin.framesForwardKinematics(robot.model, robot.data, robot.check_configuration(member.q))
    return np.array([robot.data.oMf[robot.arms[i].frame_id].translation for i in member.arms]).reshape(-1, 3)


def box_inertia(mass: float, size: Sequence[float]) -> np.ndarray:
    """Principal moments of a uniform box of ``size`` (m) along its own axes (kg m^2), (3,)."""
    a, b, c = (float(s) for s in size)
    return mass / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])


def cylinder_inertia(mass: float, length: float, radius: float) -> np.ndarray:
    """Principal moments of a uniform solid cylinder along its own axes, its axis along x (kg m^2), (3,)."""
    across = mass * (3.0 * radius * radius + length * length) / 12.0
    return np.array([0.5 * mass * radius * radius, across, across])


def _rot_z(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


# ----------------------------------------------------------------------------------------------
# reading a team description


def load_team(path: str | Path) -> Team:
    """Read a team description (TOML, see the module's docstring) and build the team.

    Raises:
        TeamError: the file cannot be read or parsed, or its content is wrong (the message
            names the value and where it is); other :class:`MobmanipError` from loading a robot.
    """
    from ..support.reading import read_user_toml

    path = Path(path)
    data = read_user_toml(path, "team", limit=MAX_TEAM_BYTES, error=TeamError)
    return team_from_dict(data, path.resolve().parent, where=str(path))


#: Largest team file read (bytes): a team of the most robots fits in a few kilobytes.
MAX_TEAM_BYTES = 4 * 1024 * 1024

_TOP = {"name", "task", "tolerance", "decoupled", "object", "robots"}
_OBJECT = {"mass", "position", "yaw_deg", "size", "inertia", "shape", "length", "radius"}
_ROBOT = {"name", "robot", "position", "yaw_deg", "posture", "reach", "platform", "joints", "grasps"}
_GRASP = {"arm", "point"}


def team_from_dict(data: Mapping, base_dir: Path | str = ".", where: str = "team") -> Team:
    """Build a team from a parsed description; ``base_dir`` anchors relative spec paths.

    Raises:
        TeamError: naming the bad value and where it is.
    """
    base_dir = Path(base_dir)
    _keys(data, _TOP, where)
    name = _get(data, "name", str, where, "team")
    tolerance = _number(data.get("tolerance", DEFAULT_TOLERANCE), f"{where}: tolerance", positive=True)
    decoupled = _get(data, "decoupled", bool, where, False)
    robots = _get(data, "robots", list, where, None)
    if not robots:
        raise TeamError(f"{where}: no [[robots]]; a team needs at least one robot")
    obj = _get(data, "object", dict, where, None)
    if obj is None:
        raise TeamError(f"{where}: no [object] table")
    _keys(obj, _OBJECT, f"{where} [object]")
    mass = _number(obj.get("mass"), f"{where} [object] mass (kg)", positive=False)
    center = _vector(obj.get("position", [0.0, 0.0, 0.0]), 3, f"{where} [object] position")
    yaw = math.radians(_number(obj.get("yaw_deg", 0.0), f"{where} [object] yaw_deg"))
    R = _rot_z(yaw)

    members: list = []
    grasp_points: list = []
    seen: dict[str, int] = {}
    for k, entry in enumerate(robots):
        here = f"{where} [[robots]] #{k + 1}"
        if not isinstance(entry, dict):
            raise TeamError(f"{here}: expected a table, got {entry!r}")
        member, points = _member(entry, here, base_dir, center, R)
        if member.name in seen:
            raise TeamError(f"{here}: robot name {member.name!r} is already used by [[robots]] #{seen[member.name]}")
        seen[member.name] = k + 1
        members.append(member)
        grasp_points.append(points)
    task_name = _get(data, "task", str, where, members[0].robot.spec.default_task)
    try:
        task = get_task(task_name)
    except MobmanipError as exc:
        raise TeamError(f"{where}: {exc}") from None

    for member, points, k in zip(members, grasp_points, range(len(members))):
        here = f"{where} [[robots]] #{k + 1} ({member.name})"
        if _get(robots[k], "reach", bool, here, False):
            member = _reach(member, points, task, here)
            members[k] = member
        _check_hands(member, points, task, tolerance, here)

    points = np.vstack(grasp_points)
    hands = np.vstack([hand_positions(m) for m in members])
    shape = _shape(obj, f"{where} [object]")
    inertia = _inertia(obj, mass, R, f"{where} [object]") if shape is None else R @ np.diag(shape.moments(mass)) @ R.T
    if inertia is None:
        inertia = _sphere(mass, hands - center)
    held = HeldObject(mass, inertia, center, hands - center)
    return Team(name, task.name, tuple(members), held, points, yaw, decoupled, shape)


def _sphere(mass: float, offsets: np.ndarray) -> np.ndarray:
    radius2 = float(np.max(np.einsum("ij,ij->i", offsets, offsets))) if len(offsets) else 0.0
    return 0.4 * mass * radius2 * np.eye(3)


def _member(entry: Mapping, here: str, base_dir: Path, center: np.ndarray, R: np.ndarray):
    _keys(entry, _ROBOT, here)
    reference = _get(entry, "robot", str, here, None)
    if reference is None:
        raise TeamError(f"{here}: no 'robot' (a built-in robot name or a spec path)")
    name = _get(entry, "name", str, here, reference)
    here = f"{here} ({name})"
    from ..support.reading import looks_like_path, read_user_bytes, resolve_beside

    try:
        if looks_like_path(reference):  # a spec path, relative to the team file: never the current folder
            candidate = resolve_beside(reference, base_dir / "team.toml")
            read_user_bytes(candidate, "robot file", limit=MAX_TEAM_BYTES, error=TeamError)  # no /dev/zero
            robot = load_robot(candidate)
        else:
            robot = load_robot(reference)
    except MobmanipError as exc:
        raise TeamError(f"{here}: {exc}") from None
    platform = _get(entry, "platform", str, here, "own")
    if platform not in ("own", "fixed"):
        raise TeamError(f"{here}: platform must be 'own' or 'fixed', got {platform!r}")
    if platform == "fixed":
        robot = robot.with_platform("fixed")
    position = _vector(entry.get("position", [0.0, 0.0]), 2, f"{here} position")
    yaw = math.radians(_number(entry.get("yaw_deg", 0.0), f"{here} yaw_deg"))
    posture = _get(entry, "posture", str, here, "hold" if robot.spec.hold else "home")
    if posture == "hold":
        if not robot.spec.hold:
            raise TeamError(f"{here}: posture 'hold' but robot {robot.name!r} has no [hold] posture; use 'home'")
        joints = dict(robot.spec.hold)
    elif posture == "home":
        joints = {}
    else:
        raise TeamError(f"{here}: posture must be 'home' or 'hold', got {posture!r}")
    extra = _get(entry, "joints", dict, here, {})
    joints.update(extra)
    try:
        q = robot.configuration((position[0], position[1], yaw), joints)
    except MobmanipError as exc:
        raise TeamError(f"{here}: {exc}") from None
    arm_names = [arm.name for arm in robot.arms]
    grasps = _get(entry, "grasps", list, here, None)
    if not grasps:
        raise TeamError(f"{here}: no [[robots.grasps]]; name the arms that hold the object")
    arms, points = [], []
    for j, grasp in enumerate(grasps):
        at = f"{here} grasp #{j + 1}"
        if not isinstance(grasp, dict):
            raise TeamError(f"{at}: expected a table, got {grasp!r}")
        _keys(grasp, _GRASP, at)
        arm = _get(grasp, "arm", str, at, arm_names[0] if len(arm_names) == 1 else None)
        if arm is None:
            raise TeamError(f"{at}: no 'arm'; robot {robot.name!r} has arms {arm_names}")
        if arm not in arm_names:
            raise TeamError(f"{at}: unknown arm {arm!r}; robot {robot.name!r} has arms {arm_names}")
        index = arm_names.index(arm)
        if index in arms:
            raise TeamError(f"{at}: arm {arm!r} already grasps the object")
        arms.append(index)
        point = _vector(grasp.get("point"), 3, f"{at} point")
        points.append(center + R @ point)
    return Member(name, robot, q, tuple(arms)), np.array(points)


def _linear_rows(task) -> list[int]:
    """The world axes (0 x, 1 y, 2 z) in which hands are placed for this task."""
    rows = [r for r in task.rows if r < 3]
    return rows if 2 in rows else [0, 1]


def _check_hands(member: Member, points: np.ndarray, task, tolerance: float, here: str) -> None:
    rows = _linear_rows(task)
    hands = hand_positions(member)
    for arm, hand, point in zip(member.arm_names, hands, points):
        gap = float(np.linalg.norm((hand - point)[rows]))
        if gap > tolerance:
            where = "horizontally " if rows == [0, 1] else ""
            raise TeamError(
                f"{here}: hand {arm!r} is at {np.round(hand, 4).tolist()}, {gap:.4g} m {where}from its grasp point "
                f"{np.round(point, 4).tolist()} (tolerance {tolerance:g} m); move the robot, change its joints "
                "or set reach = true"
            )


def _reach(member: Member, points: np.ndarray, task, here: str) -> Member:
    """The member with its grasping arms' joints solved so that each hand meets its grasp point
    (bounded nonlinear least squares, scipy's trust-region reflective method, from the given
    posture; position only, in the task's linear coordinates)."""
    from scipy.optimize import least_squares

    robot, rows = member.robot, _linear_rows(task)
    model = robot.model
    joints = [(name, model.joints[model.getJointId(name)]) for i in member.arms for name in robot.arms[i].joint_names]
    if any(j.nq != 1 for _, j in joints):
        raise TeamError(f"{here}: reach = true needs arms of one-degree-of-freedom joints")
    index = np.array([j.idx_q for _, j in joints])
    lower = np.maximum(model.lowerPositionLimit[index], -1e3)
    upper = np.minimum(model.upperPositionLimit[index], 1e3)
    q0 = member.q.copy()
    start = np.clip(q0[index], lower, upper)

    def residual(values):
        q = q0.copy()
        q[index] = values
        pin.framesForwardKinematics(model, robot.data, q)
        hands = np.array([robot.data.oMf[robot.arms[i].frame_id].translation for i in member.arms])
        return (hands - points)[:, rows].ravel()

    solution = least_squares(residual, start, bounds=(lower, upper), xtol=1e-12, ftol=1e-12, gtol=1e-12)
    q = q0.copy()
    q[index] = solution.x
    return Member(member.name, robot, q, member.arms)


def _shape(obj: Mapping, here: str) -> ObjectShape | None:
    """The object's solid: a box of ``size``, a cylinder of ``length`` and ``radius``, or none."""
    from ..support.ranges import LINK_OFFSET

    kind = _get(obj, "shape", str, here, "box" if "size" in obj else None)
    if kind is None:
        for key in ("length", "radius"):
            if key in obj:
                raise TeamError(f'{here}: {key} describes a cylinder: give shape = "cylinder" too')
        return None
    given = [key for key in ("size", "length", "radius", "inertia") if key in obj]
    if "inertia" in obj:
        raise TeamError(
            f"{here}: give either size or inertia, not both (nor a cylinder's length and radius with inertia)"
        )
    if kind == "box":
        if given != ["size"]:
            raise TeamError(
                f'{here}: a box is given by its size alone (a cylinder by shape = "cylinder", length and radius), '
                f"got {given}"
            )
        size = _vector(obj["size"], 3, f"{here} size")
        if np.any(size < 0) or np.any(size > LINK_OFFSET):
            raise TeamError(
                f"{here}: size must be three lengths from 0 to {LINK_OFFSET:g} m (the supported range), "
                f"got {obj['size']!r}"
            )
        return ObjectShape("box", (float(size[0]), float(size[1]), float(size[2])))
    if kind == "cylinder":
        if sorted(given) != ["length", "radius"]:
            raise TeamError(
                f"{here}: a cylinder is given by its length and radius alone (its inertia follows), got {given}"
            )
        length = _number(obj["length"], f"{here} length (m)", positive=False)
        radius = _number(obj["radius"], f"{here} radius (m)", positive=False)
        if not (0.0 <= length <= LINK_OFFSET and 0.0 <= 2.0 * radius <= LINK_OFFSET):
            raise TeamError(
                f"{here}: length and diameter must be from 0 to {LINK_OFFSET:g} m, got {length!r}, {radius!r}"
            )
        return ObjectShape("cylinder", (length, 2.0 * radius, 2.0 * radius))
    raise TeamError(f"{here}: shape must be 'box' or 'cylinder', got {kind!r}")


def _inertia(obj: Mapping, mass: float, R: np.ndarray, here: str) -> np.ndarray | None:
    if "inertia" not in obj:
        return None
    value = obj["inertia"]
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        array = None
    if array is not None and array.shape == (3,):
        array = np.diag(array)
    if array is None or array.shape != (3, 3) or not np.all(np.isfinite(array)):
        raise TeamError(f"{here}: inertia must be 3 principal moments or a 3 x 3 matrix (kg m^2), got {value!r}")
    from ..support.ranges import LINK_INERTIA

    if np.abs(array).max() > LINK_INERTIA:
        raise TeamError(
            f"{here}: inertia entries must be at most {LINK_INERTIA:g} kg m^2 (the supported range), got {value!r}"
        )
    if not np.allclose(array, array.T, rtol=0, atol=1e-12 * max(1.0, float(np.abs(array).max()))):
        raise TeamError(f"{here}: inertia must be symmetric, got {value!r}")
    if np.linalg.eigvalsh(array)[0] < -1e-12 * max(1.0, float(np.abs(array).max())):
        raise TeamError(f"{here}: inertia must be positive semi-definite, got {value!r}")
    return R @ array @ R.T


def _keys(table: Mapping, known: set[str], where: str) -> None:
    unknown = sorted(set(table) - known)
    if unknown:
        raise TeamError(f"{where}: unknown keys {unknown}; expected some of {sorted(known)}")


def _get(table: Mapping, key: str, kind: type, where: str, default):
    if key not in table:
        return default
    value = table[key]
    if not isinstance(value, kind) or (kind is not bool and isinstance(value, bool)):
        raise TeamError(f"{where}: {key} must be a {kind.__name__}, got {value!r}")
    return value


def _number(value, what: str, positive: bool | None = None) -> float:
    """A finite number; ``positive`` True: > 0, False: >= 0, None: any sign."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TeamError(f"{what} must be a number, got {value!r}")
    try:
        value = float(value)
    except OverflowError:  # an integer of hundreds of digits
        raise TeamError(f"{what} must be a finite number, got an integer of {len(str(abs(value)))} digits") from None
    if not math.isfinite(value) or (positive and value <= 0.0) or (positive is False and value < 0.0):
        sign = {True: "a positive", False: "a non-negative", None: "a finite"}[positive]
        raise TeamError(f"{what} must be {sign} number, got {value!r}")
    return value


def _vector(value, n: int, what: str) -> np.ndarray:
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise TeamError(f"{what} must be a list of {n} numbers, got {value!r}")
    return np.array([_number(v, what) for v in value])
