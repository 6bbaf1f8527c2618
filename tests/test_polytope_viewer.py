"""The capacity polytopes in the meshcat viewer: what is drawn (vertices, triangles, edges) against
independent support programs, the scene paths of the registry, and the scene in a real browser
(headless Chromium through Playwright, see ``browser_util``), live and exported.
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from browser_util import opened_page, scene_objects, wait_for_scene, world_matrix
from conftest import random_configurations
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.measures import POLYTOPE_KINDS, get_measure
from mobmanip.viz.scene import EllipsoidViewer, analyze_pair, planar_thickness, scene_path
from mobmanip.viz.shapes import DRAWINGS, polytope_geometry
from polytope_util import dynamic_lp, kinematic_lp, terms

POLYTOPES = tuple(POLYTOPE_KINDS)
MEASURES = ("kinematic", "dynamic", *POLYTOPES)
M = "meshcat/"


def _unit(rng, n: int, m: int) -> np.ndarray:
    u = rng.normal(size=(n, m))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def _outward(points, triangles) -> bool:
    """Every triangle's normal points away from the centroid of the points."""
    c = points.mean(axis=0)
    T = points[triangles]
    normals = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    return bool(np.all(np.einsum("ij,ij->i", normals, T.mean(axis=1) - c) > 0.0))


def test_drawn_translational_polytope_is_the_set(rng):
    """TIAGo++ holding an object (translational task): the mesh's points, scaled back, have the
    supports of the joint box's program; its triangles close an outward-oriented surface whose
    volume is the set's; every edge is one of a triangle."""
    robot = mobmanip.load_robot("tiago_dual")
    q = random_configurations(robot, rng, 1)[0]
    an, t = terms(robot, q, "translational")
    references = {
        "kinematic_polytope": kinematic_lp(t["J_u"], t["W"], t["velocity_limits"]),
        "dynamic_polytope": dynamic_lp(
            t["J_u"], t["W"], t["P"], t["Q"], t["xi"], t["M_o"], t["g_o"], t["effort_limits"]
        ),
    }
    polytopes = mobmanip.analyze(robot, q, "translational", measures=POLYTOPES)
    for name, lp in references.items():
        scale = 0.37
        points, triangles, segments = polytope_geometry(polytopes.measure(name), "translational", scale)
        for d in _unit(rng, 20, 3):
            expected = lp(d)
            assert float(np.max(points @ d)) / scale == pytest.approx(expected, abs=1e-7 * max(abs(expected), 1.0))
        assert _outward(points, triangles)
        T = points[triangles]
        volume = np.einsum("ij,ij->i", T[:, 0], np.cross(T[:, 1], T[:, 2])).sum() / 6.0
        assert volume / scale**3 == pytest.approx(polytopes.measure(name).volume, rel=1e-9)
        tri_edges = {tuple(sorted((int(a), int(b)))) for tri in triangles for a, b in zip(tri, np.roll(tri, -1))}
        assert {tuple(e) for e in segments.tolist()} <= tri_edges


