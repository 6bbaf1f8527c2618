"""The paper robot's URDF (Tables 1 and 2), its spec, and the errors bad specs and URDFs raise."""

from __future__ import annotations

import importlib.util
import inspect
import re

import numpy as np
import pytest
import yourdfpy

import mobmanip
import mobmanip.errors
from conftest import HALF_TRACK, PAPER_SPEC, PAPER_URDF, ROOT, WHEEL_RADIUS, replace_joint_block, write_variant
from mobmanip.errors import (
    JointNotFoundError,
    LimitError,
    MobmanipError,
    SpecError,
    UnknownRobotError,
    UrdfError,
    WheelError,
)

ARM_JOINTS = [f"arm_{side}_{k}_joint" for side in ("right", "left") for k in (1, 2, 3)]
# Table 1 (per joint 1, 2, 3) and Table 2 (wheels: 200 N m, rim speed 1 m/s -> 1/r rad/s).
ARM_EFFORT = (200.0, 100.0, 30.0)
ARM_VELOCITY = 3.14
WHEEL_EFFORT = 200.0
WHEEL_VELOCITY = 1.0 / WHEEL_RADIUS


def load_generator():
    path = ROOT / "scripts" / "generate_planar_dual_arm.py"
    spec = importlib.util.spec_from_file_location("generate_planar_dual_arm", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def urdf():
    return yourdfpy.URDF.load(str(PAPER_URDF), build_scene_graph=False, load_meshes=False)


# ----- the committed URDF -----


def test_generator_reproduces_the_committed_urdf_byte_for_byte(tmp_path, capsys):
    generator = load_generator()
    committed = PAPER_URDF.read_bytes()
    assert generator.generate().encode() == committed
    out = tmp_path / "regenerated.urdf"
    assert generator.main(["--out", str(out)]) == 0
    assert out.read_bytes() == committed
    assert str(out) in capsys.readouterr().out


def test_yourdfpy_validates_the_committed_urdf(urdf):
    assert urdf.validate() is True
    assert urdf.robot.name == "planar_dual_arm"


def test_urdf_masses_and_inertias_are_tables_1_and_2(urdf):
    links = urdf.link_map

    def inertial(name):
        item = links[name].inertial
        return item.mass, np.asarray(item.inertia), np.asarray(item.origin)[:3, 3]

    mass, inertia, com = inertial("base_link")
    assert mass == 94.0
    assert inertia[2, 2] == 6.609  # I_c about the vertical through P_o
    np.testing.assert_array_equal(com, 0.0)  # platform centre of mass at P_o
    for side in ("right", "left"):
        mass, inertia, com = inertial(f"wheel_{side}_link")
        assert mass == 5.0
        assert inertia[1, 1] == 0.01  # I_w about the axle (y)
        assert inertia[0, 0] == inertia[2, 2] == 0.135  # I_m about a diameter
        np.testing.assert_array_equal(com, 0.0)
        for k, (m, lc, izz) in enumerate(zip((10.0, 6.0, 2.0), (0.25, 0.25, 0.1), (0.5, 0.3, 0.01)), start=1):
            mass, inertia, com = inertial(f"arm_{side}_{k}_link")
            assert mass == m
            assert inertia[2, 2] == izz
            np.testing.assert_array_equal(com, [lc, 0.0, 0.0])


def test_urdf_geometry_is_tables_1_and_2(urdf):
    joints = urdf.joint_map
    for side, y in (("right", -HALF_TRACK), ("left", HALF_TRACK)):
        wheel = joints[f"wheel_{side}_joint"]
        assert wheel.type == "continuous"
        np.testing.assert_array_equal(np.asarray(wheel.origin)[:3, 3], [0.0, y, 0.0])
        (collision,) = urdf.link_map[f"wheel_{side}_link"].collisions
        assert collision.geometry.cylinder.radius == WHEEL_RADIUS
        # Both arms start at P_o in the horizontal plane, with vertical joint axes.
        first = joints[f"arm_{side}_1_joint"]
        np.testing.assert_array_equal(np.asarray(first.origin)[:2, 3], 0.0)
        for k in (1, 2, 3):
            np.testing.assert_array_equal(joints[f"arm_{side}_{k}_joint"].axis, [0.0, 0.0, 1.0])
        # Link lengths L_i = 0.5 m: the offsets of joint 2, joint 3 and the tool.
        for child in (f"arm_{side}_2_joint", f"arm_{side}_3_joint", f"arm_{side}_tool_joint"):
            np.testing.assert_array_equal(np.asarray(joints[child].origin)[:3, 3], [0.5, 0.0, 0.0])


def test_urdf_limits_are_tables_1_and_2(urdf):
    joints = urdf.joint_map
    for side in ("right", "left"):
        wheel = joints[f"wheel_{side}_joint"].limit
        assert wheel.effort == WHEEL_EFFORT
        assert wheel.velocity == pytest.approx(WHEEL_VELOCITY, rel=1e-15)
        for k, effort in enumerate(ARM_EFFORT, start=1):
            limit = joints[f"arm_{side}_{k}_joint"].limit
            assert limit.effort == effort
            assert limit.velocity == ARM_VELOCITY


# ----- the loaded robot -----


def test_loaded_platform_geometry(robot):
    assert robot.platform.kind == "differential_drive"
    assert robot.platform.radius == pytest.approx(WHEEL_RADIUS, abs=1e-12)
    assert robot.platform.half_track == pytest.approx(HALF_TRACK, abs=1e-12)
    np.testing.assert_allclose(robot.platform.axle_center, 0.0, atol=1e-12)


def test_reduced_velocity_order(robot):
    assert robot.reduced_velocity_names == ("wheel_right_joint", "wheel_left_joint", *ARM_JOINTS)
    assert [arm.end_effector for arm in robot.arms] == ["arm_right_tool_link", "arm_left_tool_link"]


def test_loaded_limits_per_reduced_velocity(robot):
    np.testing.assert_allclose(robot.velocity_limits, [WHEEL_VELOCITY] * 2 + [ARM_VELOCITY] * 6, rtol=1e-15)
    np.testing.assert_array_equal(robot.effort_limits, [WHEEL_EFFORT] * 2 + list(ARM_EFFORT) * 2)


def test_limit_overrides_replace_only_what_they_name(robot):
    changed = robot.with_wheel_limits(velocity=0.5 / WHEEL_RADIUS, effort=50.0).with_limits(
        effort={"arm_left_3_joint": 12.0}
    )
    np.testing.assert_allclose(changed.velocity_limits, [0.5 / WHEEL_RADIUS] * 2 + [ARM_VELOCITY] * 6, rtol=1e-15)
    np.testing.assert_array_equal(changed.effort_limits, [50.0, 50.0, 200.0, 100.0, 30.0, 200.0, 100.0, 12.0])
    # The original robot is untouched.
    np.testing.assert_array_equal(robot.effort_limits, [WHEEL_EFFORT] * 2 + list(ARM_EFFORT) * 2)


# ----- errors -----


def error_classes():
    """Every exception class defined in mobmanip's error and I/O modules."""
    modules = (mobmanip.errors, mobmanip.support.files)
    return sorted(
        {
            obj
            for module in modules
            for _, obj in inspect.getmembers(module, inspect.isclass)
            if issubclass(obj, Exception) and obj.__module__ == module.__name__
        },
        key=lambda cls: cls.__name__,
    )


def test_every_error_class_is_a_mobmanip_error():
    classes = error_classes()
    assert len(classes) >= 9
    for cls in classes:
        assert issubclass(cls, MobmanipError), cls


def test_unknown_robot(tmp_path):
    with pytest.raises(UnknownRobotError) as info:
        mobmanip.load_robot("planar_dual_armm")
    assert isinstance(info.value, MobmanipError)
    assert "planar_dual_armm" in str(info.value)
    assert "planar_dual_arm" in info.value.builtins
    with pytest.raises(UnknownRobotError):
        mobmanip.load_robot(str(tmp_path / "nowhere.toml"))


def test_spec_naming_missing_joints_and_frame_names_each(tmp_path):
    spec = write_variant(
        tmp_path,
        PAPER_URDF.read_text(),
        spec_edits=[
            ('"arm_right_2_joint"', '"arm_right_elbow_joint"'),
            ('"arm_left_3_joint"', '"arm_left_wrist_joint"'),
            ('end_effector = "arm_left_tool_link"', 'end_effector = "arm_left_gripper_link"'),
        ],
    )
    with pytest.raises(SpecError) as info:
        mobmanip.load_robot(spec)
    message = str(info.value)
    for name in ("arm_right_elbow_joint", "arm_left_wrist_joint", "arm_left_gripper_link"):
        assert name in message
    assert "arm_right_2_joint" in message  # the closest existing name is suggested


def test_spec_naming_a_missing_wheel_joint(tmp_path):
    spec = write_variant(
        tmp_path, PAPER_URDF.read_text(), spec_edits=[('left = "wheel_left_joint"', 'left = "wheel_l"')]
    )
    with pytest.raises(SpecError, match="wheel_l'"):
        mobmanip.load_robot(spec)


def test_urdf_without_the_spec_wheel_joint(tmp_path):
    text = PAPER_URDF.read_text().replace('name="wheel_left_joint"', 'name="caster_joint"')
    with pytest.raises(SpecError, match="wheel_left_joint"):
        mobmanip.load_robot(write_variant(tmp_path, text))


def test_differential_drive_spec_without_wheels(tmp_path):
    spec = write_variant(
        tmp_path,
        PAPER_URDF.read_text(),
        spec_edits=[('[wheels]\nright = "wheel_right_joint"\nleft = "wheel_left_joint"\n', "")],
    )
    with pytest.raises(SpecError, match="wheels"):
        mobmanip.load_robot(spec)


def _truncation_cases():
    text = PAPER_URDF.read_text()
    after_last_arm_link = text.index("</link>", text.index('<link name="arm_left_3_link"')) + len("</link>")
    return [
        pytest.param(len(text) // 2, id="half"),
        pytest.param(text.index('name="arm_left_2_link"') + 12, id="inside-attribute"),
        pytest.param(text.rindex("</robot>"), id="no-closing-robot-tag"),
        pytest.param(40, id="inside-xml-declaration"),
        pytest.param(
            after_last_arm_link,
            id="after-complete-element",
        ),
    ]


@pytest.mark.parametrize("cut", _truncation_cases())
def test_truncated_urdf_is_a_urdf_error_naming_the_path(tmp_path, cut):
    spec = write_variant(tmp_path, PAPER_URDF.read_text()[:cut])
    with pytest.raises(UrdfError) as info:
        mobmanip.load_robot(spec)
    assert str(tmp_path / "variant.urdf") in str(info.value)
    assert info.value.path == str(tmp_path / "variant.urdf")


@pytest.mark.parametrize("content", ["", "not xml at all", "<robot name='x'/>"], ids=["empty", "text", "no-links"])
def test_malformed_urdf_is_a_urdf_error_naming_the_path(tmp_path, content):
    spec = write_variant(tmp_path, content)
    with pytest.raises(UrdfError) as info:
        mobmanip.load_robot(spec)
    assert str(tmp_path / "variant.urdf") in str(info.value)


def test_missing_urdf_is_a_urdf_error_naming_the_path(tmp_path):
    spec = write_variant(tmp_path, "")
    (tmp_path / "variant.urdf").unlink()
    with pytest.raises(UrdfError) as info:
        mobmanip.load_robot(spec)
    assert str(tmp_path / "variant.urdf") in str(info.value)


@pytest.mark.parametrize(
    ("kind", "joint", "literal", "value"),
    [
        ("effort", "arm_right_1_joint", "0", 0.0),
        ("effort", "arm_left_2_joint", "-1", -1.0),
        ("velocity", "wheel_right_joint", "nan", float("nan")),
        ("velocity", "arm_right_3_joint", "-0.5", -0.5),
        ("effort", "wheel_left_joint", "inf", float("inf")),
    ],
)
def test_non_positive_limit_override_is_a_limit_error(tmp_path, kind, joint, literal, value):
    spec_text = PAPER_SPEC.read_text()
    assert "[limits" not in spec_text.replace("# [limits", "")
    spec = write_variant(tmp_path, PAPER_URDF.read_text())
    spec.write_text(spec.read_text() + f"\n[limits.{kind}]\n{joint} = {literal}\n")
    with pytest.raises(LimitError) as info:
        mobmanip.load_robot(spec)
    error = info.value
    assert isinstance(error, MobmanipError)
    assert error.name == joint and error.kind == kind
    assert error.value == value or (np.isnan(value) and np.isnan(error.value))
    assert joint in str(error) and literal in str(error)


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf"), None])
def test_non_positive_limit_in_python_is_a_limit_error(robot, value):
    with pytest.raises(LimitError) as info:
        robot.with_limits(velocity={"arm_left_1_joint": value})
    assert info.value.name == "arm_left_1_joint"
    assert "arm_left_1_joint" in str(info.value) and repr(value) in str(info.value)
    with pytest.raises(LimitError):
        robot.with_wheel_limits(effort=value if value is not None else 0.0)


def test_limit_for_an_unknown_joint(robot):
    with pytest.raises(JointNotFoundError, match="arm_left_9_joint"):
        robot.with_limits(effort={"arm_left_9_joint": 10.0})


def test_toml_syntax_error_is_a_spec_error(tmp_path):
    spec = write_variant(tmp_path, PAPER_URDF.read_text())
    spec.write_text(spec.read_text() + "\n[[arms]\nname = 'third'\n")
    with pytest.raises(SpecError) as info:
        mobmanip.load_robot(spec)
    assert str(spec) in str(info.value)


@pytest.mark.parametrize(
    ("hold", "message"),
    [
        ("wheel_left_joint = 0.5", "'wheel_left_joint', which is not an arm or torso joint"),
        ("arm_left_2_joint = nan", "hold position of 'arm_left_2_joint' must be a finite number"),
        ('arm_left_2_joint = "bent"', "hold position of 'arm_left_2_joint' must be a finite number"),
        ("arm_left_2_joint = 3.5", r"arm_left_2_joint = 3\.5 lies outside its range \[-3\.14159, 3\.14159\]"),
    ],
)
def test_bad_hold_posture_is_a_spec_error_naming_it(tmp_path, hold, message):
    spec = write_variant(tmp_path, PAPER_URDF.read_text())
    spec.write_text(spec.read_text() + f"\n[hold]\narm_right_2_joint = 1.0\n{hold}\n")
    with pytest.raises(SpecError, match=message):
        mobmanip.load_robot(spec)


def test_hold_posture_of_a_spec(tmp_path):
    spec = write_variant(tmp_path, PAPER_URDF.read_text())
    spec.write_text(spec.read_text() + "\n[hold]\narm_right_2_joint = 1.0\narm_left_2_joint = -1.0\n")
    robot = mobmanip.load_robot(spec)
    expected = robot.configuration(joints={"arm_right_2_joint": 1.0, "arm_left_2_joint": -1.0})
    np.testing.assert_array_equal(robot.hold_configuration(), expected)
    np.testing.assert_array_equal(mobmanip.load_robot("planar_dual_arm").hold_configuration(), robot.neutral())


def _wheels_without_geometry():
    text = PAPER_URDF.read_text()
    for side in ("right", "left"):
        pattern = re.compile(rf'(<link name="wheel_{side}_link">.*?</inertial>\n).*?(  </link>)', re.S)
        text, count = pattern.subn(r"\1\2", text)
        assert count == 1
    assert "cylinder" not in text
    return text


def test_wheel_without_cylinder_or_sphere_is_a_wheel_error(tmp_path):
    with pytest.raises(WheelError, match="radius"):
        mobmanip.load_robot(write_variant(tmp_path, _wheels_without_geometry()))


def test_wheel_radius_from_the_spec_when_the_urdf_has_no_geometry(tmp_path):
    spec = write_variant(tmp_path, _wheels_without_geometry(), spec_edits=[("# radius = 0.075", "radius = 0.08")])
    robot = mobmanip.load_robot(spec)
    assert robot.platform.radius == 0.08
    assert robot.platform.c == pytest.approx(0.08 / (2 * HALF_TRACK), rel=1e-12)


def test_spherical_wheel_radius(tmp_path):
    text = PAPER_URDF.read_text().replace('<cylinder radius="0.075" length="0.04"/>', '<sphere radius="0.1"/>')
    assert text.count("sphere") == 4
    robot = mobmanip.load_robot(write_variant(tmp_path, text))
    assert robot.platform.radius == 0.1


def test_wheel_turning_about_a_vertical_axis_is_a_wheel_error(tmp_path):
    text = replace_joint_block(PAPER_URDF.read_text(), "wheel_left_joint", '<axis xyz="0 1 0"/>', '<axis xyz="0 0 1"/>')
    with pytest.raises(WheelError, match="wheel_left_joint"):
        mobmanip.load_robot(write_variant(tmp_path, text))


# ----- xacro substitutions left in a URDF -----


def test_optenv_substitution_reads_as_its_default(tmp_path, monkeypatch):
    """``$(optenv NAME DEFAULT)`` (as in Husky's shipped URDF) is its default, whatever the environment."""
    monkeypatch.setenv("ARM_XYZ", "9 9 9")
    text = replace_joint_block(
        PAPER_URDF.read_text(), "arm_right_2_joint", 'xyz="0.5 0.0 0.0"', 'xyz="$(optenv ARM_XYZ 0.5 0.0 0.0)"'
    )
    robot = mobmanip.load_robot(write_variant(tmp_path, text))
    reference = mobmanip.load_robot("planar_dual_arm")
    q = reference.configuration((0.3, -0.2, 0.7), {"arm_right_2_joint": 0.4, "arm_left_3_joint": -0.9})
    np.testing.assert_array_equal(
        mobmanip.unified_jacobian(robot, q, "planar"), mobmanip.unified_jacobian(reference, q, "planar")
    )


@pytest.mark.parametrize("substitution", ["$(arg arm_roll)", "$(find my_robot)", "$(optenv ONLY_A_NAME)"])
def test_other_xacro_substitution_is_a_urdf_error_naming_it_and_its_line(tmp_path, substitution):
    text = replace_joint_block(PAPER_URDF.read_text(), "arm_right_2_joint", 'rpy="0 0 0"', f'rpy="{substitution}"')
    line = text[: text.index(substitution)].count("\n") + 1
    with pytest.raises(UrdfError, match=rf"line {line}: unexpanded xacro substitution '{re.escape(substitution)}'"):
        mobmanip.load_robot(write_variant(tmp_path, text))


def test_substitutions_in_comments_simulator_sections_and_mesh_names_are_left_alone(tmp_path):
    """As in TIAGo Pro's shipped URDF: a commented-out xacro include, and others where no model is built from."""
    extra = (
        '<!-- <xacro:include filename="$(find gripper)/urdf/g.xacro"/> -->'
        '<gazebo reference="base_link"><plugin filename="$(arg plugin)"/></gazebo>'
        '<transmission name="t"><joint name="$(arg j)"/></transmission>'
    )
    text = PAPER_URDF.read_text().replace("</robot>", extra + "</robot>")
    text = replace_joint_block(text, "arm_right_2_joint", 'rpy="0 0 0"', 'rpy="$(optenv R 0 0 0)"')
    robot = mobmanip.load_robot(write_variant(tmp_path, text))
    assert robot.nx == mobmanip.load_robot("planar_dual_arm").nx
