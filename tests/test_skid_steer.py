"""The skid-steer platform kind on a real foreign robot: Clearpath's Husky (as shipped in
pybullet's data) carrying a KUKA iiwa attached by a fixed joint.

Checked independently of the kind's own code: the constraints A(q) written here from the wheel
geometry annihilate S; S does not change along motions (finite differences through
``pin.integrate``); the kinetic energy; J_u against central differences; and the unified
Jacobian's platform columns (and so the kinematic ellipsoid) against a hand derivation of the
instantaneous-centre model.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mobmanip.errors import MissingLimitError, WheelError
from mobmanip.robot.detect import detect_spec, spec_to_toml

pybullet_data = pytest.importorskip("pybullet_data", reason="the Husky and iiwa URDFs ship with pybullet")

DATA = Path(pybullet_data.getDataPath())
RADIUS = 0.17775  # Husky's wheel collision cylinder
WHEELS = {"front_left_wheel": (0.256, 0.2854), "front_right_wheel": (0.256, -0.2854),
          "rear_left_wheel": (-0.256, 0.2854), "rear_right_wheel": (-0.256, -0.2854)}  # fmt: skip
IIWA_JOINTS = [f"lbr_iiwa_joint_{k}" for k in range(1, 8)]
EE = "lbr_iiwa_link_7"
SIDE_SPEED = 1.0 / RADIUS  # rad/s: 1 m/s at the rim
SIDE_TORQUE = 80.0


def husky_with_arm(directory: Path, wheel_limits: dict[str, tuple[float, float]] | None = None) -> Path:
    """Husky's URDF with the iiwa (its links, joints and materials) bolted onto the top plate.

    ``wheel_limits`` adds ``<limit velocity effort>`` to named wheel joints (the Husky has none).
    """
    husky = (DATA / "husky" / "husky.urdf").read_text()
    iiwa = (DATA / "kuka_iiwa" / "model.urdf").read_text()
    body = iiwa[iiwa.index(">", iiwa.index("<robot")) + 1 : iiwa.rindex("</robot>")]
    body = re.sub(r'<material name="(\w+)">.*?</material>', "", body, flags=re.S)  # Husky defines its own
    body = body.replace('filename="meshes/', 'filename="iiwa_meshes/')
    mount = (
        '<joint name="arm_mount" type="fixed"><parent link="top_plate_link"/><child link="lbr_iiwa_link_0"/>'
        '<origin xyz="0.15 0 0.01" rpy="0 0 0"/></joint>'
    )
    text = husky.replace("</robot>", body + mount + "</robot>")
    text = text.replace('filename="meshes/', 'filename="husky_meshes/')
    # the meshes travel with the URDF: the viewer reads meshes only inside the robot's package
    for name, source in (("husky_meshes", DATA / "husky" / "meshes"), ("iiwa_meshes", DATA / "kuka_iiwa" / "meshes")):
        if not (directory / name).exists():
            shutil.copytree(source, directory / name)
    for joint, (velocity, effort) in (wheel_limits or {}).items():
        pattern = rf'(<joint name="{joint}" type="continuous">)'
        text, count = re.subn(pattern, rf'\1<limit velocity="{velocity}" effort="{effort}"/>', text)
        assert count == 1, joint
    path = directory / "husky_iiwa.urdf"
    path.write_text(text)
    return path


def spec_text(urdf: Path) -> str:
    return f"""
