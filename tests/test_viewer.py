"""The meshcat viewer: the ellipsoid transforms, the scene in a real browser, the export, the CLI.

Browser tests run headless Chromium (/usr/bin/chromium) through Playwright and read the three.js
scene of the meshcat page (see ``browser_util``); they are skipped, with the reason, only when
Chromium or Playwright is missing. Every viewer a test starts is closed by its fixture, which
stops its meshcat server.
"""

from __future__ import annotations

import math
import os
import re
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pinocchio as pin
import pytest

from browser_util import (
    VIEWPORT,
    classify,
    patch,
    project,
    scene_objects,
    screenshot,
    wait_for_scene,
    world_matrix,
)
from mobmanip.casestudy import PLATFORM_SPEEDS, WHEEL_TORQUES, configuration_at, optimal_posture
from mobmanip.cli import main
from mobmanip.sets.ellipsoid import Ellipsoid
from mobmanip.viz.scene import (
    ELLIPSOID_PATHS,
    MIN_SEMI_AXIS,
    PLANAR_THICKNESS,
    EllipsoidViewer,
    ScaleFactors,
    aligned,
    analyze_pair,
    ellipsoid_frame,
    ellipsoid_matrix,
    visual_model,
)
from mobmanip.viz.server import MeshcatServer, PortBusyError
from mobmanip.viz.sweeps import fig3_frames, fig4_frames, object_angle_frames

M = "meshcat/"  # meshcat's root in the three.js scene tree
TOL = 1e-5  # what three.js reports back (a decomposed and recomposed matrix) against numpy


def random_ellipsoid(rng, m: int, center_scale: float = 0.0) -> Ellipsoid:
    G = rng.normal(size=(m, m)) * rng.uniform(0.5, 3.0, size=m)
    return Ellipsoid.from_generator(center_scale * rng.normal(size=m), G)


