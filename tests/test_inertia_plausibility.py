"""Plausibility of inertial data (issue 38, item 3): a link whose rotational inertia is far below
what its mass has in its geometry's bounding box is warned, naming the link and the numbers, and
refused under --strict, as the vendor flaws are (:mod:`mobmanip.descriptions.flaws`).

The reference numbers are computed here from the files' own values: a solid box of mass m and
edges a, b, c has the trace m (a^2 + b^2 + c^2) / 6 (each moment m (b^2 + c^2) / 12, and so on).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mobmanip.descriptions import read_description
from mobmanip.descriptions.flaws import PLAUSIBLE_TRACE_FRACTION, ImplausibleInertia
from mobmanip.descriptions.resources import example_robot_data_share

DATA = Path(__file__).resolve().parent / "data"
ROOT = Path(__file__).resolve().parents[1]
TIDYBOT = DATA / "menagerie_stanford_tidybot" / "tidybot.xml"
#: TidyBot's base: 60 kg, diaginertia 0.001 each; its geometry in this fixture is five
#: placeholder boxes of 0.0625 x 0.03125 x 0.03125 m at its origin.
BASE_MASS, BASE_MOMENT, BOX = 60.0, 0.001, (0.0625, 0.03125, 0.03125)


def implausible(description) -> list[ImplausibleInertia]:
    return [flaw for flaw in description.flaws if isinstance(flaw, ImplausibleInertia)]


def test_tidybots_base_is_named_with_its_numbers():
    (flaw,) = implausible(read_description(TIDYBOT))
    box_trace = BASE_MASS * sum(e * e for e in BOX) / 6
    assert flaw.link == "base_link" and flaw.mass == BASE_MASS
    assert flaw.trace == pytest.approx(3 * BASE_MOMENT, rel=1e-15)
    np.testing.assert_allclose(flaw.extents, BOX, rtol=1e-12)
    assert flaw.box_trace == pytest.approx(box_trace, rel=1e-12)
    text = flaw.warning
    assert text.startswith("link 'base_link': rotational inertia implausibly small for its mass: 60 kg")
    for number in (
        "0.001, 0.001, 0.001",
        "trace 0.003",
        "0.0625 x 0.0312 x 0.0312 m",
        f"{box_trace:.3g}",
        "19.5 times",
    ):
        assert number in text, (number, text)


@pytest.fixture(scope="module")
def tidybot_spec(tmp_path_factory):
    spec = tmp_path_factory.mktemp("tidybot") / "tidybot.toml"
    argv = ["init-spec", str(TIDYBOT), "--ee", "pinch_site", "--velocity-limit", "joint_*=1.4"]
    for name in ("base_x", "base_y", "base_yaw"):
        argv += ["--velocity-limit", f"{name}=1", "--effort-limit", f"{name}=200"]
    assert mobmanip.cli.main([*argv, "--out", str(spec)]) == 0
    return spec


def test_analyze_warns_once_and_strict_refuses(tidybot_spec, capfd):
    code, out, err = run_cli(capfd, "analyze", tidybot_spec)
    assert code == 0, err
    assert err.count("warning: link 'base_link': rotational inertia implausibly small") == 1
    assert "--strict refuses instead" in err
    code, _, err = run_cli(capfd, "analyze", tidybot_spec, "--strict")
    assert_one_line_error(code, err, "link 'base_link' rotational inertia implausibly small", "drop --strict")


@pytest.mark.parametrize(
    "path",
    [
        DATA / "menagerie_tiago_dual" / "tiago_dual.xml",
        DATA / "menagerie_franka_mobile_fr3_duo" / "mobile_fr3_duo.xml",
        DATA / "menagerie_hello_robot_stretch_3" / "stretch.xml",
        ROOT / "robots" / "planar_dual_arm.urdf",
        "tiago_description/robots/tiago_dual.urdf",
        "baxter_description/urdf/baxter.urdf",
        "talos_data/robots/talos_reduced.urdf",
        "anymal_b_simple_description/robots/anymal-kinova.urdf",
    ],
    ids=lambda p: Path(p).stem,
)
def test_well_made_robots_are_not_warned(path):
    """Including files whose light frames carry placeholder point masses (TIAGo's and TALOS's
    force sensors, Baxter's covers): too small a share of the robot to be judged."""
    if isinstance(path, str):
        path = example_robot_data_share() / "example-robot-data" / "robots" / path
    assert implausible(read_description(path)) == []


URDF = """<robot name="block">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <joint name="j" type="revolute"><parent link="base"/><child link="body"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
  <link name="body">
    <inertial><mass value="MASS"/><inertia ixx="M" iyy="M" izz="M" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.3 0 0" rpy="0 0 0.5"/><geometry><box size="0.4 0.2 0.1"/></geometry></collision>
  </link>
</robot>
"""


@pytest.mark.parametrize(("factor", "warned"), [(0.999, True), (1.001, False)])
def test_the_threshold_is_a_tenth_of_the_solid_box_in_the_link_frame(tmp_path, factor, warned):
    """A 10 kg link whose box geometry is turned 0.5 rad about z: its bounding box in the link
    frame is the turned box's, and the rule's line is a tenth of a solid box's trace there."""
    c, s = np.cos(0.5), np.sin(0.5)
    edges = np.array([0.4 * c + 0.2 * s, 0.4 * s + 0.2 * c, 0.1])
    box_trace = 10.0 * float(edges @ edges) / 6
    moment = factor * PLAUSIBLE_TRACE_FRACTION * box_trace / 3
    path = tmp_path / "block.urdf"
    path.write_text(URDF.replace("MASS", "10").replace('"M"', f'"{moment!r}"'))
    found = implausible(read_description(path))
    assert [f.link for f in found] == (["body"] if warned else [])
    if warned:
        np.testing.assert_allclose(found[0].extents, edges, rtol=1e-12)


def test_a_light_link_is_not_judged(tmp_path):
    """Under 2 % of the robot's mass: a point mass on a frame does not matter to the measures."""
    path = tmp_path / "light.urdf"
    path.write_text(URDF.replace("MASS", "0.02").replace('"M"', '"0"').replace('value="1"', 'value="1.5"'))
    assert implausible(read_description(path)) == []


def _mesh_files():
    """Mesh files of several exporters: TIAGo's STL and COLLADA (one file with unused vertices),
    Romeo's COLLADA placed by translate/rotate/scale nodes (a scale of 0.01), an OBJ whose faces
    leave vertices out (Alexander's hip)."""
    share = example_robot_data_share() / "example-robot-data" / "robots"
    names = [
        "tiago_description/meshes/torso/torso_lift_collision_neck.dae",
        "tiago_description/meshes/torso/torso_lift_collision_core.dae",
        "romeo_description/meshes/V1/visual/RWristYaw.dae",
        "romeo_description/meshes/V1/visual/Torso.dae",
        "alexander_description/meshes/LeftHipRollLink.obj",
    ]
    found = [share / name for name in names if (share / name).is_file()]
    found += sorted((share / "tiago_description" / "meshes" / "arm").glob("*.stl"))[:4]
    return found


def test_mesh_bounds_are_the_mesh_librarys(recwarn):
    """The bounds read with NumPy (no mesh library is imported when a robot loads) equal trimesh's
    for every format read: vertices no face uses are left out, COLLADA nodes placed."""
    trimesh = pytest.importorskip("trimesh")
    from mobmanip.descriptions.extents import mesh_bounds

    files = _mesh_files()
    assert len(files) >= 8
    for path in files:
        ours = np.array(mesh_bounds.__wrapped__(str(path)))
        theirs = np.asarray(trimesh.load(str(path), force="mesh", process=False).bounds)
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-6 * np.ptp(theirs, axis=0).max(), err_msg=str(path))
