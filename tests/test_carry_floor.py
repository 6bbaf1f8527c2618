"""``carry`` on the floor: the QP's floor rows keep every sample of the motion within the floor,
checked afterwards by the trajectory analysis (the floor's wrench from the samples' estimated
rates, the contacts' forces shared independently of the QP: mobmanip.motion.ground and
mobmanip.motion.traction, themselves checked against the free-flyer RNEA); where the plain carry
slips a wheel on the example line sped up. A path the floor cannot allow fails naming the row."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip import load_robot
from mobmanip.errors import CarryFailed
from mobmanip.motion.carry import ObjectPath, carry, read_path
from mobmanip.motion.carry_floor import CarryFloor, floor_rows
from mobmanip.motion.ground import ground_along
from mobmanip.motion.traction import traction_along
from mobmanip.motion.trajectory import Trajectory, read_trajectory, trajectory_from_samples
from mobmanip.motion.trajectory_analysis import analyze_trajectory
from mobmanip.robot.tasks import get_task

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _floor_along(robot, t, q, mu, samples=slice(None)):
    """(smallest stability margin (m), largest traction use, smallest normal force (N)) of the
    motion sampled at (t, q), by the trajectory analysis, over ``samples``."""
    motion = trajectory_from_samples(robot, t, q)
    analysis = analyze_trajectory(robot, motion)
    ground = ground_along(robot, motion, analysis.object_acceleration, analysis.task)
    traction = traction_along(ground, motion, mu)
    return (float(ground.margin[samples].min()), float(traction.use[samples].max()),
            float(traction.normal[samples].min()))  # fmt: skip


@pytest.mark.parametrize("name, speed", [("planar_dual_arm", 3.0), ("tiago_dual", 2.0)])
def test_carry_on_the_floor_keeps_every_sample_where_the_plain_carry_slips(name, speed):
    robot = mobmanip.load_robot(name)
    path = read_path(EXAMPLES / "carry_line.csv")
    fast = ObjectPath(path.t / speed, path.xy)
    mu = 0.2
    plain = carry(robot, fast, prepare=0.0)
    _, plain_use, _ = _floor_along(robot, plain.motion.t, plain.motion.q, mu)
    assert plain_use > 1.0  # the plain QP motion slips a wheel
    grounded = carry(robot, fast, prepare=0.0, floor=CarryFloor(mu=mu))
    margin, use, normal = _floor_along(robot, grounded.motion.t, grounded.motion.q, mu)
    assert use <= 1.0 and normal > 0.0 and margin > 0.0
    assert grounded.motion.tracking_error.max() < 1e-3  # it still carries the object along the path
    assert grounded.summary()["floor"]["mu"] == mu


def test_tiago_carries_on_the_floor_from_its_hold_posture_self_motion_and_all():
    """TIAGo from its spec's hold posture (the arm bent in front), with the default self-motion
    and its own mu (0.5): the self-motion and the QP motion both keep every sample on the floor
    by the trajectory analysis. With a reserve of 0.1 every support keeps a tenth of its equal
    share, so the analysis' least normal force is clear of zero (about 10.7 N); without one the
    capacity term takes a caster to zero load, a bound the analysis, from the samples' rates,
    reads as -0.13 N. From home (the arm stretched out to the side, arm_1_joint at its limit)
    the self-motion spun the base to -2.1 rad/s and failed at its 38th step
    (tests/test_builtin_robots_cli.py keeps that message)."""
    robot = mobmanip.load_robot("tiago")
    path = read_path(EXAMPLES / "carry_line.csv")
    result = carry(robot, path, floor=CarryFloor(reserve=0.1))
    assert result.preparation is not None and len(result.preparation.t) > 100  # it moved before the path
    for run in (result.preparation, result.motion):
        margin, use, normal = _floor_along(robot, run.t, run.q, 0.5)
        assert use <= 1.0 and normal > 0.0 and margin > 0.0
    assert result.motion.tracking_error.max() < 1e-3


def test_a_path_the_floor_cannot_allow_fails_naming_the_floor_row():
    robot = mobmanip.load_robot("planar_dual_arm")
    path = read_path(EXAMPLES / "carry_line.csv")
    with pytest.raises(CarryFailed) as info:
        carry(robot, ObjectPath(path.t / 3.0, path.xy), prepare=0.0, floor=CarryFloor(mu=0.1))
    d = info.value.diagnosis
    assert d.kind == "floor" and d.joint.startswith("traction of wheel_") and "(mu = 0.1)" in d.joint
    assert "the floor binds: traction of wheel_" in str(info.value)
    partial = info.value.partial
    # what succeeded kept the floor; the last two samples' rates are estimated across the end of
    # a motion that stops there (no step follows the failing one), so they are left out
    margin, use, normal = _floor_along(robot, partial.t, partial.q, 0.1, slice(None, -2))
    assert use <= 1.0 and normal > 0.0 and margin > 0.0


def test_the_zmp_and_support_rows_are_the_floor_of_the_step():
    """At a random step, the rows' values are the zero-moment point's distance to each polygon
    edge (less the margin) times the normal force, and the compliant normal forces, as the
    trajectory analysis finds them for that step's motion (velocity terms at x_prev)."""
    robot = mobmanip.load_robot("tiago_dual")
    rng = np.random.default_rng(3)
    q = robot.hold_configuration()
    task = get_task(robot.spec.default_task)
    x_prev, x, h = rng.normal(scale=0.3, size=robot.nx), rng.normal(scale=0.3, size=robot.nx), 0.02
    floor = CarryFloor(mu=0.5, zmp_margin=0.03, reserve=0.1)
    G, g, labels = floor_rows(robot, q, x_prev, h, task, None, floor)
    values = G @ np.r_[x, 0.0] - g
    xdot = (x - x_prev) / h
    motion = Trajectory(np.array([0.0]), q[None], x_prev[None], xdot[None], np.zeros(1))
    terms = mobmanip.motion.motion_terms(robot, q, x_prev, task)
    ground = ground_along(robot, motion, terms.object_acceleration(xdot)[None], task.name)
    traction = traction_along(ground, motion, 0.5)
    zmp_rows = [k for k, label in enumerate(labels) if label.startswith("the zero-moment point")]
    # max over edges of (n.zmp - n.p + margin) = margin - stability margin
    assert values[zmp_rows].max() / ground.normal[0] == pytest.approx(0.03 - ground.margin[0], abs=1e-9)
    support_rows = [k for k, label in enumerate(labels) if label.startswith("support ")]
    least = 0.1 * (pin.computeTotalMass(robot.model) + robot.spec.object_mass) * 9.81 / len(support_rows)
    np.testing.assert_allclose(-values[support_rows] + least, traction.normal[0], atol=1e-9 * ground.normal[0])


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "mobmanip", *args], capture_output=True, text=True)


