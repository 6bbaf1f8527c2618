"""Robot specs: which URDF, which joints are the wheels, which are the arms, and limits.

A spec is a small TOML file next to its URDF::

    name = "planar_dual_arm"
    urdf = "planar_dual_arm.urdf"          # relative to this file, or "example-robot-data:..."
    platform = "differential_drive"        # a kind of mobmanip.platforms.KINDS, e.g. "fixed"
    default_task = "planar"
    strict = false                          # true: refuse the file's flaws instead of repairing them
    accepted_repairs = ["antenna_link"]     # links whose repair was reviewed: no warning for them
    package_paths = ["../ws/src"]           # where $(find PKG) and package:// look (xacro, meshes)

    [xacro_args]                            # a xacro file's $(arg NAME) values
    arm_type = "right"

    torso = ["torso_lift_joint"]            # optional: actuated joints shared by all arms

    [wheels]                                # the platform kind's own table (see its module)
    right = "wheel_right_joint"
    left = "wheel_left_joint"
    # radius = 0.075                       # optional overrides of the URDF geometry (m)
    # half_track = 0.171

    [[arms]]                                # ordered: arm 1 first
    name = "right"
    joints = ["arm_right_1_joint", ...]
    end_effector = "arm_right_tool_link"

    [object]
    mass = 2.0                              # kg, default object for multi-arm tasks
    grasp_offsets = [[0, -0.15, 0], [0, 0.15, 0]]   # optional: where each arm grasps it (m)

    [limits.velocity]                       # optional overrides by joint name
    [limits.effort]
    [reference]                             # positions of joints locked out of the model,
    torso_lift_joint = 0.15                 # and home positions of the moving ones

    [hold]                                  # optional: arm/torso positions of a posture in which
    arm_right_1_joint = 1.08                # the hands hold the default object (sweeps start
                                            # their inverse kinematics from it)
    [postures.tucked]                       # optional: more named postures (--posture tucked);
    arm_right_1_joint = 0.2                 # "home" is the home configuration, "hold" is [hold]

The reduced velocity is ordered [platform, torso joints, arm 1 joints, arm 2 joints, ...].

:class:`RobotSpec` is checked on construction for its own consistency; the cross-check
against the URDF happens when the robot is loaded (:func:`mobmanip.robot.model.load_robot`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from ..descriptions.resources import builtin_robot_names, builtin_robots_dir, resolve_urdf_reference
from ..errors import LimitError, SpecError, UnknownRobotError
from ..platforms import KINDS, WheelSpec, WheelsSpec, get_kind
from .support_spec import SupportSpec, support_spec_from_table
from .tasks import TASKS

__all__ = ["ArmSpec", "RobotSpec", "WheelSpec", "find_spec", "load_spec", "spec_from_dict"]


def _positive(name: str, kind: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LimitError(name, kind, value)
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise LimitError(name, kind, value)
    return value


def _frozen_limits(limits: Mapping[str, object], kind: str) -> Mapping[str, float]:
    return MappingProxyType({str(k): _positive(str(k), kind, v) for k, v in limits.items()})


@dataclass(frozen=True)
class ArmSpec:
    """One arm: its actuated joints (base to tip) and its end-effector frame."""

    name: str
    joints: tuple[str, ...]
    end_effector: str

    def __post_init__(self):
        if not self.joints:
            raise SpecError(f"arm {self.name!r} has no joints")
        if len(set(self.joints)) != len(self.joints):
            raise SpecError(f"arm {self.name!r} lists a joint twice: {list(self.joints)}")


@dataclass(frozen=True)
class RobotSpec:
    """A wheeled (or fixed-base) manipulator described on top of its URDF.

    Attributes:
        name: robot name.
        urdf: path of the URDF file.
        platform: a platform kind of :data:`mobmanip.platforms.KINDS`, e.g.
            ``"differential_drive"``, ``"fixed"`` or ``"omnidirectional"``.
        arms: the arms, in order (arm 1 first).
        wheels: the platform kind's ``[wheels]`` (e.g. :class:`WheelSpec` for a differential
            drive); ``None`` for kinds that take none.
        default_task: task space used when none is asked for.
        velocity_limits: per-joint velocity limit overrides (rad/s or m/s), and of the
            platform's own reduced velocities that are not joints (e.g. an omnidirectional
            base's ``base_x``, ``base_y`` in m/s and ``base_yaw`` in rad/s).
        effort_limits: per-joint effort limit overrides (N m or N), same keys.
        object_mass: mass of the default held object (kg); 0 means the task point carries no load.
        reference: positions of joints that are not wheels, torso or arm joints; they are
            locked at these values (default 0) when the model is reduced. For a moving joint
            the value is its home position (see :meth:`mobmanip.robot.model.Robot.neutral`).
        torso: actuated joints shared by all arms (e.g. a lift), base to tip; in the reduced
            velocity they follow the platform and precede the arms.
        hold: positions of arm and torso joints (joints not named stay at home) of a posture in
            which the end effectors hold the default object together; sweeps take it as the
            reference posture of their inverse kinematics (see :mod:`mobmanip.sweep`). Empty:
            the home configuration is that reference. It is the posture named ``"hold"``.
        postures: further named postures, name -> (joint -> position), arm and torso joints as
            in ``hold``; ``"home"`` and ``"hold"`` are reserved (see
            :mod:`mobmanip.postures.named`).
        grasp_offsets: where each arm grasps the default object, from its centre (m), one row
            per arm, in the frame of the hold; empty when not declared. The distances between
            them are how far apart holding hands may be (a larger spread is warned about).
        package_dirs: directories where ``package://`` mesh URIs are resolved.
        source: the spec file this came from, if any.
        support: the ``[support]`` table: passive supports, friction (see :mod:`mobmanip.robot.support`).
        strict: refuse the robot file's flaws (non-physical inertias, see
            :mod:`mobmanip.descriptions.flaws`) instead of repairing them with a warning.
        accepted_repairs: links whose flaws the spec's author has reviewed: they are repaired
            without a warning (MuJoCo's ``balanceinertia="true"`` in a model says the same).
            A strict spec accepts none.
        xacro_args: values of a xacro file's ``$(arg NAME)`` (see :mod:`mobmanip.descriptions.xacro`).
        package_paths: folders where ``$(find PKG)`` and ``package://PKG`` look first (before
            ``ROS_PACKAGE_PATH``); also added to :attr:`package_dirs`.
    """

    name: str
    urdf: Path
    platform: str
    arms: tuple[ArmSpec, ...]
    wheels: WheelsSpec | None = None
    default_task: str = "planar"
    velocity_limits: Mapping[str, float] = field(default_factory=dict)
    effort_limits: Mapping[str, float] = field(default_factory=dict)
    object_mass: float = 0.0
    reference: Mapping[str, float] = field(default_factory=dict)
    torso: tuple[str, ...] = ()
    hold: Mapping[str, float] = field(default_factory=dict)
    postures: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    grasp_offsets: tuple[tuple[float, float, float], ...] = ()
    package_dirs: tuple[Path, ...] = ()
    source: Path | None = None
    support: SupportSpec | None = None
    strict: bool = False
    accepted_repairs: tuple[str, ...] = ()
    xacro_args: Mapping[str, str] = field(default_factory=dict)
    package_paths: tuple[Path, ...] = ()

    def __post_init__(self):
        kind = get_kind(self.platform)
        if kind.takes_wheels and self.wheels is None:
            raise SpecError(f"robot {self.name!r}: a {self.platform} platform needs [wheels]")
        if not kind.takes_wheels and self.wheels is not None:
            raise _wheels_not_taken(self.name, self.platform)
        if not self.arms:
            raise SpecError(f"robot {self.name!r} has no arms")
        if not isinstance(self.strict, bool):
            raise SpecError(f"robot {self.name!r}: strict must be true or false, got {self.strict!r}")
        accepted = tuple(self.accepted_repairs)
        if not all(isinstance(link, str) for link in accepted):
            raise SpecError(f"robot {self.name!r}: accepted_repairs must be link names, got {list(accepted)!r}")
        if accepted and self.strict:
            raise SpecError(
                f"robot {self.name!r}: strict = true refuses every repair, so accepted_repairs "
                f"({', '.join(accepted)}) contradicts it; remove one"
            )
        object.__setattr__(self, "accepted_repairs", accepted)
        arguments = {}
        for key, value in dict(self.xacro_args).items():
            if isinstance(value, bool):
                value = "true" if value else "false"
            if not isinstance(value, (str, int, float)):
                raise SpecError(f"robot {self.name!r}: [xacro_args] {key} must be a string or a number, got {value!r}")
            arguments[str(key)] = str(value)
        object.__setattr__(self, "xacro_args", MappingProxyType(arguments))
        object.__setattr__(self, "package_paths", tuple(Path(p) for p in self.package_paths))
        if self.default_task not in TASKS:
            raise SpecError(f"unknown default_task {self.default_task!r}; expected one of {', '.join(TASKS)}")
        names = [a.name for a in self.arms]
        if len(set(names)) != len(names):
            raise SpecError(f"robot {self.name!r}: arm names repeat: {names}")
        torso = tuple(self.torso)
        if not all(isinstance(j, str) for j in torso):
            raise SpecError(f"robot {self.name!r}: torso joints must be strings, got {list(torso)!r}")
        if len(set(torso)) != len(torso):
            raise SpecError(f"robot {self.name!r}: the torso lists a joint twice: {list(torso)}")
        object.__setattr__(self, "torso", torso)
        seen: dict[str, str] = dict.fromkeys(torso, "torso")
        for arm in self.arms:
            for joint in arm.joints:
                if joint in seen:
                    owner = "the torso" if seen[joint] == "torso" else f"arm {seen[joint]!r}"
                    raise SpecError(f"joint {joint!r} belongs to {owner} and to arm {arm.name!r}")
                seen[joint] = arm.name
        if self.wheels is not None:
            for joint in self.wheels.joint_names:
                if joint in seen:
                    owner = "the torso" if seen[joint] == "torso" else f"arm {seen[joint]!r}"
                    raise SpecError(f"joint {joint!r} is both a wheel and in {owner}")
        object.__setattr__(self, "velocity_limits", _frozen_limits(self.velocity_limits, "velocity"))
        object.__setattr__(self, "effort_limits", _frozen_limits(self.effort_limits, "effort"))
        if isinstance(self.object_mass, bool) or not isinstance(self.object_mass, (int, float)):
            raise SpecError(f"object mass must be a number, got {self.object_mass!r}")
        if not math.isfinite(self.object_mass) or self.object_mass < 0.0:
            raise SpecError(f"object mass must be finite and non-negative, got {self.object_mass!r}")
        reference = {}
        for joint, value in dict(self.reference).items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SpecError(f"reference position of {joint!r} must be a finite number, got {value!r}")
            reference[str(joint)] = float(value)
        object.__setattr__(self, "reference", MappingProxyType(reference))
        object.__setattr__(self, "hold", _posture_table(self.name, "[hold]", self.hold, seen))
        postures = {}
        for name, table in dict(self.postures).items():
            if name in ("home", "hold"):
                raise SpecError(
                    f"robot {self.name!r}: [postures.{name}] is reserved ({name!r} is "
                    + ("the home configuration" if name == "home" else "[hold]")
                    + "); give it another name"
                )
            if not isinstance(table, Mapping):
                raise SpecError(f"robot {self.name!r}: [postures.{name}] must be a table of joint positions")
            postures[str(name)] = _posture_table(self.name, f"[postures.{name}]", table, seen)
        object.__setattr__(self, "postures", MappingProxyType(postures))
        object.__setattr__(self, "grasp_offsets", _grasp_offsets(self.name, self.grasp_offsets, len(self.arms)))
        object.__setattr__(self, "arms", tuple(self.arms))
        object.__setattr__(self, "package_dirs", tuple(Path(p) for p in self.package_dirs))

    @property
    def read_options(self) -> dict:
        """The options :func:`mobmanip.descriptions.read_description` reads the robot file with:
        ``package_dirs`` (mesh folders, :attr:`package_paths` included), and for a format that
        takes them ``xacro_args`` and ``package_paths``."""
        dirs = tuple(dict.fromkeys(self.package_dirs + self.package_paths))
        return {"package_dirs": dirs, "xacro_args": dict(self.xacro_args), "package_paths": self.package_paths}

    @property
    def arm_joint_names(self) -> tuple[str, ...]:
        """All arm joints, arm by arm in spec order."""
        return tuple(j for arm in self.arms for j in arm.joints)

    @property
    def wheel_joint_names(self) -> tuple[str, ...]:
        """The URDF joints the platform keeps moving (e.g. the drive wheels, right then left)."""
        return self.wheels.joint_names if self.wheels is not None else ()

    @property
    def active_joint_names(self) -> tuple[str, ...]:
        """Every joint that stays free in the model: the platform's wheels, torso, then arms."""
        return self.wheel_joint_names + self.torso + self.arm_joint_names

    @property
    def platform_limit_names(self) -> tuple[str, ...]:
        """Names other than joints that ``[limits.*]`` may set (the platform kind's own)."""
        return get_kind(self.platform).limit_names(self.wheels)


