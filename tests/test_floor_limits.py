"""What stops a maximum on the floor, named as the physics has it and ranked by what relaxing each
limit is worth (issue 39, item 3).

The reference (tests/floor_reference.py) writes the whole robot on the floor with its own
floating-base equations and solves it with scipy's HiGHS; from its solution this file reads, with
nothing of mobmanip's reading, what binds at a maximum:

- **tip-over** where a contact carries no load and the zero-moment point is on the support
  polygon's edge (about the edge between the contacts still loaded, or about the one left);
- **traction** where every contact is loaded, the zero-moment point is inside the polygon, a
  loaded wheel is at its friction pyramid's limit and 0.1 % more friction moves the maximum.

Stretch at home holding 0.5 kg, on its default floor (mu 0.5; its three contacts share the weight
as equally stiff springs, its two wheels their sideways force as equal tyres): along -z the robot
tips about the edge joint_left_wheel to caster_link (joint_right_wheel at 0 N). Along +y and -y
it does *not* tip: the zero-moment point stays 2.6 mm and 4.6 mm inside, the lighter wheel
carries 2.3 N and 4.1 N, and the heavier wheel (118 N, 97 N) pushes along the floor at its
friction limit: 1 % more friction gives 0.056 and 0.022 m/s^2 more (with every sharing of the
sideways force allowed, ``load="any"``, +y tips: tests/test_floor_readings.py). A reading that
says tip-over there, or traction along -z, fails here.

The limits' ranking (``limits``, the first is what to change) is checked against the reference's
own multipliers (scipy's ``marginals``) times each limit's scale, limit by limit, on Stretch and
TIAGo++, and by relaxing the first-ranked limit in the reference: the maximum grows by its gain.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import mobmanip
from floor_reference import GRAVITY, build_problem, polygon_margin, straight_line, support_polygon
from mobmanip.analysis.reaches import axis_reaches
from mobmanip.commands.common import describe_reaches
from mobmanip.postures.named import named_configuration
from mobmanip.robot.tasks import get_task
from mobmanip.terms.constraints.floor import Floor

MU, FACES = 0.5, 8
TILT = MU * math.cos(math.pi / FACES)  # a face of the inscribed pyramid: u . f_t <= TILT f_n
SLIP = "(traction at its friction limit, mu = 0.5)"
EDGE = "caster_link to joint_right_wheel"
CASES = {  # robot, posture, task, object mass (kg)
    "stretch": ("stretch", "home", "translational", 0.5),
    "tiago_dual": ("tiago_dual", "hold", "spatial", 2.0),
}


@pytest.fixture(scope="module")
def grounded():
    """Per case: the robot, mobmanip's reaches on the default floor (mu 0.5) by axis, and the
    reference's problem."""
    out = {}
    for key, (name, posture, task, mass) in CASES.items():
        robot = mobmanip.load_robot(name)
        q = named_configuration(robot, posture)
        analysis = mobmanip.analyze(
            robot, q, task, object_mass=mass, measures=("dynamic_polytope",), constraints=(Floor(mu=MU),)
        )
        reaches = {r["axis"]: r for r in axis_reaches(analysis.measures["dynamic_polytope"], task)}
        out[key] = robot, task, reaches, build_problem(robot, q, task, analysis.held_object)
    return out


def _direction(task: str, axis: str) -> np.ndarray:
    labels = get_task(task).labels
    e = np.zeros(len(labels))
    e[labels.index(axis[1:])] = 1.0 if axis[0] == "+" else -1.0
    return e


def _reference(problem, e, mu=MU):
    """The reference's straight-line maximum on the default floor (springs: the compliant sharing)."""
    return straight_line(problem, e, mode="friction", mu=mu, faces=FACES, springs=True)


def _physics(problem, e) -> dict:
    """What binds at the reference's maximum along ``e``, from its contact forces alone."""
    found = _reference(problem, e)
    normals = found.forces[:, 2]
    names = [c.name for c in problem.contacts]
    total = float(normals.sum())
    margin = polygon_margin(support_polygon(problem.points), found.zmp)
    unloaded = [n for n, f in zip(names, normals) if f <= 1e-6 * total]
    out = {"value": found.value, "normals": dict(zip(names, normals)), "margin": margin}
    if unloaded and abs(margin) <= 1e-6:
        out.update(kind="tip-over", lifting=set(unloaded), about={n for n in names if n not in unloaded})
        return out
    faces = problem.heading + 2.0 * math.pi * np.arange(FACES) / FACES
    units = np.column_stack([np.cos(faces), np.sin(faces)])
    at_limit = {
        n
        for c, n in zip(problem.contacts, names)
        if c.driven
        and normals[names.index(n)] > 1e-6 * total
        and float(np.max(units @ found.forces[names.index(n), :2])) >= (1 - 1e-6) * TILT * normals[names.index(n)]
    }
    more_friction = _reference(problem, e, mu=MU * 1.001).value
    if at_limit and more_friction > found.value * (1 + 1e-6):
        out.update(kind="traction", wheels=at_limit)
    else:
        out.update(kind="other")
    return out


