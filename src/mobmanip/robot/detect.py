"""Inferring a robot spec from a robot file alone: drive wheels, arms, torso and a TOML to edit.

:func:`spec_from_urdf` reads the file once (any registered format, see
:func:`mobmanip.descriptions.read_description`), looks at its structure and geometry and
returns a :class:`~mobmanip.robot.spec.RobotSpec` ready for :func:`mobmanip.robot.model.load_robot`;
:func:`spec_to_toml` writes any spec as a commented TOML file for the user to check and edit.

The rules:

- A *wheel candidate* is a continuous joint whose child link carries a cylinder about the joint
  axis or a sphere (:func:`mobmanip.platforms.wheels.wheel_radius`) and that lies on no arm's path
  (:func:`mobmanip.platforms.wheels.wheel_candidates`). Each wheeled platform kind of
  :data:`mobmanip.platforms.KINDS` says whether the candidates fit it (its ``detect``): e.g. a
  differential drive is two lateral wheels on no swivel, the right one with the smaller lateral
  (y) position in the root link's frame (forward = +x). Without an explicit platform the kind
  that fits is taken; none fitting means a fixed platform, and a kind that fits ambiguously
  raises :class:`~mobmanip.errors.WheelError` listing the candidates and what to add.
- An *arm* is the actuated (revolute, continuous, prismatic) joints on the path from the root
  link to the end-effector frame, drive wheels excluded (and no joint on such a path is taken
  for a drive wheel). Joints on the path of more than one arm (a
  torso lift, say) belong to no arm: they become the spec's ``torso`` (``torso=True``) or are
  locked (default), in both cases at mid-range (their home position when actuated).
- Every other joint is locked at zero, or at mid-range when zero is outside its limits; an
  arm or torso joint whose range excludes zero gets its mid-range as home position.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..descriptions import RobotDescription, check_supported, read_description
from ..descriptions.flaws import refuse
from ..descriptions.resources import (
    EXAMPLE_ROBOT_DATA_PREFIX,
    STRETCH_URDF_PREFIX,
    example_robot_data_share,
    stretch_urdf_dir,
)
from ..errors import FrameNotFoundError, JointNotFoundError, SpecError, WheelError
from ..platforms import KINDS, Detected, PlatformKind, WheelsSpec, get_kind
from ..platforms.omnidirectional import OMNI_COORDINATES
from ..platforms.wheels import WheelCandidate, wheel_candidates
from ..support.toml import toml_array, toml_comment, toml_key, toml_string
from .detect_report import Missing, choice_reason, explain_wheels, platform_reasons
from .spec import ArmSpec, RobotSpec
from .support_spec import DEFAULT_FACES, SupportSpec

__all__ = [
    "Detection",
    "WheelCandidate",
    "arm_joints",
    "detect_platform",
    "detect_spec",
    "parse_wheel_list",
    "spec_from_urdf",
    "spec_to_toml",
    "wheel_candidates",
]


@dataclass(frozen=True)
class Detection:
    """What :func:`detect_spec` found.

    Attributes:
        spec: the inferred spec.
        shared_joints: actuated joints on the path of more than one arm (torso or locked).
        notes: one-line remarks for the user (written as comments by ``init-spec``).
        urdf_limits: ``{joint: (velocity, effort)}`` from the URDF for every active joint.
        considered: what detection looked at and why it chose the platform kind: every
            wheel-like joint and what became of it, each wheeled kind's verdict, the choice.
        missing: values the spec still needs (wheel radii, limits), with the flags that give
            them; empty when the spec loads as it is.
        source_format: how messages name the robot file's format (``"URDF"``, ``"MJCF"``,
            ``"xacro"``), for :func:`spec_to_toml`'s ``source_format``.
    """

    spec: RobotSpec
    shared_joints: tuple[str, ...]
    notes: tuple[str, ...]
    urdf_limits: Mapping[str, tuple[float | None, float | None]]
    considered: tuple[str, ...] = ()
    missing: tuple[Missing, ...] = ()
    source_format: str = "URDF"


#: How messages name a robot file of each format of :mod:`mobmanip.descriptions`.
FORMAT_NAMES = {"urdf": "URDF", "mjcf": "MJCF", "xacro": "xacro"}


def _source(source_format: str) -> str:
    """``"the URDF"``, ``"the MJCF file"``: the robot file in a message."""
    return "the URDF" if source_format == "URDF" else f"the {source_format} file"


def detect_platform(
    description: RobotDescription, candidates: Sequence, path: str | Path = "URDF"
) -> tuple[PlatformKind, Detected | None]:
    """The platform kind the wheel candidates fit, and what it found (``None``: fixed).

    Every wheeled kind of :data:`mobmanip.platforms.KINDS` is asked; exactly one must fit.

    Raises:
        WheelError: no kind fits but one fits ambiguously (its message says what to add), or
            several kinds fit (the message lists them; choose with ``--platform``).
    """
    found, errors = [], []
    for kind in KINDS.values():
        if not kind.takes_wheels:
            continue
        try:
            detected = kind.detect(description, candidates, str(path))
        except WheelError as exc:
            errors.append(exc)
            continue
        if detected is not None:
            found.append((kind, detected))
    if len(found) == 1:
        return found[0]
    if len(found) > 1:
        raise WheelError(
            f"{path}: the wheels fit several platform kinds ({', '.join(k.name for k, _ in found)}); "
            "choose one with --platform"
        )
    if errors:
        raise errors[0]
    return KINDS["fixed"], None


def _frame_link(description: RobotDescription, frame: str, path: str | Path) -> str:
    """The link whose path from the root carries ``frame`` (a link, or a joint's child link)."""
    link = description.frame_link(frame)
    if link is None:
        raise FrameNotFoundError(frame, description.frame_names, where=str(path))
    return link


def arm_joints(
    description: RobotDescription, end_effector: str, exclude: Iterable[str] = (), path: str | Path = "URDF"
) -> list[str]:
    """The actuated joints from the root link to ``end_effector``, root first.

    Args:
        description: the robot file as read.
        end_effector: a link (or joint) name.
        exclude: joints to leave out (the wheels).
        path: the URDF's path, for messages.

    Raises:
        FrameNotFoundError: unknown frame (the message lists existing frames, closest first).
    """
    link = _frame_link(description, end_effector, path)
    exclude = set(exclude)
    return [j.name for j in description.chain(link) if j.moves and j.name not in exclude]


def _arm_name(end_effector: str, k: int, taken: set[str]) -> str:
    tokens = set(re.split(r"[^a-z]+", end_effector.lower()))
    sides = [s for s in ("right", "left") if s in tokens]
    name = sides[0] if len(sides) == 1 else f"arm{k + 1}"
    return name if name not in taken else f"arm{k + 1}"


def _mid_range(description: RobotDescription, name: str) -> float | None:
    """Mid-range of a joint with finite position limits, else ``None``."""
    joint = description.joints[name]
    limit = joint.limits
    if joint.type == "continuous" or limit is None or limit.lower is None or limit.upper is None:
        return None
    lower, upper = float(limit.lower), float(limit.upper)
    if not (math.isfinite(lower) and math.isfinite(upper)) or upper < lower:
        return None
    return 0.5 * (lower + upper)


def _excludes_zero(description: RobotDescription, name: str) -> bool:
    joint = description.joints[name]
    limit = joint.limits
    if joint.type not in ("revolute", "prismatic") or limit is None or limit.lower is None or limit.upper is None:
        return False
    return not (float(limit.lower) <= 0.0 <= float(limit.upper))


def _planar(description: RobotDescription, joints: Iterable[str]) -> bool:
    """Whether every joint moves in the horizontal plane (revolute about z, prismatic along x-y)."""
    for name in joints:
        joint = description.joints[name]
        axis = description.axis_in_root(name)
        vertical = abs(float(axis[2])) >= 1.0 - 1e-9
        if joint.type == "prismatic" and abs(float(axis[2])) > 1e-9:
            return False
        if joint.type != "prismatic" and not vertical:
            return False
    return True


def detect_spec(
    path: str | Path,
    end_effectors: Sequence[str],
    wheels: tuple[str, ...] | None = None,
    platform: str | None = None,
    *,
    torso: bool = False,
    name: str | None = None,
    default_task: str | None = None,
    wheel_radius: float | None = None,
    wheel_limits: tuple[float | None, float | None] = (None, None),
    limits: Mapping[str, tuple[float | None, float | None]] | None = None,
    strict: bool = False,
    read_options: Mapping[str, Any] | None = None,
) -> Detection:
    """Infer a spec from a robot file; see the module docstring for the rules.

    Args:
        path: the robot file (a URDF, or any format :func:`mobmanip.descriptions.read_description` reads).
        end_effectors: one end-effector frame per arm, arm 1 first (link or joint names).
        wheels: the platform's wheel joints (for a differential drive ``(right, left)``), to
            skip wheel detection.
        platform: a kind of :data:`mobmanip.platforms.KINDS`; ``None`` means the wheeled kind
            the URDF's wheels fit (a differential drive when wheels are given), else fixed.
        torso: make the joints shared by several arms the spec's torso (else lock them).
        name: robot name (default: the URDF's robot name).
        default_task: task space (default: ``"planar"`` if every arm joint moves in the
            horizontal plane, else ``"spatial"``).
        wheel_radius: radius (m) of wheels known by their name only (mesh geometry); written
            as the spec's ``[wheels] radius``.
        wheel_limits: ``(velocity, effort)`` for each of the platform's wheel coordinates the
            URDF gives no limit (``None``: leave it to the URDF).
        limits: ``{joint: (velocity, effort)}`` overrides of any active joint's limits.
        strict: refuse the file's flaws (see :mod:`mobmanip.descriptions.flaws`) and write
            ``strict = true``; else each is noted (it is repaired, with a warning, at load).
        read_options: handed to :func:`mobmanip.descriptions.read_description` (e.g. a xacro
            file's ``xacro_args`` and ``package_dirs``); written into the spec where a spec key
            holds them.

    Raises:
        UrdfError: unreadable URDF, unsupported construct, or a mimic joint on an arm (for
            another format, its :class:`~mobmanip.errors.DescriptionError`).
        FrameNotFoundError: unknown end-effector frame.
        JointNotFoundError: an explicit wheel joint that does not exist.
        WheelError: ambiguous or unusable drive wheels.
        SpecError: no end effector, an end effector no joint moves, or an unknown platform.
    """
    path = Path(path)
    read_options = dict(read_options or {})
    description = _read_checked(path, read_options, strict, platform)
    end_effectors = list(end_effectors)
    if not end_effectors:
        raise SpecError(f"{path}: name at least one end-effector frame")
    notes = _description_notes(description)
    candidates, on_arms = _wheels_off_the_arms(description, end_effectors, wheel_radius, path)
    kind, wheel_spec = _choose_platform(description, candidates, wheels, platform, path, notes)
    drive = set(wheels or ()) | set(wheel_spec.joint_names if wheel_spec is not None else ())
    how = "wheels" if wheels is not None else ("platform" if platform is not None else "detected")
    support, contacts = _drive_unit_contacts(description, candidates, kind, drive, notes)
    considered = _considered(description, candidates, kind, drive, on_arms, how, path, contacts)
    wheel_spec, unmeasured = _given_radius(wheel_spec, wheel_radius, candidates, drive)
    extra = [c.name for c in candidates if c.name not in drive]
    if extra and kind.takes_wheels:
        notes.append(f"wheel-like joints that are not platform wheels are locked: {', '.join(extra)}")

    arms, shared = _arms(description, end_effectors, drive, path)
    torso_joints = shared if torso else ()
    active = set(torso_joints) | {j for arm in arms for j in arm.joints}
    if wheel_spec is not None:
        active |= set(wheel_spec.joint_names)
    reference = _reference(description, shared)
    if shared:
        if torso:
            notes.append(f"joints shared by several arms form the torso: {', '.join(shared)}")
        else:
            notes.append(f"joints shared by several arms are locked at mid-range: {', '.join(shared)}")
    if default_task is None:
        default_task = "planar" if _planar(description, active - drive) else "spatial"

    urdf_limits, given_v, given_e = _limits(description, kind, wheel_spec, active, wheel_limits, limits)
    postures = _keyframe_postures(description, torso_joints + tuple(j for arm in arms for j in arm.joints), notes)
    spec = RobotSpec(
        name=name or description.name or path.stem,
        urdf=path.resolve(),
        platform=kind.name,
        arms=tuple(arms),
        wheels=wheel_spec,
        default_task=default_task,
        reference=reference,
        torso=torso_joints,
        postures=postures,
        velocity_limits=given_v,
        effort_limits=given_e,
        package_dirs=(path.resolve().parent,),
        strict=strict,
        xacro_args=read_options.get("xacro_args") or {},
        package_paths=tuple(Path(p).resolve() for p in read_options.get("package_paths") or ()),
        support=support,
    )
    missing = _missing(spec, kind, urdf_limits, unmeasured)
    source_format = FORMAT_NAMES.get(description.format, description.format)
    notes += _platform_limits_notes(description, kind, wheel_spec, source_format)
    return Detection(
        spec=spec,
        shared_joints=shared,
        notes=tuple(notes),
        urdf_limits=urdf_limits,
        considered=tuple(considered),
        missing=tuple(missing),
        source_format=source_format,
    )


def _read_checked(path: Path, read_options: Mapping[str, Any], strict: bool, platform: str | None) -> RobotDescription:
    """The robot file as read, checked before any detection: its flaws refused when ``strict``,
    a construct mobmanip does not support refused, and the ``platform`` asked for a known kind.

    Raises:
        UrdfError: as :func:`detect_spec` (another format: its own
            :class:`~mobmanip.errors.DescriptionError`).
        SpecError: an unknown platform kind (the message lists the known ones).
    """
    description = read_description(path, **read_options)
    if strict:
        refuse(description.flaws, description.error)
    check_supported(description)
    if platform is not None:
        get_kind(platform)  # an unknown kind is a SpecError listing the known ones
    return description


def _description_notes(description: RobotDescription) -> list[str]:
    """The notes every detection starts with: the platform's frame, what reading the file
    remarked, and each flaw that is repaired at load."""
    notes: list[str] = [f"platform frame: root link {description.root_link!r} (forward = +x, left = +y)"]
    notes += [f"{description.format}: {note}" for note in description.notes]
    notes += [flaw.note for flaw in description.flaws]
    return notes


def _wheels_off_the_arms(
    description: RobotDescription, end_effectors: Sequence[str], wheel_radius: float | None, path: Path
) -> tuple[list[WheelCandidate], dict[str, str]]:
    """The wheel candidates that lie on no arm's path, and the wheel-like joints that do (joint
    -> the end effector whose path holds it), ``wheel_radius`` (m) given to wheels known by
    name only.

    Raises:
        FrameNotFoundError: an unknown end-effector frame.
    """
    on_arm_paths = {j: ee for ee in end_effectors for j in arm_joints(description, ee, (), path)}
    candidates = wheel_candidates(description, exclude=on_arm_paths, radius=wheel_radius)
    on_arms = {
        c.name: on_arm_paths[c.name]
        for c in wheel_candidates(description, radius=wheel_radius)
        if c.name in on_arm_paths
    }
    return candidates, on_arms


def _choose_platform(
    description: RobotDescription,
    candidates: Sequence[WheelCandidate],
    wheels: tuple[str, ...] | None,
    platform: str | None,
    path: Path,
    notes: list[str],
) -> tuple[PlatformKind, WheelsSpec | None]:
    """The platform kind and its wheels (``None``: none the spec names), from the wheels given
    (a differential drive's unless ``platform`` says otherwise), from the platform given, from
    the file's planar base joints, or detected among the ``candidates``; what was chosen is
    said in ``notes``.

    Raises:
        JointNotFoundError: a given wheel joint that does not exist.
        WheelError: wheels that do not fit, none of the given platform's found, or several kinds
            that fit (:func:`detect_platform`).
    """
    wheel_spec: WheelsSpec | None = None
    if wheels is not None:
        for joint in wheels:
            if joint not in description.joints:
                raise JointNotFoundError(joint, description.joints, where=str(path))
        kind = get_kind(platform or "differential_drive")
        given = (kind if kind.takes_wheels else KINDS["differential_drive"]).wheels_from_joints(tuple(wheels))
        if kind.takes_wheels:
            wheel_spec = given
            notes.append(f"{kind.name} wheels: {', '.join(given.joint_names)}")
        else:
            notes.append(f"platform {kind.name!r}: wheels {', '.join(given.joint_names)} are locked")
    elif platform is None and description.planar_base:
        kind = KINDS["omnidirectional"]
        names = ", ".join(j.name for j in description.planar_base)
        notes.append(f"platform omnidirectional: the file moves its root link on planar joints ({names})")
    elif platform is None:
        kind, detected = detect_platform(description, candidates, path)
        if detected is not None:
            wheel_spec = detected.wheels
            notes.extend(detected.notes)
    else:
        kind = get_kind(platform)
        if kind.takes_wheels:
            detected = kind.detect(description, candidates, str(path))
            if detected is None:
                listed = ", ".join(c.describe() for c in candidates) or "none"
                raise WheelError(
                    f"{path}: no wheels of a {kind.name} platform found (wheel-shaped continuous joints: {listed}); "
                    "name them with --wheels or choose another platform"
                )
            wheel_spec = detected.wheels
            notes.extend(detected.notes)
    return kind, wheel_spec


def _drive_unit_contacts(
    description: RobotDescription,
    candidates: Sequence[WheelCandidate],
    kind: PlatformKind,
    drive: set[str],
    notes: list[str],
) -> tuple[SupportSpec | None, dict[str, int]]:
    """The spec's ``[support]`` of a base with no wheel joints of its own (``omnidirectional``:
    a file that moves its base on planar joints, the mobile FR3 Duo) that stands on steered drive
    units: one driven contact (``[support] wheels``) per unit, below its wheel's centre by the
    radius, in the root frame (m). A steered unit pushes the floor in any direction (it steers,
    then drives), so the rows have no rollers. The casters beside them (a wheel on a swivel that
    trails it) are passive supports: the floor model takes those whose link is named like a
    caster; the others are written as ``[support] casters`` rows, below their centres likewise.

    Returns:
        The table (``None`` when there is no unit) and each unit's wheel joint -> its row.
    """
    if kind.name != "omnidirectional":
        return None, {}

    def floor(c: WheelCandidate) -> tuple[float, float, float]:
        x, y, z = (float(v) for v in c.position)
        return round(x, 9), round(y, 9), round(z - float(c.radius or 0.0), 9)

    def rolling(c: WheelCandidate) -> bool:
        return c.name not in drive and c.radius is not None and abs(float(c.axis[2])) < 1e-6

    units = [c for c in candidates if c.steered_unit and rolling(c)]
    if not units:
        return None, {}
    casters = [c for c in candidates if c.steering_joint and not c.steered_unit and rolling(c)]
    unnamed = [c for c in casters if "caster" not in description.joints[c.name].child.lower()]
    named = [description.joints[c.name].child for c in casters if c not in unnamed]
    parts = [
        "the base's floor contacts: its steered drive units "
        + ", ".join(f"{c.steering_joint}/{c.name}" for c in units)
        + " as [support] wheels (driven: the base's efforts are their traction)"
    ]
    if named:
        parts.append(f"the casters {', '.join(named)} (found by their names)")
    if unnamed:
        parts.append(f"the casters of {', '.join(c.name for c in unnamed)} as [support] casters")
    notes.append("; ".join(parts))
    support = SupportSpec(wheels=tuple(floor(c) for c in units), casters=tuple(floor(c) for c in unnamed))
    return support, {c.name: k for k, c in enumerate(units)}


def _considered(
    description: RobotDescription,
    candidates: Sequence[WheelCandidate],
    kind: PlatformKind,
    drive: set[str],
    on_arms: Mapping[str, str],
    how: str,
    path: Path,
    contacts: Mapping[str, int] | None = None,
) -> list[str]:
    """What detection looked at and why it chose ``kind`` (:attr:`Detection.considered`): every
    wheel-like joint and what became of it (``contacts``: the ones whose floor contact is a row of
    ``[support] wheels``), each wheeled kind's verdict when the kind was detected (``how``:
    ``"wheels"``, ``"platform"`` or ``"detected"``), and the choice."""
    considered = explain_wheels(description, candidates, drive if kind.takes_wheels else (), on_arms, contacts)
    if candidates and how == "detected":
        considered += platform_reasons(description, candidates, str(path))
    considered.append(choice_reason(kind.name, how, candidates))
    return considered


def _given_radius(
    wheel_spec: WheelsSpec | None, wheel_radius: float | None, candidates: Sequence[WheelCandidate], drive: set[str]
) -> tuple[WheelsSpec | None, list[str]]:
    """The platform's wheels with the ``wheel_radius`` given (m), for a kind whose wheels have
    one, and the ``drive`` wheels whose radius is still unknown (mesh geometry, no radius given)."""
    unmeasured = [c.name for c in candidates if c.radius is None and c.name in drive]
    if wheel_spec is not None and wheel_radius is not None and hasattr(wheel_spec, "radius"):
        # kinds with a radius (checked just above); mypy sees only the base class
        wheel_spec = dataclasses.replace(wheel_spec, radius=float(wheel_radius))  # type: ignore[call-arg]
        unmeasured = []
    return wheel_spec, unmeasured


def _arms(
    description: RobotDescription, end_effectors: Sequence[str], drive: set[str], path: Path
) -> tuple[list[ArmSpec], tuple[str, ...]]:
    """One arm per end effector, and the joints shared by several arms' paths.

    Each arm is the actuated joints on its path from the root link, the ``drive`` wheels and
    the shared joints left out, named after its side when the end effector's name says one.

    Raises:
        SpecError: an end effector that no joint of its own moves.
        UrdfError: a mimic joint on an arm's path (another format: its own
            :class:`~mobmanip.errors.DescriptionError`).
    """
    paths = [arm_joints(description, ee, drive, path) for ee in end_effectors]
    counts: dict[str, int] = {}
    for joints in paths:
        for joint in joints:
            counts[joint] = counts.get(joint, 0) + 1
    shared = tuple(j for j in dict.fromkeys(j for p in paths for j in p) if counts[j] > 1)
    mimics = description.mimics
    arms: list[ArmSpec] = []
    taken: set[str] = set()
    for k, (ee, joints) in enumerate(zip(end_effectors, paths)):
        own = tuple(j for j in joints if j not in shared)
        if not own:
            raise SpecError(
                f"{path}: end-effector frame {ee!r} is moved by no joint of its own"
                + (f" (only by the shared joints {', '.join(shared)})" if shared else "")
            )
        for joint in own + shared:
            if joint in mimics:
                raise description.error(
                    f"joint {joint!r} on the path to {ee!r} mimics {mimics[joint]!r}; "
                    "mimic joints cannot be actuated here (pick an end-effector frame before it)"
                )
        arm_name = _arm_name(ee, k, taken)
        taken.add(arm_name)
        arms.append(ArmSpec(name=arm_name, joints=own, end_effector=ee))
    return arms, shared


def _reference(description: RobotDescription, shared: Sequence[str]) -> dict[str, float]:
    """The spec's ``[reference]``: the ``shared`` joints (a torso, locked or home) at mid-range,
    and every other moving joint whose range excludes zero at its mid-range."""
    reference: dict[str, float] = {}
    for joint in description.moving_joints():
        mid = _mid_range(description, joint.name)
        if joint.name in shared and mid is not None:
            reference[joint.name] = mid  # the torso, locked or home: mid-height
        elif _excludes_zero(description, joint.name) and mid is not None:
            reference[joint.name] = mid
    return reference


def _limits(
    description: RobotDescription,
    kind: PlatformKind,
    wheel_spec: WheelsSpec | None,
    active: set[str],
    wheel_limits: tuple[float | None, float | None],
    limits: Mapping[str, tuple[float | None, float | None]] | None,
) -> tuple[dict[str, tuple[float | None, float | None]], dict, dict]:
    """The file's limits and the spec's overrides.

    Args:
        description: the robot file as read; ``kind`` and ``wheel_spec`` its platform.
        active: the spec's active joints (arms, torso, wheels).
        wheel_limits, limits: as :func:`detect_spec`'s.

    Returns:
        ``(file_limits, velocity, effort)``: ``{name: (velocity, effort)}`` from the file for every
        active joint and platform coordinate (``None`` where it gives none), and the spec's
        velocity and effort overrides by name.
    """
    urdf_limits = {j: description.limits(j) for j in sorted(active)}
    urdf_limits.update(kind.description_limits(wheel_spec, description))
    wheel_names = set(kind.description_limits(wheel_spec, description)) | set(
        wheel_spec.joint_names if wheel_spec else ()
    )
    platform_limits = {n: pair for n, pair in urdf_limits.items() if n in wheel_names}
    if kind.name == "omnidirectional" and len(description.planar_base) == 3:
        # the file's own base joints give the base's limits, unless the command line does
        base = {name: (j.velocity_limit, j.effort_limit) for name, j in zip(OMNI_COORDINATES, description.planar_base)}
        limits = {**base, **(limits or {})}
    given_v, given_e = _given_limits(platform_limits, wheel_limits, limits or {})
    return urdf_limits, given_v, given_e


def _platform_limits_notes(
    description: RobotDescription, kind: PlatformKind, wheel_spec: WheelsSpec | None, source_format: str
) -> list[str]:
    """A note naming the platform coordinates that need limits the robot file does not give
    (none when it gives them all)."""
    needed = [name for name, _ in kind.toml_limit_hints(wheel_spec)]
    needed += [name for name, pair in kind.description_limits(wheel_spec, description).items() if None in pair]
    if not needed:
        return []
    return [
        f"a {kind.name} platform needs limits for {', '.join(needed)} in [limits.velocity] and "
        f"[limits.effort] ({_source(source_format)} gives none)"
    ]


def _keyframe_postures(
    description: RobotDescription, joints: Sequence[str], notes: list[str]
) -> dict[str, dict[str, float]]:
    """The file's keyframes as the spec's ``[postures.NAME]``: each one's positions of ``joints``
    (the arm and torso joints, the only ones a posture sets).

    A keyframe named like a posture mobmanip reserves (``home``, ``hold``) is offered as
    ``keyframe_NAME``; one that sets none of ``joints`` is left out. Each is said in ``notes``.
    """
    out: dict[str, dict[str, float]] = {}
    for name, values in description.keyframes.items():
        posture = f"keyframe_{name}" if name in ("home", "hold") else name
        kept = {joint: float(values[joint]) for joint in joints if joint in values}
        if not kept or posture in out:
            why = "sets no arm or torso joint" if not kept else f"would be a second [postures.{posture}]"
            notes.append(f"keyframe {name!r} {why}: not offered as a posture")
            continue
        outside = [
            joint
            for joint, value in kept.items()
            if (limit := description.joints[joint].limits) is not None
            and description.joints[joint].type != "continuous"
            and (
                (limit.lower is not None and value < limit.lower - 1e-9)
                or (limit.upper is not None and value > limit.upper + 1e-9)
            )
        ]
        out[posture] = kept
        reserved = f" (mobmanip's {name!r} is its own)" if posture != name else ""
        warn = f"; outside their ranges: {', '.join(outside)}" if outside else ""
        notes.append(f"keyframe {name!r} is [postures.{posture}]{reserved}: its arm and torso joints{warn}")
    return out


def _given_limits(platform_limits, wheel_limits, limits) -> tuple[dict, dict]:
    """Spec limit overrides from the command line: the wheel values for every platform
    coordinate whose URDF limit is missing, then explicit ones by name."""
    velocity, effort = {}, {}
    for name, (vel, eff) in platform_limits.items():
        if vel is None and wheel_limits[0] is not None:
            velocity[name] = float(wheel_limits[0])
        if eff is None and wheel_limits[1] is not None:
            effort[name] = float(wheel_limits[1])
    for name, (vel, eff) in limits.items():
        if vel is not None:
            velocity[name] = float(vel)
        if eff is not None:
            effort[name] = float(eff)
    return velocity, effort


def _missing(spec: RobotSpec, kind: PlatformKind, urdf_limits, unmeasured) -> list[Missing]:
    """What the spec still lacks, grouped, with the flags that give it."""
    out = []
    if unmeasured:
        out.append(Missing("wheel radius (mesh geometry)", tuple(unmeasured), "--wheel-radius M"))
    platform_names = set(kind.limit_names(spec.wheels)) | set(spec.wheel_joint_names)
    for what, table, index, wheel_flag, flag in (
        ("velocity limit", spec.velocity_limits, 0, "--wheel-velocity-limit RAD_S", "--velocity-limit NAME=V"),
        ("effort limit", spec.effort_limits, 1, "--wheel-effort-limit NM", "--effort-limit NAME=E"),
    ):
        hinted = [name for name, _ in kind.toml_limit_hints(spec.wheels) if name not in table]
        lacking = [
            name
            for name, pair in urdf_limits.items()
            if pair[index] is None and name not in table and name not in hinted
        ]
        wheels = [n for n in lacking if n in platform_names]
        others = [n for n in lacking if n not in platform_names] + hinted
        if wheels:
            out.append(Missing(what, tuple(wheels), wheel_flag))
        if others:
            out.append(Missing(what, tuple(others), flag))
    return out


def spec_from_urdf(
    path: str | Path,
    end_effectors: Sequence[str],
    wheels: tuple[str, ...] | None = None,
    platform: str | None = None,
    **options: Any,
) -> RobotSpec:
    """The spec :func:`detect_spec` infers (same arguments), without the notes."""
    return detect_spec(path, end_effectors, wheels, platform, **options).spec


def parse_wheel_list(text: str) -> tuple[str, ...]:
    """``"RIGHT,LEFT"`` -> ``("RIGHT", "LEFT")``: comma-separated wheel joint names.

    How many a platform takes, and in which order, is the platform kind's to say.

    Raises:
        WheelError: an empty name.
    """
    parts = tuple(p.strip() for p in str(text).split(","))
    if not all(parts):
        raise WheelError(f"wheels must be given as comma-separated joint names (e.g. RIGHT,LEFT), got {text!r}")
    return parts


# ----- writing a spec as TOML -----


def _key(name: str) -> str:
    return toml_key(name)


def _string(value: str) -> str:
    return toml_string(value)


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
    try:
        return STRETCH_URDF_PREFIX + urdf.relative_to(stretch_urdf_dir().resolve()).as_posix()
    except (ValueError, SpecError):
        pass
    if base_dir is not None:
        try:
            return Path(os.path.relpath(urdf, Path(base_dir).resolve())).as_posix()
        except ValueError:  # another drive on Windows
            pass
    return urdf.as_posix()


def _folder_reference(folder: Path, base_dir: Path | None) -> str:
    """A folder as the spec names it: relative to ``base_dir`` when given, else absolute."""
    folder = Path(folder).resolve()
    if base_dir is not None:
        try:
            return Path(os.path.relpath(folder, Path(base_dir).resolve())).as_posix()
        except ValueError:  # another drive on Windows
            pass
    return folder.as_posix()


def spec_to_toml(
    spec: RobotSpec,
    base_dir: str | Path | None = None,
    *,
    notes: Sequence[str] = (),
    urdf_limits: Mapping[str, tuple[float | None, float | None]] | None = None,
    shared_joints: Sequence[str] = (),
    source_format: str = "URDF",
) -> str:
    """A commented TOML text that :func:`mobmanip.robot.spec.load_spec` reads back to an equal spec.

    Args:
        spec: the spec to write.
        base_dir: directory the file will live in; the URDF path is written relative to it
            (absolute without it; ``example-robot-data:...`` for that package's robots).
        notes: remarks written as comments at the top.
        urdf_limits: ``{joint: (velocity, effort)}`` from the URDF, written as commented hints
            under ``[limits.*]`` (a missing one is flagged as required).
        shared_joints: joints shared by several arms; when they are not the torso, a commented
            ``torso = [...]`` line shows how to actuate them.
        source_format: how the comments name the robot file's format (``"URDF"``, ``"MJCF"``,
            ``"xacro"``: :attr:`Detection.source_format`).
    """
    head = f"# mobmanip robot spec for {spec.name!r}, inferred from its robot file; check it and edit as needed."
    out = [toml_comment(head)]
    out += [toml_comment(f"# {note}") for note in notes]
    out += [
        f"name = {_string(spec.name)}",
        f"urdf = {_string(_urdf_reference(spec.urdf, None if base_dir is None else Path(base_dir)))}",
        f"platform = {_string(spec.platform)}  # {', '.join(json.dumps(k) for k in KINDS)}",
        f"default_task = {_string(spec.default_task)}  # planar, planar_rigid, translational or spatial",
    ]
    if spec.strict:
        out.append("strict = true  # refuse the robot file's flaws instead of repairing them")
    if spec.accepted_repairs:
        out.append(f"accepted_repairs = {toml_array(spec.accepted_repairs)}  # repaired without a warning")
    if spec.package_paths:
        folders = [_folder_reference(p, None if base_dir is None else Path(base_dir)) for p in spec.package_paths]
        out.append(f"package_paths = {toml_array(folders)}  # where $(find PKG) and package:// look first")

    if spec.torso:
        out += ["", "# Actuated joints shared by all arms (after the platform in the reduced velocity).",
                f"torso = {toml_array(spec.torso)}"]  # fmt: skip
    elif shared_joints:
        out += ["", "# Joints shared by the arms are locked (see [reference]); to actuate them:",
                f"# torso = {toml_array(shared_joints)}"]  # fmt: skip
    kind = get_kind(spec.platform)
    if spec.wheels is not None:
        out += ["", *kind.toml_lines(spec.wheels)]
    out += ["", "# Arms in order (arm 1 first): actuated joints base to tip, then the end-effector frame."]
    for arm in spec.arms:
        out += [
            "[[arms]]",
            f"name = {_string(arm.name)}",
            f"joints = {toml_array(arm.joints)}",
            f"end_effector = {_string(arm.end_effector)}",
            "",
        ]
    out += ["# The default held object.", "[object]", f"mass = {_number(spec.object_mass)}  # kg"]
    if spec.grasp_offsets:
        rows = ", ".join("[" + ", ".join(_number(v) for v in row) + "]" for row in spec.grasp_offsets)
        out.append(f"grasp_offsets = [{rows}]  # m, where each arm grasps it, from its centre")
    out.append("")
    hints = dict(kind.toml_limit_hints(spec.wheels))
    joints = [j for j in spec.active_joint_names if kind.limits_by_joint or j not in spec.wheel_joint_names]
    active = list(kind.limit_names(spec.wheels)) + joints
    for kind, table, unit in (
        ("velocity", spec.velocity_limits, "rad/s or m/s"),
        ("effort", spec.effort_limits, "N m or N"),
    ):
        out += [
            f"# Limit overrides by joint name ({unit}); without one, {_source(source_format)}'s value is used.",
            f"[limits.{kind}]",
        ]
        for joint in active:
            if joint in table:
                out.append(f"{_key(joint)} = {_number(table[joint])}")
            elif joint in hints:
                out.append(f"# {_key(joint)} = ...  # {hints[joint]}")
            elif urdf_limits is not None and joint in urdf_limits:
                value = urdf_limits[joint][0 if kind == "velocity" else 1]
                if value is None:
                    out.append(f"# {_key(joint)} = ...  # REQUIRED: {_source(source_format)} gives none")
                else:
                    out.append(f"# {_key(joint)} = {_number(value)}  # {source_format} value")
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
        "# object together (`--posture hold`); `mobmanip sweep` starts its inverse kinematics from",
        "# it (else from home).",
    ]
    if spec.hold:
        out += ["[hold]", *(f"{_key(joint)} = {_number(value)}" for joint, value in spec.hold.items())]
    else:
        out += ["# [hold]", f"# {_key(first)} = 0.0"]
    for posture, joints in spec.postures.items():
        out += ["", toml_comment(f"# Posture {posture!r} (`--posture {posture}`)."), f"[postures.{_key(posture)}]"]
        out += [f"{_key(joint)} = {_number(value)}" for joint, value in joints.items()]
    if spec.support is not None:
        out += ["", *_support_lines(spec.support)]
    if spec.xacro_args:
        out += ["", "# The xacro file's $(arg NAME) values.", "[xacro_args]"]
        out += [f"{_key(name)} = {_string(value)}" for name, value in spec.xacro_args.items()]
    return "\n".join(out) + "\n"


def _rows(rows: Sequence[Sequence[float]]) -> str:
    return "[" + ", ".join("[" + ", ".join(_number(v) for v in row) + "]" for row in rows) + "]"


def _support_lines(support: SupportSpec) -> list[str]:
    """The spec's ``[support]`` table: every key whose value is not the default."""
    out = ["# Where the robot touches the floor (analyze --ground; see mobmanip.robot.support).", "[support]"]
    if support.mu is not None:
        out.append(f"mu = {_number(support.mu)}")
    if support.faces != DEFAULT_FACES:
        out.append(f"faces = {support.faces}")
    if not support.urdf_casters:
        out.append("urdf_casters = false")
    if support.casters:
        out.append(f"casters = {_rows(support.casters)}  # passive supports (m, root frame)")
    if support.wheels:
        out.append(f"wheels = {_rows(support.wheels)}  # driven contacts (m, root frame)")
    if support.rollers:
        out.append(f"rollers = [{', '.join(_number(v) for v in support.rollers)}]  # deg")
    if support.stiffness:
        out += ["", "[support.stiffness]", *(f"{_key(k)} = {_number(v)}" for k, v in support.stiffness.items())]
    return out
