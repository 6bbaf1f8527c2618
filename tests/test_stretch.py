"""Hello Robot's Stretch: detection that explains itself on its URDF (mesh wheels without
limits, a telescoping arm with placeholder limits) and the sourced built-in spec."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.analysis.plausibility import limit_warnings
from mobmanip.cli import main
from mobmanip.descriptions.resources import stretch_urdf_dir
from mobmanip.descriptions.urdf import read_urdf
from mobmanip.postures.named import named_configuration
from mobmanip.robot.detect import arm_joints, detect_spec
from mobmanip.robot.detect_report import candidate_frames

URDF = stretch_urdf_dir() / "SE3" / "stretch_description_SE3_eoa_wrist_dw3_tool_sg3.urdf"
EE = "link_grasp_center"
WHEELS = ("joint_right_wheel", "joint_left_wheel")


def _run(argv, capsys):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_mesh_wheels_are_found_and_everything_missing_is_asked_at_once(tmp_path, capsys):
    found = detect_spec(URDF, [EE])
    assert found.spec.platform == "differential_drive"
    assert (found.spec.wheels.right, found.spec.wheels.left) == WHEELS
    lines = [line for line in found.considered if line.startswith("wheel-like joint")]
    assert len(lines) == 2 and all("mesh geometry" in line and "platform wheel" in line for line in lines)
    assert found.considered[-1].startswith("platform differential_drive")
    missing = {m.flag.split()[0]: set(m.names) for m in found.missing}
    assert missing == {
        "--wheel-radius": set(WHEELS),
        "--wheel-velocity-limit": set(WHEELS),
        "--wheel-effort-limit": set(WHEELS),
    }
    # the command prints them in one message (one line on standard error)
    out = tmp_path / "stretch.toml"
    code, stdout, err = _run(["init-spec", URDF, "--ee", EE, "--out", out], capsys)
    assert code == 0 and "mesh geometry" in stdout
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1
    assert all(flag in warnings[0] for flag in ("--wheel-radius", "--wheel-velocity-limit", "--wheel-effort-limit"))


def test_flags_fill_the_gaps_and_the_geometry_is_the_urdf(tmp_path, capsys):
    out = tmp_path / "stretch.toml"
    argv = ["init-spec", URDF, "--ee", EE, "--out", out, "--wheel-radius", "0.0508"]
    code, _, err = _run(argv + ["--wheel-velocity-limit", "5.9", "--wheel-effort-limit", "4.7"], capsys)
    assert code == 0 and "warning" not in err
    robot = mobmanip.load_robot(mobmanip.robot.spec.load_spec(out))
    assert robot.platform.radius == 0.0508
    urdf = read_urdf(URDF)
    y = [urdf.joints[name].origin.xyz[1] for name in WHEELS]  # the wheels' lateral offsets
    assert abs(robot.platform.half_track - 0.5 * (y[1] - y[0])) < 1e-12
    np.testing.assert_array_equal(robot.velocity_limits[:2], [5.9, 5.9])
    np.testing.assert_array_equal(robot.effort_limits[:2], [4.7, 4.7])
    # the URDF's own arm limits are the placeholders of the issue: flagged, both kinds
    found = limit_warnings(robot)
    assert len(found) == 2 and "1 rad/s" in found[0] and "100 N m" in found[1]


def test_list_frames_ranks_the_grasp_centre_first(capsys):
    code, out, _ = _run(["init-spec", URDF, "--list-frames"], capsys)
    assert code == 0
    rows = out.splitlines()[1:]
    assert rows[0].split()[0] == EE
    urdf = read_urdf(URDF)
    for link, count, _, _ in candidate_frames(urdf, exclude=WHEELS):
        assert count == len(arm_joints(urdf, link, WHEELS))  # actuated joints from the root, counted again
    assert not any(row.split()[0].startswith("link_right_wheel") for row in rows)


def test_init_spec_needs_ee_unless_listing(capsys):
    code, _, err = _run(["init-spec", URDF], capsys)
    assert code == 2 and "--list-frames" in err


# ----- the built-in spec -----


@pytest.fixture(scope="module")
def stretch():
    return mobmanip.load_robot("stretch")


def test_built_in_limits_are_the_sourced_ones(stretch):
    names = stretch.reduced_velocity_names
    assert names == (*WHEELS, "joint_lift", "joint_arm_l0", "joint_wrist_yaw")
    rim = stretch.velocity_limits[:2] * stretch.platform.radius
    np.testing.assert_allclose(rim, 0.3, rtol=1e-4)  # the SDK's base max speed, m/s
    np.testing.assert_allclose(stretch.effort_limits[2:4], [75.0 * 4.35, 55.9 * 4.35], rtol=2e-3)
    assert limit_warnings(stretch) == ()
    assert mobmanip.analyze(stretch, stretch.neutral()).warnings == ()


def test_lift_alone_sets_the_vertical_speed(stretch):
    """The kinematic ellipsoid of one end effector reaches ||Y J^T u|| along a unit u (Y the
    velocity limits); at home the z row of J is the lift's 1 and entries of 1e-5 (the URDF's
    rounded angles), so the reach along z is the lift's 0.15 m/s to 1e-5."""
    an = mobmanip.analyze(stretch, stretch.neutral(), "translational")
    J = an.unified_jacobian
    up = np.array([0.0, 0.0, 1.0])
    by_hand = np.linalg.norm(stretch.velocity_limits * (J.T @ up))
    assert abs(an.kinematic.support(up) - by_hand) < 1e-12 * by_hand
    assert abs(by_hand - 0.15) < 1e-5
    lift = stretch.reduced_velocity_names.index("joint_lift")
    assert abs(J[2, lift] - 1.0) < 1e-9 and np.max(np.abs(np.delete(J[2], lift))) < 1e-4


def test_stow_posture_is_the_sdk_stow(stretch):
    q = named_configuration(stretch, "stow")
    joints = stretch.configuration_dict(q)["joints"]
    assert joints["joint_lift"] == 0.23 and joints["joint_wrist_yaw"] == 3.4 and joints["joint_arm_l0"] == 0.0
    pin.framesForwardKinematics(stretch.model, stretch.data, q)
    low = stretch.data.oMf[stretch.arms[0].frame_id].translation[2]
    pin.framesForwardKinematics(stretch.model, stretch.data, stretch.neutral())
    high = stretch.data.oMf[stretch.arms[0].frame_id].translation[2]
    # the lift is vertical: the hand drops by its travel (to 1e-5: the URDF's angles are rounded to 1e-4 rad)
    assert abs((high - low) - (0.55 - 0.23)) < 1e-5


def test_extra_wheels_are_reported():
    """TIAGo++'s casters are wheel-shaped but on swivels: each is listed with its fate, and the
    spec's notes name every wheel-like joint that is not a platform wheel."""
    from mobmanip.descriptions.resources import example_robot_data_share
    from mobmanip.platforms.wheels import wheel_candidates

    urdf_path = example_robot_data_share() / "example-robot-data/robots/tiago_description/robots/tiago_dual.urdf"
    found = detect_spec(urdf_path, ["arm_right_tool_link", "arm_left_tool_link"])
    candidates = [c.name for c in wheel_candidates(read_urdf(urdf_path))]
    extra = [name for name in candidates if name not in ("wheel_right_joint", "wheel_left_joint")]
    assert len(extra) >= 4
    for name in extra:
        line = next(line for line in found.considered if line.startswith(f"wheel-like joint {name} "))
        assert "locked" in line
    note = next(note for note in found.notes if note.startswith("wheel-like joints that are not platform wheels"))
    assert all(name in note for name in extra)