name = "husky_iiwa"
urdf = "{urdf.name}"
platform = "skid_steer"
default_task = "translational"
[wheels]
right = ["front_right_wheel", "rear_right_wheel"]
left = ["front_left_wheel", "rear_left_wheel"]
[[arms]]
name = "arm"
joints = {IIWA_JOINTS!r}
end_effector = "{EE}"
[limits.velocity]
right_side = {SIDE_SPEED!r}
left_side = {SIDE_SPEED!r}
[limits.effort]
right_side = {SIDE_TORQUE!r}
left_side = {SIDE_TORQUE!r}
""".replace("'", '"')


@pytest.fixture(scope="module")
def husky_spec(tmp_path_factory) -> Path:
    directory = tmp_path_factory.mktemp("husky")
    urdf = husky_with_arm(directory)
    spec = directory / "husky_iiwa.toml"
    spec.write_text(spec_text(urdf))
    return spec


@pytest.fixture(scope="module")
def husky(husky_spec):
    return mobmanip.load_robot(husky_spec)


def random_q(robot, rng):
    q = pin.randomConfiguration(robot.model, *_finite_bounds(robot.model))
    yaw = rng.uniform(-math.pi, math.pi)
    q[:4] = (*rng.uniform(-2, 2, size=2), math.cos(yaw), math.sin(yaw))
    return q


def _finite_bounds(model):
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    lower[~np.isfinite(lower)] = -1.0
    upper[~np.isfinite(upper)] = 1.0
    return lower, upper


def constraint_matrix(robot, q) -> np.ndarray:
    """A(q) of the skid-steer model, written from the URDF's wheel positions (Pinocchio's tangent
    space, platform-frame base velocity): no lateral velocity at the wheels' centroid; the wheels
    of a side turn together; each side's wheels roll at the speed of the platform's track line
    b = the sides' half distance from the centroid."""
    model = robot.model
    nv = model.nv
    centroid = np.mean(list(WHEELS.values()), axis=0)
    b = 0.2854
    rows = []
    lateral = np.zeros(nv)
    lateral[[1, 2]] = (1.0, centroid[0])  # v_y + omega x_c = 0
    rows.append(lateral)
    v = {name: model.joints[model.getJointId(name)].idx_v for name in WHEELS}
    for front, rear in (("front_right_wheel", "rear_right_wheel"), ("front_left_wheel", "rear_left_wheel")):
        same = np.zeros(nv)
        same[v[front]], same[v[rear]] = 1.0, -1.0  # all Husky wheel axes are +y
        rows.append(same)
    for wheel, y in (("front_right_wheel", centroid[1] - b), ("front_left_wheel", centroid[1] + b)):
        rolling = np.zeros(nv)
        rolling[[0, 2]] = (1.0, -y)  # forward speed of the track line at lateral position y
        rolling[v[wheel]] = -RADIUS
        rows.append(rolling)
    return np.array(rows)


def test_husky_spec_loads_with_per_side_limits(husky):
    assert husky.platform.kind == "skid_steer"
    assert husky.reduced_velocity_names[:2] == ("right_side", "left_side")
    assert husky.nx == 2 + 7
    np.testing.assert_allclose(husky.velocity_limits[:2], SIDE_SPEED)
    np.testing.assert_allclose(husky.effort_limits[:2], SIDE_TORQUE)
    assert husky.platform.radius == pytest.approx(RADIUS, abs=1e-12)
    assert husky.platform.half_track == pytest.approx(0.2854, abs=1e-12)
    np.testing.assert_allclose(husky.platform.center, (0.0, 0.0), atol=1e-12)


def test_a_wheel_limit_reaches_each_side_as_its_wheels_give_it(husky):
    """--wheel-velocity-limit / --wheel-effort-limit are each wheel's: a side of two wheels geared
    together turns at their rate and pushes with both torques (the Husky's sides: two wheels each)."""
    limited = husky.with_wheel_limits(velocity=3.0, effort=5.0)
    np.testing.assert_allclose(limited.velocity_limits[:2], (3.0, 3.0))
    np.testing.assert_allclose(limited.effort_limits[:2], (2 * 5.0, 2 * 5.0))
    np.testing.assert_array_equal(limited.effort_limits[2:], husky.effort_limits[2:])  # the arm's are its own


def test_the_wheel_limit_flags_reach_each_side(husky, husky_spec, tmp_path, capsys):
    """``analyze --wheel-velocity-limit 3 --wheel-effort-limit 5`` on the Husky (issue 39: the flags
    did not reach its sides): each side turns at 3 rad/s and pushes with its two wheels' 10 N m,
    and the kinematic ellipsoid is the one of those limits."""
    import json

    from mobmanip.cli import main

    out = tmp_path / "a.json"
    argv = ["analyze", str(husky_spec), "--wheel-velocity-limit", "3", "--wheel-effort-limit", "5", "--json", str(out)]
    assert main(argv) == 0
    capsys.readouterr()
    doc = json.loads(out.read_text())
    np.testing.assert_allclose(doc["velocity_limits"][:2], (3.0, 3.0), rtol=1e-15)
    np.testing.assert_allclose(doc["effort_limits"][:2], (10.0, 10.0), rtol=1e-15)
    np.testing.assert_allclose(doc["velocity_limits"][2:], husky.velocity_limits[2:], rtol=1e-15)
    # the velocity ellipsoid of those limits: J_u diag(limits) mapped onto the unit ball, from the JSON's J_u
    J = np.asarray(doc["unified_jacobian"], dtype=float) * np.r_[3.0, 3.0, husky.velocity_limits[2:]]
    singular = np.linalg.svd(J, compute_uv=False)  # descending, the task's rows (a zero: a direction it cannot move)
    np.testing.assert_allclose(doc["kinematic_ellipsoid"]["semi_axes"], singular, rtol=1e-9, atol=1e-9)


