"""Motion synthesis (mobmanip carry): tracking, limits, no slip and capacity against the baseline."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
import mobmanip.motion.carry as carry_module
from mobmanip.cli import main
from mobmanip.commands.outputs import carry_outputs
from mobmanip.errors import ArgumentError
from mobmanip.motion import motion_terms
from mobmanip.motion.carry import ObjectPath, carry, default_start, read_path
from mobmanip.motion.trajectory import read_trajectory, trajectory_from_samples
from mobmanip.motion.trajectory_analysis import analyze_trajectory
from mobmanip.placement import place
from mobmanip.terms.dynamics import end_effector_positions

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module", params=["carry_line.csv", "carry_turn.csv"])
def paper_run(request):
    robot = mobmanip.load_robot("planar_dual_arm")
    path = read_path(EXAMPLES / request.param)
    return robot, path, carry(robot, path)


def test_example_paths_are_2_m(paper_run):
    _, path, _ = paper_run
    assert path.length() == pytest.approx(2.0, abs=1e-3)


def test_tracks_the_path_within_1_mm(paper_run):
    """Against the path as the module doc defines it between samples: a cubic spline in time
    (SciPy's, not-a-knot), built here from the CSV's samples."""
    from scipy.interpolate import CubicSpline

    robot, path, result = paper_run
    spline = CubicSpline(path.t, path.xy)
    for run in (result.motion, result.baseline):
        start = end_effector_positions(robot, run.q[0]).mean(axis=0)
        for t, q in zip(run.t, run.q):
            goal = start[:2] + spline(t) - path.xy[0]
            centre = end_effector_positions(robot, q).mean(axis=0)
            assert np.linalg.norm(centre[:2] - goal) <= 1e-3


def test_limits_hold_at_every_step(paper_run):
    robot, _, result = paper_run
    model = robot.model
    for motion in (result.preparation, result.motion):
        assert np.all(np.abs(motion.x) <= robot.velocity_limits * (1 + 1e-9))
        for arm in robot.arms:
            for name in arm.joint_names:
                joint = model.joints[model.getJointId(name)]
                lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
                values = motion.q[:, joint.idx_q]
                assert np.all(values >= lo - 1e-12) and np.all(values <= hi + 1e-12)


def test_self_motion_before_the_path(paper_run):
    """The QP motion starts where a self-motion from the start posture ends: the object stays
    where the start posture holds it (within 1 mm, recomputed by forward kinematics), the
    objective rises, the self-motion ends at the path's first time stamp and the baseline starts
    from the start posture; without it (prepare=0) both start there."""
    robot, path, result = paper_run
    prep, motion, base = result.preparation, result.motion, result.baseline
    np.testing.assert_array_equal(prep.q[0], default_start(robot))
    np.testing.assert_array_equal(base.q[0], default_start(robot))
    np.testing.assert_array_equal(motion.q[0], prep.q[-1])
    assert prep.t[-1] == pytest.approx(path.t[0], abs=1e-12)
    held = end_effector_positions(robot, prep.q[0]).mean(axis=0)
    for q in prep.q:
        assert np.linalg.norm(end_effector_positions(robot, q).mean(axis=0) - held) <= 1e-3

    # the capacities recomputed by analyze (not the evaluator that drove the motion)
    def minor(q):
        return mobmanip.analyze(robot, q, "planar", method="exact").kinematic.semi_axes[-1]

    assert minor(prep.q[-1]) > minor(prep.q[0]) * 1.05
    start = result.starts()
    assert start["qp"]["capacity"] == pytest.approx(minor(motion.q[0]), rel=1e-9)
    assert start["pinv"]["capacity"] == pytest.approx(minor(base.q[0]), rel=1e-9)
    assert start["qp"]["self_motion_start_capacity"] == pytest.approx(minor(prep.q[0]), rel=1e-9)
    assert start["qp"]["capacity"] > start["pinv"]["capacity"]  # the self-motion raised it
    short = ObjectPath(path.t[:3], path.xy[:3])
    plain = carry(robot, short, prepare=0.0)
    assert plain.preparation is None
    np.testing.assert_array_equal(plain.motion.q[0], plain.baseline.q[0])
    with pytest.raises(ArgumentError, match="prepare"):
        carry(robot, short, prepare=-1.0)


def _platform_pose(q):
    yaw = np.arctan2(q[3], q[2])
    return pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, yaw), np.array([q[0], q[1], 0.0]))


def test_no_lateral_slip(paper_run):
    """Every step is a motion the wheels make: the platform's SE(2) displacement (log6 of the
    relative pose) is exactly S x dt, with no lateral part, and the joints moved by x dt."""
    robot, _, result = paper_run
    motion = result.motion
    S = robot.S
    for a, b, x, dt in zip(motion.q[:-1], motion.q[1:], motion.x, np.diff(motion.t)):
        twist = pin.log6(_platform_pose(a).inverse() * _platform_pose(b))
        d = pin.difference(robot.model, a, b)
        d[:3] = (twist.linear[0], twist.linear[1], twist.angular[2])
        assert abs(twist.linear[1]) <= 1e-9
        np.testing.assert_allclose(d, S @ x * dt, atol=1e-9)
        # world-frame form: the platform moves along its heading on the step's mid-chord
        heading = 0.5 * (np.arctan2(a[3], a[2]) + np.arctan2(b[3], b[2]))
        step = b[:2] - a[:2]
        assert abs(-np.sin(heading) * step[0] + np.cos(heading) * step[1]) <= 1e-9


def test_carry_output_reads_back_without_slip(paper_run, tmp_path):
    """trajectory.csv written by carry, read back by mobmanip trajectory's reader, shows no
    lateral slip (its rates come from the SE(2) log, which keeps yaw changes of 1e-8 rad, and
    carry steps the platform by the exact SE(2) exponential): far below the issue's 1e-9, at the
    rounding of metre-sized positions over 20 ms steps (~1e-14 m/s); pin.difference and
    pin.integrate alone left ~1e-9 here."""
    robot, _, result = paper_run
    carry_outputs(robot, result, tmp_path)
    trajectory = read_trajectory(robot, tmp_path / "trajectory.csv")
    assert len(trajectory) == len(result.motion.t)
    assert trajectory.slip.max() < 1e-12


def test_capacity_beats_the_baseline_by_20_percent(paper_run):
    """The minimum kinematic minor semi-axis along the path, recomputed by analyze (not the
    gradient evaluator), is at least 1.2 times the pseudo-inverse baseline's."""
    robot, _, result = paper_run
    minima = []
    for run in (result.motion, result.baseline):
        values = [mobmanip.analyze(robot, q, "planar", method="exact").kinematic.semi_axes[-1] for q in run.q]
        np.testing.assert_allclose(values, run.capacity, rtol=1e-9)
        minima.append(min(values))
    assert minima[0] >= 1.2 * minima[1]


