"""Built-in robots beyond the paper's: TIAGo++ (with and without torso), UR5, Panda, and an
omnidirectional variant of the paper's robot.

Expected values come from the URDF files themselves (parsed here with ElementTree, not through
mobmanip) or from closed-form kinematics, never from mobmanip's own output.
"""

from __future__ import annotations

import math
import socket
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import configuration_within_limits
from mobmanip.descriptions.resources import example_robot_data_share
from mobmanip.errors import JointNotFoundError, LimitError, MissingLimitError, SpecError
from mobmanip.robot.spec import load_spec
from mobmanip.terms.dynamics import end_effector_positions, reduced_dynamics, unified_jacobian

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
PAPER_URDF = ROBOTS / "planar_dual_arm.urdf"
ERD_ROBOTS = example_robot_data_share() / "example-robot-data" / "robots"
TIAGO_URDF = ERD_ROBOTS / "tiago_description" / "robots" / "tiago_dual.urdf"

TIAGO_ARMS = [f"arm_{side}_{k}_joint" for side in ("right", "left") for k in range(1, 8)]
TIAGO_TOOLS = ("arm_right_tool_link", "arm_left_tool_link")

# Central differences with step H: truncation error ~ H^2 |d^3 p / dt^3| ~ 1e-10 for these
# robots' sub-metre links and unit-scale rates, round-off ~ eps |p| / H ~ 1e-11. A bound of
# 1e-7 (on Jacobian entries of order 0.1 .. 1) leaves a factor >100 over what is observed.
H = 1e-5
FD_ATOL = 1e-7


# ----- helpers -----


def _xml_joint(urdf: Path, name: str) -> ET.Element:
    joint = ET.parse(urdf).getroot().find(f"joint[@name='{name}']")
    assert joint is not None, name
    return joint


def _xml_limit(urdf: Path, name: str, attribute: str) -> float:
    return float(_xml_joint(urdf, name).find("limit").get(attribute))


def _xml_origin_xyz(urdf: Path, name: str) -> np.ndarray:
    return np.array([float(v) for v in _xml_joint(urdf, name).find("origin").get("xyz").split()])


def _xml_count_joints(urdf: Path, types=("revolute", "continuous", "prismatic"), prefix: str = "") -> int:
    root = ET.parse(urdf).getroot()
    return sum(1 for j in root.findall("joint") if j.get("type") in types and j.get("name").startswith(prefix))


def _tool_placements(robot, q):
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return [robot.data.oMf[arm.frame_id].copy() for arm in robot.arms]


def _finite_difference_twists(robot, q, x) -> np.ndarray:
    """Stacked (linear, angular) world-frame velocities of the tool frames along v = S x."""
    v = robot.S @ x
    plus = _tool_placements(robot, pin.integrate(robot.model, q, H * v))
    minus = _tool_placements(robot, pin.integrate(robot.model, q, -H * v))
    rows = []
    for p, m in zip(plus, minus):
        rows.append((p.translation - m.translation) / (2 * H))
        rows.append(pin.log3(p.rotation @ m.rotation.T) / (2 * H))  # world-frame rotation vector
    return np.concatenate(rows)


@pytest.fixture(scope="module")
def tiago_torso():
    return mobmanip.load_robot("tiago_dual_torso")


# ----- TIAGo++ -----


def test_tiago_loads_offline_from_example_robot_data(monkeypatch):
    def no_network(*args, **kwargs):
        raise AssertionError("loading a built-in robot must not open a network connection")

    monkeypatch.setattr(socket, "socket", no_network)
    monkeypatch.setattr(socket, "create_connection", no_network)
    robot = mobmanip.load_robot("tiago_dual")
    assert robot.spec.urdf == TIAGO_URDF
    assert robot.nx == 16
    assert robot.reduced_velocity_names == ("wheel_right_joint", "wheel_left_joint", *TIAGO_ARMS)
    assert robot.arm_slices == (slice(2, 9), slice(9, 16))
    # Only wheels and arm joints stay free: head, hands, casters, suspensions and torso are locked.
    assert set(robot.joint_names) == {"wheel_right_joint", "wheel_left_joint", *TIAGO_ARMS}


