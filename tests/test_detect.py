"""Inferring a spec from a URDF (mobmanip.robot.detect), `init-spec`, `analyze --urdf`, and the errors
that name what is wrong with a URDF.

Broken URDFs are small edits of the paper's URDF written into tmp_path.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from mobmanip.cli import main
from mobmanip.descriptions.resources import example_robot_data_share
from mobmanip.descriptions.urdf import read_urdf
from mobmanip.errors import (
    FrameNotFoundError,
    JointNotFoundError,
    LimitError,
    MissingLimitError,
    MobmanipError,
    UrdfError,
    WheelError,
)
from mobmanip.robot.detect import detect_spec, spec_from_urdf, spec_to_toml, wheel_candidates
from mobmanip.robot.spec import ArmSpec, RobotSpec, WheelSpec, find_spec, load_spec
from mobmanip.robot.support_spec import SupportSpec
from mobmanip.terms.dynamics import end_effector_positions, unified_jacobian

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
PAPER_URDF = ROBOTS / "planar_dual_arm.urdf"
TIAGO_URDF = (
    example_robot_data_share() / "example-robot-data" / "robots" / "tiago_description" / "robots" / "tiago_dual.urdf"
)
TOOLS = ["arm_right_tool_link", "arm_left_tool_link"]


# ----- helpers -----


def _edit_element(text: str, tag: str, name: str, old: str, new: str) -> str:
    """Replace ``old`` by ``new`` inside the ``<tag name="name">...</tag>`` element only."""
    match = re.search(rf'<{tag} name="{name}".*?</{tag}>', text, re.S)
    assert match is not None, name
    block = match.group(0)
    assert old in block, (name, old)
    return text[: match.start()] + block.replace(old, new, 1) + text[match.end() :]


def _add_before_end(text: str, xml: str) -> str:
    return text.replace("</robot>", xml + "\n</robot>")


def _write(tmp_path: Path, text: str, name: str = "robot") -> Path:
    path = tmp_path / f"{name}.urdf"
    path.write_text(text)
    return path


def _paper_spec_for(tmp_path: Path, urdf: Path) -> Path:
    """The paper's built-in spec, pointed at another URDF."""
    text = (ROBOTS / "planar_dual_arm.toml").read_text().replace('"planar_dual_arm.urdf"', f'"{urdf.as_posix()}"')
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


def _same_robot(a, b) -> None:
    """Same reduced velocities, constraint matrix, limits and home pose."""
    assert a.reduced_velocity_names == b.reduced_velocity_names
    assert a.model.nv == b.model.nv
    np.testing.assert_array_equal(a.S, b.S)
    np.testing.assert_array_equal(a.neutral(), b.neutral())
    np.testing.assert_allclose(
        end_effector_positions(a, a.neutral()), end_effector_positions(b, b.neutral()), rtol=0, atol=1e-12
    )
    np.testing.assert_array_equal(a.velocity_limits, b.velocity_limits)
    np.testing.assert_array_equal(a.effort_limits, b.effort_limits)


def _extra_wheel(name: str, x: float, y: float) -> str:
    return f"""
  <joint name="{name}" type="continuous">
    <parent link="base_link"/><child link="{name}_link"/>
    <origin xyz="{x} {y} 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit effort="50.0" velocity="10.0"/>
  </joint>
  <link name="{name}_link">
    <inertial><mass value="1.0"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0" rpy="1.5707963267948966 0 0"/>
      <geometry><cylinder radius="0.075" length="0.04"/></geometry></collision>
  </link>"""


