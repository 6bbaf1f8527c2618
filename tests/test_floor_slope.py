"""The floor as a ramp (``Floor(slope=, uphill=)``): the platform's plane is the ramp's, gravity
leans in its axes, and the robot's and the object's weights change with it.

Checked three ways: against the independent whole-robot LP (tests/floor_reference.py, its
generalized gravity from Pinocchio's own model with gravity leaning), against the statics of the
whole robot at rest (the floor carries the weight, the wheels alone hold it along the ramp), and
in MuJoCo with gravity leaning (tests/mujoco_referee.py), whose floor is level. Every reference's
gravity is worked out from the ramp's slope and uphill direction (``floor_reference.ramp_gravity``),
never read from the floor under test: a gravity leaning the wrong way would lean both sides alike.

The paper robot's object is held level here (``Floor(level=True)``), as MuJoCo's weld holds it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from floor_reference import PAPER_CASTERS, build_problem, force_support, ramp_gravity, straight_line, support
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.errors import MobmanipError
from mobmanip.postures.named import named_configuration
from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor, ground_reaction

MASS = 2.0
RAMPS = [(5.0, 0.0), (5.0, 120.0), (10.0, -60.0)]  # (slope, uphill direction), deg
#: the floor, and the reference's mode, mu and load sharing
FLOORS = {
    "mu 0.5": (dict(mu=0.5), ("friction", 0.5, True, 0.0)),
    "no tip-over": (dict(mu=None), ("no_tip", None, False, 0.0)),
    "mu 1.0, reserve 0.1": (dict(mu=1.0, reserve=0.1), ("friction", 1.0, True, 0.1)),
}


def _case(name):
    if name == "tiago_dual hold":
        robot = mobmanip.load_robot("tiago_dual")
        return robot, named_configuration(robot, "hold"), "spatial", None
    robot = mobmanip.load_robot("planar_dual_arm")
    return robot, configuration_at(robot, optimal_posture(robot), 0.0), "planar", PAPER_CASTERS


def _axes(m):
    return [s * e for e in np.eye(m)[: min(m, 3)] for s in (1.0, -1.0)]


def _seen_along_gravity(robot, q, analysis, floor_z, gravity):
    """Statics by hand: the centre of mass of robot and object, seen along gravity on the floor, (2,)."""
    m, obj = pin.computeTotalMass(robot.model), analysis.held_object
    c = m * pin.centerOfMass(robot.model, robot.model.createData(), q) + obj.mass * np.asarray(obj.center)
    c /= m + obj.mass
    return c[:2] - (c[2] - floor_z) * gravity[:2] / gravity[2]


def _tiago_on(ramp, measure):
    """TIAGo++ holding 2 kg in its hold posture on a ramp (mu 0.5): (robot, q, floor, analysis)."""
    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    constraint = Floor(level=True, mu=0.5, slope=ramp[0], uphill=ramp[1])
    analysis = mobmanip.analyze(robot, q, "spatial", object_mass=MASS, measures=(measure,), constraints=(constraint,))
    return robot, q, constraint, analysis


@pytest.mark.parametrize("floor", list(FLOORS))
@pytest.mark.parametrize("ramp", RAMPS)
@pytest.mark.parametrize("case", ["tiago_dual hold", "paper 0 deg"])
def test_on_a_ramp_the_reaches_equal_the_independent_lp(case, ramp, floor):
    robot, q, task, casters = _case(case)
    options, (mode, mu, springs, reserve) = FLOORS[floor]
    constraint = Floor(level=True, **options, slope=ramp[0], uphill=ramp[1])
    analysis = mobmanip.analyze(robot, q, task, object_mass=MASS, constraints=(constraint,),
                                measures=("dynamic_polytope", "dynamic_polytope_min_norm"))  # fmt: skip
    gravity = ramp_gravity(ramp)
    problem = build_problem(robot, q, task, analysis.held_object, casters=casters, gravity=gravity, level=True)
    P, policy = analysis.measures["dynamic_polytope"], analysis.measures["dynamic_polytope_min_norm"]
    for e in _axes(P.dim):
        ref = straight_line(problem, e, mode=mode, mu=mu, springs=springs, reserve=reserve).value
        assert P.straight_line_reach(e) == pytest.approx(ref, rel=1e-6), (case, ramp, floor, e)
    e = np.eye(P.dim)[0]
    ref = support(problem, e, mode=mode, mu=mu, springs=springs, reserve=reserve, policy=True).value
    assert policy.support(e) == pytest.approx(ref, rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("case", ["tiago_dual hold", "paper 0 deg"])
def test_the_force_capacity_on_a_ramp_equals_the_independent_lp(case):
    robot, q, task, casters = _case(case)
    constraint = Floor(level=True, mu=0.5, slope=8.0, uphill=30.0)
    analysis = mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("force_polytope",),
                                constraints=(constraint,))  # fmt: skip
    F = analysis.measures["force_polytope"]
    problem = build_problem(
        robot, q, task, analysis.held_object, casters=casters, gravity=ramp_gravity((8.0, 30.0)), level=True
    )
    for e in _axes(F.dim):
        ref = force_support(problem, e, mode="friction", mu=0.5, springs=True).value
        assert F.support(e) == pytest.approx(ref, rel=1e-6, abs=1e-6), (case, e)


def test_a_ramp_changes_the_reaches_the_way_gravity_leans():
    """A ramp rising along +x: accelerating the object uphill (+x) reaches less than on the level
    floor and downhill (-x) more for the paper robot, whose limit there is its wheels' traction
    (the weight's share along the ramp adds to what they must push uphill); a level ramp is the
    level floor exactly."""
    robot, q, task, _ = _case("paper 0 deg")

    def reach(floor, e):
        return mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("dynamic_polytope",),
                                constraints=(floor,)).measures["dynamic_polytope"].straight_line_reach(e)  # fmt: skip

    x = np.array([1.0, 0.0])
    level, ramp = Floor(level=True, mu=0.5), Floor(level=True, mu=0.5, slope=5.0)
    assert reach(Floor(level=True, mu=0.5, slope=0.0, uphill=45.0), x) == reach(level, x)
    assert reach(ramp, x) < reach(level, x) and reach(ramp, -x) > reach(level, -x)


@pytest.mark.parametrize("case, ramp", [("tiago_dual hold", (5.0, 0.0)), ("paper 0 deg", (5.0, 120.0))])
def test_at_rest_on_a_ramp_the_floor_carries_the_weight_and_the_wheels_hold_it(case, ramp):
    """Robot and object still (the force problem at f = 0: no motion at all) on a ramp: the
    contact forces sum to the whole weight turned into the ramp's axes (normal m g cos s, along
    the ramp m g sin s uphill), the frictionless casters carry none of the part along the ramp,
    and the wheels stay in their pyramids."""
    robot, q, task, _ = _case(case)
    constraint = Floor(level=True, mu=0.5, slope=ramp[0], uphill=ramp[1])
    P = mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("force_polytope",),
                         constraints=(constraint,)).measures["force_polytope"]  # fmt: skip
    w = P.witness_at(np.zeros(P.dim))
    info = P.model["floor"]
    forces = w.variables[CONTACT_FORCES]
    total = np.zeros(3)
    for contact in info["contacts"]:
        a, b = contact["columns"]
        f = np.zeros(3)
        f[3 - (b - a) :] = forces[a:b]
        total += f
        if not contact["driven"]:
            assert b - a == 1  # a caster: its normal only
    weight = (pin.computeTotalMass(robot.model) + MASS) * ramp_gravity(ramp)
    np.testing.assert_allclose(total, -weight, atol=1e-7 * np.linalg.norm(weight))
    assert np.hypot(*total[:2]) == pytest.approx(np.linalg.norm(weight) * np.sin(np.radians(ramp[0])), rel=1e-9)
    reaction = ground_reaction(info, forces)
    assert all(c.get("traction_use") is None or c["traction_use"] <= 1.0 + 1e-9 for c in reaction["contacts"].values())


def test_bad_ramps_are_one_line_errors():
    for options, message in (
        (dict(slope=-1.0), "the floor's slope must be from 0 to 30 deg, got -1.0"),
        (dict(slope=45.0), "the floor's slope must be from 0 to 30 deg, got 45.0"),
        (dict(slope=float("nan")), "the floor's slope must be a finite angle in degrees, got nan"),
        (dict(slope=5.0, uphill=float("inf")), "the floor's uphill direction must be a finite angle"),
    ):
        with pytest.raises(MobmanipError, match=message.replace("(", r"\(").replace(")", r"\)")):
            Floor(level=True, **options)


@pytest.mark.parametrize("ramp, reserve", [((5.0, 0.0), 0.0), ((10.0, -60.0), 0.3)])
@pytest.mark.parametrize("name", ["tiago_dual", "paper 0", "paper 90"])
def test_on_a_ramp_each_maximum_is_mujocos(name, ramp, reserve):
    """MuJoCo on a level floor with gravity leaning as the ramp's: the calm efforts of each grounded
    axis maximum (itself) give the predicted object acceleration at t = 0 within 3 % per component
    and the predicted normal forces within 0.1 % of the weight (measured: 0.21 % and 0.025 %), and
    hold 20 ms (no support rises, the base does not rock, no wheel slides) on every axis but
    TIAGo++ -x without a reserve, as on the level floor; with a reserve of 0.3 on all of them."""
    pytest.importorskip("mujoco")
    from mujoco_referee import build
    from test_floor_physics import SHORT, _at_t0, _axes, _held, _object
    from test_floor_physics import _case as physics_case

    robot, q, task, casters, base = physics_case(name)
    constraint = Floor(level=True, mu=0.5, slope=ramp[0], uphill=ramp[1], reserve=reserve)
    P = mobmanip.analyze(robot, q, task, object_mass=MASS, measures=("dynamic_polytope",),
                         constraints=(constraint,)).measures["dynamic_polytope"]  # fmt: skip
    referee = build(robot, q, support_points=casters, object=_object(robot, q, task), mu=0.5,
                    gravity=ramp_gravity(ramp))  # fmt: skip
    gave_way = []
    for e in _axes(base):
        target = P.straight_line_reach(e) * e
        assert np.linalg.norm(target) > 0.0
        w = _at_t0(referee, P, target, task, (name, ramp, e))
        if not _held(referee.rollout(w.variables["tau"], duration=0.02)):
            gave_way.append((float(e.sum()), int(np.argmax(np.abs(e)))))
    assert gave_way == ([(s, k) for (n, s, k) in SHORT if n == name] if reserve == 0.0 else []), gave_way


@pytest.mark.parametrize("ramp", [(0.0, 0.0), (5.0, 0.0), (5.0, 90.0), (3.0, -135.0)])
def test_standing_still_on_a_ramp_the_zmp_is_the_centre_of_mass_projected_alongramp_gravity(ramp):
    """Statics in closed form: with no motion at all (the force problem at f = 0), the centre of
    pressure of the normal forces is where the line through the centre of mass (robot and object)
    along gravity meets the floor: downhill of the level floor's by h tan s."""
    robot, q, constraint, analysis = _tiago_on(ramp, "force_polytope")
    F = analysis.measures["force_polytope"]
    reaction = ground_reaction(F.model["floor"], F.witness_at(np.zeros(6)).variables[CONTACT_FORCES])
    z0 = np.mean([contact["point"][2] for contact in F.model["floor"]["contacts"]])
    seen = _seen_along_gravity(robot, q, analysis, z0, ramp_gravity(ramp))
    np.testing.assert_allclose(reaction["zmp"], seen, atol=1e-9)


