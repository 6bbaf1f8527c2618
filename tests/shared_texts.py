"""Input texts that several test files build from: a xacro robot's macros and links, a site on a
grid. Each file keeps its own variations (a xacro robot whose forearm's mass and tool frame come
from arguments or are written out, the site's grid and starts). The MJCF robots the tests write
are files of their own, in ``tests/data/mjcf``."""

from __future__ import annotations

#: The xacro header of a robot file (``name``: its name attribute, with a leading space, or "").
XACRO_HEADER = '<?xml version="1.0"?>\n<robot{name} xmlns:xacro="http://www.ros.org/wiki/xacro">\n'

#: A xacro robot's macros: a box's inertia, a wheel (a continuous joint under base_link), an arm
#: link with its revolute joint (its origin given as a block). They use the property wheel_radius.
XACRO_MACROS = """  <xacro:macro name="box_inertia" params="m x y z">
    <inertia ixx="${m*(y*y+z*z)/12}" ixy="0" ixz="0" iyy="${m*(x*x+z*z)/12}" iyz="0" izz="${m*(x*x+y*y)/12}"/>
  </xacro:macro>
  <xacro:macro name="wheel" params="side y">
    <link name="wheel_${side}_link">
      <inertial><mass value="2.0"/>
        <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.0064" iyz="0" izz="0.004"/></inertial>
      <collision><origin xyz="0 0 0" rpy="${-pi/2} 0 0"/>
        <geometry><cylinder radius="${wheel_radius}" length="0.04"/></geometry></collision>
    </link>
    <joint name="wheel_${side}_joint" type="continuous">
      <parent link="base_link"/><child link="wheel_${side}_link"/>
      <origin xyz="0 ${y} ${wheel_radius}"/><axis xyz="0 1 0"/>
      <limit effort="20" velocity="12"/>
    </joint>
  </xacro:macro>
  <xacro:macro name="arm_link" params="name parent length mass axis *origin">
    <link name="${name}_link">
      <inertial><origin xyz="${length/2} 0 0"/><mass value="${mass}"/>
        <xacro:box_inertia m="${mass}" x="${length}" y="0.06" z="0.06"/></inertial>
    </link>
    <joint name="${name}_joint" type="revolute">
      <parent link="${parent}"/><child link="${name}_link"/>
      <xacro:insert_block name="origin"/><axis xyz="${axis}"/>
      <limit lower="-2.5" upper="2.5" effort="${40*mass}" velocity="2.0"/>
    </joint>
  </xacro:macro>
"""

_XACRO_BODY = """  <link name="base_link">
    <inertial><origin xyz="0 0 0.15"/><mass value="30"/>
      <xacro:box_inertia m="30" x="0.6" y="0.5" z="0.2"/></inertial>
  </link>
  <xacro:wheel side="right" y="-0.22"/>
  <xacro:wheel side="left" y="0.22"/>
  <xacro:arm_link name="shoulder" parent="base_link" length="0.1" mass="3.0" axis="0 0 1">
    <origin xyz="0.1 0 0.3"/>
  </xacro:arm_link>
  <xacro:arm_link name="upper" parent="shoulder_link" length="${L}" mass="2.0" axis="0 1 0">
    <origin xyz="0.1 0 0.05"/>
  </xacro:arm_link>
  <xacro:arm_link name="fore" parent="upper_link" length="0.3" mass="@FORE_MASS@" axis="0 1 0">
    <origin xyz="${L} 0 0"/>
  </xacro:arm_link>
  <link name="@TOOL@"/>
  <joint name="tool_joint" type="fixed"><parent link="fore_link"/><child link="@TOOL@"/>
    <origin xyz="0.3 0 0"/></joint>
</robot>
"""


def xacro_body(fore_mass: str, tool: str) -> str:
    """The xacro robot's links and joints through :data:`XACRO_MACROS`, to the end of the file: a
    base on two wheels, a shoulder, an upper arm of length ``${L}`` and a forearm of mass
    ``fore_mass``, a tool frame named ``tool`` (both as written in the file: a number, a name or
    an ``$(arg ...)``)."""
    return _XACRO_BODY.replace("@FORE_MASS@", fore_mass).replace("@TOOL@", tool)


def grid_site(starts: int, x_count: int) -> str:
    """A site file: the paper robot's kinematic capacity along +x on a grid of x from 0 to 2 m
    (``x_count`` positions), y 0 and 1 m, at a height of 0.35 m, ``starts`` starts a position."""
    return (
        f'robot = "planar_dual_arm"\nobjective = "kinematic:capacity:+x"\nstarts = {starts}\n'
        f"[grid]\nx = [0.0, 2.0, {x_count}]\ny = [0.0, 1.0, 2]\nz = 0.35\n"
    )
