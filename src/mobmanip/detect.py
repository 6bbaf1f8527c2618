"""Inferring a robot spec from a URDF alone: drive wheels, arms, torso and a TOML to edit.

:func:`spec_from_urdf` looks at the URDF's structure and geometry (through yourdfpy) and
returns a :class:`~mobmanip.spec.RobotSpec` ready for :func:`mobmanip.model.load_robot`;
:func:`spec_to_toml` writes any spec as a commented TOML file for the user to check and edit.

The rules:

- A *drive wheel* is a continuous joint whose child link carries a cylinder about the joint
  axis or a sphere (:func:`mobmanip.urdf.wheel_radius`), whose axis is the platform's lateral
  (y) axis, and that no other rotating joint carries (so caster wheels, which hang on a swivel,
  and wheels on an arm are not drive wheels). With more than two such joints, those with an
  effort limit (driven) are preferred; if that still leaves more than two the choice is
  ambiguous and :class:`~mobmanip.errors.WheelError` lists the candidates. The right wheel is the
  one with the smaller lateral (y) position in the root link's frame (forward = +x).
- An *arm* is the actuated (revolute, continuous, prismatic) joints on the path from the root
  link to the end-effector frame, drive wheels excluded (and no joint on such a path is taken
  for a drive wheel). Joints on the path of more than one arm (a
  torso lift, say) belong to no arm: they become the spec's ``torso`` (``torso=True``) or are
  locked (default), in both cases at mid-range (their home position when actuated).
- Every other joint is locked at zero, or at mid-range when zero is outside its limits; an
  arm or torso joint whose range excludes zero gets its mid-range as home position.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import FrameNotFoundError, JointNotFoundError, SpecError, UrdfError, WheelError
from .resources import EXAMPLE_ROBOT_DATA_PREFIX, example_robot_data_share
from .spec import OMNI_COORDINATES, PLATFORM_KINDS, ArmSpec, RobotSpec, WheelSpec
from .urdf import (
    MOVING_JOINT_TYPES,
    check_supported,
    joint_axis,
    joint_limits,
    joint_path,
    mimic_joints,
    read_urdf,
    root_link,
    wheel_radius,
    zero_configuration_placements,
)

#: |cos| between a wheel axis and the platform's lateral axis above which the wheel counts as
#: lateral; the same threshold the model uses when it reads the wheel axis signs.
_LATERAL = 0.99


@dataclass(frozen=True)
class WheelCandidate:
    """A continuous joint whose child link is wheel-shaped.

    Attributes:
        name: joint name.
        radius: wheel radius from the geometry (m).
        position: joint origin in the root link's frame at the zero configuration (m), (3,).
        axis: joint axis in the root link's frame, (3,).
        carried_by_rotating_joint: whether a revolute/continuous joint lies between it and the root.
        driven: whether the URDF gives it a positive effort limit.
    """

    name: str
    radius: float
    position: np.ndarray
    axis: np.ndarray
    carried_by_rotating_joint: bool
    driven: bool

    @property
    def lateral(self) -> bool:
        """Whether it turns about the platform's lateral (y) axis."""
        return abs(float(self.axis[1])) >= _LATERAL

    def describe(self) -> str:
        x, y, z = self.position
        return f"{self.name} (r = {self.radius:g} m at x = {x:.3f}, y = {y:.3f} m)"


@dataclass(frozen=True)
class Detection:
    """What :func:`detect_spec` found.

    Attributes:
        spec: the inferred spec.
        shared_joints: actuated joints on the path of more than one arm (torso or locked).
        notes: one-line remarks for the user (written as comments by ``init-spec``).
        urdf_limits: ``{joint: (velocity, effort)}`` from the URDF for every active joint.
    """

    spec: RobotSpec
    shared_joints: tuple[str, ...]
    notes: tuple[str, ...]
    urdf_limits: Mapping[str, tuple[float | None, float | None]]


def wheel_candidates(urdf) -> list[WheelCandidate]:
    """Every continuous joint with a wheel-shaped child link, in URDF order."""
    placements = zero_configuration_placements(urdf)
    out = []
    for joint in urdf.robot.joints:
        if joint.type != "continuous":
            continue
        radius = wheel_radius(urdf, joint.name)
        if radius is None:
            continue
        pose = placements[joint.name]
        ancestors = joint_path(urdf, joint.parent)
        _, effort = joint_limits(urdf, joint.name)
        out.append(
            WheelCandidate(
                name=joint.name,
                radius=radius,
                position=pose[:3, 3].copy(),
                axis=pose[:3, :3] @ joint_axis(joint),
                carried_by_rotating_joint=any(j.type in ("revolute", "continuous") for j in ancestors),
                driven=effort is not None and effort > 0.0,
            )
        )
    return out


