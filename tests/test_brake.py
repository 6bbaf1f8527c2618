"""The hardest stop from a straight run (``mobmanip brake``, :mod:`mobmanip.analysis.braking`).

Braking with its arms still, the robot only translates, so where it tips over the answer has a
closed form written here from Pinocchio's centre of mass and the wheels' inertias, not from the
floor's rows: the zero-moment point reaches the support polygon's front edge x_f when

    d (z_c + sum_w I_w / (m r)) = g cos(s) (x_f - x_c) + g sin(s) z_c

(c the centre of mass of robot and object, z_c its height above the floor, I_w a wheel's inertia
about its axle: a wheel slowing down at d / r hands its spin's moment to the floor too; s the
ramp's slope, uphill along the run). The stop's set lies inside the grounded set, turns with the
robot, and the command reports it in both senses.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.analysis.braking import braking_set, hardest_stop
from mobmanip.robot.support import robot_support
from mobmanip.terms.constraints.floor import Floor

G = 9.81


def _closed_form(robot, q, mass: float, slope_deg: float = 0.0) -> float:
    """The deceleration at which the stop tips the robot forward over its front edge (see above)."""
    held = mobmanip.analyze(robot, q, "planar", object_mass=mass, measures=("kinematic",)).held_object
    model = robot.model
    data = model.createData()
    m_robot = pin.computeTotalMass(model)
    c = (m_robot * pin.centerOfMass(model, data, q) + held.mass * np.asarray(held.center)) / (m_robot + held.mass)
    m = m_robot + held.mass
    pin.computeJointJacobians(model, data, q)
    spin = 0.0
    for name, radius in robot.platform.wheels():
        jid = model.getJointId(name)
        axis = pin.getJointJacobian(model, data, jid, pin.LOCAL)[3:, model.joints[jid].idx_v]
        inertia = model.inertias[jid]
        assert np.linalg.norm(np.cross(inertia.lever, axis)) < 1e-9  # its centre of mass on the axle
        spin += float(axis @ inertia.inertia @ axis) / radius
    support = robot_support(robot)
    front = support.root_points()[:, 0].max()
    height = c[2] - support.floor_z
    s = math.radians(slope_deg)
    return (G * math.cos(s) * (front - c[0]) + G * math.sin(s) * height) / (height + spin / m)


@pytest.mark.parametrize("slope", [0.0, 5.0])
def test_a_stop_that_tips_the_robot_is_the_closed_form(slope):
    """Stretch braking from a forward run, 0.5 kg held, the wheels' traction not limited and any
    sharing of the load (exact tip-over): it tips forward over its wheels' axle, at the closed
    form's deceleration to 1e-9, on a level floor and driving up a 5 deg ramp (which helps it stop)."""
    robot = mobmanip.load_robot("stretch")
    q = mobmanip.named_configuration(robot, "home")
    floor = Floor(mu=None, load="any", slope=slope, uphill=0.0)
    stop = hardest_stop(robot, q, 1, 1.0, 0.5, floor)
    assert any("tips over about the edge joint_right_wheel to joint_left_wheel" in b for b in stop.binding), stop
    expected = _closed_form(robot, q, 0.5, slope)
    assert stop.deceleration == pytest.approx(expected, rel=1e-9)
    assert stop.distance == pytest.approx(1.0 / (2.0 * expected), rel=1e-9)
    assert stop.time == pytest.approx(1.0 / expected, rel=1e-9)
    assert stop.speed_for(stop.distance) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("name, posture, mass", [("tiago_dual", "hold", 2.0), ("tiago_pro", "home", 1.0)])
def test_the_stop_lies_inside_the_grounded_set_and_turns_with_the_robot(name, posture, mass):
    """Holding the arms and the turn at zero only restricts: each sense's deceleration is at most
    the grounded set's straight-line reach against the run; the robot turned by 1 rad and moved
    brakes as hard; on a ramp rising along the run it brakes harder forward than on the level, and
    less backward (driving downhill)."""
    robot = mobmanip.load_robot(name)
    q = mobmanip.named_configuration(robot, posture)
    floor = Floor(mu=0.5)
    grounded = mobmanip.analyze(
        robot, q, "planar", object_mass=mass, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5, level=True),)
    ).measures["dynamic_polytope"]
    turned = q.copy()
    turned[:4] = (2.0, -1.0, math.cos(1.0), math.sin(1.0))
    for sense in (1, -1):
        stop = hardest_stop(robot, q, sense, 1.0, mass, floor)
        assert 0.0 < stop.deceleration <= grounded.straight_line_reach([-sense, 0.0]) * (1 + 1e-9)
        there = hardest_stop(robot, turned, sense, 1.0, mass, floor)
        assert there.deceleration == pytest.approx(stop.deceleration, rel=1e-7)
        ramp = hardest_stop(robot, q, sense, 1.0, mass, Floor(mu=0.5, slope=5.0, uphill=0.0))
        assert (ramp.deceleration > stop.deceleration) == (sense > 0)


def test_the_braking_set_holds_the_arms_and_the_turn():
    """Every point of the braking set is reached with the arms' reduced accelerations and the
    base's yaw acceleration at zero (its witness)."""
    robot = mobmanip.load_robot("tiago_dual")
    q = mobmanip.named_configuration(robot, "hold")
    braking = braking_set(robot, q, 2.0, Floor(mu=0.5))
    xdot = braking.straight_line_witness([-1.0, 0.0]).variables["xdot"]
    S = robot.null_space(q)
    assert np.abs(xdot[robot.platform.n_reduced :]).max() <= 1e-9 * np.abs(xdot).max()
    assert abs(S[2] @ xdot) <= 1e-9 * np.abs(xdot).max()


