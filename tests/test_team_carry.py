"""Teams that move (mobmanip team-carry): the beam team carries its beam through a 90 deg turn.

Every figure is recomputed here from the motion's configurations, not taken from the QP: the
object's pose from the hands' positions through Pinocchio's forward kinematics of each robot,
the lateral slip from each platform's pose sequence, the limits from each robot's Pinocchio
model, the efforts by Pinocchio's inverse dynamics, the capacity by ``analyze_team`` of a team
rebuilt at the configurations.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from mobmanip.cli import main
from mobmanip.coordination.capacity import TeamCapacity
from mobmanip.coordination.carry import lateral_slip, team_carry
from mobmanip.errors import ArgumentError
from mobmanip.gradients import Objective
from mobmanip.motion.carry import ObjectPath, read_path
from mobmanip.motion.trajectory import read_trajectory, tangent_integrate
from mobmanip.team import Member, Team, analyze_team, load_team

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TEAM = EXAMPLES / "beam_team.toml"
#: carry_turn.csv (a 90 deg arc of radius 1.27 m, 2 m in 12 s) scaled to the beam team, which is
#: 3.4 m from platform to platform: radius 2.55 m.
SCALE = 2.0


def beam_path() -> ObjectPath:
    path = read_path(EXAMPLES / "carry_turn.csv")
    return ObjectPath(path.t, path.xy * SCALE)


@pytest.fixture(scope="module")
def beam():
    team = load_team(TEAM)
    path = beam_path()
    return team, path, team_carry(team, path)


def _hands(team: Team, qs) -> np.ndarray:
    """World positions of every grasping hand (members in order), by forward kinematics."""
    out = []
    for member, q in zip(team.members, qs):
        model = member.robot.model
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        out.extend(data.oMf[model.getFrameId(member.robot.arms[a].end_effector)].translation for a in member.arms)
    return np.array(out)


def _rigid_fit(before: np.ndarray, after: np.ndarray) -> tuple[float, np.ndarray]:
    """The planar rigid motion (angle, translation) that best takes the points ``before`` to
    ``after`` (least squares, Kabsch in the plane)."""
    a, b = before[:, :2], after[:, :2]
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, v = (a - ca).T, (b - cb).T
    angle = np.arctan2(np.sum(u[0] * v[1] - u[1] * v[0]), np.sum(u[0] * v[0] + u[1] * v[1]))
    R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return float(angle), cb - R @ ca


def _expected_object(team: Team, path: ObjectPath, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The object's centre (N, 2) and turn (N,) the path asks: its x axis along the beam."""
    shift, turn = path.sample(t)
    yaw = team.object_yaw
    R = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    return team.held_object.center[:2] + shift[:, :2] @ R.T, turn


def test_the_beam_turns_90_degrees_along_its_length(beam):
    team, path, result = beam
    centre, turn = _expected_object(team, path, result.motion.t[-1:])
    assert np.degrees(turn[-1]) == pytest.approx(90.0, abs=1e-9)
    # the beam (along y at the start) moves lengthwise, then turns left: its centre ends at (-2R, 2R)
    radius = SCALE * 4.0 / np.pi
    assert centre[-1] == pytest.approx([-radius, radius], abs=1e-6)


