"""The description seam: a robot file is read once, by the format its suffix names, into one
neutral description.

- A toy format registered from its own file (``tests/toy_format.py``: a gzip'd URDF, ``.urdfz``,
  one registration line) loads a robot through a spec, the command line's ``--urdf`` and
  ``init-spec`` with no edit anywhere else, and every result equals the plain URDF's.
- The registry refuses what it cannot read, in one line naming the file and the known suffixes.
- The neutral description of every built-in robot matches Pinocchio's own reading of the same
  text (urdfdom, an independent parser): joint names, types, axes, placements, limits, masses.
"""

from __future__ import annotations

import dataclasses
import json
import math
import pickle

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from hostile_util import PAPER_SPEC_TEXT, assert_one_line_error, run_cli
from mobmanip.descriptions import (
    DescriptionFormat,
    RobotDescription,
    format_for,
    known_suffixes,
    read_description,
    register_format,
    unregister_format,
)
from mobmanip.descriptions.resources import builtin_robot_names, builtin_robots_dir
from mobmanip.errors import ArgumentError, DescriptionError, MobmanipError, UnknownFormatError, UrdfError
from mobmanip.robot.collision import SelfCollision
from mobmanip.robot.spec import find_spec
from mobmanip.viz.scene import visual_model
from toy_format import FORMAT, write_urdfz

PAPER_URDF = builtin_robots_dir() / "planar_dual_arm.urdf"
TOOLS = ("arm_right_tool_link", "arm_left_tool_link")


def _toy_robot(tmp_path, name: str = "planar_dual_arm"):
    """The built-in robot ``name`` with its URDF as a ``.urdfz`` beside a copy of its spec."""
    spec = find_spec(name)
    urdfz = write_urdfz(spec.urdf, tmp_path / "robot.urdfz")
    toy = dataclasses.replace(spec, urdf=urdfz)
    return spec, toy


