"""A team on its floor while it carries (``team_carry(..., floor=)``, ``team-carry --ground``).

Reference, assembled here without mobmanip's reduced terms or grasp matrix: each robot rebuilt
from its URDF with a free-flyer root (tests/floor_reference.py); its floor wrench is the base
wrench Pinocchio's RNEA needs for the step (velocity terms at the previous step's rates, as the
step's model takes them), plus what its hands push on the object with. The object's motion is
read from the hands' own velocities and accelerations (Pinocchio's frame quantities), as a rigid
planar body fitted by least squares (v + w x r, a + alpha x r - w^2 r at each grasp point); the
load M_o a_o is shared among the hands by the least-norm split of the test's own grasp map, and
the object's weight (the planar task leaves the vertical out) equally. The contacts' loads and
the wheels' traction then follow as in tests/test_retime.py (a plane of compressions, the
least-squares split of the tangential forces).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from floor_reference import free_flyer_configuration, free_flyer_model, free_flyer_null_space
from mobmanip.coordination.carry import team_carry
from mobmanip.coordination.effort import team_step_maps
from mobmanip.coordination.floor import TeamFloor
from mobmanip.errors import ArgumentError
from mobmanip.motion.carry import ObjectPath, read_path
from mobmanip.motion.carry_floor import CarryFloor
from mobmanip.robot.support import robot_support
from mobmanip.robot.tasks import get_task
from mobmanip.team.members import load_team
from test_retime import _contact_loads, _wheel_forces

G = 9.81
BEAM = "examples/beam_team.toml"
MASS = 4.0  # the beam's, as the example's TOML says
LENGTH, WIDTH = 1.5, 0.08


@pytest.fixture(scope="module")
def team():
    return load_team(BEAM)


def _hand_frames(team):
    """(robot index, frame name) of every grasping hand, in the team's order."""
    return [(i, m.robot.model.frames[m.robot.arms[a].frame_id].name) for i, m in enumerate(team.members)
            for a in m.arms]  # fmt: skip


def _robot_part(robot, q, x_prev, xdot):
    """The free-flyer RNEA's base wrench (force, moment about the world origin; world axes) and the
    model, data and configuration it ran at (for the hands)."""
    model = free_flyer_model(robot)
    data = model.createData()
    q_f = free_flyer_configuration(robot, model, q)
    S_f = free_flyer_null_space(robot, model, q)
    v, a = S_f @ x_prev, S_f @ xdot
    wrench = pin.rnea(model, data, q_f, v, a)[:6]
    pin.forwardKinematics(model, data, q_f, v, a)
    pin.updateFramePlacements(model, data)
    base = data.oMi[1]
    force = base.rotation @ wrench[:3]
    return np.r_[force, base.rotation @ wrench[3:] + np.cross(base.translation, force)], model, data