@pytest.mark.parametrize("which", ["motion", "baseline"])
def test_the_object_follows_the_path_within_1_mm(beam, which):
    """The object's pose from the hands (their best rigid motion from the start), by forward
    kinematics of each robot's configurations, against the path."""
    team, path, result = beam
    run = getattr(result, which)
    start = _hands(team, [q[0] for q in run.q])
    centre, turn = _expected_object(team, path, run.t)
    worst_centre = worst_hand = worst_turn = 0.0
    c0 = team.held_object.center[:2]
    for k in range(len(run.t)):
        hands = _hands(team, [q[k] for q in run.q])
        angle, shift = _rigid_fit(start, hands)
        R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        worst_centre = max(worst_centre, float(np.linalg.norm(R @ c0 + shift - centre[k])))
        worst_turn = max(worst_turn, abs(angle - turn[k]))
        Rk = np.array([[np.cos(turn[k]), -np.sin(turn[k])], [np.sin(turn[k]), np.cos(turn[k])]])
        goals = centre[k] + (start[:, :2] - c0) @ Rk.T
        worst_hand = max(worst_hand, float(np.max(np.linalg.norm(hands[:, :2] - goals, axis=1))))
    limit = 1e-3 if which == "motion" else 5e-3  # the baseline has no limits and lags in the turn
    assert worst_centre <= limit and worst_hand <= limit
    assert worst_turn <= limit  # rad: 1 mm over a metre
    if which == "motion":
        assert worst_hand == pytest.approx(result.motion.hand_error.max(), rel=0.05, abs=1e-6)


def test_no_platform_slides_sideways(beam):
    """Each platform's displacement over a step, across its mean heading, from its poses alone."""
    team, _, result = beam
    for run in (result.preparation, result.motion, result.baseline):
        for member, q in zip(team.members, run.q):
            x, y, c, s = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
            heading = np.unwrap(np.arctan2(s, c))
            mid = 0.5 * (heading[1:] + heading[:-1])
            across = (-np.sin(mid) * np.diff(x) + np.cos(mid) * np.diff(y)) / np.diff(run.t)
            along = (np.cos(mid) * np.diff(x) + np.sin(mid) * np.diff(y)) / np.diff(run.t)
            assert np.abs(across).max() <= 1e-9
            np.testing.assert_allclose(lateral_slip(member.robot, run.t, q), across, atol=1e-12)
            if run is result.motion:
                assert np.abs(along).max() > 0.1  # the platforms do drive
                assert np.ptp(heading) > np.radians(30)  # and turn
        # no collision rows: how close the platforms came, from the poses (0.5 m x 0.28 m boxes)
        gap = np.linalg.norm(run.q[0][:, :2] - run.q[1][:, :2], axis=1).min()
        assert result.summary()[run.method]["min_platform_distance"] == pytest.approx(gap)
        assert gap > 1.0


def _velocities(model, t, qs) -> np.ndarray:
    return np.array([pin.difference(model, a, b) for a, b in zip(qs[:-1], qs[1:])]) / np.diff(t)[:, None]


def test_every_robot_stays_within_its_position_and_velocity_limits(beam):
    team, _, result = beam
    for run in (result.preparation, result.motion):
        for member, q in zip(team.members, run.q):
            model = member.robot.model
            arms = [model.joints[model.getJointId(n)] for arm in member.robot.arms for n in arm.joint_names]
            for joint in arms:
                values = q[:, joint.idx_q]
                assert np.all(values >= model.lowerPositionLimit[joint.idx_q] - 1e-9)
                assert np.all(values <= model.upperPositionLimit[joint.idx_q] + 1e-9)
            v = _velocities(model, run.t, q)
            limited = np.isfinite(model.velocityLimit) & (model.velocityLimit < 1e300)
            assert np.all(np.abs(v[:, limited]) <= model.velocityLimit[limited] * (1 + 1e-6))
    summary = result.summary()
    assert summary["qp"]["samples_beyond_a_joint_range"] == 0 and summary["qp"]["max_velocity_share"] <= 1.0
    # the baseline has no limits: on this path it takes the north robot's arm past its range
    assert summary["pinv"]["samples_beyond_a_joint_range"] > 0