def test_tiago_wheel_geometry_and_limits_come_from_the_urdf(tiago):
    root = ET.parse(TIAGO_URDF).getroot()
    sphere = root.find("link[@name='wheel_right_link']/collision/geometry/sphere")
    assert tiago.platform.radius == pytest.approx(float(sphere.get("radius")))
    y_right = _xml_origin_xyz(TIAGO_URDF, "wheel_right_joint")[1]
    y_left = _xml_origin_xyz(TIAGO_URDF, "wheel_left_joint")[1]
    assert tiago.platform.half_track == pytest.approx((y_left - y_right) / 2)
    for k, name in enumerate(tiago.reduced_velocity_names):
        assert tiago.velocity_limits[k] == pytest.approx(_xml_limit(TIAGO_URDF, name, "velocity"))
        assert tiago.effort_limits[k] == pytest.approx(_xml_limit(TIAGO_URDF, name, "effort"))


def test_tiago_unified_jacobian_matches_finite_differences(tiago, rng):
    for _ in range(3):
        q = configuration_within_limits(tiago, rng, one_turn=False)
        J_u = unified_jacobian(tiago, q, "spatial")
        assert J_u.shape == (12, 16)
        for _ in range(3):
            x = rng.standard_normal(tiago.nx)
            np.testing.assert_allclose(J_u @ x, _finite_difference_twists(tiago, q, x), rtol=0, atol=FD_ATOL)


def test_tiago_reduced_inertia_gives_the_kinetic_energy(tiago, rng):
    for _ in range(5):
        q = configuration_within_limits(tiago, rng, one_turn=False)
        x = rng.standard_normal(tiago.nx)
        P = reduced_dynamics(tiago, q).P
        energy = pin.computeKineticEnergy(tiago.model, tiago.data, q, tiago.S @ x)
        # CRBA and the kinetic-energy pass evaluate the same quadratic form by different
        # algorithms; they agree to round-off (~1e-15 relative), 1e-10 leaves ample margin.
        assert 0.5 * x @ P @ x == pytest.approx(energy, rel=1e-10)


def test_tiago_positive_wheel_rates_drive_both_tools_forward(tiago, rng):
    radius = float(
        ET.parse(TIAGO_URDF).getroot().find("link[@name='wheel_right_link']/collision/geometry/sphere").get("radius")
    )
    for _ in range(3):
        q = configuration_within_limits(tiago, rng, one_turn=False)
        yaw = math.atan2(q[3], q[2])
        x = np.zeros(tiago.nx)
        x[:2] = 1.0  # both wheels at +1 rad/s, arms still: pure forward translation at r m/s
        twist = unified_jacobian(tiago, q, "spatial") @ x
        forward = radius * np.array([math.cos(yaw), math.sin(yaw), 0.0])
        for arm in range(2):
            np.testing.assert_allclose(twist[6 * arm : 6 * arm + 3], forward, atol=1e-12)
            np.testing.assert_allclose(twist[6 * arm + 3 : 6 * arm + 6], 0.0, atol=1e-12)


# ----- TIAGo++ with the torso lift -----


def test_tiago_torso_sits_between_platform_and_arms(tiago_torso):
    robot = tiago_torso
    assert robot.nx == 17
    assert robot.reduced_velocity_names == ("wheel_right_joint", "wheel_left_joint", "torso_lift_joint", *TIAGO_ARMS)
    assert robot.torso_slice == slice(2, 3)
    assert robot.arm_slices == (slice(3, 10), slice(10, 17))
    v = robot.model.joints[robot.model.getJointId("torso_lift_joint")].idx_v
    expected = np.zeros(robot.model.nv)
    expected[v] = 1.0
    np.testing.assert_array_equal(robot.S[:, 2], expected)
    np.testing.assert_array_equal(robot.B[:, 2], expected)
    assert robot.velocity_limits[2] == pytest.approx(_xml_limit(TIAGO_URDF, "torso_lift_joint", "velocity"))
    assert robot.effort_limits[2] == pytest.approx(_xml_limit(TIAGO_URDF, "torso_lift_joint", "effort"))


