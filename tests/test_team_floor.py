"""A team on the floor (issue 24: the team polytopes gain the grounded variant): every robot stands
on its own wheels and casters, and the object is one.

Checked against an independent LP (tests/floor_reference.py, ``team_straight_line`` and, for
the heading sweep's reaches from its set's centre, ``team_ray_radius``: each robot's whole-body
equations from Pinocchio with a floating base restricted to its own S, its own contact forces and
floor rows, and one object whose task and level rows sum every robot's hands), against a team of
one (the robot's own grounded analysis), and in what the floor carries. The beam is held level
(``Floor(level=True)``): the robots carry its weight (its planar task alone would not).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from floor_reference import (
    GRAVITY,
    PAPER_CASTERS,
    build_problem,
    polygon_margin,
    ramp_gravity,
    support_polygon,
    team_ray_radius,
    team_straight_line,
)
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.postures.named import named_configuration
from mobmanip.team import Member, Team, load_team, team_from_dict
from mobmanip.team.analysis import NO_SHARE, analyze_team, ray_radius
from mobmanip.terms.constraints.floor import CONTACT_FORCES, LEVEL_WRENCHES, Floor, ground_reaction
from test_floor_cli import _cli

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
BEAM = load_team(EXAMPLES / "beam_team.toml")
BEAM_DATA = tomllib.loads((EXAMPLES / "beam_team.toml").read_text())

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


@pytest.fixture(scope="module")
def beam_on_the_floor():
    """The beam team analysed on the floor with mu 0.5, the beam held level (shared: read only)."""
    return analyze_team(BEAM, ("dynamic_polytope",), constraints=(Floor(level=True, mu=0.5),))


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


def test_the_floor_binds_the_team_and_the_robots_share_the_beam(beam_on_the_floor):
    """With mu = 0.5 the beam's +x reach falls well below the ideal team's (sideways, the paper
    robots' wheels slip), and at the maximum the two floors carry the whole weight, both robots
    and the beam once: the hands of both robots together hold the beam's weight (one object: its
    level rows add up over the team; each robot on its own carried all of it before)."""
    ideal = analyze_team(BEAM, ("dynamic_polytope",)).measure("dynamic_polytope")
    P = beam_on_the_floor.measure("dynamic_polytope")
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


def test_team_ground_from_the_command_line(beam_on_the_floor, tmp_path):
    """``mobmanip team ... --mu 0.5``: the JSON's reaches are the Python API's, the model names
    the floor and its mu for each robot, each reach's floor per robot, and the summary names the
    robot whose contact or joint stops each reach; bad floor options are one line."""
    import json

    out = tmp_path / "t.json"
    path = Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml"
    run = _cli("team", str(path), "--polytope", "--mu", "0.5", "--level", "--json", str(out))
    assert run.returncode == 0, run.stderr
    doc = json.loads(out.read_text())
    P = beam_on_the_floor.measure("dynamic_polytope")
    entry = doc["dynamic_polytope"]
    assert entry["model"]["constraints"][-1]["mu"] == 0.5
    assert entry["model"]["south"]["floor"]["mu"] == 0.5 and entry["model"]["north"]["floor"]["mu"] == 0.5
    reaches = {r["axis"]: r for r in entry["reaches"]}
    assert reaches["+x"]["straight_line"] == pytest.approx(P.straight_line_reach([1, 0, 0]), rel=1e-9)
    assert reaches["+y"]["support"] == pytest.approx(P.support([0, 1, 0]), rel=1e-9)
    assert set(reaches["+x"]["floors"]) == {"south", "north"}
    assert all(b.startswith(("south: ", "north: ")) for b in reaches["+x"]["binding"])
    assert "on the floor (mu 0.5), every robot on its own contacts:" in run.stdout
    # +x is stopped first by the wheels' traction, ranked by the reach 1 % more of each gives
    plus_x = next(line for line in run.stdout.splitlines() if line.strip().startswith("+x: straight line"))
    assert "stops it (gain per 1 % more): wheel traction: " in plus_x and "north/wheel_left_joint +" in plus_x
    assert "dynamic ellipsoid [ignores floor: an ellipsoid cannot honour it]" in run.stdout
    bad = _cli("team", str(path), "--mu", "-1")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert "mu must be a finite friction coefficient >= 0, got -1.0" in bad.stderr


#: The floor of the heading sweep: the reference's mode, mu and equally stiff contacts.
SWEEP_FLOOR = Floor(level=True, mu=0.5)
SWEEP_REFERENCE = {"mode": "friction", "mu": 0.5, "springs": True}
#: The sweep's platforms (rad): south and north stand at these headings, the beam between them at 0.18 rad.
HEADINGS = {"south": 1.0, "north": 2.5}
BEAM_YAW = 0.18
SWEEP_OFFSET = 10.0  # deg: the sweep's one heading, the beam turned from BEAM_YAW


def _turned_beam(beam_yaw: float, headings: dict) -> dict:
    """The beam team's description with the beam at ``beam_yaw`` and each robot at its heading
    (rad), standing where its end of the beam is where it was seen from the robot (examples/
    beam_team.toml: ahead of it, its hands where they were): the arms' joints reach as before."""
    data = copy.deepcopy(BEAM_DATA)
    centre = np.array(data["object"]["position"][:2])
    old = math.radians(data["object"]["yaw_deg"])

    def end(yaw, robot):  # the beam's end the robot holds (its grasp points share x and y)
        x, y = robot["grasps"][0]["point"][:2]
        return centre + x * np.array([math.cos(yaw), math.sin(yaw)]) + y * np.array([-math.sin(yaw), math.cos(yaw)])

    for robot in data["robots"]:
        turn = headings[robot["name"]] - math.radians(robot["yaw_deg"])  # about the robot's end of the beam
        c, s = math.cos(turn), math.sin(turn)
        behind = np.array(robot["position"]) - end(old, robot)
        robot["position"] = (end(beam_yaw, robot) + np.array([[c, -s], [s, c]]) @ behind).tolist()
        robot["yaw_deg"] = math.degrees(headings[robot["name"]])
    data["object"]["yaw_deg"] = math.degrees(beam_yaw)
    return data


