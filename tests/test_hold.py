"""How long a grounded capacity holds (mobmanip.motion.hold): the replay of constant efforts in
mobmanip's own model, checked by properties here and against MuJoCo in tests/test_floor_physics.py.

- at rest the replay's accelerations are the ones the grounded polytope's linear program found
  for the same efforts (a linear solve of the closed chain against an LP over the set's rows);
- efforts that hold the object still keep the robot still and every contact as it was;
- the hands stay welded to the object (their distance and relative orientation do not drift);
- halving the integration step moves the predicted hold time by at most a step;
- the held reach is where the replay stops holding: it holds there, and a little beyond it does not.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.errors import ArgumentError, SpecError, TaskError
from mobmanip.motion.hold import forward_accelerations, held_reach, replay
from mobmanip.motion.in_motion import motion_terms
from mobmanip.postures.named import named_configuration
from mobmanip.terms.constraints.floor import Floor

MASS = 2.0
MU = 0.5


def _tiago():
    robot = mobmanip.load_robot("tiago_dual")
    return robot, named_configuration(robot, "hold"), "spatial"


def _paper(angle=0.0):
    robot = mobmanip.load_robot("planar_dual_arm")
    return robot, configuration_at(robot, optimal_posture(robot), angle), "planar"


def _grounded(robot, q, task):
    return mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(Floor(mu=MU),)
    ).measures["dynamic_polytope"]


@pytest.mark.parametrize("case", [_tiago, _paper])
def test_the_closed_chain_solve_gives_the_lps_accelerations(case):
    robot, q, task = case()
    polytope = _grounded(robot, q, task)
    terms = motion_terms(robot, q, np.zeros(robot.nx), task, object_mass=MASS)
    for k in range(polytope.dim):
        for sign in (1.0, -1.0):
            e = sign * np.eye(polytope.dim)[k]
            point = 0.9 * polytope.straight_line_reach(e) * e
            witness = polytope.witness_at(point, least="xdot")
            xdot, _, a_o = forward_accelerations(terms, witness.variables["tau"])
            scale = max(1.0, float(np.abs(witness.variables["xdot"]).max()))
            assert np.abs(xdot - witness.variables["xdot"]).max() <= 1e-9 * scale
            assert np.abs(a_o - point).max() <= 1e-9 * max(1.0, float(np.abs(point).max()))


def test_efforts_that_hold_the_object_still_keep_everything_still():
    robot, q, task = _tiago()
    terms = motion_terms(robot, q, np.zeros(robot.nx), task, object_mass=MASS)
    hold = replay(robot, q, terms.static_torques(), task, object_mass=MASS, floor=Floor(mu=MU), duration=0.05)
    assert hold.holds and hold.held == 0.05
    assert np.abs(hold.object_acceleration).max() <= 1e-9
    assert np.abs(hold.q - q).max() <= 1e-12
    assert np.abs(hold.normal - hold.normal[0]).max() <= 1e-9 * hold.normal[0].sum()
    assert (hold.normal > 0).all()
    # the normal forces at rest balance the robot and the object
    weight = (float(pin.computeTotalMass(robot.model)) + MASS) * 9.81
    assert abs(hold.normal[0].sum() - weight) <= 1e-3 * weight


def _hands(robot, q):
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return [robot.data.oMf[arm.frame_id].copy() for arm in robot.arms]


def test_the_hands_stay_welded_to_the_object():
    """The closed chain is held at the acceleration level; what drifts is the integrator's error
    (semi-implicit Euler, first order): it halves with the step, so the limit keeps the weld."""
    robot, q, task = _tiago()
    polytope = _grounded(robot, q, task)
    e = -np.eye(6)[0]
    tau = polytope.witness_at(0.9 * polytope.straight_line_reach(e) * e, least="xdot").variables["tau"]
    drift = []
    for step in (2.5e-4, 1.25e-4):
        hold = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU), step=step, stop=False)
        first, last = _hands(robot, hold.q[0]), _hands(robot, hold.q[-1])
        assert np.linalg.norm(last[0].translation - first[0].translation) > 3e-3  # the hands did move ...
        relative0, relative = first[0].inverse() * first[1], last[0].inverse() * last[1]
        drift.append(np.linalg.norm(pin.log6(relative0.inverse() * relative).vector))  # ... together
    assert drift[0] <= 1e-4  # rad and m, after 20 ms
    assert 1.8 <= drift[0] / drift[1] <= 2.2


@pytest.mark.parametrize("axis", [0, 1])
def test_halving_the_step_moves_the_hold_time_by_at_most_a_step(axis):
    robot, q, task = _tiago()
    polytope = _grounded(robot, q, task)
    e = -np.eye(6)[axis]
    tau = polytope.witness_at(0.97 * polytope.straight_line_reach(e) * e, least="xdot").variables["tau"]
    coarse = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU), step=2.5e-4)
    fine = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU), step=1.25e-4)
    assert not coarse.holds and not fine.holds
    assert coarse.binds.split(" ")[0] == fine.binds.split(" ")[0]
    assert abs(coarse.held - fine.held) <= 2.5e-4


@pytest.mark.parametrize("axis", [0, 2])
def test_the_held_reach_holds_and_a_little_more_does_not(axis):
    robot, q, task = _tiago()
    polytope = _grounded(robot, q, task)
    e = -np.eye(6)[axis] if axis == 0 else np.eye(6)[axis]
    found = held_reach(robot, q, polytope, e, task, object_mass=MASS, floor=Floor(mu=MU), duration=0.02)
    assert not found.instant_hold.holds  # these axes need it: the instantaneous maximum gives way
    assert 0.0 < found.reach < 0.97 * found.instant
    assert found.hold.holds and found.hold.held == 0.02
    replayed = replay(robot, q, found.witness.variables["tau"], task, object_mass=MASS, floor=Floor(mu=MU))
    assert replayed.holds
    beyond = polytope.witness_at((found.reach + 0.01 * found.instant) * e, least="xdot")
    assert not replay(robot, q, beyond.variables["tau"], task, object_mass=MASS, floor=Floor(mu=MU)).holds


def test_bad_replays_say_what_is_wrong():
    robot, q, task = _tiago()
    tau = np.zeros(robot.nx)
    with pytest.raises(ArgumentError, match="duration must be a positive number"):
        replay(robot, q, tau, task, duration=-1.0)
    with pytest.raises(ArgumentError, match="step must be a positive number"):
        replay(robot, q, tau, task, step=float("nan"))
    with pytest.raises(ArgumentError, match=f"tau must be {robot.nx} finite efforts"):
        replay(robot, q, tau[:-1], task)
    with pytest.raises(TaskError, match="needs a friction coefficient"):
        replay(robot, q, tau, task, floor=Floor(mu=None))
    omni = mobmanip.load_robot("planar_dual_arm_omni")
    with pytest.raises(SpecError, match="covers differential-drive platforms; 'planar_dual_arm_omni'"):
        replay(omni, named_configuration(omni, "home"), np.zeros(omni.nx), "planar")
    polytope = _grounded(robot, q, task)
    with pytest.raises(TaskError, match="nonzero finite 6-vector"):
        held_reach(robot, q, polytope, np.zeros(6), task)


@pytest.mark.parametrize("task", ["planar", "translational"])
def test_a_task_that_leaves_rows_out_holds_the_object_level_as_the_floor_does(task):
    """A planar or translational task on a spatial robot: the floor constraint keeps the object
    level (the hands' level rows); the replay's closed chain does the same, so at t = 0 it gives
    the object the acceleration the LP found for the same efforts."""
    robot, q, _ = _tiago()
    polytope = _grounded(robot, q, task)
    for k in range(polytope.dim):
        e = np.eye(polytope.dim)[k]
        point = 0.9 * polytope.straight_line_reach(e) * e
        tau = polytope.witness_at(point, least="xdot").variables["tau"]
        hold = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU), duration=1e-3, stop=False)
        assert np.abs(hold.object_acceleration[0] - point).max() <= 1e-9 * np.abs(point).max()


def test_a_reserve_ends_the_hold_where_a_support_reaches_it():
    """With a reserve r every support must keep r of its equal share of the weight: the replay of
    the same efforts gives way earlier, at the sample where the first normal force crosses it."""
    robot, q, task = _tiago()
    polytope = _grounded(robot, q, task)
    e = -np.eye(6)[0]
    tau = polytope.witness_at(0.9 * polytope.straight_line_reach(e) * e, least="xdot").variables["tau"]
    plain = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU), stop=False)
    weight = (float(pin.computeTotalMass(robot.model)) + MASS) * 9.81
    n = plain.normal.shape[1]
    reserve = 0.5 * plain.normal[0].min() * n / weight  # half the least-loaded support's start
    share = reserve * weight / n
    first = int(np.flatnonzero((plain.normal <= share).any(axis=1))[0])
    reserved = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU, reserve=reserve))
    assert "unloads to its reserve" in reserved.binds
    assert reserved.held == pytest.approx(plain.time[first - 1]) and 0.0 < reserved.held < plain.held
