"""Wheels as the platform kinds see them: candidates in a robot's description, geometry in a
loaded model.

Shared by the wheeled kinds for detection (:func:`wheel_candidates`, from the shapes and tree of
a :class:`~mobmanip.descriptions.RobotDescription`) and for reading their geometry once the
Pinocchio model exists (:func:`wheel_geometry`).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..descriptions import RobotDescription
from ..errors import WheelError
from .base import positive_length

#: |cos| between a wheel axis and the platform's lateral axis above which the wheel counts as
#: lateral (rolling along the platform's x axis).
LATERAL = 0.99

#: A continuous joint (or its child link) whose name matches this is named like a wheel.
WHEEL_NAME = re.compile(r"wheel", re.IGNORECASE)

#: m: a wheel whose centre lies this close to its steering joint's axis is on it (a steered
#: drive unit); farther, the swivel trails it (a caster).
ON_AXIS = 1e-6


def named_like_wheel(description: RobotDescription, joint_name: str) -> bool:
    """Whether a joint or its child link is named like a wheel (contains "wheel")."""
    joint = description.joints[joint_name]
    return bool(WHEEL_NAME.search(joint.name) or WHEEL_NAME.search(joint.child))


def wheel_shape(description: RobotDescription, joint_name: str) -> tuple[str, float] | None:
    """The wheel shape of a joint's child link: ``("cylinder", r)`` for a cylinder about the
    joint axis, ``("sphere", r)``, from its collision (preferred) or visual shapes; ``None``
    when it carries neither (e.g. only meshes). ``r`` in m."""
    joint = description.joints[joint_name]
    link = description.links[joint.child]
    axis = joint.unit_axis
    for shapes in (link.collisions, link.visuals):
        for shape in shapes:
            if shape.kind == "cylinder" and shape.radius is not None:
                cylinder_axis = shape.origin.rotation[:, 2]
                if abs(abs(float(cylinder_axis @ axis)) - 1.0) < 1e-6:
                    return "cylinder", float(shape.radius)
            elif shape.kind == "sphere" and shape.radius is not None:
                return "sphere", float(shape.radius)
    return None


def wheel_radius(description: RobotDescription, joint_name: str) -> float | None:
    """Radius (m) of a wheel from its link's collision (preferred) or visual shapes: a cylinder
    whose axis is parallel to the joint axis, or a sphere; ``None`` when it carries no such shape."""
    shape = wheel_shape(description, joint_name)
    return None if shape is None else shape[1]


@dataclass(frozen=True)
class WheelCandidate:
    """A continuous joint whose child link is wheel-shaped, or named like a wheel.

    Attributes:
        name: joint name.
        radius: wheel radius (m): from the geometry, or given (``--wheel-radius``) for a wheel
            known by its name only; ``None`` when neither gives one.
        position: joint origin in the root link's frame at the zero configuration (m), (3,).
        axis: joint axis in the root link's frame, (3,).
        carried_by_rotating_joint: whether a revolute/continuous joint lies between it and the root.
        driven: whether the URDF gives it a positive effort limit.
        steering_joint: the nearest revolute/continuous joint above it with a vertical axis
            (a steering or caster swivel), or ``None``.
        steering_offset: with a steering joint, the wheel centre's distance from that joint's
            axis (m): within :data:`ON_AXIS`, the joint steers the wheel about its own centre (a
            steered drive unit); farther, the swivel trails it (a caster). ``None`` without one.
    """

    name: str
    radius: float | None
    position: np.ndarray
    axis: np.ndarray
    carried_by_rotating_joint: bool
    driven: bool
    steering_joint: str | None = None
    shape: str = "cylinder"
    steering_offset: float | None = None

    @property
    def steered_unit(self) -> bool:
        """Whether it is a steered drive unit: on a steering joint whose axis passes through its
        centre (not a caster, whose swivel trails the wheel)."""
        return self.steering_joint is not None and self.steering_offset is not None and self.steering_offset <= ON_AXIS

    @property
    def lateral(self) -> bool:
        """Whether it turns about the platform's lateral (y) axis."""
        return abs(float(self.axis[1])) >= LATERAL

    def describe(self) -> str:
        x, y, _ = self.position
        size = "r unknown" if self.radius is None else f"r = {self.radius:g} m"
        return f"{self.name} ({size} at x = {x:.3f}, y = {y:.3f} m)"

    def explain(self) -> str:
        """One line: its shape and radius, axis, whether driven, on a swivel."""
        if self.shape in ("cylinder", "sphere"):
            size = f"{self.shape} of radius {self.radius:g} m"
        elif self.radius is not None:
            size = f"named like a wheel, mesh geometry, radius {self.radius:g} m as given"
        else:
            size = "named like a wheel, mesh geometry (no cylinder or sphere to read a radius from)"
        axis = "lateral axis" if self.lateral else f"axis {np.round(self.axis, 3).tolist()}"
        extra = ""
        if self.steered_unit:
            extra = f", on steering joint {self.steering_joint!r} through its centre (a steered drive unit)"
        elif self.steering_joint:
            trail = "" if self.steering_offset is None else f", {self.steering_offset:.3g} m off its axis"
            extra = f", on swivel {self.steering_joint!r}{trail} (a caster)"
        driven = "driven (positive effort limit)" if self.driven else "no effort limit"
        return f"{self.describe()}: {size}, {axis}, {driven}{extra}"