def test_constraints_annihilate_s_and_s_spans_their_null_space(husky, rng):
    for _ in range(5):
        q = random_q(husky, rng)
        S = husky.null_space(q)
        A = constraint_matrix(husky, q)
        np.testing.assert_allclose(A @ S, 0.0, atol=1e-12)
        platform_coords = [0, 1, 2] + [husky.model.joints[husky.model.getJointId(n)].idx_v for n in WHEELS]
        A_platform = A[:, platform_coords]
        assert np.linalg.matrix_rank(A_platform) + husky.platform.n_reduced == len(platform_coords)
        assert np.linalg.matrix_rank(S[platform_coords][:, :2]) == 2


def test_s_is_constant_along_motions_and_sdot_is_zero(husky, rng):
    q = random_q(husky, rng)
    x = rng.normal(size=husky.nx)
    h = 1e-6
    plus = husky.null_space(pin.integrate(husky.model, q, husky.null_space(q) @ x * h))
    minus = husky.null_space(pin.integrate(husky.model, q, -husky.null_space(q) @ x * h))
    np.testing.assert_allclose((plus - minus) / (2 * h), husky.null_space_rate(q, x), atol=1e-9)
    np.testing.assert_array_equal(husky.null_space_rate(q, x), 0.0)
    # Robot.null_space returns its cached S for a kind that says it does not vary with q, so the
    # difference above is of a constant; the kind's own block, evaluated at each configuration,
    # must not change along the motion (else the cache and Sdot = 0 would be wrong) ...
    assert not husky.platform.varies_with_q
    v = husky.null_space(q) @ x
    for step in (h, 0.3, 1.7):
        for sign in (1.0, -1.0):
            moved = pin.integrate(husky.model, q, sign * step * v)
            rows, block = husky.platform.tangent_block(moved)
            np.testing.assert_allclose(block, husky.platform.tangent_block(q)[1], atol=1e-12)
            # ... and the cached S satisfies the wheels' constraints there, from the geometry
            np.testing.assert_allclose(constraint_matrix(husky, moved) @ husky.null_space(moved), 0.0, atol=1e-12)


def test_kinetic_energy_of_the_reduced_inertia(husky, rng):
    for _ in range(5):
        q, x = random_q(husky, rng), rng.normal(size=husky.nx)
        P = mobmanip.reduced_dynamics(husky, q).P
        energy = pin.computeKineticEnergy(husky.model, husky.data, q, husky.null_space(q) @ x)
        assert 0.5 * x @ P @ x == pytest.approx(energy, rel=1e-12)


def test_unified_jacobian_against_central_differences(husky, rng):
    for _ in range(3):
        q, x = random_q(husky, rng), rng.normal(size=husky.nx)
        J_u = mobmanip.unified_jacobian(husky, q, "translational")
        h = 1e-6
        v = husky.null_space(q) @ x
        plus, minus = pin.integrate(husky.model, q, v * h), pin.integrate(husky.model, q, -v * h)
        numeric = (position(husky, plus) - position(husky, minus)) / (2 * h)
        np.testing.assert_allclose(J_u @ x, numeric, atol=1e-7)


def position(robot, q, frame: str = EE) -> np.ndarray:
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return robot.data.oMf[robot.frame_id(frame)].translation.copy()


def hand_platform_columns(q, p_ee) -> np.ndarray:
    """World velocity of a point of the platform per unit side rate, by hand: the centroid
    (here the platform origin) moves forward at r/2 (eta_r + eta_l), the platform turns at
    r/(2b) (eta_r - eta_l)."""
    yaw = math.atan2(q[3], q[2])
    heading = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    arm = p_ee - np.array([q[0], q[1], 0.0])
    turning = np.cross([0.0, 0.0, 1.0], arm)
    c = RADIUS / (2 * 0.2854)
    return np.column_stack([RADIUS / 2 * heading + c * turning, RADIUS / 2 * heading - c * turning])


def test_kinematic_ellipsoid_platform_contribution_is_the_hand_derived_skid_steer(husky, rng):
    for _ in range(3):
        q = random_q(husky, rng)
        result = mobmanip.analyze(husky, q, task="translational")
        p_ee = result.end_effector_positions[0]
        hand = hand_platform_columns(q, p_ee)
        np.testing.assert_allclose(result.unified_jacobian[:, :2], hand, atol=1e-12)
        # The arm's columns from a plain frame Jacobian; the ellipsoid from the hand-built J_u: one
        # hand (W = I), J_hat = J_u diag(qdot_max) of full row rank, so the set is v^T (J_hat
        # J_hat^T)^-1 v <= 1 and its semi-axes are J_hat's singular values.
        pin.computeJointJacobians(husky.model, husky.data, q)
        pin.updateFramePlacements(husky.model, husky.data)
        J = pin.getFrameJacobian(husky.model, husky.data, husky.frame_id(EE), pin.LOCAL_WORLD_ALIGNED)[:3]
        arm_columns = J[:, [husky.model.joints[husky.model.getJointId(n)].idx_v for n in IIWA_JOINTS]]
        J_hat = np.hstack([hand, arm_columns]) * husky.velocity_limits
        np.testing.assert_array_equal(result.grasp_matrix, np.eye(3))
        semi_axes = np.linalg.svd(J_hat, compute_uv=False)
        scale = semi_axes[0]
        np.testing.assert_allclose(result.kinematic.semi_axes, semi_axes, rtol=0, atol=1e-10 * scale)
        matrix = np.linalg.inv(J_hat @ J_hat.T)
        np.testing.assert_allclose(result.kinematic.matrix * scale**2, matrix * scale**2, atol=1e-8)
        locked = mobmanip.analyze(husky.with_platform("fixed"), q, task="translational")
        assert result.kinematic.semi_axes[0] > locked.kinematic.semi_axes[0]