def test_tiago_torso_lifts_both_tools_straight_up(tiago_torso, rng):
    for _ in range(3):
        q = configuration_within_limits(tiago_torso, rng, one_turn=False)
        column = unified_jacobian(tiago_torso, q, "spatial")[:, tiago_torso.torso_slice][:, 0]
        np.testing.assert_allclose(column, [0, 0, 1, 0, 0, 0] * 2, atol=1e-12)
        x = rng.standard_normal(tiago_torso.nx)
        np.testing.assert_allclose(
            unified_jacobian(tiago_torso, q, "spatial") @ x,
            _finite_difference_twists(tiago_torso, q, x),
            rtol=0,
            atol=FD_ATOL,
        )
        energy = pin.computeKineticEnergy(tiago_torso.model, tiago_torso.data, q, tiago_torso.S @ x)
        assert 0.5 * x @ reduced_dynamics(tiago_torso, q).P @ x == pytest.approx(energy, rel=1e-10)


def test_tiago_torso_home_matches_the_locked_reference(tiago, tiago_torso):
    # The torso variant's home position of the lift is the height at which tiago_dual locks it,
    # so both robots put the tools at the same place at home.
    ref = tiago.spec.reference["torso_lift_joint"]
    lower = _xml_joint(TIAGO_URDF, "torso_lift_joint").find("limit")
    assert ref == pytest.approx((float(lower.get("lower")) + float(lower.get("upper"))) / 2)
    np.testing.assert_allclose(
        end_effector_positions(tiago_torso, tiago_torso.neutral()),
        end_effector_positions(tiago, tiago.neutral()),
        atol=1e-12,
    )


# ----- the nonholonomic platform seen from a task point -----


def _platform_block(robot, q, arm: int) -> np.ndarray:
    """Rows of one tool's planar velocity, columns of the wheel rates, (2, 2)."""
    return unified_jacobian(robot, q, "planar")[2 * arm : 2 * arm + 2, :2]


@pytest.mark.parametrize(
    "joints",
    [
        (2 * math.pi / 3, 2 * math.pi / 3, 2 * math.pi / 3),  # folded into a triangle: tool at P_o
        (math.pi / 2, 0.0, 0.0),  # stretched sideways: tool on the axle line, 1.5 m out
        (-math.pi / 2, 0.4, -0.8),  # zig-zag whose x offsets cancel: tool on the axle line, right side
    ],
)
def test_wheels_move_an_axle_line_point_only_forward(joints):
    robot = mobmanip.load_robot("planar_dual_arm")
    q = robot.configuration(joints=dict(zip(["arm_right_1_joint", "arm_right_2_joint", "arm_right_3_joint"], joints)))
    tool = end_effector_positions(robot, q)[0]
    assert abs(tool[0]) < 1e-12  # on the axle line (x = 0 in the platform frame at the origin)
    block = _platform_block(robot, q, arm=0)
    np.testing.assert_allclose(block[1], 0.0, atol=1e-12)  # nothing along the axle (lateral)
    assert np.linalg.matrix_rank(block, tol=1e-9) == 1