def wheel_candidates(
    description: RobotDescription, exclude: Iterable[str] = (), radius: float | None = None
) -> list[WheelCandidate]:
    """Every continuous joint with a wheel-shaped child link, or named like a wheel (a mesh
    wheel: radius ``radius`` in m, unknown without it), in file order (``exclude`` left out)."""
    placements = description.zero_configuration_placements()
    exclude = set(exclude)
    out = []
    for joint in description.joints.values():
        if joint.type != "continuous" or joint.name in exclude:
            continue
        found = wheel_shape(description, joint.name)
        if found is None and not named_like_wheel(description, joint.name):
            continue
        shape, size = found if found is not None else ("mesh", radius)
        pose = placements[joint.name]
        ancestors = description.chain(joint.parent)
        effort = joint.effort_limit
        steering, offset = None, None
        for above in reversed(ancestors):
            if above.type in ("revolute", "continuous"):
                axis = description.axis_in_root(above.name)
                if abs(float(axis[2])) >= LATERAL:
                    steering = above.name
                    offset = _off_axis(pose[:3, 3], placements[above.name][:3, 3], axis)
                break
        out.append(
            WheelCandidate(
                name=joint.name,
                radius=size,
                position=pose[:3, 3].copy(),
                axis=pose[:3, :3] @ joint.unit_axis,
                carried_by_rotating_joint=any(j.type in ("revolute", "continuous") for j in ancestors),
                driven=effort is not None and effort > 0.0,
                steering_joint=steering,
                shape=shape,
                steering_offset=offset,
            )
        )
    return out


def _off_axis(point: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> float:
    """The distance (m) from ``point`` to the line through ``origin`` along the unit ``axis``."""
    d = np.asarray(point, dtype=float) - np.asarray(origin, dtype=float)
    return float(np.linalg.norm(d - float(d @ axis) * axis))


@dataclass(frozen=True)
class WheelGeometry:
    """Where a wheel joint sits in a loaded model, at the home configuration.

    Attributes:
        name: joint name.
        v_index: its tangent index.
        center: joint origin in the platform frame (m), (3,).
        axis: joint axis in the platform frame (unit), (3,).
        sign: +1 if a positive joint rate rolls the wheel forward (+x), else -1.
    """

    name: str
    v_index: int
    center: np.ndarray
    axis: np.ndarray
    sign: float


def wheel_geometry(model: pin.Model, names, role: str = "wheel", q: np.ndarray | None = None) -> list[WheelGeometry]:
    """Centres, axes and forward signs of wheel joints of a model (platform at the origin).

    Args:
        model: the Pinocchio model with its planar root joint.
        names: wheel joint names.
        role: what the wheels are, for messages (e.g. ``"right wheel"``).
        q: configuration (default: neutral); steering joints, if any, are where q puts them.

    Raises:
        WheelError: a wheel that does not turn about the platform's lateral (y) axis.
    """
    data = model.createData()
    q0 = pin.neutral(model) if q is None else q
    pin.computeJointJacobians(model, data, q0)
    out = []
    for name in names:
        joint_id = model.getJointId(name)
        joint = model.joints[joint_id]
        if joint.nv != 1:
            raise WheelError(f"{role} {name!r} has {joint.nv} degrees of freedom; a wheel has one")
        v = joint.idx_v
        axis = pin.getJointJacobian(model, data, joint_id, pin.LOCAL_WORLD_ALIGNED)[3:, v].copy()
        if float(np.linalg.norm(axis)) < 0.5:
            raise WheelError(f"{role} {name!r} does not rotate (a prismatic joint?); a wheel must be revolute")
        if abs(axis[1]) < LATERAL:
            raise WheelError(
                f"{role} {name!r} turns about {np.round(axis, 3).tolist()} in the platform frame; "
                "a drive wheel must turn about the platform's lateral (y) axis"
            )
        out.append(
            WheelGeometry(
                name=name,
                v_index=v,
                center=data.oMi[joint_id].translation.copy(),
                axis=axis,
                sign=1.0 if axis[1] > 0 else -1.0,  # rolling forward = positive rotation about +y
            )
        )
    return out


def radius_of(description: RobotDescription, name: str, override: float | None) -> float:
    """A wheel's radius (m): the spec's override, else the description's shapes.

    Raises:
        WheelError: no override and no cylinder about the axis or sphere in the URDF.
    """
    if override is not None:
        return positive_length(f"[wheels] radius of {name!r}", override)
    radius = wheel_radius(description, name)
    if radius is None:
        raise WheelError(
            f"wheel {name!r} has no cylinder about its axis or sphere to read a radius from; "
            "set [wheels] radius in the spec (mobmanip init-spec --wheel-radius M writes it)"
        )
    return positive_length(f"radius of wheel {name!r} (its URDF cylinder or sphere)", radius)


def side_by_side_message(right: str, left: str, y_right: float, y_left: float) -> str:
    return (
        f"right wheel {right!r} (y = {y_right:.3f} m) is not to the right of "
        f"left wheel {left!r} (y = {y_left:.3f} m); swap them in the spec"
    )