#: The documented effort reserve: the QP keeps each step's efforts within 99 % of the limits
#: (written out here, not read from the module under test).
EFFORT_RESERVE = 0.99


def _check_efforts(robot, result) -> float:
    """The QP motions' wheel and joint efforts are within their limits: per step, from the
    step's change of rates by the paper's policy (MotionTerms.torques, not the QP's own matrix),
    and per sample as mobmanip trajectory estimates them from the configurations alone.
    Returns the largest share of a limit used by a step."""
    previous = np.zeros(robot.nx)
    largest = 0.0
    for run in (result.preparation, result.motion):
        for q, x, dt in zip(run.q[:-1], run.x, np.diff(run.t)):
            tau = motion_terms(robot, q, previous).torques((x - previous) / dt)
            share = float(np.max(np.abs(tau) / robot.effort_limits))
            assert share <= EFFORT_RESERVE * (1 + 1e-9)
            largest = max(largest, share)
            previous = x
        sampled = trajectory_from_samples(robot, run.t, run.q)
        assert analyze_trajectory(robot, sampled).effort_use.max() <= 1.0
    return largest


@pytest.mark.parametrize("name", ["carry_line.csv", "carry_turn.csv"])
def test_tiago_capacity_against_the_baseline_and_the_best_start(name):
    """TIAGo++ with the default objective (the kinematic minor semi-axis, spatial task).

    Its efforts stay within the limits (the QP bounds them; an unbounded step once asked 1.5
    times a wheel's limit). On the turn the QP's minimum along the path is at least 1.2 times the baseline's. On the
    line the baseline's minimum is its start's, and no motion can beat the best posture holding
    the object at the path's start: base placement (SLSQP from 8 platform headings, free grasp
    turn) finds that best hold independently, the self-motion's start reaches it within 0.1%
    and the QP keeps it along the path. That best is below 1.2 times the baseline's minimum:
    the issue's 1.2x is out of reach on this line for any motion from this hold.
    """
    robot = mobmanip.load_robot("tiago_dual")
    result = carry(robot, read_path(EXAMPLES / name))
    motion, base = result.motion, result.baseline
    assert motion.tracking_error.max() <= 1e-3 and result.preparation.tracking_error.max() <= 1e-3
    # the reserve from both sides: the self-motion's first step (from rest, the capacity term
    # asking half the velocity limits at once) is held exactly at the reserve, not below it
    assert _check_efforts(robot, result) == pytest.approx(EFFORT_RESERVE, abs=1e-6)
    assert carry_module.EFFORT_SHARE == EFFORT_RESERVE
    values = [mobmanip.analyze(robot, q, "spatial").kinematic.semi_axes[-1] for q in (motion.q[0], base.q[0])]
    np.testing.assert_allclose(values, [motion.capacity[0], base.capacity[0]], rtol=1e-9)
    if name == "carry_turn.csv":
        assert motion.capacity.min() >= 1.2 * base.capacity.min()
        return
    assert base.capacity.min() == base.capacity[0]
    centre = end_effector_positions(robot, base.q[0]).mean(axis=0)
    best = place(robot, centre, "kinematic:minor_axis", reference=base.q[0]).value
    assert motion.capacity[0] <= best * (1 + 1e-6)
    assert motion.capacity.min() >= 0.999 * best
    assert best < 1.2 * base.capacity.min()


