"""Trajectory analysis: estimated rates, the exact time-scaling margin, CSV in and out, the command."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.cli import main
from mobmanip.commands.outputs import write_trajectory_csv
from mobmanip.errors import ArgumentError, JointNotFoundError
from mobmanip.motion import motion_terms
from mobmanip.motion.trajectory import (
    planar_exp,
    planar_log,
    read_trajectory,
    tangent_difference,
    trajectory_from_samples,
)
from mobmanip.motion.trajectory_analysis import analyze_trajectory


def arc_motion(robot, n=60, duration=6.0, speed=0.3, yaw_rate=0.15, amplitude=0.25):
    """A platform on a circle (no slip) with every arm joint swinging: closed-form samples and
    the exact reduced velocities and accelerations of the arm joints."""
    q0 = robot.hold_configuration()
    t = np.linspace(0.0, duration, n)
    base = robot.configuration_dict(q0)["joints"]
    arms = [name for arm in robot.arms for name in arm.joint_names]
    qs = []
    for ti in t:
        yaw = yaw_rate * ti
        radius = speed / yaw_rate
        joints = dict(base)
        for k, name in enumerate(arms):
            joints[name] = base[name] + amplitude * math.sin(0.8 * ti + k)
        qs.append(robot.configuration((radius * math.sin(yaw), radius * (1 - math.cos(yaw)), yaw), joints))
    return t, np.array(qs), arms


def test_estimated_rates_match_the_closed_form(tiago):
    t, qs, arms = arc_motion(tiago, n=400)
    tr = trajectory_from_samples(tiago, t, qs, known_joints=arms)
    assert tr.slip.max() < 1e-9  # a circle driven by the wheels: no lateral slip
    names = tiago.reduced_velocity_names
    i = 200
    for k, name in enumerate(arms):
        j = names.index(name)
        assert tr.x[i, j] == pytest.approx(0.25 * 0.8 * math.cos(0.8 * t[i] + k), abs=2e-5)
        assert tr.xdot[i, j] == pytest.approx(-0.25 * 0.64 * math.sin(0.8 * t[i] + k), abs=2e-4)
    # the wheels drive the platform at 0.3 m/s turning at 0.15 rad/s: S x gives the platform's twist
    v = tiago.null_space(qs[i]) @ tr.x[i]
    np.testing.assert_allclose(v[:3], [0.3, 0.0, 0.15], atol=1e-9)


def _limit_use(robot, trajectory):
    """Largest |x_i|/xdot_max_i and |tau_i|/tau_max_i, efforts from Pinocchio's RNEA directly."""
    vel = np.max(np.abs(trajectory.x) / robot.velocity_limits)
    eff = 0.0
    data = robot.model.createData()
    for q, x, xdot in zip(trajectory.q, trajectory.x, trajectory.xdot):
        terms = motion_terms(robot, q, x)
        S = terms.S
        a = S @ xdot + robot.null_space_rate(q, x) @ x  # joint accelerations, Sdot x included
        tau = S.T @ pin.rnea(robot.model, data, q, S @ x, a)
        a_o = terms.object_acceleration(xdot)
        wrench = terms.M_o @ a_o + terms.c_o + terms.g_o
        tau = np.linalg.solve(terms.Q, tau + terms.J_u.T @ np.linalg.pinv(terms.W) @ wrench)
        eff = max(eff, float(np.max(np.abs(tau) / robot.effort_limits)))
    return vel, eff


