"""The task on the floor is the user's (issue 35, items 1 and 3).

The floor adds contacts, not rows of the task: a translational task's hands apply forces and no
moments on the floor as off it, and holding the object level is a requirement the user names
(``Floor(level=True)``). Checked against the independent whole-robot LP (tests/floor_reference.py,
built from the free-flyer Pinocchio model and the contacts alone), with and without its own level
rows, and by the invariants every floor model keeps, on every wheeled robot this project ships
and every task it analyses:

- contacts allowed to pull and no traction limit give back the ideal set;
- the set on the floor lies inside the ideal one;
- the results are continuous in the model's data (1e-6 perturbations of joint axes and origins
  move every reach by its own order, not by half of it);
- moving and turning the whole robot in the world moves and turns its sets, nothing else.

Stretch's file writes pi/2 as 1.5708: its wrist-yaw axis tilts by 4e-6 rad. An equation "the hand
does not roll or pitch" froze that joint on the floor only and halved grounded reaches (+x support
23.10 against the ideal 24.06 m/s^2 with every contact free to pull).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import floor_reference as fr
import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.postures.named import named_configuration
from mobmanip.robot.support import robot_support
from mobmanip.terms.constraints.floor import Floor

REL = 1e-6  # the agreement asked of two exact computations of one reach (issue 35)


def _axes(m: int) -> list[np.ndarray]:
    return [s * e for e in np.eye(m) for s in (1.0, -1.0)]


def _reach_tol(a: float, b: float) -> float:
    return REL * max(abs(a), abs(b), 1.0)


def _grounded(robot, q, task, mass, floor):
    return mobmanip.analyze(
        robot, q, task, object_mass=mass, measures=("dynamic_polytope",), constraints=(floor,) if floor else ()
    )


def _casters(robot) -> tuple:
    """The passive supports where the robot's spec puts them: where the contacts are is the one
    input the reference shares with mobmanip (everything it computes, it computes itself)."""
    return tuple(
        fr.SupportPoint(c.name, "root_joint", np.asarray(c.point, dtype=float), False)
        for c in robot_support(robot).contacts
        if not c.driven
    )


@pytest.fixture(scope="module")
def stretch():
    robot = mobmanip.load_robot("stretch")
    q = named_configuration(robot, "home")
    ideal = _grounded(robot, q, "translational", 0.5, None)
    return robot, q, ideal


# (floor, reference mode, reference options): --no-traction, --mu 1.0, --mu 0.5 --load any
STRETCH_FLOORS = {
    "no traction": (Floor(mu=None), "no_tip", {}),
    "mu 1.0": (Floor(mu=1.0), "friction", {"mu": 1.0, "springs": True}),
    "mu 0.5, any": (Floor(mu=0.5, load="any"), "friction", {"mu": 0.5}),
}


@pytest.mark.parametrize("level", [False, True], ids=["task", "held level"])
@pytest.mark.parametrize("floor", list(STRETCH_FLOORS))
def test_stretch_on_the_floor_is_the_independent_lp(stretch, floor, level):
    """Stretch at home holding 0.5 kg (translational): every reach along the task axes equals the
    whole-robot LP's, without level rows and, when asked, with them."""
    robot, q, ideal = stretch
    chosen, mode, options = STRETCH_FLOORS[floor]
    if level:
        chosen = Floor(mu=chosen.mu, load=chosen.load, level=True)
    grounded = _grounded(robot, q, "translational", 0.5, chosen)
    assert grounded.measures["dynamic_polytope"].model["floor"]["level"] is level
    problem = fr.build_problem(robot, q, "translational", ideal.held_object, casters=_casters(robot), level=level)
    for e in _axes(3):
        ours = grounded.measures["dynamic_polytope"].straight_line_reach(e)
        ref = fr.straight_line(problem, e, mode=mode, **options).value
        assert abs(ours - ref) <= _reach_tol(ours, ref), (floor, e, ours, ref)
        ours = grounded.measures["dynamic_polytope"].support(e)
        ref = fr.support(problem, e, mode=mode, **options).value
        assert abs(ours - ref) <= _reach_tol(ours, ref), (floor, e, ours, ref)