def detect_wheels(urdf, path: str | Path = "URDF", exclude: Iterable[str] = ()) -> WheelSpec | None:
    """The drive wheels of a differential drive, or ``None`` if the URDF has none.

    Args:
        urdf: the parsed URDF.
        path: the URDF's path, for messages.
        exclude: joints that cannot be wheels (those on the way to an end effector).

    Raises:
        WheelError: only one drive wheel, more than two (ambiguous; the message lists them),
            or two at the same lateral position.
    """
    exclude = set(exclude)
    candidates = [c for c in wheel_candidates(urdf) if c.name not in exclude]
    drive = [c for c in candidates if c.lateral and not c.carried_by_rotating_joint]
    if len(drive) > 2 and sum(c.driven for c in drive) >= 2:
        drive = [c for c in drive if c.driven]
    if not drive:
        return None
    if len(drive) != 2:
        what = "only one drive wheel" if len(drive) == 1 else f"{len(drive)} possible drive wheels"
        others = [c for c in candidates if c not in drive]
        also = f"; not drive wheels: {', '.join(c.name for c in others)}" if others else ""
        raise WheelError(
            f"{path}: {what}: {', '.join(c.describe() for c in drive)}{also}; "
            "name the pair explicitly (--wheels RIGHT,LEFT) or choose another platform"
        )
    right, left = sorted(drive, key=lambda c: float(c.position[1]))
    if float(left.position[1] - right.position[1]) < 1e-6:
        raise WheelError(
            f"{path}: wheels {right.name!r} and {left.name!r} sit at the same lateral position; "
            "name the pair explicitly (--wheels RIGHT,LEFT)"
        )
    return WheelSpec(right=right.name, left=left.name)


def _frame_link(urdf, frame: str, path: str | Path) -> str:
    """The link whose path from the root carries ``frame`` (a link, or a joint's child link)."""
    if frame in urdf.link_map:
        return frame
    if frame in urdf.joint_map:
        return urdf.joint_map[frame].child
    raise FrameNotFoundError(frame, list(urdf.link_map) + list(urdf.joint_map), where=str(path))


def arm_joints(urdf, end_effector: str, exclude: Iterable[str] = (), path: str | Path = "URDF") -> list[str]:
    """The actuated joints from the root link to ``end_effector``, root first.

    Args:
        urdf: the parsed URDF.
        end_effector: a link (or joint) name.
        exclude: joints to leave out (the wheels).
        path: the URDF's path, for messages.

    Raises:
        FrameNotFoundError: unknown frame (the message lists existing frames, closest first).
    """
    link = _frame_link(urdf, end_effector, path)
    exclude = set(exclude)
    return [j.name for j in joint_path(urdf, link) if j.type in MOVING_JOINT_TYPES and j.name not in exclude]


def _arm_name(end_effector: str, k: int, taken: set[str]) -> str:
    tokens = set(re.split(r"[^a-z]+", end_effector.lower()))
    sides = [s for s in ("right", "left") if s in tokens]
    name = sides[0] if len(sides) == 1 else f"arm{k + 1}"
    return name if name not in taken else f"arm{k + 1}"


def _mid_range(urdf, name: str) -> float | None:
    """Mid-range of a joint with finite position limits, else ``None``."""
    joint = urdf.joint_map[name]
    limit = joint.limit
    if joint.type == "continuous" or limit is None or limit.lower is None or limit.upper is None:
        return None
    lower, upper = float(limit.lower), float(limit.upper)
    if not (math.isfinite(lower) and math.isfinite(upper)) or upper < lower:
        return None
    return 0.5 * (lower + upper)


def _excludes_zero(urdf, name: str) -> bool:
    joint = urdf.joint_map[name]
    limit = joint.limit
    if joint.type not in ("revolute", "prismatic") or limit is None or limit.lower is None or limit.upper is None:
        return False
    return not (float(limit.lower) <= 0.0 <= float(limit.upper))