def _efforts(team: Team, run, mass_matrix: np.ndarray) -> np.ndarray:
    """Each step's largest effort over its limit, by Pinocchio's inverse dynamics of each robot
    with the hands' share of the object's load (the least-norm wrenches, as the policy): tau =
    S^T (rnea(q, v, a) + J_hands^T h), h = W^+ (M_o a_o) with a_o from the hands' rigid motion."""
    n = len(run.t)
    start = _hands(team, [q[0] for q in run.q])
    c0 = team.held_object.center[:2]
    poses = []
    for k in range(n):
        angle, shift = _rigid_fit(start, _hands(team, [q[k] for q in run.q]))
        R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        poses.append(np.r_[R @ c0 + shift, angle])
    poses = np.array(poses)
    dt = np.diff(run.t)
    object_velocity = np.diff(poses, axis=0) / dt[:, None]
    worst = np.zeros(n - 2)
    vel = [_velocities(m.robot.model, run.t, q) for m, q in zip(team.members, run.q)]
    for k in range(1, n - 1):
        a_o = (object_velocity[k] - object_velocity[k - 1]) / dt[k]
        hands = _hands(team, [q[k] for q in run.q])
        centre = poses[k, :2]
        W = np.hstack([[[1, 0, 0], [0, 1, 0], [-(p[1] - centre[1]), p[0] - centre[0], 1]] for p in hands])
        h = (np.linalg.pinv(W) @ (mass_matrix @ a_o)).reshape(-1, 3)
        hand = 0
        for i, member in enumerate(team.members):
            robot = member.robot
            model = robot.model
            data = model.createData()
            q = run.q[i][k]
            a = (vel[i][k] - vel[i][k - 1]) / dt[k]
            tau = pin.rnea(model, data, q, vel[i][k - 1], a)
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            for arm in member.arms:
                frame = model.getFrameId(robot.arms[arm].end_effector)
                J = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)[[0, 1, 5]]
                tau = tau + J.T @ h[hand]
                hand += 1
            S = robot.null_space(q)
            reduced = S.T @ tau  # wheel rates as reduced velocities: Q = I
            limits = np.array([model.effortLimit[int(np.flatnonzero(S[:, j])[-1])] for j in range(S.shape[1])])
            worst[k - 1] = max(worst[k - 1], float(np.max(np.abs(reduced) / limits)))
    return worst


def test_every_robot_stays_within_its_effort_limits(beam):
    team, _, result = beam
    obj = team.held_object
    M_o = np.diag([obj.mass, obj.mass, obj.inertia[2, 2]])
    efforts = _efforts(team, result.motion, M_o)
    assert efforts.max() <= 1.0
    # step by step the QP's model of the efforts (its first step, from the self-motion's last
    # rates, is not seen by the differences here)
    np.testing.assert_allclose(efforts, result.motion.effort[1:], rtol=1e-2, atol=1e-5)
    # the check sees a violation: the baseline, which has no limits, asks twice an effort limit
    assert _efforts(team, result.baseline, M_o).max() > 1.5


def test_where_the_efforts_bind_they_keep_the_one_percent_reserve():
    """The carry's efforts are held to 0.99 of every limit (|tau| <= 0.99 tau_max). On the beam
    path they never come near it (at most 1.6 %); here they do: the beam carried 0.3 m along its
    length in 1.5 s (a quintic), with a capacity gain so large the QP drives the arms as hard as
    the limits allow. The largest modelled effort is then 0.99 of its limit to 1e-9, never more;
    the modelled efforts are Pinocchio's inverse dynamics of the motion to 2e-3 of the limits, and
    those are within the limits."""
    team = load_team(TEAM)
    t = np.linspace(0.0, 1.5, 16)
    s = t / 1.5
    path = ObjectPath(t, np.c_[0.3 * (10 * s**3 - 15 * s**4 + 6 * s**5), np.zeros_like(t)])
    result = team_carry(team, path, prepare=0.0, gain=1e3)
    effort = result.motion.effort
    assert effort.max() == pytest.approx(0.99, abs=1e-9)  # the reserve binds, and holds
    obj = team.held_object
    M_o = np.diag([obj.mass, obj.mass, obj.inertia[2, 2]])
    efforts = _efforts(team, result.motion, M_o)
    np.testing.assert_allclose(efforts, effort[1:], rtol=0.0, atol=2e-3)  # measured: 5e-4
    assert efforts.max() <= 1.0