def unit_vectors(rng, n: int, dim: int) -> np.ndarray:
    u = rng.normal(size=(n, dim))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def port_open(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(0.5)
        return s.connect_ex(("127.0.0.1", port)) == 0


# --------------------------------------------------------------------------- transform math


def test_matrix_maps_unit_sphere_onto_a_3d_ellipsoid(rng):
    for _ in range(5):
        e = random_ellipsoid(rng, 3, center_scale=2.0)
        origin, k = rng.normal(size=3), rng.uniform(0.05, 0.5)
        T = ellipsoid_matrix(e, "translational", origin, k)
        x = unit_vectors(rng, 200, 3) @ T[:3, :3].T + T[:3, 3]
        d = (x - origin) / k - e.center
        np.testing.assert_allclose(np.einsum("ni,ij,nj->n", d, e.matrix, d), 1.0, rtol=1e-9)
        p, R, r = ellipsoid_frame(e, "translational", origin, k)
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        np.testing.assert_allclose(np.abs(np.sum(R * e.axes.T, axis=0)), 1.0, rtol=1e-12)  # columns = axes
        np.testing.assert_allclose(r, k * e.semi_axes, rtol=1e-12)
        np.testing.assert_allclose(p, origin + k * e.center, rtol=1e-12)


def test_planar_ellipse_is_a_flat_ellipsoid_in_the_horizontal_plane(rng):
    for task in ("planar", "planar_rigid"):
        e = random_ellipsoid(rng, 2 if task == "planar" else 3, center_scale=1.0)
        # planar_rigid draws the shadow on (x, y): the ellipse {c + G[:2] z}; its matrix is (G G^T)^-1.
        G2 = e.generator[:2]
        A2 = np.linalg.inv(G2 @ G2.T)
        origin, k, thickness = np.array([0.3, -0.2, 0.35]), 0.1, 0.012
        T = ellipsoid_matrix(e, task, origin, k, thickness)
        u = unit_vectors(rng, 100, 2)
        x = np.column_stack([u, np.zeros(len(u))]) @ T[:3, :3].T + T[:3, 3]
        d = (x[:, :2] - origin[:2]) / k - e.center[:2]
        np.testing.assert_allclose(np.einsum("ni,ij,nj->n", d, A2, d), 1.0, rtol=1e-9)
        np.testing.assert_allclose(x[:, 2], origin[2], atol=1e-12)  # in the horizontal plane
        np.testing.assert_allclose(T[:3, 2], [0.0, 0.0, thickness], atol=1e-12)  # third axis: vertical, thin
        assert np.linalg.det(T[:3, :3]) > 0


def test_spatial_ellipsoid_is_drawn_as_its_linear_shadow(rng):
    e = random_ellipsoid(rng, 6, center_scale=1.0)
    G3 = e.generator[:3]
    A3 = np.linalg.inv(G3 @ G3.T)  # the linear velocities reachable with any angular velocity
    origin, k = np.zeros(3), 0.2
    T = ellipsoid_matrix(e, "spatial", origin, k)
    x = unit_vectors(rng, 200, 3) @ T[:3, :3].T + T[:3, 3]
    d = x / k - e.center[:3]
    np.testing.assert_allclose(np.einsum("ni,ij,nj->n", d, A3, d), 1.0, rtol=1e-8)


def test_zero_semi_axis_is_drawn_thin_not_singular():
    e = Ellipsoid.from_generator(np.zeros(3), np.diag([2.0, 1.0, 0.0]))
    assert e.degenerate
    p, R, r = ellipsoid_frame(e, "translational", np.zeros(3), 0.25)
    np.testing.assert_allclose(r, [0.5, 0.25, MIN_SEMI_AXIS])
    assert np.isfinite(ellipsoid_matrix(e, "translational", np.zeros(3), 0.25)).all()


def test_alignment_keeps_the_shape_and_follows_the_previous_axes(rng):
    for planar in (False, True):
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        if np.linalg.det(R) < 0:
            R[:, 2] *= -1
        if planar:
            R = np.eye(3)
            R[:2, :2] = [[math.cos(0.3), -math.sin(0.3)], [math.sin(0.3), math.cos(0.3)]]
        semi = np.array([0.5, 0.2, 0.01 if planar else 0.1])
        swapped = R[:, [1, 0, 2]] * [-1.0, 1.0, 1.0]  # same ellipsoid axes, other order and sign
        R2, s2 = aligned(swapped, semi[[1, 0, 2]], R, planar)
        np.testing.assert_allclose(R2 @ np.diag(s2**2) @ R2.T, R @ np.diag(semi**2) @ R.T, atol=1e-12)
        np.testing.assert_allclose(R2, R, atol=1e-12)
        np.testing.assert_allclose(s2, semi)


def test_scale_factors_fit_the_largest_extent(robot):
    q = robot.configuration(joints={"arm_right_2_joint": 0.8, "arm_right_3_joint": 1.1, "arm_left_2_joint": -0.8})
    a, locked = analyze_pair(robot, q)
    s = ScaleFactors.fit([a, locked], size=0.5)
    assert max(a.kinematic.semi_axes[0], locked.kinematic.semi_axes[0]) * s.kinematic == pytest.approx(0.5)
    assert max(a.dynamic.semi_axes[0], locked.dynamic.semi_axes[0]) * s.dynamic == pytest.approx(0.5)
    assert re.fullmatch(r"kinematic: 1 m/s = [0-9.e-]+ m; dynamic: 1 m/s\^2 = [0-9.e-]+ m", s.describe())


@pytest.mark.parametrize("name", ["planar_dual_arm", "tiago_dual"])
def test_visual_model_moves_like_the_robot(name, rng):
    import mobmanip

    robot = mobmanip.load_robot(name)
    model, geometry = visual_model(robot)
    assert geometry.ngeoms > 0
    data = model.createData()
    for _ in range(3):
        yaw = rng.uniform(-math.pi, math.pi)
        q = robot.configuration(platform=(*rng.uniform(-2, 2, size=2), yaw))
        for arm in robot.arms:
            for joint in arm.joint_names:
                q[robot.model.joints[robot.model.getJointId(joint)].idx_q] = rng.uniform(-1.5, 1.5)
        pin.forwardKinematics(robot.model, robot.data, q)
        pin.forwardKinematics(model, data, q)
        for j in range(1, model.njoints):
            np.testing.assert_allclose(data.oMi[j].homogeneous, robot.data.oMi[j].homogeneous, atol=1e-12)


# --------------------------------------------------------------------------- viewer without a browser


@pytest.fixture(scope="module")
def posture():
    import mobmanip

    return optimal_posture(mobmanip.load_robot("planar_dual_arm"))


@pytest.fixture
def counted_viewer(robot):
    viewer = EllipsoidViewer(robot)
    sent = []
    window = viewer["mobmanip"].window
    original = window.send

    def send(command):
        sent.append(command.lower()["type"])
        return original(command)

    window.send = send
    yield viewer, sent
    viewer.close()


def test_show_and_update_send_only_transforms(counted_viewer, robot, posture):
    viewer, sent = counted_viewer
    for angle in (0.0, 45.0, 90.0):
        q = configuration_at(robot, posture, angle, heading=0.3)
        viewer.update(q, *analyze_pair(robot, q))
    assert sent and set(sent) <= {"set_transform", "set_property"}  # meshes were loaded once, at creation
    n_geometries = viewer.visual_model.ngeoms
    assert sent.count("set_transform") >= 3 * (n_geometries + 1 + 4)


def test_close_stops_the_server(robot):
    viewer = EllipsoidViewer(robot)
    port, pid = viewer.port, viewer.server_pid
    assert port_open(port)
    viewer.close()
    viewer.close()  # twice is fine
    assert not viewer.server_running
    assert not port_open(port)
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


def test_busy_port_is_refused_with_a_clear_message(tmp_path, capsys):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        with pytest.raises(PortBusyError, match=f"port {port} is in use"):
            MeshcatServer(port)
        rc = main(["view", "planar_dual_arm", "--port", str(port), "--export", str(tmp_path / "x.html")])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and f"port {port} is in use" in err
    assert not (tmp_path / "x.html").exists()


def test_without_port_the_next_free_one_is_taken(robot):
    with EllipsoidViewer(robot) as first, EllipsoidViewer(robot) as second:
        assert first.port != second.port
        assert first.url.startswith("http://127.0.0.1:")
        assert 7000 <= min(first.port, second.port)


def run_cli(argv) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # argparse's own errors
        return exc.code


@pytest.mark.parametrize(
    "argv, message",
    [
        (["view", "no_such_robot"], "unknown robot 'no_such_robot'"),
        (["view", "planar_dual_arm", "--sweep", "fig3", "--platform", "fixed"], "needs the robot's own moving"),
        (["view", "ur5", "--sweep", "fig4"], "needs the robot's own moving platform"),
        (["view", "tiago_dual", "--sweep", "fig3"], "two 3-joint arms"),
        (["view", "planar_dual_arm", "--size", "-1"], "--size must be a positive"),
        (["view", "planar_dual_arm", "--sweep", "nope"], "invalid choice"),
    ],
)
def test_view_bad_input_exits_2_with_one_line(argv, message, capsys):
    assert run_cli(argv) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and captured.err.startswith("mobmanip: error:")
    assert message in captured.err
    assert "meshcat viewer" not in captured.out


def test_sweep_frames_hold_the_papers_values(robot, posture):
    radius = robot.platform.radius
    frames = fig3_frames(robot)
    held = [f for f in frames if f.hold > 0]
    assert len(held) == 9
    speeds = sorted({round(float(f.analysis.robot.velocity_limits[0]) * radius, 9) for f in held})
    assert speeds == sorted(PLATFORM_SPEEDS)
    assert all(f.locked is not None and f.locked.robot.platform.kind == "fixed" for f in frames)
    frames = fig4_frames(robot)
    held = [f for f in frames if f.hold > 0]
    assert sorted({float(f.analysis.robot.effort_limits[0]) for f in held}) == sorted(WHEEL_TORQUES)
    assert all(f.analysis.decoupled for f in frames)
    frames = object_angle_frames(robot, angles_deg=(0.0, 30.0, 90.0))
    for frame, angle in zip(frames, (0.0, 30.0, 90.0)):
        c = frame.analysis.held_object.center
        assert math.degrees(math.atan2(c[1], c[0])) == pytest.approx(angle, abs=1e-6)


# --------------------------------------------------------------------------- in the browser


def expected_paths(viewer) -> dict[str, str]:
    """Scene path -> three.js type, for everything the viewer draws."""
    paths = {f"{M}mobmanip/robot/visuals/{g.name}": "Mesh" for g in viewer.visual_model.geometryObjects}
    paths[f"{M}mobmanip/object"] = "Mesh"
    for (locked, _), path in ELLIPSOID_PATHS.items():
        paths[f"{M}{path}/shape"] = "LineSegments" if locked else "Mesh"
        paths[f"{M}{path}/axes"] = "LineSegments"
    return paths


@pytest.fixture(scope="module")
def live(browser, posture):
    """A viewer of the paper's robot (object at 90 deg) seen from above, and a page on it."""
    import mobmanip

    robot = mobmanip.load_robot("planar_dual_arm")
    viewer = EllipsoidViewer(robot)
    q = configuration_at(robot, posture, 90.0)
    analysis, locked = analyze_pair(robot, q)
    viewer.show(q, analysis, locked)
    viewer.set_camera(2.2, elevation_deg=89.0, azimuth_deg=-90.0)  # looking down, +y up on the screen
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(viewer.url)
    wait_for_scene(page, tuple(expected_paths(viewer)))
    yield {"viewer": viewer, "page": page, "robot": robot, "q": q, "analysis": analysis, "locked": locked}
    page.close()
    viewer.close()


def _show(live, q):
    viewer, page = live["viewer"], live["page"]
    analysis, locked = analyze_pair(live["robot"], q)
    viewer.update(q, analysis, locked)
    viewer.set_locked_visible(True)
    wait_for_scene(page)
    return analysis, locked


def _arm_polylines(robot, q):
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    lines = []
    for arm in robot.arms:
        points = [data.oMi[robot.model.getJointId(j)].translation for j in arm.joint_names]
        lines.append(np.array(points + [data.oMf[arm.frame_id].translation]))
    return lines


def _distance_to_polyline(points, line):
    best = np.full(len(points), np.inf)
    for a, b in zip(line[:-1, :2], line[1:, :2]):
        t = np.clip((points - a) @ (b - a) / max((b - a) @ (b - a), 1e-12), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - (a + t[:, None] * (b - a)), axis=1))
    return best