def _same_document(a, b, where: str = "") -> None:
    """Two JSON documents equal: the same keys, lists and strings, numbers to 1e-12 (relative
    to their size, at least 1)."""
    assert type(a) is type(b), where
    if isinstance(a, dict):
        assert list(a) == list(b), where
        for key in a:
            _same_document(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            _same_document(x, y, f"{where}[{k}]")
    elif isinstance(a, float):
        assert abs(a - b) <= 1e-12 * max(1.0, abs(a)), (where, a, b)
    else:
        assert a == b, where


# ----- a toy format from its own file


def test_the_toy_format_is_registered_by_its_own_file():
    assert format_for("robot.urdfz") is FORMAT
    assert format_for("ROBOT.URDFZ") is FORMAT  # suffixes are matched case-insensitively
    assert format_for("robot.urdf").name == "urdf"
    assert ".urdfz" in known_suffixes() and ".urdf" in known_suffixes()


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual_torso"])
def test_a_robot_loads_through_the_toy_format_and_analyses_as_the_plain_urdf(tmp_path, name, rng):
    spec, toy = _toy_robot(tmp_path, name)
    plain, wrapped = mobmanip.load_robot(spec), mobmanip.load_robot(toy)
    assert wrapped.description.format == "urdfz" and plain.description.format == "urdf"
    assert wrapped.description.source == toy.urdf
    # the same robot: every part of the two descriptions is equal
    assert wrapped.description.joints == plain.description.joints
    assert wrapped.description.links == plain.description.links
    assert wrapped.reduced_velocity_names == plain.reduced_velocity_names
    np.testing.assert_array_equal(wrapped.velocity_limits, plain.velocity_limits)
    np.testing.assert_array_equal(wrapped.effort_limits, plain.effort_limits)
    for _ in range(3):
        joints = {j: float(rng.uniform(-1.0, 1.0)) for arm in spec.arms for j in arm.joints}
        q = plain.configuration(tuple(rng.uniform(-1.0, 1.0, 3)), joints)
        a, b = mobmanip.analyze(plain, q, method="exact"), mobmanip.analyze(wrapped, q, method="exact")
        _same_document(json.loads(json.dumps(a.to_dict())), json.loads(json.dumps(b.to_dict())))


def test_the_viewer_and_self_collision_read_the_toy_format_too(tmp_path):
    spec, toy = _toy_robot(tmp_path)
    plain, wrapped = mobmanip.load_robot(spec), mobmanip.load_robot(toy)
    (model_a, geometry_a), (model_b, geometry_b) = visual_model(plain), visual_model(wrapped)
    assert list(model_a.names) == list(model_b.names)
    assert [g.name for g in geometry_a.geometryObjects] == [g.name for g in geometry_b.geometryObjects]
    q = plain.configuration((0.1, -0.2, 0.3), {"arm_right_2_joint": 0.9, "arm_left_2_joint": -0.9})
    distances_a, gradient_a = SelfCollision(plain).distances(q)
    distances_b, gradient_b = SelfCollision(wrapped).distances(q)
    np.testing.assert_allclose(distances_b, distances_a, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gradient_b, gradient_a, rtol=0, atol=1e-12)


def test_a_spec_names_a_toy_file_like_any_urdf(tmp_path):
    write_urdfz(PAPER_URDF, tmp_path / "robot.urdfz")
    (tmp_path / "robot.toml").write_text(PAPER_SPEC_TEXT.replace("planar_dual_arm.urdf", "robot.urdfz"))
    robot = mobmanip.load_robot(tmp_path / "robot.toml")
    assert robot.description.format == "urdfz"
    assert robot.nx == mobmanip.load_robot("planar_dual_arm").nx


def test_the_command_line_reads_the_toy_format_with_urdf_and_init_spec(tmp_path, capfd):
    urdf = tmp_path / "robot.urdf"
    urdf.write_bytes(PAPER_URDF.read_bytes())
    urdfz = write_urdfz(urdf, tmp_path / "robot.urdfz")
    documents = []
    for path in (urdf, urdfz):
        out = tmp_path / f"{path.suffix[1:]}.json"
        code, _, err = run_cli(capfd, "analyze", "--urdf", path, "--ee", TOOLS[0], "--ee", TOOLS[1], "--json", out)
        assert code == 0, err
        documents.append(json.loads(out.read_text()))
    _same_document(*documents)
    spec = tmp_path / "from_toy.toml"
    code, _, err = run_cli(capfd, "init-spec", urdfz, "--ee", TOOLS[0], "--ee", TOOLS[1], "--out", spec)
    assert code == 0, err
    assert 'urdf = "robot.urdfz"' in spec.read_text()
    code, out, err = run_cli(capfd, "init-spec", urdfz, "--list-frames")
    assert code == 0 and TOOLS[0] in out


def test_a_broken_toy_file_is_one_line_naming_it(tmp_path, capfd):
    broken = tmp_path / "robot.urdfz"
    broken.write_bytes(b"not gzip at all")
    with pytest.raises(DescriptionError) as info:
        read_description(broken)
    assert info.value.path == str(broken)
    code, _, err = run_cli(capfd, "analyze", "--urdf", broken, "--ee", TOOLS[0])
    assert_one_line_error(code, err, str(broken), "not a gzip'd URDF")


def test_the_toy_format_keeps_the_urdf_checks(tmp_path):
    text = PAPER_URDF.read_text().replace('<mass value="5.0"/>', '<mass value="nan"/>', 1)
    (tmp_path / "bad.urdf").write_text(text)
    urdfz = write_urdfz(tmp_path / "bad.urdf", tmp_path / "bad.urdfz")
    with pytest.raises(UrdfError) as info:  # its content is a URDF: its checks and their messages
        read_description(urdfz)
    assert str(urdfz) in str(info.value) and "mass is not finite: nan" in str(info.value)


# ----- the registry


def test_an_unknown_suffix_is_one_error_naming_the_file_and_the_known_suffixes(tmp_path, capfd):
    path = tmp_path / "robot.sdf"
    path.write_text("<sdf/>")
    with pytest.raises(UnknownFormatError) as info:
        read_description(path)
    message = str(info.value)
    assert str(path) in message and "'.sdf'" in message
    for suffix in known_suffixes():
        assert suffix in message
    assert isinstance(info.value, MobmanipError) and info.value.known == known_suffixes()
    (tmp_path / "robot.toml").write_text(PAPER_SPEC_TEXT.replace("planar_dual_arm.urdf", "robot.sdf"))
    code, _, err = run_cli(capfd, "analyze", tmp_path / "robot.toml")
    assert_one_line_error(code, err, str(path), ".urdf")


def test_registering_a_clashing_format_is_refused_unless_it_replaces():
    def read(path, **options):  # pragma: no cover - never called
        raise AssertionError

    with pytest.raises(ArgumentError, match="clashes with registered format 'urdf'"):
        register_format(DescriptionFormat("urdf2", (".urdf",), read))
    assert register_format(FORMAT) is FORMAT  # the same one again: nothing happens
    longer = register_format(DescriptionFormat("toy_longer", (".b.urdfz",), read))
    try:
        assert format_for("x.b.urdfz") is longer and format_for("x.urdfz") is FORMAT  # longest suffix wins
    finally:
        unregister_format("toy_longer")
    assert "toy_longer" not in [f.name for f in mobmanip.descriptions.formats().values()]
    with pytest.raises(ArgumentError):
        DescriptionFormat("bad", ("urdfz",), read)  # a suffix starts with its dot


def test_a_description_is_immutable_and_pickles(tmp_path):
    description = read_description(PAPER_URDF)
    with pytest.raises(dataclasses.FrozenInstanceError):
        description.name = "other"  # type: ignore[misc]
    with pytest.raises(TypeError):
        description.joints["x"] = description.joints["wheel_right_joint"]  # type: ignore[index]
    placements = description.zero_configuration_placements()
    with pytest.raises(ValueError):
        placements["wheel_right_joint"][0, 3] = 1.0
    again = pickle.loads(pickle.dumps(description))
    assert again == description and again.model_text == description.model_text
    assert again.build_model().nq == description.build_model().nq


def test_the_tree_questions_of_the_paper_robot():
    description = read_description(PAPER_URDF)
    assert description.root_link == "base_link"
    chain = [j.name for j in description.chain("arm_right_tool_link")]
    assert chain[-4:] == ["arm_right_1_joint", "arm_right_2_joint", "arm_right_3_joint", "arm_right_tool_joint"]
    assert description.parent_joint("arm_right_1_link").name == "arm_right_1_joint"
    assert description.parent_joint("base_link") is None
    assert description.subtree_links("arm_right_2_joint") == [
        "arm_right_2_link",
        "arm_right_3_link",
        "arm_right_tool_link",
    ]
    assert description.frame_link("arm_right_tool_joint") == "arm_right_tool_link"
    assert description.is_leaf("arm_left_tool_link") and not description.is_leaf("base_link")
    assert description.limits("wheel_right_joint") == (13.333333333333334, 200.0)


# ----- the description and Pinocchio, two readings of one file


def _builtin_descriptions() -> dict[str, RobotDescription]:
    out: dict[str, RobotDescription] = {}
    for name in builtin_robot_names():
        spec = find_spec(name)
        if str(spec.urdf) not in {str(d.source) for d in out.values()}:
            out[name] = read_description(spec.urdf, package_dirs=spec.package_dirs)
    return out


DESCRIPTIONS = _builtin_descriptions()

#: Pinocchio's joint models per URDF joint type (an axis along x, y, z or another one).
PINOCCHIO_TYPES = {
    "revolute": ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned"),
    "continuous": ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ", "JointModelRevoluteUnboundedUnaligned"),
    "prismatic": ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned"),
}


def _rigid_links(description: RobotDescription, link: str) -> list[str]:
    """``link`` and every link fixed to it (reached through fixed joints only)."""
    out, stack = [], [link]
    while stack:
        here = stack.pop()
        out.append(here)
        stack.extend(j.child for j in description.child_joints(here) if j.type == "fixed")
    return out


@pytest.mark.parametrize("name", list(DESCRIPTIONS))
def test_the_description_matches_pinocchios_reading_of_the_same_text(name):
    description = DESCRIPTIONS[name]
    model = pin.buildModelFromXML(description.model_text)  # urdfdom parses the text on its own; fixed base
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    moving = [j for j in description.joints.values() if j.type != "fixed"]
    assert sorted(model.names[1:]) == sorted(j.name for j in moving)
    placements = description.zero_configuration_placements()
    for joint in moving:
        k = model.getJointId(joint.name)
        pinocchio_joint = model.joints[k]
        assert pinocchio_joint.shortname() in PINOCCHIO_TYPES[joint.type], joint.name
        # where it sits and how it turns at the zero configuration, in the root link's frame
        np.testing.assert_allclose(data.oMi[k].homogeneous, placements[joint.name], rtol=0, atol=1e-12)
        jacobian = pin.computeJointJacobian(model, data, pin.neutral(model), k)  # in the joint's own frame
        column = jacobian[:, pinocchio_joint.idx_v]
        np.testing.assert_allclose(column[:3] if joint.type == "prismatic" else column[3:], joint.unit_axis, atol=1e-12)
        # limits as written
        velocity, effort = description.limits(joint.name)
        if velocity is not None:
            assert model.velocityLimit[pinocchio_joint.idx_v] == velocity, joint.name
        if effort is not None:
            assert model.effortLimit[pinocchio_joint.idx_v] == effort, joint.name
        if joint.type in ("revolute", "prismatic") and joint.limits is not None:
            if joint.limits.lower is not None:
                assert model.lowerPositionLimit[pinocchio_joint.idx_q] == joint.limits.lower, joint.name
            if joint.limits.upper is not None:
                assert model.upperPositionLimit[pinocchio_joint.idx_q] == joint.limits.upper, joint.name
        # the mass each joint carries rigidly: its child and everything fixed to it
        mass = sum(
            description.links[link].inertial.mass
            for link in _rigid_links(description, joint.child)
            if description.links[link].inertial is not None
        )
        assert math.isclose(model.inertias[k].mass, mass, rel_tol=1e-12, abs_tol=1e-15), joint.name
    total = sum(link.inertial.mass for link in description.links.values() if link.inertial is not None)
    assert math.isclose(sum(inertia.mass for inertia in model.inertias), total, rel_tol=1e-12)


def test_geometry_comes_in_two_kinds():
    description = read_description(PAPER_URDF)
    model = description.build_model()
    assert description.build_geometry(model, "collision").ngeoms > 0
    assert description.build_geometry(model, "visual").ngeoms > 0
    with pytest.raises(ArgumentError, match="collision, visual"):
        description.build_geometry(model, "inertial")