def test_stretch_relaxed_floor_is_its_ideal_set(stretch):
    """Every contact may pull, no traction limit: the ideal set, reading for reading (the +x
    support was 23.10 m/s^2 on the floor against 24.06 ideal)."""
    robot, q, ideal = stretch
    relaxed = _grounded(robot, q, "translational", 0.5, Floor(lift=True)).measures["dynamic_polytope"]
    free = ideal.measures["dynamic_polytope"]
    for e in _axes(3):
        for reading in ("support", "straight_line_reach"):
            a, b = getattr(relaxed, reading)(e), getattr(free, reading)(e)
            assert abs(a - b) <= _reach_tol(a, b), (reading, e, a, b)
    assert relaxed.support(np.array([1.0, 0.0, 0.0])) > 24.0


def test_holding_level_is_asked_for_and_binds_where_the_wrist_tilts():
    """TIAGo++ holding 2 kg (translational task): held level, the hands may not roll or pitch
    beyond the band, which its arms' tilted wrists feel: the reaches change and equal the LP's
    with level rows; not asked, they equal the LP's without them."""
    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    free = _grounded(robot, q, "translational", 2.0, None)
    plain = _grounded(robot, q, "translational", 2.0, Floor(mu=None)).measures["dynamic_polytope"]
    level = _grounded(robot, q, "translational", 2.0, Floor(mu=None, level=True)).measures["dynamic_polytope"]
    problems = {
        flag: fr.build_problem(robot, q, "translational", free.held_object, level=flag) for flag in (False, True)
    }
    changed = 0.0
    for e in _axes(3):
        for flag, polytope in ((False, plain), (True, level)):
            ours, ref = polytope.straight_line_reach(e), fr.straight_line(problems[flag], e, mode="no_tip").value
            assert abs(ours - ref) <= _reach_tol(ours, ref), (flag, e, ours, ref)
        changed = max(changed, abs(plain.straight_line_reach(e) - level.straight_line_reach(e)))
    assert changed > 0.1  # the requirement binds (m/s^2): holding level is a different question


def test_the_level_band_is_stated_and_checked():
    with pytest.raises(mobmanip.MobmanipError, match="level tolerance must be a positive number"):
        Floor(level=True, level_tolerance=0.0)
    with pytest.raises(mobmanip.MobmanipError, match="level must be True or False"):
        Floor(level="yes")
    assert "held level" in Floor(level=True).describe()["level"]
    assert "level" not in Floor().describe()


# ------------------------------------------------------------------------------------------------
# The invariants, over the wheeled robots this project ships and every task each analyses (the
# foreign skid-steer, steered and omnidirectional robots: tests/test_floor_kinds.py)


def _paper_case():
    robot = mobmanip.load_robot("planar_dual_arm")
    return robot, configuration_at(robot, optimal_posture(robot), 45.0)


def _paper_omni_case():
    """The paper's arms on the omnidirectional base, in the differential drive's posture above."""
    paper, q_paper = _paper_case()
    robot = mobmanip.load_robot("planar_dual_arm_omni")
    joints = {n: v for n, v in paper.configuration_dict(q_paper)["joints"].items() if robot.model.existJointName(n)}
    return robot, robot.configuration(platform=(0.0, 0.0, 0.0), joints=joints)


def _tiago_pro_case():
    """TIAGo Pro (skid-steer) with its arms bent in front (at home they hang straight down: a
    singular posture, where the exact set itself jumps under a 1e-8 tilt)."""
    robot = mobmanip.load_robot("tiago_pro")
    q = named_configuration(robot, "home")
    for side in ("right", "left"):
        for k, value in enumerate((0.3, 0.5, -0.4, 1.2, 0.2, 0.5, 0.1), start=1):
            q[robot.model.joints[robot.model.getJointId(f"arm_{side}_{k}_joint")].idx_q] = value
    return robot, q


