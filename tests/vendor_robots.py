"""Robots as vendors publish them, for the vendor-flaw tests.

Fetch's own URDF (fetch_ros' ``fetch_description``) is licensed CC BY-NC-SA 4.0, which this
BSD project cannot ship, not even stripped of its meshes. :func:`fetch_like_urdf` writes an
equivalent robot instead, with numbers of its own: a differential-drive base with two
cylinder wheels, a prismatic torso lift, a pan-tilt head, a 7-joint arm (three of them
continuous rolls), a gripper with two prismatic fingers, a bellows, sensors on fixed joints and
camera frames with no ``<inertial>``; and Fetch's flaw: each finger's inertia is
``ixx=0.002 iyy=0 izz=0``, principal moments 0, 0, 0.002 that break the triangle inequality.
"""

from __future__ import annotations

import math
from pathlib import Path

#: The links whose inertia is flawed, as in Fetch's URDF.
FETCH_FLAWED = ("r_gripper_finger_link", "l_gripper_finger_link")

#: The flawed tensor (kg m^2): ixx, iyy, izz (no products).
FINGER_INERTIA = (0.002, 0.0, 0.0)

WHEEL_RADIUS = 0.06
HALF_TRACK = 0.19

#: Arm joints base to tip: name, type, axis, origin in the parent, (lower, upper), velocity, effort,
#: then the link's mass, centre of mass and principal moments (all physical).
ARM = (
    ("shoulder_pan", "revolute", "0 0 1", (0.12, 0.0, 0.35), (-1.6, 1.6), 1.25, 33.0,
     2.5, (0.09, 0.0, 0.0), (0.0086, 0.009, 0.0042)),
    ("shoulder_lift", "revolute", "0 1 0", (0.12, 0.0, 0.06), (-1.2, 1.5), 1.45, 130.0,
     2.6, (0.14, 0.0, 0.0), (0.0023, 0.011, 0.0115)),
    ("upperarm_roll", "continuous", "1 0 0", (0.22, 0.0, 0.0), None, 1.57, 77.0,
     2.3, (0.12, 0.0, 0.0), (0.0019, 0.0045, 0.0047)),
    ("elbow_flex", "revolute", "0 1 0", (0.13, 0.0, 0.0), (-2.25, 2.25), 1.52, 66.0,
     2.1, (0.12, 0.0, 0.0), (0.002, 0.0084, 0.0086)),
    ("forearm_roll", "continuous", "1 0 0", (0.2, 0.0, 0.0), None, 1.57, 29.0,
     1.65, (0.11, 0.0, 0.0), (0.0015, 0.0031, 0.0035)),
    ("wrist_flex", "revolute", "0 1 0", (0.12, 0.0, 0.0), (-2.16, 2.16), 2.27, 25.7,
     1.7, (0.1, 0.0, 0.0), (0.0018, 0.0042, 0.0042)),
    ("wrist_roll", "continuous", "1 0 0", (0.14, 0.0, 0.0), None, 2.27, 7.4,
     0.14, (0.03, 0.0, 0.0), (0.0001, 0.0001, 0.0001)),
)  # fmt: skip


def _inertial(mass, com=(0.0, 0.0, 0.0), moments=(0.0, 0.0, 0.0)) -> str:
    ixx, iyy, izz = moments
    xyz = " ".join(repr(float(c)) for c in com)
    return (
        f'<inertial><origin xyz="{xyz}" rpy="0 0 0"/><mass value="{mass!r}"/>'
        f'<inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{iyy!r}" iyz="0" izz="{izz!r}"/></inertial>'
    )


def _joint(name, kind, parent, child, xyz, axis="1 0 0", limit=None) -> str:
    origin = " ".join(repr(float(c)) for c in xyz)
    text = f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
    text += f'<origin xyz="{origin}" rpy="0 0 0"/>'
    if kind != "fixed":
        text += f'<axis xyz="{axis}"/>'
    if limit is not None:
        text += "<limit " + " ".join(f'{k}="{v!r}"' for k, v in limit.items()) + "/>"
    return text + "</joint>"


