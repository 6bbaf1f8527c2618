"""Robot specs: which URDF, which joints are the wheels, which are the arms, and limits.

A spec is a small TOML file next to its URDF::

    name = "planar_dual_arm"
    urdf = "planar_dual_arm.urdf"          # relative to this file, or "example-robot-data:..."
    platform = "differential_drive"        # or "fixed", "omnidirectional"
    default_task = "planar"

    [wheels]                                # differential drive only
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

    [limits.velocity]                       # optional overrides by joint name
    [limits.effort]
    [reference]                             # positions of joints locked out of the model
    torso_lift_joint = 0.15

:class:`RobotSpec` is checked on construction for its own consistency; the cross-check
against the URDF happens when the robot is loaded (:func:`mobmanip.model.load_robot`).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from .errors import LimitError, SpecError, UnknownRobotError
from .resources import builtin_robot_names, builtin_robots_dir, resolve_urdf_reference
from .tasks import TASKS

PLATFORM_KINDS = ("differential_drive", "fixed", "omnidirectional")
OMNI_COORDINATES = ("base_x", "base_y", "base_yaw")


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
class WheelSpec:
    """The two drive wheels of a differential-drive platform.

    Attributes:
        right: name of the right wheel's joint.
        left: name of the left wheel's joint.
        radius: wheel radius override (m); ``None`` reads it from the URDF geometry.
        half_track: half the distance between the wheels (m); ``None`` reads the URDF.
    """

    right: str
    left: str
    radius: float | None = None
    half_track: float | None = None

    def __post_init__(self):
        if self.right == self.left:
            raise SpecError(f"right and left wheel are the same joint {self.right!r}")
        for label, value in (("wheel radius", self.radius), ("half_track", self.half_track)):
            if value is not None:
                _positive(label, "geometry", value)


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
        platform: ``"differential_drive"``, ``"fixed"`` or ``"omnidirectional"``.
        arms: the arms, in order (arm 1 first).
        wheels: the drive wheels (differential drive only).
        default_task: task space used when none is asked for.
        velocity_limits: per-joint velocity limit overrides (rad/s or m/s); for an
            omnidirectional base also ``base_x``, ``base_y`` (m/s) and ``base_yaw`` (rad/s).
        effort_limits: per-joint effort limit overrides (N m or N), same keys.
        object_mass: mass of the default held object (kg).
        reference: positions of joints that are not wheels or arm joints; they are locked at
            these values (default 0) when the model is reduced.
        package_dirs: directories where ``package://`` mesh URIs are resolved.
        source: the spec file this came from, if any.
    """

    name: str
    urdf: Path
    platform: str
    arms: tuple[ArmSpec, ...]
    wheels: WheelSpec | None = None
    default_task: str = "planar"
    velocity_limits: Mapping[str, float] = field(default_factory=dict)
    effort_limits: Mapping[str, float] = field(default_factory=dict)
    object_mass: float = 1.0
    reference: Mapping[str, float] = field(default_factory=dict)
    package_dirs: tuple[Path, ...] = ()
    source: Path | None = None

    def __post_init__(self):
        if self.platform not in PLATFORM_KINDS:
            raise SpecError(f"unknown platform {self.platform!r}; expected one of {', '.join(PLATFORM_KINDS)}")
        if self.platform == "differential_drive" and self.wheels is None:
            raise SpecError(f"robot {self.name!r}: a differential-drive platform needs [wheels]")
        if not self.arms:
            raise SpecError(f"robot {self.name!r} has no arms")
        if self.default_task not in TASKS:
            raise SpecError(f"unknown default_task {self.default_task!r}; expected one of {', '.join(TASKS)}")
        names = [a.name for a in self.arms]
        if len(set(names)) != len(names):
            raise SpecError(f"robot {self.name!r}: arm names repeat: {names}")
        seen: dict[str, str] = {}
        for arm in self.arms:
            for joint in arm.joints:
                if joint in seen:
                    raise SpecError(f"joint {joint!r} belongs to arms {seen[joint]!r} and {arm.name!r}")
                seen[joint] = arm.name
        if self.wheels is not None:
            for joint in (self.wheels.right, self.wheels.left):
                if joint in seen:
                    raise SpecError(f"joint {joint!r} is both a wheel and in arm {seen[joint]!r}")
        object.__setattr__(self, "velocity_limits", _frozen_limits(self.velocity_limits, "velocity"))
        object.__setattr__(self, "effort_limits", _frozen_limits(self.effort_limits, "effort"))
        _positive("object", "mass", self.object_mass)
        reference = {}
        for joint, value in dict(self.reference).items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SpecError(f"reference position of {joint!r} must be a finite number, got {value!r}")
            reference[str(joint)] = float(value)
        object.__setattr__(self, "reference", MappingProxyType(reference))
        object.__setattr__(self, "arms", tuple(self.arms))
        object.__setattr__(self, "package_dirs", tuple(Path(p) for p in self.package_dirs))

    @property
    def arm_joint_names(self) -> tuple[str, ...]:
        """All arm joints, arm by arm in spec order."""
        return tuple(j for arm in self.arms for j in arm.joints)