def _normalised_radius(points, ellipsoid, center, k):
    """||diag(1 / (k s)) axes (x - o)|| for points (n, 2) and a 2-D ellipse."""
    local = (points - center[:2]) @ ellipsoid.axes.T
    return np.linalg.norm(local / (k * ellipsoid.semi_axes), axis=1), local


def test_scene_graph_holds_the_named_objects(live):
    objects = scene_objects(live["page"])
    for path, kind in expected_paths(live["viewer"]).items():
        assert path in objects, path
        assert objects[path]["type"] == kind, path
    assert objects[f"{M}mobmanip/locked/kinematic/shape"]["visible"]


def test_screenshot_shows_robot_and_ellipsoid_colours(live):
    viewer, page, robot = live["viewer"], live["page"], live["robot"]
    analysis, _ = _show(live, live["q"])
    viewer.set_locked_visible(False)
    wait_for_scene(page)
    image = screenshot(page)
    o, k = analysis.held_object.center, viewer.scales
    # Sample the plane of the ellipses where exactly one of them is, away from the arms, the object
    # and the principal axes (dark lines).
    grid = np.stack(np.meshgrid(np.linspace(-0.6, 0.6, 81), np.linspace(-0.6, 0.6, 81)), -1).reshape(-1, 2) + o[:2]
    r_kin, local_kin = _normalised_radius(grid, analysis.kinematic, o, k.kinematic)
    r_dyn, local_dyn = _normalised_radius(grid, analysis.dynamic, o, k.dynamic)
    clear = np.ones(len(grid), dtype=bool)
    for line in _arm_polylines(robot, live["q"]):
        clear &= _distance_to_polyline(grid, line) > 0.07
    clear &= np.linalg.norm(grid - o[:2], axis=1) > 0.08
    clear &= (np.abs(local_kin).min(axis=1) > 0.02) & (np.abs(local_dyn).min(axis=1) > 0.02)
    regions = {"green": clear & (r_kin < 0.85) & (r_dyn > 1.1), "magenta": clear & (r_dyn < 0.85) & (r_kin > 1.1)}
    for colour, inside in regions.items():
        assert inside.sum() >= 20, (colour, inside.sum())
        pixels = project(page, np.column_stack([grid[inside], np.full(inside.sum(), o[2])]))
        hits = [classify(patch(image, xy), colour).mean() > 0.5 for xy in pixels]
        assert np.mean(hits) > 0.9, (colour, np.mean(hits))
    # The robot: the grey platform body and the orange right arm (its links' centres).
    data = viewer.model.createData()
    geometry_data = viewer.visual_model.createData()
    pin.forwardKinematics(viewer.model, data, live["q"])
    pin.updateGeometryPlacements(viewer.model, data, viewer.visual_model, geometry_data)
    centres = {g.name: geometry_data.oMg[i].translation for i, g in enumerate(viewer.visual_model.geometryObjects)}
    top = centres["base_link_0"] + [0.0, 0.0, 0.09]
    on_platform = np.stack(np.meshgrid(np.linspace(-0.2, 0.2, 5), np.linspace(-0.1, 0.1, 3)), -1).reshape(-1, 2)
    on_platform = np.column_stack([on_platform + top[:2], np.full(len(on_platform), top[2])])
    keep = np.ones(len(on_platform), dtype=bool)
    for line in _arm_polylines(robot, live["q"]):
        keep &= _distance_to_polyline(on_platform[:, :2], line) > 0.06
    assert keep.sum() >= 5
    assert all(classify(patch(image, xy, 2), "grey").mean() > 0.8 for xy in project(page, on_platform[keep]))
    right = [c for name, c in centres.items() if name.startswith("arm_right")]
    visible = [c for c in right if _normalised_radius(c[None, :2], analysis.dynamic, o, k.dynamic)[0][0] > 1.1]
    assert len(visible) >= 2
    assert all(classify(patch(image, xy, 1), "orange").mean() > 0.5 for xy in project(page, visible))
    # The locked pair's rings appear when it is shown, and only then.
    ring = np.linspace(0.0, 2 * np.pi, 48, endpoint=False)
    counts = {}
    for shown in (False, True):
        viewer.set_locked_visible(shown)
        wait_for_scene(page)
        image = screenshot(page)
        for kind, colour in (("kinematic", "yellow"), ("dynamic", "red")):
            e = getattr(live["locked"], kind)
            points = o[:2] + (np.column_stack([np.cos(ring), np.sin(ring)]) * (k[kind] * e.semi_axes)) @ e.axes
            keep = np.ones(len(points), dtype=bool)
            for line in _arm_polylines(robot, live["q"]):
                keep &= _distance_to_polyline(points, line) > 0.06
            pixels = project(page, np.column_stack([points[keep], np.full(keep.sum(), o[2])]))
            counts[shown, colour] = np.mean([classify(patch(image, xy, 2), colour).any() for xy in pixels])
    assert counts[True, "yellow"] > 0.7 and counts[True, "red"] > 0.7, counts
    assert counts[False, "yellow"] < 0.1 and counts[False, "red"] < 0.1, counts


