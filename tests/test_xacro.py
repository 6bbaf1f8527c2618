"""xacro robots (issue 25, item 2): expanded with the ``xacro`` package (no ROS), ``$(arg)`` from
``--xacro-arg`` or a spec's ``[xacro_args]``, ``$(find PKG)`` from ``--package-path``, a spec's
``package_paths`` or ``ROS_PACKAGE_PATH``; the analysis of the xacro robot from the command line
equals that of the same robot written as a plain URDF; an unresolved package or an argument
without a value is one clear error naming it and the option that supplies it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hostile_util import assert_one_line_error, run_cli
from mobmanip.descriptions import find_package, read_description
from mobmanip.errors import XacroError
from mobmanip.robot.spec import load_spec
from shared_texts import XACRO_HEADER, XACRO_MACROS, xacro_body

WHEEL_RADIUS = 0.08
HALF_TRACK = 0.22

#: A package of macros, found by $(find xbot_description): a wheel and an arm link.
MACROS = (
    XACRO_HEADER.format(name="")
    + '  <xacro:property name="wheel_radius" value="0.08"/>\n'
    + XACRO_MACROS
    + "</robot>\n"
)

#: The robot: args for the arm's length and mass, the macros included through $(find).
ROBOT = (
    XACRO_HEADER.format(name=' name="xbot"')
    + """  <xacro:arg name="upper_length" default="0.4"/>
  <xacro:arg name="payload_mass" default="1.0"/>
  <xacro:include filename="$(find xbot_description)/urdf/macros.xacro"/>
  <xacro:property name="L" value="$(arg upper_length)"/>
