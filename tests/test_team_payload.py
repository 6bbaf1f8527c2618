"""The heaviest object a team can hold (``mobmanip.team.payload.team_payload``, ``team --payload``).

References: the team's capacity sets that exist already (``analyze_team(...).measure(
"dynamic_polytope")`` at the object's mass m contains the acceleration asked for exactly when m
is at most the payload), read just below and just above the program's mass; a team of one against
the robot's own payload; and, where the program finds no limit, the independent whole-team LP of
tests/floor_reference.py still holding the object at ten tonnes.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from floor_reference import PAPER_CASTERS, build_problem, team_straight_line
from hostile_util import run_cli
from mobmanip.analysis.payload import payload, scaled_object, unit_object
from mobmanip.team import Member, Team, load_team
from mobmanip.team.analysis import analyze_team
from mobmanip.team.members import hand_positions
from mobmanip.team.payload import team_payload
from mobmanip.terms.constraints.floor import Floor

ROOT = Path(__file__).resolve().parents[1]
RTOL = 1e-6


@pytest.fixture(scope="module")
def tiago():
    return mobmanip.load_robot("tiago_dual")


@pytest.fixture(scope="module")
def pair(tiago):
    """Two TIAGo++ facing each other in their hold posture, all four hands on one long object."""
    qa = tiago.hold_configuration()
    west = Member("west", tiago, qa, (0, 1))
    qb = qa.copy()
    qb[0] = 2.0 * hand_positions(west)[:, 0].mean() + 0.1
    qb[2], qb[3] = -1.0, 0.0  # facing -x
    return Team.holding([west, Member("east", tiago, qb, (0, 1))], 4.0, task="spatial")


def _holds(team, mass, constraints, a) -> bool:
    """Whether the team's dynamic polytope at ``mass`` contains ``a``."""
    held = replace(team, held_object=scaled_object(unit_object(team.held_object), mass))
    found = analyze_team(held, ("dynamic_polytope",), constraints=constraints).measure("dynamic_polytope")
    return not found.empty and found.contains(a)


CASES = {
    "ideal, still": ((), np.zeros(6)),
    "ideal, accelerating": ((), np.array([0.5, 0.0, 0.2, 0.0, 0.0, 0.0])),
    "floor mu 0.5, still": ((Floor(mu=0.5),), np.zeros(6)),
    "floor mu 0.5 reserve 0.2, accelerating": ((Floor(mu=0.5, reserve=0.2),), np.array([0.0, 0.4, 0.0, 0.0, 0.0, 0.3])),
}


@pytest.mark.parametrize("case", list(CASES))
def test_the_team_payload_is_where_the_teams_set_stops_holding(pair, case):
    constraints, a = CASES[case]
    found = team_payload(pair, acceleration=a, constraints=constraints)
    assert found.status == "bounded"
    assert found.mass > 1.0
    assert _holds(pair, found.mass * (1 - RTOL), constraints, a)
    assert not _holds(pair, found.mass * (1 + RTOL), constraints, a)
    # what stops it is named by robot
    assert found.binding and all(label.split(":")[0] in ("west", "east") for label in found.binding)
    assert found.to_dict()["robot"] == "team"


def test_a_team_of_one_is_the_robot(tiago):
    q = tiago.hold_configuration()
    floor = Floor(mu=0.5, reserve=0.1)
    one = Team.holding([Member("solo", tiago, q, (0, 1))], 2.0, task="spatial")
    own = payload(tiago, q, "spatial", constraints=(floor,))
    assert team_payload(one, constraints=(floor,)).mass == pytest.approx(own.mass, rel=1e-9)


def test_a_braced_beam_has_no_limit_and_the_reference_agrees():
    """Two paper robots holding the beam level brace against each other through it: their arms'
    joints turn about the vertical and carry none of its weight, and the pair cannot tip. The
    program finds no limit; the independent team LP holds ten tonnes."""
    beam = load_team(ROOT / "examples" / "beam_team.toml")
    assert team_payload(beam, constraints=(Floor(mu=0.5, level=True),)).status == "unbounded"
    heavy = replace(beam, held_object=scaled_object(unit_object(beam.held_object), 1e4))
    problems = [
        build_problem(m.robot, m.q, heavy.task, heavy.held_object, casters=PAPER_CASTERS, level=True)
        for m in heavy.members
    ]
    reach = team_straight_line(problems, np.array([1.0, 0.0, 0.0]), mode="friction", mu=0.5, springs=True)
    assert reach > 0.0


def test_the_command_prints_and_writes_the_payload(tmp_path, capfd):
    out = tmp_path / "box.json"
    code, text, err = run_cli(capfd, "team", ROOT / "examples" / "two_arms_box.toml", "--payload", "--json", out)
    assert code == 0, err
    document = json.loads(out.read_text())["payload"]
    assert f"heaviest object team box can hold still on the ideal model (no floor): {document['mass']:.6g} kg" in text
    assert "what stops it: joint effort" in text
    assert document["status"] == "bounded" and document["binding"]
