"""The motion floor (``retime --ground``, ``carry --ground``) on every platform kind that rolls on
wheels: a mecanum base (the paper's arms on four wheels whose rollers run at +-45 deg), a
skid-steer (PAL's TIAGo Pro) and a steered tricycle (its rear wheels rolling free).

Reference, assembled here from the floor's resultant wrench of the retimed motion
(:func:`mobmanip.motion.ground.ground_along`, the centroidal route): each contact's load as
equally stiff contacts under a rigid platform share it (a plane of compressions), and the driven
contacts' traction as equally stiff tyres share the floor's (F_x, F_y, M_z), each contact pushing
only where its mechanism lets it (a mecanum wheel across its rollers, a free rear wheel across its
rolling direction, any other wheel both ways): the least-squares split over those directions. At
every grid point the zero-moment point keeps its margin, every contact its reserve, and every
wheel's traction its friction; and the floor binds somewhere.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.errors import MobmanipError
from mobmanip.motion.carry_floor import CarryFloor
from mobmanip.motion.ground import ground_along
from mobmanip.motion.retime import retime
from mobmanip.motion.traction import traction_along
from mobmanip.motion.trajectory import trajectory_from_samples
from mobmanip.motion.trajectory_analysis import analyze_trajectory
from mobmanip.robot.support import robot_support
from test_motion_steered import rolling_path
from test_retime import _contact_loads
from test_steered import write_tricycle

FLOOR = CarryFloor(mu=0.5, zmp_margin=0.02, reserve=0.2)
N = 61


def _smooth(n=N, length=4.0):
    s = np.linspace(0.0, length, n)
    return s, 0.5 - 0.5 * np.cos(math.pi * s / length)


def _move(robot, q, u, changes):
    for name, change in changes:
        q[:, robot.model.joints[robot.model.getJointId(name)].idx_q] += change * u


def _mecanum():
    robot = mobmanip.load_robot("planar_dual_arm_omni")
    s, u = _smooth()
    q = np.tile(robot.hold_configuration(), (N, 1))
    yaw = 0.6 * u
    q[:, 0], q[:, 1], q[:, 2], q[:, 3] = 0.8 * u, 0.5 * u, np.cos(yaw), np.sin(yaw)  # sideways while turning
    _move(robot, q, u, [("arm_right_1_joint", 0.3), ("arm_left_2_joint", -0.3)])
    return robot, trajectory_from_samples(robot, s, q), 2.0


def _skid_steer():
    robot = mobmanip.load_robot("tiago_pro")
    s, u = _smooth()
    q = np.tile(robot.hold_configuration(), (N, 1))
    q[:, 0] += 1.0 * u  # straight ahead
    _move(robot, q, u, [("arm_left_2_joint", 0.3), ("arm_right_2_joint", 0.3)])
    known = [name for name in robot.joint_names if "wheel" not in name]
    return robot, trajectory_from_samples(robot, s, q, known_joints=known), 1.0


def _tricycle(tmp_path_factory):
    robot = mobmanip.load_robot(write_tricycle(tmp_path_factory.mktemp("tricycle_floor")))
    x0, xdot = np.zeros(robot.nx), np.zeros(robot.nx)
    x0[0], xdot[1] = 3.0, 0.2  # drive on while the steering turns: a curve that tightens
    times = np.linspace(0.0, 2.0, 41)
    q = rolling_path(robot, robot.neutral(), x0, xdot, times, substeps=20)
    path = trajectory_from_samples(robot, times, q, x0 + times[:, None] * xdot, np.tile(xdot, (len(times), 1)))
    return robot, path, 1.0


def _directions(robot, support, yaw):
    """Where each driven contact pushes along the floor (world axes), from the kind's mechanism."""
    rolling_free = set(robot.spec.wheels.rear) if robot.platform.kind == "steered" else set()
    c, s = math.cos(yaw), math.sin(yaw)
    out = {}
    for k, contact in enumerate(support.contacts):
        if not contact.driven:
            continue
        if contact.free is not None:  # rollers: only across them
            free = np.array(contact.free) / np.hypot(*contact.free)
            across = [np.array([-free[1], free[0]])]
        elif contact.name in rolling_free:  # a free rear wheel rolls along the platform's x axis
            across = [np.array([0.0, 1.0])]
        else:
            across = [np.array([1.0, 0.0]), np.array([0.0, 1.0])]
        out[k] = [np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]]) for d in across]
    return out


def _traction(support, pose, force, moment, directions):
    """Each driven contact's tangential force (world) as the least-squares split of (F_x, F_y, M_z
    about the world origin) over the directions it pushes in."""
    points = support.world_points(pose)
    columns, owners = [], []
    for k, ds in directions.items():
        for d in ds:
            columns.append([d[0], d[1], points[k, 0] * d[1] - points[k, 1] * d[0]])
            owners.append((k, d))
    split = np.linalg.lstsq(np.array(columns).T, np.array([force[0], force[1], moment[2]]), rcond=None)[0]
    out = {k: np.zeros(2) for k in directions}
    for (k, d), t in zip(owners, split):
        out[k] += t * d
    return out


