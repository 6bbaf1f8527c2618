"""Hostile and broken input (1): physically invalid models are refused at load, naming the link
or joint and the value, and every failure of the command line is one line with exit code 2."""

from __future__ import annotations

import os

import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli, write_robot
from mobmanip.errors import LimitError, RangeError, UrdfError, WheelError
from mobmanip.support.native_stderr import captured_native_stderr
from mobmanip.support.ranges import EFFORT_LIMIT, LIMIT_RATIO, VELOCITY_LIMIT

WHEEL_MASS = '<mass value="5.0"/>'
WHEEL_INERTIA = 'ixx="0.135" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.135"'
WHEEL_LIMIT = 'effort="200.0" velocity="13.333333333333334"'
ARM_AXIS = '<axis xyz="0 0 1"/>'


def _inertia(ixx, iyy, izz, ixy=0.0, ixz=0.0, iyz=0.0):
    return f'ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" izz="{izz}"'


# Each case: URDF edits, then what the one-line message must name (the link or joint, the value).
PHYSICAL = {
    "nan mass": ([(WHEEL_MASS, '<mass value="nan"/>')], ["wheel_right_link", "mass", "nan"]),
    "negative mass": ([(WHEEL_MASS, '<mass value="-5.0"/>')], ["wheel_right_link", "-5"]),
    "infinite mass": ([(WHEEL_MASS, '<mass value="inf"/>')], ["wheel_right_link", "inf"]),
    "huge mass": ([(WHEEL_MASS, '<mass value="1e300"/>')], ["wheel_right_link", "1e+300"]),
    "negative moment": ([(WHEEL_INERTIA, _inertia(-0.135, 0.01, 0.135))], ["wheel_right_link", "positive"]),
    "indefinite products": ([(WHEEL_INERTIA, _inertia(0.135, 0.01, 0.135, ixy=0.2))], ["wheel_right_link", "positive"]),
    "triangle inequality": ([(WHEEL_INERTIA, _inertia(1.0, 0.01, 0.135))], ["wheel_right_link", "triangle"]),
    "nan inertia": ([(WHEEL_INERTIA, _inertia(0.135, "nan", 0.135))], ["wheel_right_link", "inertia", "nan"]),
    "zero wheel axis": ([('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>')], ["wheel_right_joint", "axis"]),
    "zero arm axis": ([(ARM_AXIS, '<axis xyz="0 0 0"/>')], ["arm_right_1_joint", "axis"]),
    "nan arm axis": ([(ARM_AXIS, '<axis xyz="0 nan 1"/>')], ["arm_right_1_joint", "axis", "nan"]),
    "nan velocity": ([(WHEEL_LIMIT, 'effort="200.0" velocity="nan"')], ["wheel_right_joint", "velocity", "nan"]),
    "negative velocity": ([(WHEEL_LIMIT, 'effort="200.0" velocity="-1"')], ["wheel_right_joint", "velocity", "-1"]),
    "negative effort": ([(WHEEL_LIMIT, 'effort="-200" velocity="13"')], ["wheel_right_joint", "effort", "-200"]),
    "infinite effort": ([(WHEEL_LIMIT, 'effort="inf" velocity="13"')], ["wheel_right_joint", "effort", "inf"]),
    "nan origin": ([('<origin xyz="0 -0.171 0"', '<origin xyz="0 nan 0"')], ["wheel_right_joint", "origin", "nan"]),
    "duplicate link": (
        [('<link name="wheel_right_link">', '<link name="base_link"/><link name="wheel_right_link">')],
        ["base_link", "more than once"],
    ),
    "duplicate joint": (
        [('<joint name="wheel_left_joint"', '<joint name="wheel_right_joint"')],
        ["wheel_right_joint", "more than once"],
    ),
}


@pytest.mark.parametrize("case", sorted(PHYSICAL))
def test_physically_invalid_urdf_is_refused_naming_where_and_what(tmp_path, capfd, case):
    edits, needles = PHYSICAL[case]
    spec = write_robot(tmp_path, urdf_edits=edits)
    with pytest.raises((UrdfError, WheelError)):
        mobmanip.load_robot(spec)
    code, out, err = run_cli(capfd, "analyze", spec)
    assert_one_line_error(code, err, *needles)
    assert out == ""  # nothing analysed


def test_arm_joint_limits_the_wrong_way_round_are_refused(tmp_path, capfd):
    limit = '<limit lower="-3.141592653589793" upper="3.141592653589793" effort="100.0" velocity="3.14"/>'
    swapped = '<limit lower="1.5" upper="-1.5" effort="100.0" velocity="3.14"/>'
    spec = write_robot(tmp_path, urdf_edits=[(limit, swapped)])
    code, _, err = run_cli(capfd, "analyze", spec)
    assert_one_line_error(code, err, "lower=1.5", "upper=-1.5")


