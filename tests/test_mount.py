"""``init-spec --mount ARM.urdf --on BASE.urdf --at X,Y,Z,YAW`` (issue 28, item 10): one robot from
a base and an arm. Checked against the same robot merged by hand (the Husky carrying a KUKA iiwa of
``test_skid_steer``): the same mass matrix and end-effector pose at random configurations; the
mount pose against the transform it names; name clashes renamed consistently; bad input refused in
one line with nothing written."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli

pybullet_data = pytest.importorskip("pybullet_data", reason="the Husky and iiwa URDFs ship with pybullet")

DATA = Path(pybullet_data.getDataPath())
HUSKY, IIWA = DATA / "husky" / "husky.urdf", DATA / "kuka_iiwa" / "model.urdf"
EE = "lbr_iiwa_link_7"


def _mounted(tmp_path, capfd, at="0.15,0,0.01,0", link="top_plate_link", name="mounted"):
    from test_skid_steer import SIDE_SPEED, SIDE_TORQUE  # the hand-merged robot's side limits

    spec = tmp_path / f"{name}.toml"
    argv = ["init-spec", "--mount", IIWA, "--on", HUSKY, "--at", at, "--on-link", link, "--ee", EE, "--out", spec]
    limits = ["--wheel-velocity-limit", SIDE_SPEED, "--wheel-effort-limit", SIDE_TORQUE]
    code, out, err = run_cli(capfd, *argv, *limits)
    assert code == 0, err
    return spec, out


def _random_q(model, rng):
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    lower[~np.isfinite(lower)], upper[~np.isfinite(upper)] = -1.0, 1.0
    q = pin.randomConfiguration(model, lower, upper)
    yaw = rng.uniform(-math.pi, math.pi)
    q[:4] = (*rng.uniform(-2, 2, size=2), math.cos(yaw), math.sin(yaw))
    return q


def test_mounting_gives_the_robot_merged_by_hand(tmp_path, capfd):
    from test_skid_steer import husky_with_arm, spec_text

    spec, out = _mounted(tmp_path, capfd)
    assert f"wrote {tmp_path / 'mounted.urdf'}" in out
    by_hand = tmp_path / "by_hand"
    by_hand.mkdir()
    reference = by_hand / "husky_iiwa.toml"
    reference.write_text(spec_text(husky_with_arm(by_hand)))
    ours, theirs = mobmanip.load_robot(spec), mobmanip.load_robot(reference)
    assert list(ours.model.names) == list(theirs.model.names)
    assert ours.model.nv == theirs.model.nv == 3 + 4 + 7  # planar root, four wheels, the iiwa
    rng = np.random.default_rng(7)
    frame_a, frame_b = ours.model.getFrameId(EE), theirs.model.getFrameId(EE)
    for _ in range(5):
        q = _random_q(ours.model, rng)
        da, db = ours.model.createData(), theirs.model.createData()
        ma, mb = pin.crba(ours.model, da, q), pin.crba(theirs.model, db, q)
        np.testing.assert_allclose(np.triu(ma), np.triu(mb), rtol=0, atol=1e-12)
        pin.framesForwardKinematics(ours.model, da, q)
        pin.framesForwardKinematics(theirs.model, db, q)
        np.testing.assert_allclose(da.oMf[frame_a].homogeneous, db.oMf[frame_b].homogeneous, rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            pin.computeGeneralizedGravity(ours.model, da, q),
            pin.computeGeneralizedGravity(theirs.model, db, q),
            rtol=0,
            atol=1e-10,
        )
    a, b = (mobmanip.analyze(r, r.neutral(), "translational") for r in (ours, theirs))
    np.testing.assert_allclose(a.kinematic.semi_axes, b.kinematic.semi_axes, rtol=1e-12)


def test_the_arm_sits_at_the_pose_named(tmp_path, capfd):
    x, y, z, yaw = 0.1, -0.05, 0.02, 90.0
    spec, _ = _mounted(tmp_path, capfd, at=f"{x},{y},{z},{yaw}", link="top_plate_link")
    robot = mobmanip.load_robot(spec)
    model = robot.model
    data = model.createData()
    q = _random_q(model, np.random.default_rng(3))
    pin.framesForwardKinematics(model, data, q)
    relative = data.oMf[model.getFrameId("top_plate_link")].actInv(data.oMf[model.getFrameId("lbr_iiwa_link_0")])
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    np.testing.assert_allclose(relative.rotation, [[c, -s, 0], [s, c, 0], [0, 0, 1]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(relative.translation, [x, y, z], rtol=0, atol=1e-15)


def test_the_meshes_travel_with_the_composed_urdf(tmp_path, capfd):
    spec, _ = _mounted(tmp_path, capfd)
    meshes = sorted(p.relative_to(tmp_path).as_posix() for p in (tmp_path / "mounted_meshes").rglob("*") if p.is_file())
    assert "mounted_meshes/base/meshes/wheel.stl" in meshes and "mounted_meshes/arm/meshes/link_7.stl" in meshes
    for path in (tmp_path / "mounted_meshes").rglob("*.stl"):
        role, *rest = path.relative_to(tmp_path / "mounted_meshes").parts
        source = (HUSKY if role == "base" else IIWA).parent.joinpath(*rest)
        assert path.read_bytes() == source.read_bytes()
    page = tmp_path / "scene.html"
    code, out, err = run_cli(capfd, "view", spec, "--export", page, "--no-locked")
    assert code == 0, err
    assert "not drawn" not in out and "could not be loaded" not in out
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no draft left


BASE = """<robot name="cart"><material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <link name="base_link"><visual><geometry><box size="0.4 0.3 0.1"/></geometry><material name="grey"/></visual>
    <inertial><mass value="10"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="link_1"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
    </inertial></link>
  <joint name="joint_1" type="fixed"><parent link="base_link"/><child link="link_1"/></joint>