def test_carry_ground_from_the_command_line_checked_by_trajectory_ground(tmp_path):
    path = read_path(EXAMPLES / "carry_line.csv")
    fast = tmp_path / "fast.csv"
    fast.write_text("t,x,y\n" + "".join(f"{t!r},{x!r},{y!r}\n" for t, (x, y) in zip((path.t / 3).tolist(),
                                                                                       path.xy.tolist())))  # fmt: skip
    out = tmp_path / "out"
    run = _cli("carry", "planar_dual_arm", "--path", str(fast), "--prepare", "0", "--mu", "0.2", "--fastest",
               "--out", str(out))  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert json.loads((out / "carry.json").read_text())["floor"]["zmp_margin"] == 0.02
    # --fastest: the same path at its fastest timing on the same floor, a trajectory file
    fastest = json.loads((out / "fastest.json").read_text())
    assert fastest["floor"] == {"mu": 0.2, "zmp_margin": 0.02, "reserve": 0.0, "load": "compliant"}
    assert f"on the same floor: {fastest['duration']:.4g} s" in run.stdout
    retimed = read_trajectory(load_robot("planar_dual_arm"), out / "fastest.csv")
    assert retimed.t[-1] - retimed.t[0] == pytest.approx(fastest["duration"], rel=1e-12)
    check = _cli("trajectory", "planar_dual_arm", str(out / "trajectory.csv"), "--mu", "0.2", "--out",
                 str(tmp_path / "check"))  # fmt: skip
    assert check.returncode == 0, check.stderr
    doc = json.loads((tmp_path / "check" / "analysis.json").read_text())
    assert doc["traction"]["max_traction_use"] <= 1.0 and doc["min_stability_margin"] > 0.0
    # the carry keeps its floor at its own speed: the floor's time-scaling margin is above 1
    floor_k = doc["floor_time_scaling"]["k_max"]
    assert floor_k > 1.0 and f"time-scaling margin on the floor {floor_k:.6g}" in check.stdout
    assert "slips" not in check.stderr and "unloads" not in check.stderr
    for bad, message in ((("--zmp-margin", "-1"), "--zmp-margin must be a distance >= 0 m"),
                         (("--ground", "--load", "any"), "carry's floor shares the load"),
                         (("--level",), "carry keeps the object as its task holds it: --level")):  # fmt: skip
        run = _cli("carry", "planar_dual_arm", "--path", str(fast), *bad)
        lines = run.stderr.strip().splitlines()
        assert run.returncode == 2 and len(lines) == 1 and lines[0].startswith(f"mobmanip: error: {message}")


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual"])
def test_a_zmp_margin_the_support_polygon_cannot_give_is_refused_up_front(name):
    """No point of the support polygon is farther from its edges than the largest circle inside it
    (its radius found here on a 1 mm grid, independently of the LP): a margin beyond it is one
    clear error naming the margin, the largest possible one and the contacts, not a QP that fails
    at step 0 saying that slowing down likely helps."""
    from mobmanip.errors import ArgumentError
    from mobmanip.robot.support import deepest_margin, polygon_margin

    robot = mobmanip.load_robot(name)
    support, _, _ = CarryFloor().resolve(robot)
    polygon = support.polygon((0.0, 0.0, 0.0))
    lo, hi = polygon.min(axis=0), polygon.max(axis=0)
    grid = np.stack(np.meshgrid(*(np.arange(a, b, 1e-3) for a, b in zip(lo, hi))), axis=-1).reshape(-1, 2)
    edges = np.roll(polygon, -1, axis=0) - polygon
    normals = np.c_[edges[:, 1], -edges[:, 0]] / np.linalg.norm(edges, axis=1)[:, None]  # outward (ccw)
    margins = np.min(np.einsum("ij,ij->i", normals, polygon) - grid @ normals.T, axis=1)
    best = float(margins.max())
    assert best == pytest.approx(polygon_margin(polygon, grid[np.argmax(margins)]), abs=1e-12)
    deepest = deepest_margin(polygon)
    assert best <= deepest + 1e-12 and deepest - best < 1e-3
    CarryFloor(zmp_margin=0.99 * deepest).resolve(robot)
    with pytest.raises(ArgumentError, match=rf"margin {1.01 * deepest:g} m is more than {name}'s support polygon"):
        CarryFloor(zmp_margin=1.01 * deepest).resolve(robot)


