"""Nested sets stay visible in the viewer: a set whose drawing contains another is drawn as an
outline (its principal rings, or a polytope's edges) instead of a surface that would hide the
inner one.

Containment is checked here independently of the support functions the viewer compares: for
centred ellipsoids by the matrix order (E_B inside E_A iff G_A G_A^T - G_B G_B^T is positive
semidefinite), for shifted ones by points on the inner boundary tested against the outer's
inequality, and in the browser by the inner set's colour in the rendered page.
"""

from __future__ import annotations

import numpy as np
import pytest

import mobmanip
from browser_util import VIEWPORT, chromium, classify, missing_browser, patch, project, scene_objects, screenshot
from mobmanip.sets.ellipsoid import Ellipsoid
from mobmanip.viz.nesting import nested, outlined
from mobmanip.viz.scene import EllipsoidViewer
from mobmanip.viz.sweeps import fig3_frames

M = "meshcat/"


def _ellipse(rng, m: int, center_scale: float = 0.0) -> Ellipsoid:
    Q, _ = np.linalg.qr(rng.normal(size=(m, m)))
    return Ellipsoid.from_generator(center_scale * rng.normal(size=m), Q * rng.uniform(0.3, 2.0, size=m))


@pytest.mark.parametrize("m, task", [(2, "planar"), (3, "translational")])
def test_centred_ellipsoids_nest_by_the_matrix_order(m, task):
    rng = np.random.default_rng(11 + m)
    seen = {True: 0, False: 0}
    for _ in range(200):
        a, b = _ellipse(rng, m), _ellipse(rng, m)
        ka, kb = rng.uniform(0.1, 1.0, size=2)
        Ga, Gb = ka * a.generator, kb * b.generator
        gap = np.linalg.eigvalsh(Ga @ Ga.T - Gb @ Gb.T).min()
        if abs(gap) < 0.05 * np.linalg.eigvalsh(Ga @ Ga.T).max():
            continue  # too close to touching for any sampled test to be fair
        scales = {"a": ka, "b": kb}
        found = nested({"a": a, "b": b}, task, scales.__getitem__)
        assert ("b" in found["a"]) == (gap > 0), gap
        seen[gap > 0] += 1
    assert min(seen.values()) >= 10, seen  # both outcomes were tested


def test_shifted_ellipses_nest_as_their_boundary_points_say():
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 2.0 * np.pi, 2000, endpoint=False)
    circle = np.column_stack([np.cos(t), np.sin(t)])
    seen = {True: 0, False: 0}
    for _ in range(200):
        a, b = _ellipse(rng, 2, 0.3), _ellipse(rng, 2, 0.3)
        boundary = b.center + circle @ b.generator.T
        d = boundary - a.center
        level = np.einsum("ni,ij,nj->n", d, a.matrix, d).max()  # <= 1: every point of b is in a
        if abs(level - 1.0) < 0.05:
            continue
        found = nested({"a": a, "b": b}, "planar", lambda key: 1.0)
        assert ("b" in found["a"]) == (level < 1.0), level
        seen[level < 1.0] += 1
    assert min(seen.values()) >= 5, seen


def test_of_two_equal_sets_one_is_outlined():
    e = Ellipsoid.from_generator(np.zeros(2), np.diag([2.0, 1.0]))
    small = Ellipsoid.from_generator(np.zeros(2), np.diag([1.0, 0.5]))
    found = nested({"x": e, "y": e, "z": small}, "planar", lambda key: 1.0)
    assert found == {"x": ("y", "z"), "y": ("x", "z"), "z": ()}
    assert outlined(found) == {"x": ("y", "z"), "y": ("z",)}


@pytest.fixture(scope="module")
def fig3():
    robot = mobmanip.load_robot("planar_dual_arm")
    frames = fig3_frames(robot)
    viewer = EllipsoidViewer(robot)
    yield {"robot": robot, "frames": frames, "viewer": viewer, "schedule": viewer.animate(frames, step=0.1)}
    viewer.close()


