"""A team on the floor (issue 24: the team polytopes gain the grounded variant): every robot stands
on its own wheels and casters, and the object is one.

Checked against an independent LP (tests/floor_reference.py, ``team_straight_line``: each robot's
whole-body equations from Pinocchio with a floating base restricted to its own S, its own contact
forces, and one object whose task and level rows sum every robot's hands), against a team of one
(the robot's own grounded analysis), and in what the floor carries. The beam is held level
(``Floor(level=True)``): the robots carry its weight (its planar task alone would not).
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from floor_reference import GRAVITY, PAPER_CASTERS, build_problem, ramp_gravity, team_straight_line
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.postures.named import named_configuration
from mobmanip.team import Member, Team, load_team, team_from_dict
from mobmanip.team.analysis import analyze_team, ray_radius
from mobmanip.terms.constraints.floor import CONTACT_FORCES, LEVEL_WRENCHES, Floor, ground_reaction
from test_floor_cli import _cli

BEAM = load_team(Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml")
BEAM_DATA = tomllib.loads((Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml").read_text())

#: the floors checked: the floor constraint, and the reference's mode, mu and load sharing
FLOORS = {
    "no tip-over": (Floor(level=True, mu=None), ("no_tip", None, False)),
    "mu 0.5, compliant": (Floor(level=True, mu=0.5), ("friction", 0.5, True)),
    "mu 0.5, any sharing": (Floor(level=True, mu=0.5, load="any"), ("friction", 0.5, False)),
    "mu 1.0, reserve 0.1": (Floor(level=True, mu=1.0, reserve=0.1), ("friction", 1.0, True)),
}


def _directions(m):
    axes = np.eye(m)
    mixed = np.array([0.6, -0.8, 0.0])[:m] if m == 3 else np.ones(m) / np.sqrt(m)
    return [*axes, *-axes, mixed / np.linalg.norm(mixed)]


@pytest.mark.parametrize("floor", list(FLOORS))
def test_the_beam_team_on_the_floor_equals_the_independent_lp(floor):
    """Two paper robots carrying the 1.5 m, 4 kg beam (planar_rigid), each on its own four corner
    casters and two wheels: every straight-line reach equals the team reference LP to 1e-6."""
    constraint, (mode, mu, springs) = FLOORS[floor]
    P = analyze_team(BEAM, ("dynamic_polytope",), constraints=(constraint,)).measure("dynamic_polytope")
    problems = [
        build_problem(m.robot, m.q, BEAM.task, BEAM.held_object, casters=PAPER_CASTERS, level=True)
        for m in BEAM.members
    ]
    reserve = constraint.reserve
    for e in _directions(P.dim):
        ref = team_straight_line(problems, e, mode=mode, mu=mu, springs=springs, reserve=reserve)
        assert ref > 0.0
        assert P.straight_line_reach(e) == pytest.approx(ref, rel=1e-6), (floor, e)


def test_the_floor_binds_the_team_and_the_robots_share_the_beam():
    """With mu = 0.5 the beam's +x reach falls well below the ideal team's (sideways, the paper
    robots' wheels slip), and at the maximum the two floors carry the whole weight, both robots
    and the beam once: the hands of both robots together hold the beam's weight (one object: its
    level rows add up over the team; each robot on its own carried all of it before)."""
    ideal = analyze_team(BEAM, ("dynamic_polytope",)).measure("dynamic_polytope")
    P = analyze_team(BEAM, ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.5),)).measure("dynamic_polytope")
    e = np.array([1.0, 0.0, 0.0])
    assert P.straight_line_reach(e) < 0.5 * ideal.straight_line_reach(e)
    w = P.straight_line_witness(e)
    total = sum(float(pin.computeTotalMass(m.robot.model)) for m in BEAM.members) + BEAM.held_object.mass
    normals, beam_share = 0.0, []
    for member in BEAM.members:
        info = P.model[member.name]["floor"]
        floor = ground_reaction(info, w.variables[f"{member.name}.{CONTACT_FORCES}"])
        normals += sum(c["normal"] for c in floor["contacts"].values())
        assert floor["margin"] >= -1e-9  # its zero-moment point inside its own support
        level = w.variables[f"{member.name}.{LEVEL_WRENCHES}"].reshape(len(member.robot.arms), 3)
        beam_share.append(float(level[:, 0].sum()))  # the hands' vertical forces on the beam
    assert normals == pytest.approx(total * GRAVITY, rel=1e-9)
    assert sum(beam_share) == pytest.approx(BEAM.held_object.mass * GRAVITY, rel=1e-9)


@pytest.mark.parametrize("case", ["tiago_dual hold", "paper 90 deg"])
def test_a_team_of_one_on_the_floor_is_the_robots_own_grounded_analysis(case):
    if case == "tiago_dual hold":
        robot = mobmanip.load_robot("tiago_dual")
        q, task = named_configuration(robot, "hold"), "spatial"
    else:
        robot = mobmanip.load_robot("planar_dual_arm")
        q, task = configuration_at(robot, optimal_posture(robot), 90.0), "planar"
    floor = Floor(level=True, mu=0.5)
    team = Team.holding([Member("solo", robot, q, tuple(range(len(robot.arms))))], 2.0, task=task)
    got = analyze_team(team, ("dynamic_polytope",), constraints=(floor,)).measure("dynamic_polytope")
    ref = mobmanip.analyze(robot, q, task, object_mass=2.0, measures=("dynamic_polytope",), constraints=(floor,))
    ref_set = ref.measures["dynamic_polytope"]
    for e in _directions(got.dim):
        assert got.straight_line_reach(e) == pytest.approx(ref_set.straight_line_reach(e), rel=1e-9), e
        assert got.support(e) == pytest.approx(ref_set.support(e), rel=1e-9), e


def test_team_ground_from_the_command_line(tmp_path):
    """``mobmanip team ... --mu 0.5``: the JSON's reaches are the Python API's, the model names
    the floor and its mu for each robot, each reach's floor per robot, and the summary names the
    robot whose contact or joint stops each reach; bad floor options are one line."""
    import json

    out = tmp_path / "t.json"
    path = Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml"
    run = _cli("team", str(path), "--polytope", "--mu", "0.5", "--level", "--json", str(out))
    assert run.returncode == 0, run.stderr
    doc = json.loads(out.read_text())
    P = analyze_team(BEAM, ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.5),)).measure("dynamic_polytope")
    entry = doc["dynamic_polytope"]
    assert entry["model"]["constraints"][-1]["mu"] == 0.5
    assert entry["model"]["south"]["floor"]["mu"] == 0.5 and entry["model"]["north"]["floor"]["mu"] == 0.5
    reaches = {r["axis"]: r for r in entry["reaches"]}
    assert reaches["+x"]["straight_line"] == pytest.approx(P.straight_line_reach([1, 0, 0]), rel=1e-9)
    assert reaches["+y"]["support"] == pytest.approx(P.support([0, 1, 0]), rel=1e-9)
    assert set(reaches["+x"]["floors"]) == {"south", "north"}
    assert all(b.startswith(("south: ", "north: ")) for b in reaches["+x"]["binding"])
    assert "on the floor (mu 0.5), every robot on its own contacts:" in run.stdout
    assert "stops it: wheel traction: north/wheel_left_joint" in run.stdout
    assert "dynamic ellipsoid [ignores floor: an ellipsoid cannot honour it]" in run.stdout
    bad = _cli("team", str(path), "--mu", "-1")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert "mu must be a finite friction coefficient >= 0, got -1.0" in bad.stderr


def test_a_heading_sweep_on_the_floor(tmp_path):
    """``--sweep-heading`` with the floor: at the description's own heading the sweep's reaches are
    the grounded set's ray radii; along x the robot named as limiting it is one whose joint limits
    bind at the maximum (with each tyre carrying half of its axle's sideways force, both robots'
    arm efforts bind there beside the wheels' traction); turned by 10 deg the beam's reaches are
    those of the team built at that heading. The headings run on a local Dask cluster of two
    workers, each heading a task: the jobs travel pickled with their floor, and what comes back is
    the reference's (tests/test_cluster.py holds a cluster's files equal to a serial run's)."""
    import json

    path = Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml"
    out = tmp_path / "s.json"
    run = _cli("team", str(path), "--measure", "dynamic_polytope", "--mu", "0.5", "--level", "--sweep-heading",
               "0,10", "--json", str(out), "--dask", "local:2")  # fmt: skip
    assert run.returncode == 0, run.stderr
    points = json.loads(out.read_text())["heading_sweep"]["points"]
    P = analyze_team(BEAM, ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.5),)).measure("dynamic_polytope")
    assert points[0]["offset_deg"] == 0.0
    np.testing.assert_allclose(points[0]["reach"]["dynamic_polytope"], [ray_radius(P, e) for e in np.eye(3)], rtol=1e-9)
    ideal = analyze_team(BEAM, ("dynamic_polytope",)).measure("dynamic_polytope")
    assert points[0]["reach"]["dynamic_polytope"][0] < 0.5 * ray_radius(ideal, np.eye(3)[0])  # the floor binds
    named = points[0]["limiting_robot"]["dynamic_polytope"][0]
    binding = P.straight_line_witness(np.eye(3)[0]).binding
    assert named == "" or any(label.startswith(f"{named}: ") and "effort limit" in label for label in binding)
    data = copy.deepcopy(BEAM_DATA)  # the beam turned by 10 deg, the arms where the sweep put them
    data["object"]["yaw_deg"] += 10.0
    for robot in data["robots"]:
        robot["reach"] = False
        robot["joints"] = {**robot["joints"], **points[1]["joints"][robot["name"]]}
    turned = analyze_team(
        team_from_dict(data, path.parent), ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.5),)
    )
    turned = turned.measure("dynamic_polytope")
    got = points[1]["reach"]["dynamic_polytope"]
    np.testing.assert_allclose(got, [ray_radius(turned, e) for e in np.eye(3)], rtol=1e-9)
    assert not np.allclose(got, points[0]["reach"]["dynamic_polytope"], rtol=1e-3)


