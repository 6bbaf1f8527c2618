"""Exported viewer pages keep each mesh file once, compressed (issue 28, item 10): every built-in
robot's page and a motion page stay under 10 MB, the commands a page rebuilds are meshcat's own
(checked by a rebuild written in the tests, ``page_util``), and a real browser draws the same scene
from the exported page as from the live viewer."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import mobmanip
from browser_util import VIEWPORT, scene_objects, screenshot, wait_for_scene, world_matrix
from hostile_util import run_cli
from mobmanip.descriptions.resources import builtin_robot_names
from mobmanip.viz.compact_page import compact
from mobmanip.viz.scene import EllipsoidViewer, analyze_pair
from page_util import STL_RECORD, meshcat_commands, page_commands

LIMIT = 10 * 1024 * 1024  # bytes
umsgpack = pytest.importorskip("umsgpack")


@pytest.mark.parametrize("name", builtin_robot_names())
def test_every_built_in_robot_exports_a_page_under_10_mb(name, tmp_path, capfd):
    page = tmp_path / f"{name}.html"
    code, out, err = run_cli(capfd, "view", name, "--export", page)
    assert code == 0, err
    assert page.stat().st_size < LIMIT, page.stat().st_size
    assert page_commands(page.read_text()), "no compressed store: the page was not rewritten"


def test_a_motion_page_stays_under_10_mb(tmp_path, capfd):
    motion = tmp_path / "m.csv"
    motion.write_text("t,platform_x,platform_y,platform_yaw\n0,0,0,0\n1,0.2,0,0\n2,0.4,0,0.1\n3,0.6,0.05,0.2\n")
    page = tmp_path / "motion.html"
    code, out, err = run_cli(capfd, "trajectory", "stretch", motion, "--export", page)  # the largest meshes
    assert code == 0, err
    assert page.stat().st_size < LIMIT, page.stat().st_size


def _mesh_files(command: dict) -> list:
    """(format, data) of each mesh file a decoded set_object command carries."""
    if command.get("type") != "set_object":
        return []
    obj = command["object"]
    found = [(g["format"], g["data"]) for g in obj.get("geometries", []) if g.get("type") == "_meshfile"]
    if obj["object"].get("type") == "_meshfile_object":
        found.append((obj["object"]["format"], obj["object"]["data"]))
    return found


def _same_command(mine: dict, theirs: dict) -> None:
    """Two decoded commands equal, except that a binary STL's face normals may be recomputed
    from its corners (within 2.6 deg of the stored ones; corners and attributes bit for bit)."""
    for (fa, a), (fb, b) in zip(_mesh_files(mine), _mesh_files(theirs), strict=True):
        assert fa == fb
        a, b = getattr(a, "data", a), getattr(b, "data", b)
        if a == b:
            continue
        assert fa == "stl" and a[:84] == b[:84]
        ra, rb = (np.frombuffer(x, STL_RECORD, offset=84) for x in (a, b))
        np.testing.assert_array_equal(ra["corners"].view(np.uint32), rb["corners"].view(np.uint32))
        np.testing.assert_array_equal(ra["attribute"], rb["attribute"])
        na, nb = ra["normal"].astype(float), rb["normal"].astype(float)
        c = ra["corners"].astype(float)
        faces = np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1) > 0
        cos = np.einsum("ij,ij->i", na, nb)[faces] / (np.linalg.norm(na, axis=1) * np.linalg.norm(nb, axis=1))[faces]
        assert cos.min() > np.cos(np.radians(2.6))
    for command in (mine, theirs):  # the rest is compared decoded, mesh files taken out
        if command.get("type") != "set_object":
            continue
        for g in command["object"].get("geometries", []):
            if g.get("type") == "_meshfile":
                g.pop("data")
        if command["object"]["object"].get("type") == "_meshfile_object":
            command["object"]["object"].pop("data")
    assert mine == theirs


@pytest.mark.parametrize("name", ["tiago_dual", "stretch", "panda"])
def test_the_page_rebuilds_meshcats_commands_with_each_mesh_stored_once(name):
    robot = mobmanip.load_robot(name)
    q = robot.neutral()
    analysis, locked = analyze_pair(robot, q, None)
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis, locked)
        original = viewer._vis.static_html()  # meshcat's own page
    theirs = meshcat_commands(original)
    page = compact(original)
    mine = page_commands(page)
    assert mine is not None and len(mine) == len(theirs) and len(theirs) > 10
    distinct = set()
    for a, b in zip(mine, theirs, strict=True):
        da, db = umsgpack.unpackb(a), umsgpack.unpackb(b)
        for _, d in _mesh_files(db):
            raw = getattr(d, "data", d)
            if len(raw) >= 1024:  # smaller ones stay inside their command
                distinct.add(raw.encode("utf-8") if isinstance(raw, str) else raw)
        _same_command(da, db)
    table = re.search(r'id="mobmanip-scene-table">(.*?)</script>', page).group(1)
    assert len(json.loads(table)["meshes"]) == len(distinct)  # each distinct mesh file once
    assert "octet-binary;base64" not in page  # no command left in meshcat's form
    assert len(page) < len(original) / 2


def test_a_compact_page_draws_the_robot_as_the_live_viewer_does(browser, tmp_path):
    """TIAGo++ (70 mesh objects from 21 binary STL files): the exported page, offline, holds
    the same objects at the same places as the live viewer, each mesh with as many vertices,
    and looks the same."""
    robot = mobmanip.load_robot("tiago_dual")
    q = robot.neutral()
    analysis, locked = analyze_pair(robot, q, None)
    vertices = """() => {
      const out = {};
      viewer.scene.traverse((o) => { if (o.isMesh) out[o.uuid] = o.geometry.attributes.position.count; });
      let total = 0, meshes = 0;
      for (const n of Object.values(out)) { total += n; meshes += 1; }
      return [meshes, total];
    }"""
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis, locked)
        path = viewer.export_html(tmp_path / "tiago_dual.html")
        live = browser.new_page(viewport=VIEWPORT)
        offline = browser.new_page(viewport=VIEWPORT)
        requests: list[str] = []
        offline.route(re.compile(r"^https?://"), lambda route: (requests.append(route.request.url), route.abort()))
        try:
            live.goto(viewer.url)
            wait_for_scene(live, timeout=60)
            offline.goto(path.as_uri())
            wait_for_scene(offline, timeout=60)
            ours, theirs = scene_objects(live), scene_objects(offline)
            robot_paths = [p for p in ours if "/robot/visuals/" in p]
            assert len(robot_paths) == len(viewer.visual_model.geometryObjects)
            assert {p: (o["type"], o["visible"]) for p, o in ours.items()} == {
                p: (o["type"], o["visible"]) for p, o in theirs.items()
            }
            for p in robot_paths:
                np.testing.assert_allclose(world_matrix(offline, p), world_matrix(live, p), atol=1e-9)
            counted = offline.evaluate(vertices)
            assert counted == live.evaluate(vertices) and counted[1] > 100_000
            a, b = screenshot(live).astype(float), screenshot(offline).astype(float)
            assert np.mean(np.abs(a - b)) < 2.0
            assert np.mean(np.abs(a - 255.0)) > 10  # something is drawn (not a blank page)
            assert requests == []
        finally:
            live.close()
            offline.close()