def _reference_problems(team) -> list:
    """Each robot's floor equations in the reference (its contacts from its URDF and the paper
    robot's casters, placed by Pinocchio at its pose), the beam held level."""
    return [
        build_problem(m.robot, m.q, team.task, team.held_object, casters=PAPER_CASTERS, level=True)
        for m in team.members
    ]


def _reference_shares(problems, e, step: float = 1e-4) -> np.ndarray:
    """Each robot's share in limiting the reference's reach along e: the elasticity of its ray
    radius with respect to the robot's effort limits (the mean of the one-sided differences of
    the logs over ``step``)."""
    r0 = team_ray_radius(problems, e, **SWEEP_REFERENCE)
    shares = []
    for i in range(len(problems)):
        up, down = (
            team_ray_radius(
                [dataclasses.replace(p, tau_max=p.tau_max * s) if j == i else p for j, p in enumerate(problems)],
                e,
                **SWEEP_REFERENCE,
            )
            for s in (1.0 + step, 1.0 - step)
        )
        shares.append(0.5 * (math.log(up / r0) / math.log1p(step) + math.log(r0 / down) / -math.log1p(-step)))
    return np.array(shares)


@pytest.fixture(scope="module")
def turned_sweep():
    """The turned beam team's heading sweep on the floor, at one heading, analysed on a local Dask
    cluster of one worker (the job travels pickled with its floor): (description, its point)."""
    from mobmanip.support.cluster import dask_executor
    from mobmanip.team.heading_jobs import HeadingJob, run_heading_sweep

    data = _turned_beam(BEAM_YAW, HEADINGS)
    job = HeadingJob(data, (SWEEP_OFFSET,), str(EXAMPLES), ("dynamic_polytope",), constraints=(SWEEP_FLOOR,))
    with dask_executor("local:1") as executor:
        (point,) = run_heading_sweep(job, executor).to_dict()["points"]
    return data, point