</robot>"""
ARM = """<robot name="stick"><material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <material name="blue"><color rgba="0 0 1 1"/></material>
  <link name="link_0"/>
  <link name="link_1"><visual><geometry><box size="0.1 0.1 0.1"/></geometry><material name="grey"/></visual>
    <inertial><origin xyz="0.2 0 0"/><mass value="2"/>
    <inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="link_2"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="joint_1" type="revolute"><parent link="link_0"/><child link="link_1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="1" effort="10"/></joint>
  <joint name="joint_2" type="revolute"><parent link="link_1"/><child link="link_2"/><origin xyz="0.4 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1" effort="10"/></joint>
</robot>"""


def _files(tmp_path):
    (tmp_path / "cart.urdf").write_text(BASE)
    (tmp_path / "stick.urdf").write_text(ARM)
    return tmp_path / "stick.urdf", tmp_path / "cart.urdf"


def test_clashing_names_are_prefixed_consistently(tmp_path, capfd):
    arm, base = _files(tmp_path)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    spec = out_dir / "r.toml"
    argv = ["init-spec", "--mount", arm, "--on", base, "--at", "0,0,0.05,0", "--ee", "link_2", "--out", spec]
    code, out, err = run_cli(capfd, *argv, "--platform", "fixed")
    assert code == 0, err
    assert "link 'link_1' -> 'arm_link_1'" in out and "joint 'joint_1' -> 'arm_joint_1'" in out
    assert "material 'grey'" not in out  # defined alike: kept once, not renamed
    robot = mobmanip.load_robot(spec)
    model = robot.model
    assert robot.arms[0].joint_names == ("arm_joint_1", "joint_2")
    # the arm's link_1 (2 kg, centre 0.2 m along the rotating link) moved by arm_joint_1; the
    # base's link_1 (1 kg) fixed: the joint's inertia about z is the arm's own, by hand.
    data = model.createData()
    q = pin.neutral(model)
    M = pin.crba(model, data, q)
    v1 = model.joints[model.getJointId("arm_joint_1")].idx_v
    expected = 0.03 + 2 * 0.2**2 + 0.01 + 1 * (0.4 + 0.1) ** 2
    assert M[v1, v1] == pytest.approx(expected, rel=1e-12)
    text = (out_dir / "r.urdf").read_text()
    assert text.count('<material name="grey">') == 1 and '<material name="blue">' in text


@pytest.mark.parametrize(
    "extra, needles",
    [
        (["--at", "0,0,0"], ["--at", "X,Y,Z,YAW"]),
        (["--at", "0,0,nan,0"], ["--at"]),
        (["--at", "0,0,0,0", "--on-link", "nowhere"], ["nowhere", "base_link"]),
        (["--at", "0,0,0,0", "--prefix", ""], ["clashes", "--prefix"]),
        ([], ["missing --at"]),
    ],
)
def test_bad_mounts_are_refused_in_one_line_and_write_nothing(tmp_path, capfd, extra, needles):
    arm, base = _files(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    argv = ["init-spec", "--mount", arm, "--on", base, "--ee", "link_2", "--out", tmp_path / "r.toml", *extra]
    code, out, err = run_cli(capfd, *argv)
    assert_one_line_error(code, err, *needles)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_other_bad_uses_are_refused_in_one_line(tmp_path, capfd):
    arm, base = _files(tmp_path)
    (tmp_path / "stick.xacro").write_text(ARM)
    xacro, missing, over = tmp_path / "stick.xacro", tmp_path / "none.urdf", tmp_path / "cart.toml"
    cases = [
        (["init-spec", base, "--mount", arm, "--on", base, "--at", "0,0,0,0"], ["not both"]),
        (["init-spec", "--mount", arm, "--on", base, "--at", "0,0,0,0", "--ee", "link_2"], ["--out"]),
        (["init-spec", "--mount", xacro, "--on", base, "--at", "0,0,0,0", "--list-frames"], ["xacro"]),
        (["init-spec", "--mount", missing, "--on", base, "--at", "0,0,0,0", "--list-frames"], ["none.urdf"]),
        (["init-spec", "--mount", arm, "--on", base, "--at", "0,0,0,0", "--ee", "link_2", "--out", over],
         ["cart.urdf", "--out"]),
        (["init-spec", base, "--on-link", "base_link", "--ee", "link_1"], ["--on-link"]),
        (["init-spec"], ["PATH", "--mount"]),
    ]  # fmt: skip
    for argv, needles in cases:
        code, out, err = run_cli(capfd, *argv)
        assert_one_line_error(code, err, *needles)
    assert (tmp_path / "cart.urdf").read_text() == BASE  # the base was not overwritten
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cart.urdf", "stick.urdf", "stick.xacro"]


def test_list_frames_of_a_mounted_arm(tmp_path, capfd):
    code, out, err = run_cli(capfd, "init-spec", "--mount", IIWA, "--on", HUSKY, "--at", "0,0,0.3,0", "--list-frames")
    assert code == 0, err
    assert out.splitlines()[-1].split()[0] == EE
    assert f"{IIWA} on {HUSKY}" in out
    code, out, err = run_cli(capfd, "init-spec", HUSKY, "--list-frames")
    assert "--mount ARM.urdf --on" in out  # the base alone says how to add an arm


def test_package_meshes_travel_too_and_the_page_draws_both_robots(tmp_path, capfd):
    """Issue 39: a UR10 from example-robot-data (its meshes named ``package://example-robot-data/
    robots/...``) on a Husky: the arm's meshes were left behind and the page drew a Husky alone.
    Every visual mesh of both is copied byte for byte, and the exported page holds each distinct
    mesh file once: the Husky's 5 and the UR10's 7."""
    import json
    import re
    import xml.etree.ElementTree as ET

    from mobmanip.descriptions.resources import example_robot_data_share

    share = example_robot_data_share()
    ur10 = share / "example-robot-data" / "robots" / "ur_description" / "urdf" / "ur10_robot.urdf"
    spec = tmp_path / "husky_ur10.toml"
    code, _, err = run_cli(capfd, "init-spec", "--mount", ur10, "--on", HUSKY, "--at", "0,0,0.3,0", "--ee", "tool0",
                           "--wheel-velocity-limit", "10", "--wheel-effort-limit", "50", "--out", spec)  # fmt: skip
    assert code == 0, err
    composed = ET.parse(tmp_path / "husky_ur10.urdf").getroot()
    visual = {m.get("filename") for link in composed.iter("link") for v in link.iter("visual") for m in v.iter("mesh")}
    arm = {f for f in visual if "/arm/" in f}
    assert len(arm) == 7 and len(visual - arm) == 5
    for name in arm:
        package_path = name.split("/_packages/", 1)[1]  # example-robot-data/robots/ur_description/...
        assert (tmp_path / name).read_bytes() == (share / package_path).read_bytes()
    page = tmp_path / "page.html"
    code, out, err = run_cli(capfd, "view", spec, "--export", page, "--no-locked")
    assert code == 0, err
    assert "not drawn" not in out and "not drawn" not in err
    table = json.loads(re.search(r'id="mobmanip-scene-table">(.*?)</script>', page.read_text()).group(1))
    assert len(table["meshes"]) == len(visual) == 12