def test_command_writes_a_trajectory_that_analyses(tmp_path):
    path = tmp_path / "path.csv"
    path.write_text("t,x,y\n0,0,0\n1,0.1,0\n2,0.2,0.05\n")
    out = tmp_path / "out"
    out.mkdir()
    assert main(["carry", "planar_dual_arm", "--path", str(path), "--out", str(out), "--step", "0.05"]) == 0
    header = next(csv.reader(open(out / "trajectory.csv")))
    robot = mobmanip.load_robot("planar_dual_arm")
    joints = list(robot.configuration_dict(robot.neutral())["joints"])
    assert header == ["t", "platform_x", "platform_y", "platform_yaw", *joints, "capacity", "baseline_capacity",
                      "tracking_error"]  # fmt: skip
    summary = json.loads((out / "carry.json").read_text())
    assert summary["qp"]["max_tracking_error"] <= 1e-3
    trajectory = read_trajectory(robot, out / "trajectory.csv")
    assert len(trajectory) == 41
    assert trajectory.slip.max() < 1e-6


def test_bad_paths_are_refused(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("t,x,q\n0,0,0\n1,1,1\n")
    with pytest.raises(ArgumentError, match="header"):
        read_path(path)
    path.write_text("t,x,y\n0,0,0\n1,nan,1\n")
    with pytest.raises(ArgumentError, match="line 3, column 'x'"):
        read_path(path)
    with pytest.raises(ArgumentError, match="increasing"):
        ObjectPath(np.array([0.0, 0.0]), np.zeros((2, 2)))
    assert main(["carry", "planar_dual_arm", "--path", str(path)]) == 2


def test_a_singular_start_is_refused_by_name(tmp_path, capsys):
    """The UR5's home posture lies stretched out: its Jacobian (Pinocchio's, read here directly)
    has a zero singular value (to round-off), so the minor axis is not defined there. ``carry`` says so in one
    line naming the start posture and how to give another, before any motion is computed."""
    ur5 = mobmanip.load_robot("ur5")
    q = ur5.neutral()
    frame = ur5.model.getFrameId(ur5.arms[0].end_effector)
    J = pin.computeFrameJacobian(ur5.model, ur5.data, q, frame, pin.LOCAL_WORLD_ALIGNED)
    sigma = np.linalg.svd(J, compute_uv=False)
    assert sigma[-1] < 1e-10 * sigma[0]  # rank 5, to round-off
    path = tmp_path / "ahead.csv"
    path.write_text("t,x,y\n0,0,0\n1,0.05,0\n")
    assert main(["carry", "ur5", "--path", str(path), "--prepare", "0"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.splitlines() == [
        "mobmanip: error: kinematic:minor_axis is not defined at the start posture (the home configuration): "
        "the posture is singular there; start from another (--start Q.json, or a [hold] posture in the spec)"
    ]