def _named_case(name, posture):
    def make():
        robot = mobmanip.load_robot(name)
        return robot, named_configuration(robot, posture)

    return make


def _tiago_case():
    """TIAGo with its arm bent in front (at home it is stretched out, near a singular posture
    where even the ideal set moves by 4e-4 of itself under the perturbation below)."""
    robot = mobmanip.load_robot("tiago")
    q = named_configuration(robot, "home")
    for k, value in enumerate((0.4, 0.3, -0.5, 1.3, 0.3, 0.6, 0.2), start=1):
        q[robot.model.joints[robot.model.getJointId(f"arm_{k}_joint")].idx_q] = value
    return robot, q


#: (make the robot and its configuration, tasks, object mass kg)
ZOO = {
    "planar_dual_arm": (_paper_case, ("planar", "planar_rigid"), 2.0),
    "tiago_dual": (_named_case("tiago_dual", "hold"), ("planar", "translational", "spatial"), 2.0),
    "tiago": (_tiago_case, ("planar", "translational", "spatial"), 0.5),
    "stretch": (_named_case("stretch", "home"), ("planar", "translational"), 0.5),
    "tiago_pro": (_tiago_pro_case, ("planar",), 1.0),  # skid-steer
    "planar_dual_arm_omni": (_paper_omni_case, ("planar",), 2.0),  # mecanum wheels
}
CASES = [(name, task) for name, (_, tasks, _) in ZOO.items() for task in tasks]


@pytest.fixture(scope="module")
def zoo():
    return {name: make() for name, (make, _, _) in ZOO.items()}


def _reaches(robot, q, task, mass, floor) -> np.ndarray:
    polytope = _grounded(robot, q, task, mass, floor).measures["dynamic_polytope"]
    m = len(mobmanip.robot.tasks.get_task(task).rows)
    return np.array([[polytope.straight_line_reach(e), polytope.support(e)] for e in _axes(m)])


@pytest.mark.parametrize(("name", "task"), CASES)
def test_relaxed_floor_equals_the_ideal_set_and_the_floor_lies_inside(zoo, name, task):
    robot, q = zoo[name]
    mass = ZOO[name][2]
    ideal = _reaches(robot, q, task, mass, None)
    relaxed = _reaches(robot, q, task, mass, Floor(lift=True))
    np.testing.assert_allclose(relaxed, ideal, rtol=REL, atol=REL)
    for floor in (Floor(mu=None), Floor(mu=0.5), Floor(mu=0.5, load="any")):
        grounded = _reaches(robot, q, task, mass, floor)
        assert np.all(grounded[:, 0] <= ideal[:, 0] + REL * (1.0 + ideal[:, 0])), (floor, grounded, ideal)
        assert np.all(grounded[:, 1] <= ideal[:, 1] + REL * (1.0 + np.abs(ideal[:, 1]))), (floor, grounded, ideal)


def _turned(robot, q, x, y, yaw):
    """q with the platform at (x, y) and turned by yaw (rad) from its own heading."""
    q = q.copy()
    heading = math.atan2(q[3], q[2]) + yaw
    q[:4] = (x, y, math.cos(heading), math.sin(heading))
    return q


def _rotation(task: str, yaw: float) -> np.ndarray:
    """How a turn of the whole robot by yaw about the vertical acts on the task's rows."""
    c, s = math.cos(yaw), math.sin(yaw)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    full = np.zeros((6, 6))
    full[:3, :3] = full[3:, 3:] = Rz
    rows = list(mobmanip.robot.tasks.get_task(task).rows)
    return full[np.ix_(rows, rows)]