def _agrees(limits: list[dict], physics: dict) -> bool:
    """Whether a reading's ranked limits name what the physics finds binding: its first limit is
    of that kind (a tip-over naming the contacts it tips about and those lifting; traction on a
    wheel at its limit), and nothing says tip-over where no contact is unloaded."""
    if not limits:
        return False
    first = limits[0]
    tips = [entry for entry in limits if entry["kind"] == "tip-over"]
    if physics["kind"] == "tip-over":
        if first["kind"] != "tip-over":
            return False
        about, _, lifting = first["label"].partition("(")
        return all(n in about for n in physics["about"]) and all(n in lifting for n in physics["lifting"])
    if tips:
        return False
    if physics["kind"] == "traction":
        return first["kind"] == "traction" and first["label"].split(" ", 1)[0] in physics["wheels"]
    return True


def test_stretch_readings_name_the_limit_the_physics_finds(grounded):
    """+y and -y: traction (every contact loaded, the ZMP millimetres inside, the heavy wheel at
    its friction limit); -z: tip-over about joint_left_wheel to caster_link."""
    robot, task, reaches, problem = grounded["stretch"]
    expected = {"+y": "traction", "-y": "traction", "-z": "tip-over"}
    for axis, kind in expected.items():
        physics = _physics(problem, _direction(task, axis))
        reading = reaches[axis]
        assert reading["straight_line"] == pytest.approx(physics["value"], rel=1e-6)
        assert physics["kind"] == kind, (axis, physics)
        if kind == "traction":  # the figures behind "not tip-over": a margin of millimetres, no contact unloaded
            assert physics["margin"] > 2e-3 and min(physics["normals"].values()) > 2.0, physics
        assert _agrees(reading["limits"], physics), (axis, reading["limits"], physics)
    assert reaches["-z"]["limits"][0]["label"].startswith(
        "the robot tips over about the edge joint_left_wheel to caster_link (joint_right_wheel lifting off)"
    )


def test_where_traction_binds_millimetres_from_the_edge_the_reading_names_that_edge(grounded):
    """+y and -y stop at traction with the zero-moment point 2.6 and 4.6 mm inside: the reading
    names tip-over as the next limit, about the edge the reference's zero-moment point is nearest
    (the reference's own hull of its contact points), at the reference's distance. -z (tipping)
    and +x (4 cm inside) name none."""
    robot, task, reaches, problem = grounded["stretch"]
    names = [c.name for c in problem.contacts]
    xy = np.asarray(problem.points)[:, :2]
    for axis in ("+y", "-y"):
        found = _reference(problem, _direction(task, axis))
        p = np.asarray(found.zmp, dtype=float)[:2]
        polygon = support_polygon(problem.points)
        distances = []
        for a, b in zip(polygon, np.roll(polygon, -1, axis=0)):
            t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
            distances.append((float(np.linalg.norm(p - a - t * (b - a))), a, b))
        distance, a, b = min(distances, key=lambda item: item[0])
        edge = {names[int(np.argmin(np.linalg.norm(xy - v, axis=1)))] for v in (a, b)}
        ground = reaches[axis]["floor"]
        assert set(ground["next_tip_over_edge"]) == edge, axis
        assert ground["margin"] == pytest.approx(distance, abs=1e-6) and 2e-3 < distance < 5e-3
    for axis in ("-z", "+x"):
        assert "next_tip_over_edge" not in reaches[axis]["floor"], axis
    a, b = reaches["+y"]["floor"]["next_tip_over_edge"]
    printed = describe_reaches([reaches["+y"]], "m/s^2", None)
    assert f"(tip-over next: 2.6 mm from tipping about the edge {a} to {b})" in printed


def test_a_planted_label_fails(grounded):
    """The old reading (a wheel that slips where the robot tips, along -z) and its opposite (a
    tip-over where a loaded wheel slips, along +y) are both refused by the check above."""
    robot, task, reaches, problem = grounded["stretch"]
    slip = {"label": f"joint_right_wheel slips {SLIP}", "kind": "traction"}
    tip = {"label": f"the robot tips over about the edge {EDGE} (joint_left_wheel lifting off)", "kind": "tip-over"}
    for axis, planted in (("-z", slip), ("+y", tip), ("-y", tip)):
        physics = _physics(problem, _direction(task, axis))
        assert _agrees(reaches[axis]["limits"], physics)
        assert not _agrees([{**planted, "gain": 1.0}, *reaches[axis]["limits"]], physics), axis


