#!/usr/bin/env python3
"""Generate ``robots/planar_dual_arm.urdf``, the paper's two-arm differential-drive robot.

All numbers come from Tables 1 and 2 of the paper (see DESIGN.md, "The paper's case study"):

* platform body: 94 kg, 6.609 kg m^2 about the vertical axis through P_o, centre of mass at P_o;
* two driving wheels of radius 0.075 m, half-track 0.171 m, 5 kg each, 0.01 kg m^2 about the
  axle and 0.135 kg m^2 about a diameter, 200 N m and 1/r rad/s (rim speed 1 m/s);
* two identical 3R arms with vertical joint axes mounted above P_o, links 0.5 m long, centres of
  mass 0.25, 0.25, 0.1 m from each joint, masses 10, 6, 2 kg, inertias 0.5, 0.3, 0.01 kg m^2,
  200, 100, 30 N m and 3.14 rad/s.

The base_link frame sits at P_o (the midpoint of the wheel axle), +x forward, +z up.
Moments of inertia about horizontal axes do not enter the planar dynamics; they are set to
physically valid values (a flat plate for the platform, slender rods for the links).
The arms are mounted at different heights only so that their links do not intersect in the
viewer; in the horizontal plane both start at P_o.

Usage: ``python scripts/generate_planar_dual_arm.py [--out PATH]`` (default: the committed
file); ``--out -`` prints to standard output.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

# Table 2: platform and object.
HALF_TRACK = 0.171
WHEEL_RADIUS = 0.075
WHEEL_WIDTH = 0.04
PLATFORM_MASS = 94.0
PLATFORM_IZZ = 6.609
WHEEL_MASS = 5.0
WHEEL_I_AXLE = 0.01
WHEEL_I_DIAMETER = 0.135
WHEEL_EFFORT = 200.0
WHEEL_VELOCITY = 1.0 / WHEEL_RADIUS

# Table 1: each arm (first, second, third link).
LINK_LENGTH = (0.5, 0.5, 0.5)
LINK_COM = (0.25, 0.25, 0.1)
LINK_MASS = (10.0, 6.0, 2.0)
LINK_IZZ = (0.5, 0.3, 0.01)
JOINT_EFFORT = (200.0, 100.0, 30.0)
JOINT_VELOCITY = (3.14, 3.14, 3.14)

# Mounting heights of the arms above P_o (visual separation only).
ARM_HEIGHT = {"right": 0.30, "left": 0.40}
LINK_SECTION = 0.05

DEFAULT_OUT = Path(__file__).resolve().parents[1] / "robots" / "planar_dual_arm.urdf"


def _f(value: float) -> str:
    """Shortest round-trip text for a float, so the file is stable and exact."""
    return repr(float(value))


def _inertial(mass, com, ixx, iyy, izz) -> str:
    x, y, z = com
    return (
        f"    <inertial>\n"
        f'      <origin xyz="{_f(x)} {_f(y)} {_f(z)}" rpy="0 0 0"/>\n'
        f'      <mass value="{_f(mass)}"/>\n'
        f'      <inertia ixx="{_f(ixx)}" ixy="0" ixz="0" iyy="{_f(iyy)}" iyz="0" izz="{_f(izz)}"/>\n'
        f"    </inertial>\n"
    )


def _box(xyz, size, material) -> str:
    x, y, z = xyz
    sx, sy, sz = size
    return (
        f"    <visual>\n"
        f'      <origin xyz="{_f(x)} {_f(y)} {_f(z)}" rpy="0 0 0"/>\n'
        f'      <geometry><box size="{_f(sx)} {_f(sy)} {_f(sz)}"/></geometry>\n'
        f'      <material name="{material}"/>\n'
        f"    </visual>\n"
    )


def _wheel(side: str, y: float) -> str:
    cylinder = (
        '      <origin xyz="0 0 0" rpy="1.5707963267948966 0 0"/>\n'
        f'      <geometry><cylinder radius="{_f(WHEEL_RADIUS)}" length="{_f(WHEEL_WIDTH)}"/></geometry>\n'
    )
    return (
        f'  <joint name="wheel_{side}_joint" type="continuous">\n'
        f'    <parent link="base_link"/>\n'
        f'    <child link="wheel_{side}_link"/>\n'
        f'    <origin xyz="0 {_f(y)} 0" rpy="0 0 0"/>\n'
        f'    <axis xyz="0 1 0"/>\n'
        f'    <limit effort="{_f(WHEEL_EFFORT)}" velocity="{_f(WHEEL_VELOCITY)}"/>\n'
        f"  </joint>\n"
        f'  <link name="wheel_{side}_link">\n'
        + _inertial(WHEEL_MASS, (0, 0, 0), WHEEL_I_DIAMETER, WHEEL_I_AXLE, WHEEL_I_DIAMETER)
        + "    <visual>\n"
        + cylinder
        + '      <material name="wheel"/>\n    </visual>\n'
        + "    <collision>\n"
        + cylinder
        + "    </collision>\n"
        + "  </link>\n"
    )


def _arm(side: str) -> str:
    out = []
    parent = "base_link"
    origin = (0.0, 0.0, ARM_HEIGHT[side])
    for k in range(3):
        name = f"arm_{side}_{k + 1}"
        length, com, mass, izz = LINK_LENGTH[k], LINK_COM[k], LINK_MASS[k], LINK_IZZ[k]
        out.append(
            f'  <joint name="{name}_joint" type="revolute">\n'
            f'    <parent link="{parent}"/>\n'
            f'    <child link="{name}_link"/>\n'
            f'    <origin xyz="{_f(origin[0])} {_f(origin[1])} {_f(origin[2])}" rpy="0 0 0"/>\n'
            f'    <axis xyz="0 0 1"/>\n'
            f'    <limit lower="{_f(-3.141592653589793)}" upper="{_f(3.141592653589793)}" '
            f'effort="{_f(JOINT_EFFORT[k])}" velocity="{_f(JOINT_VELOCITY[k])}"/>\n'
            f"  </joint>\n"
            f'  <link name="{name}_link">\n'
            + _inertial(mass, (com, 0, 0), izz / 100.0, izz, izz)
            + _box((length / 2, 0, 0), (length, LINK_SECTION, LINK_SECTION), f"arm_{side}")
            + "  </link>\n"
        )
        parent = f"{name}_link"
        origin = (length, 0.0, 0.0)
    out.append(
        f'  <joint name="arm_{side}_tool_joint" type="fixed">\n'
        f'    <parent link="{parent}"/>\n'
        f'    <child link="arm_{side}_tool_link"/>\n'
        f'    <origin xyz="{_f(origin[0])} 0 0" rpy="0 0 0"/>\n'
        f"  </joint>\n"
        f'  <link name="arm_{side}_tool_link"/>\n'
    )
    return "".join(out)


def generate() -> str:
    """Return the URDF text of the paper's robot."""
    return (
        '<?xml version="1.0"?>\n'
        "<!-- Generated by scripts/generate_planar_dual_arm.py from Tables 1 and 2 of the paper.\n"
        "     Do not edit by hand: change the generator and run it again. -->\n"
        '<robot name="planar_dual_arm">\n'
        '  <material name="platform"><color rgba="0.55 0.57 0.6 1"/></material>\n'
        '  <material name="wheel"><color rgba="0.15 0.15 0.15 1"/></material>\n'
        '  <material name="arm_right"><color rgba="0.85 0.45 0.2 1"/></material>\n'
        '  <material name="arm_left"><color rgba="0.25 0.5 0.8 1"/></material>\n'
        '  <link name="base_link">\n'
        + _inertial(PLATFORM_MASS, (0, 0, 0), PLATFORM_IZZ / 2, PLATFORM_IZZ / 2, PLATFORM_IZZ)
        + _box((0.0, 0.0, 0.09), (0.5, 0.28, 0.18), "platform")
        + "  </link>\n"
        + _wheel("right", -HALF_TRACK)
        + _wheel("left", HALF_TRACK)
        + _arm("right")
        + _arm("left")
        + "</robot>\n"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="output path, '-' for stdout")
    args = parser.parse_args(argv)
    text = generate()
    if args.out == "-":
        sys.stdout.write(text)
    else:
        Path(args.out).write_text(text)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