def fetch_like_text(finger_inertia=FINGER_INERTIA) -> str:
    """The Fetch-like URDF (see the module docstring); ``finger_inertia`` (ixx, iyy, izz) of both
    fingers, Fetch's flawed one by default."""
    parts = ['<?xml version="1.0"?>', '<robot name="fetch_like">']
    link = parts.append
    link(
        '<link name="base_link">' + _inertial(70.0, (-0.03, 0.0, 0.16), (1.0, 1.2, 1.25))
        + '<collision><origin xyz="0 0 0.18"/><geometry><box size="0.5 0.5 0.3"/></geometry></collision></link>'
    )  # fmt: skip
    for side, y in (("r", -HALF_TRACK), ("l", HALF_TRACK)):
        link(
            f'<link name="{side}_wheel_link">' + _inertial(4.3, moments=(0.0045, 0.005, 0.0045))
            + f'<collision><origin xyz="0 0 0" rpy="{-math.pi / 2!r} 0 0"/>'
            f'<geometry><cylinder radius="{WHEEL_RADIUS!r}" length="0.04"/></geometry></collision></link>'
        )  # fmt: skip
        link(
            _joint(f"{side}_wheel_joint", "continuous", "base_link", f"{side}_wheel_link", (0.0, y, 0.06), "0 1 0",
                   {"effort": 9.0, "velocity": 17.0})
        )  # fmt: skip
    link('<link name="torso_lift_link">' + _inertial(10.8, (-0.01, 0.0, -0.08), (0.095, 0.33, 0.335)) + "</link>")
    link(
        _joint("torso_lift_joint", "prismatic", "base_link", "torso_lift_link", (-0.09, 0.0, 0.38), "0 0 1",
               {"lower": 0.0, "upper": 0.38, "effort": 450.0, "velocity": 0.1})
    )  # fmt: skip
    link('<link name="head_pan_link">' + _inertial(2.2, (0.03, 0.0, 0.05), (0.0095, 0.0128, 0.0185)) + "</link>")
    link(
        _joint("head_pan_joint", "revolute", "torso_lift_link", "head_pan_link", (0.05, 0.0, 0.6), "0 0 1",
               {"lower": -1.57, "upper": 1.57, "effort": 0.32, "velocity": 1.57})
    )  # fmt: skip
    link('<link name="head_tilt_link">' + _inertial(0.9, (0.06, 0.0, 0.0), (0.0014, 0.0059, 0.0063)) + "</link>")
    link(
        _joint("head_tilt_joint", "revolute", "head_pan_link", "head_tilt_link", (0.14, 0.0, 0.06), "0 1 0",
               {"lower": -0.76, "upper": 1.45, "effort": 0.68, "velocity": 1.57})
    )  # fmt: skip
    link('<link name="head_camera_link"/>')  # a camera frame: no <inertial>
    link(_joint("head_camera_joint", "fixed", "head_tilt_link", "head_camera_link", (0.055, 0.0, 0.02)))
    parent = "torso_lift_link"
    for name, kind, axis, xyz, bounds, velocity, effort, mass, com, moments in ARM:
        link(f'<link name="{name}_link">' + _inertial(mass, com, moments) + "</link>")
        limit = {"effort": effort, "velocity": velocity}
        if bounds is not None:
            limit = {"lower": bounds[0], "upper": bounds[1], **limit}
        link(_joint(f"{name}_joint", kind, parent, f"{name}_link", xyz, axis, limit))
        parent = f"{name}_link"
    link('<link name="gripper_link">' + _inertial(1.5, (-0.09, 0.0, 0.0), (0.0013, 0.0019, 0.0024)) + "</link>")
    link(_joint("gripper_axis", "fixed", parent, "gripper_link", (0.17, 0.0, 0.0)))
    for side, sign in (("r", 1.0), ("l", -1.0)):
        link(f'<link name="{side}_gripper_finger_link">' + _inertial(0.08, (0.0, 0.0, 0.0), finger_inertia) + "</link>")
        link(
            _joint(f"{side}_gripper_finger_joint", "prismatic", "gripper_link", f"{side}_gripper_finger_link",
                   (0.0, 0.016 * sign, 0.0), f"0 {sign:g} 0",
                   {"lower": 0.0, "upper": 0.05, "effort": 60.0, "velocity": 0.05})
        )  # fmt: skip
    link('<link name="bellows_link">' + _inertial(0.17, (0.0, 0.0, -0.2), (0.0017, 0.0017, 0.0033)) + "</link>")
    link(
        _joint("bellows_joint", "prismatic", "torso_lift_link", "bellows_link", (0.0, 0.0, 0.0), "0 0 1",
               {"lower": 0.0, "upper": 0.4, "effort": 5.0, "velocity": 0.1})
    )  # fmt: skip
    for name, mass, xyz in (("estop", 0.002, (-0.12, 0.24, 0.35)), ("laser", 0.008, (0.24, 0.0, 0.24))):
        link(f'<link name="{name}_link">' + _inertial(mass, moments=(3e-7, 3e-7, 3e-7)) + "</link>")
        link(_joint(f"{name}_joint", "fixed", "base_link", f"{name}_link", xyz))
    parts.append("</robot>")
    return "\n".join(parts) + "\n"


def fetch_like_urdf(directory: Path, name: str = "fetch_like.urdf", **options) -> Path:
    """Write :func:`fetch_like_text` into ``directory``; returns its path."""
    path = Path(directory) / name
    path.write_text(fetch_like_text(**options))
    return path