def test_the_team_page_draws_each_robots_support_and_zmp(tmp_path):
    """``team ... --mu 0.5 --export``: each robot's support polygon is its own support at its pose,
    its zero-moment point at rest inside it (the margin its polygon gives), and the page draws
    both per robot and says the margins."""
    from mobmanip.analysis.reaches import floors_at_rest
    from mobmanip.robot.support import polygon_margin, robot_support

    P = analyze_team(BEAM, ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.5),)).measure("dynamic_polytope")
    found = floors_at_rest(P)
    assert set(found) == {"south", "north"}
    for member in BEAM.members:
        pose = member.robot.configuration_dict(member.q)["platform"]
        polygon = robot_support(member.robot).polygon(tuple(pose))
        floor = found[member.name]
        assert sorted(map(tuple, np.round(floor["polygon"], 12))) == sorted(map(tuple, np.round(polygon, 12)))
        assert floor["margin"] == pytest.approx(polygon_margin(polygon, floor["zmp"]), abs=1e-12)
        assert floor["margin"] > 0.0
    page = tmp_path / "beam.html"
    path = Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml"
    run = _cli("team", str(path), "--measure", "dynamic_polytope", "--mu", "0.5", "--level", "--export", str(page))
    assert run.returncode == 0, run.stderr
    from browser_util import exported_scene, missing_browser

    if missing_browser():
        pytest.skip(f"the page's scene needs a browser: {missing_browser()}")
    drawn, text = exported_scene(page)
    for name in ("south", "north"):
        assert {f"meshcat/mobmanip/team/floor/{name}/polygon", f"meshcat/mobmanip/team/floor/{name}/zmp"} <= drawn
        assert f"{name}: support polygon (dark line), zero-moment point at rest (dot), margin " in text
        assert f"margin {found[name]['margin']:.3f} m" in text


