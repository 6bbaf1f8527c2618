"""Commands run on built-in robots nobody had tried them on, as a user would: a refusal is one line
given before any work (nothing printed first, no kernel compiled, no folder made)."""

from __future__ import annotations

from pathlib import Path

import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli

FLOOR_REFUSAL = "the floor model covers platforms that move on the floor"


@pytest.fixture(scope="module")
def rest_to_rest(tmp_path_factory):
    """0.2 m straight ahead in 2 s from rest to rest (a quintic), as an object path and as a
    platform trajectory."""
    folder = tmp_path_factory.mktemp("paths")
    times = [0.1 * i for i in range(21)]
    xs = [0.2 * (10 * (t / 2) ** 3 - 15 * (t / 2) ** 4 + 6 * (t / 2) ** 5) for t in times]
    path, trajectory = folder / "path.csv", folder / "trajectory.csv"
    path.write_text("t,x,y\n" + "".join(f"{t:.2f},{x:.9f},0\n" for t, x in zip(times, xs)))
    trajectory.write_text(
        "t,platform_x,platform_y,platform_yaw\n" + "".join(f"{t:.2f},{x:.9f},0,0\n" for t, x in zip(times, xs))
    )
    return path, trajectory


@pytest.mark.parametrize(
    "argv",
    [
        ("sweep", "panda", "--ground", "--angle", "0:90:2", "--distance", "0.5"),
        ("sweep", "planar_dual_arm", "--platform", "fixed", "--ground", "--angle", "0:90:2", "--distance", "0.8"),
        ("carry", "panda", "--ground", "--no-progress"),
        ("trajectory", "ur5", "--ground"),
    ],
    ids=["sweep-fixed", "sweep-locked", "carry-fixed", "trajectory-fixed"],
)
def test_the_floor_on_a_fixed_platform_is_refused_before_any_work(capfd, tmp_path, rest_to_rest, argv):
    """sweep printed its estimate and compiled its kernels (about 20 s), carry compiled its
    gradient kernels, trajectory printed its whole analysis, all before refusing."""
    path, trajectory = rest_to_rest
    command, robot, *options = argv
    given = {"sweep": ("-o", tmp_path / "out"), "carry": ("--path", path), "trajectory": ()}[command]
    csv = (trajectory,) if command == "trajectory" else ()
    code, out, err = run_cli(capfd, command, robot, *csv, *options, *given)
    assert_one_line_error(code, err, FLOOR_REFUSAL, f"'{robot}' has a fixed platform")
    assert out == ""
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "robot, needle",
    [
        ("stretch", "the case study's posture needs two 3-joint arms; 'stretch' has arms of 3 joints"),
        ("tiago_dual", "the case study's posture needs two 3-joint arms; 'tiago_dual' has arms of 7 and 7 joints"),
        ("ur5", "the case study needs a differential drive with two arms; 'ur5' does not fit"),
    ],
)
def test_the_case_study_refuses_another_robot_before_printing(capfd, tmp_path, robot, needle):
    """`paper --robot R` printed '[1/4] loaded R' before refusing R (the line ran into the error
    line when standard output was not a terminal)."""
    code, out, err = run_cli(capfd, "paper", "--robot", robot, "--out", tmp_path / "paper")
    assert_one_line_error(code, err, needle)
    assert out == ""
    assert not (tmp_path / "paper").exists()


@pytest.mark.parametrize("command", ["trajectory", "retime"])
def test_a_trajectory_that_moves_a_fixed_platform_is_refused(capfd, rest_to_rest, command):
    """A fixed arm's trajectory whose platform columns move 0.2 m: `trajectory` reported the motion
    as 0.186 m/s of 'platform slip' and `retime` asked for velocity or effort limits the UR5 has
    (no joint moved, so nothing limited the speed)."""
    _, trajectory = rest_to_rest
    code, out, err = run_cli(capfd, command, "ur5", trajectory)
    assert_one_line_error(
        code, err, "robot 'ur5' has a fixed platform, but platform_x changes by 0.2 m", "keep platform_x"
    )
    assert out == ""


def test_a_fixed_platform_mounted_away_from_the_origin_is_read(tmp_path):
    """Constant platform columns say where a fixed arm is mounted: the hand's path is the one
    mounted at the origin, carried over by that pose (forward kinematics by hand)."""
    import numpy as np
    import pinocchio as pin

    from mobmanip.motion.trajectory import read_trajectory
    from mobmanip.robot.model import load_robot

    robot = load_robot("ur5")
    rows = "".join(f"{0.1 * i:.1f},1.5,-0.5,0.7,{0.1 * i:.2f},-1.0,1.5\n" for i in range(5))
    path = tmp_path / "mounted.csv"
    path.write_text("t,platform_x,platform_y,platform_yaw,shoulder_pan_joint,shoulder_lift_joint,elbow_joint\n" + rows)
    mounted = read_trajectory(robot, path)
    (tmp_path / "origin.csv").write_text(path.read_text().replace(",1.5,-0.5,0.7,", ",0,0,0,"))
    origin = read_trajectory(robot, tmp_path / "origin.csv")
    c, s = np.cos(0.7), np.sin(0.7)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    tool = robot.model.getFrameId("tool0")

    def hand(q):
        pin.framesForwardKinematics(robot.model, robot.data, q)
        return robot.data.oMf[tool].translation.copy()

    for q_mounted, q_origin in zip(mounted.q, origin.q):
        assert np.allclose(hand(q_mounted), turn @ hand(q_origin) + [1.5, -0.5, 0.0], atol=1e-12)
    pan = robot.reduced_velocity_names.index("shoulder_pan_joint")
    assert np.allclose(mounted.x[:, pan], 1.0, atol=1e-9)  # 0.1 rad every 0.1 s
    assert np.allclose(np.delete(mounted.x, pan, axis=1), 0.0, atol=1e-12)
    assert np.all(mounted.slip == 0.0)