@pytest.mark.parametrize("limit", ["effort", "velocity"])
def test_time_scaling_margin_is_exact(tiago, limit):
    # make the other kind of limit slack, so that the kind under test decides the margin
    names = tiago.reduced_velocity_names
    if limit == "effort":
        robot = tiago.with_limits(velocity=dict(zip(names, 50.0 * tiago.velocity_limits)))
    else:
        robot = tiago.with_limits(effort=dict(zip(names, 50.0 * tiago.effort_limits)))
    t, qs, arms = arc_motion(robot, n=40)
    tr = trajectory_from_samples(robot, t, qs, known_joints=arms)
    result = analyze_trajectory(robot, tr)
    k = result.scaling.k_max
    assert result.scaling.feasible and k is not None
    assert result.scaling.limit.startswith(limit)
    # the same configurations with time stamps t / k, rates re-estimated, efforts from RNEA
    fast = trajectory_from_samples(robot, t / k, qs, known_joints=arms)
    scaled = tr.scaled(k)
    np.testing.assert_allclose(scaled.x, fast.x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(scaled.xdot, fast.xdot, rtol=1e-7, atol=1e-9)
    vel, eff = _limit_use(robot, fast)
    assert max(vel, eff) <= 1.0 + 1e-9
    assert max(vel, eff) == pytest.approx(1.0, abs=1e-9)
    faster = trajectory_from_samples(robot, t / (1.001 * k), qs, known_joints=arms)
    vel, eff = _limit_use(robot, faster)
    assert max(vel, eff) > 1.0 + 1e-4


def test_demands_against_capacity(robot, rng):
    """The paper's robot on a straight drive: v_o is the platform's speed; in the planar task the
    kinematic capacity along v_o is the ellipse's reach in that direction."""
    q0 = robot.hold_configuration()
    t = np.linspace(0.0, 2.0, 21)
    qs = np.array([robot.configuration((0.2 * ti, 0.0, 0.0), robot.configuration_dict(q0)["joints"]) for ti in t])
    arms = [name for arm in robot.arms for name in arm.joint_names]
    tr = trajectory_from_samples(robot, t, qs, known_joints=arms)
    result = analyze_trajectory(robot, tr)
    np.testing.assert_allclose(result.object_velocity, np.tile([0.2, 0.0], (21, 1)), atol=1e-9)
    np.testing.assert_allclose(result.object_acceleration, 0.0, atol=1e-9)
    kin = mobmanip.analyze(robot, qs[0], "planar").kinematic
    assert result.velocity_capacity[5] == pytest.approx(kin.radius_along(np.array([1.0, 0.0])), rel=1e-9)
    # constant speed: no effort but gravity's (none on a horizontal plane); margin from the wheels' speed
    wheel = robot.reduced_velocity_names.index("wheel_right_joint")
    assert result.scaling.k_max == pytest.approx(robot.velocity_limits[wheel] / abs(tr.x[0, wheel]), rel=1e-9)


def test_csv_round_trip_and_command(tiago, tmp_path):
    t, qs, arms = arc_motion(tiago, n=30)
    path = tmp_path / "traj.csv"
    write_trajectory_csv(tiago, path, t, qs)
    header = next(csv.reader(open(path)))
    assert header[:4] == ["t", "platform_x", "platform_y", "platform_yaw"]
    tr = read_trajectory(tiago, path)
    for a, b in zip(tr.q, qs):
        np.testing.assert_allclose(pin.difference(tiago.model, a, b), 0.0, atol=1e-12)
    out = tmp_path / "out"
    out.mkdir()
    page = tmp_path / "motion.html"
    assert main(["trajectory", "tiago_dual", str(path), "--out", str(out), "--export", str(page), "--every", "10"]) == 0
    html = page.read_text()
    # self-contained: meshes and animation embedded, nothing fetched (the browser test plays such a page)
    assert "<html" in html.lower() and len(html) > 100_000 and 'src="http' not in html
    doc = json.loads((out / "analysis.json").read_text())
    direct = analyze_trajectory(tiago, tr)
    assert doc["time_scaling"]["k_max"] == pytest.approx(direct.scaling.k_max, rel=1e-12)
    assert (out / "analysis.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = list(csv.reader(open(out / "analysis.csv")))
    assert len(rows) == 31


def test_bad_trajectories_are_refused(tiago, tmp_path):
    q = tiago.hold_configuration()
    with pytest.raises(ArgumentError, match="increase"):
        trajectory_from_samples(tiago, [0.0, 1.0, 1.0], np.array([q, q, q]))
    with pytest.raises(ArgumentError, match="at least 3"):
        trajectory_from_samples(tiago, [0.0, 1.0], np.array([q, q]))
    path = tmp_path / "bad.csv"
    path.write_text("t,platform_x,platform_y,platform_yaw,no_such_joint\n0,0,0,0,0\n1,0,0,0,0\n2,0,0,0,0\n")
    with pytest.raises(JointNotFoundError, match="no_such_joint"):
        read_trajectory(tiago, path)
    path.write_text("t,platform_x,platform_y,platform_yaw\n0,0,0,0\n1,0,x,0\n2,0,0,0\n")
    with pytest.raises(ArgumentError, match="line 3, column 'platform_y'"):
        read_trajectory(tiago, path)
    assert main(["trajectory", "tiago_dual", str(path)]) == 2


def _planar(x, y, yaw):
    return np.array([x, y, math.cos(yaw), math.sin(yaw)])


def test_planar_log_and_exp_against_pinocchio(rng):
    """Away from tiny turns the SE(2) log and exp are Pinocchio's planar difference and
    integrate; exp undoes log; and a turn of 1e-8 rad about yaw 0 is recovered to rounding,
    where cos(yaw) is 1 in floating point."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "root")
    for _ in range(50):
        qa = _planar(*rng.uniform(-2.0, 2.0, 2), rng.uniform(-math.pi, math.pi))
        qb = _planar(*rng.uniform(-2.0, 2.0, 2), rng.uniform(-math.pi, math.pi))
        xi = planar_log(qa, qb)
        np.testing.assert_allclose(xi, pin.difference(model, qa, qb), atol=1e-12)
        np.testing.assert_allclose(planar_exp(qa, xi), qb, atol=1e-12)
        step = rng.uniform(-0.5, 0.5, 3)
        np.testing.assert_allclose(planar_exp(qa, step), pin.integrate(model, qa, step), atol=1e-12)
        np.testing.assert_allclose(tangent_difference(model, qa, qb), xi, atol=0.0)
    for tiny in (1e-8, -3e-9, 1e-5):
        qa, qb = _planar(0.3, -0.1, 0.0), _planar(0.3, -0.1, tiny)
        assert planar_log(qa, qb)[2] == pytest.approx(tiny, rel=1e-9)
        # moving straight ahead by 2 mm while turning: the chord's lateral part is tiny * 1 mm
        qb = planar_exp(qa, np.array([2e-3, 0.0, tiny]))
        chord = qb[:2] - qa[:2]
        assert chord[1] == pytest.approx(2e-3 * math.sin(tiny / 2.0), rel=1e-9)
        # to the rounding of a 2 mm step
        np.testing.assert_allclose(planar_log(qa, qb), [2e-3, 0.0, tiny], rtol=1e-12, atol=1e-16)


def test_polytope_reach_along_the_object_velocity(tiago):
    """--polytope: at every sample the kinematic polytope's radius along v_o's direction d (its
    support function, as the ellipsoid's velocity_capacity) equals the optimum of an independent
    LP over object velocities and joint rates (max d . v with W^T v = J_u x, |x_i| <= xdot_max_i);
    it is at least the ellipsoid's (the ellipsoid lies inside the polytope) and at least the
    largest speed straight along d (a second LP: max s with J_u x = s W^T d)."""
    from scipy.optimize import linprog

    t, qs, arms = arc_motion(tiago, n=12)
    result = analyze_trajectory(tiago, trajectory_from_samples(tiago, t, qs, known_joints=arms), polytope=True)
    reach = result.velocity_polytope_capacity
    assert reach.shape == (12,)
    assert np.all(reach >= result.velocity_capacity * (1 - 1e-9))
    nx = tiago.nx
    bounds = [(-v, v) for v in tiago.velocity_limits]
    for i in (0, 5, 11):
        terms = motion_terms(tiago, result.trajectory.q[i], result.trajectory.x[i])
        d = result.object_velocity[i] / np.linalg.norm(result.object_velocity[i])
        m, mk = terms.W.shape
        support = linprog(
            np.r_[-d, np.zeros(nx)],
            A_eq=np.hstack([terms.W.T, -terms.J_u]),
            b_eq=np.zeros(mk),
            bounds=[(None, None)] * m + bounds,
            method="highs",
        )
        assert support.status == 0
        assert reach[i] == pytest.approx(-support.fun, rel=1e-7)
        ray = linprog(
            np.r_[np.zeros(nx), -1.0],
            A_eq=np.hstack([terms.J_u, -(terms.W.T @ d)[:, None]]),
            b_eq=np.zeros(mk),
            bounds=bounds + [(0, None)],
            method="highs",
        )
        assert ray.status == 0 and 0.0 < ray.x[-1] <= reach[i] * (1 + 1e-9)
    header, values = result.table()
    assert header[-1] == "velocity_polytope_capacity"
    np.testing.assert_array_equal(values[:, -1], reach)
    assert result.to_dict()["min_velocity_polytope_capacity"] == reach.min()