def test_wheels_span_the_plane_at_a_point_in_front_of_the_axle(rng):
    robot = mobmanip.load_robot("planar_dual_arm")
    root = ET.parse(PAPER_URDF).getroot()
    r = float(root.find("link[@name='wheel_right_link']/collision/geometry/cylinder").get("radius"))
    b = _xml_origin_xyz(PAPER_URDF, "wheel_left_joint")[1]
    c = r / (2 * b)
    for joints in [(0.0, 0.0, 0.0), *[tuple(rng.uniform(-1.0, 1.0, size=3)) for _ in range(4)]]:
        q = robot.configuration(
            joints=dict(zip(["arm_right_1_joint", "arm_right_2_joint", "arm_right_3_joint"], joints))
        )
        px, py, _ = end_effector_positions(robot, q)[0]
        assert px > 0.1
        block = _platform_block(robot, q, arm=0)
        # Point p on a platform moving at v = r/2 (eta_r + eta_l), omega = c (eta_r - eta_l):
        # p_dot = (v - omega p_y, omega p_x).
        expected = np.array([[r / 2 - c * py, r / 2 + c * py], [c * px, -c * px]])
        np.testing.assert_allclose(block, expected, atol=1e-12)
        assert np.linalg.matrix_rank(block, tol=1e-9) == 2


# ----- fixed-base arms -----