def test_without_friction_no_robot_limits_a_reach_the_floor_forbids():
    """mu = 0: the floors push nothing along x, so the beam cannot accelerate along x from rest
    (its reach is zero to the programs' rounding) and no robot's limits change that: every share
    is 0, where the ratios of two roundings of zero gave shares of -22 to 17. Along y (the robots'
    headings: their bases recoil, their wheels roll freely) the arms' limits bind as before."""
    A = analyze_team(BEAM, ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.0),))
    P = A.measure("dynamic_polytope")
    ex = np.array([1.0, 0.0, 0.0])
    assert abs(P.straight_line_reach(ex)) < 1e-9 and abs(ray_radius(P, ex)) < 1e-9
    shares = A.contributions("dynamic_polytope", np.array([ex, -ex]))
    np.testing.assert_array_equal(shares, 0.0)
    assert A.limiting_robots("dynamic_polytope", np.array([ex]))[0] == ""
    along_y = A.contributions("dynamic_polytope", np.array([[0.0, 1.0, 0.0]]))[0]
    assert along_y.sum() > 0.5  # the arms' limits bind there, and the robot with the larger share is named
    assert (
        A.limiting_robots("dynamic_polytope", np.array([[0.0, 1.0, 0.0]]))[0]
        == BEAM.members[int(np.argmax(along_y))].name
    )


def test_the_beam_team_on_a_ramp_equals_the_independent_lp():
    """Both robots on one ramp (6 deg, rising towards 45 deg): each robot's weight and the beam's
    lean, and the beam's own load is counted once although every robot's floor states it."""
    ramp = (6.0, 45.0)  # slope, uphill (deg)
    constraint = Floor(level=True, mu=0.5, slope=ramp[0], uphill=ramp[1])
    P = analyze_team(BEAM, ("dynamic_polytope",), constraints=(constraint,)).measure("dynamic_polytope")
    gravity = ramp_gravity(ramp)  # from the ramp itself, never from the floor under test
    problems = [
        build_problem(m.robot, m.q, BEAM.task, BEAM.held_object, casters=PAPER_CASTERS, gravity=gravity, level=True)
        for m in BEAM.members
    ]
    level = analyze_team(BEAM, ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.5),)).measure(
        "dynamic_polytope"
    )
    for e in _directions(P.dim):
        ref = team_straight_line(problems, e, mode="friction", mu=0.5, springs=True)
        assert P.straight_line_reach(e) == pytest.approx(ref, rel=1e-6), e
    assert P.straight_line_reach([1.0, 0.0, 0.0]) < level.straight_line_reach([1.0, 0.0, 0.0])