def _run(argv, capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


# ----- detection matches the built-in specs -----


def test_detects_the_paper_robot_as_its_spec():
    built_in = find_spec("planar_dual_arm")
    spec = spec_from_urdf(PAPER_URDF, TOOLS)
    assert spec.platform == "differential_drive"
    assert (spec.wheels.right, spec.wheels.left) == (built_in.wheels.right, built_in.wheels.left)
    assert [(a.joints, a.end_effector) for a in spec.arms] == [(a.joints, a.end_effector) for a in built_in.arms]
    assert spec.default_task == built_in.default_task == "planar"  # every arm joint turns about z
    _same_robot(mobmanip.load_robot(spec), mobmanip.load_robot(built_in))


def test_detects_tiago_as_its_specs():
    for torso, name in ((False, "tiago_dual"), (True, "tiago_dual_torso")):
        built_in = find_spec(name)
        found = detect_spec(TIAGO_URDF, TOOLS, torso=torso)
        spec = found.spec
        assert (spec.wheels.right, spec.wheels.left) == ("wheel_right_joint", "wheel_left_joint")
        assert [(a.joints, a.end_effector) for a in spec.arms] == [(a.joints, a.end_effector) for a in built_in.arms]
        assert found.shared_joints == ("torso_lift_joint",)  # on the path to both tools
        assert spec.torso == built_in.torso
        assert spec.reference["torso_lift_joint"] == built_in.reference["torso_lift_joint"]
        assert spec.default_task == "spatial"
        _same_robot(mobmanip.load_robot(spec), mobmanip.load_robot(built_in))


def test_tiago_casters_are_wheel_shaped_but_not_drive_wheels():
    candidates = {c.name: c for c in wheel_candidates(read_urdf(TIAGO_URDF))}
    casters = {n for n in candidates if n.startswith("caster_")}
    assert len(casters) == 4
    assert all(candidates[n].carried_by_rotating_joint for n in casters)  # each hangs on a swivel
    assert not candidates["wheel_right_joint"].carried_by_rotating_joint  # hangs on a prismatic suspension


def test_right_and_left_follow_the_lateral_position_not_the_names(tmp_path):
    # Hang both wheels on a chassis turned by 180 deg about z: the joint called "right" ends up
    # on the left (+y) of the platform and its axis points along -y.
    text = PAPER_URDF.read_text()
    for side in ("right", "left"):
        text = _edit_element(
            text, "joint", f"wheel_{side}_joint", '<parent link="base_link"/>', '<parent link="chassis"/>'
        )
    text = _add_before_end(
        text,
        '<link name="chassis"/><joint name="chassis_joint" type="fixed"><parent link="base_link"/>'
        '<child link="chassis"/><origin xyz="0 0 0" rpy="0 0 3.141592653589793"/></joint>',
    )
    spec = spec_from_urdf(_write(tmp_path, text), TOOLS)
    assert (spec.wheels.right, spec.wheels.left) == ("wheel_left_joint", "wheel_right_joint")
    robot = mobmanip.load_robot(spec)  # the model's own right-of-left check agrees
    x = np.zeros(robot.nx)
    x[:2] = 1.0
    q = robot.neutral()
    linear = unified_jacobian(robot, q, "translational")[:3] @ x
    np.testing.assert_allclose(linear, [0.075, 0.0, 0.0], atol=1e-12)  # forward at r = 0.075 m/s


# ----- wheels: ambiguity and explicit pairs -----


def test_more_than_two_drive_wheels_is_ambiguous(tmp_path):
    text = _add_before_end(
        PAPER_URDF.read_text(),
        _extra_wheel("wheel_front_joint", 0.3, 0.1) + _extra_wheel("wheel_back_joint", -0.3, -0.1),
    )
    path = _write(tmp_path, text)
    with pytest.raises(WheelError) as info:
        spec_from_urdf(path, TOOLS)
    message = str(info.value)
    for name in ("wheel_right_joint", "wheel_left_joint", "wheel_front_joint", "wheel_back_joint"):
        assert name in message
    assert "--wheels" in message
    # An explicit pair settles it; the other wheels are locked.
    spec = spec_from_urdf(path, TOOLS, wheels=("wheel_right_joint", "wheel_left_joint"))
    robot = mobmanip.load_robot(spec)
    assert "wheel_front_joint" not in robot.joint_names
    _same_robot(robot, mobmanip.load_robot("planar_dual_arm"))


def test_a_wheel_shaped_joint_on_an_arm_is_an_arm_joint(tmp_path):
    # Make the right shoulder a continuous joint about the lateral axis whose link is a cylinder
    # about that axis: wheel-shaped, driven and on the base, but on the way to an end effector.
    text = _edit_element(PAPER_URDF.read_text(), "joint", "arm_right_1_joint", 'type="revolute"', 'type="continuous"')
    text = _edit_element(text, "joint", "arm_right_1_joint", '<axis xyz="0 0 1"/>', '<axis xyz="0 1 0"/>')
    cylinder = (
        '</inertial><collision><origin xyz="0 0 0" rpy="1.5707963267948966 0 0"/>'
        '<geometry><cylinder radius="0.05" length="0.1"/></geometry></collision>'
    )
    text = _edit_element(text, "link", "arm_right_1_link", "</inertial>", cylinder)
    path = _write(tmp_path, text)
    assert "arm_right_1_joint" in {c.name for c in wheel_candidates(read_urdf(path))}
    spec = spec_from_urdf(path, TOOLS)
    assert (spec.wheels.right, spec.wheels.left) == ("wheel_right_joint", "wheel_left_joint")
    assert spec.arms[0].joints == ("arm_right_1_joint", "arm_right_2_joint", "arm_right_3_joint")
    assert spec.default_task == "spatial"  # the shoulder now pitches out of the plane


def test_explicit_unknown_wheel_is_named(tmp_path):
    with pytest.raises(JointNotFoundError) as info:
        spec_from_urdf(PAPER_URDF, TOOLS, wheels=("wheel_rigth_joint", "wheel_left_joint"))
    assert "'wheel_rigth_joint'" in str(info.value)
    assert info.value.available[0] == "wheel_right_joint"


def test_a_single_drive_wheel_is_refused(tmp_path):
    text = _edit_element(PAPER_URDF.read_text(), "joint", "wheel_left_joint", 'type="continuous"', 'type="revolute"')
    with pytest.raises(WheelError, match="only one drive wheel: wheel_right_joint"):
        spec_from_urdf(_write(tmp_path, text), TOOLS)


def test_a_robot_without_wheels_is_fixed():
    spec = spec_from_urdf(
        example_robot_data_share() / "example-robot-data/robots/ur_description/urdf/ur5_robot.urdf", ["tool0"]
    )
    assert spec.platform == "fixed" and spec.wheels is None
    assert spec.arms[0].joints == find_spec("ur5").arms[0].joints


# ----- frames -----


def test_unknown_end_effector_lists_frames_closest_first():
    with pytest.raises(FrameNotFoundError) as info:
        spec_from_urdf(TIAGO_URDF, ["arm_rigth_tool_link"])
    assert "'arm_rigth_tool_link'" in str(info.value)
    assert info.value.available[0] == "arm_right_tool_link"
    assert str(info.value).index("arm_right_tool_link") < str(info.value).index("arm_left_tool_link")


# ----- init-spec and analyze --urdf -----


@pytest.mark.parametrize(
    ("urdf", "name", "extra"),
    [
        (PAPER_URDF, "planar_dual_arm", []),
        (TIAGO_URDF, "tiago_dual", []),
        (TIAGO_URDF, "tiago_dual_torso", ["--torso"]),
    ],
)
def test_init_spec_output_loads_back_to_the_built_in_robot(tmp_path, capsys, urdf, name, extra):
    out = tmp_path / "specs" / "robot.toml"
    out.parent.mkdir()
    argv = ["init-spec", urdf, "--ee", TOOLS[0], "--ee", TOOLS[1], "--out", out, *extra]
    code, stdout, stderr = _run(argv, capsys)
    assert (code, stderr) == (0, "")
    assert str(out) in stdout
    text = out.read_text()
    assert text.lstrip().startswith("#")  # commented for the user
    if urdf == PAPER_URDF:
        assert not Path(re.search(r'^urdf = "(.*)"$', text, re.M).group(1)).is_absolute()  # relative to --out
    else:
        assert 'urdf = "example-robot-data:tiago_description/robots/tiago_dual.urdf"' in text
    _same_robot(mobmanip.load_robot(load_spec(out)), mobmanip.load_robot(name))


def test_init_spec_to_stdout_uses_an_absolute_path(tmp_path, capsys, monkeypatch):
    code, stdout, _ = _run(["init-spec", PAPER_URDF, "--ee", TOOLS[0], "--ee", TOOLS[1]], capsys)
    assert code == 0
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "robot.toml").write_text(stdout)
    monkeypatch.chdir(tmp_path)
    _same_robot(mobmanip.load_robot(load_spec(elsewhere / "robot.toml")), mobmanip.load_robot("planar_dual_arm"))


