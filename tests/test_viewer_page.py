"""The viewer page explains itself: legend and scales in the page, a camera that frames the robot
and its object, and small sets magnified by a stated factor; checked in headless Chromium for
every built-in robot, on the live page and on the exported one.

One browser for the module; each robot's viewer is closed (its server stopped) by its fixture.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from browser_util import project, wait_for_scene, world_matrix
from mobmanip.cli import main
from mobmanip.measures import get_measure
from mobmanip.viz.page import MAGNIFY_BELOW, MAGNIFY_TO, inject, magnification, visual_box
from mobmanip.viz.scene import OBJECT_COLOR, EllipsoidViewer, analyze_pair, scene_path, visual_model

ROBOTS = sorted(p.stem for p in (Path(__file__).resolve().parents[1] / "robots").glob("*.toml"))
#: The robots whose live page is checked beside the exported one: a differential drive with two
#: planar arms and a two-arm base with many meshes (the live page is the same scene, sent over
#: meshcat's websocket instead of written into the file; every robot's exported page is checked).
#: Each page costs seconds of software rendering on a 2-core machine (Stretch's live page: 26 s).
LIVE = ("planar_dual_arm", "tiago_dual")
VIEW = {"width": 800, "height": 500}  # small pages render fast
M = "meshcat/"
TOL = 1e-5
SPHERE = np.vstack([np.eye(3), -np.eye(3)])  # extreme points of the unit sphere along the axes


# --------------------------------------------------------------------------- without a browser


def test_magnification_is_the_smallest_1_2_5_factor_that_makes_a_small_set_visible(rng):
    size = 0.5
    assert magnification(0.0, size) == 1.0  # nothing to magnify
    for extent in rng.uniform(MAGNIFY_BELOW * size, 2 * size, 20):
        assert magnification(float(extent), size) == 1.0
    series = [m * 10.0**e for e in range(-1, 8) for m in (1.0, 2.0, 5.0)]
    for extent in 10.0 ** rng.uniform(-7, math.log10(MAGNIFY_BELOW * size), 50):
        f = magnification(float(extent), size)
        assert any(math.isclose(f, s, rel_tol=1e-12) for s in series)
        assert f * extent >= MAGNIFY_TO * size * (1 - 1e-12)
        smaller = max(s for s in series if s < f * (1 - 1e-9))
        assert smaller * extent < MAGNIFY_TO * size  # the next smaller factor would not do


def _surface_points(model, geometry, q, per_mesh: int = 40) -> np.ndarray:
    """Points on the robot's visual geometry at q (world, m), from the shapes' own parameters:
    mesh vertices, box corners, cylinder rims, sphere poles; joint origins besides."""
    data, gdata = model.createData(), geometry.createData()
    pin.forwardKinematics(model, data, q)
    pin.updateGeometryPlacements(model, data, geometry, gdata)
    points = [data.oMi[j].translation for j in range(1, model.njoints)]
    for i, geom in enumerate(geometry.geometryObjects):
        shape, M_ = geom.geometry, gdata.oMg[i]
        kind = type(shape).__name__
        if kind.startswith("BVH"):
            n = shape.num_vertices
            local = np.array([shape.vertex(int(k)) for k in np.linspace(0, n - 1, min(n, per_mesh)).astype(int)])
        elif kind == "Box":
            h = np.asarray(shape.halfSide)
            local = np.array([[x, y, z] for x in (-h[0], h[0]) for y in (-h[1], h[1]) for z in (-h[2], h[2])])
        elif kind in ("Cylinder", "Capsule"):
            t = np.linspace(0, 2 * np.pi, 8, endpoint=False)
            ring = np.column_stack([shape.radius * np.cos(t), shape.radius * np.sin(t)])
            local = np.vstack([np.column_stack([ring, np.full(8, z)]) for z in (-shape.halfLength, shape.halfLength)])
        elif kind == "Sphere":
            local = shape.radius * np.vstack([np.eye(3), -np.eye(3)])
        else:
            local = np.zeros((1, 3))
        points.extend(local @ M_.rotation.T + M_.translation)
    return np.array(points)


@pytest.mark.parametrize("name", ["tiago_dual", "panda"])
def test_visual_box_holds_every_point_of_the_geometry(name, rng):
    robot = mobmanip.load_robot(name)
    model, geometry = visual_model(robot)
    for _ in range(2):
        q = robot.neutral()
        q[:2] = rng.uniform(-1, 1, 2)
        yaw = rng.uniform(-np.pi, np.pi)
        q[2:4] = (np.cos(yaw), np.sin(yaw))
        lower, upper = visual_box(model, geometry, q)
        points = _surface_points(model, geometry, q, per_mesh=400)
        assert np.all(points >= lower - 1e-9) and np.all(points <= upper + 1e-9)
        # and not loose: each face within 10 cm of a point (a mesh's own box, turned, grows a little)
        assert np.all(points.min(axis=0) - lower < 0.1) and np.all(upper - points.max(axis=0) < 0.1)


def test_a_page_receives_the_sets_and_the_object_before_the_robots_meshes():
    """meshcat sends the scene to a page (and writes it into an exported one) in the order of its
    tree: every set and the object come before the robot's first mesh, so that a live page shows
    what was computed while the heaviest part still streams in."""
    import base64

    import msgpack

    robot = mobmanip.load_robot("planar_dual_arm")
    q = robot.neutral()
    analysis, locked = analyze_pair(robot, q)
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis, locked)
        html = viewer._vis.static_html()
    order = []
    for text in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html):
        command = msgpack.unpackb(base64.b64decode(text), raw=False, strict_map_key=False)
        if isinstance(command, dict) and command.get("type") == "set_object":
            order.append(command["path"])
    first_mesh = next(i for i, path in enumerate(order) if path.startswith("/meshcat/mobmanip/robot/"))
    sets = [scene_path(name, is_locked) for source, is_locked in ((analysis, False), (locked, True))
            for name in source.measures]  # fmt: skip
    for path in [*sets, "mobmanip/object"]:
        assert any(p.startswith(f"/meshcat/{path}") for p in order[:first_mesh]), (path, order)


def test_inject_puts_the_script_before_the_end_of_the_body():
    html = inject("<html><body><p>x</p></body></html>")
    assert html.index("mobmanip_page") < html.index("</body>") and html.endswith("</body></html>")
    assert "mobmanip_page" in inject("<p>no body</p>")


# --------------------------------------------------------------------------- in the browser


_LEGEND_JS = """() => {
  const box = document.getElementById("mobmanip-legend");
  if (!box) return null;
  const r = box.getBoundingClientRect();
  const rows = [...box.querySelectorAll(".mm-row:not(.mm-note)")].map(row => {
    const key = row.querySelector(".mm-key");
    const cs = getComputedStyle(key);
    return [row.textContent, key.classList.contains("mm-ring") ? cs.borderTopColor : cs.backgroundColor];
  });
  const notes = [...box.querySelectorAll(".mm-note")].map(n => n.textContent);
  return {rect: [r.left, r.top, r.right, r.bottom], title: box.querySelector(".mm-title").textContent,
          rows, notes, visible: getComputedStyle(box).visibility === "visible" && r.width > 0};
}"""


def _rgb(color: int) -> str:
    return f"rgb({(color >> 16) & 255}, {(color >> 8) & 255}, {color & 255})"


def _open(browser, url: str):
    page = browser.new_page(viewport=VIEW)
    page.goto(url)
    # a robot with many meshes (Stretch) takes tens of seconds to load on a busy 2-core machine
    page.wait_for_function("() => document.getElementById('mobmanip-legend') !== null", timeout=90000)
    wait_for_scene(page, timeout=90.0, stable=0.5)
    return page


def _check_legend(page, viewer, robot, analysis, locked):
    legend = page.evaluate(_LEGEND_JS)
    assert legend is not None and legend["visible"]
    left, top, right, bottom = legend["rect"]
    assert 0 <= left < right <= VIEW["width"] and 0 <= top < bottom <= VIEW["height"]
    assert robot.name in legend["title"]
    expected = []  # (text start, scale, colour) of each drawn set, in the registry's order
    for source, is_locked in ((analysis, False), (locked, True)):
        for name, task_set in ({} if source is None else source.measures).items():
            measure = get_measure(name)
            what = f"locked platform, {measure.label}" if is_locked else measure.label
            if task_set.empty:
                assert any(n.startswith(what) and "EMPTY" in n for n in legend["notes"]), (what, legend["notes"])
                continue
            factor = viewer.magnified[is_locked, name]
            color = measure.locked_color if is_locked else measure.color
            expected.append((what, viewer.scales[name] * factor, _rgb(color)))
    rows = legend["rows"]
    assert len(rows) == len(expected) + 1  # and the object's
    for (text, color), (what, scale, want_color) in zip(rows, expected):
        assert text.startswith(what + ": 1 m/s"), text
        number = float(re.search(r"= ([0-9.e+-]+) m", text).group(1))
        assert number == pytest.approx(scale, rel=5e-3)  # printed to 3 significant digits
        assert color == want_color
    assert rows[-1][1] == _rgb(OBJECT_COLOR) and "object" in rows[-1][0]


def _check_framed(page, viewer, q, analysis, locked):
    """Every point of the robot's geometry, the object and the drawn sets project inside the page,
    and together they fill a good part of it."""
    points = _surface_points(viewer.model, viewer.visual_model, q)
    pixels = project(page, points)
    obj = project(page, [analysis.held_object.center])[0]
    sets = [analysis.held_object.center]
    for source, is_locked in ((analysis, False), (locked, True)):
        for name, task_set in ({} if source is None else source.measures).items():
            if not task_set.empty:
                T = world_matrix(page, f"{M}{scene_path(name, is_locked)}/shape")
                sets.extend(SPHERE @ T[:3, :3].T + T[:3, 3])  # the unit sphere as drawn
    around = project(page, sets)
    w, h = VIEW["width"], VIEW["height"]
    for xy in (pixels, around):
        assert np.all(xy[:, 0] >= 0) and np.all(xy[:, 0] <= w), (xy[:, 0].min(), xy[:, 0].max())
        assert np.all(xy[:, 1] >= 0) and np.all(xy[:, 1] <= h), (xy[:, 1].min(), xy[:, 1].max())
    assert 0 <= obj[0] <= w and 0 <= obj[1] <= h
    every = np.vstack([pixels, around])
    spread = every.max(axis=0) - every.min(axis=0)
    assert spread[0] > 0.5 * w or spread[1] > 0.5 * h, spread  # framed, not a speck
    return pixels


@pytest.fixture(scope="module", params=ROBOTS)
def shown(request, browser, tmp_path_factory):
    """A robot in its home configuration (what `mobmanip view ROBOT` shows), its viewer, its
    exported page and, for the robots of :data:`LIVE`, its live page."""
    robot = mobmanip.load_robot(request.param)
    q = robot.neutral()
    analysis, locked = analyze_pair(robot, q)
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis, locked)
        path = viewer.export_html(tmp_path_factory.mktemp("page") / f"{robot.name}.html")
        pages = [_open(browser, path.as_uri())]
        if robot.name in LIVE:
            pages.insert(0, _open(browser, viewer.url))
        yield {
            "robot": robot,
            "q": q,
            "analysis": analysis,
            "locked": locked,
            "viewer": viewer,
            "pages": tuple(pages),
        }
        for page in pages:
            page.close()


def test_legend_names_every_drawn_set_with_its_colour_and_scale(shown):
    for page in shown["pages"]:
        _check_legend(page, shown["viewer"], shown["robot"], shown["analysis"], shown["locked"])


def test_robot_and_object_are_inside_the_frame(shown):
    args = shown["viewer"], shown["q"], shown["analysis"], shown["locked"]
    drawn = [_check_framed(page, *args) for page in shown["pages"]]
    if len(drawn) == 2:
        np.testing.assert_allclose(drawn[0], drawn[1], atol=1.0)  # the exported page frames it as the live one


# A part that never arrives added to what the page waits for: the banner it shows, then restored.
_PLANT_JS = """() => {
  const data = viewer.scene_tree.children.meshcat.children.mobmanip.object.mobmanip_page;
  const expect = data.expect;
  data.expect = [...expect, "mobmanip/never/sent"];
  window.mobmanipTick();
  const text = document.getElementById("mobmanip-progress").textContent;
  data.expect = expect;
  window.mobmanipTick();
  return [text, document.getElementById("mobmanip-progress") === null];
}"""


def test_the_page_counts_the_parts_of_the_scene_until_they_have_arrived(shown):
    """The page waits for every part drawn (each visual geometry, the object, each non-empty set)
    and says how many have arrived until all have (the live page received TIAGo++'s sets 20-45 s
    after its legend with no sign of work); loaded, it says nothing."""
    viewer, analysis, locked = shown["viewer"], shown["analysis"], shown["locked"]
    drawn = sum(not s.empty for a in (analysis, locked) if a is not None for s in a.measures.values())
    expect = viewer._page["expect"]
    assert len(expect) == len(set(expect)) == viewer.visual_model.ngeoms + 1 + drawn
    for page in shown["pages"]:
        assert page.evaluate("() => document.getElementById('mobmanip-progress')") is None
        text, cleared = page.evaluate(_PLANT_JS)
        assert text == f"receiving the scene: {len(expect)} of {len(expect) + 1} parts..."
        assert cleared


def test_magnified_small_set_is_drawn_larger_and_says_so(browser):
    """The locked platform's arms get 1/2000 of their torque: its dynamic ellipsoid would be a
    speck at the shared scale, so it is drawn a 1-2-5 factor larger, and the legend says by how much."""
    from mobmanip.analysis import analyze

    robot = mobmanip.load_robot("planar_dual_arm")
    q = robot.configuration(joints={"arm_right_2_joint": 0.8, "arm_right_3_joint": 1.1, "arm_left_2_joint": -0.8})
    arm_joints = [j for arm in robot.arms for j in arm.joint_names]
    weak = robot.with_limits(effort={j: robot.joint_effort_limits[j] / 2000 for j in arm_joints})
    analysis, _ = analyze_pair(robot, q)
    locked = analyze(weak.with_platform("fixed"), q, analysis.task)
    ratio = locked.dynamic.semi_axes[0] / analysis.dynamic.semi_axes[0]
    assert ratio < MAGNIFY_BELOW  # small indeed
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis, locked)
        factor = viewer.magnified[True, "dynamic"]
        assert factor > 1 and viewer.magnified[False, "dynamic"] == 1.0 == viewer.magnified[True, "kinematic"]
        k = viewer.scales["dynamic"]
        assert k * analysis.dynamic.semi_axes[0] == pytest.approx(viewer.size)  # the largest set sets the scale
        page = _open(browser, viewer.url)
        try:
            drawn = world_matrix(page, f"{M}mobmanip/locked/dynamic/shape")
            G = np.eye(3)[:, :2] @ (k * factor * locked.dynamic.generator)
            L = drawn[:3, :3]
            np.testing.assert_allclose((L @ L.T)[:2, :2], (G @ G.T)[:2, :2], atol=TOL)
            assert np.linalg.norm(L[:, 0]) >= MAGNIFY_TO * viewer.size  # visible now
            legend = page.evaluate(_LEGEND_JS)
            row = next(text for text, _ in legend["rows"] if text.startswith("locked platform, dynamic"))
            assert f"\u00d7{factor:g}" in row
            assert float(re.search(r"= ([0-9.e+-]+) m", row).group(1)) == pytest.approx(k * factor, rel=5e-3)
            assert any(f"{factor:g} times larger" in note for note in legend["notes"])
        finally:
            page.close()


def test_exported_page_of_the_view_command_has_the_legend_and_the_frame(browser, tmp_path, capsys):
    path = tmp_path / "tiago_dual.html"
    assert main(["view", "tiago_dual", "--export", str(path)]) == 0
    capsys.readouterr()
    robot = mobmanip.load_robot("tiago_dual")
    q = robot.neutral()
    analysis, _ = analyze_pair(robot, q)
    model, geometry = visual_model(robot)
    page = _open(browser, path.as_uri())
    try:
        legend = page.evaluate(_LEGEND_JS)
        assert legend["visible"] and "tiago_dual" in legend["title"]
        pixels = project(page, _surface_points(model, geometry, q))
        assert np.all((pixels >= 0) & (pixels <= [VIEW["width"], VIEW["height"]]))
    finally:
        page.close()