def test_real_robots_with_rounding_in_small_links_still_load():
    # TIAGo++'s antenna links (1 mg) have principal moments a few 1e-8 kg m^2 off positivity.
    robot = mobmanip.load_robot("tiago_dual")
    assert robot.nx == 16


@pytest.mark.parametrize(
    ("edit", "needles"),
    [
        (("# radius = 0.075", "radius = 0.0"), ["radius", "0.0"]),
        (("# radius = 0.075", "radius = -0.075"), ["radius", "-0.075"]),
        (("# radius = 0.075", "radius = nan"), ["radius", "nan"]),
        (("# radius = 0.075", "radius = 1e300"), ["radius", "1e+300"]),
        (("# half_track = 0.171", "half_track = 0"), ["half_track", "0"]),
    ],
)
def test_wheel_geometry_in_a_spec_is_checked(tmp_path, capfd, edit, needles):
    spec = write_robot(tmp_path, spec_edits=[edit])
    code, _, err = run_cli(capfd, "analyze", spec)
    assert_one_line_error(code, err, *needles)


def test_wheel_radius_from_the_urdf_geometry_is_checked(tmp_path, capfd):
    spec = write_robot(
        tmp_path,
        urdf_edits=[
            ('<cylinder radius="0.075" length="0.04"/>', '<cylinder radius="0" length="0.04"/>'),
            ('<cylinder radius="0.075" length="0.04"/>', '<cylinder radius="0" length="0.04"/>'),
        ],
    )
    code, _, err = run_cli(capfd, "analyze", spec)
    assert_one_line_error(code, err, "wheel_right_joint", "radius")


@pytest.mark.parametrize(
    ("kind", "value"),
    [("velocity", 1e-300), ("velocity", 1e12), ("effort", 1e-300), ("effort", 1e12), ("effort", 1e300)],
)
def test_limits_outside_the_supported_range_are_refused(robot, kind, value):
    low, high = VELOCITY_LIMIT if kind == "velocity" else EFFORT_LIMIT
    assert not low <= value <= high
    with pytest.raises(RangeError, match="wheel_right_joint") as info:
        robot.with_wheel_limits(**{kind: value})
    assert "supported range" in str(info.value)


def test_limits_whose_ratio_is_too_large_are_refused_naming_both(robot):
    slow = robot.with_limits(velocity={"arm_left_3_joint": 1.0})  # the smallest limit: 1 rad/s
    with pytest.raises(RangeError, match="ratio") as info:
        slow.with_wheel_limits(velocity=LIMIT_RATIO * 1.5)
    assert "wheel_right_joint" in str(info.value) and "arm_left_3_joint" in str(info.value)
    slow.with_wheel_limits(velocity=LIMIT_RATIO * 0.9)  # inside: accepted


def test_non_positive_limits_are_refused(robot):
    for value in (0.0, -1.0, float("nan"), "fast"):
        with pytest.raises(LimitError):
            robot.with_wheel_limits(velocity=value)


# ----- one error path


def test_native_stderr_is_captured():
    with captured_native_stderr() as native:
        os.write(2, b"Error:   joint [j]: velocity value (nan) is not a valid float\n         at line 224 in x.cpp\n")
    assert native.first_error() == "joint [j]: velocity value (nan) is not a valid float"


def test_pinocchio_parser_messages_never_reach_the_terminal_raw(tmp_path, capfd):
    # urdfdom rejects a non-numeric limit that yourdfpy would read: mobmanip must report it in one line.
    spec = write_robot(tmp_path, urdf_edits=[(WHEEL_LIMIT, 'effort="200.0" velocity="13.3x"')])
    code, out, err = run_cli(capfd, "analyze", spec)
    line = assert_one_line_error(code, err)
    assert "at line" not in line and ".cpp" not in line


@pytest.mark.parametrize(
    "argv",
    [
        ["--wheel-effort-limit", "1e-300"],
        ["--wheel-effort-limit", "1e300"],
        ["--wheel-velocity-limit", "1e308"],
        ["--wheel-velocity-limit", "nan"],
        ["--object-mass", "1e308"],
        ["--object-mass", "inf"],
        ["--object-mass", "-1"],
    ],
)
def test_extreme_command_line_values_give_one_line_and_no_warning(capfd, argv):
    code, out, err = run_cli(capfd, "analyze", "planar_dual_arm", *argv)
    assert_one_line_error(code, err, repr(float(argv[1])))
    assert "Warning" not in err


def test_a_bug_is_one_line_too(monkeypatch, capfd):
    import mobmanip.cli as cli
    from mobmanip.commands import analyze

    def broken(args):
        raise TypeError("something internal")

    monkeypatch.setattr(analyze, "run", broken)  # the parser is built at each call
    monkeypatch.delenv("MOBMANIP_TRACEBACK", raising=False)
    capfd.readouterr()
    code = cli.main(["analyze", "planar_dual_arm"])
    lines = capfd.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1
    assert lines[0].startswith("mobmanip: error: internal error (TypeError: something internal)")
