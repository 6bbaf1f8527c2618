"""Team descriptions (TOML): the shipped example, inverse kinematics to the grasp points, and
errors that name the bad value and where it is."""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mobmanip.errors import MobmanipError, TeamError
from mobmanip.team import box_inertia, hand_positions, load_team, team_from_dict

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml"


@pytest.fixture(scope="module")
def example_data():
    return tomllib.loads(EXAMPLE.read_text())


@pytest.fixture(scope="module")
def example():
    return load_team(EXAMPLE)


def test_the_example_places_every_hand_on_its_grasp_point(example, example_data):
    obj = example_data["object"]
    yaw = math.radians(obj["yaw_deg"])
    R = np.array([[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    center = np.array(obj["position"])
    wanted = [center + R @ np.array(g["point"]) for r in example_data["robots"] for g in r["grasps"]]
    hands = np.vstack([hand_positions(m) for m in example.members])
    # reach = true solved the arms: the hands meet their grasp points in the horizontal plane
    np.testing.assert_allclose(hands[:, :2], np.array(wanted)[:, :2], atol=1e-8)
    # the beam's ends are 1.5 m apart
    assert np.linalg.norm(hands[0, :2] - hands[2, :2]) == pytest.approx(1.5, abs=1e-8)
    # its inertia is the uniform box's, turned with the beam: long axis along world y
    I = example.held_object.inertia
    principal = box_inertia(obj["mass"], obj["size"])
    np.testing.assert_allclose(np.diag(I), [principal[1], principal[0], principal[2]], atol=1e-12)
    # the object offsets are the actual hands' about the given centre
    np.testing.assert_allclose(example.held_object.offsets, hands - center, atol=0)


def test_a_box_inertia_is_the_textbook_one():
    # a thin rod of length L about its middle: m L^2 / 12 across, zero along
    I = box_inertia(3.0, (2.0, 0.0, 0.0))
    np.testing.assert_allclose(I, [0.0, 1.0, 1.0])


def test_a_cylinder_is_drawn_and_weighed_as_one(example_data):
    """A beam given as a cylinder along its x axis: its inertia the textbook solid cylinder's
    (m r^2 / 2 about the axis, m (3 r^2 + L^2) / 12 across), turned with the beam (long axis along
    world y); its shape kept for the drawings, with its length and diameter as extents."""
    data = copy.deepcopy(example_data)
    obj = data["object"]
    obj.pop("size")
    obj.update(shape="cylinder", length=1.5, radius=0.04)
    team = team_from_dict(data, EXAMPLE.parent)
    m, r, L = obj["mass"], 0.04, 1.5
    across = m * (3 * r * r + L * L) / 12
    np.testing.assert_allclose(np.diag(team.held_object.inertia), [across, m * r * r / 2, across], atol=1e-12)
    assert team.object_shape.kind == "cylinder" and team.object_shape.size == (1.5, 0.08, 0.08)
    assert team.object_shape.describe() == "cylinder 1.5 m long, 0.04 m radius"
    # the box of the example keeps its size; a team built in Python has no shape to draw
    assert load_team(EXAMPLE).object_shape.size == tuple(example_data["object"]["size"])
    corners = load_team(EXAMPLE).object_shape.corners(np.zeros(3), math.radians(90.0))
    np.testing.assert_allclose(np.ptp(corners, axis=0), [0.08, 1.5, 0.08], atol=1e-12)


def _broken(data, edit):
    data = copy.deepcopy(data)
    edit(data)
    return data


def _set(path, value):
    def edit(data):
        target = data
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value

    return edit


@pytest.mark.parametrize(
    "edit, words",
    [
        (_set(("robots", 0, "robot"), "no_such_robot"), ["#1", "no_such_robot"]),
        (_set(("robots", 1, "name"), "south"), ["#2", "'south'", "already used"]),
        (_set(("robots", 1, "reach"), False), ["north", "'right'", "from its grasp point"]),
        (_set(("robots", 0, "position"), [0.0, -2.5]), ["south", "from its grasp point"]),
        (_set(("robots", 1, "grasps", 0, "arm"), "middle"), ["north", "grasp #1", "'middle'", "right"]),
        (_set(("robots", 1, "grasps", 1, "arm"), "right"), ["north", "grasp #2", "'right'", "already"]),
        (_set(("object", "mass"), -1.0), ["[object] mass", "-1.0"]),
        (_set(("object", "colour"), "red"), ["[object]", "colour"]),
        (lambda d: d["object"].update(inertia=[1.0, 2.0]) or d["object"].pop("size"), ["inertia", "[1.0, 2.0]"]),
        (_set(("object", "inertia"), [1.0, 2.0, 3.0]), ["either size or inertia"]),
        (_set(("object", "shape"), "sphere"), ["[object]", "'sphere'", "cylinder"]),
        (_set(("object", "radius"), 0.04), ["[object]", "radius", 'shape = "cylinder"']),
        (_set(("object", "shape"), "cylinder"), ["[object]", "length and radius", "['size']"]),
        (
            lambda d: d["object"].update(shape="cylinder", length=1.5, radius=-0.1) or d["object"].pop("size"),
            ["[object] radius", "-0.1"],
        ),  # fmt: skip
        (_set(("robots", 0, "posture"), "dance"), ["south", "'dance'"]),
        (_set(("robots", 0, "posture"), "hold"), ["south", "no [hold]"]),
        (_set(("robots", 0, "yaw_deg"), float("nan")), ["south", "yaw_deg", "nan"]),
        (_set(("robots", 0, "joints", "arm_right_9_joint"), 0.1), ["south", "arm_right_9_joint"]),
        (_set(("task",), "flying"), ["flying", "planar"]),
        (_set(("tolerance",), 0.0), ["tolerance", "0.0"]),
        (_set(("robots",), []), ["no [[robots]]"]),
        (_set(("robots", 0, "grasps"), []), ["south", "grasps"]),
    ],
)
def test_a_bad_description_names_what_is_wrong(example_data, edit, words):
    with pytest.raises(TeamError) as caught:
        team_from_dict(_broken(example_data, edit), EXAMPLE.parent, where="beam_team.toml")
    message = str(caught.value)
    for word in words:
        assert word in message, message
    assert isinstance(caught.value, MobmanipError)


def test_an_unreadable_file_is_a_team_error(tmp_path):
    bad = tmp_path / "t.toml"
    bad.write_text("name = ")
    with pytest.raises(TeamError, match="not valid TOML"):
        load_team(bad)
    with pytest.raises(TeamError, match="cannot read"):
        load_team(tmp_path / "missing.toml")


def test_a_robot_spec_path_is_found_next_to_the_description(tmp_path, example_data):
    root = Path(__file__).resolve().parents[1] / "robots"
    spec = (
        (root / "planar_dual_arm.toml")
        .read_text()
        .replace('urdf = "planar_dual_arm.urdf"', f'urdf = "{(root / "planar_dual_arm.urdf").as_posix()}"')
    )
    (tmp_path / "mine.toml").write_text(spec)
    data = _broken(example_data, _set(("robots", 1, "robot"), "mine.toml"))
    team = team_from_dict(data, tmp_path)
    assert team.members[1].robot.name == "planar_dual_arm"


def test_the_shadow_of_each_robots_own_set_is_the_hull_of_its_vertices(example):
    """Regression: projecting an intersection-form polytope whose shadow has several candidate
    facets through one vertex once failed in the 2-D hull enumeration."""
    from scipy.spatial import ConvexHull

    from mobmanip.team.analysis import analyze_team

    an = analyze_team(example, measures=("kinematic_polytope",))
    sets = [an.measure("kinematic_polytope")] + [an.member_set("kinematic_polytope", i) for i in range(2)]
    d = np.random.default_rng(3).normal(size=(200, 2))
    for polytope in sets:
        shadow = polytope.project((0, 1)).vertices
        V = polytope.vertices[:, :2]
        hull = V[ConvexHull(V).vertices]
        assert len(shadow) == len(hull)
        np.testing.assert_allclose((d @ shadow.T).max(axis=1), (d @ hull.T).max(axis=1), rtol=1e-12, atol=1e-12)
