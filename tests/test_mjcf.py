"""MJCF robot files (issue 25, item 3) through the description seam, and the same robot from its
MJCF and its URDF: MuJoCo Menagerie's TIAGo++ (``tests/data/menagerie_tiago_dual``, Apache-2.0,
meshes removed) against example-robot-data's TIAGo++ URDF.

The tolerance of the comparison: the two files give the arms the same joint placements (the
MJCF was converted from PAL's URDF), so the unified Jacobian and the kinematic ellipsoid agree
to round-off (1e-12). Their mass data differ (the MJCF lumps the gripper into ``arm_*_7_link``,
MuJoCo's conversion balanced ``arm_*_1_link``'s tensor, the torso and the base weigh otherwise),
so the dynamic ellipsoids differ (a semi-axis by up to 5 times its size over the postures tried);
with the MJCF's link inertias put into the URDF robot's model the two agree to 1e-9: every
difference is the files' mass data.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mjcf_util import compiled_inertia, mjcf_text, read_beside_mujoco
from mobmanip.descriptions import read_description
from mobmanip.descriptions.resources import example_robot_data_share
from mobmanip.errors import MjcfError
from mobmanip.robot.detect import spec_from_urdf
from mobmanip.robot.spec import load_spec

DATA = Path(__file__).resolve().parent / "data"
TIAGO_MJCF = DATA / "menagerie_tiago_dual" / "tiago_dual.xml"
TIAGO_URDF = (
    example_robot_data_share() / "example-robot-data" / "robots" / "tiago_description" / "robots" / "tiago_dual.urdf"
)
HANDS = ["arm_right_7_link", "arm_left_7_link"]


def _inertia_of(link) -> pin.Inertia:
    inertial = link.inertial
    R = inertial.origin.rotation
    return pin.Inertia(inertial.mass, np.asarray(inertial.origin.xyz), R @ inertial.inertia_matrix @ R.T)


def test_the_menagerie_tiago_is_read_and_pinocchio_builds_the_same_tree():
    description = read_description(TIAGO_MJCF)
    assert description.format == "mjcf" and description.root_link == "base_link"
    moving = [j.name for j in description.moving_joints()]
    assert len(moving) == 25 and moving[:4] == [
        f"wheel_{p}_joint" for p in ("front_right", "front_left", "rear_right", "rear_left")
    ]
    assert description.joints["torso_lift_joint"].type == "prismatic"
    assert description.joints["arm_right_1_joint"].limits.lower == pytest.approx(-1.1781)
    assert description.joints["wheel_front_right_joint"].type == "continuous"  # no range: a wheel
    assert any("free joint" in note for note in description.notes) and any(
        "contact" in note for note in description.notes
    )
    model = description.build_model(pin.JointModelPlanar())
    assert [model.names[j] for j in range(2, model.njoints)] == moving
    # every link's inertia as the description reads it is the one Pinocchio's builder made
    for name in moving:
        link = description.links[description.joints[name].child]
        expected = _inertia_of(link).toDynamicParameters()
        np.testing.assert_allclose(model.inertias[model.getJointId(name)].toDynamicParameters(), expected, atol=1e-12)
    # the wheel cylinders are shapes about the wheel axis: detection finds the wheels' radius
    wheel = description.links["wheel_front_right_link"].collisions[0]
    assert wheel.kind == "cylinder" and wheel.radius == pytest.approx(0.0762)
    # the viewer's geometry: Pinocchio's MJCF geometry builder on the same model
    geometry = description.build_geometry(model, "collision")
    assert geometry.ngeoms == 1 + 4 + 6  # the torso box, the wheels, the wrists' cylinders


@pytest.fixture(scope="module")
def both():
    """TIAGo++ from its URDF and from the Menagerie MJCF, platforms locked (the two bases differ:
    a differential drive with casters, an omnidirectional base of four wheels), the torso at
    mid-height, the arms to their 7th link, the MJCF robot given the URDF's limits (MJCF has no
    velocity limits and these actuators none either)."""
    urdf_robot = mobmanip.load_robot(spec_from_urdf(TIAGO_URDF, HANDS, platform="fixed"))
    limits = {
        name: (float(v), float(e))
        for name, v, e in zip(urdf_robot.reduced_velocity_names, urdf_robot.velocity_limits, urdf_robot.effort_limits)
    }
    mjcf_robot = mobmanip.load_robot(spec_from_urdf(TIAGO_MJCF, HANDS, platform="fixed", limits=limits))
    assert urdf_robot.reduced_velocity_names == mjcf_robot.reduced_velocity_names
    assert dict(urdf_robot.spec.reference) == dict(mjcf_robot.spec.reference) == {"torso_lift_joint": 0.175}
    return urdf_robot, mjcf_robot


def _postures(robot, count=8):
    rng = np.random.default_rng(25)
    out = []
    for _ in range(count):
        joints = {}
        for name in robot.reduced_velocity_names:
            limit = robot.description.joints[name].limits
            joints[name] = float(rng.uniform(limit.lower, limit.upper))
        out.append(joints)
    return out


def test_kinematics_from_mjcf_and_urdf_agree_to_round_off(both):
    urdf_robot, mjcf_robot = both
    for joints in _postures(urdf_robot):
        a = mobmanip.analyze(
            urdf_robot, urdf_robot.configuration(joints=joints), task="spatial", measures=("kinematic",)
        )
        b = mobmanip.analyze(
            mjcf_robot, mjcf_robot.configuration(joints=joints), task="spatial", measures=("kinematic",)
        )
        np.testing.assert_allclose(b.unified_jacobian, a.unified_jacobian, rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.kinematic.semi_axes, a.kinematic.semi_axes, rtol=1e-10)


def test_dynamics_differ_by_the_files_mass_data_only(both):
    urdf_robot, mjcf_robot = both
    # the data that differ, as the docs list them
    u, m = urdf_robot.description, mjcf_robot.description
    for k in (2, 3, 5, 6):
        assert m.links[f"arm_right_{k}_link"].inertial.mass == pytest.approx(
            u.links[f"arm_right_{k}_link"].inertial.mass, rel=1e-5
        )
    assert np.allclose(np.linalg.eigvalsh(m.links["arm_right_1_link"].inertial.inertia_matrix), 0.00510233)  # balanced
    assert m.links["arm_right_7_link"].inertial.mass == pytest.approx(1.13701)  # the gripper lumped in
    assert u.links["arm_right_7_link"].inertial.mass == pytest.approx(0.234252)
    # the URDF robot with the MJCF's inertias (joint frames coincide): the MJCF robot's dynamics
    model = pin.Model(urdf_robot.model)
    for j in range(2, model.njoints):
        model.inertias[j] = mjcf_robot.model.inertias[mjcf_robot.model.getJointId(model.names[j])]
    swapped = dataclasses.replace(urdf_robot, model=model, data=model.createData())
    largest = 0.0
    for joints in _postures(urdf_robot):
        a, b, c = (
            mobmanip.analyze(r, r.configuration(joints=joints), task="spatial")
            for r in (urdf_robot, mjcf_robot, swapped)
        )
        largest = max(largest, float(np.max(np.abs(b.dynamic.semi_axes / a.dynamic.semi_axes - 1.0))))
        np.testing.assert_allclose(c.dynamic.semi_axes, b.dynamic.semi_axes, rtol=1e-9)
        np.testing.assert_allclose(
            c.dynamic.center, b.dynamic.center, rtol=0, atol=1e-9 * np.abs(b.dynamic.center).max()
        )
    assert largest > 0.5  # the mass data matter: a semi-axis moves by up to 5 times its size over these postures


def test_the_mjcf_robot_analyses_from_the_command_line(tmp_path, capfd):
    spec = tmp_path / "tiago_mjcf.toml"
    code, out, err = run_cli(capfd, "init-spec", TIAGO_MJCF, "--ee", HANDS[0], "--ee", HANDS[1], "--out", spec)
    assert code == 0
    # MJCF gives no velocity limits and these actuators no effort limits: one message names them all and the flags
    assert err.count("\n") == 1 and "--velocity-limit NAME=V" in err and "--wheel-velocity-limit" in err
    assert "skid_steer" in spec.read_text()  # four plain wheels (Menagerie does not model the omni rollers)
    code, _, err = run_cli(capfd, "analyze", spec)
    assert_one_line_error(code, err, "velocity")
    urdf_robot = mobmanip.load_robot(spec_from_urdf(TIAGO_URDF, HANDS, platform="fixed"))
    limits = []
    for name, v, e in zip(urdf_robot.reduced_velocity_names, urdf_robot.velocity_limits, urdf_robot.effort_limits):
        limits += ["--velocity-limit", f"{name}={v}", "--effort-limit", f"{name}={e}"]
    argv = ["init-spec", TIAGO_MJCF, "--ee", HANDS[0], "--ee", HANDS[1], "--platform", "fixed", *limits, "--out", spec]
    code, _, err = run_cli(capfd, *argv)
    assert code == 0 and err == ""
    out_json = tmp_path / "a.json"
    code, printed, err = run_cli(capfd, "analyze", spec, "--json", out_json)
    assert code == 0, err
    document = json.loads(out_json.read_text())
    assert document["platform"] == "fixed" and len(document["reduced_velocity_names"]) == 14
    assert load_spec(spec).urdf.resolve() == TIAGO_MJCF.resolve()


#: Angles in degrees, a default class, a body with two joints, geoms that carry the mass, a site,
#: position and velocity actuators (the radians variant replaces the degrees).
MINIMAL = mjcf_text("mini")


def test_defaults_degrees_several_joints_per_body_sites_and_actuator_limits(tmp_path, capfd):
    path = tmp_path / "mini.xml"
    path.write_text(MINIMAL)
    d = read_description(path)
    assert [j.name for j in d.moving_joints()] == ["pan", "lift", "elbow"]
    assert d.joints["pan"].child == "shoulder__pan" and d.joints["lift"].parent == "shoulder__pan"
    assert d.joints["lift"].limits.lower == pytest.approx(-np.pi / 2) and d.joints["lift"].axis == (0.0, 1.0, 0.0)
    assert d.limits("pan") == (2.0, 50.0) and d.limits("lift") == (1.5, 60.0) and d.limits("elbow") == (3.0, 20.0)
    assert "tool" in d.links and d.frame_link("tool") == "tool"
    radians = tmp_path / "radians.xml"
    radians.write_text(
        MINIMAL.replace('angle="degree"', 'angle="radian"')
        .replace('range="-90 90"', 'range="-1.5707963267948966 1.5707963267948966"')
        .replace('range="-180 180"', 'range="-3.141592653589793 3.141592653589793"')
        .replace('euler="0 0 45"', 'euler="0 0 0.7853981633974483"')
    )  # noqa: E501
    model_deg, model_rad = (read_description(p).build_model(pin.JointModelPlanar()) for p in (path, radians))
    q = pin.randomConfiguration(model_deg, -np.ones(model_deg.nq), np.ones(model_deg.nq))
    tool = [m.createData() for m in (model_deg, model_rad)]
    for model, data in zip((model_deg, model_rad), tool):
        pin.framesForwardKinematics(model, data, q)
    np.testing.assert_allclose(tool[0].oMf[model_deg.getFrameId("tool")].translation,
                               tool[1].oMf[model_rad.getFrameId("tool")].translation, atol=1e-12)  # fmt: skip
    # the site is an end effector; a fixed-base analysis from the command line
    code, out, err = run_cli(capfd, "analyze", "--urdf", path, "--ee", "tool", "--measure", "kinematic")
    assert code == 0, err
    assert "pan, lift, elbow" in out


def test_what_mobmanip_cannot_model_is_refused_by_name(tmp_path, capfd):
    ball = tmp_path / "ball.xml"
    ball.write_text(MINIMAL.replace('<joint name="elbow"', '<joint name="elbow" type="ball"'))
    with pytest.raises(MjcfError, match="'elbow'.*ball"):
        read_description(ball)
    two = tmp_path / "two.xml"
    two.write_text(
        MINIMAL.replace("</worldbody>", '<body name="table"><geom size="1 1 1" type="box"/></body></worldbody>')
    )
    code, _, err = run_cli(capfd, "init-spec", two, "--list-frames")
    assert_one_line_error(code, err, "'base', 'table'", "one robot body")


def test_an_xml_file_that_is_a_urdf_is_read_as_one(tmp_path):
    path = tmp_path / "robot.xml"
    path.write_text((Path(__file__).resolve().parents[1] / "robots" / "planar_dual_arm.urdf").read_text())
    assert read_description(path).format == "urdf"


#: A base on planar joints of the root body, velocity actuators, a two-joint arm.
HOLONOMIC = mjcf_text("holonomic")


def test_a_base_on_planar_joints_is_an_omnidirectional_platform(tmp_path, capfd):
    """MuJoCo mobile bases are often a slide along x, a slide along y and a hinge about z on the
    root body (TidyBot, the mobile Frankas): the omnidirectional kind, with those joints' limits."""
    path = tmp_path / "holonomic.xml"
    path.write_text(HOLONOMIC)
    description = read_description(path)
    assert [j.name for j in description.planar_base] == ["joint_x", "joint_y", "joint_th"]
    assert [j.name for j in description.moving_joints()] == ["j1", "j2"]
    spec = tmp_path / "holonomic.toml"
    code, out, err = run_cli(capfd, "init-spec", path, "--ee", "grasp", "--out", spec)
    assert code == 0 and err == "", err
    loaded = load_spec(spec)
    assert loaded.platform == "omnidirectional"
    assert dict(loaded.velocity_limits) == {"base_x": 1.0, "base_y": 0.8, "base_yaw": 1.5}
    assert dict(loaded.effort_limits) == {"base_x": 300.0, "base_y": 300.0, "base_yaw": 100.0}
    robot = mobmanip.load_robot(loaded)
    assert robot.reduced_velocity_names == ("base_x", "base_y", "base_yaw", "j1", "j2")
    np.testing.assert_array_equal(robot.velocity_limits, [1.0, 0.8, 1.5, 2.0, 2.5])
    code, out, err = run_cli(capfd, "analyze", spec)
    assert code == 0, err


