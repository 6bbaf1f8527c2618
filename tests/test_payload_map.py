"""The payload over a map of object positions (``mobmanip.sweep.payload_map``, ``payload --map``).

References: at sampled positions the cell's mass against the bisection on the mass over the
capacity sets that existed before the payload program (tests/test_payload.py's reference), and the
object's position recomputed here from Pinocchio's frames at the configuration the map used.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from hostile_util import assert_one_line_error, run_cli
from mobmanip import analyze, load_robot
from mobmanip.errors import ArgumentError
from mobmanip.sweep.payload_map import payload_map
from mobmanip.sweep.spec import SweepGrid
from mobmanip.terms.constraints.floor import Floor
from test_payload import RTOL, bisection

ACCELERATION = np.array([1.0, 0.0])


@pytest.fixture(scope="module")
def paper():
    robot = load_robot("planar_dual_arm")
    grid = SweepGrid(np.linspace(-60.0, 60.0, 5), np.linspace(0.3, 0.9, 4))
    return robot, payload_map(robot, grid, "planar", acceleration=ACCELERATION, constraints=(Floor(mu=0.5),))


@pytest.mark.parametrize("cell", [(0, 0), (2, 3), (4, 1)])
def test_a_cell_is_the_bisection_at_its_configuration(paper, cell):
    robot, found = paper
    assert found.status[cell] == "bounded"
    q = found.configurations[cell]
    lo, hi = bisection(robot, q, ACCELERATION, Floor(mu=0.5))
    assert lo - RTOL * hi <= found.mass[cell] <= hi + RTOL * hi


def test_each_cell_holds_the_object_where_the_map_says(paper):
    """The object between the hands is at the cell's angle from the heading and distance from the
    arms' common first joint (the paper robot's reference point), from Pinocchio's frames."""
    robot, found = paper
    model, data = robot.model, robot.model.createData()
    first = model.getJointId(robot.arms[0].joint_names[0])
    for i, angle in enumerate(found.angle_deg):
        for j, distance in enumerate(found.distance):
            q = found.configurations[i, j]
            pin.forwardKinematics(model, data, q)
            centre = analyze(robot, q, "planar", measures=("kinematic",)).held_object.center
            offset = centre[:2] - data.oMi[first].translation[:2]
            heading = math.atan2(q[3], q[2])
            assert np.linalg.norm(offset) == pytest.approx(distance, abs=1e-9)
            assert math.degrees(math.atan2(offset[1], offset[0]) - heading) == pytest.approx(angle, abs=1e-7)


def test_a_harder_acceleration_lowers_every_cell_and_the_ideal_is_no_lower(paper):
    robot, found = paper
    grid = SweepGrid(found.angle_deg, found.distance)
    harder = payload_map(robot, grid, "planar", acceleration=2.0 * ACCELERATION, constraints=(Floor(mu=0.5),))
    ideal = payload_map(robot, grid, "planar", acceleration=ACCELERATION)
    assert np.all(harder.mass < found.mass)
    assert np.all(ideal.mass >= found.mass * (1 - 1e-9))


def test_command_writes_the_map(tmp_path, capfd):
    out = tmp_path / "map"
    code, stdout, stderr = run_cli(
        capfd, "payload", "planar_dual_arm", "--map", "--angle=-60:60:5", "--distance", "0.3:0.9:4",
        "--accel", "1,0", "--mu", "0.5", "--out", out,
    )  # fmt: skip
    assert code == 0, stderr
    document = json.loads((out / "payload_map.json").read_text())
    best = document["best"]
    assert f"heaviest object: {best['mass']:.6g} kg at {best['angle_deg']:g} deg" in stdout
    assert len((out / "payload_map.csv").read_text().splitlines()) == 1 + 20
    assert (out / "payload_map.png").stat().st_size > 0
    code, _, err = run_cli(capfd, "payload", "planar_dual_arm", "--map", "--posture", "hold")
    assert_one_line_error(code, err, "--map", "--posture")
    code, _, err = run_cli(capfd, "payload", "planar_dual_arm", "--map", "--distance", "0:1:3")
    assert_one_line_error(code, err, "--distance")
    code, _, err = run_cli(capfd, "payload", "planar_dual_arm", "--dask", "local:1")
    assert_one_line_error(code, err, "--dask", "--map")
    urdf = Path(__file__).resolve().parents[1] / "robots" / "planar_dual_arm.urdf"
    code, _, err = run_cli(
        capfd, "payload", "--urdf", urdf, "--ee", "arm_right_tool_link", "--map", "--dask", "local:1"
    )
    assert_one_line_error(code, err, "--dask", "--urdf")