def _posture_table(robot: str, where: str, table: Mapping, joints: Mapping[str, str]) -> Mapping[str, float]:
    """A posture's joint positions checked: arm or torso joints only, finite numbers."""
    out = {}
    for joint, value in dict(table).items():
        if joint not in joints:
            raise SpecError(
                f"robot {robot!r}: {where} names {joint!r}, which is not an arm or torso joint; "
                f"expected some of {list(joints)}"
            )
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            label = "hold" if where == "[hold]" else where
            raise SpecError(f"robot {robot!r}: {label} position of {joint!r} must be a finite number, got {value!r}")
        out[str(joint)] = float(value)
    return MappingProxyType(out)


def _grasp_offsets(robot: str, rows, n_arms: int) -> tuple[tuple[float, float, float], ...]:
    """[object] grasp_offsets checked: one (x, y, z) row of finite metres per arm, or none."""
    rows = tuple(rows)
    if not rows:
        return ()
    bad = SpecError(
        f"robot {robot!r}: [object] grasp_offsets must be {n_arms} rows [x, y, z] of finite metres "
        f"(one per arm), got {[list(r) if isinstance(r, (list, tuple)) else r for r in rows]!r}"
    )
    if len(rows) != n_arms:
        raise bad
    out = []
    for row in rows:
        if not isinstance(row, (list, tuple)) or len(row) != 3:
            raise bad
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in row):
            raise bad
        out.append((float(row[0]), float(row[1]), float(row[2])))
    return tuple(out)