def _planar(urdf, joints: Iterable[str]) -> bool:
    """Whether every joint moves in the horizontal plane (revolute about z, prismatic along x-y)."""
    placements = zero_configuration_placements(urdf)
    for name in joints:
        joint = urdf.joint_map[name]
        axis = placements[name][:3, :3] @ joint_axis(joint)
        vertical = abs(float(axis[2])) >= 1.0 - 1e-9
        if joint.type == "prismatic" and abs(float(axis[2])) > 1e-9:
            return False
        if joint.type != "prismatic" and not vertical:
            return False
    return True


def detect_spec(
    path: str | Path,
    end_effectors: Sequence[str],
    wheels: tuple[str, str] | None = None,
    platform: str | None = None,
    *,
    torso: bool = False,
    name: str | None = None,
    default_task: str | None = None,
) -> Detection:
    """Infer a spec from a URDF; see the module docstring for the rules.

    Args:
        path: the URDF file.
        end_effectors: one end-effector frame per arm, arm 1 first (link or joint names).
        wheels: ``(right, left)`` drive-wheel joints, to skip wheel detection.
        platform: ``"differential_drive"``, ``"fixed"`` or ``"omnidirectional"``; ``None``
            means differential drive if two drive wheels are found (or given), else fixed.
        torso: make the joints shared by several arms the spec's torso (else lock them).
        name: robot name (default: the URDF's robot name).
        default_task: task space (default: ``"planar"`` if every arm joint moves in the
            horizontal plane, else ``"spatial"``).

    Raises:
        UrdfError: unreadable URDF, unsupported construct, or a mimic joint on an arm.
        FrameNotFoundError: unknown end-effector frame.
        JointNotFoundError: an explicit wheel joint that does not exist.
        WheelError: ambiguous or unusable drive wheels.
        SpecError: no end effector, an end effector no joint moves, or an unknown platform.
    """
    path = Path(path)
    urdf = read_urdf(path)
    check_supported(urdf, path)
    if platform is not None and platform not in PLATFORM_KINDS:
        raise SpecError(f"unknown platform {platform!r}; expected one of {', '.join(PLATFORM_KINDS)}")
    end_effectors = list(end_effectors)
    if not end_effectors:
        raise SpecError(f"{path}: name at least one end-effector frame")
    notes: list[str] = [f"platform frame: root link {root_link(urdf, path)!r} (forward = +x, left = +y)"]

    on_arm_paths = {j for ee in end_effectors for j in arm_joints(urdf, ee, (), path)}
    candidates = {c.name: c for c in wheel_candidates(urdf) if c.name not in on_arm_paths}
    if wheels is not None:
        for joint in wheels:
            if joint not in urdf.joint_map:
                raise JointNotFoundError(joint, urdf.joint_map, where=str(path))
        wheel_spec = WheelSpec(right=wheels[0], left=wheels[1])
    elif platform in (None, "differential_drive"):
        wheel_spec = detect_wheels(urdf, path, exclude=on_arm_paths)
    else:
        wheel_spec = None
    if platform is None:
        platform = "differential_drive" if wheel_spec is not None else "fixed"
    if platform == "differential_drive":
        if wheel_spec is None:
            listed = ", ".join(c.describe() for c in candidates.values()) or "none"
            raise WheelError(
                f"{path}: no drive wheels found (wheel-shaped continuous joints: {listed}); "
                "name them with --wheels RIGHT,LEFT or choose another platform"
            )
        radius = wheel_radius(urdf, wheel_spec.right)
        notes.append(
            f"drive wheels: right {wheel_spec.right!r}, left {wheel_spec.left!r}"
            + (f" (radius {radius:g} m from the URDF geometry)" if radius is not None else "")
        )
    elif wheel_spec is not None:
        notes.append(f"platform {platform!r}: wheels {wheel_spec.right!r} and {wheel_spec.left!r} are locked")
        wheel_spec = None
    drive = set(wheels or ()) | ({wheel_spec.right, wheel_spec.left} if wheel_spec is not None else set())
    paths = [arm_joints(urdf, ee, drive, path) for ee in end_effectors]
    counts: dict[str, int] = {}
    for joints in paths:
        for joint in joints:
            counts[joint] = counts.get(joint, 0) + 1
    shared = tuple(j for j in dict.fromkeys(j for p in paths for j in p) if counts[j] > 1)
    mimics = mimic_joints(urdf)
    arms, taken = [], set()
    for k, (ee, joints) in enumerate(zip(end_effectors, paths)):
        own = tuple(j for j in joints if j not in shared)
        if not own:
            raise SpecError(
                f"{path}: end-effector frame {ee!r} is moved by no joint of its own"
                + (f" (only by the shared joints {', '.join(shared)})" if shared else "")
            )
        for joint in own + shared:
            if joint in mimics:
                raise UrdfError(
                    str(path),
                    f"joint {joint!r} on the path to {ee!r} mimics {mimics[joint]!r}; "
                    "mimic joints cannot be actuated here (pick an end-effector frame before it)",
                )
        arm_name = _arm_name(ee, k, taken)
        taken.add(arm_name)
        arms.append(ArmSpec(name=arm_name, joints=own, end_effector=ee))

    torso_joints = shared if torso else ()
    reference: dict[str, float] = {}
    active = set(torso_joints) | {j for arm in arms for j in arm.joints}
    if wheel_spec is not None:
        active |= {wheel_spec.right, wheel_spec.left}
    for joint in urdf.robot.joints:
        if joint.type not in MOVING_JOINT_TYPES:
            continue
        mid = _mid_range(urdf, joint.name)
        if joint.name in shared and mid is not None:
            reference[joint.name] = mid  # the torso, locked or home: mid-height
        elif _excludes_zero(urdf, joint.name) and mid is not None:
            reference[joint.name] = mid
    if shared:
        if torso:
            notes.append(f"joints shared by several arms form the torso: {', '.join(shared)}")
        else:
            notes.append(f"joints shared by several arms are locked at mid-range: {', '.join(shared)}")
    if default_task is None:
        default_task = "planar" if _planar(urdf, active - drive) else "spatial"

    urdf_limits = {j: joint_limits(urdf, j) for j in sorted(active)}
    spec = RobotSpec(
        name=name or urdf.robot.name or path.stem,
        urdf=path.resolve(),
        platform=platform,
        arms=tuple(arms),
        wheels=wheel_spec,
        default_task=default_task,
        reference=reference,
        torso=torso_joints,
        package_dirs=(path.resolve().parent,),
    )
    if platform == "omnidirectional":
        notes.append(
            "an omnidirectional base needs limits for base_x, base_y (m/s, N) and base_yaw (rad/s, N m) "
            "in [limits.velocity] and [limits.effort]"
        )
    return Detection(spec=spec, shared_joints=shared, notes=tuple(notes), urdf_limits=urdf_limits)