def test_drawn_planar_polytope_is_its_outline(rng):
    """The paper's robot: a planar set is its outline (no triangles), a closed loop through every
    vertex, lifted by the thickness; a spatial task's polytope is drawn as its linear shadow."""
    robot = mobmanip.load_robot("planar_dual_arm")
    q = configuration_at(robot, optimal_posture(robot), 45.0)
    an = mobmanip.analyze(robot, q, "planar", measures=POLYTOPES)
    kin = an.measure("kinematic_polytope")
    points, triangles, segments = polytope_geometry(kin, "planar", 0.2, thickness=0.018)
    assert len(triangles) == 0
    np.testing.assert_allclose(points[:, :2], 0.2 * kin.vertices, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(points[:, 2], 0.018)
    degree = np.bincount(segments.ravel(), minlength=len(points))
    assert len(segments) == len(points) and np.all(degree == 2)  # one closed loop
    _, t = terms(robot, q, "planar")
    lp = kinematic_lp(t["J_u"], t["W"], t["velocity_limits"])
    for d in _unit(rng, 20, 2):
        assert float(np.max(points[:, :2] @ d)) / 0.2 == pytest.approx(lp(d), abs=1e-7 * max(lp(d), 1.0))
    # a planar_rigid task (x, y, yaw) is drawn as the shadow on (x, y)
    rigid = mobmanip.analyze(robot, q, "planar_rigid", measures=("kinematic_polytope",)).measure("kinematic_polytope")
    shadow, _, _ = polytope_geometry(rigid, "planar_rigid", 1.0)
    for d in _unit(rng, 10, 2):
        assert float(np.max(shadow[:, :2] @ d)) == pytest.approx(rigid.support(np.r_[d, 0.0]), rel=1e-9)


def test_viewer_loads_polytopes_at_the_registrys_paths():
    robot = mobmanip.load_robot("planar_dual_arm")
    q = configuration_at(robot, optimal_posture(robot), 90.0)
    analysis, locked = analyze_pair(robot, q, measures=MEASURES)
    with EllipsoidViewer(robot, measures=MEASURES) as viewer:
        viewer.show(q, analysis, locked)
        paths = viewer.scene_paths()
        for name in POLYTOPES:
            assert paths[False, name] == scene_path(name) == f"mobmanip/{get_measure(name).scene_path}"
            assert paths[True, name] == f"mobmanip/locked/{name}"
        assert viewer.undrawn == {}
        # one scale per quantity, fitted to the farthest drawn point: the polytopes enclose the ellipses
        for quantity, names in (("kinematic", POLYTOPES[:1]), ("dynamic", POLYTOPES[1:])):
            far = max(
                DRAWINGS["polytope"].extent(source.measure(name), "planar")
                for source in (analysis, locked)
                for name in names
            )
            assert far * viewer.scales[quantity] == pytest.approx(0.5, rel=1e-12)


_POSITIONS_JS = """(path) => {
  let node = viewer.scene_tree;
  for (const name of path) { node = node.children[name]; if (node === undefined) return null; }
  const g = node.object.geometry;
  return [Array.from(g.attributes.position.array), g.index ? Array.from(g.index.array) : null];
}"""


def _drawn_points(page, path: str):
    """World points of the geometry at a scene path (meshcat's z-up world), and its index array."""
    positions, index = page.evaluate(_POSITIONS_JS, path.split("/") + ["<object>"])
    local = np.array(positions, dtype=float).reshape(-1, 3)
    T = world_matrix(page, path)
    return local @ T[:3, :3].T + T[:3, 3], index


def test_polytopes_are_drawn_in_the_browser_live_and_exported(browser, tmp_path, rng):
    """TIAGo++ (translational): the kinematic polytope's mesh and edges exist at the registry's
    path in the page; its world points are the task point plus the scale times the set's
    vertices (their supports those of the joint box's program); the locked set is drawn as edges
    only; the exported page holds the same objects at the same places. Shown with the ellipsoids,
    which the polytopes contain, every polytope is drawn as its edges only (no mesh to hide them)."""
    robot = mobmanip.load_robot("tiago_dual")
    q = random_configurations(robot, rng, 1)[0]
    analysis, locked = analyze_pair(robot, q, "translational", measures=MEASURES)
    alone, _ = analyze_pair(robot, q, "translational", measures=("kinematic_polytope",))
    _, t = terms(robot, q, "translational")
    lp = kinematic_lp(t["J_u"], t["W"], t["velocity_limits"])
    base = f"{M}mobmanip/polytopes/kinematic_polytope"
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis, locked)
        with opened_page(browser, viewer.url) as page:
            required = (f"{base}/edges", f"{M}mobmanip/locked/kinematic_polytope/edges")
            wait_for_scene(page, required)
            objects = scene_objects(page)
            k, origin = viewer.scales["kinematic"], analysis.held_object.center
            # the polytope contains the ellipsoid (the joint box holds the unit ball): outlined
            assert (False, "kinematic") in viewer.outlined[False, "kinematic_polytope"]
            for name in POLYTOPES:
                assert f"{M}mobmanip/polytopes/{name}/shape" not in objects, name
                assert objects[f"{M}mobmanip/polytopes/{name}/edges"]["type"] == "LineSegments"
            edges, _ = _drawn_points(page, f"{base}/edges")
            for d in _unit(rng, 10, 3):
                assert float(np.max((edges - origin) @ d)) / k == pytest.approx(lp(d), rel=1e-5)
            viewer.show(q, alone, None)  # the polytope alone: nothing inside it, a translucent mesh
            wait_for_scene(page, (f"{base}/shape", f"{base}/edges"))
            objects = scene_objects(page)
            assert objects[f"{base}/shape"]["type"] == "Mesh" and objects[f"{base}/edges"]["type"] == "LineSegments"
            assert f"{M}mobmanip/locked/kinematic_polytope/shape" not in objects  # locked: edges only
            points, index = _drawn_points(page, f"{base}/shape")
            poly = alone.measure("kinematic_polytope")
            np.testing.assert_allclose(points, origin + k * poly.vertices, rtol=0, atol=1e-5)
            np.testing.assert_array_equal(np.array(index).reshape(-1, 3), poly.triangles)
            for d in _unit(rng, 10, 3):
                assert float(np.max((points - origin) @ d)) / k == pytest.approx(lp(d), rel=1e-5)
            exported = viewer.export_html(tmp_path / "scene.html")
            with opened_page(browser, exported.as_uri()) as offline:
                wait_for_scene(offline, (f"{base}/shape", f"{base}/edges"))
                theirs = scene_objects(offline)
                for path in (f"{base}/shape", f"{base}/edges"):
                    assert theirs[path]["type"] == objects[path]["type"]
                again, _ = _drawn_points(offline, f"{base}/shape")
                np.testing.assert_allclose(again, points, rtol=0, atol=1e-6)


def test_planar_outline_in_the_browser(browser):
    """The paper's robot: the outline lies in the horizontal plane at the task point's height
    plus the measure's thickness, through the scaled vertices."""
    robot = mobmanip.load_robot("planar_dual_arm")
    q = configuration_at(robot, optimal_posture(robot), 30.0)
    analysis, locked = analyze_pair(robot, q, measures=("kinematic", "kinematic_polytope"))
    path = f"{M}mobmanip/polytopes/kinematic_polytope/edges"
    with EllipsoidViewer(robot) as viewer:
        viewer.show(q, analysis, locked)
        with opened_page(browser, viewer.url) as page:
            wait_for_scene(page, (path,))
            points, _ = _drawn_points(page, path)
        origin, k = analysis.held_object.center, viewer.scales["kinematic"]
    np.testing.assert_allclose(points[:, 2], origin[2] + planar_thickness("kinematic_polytope"), atol=1e-6)
    vertices = origin[:2] + k * analysis.measure("kinematic_polytope").vertices
    for p in points[:, :2]:
        assert np.min(np.linalg.norm(vertices - p, axis=1)) <= 1e-5
    assert len(points) == 2 * len(vertices)  # each vertex ends two edges