def test_init_spec_for_an_omnidirectional_base_asks_for_its_limits(tmp_path, capsys):
    out = tmp_path / "omni.toml"
    argv = ["init-spec", PAPER_URDF, "--ee", TOOLS[0], "--ee", TOOLS[1], "--platform", "omnidirectional", "--out", out]
    assert _run(argv, capsys)[0] == 0
    text = out.read_text()
    spec = load_spec(out)
    assert spec.platform == "omnidirectional" and spec.wheels is None
    with pytest.raises(MissingLimitError, match="'base_x'"):
        mobmanip.load_robot(spec)
    # Filling in the lines the file flags as required makes it load.
    values = {"velocity": (1.0, 0.5, 2.0), "effort": (300.0, 200.0, 100.0)}
    for kind in ("velocity", "effort"):
        head, table = text.split(f"[limits.{kind}]\n", 1)
        for coordinate, value in zip(("base_x", "base_y", "base_yaw"), values[kind]):
            line = f"# {coordinate} = ...  # REQUIRED for an omnidirectional base"
            assert line in table
            table = table.replace(line, f"{coordinate} = {value}", 1)
        text = f"{head}[limits.{kind}]\n{table}"
    out.write_text(text)
    robot = mobmanip.load_robot(load_spec(out))
    assert robot.reduced_velocity_names[:3] == ("base_x", "base_y", "base_yaw")
    np.testing.assert_array_equal(robot.velocity_limits[:3], values["velocity"])
    np.testing.assert_array_equal(robot.effort_limits[:3], values["effort"])
    assert "wheel_right_joint" not in robot.joint_names