@pytest.fixture(scope="module", params=["mecanum", "skid_steer", "tricycle"])
def case(request, tmp_path_factory):
    if request.param == "tricycle":
        return _tricycle(tmp_path_factory)
    return {"mecanum": _mecanum, "skid_steer": _skid_steer}[request.param]()


def test_the_floor_holds_at_every_grid_point_on_every_kind(case):
    robot, path, mass = case
    free = retime(robot, path, object_mass=mass)
    grounded = retime(robot, path, object_mass=mass, floor=FLOOR)
    assert grounded.duration > free.duration * 1.05  # the floor binds
    motion = grounded.trajectory
    analysis = analyze_trajectory(robot, motion, object_mass=mass)
    assert analysis.velocity_use.max() <= 1.0 + 1e-9 and analysis.effort_use.max() <= 1.0 + 1e-9
    along = ground_along(robot, motion, analysis.object_acceleration, object_mass=mass)
    assert along.margin.min() >= FLOOR.zmp_margin - 1e-7
    support = robot_support(robot)
    total = (pin.computeTotalMass(robot.model) + mass) * 9.81
    least = FLOOR.reserve * total / len(support.contacts)
    # trajectory --ground's reading of the same motion: the floor of motion's one sharing
    reading = traction_along(along, motion, 0.5)
    lowest, use = np.inf, 0.0
    for i in range(len(motion)):
        pose = (motion.q[i, 0], motion.q[i, 1], math.atan2(motion.q[i, 3], motion.q[i, 2]))
        loads = _contact_loads(support, pose, along.force[i], along.moment[i])
        lowest = min(lowest, float(loads.min() - least))
        pushes = _traction(support, pose, along.force[i], along.moment[i], _directions(robot, support, pose[2]))
        np.testing.assert_allclose(reading.normal[i], loads, rtol=0, atol=1e-9 * total)
        assert [reading.wheels.index(support.contacts[k].name) for k in pushes] == list(range(len(pushes)))
        np.testing.assert_allclose(reading.tangential[i], np.array(list(pushes.values())), rtol=0, atol=1e-9 * total)
        for k, t in pushes.items():  # within the cone (the rows keep a pyramid inscribed in it, or the cone itself
            use = max(use, float(np.linalg.norm(t) / (0.5 * (1 - FLOOR.reserve) * loads[k])))  # where one way only)
    assert lowest >= -1e-6 * total
    assert use <= 1.0 + 1e-6
    # the floor binds somewhere: a support at its reserve, or a wheel at least on its pyramid's faces
    assert lowest <= 1e-6 * total or use >= math.cos(math.pi / 8) - 1e-6


def test_a_skid_steer_that_turns_on_the_floor_is_refused_by_name():
    robot, path, mass = _skid_steer()
    q = path.q.copy()
    _, u = _smooth()
    q[:, 2], q[:, 3] = np.cos(0.3 * u), np.sin(0.3 * u)
    known = [name for name in robot.joint_names if "wheel" not in name]
    turning = trajectory_from_samples(robot, path.t, q, known_joints=known)
    with pytest.raises(MobmanipError, match="turns tiago_pro's base .* a skid-steer turns only by sliding"):
        retime(robot, turning, object_mass=mass, floor=FLOOR)
    assert retime(robot, turning, object_mass=mass).duration > 0.0  # without the floor it is retimed


def test_a_fixed_base_has_no_floor_to_keep():
    panda = mobmanip.load_robot("panda")
    s = np.linspace(0.0, 1.0, 5)
    path = trajectory_from_samples(panda, s, np.tile(panda.hold_configuration(), (5, 1)))
    with pytest.raises(MobmanipError, match="needs a platform that moves on wheels"):
        retime(panda, path, floor=CarryFloor())


def test_carry_on_the_floor_says_a_skid_steer_cannot_turn_and_that_slowing_down_does_not_help(tmp_path, capfd):
    from pathlib import Path

    from hostile_util import run_cli

    turn = Path(__file__).resolve().parents[1] / "examples" / "carry_turn.csv"
    code, _, err = run_cli(capfd, "carry", "tiago_pro", "--path", turn, "--ground", "--mu", "0.5", "--out", tmp_path,
                           "--no-progress")  # fmt: skip
    assert code != 0
    last = err.strip().splitlines()[-1]
    assert last.startswith("mobmanip: error: ") and "a skid-steer turns only by sliding" in last
    assert "slowing down does not help" in last
