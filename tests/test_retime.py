"""The fastest timing of a path (``mobmanip.motion.retime``, ``mobmanip retime``).

References: TOPP-RA's own implementation (``toppra``) on the same path and limits, with its
inverse dynamics from Pinocchio's RNEA on the robot's URDF read directly; the bang-coast-bang
closed form of one joint turning about a vertical axis; the floor checked at every grid point
through the zero-moment point and the contact loads assembled here from the floor's resultant
wrench; invariance under the input's own timing.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

from hostile_util import assert_one_line_error, run_cli
from mobmanip import load_robot
from mobmanip.errors import MobmanipError, NumericalError
from mobmanip.motion.carry_floor import CarryFloor
from mobmanip.motion.ground import ground_along
from mobmanip.motion.retime import retime, stops_along
from mobmanip.motion.trajectory import read_trajectory, trajectory_from_samples
from mobmanip.motion.trajectory_analysis import analyze_trajectory
from mobmanip.robot.support import robot_support
from retime_util import arm_indices, sine_path, toppra_duration

GRAVITY_Z = 9.81


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.mark.parametrize("discretization", ["interpolation", "collocation"])
def test_equals_toppra_with_joint_velocity_and_effort_limits(panda, discretization):
    """The same path, grid and limits as TOPP-RA's own implementation, in both of its
    discretizations (measured: 7e-9 and 3e-7 apart)."""
    toppra = pytest.importorskip("toppra")
    from mobmanip.descriptions.resources import example_robot_data_share

    toppra.setup_logging("WARNING")
    n = 201
    s, q, x_s, x_ss = sine_path(panda, n)
    ours = retime(
        panda, trajectory_from_samples(panda, s, q, x_s, x_ss), object_mass=0.0, discretization=discretization
    )

    # the reference: the Panda's URDF read by Pinocchio itself, fingers locked at zero
    robots = example_robot_data_share() / "example-robot-data" / "robots"
    full = pin.buildModelFromUrdf(str(robots / "panda_description" / "urdf" / "panda.urdf"))
    fingers = [full.getJointId(name) for name in ("panda_finger_joint1", "panda_finger_joint2")]
    model = pin.buildReducedModel(full, fingers, pin.neutral(full))
    data = model.createData()
    iq, _ = arm_indices(panda)
    home = q[0, iq]

    def inverse_dynamics(qq, qd, qdd):
        return pin.rnea(model, data, qq, qd, qdd)

    velocity = model.velocityLimit
    effort = model.effortLimit
    assert np.allclose(velocity, panda.velocity_limits) and np.allclose(effort, panda.effort_limits)
    duration = toppra_duration(home, s, velocity, effort, inverse_dynamics, discretization)
    assert ours.duration == pytest.approx(duration, rel=1e-6)
    assert ours.duration < 0.9 * (s[-1] - s[0])  # the input's timing is far from its limits here


def test_one_joint_turning_about_the_vertical_is_bang_coast_bang(panda):
    """Joint 1 alone, its axis vertical: tau = I qdd with I constant (Pinocchio's CRBA here), no
    gravity and no velocity term on it. The fastest turn by D within |qd| <= v, |tau| <= T is
    D / v + v / alpha (alpha = T / I) when it reaches v, else 2 sqrt(D / alpha)."""
    robot = panda.with_limits(effort={name: 1e6 for name in panda.reduced_velocity_names[1:]})
    iq, iv = arm_indices(robot)
    home = robot.hold_configuration()
    model = robot.model
    data = model.createData()
    inertia = pin.crba(model, data, home)[iv[0], iv[0]]
    v, T = float(robot.velocity_limits[0]), float(robot.effort_limits[0])
    alpha = T / inertia
    for turn in (3.0, 0.2):
        n = 2001
        s = np.linspace(0.0, 1.0, n)
        q = np.tile(home, (n, 1))
        q[:, iq[0]] = home[iq[0]] + turn * s
        x_s, x_ss = np.zeros((n, 7)), np.zeros((n, 7))
        x_s[:, 0] = turn
        found = retime(robot, trajectory_from_samples(robot, s, q, x_s, x_ss), object_mass=0.0)
        closed = turn / v + v / alpha if turn >= v * v / alpha else 2.0 * math.sqrt(turn / alpha)
        # one grid interval at each switch: O(1 / n)
        assert found.duration == pytest.approx(closed, rel=2e-3), turn
        assert set(found.binding_kind) <= {"velocity", "effort"}


def test_the_inputs_own_timing_does_not_matter(panda):
    n = 101
    s, q, x_s, x_ss = sine_path(panda, n)
    first = retime(panda, trajectory_from_samples(panda, s, q, x_s, x_ss), object_mass=0.5)
    for k in (0.4, 3.0):  # the same path run k times faster: s -> s / k
        again = retime(panda, trajectory_from_samples(panda, s / k, q, x_s * k, x_ss * k * k), object_mass=0.5)
        assert again.duration == pytest.approx(first.duration, rel=1e-9)
        # s' counts the new parameter; compared squared (the program's variable: a square root
        # would turn rounding at a near stop, 1e-14, into 1e-7)
        squared = (first.speed / k) ** 2
        assert np.allclose(again.speed**2, squared, rtol=1e-7, atol=1e-12 * squared.max())


def test_profile_properties(panda):
    n = 101
    s, q, x_s, x_ss = sine_path(panda, n)
    result = retime(panda, trajectory_from_samples(panda, s, q, x_s, x_ss), object_mass=0.5)
    assert result.speed[0] == 0.0 and result.speed[-1] == 0.0
    assert np.all(np.diff(result.t) > 0.0)
    assert np.all(result.speed <= result.controllable * (1 + 1e-9) + 1e-12)
    assert np.all(result.controllable <= result.limit * (1 + 1e-9) + 1e-12)
    # the retimed motion: x = x_s s', xdot = x_s s'' + x_ss s'^2, and within every limit
    motion = result.trajectory
    assert np.allclose(motion.x, x_s * result.speed[:, None])
    analysis = analyze_trajectory(panda, motion, object_mass=0.5)
    assert analysis.velocity_use.max() <= 1.0 + 1e-9
    assert analysis.effort_use.max() <= 1.0 + 1e-9
    # each interval's s'' kept at its end too: sample i + 1 reached with interval i's s''
    b, a = result.speed**2, result.acceleration
    ends = trajectory_from_samples(
        panda,
        motion.t[1:],
        motion.q[1:],
        x_s[1:] * result.speed[1:, None],
        x_s[1:] * a[:-1, None] + x_ss[1:] * b[1:, None],
    )
    at_ends = analyze_trajectory(panda, ends, object_mass=0.5)
    assert at_ends.velocity_use.max() <= 1.0 + 1e-9
    assert at_ends.effort_use.max() <= 1.0 + 1e-9
    # time optimal: some limit is tight at one end of nearly every interval
    start = np.maximum(analysis.velocity_use.max(axis=1), analysis.effort_use.max(axis=1))[:-1]
    end = np.maximum(at_ends.velocity_use.max(axis=1), at_ends.effort_use.max(axis=1))
    assert np.mean(np.maximum(start, end) > 1.0 - 1e-6) > 0.95


# ----- on the floor -----


@pytest.fixture(scope="module")
def tiago():
    return load_robot("tiago_dual")


def _drive_and_reach(robot, n=121):
    """TIAGo++ driving 1.2 m along an arc while its arms move: a smooth whole-body path."""
    home = robot.hold_configuration()
    s = np.linspace(0.0, 6.0, n)
    u = 0.5 - 0.5 * np.cos(math.pi * s / 6.0)
    yaw = 0.4 * u
    q = np.tile(home, (n, 1))
    q[:, 0] = 3.0 * np.sin(yaw)  # an arc of radius 3 m, 1.2 m long: the wheels roll without sliding
    q[:, 1] = 3.0 * (1.0 - np.cos(yaw))
    q[:, 2], q[:, 3] = np.cos(yaw), np.sin(yaw)
    model = robot.model
    for name, change in (("arm_left_2_joint", 0.3), ("arm_right_2_joint", 0.3), ("arm_left_4_joint", -0.4)):
        j = model.getJointId(name)
        q[:, model.joints[j].idx_q] += change * u
    known = [name for name in robot.joint_names if "wheel" not in name]
    return trajectory_from_samples(robot, s, q, known_joints=known)


def _contact_loads(support, pose, force, moment):
    """Equally stiff contacts under a rigid platform: normal forces f_c = k0 + k1 x_c + k2 y_c
    (a plane of compressions), balancing the resultant's vertical force and its moments about
    the floor (assembled here, by least squares over the plane's three numbers)."""
    points = support.world_points(pose)
    z = support.floor_z
    A = np.c_[np.ones(len(points)), points[:, 0], points[:, 1]]  # f = A k
    # sum f = F_z; sum y f = M_x + z F_y; sum -x f = M_y - z F_x
    balance = np.vstack([np.ones(len(points)), points[:, 1], -points[:, 0]])
    target = np.array([force[2], moment[0] + z * force[1], moment[1] - z * force[0]])
    k = np.linalg.solve(balance @ A, target)
    return A @ k


def _wheel_forces(support, pose, force, moment):
    """The driven wheels' tangential forces (world x, y), the casters rolling freely: they carry
    the resultant's F_x, F_y and its yaw moment about the world origin, split as equal tyres (the
    least-squares split), (wheels, 2)."""
    driven = [c for c, contact in enumerate(support.contacts) if contact.driven]
    points = support.world_points(pose)[driven]
    B = np.zeros((3, 2 * len(driven)))
    B[0, 0::2], B[1, 1::2] = 1.0, 1.0
    B[2, 0::2], B[2, 1::2] = -points[:, 1], points[:, 0]
    split = np.linalg.lstsq(B, np.array([force[0], force[1], moment[2]]), rcond=None)[0]
    return driven, split.reshape(-1, 2)


def test_the_floor_holds_at_every_grid_point(tiago):
    path = _drive_and_reach(tiago)
    free = retime(tiago, path, object_mass=2.0)
    floor = CarryFloor(mu=0.5, zmp_margin=0.05, reserve=0.2)
    grounded = retime(tiago, path, object_mass=2.0, floor=floor)
    assert grounded.duration > free.duration * 1.2  # 3.95 s against 2.25 s when measured
    assert "contact" in grounded.binding_kind

    motion = grounded.trajectory
    analysis = analyze_trajectory(tiago, motion, object_mass=2.0)
    assert analysis.velocity_use.max() <= 1.0 + 1e-9
    assert analysis.effort_use.max() <= 1.0 + 1e-9
    along = ground_along(tiago, motion, analysis.object_acceleration, object_mass=2.0)
    assert along.margin.min() >= 0.05 - 1e-7
    support = robot_support(tiago)
    total = (pin.computeTotalMass(tiago.model) + 2.0) * GRAVITY_Z
    least = 0.2 * total / len(support.contacts)
    lowest, traction = np.inf, 0.0
    for i in range(len(motion)):
        pose = (motion.q[i, 0], motion.q[i, 1], math.atan2(motion.q[i, 3], motion.q[i, 2]))
        loads = _contact_loads(support, pose, along.force[i], along.moment[i])
        assert loads.sum() == pytest.approx(along.force[i][2], rel=1e-9)
        lowest = min(lowest, float(loads.min() - least))
        driven, tangential = _wheel_forces(support, pose, along.force[i], along.moment[i])
        # the pyramid inscribed in the cone: within the cone, with the reserve's share kept
        use = np.linalg.norm(tangential, axis=1) / (0.5 * (1 - 0.2) * loads[driven])
        traction = max(traction, float(use.max()))
    assert lowest >= -1e-6 * total
    assert lowest <= 1e-6 * total  # some support is at its reserve: the floor binds
    assert traction <= 1.0 + 1e-9


def test_an_end_that_cannot_stand_still_is_named(tiago):
    """With reserve 0.3 the last posture keeps its back casters above their reserve only while the
    robot accelerates (measured at rest: 5 N short on the right one): no timing brings it to rest
    there, and the error says why, naming the casters."""
    path = _drive_and_reach(tiago)
    with pytest.raises(NumericalError, match="no timing of the path") as failure:
        retime(tiago, path, object_mass=2.0, floor=CarryFloor(mu=0.5, zmp_margin=0.05, reserve=0.3))
    assert "the last sample cannot be held still (s'' = 0): support caster_back_right_2_link loaded" in str(
        failure.value
    )


def _planar_path(robot, n=21):
    home = robot.hold_configuration()
    s = np.linspace(0.0, 1.0, n)
    q = np.tile(home, (n, 1))
    q[:, 0] = 0.3 * s
    return trajectory_from_samples(robot, s, q)


def test_a_posture_that_cannot_be_held_is_named(panda):
    weak = panda.with_limits(effort={"panda_joint2": 1e-3})
    n = 21
    s, q, x_s, x_ss = sine_path(weak, n)
    with pytest.raises(NumericalError, match="panda_joint2"):
        retime(weak, trajectory_from_samples(weak, s, q, x_s, x_ss), object_mass=0.0)


# ----- the command -----


def test_command_writes_a_trajectory_that_trajectory_reads(tiago, tmp_path, capfd):
    from mobmanip.commands.outputs import write_trajectory_csv

    path = _drive_and_reach(tiago, n=41)
    source = write_trajectory_csv(tiago, tmp_path / "path.csv", path.t, path.q)
    out = tmp_path / "out"
    code, stdout, stderr = run_cli(
        capfd, "retime", "tiago_dual", source, "--object-mass", "1.5", "--ground", "--reserve", "0.2",
        "--stop-within", "0.2", "--out", out,
    )  # fmt: skip
    assert code == 0, stderr
    assert "fastest timing from rest to rest" in stdout and "what limits it:" in stdout
    document = json.loads((out / "retime.json").read_text())
    retimed = read_trajectory(tiago, out / "retimed.csv")
    assert retimed.t[-1] - retimed.t[0] == pytest.approx(document["duration"], rel=1e-12)
    assert np.allclose(retimed.q, path.q, atol=1e-9)
    assert (out / "retime.png").stat().st_size > 0
    assert document["floor"]["reserve"] == 0.2
    stops = document["stops"]
    k = stops["lowest_at_sample"]
    assert f"at most {stops['lowest_base_speed']:.4g} m/s at sample {k}" in stdout
    columns, driving = stops["columns"], _driving(path, tiago)
    ahead = [r for r, d in enumerate(columns["distance"]) if columns["distance"][-1] - d >= 0.2 and r in driving]
    assert stops["lowest_base_speed"] == min(columns["base_speed"][r] for r in ahead) > 0.0


@pytest.mark.parametrize(
    "options, message",
    [
        (["--level"], "--level"),
        (["--load", "any"], "--load any"),
        (["--zmp-margin", "-1"], "--zmp-margin"),
    ],
)
def test_command_refuses_floor_options_it_does_not_model(tmp_path, capfd, options, message):
    source = tmp_path / "path.csv"
    source.write_text("t,platform_x,platform_y,platform_yaw\n0,0,0,0\n1,0.1,0,0\n2,0.2,0,0\n")
    code, _, stderr = run_cli(capfd, "retime", "tiago_dual", source, *options)
    assert_one_line_error(code, stderr, message)


def test_effort_map_is_the_efforts_of_the_motion(tiago):
    """The rows' efforts, L xdot + bias, equal :meth:`MotionTerms.torques` at any acceleration."""
    from mobmanip.motion.in_motion import motion_terms

    rng = np.random.default_rng(7)
    q = tiago.hold_configuration()
    terms = motion_terms(tiago, q, rng.normal(size=tiago.nx) * 0.4, object_mass=2.0)
    L, bias = terms.effort_map()
    for _ in range(3):
        xdot = rng.normal(size=tiago.nx)
        expected = terms.torques(xdot)
        assert np.allclose(L @ xdot + bias, expected, rtol=1e-10, atol=1e-10 * np.abs(expected).max())


# ----- braking along a path -----


def _straight(robot, n=81, length=2.0):
    """The platform driving straight ahead at a constant rate (0.5 m per unit of s), arms still."""
    home = robot.hold_configuration()
    s = np.linspace(0.0, length / 0.5, n)
    q = np.tile(home, (n, 1))
    q[:, 0] = home[0] + 0.5 * s
    known = [name for name in robot.joint_names if "wheel" not in name]
    return trajectory_from_samples(robot, s, q, known_joints=known)


def test_the_highest_speed_that_stops_within_a_distance_is_the_closed_form(tiago):
    """Driving straight with the arms still, nothing depends on the speed, so the hardest stop is a
    constant deceleration: the largest one every effort allows, a_min = max over joints of the
    bound of |tau' a + tau_g| <= T, with tau' = S^T M S x_s and tau_g = S^T g assembled here from
    Pinocchio's CRBA and gravity (no object). From it, v = sqrt(2 |a_min| (s_j - s_i)) in s' and the
    platform's speed 0.5 v. The one velocity term left out, 3e-7 N m at s' = 1 (checked below: the
    file's wheels spin against a slightly tilted inertia), moves v by 4e-8 of itself."""
    path = _straight(tiago)
    found = stops_along(tiago, path, 0.3, object_mass=0.0)
    model, data = tiago.model, tiago.model.createData()
    i = 10
    q, x_s = path.q[i], path.x[i]
    S = tiago.null_space(q)
    per_a = np.linalg.solve(tiago.Q, S.T @ pin.crba(model, data, q) @ S @ x_s)
    static = np.linalg.solve(tiago.Q, S.T @ pin.computeGeneralizedGravity(model, data, q))
    T = np.asarray(tiago.effort_limits)
    moving = np.abs(per_a) > 1e-12
    lower = np.where(per_a[moving] > 0, (-T - static)[moving] / per_a[moving], (T - static)[moving] / per_a[moving])
    a_min = float(lower.max())
    j = int(found.stop_at[i])
    assert found.distance[j] - found.distance[i] <= 0.3 + 1e-12 < found.distance[j + 1] - found.distance[i]
    expected = math.sqrt(2.0 * -a_min * (path.t[j] - path.t[i]))
    assert expected * np.abs(x_s).max() < np.asarray(tiago.velocity_limits)[np.argmax(np.abs(x_s))]  # efforts bind
    velocity_term = S.T @ (
        pin.rnea(model, data, q, S @ x_s, np.zeros(model.nv)) - pin.computeGeneralizedGravity(model, data, q)
    )
    assert np.abs(velocity_term).max() < 1e-6
    assert found.speed[i] == pytest.approx(expected, rel=1e-6)
    assert found.base_speed[i] == pytest.approx(0.5 * expected, rel=1e-6)


def test_a_floor_lowers_the_speed_from_which_it_stops(tiago):
    path = _straight(tiago)
    free = stops_along(tiago, path, 0.3, object_mass=2.0)
    grounded = stops_along(tiago, path, 0.3, object_mass=2.0, floor=CarryFloor(mu=0.5, reserve=0.2))
    inside = free.stop_at > np.arange(len(path))
    assert np.all(grounded.speed[inside] <= free.speed[inside] * (1 + 1e-9))
    assert np.any(grounded.speed[inside] < 0.9 * free.speed[inside])
    with pytest.raises(MobmanipError, match="stopping distance"):
        stops_along(tiago, path, -1.0)


def _driving(path, robot):
    """The samples where the platform drives at least a tenth of its fastest (the test's own)."""
    rates = np.array([np.linalg.norm((robot.null_space(q) @ x)[:2]) for q, x in zip(path.q, path.x)])
    return set(np.flatnonzero(rates >= 0.1 * rates.max()).tolist())


@pytest.mark.parametrize(
    "name, task, mass",
    [("tiago_dual", "spatial", 2.0), ("tiago_dual", "planar_rigid", 0.0), ("planar_dual_arm", "planar", 2.0)],
)
def test_path_terms_equal_the_reduced_dynamics_at_every_sample(tiago, name, task, mass):
    """Two routes to the rows: the stacked Newton-Euler terms retime uses (path_terms) against the
    reduced dynamics P, xi and the grasp of :func:`motion_terms` with :func:`floor_wrench` and
    :func:`rest_wrench`, sample by sample, on a path that drives along an arc (S changes with the heading) while the
    arms move."""
    robot = tiago if name == "tiago_dual" else load_robot(name)
    if name == "tiago_dual":
        path = _drive_and_reach(robot, n=9)
    else:  # the paper robot along an arc, its arms swinging
        home = robot.hold_configuration()
        s = np.linspace(0.0, 2.0, 9)
        yaw = 0.3 * s
        q = np.tile(home, (9, 1))
        q[:, 0], q[:, 1] = 2.0 * np.sin(yaw), 2.0 * (1.0 - np.cos(yaw))
        q[:, 2], q[:, 3] = np.cos(yaw), np.sin(yaw)
        for arm in robot.arms:
            for joint in arm.joint_names:
                q[:, robot.model.joints[robot.model.getJointId(joint)].idx_q] += 0.2 * np.sin(s)
        known = [n for n in robot.joint_names if "wheel" not in n]
        path = trajectory_from_samples(robot, s, q, known_joints=known)
    terms = assert_path_terms_match(robot, path, task, mass)
    assert np.abs(terms.effort_b).max() > 1e-3 * np.abs(terms.effort_0).max()  # the velocity terms are there


def assert_path_terms_match(robot, path, task, mass):
    """path_terms (stacked Newton-Euler) against motion_terms' effort map, floor_wrench and
    rest_wrench (the reduced dynamics P, xi and the grasp), sample by sample, to 1e-10 of their scale."""
    from mobmanip.motion.ground import floor_wrench, rest_wrench
    from mobmanip.motion.in_motion import motion_terms
    from mobmanip.motion.path_terms import path_terms
    from mobmanip.robot.tasks import get_task

    terms = path_terms(robot, path, get_task(task), mass, wrench=True)
    for i in range(len(path)):
        q, x_s, x_ss = path.q[i], path.x[i], path.xdot[i]
        reference = motion_terms(robot, q, x_s, task, object_mass=mass)
        L, moving = reference.effort_map()
        static = reference.static_torques()
        scale = max(np.abs(static).max(), np.abs(L @ x_s).max())  # the paper robot's gravity is 0
        assert np.allclose(terms.effort_0[i], static, rtol=0, atol=1e-10 * scale)
        assert np.allclose(terms.effort_a[i], L @ x_s, rtol=0, atol=1e-10 * scale)
        assert np.allclose(terms.effort_b[i], L @ x_ss + moving - static, rtol=0, atol=1e-10 * scale)
        rows = list(get_task(task).rows)
        a0, a1 = np.zeros(6), np.zeros((6, robot.nx))
        a0[rows] = reference.W_pinv.T @ (reference.drift - reference.grasp_drift)
        a1[rows] = reference.W_pinv.T @ reference.J_u
        offset, linear = floor_wrench(robot, q, x_s, mass, a0, a1)
        weight = rest_wrench(robot, q, mass)
        size = np.abs(weight).max()
        assert np.allclose(terms.wrench_0[i], weight, rtol=0, atol=1e-10 * size)
        assert np.allclose(terms.wrench_a[i], linear @ x_s, rtol=0, atol=1e-10 * size)
        assert np.allclose(terms.wrench_b[i], linear @ x_ss + offset - weight, rtol=0, atol=1e-10 * size)
    return terms
