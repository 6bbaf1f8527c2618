"""carry's failures diagnose: the step, the binding limit (joint, kind, asked vs allowed),
whether slowing down helps, and the part that succeeded written and flagged partial.

Stretch 3 as the project models it (the telescoping arm as its last 0.13 m segment) cannot carry
either example path: the arm reaches the end of its range. The diagnosis names that limit, and
it is checked independently: the partial motion's last configuration has the arm within a
millimetre of the URDF's upper limit, and the path slowed 4x fails at the same place along the
path (so speed is not the cause, as the diagnosis says).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from mobmanip.cli import main
from mobmanip.errors import CarryFailed
from mobmanip.motion.carry import ObjectPath, carry, read_path
from mobmanip.motion.trajectory import read_trajectory

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def stretch():
    return mobmanip.load_robot("stretch")


def _arm_upper_limit(robot):
    model = robot.model
    joint = model.joints[model.getJointId("joint_arm_l0")]
    return float(model.upperPositionLimit[joint.idx_q])


@pytest.mark.parametrize("name", ["carry_line.csv", "carry_turn.csv"])
def test_stretch_names_the_arm_at_the_end_of_its_range(stretch, name, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["carry", "stretch", "--path", str(EXAMPLES / name), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1
    assert "position limit of joint_arm_l0" in err[0] and "slowing down does not help" in err[0]
    summary = json.loads((out / "carry.json").read_text())
    assert summary["partial"] is True
    failure = summary["failure"]
    upper = _arm_upper_limit(stretch)
    assert failure["joint"] == "joint_arm_l0" and failure["kind"] == "position"
    assert failure["slowing_helps"] is False and failure["unit"] == "m/s"
    assert failure["position_limit"] == pytest.approx(upper, abs=1e-12)
    assert abs(failure["asked"]) > 10 * abs(failure["allowed"])  # the step asks far more than the range leaves
    # the part that succeeded: a trajectory that reads back, ending at the failing step, the arm
    # at the end of its range there (from the configuration itself, not the diagnosis)
    trajectory = read_trajectory(stretch, out / "trajectory.csv")
    assert trajectory.t[-1] == pytest.approx(failure["t"], abs=1e-9) == pytest.approx(summary["completed_until"])
    arm = stretch.configuration_dict(trajectory.q[-1])["joints"]["joint_arm_l0"]
    assert upper - 1e-3 <= arm <= upper + 1e-9
    assert trajectory.slip.max() < 1e-9
    assert (out / "preparation.csv").exists()
    assert "partial" in captured.out


def test_slowing_down_fails_at_the_same_place(stretch):
    """Slowed 4x, the same path fails at the same place along it: a position limit, as said."""
    path = read_path(EXAMPLES / "carry_line.csv")
    places = []
    for k in (1.0, 4.0):
        with pytest.raises(CarryFailed) as info:
            carry(stretch, ObjectPath(path.t * k, path.xy), prepare=0.0)
        d = info.value.diagnosis
        assert d.kind == "position" and d.joint == "joint_arm_l0" and d.slowing_helps is False
        places.append(np.interp(d.t / k, path.t, path.xy[:, 0]))
    assert places[1] == pytest.approx(places[0], abs=0.02)  # m along the path


def test_a_fast_path_names_a_wheel_velocity_and_slowing_helps():
    """The paper robot on the example line run 10 times faster: a wheel's velocity limit binds,
    the step asks more than the limit (rim speed 1 m/s: 1 / r rad/s), and slowing down helps
    (the path at its own speed is carried)."""
    robot = mobmanip.load_robot("planar_dual_arm")
    path = read_path(EXAMPLES / "carry_line.csv")
    with pytest.raises(CarryFailed) as info:
        carry(robot, ObjectPath(path.t / 10.0, path.xy), prepare=0.0)
    d = info.value.diagnosis
    assert d.kind == "velocity" and d.joint.startswith("wheel_") and d.slowing_helps is True
    assert d.unit == "rad/s"
    assert d.allowed == pytest.approx(np.copysign(1.0 / robot.platform.radius, d.asked), rel=1e-9)
    assert abs(d.asked) > abs(d.allowed)
    assert "slowing the path down helps" in str(info.value)
    partial = info.value.partial
    assert partial.t[-1] == pytest.approx(d.t) and len(partial.q) == d.step + 1
    assert np.all(np.abs(partial.x) <= robot.velocity_limits * (1 + 1e-9))
    carry(robot, path, prepare=0.0)  # ten times slower: no error
