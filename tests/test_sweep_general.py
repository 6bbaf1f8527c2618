"""Sweeps for any robot: inverse-kinematics postures, checked by forward kinematics and against analyze."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.analysis import analyze
from mobmanip.cli import main
from mobmanip.commands.outputs import write_sweep_npz
from mobmanip.postures.inverse_kinematics import POSITION_TOLERANCE, rotation_log, solve_postures
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep, sweep_configurations
from mobmanip.sweep.runner import UnreachableGridError

#: TIAGo++ holding a box of about 0.26 m between its hands, 0.44 m in front of the shoulders at
#: 0.87 m height (the same joint values on both arms give mirrored postures).
TIAGO_HOLD = dict(
    zip(
        [f"arm_{side}_{i}_joint" for side in ("right", "left") for i in range(1, 8)],
        [0.93, 0.27, 1.33, 1.91, 0.17, -0.31, 2.01] * 2,
    )
)


def rz(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def placements(robot, q):
    """(positions (k, 3), rotations (k, 3, 3), first joints' positions (k, 3)) at q."""
    pin.framesForwardKinematics(robot.model, robot.data, q)
    frames = [robot.data.oMf[arm.frame_id] for arm in robot.arms]
    firsts = [robot.data.oMi[robot.model.getJointId(arm.joint_names[0])].translation for arm in robot.arms]
    return (
        np.array([f.translation for f in frames]),
        np.array([f.rotation for f in frames]),
        np.array(firsts),
    )


def expected_targets(robot, q_ref, angle_deg, distance):
    """End-effector targets of the documented hold, computed from forward kinematics alone."""
    points, _, firsts = placements(robot, q_ref)
    centre = points.mean(axis=0)
    origin = firsts[:, :2].mean(axis=0)
    alpha = math.radians(angle_deg)
    c = np.array([origin[0] + distance * math.cos(alpha), origin[1] + distance * math.sin(alpha), centre[2]])
    return c + (points - centre) @ rz(alpha).T


def joint_limits(robot, names):
    model = robot.model
    idx = [model.joints[model.getJointId(n)].idx_q for n in names]
    return model.lowerPositionLimit[idx], model.upperPositionLimit[idx]


# ----- the inverse kinematics itself -----


def test_log3_matches_pinocchio(rng):
    angles = np.concatenate([rng.uniform(0.0, math.pi, 200), [0.0, 1e-9, math.pi - 1e-3, math.pi - 1e-6, math.pi]])
    axes = rng.normal(size=(len(angles), 3))
    rotations = np.array([pin.exp3(t * a / np.linalg.norm(a)) for t, a in zip(angles, axes)])
    ours = rotation_log(rotations)
    for omega, R in zip(ours, rotations):  # a half turn has two logs; compare through exp
        np.testing.assert_allclose(pin.exp3(omega), R, atol=1e-12)
    reference = np.array([pin.log3(R) for R in rotations[:-1]])
    np.testing.assert_allclose(ours[:-1], reference, atol=1e-11)


def test_tiago_postures_put_every_hand_on_its_target(tiago):
    """Forward kinematics of every solved posture: each hand at the object centre plus its
    grasp offset turned by the angle, joints within limits; out of reach: NaN."""
    q_ref = tiago.configuration(joints=TIAGO_HOLD)
    angles, distances = [-20.0, 0.0, 20.0], [0.4, 0.5, 0.6, 1.2]
    table = solve_postures(tiago, angles, distances, q_ref)
    assert table.reachable[:, :3].all() and not table.reachable[:, 3].any()
    assert np.isnan(table.joints[:, 3]).all() and (table.position_error[:, 3] > 0.1).all()
    lower, upper = joint_limits(tiago, table.joint_names)
    for ia, angle in enumerate(angles):
        for idist, distance in enumerate(distances[:3]):
            joints = table.joints[ia, idist]
            assert np.all(joints >= lower) and np.all(joints <= upper)
            q = tiago.configuration(joints={**TIAGO_HOLD, **dict(zip(table.joint_names, joints))})
            points, rotations, _ = placements(tiago, q)
            target = expected_targets(tiago, q_ref, angle, distance)
            assert np.max(np.linalg.norm(points - target, axis=1)) <= POSITION_TOLERANCE
            # the orientation left over is the reported one
            _, ref_rotations, _ = placements(tiago, q_ref)
            turned = rz(math.radians(angle)) @ ref_rotations
            left_over = max(np.linalg.norm(pin.log3(R.T @ R1)) for R, R1 in zip(rotations, turned))
            assert left_over == pytest.approx(table.rotation_error[ia, idist], abs=1e-9)
    # near the reference hold the hands keep its orientation, turned with the object
    assert np.all(table.rotation_error[:, 1] < 1e-6)
    # torso and every joint outside the arms stay at the reference posture
    q = sweep_configurations(tiago, SweepGrid(angles, distances), table, np.array([0]))[0][0]
    arm_q = [tiago.model.joints[tiago.model.getJointId(n)].idx_q for n in table.joint_names]
    others = np.setdiff1d(np.arange(4, tiago.model.nq), arm_q)
    np.testing.assert_array_equal(q[others], q_ref[others])


def test_planar_robot_ik_reaches_the_closed_form_objects(robot):
    """The general IK on the paper's robot: other joint angles than the closed form, the same
    end-effector positions (the object), and the same reach."""
    grid = SweepGrid(angle_deg=[0.0, 45.0, 90.0, 200.0], distance=[0.35, 0.8, 1.3, 1.6], heading_deg=[0.0, 30.0])
    spec = SweepSpec("planar_dual_arm", task="planar")
    closed = run_sweep(spec, grid, workers=1)
    general = run_sweep(SweepSpec("planar_dual_arm", task="planar", postures="ik"), grid, workers=1)
    assert closed.postures.method == "planar" and general.postures.method == "ik"
    np.testing.assert_array_equal(general.reachable, closed.reachable)
    assert closed.reachable[:, :3].all() and not closed.reachable[:, 3].any()
    flat = np.flatnonzero(closed.reachable.ravel())
    q_closed, _ = sweep_configurations(robot, grid, closed.postures, flat)
    q_general, _ = sweep_configurations(robot, grid, general.postures, flat)
    moved = 0.0
    for a, b in zip(q_closed, q_general):
        pa, _, _ = placements(robot, a)
        pb, _, _ = placements(robot, b)
        np.testing.assert_allclose(pb, pa, rtol=0, atol=2 * POSITION_TOLERANCE)
        moved = max(moved, float(np.max(np.abs(a - b))))
    assert moved > 0.1  # genuinely different postures
    assert np.isnan(general.index("kinematic.volume")[:, 3]).all()


def test_rotation_about_a_vertical_first_joint_only_turns_the_arm():
    """UR5: its first joint is vertical through the reference point, so the posture at angle
    alpha is the one at 0 with that joint turned by alpha, and the indices do not change."""
    grid = SweepGrid(angle_deg=[-60.0, 0.0, 60.0, 120.0], distance=[0.4, 0.6])
    result = run_sweep(SweepSpec("ur5"), grid, workers=1)
    assert result.reachable.all()
    names, joints = result.joint_positions()
    assert names[0] == "shoulder_pan_joint"
    turn = (joints[:, :, 0] - joints[1:2, :, 0]) - np.radians(grid.angle_deg)[:, None]
    np.testing.assert_allclose((turn + math.pi) % (2 * math.pi) - math.pi, 0.0, atol=1e-6)
    np.testing.assert_allclose(joints[:, :, 1:], np.broadcast_to(joints[1:2, :, 1:], joints[:, :, 1:].shape), atol=1e-6)
    for kind in ("kinematic", "dynamic"):
        volume = result.index(f"{kind}.volume")[:, :, 0, 0, 0]
        np.testing.assert_allclose(volume, np.broadcast_to(volume[1:2], volume.shape), rtol=1e-5)


def test_single_arm_end_effector_is_the_object():
    """Panda: the hand itself is the task point, at distance d from the first joint, at the
    home hand's height; neighbouring grid points get neighbouring postures."""
    panda = mobmanip.load_robot("panda")
    angles, distances = np.arange(0.0, 41.0, 10.0), np.arange(0.3, 0.61, 0.1)
    table = solve_postures(panda, angles, distances)
    assert table.reachable.all()
    np.testing.assert_array_equal(table.hold.offsets, 0.0)
    home, _, firsts = placements(panda, panda.neutral())
    for ia, angle in enumerate(angles):
        for idist, distance in enumerate(distances):
            q = panda.configuration(joints=dict(zip(table.joint_names, table.joints[ia, idist])))
            hand, _, _ = placements(panda, q)
            alpha = math.radians(angle)
            target = [firsts[0, 0] + distance * math.cos(alpha), firsts[0, 1] + distance * math.sin(alpha), home[0, 2]]
            assert np.linalg.norm(hand[0] - target) <= POSITION_TOLERANCE
    # continuity: 10 deg or 0.1 m between neighbours moves no joint by more than 0.5 rad
    assert np.max(np.abs(np.diff(table.joints, axis=0))) < 0.5
    assert np.max(np.abs(np.diff(table.joints, axis=1))) < 0.5


# ----- sweeps -----


def test_tiago_sweep_equals_analyze_batch_and_analyze(tiago):
    """A small TIAGo++ sweep against analyze_batch and analyze at configurations rebuilt from
    the saved joint positions, on variant robots for the limit scales."""
    grid = SweepGrid(
        angle_deg=[-20.0, 0.0, 20.0],
        distance=[0.45, 0.55, 1.3],
        heading_deg=[0.0, 40.0],
        wheel_velocity_scale=[0.2, 1.0],
        wheel_effort_scale=[1.0, 0.3],
    )
    result = run_sweep(SweepSpec("tiago_dual", reference=TIAGO_HOLD), grid, workers=1)
    assert result.task == "spatial" and result.postures.method == "ik"
    assert result.reachable[:, :2].all() and not result.reachable[:, 2].any()
    assert np.isnan(result.index("dynamic.volume")[:, 2]).all()
    names, joints = result.joint_positions()
    v0, e0 = tiago.velocity_limits[0], tiago.effort_limits[0]
    points = [(ia, idist, ih) for ia in range(3) for idist in range(2) for ih in range(2)]
    qs = np.array(
        [
            tiago.configuration(
                (0.0, 0.0, math.radians(grid.heading_deg[ih])),
                {**TIAGO_HOLD, **dict(zip(names, joints[ia, idist]))},
            )
            for ia, idist, ih in points
        ]
    )
    for iv, vs in enumerate(grid.wheel_velocity_scale):
        for ie, es in enumerate(grid.wheel_effort_scale):
            variant = tiago.with_wheel_limits(velocity=vs * v0, effort=es * e0)
            batch = mobmanip.analyze_batch(variant, qs)
            for row, (ia, idist, ih) in enumerate(points):
                at = (ia, idist, ih, iv, ie)
                phi = math.radians(grid.angle_deg[ia] + grid.heading_deg[ih])
                radial = np.array([math.cos(phi), math.sin(phi), 0.0, 0.0, 0.0, 0.0])
                for kind in ("kinematic", "dynamic"):
                    e = getattr(batch, kind)
                    scale = e.semi_axes[row, 0]
                    got = result.indices[f"{kind}_semi_axes"][at]
                    np.testing.assert_allclose(got, e.semi_axes[row], rtol=0, atol=1e-10 * scale)
                    assert result.index(f"{kind}.volume")[at] == pytest.approx(e.volume[row], rel=1e-9)
                    capacity = result.index(f"{kind}.capacity")[at]
                    assert capacity == pytest.approx(e.support(radial[None])[row], abs=1e-10 * scale)
    single = analyze(tiago.with_wheel_limits(velocity=0.2 * v0, effort=0.3 * e0), qs[5])
    ia, idist, ih = points[5]
    for kind in ("kinematic", "dynamic"):
        e = getattr(single, kind)
        got = result.indices[f"{kind}_semi_axes"][ia, idist, ih, 0, 1]
        np.testing.assert_allclose(got, e.semi_axes, rtol=0, atol=1e-9 * e.semi_axes[0])
    # the object the analysis holds is where the grid point puts it
    centre = single.held_object.center
    alpha = math.radians(grid.angle_deg[ia] + grid.heading_deg[ih])
    origin = rz(math.radians(grid.heading_deg[ih])) @ np.append(result.postures.hold.origin, 0.0)
    expected = origin[:2] + grid.distance[idist] * np.array([math.cos(alpha), math.sin(alpha)])
    np.testing.assert_allclose(centre[:2], expected, atol=2 * POSITION_TOLERANCE)
    assert centre[2] == pytest.approx(result.postures.hold.height, abs=2 * POSITION_TOLERANCE)


def test_chunks_and_processes_do_not_change_an_ik_sweep():
    """Each chunk gets its own rows of the posture table: any chunking, same results."""
    grid = SweepGrid(angle_deg=[-30.0, 0.0, 30.0, 150.0], distance=[0.3, 0.5, 0.9], heading_deg=[0.0, 90.0, 200.0])
    spec = SweepSpec("panda")
    whole = run_sweep(spec, grid, workers=1)
    pieces = run_sweep(spec, grid, workers=2, chunk_size=4)
    np.testing.assert_array_equal(pieces.reachable, whole.reachable)
    assert whole.reachable.any() and not whole.reachable.all()
    for key in whole.indices:
        np.testing.assert_allclose(pieces.indices[key], whole.indices[key], rtol=1e-12, atol=0, err_msg=key)


def test_no_reachable_point_is_one_error_naming_the_grid(tiago, tmp_path, capsys):
    # As reference, TIAGo's home posture (an empty one) holds its hands 1.97 m apart, arms
    # stretched sideways: nothing else fits
    home = SweepSpec("tiago_dual", reference={})
    with pytest.raises(UnreachableGridError, match=r"distance 0\.5 m, angle 0 deg.*1\.97 m apart"):
        run_sweep(home, SweepGrid(angle_deg=[0.0], distance=[0.5]), workers=1)
    with pytest.raises(UnreachableGridError, match=r"distance 2, 3 m .* reach 1\.5 m at most"):
        run_sweep(SweepSpec("planar_dual_arm"), SweepGrid(angle_deg=[0.0], distance=[2.0, 3.0]), workers=1)
    code = main(["sweep", "ur5", "--angle", "0", "--distance", "3", "--no-progress", "-o", str(tmp_path / "u")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "distance 3 m" in err


@pytest.mark.parametrize("name", ["tiago_dual", "tiago_dual_torso"])
def test_tiago_hold_posture_holds_a_box_between_facing_hands(name):
    """The spec's [hold]: within the joint ranges, tool frames 0.30 m apart at one height, each
    approach (x) axis pointing at the other hand, in front of the platform."""
    robot = mobmanip.load_robot(name)
    names = list(robot.spec.hold)
    assert sorted(names) == sorted(n for arm in robot.arms for n in arm.joint_names)
    values = np.array([robot.spec.hold[n] for n in names])
    lower, upper = joint_limits(robot, names)
    assert (lower < values).all() and (values < upper).all()
    points, rotations, _ = placements(robot, robot.hold_configuration())
    between = points[1] - points[0]
    assert np.linalg.norm(between) == pytest.approx(0.30, abs=1e-3)
    assert abs(between[2]) < 1e-3 and (points[:, 0] > 0.5).all()
    for a, toward in ((0, between), (1, -between)):
        assert rotations[a][:, 0] @ toward / np.linalg.norm(toward) > 1.0 - 1e-6


def test_sweeps_start_from_the_spec_hold(tiago):
    """Without a reference posture, a TIAGo++ sweep holds the object as the spec's [hold] does:
    the same as passing that posture explicitly, and in reach around it."""
    grid = SweepGrid(angle_deg=[-20.0, 0.0, 20.0], distance=[0.45, 0.6, 1.3])
    default = run_sweep(SweepSpec("tiago_dual"), grid, workers=1)
    explicit = run_sweep(SweepSpec("tiago_dual", reference=dict(tiago.spec.hold)), grid, workers=1)
    np.testing.assert_array_equal(default.postures.reference, tiago.hold_configuration())
    np.testing.assert_array_equal(default.reachable, explicit.reachable)
    assert default.reachable[:, :2].all() and not default.reachable[:, 2].any()
    for key in default.indices:
        np.testing.assert_array_equal(default.indices[key], explicit.indices[key], err_msg=key)
    # the hold's own object: 0.55 m ahead of base_footprint, the arms' reference point at x = -0.036 m
    points, _, firsts = placements(tiago, tiago.hold_configuration())
    assert default.postures.hold.height == pytest.approx(points[:, 2].mean(), abs=1e-12)
    assert np.linalg.norm(points.mean(axis=0)[:2] - firsts[:, :2].mean(axis=0)) == pytest.approx(0.586, abs=2e-3)


def test_bad_posture_settings():
    grid = SweepGrid(angle_deg=[0.0], distance=[0.5])
    with pytest.raises(mobmanip.errors.ArgumentError, match="postures must be one of"):
        run_sweep(SweepSpec("ur5", postures="closed"), grid, workers=1)
    with pytest.raises(mobmanip.errors.ArgumentError, match="reference posture needs postures 'ik'"):
        run_sweep(SweepSpec("planar_dual_arm", postures="planar", reference={"arm_right_2_joint": 1.0}), grid)
    with pytest.raises(mobmanip.errors.JointNotFoundError, match="elbow"):
        run_sweep(SweepSpec("ur5", reference={"elbow": 1.0}), grid, workers=1)


def test_cli_ik_sweep_writes_postures(tmp_path, capsys):
    hold = tmp_path / "hold.json"
    hold.write_text('{"joints": ' + str(TIAGO_HOLD).replace("'", '"') + "}")
    out = tmp_path / "tiago"
    args = ["sweep", "tiago_dual", "--reference", str(hold), "--angle=-10,10", "--distance", "0.5,1.4"]
    code = main([*args, "--workers", "1", "--no-progress", "--no-csv", "-o", str(out)])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "postures by inverse kinematics" in printed.out and "2 of 4 (angle, distance) points in reach" in printed.out
    data = np.load(out / "sweep.npz")
    assert str(data["meta_postures"]) == "ik"
    assert data["posture_joints"].shape == (2, 2, 14) and len(data["posture_joint_names"]) == 14
    assert np.isfinite(data["posture_joints"][:, 0]).all() and np.isnan(data["posture_joints"][:, 1]).all()
    assert (data["posture_position_error"][:, 0] <= POSITION_TOLERANCE).all()
    assert data["hold_offsets"].shape == (2, 3) and data["hold_rotations"].shape == (2, 3, 3)
    assert "posture_right" not in data.files


def test_planar_npz_keeps_its_keys_and_adds_the_joint_positions(robot, tmp_path):
    grid = SweepGrid(angle_deg=[0.0, 120.0], distance=[0.9, 1.7])
    result = run_sweep(SweepSpec("planar_dual_arm"), grid, workers=1)
    data = np.load(write_sweep_npz(result, tmp_path / "p.npz"))
    assert str(data["meta_postures"]) == "planar"
    np.testing.assert_array_equal(data["posture_right"], result.postures.right)
    np.testing.assert_array_equal(data["posture_left"], result.postures.left)
    names, joints = [str(n) for n in data["posture_joint_names"]], data["posture_joints"]
    assert joints.shape == (2, 2, 6) and np.isnan(joints[:, 1]).all()
    for ia, angle in enumerate(grid.angle_deg):
        q = robot.configuration(joints=dict(zip(names, joints[ia, 0])))
        points, _, _ = placements(robot, q)
        radial = 0.9 * np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle))])
        np.testing.assert_allclose(points[:, :2], [radial, radial], atol=1e-12)