def _wheels_not_taken(robot: str, platform: str) -> SpecError:
    wheeled = [k.name for k in KINDS.values() if k.takes_wheels]
    listed = wheeled[0] if len(wheeled) == 1 else f"{', '.join(wheeled[:-1])} or {wheeled[-1]}"
    return SpecError(
        f"robot {robot!r}: [wheels] is only for a {listed} platform, not {platform!r} "
        "(other platforms lock any wheels of the URDF); remove it"
    )


def _require(table: Mapping, key: str, kind: type, where: str):
    if key not in table:
        raise SpecError(f"{where}: missing key {key!r}")
    value = table[key]
    if not isinstance(value, kind):
        raise SpecError(f"{where}: {key!r} must be a {kind.__name__}, got {value!r}")
    return value


def _optional(table: Mapping, key: str, kind: type, where: str, default):
    if key not in table:
        return default
    value = table[key]
    if not isinstance(value, kind):
        raise SpecError(f"{where}: {key!r} must be a {kind.__name__}, got {value!r}")
    return value


def _folder(entry: object, base_dir: Path, where: str) -> Path:
    """A folder of ``package_paths``: relative to the spec's folder unless absolute."""
    if not isinstance(entry, str) or not entry:
        raise SpecError(f"{where}: package_paths must be a list of folders, got {entry!r}")
    path = Path(entry).expanduser()
    return path if path.is_absolute() else base_dir / path