def _assert_ellipsoid_drawn(matrix, analysis, kind, k, thickness):
    """The world transform equals the analysis: centre = task point, columns = axes x semi-axes x k."""
    e = getattr(analysis, kind)
    assert matrix is not None
    np.testing.assert_allclose(matrix[:3, 3], analysis.held_object.center + k * np.append(e.center, 0.0), atol=TOL)
    np.testing.assert_allclose(matrix[3], [0, 0, 0, 1], atol=TOL)
    L = matrix[:3, :3]
    for i in range(2):
        direction = np.append(e.axes[i], 0.0)
        sign = np.sign(L[:, i] @ direction)
        np.testing.assert_allclose(L[:, i], sign * k * e.semi_axes[i] * direction, atol=TOL)
    np.testing.assert_allclose(np.abs(L[:, 2]), [0.0, 0.0, thickness], atol=TOL)


def test_update_moves_the_ellipsoids_to_the_analysis(live, posture):
    viewer, page, robot = live["viewer"], live["page"], live["robot"]
    before = scene_objects(page)
    q = configuration_at(robot, posture, 30.0, heading=0.4)
    q[:2] = (0.3, -0.2)
    analysis, locked = _show(live, q)
    after = scene_objects(page)
    assert {p: o["uuid"] for p, o in after.items()} == {p: o["uuid"] for p, o in before.items()}  # nothing reloaded
    for (is_locked, kind), path in ELLIPSOID_PATHS.items():
        source = locked if is_locked else analysis
        matrix = world_matrix(page, f"{M}{path}/shape")
        _assert_ellipsoid_drawn(matrix, source, kind, viewer.scales[kind], PLANAR_THICKNESS[is_locked, kind])
        np.testing.assert_allclose(world_matrix(page, f"{M}{path}/axes"), matrix, atol=TOL)
    np.testing.assert_allclose(world_matrix(page, f"{M}mobmanip/object")[:3, 3], analysis.held_object.center, atol=TOL)
    # The robot's links follow the analysis model's joints.
    pin.forwardKinematics(robot.model, robot.data, q)
    for geom in viewer.visual_model.geometryObjects:
        expected = (robot.data.oMi[geom.parentJoint] * geom.placement).homogeneous
        drawn = world_matrix(page, f"{M}mobmanip/robot/visuals/{geom.name}", node=True)
        np.testing.assert_allclose(drawn[:3, 3], expected[:3, 3], atol=TOL)
        np.testing.assert_allclose(drawn[:3, :3] @ drawn[:3, :3].T, np.eye(3), atol=TOL)
        np.testing.assert_allclose(drawn[:3, :3], expected[:3, :3], atol=TOL)