def _capacity_at(team: Team, qs, centre: np.ndarray, turn: float) -> float:
    """The team's kinematic minor semi-axis by ``analyze_team`` of a team rebuilt at qs."""
    members = [Member(m.name, m.robot, q, m.arms) for m, q in zip(team.members, qs)]
    obj = team.held_object
    R = pin.rpy.rpyToMatrix(0.0, 0.0, turn)
    rebuilt = Team.holding(
        members, obj.mass, task=team.task, center=np.r_[centre, obj.center[2]], inertia=R @ obj.inertia @ R.T
    )
    return float(analyze_team(rebuilt, ["kinematic"]).measures["kinematic"].semi_axes.min())


def test_capacity_is_at_least_1_2_times_the_baseline_from_the_same_start(beam):
    team, path, result = beam
    motion, base, prep = result.motion, result.baseline, result.preparation
    for member, q_prep, q_base in zip(team.members, prep.q, base.q):
        np.testing.assert_array_equal(q_prep[0], member.q)  # the same start: the team's posture
        np.testing.assert_array_equal(q_base[0], member.q)
    for run in (motion, base, prep):
        centre, turn = _expected_object(team, path, run.t) if run is not prep else (None, None)
        picks = {0, int(np.argmin(run.capacity)), len(run.t) - 1}
        for k in sorted(picks):
            if run is prep:
                c, a = team.held_object.center[:2], 0.0
            else:
                c, a = centre[k], float(turn[k])
            expected = _capacity_at(team, [q[k] for q in run.q], c, a)
            assert run.capacity[k] == pytest.approx(expected, rel=1e-3)
    assert prep.capacity[-1] > prep.capacity[0]  # the self-motion climbed
    ratio = motion.capacity.min() / base.capacity.min()
    assert ratio >= 1.2
    assert result.summary()["min_capacity_ratio"] == pytest.approx(ratio)
    means = motion.capacity.mean() / base.capacity.mean()
    assert result.summary()["mean_capacity_ratio"] == pytest.approx(means, rel=1e-12)


def test_team_carry_figures_meet_the_paper_figures_standard(beam):
    """capacity.png and paths.png of a team carry (tests/figure_checks.py), the team named."""
    import matplotlib.pyplot as plt

    from figure_checks import check_paper_ready
    from mobmanip.viz.motion_figures import carry_figure, team_carry_figure

    team, _, result = beam
    for name, fig in (
        ("capacity.png", carry_figure(result, f"team {team.name}")),
        ("paths.png", team_carry_figure(result)),
    ):
        try:
            check_paper_ready(fig, name)
            assert team.name in fig.axes[0].get_title()
        finally:
            plt.close(fig)


def test_the_fast_kinematic_gradient_matches_the_stacked_terms_and_differences():
    team = load_team(TEAM)
    capacity = TeamCapacity(team, Objective.parse("kinematic:minor_axis", team.task))
    qs = [m.q for m in team.members]
    held = team.held_object
    value, grad = capacity.gradient(qs, held)
    assert value == pytest.approx(analyze_team(team, ["kinematic"]).measures["kinematic"].semi_axes.min())
    # a directional derivative along a combined motion of both robots, by larger central differences
    rng = np.random.default_rng(3)
    direction = rng.normal(size=team.nx)
    eps = 1e-4
    ends = []
    for sign in (1.0, -1.0):
        moved = [
            tangent_integrate(m.robot.model, q, m.robot.null_space(q) @ (sign * eps * direction[s]))
            for m, q, s in zip(team.members, qs, team.member_slices())
        ]
        ends.append(capacity.value(moved, held))
    assert (ends[0] - ends[1]) / (2 * eps) == pytest.approx(grad @ direction, rel=1e-5)


