"""Every registered measure as an objective (issue 36, item 4): ``place`` and ``carry`` take any
measure's reading (``MEASURE:READING:DIRECTION``), its gradient taken by central differences
checked at two steps (:mod:`mobmanip.gradients.readings`).

The reference is a toy measure with a closed form: the bounding box of the kinematic ellipsoid
(``tests/test_measures.py``'s ``kinematic_box``). Its support along a task axis e is
sqrt(e^T C e), which is the kinematic ellipsoid's capacity along e (its centre is 0): an
objective with a closed-form adjoint gradient of its own. So the box's reading, differenced, must
give that gradient; carried and placed by it, the robot must move and stand as it does for the
ellipsoid's capacity.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import mobmanip
from mobmanip import register_measure, unregister_measure
from mobmanip.errors import MeasureError, UnknownMeasureError
from mobmanip.gradients import GradientEvaluator, ReadingGradient, ReadingObjective, objective_evaluator
from mobmanip.measures import VELOCITY, Measure
from mobmanip.motion.carry import ObjectPath, carry, default_start
from mobmanip.placement.grounded import place_polytope
from mobmanip.placement.optimize import place
from test_measures import BOX, Box


@pytest.fixture(scope="module")
def box():
    """The toy measure registered for the module."""
    register_measure(BOX)
    yield BOX.name
    unregister_measure(BOX.name)


def _turned(robot, q, heading):
    q = q.copy()
    q[2], q[3] = math.cos(heading), math.sin(heading)
    return q


@pytest.mark.parametrize("heading", [0.0, 1.0, 2.5])
@pytest.mark.parametrize("axis", ["+x", "-y"])
def test_the_differenced_reading_is_the_closed_form_gradient(box, tiago, paper, heading, axis):
    """TIAGo++ at its hold posture and the paper robot at its start posture, the platform turned:
    the box's support, differenced, against the ellipsoid capacity's adjoint gradient."""
    for robot, q in ((tiago, tiago.hold_configuration()), (paper, default_start(paper))):
        q = _turned(robot, q, heading)
        value, grad, ok = GradientEvaluator(robot, f"kinematic:capacity:{axis}")(q)
        assert ok
        reading = ReadingGradient(robot, f"{box}:support:{axis}")
        got, diff, defined = reading(q)
        assert defined and reading.kinks == 0
        assert got == pytest.approx(value, rel=1e-12)
        scale = float(np.max(np.abs(grad)))
        np.testing.assert_allclose(diff, grad, rtol=0, atol=1e-6 * scale)
        assert reading.evaluations == 4 * robot.model.nv + 1


def test_a_kink_is_counted_and_a_smooth_point_is_not(paper):
    """A toy measure whose box has half-width 1 + |t| along x, t an arm joint's angle. Away from
    t = 0 both differences are the slope 1; at t = 0.6 h (h the step) the difference at h is
    (1.6 h - 0.4 h) / 2h = 0.6 and at 2h it is 0.3: they disagree, and the point counts as a kink."""
    joint = paper.model.joints[paper.model.getJointId("arm_left_2_joint")]

    def kinked(terms):
        return Box(np.zeros(2), np.array([1.0 + abs(terms.q[joint.idx_q]), 1.0]))

    measure = Measure("kinked_box", "kinked_box", VELOCITY, "kinked box", "box", 0x777777, 0xBBBBBB, kinked)
    register_measure(measure)
    try:
        reading = ReadingGradient(paper, "kinked_box:support:+x", "planar")
        q = default_start(paper).copy()
        q[joint.idx_q] = 0.3
        value, grad, ok = reading(q)
        assert ok and reading.kinks == 0 and value == pytest.approx(1.3, rel=1e-12)
        expected = np.zeros(paper.model.nv)
        expected[joint.idx_v] = 1.0
        np.testing.assert_allclose(grad, expected, rtol=0, atol=1e-9)
        q[joint.idx_q] = 0.6 * reading.step
        _, grad, ok = reading(q)
        assert ok and reading.kinks == 1
        assert grad[joint.idx_v] == pytest.approx(0.6, abs=1e-9)  # the difference at the smaller step
    finally:
        unregister_measure(measure.name)


def test_objectives_are_dispatched_by_what_they_read(box, paper):
    assert isinstance(objective_evaluator(paper, "kinematic:capacity:+x"), GradientEvaluator)
    assert isinstance(objective_evaluator(paper, f"{box}:support:+x"), ReadingGradient)
    assert isinstance(objective_evaluator(paper, "force_polytope:support:-y"), ReadingGradient)
    with pytest.raises(UnknownMeasureError, match="unknown measure 'no_such'; expected one of kinematic, dynamic"):
        ReadingObjective.parse("no_such:support:+x", "planar")
    with pytest.raises(MeasureError, match="the kinematic ellipsoid's objectives are kinematic:INDEX"):
        ReadingObjective.parse("kinematic:support:+x", "planar")


def test_carry_climbs_the_readings_difference_as_it_climbs_the_closed_form(box, paper):
    """The paper robot carries along a short bend with a self-motion first: by the box's support
    and by the ellipsoid's capacity, the same motion (to the differences' accuracy)."""
    path = ObjectPath(np.array([0.0, 1.0, 2.0]), np.array([[0.0, 0.0], [0.1, 0.05], [0.2, 0.05]]))
    by_gradient = carry(paper, path, "kinematic:capacity:+x", prepare=0.5)
    by_reading = carry(paper, path, f"{box}:support:+x", prepare=0.5)
    assert by_reading.objective.name == f"{box}:support:+x"
    for a, b in ((by_gradient.preparation, by_reading.preparation), (by_gradient.motion, by_reading.motion)):
        assert a.q.shape == b.q.shape
        np.testing.assert_allclose(b.q, a.q, rtol=0, atol=1e-7)
        np.testing.assert_allclose(b.capacity, a.capacity, rtol=1e-8)
    assert by_reading.motion.capacity[0] > by_reading.preparation.capacity[0]  # the self-motion climbed


def test_place_by_the_reading_stands_where_the_closed_form_does(box, paper):
    """Placing by the box's support starts from the ellipsoid capacity's optimum (its surrogate)
    and cannot beat it (the box's support is that capacity): the same value, to the searches'
    tolerance."""
    target = (1.0, 0.5, 0.35)
    best = place(paper, target, "kinematic:capacity:+x", "planar")
    got = place_polytope(paper, target, f"{box}:support:+x", "planar", budget=60)
    assert got.value == pytest.approx(best.value, rel=1e-6)
    value, _, _ = GradientEvaluator(paper, "kinematic:capacity:+x", "planar")(got.q)
    assert value == pytest.approx(got.value, rel=1e-9)


def test_place_and_carry_take_a_force_measure_from_the_command_line(tmp_path, capsys):
    """A force measure has no ellipsoid of its quantity: place starts from the largest kinematic
    ellipsoid's hold and searches from there; its answer is never below that start's reading, and
    carry runs with it."""
    from mobmanip.cli import main

    out = tmp_path / "place.json"
    code = main(["place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "force_polytope:support:-y",
                 "--budget", "40", "--json", str(out)])  # fmt: skip
    printed = capsys.readouterr().out
    assert code == 0, printed
    document = json.loads(out.read_text())
    assert document["ungrounded"]["objective"] == "kinematic:log_volume"
    assert document["value"] >= document["ungrounded"]["objective_value"] > 0.0
    assert math.isfinite(document["value"])
    robot = mobmanip.load_robot("planar_dual_arm")
    q = robot.configuration(tuple(document["q"]["platform"]), document["q"]["joints"])
    again = mobmanip.analyze(robot, q, measures=("force_polytope",)).measure("force_polytope")
    assert again.support(np.array([0.0, -1.0])) == pytest.approx(document["value"], rel=1e-6)
