"""Readings on the floor name the real limit (issue 39, item 3): where a maximum puts the
zero-moment point on the support polygon's edge and leaves contacts with no load, the robot is
about to tip over, and "what stops it" says so, naming the edge (or the one contact still loaded);
an unloaded wheel's friction rows, all tight at zero force, are not a slip.

Stretch at home holding 0.5 kg on its two wheels and one caster, with every sharing of the load
and of the wheels' sideways forces that balances it (``load="any"``: exact tip-over; with the
compliant sharing its +y and -y maxima are traction's, a wheel of its axle carrying half the
sideways force): along +y, -y and -z its maxima tip it (the limit was reported as "wheel
traction: joint_right_wheel ... slips" with the ZMP margin 0.000 m and a wheel carrying 0 N).
Each label is checked against the contact forces of the maximiser, computed here from the
witness: the contacts named lifting carry nothing, the others do, and the zero-moment point lies
on the segment between the contacts named.
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from mobmanip.analysis.reaches import axis_reaches
from mobmanip.postures.named import named_configuration
from mobmanip.terms.constraints.floor import CONTACT_FORCES, Floor


@pytest.fixture(scope="module")
def stretch():
    robot = mobmanip.load_robot("stretch")
    q = named_configuration(robot, "home")
    polytope = mobmanip.analyze(
        robot,
        q,
        "translational",
        object_mass=0.5,
        measures=("dynamic_polytope",),
        constraints=(Floor(mu=0.5, load="any"),),
    ).measures["dynamic_polytope"]
    return polytope, {r["axis"]: r for r in axis_reaches(polytope, "translational")}


def _forces(polytope, axis: str) -> tuple[dict, np.ndarray]:
    """Each contact's (point (x, y), normal force N) at the straight-line maximum along ``axis``,
    and the zero-moment point, from the witness's contact forces and the contacts' points."""
    sign, k = (1.0 if axis[0] == "+" else -1.0), "xyz".index(axis[1])
    e = np.zeros(3)
    e[k] = sign
    w = polytope.straight_line_witness(e)
    forces = w.variables[CONTACT_FORCES]
    out = {}
    for contact in polytope.model["floor"]["contacts"]:
        a, b = contact["columns"]
        out[contact["name"]] = (np.asarray(contact["point"][:2]), float(forces[b - 1]))
    total = sum(n for _, n in out.values())
    zmp = sum(p * n for p, n in out.values()) / total
    return out, zmp


@pytest.mark.parametrize("axis", ["+y", "-y", "-z"])
def test_a_maximum_that_tips_the_robot_says_tip_over(stretch, axis):
    polytope, reaches = stretch
    binding = reaches[axis]["binding"]
    tips = [label for label in binding if "tips over" in label]
    assert len(tips) == 1, binding
    contacts, zmp = _forces(polytope, axis)
    weight = sum(n for _, n in contacts.values())
    lifting = [name for name in contacts if f"{name}" in tips[0].split("(")[-1]]
    assert lifting, tips[0]
    for name, (_, normal) in contacts.items():
        if name in lifting:
            assert normal <= 1e-6 * weight, (name, normal)
            assert not any(label.startswith(f"{name} slips") for label in binding), binding
        else:
            assert normal > 1e-3 * weight, (name, normal)
    about = [name for name in contacts if name not in lifting]
    if len(about) == 1:  # at a corner
        assert f"about {about[0]}," in tips[0]
        np.testing.assert_allclose(zmp, contacts[about[0]][0], atol=1e-6)
    else:  # on the segment between the two loaded contacts
        a, b = (contacts[name][0] for name in about)
        assert f"about the edge {about[0]} to {about[1]}" in tips[0] or f"{about[1]} to {about[0]}" in tips[0]
        cross = (b - a)[0] * (zmp - a)[1] - (b - a)[1] * (zmp - a)[0]
        assert abs(cross) / np.linalg.norm(b - a) <= 1e-6


def test_a_maximum_inside_the_polygon_names_no_tip_over(stretch):
    """Along -x the zero-moment point stays 7 mm inside the polygon: no tip-over is named."""
    _, reaches = stretch
    assert reaches["-x"]["floor"]["margin"] > 1e-3
    assert not any("tips over" in label for label in reaches["-x"]["binding"])


def test_the_summary_names_the_tip_over_and_its_edge(capfd):
    from hostile_util import run_cli

    code, out, err = run_cli(capfd, "analyze", "stretch", "--ground", "--load", "any")
    assert code == 0, err
    lines = {line.split(":")[0].strip(): line for line in out.splitlines() if line.startswith("      ")}
    assert "tip-over: about the edge caster_link to joint_right_wheel (joint_left_wheel lifting off)" in lines["+y"]
    assert "tip-over: about joint_left_wheel, the one contact still loaded" in lines["-z"]
    assert "wheel traction" not in lines["-y"]


def test_each_grounded_reach_is_printed_beside_the_ideal_one(tmp_path, capfd):
    """``analyze --ground`` gives, per axis, the ideal set's straight-line reach beside the grounded
    one (JSON ``ideal_straight_line``) and the drop in percent; the ideal reach is the one of the
    analysis without the floor, and never below the grounded one (a differential drive)."""
    import json

    from hostile_util import run_cli

    out = tmp_path / "a.json"
    code, printed, err = run_cli(capfd, "analyze", "tiago_dual", "--posture", "hold", "--ground", "--json", out)
    assert code == 0, err
    reaches = json.loads(out.read_text())["dynamic_polytope"]["reaches"]
    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    ideal = mobmanip.analyze(robot, q, measures=("dynamic_polytope",)).measures["dynamic_polytope"]
    labels = list(mobmanip.robot.tasks.get_task("spatial").labels)
    for r in reaches:
        e = np.zeros(6)
        e[labels.index(r["axis"][1:])] = 1.0 if r["axis"][0] == "+" else -1.0
        assert r["ideal_straight_line"] == pytest.approx(ideal.straight_line_reach(e), rel=1e-9)
        assert r["straight_line"] <= r["ideal_straight_line"] * (1 + 1e-9)
        drop = 100.0 * (r["straight_line"] - r["ideal_straight_line"]) / r["ideal_straight_line"]
        assert f"(ideal straight line {r['ideal_straight_line']:.4g}: {drop:+.1f} %)" in printed


def test_a_grounded_sets_halfspaces_list_each_facet_once():
    """TIAGo++ on the floor, translational (a 3-D set with square and larger facets, which Qhull
    lists once per triangle: 1,758 rows for 856 facets): every row of ``halfspaces`` is a facet of
    the vertices' hull (every vertex inside it, at least three on it), and no two rows are the
    same plane."""
    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    P = mobmanip.analyze(
        robot, q, "translational", object_mass=2.0, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    ).measures["dynamic_polytope"]
    A, b = P.halfspaces
    V = P.vertices
    slack = b[:, None] - A @ V.T
    scale = float(np.abs(V).max())
    assert slack.min() >= -1e-9 * scale
    assert (np.abs(slack) <= 1e-9 * scale).sum(axis=1).min() >= 3
    gaps = np.abs(A[:, None, :] - A[None, :, :]).max(axis=2) + np.abs(b[:, None] - b[None, :]) / scale
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min() > 1e-9
