"""How long a grounded capacity holds (mobmanip.motion.hold): the replay of constant efforts in
mobmanip's own model, checked by properties here and against MuJoCo in tests/test_floor_physics.py.

- at rest the replay's accelerations are the ones the grounded polytope's linear program found
  for the same efforts (a linear solve of the closed chain against an LP over the set's rows);
- efforts that hold the object still keep the robot still and every contact as it was;
- the hands stay welded to the object (their distance and relative orientation do not drift);
- halving the integration step moves the predicted hold time by at most a step;
- the contact forces as affine maps of the efforts (the held reach's program) are the replay's own;
- the held reach holds, reaches its point at t = 0, is where its own linearised program stops,
  and is at least the reach of the calm efforts.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.errors import ArgumentError, SpecError, TaskError
from mobmanip.motion.ground import floor_wrench
from mobmanip.motion.hold import contact_maps, forward_accelerations, held_reach, replay
from mobmanip.motion.in_motion import motion_terms
from mobmanip.motion.traction import contact_forces
from mobmanip.postures.named import named_configuration
from mobmanip.robot.tasks import TaskSpace, get_task
from mobmanip.terms.constraints.floor import LEVEL_ROWS, Floor

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


def _one_step(robot, q, x, tau, task, support):
    """The replay's contact forces at one state, step by step as :func:`replay` computes them
    (the closed chain's solve; the floor's wrench: the robot's own, and each hand's wrench on the
    object at the hand; the compliant sharing, the least-use split)."""
    rows = tuple(sorted(set(get_task(task).rows) | set(LEVEL_ROWS)))
    labels = get_task("spatial").labels
    welded = TaskSpace("welded", rows, tuple(labels[r] for r in rows))
    terms = motion_terms(robot, q, x, welded, object_mass=MASS)
    xdot, h, _ = forward_accelerations(terms, tau)
    offset, linear = floor_wrench(robot, q, x, 0.0, np.zeros(6), np.zeros((6, robot.nx)))
    wrench = offset + linear @ xdot
    for hand, placement in zip(h.reshape(len(robot.arms), len(rows)), _hands(robot, q)):
        f = np.zeros(6)
        f[list(rows)] = hand
        wrench += np.r_[f[:3], np.cross(placement.translation, f[:3]) + f[3:]]
    z = support.floor_z
    zmp = np.array([(z * wrench[0] - wrench[4]) / wrench[2], (wrench[3] + z * wrench[1]) / wrench[2]])
    pose = (float(q[0]), float(q[1]), np.arctan2(q[3], q[2]))
    driven = np.array([c.driven for c in support.contacts])
    return contact_forces(support.world_points(pose), driven, wrench[:3], wrench[3:], zmp, MU), welded


@pytest.mark.parametrize("case", [_tiago, _paper])
def test_the_contact_maps_are_the_replays_contact_forces(case):
    """At a state of a replay, :func:`contact_maps` assembles the contact forces as affine
    functions of the efforts; the replay's own step computes them for one tau. Equal for efforts
    other than the ones that made the state; the tangential forces too (the compliant floor leaves
    the wheels no split: each tyre of the axle carries half of its lateral force)."""
    robot, q, task = case()
    polytope = _grounded(robot, q, task)
    support = Floor(mu=MU).resolve(robot)[0]
    e = np.eye(polytope.dim)[0]
    tau = polytope.witness_at(0.9 * polytope.straight_line_reach(e) * e, least="xdot").variables["tau"]
    hold = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU), stop=False)
    rng = np.random.default_rng(5)
    for k in (0, 40, 80):
        other = polytope.witness_at(rng.uniform(-0.5, 0.5) * polytope.straight_line_reach(e) * e).variables["tau"]
        for effort in (tau, other):
            (normal, tangential, use), welded = _one_step(robot, hold.q[k], hold.velocity[k], effort, task, support)
            maps = contact_maps(robot, hold.q[k], hold.velocity[k], welded, MASS, support)
            N, n0 = maps.normal
            assert np.abs(N @ effort + n0 - normal).max() <= 1e-9 * np.abs(normal).sum()
            T, t0 = maps.tangential
            assert maps.split.shape[1] == 0
            np.testing.assert_allclose((T @ effort + t0).reshape(-1, 2), tangential, rtol=1e-9, atol=1e-9)


def _calm_reach(robot, q, task, polytope, e, tolerance=0.005):
    """The largest reach (by bisection) whose calm efforts hold for 20 ms: the first answer."""
    instant = polytope.straight_line_reach(e)
    low, high = 0.0, instant
    while high - low > tolerance * instant:
        middle = 0.5 * (low + high)
        tau = polytope.witness_at(middle * e, least="xdot").variables["tau"]
        held = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU)).holds
        low, high = (middle, high) if held else (low, middle)
    return low


@pytest.mark.parametrize("axis", [0, 5])
def test_the_held_reach_holds_and_beats_the_calm_efforts(axis):
    """The held reach's efforts reach it at t = 0 (the closed chain's solve, not the LP, gives the
    object's acceleration), the replay holds them for 20 ms, the linearised program around the
    last round's replay allows about the tolerance more, and the reach is at least the calm efforts' (for
    TIAGo++ -x, 22.5 against 12.5 m/s^2: the calm efforts swing the arms the most)."""
    robot, q, task = _tiago()
    polytope = _grounded(robot, q, task)
    e = -np.eye(6)[axis] if axis == 0 else np.eye(6)[axis]
    found = held_reach(robot, q, polytope, e, task, object_mass=MASS, floor=Floor(mu=MU), duration=0.02)
    assert not found.instant_hold.holds  # these axes need it: 97 % of the maximum gives way
    assert 0.0 < found.reach < found.instant
    tau = found.witness.variables["tau"]
    terms = motion_terms(robot, q, np.zeros(robot.nx), task, object_mass=MASS)
    _, _, a_o = forward_accelerations(terms, tau)
    assert np.abs(a_o - found.reach * e).max() <= 1e-8 * found.reach
    assert polytope.contains(found.reach * e)
    replayed = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU))
    assert replayed.holds and found.hold.holds and found.hold.held == 0.02
    assert abs(found.bound - found.reach) <= 1.1 * 0.005 * found.instant  # the rounds settled
    calm = _calm_reach(robot, q, task, polytope, e)
    assert found.reach >= calm
    if axis == 0:
        assert found.reach >= 1.5 * calm
    # at 97 % of the maximum: the efforts that hold it longest reach it and hold longer than the calm ones
    top = 0.97 * found.instant
    _, _, a_o = forward_accelerations(terms, found.instant_witness.variables["tau"])
    assert np.abs(a_o - top * e).max() <= 1e-8 * top
    calm_tau = polytope.witness_at(top * e, least="xdot").variables["tau"]
    calm_hold = replay(robot, q, calm_tau, task, object_mass=MASS, floor=Floor(mu=MU))
    assert found.instant_hold.held > calm_hold.held
    again = replay(robot, q, found.instant_witness.variables["tau"], task, object_mass=MASS, floor=Floor(mu=MU))
    assert again.held == found.instant_hold.held


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
    with pytest.raises(ArgumentError, match="iterations must be a positive integer, got 0"):
        held_reach(robot, q, polytope, np.eye(6)[0], task, iterations=0)
    # the program's seam: the polytope's rows, read-only, and the witness of a solution of them
    rows = polytope.lifted_rows()
    with pytest.raises(ValueError):
        rows.A_ub[0, 0] = 1.0
    witness = polytope.witness_at(np.zeros(6))
    z = np.zeros(len(rows.lower))
    for name, where in polytope.variables.items():
        z[where] = witness.variables[name]
    assert np.array_equal(polytope.witness_of(z).variables["tau"], witness.variables["tau"])
    with pytest.raises(TaskError, match="lifted rows has"):
        polytope.witness_of(z[:-1])
    z[np.arange(len(z))[polytope.variables["tau"]][0]] += 1.0
    with pytest.raises(TaskError, match="not a solution of the lifted rows"):
        polytope.witness_of(z)


@pytest.mark.parametrize("task", ["planar", "translational"])
def test_a_task_that_leaves_rows_out_holds_the_object_as_the_floor_does(task):
    """A planar or translational task on a spatial robot: the floor constraint holds the object in
    the task's rows only (level only when asked); the replay's closed chain does the same, so at
    t = 0 it gives the object the acceleration the LP found for the same efforts."""
    robot, q, _ = _tiago()
    polytope = _grounded(robot, q, task)
    for k in range(polytope.dim):
        e = np.eye(polytope.dim)[k]
        point = 0.9 * polytope.straight_line_reach(e) * e
        tau = polytope.witness_at(point, least="xdot").variables["tau"]
        hold = replay(robot, q, tau, task, object_mass=MASS, floor=Floor(mu=MU), duration=1e-3, stop=False)
        assert np.abs(hold.object_acceleration[0] - point).max() <= 1e-9 * np.abs(point).max()


def _lp_normals(polytope, witness) -> np.ndarray:
    """Every contact's normal force in the LP's solution (the last column of its force)."""
    forces = witness.variables["contact_forces"]
    return np.array([forces[c["columns"][1] - 1] for c in polytope.model["floor"]["contacts"]])


def _stretch():
    robot = mobmanip.load_robot("stretch")  # the vendor's file: a prismatic lift, frames turned
    return robot, named_configuration(robot, "home"), "translational"


@pytest.mark.parametrize(
    ("case", "task", "level"),
    [(_paper, "planar", False), (_paper, "planar", True), (_tiago, "spatial", False),
     (_tiago, "translational", False), (_tiago, "planar", False), (_stretch, "translational", False)],
    ids=["paper-planar", "paper-planar-level", "tiago-spatial", "tiago-translational", "tiago-planar",
         "stretch-translational"],
)  # fmt: skip
def test_at_rest_the_replay_loads_the_contacts_as_the_lp_does(case, task, level):
    """At t = 0 the replay's normal forces are the LP's for the same efforts, along every axis at
    90 % of its reach. A task that leaves out the object's vertical force (planar, not held
    level) leaves its weight and tipping moments to whatever else bears them, and the floor
    carries what the hands apply to the object at their own points: a squeeze between hands at
    different heights (the paper's arms hold at 0.3 and 0.4 m) tips the robot. The replay used to
    put the whole object, weight included, at the hands' midpoint: 1.6-3 % of the weight apart,
    and the paper robot's +x at 97 % (object at 90 deg) then 'gave way after 0 ms', a caster at -27.5 N.

    Independently, the normal forces add up to the weight the floor carries plus the rate of the
    vertical momentum, from Pinocchio's centroidal map at rest (A_G S xdot) and the object's own
    m a_z: the robot's weight, and the object's only where the hands hold it vertically."""
    robot, q, _ = case()
    carried = level or 2 in get_task(task).rows
    A_G = pin.computeCentroidalMap(robot.model, robot.model.createData(), q)[2] @ robot.null_space(q)
    floor = Floor(mu=MU, level=level)
    polytope = mobmanip.analyze(
        robot, q, task, object_mass=MASS, measures=("dynamic_polytope",), constraints=(floor,)
    ).measures["dynamic_polytope"]
    for k in range(polytope.dim):
        for sign in (1.0, -1.0):
            e = sign * np.eye(polytope.dim)[k]
            witness = polytope.witness_at(0.9 * polytope.straight_line_reach(e) * e, least="xdot")
            hold = replay(robot, q, witness.variables["tau"], task, object_mass=MASS, floor=floor, duration=5e-4,
                          stop=False)  # fmt: skip
            expected = _lp_normals(polytope, witness)
            assert np.abs(hold.normal[0] - expected).max() <= 1e-12 * expected.sum()
            a_z = float(witness.point[list(get_task(task).rows).index(2)]) if 2 in get_task(task).rows else 0.0
            weight = (float(pin.computeTotalMass(robot.model)) + (MASS if carried else 0.0)) * 9.81
            total = weight + A_G @ witness.variables["xdot"] + (MASS * a_z if carried else 0.0)
            assert hold.normal[0].sum() == pytest.approx(total, rel=1e-9)


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