def spec_from_urdf(
    path: str | Path,
    end_effectors: Sequence[str],
    wheels: tuple[str, str] | None = None,
    platform: str | None = None,
    **options,
) -> RobotSpec:
    """The spec :func:`detect_spec` infers (same arguments), without the notes."""
    return detect_spec(path, end_effectors, wheels, platform, **options).spec


def parse_wheel_pair(text: str) -> tuple[str, str]:
    """``"RIGHT,LEFT"`` -> ``("RIGHT", "LEFT")``.

    Raises:
        WheelError: not exactly two non-empty names.
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 2 or not all(parts):
        raise WheelError(f"wheels must be given as RIGHT,LEFT (two joint names), got {text!r}")
    return parts[0], parts[1]


# ----- writing a spec as TOML -----

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(name: str) -> str:
    return name if _BARE_KEY.match(name) else json.dumps(name)


def _string(value: str) -> str:
    return json.dumps(value)  # a JSON string is a valid TOML basic string


def _number(value: float) -> str:
    return repr(float(value))


def _urdf_reference(urdf: Path, base_dir: Path | None) -> str:
    """How the spec file names its URDF: example-robot-data prefix, relative or absolute path."""
    urdf = Path(urdf).resolve()
    try:
        robots = (example_robot_data_share() / "example-robot-data" / "robots").resolve()
        return EXAMPLE_ROBOT_DATA_PREFIX + urdf.relative_to(robots).as_posix()
    except (ValueError, SpecError):
        pass
    if base_dir is not None:
        try:
            return Path(os.path.relpath(urdf, Path(base_dir).resolve())).as_posix()
        except ValueError:  # another drive on Windows
            pass
    return urdf.as_posix()


def spec_to_toml(
    spec: RobotSpec,
    base_dir: str | Path | None = None,
    *,
    notes: Sequence[str] = (),
    urdf_limits: Mapping[str, tuple[float | None, float | None]] | None = None,
    shared_joints: Sequence[str] = (),
) -> str:
    """A commented TOML text that :func:`mobmanip.spec.load_spec` reads back to an equal spec.

    Args:
        spec: the spec to write.
        base_dir: directory the file will live in; the URDF path is written relative to it
            (absolute without it; ``example-robot-data:...`` for that package's robots).
        notes: remarks written as comments at the top.
        urdf_limits: ``{joint: (velocity, effort)}`` from the URDF, written as commented hints
            under ``[limits.*]`` (a missing one is flagged as required).
        shared_joints: joints shared by several arms; when they are not the torso, a commented
            ``torso = [...]`` line shows how to actuate them.
    """
    out = [f"# mobmanip robot spec for {spec.name!r}, inferred from its URDF; check it and edit as needed."]
    out += [f"# {note}" for note in notes]
    out += [
        f"name = {_string(spec.name)}",
        f"urdf = {_string(_urdf_reference(spec.urdf, None if base_dir is None else Path(base_dir)))}",
        f'platform = {_string(spec.platform)}  # "differential_drive", "fixed" or "omnidirectional"',
        f"default_task = {_string(spec.default_task)}  # planar, planar_rigid, translational or spatial",
    ]
    if spec.torso:
        out += ["", "# Actuated joints shared by all arms (after the platform in the reduced velocity).",
                f"torso = {json.dumps(list(spec.torso))}"]  # fmt: skip
    elif shared_joints:
        out += ["", "# Joints shared by the arms are locked (see [reference]); to actuate them:",
                f"# torso = {json.dumps(list(shared_joints))}"]  # fmt: skip
    if spec.wheels is not None:
        w = spec.wheels
        out += [
            "",
            "# Right and left drive wheel; radius and half-track are read from the URDF unless set.",
            "[wheels]",
        ]
        out += [f"right = {_string(w.right)}", f"left = {_string(w.left)}"]
        for key, value in (("radius", w.radius), ("half_track", w.half_track)):
            out.append(f"{key} = {_number(value)}" if value is not None else f"# {key} = ...  # m, overrides the URDF")
    out += ["", "# Arms in order (arm 1 first): actuated joints base to tip, then the end-effector frame."]
    for arm in spec.arms:
        out += [
            "[[arms]]",
            f"name = {_string(arm.name)}",
            f"joints = {json.dumps(list(arm.joints))}",
            f"end_effector = {_string(arm.end_effector)}",
            "",
        ]
    out += ["# The default held object.", "[object]", f"mass = {_number(spec.object_mass)}  # kg", ""]
    active = list(spec.active_joint_names)
    if spec.platform == "omnidirectional":
        active = list(OMNI_COORDINATES) + active
    for kind, table, unit in (
        ("velocity", spec.velocity_limits, "rad/s or m/s"),
        ("effort", spec.effort_limits, "N m or N"),
    ):
        out += [f"# Limit overrides by joint name ({unit}); without one, the URDF's value is used.", f"[limits.{kind}]"]
        for joint in active:
            if joint in table:
                out.append(f"{_key(joint)} = {_number(table[joint])}")
            elif joint in OMNI_COORDINATES:
                out.append(f"# {_key(joint)} = ...  # REQUIRED for an omnidirectional base")
            elif urdf_limits is not None and joint in urdf_limits:
                value = urdf_limits[joint][0 if kind == "velocity" else 1]
                if value is None:
                    out.append(f"# {_key(joint)} = ...  # REQUIRED: the URDF gives none")
                else:
                    out.append(f"# {_key(joint)} = {_number(value)}  # URDF value")
        out.append("")
    out += [
        "# Positions (rad or m) of the locked joints (others are locked at 0), and home positions",
        "# of moving joints whose range excludes 0.",
        "[reference]",
    ]
    out += [f"{_key(joint)} = {_number(value)}" for joint, value in spec.reference.items()]
    first = spec.arms[0].joints[0]
    out += [
        "",
        "# Optional: arm (and torso) positions of a posture in which the end effectors hold an",
        "# object together; `mobmanip sweep` starts its inverse kinematics from it (else from home).",
        "# [hold]",
        f"# {_key(first)} = 0.0",
    ]
    return "\n".join(out) + "\n"