def test_analyze_accepts_a_urdf_instead_of_a_robot(capsys):
    code, by_urdf, _ = _run(["analyze", "--urdf", PAPER_URDF, "--ee", TOOLS[0], "--ee", TOOLS[1]], capsys)
    assert code == 0
    code, by_name, _ = _run(["analyze", "planar_dual_arm"], capsys)
    assert code == 0
    line = next(x for x in by_name.splitlines() if x.startswith("reduced velocities:"))
    assert line in by_urdf.splitlines()


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["analyze"], "give a ROBOT"),
        (["analyze", "planar_dual_arm", "--urdf", PAPER_URDF, "--ee", TOOLS[0]], "not both"),
        (["analyze", "--urdf", PAPER_URDF], "needs at least one --ee"),
        (["analyze", "planar_dual_arm", "--ee", TOOLS[0]], "--ee and --wheels go with --urdf"),
        (["analyze", "--urdf", PAPER_URDF, "--ee", TOOLS[0], "--wheels", "wheel_right_joint"], "RIGHT,LEFT"),
        (["analyze", "--urdf", PAPER_URDF, "--ee", "arm_right_tool"], "unknown frame 'arm_right_tool'"),
        (["init-spec", PAPER_URDF, "--ee", "nowhere_link"], "unknown frame 'nowhere_link'"),
    ],
)
def test_command_line_mistakes_are_one_line_errors(capsys, argv, expected):
    code, stdout, stderr = _run(argv, capsys)
    assert code == 2
    assert stderr.count("\n") == 1 and stderr.startswith("mobmanip: error: ")
    assert expected in stderr


# ----- broken URDFs name what is wrong -----


def _zero_limit(text):
    return _edit_element(text, "joint", "arm_right_2_joint", 'velocity="3.14"', 'velocity="0"')


def _mimic(text):
    return _edit_element(
        text, "joint", "arm_left_3_joint", '<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/><mimic joint="arm_left_2_joint"/>'
    )


def _no_inertia(text):
    return re.sub(r'(<link name="arm_right_3_link">\s*)<inertial>.*?</inertial>', r"\1", text, flags=re.S)


def _closed_loop(text):
    return _add_before_end(
        text,
        '<joint name="loop_joint" type="fixed"><parent link="arm_left_tool_link"/>'
        '<child link="arm_right_tool_link"/></joint>',
    )


def _floating(text):
    return _edit_element(text, "joint", "arm_right_1_joint", 'type="revolute"', 'type="floating"')


def _missing_limit(text):
    return _edit_element(text, "joint", "wheel_left_joint", '<limit effort="200.0" velocity="13.333333333333334"/>', "")