def test_side_limits_come_from_the_slowest_wheel_and_the_summed_torque(tmp_path):
    limits = {"front_right_wheel": (9.0, 30.0), "rear_right_wheel": (7.0, 25.0),
              "front_left_wheel": (8.0, 20.0), "rear_left_wheel": (8.5, 20.0)}  # fmt: skip
    urdf = husky_with_arm(tmp_path, limits)
    text = re.sub(r"\[limits.velocity\].*", "", spec_text(urdf), flags=re.S)
    spec = tmp_path / "husky.toml"
    spec.write_text(text)
    robot = mobmanip.load_robot(spec)
    np.testing.assert_array_equal(robot.velocity_limits[:2], (7.0, 8.0))
    np.testing.assert_array_equal(robot.effort_limits[:2], (55.0, 40.0))
    # Q = S^T B = I: each side's torque is shared by its wheels.
    np.testing.assert_allclose(robot.Q, np.eye(robot.nx), atol=1e-15)


def test_init_spec_detects_the_husky_as_skid_steer_and_names_the_missing_limits(tmp_path):
    urdf = husky_with_arm(tmp_path)
    found = detect_spec(urdf, [EE])
    spec = found.spec
    assert spec.platform == "skid_steer"
    assert spec.wheels.right == ("front_right_wheel", "rear_right_wheel")
    assert spec.wheels.left == ("front_left_wheel", "rear_left_wheel")
    assert spec.arms[0].joints == tuple(IIWA_JOINTS)
    assert any("needs limits for right_side, left_side" in note for note in found.notes)
    text = spec_to_toml(spec, tmp_path, notes=found.notes, urdf_limits=found.urdf_limits)
    assert "# right_side = ...  # REQUIRED: the URDF gives none" in text
    written = tmp_path / "detected.toml"
    written.write_text(text)
    with pytest.raises(MissingLimitError, match=r"right_side.*\[limits.velocity\]"):
        mobmanip.load_robot(written)
    completed = text.replace("# right_side = ...  # REQUIRED: the URDF gives none", "right_side = 5.0", 1)
    completed = completed.replace("# left_side = ...  # REQUIRED: the URDF gives none", "left_side = 5.0", 1)
    completed = completed.replace("# right_side = ...  # REQUIRED: the URDF gives none", "right_side = 60.0", 1)
    completed = completed.replace("# left_side = ...  # REQUIRED: the URDF gives none", "left_side = 60.0", 1)
    written.write_text(completed)
    robot = mobmanip.load_robot(written)
    assert robot.platform.kind == "skid_steer"
    np.testing.assert_array_equal(robot.velocity_limits[:2], 5.0)
    np.testing.assert_array_equal(robot.effort_limits[:2], 60.0)


def test_init_spec_command_on_the_husky(tmp_path):
    urdf = husky_with_arm(tmp_path)
    out = tmp_path / "husky.toml"
    done = subprocess.run(
        [sys.executable, "-m", "mobmanip", "init-spec", str(urdf), "--ee", EE, "--out", str(out)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert "skid_steer" in done.stdout
    assert 'platform = "skid_steer"' in out.read_text()


def test_the_viewer_builds_the_husky_with_its_meshes(husky):
    """The viewer reads the URDF as the loader does ($(optenv ...) at its default) and finds the
    meshes of both the Husky and the iiwa."""
    from mobmanip.viz.scene import visual_model

    model, geometry = visual_model(husky)
    assert list(model.names) == list(husky.model.names)
    meshes = {Path(g.meshPath).name for g in geometry.geometryObjects if g.meshPath}
    assert {"wheel.stl", "base_link.stl"} <= meshes
    assert any(name.startswith("link_") for name in meshes)


def test_wheels_on_the_command_line_are_a_differential_drive_pair_only(tmp_path):
    urdf = husky_with_arm(tmp_path)
    with pytest.raises(WheelError, match=r"give a skid_steer platform's wheels in its spec's \[wheels\] table"):
        detect_spec(urdf, [EE], wheels=("front_right_wheel", "front_left_wheel"), platform="skid_steer")
