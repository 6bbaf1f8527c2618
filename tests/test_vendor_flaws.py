"""Robot files as vendors publish them (issue 25, item 1): a non-physical inertia never blocks an
analysis; it is repaired by MuJoCo's balanceinertia rule with one warning per link (stderr and the
JSON's "warnings"), or refused under --strict / ``strict = true`` with the check's message and the
way forward.

Fetch (a Fetch-like URDF with Fetch's finger flaw: its own file is CC BY-NC-SA, see
``vendor_robots.py``), PR2 and Romeo from example-robot-data, and TIAGo++ go through ``init-spec``
and ``analyze``. Fetch's kinematic ellipsoid is checked against a raw-Pinocchio reference built
here (``pin.buildModelFromUrdf`` of the unrepaired file, S, W and the limits by hand) to 1e-12;
its dynamic ellipsoid against the same reference with the repair's stated effect (the reduced
inertia changed by the repaired links' rotational share, nothing else) to 1e-9.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import set_joints
from ellipsoid_reference import dynamic_ellipsoid_closed_form
from hostile_util import assert_one_line_error, run_cli
from mobmanip.descriptions import read_description
from mobmanip.descriptions.resources import example_robot_data_share
from mobmanip.errors import SpecError, UrdfError
from mobmanip.robot.detect import spec_from_urdf
from mobmanip.robot.spec import load_spec
from vendor_robots import FETCH_FLAWED, FINGER_INERTIA, HALF_TRACK, WHEEL_RADIUS, fetch_like_urdf

ROBOTS = example_robot_data_share() / "example-robot-data" / "robots"
PR2 = ROBOTS / "pr2_description" / "urdf" / "pr2.urdf"
ROMEO = ROBOTS / "romeo_description" / "urdf" / "romeo_small.urdf"
TIAGO_DUAL = ROBOTS / "tiago_description" / "robots" / "tiago_dual.urdf"

#: The Fetch-like arm posture analysed (joints not named stay at zero).
FETCH_POSTURE = {
    "torso_lift_joint": 0.2,
    "shoulder_pan_joint": 0.4,
    "shoulder_lift_joint": -0.5,
    "upperarm_roll_joint": 0.3,
    "elbow_flex_joint": 1.2,
    "forearm_roll_joint": -0.4,
    "wrist_flex_joint": 0.8,
    "wrist_roll_joint": 0.2,
}
ARM_JOINTS = list(FETCH_POSTURE)


def balanced(inertia: np.ndarray) -> np.ndarray:
    """MuJoCo's balanceinertia, written here from its documentation: a tensor whose principal
    moments break the triangle inequality gets all three at their mean."""
    moments = np.linalg.eigvalsh(inertia)
    if moments[0] >= 0.0 and moments[2] <= moments[0] + moments[1]:
        return inertia
    return max(moments.mean(), 0.0) * np.eye(3)


@pytest.fixture(scope="module")
def fetch(tmp_path_factory):
    """The Fetch-like robot: its URDF, the spec init-spec writes, the loaded robot."""
    folder = tmp_path_factory.mktemp("fetch")
    urdf = fetch_like_urdf(folder)
    spec = folder / "fetch.toml"
    assert mobmanip.cli.main(["init-spec", str(urdf), "--ee", "gripper_link", "--out", str(spec)]) == 0
    return urdf, spec, mobmanip.load_robot(load_spec(spec))


# ----- the rule and its warnings


def test_each_flawed_link_is_recorded_with_its_values_and_repair(fetch):
    urdf, _, robot = fetch
    description = read_description(urdf)
    assert [flaw.link for flaw in description.flaws] == list(FETCH_FLAWED)
    for flaw in description.flaws:
        np.testing.assert_array_equal(flaw.inertia, np.diag(FINGER_INERTIA))
        np.testing.assert_allclose(flaw.repaired, balanced(np.diag(FINGER_INERTIA)), rtol=1e-15)
        assert flaw.change == pytest.approx(2 * 0.002 / 3, rel=1e-12)
    assert len(robot.warnings) == 2
    for link, text in zip(FETCH_FLAWED, robot.warnings):
        assert text.startswith(f"link {link!r}: inertia (ixx=0.002 iyy=0 izz=0")
        assert "triangle inequality" in text and "balanceinertia" in text and "0.000666667 kg m^2" in text
        assert "--strict" in text and "kinematic results unaffected" in text


def test_repair_changes_the_model_only_by_the_stated_rotational_share(fetch):
    """The repaired Pinocchio model equals the model of the URDF with the balanced tensors
    written into it: same masses and centres of mass, rotational inertia changed by the share."""
    urdf, _, _ = fetch
    description = read_description(urdf)
    repaired = description.build_model(pin.JointModelPlanar())
    raw = description.build_model(pin.JointModelPlanar(), repaired=False)
    text = urdf.read_text()
    mean = sum(FINGER_INERTIA) / 3
    edited = text.replace('ixx="0.002" ixy="0" ixz="0" iyy="0.0" iyz="0" izz="0.0"',
                          f'ixx="{mean!r}" ixy="0" ixz="0" iyy="{mean!r}" iyz="0" izz="{mean!r}"')  # fmt: skip
    assert edited.count(repr(mean)) == 6
    by_hand = pin.buildModelFromXML(edited, pin.JointModelPlanar())
    for a, b, c in zip(repaired.inertias, by_hand.inertias, raw.inertias):
        np.testing.assert_allclose(a.toDynamicParameters(), b.toDynamicParameters(), rtol=0, atol=1e-15)
        assert a.mass == c.mass
        np.testing.assert_array_equal(a.lever, c.lever)


def test_analyze_warns_once_per_repaired_link_on_stderr_and_in_the_json(fetch, tmp_path, capfd):
    _, spec, _ = fetch
    out = tmp_path / "fetch.json"
    code, printed, err = run_cli(capfd, "analyze", spec, "--json", out)
    assert code == 0, err
    for link in FETCH_FLAWED:
        assert err.count(f"warning: link {link!r}: inertia") == 1  # once, though the analysis carries it too
    warnings = json.loads(out.read_text())["warnings"]
    assert [w for w in warnings if "balanceinertia" in w] == list(mobmanip.load_robot(load_spec(spec)).warnings)


def test_strict_refuses_with_the_message_and_the_way_forward(fetch, tmp_path, capfd):
    urdf, spec, _ = fetch
    for argv in (["analyze", spec, "--strict"], ["analyze", "--urdf", urdf, "--ee", "gripper_link", "--strict"]):
        code, out, err = run_cli(capfd, *argv)
        line = assert_one_line_error(code, err, "r_gripper_finger_link", "ixx=0.002 iyy=0 izz=0", "triangle inequality")
        assert "correct it in the file, or drop --strict" in line and "balanceinertia" in line and out == ""
    strict_spec = tmp_path / "strict.toml"
    strict_spec.write_text(spec.read_text().replace("default_task =", "strict = true\ndefault_task =", 1))
    strict_spec.with_name(urdf.name).write_text(urdf.read_text())
    with pytest.raises(UrdfError, match="r_gripper_finger_link.*strict"):
        mobmanip.load_robot(strict_spec)
    with pytest.raises(UrdfError, match="r_gripper_finger_link"):
        mobmanip.load_robot(load_spec(spec), strict=True)
    code, _, err = run_cli(capfd, "init-spec", urdf, "--ee", "gripper_link", "--strict")
    assert_one_line_error(code, err, "r_gripper_finger_link", "triangle inequality")


def test_init_spec_notes_each_flaw_and_writes_strict_when_asked(fetch, tmp_path, capfd):
    _, spec, _ = fetch
    text = spec.read_text()
    for link in FETCH_FLAWED:
        assert f"# link {link!r}: inertia (ixx=0.002" in text and "accepted_repairs" in text


def test_accepted_repairs_are_made_without_a_warning(fetch, tmp_path, capfd):
    urdf, spec, robot = fetch
    accepted = tmp_path / "accepted.toml"
    listed = f"accepted_repairs = {json.dumps(list(FETCH_FLAWED))}\ndefault_task ="
    accepted.write_text(spec.read_text().replace("default_task =", listed, 1))
    accepted.with_name(urdf.name).write_text(urdf.read_text())
    quiet = mobmanip.load_robot(accepted)
    assert quiet.warnings == ()
    np.testing.assert_array_equal(pin.crba(quiet.model, quiet.data, quiet.neutral()),
                                  pin.crba(robot.model, robot.data, robot.neutral()))  # fmt: skip
    code, _, err = run_cli(capfd, "analyze", accepted)
    assert code == 0 and "inertia" not in err
    # --strict still refuses them: it refuses every repair
    code, _, err = run_cli(capfd, "analyze", accepted, "--strict")
    assert_one_line_error(code, err, "r_gripper_finger_link")
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(accepted.read_text().replace('"r_gripper_finger_link"', '"r_gripper_finger_lnk"'))
    with pytest.raises(SpecError, match="r_gripper_finger_lnk.*closest: r_gripper_finger_link"):
        mobmanip.load_robot(wrong)
    with pytest.raises(SpecError, match="contradicts"):
        both = tmp_path / "both.toml"
        both.write_text(accepted.read_text().replace("default_task =", "strict = true\ndefault_task =", 1))
        load_spec(both)


# ----- Fetch against a raw-Pinocchio reference


def _reference(urdf: Path, robot, repaired_by_hand: bool):
    """J_u, P, xi and the limits at FETCH_POSTURE from Pinocchio's own parse of the file (no
    repair unless ``repaired_by_hand``: then the stated share is added to M), with S of the
    differential drive and the reduced-velocity order written here."""
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelPlanar())
    data = model.createData()
    q = set_joints(model, pin.neutral(model), FETCH_POSTURE)
    names = ["r_wheel_joint", "l_wheel_joint", *ARM_JOINTS]
    S = np.zeros((model.nv, len(names)))
    r, b = WHEEL_RADIUS, HALF_TRACK
    S[0, :2] = (r / 2, r / 2)  # forward speed of the base (its local x)
    S[2, :2] = (r / (2 * b), -r / (2 * b))  # yaw rate: the right wheel faster turns left
    for k, name in enumerate(names):
        S[model.joints[model.getJointId(name)].idx_v, k] = 1.0
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = pin.getFrameJacobian(model, data, model.getFrameId("gripper_link"), pin.LOCAL_WORLD_ALIGNED)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    if repaired_by_hand:
        for link in FETCH_FLAWED:
            frame = model.getFrameId(link, pin.FrameType.BODY)
            Jw = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)[3:]
            R = data.oMf[frame].rotation  # the <inertial> frame is the link frame here
            written = np.diag(FINGER_INERTIA)
            M = M + Jw.T @ R @ (balanced(written) - written) @ R.T @ Jw
    gravity = pin.computeGeneralizedGravity(model, data, q)
    by_name = {j.name: j for j in read_description(urdf).joints.values()}
    velocity = np.array([by_name[n].limits.velocity for n in names])
    effort = np.array([by_name[n].limits.effort for n in names])
    return J @ S, S.T @ M @ S, -S.T @ gravity, velocity, effort, names


def test_fetch_kinematic_ellipsoid_equals_the_raw_pinocchio_reference(fetch):
    urdf, _, robot = fetch
    analysis = mobmanip.analyze(robot, robot.configuration(joints=FETCH_POSTURE), task="spatial")
    J_u, _, _, velocity, _, names = _reference(urdf, robot, repaired_by_hand=False)
    assert list(robot.reduced_velocity_names) == names
    np.testing.assert_allclose(analysis.unified_jacobian, J_u, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(robot.velocity_limits, velocity)
    s = np.linalg.svd(J_u * velocity, compute_uv=False)  # W = I: semi-axes are J diag(qdot_max)'s singular values
    kinematic = analysis.kinematic
    np.testing.assert_allclose(kinematic.semi_axes, s, rtol=0, atol=1e-12 * s[0])
    # the shape matrix: x^T A x <= 1 with A = (J Y^-1 (J Y^-1)^T)^-1
    J_hat = J_u * velocity
    np.testing.assert_allclose(kinematic.matrix @ (J_hat @ J_hat.T), np.eye(6), rtol=0, atol=1e-10)


def test_fetch_dynamic_ellipsoid_differs_from_the_raw_reference_by_the_stated_repair(fetch):
    urdf, _, robot = fetch
    analysis = mobmanip.analyze(robot, robot.configuration(joints=FETCH_POSTURE), task="spatial")
    raw = _reference(urdf, robot, repaired_by_hand=False)
    by_hand = _reference(urdf, robot, repaired_by_hand=True)
    J_u, P, xi, _, effort, _ = by_hand
    np.testing.assert_allclose(analysis.reduced_inertia, P, rtol=0, atol=1e-12)
    np.testing.assert_allclose(analysis.bias, raw[2], rtol=0, atol=1e-12)  # gravity: not touched by the repair
    np.testing.assert_array_equal(robot.effort_limits, effort)
    m, nx = 6, len(effort)
    _, centre, semi_axes = dynamic_ellipsoid_closed_form(
        J_u, np.eye(m), P, np.eye(nx), xi, np.zeros((m, m)), np.zeros(m), effort
    )
    dynamic = analysis.dynamic
    np.testing.assert_allclose(dynamic.semi_axes, semi_axes, rtol=1e-9)
    np.testing.assert_allclose(dynamic.center, centre, rtol=0, atol=1e-9 * np.abs(centre).max())
    # The repair's whole effect, measured: the unrepaired robot's ellipsoid is another one, and the
    # difference is exactly what the stated change of P makes (checked above); it stays within the
    # repaired links' share: no semi-axis moves by more than the relative change of P they cause.
    unrepaired = dynamic_ellipsoid_closed_form(
        raw[0], np.eye(m), raw[1], np.eye(nx), raw[2], np.zeros((m, m)), np.zeros(m), effort
    )[2]
    change = np.abs(dynamic.semi_axes / unrepaired - 1.0)
    L = np.linalg.cholesky(raw[1])
    share = np.linalg.norm(np.linalg.solve(L, np.linalg.solve(L, P - raw[1]).T), 2)  # ||L^-1 dP L^-T||
    assert 0.0 < change.max() <= share / (1.0 - share)


# ----- vendor robots from example-robot-data and TIAGo++


@pytest.mark.parametrize(
    ("urdf", "ends", "flawed"),
    [
        (PR2, ["r_gripper_tool_frame", "l_gripper_tool_frame"], ["sensor_mount_link", "double_stereo_link"]),
        (ROMEO, ["r_gripper", "l_gripper"], None),
        (
            TIAGO_DUAL,
            ["arm_right_tool_link", "arm_left_tool_link"],
            ["base_antenna_left_link", "base_antenna_right_link"],
        ),
    ],
    ids=["pr2", "romeo", "tiago_dual"],
)
def test_vendor_robots_analyse_with_one_warning_per_repaired_link(tmp_path, capfd, urdf, ends, flawed):
    description = read_description(urdf)
    links = [flaw.link for flaw in description.flaws]
    assert links and (flawed is None or links == flawed)
    spec = tmp_path / "robot.toml"
    argv = ["init-spec", urdf, *[a for end in ends for a in ("--ee", end)], "--out", spec]
    code, _, err = run_cli(capfd, *argv)
    assert code == 0, err
    out = tmp_path / "robot.json"
    code, printed, err = run_cli(capfd, "analyze", spec, "--json", out)
    assert code == 0, err
    document = json.loads(out.read_text())
    repairs = [w for w in document["warnings"] if "balanceinertia" in w]
    assert [w.split("'")[1] for w in repairs] == links  # one per link, in file order
    for link in links:
        assert err.count(f"warning: link {link!r}: inertia") == 1
    assert document["kinematic_ellipsoid"]["semi_axes"][0] > 0.0
    code, _, err = run_cli(capfd, "analyze", spec, "--strict")
    assert_one_line_error(code, err, links[0], "correct it in the file, or drop --strict")


def test_kinematic_results_do_not_depend_on_the_repair(tmp_path):
    """The same robot with the repair and with hand-made physical fingers: the kinematic
    ellipsoid is bit-for-bit the same (nothing kinematic reads an inertia)."""
    flawed = mobmanip.load_robot(spec_from_urdf(fetch_like_urdf(tmp_path), ["gripper_link"]))
    clean_dir = tmp_path / "clean"
    clean_dir.mkdir()
    clean = mobmanip.load_robot(
        spec_from_urdf(fetch_like_urdf(clean_dir, finger_inertia=(1e-4, 1e-4, 1e-4)), ["gripper_link"])
    )  # fmt: skip
    assert clean.warnings == () and len(flawed.warnings) == 2
    a, b = (
        mobmanip.analyze(robot, robot.configuration(joints=FETCH_POSTURE), measures=("kinematic",)).kinematic
        for robot in (flawed, clean)
    )
    np.testing.assert_array_equal(a.semi_axes, b.semi_axes)
    np.testing.assert_array_equal(a.axes, b.axes)


TURNED_FLAW = """<?xml version="1.0"?>
<robot name="turned">
  <link name="base">
    <inertial><mass value="5"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <link name="arm">
    <inertial>
      <origin xyz="0.1 -0.03 0.02" rpy="0.4 -0.7 1.1"/>
      <mass value="1.2"/>
      <inertia ixx="0.03" ixy="0.002" ixz="-0.001" iyy="0.004" iyz="0.0015" izz="0.002"/>
    </inertial>
  </link>
  <link name="tool"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0.3" rpy="0 0.2 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" velocity="2" effort="50"/>
  </joint>
  <joint name="tool_joint" type="fixed"><parent link="arm"/><child link="tool"/><origin xyz="0.4 0 0"/></joint>