@pytest.mark.parametrize(
    ("name", "urdf", "prefix"),
    [
        ("ur5", ERD_ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf", ""),
        ("panda", ERD_ROBOTS / "panda_description" / "urdf" / "panda.urdf", "panda_joint"),  # fingers excluded
    ],
)
def test_fixed_base_arms_load_with_their_joints_only(name, urdf, prefix, rng):
    robot = mobmanip.load_robot(name)
    assert robot.platform.kind == "fixed"
    assert robot.wheel_platform is None
    assert robot.nx == _xml_count_joints(urdf, prefix=prefix)
    np.testing.assert_array_equal(robot.S[:3], 0.0)  # the root joint never moves
    for k, joint in enumerate(robot.reduced_velocity_names):
        assert robot.velocity_limits[k] == pytest.approx(_xml_limit(urdf, joint, "velocity"))
    q = configuration_within_limits(robot, rng, one_turn=False)
    x = rng.standard_normal(robot.nx)
    np.testing.assert_allclose(
        unified_jacobian(robot, q, "spatial") @ x, _finite_difference_twists(robot, q, x), rtol=0, atol=FD_ATOL
    )


def test_panda_home_is_inside_the_joint_ranges():
    # Zero is outside panda_joint4's range; the spec's [reference] gives the arm a home pose.
    robot = mobmanip.load_robot("panda")
    urdf = ERD_ROBOTS / "panda_description" / "urdf" / "panda.urdf"
    home = robot.configuration_dict(robot.neutral())["joints"]
    for joint in robot.reduced_velocity_names:
        limit = _xml_joint(urdf, joint).find("limit")
        assert float(limit.get("lower")) <= home[joint] <= float(limit.get("upper")), joint
    assert "panda_finger_joint1" not in robot.joint_names  # the fingers are locked


# ----- omnidirectional variant of the paper's robot -----

OMNI_LIMITS = {
    "velocity": {"base_x": 1.0, "base_y": 0.8, "base_yaw": 2.0},
    "effort": {"base_x": 400.0, "base_y": 300.0, "base_yaw": 150.0},
}


def _omni_spec(tmp_path: Path, limits=OMNI_LIMITS, extra: str = "") -> Path:
    lines = [
        'name = "planar_dual_arm_omni"',
        f"urdf = {str(PAPER_URDF)!r}",
        'platform = "omnidirectional"',
        'default_task = "planar"',
        extra,
    ]
    for side in ("right", "left"):
        joints = [f"arm_{side}_{k}_joint" for k in (1, 2, 3)]
        lines += ["[[arms]]", f'name = "{side}"', f"joints = {joints!r}", f'end_effector = "arm_{side}_tool_link"']
    for kind, table in limits.items():
        lines.append(f"[limits.{kind}]")
        lines += [f"{k} = {v}" for k, v in table.items()]
    path = tmp_path / "omni.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_omnidirectional_variant_loads_with_identity_on_the_base(tmp_path):
    robot = mobmanip.load_robot(load_spec(_omni_spec(tmp_path)))
    assert robot.platform.kind == "omnidirectional"
    assert robot.reduced_velocity_names[:3] == ("base_x", "base_y", "base_yaw")
    assert robot.nx == 3 + 6
    np.testing.assert_array_equal(robot.S[:3, :3], np.eye(3))
    np.testing.assert_array_equal(robot.S[:3, 3:], 0.0)
    np.testing.assert_array_equal(robot.S[3:, :3], 0.0)
    # The wheels of the URDF are locked out of the model.
    assert "wheel_right_joint" not in robot.joint_names and "wheel_left_joint" not in robot.joint_names
    np.testing.assert_array_equal(robot.velocity_limits[:3], list(OMNI_LIMITS["velocity"].values()))
    np.testing.assert_array_equal(robot.effort_limits[:3], list(OMNI_LIMITS["effort"].values()))


def test_omnidirectional_base_moves_an_axle_line_point_sideways(tmp_path):
    # Unlike the differential drive, a holonomic base moves any point in every planar direction:
    # for p = (p_x, p_y) the base columns are e_x, e_y and omega x p = (-p_y, p_x).
    robot = mobmanip.load_robot(load_spec(_omni_spec(tmp_path)))
    q = robot.configuration(joints={"arm_right_1_joint": math.pi / 2})
    px, py, _ = end_effector_positions(robot, q)[0]
    block = unified_jacobian(robot, q, "planar")[:2, :3]
    np.testing.assert_allclose(block, [[1.0, 0.0, -py], [0.0, 1.0, px]], atol=1e-12)


@pytest.mark.parametrize("kind", ["velocity", "effort"])
@pytest.mark.parametrize("coordinate", ["base_x", "base_y", "base_yaw"])
def test_omnidirectional_base_limits_are_required(tmp_path, kind, coordinate):
    limits = {k: dict(v) for k, v in OMNI_LIMITS.items()}
    del limits[kind][coordinate]
    spec = load_spec(_omni_spec(tmp_path, limits))
    with pytest.raises(MissingLimitError) as info:
        mobmanip.load_robot(spec)
    assert isinstance(info.value, LimitError)
    assert info.value.name == coordinate and info.value.kind == kind
    assert f"'{coordinate}'" in str(info.value) and f"[limits.{kind}]" in str(info.value)


def test_omnidirectional_rejects_an_unknown_base_coordinate(tmp_path):
    limits = {k: dict(v) for k, v in OMNI_LIMITS.items()}
    limits["velocity"]["base_z"] = 1.0
    with pytest.raises(JointNotFoundError, match="base_z"):
        mobmanip.load_robot(load_spec(_omni_spec(tmp_path, limits)))


def test_omnidirectional_spec_with_wheels_is_refused(tmp_path):
    extra = '[wheels]\nright = "wheel_right_joint"\nleft = "wheel_left_joint"'
    with pytest.raises(SpecError, match="only for a differential_drive"):
        load_spec(_omni_spec(tmp_path, extra=extra))


def test_platform_pose_reads_the_platforms_world_placement(tiago, rng):
    """``platform_pose(q)`` is where Pinocchio puts the root body: (x, y) of its origin and the
    heading of its x axis, at random configurations (yaw over the whole circle)."""
    from mobmanip.robot.model import platform_pose

    for _ in range(20):
        yaw = rng.uniform(-math.pi, math.pi)
        q = tiago.configuration((rng.uniform(-5, 5), rng.uniform(-5, 5), yaw))
        pin.forwardKinematics(tiago.model, tiago.data, q)
        placement = tiago.data.oMi[1]
        x, y, heading = platform_pose(q)
        np.testing.assert_allclose([x, y], placement.translation[:2], rtol=0, atol=1e-12)
        axis = placement.rotation[:2, 0]
        assert abs(heading - math.atan2(axis[1], axis[0])) < 1e-12
        assert abs(heading - yaw) < 1e-12