def _require(table: Mapping, key: str, kind: type, where: str):
    if key not in table:
        raise SpecError(f"{where}: missing key {key!r}")
    value = table[key]
    if not isinstance(value, kind):
        raise SpecError(f"{where}: {key!r} must be a {kind.__name__}, got {value!r}")
    return value


def spec_from_dict(data: Mapping, base_dir: Path, source: Path | None = None) -> RobotSpec:
    """Build a :class:`RobotSpec` from parsed TOML; ``base_dir`` anchors a relative URDF path."""
    where = str(source) if source else "spec"
    known = {"name", "urdf", "platform", "default_task", "wheels", "arms", "object", "limits", "reference"}
    unknown = sorted(set(data) - known)
    if unknown:
        raise SpecError(f"{where}: unknown keys {unknown}; expected some of {sorted(known)}")
    urdf, package_dirs = resolve_urdf_reference(_require(data, "urdf", str, where), base_dir)
    name = data.get("name", urdf.stem)
    platform = data.get("platform", "differential_drive")
    wheels = None
    if "wheels" in data:
        table = _require(data, "wheels", dict, where)
        extra = sorted(set(table) - {"right", "left", "radius", "half_track"})
        if extra:
            raise SpecError(f"{where}: unknown keys in [wheels]: {extra}")
        wheels = WheelSpec(
            right=_require(table, "right", str, f"{where} [wheels]"),
            left=_require(table, "left", str, f"{where} [wheels]"),
            radius=table.get("radius"),
            half_track=table.get("half_track"),
        )
    arms = []
    for k, table in enumerate(_require(data, "arms", list, where)):
        arm_where = f"{where} [[arms]] #{k + 1}"
        if not isinstance(table, dict):
            raise SpecError(f"{arm_where}: expected a table, got {table!r}")
        joints = _require(table, "joints", list, arm_where)
        if not all(isinstance(j, str) for j in joints):
            raise SpecError(f"{arm_where}: joints must be strings, got {joints!r}")
        arms.append(
            ArmSpec(
                name=table.get("name", f"arm{k + 1}"),
                joints=tuple(joints),
                end_effector=_require(table, "end_effector", str, arm_where),
            )
        )
    limits = data.get("limits", {})
    obj = data.get("object", {})
    return RobotSpec(
        name=name,
        urdf=urdf,
        platform=platform,
        arms=tuple(arms),
        wheels=wheels,
        default_task=data.get("default_task", "planar"),
        velocity_limits=limits.get("velocity", {}),
        effort_limits=limits.get("effort", {}),
        object_mass=obj.get("mass", 1.0),
        reference=data.get("reference", {}),
        package_dirs=package_dirs,
        source=source,
    )


def load_spec(path: str | Path) -> RobotSpec:
    """Read a spec TOML file.

    Raises:
        SpecError: the file cannot be read or parsed, or its content is inconsistent.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise SpecError(f"cannot read spec {path}: {exc.strerror or exc}") from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"spec {path} is not valid TOML: {exc}") from exc
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
    if path.is_file():
        return load_spec(path)
    raise UnknownRobotError(text, builtin_robot_names())