def test_the_trajectory_may_follow_the_options(capfd, rest_to_rest):
    """`retime ROBOT --object-mass 2 TRAJ.csv` was refused ('unrecognized arguments: TRAJ.csv'):
    argparse had matched the optional TRAJ.csv to nothing on reading ROBOT. Either order now
    reads the same command; a word too many is still refused."""
    _, trajectory = rest_to_rest
    after = run_cli(capfd, "retime", "planar_dual_arm", "--object-mass", "2", trajectory)
    before = run_cli(capfd, "retime", "planar_dual_arm", trajectory, "--object-mass", "2")
    assert after[0] == 0 and after == before
    code, _, err = run_cli(capfd, "retime", "planar_dual_arm", "--object-mass", "2", trajectory, "extra")
    assert_one_line_error(code, err, "unrecognized arguments: extra")


def test_a_failed_self_motion_is_not_blamed_on_the_path(capfd, rest_to_rest):
    """TIAGo on the floor from home: the self-motion before the path (the object held still) fails; the
    message said 'slowing the path down likely helps', which cannot help a motion the path does
    not drive. The step's time is the self-motion's: the path's start less --prepare, plus the
    steps taken."""
    import json
    import re

    path, _ = rest_to_rest
    tiago = mobmanip.load_robot("tiago")  # from home, its arm stretched out to the side
    start = Path(path).with_name("home.json")
    start.write_text(json.dumps(tiago.configuration_dict(tiago.neutral())))
    code, _, err = run_cli(capfd, "carry", "tiago", "--path", path, "--start", start, "--ground", "--no-progress")
    line = assert_one_line_error(
        code, err, "of the self-motion before the path", "the floor binds", "slowing the path down does not help",
        "--prepare S; 0: none",
    )  # fmt: skip
    assert "likely helps" not in line
    step, t = re.search(r"at step (\d+) of the self-motion before the path \(t = (-?[\d.]+) s", line).groups()
    assert float(t) == pytest.approx(-30.0 + 0.02 * int(step), abs=1e-9)


def test_a_self_motion_diagnosis_names_the_limit_without_the_paths_advice():
    from mobmanip.motion.carry_step import CarryDiagnosis

    during = CarryDiagnosis(7, -12.5, "arm_2_joint", "position", asked=0.3, allowed=0.1, position=1.2,
                            position_limit=1.25, slowing_helps=False, unit="rad/s", self_motion=True)  # fmt: skip
    message = during.message()
    assert message.startswith("at step 7 of the self-motion before the path (t = -12.5 s, the object held still) ")
    assert "the position limit of arm_2_joint binds: the step asks 0.3, the limit allows 0.1 (rad/s)" in message
    assert "the path needs it" not in message
    assert during.to_dict()["self_motion"] is True


def test_tiago_sweeps_its_default_grid_from_its_hold_posture(capfd, tmp_path):
    """`sweep tiago` with the default grid used to reach none of it: the inverse kinematics
    started from home, the arm stretched out to the side with arm_1_joint at its limit. From the
    spec's hold posture (the arm bent in front) it reaches the grid's near points; each posture
    holds the hand where the grid asks, by Pinocchio's forward kinematics: at the grid's angle
    and distance from the reference point, at the hold's height (1e-9 m)."""
    import numpy as np
    import pinocchio as pin

    code, out, err = run_cli(capfd, "sweep", "tiago", "--no-progress", "-o", tmp_path / "s")
    assert code == 0, err
    table = np.load(tmp_path / "s" / "sweep.npz")
    reached = table["reachable"][..., 0]
    assert 10 <= reached.sum() < reached.size
    assert f"{int(reached.sum())} of {reached.size} (angle, distance) points in reach" in out
    tiago = mobmanip.load_robot("tiago")
    hand = tiago.model.getFrameId(tiago.arms[0].end_effector)
    origin, height = table["hold_origin"], float(table["hold_height"])
    names = [str(n) for n in table["posture_joint_names"]]
    for i, j in np.argwhere(reached):
        q = tiago.configuration((0.0, 0.0, 0.0), dict(zip(names, table["posture_joints"][i, j].tolist())))
        pin.framesForwardKinematics(tiago.model, tiago.data, q)
        a, d = np.radians(table["angle_deg"][i]), table["distance"][j]
        expected = np.r_[origin + d * np.array([np.cos(a), np.sin(a)]), height]
        assert np.linalg.norm(tiago.data.oMf[hand].translation - expected) < 1e-9