def test_the_command_reports_both_senses(tmp_path, capfd):
    from hostile_util import assert_one_line_error, run_cli

    out = tmp_path / "b.json"
    code, printed, err = run_cli(
        capfd, "brake", "tiago_dual", "--posture", "hold", "--object-mass", "2", "--within", "0.3", "--json", out
    )
    assert code == 0, err
    document = json.loads(out.read_text())
    forward, backward = document["stops"]
    assert (forward["sense"], backward["sense"]) == ("forward", "backward")
    for stop in (forward, backward):
        assert stop["distance"] == pytest.approx(1.0 / (2.0 * stop["deceleration"]), rel=1e-12)
        assert stop["within"]["speed"] == pytest.approx(math.sqrt(2.0 * stop["deceleration"] * 0.3), rel=1e-12)
        assert f"{stop['deceleration']:.4g} m/s^2, stops in {stop['distance']:.4g} m" in printed
    code, _, err = run_cli(capfd, "brake", "panda")
    assert_one_line_error(code, err, "panda has a fixed platform", "no stop")
    assert "steer" not in err  # it spoke of a steered base's steering
    code, _, err = run_cli(capfd, "brake", "stretch", "--speed", "-1")
    assert_one_line_error(code, err, "--speed")


@pytest.mark.parametrize("slope", [0.0, 5.0])
@pytest.mark.parametrize("sense", [1, -1])
def test_tiago_stops_in_mujoco_as_predicted(sense, slope):
    """TIAGo++ holding 2 kg, braking from 1 m/s forward and backward on a level floor and driving
    up or down a 5 deg ramp (mu 0.5): the stop's efforts, from the run's speed in MuJoCo (the
    wheels turning as S says, the object moving with the base) with a joint feedback that stays
    under 0.01 N m, stop the robot within 1e-3 of the predicted distance, no support rises, no
    wheel slides faster than 1e-6 m/s and every wheel stays within friction (measured: at most
    0.74 of it; the distances within 2e-4)."""
    pytest.importorskip("mujoco")
    import mobmanip.referee as referee_package

    robot = mobmanip.load_robot("tiago_dual")
    q = mobmanip.named_configuration(robot, "hold")
    floor = Floor(mu=0.5, slope=slope)
    stop = hardest_stop(robot, q, sense, 1.0, 2.0, floor)
    info = braking_set(robot, q, 2.0, floor).model["floor"]
    # the ramp rises along +x: in its axes gravity has g sin s downhill (-x) and g cos s into it
    s = math.radians(slope)
    gravity = 9.81 * np.array([-math.sin(s), 0.0, -math.cos(s)]) if slope else None
    held = mobmanip.analyze(robot, q, "planar", object_mass=2.0, measures=("kinematic",)).held_object
    referee = referee_package.build(
        robot, q, contacts=referee_package.contacts_of_floor(info), object=referee_package.object_for_referee(held),
        grasp="level", mu=0.5, gravity=gravity,
    )  # fmt: skip
    S = robot.null_space(q)
    n = robot.platform.n_reduced
    x = np.zeros(robot.nx)
    x[:n] = np.linalg.lstsq(S[:3, :n], [sense * 1.0, 0.0, 0.0], rcond=None)[0]
    run = referee.rollout(stop.tau, stop.time, velocity=x, feedback=(200.0, 20.0))
    travelled = float(np.linalg.norm(run.base_position[-1, :2] - run.base_position[0, :2]))
    assert travelled == pytest.approx(stop.distance, rel=1e-3)
    step = run.time[-1] - run.time[-2]
    assert np.linalg.norm(run.base_position[-1] - run.base_position[-2]) / step <= 1e-3  # stopped
    driven = [k for k, s in enumerate(run.supports) if s.driven]
    assert -run.penetration.min() <= 1e-6 and run.slip_speed[:, driven].max() <= 1e-6
    assert run.friction_use[:, driven].max() < 1.0 and run.feedback < 0.01


def test_a_steered_base_brakes_from_a_straight_run_only(tmp_path, capfd):
    """The steered tricycle with its steering at 0.4 rad turns as it drives: a straight run does
    not exist, and the command says so in one line; steering at 0, it brakes both ways, within its
    grounded set (its drive wheel's traction stops a harder stop)."""
    from hostile_util import assert_one_line_error, run_cli
    from test_steered import write_tricycle

    spec = write_tricycle(tmp_path)
    robot = mobmanip.load_robot(spec)
    q = mobmanip.named_configuration(robot, "home")
    steer = robot.model.joints[robot.model.getJointId("steer_joint")].idx_q
    q[steer] = 0.4
    configuration = tmp_path / "q.json"
    configuration.write_text(json.dumps(robot.configuration_dict(q)))
    code, _, err = run_cli(capfd, "brake", spec, "--q", configuration, "--object-mass", "1")
    assert_one_line_error(code, err, "cannot drive straight", "steering")
    q[steer] = 0.0
    grounded = mobmanip.analyze(
        robot, q, "planar", object_mass=1.0, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5, level=True),)
    ).measures["dynamic_polytope"]
    for sense in (1, -1):
        stop = hardest_stop(robot, q, sense, 1.0, 1.0, Floor(mu=0.5))
        assert 0.0 < stop.deceleration <= grounded.straight_line_reach([-sense, 0.0]) * (1 + 1e-9)
        assert any("drive_wheel slips" in b for b in stop.binding), stop.binding