def test_the_floor_time_scaling_margin_is_where_the_floor_readings_break():
    """The paper robot's grounded carry (mu 0.2): the floor's time-scaling margin k, found from
    the floor's wrench at the motion's own speed and at rest, is where the readings of the motion
    replayed faster break: at 0.99 k every sample keeps the zero-moment point inside, every
    support loaded and every wheel's traction use at most 1; at 1.05 k some sample does not."""
    from mobmanip.motion.traction import floor_time_scaling

    robot = mobmanip.load_robot("planar_dual_arm")
    path = read_path(EXAMPLES / "carry_line.csv")
    grounded = carry(robot, ObjectPath(path.t / 3.0, path.xy), prepare=0.0, floor=CarryFloor(mu=0.2))
    motion = trajectory_from_samples(robot, grounded.motion.t, grounded.motion.q)
    analysis = analyze_trajectory(robot, motion)
    ground = ground_along(robot, motion, analysis.object_acceleration, analysis.task)
    scaling = floor_time_scaling(robot, motion, ground, 0.2)
    k = scaling.k_max
    assert k is not None and 1.0 < k < 10.0, scaling

    def readings(factor):
        fast = motion.scaled(factor)
        result = analyze_trajectory(robot, fast)
        along = ground_along(robot, fast, result.object_acceleration, result.task)
        traction = traction_along(along, fast, 0.2)
        return float(along.margin.min()), float(traction.use.max()), float(traction.normal.min())

    margin, use, normal = readings(0.99 * k)
    assert margin > 0.0 and use <= 1.0 and normal > 0.0
    margin, use, normal = readings(1.05 * k)
    assert margin < 0.0 or use > 1.0 or normal <= 0.0