def test_export_renders_the_same_scene(live, browser, tmp_path):
    viewer, page = live["viewer"], live["page"]
    _show(live, live["q"])
    path = viewer.export_html(tmp_path / "scene.html")
    assert "<script src" not in path.read_text()  # the viewer's code is inline
    offline = browser.new_page(viewport=VIEWPORT)
    requests = []
    offline.route(re.compile(r"^https?://"), lambda route: (requests.append(route.request.url), route.abort()))
    try:
        offline.goto(path.as_uri())
        wait_for_scene(offline, tuple(expected_paths(viewer)))
        mine = {p: o for p, o in scene_objects(page).items() if p.startswith(M)}
        theirs = {p: o for p, o in scene_objects(offline).items() if p.startswith(M)}
        assert {p: (o["type"], o["visible"]) for p, o in mine.items()} == {
            p: (o["type"], o["visible"]) for p, o in theirs.items()
        }
        for p in mine:
            np.testing.assert_allclose(world_matrix(offline, p), world_matrix(page, p), atol=TOL)
        a, b = screenshot(page).astype(float), screenshot(offline).astype(float)
        assert np.mean(np.abs(a - b)) < 2.0
        for colour in ("green", "magenta", "orange", "grey", "yellow", "red"):
            na, nb = classify(a.astype(np.uint8), colour).sum(), classify(b.astype(np.uint8), colour).sum()
            assert abs(na - nb) <= 0.05 * max(na, nb) + 20, (colour, na, nb)
        assert requests == []  # it rendered offline
    finally:
        offline.close()


