"""Placement that maximises a polytope's reading on the floor (mobmanip.placement.grounded): the
found placement holds the object (forward kinematics), its grounded straight-line reach is at
least that of the ungrounded optimum's placement read on the floor, and no worse than a coarse
grid of placements built here with their own inverse kinematics; the command's bad requests."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import least_squares

import mobmanip
from mobmanip.placement.grounded import place_polytope
from mobmanip.terms.constraints.floor import Floor

TARGET = np.array([1.0, 0.5, 0.35])
MASS = 2.0


def _grounded_reach(robot, q):
    analysis = mobmanip.analyze(robot, q, "planar", object_mass=MASS, constraints=(Floor(mu=0.5),),
                                measures=("dynamic_polytope",))  # fmt: skip
    polytope = analysis.measure("dynamic_polytope")
    return 0.0 if polytope.empty else polytope.straight_line_reach([1.0, 0.0])


def _tips(robot, q):
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    return np.array([data.oMf[arm.frame_id].translation for arm in robot.arms])


def _grid(robot):
    """Platform at distance r from the object's vertical, the object at bearing alpha in the
    platform's frame, the platform at heading theta; each arm's three joints put its tip over
    the object by scipy's least squares from an elbow-left or elbow-right seed (mirrored for the
    other arm). Yields the configurations whose tips are over the object to 1e-9 m."""
    model = robot.model
    idx = [[model.joints[model.getJointId(n)].idx_q for n in arm.joint_names] for arm in robot.arms]
    for r in (0.6, 0.9, 1.2):
        for alpha in np.radians([0.0, 90.0, 180.0, 270.0]):
            for theta in np.radians(np.arange(0.0, 360.0, 45.0)):
                bearing = theta + alpha
                q = robot.neutral()
                q[:4] = (TARGET[0] - r * math.cos(bearing), TARGET[1] - r * math.sin(bearing),
                         math.cos(theta), math.sin(theta))  # fmt: skip
                for elbow in (1.0, -1.0):
                    for k, arm_idx in enumerate(idx):
                        side = elbow if k == 0 else -elbow
                        seed = np.array([alpha - side * 0.6, side * 1.2, side * 0.2])

                        def error(joints, arm_idx=arm_idx, k=k, base=q):
                            trial = base.copy()
                            trial[arm_idx] = joints
                            return _tips(robot, trial)[k, :2] - TARGET[:2]

                        q[arm_idx] = least_squares(error, seed, xtol=1e-14, ftol=1e-14, gtol=1e-14).x
                    q_arms = q.copy()
                    for arm_idx in idx:  # joint angles into the limits' (-pi, pi]
                        q_arms[arm_idx] = np.remainder(q_arms[arm_idx] + math.pi, 2.0 * math.pi) - math.pi
                    if np.abs(_tips(robot, q_arms)[:, :2] - TARGET[:2]).max() < 1e-9:
                        yield q_arms


def test_the_grounded_placement_beats_the_ungrounded_optimum_and_a_grid():
    robot = mobmanip.load_robot("planar_dual_arm")
    result = place_polytope(robot, TARGET, "dynamic_polytope:reach:+x", "planar", constraints=(Floor(mu=0.5),),
                            object_mass=MASS, starts=4, budget=150)  # fmt: skip
    # it holds the object: both tips over the target (the hold's heights are the arms' own)
    tips = _tips(robot, result.q)
    np.testing.assert_allclose(tips[:, :2], np.tile(TARGET[:2], (2, 1)), atol=1e-6)
    assert tips[:, 2].mean() == pytest.approx(TARGET[2], abs=1e-6)
    # its value is the grounded reach there, at least the ungrounded optimum's on the floor
    found = _grounded_reach(robot, result.q)
    assert result.value == pytest.approx(found, rel=1e-9)
    ungrounded = _grounded_reach(robot, result.ungrounded.q)
    assert result.ungrounded_value == pytest.approx(ungrounded, rel=1e-9)
    assert found >= ungrounded
    assert result.evaluations <= 150
    # and no worse than a coarse grid of placements
    values = [_grounded_reach(robot, q) for q in _grid(robot)]
    assert len(values) >= 100
    assert found >= max(values)


def test_the_search_climbs_to_a_known_maximum(monkeypatch):
    """The derivative-free stage maximises: with the polytope's reading replaced by one written
    here whose maximum is known (10 minus the squared distance of the platform from (1.0, -0.4),
    a position from which the hands hold the object), the search ends at that maximum to 1e-4,
    well above every seed (the ungrounded optimum reads about 9.14 there). Whatever the best seed,
    a search that runs downhill stays at it."""
    from mobmanip.placement import grounded

    aim = np.array([1.0, -0.4])

    def reading(robot, q, *args, **kwargs):
        return 10.0 - float(np.sum((np.asarray(q[:2]) - aim) ** 2))

    monkeypatch.setattr(grounded, "polytope_value", reading)
    robot = mobmanip.load_robot("planar_dual_arm")
    result = place_polytope(robot, TARGET, "dynamic_polytope:reach:+x", "planar", object_mass=MASS, starts=4,
                            budget=1000)  # fmt: skip
    assert result.ungrounded_value < 9.5
    assert result.value == pytest.approx(reading(robot, result.q), abs=1e-12)
    assert result.value == pytest.approx(10.0, abs=1e-4)
    np.testing.assert_allclose(_tips(robot, result.q)[:, :2], np.tile(TARGET[:2], (2, 1)), atol=1e-6)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "mobmanip", *args], capture_output=True, text=True)


@pytest.mark.parametrize(
    "args, message",
    [
        (("--objective", "dynamic:capacity:+x", "--mu", "0.5"), "--ground needs a measure's reading"),
        (("--objective", "dynamic_polytope:widest:+x"), "the reading must be one of reach, support"),
        (("--objective", "dynamic_polytope:reach:+x", "--budget", "0"), "--budget must be at least 1"),
        (
            ("--objective", "dynamic_polytope:reach:+q"),
            "direction '+q' is neither a signed axis of the planar task (+x, -x, +y, -y) nor 2 numbers like 1,0",
        ),
        (
            ("--objective", "dynamic_polytope:reach:+x", "--figure", "f.png"),
            "--figure is not available with a measure's reading",
        ),
    ],
)
def test_bad_polytope_placements_are_one_line_errors(args, message):
    run = _cli("place", "planar_dual_arm", "--object", "1,0.5,0.35", *args)
    assert run.returncode == 2
    lines = [line for line in run.stderr.splitlines() if line.startswith("mobmanip: error:")]
    assert len(lines) == 1 and message in lines[0], run.stderr
