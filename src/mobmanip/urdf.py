"""Reading and inspecting URDF files with yourdfpy (structure, limits, wheel geometry)."""

from __future__ import annotations

import logging
from pathlib import Path
from xml.etree import ElementTree

import numpy as np

from .errors import UrdfError

MOVING_JOINT_TYPES = ("revolute", "continuous", "prismatic")


def read_urdf(path: str | Path):
    """Parse a URDF with yourdfpy, without loading meshes.

    Raises:
        UrdfError: the file is missing, unreadable or not a valid URDF.
    """
    import yourdfpy

    path = Path(path)
    if not path.is_file():
        raise UrdfError(str(path), "file not found")
    # yourdfpy's parser recovers from broken XML (and logs about it); parse strictly first so a
    # truncated or malformed file is reported as such instead of as a partial robot.
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as exc:
        raise UrdfError(str(path), f"not well-formed XML: {exc}") from exc
    except OSError as exc:
        raise UrdfError(str(path), f"cannot read: {exc.strerror or exc}") from exc
    if root.tag != "robot":
        raise UrdfError(str(path), f"root element is <{root.tag}>, expected <robot>")
    logger = logging.getLogger("yourdfpy")
    level = logger.level
    logger.setLevel(logging.CRITICAL)  # its warnings (missing meshes, ...) are not ours to print
    try:
        urdf = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False, load_collision_meshes=False)
    except Exception as exc:  # KeyError, ValueError, ...: all mean "malformed"
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise UrdfError(str(path), f"cannot parse: {reason}") from exc
    finally:
        logger.setLevel(level)
    if not urdf.robot.links:
        raise UrdfError(str(path), "no links")
    return urdf


def _rotation(origin) -> np.ndarray:
    return np.eye(3) if origin is None else np.asarray(origin)[:3, :3]


def wheel_radius(urdf, joint_name: str) -> float | None:
    """Radius of a wheel from its link's collision (preferred) or visual geometry.

    A wheel is a cylinder whose axis is parallel to the joint axis, or a sphere.

    Returns:
        The radius in metres, or ``None`` when the link carries no such shape.
    """
    joint = urdf.joint_map[joint_name]
    link = urdf.link_map[joint.child]
    axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), dtype=float)
    axis = axis / np.linalg.norm(axis)
    for shapes in (link.collisions, link.visuals):
        for shape in shapes:
            geometry = shape.geometry
            if geometry.cylinder is not None:
                cylinder_axis = _rotation(shape.origin)[:, 2]
                if abs(abs(float(cylinder_axis @ axis)) - 1.0) < 1e-6:
                    return float(geometry.cylinder.radius)
            elif geometry.sphere is not None:
                return float(geometry.sphere.radius)
    return None


def joint_limits(urdf, joint_name: str) -> tuple[float | None, float | None]:
    """``(velocity, effort)`` limits of a joint as written in the URDF (``None`` if absent)."""
    limit = urdf.joint_map[joint_name].limit
    if limit is None:
        return None, None
    return limit.velocity, limit.effort


def mimic_joints(urdf) -> dict[str, str]:
    """Joints that mimic another joint: ``{mimicking joint: mimicked joint}``."""
    return {j.name: j.mimic.joint for j in urdf.robot.joints if j.mimic is not None}


#: URDF joint types mobmanip cannot model inside a robot (it adds the planar root joint itself).
UNSUPPORTED_JOINT_TYPES = ("floating", "planar")


def _origin(joint) -> np.ndarray:
    return np.eye(4) if joint.origin is None else np.asarray(joint.origin, dtype=float)


def parent_joint_map(urdf) -> dict[str, object]:
    """``{child link: the joint that carries it}`` (valid once :func:`check_supported` passed)."""
    return {j.child: j for j in urdf.robot.joints}