def test_a_heading_sweep_on_the_floor_equals_the_independent_lp(turned_sweep):
    """The beam team with its platforms turned to 1 and 2.5 rad (a transposed platform rotation
    mirrors their supports and friction pyramids there), its beam turned by the sweep from 0.18
    rad by 10 deg: the sweep's reaches along the task axes (from its set's centre) equal the team
    reference LP's (tests/floor_reference.py: each robot's floor rows built from its URDF, its
    wheels' pyramids turned by its own heading, solved by HiGHS) to 1e-9, and lie below the
    reference's reaches with the floor's forces free (the floor binds). The robot named as
    limiting each axis is the one whose effort limits move the reference's reach most; and the
    beam did turn: at its heading before, the reference's reaches differ."""
    data, point = turned_sweep
    assert point["offset_deg"] == SWEEP_OFFSET and point["reachable"]
    moved = copy.deepcopy(data)  # the sweep's team: the beam turned, the arms at the sweep's joints
    moved["object"]["yaw_deg"] += SWEEP_OFFSET
    for robot in moved["robots"]:
        robot["reach"] = False
        robot["joints"] = {**robot["joints"], **point["joints"][robot["name"]]}
    team = team_from_dict(moved, EXAMPLES)  # the hands on their grasp points, or a TeamError
    platforms = [m.robot.configuration_dict(m.q)["platform"][2] for m in team.members]
    np.testing.assert_allclose(platforms, [HEADINGS[m.name] for m in team.members], atol=1e-12)
    problems = _reference_problems(team)
    got = np.array(point["reach"]["dynamic_polytope"])
    ref = np.array([team_ray_radius(problems, e, **SWEEP_REFERENCE) for e in np.eye(3)])
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=0.0)
    assert np.all(got < 0.9 * np.array([team_ray_radius(problems, e) for e in np.eye(3)]))  # the floor binds
    for axis, e in enumerate(np.eye(3)):
        shares = _reference_shares(problems, e)
        top = int(np.argmax(shares))
        assert shares[top] >= NO_SHARE and shares[top] - np.delete(shares, top).max() > 0.05, shares
        assert point["limiting_robot"]["dynamic_polytope"][axis] == team.members[top].name, (axis, shares)
    before = _reference_problems(team_from_dict(data, EXAMPLES))
    unturned = [team_ray_radius(before, e, **SWEEP_REFERENCE) for e in np.eye(3)]
    assert not np.allclose(got, unturned, rtol=1e-3)


def test_the_team_page_draws_each_robots_support_and_zmp(beam_on_the_floor, tmp_path):
    """``team ... --mu 0.5 --export``: each robot's support polygon is the hull of its contacts at
    its pose (the reference's: its wheels and casters placed by Pinocchio), its zero-moment point
    at rest inside it (the margin that polygon gives), and the page draws both per robot and says
    the margins."""
    from mobmanip.analysis.reaches import floors_at_rest

    found = floors_at_rest(beam_on_the_floor.measure("dynamic_polytope"))
    assert set(found) == {"south", "north"}
    for member in BEAM.members:
        # the reference's contacts where Pinocchio puts them at the robot's pose, and their hull
        problem = build_problem(member.robot, member.q, BEAM.task, BEAM.held_object, casters=PAPER_CASTERS, level=True)
        polygon = support_polygon(problem.points)
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


def test_the_beam_team_on_a_ramp_equals_the_independent_lp(beam_on_the_floor):
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
    level = beam_on_the_floor.measure("dynamic_polytope")
    for e in _directions(P.dim):
        ref = team_straight_line(problems, e, mode="friction", mu=0.5, springs=True)
        assert P.straight_line_reach(e) == pytest.approx(ref, rel=1e-6), e
    assert P.straight_line_reach([1.0, 0.0, 0.0]) < level.straight_line_reach([1.0, 0.0, 0.0])
