"""A user's constraint in the held reach (``analyze --ground --hold``, issue 36 item 1, for hold).

The replay holds the efforts constant, so a constraint's rows over the efforts hold throughout it
when they hold at the start: the toy effort share of ``tests/toy_constraint.py`` then gives the
held reach of the robot whose effort limits are scaled by the share (the reference: no
constraint machinery, the robot's own limits). Rows over anything else would be kept at the
start only, and are refused by name.
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mobmanip.errors import ArgumentError
from mobmanip.motion.hold import held_reach
from mobmanip.postures.named import named_configuration
from mobmanip.terms.constraints.floor import Floor
from mobmanip.terms.constraints.options import (
    ConstraintOption,
    register_constraint_option,
    unregister_constraint_option,
)
from toy_constraint import EffortShare, ObjectAccelerationCap

SHARE = 0.02  # binds along +-x: the reach at rest falls from 1.4893 to 0.7328 m/s^2
FLOOR = Floor(mu=0.5)


@pytest.fixture(scope="module")
def home():
    robot = mobmanip.load_robot("planar_dual_arm")
    return robot, named_configuration(robot, "home")


def _held(robot, q, constraints, direction):
    result = mobmanip.analyze(robot, q, "planar", constraints=constraints, measures=("dynamic_polytope",),
                              method="exact")  # fmt: skip
    polytope = result.measure("dynamic_polytope")
    return held_reach(robot, q, polytope, np.array(direction, dtype=float), "planar",
                      object_mass=result.held_object.mass, floor=FLOOR, duration=0.02)  # fmt: skip


@pytest.mark.parametrize("direction", [(1.0, 0.0), (-1.0, 0.0)])
def test_a_held_reach_keeps_an_effort_share_as_the_robot_with_its_limits_scaled(home, direction):
    """Measured: held 20 ms, 0.72916 m/s^2 of the 0.73282 at rest, both ways. Both equal the
    scaled robot's to 1e-9, every effort held is within the share, and the share binds (without
    it the reach at rest is 1.4893)."""
    robot, q = home
    scaled = robot.with_limits(effort={n: v * SHARE for n, v in robot.joint_effort_limits.items()})
    ours = _held(robot, q, (FLOOR, EffortShare(SHARE)), direction)
    theirs = _held(scaled, q, (FLOOR,), direction)
    assert ours.hold is not None and ours.hold.holds
    assert ours.reach == pytest.approx(theirs.reach, rel=1e-9) and ours.reach > 0.5
    assert ours.instant == pytest.approx(theirs.instant, rel=1e-9)
    tau = ours.witness.variables["tau"]
    assert np.all(np.abs(tau) <= SHARE * robot.effort_limits * (1.0 + 1e-9))
    plain = _held(robot, q, (FLOOR,), direction)
    assert plain.instant > ours.instant * (1.0 + 1e-3) or plain.reach > ours.reach * (1.0 + 1e-3)  # it binds


def test_rows_over_other_variables_are_refused_by_name(home):
    robot, q = home
    with pytest.raises(ArgumentError, match="over the efforts only: row .object acceleration"):
        _held(robot, q, (FLOOR, ObjectAccelerationCap()), (1.0, 0.0))


def test_the_command_without_the_floor_refuses_hold_in_one_line(capfd):
    """A registered option without --ground: one line (it was an internal error: the first
    constraint was taken for the floor)."""
    register_constraint_option(ConstraintOption("--effort-share", EffortShare, "keep every effort within a share"))
    try:
        code, _, err = run_cli(capfd, "analyze", "planar_dual_arm", "--hold", "0.02", "--effort-share", "0.5")
    finally:
        unregister_constraint_option("--effort-share")
    assert_one_line_error(code, err, "--hold replays efforts on the floor: it needs --ground")