def _reference_wrenches(team, qs, x_prev, x, h):
    """Each robot's floor wrench over a step from x_prev to x (see the module's docstring), (k, 6)."""
    slices = [slice(sum(m.robot.nx for m in team.members[:i]), sum(m.robot.nx for m in team.members[: i + 1]))
              for i in range(len(team.members))]  # fmt: skip
    parts = [_robot_part(m.robot, q, x_prev[s], (x[s] - x_prev[s]) / h) for m, q, s in zip(team.members, qs, slices)]
    held = team.held_object
    r = held.offsets
    # every hand's planar velocity and acceleration (x, y, yaw), world axes
    vel, acc = [], []
    for i, name in _hand_frames(team):
        _, model, data = parts[i]
        frame = model.getFrameId(name)
        v = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
        a = pin.getFrameClassicalAcceleration(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
        vel.append([v.linear[0], v.linear[1], v.angular[2]])
        acc.append([a.linear[0], a.linear[1], a.angular[2]])
    rigid = np.vstack([[[1.0, 0.0, -ry], [0.0, 1.0, rx], [0.0, 0.0, 1.0]] for rx, ry in r[:, :2]])
    twist = np.linalg.lstsq(rigid, np.ravel(vel), rcond=None)[0]
    w = twist[2]
    centripetal = np.ravel([[w * w * rx, w * w * ry, 0.0] for rx, ry in r[:, :2]])
    a_o = np.linalg.lstsq(rigid, np.ravel(acc) + centripetal, rcond=None)[0]
    inertia = MASS * (LENGTH**2 + WIDTH**2) / 12.0  # the beam as a uniform box, about the vertical
    load = np.array([MASS * a_o[0], MASS * a_o[1], inertia * a_o[2]])
    share = np.linalg.lstsq(rigid.T, load, rcond=None)[0].reshape(-1, 3)  # least-norm hand wrenches
    out = np.array([p[0].copy() for p in parts])
    for k, (i, _) in enumerate(_hand_frames(team)):
        p = held.center + r[k]
        force = np.array([share[k, 0], share[k, 1], MASS * G / len(r)])
        out[i, :3] += force
        out[i, 3:] += np.array([0.0, 0.0, share[k, 2]]) + np.cross(p, force)
    return out


def _margin(polygon: np.ndarray, p: np.ndarray) -> float:
    """Signed distance of p to a convex polygon's nearest edge (positive inside), by hand."""
    edges = np.roll(polygon, -1, axis=0) - polygon
    area = np.sum(polygon[:, 0] * np.roll(polygon[:, 1], -1) - np.roll(polygon[:, 0], -1) * polygon[:, 1])
    inward = np.c_[-edges[:, 1], edges[:, 0]] * np.sign(area) / np.linalg.norm(edges, axis=1)[:, None]
    return float(np.min(np.einsum("ij,ij->i", inward, p - polygon)))


def test_the_beam_is_the_box_the_reference_takes(team):
    held = team.held_object
    assert held.mass == MASS
    assert held.inertia[2, 2] == pytest.approx(MASS * (LENGTH**2 + WIDTH**2) / 12.0, rel=1e-12)


@pytest.mark.parametrize("seed", [3, 8])
def test_each_robots_floor_wrench_and_rows_are_the_free_flyer_rnea_and_the_hands_share(team, seed):
    """At the team's posture with random rates: each robot's floor wrench over the step equals the
    reference to 1e-9 of the weights; its rows' slack gives the reference's zero-moment point
    margin, contact loads and traction use."""
    rng = np.random.default_rng(seed)
    floor = CarryFloor(mu=0.5, zmp_margin=0.02, reserve=0.1)
    grounded = TeamFloor.build(team, floor)
    qs = [m.q for m in team.members]
    task = get_task(team.task)
    nx, h = team.nx, 0.05
    x_prev = rng.normal(scale=0.3, size=nx)
    x = x_prev + rng.normal(scale=0.05, size=nx)
    maps = team_step_maps(team, qs, x_prev, h, task, team.held_object)
    wrenches = grounded.wrenches(team, qs, x_prev, h, task, team.held_object, maps.hand_wrenches)
    reference = _reference_wrenches(team, qs, x_prev, x, h)
    weights = [(pin.computeTotalMass(m.robot.model) + MASS / 2) * G for m in team.members]
    for (w0, w1), ref, weight in zip(wrenches, reference, weights):
        np.testing.assert_allclose(w0 + w1 @ x, ref, rtol=0, atol=1e-9 * weight)

    G_rows, g_rows, labels, _ = grounded.step_rows(team, qs, wrenches)
    slack = g_rows - G_rows @ x
    margins, uses = grounded.readings(team, qs, wrenches, x)
    for i, (member, q, ref, weight) in enumerate(zip(team.members, qs, reference, weights)):
        mine = np.array([label.startswith(f"{member.name}: ") for label in labels])
        kinds = grounded.rows[i].kinds
        support = robot_support(member.robot)
        pose = (q[0], q[1], math.atan2(q[3], q[2]))
        force, moment = ref[:3], ref[3:]
        z = support.floor_z
        zmp = np.array([(z * force[0] - moment[1]) / force[2], (moment[0] + z * force[1]) / force[2]])
        margin = _margin(support.polygon(pose), zmp)
        tip = slack[mine][[k == "tip-over" for k in kinds]]
        assert tip.min() / force[2] + floor.zmp_margin == pytest.approx(margin, abs=1e-9)
        assert margins[i] == pytest.approx(margin, abs=1e-9)
        loads = _contact_loads(support, pose, force, moment)
        least = floor.reserve * weight / len(loads)
        np.testing.assert_allclose(slack[mine][[k == "contact" for k in kinds]] + least, loads, atol=1e-9 * weight)
        driven, pushes = _wheel_forces(support, pose, force, moment)
        use = np.linalg.norm(pushes, axis=1) / (floor.mu * loads[driven])
        assert uses[i] == pytest.approx(use.max(), rel=1e-9)


def _short_path(seconds=4.0):
    """The first seconds of the turning path, scaled to the beam's team (as the README's example)."""
    path = read_path("examples/carry_turn.csv")
    keep = path.t <= seconds + 1e-9
    return ObjectPath(path.t[keep], 2.0 * path.xy[keep], None, None if path.yaw is None else path.yaw[keep])


def _reference_readings(result, run, h, mu):
    """The reference's least zero-moment point margin (m) and largest traction use over a run
    from rest, per robot; the object at each sample where its hands hold it (``carried``: within
    the tracking error of where the step's model takes it)."""
    x = np.hstack(run.x)
    margin, use = np.full(len(result.team.members), np.inf), np.zeros(len(result.team.members))
    for k in range(len(x)):
        qs = [q[k] for q in run.q]
        moved, _ = result.carried(qs)
        wrenches = _reference_wrenches(moved, qs, np.zeros(moved.nx) if k == 0 else x[k - 1], x[k], h)
        for i, (member, q, ref) in enumerate(zip(moved.members, qs, wrenches)):
            support = robot_support(member.robot)
            pose = (q[0], q[1], math.atan2(q[3], q[2]))
            force, moment = ref[:3], ref[3:]
            loads = _contact_loads(support, pose, force, moment)
            driven, pushes = _wheel_forces(support, pose, force, moment)
            use[i] = max(use[i], float(np.max(np.linalg.norm(pushes, axis=1) / (mu * loads[driven]))))
            z = support.floor_z
            zmp = np.array([(z * force[0] - moment[1]) / force[2], (moment[0] + z * force[1]) / force[2]])
            margin[i] = min(margin[i], _margin(support.polygon(pose), zmp))
    return margin, use


def _straight_path():
    """0.3 m along the beam in 2 s, from rest to rest (the object's frame)."""
    t = np.linspace(0.0, 2.0, 41)
    return ObjectPath(t, np.c_[0.15 * (1.0 - np.cos(math.pi * t / 2.0)), np.zeros_like(t)])


def test_on_the_floor_no_wheel_slips_where_the_plain_team_carry_slips(team):
    """The plain QP motion sets off with the capacity term's whole velocity in its first step: read
    by the reference, the south robot's wheels then push 1.17 times what friction 0.3 holds
    (measured). On the floor the same team keeps every wheel within friction and every
    zero-moment point inside by its margin, at every step, read by the reference (its object
    where the hands hold it: within 1e-5 m of where the step's model takes it, hence the
    tolerances), and its own readings agree with the reference's to 1e-6."""
    path, floor = _straight_path(), CarryFloor(mu=0.3, zmp_margin=0.02)
    plain = team_carry(team, path, prepare=0.0, step=0.05)
    grounded = team_carry(team, path, prepare=0.0, step=0.05, floor=floor)
    _, plain_use = _reference_readings(plain, plain.motion, 0.05, 0.3)
    margin, use = _reference_readings(grounded, grounded.motion, 0.05, 0.3)
    assert plain_use.max() > 1.1
    assert use.max() <= math.cos(math.pi / 8) + 1e-5  # the pyramid inscribed in the cone
    assert use.max() >= math.cos(math.pi / 8) - 1e-5  # and it binds
    assert margin.min() >= floor.zmp_margin - 1e-5
    run = grounded.motion
    np.testing.assert_allclose(run.zmp_margin.min(axis=0), margin, atol=1e-6)
    np.testing.assert_allclose(np.nanmax(run.traction_use, axis=0), use, atol=1e-6)
    summary = grounded.summary()
    assert summary["floor"]["mu"] == 0.3 and set(summary["qp"]["floor"]["min_zmp_margin"]) == {"south", "north"}


def test_team_carry_ground_from_the_command_line(tmp_path, capfd):
    from mobmanip.cli import main

    path = tmp_path / "path.csv"
    straight = _straight_path()
    path.write_text("t,x,y\n" + "".join(f"{t:.6f},{x:.9f},{y:.9f}\n" for t, (x, y) in zip(straight.t, straight.xy)))
    assert main(["team-carry", BEAM, "--path", str(path), "--prepare", "0", "--ground", "--mu", "0.3"]) == 0
    out = capfd.readouterr().out
    assert "floor, QP with capacity: south zero-moment point at least" in out
    assert "traction use up to 0.924" in out
    assert main(["team-carry", BEAM, "--path", str(path), "--ground", "--slope", "5"]) == 2
    err = capfd.readouterr().err
    assert err.startswith("mobmanip: error: ") and "level floor" in err and len(err.splitlines()) == 1


def test_a_ramp_is_refused_for_a_team(team):
    with pytest.raises(ArgumentError, match="level floor"):
        TeamFloor.build(team, CarryFloor(mu=0.5, slope=5.0))
