"""A team in the meshcat viewer, read back from the exported page in a headless Chromium: every
robot's visuals where Pinocchio places them, the object at its centre, the team's sets there."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from browser_util import VIEWPORT, geometry_corners, legend_share, scene_objects, wait_for_scene, world_matrix
from mobmanip.team import load_team
from mobmanip.team.analysis import analyze_team
from mobmanip.viz.scene import planar_thickness, visual_model
from mobmanip.viz.shapes import ellipsoid_matrix
from mobmanip.viz.team_scene import TEAM_PATH, TeamViewer

BEAM = Path(__file__).resolve().parents[1] / "examples" / "beam_team.toml"
M = "meshcat/"


#: The largest share of the view the legend may cover (issue 39: a third of it hid the team).
LEGEND_SHARE = 0.2


def test_the_exported_team_scene_places_robots_object_and_sets(browser, tmp_path):
    """Also: the beam drawn as a box of the size its description gives, where it lies; the
    legend, its outline notes folded, under LEGEND_SHARE of the view."""
    described = tomllib.loads(BEAM.read_text())["object"]
    analysis = analyze_team(
        load_team(BEAM), measures=("kinematic", "dynamic", "kinematic_polytope", "dynamic_polytope")
    )
    team = analysis.team
    with TeamViewer(analysis) as viewer:
        page_file = viewer.export_html(tmp_path / "team.html")
        scales = dict(viewer.scales)
    center = team.held_object.center
    kin = f"{M}{TEAM_PATH}/sets/kinematic"
    poly = f"{M}{TEAM_PATH}/sets/kinematic_polytope"
    page = browser.new_page(viewport=VIEWPORT)
    try:
        page.goto(page_file.as_uri())
        wait_for_scene(page, (f"{kin}/shape", f"{poly}/edges", f"{M}{TEAM_PATH}/object/center"))
        objects = scene_objects(page)
        # each robot's visual geometry where Pinocchio puts it at the robot's configuration
        for member in team.members:
            model, geometry = visual_model(member.robot)
            data, gdata = model.createData(), geometry.createData()
            pin.updateGeometryPlacements(model, data, geometry, gdata, member.q)
            checked = 0
            for k, g in enumerate(geometry.geometryObjects):
                path = f"{M}{TEAM_PATH}/robots/{member.name}/visuals/{g.name}"
                if path not in objects:
                    continue
                T = world_matrix(page, path, node=True)
                np.testing.assert_allclose(T[:3, 3], gdata.oMg[k].translation, atol=1e-6)
                np.testing.assert_allclose(T[:3, :3], gdata.oMg[k].rotation, atol=1e-6)
                checked += 1
            assert checked >= 5, member.name
        np.testing.assert_allclose(world_matrix(page, f"{M}{TEAM_PATH}/object/center")[:3, 3], center, atol=1e-6)
        # the beam: a box of its described size about its described centre, turned by its yaw
        # (90 deg: its 1.5 m along the world's y)
        corners = geometry_corners(page, f"{M}{TEAM_PATH}/object/body")
        yaw = np.radians(described["yaw_deg"])
        axes = np.array([[np.cos(yaw), np.sin(yaw), 0.0], [-np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
        local = (corners - described["position"]) @ axes.T  # in the beam's own axes
        np.testing.assert_allclose(np.ptp(local, axis=0), described["size"], atol=1e-6)
        np.testing.assert_allclose(local.mean(axis=0), 0.0, atol=1e-6)
        share = legend_share(page)
        assert share < LEGEND_SHARE, share
        # the kinematic ellipsoid's group is the one the single-robot viewer would place there
        expected = ellipsoid_matrix(
            analysis.measure("kinematic"), team.task, center, scales["velocity"], planar_thickness("kinematic")
        )
        np.testing.assert_allclose(world_matrix(page, kin, node=True), expected, atol=1e-6)
        # the polytope's outline, the largest velocity set, reaches the viewer's size (0.5 m)
        assert objects[f"{poly}/edges"]["type"] == "LineSegments"
        shadow = analysis.measure("kinematic_polytope").project((0, 1)).vertices
        assert scales["velocity"] * np.max(np.linalg.norm(shadow, axis=1)) == pytest.approx(0.5, rel=1e-12)
    finally:
        page.close()