def test_bad_arguments_are_refused():
    team = load_team(TEAM)
    path = beam_path()
    for kwargs in ({"frame": "robot"}, {"step": 0.0}, {"gain": -1.0}, {"prepare": float("nan")}):
        with pytest.raises(ArgumentError):
            team_carry(team, path, **kwargs)
    with pytest.raises(ArgumentError):
        team_carry("beam", path)  # type: ignore[arg-type]


# ----- the command -----


def test_command_writes_one_trajectory_per_robot(tmp_path, capsys):
    short = tmp_path / "short.csv"
    path = read_path(EXAMPLES / "carry_turn.csv")
    rows = ["t,x,y"] + [f"{float(t)!r},{float(x)!r},{float(y)!r}" for t, (x, y) in zip(path.t[:21], path.xy[:21])]
    short.write_text("\n".join(rows) + "\n")
    out = tmp_path / "out"
    code = main(["team-carry", str(TEAM), "--path", str(short), "--scale", "2", "--prepare", "1", "--out", str(out)])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "min capacity ratio" in printed.out
    team = load_team(TEAM)
    summary = json.loads((out / "team_carry.json").read_text())
    assert summary["robots"] == ["south", "north"]
    for member in team.members:
        for kind in ("trajectory", "baseline", "preparation"):
            name = summary["files"][kind][member.name] if kind in summary["files"] else None
            assert name == f"{kind}_{member.name}.csv"
            trajectory = read_trajectory(member.robot, out / name)
            assert len(trajectory.t) >= 2
        motion = read_trajectory(member.robot, out / f"trajectory_{member.name}.csv")
        assert motion.t[0] == pytest.approx(0.0) and motion.t[-1] == pytest.approx(2.0)
    assert summary["qp"]["max_hand_error"] <= 1e-3
    assert (out / "capacity.png").stat().st_size > 0 and (out / "paths.png").stat().st_size > 0


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--scale", "-1"], "--scale"),
        (["--step", "0"], "--step"),
        (["--max-work", "10"], "robot-steps"),
        (["--objective", "kinematic:nothing"], "nothing"),
    ],
)
def test_command_refuses_bad_input_in_one_line(extra, words, tmp_path, capsys):
    code = main(["team-carry", str(TEAM), "--path", str(EXAMPLES / "carry_turn.csv"), *extra])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("mobmanip: error: ") and err.count("\n") == 1 and words in err


def test_command_refuses_an_unknown_frame(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["team-carry", str(TEAM), "--path", str(EXAMPLES / "carry_turn.csv"), "--frame", "robot"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.startswith("mobmanip: error: ") and "--frame" in err


def test_command_refuses_a_scale_beyond_the_supported_positions(tmp_path, capsys):
    far = tmp_path / "far.csv"
    far.write_text("t,x,y\n0,0,0\n1,900000,0\n")
    code = main(["team-carry", str(TEAM), "--path", str(far), "--scale", "1000"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("mobmanip: error: --scale 1000") and err.count("\n") == 1


def test_command_refuses_a_missing_path(tmp_path, capsys):
    code = main(["team-carry", str(TEAM), "--path", str(tmp_path / "nowhere.csv")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("mobmanip: error: ") and err.count("\n") == 1


def test_a_failing_carry_names_the_robot_and_joint_and_keeps_what_succeeded(tmp_path, capsys):
    """The unscaled turn (radius 1.27 m, tighter than the 3.4 m team) cannot be followed."""
    out = tmp_path / "out"
    code = main(["team-carry", str(TEAM), "--path", str(EXAMPLES / "carry_turn.csv"), "--prepare", "0",
                 "--out", str(out)])  # fmt: skip
    printed = capsys.readouterr()
    assert code == 2
    assert printed.err.startswith("mobmanip: error: the team's carry QP has no solution")
    assert printed.err.count("\n") == 1
    summary = json.loads((out / "team_carry.json").read_text())
    assert summary["partial"] is True and 0.0 < summary["completed_until"] < 12.0
    assert (out / "trajectory_south.csv").is_file() and (out / "trajectory_north.csv").is_file()