#: Full inertias on bodies turned in their parents, motors and geared velocity actuators.
FULL_INERTIA = mjcf_text("full")


def test_full_inertias_and_geared_velocity_actuators_read_as_mujoco_reads_them(tmp_path):
    """A body's ``fullinertia`` (off-diagonal xy, xz, yz all different) and a velocity actuator's
    ``gear``, read by mobmanip and by MuJoCo's own parser: every link's mass, centre of mass and
    inertia tensor in its frame agree to 1e-9 (swapping xz and yz is 0.01 kg m^2 off), on a body
    turned in its parent, and each joint's velocity limit is the actuator's largest command over
    its gear, as MuJoCo's compiled gear and ctrlrange give it (multiplying by the gear is 16x off
    on the shoulder)."""
    pytest.importorskip("mujoco")
    path = tmp_path / "full.xml"
    path.write_text(FULL_INERTIA)
    description, model, theirs = read_beside_mujoco(path)
    for joint, body in (("shoulder", "upper"), ("elbow", "lower")):
        mass, com, tensor = compiled_inertia(theirs, body)
        # the description's reading (checks, repairs, the viewer) and Pinocchio's model alike
        for inertia in (_inertia_of(description.links[body]), model.inertias[model.getJointId(joint)]):
            assert inertia.mass == pytest.approx(mass, rel=1e-12)
            np.testing.assert_allclose(inertia.lever, com, atol=1e-12)
            np.testing.assert_allclose(inertia.inertia, tensor, atol=1e-9)
    for joint in ("shoulder", "elbow"):
        on_joint = [a for a in range(theirs.nu) if theirs.actuator_trnid[a, 0] == theirs.joint(joint).id]
        (a,) = [a for a in on_joint if theirs.actuator_biastype[a] == 1]  # the velocity actuator (affine bias)
        expected = np.abs(theirs.actuator_ctrlrange[a]).max() / abs(theirs.actuator_gear[a, 0])
        assert description.limits(joint)[0] == pytest.approx(expected, rel=1e-12)