_CAPTION_JS = """(t) => {
  viewer.animator.pause(); viewer.animator.seek(t); window.mobmanipTick();
  const box = document.getElementById("mobmanip-caption");
  return box ? box.textContent : null;
}"""


def test_animation_export_plays_the_sweep(robot, browser, tmp_path):
    """The exported Fig. 3 sweep plays each held frame's ellipses, and every frame carries its
    caption: the held ones their label, the ones between the paper's speeds the speed of their
    own wheel limit (read from the frame's robot, to the caption's 3 digits)."""
    frames = fig3_frames(robot)
    with EllipsoidViewer(robot) as viewer:
        schedule = viewer.animate(frames, step=0.1)
        path = viewer.export_html(tmp_path / "fig3.html")
        scales = viewer.scales
        n_tracks = viewer.visual_model.ngeoms + 1 + len(ELLIPSOID_PATHS)
    page = browser.new_page(viewport=VIEWPORT)
    try:
        page.goto(path.as_uri())
        page.wait_for_function(
            f"() => typeof viewer !== 'undefined' && viewer.animator.actions.length == {n_tracks}", timeout=30000
        )
        duration = page.evaluate("() => viewer.animator.duration")
        assert duration == pytest.approx(schedule[-1][1], abs=0.05)
        held = [f for f in frames if f.hold > 0]
        assert len(schedule) == len(held) == 9
        for index in (0, 4, 8):
            start, end, label = schedule[index]
            frame = held[index]
            assert label == held[index].label
            assert page.evaluate(_CAPTION_JS, (start + end) / 2) == label
            for (is_locked, kind), p in ELLIPSOID_PATHS.items():
                source = frame.locked if is_locked else frame.analysis
                e = getattr(source, kind)
                drawn = world_matrix(page, f"{M}{p}/shape")
                # The animation may reorder or flip the axes to move smoothly: compare the shape L L^T.
                np.testing.assert_allclose(drawn[:3, 3], source.held_object.center, atol=TOL)
                E = np.eye(3)[:, :2]
                G = scales[kind] * E @ e.generator
                expected = G @ G.T + np.diag([0.0, 0.0, PLANAR_THICKNESS[is_locked, kind] ** 2])
                np.testing.assert_allclose(drawn[:3, :3] @ drawn[:3, :3].T, expected, atol=TOL)
        starts = np.cumsum([0.0] + [f.hold + 0.1 for f in frames[:-1]])
        between = [i for i, f in enumerate(frames) if f.hold == 0 and "between" in f.caption]
        turning = [i for i, f in enumerate(frames) if f.hold == 0 and "turning" in f.caption]
        assert between and turning and len(between) + len(turning) + len(held) == len(frames)
        radius = robot.platform.radius
        for i in (between[0], between[-1], turning[0]):
            caption = page.evaluate(_CAPTION_JS, starts[i] + 0.05)
            assert caption == frames[i].caption
            speed = float(re.search(r"platform speed <= ([0-9.e-]+) m/s", caption).group(1))
            limit = float(frames[i].analysis.robot.velocity_limits[0]) * radius
            assert speed == pytest.approx(limit, rel=5e-3)
            angle = float(re.search(r"object at ([0-9.]+) deg", caption).group(1))
            q = frames[i].q  # the object's direction from the platform's heading, in the world
            rel = frames[i].analysis.held_object.center[:2] - q[:2]
            seen = math.degrees(math.atan2(rel[1], rel[0]) - math.atan2(q[3], q[2]))
            assert angle == pytest.approx(seen, abs=0.05)
    finally:
        page.close()