"""
    + xacro_body("$(arg payload_mass)", "$(arg tool_name)")
)


def _box(m, x, y, z):
    return (
        f'<inertia ixx="{m * (y * y + z * z) / 12!r}" ixy="0" ixz="0" iyy="{m * (x * x + z * z) / 12!r}" iyz="0" '
        f'izz="{m * (x * x + y * y) / 12!r}"/>'
    )


def plain_urdf(upper_length: float, payload_mass: float, tool: str) -> str:
    """The same robot written out by hand, without xacro."""
    parts = ['<robot name="xbot">', '<link name="base_link"><inertial><origin xyz="0 0 0.15"/><mass value="30"/>'
             + _box(30, 0.6, 0.5, 0.2) + "</inertial></link>"]  # fmt: skip
    for side, y in (("right", -HALF_TRACK), ("left", HALF_TRACK)):
        parts.append(
            f'<link name="wheel_{side}_link"><inertial><mass value="2.0"/>'
            '<inertia ixx="0.004" ixy="0" ixz="0" iyy="0.0064" iyz="0" izz="0.004"/></inertial>'
            f'<collision><origin xyz="0 0 0" rpy="{-np.pi / 2!r} 0 0"/>'
            f'<geometry><cylinder radius="{WHEEL_RADIUS}" length="0.04"/></geometry></collision></link>'
            f'<joint name="wheel_{side}_joint" type="continuous"><parent link="base_link"/>'
            f'<child link="wheel_{side}_link"/><origin xyz="0 {y} {WHEEL_RADIUS}"/><axis xyz="0 1 0"/>'
            '<limit effort="20" velocity="12"/></joint>'
        )
    chain = (
        ("shoulder", "base_link", 0.1, 3.0, "0 0 1", "0.1 0 0.3"),
        ("upper", "shoulder_link", upper_length, 2.0, "0 1 0", "0.1 0 0.05"),
        ("fore", "upper_link", 0.3, payload_mass, "0 1 0", f"{upper_length!r} 0 0"),
    )
    for name, parent, length, mass, axis, origin in chain:
        parts.append(
            f'<link name="{name}_link"><inertial><origin xyz="{length / 2!r} 0 0"/><mass value="{mass!r}"/>'
            + _box(mass, length, 0.06, 0.06) + "</inertial></link>"
            f'<joint name="{name}_joint" type="revolute"><parent link="{parent}"/><child link="{name}_link"/>'
            f'<origin xyz="{origin}"/><axis xyz="{axis}"/>'
            f'<limit lower="-2.5" upper="2.5" effort="{40 * mass!r}" velocity="2.0"/></joint>'
        )  # fmt: skip
    parts.append(f'<link name="{tool}"/><joint name="tool_joint" type="fixed"><parent link="fore_link"/>'
                 f'<child link="{tool}"/><origin xyz="0.3 0 0"/></joint></robot>')  # fmt: skip
    return "".join(parts)


@pytest.fixture
def xbot(tmp_path):
    """The xacro robot, its macro package in a workspace, and where things are."""
    package = tmp_path / "ws" / "src" / "xbot_repo" / "xbot_description"
    (package / "urdf").mkdir(parents=True)
    (package / "package.xml").write_text(
        '<?xml version="1.0"?><package format="3"><name>xbot_description</name><version>1.0.0</version></package>'
    )
    (package / "urdf" / "macros.xacro").write_text(MACROS)
    robot = tmp_path / "robot" / "xbot.urdf.xacro"
    robot.parent.mkdir()
    robot.write_text(ROBOT)
    return robot, tmp_path / "ws" / "src", package


ARGS = ("--xacro-arg", "upper_length=0.45", "--xacro-arg", "payload_mass=1.5", "--xacro-arg", "tool_name=gripper")


def _analyze(capfd, tmp_path, name, *argv):
    out = tmp_path / f"{name}.json"
    code, printed, err = run_cli(capfd, "analyze", *argv, "--json", out)
    assert code == 0, err
    return json.loads(out.read_text()), printed


def test_xacro_robot_analyses_as_its_plain_urdf(xbot, tmp_path, capfd):
    robot, workspace, _ = xbot
    xacro_doc, printed = _analyze(capfd, tmp_path, "xacro", "--urdf", robot, "--ee", "gripper",
                                  "--package-path", workspace, *ARGS)  # fmt: skip
    plain = tmp_path / "plain.urdf"
    plain.write_text(plain_urdf(0.45, 1.5, "gripper"))
    plain_doc, plain_printed = _analyze(capfd, tmp_path, "plain", "--urdf", plain, "--ee", "gripper")
    assert xacro_doc["platform"] == "differential_drive"
    assert xacro_doc["reduced_velocity_names"] == plain_doc["reduced_velocity_names"]
    assert len(xacro_doc["reduced_velocity_names"]) == 5
    for key in ("unified_jacobian", "reduced_inertia", "bias", "velocity_limits", "effort_limits"):
        np.testing.assert_allclose(xacro_doc[key], plain_doc[key], rtol=1e-12, atol=1e-12, err_msg=key)
    for key in ("kinematic_ellipsoid", "dynamic_ellipsoid"):
        np.testing.assert_allclose(xacro_doc[key]["semi_axes"], plain_doc[key]["semi_axes"], rtol=1e-12)
        np.testing.assert_allclose(xacro_doc[key]["center"], plain_doc[key]["center"], rtol=1e-12, atol=1e-12)


def test_init_spec_records_the_args_and_package_paths_and_analyze_reads_them(xbot, tmp_path, capfd, monkeypatch):
    robot, workspace, _ = xbot
    spec = tmp_path / "specs" / "xbot.toml"
    spec.parent.mkdir()
    code, _, err = run_cli(capfd, "init-spec", robot, "--ee", "gripper", "--package-path", workspace, *ARGS,
                           "--out", spec)  # fmt: skip
    assert code == 0, err
    loaded = load_spec(spec)
    assert dict(loaded.xacro_args) == {"upper_length": "0.45", "payload_mass": "1.5", "tool_name": "gripper"}
    assert [p.resolve() for p in loaded.package_paths] == [workspace.resolve()]
    assert "../ws/src" in spec.read_text()  # relative to the spec's folder
    monkeypatch.chdir(tmp_path / "robot")  # the spec's paths do not depend on the working folder
    from_spec, _ = _analyze(capfd, tmp_path, "spec", spec)
    from_urdf, _ = _analyze(capfd, tmp_path, "urdf", "--urdf", robot, "--ee", "gripper", "--package-path", workspace,
                            *ARGS)  # fmt: skip
    assert from_spec["kinematic_ellipsoid"] == from_urdf["kinematic_ellipsoid"]
    assert from_spec["dynamic_ellipsoid"] == from_urdf["dynamic_ellipsoid"]
    # a --xacro-arg on the command line overrides the spec's
    longer, _ = _analyze(capfd, tmp_path, "longer", spec, "--xacro-arg", "upper_length=0.6")
    assert longer["kinematic_ellipsoid"] != from_spec["kinematic_ellipsoid"]


def test_ros_package_path_resolves_find(xbot, monkeypatch):
    robot, workspace, package = xbot
    monkeypatch.setenv("ROS_PACKAGE_PATH", f"/nowhere:{workspace}")
    description = read_description(robot, xacro_args={"tool_name": "tool"})
    assert description.format == "xacro" and description.source == robot
    assert "tool" in description.links and description.joints["upper_joint"].limits.effort == pytest.approx(80.0)
    assert package.parent in description.package_dirs  # package:// meshes of the package resolve
    assert find_package("xbot_description", [workspace]) == package


def test_an_unresolved_package_is_one_error_naming_it(xbot, capfd, monkeypatch):
    robot, _, _ = xbot
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    code, out, err = run_cli(capfd, "analyze", "--urdf", robot, "--ee", "gripper", *ARGS, "--package-path", "/tmp/none")
    line = assert_one_line_error(code, err, "xbot_description", "--package-path", "/tmp/none")
    assert line.startswith("mobmanip: error: xacro ") and out == ""
    with pytest.raises(XacroError, match="package 'xbot_description' not found"):
        read_description(robot, xacro_args={"tool_name": "t"})


def test_an_argument_without_a_value_names_it_and_the_option(xbot, capfd):
    robot, workspace, _ = xbot
    code, _, err = run_cli(capfd, "analyze", "--urdf", robot, "--ee", "gripper", "--package-path", workspace)
    assert_one_line_error(code, err, "$(arg tool_name)", "--xacro-arg tool_name=VALUE")


def test_xacro_options_for_a_urdf_are_refused(tmp_path, capfd):
    plain = tmp_path / "plain.urdf"
    plain.write_text(plain_urdf(0.4, 1.0, "gripper"))
    code, _, err = run_cli(capfd, "analyze", "--urdf", plain, "--ee", "gripper", "--xacro-arg", "a=1")
    assert_one_line_error(code, err, "xacro_args", "xacro")


def test_a_malformed_xacro_is_one_line(tmp_path, capfd):
    broken = tmp_path / "broken.xacro"
    broken.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:unknown_macro/></robot>')
    code, _, err = run_cli(capfd, "init-spec", broken, "--list-frames")
    assert_one_line_error(code, err, "broken.xacro", "xacro cannot expand it")
    truncated = tmp_path / "truncated.urdf.xacro"
    truncated.write_text(ROBOT[: len(ROBOT) // 2])
    code, _, err = run_cli(capfd, "init-spec", truncated, "--list-frames")
    assert_one_line_error(code, err, "truncated.urdf.xacro")


def test_a_misspelt_argument_is_one_error_naming_it_and_the_files_arguments(xbot, capfd):
    """A --xacro-arg that no file of the expansion declares or uses (here ``tool_nam``, meant for
    ``tool_name``) would be dropped, and the robot built with the default it meant to change: it is
    refused, naming the argument and the ones the files have (the macro package's included)."""
    robot, workspace, _ = xbot
    code, _, err = run_cli(
        capfd, "analyze", "--urdf", robot, "--ee", "gripper", "--package-path", workspace, *ARGS, "--xacro-arg",
        "tool_nam=gripper",
    )  # fmt: skip
    assert_one_line_error(code, err, "--xacro-arg tool_nam=gripper", "'tool_nam'", "tool_name", "upper_length")
    # every argument the files declare or use is accepted (the ones above, and nothing else added)
    code, _, err = run_cli(capfd, "analyze", "--urdf", robot, "--ee", "gripper", "--package-path", workspace, *ARGS)
    assert code == 0, err