def test_a_ramp_from_the_command_line(tmp_path):
    """``analyze --slope 5 --uphill 90``: the JSON's reaches are the Python API's and its model names
    the ramp; the summary says it; a ramp where it is not modelled (``--hold``), ``carry`` on a ramp
    holding the object level (modelled at rest only) and an
    ``--uphill`` without a slope are one-line errors; ``check_physics.py --slope`` replays the
    maxima in MuJoCo with gravity leaning, and each holds."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    def cli(*args):
        return subprocess.run([sys.executable, "-m", "mobmanip", *args], capture_output=True, text=True)

    out = tmp_path / "r.json"
    run = cli("analyze", "tiago_dual", "--posture", "hold", "--object-mass", "2", "--mu", "0.5", "--slope", "5",
              "--uphill", "90", "--json", str(out))  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "a ramp of 5 deg rising towards 90 deg" in run.stdout
    doc = json.loads(out.read_text())["dynamic_polytope"]
    assert doc["model"]["floor"]["slope"] == 5.0 and doc["model"]["floor"]["uphill"] == 90.0
    robot = mobmanip.load_robot("tiago_dual")
    P = mobmanip.analyze(robot, named_configuration(robot, "hold"), "spatial", object_mass=2.0,
                         measures=("dynamic_polytope",), constraints=(Floor(mu=0.5, slope=5.0, uphill=90.0),),
                         ).measures["dynamic_polytope"]  # fmt: skip
    reaches = {r["axis"]: r for r in doc["reaches"]}
    assert reaches["+y"]["straight_line"] == pytest.approx(P.straight_line_reach(np.eye(6)[1]), rel=1e-9)
    path = tmp_path / "p.csv"
    path.write_text("t,x,y\n0,0,0\n2,0.5,0\n")
    for args, message in (
        (("analyze", "tiago_dual", "--uphill", "30"), "--uphill says where a ramp rises: give its --slope too"),
        (("analyze", "tiago_dual", "--slope", "45"), "the floor's slope must be from 0 to 30 deg, got 45.0"),
        (("analyze", "tiago_dual", "--slope", "5", "--hold", "0.02"), "a ramp (--slope) is not modelled there"),
        (("carry", "planar_dual_arm", "--path", str(path), "--slope", "3", "--level"), "--level (the object held"),
    ):
        bad = cli(*args)
        assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and message in bad.stderr, bad.stderr
    pytest.importorskip("mujoco")
    script = Path(__file__).resolve().parents[1] / "scripts" / "check_physics.py"
    run = subprocess.run([sys.executable, str(script), "tiago_dual", "--posture", "hold", "--object-mass", "2",
                          "--task", "spatial", "--mu", "0.5", "--slope", "5", "--uphill", "30", "--reserve", "0.3",
                          "--fraction", "1"], capture_output=True, text=True)  # fmt: skip
    assert run.returncode == 0, run.stderr
    verdicts = [line.split()[-1] for line in run.stdout.splitlines() if line.strip()[:1] in "+-"]
    assert verdicts == ["holds"] * 12, run.stdout


def test_an_empty_set_on_a_ramp_says_where_the_weight_presses():
    """The paper robot with its arms straight (home), 2 kg, a 30 % reserve, on a 5 deg ramp rising
    towards 30 deg: the set is empty, and the warning places the centre of mass seen along gravity
    (downhill of the point straight below it) and says the supports fall below their reserve."""
    robot = mobmanip.load_robot("planar_dual_arm")
    q = named_configuration(robot, "home")
    constraint = Floor(level=True, mu=0.5, slope=5.0, uphill=30.0, reserve=0.3)
    analysis = mobmanip.analyze(robot, q, "planar", object_mass=MASS, measures=("dynamic_polytope",),
                                constraints=(constraint,))  # fmt: skip
    assert analysis.measures["dynamic_polytope"].empty
    z0 = np.mean([p["point"][2] for p in analysis.measures["dynamic_polytope"].model["floor"]["contacts"]])
    seen = _seen_along_gravity(robot, q, analysis, z0, ramp_gravity((5.0, 30.0)))
    level = _seen_along_gravity(robot, q, analysis, z0, np.array([0.0, 0.0, -9.81]))
    warning = next(w for w in analysis.warnings if "on the floor is empty" in w)
    assert "would bring below its reserve (0.3 of an equal share)" in warning
    assert f"seen along gravity on the floor at ({seen[0]:.3f}, {seen[1]:.3f}) m" in warning
    assert np.linalg.norm(seen - level) > 0.01  # the ramp moves it


@pytest.mark.parametrize("ramp, still", [((0.0, 0.0), True), ((5.0, 90.0), True), ((8.0, 30.0), False)])
def test_the_zmp_at_rest_is_the_statics_where_the_robot_can_stand_still(ramp, still):
    """What the viewer draws as the zero-moment point at rest (``floor_at_rest``): where the robot
    can stand perfectly still, the statics (the centre of mass seen along gravity); on an 8 deg
    ramp rising towards 30 deg TIAGo++ cannot hold its posture without moving (not even on an
    ideal floor), so the point is one of the object held still with the arms accelerating, and
    says so; asked to hold its joints still there, witness_at refuses."""
    from mobmanip.analysis.reaches import floor_at_rest

    robot, q, constraint, analysis = _tiago_on(ramp, "dynamic_polytope")
    P = analysis.measures["dynamic_polytope"]
    found = floor_at_rest(P)
    assert found["still"] is still
    statics = _seen_along_gravity(robot, q, analysis, found["floor_z"], ramp_gravity(ramp))
    if still:
        np.testing.assert_allclose(found["zmp"], statics, atol=1e-9)
    else:
        with pytest.raises(MobmanipError, match=r"is not in the set with xdot at zero"):
            P.witness_at(np.zeros(6), still=("xdot",))
        ideal = mobmanip.analyze(robot, q, "spatial", object_mass=MASS, measures=("dynamic_polytope",),
                                 constraints=(Floor(level=True, lift=True, slope=8.0, uphill=30.0),))  # fmt: skip
        with pytest.raises(MobmanipError, match=r"is not in the set with xdot at zero"):
            ideal.measures["dynamic_polytope"].witness_at(np.zeros(6), still=("xdot",))
    with pytest.raises(MobmanipError, match="still must name the set's variables"):
        P.witness_at(np.zeros(6), still=("nothing",))


def test_a_sweep_on_a_ramp_says_so_and_equals_the_analysis(tmp_path):
    """``sweep --slope 5``: the file records the ramp with the floor's parameters (it recorded only
    the name "floor", so a ramp read as the level floor), and its grounded straight-line reach at a
    point equals the analysis of that configuration on the ramp."""
    import json
    import subprocess
    import sys

    from mobmanip.robot.configurations import configuration_from_dict

    out = tmp_path / "s"
    argv = ["sweep", "planar_dual_arm", "--slope", "5", "--uphill", "90", "--mu", "0.5", "--angle", "0:90:2",
            "--distance", "1.0", "--measure", "dynamic_polytope", "--output", str(out), "--no-progress"]  # fmt: skip
    run = subprocess.run([sys.executable, "-m", "mobmanip", *argv], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    data = np.load(out / "sweep.npz")
    models = json.loads(str(data["meta_constraint_models"]))
    assert models[0]["name"] == "floor" and models[0]["slope"] == 5.0 and models[0]["uphill"] == 90.0
    robot = mobmanip.load_robot("planar_dual_arm")  # the posture the sweep used at angle 0, from its file
    joints = dict(zip(map(str, data["posture_joint_names"]), data["posture_joints"][0, 0].tolist()))
    q = configuration_from_dict(robot, {"platform": [0.0, 0.0, 0.0], "joints": joints})
    P = mobmanip.analyze(robot, q, "planar", measures=("dynamic_polytope",),
                         constraints=(Floor(mu=0.5, slope=5.0, uphill=90.0),)).measures["dynamic_polytope"]  # fmt: skip
    reach = data["dynamic_polytope_straight_line_reach"].reshape(-1)[0]
    assert reach == pytest.approx(P.straight_line_reach(np.array([1.0, 0.0])), rel=1e-9)