def _short(label: str) -> str:
    """A limit's label as :func:`_reference_gains` names it: without the friction or load details."""
    return label.split(" (traction")[0].split(" the floor (")[0]


def _reference_gains(robot, problem, found) -> dict[str, float]:
    """What 1 % more of each limit gives, from the reference's multipliers: an effort limit's
    multiplier times its limit; a loaded wheel's pyramid's multipliers times the friction its
    load gives (1 % more friction at that wheel); a contact's lifting row's times its equal share
    of the weight. By the labels mobmanip gives those limits."""
    s = found.sensitivities
    out = {}
    for k, name in enumerate(robot.reduced_velocity_names):
        for side, key in (("+", "tau_upper"), ("-", "tau_lower")):
            if s[key][k] > 0.0:
                out[f"{name} effort limit ({side})"] = 0.01 * s[key][k] * problem.tau_max[k]
    share = problem.total_mass * GRAVITY / len(problem.contacts)
    for c, contact in enumerate(problem.contacts):
        if s["normal"][c] > 0.0:
            out[f"{contact.name} lifts off"] = 0.01 * s["normal"][c] * share
        if s["friction"][c].sum() > 0.0:
            out[f"{contact.name} slips"] = 0.01 * s["friction"][c].sum() * TILT * found.forces[c, 2]
    top = max(out.values())
    return {label: gain for label, gain in out.items() if gain > 1e-6 * top}


@pytest.mark.parametrize(
    "case, axis", [("stretch", "+x"), ("stretch", "+y"), ("stretch", "-y"), ("tiago_dual", "+x"), ("tiago_dual", "+y")]
)
def test_the_ranking_is_the_reference_multipliers(grounded, case, axis):
    """Every limit that binds, with its gain, equals the reference's (11 on TIAGo++ along +x, once
    listed unranked), and in the same order: the first is what to change."""
    robot, task, reaches, problem = grounded[case]
    found = _reference(problem, _direction(task, axis))
    expected = _reference_gains(robot, problem, found)
    got = {
        entry["label"].split(" (traction")[0].split(" the floor (")[0]: entry["gain"]
        for entry in reaches[axis]["limits"]
    }
    assert set(got) == set(expected), (got, expected)
    for label, gain in expected.items():
        assert got[label] == pytest.approx(gain, rel=1e-5), label
    assert list(got) == sorted(expected, key=lambda label: -expected[label])


def test_relaxing_the_first_limit_raises_the_maximum_by_its_gain(grounded):
    """TIAGo++ along +x: 0.1 % more of the first-ranked limit (an effort limit) in the reference
    raises its maximum by a tenth of the gain; Stretch along +y (two wheels at their friction
    limit): 0.1 % more friction raises it by a tenth of the two wheels' gains together."""
    robot, task, reaches, problem = grounded["tiago_dual"]
    e = _direction(task, "+x")
    first = reaches["+x"]["limits"][0]
    assert first["kind"] == "effort"
    k = robot.reduced_velocity_names.index(first["label"].split(" ", 1)[0])
    tau_max = problem.tau_max.copy()
    tau_max[k] *= 1.001
    more = _reference(dataclasses.replace(problem, tau_max=tau_max), e).value - _reference(problem, e).value
    assert more == pytest.approx(first["gain"] / 10.0, rel=1e-3)

    robot, task, reaches, problem = grounded["stretch"]
    e = _direction(task, "+y")
    limits = reaches["+y"]["limits"]
    assert {entry["kind"] for entry in limits} == {"traction"}
    more = _reference(problem, e, mu=MU * 1.001).value - _reference(problem, e).value
    assert more == pytest.approx(sum(entry["gain"] for entry in limits) / 10.0, rel=2e-2)


def test_the_summary_groups_by_kind_in_the_order_of_the_ranking():
    """The printed line keeps the ranking: groups in the order of their best limit, each limit
    with its gain, at most six shown and the rest counted."""
    from mobmanip.commands.common import limits_summary

    limits = [
        {
            "label": "wheel_right_joint slips (traction at its friction limit, mu = 0.5)",
            "kind": "traction",
            "gain": 0.3,
        },
        {"label": "arm_1_joint effort limit (+)", "kind": "effort", "gain": 0.2},
        {"label": "wheel_left_joint slips (traction at its friction limit, mu = 0.5)", "kind": "traction", "gain": 0.1},
        *({"label": f"arm_{k}_joint effort limit (-)", "kind": "effort", "gain": 0.05 / k} for k in range(2, 7)),
    ]
    text = limits_summary(limits)
    assert text.startswith(
        "wheel traction: wheel_right_joint +0.3, wheel_left_joint +0.1; joint effort: arm_1_joint +0.2"
    )
    assert text.endswith("; and 2 more, each under +0.0125")