</robot>
"""


def test_a_repaired_inertia_in_a_turned_inertial_frame_is_mujocos(tmp_path):
    """A link whose ``<inertial>`` frame is turned (rpy 0.4, -0.7, 1.1) and whose tensor breaks the
    triangle inequality (0.03 against 0.004 + 0.002 and the off-diagonals): mobmanip's repaired
    body equals MuJoCo's own compile of the same file with ``balanceinertia`` (its principal
    moments, frame and centre of mass) to 1e-12; turned the wrong way, the repair is 1e-3 off."""
    mujoco = pytest.importorskip("mujoco")
    path = tmp_path / "turned.urdf"
    path.write_text(TURNED_FLAW)
    robot = mobmanip.load_robot(spec_from_urdf(path, ["tool"], platform="fixed"))
    inertia = robot.model.inertias[robot.model.getJointId("shoulder")]
    text = TURNED_FLAW.replace(
        "</robot>",
        '<mujoco><compiler balanceinertia="true" fusestatic="false" discardvisual="false"/></mujoco></robot>',
    )
    theirs = mujoco.MjModel.from_xml_string(text)
    body = theirs.body("arm")
    w, x, y, z = body.iquat
    R = pin.Quaternion(w, x, y, z).normalized().matrix()
    assert inertia.mass == pytest.approx(float(body.mass[0]), rel=1e-12)
    np.testing.assert_allclose(inertia.lever, body.ipos, atol=1e-12)
    np.testing.assert_allclose(inertia.inertia, R @ np.diag(body.inertia) @ R.T, atol=1e-12)