def spec_from_dict(data: Mapping, base_dir: Path, source: Path | None = None) -> RobotSpec:
    """Build a :class:`RobotSpec` from parsed TOML; ``base_dir`` anchors a relative URDF path."""
    where = str(source) if source else "spec"
    known = set(
        "name urdf platform default_task strict accepted_repairs package_paths xacro_args wheels torso arms object "
        "limits reference hold postures support".split()
    )
    unknown = sorted(set(data) - known)
    if unknown:
        raise SpecError(f"{where}: unknown keys {unknown}; expected some of {sorted(known)}")
    urdf, package_dirs = resolve_urdf_reference(_require(data, "urdf", str, where), base_dir)
    name = _optional(data, "name", str, where, urdf.stem)
    platform = _optional(data, "platform", str, where, "differential_drive")
    wheels = None
    if "wheels" in data:
        table = _require(data, "wheels", dict, where)
        kind = get_kind(platform)
        if not kind.takes_wheels:
            raise _wheels_not_taken(name, platform)
        wheels = kind.parse_wheels(table, where)
    arms = []
    for k, table in enumerate(_require(data, "arms", list, where)):
        arm_where = f"{where} [[arms]] #{k + 1}"
        if not isinstance(table, dict):
            raise SpecError(f"{arm_where}: expected a table, got {table!r}")
        extra = sorted(set(table) - {"name", "joints", "end_effector"})
        if extra:
            raise SpecError(f"{arm_where}: unknown keys {extra}; expected 'name', 'joints' and 'end_effector'")
        joints = _require(table, "joints", list, arm_where)
        if not all(isinstance(j, str) for j in joints):
            raise SpecError(f"{arm_where}: joints must be strings, got {joints!r}")
        arms.append(
            ArmSpec(
                name=_optional(table, "name", str, arm_where, f"arm{k + 1}"),
                joints=tuple(joints),
                end_effector=_require(table, "end_effector", str, arm_where),
            )
        )
    torso = data.get("torso", [])
    if not isinstance(torso, list) or not all(isinstance(j, str) for j in torso):
        raise SpecError(f"{where}: 'torso' must be a list of joint names, got {torso!r}")
    limits = _optional(data, "limits", dict, where, {})
    obj = _optional(data, "object", dict, where, {})
    extra = sorted(set(limits) - {"velocity", "effort"})
    if extra:
        raise SpecError(f"{where}: unknown keys in [limits]: {extra}; expected 'velocity' and 'effort'")
    extra = sorted(set(obj) - {"mass", "grasp_offsets"})
    if extra:
        raise SpecError(f"{where}: unknown keys in [object]: {extra}; expected 'mass' and 'grasp_offsets'")
    grasp_offsets = obj.get("grasp_offsets", [])
    if not isinstance(grasp_offsets, list):
        raise SpecError(f"{where}: [object] grasp_offsets must be a list of [x, y, z] rows, got {grasp_offsets!r}")
    return RobotSpec(
        name=name,
        urdf=urdf,
        platform=platform,
        arms=tuple(arms),
        wheels=wheels,
        default_task=_optional(data, "default_task", str, where, "planar"),
        velocity_limits=_optional(limits, "velocity", dict, f"{where} [limits]", {}),
        effort_limits=_optional(limits, "effort", dict, f"{where} [limits]", {}),
        object_mass=obj.get("mass", 0.0),
        reference=_optional(data, "reference", dict, where, {}),
        torso=tuple(torso),
        hold=_optional(data, "hold", dict, where, {}),
        postures=_optional(data, "postures", dict, where, {}),
        grasp_offsets=tuple(grasp_offsets),
        support=support_spec_from_table(data["support"], where) if "support" in data else None,
        strict=_optional(data, "strict", bool, where, False),
        accepted_repairs=tuple(_optional(data, "accepted_repairs", list, where, [])),
        xacro_args=_optional(data, "xacro_args", dict, where, {}),
        package_paths=tuple(_folder(p, base_dir, where) for p in _optional(data, "package_paths", list, where, [])),
        package_dirs=package_dirs,
        source=source,
    )


#: Largest spec file read (bytes): specs are a few kilobytes.
MAX_SPEC_BYTES = 4 * 1024 * 1024


def load_spec(path: str | Path) -> RobotSpec:
    """Read a spec TOML file.

    Raises:
        SpecError: the file cannot be read or parsed, or its content is inconsistent.
    """
    from ..support.reading import read_user_toml

    path = Path(path)
    data = read_user_toml(path, "spec", limit=MAX_SPEC_BYTES, error=SpecError)
    return spec_from_dict(data, path.resolve().parent, source=path)


def find_spec(name_or_path: str | Path) -> RobotSpec:
    """Load a built-in robot by name (e.g. ``"planar_dual_arm"``) or any spec by path.

    Raises:
        UnknownRobotError: neither a built-in name nor an existing file.
    """
    text = str(name_or_path)
    builtin = builtin_robots_dir() / f"{text}.toml"
    if "/" not in text and not text.endswith(".toml") and builtin.is_file():
        return load_spec(builtin)
    path = Path(text)
    if path.is_file() or (path.exists() and not path.is_dir()):  # a device or FIFO: refused by the reader
        return load_spec(path)
    raise UnknownRobotError(text, builtin_robot_names())