def test_view_command_serves_until_interrupted(browser):
    port = free_port()
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(
        [sys.executable, "-m", "mobmanip", "view", "planar_dual_arm", "--port", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        lines = []
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            lines.append(line)
            if line.startswith("meshcat viewer:"):
                break
        url = re.search(r"http://127\.0\.0\.1:(\d+)/static/", lines[-1])
        assert url and int(url.group(1)) == port, lines
        assert any(re.match(r"scale: kinematic: 1 m/s = \S+ m; dynamic: 1 m/s\^2 = \S+ m", x) for x in lines), lines
        page = browser.new_page(viewport=VIEWPORT)
        page.goto(url.group(0))
        wait_for_scene(page, (f"{M}mobmanip/ellipsoids/kinematic/shape", f"{M}mobmanip/locked/dynamic/shape"))
        page.close()
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=20) == 0
        assert "stopped the meshcat server" in proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdout.close()
        proc.stderr.close()
    assert not port_open(port)


def test_3d_ellipsoids_with_gravity_in_the_browser(browser):
    """A fixed-base arm, translational task: full 3-D ellipsoids; the dynamic one is shifted by gravity."""
    import mobmanip

    robot = mobmanip.load_robot("ur5")
    q = robot.configuration(joints=dict.fromkeys(robot.arms[0].joint_names, 0.5))
    analysis, locked = analyze_pair(robot, q, "translational")
    assert locked is None  # no platform to lock
    assert np.linalg.norm(analysis.dynamic.center) > 1.0  # gravity shifts the acceleration ellipsoid
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis)
        page = browser.new_page(viewport=VIEWPORT)
        try:
            page.goto(viewer.url)
            wait_for_scene(page, tuple(expected_paths(viewer)))
            for kind in ("kinematic", "dynamic"):
                e, k = getattr(analysis, kind), viewer.scales[kind]
                drawn = world_matrix(page, f"{M}mobmanip/ellipsoids/{kind}/shape")
                np.testing.assert_allclose(drawn[:3, 3], analysis.held_object.center + k * e.center, atol=TOL)
                G = k * e.generator
                np.testing.assert_allclose(drawn[:3, :3] @ drawn[:3, :3].T, G @ G.T, atol=TOL)
            locked_group = "() => viewer.scene_tree.children.meshcat.children.mobmanip.children.locked.object.visible"
            assert page.evaluate(locked_group) is False  # nothing to show for a locked platform
        finally:
            page.close()


def test_server_stops_when_its_parent_is_killed(tmp_path):
    script = tmp_path / "parent.py"
    script.write_text(
        "import time, mobmanip\n"
        "from mobmanip.viz.scene import EllipsoidViewer\n"
        "viewer = EllipsoidViewer(mobmanip.load_robot('planar_dual_arm'))\n"
        "print(viewer.port, flush=True)\n"
        "time.sleep(60)\n"
    )
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    try:
        port = int(parent.stdout.readline())
        assert port_open(port)
        parent.kill()  # SIGKILL: no atexit, no close()
        parent.wait()
        deadline = time.monotonic() + 10
        while port_open(port) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not port_open(port)
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()
        parent.stdout.close()


def test_object_angle_sweep_of_the_paper_robot_refuses_a_configuration(tmp_path, capsys):
    """The sweep aims the paper robot's arms itself; a --q would be silently ignored otherwise."""
    q_file = tmp_path / "q.json"
    q_file.write_text('{"joints": {"arm_right_2_joint": 0.5}}')
    assert run_cli(["view", "planar_dual_arm", "--sweep", "object-angle", "--q", str(q_file)]) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "leave out --q" in captured.err
