"""Constraints of the sets at rest kept by ``carry`` at every step (issue 36, item 1, for carry):
a constraint's rows over the efforts or the reduced velocities compiled over the step's rates
(:mod:`mobmanip.motion.step_constraints`), checked on the toy constraints of
``tests/toy_constraint.py``.

The reference for the effort share is the robot itself with every effort limit scaled: carry's
own effort rows keep the efforts within EFFORT_SHARE of the limits, so the toy's share s is the
scaled robot's own rows when its limits are scaled by s / EFFORT_SHARE.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from hostile_util import run_cli
from mobmanip.errors import ArgumentError, CarryFailed
from mobmanip.motion.carry import EFFORT_SHARE, ObjectPath, carry, read_path
from mobmanip.terms.constraints.options import (
    ConstraintOption,
    register_constraint_option,
    unregister_constraint_option,
)
from toy_constraint import EffortShare, ObjectAccelerationCap, SpeedShare

ROOT = Path(__file__).resolve().parents[1]
#: The example line (2 m in 12 s) after a self-motion of at most 5 s: on the paper robot the
#: self-motion asks 13.6 % of an effort limit and 10.6 % of a speed limit, the path 0.5 % of an
#: effort limit.
PATH = read_path(ROOT / "examples" / "carry_line.csv")
PREPARE = 5.0


@pytest.fixture(scope="module")
def unconstrained(robot):
    return carry(robot, PATH, prepare=PREPARE)


def test_an_effort_share_is_the_robot_with_its_limits_scaled(robot, unconstrained):
    share = 0.08
    constrained = carry(robot, PATH, prepare=PREPARE, constraints=(EffortShare(share),))
    scaled = robot.with_limits(effort={n: v * share / EFFORT_SHARE for n, v in robot.joint_effort_limits.items()})
    reference = carry(scaled, PATH, prepare=PREPARE)
    for ours, theirs in ((constrained.preparation, reference.preparation), (constrained.motion, reference.motion)):
        assert ours.q.shape == theirs.q.shape
        np.testing.assert_allclose(ours.q, theirs.q, rtol=0, atol=1e-9)
    n = min(len(constrained.preparation.q), len(unconstrained.preparation.q))
    assert np.max(np.abs(constrained.preparation.q[:n] - unconstrained.preparation.q[:n])) > 1e-3  # it binds
    assert constrained.summary()["constraints"] == [{"name": "effort_share", "share": share, "problem": "acceleration"}]


def test_a_speed_share_bounds_every_rate_of_the_qp_motion_and_binds(robot, unconstrained):
    """The self-motion climbs at up to 10.6 % of a speed limit; with the share at 5 % it keeps to
    it (the line itself needs 21.9 % of a wheel's speed, so the object is held still after it)."""
    share = 0.05
    used = np.max(np.abs(unconstrained.preparation.x) / robot.velocity_limits)
    assert used > share  # without it the self-motion goes faster
    still = ObjectPath(np.array([0.0, 1.0]), np.zeros((2, 2)))
    constrained = carry(robot, still, prepare=PREPARE, constraints=(SpeedShare(share),))
    for run in (constrained.preparation, constrained.motion):
        ratio = np.abs(run.x) / robot.velocity_limits
        assert ratio.max() <= share * (1.0 + 1e-9)
    assert np.abs(constrained.preparation.x / robot.velocity_limits).max() == pytest.approx(share, rel=1e-6)


def test_a_step_the_constraint_makes_infeasible_names_its_row(robot):
    with pytest.raises(CarryFailed) as failed:
        carry(robot, PATH, prepare=0.0, constraints=(EffortShare(0.001),))
    diagnosis = failed.value.diagnosis
    assert diagnosis.kind == "constraint"
    assert "at 0.001 of its effort limit" in diagnosis.joint
    assert "a constraint binds" in str(failed.value)


def test_a_constraint_that_cannot_join_a_step_is_refused_before_any_work(robot):
    with pytest.raises(ArgumentError, match="'object_acceleration_cap' cannot join a step of motion: its rows use a"):
        carry(robot, PATH, constraints=(ObjectAccelerationCap(),))
    with pytest.raises(ArgumentError, match="the floor in motion is carry's floor="):
        carry(robot, PATH, constraints=(mobmanip.Floor(mu=0.5),))


def test_the_command_takes_a_registered_option(tmp_path, capfd):
    register_constraint_option(ConstraintOption("--effort-share", EffortShare, "keep every effort within a share"))
    try:
        out = tmp_path / "run"
        code, _, err = run_cli(capfd, "carry", "planar_dual_arm", "--path", ROOT / "examples" / "carry_line.csv",
                               "--prepare", "0", "--effort-share", "0.5", "--out", out)  # fmt: skip
        assert code == 0, err
        document = json.loads((out / "carry.json").read_text())
        assert document["constraints"] == [{"name": "effort_share", "share": 0.5, "problem": "acceleration"}]
        code, _, err = run_cli(capfd, "retime", "planar_dual_arm", out / "trajectory.csv", "--effort-share", "0.5",
                               "--out", tmp_path / "timed")  # fmt: skip
        assert code == 0, err
        timed = json.loads((tmp_path / "timed" / "retime.json").read_text())
        assert timed["constraints"] == [{"name": "effort_share", "share": 0.5, "problem": "acceleration"}]
    finally:
        unregister_constraint_option("--effort-share")


# --------------------------------------------------------------------------- a team

TEAM = ROOT / "examples" / "beam_team.toml"


def _quintic():
    """The beam 0.3 m along its length in 1.5 s: with a large capacity gain the team's QP drives
    the arms as hard as their effort limits allow (tests/test_team_carry.py)."""
    t = np.linspace(0.0, 1.5, 16)
    s = t / 1.5
    return ObjectPath(t, np.c_[0.3 * (10 * s**3 - 15 * s**4 + 6 * s**5), np.zeros_like(t)])


def test_team_carry_keeps_an_effort_share_as_every_robot_with_its_limits_scaled():
    """team-carry with the effort share s equals team-carry of the same team whose robots' effort
    limits are scaled by s / 0.99 (the team's own rows hold 0.99 of them), to 1e-9; the share
    binds (without it the motion differs) and every modelled effort stays within it."""
    import dataclasses

    from mobmanip.coordination.carry import team_carry
    from mobmanip.team import Member
    from mobmanip.team.members import load_team

    share = 0.5
    team = load_team(TEAM)
    kept = team_carry(team, _quintic(), prepare=0.0, gain=1e3, constraints=(EffortShare(share),))
    members = tuple(
        Member(m.name, m.robot.with_limits(effort={n: v * share / EFFORT_SHARE
                                                   for n, v in m.robot.joint_effort_limits.items()}), m.q, m.arms)
        for m in team.members
    )  # fmt: skip
    scaled = team_carry(dataclasses.replace(team, members=members), _quintic(), prepare=0.0, gain=1e3)
    free = team_carry(team, _quintic(), prepare=0.0, gain=1e3)
    for a, b in zip(kept.motion.x, scaled.motion.x):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
    assert max(float(np.abs(a - b).max()) for a, b in zip(kept.motion.x, free.motion.x)) > 1e-3  # it binds
    assert kept.motion.effort.max() == pytest.approx(share, abs=1e-9)  # the share of the 1.0 limits


def test_team_carry_takes_the_registered_option(tmp_path, capfd):
    register_constraint_option(ConstraintOption("--effort-share", EffortShare, "keep every effort within a share"))
    try:
        path = _quintic()
        csv = tmp_path / "quintic.csv"
        csv.write_text("t,x,y\n" + "".join(f"{t:.17g},{x:.17g},{y:.17g}\n" for t, (x, y) in zip(path.t, path.xy)))
        code, _, err = run_cli(capfd, "team-carry", TEAM, "--path", csv, "--prepare", "0", "--effort-share", "0.5",
                               "--out", tmp_path / "run")  # fmt: skip
        assert code == 0, err
        document = json.loads((tmp_path / "run" / "team_carry.json").read_text())
        assert document["constraints"] == [{"name": "effort_share", "share": 0.5, "problem": "acceleration"}]
        assert document["qp"]["max_effort_share"] <= 0.5 + 1e-9
    finally:
        unregister_constraint_option("--effort-share")


def test_a_team_step_the_constraint_makes_infeasible_names_the_robot_and_its_row():
    from mobmanip.coordination.carry import team_carry
    from mobmanip.team.members import load_team

    with pytest.raises(CarryFailed, match=r"a constraint binds: (south|north): .* at 0.001 of its effort limit") as err:
        team_carry(load_team(TEAM), _quintic(), prepare=0.0, gain=1e3, constraints=(EffortShare(0.001),))
    assert err.value.diagnosis.kind == "constraint"


# --------------------------------------------------------------------------- the fastest timing


def _panda_sine(n=81):
    """The Panda's seven joints swinging by 0.4 rad, q(s) = home + 0.4 sin(pi s), s in [0, 1]."""
    from mobmanip.motion.trajectory import trajectory_from_samples

    panda = mobmanip.load_robot("panda")
    home = panda.hold_configuration()
    ids = [panda.model.getJointId(name) for name in panda.reduced_velocity_names]
    iq = [panda.model.joints[j].idx_q for j in ids]
    s = np.linspace(0.0, 1.0, n)
    q = np.tile(home, (n, 1))
    q[:, iq] = home[iq] + 0.4 * np.sin(np.pi * s)[:, None]
    x_s = 0.4 * np.pi * np.cos(np.pi * s)[:, None] * np.ones(len(iq))
    x_ss = -0.4 * np.pi**2 * np.sin(np.pi * s)[:, None] * np.ones(len(iq))
    return panda, trajectory_from_samples(panda, s, q, x_s, x_ss)


@pytest.mark.parametrize(
    ("constraint", "scaled"),
    [(EffortShare(0.3), "effort"), (SpeedShare(0.4), "velocity")],
    ids=["effort share", "speed share"],
)
def test_retime_keeps_a_share_as_the_robot_with_its_limits_scaled(constraint, scaled):
    """retime's own rows are |tau| <= tau_max and |x| <= xdot_max, so a share s of either is the
    robot with those limits scaled by s: the same timing, to round-off, and slower than without."""
    from mobmanip.motion.retime import retime

    panda, path = _panda_sine()
    plain = retime(panda, path, object_mass=0.5)
    kept = retime(panda, path, object_mass=0.5, constraints=(constraint,))
    limits = panda.joint_effort_limits if scaled == "effort" else panda.joint_velocity_limits
    reference = retime(panda.with_limits(**{scaled: {n: constraint.share * v for n, v in limits.items()}}), path,
                       object_mass=0.5)  # fmt: skip
    assert kept.duration == pytest.approx(reference.duration, rel=1e-9)
    np.testing.assert_allclose(kept.speed, reference.speed, rtol=1e-9, atol=1e-12)
    assert kept.duration > 1.2 * plain.duration  # it binds
    assert "constraint" in kept.binding_kind
    assert kept.to_dict()["constraints"] == [constraint.describe()]


@pytest.mark.parametrize(
    ("constraint", "scaled"),
    [(EffortShare(0.3), "effort"), (SpeedShare(0.4), "velocity")],
    ids=["effort share", "speed share"],
)
def test_the_time_scaling_margin_keeps_a_share_as_the_robot_with_its_limits_scaled(constraint, scaled):
    """``trajectory``'s margin runs the same motion k times faster within |tau| <= tau_max and
    |x| <= xdot_max: with a share s of either it is the margin of the robot with those limits
    scaled by s (computed without the constraint), to round-off; the constraint decides it, and
    it is smaller than without."""
    from mobmanip.motion.trajectory_analysis import analyze_trajectory

    panda, path = _panda_sine()
    plain = analyze_trajectory(panda, path, object_mass=0.5).scaling
    kept = analyze_trajectory(panda, path, object_mass=0.5, constraints=(constraint,)).scaling
    limits = panda.joint_effort_limits if scaled == "effort" else panda.joint_velocity_limits
    robot = panda.with_limits(**{scaled: {n: constraint.share * v for n, v in limits.items()}})
    reference = analyze_trajectory(robot, path, object_mass=0.5).scaling
    assert kept.k_max == pytest.approx(reference.k_max, rel=1e-12)
    assert kept.k_min == pytest.approx(reference.k_min, rel=1e-12, abs=1e-12)
    assert kept.sample == reference.sample
    assert kept.limit.startswith("constraint ")  # measured: 1.499 against 1.731 (effort share 0.3)
    assert kept.k_max < plain.k_max / 1.1