def root_link(urdf, path: str | Path = "URDF") -> str:
    """The name of the one link that no joint carries (the URDF's root).

    Raises:
        UrdfError: no root or several roots (``path`` names the file in the message).
    """
    children = {j.child for j in urdf.robot.joints}
    roots = [link.name for link in urdf.robot.links if link.name not in children]
    if len(roots) != 1:
        path = str(path)
        if not roots:
            raise UrdfError(path, "every link has a parent joint: the joints form a closed loop")
        raise UrdfError(path, f"several root links ({', '.join(roots)}): the URDF is not one connected tree")
    return roots[0]


def check_supported(urdf, path: str | Path) -> None:
    """Reject URDF constructs mobmanip cannot model, naming the offending joint or link.

    Checks that the joints form one tree (no link carried by two joints, no closed loop, one
    root, every link connected to it, joints name existing links) and that no joint is
    ``floating`` or ``planar``.

    Raises:
        UrdfError: the first unsupported construct found.
    """
    path = str(path)
    links = urdf.link_map
    carried_by: dict[str, str] = {}
    for joint in urdf.robot.joints:
        for role, link in (("parent", joint.parent), ("child", joint.child)):
            if link not in links:
                raise UrdfError(path, f"joint {joint.name!r} names a {role} link {link!r} that does not exist")
        if joint.child in carried_by:
            raise UrdfError(
                path,
                f"link {joint.child!r} is the child of two joints, {carried_by[joint.child]!r} and {joint.name!r}: "
                "closed kinematic loops are not supported",
            )
        carried_by[joint.child] = joint.name
        if joint.type in UNSUPPORTED_JOINT_TYPES:
            raise UrdfError(
                path,
                f"joint {joint.name!r} is of type {joint.type!r}, which mobmanip cannot model "
                "(it adds the platform's planar root joint itself)",
            )
    root = root_link(urdf, path)
    children: dict[str, list[str]] = {}
    for joint in urdf.robot.joints:
        children.setdefault(joint.parent, []).append(joint.child)
    reached, stack = {root}, [root]
    while stack:
        for child in children.get(stack.pop(), ()):
            if child not in reached:
                reached.add(child)
                stack.append(child)
    unreached = [link.name for link in urdf.robot.links if link.name not in reached]
    if unreached:
        raise UrdfError(
            path,
            f"links {', '.join(unreached)} are not connected to the root {root!r}: their joints form a closed loop",
        )


def joint_path(urdf, link: str) -> list:
    """The joints from the root link down to ``link``, root first (a tree is assumed)."""
    parents = parent_joint_map(urdf)
    path = []
    while link in parents:
        joint = parents[link]
        path.append(joint)
        link = joint.parent
    return path[::-1]


def subtree_links(urdf, joint_name: str) -> list[str]:
    """The links a joint moves: its child link and every link below it."""
    children: dict[str, list[str]] = {}
    for joint in urdf.robot.joints:
        children.setdefault(joint.parent, []).append(joint.child)
    out, stack = [], [urdf.joint_map[joint_name].child]
    while stack:
        link = stack.pop()
        out.append(link)
        stack.extend(children.get(link, ()))
    return out


def zero_configuration_placements(urdf) -> dict[str, np.ndarray]:
    """Placement (4 x 4) of every joint frame in the root link's frame with all joints at zero.

    At zero a joint's motion is the identity, so its frame is the composition of the origins
    from the root; the child link's frame is the joint frame.
    """
    out: dict[str, np.ndarray] = {}
    for link in urdf.link_map:
        pose = np.eye(4)
        for joint in joint_path(urdf, link):
            pose = pose @ _origin(joint)
            out.setdefault(joint.name, pose.copy())
    return out


def joint_axis(joint) -> np.ndarray:
    """A joint's unit axis in its own frame (URDF default: x)."""
    axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), dtype=float)
    return axis / np.linalg.norm(axis)


def link_has_inertia(urdf, link: str) -> bool:
    """Whether a link has an ``<inertial>`` with positive mass or a non-zero inertia tensor."""
    inertial = urdf.link_map[link].inertial
    if inertial is None:
        return False
    mass = inertial.mass or 0.0
    inertia = np.asarray(inertial.inertia if inertial.inertia is not None else np.zeros((3, 3)), dtype=float)
    return mass > 0.0 or bool(np.any(inertia != 0.0))
