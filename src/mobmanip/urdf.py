"""Reading and inspecting URDF files with yourdfpy (structure, limits, wheel geometry)."""

from __future__ import annotations

import logging
from pathlib import Path

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
    # yourdfpy logs warnings for missing meshes and the like; those are not our errors.
    logging.getLogger("yourdfpy").setLevel(logging.ERROR)
    try:
        urdf = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False, load_collision_meshes=False)
    except Exception as exc:  # lxml, KeyError, ValueError, ...: all mean "malformed"
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise UrdfError(str(path), f"cannot parse: {reason}") from exc
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