def test_limits_the_file_lacks_are_given_by_pattern(tmp_path, capfd):
    """Menagerie's TIAGo++ gives no velocity limits: 14 arm joints take two patterns, and a joint
    named exactly keeps its own value; a pattern that matches nothing is one line naming it."""
    spec = tmp_path / "tiago_mjcf.toml"
    argv = ["init-spec", TIAGO_MJCF, "--ee", HANDS[0], "--ee", HANDS[1], "--platform", "fixed",
            "--velocity-limit", "arm_*_joint=1.9", "--effort-limit", "arm_*_joint=39",
            "--velocity-limit", "arm_left_4_joint=1.2", "--out", spec]  # fmt: skip
    code, _, err = run_cli(capfd, *argv)
    assert code == 0 and err == "", err
    robot = mobmanip.load_robot(spec)
    assert len(robot.reduced_velocity_names) == 14
    for name, v, e in zip(robot.reduced_velocity_names, robot.velocity_limits, robot.effort_limits):
        assert (v, e) == ((1.2 if name == "arm_left_4_joint" else 1.9), 39.0), name
    code, _, err = run_cli(capfd, *argv[:-2], "--velocity-limit", "elbow_*=2", "--out", tmp_path / "b.toml")
    assert_one_line_error(code, err, "--velocity-limit elbow_*", "matches no joint")