@pytest.mark.parametrize(("name", "task"), CASES)
def test_moving_and_turning_the_whole_robot_moves_and_turns_its_grounded_set(zoo, name, task):
    """At headings of 1 and 2.5 rad from its own and 3 m away, the set along the turned axes is
    the set along the axes (a transposed platform rotation was off by 6.5 % at 1 rad)."""
    robot, q = zoo[name]
    mass = ZOO[name][2]
    floor = Floor(mu=0.5)
    here = _grounded(robot, q, task, mass, floor).measures["dynamic_polytope"]
    for yaw in (1.0, 2.5):
        there = _grounded(robot, _turned(robot, q, 3.0, -2.0, yaw), task, mass, floor).measures["dynamic_polytope"]
        R = _rotation(task, yaw)
        for e in _axes(R.shape[0]):
            a, b = here.straight_line_reach(e), there.straight_line_reach(R @ e)
            assert abs(a - b) <= _reach_tol(a, b), (yaw, e, a, b)
            a, b = here.support(e), there.support(R @ e)
            assert abs(a - b) <= _reach_tol(a, b), (yaw, e, a, b)


def _perturbed(name: str, seed: int, size: float):
    """The robot with every joint's placement turned by ``size`` rad about a random axis and moved
    by ``size`` m (its axes tilt, its origins move), as a file that rounds its numbers would."""
    robot, q = ZOO[name][0]()
    rng = np.random.default_rng(seed)
    model = robot.model
    for j in range(2, model.njoints):
        axis = rng.normal(size=3)
        turn = pin.exp3(size * axis / np.linalg.norm(axis))
        placement = model.jointPlacements[j]
        model.jointPlacements[j] = pin.SE3(placement.rotation @ turn, placement.translation + size * rng.normal(size=3))
    return robot, q


@pytest.mark.parametrize(("name", "task"), [c for c in CASES if c[1] != "planar_rigid"])
def test_grounded_reaches_are_continuous_in_the_robot_files_numbers(zoo, name, task):
    """Perturbing every joint axis and origin by 1e-6 moves every reach by less than 1e-4 of it,
    with the object held level too (a frozen joint moved them by up to half)."""
    robot, q = zoo[name]
    mass = ZOO[name][2]
    shaken, _ = _perturbed(name, seed=3, size=1e-6)
    for floor in (Floor(mu=0.5), Floor(mu=0.5, level=True)):
        before = _reaches(robot, q, task, mass, floor)
        after = _reaches(shaken, q, task, mass, floor)
        np.testing.assert_allclose(after, before, rtol=1e-4, atol=1e-4 * np.abs(before).max())


def test_a_ramp_leans_gravity_as_written_here():
    """TIAGo++ holding 2 kg on a 5 deg ramp rising towards 30 deg: its grounded reaches equal the
    independent LP's with gravity written here, g (-sin s cos u, -sin s sin u, -cos s), not taken
    from the floor under test (a gravity leaning the wrong way passed 20 ramp tests that took it
    from ``Floor.gravity()``); uphill it reaches less than on the level floor, downhill more."""
    robot = mobmanip.load_robot("tiago_dual")
    q = _turned(robot, named_configuration(robot, "hold"), 0.0, 0.0, 1.0)
    s, u = math.radians(5.0), math.radians(30.0)
    gravity = 9.81 * np.array([-math.sin(s) * math.cos(u), -math.sin(s) * math.sin(u), -math.cos(s)])
    ramp = _grounded(robot, q, "translational", 2.0, Floor(mu=0.5, slope=5.0, uphill=30.0))
    problem = fr.build_problem(robot, q, "translational", ramp.held_object, gravity=gravity)
    polytope = ramp.measures["dynamic_polytope"]
    for e in _axes(3):
        ours = polytope.straight_line_reach(e)
        ref = fr.straight_line(problem, e, mode="friction", mu=0.5, springs=True).value
        assert abs(ours - ref) <= _reach_tol(ours, ref), (e, ours, ref)
    uphill = np.array([math.cos(u), math.sin(u), 0.0])
    level = _grounded(robot, q, "translational", 2.0, Floor(mu=0.5)).measures["dynamic_polytope"]
    assert polytope.straight_line_reach(uphill) < level.straight_line_reach(uphill)
    assert polytope.straight_line_reach(-uphill) > level.straight_line_reach(-uphill)