def test_a_map_on_an_executor_equals_the_map_here(paper):
    robot, _ = paper
    """The cells sent out in tasks (a one-thread pool standing in for the cluster, whose own run is
    tests/test_cluster.py) come back the same and in their places."""
    import concurrent.futures as cf

    grid = SweepGrid(np.linspace(-60.0, 60.0, 5), np.linspace(0.3, 0.9, 8))
    here = payload_map(robot, grid, acceleration=(1.0, 0.0), constraints=(Floor(mu=0.5),))
    with cf.ThreadPoolExecutor(1) as pool:  # one thread: the workers share this process's robot
        there = payload_map(robot, grid, acceleration=(1.0, 0.0), constraints=(Floor(mu=0.5),), executor=pool,
                            robot_source="planar_dual_arm")  # fmt: skip
    np.testing.assert_array_equal(there.mass, here.mass)
    np.testing.assert_array_equal(there.limit, here.limit)
    assert len(np.unique(here.mass)) > 20  # the cells differ: a misplaced one would show
    with pytest.raises(ArgumentError, match="robot_source"):
        payload_map(robot, grid, executor=cf.ThreadPoolExecutor(1))


# ----- along a path -----


@pytest.fixture(scope="module")
def along():
    """The paper robot's arms turning through five postures, the object held still on the floor."""
    from mobmanip.motion.trajectory import trajectory_from_samples
    from mobmanip.sweep.payload_map import payload_along

    robot = load_robot("planar_dual_arm")
    home = robot.hold_configuration()
    t = np.linspace(0.0, 2.0, 5)
    q = np.tile(home, (5, 1))
    for name, change in (("arm_left_1_joint", 0.4), ("arm_right_1_joint", -0.4)):
        q[:, robot.model.joints[robot.model.getJointId(name)].idx_q] += change * t / 2.0
    path = trajectory_from_samples(robot, t, q)
    return robot, path, payload_along(robot, path, "planar", acceleration=ACCELERATION, constraints=(Floor(mu=0.5),))


def test_the_lightest_sample_is_the_bisection_at_its_posture(along):
    robot, path, found = along
    assert set(found.status) == {"bounded"}
    k = found.lightest()
    assert found.mass[k] == found.mass.min()
    lo, hi = bisection(robot, path.q[k], ACCELERATION, Floor(mu=0.5))
    assert lo - RTOL * hi <= found.mass[k] <= hi + RTOL * hi


def test_command_gives_the_payload_along_a_path(along, tmp_path, capfd):
    from mobmanip.commands.outputs import write_trajectory_csv

    robot, path, found = along
    source = write_trajectory_csv(robot, tmp_path / "path.csv", path.t, path.q)
    out = tmp_path / "along"
    code, stdout, stderr = run_cli(
        capfd, "payload", "planar_dual_arm", "--trajectory", source, "--task", "planar", "--accel", "1,0",
        "--mu", "0.5", "--out", out,
    )  # fmt: skip
    assert code == 0, stderr
    k = found.lightest()
    assert f"lightest payload along the path: {found.mass[k]:.6g} kg at sample {k}" in stdout
    document = json.loads((out / "payload_along.json").read_text())
    assert document["lightest"]["sample"] == k and len(document["mass"]) == 5
    code, _, err = run_cli(capfd, "payload", "planar_dual_arm", "--trajectory", source, "--posture", "hold")
    assert_one_line_error(code, err, "--trajectory", "--posture")