BROKEN = {
    "zero limit": (_zero_limit, LimitError, ["'arm_right_2_joint'", "0.0"]),
    "mimic": (_mimic, UrdfError, ["'arm_left_3_joint'", "mimics 'arm_left_2_joint'"]),
    "no inertia": (_no_inertia, UrdfError, ["'arm_right_3_joint'", "arm_right_3_link", "arm_right_tool_link"]),
    "closed loop": (
        _closed_loop,
        UrdfError,
        ["'arm_right_tool_link'", "'arm_right_tool_joint'", "'loop_joint'", "loop"],
    ),
    "floating": (_floating, UrdfError, ["'arm_right_1_joint'", "'floating'"]),
    "missing limit": (_missing_limit, MissingLimitError, ["'wheel_left_joint'", "[limits.velocity]"]),
}


@pytest.mark.parametrize("case", list(BROKEN))
def test_broken_urdf_with_a_spec_names_the_culprit(tmp_path, case):
    edit, error, needles = BROKEN[case]
    urdf = _write(tmp_path, edit(PAPER_URDF.read_text()))
    with pytest.raises(error) as info:
        mobmanip.load_robot(load_spec(_paper_spec_for(tmp_path, urdf)))
    for needle in needles:
        assert needle in str(info.value)


@pytest.mark.parametrize("case", list(BROKEN))
def test_broken_urdf_on_the_command_line_is_a_one_line_error(tmp_path, capsys, case):
    edit, _, needles = BROKEN[case]
    urdf = _write(tmp_path, edit(PAPER_URDF.read_text()))
    code, _, stderr = _run(["analyze", "--urdf", urdf, "--ee", TOOLS[0], "--ee", TOOLS[1]], capsys)
    assert code == 2
    assert stderr.count("\n") == 1 and stderr.startswith("mobmanip: error: ")
    for needle in needles:
        assert needle in stderr
    if case == "missing limit":  # no spec to put the limit in yet: point at init-spec
        assert "mobmanip init-spec" in stderr


def test_errors_share_one_root():
    for _, error, _ in BROKEN.values():
        assert issubclass(error, MobmanipError)
    for error in (WheelError, FrameNotFoundError, JointNotFoundError):
        assert issubclass(error, MobmanipError)


# ----- spec_to_toml round trip -----


def test_spec_to_toml_round_trips_every_field(tmp_path):
    spec = RobotSpec(
        name='paper "custom"',
        urdf=PAPER_URDF,
        platform="differential_drive",
        arms=(
            ArmSpec("right", ("arm_right_2_joint", "arm_right_3_joint"), "arm_right_tool_link"),
            ArmSpec("left", ("arm_left_1_joint", "arm_left_2_joint", "arm_left_3_joint"), "arm_left_tool_link"),
        ),
        wheels=WheelSpec("wheel_right_joint", "wheel_left_joint", radius=0.08, half_track=0.2),
        default_task="planar_rigid",
        velocity_limits={"arm_right_2_joint": 2.5, "wheel_left_joint": 10.0},
        effort_limits={"arm_left_1_joint": 150.0},
        object_mass=3.5,
        reference={"arm_right_1_joint": math.pi / 7},
        torso=(),
        support=SupportSpec(
            casters=((0.3, 0.1), (-0.25, -0.125, 0.01)),
            mu=0.7,
            faces=6,
            urdf_casters=False,
            stiffness={"caster_0": 0.4, "wheel_right_joint": 2.5},
            wheels=((0.5, 0.5),),
            rollers=(45.0,),
        ),
    )
    path = tmp_path / "a" / "spec.toml"
    path.parent.mkdir()
    path.write_text(spec_to_toml(spec, path.parent))
    back = load_spec(path)
    for field in dataclasses.fields(RobotSpec):
        if field.name == "urdf":  # written relative to the spec's directory
            assert back.urdf.resolve() == spec.urdf.resolve()
        elif field.name not in ("source", "package_dirs"):
            assert getattr(back, field.name) == getattr(spec, field.name), field.name
    robot = mobmanip.load_robot(back)
    assert robot.reduced_velocity_names[2:4] == ("arm_right_2_joint", "arm_right_3_joint")
    assert robot.platform.radius == 0.08 and robot.platform.half_track == 0.2