def test_fig3_sweep_outlines_the_dynamic_disc_that_holds_the_kinematic_one(fig3):
    viewer, frames = fig3["viewer"], fig3["frames"]
    k = viewer.scales
    inside = []
    for frame in frames:  # independently: the drawn discs (centred) by the matrix order
        Gk = k.kinematic * viewer.magnified.get((False, "kinematic"), 1.0) * frame.analysis.kinematic.generator
        Gd = k.dynamic * viewer.magnified.get((False, "dynamic"), 1.0) * frame.analysis.dynamic.generator
        inside.append(np.linalg.eigvalsh(Gd @ Gd.T - Gk @ Gk.T).min() > 0)
    assert any(inside)
    assert viewer.outlined == {(False, "dynamic"): ((False, "kinematic"),)}
    rows = {row["text"].split(":")[0]: row["style"] for row in viewer._page["rows"]}
    assert rows["kinematic ellipsoid"] == "solid" and rows["dynamic ellipsoid"] == "ring"
    assert any("dynamic ellipsoid is drawn as an outline" in note for note in viewer._page["notes"])


def test_fig3_export_shows_the_kinematic_disc_inside_the_dynamic_outline(fig3, tmp_path):
    reason = missing_browser()
    if reason is not None:
        pytest.skip(f"browser tests need Chromium and Playwright: {reason}")
    viewer, frames, schedule = fig3["viewer"], fig3["frames"], fig3["schedule"]
    viewer.set_locked_visible(False)  # the locked kinematic ring coincides with the slowest disc
    o = frames[0].analysis.held_object.center
    viewer.set_camera(2.2, elevation_deg=89.0, azimuth_deg=-90.0, target=o)
    path = viewer.export_html(tmp_path / "fig3.html")
    held = [f for f in frames if f.hold > 0]
    index = max(range(len(held)), key=lambda i: held[i].analysis.kinematic.semi_axes[1])  # the widest disc
    start, end, _ = schedule[index]
    frame = held[index]
    with chromium() as browser:
        page = browser.new_page(viewport=VIEWPORT)
        page.goto(path.as_uri())
        page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.animator.actions.length > 0")
        page.evaluate(f"() => {{ viewer.animator.pause(); viewer.animator.seek({(start + end) / 2}); }}")
        page.wait_for_timeout(1500)
        objects = scene_objects(page)
        assert not objects[f"{M}mobmanip/ellipsoids/dynamic/shape"]["visible"]
        assert objects[f"{M}mobmanip/ellipsoids/dynamic/outline"]["visible"]
        assert objects[f"{M}mobmanip/ellipsoids/kinematic/shape"]["visible"]
        image = screenshot(page)
        e = frame.analysis.kinematic
        scale = viewer.scales.kinematic * viewer.magnified.get((False, "kinematic"), 1.0)
        # points well inside the kinematic disc, off its principal axes and the object's sphere
        u = np.stack(np.meshgrid(np.linspace(-0.8, 0.8, 17), np.linspace(-0.8, 0.8, 17)), -1).reshape(-1, 2)
        u = u[(np.linalg.norm(u, axis=1) < 0.8) & (np.abs(u).min(axis=1) > 0.15)]
        points = o[:2] + (u * scale * e.semi_axes) @ e.axes
        points = points[np.linalg.norm(points - o[:2], axis=1) > 0.06]
        assert len(points) >= 20
        pixels = project(page, np.column_stack([points, np.full(len(points), o[2])]))
        hits = [classify(patch(image, xy), "green").mean() > 0.5 for xy in pixels]
        assert np.mean(hits) > 0.8, np.mean(hits)
        # the outline: magenta on the dynamic disc's rim
        d = frame.analysis.dynamic
        ring = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
        rim = o[:2] + (np.column_stack([np.cos(ring), np.sin(ring)]) * viewer.scales.dynamic * d.semi_axes) @ d.axes
        pixels = project(page, np.column_stack([rim, np.full(len(rim), o[2])]))
        inside_view = [(0 <= x < VIEWPORT["width"]) and (0 <= y < VIEWPORT["height"]) for x, y in pixels]
        rim_hits = [classify(patch(image, xy, 2), "magenta").any() for xy, ok in zip(pixels, inside_view) if ok]
        assert len(rim_hits) >= 16 and np.mean(rim_hits) > 0.6, rim_hits
        page.close()
