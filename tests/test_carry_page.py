"""``mobmanip carry ROBOT --path PATH.csv --export PAGE.html`` on TIAGo++ (issue 39: the robot drove
to the edge of a camera that framed its start), played in headless Chromium: at every sampled
time, on keyframes and between them, the robot's visual geometry (placed by Pinocchio from the
motion the same command writes with ``--out``, read back as a user would) projects inside the
central 80 % of the view, at a readable size; the legend covers under a fifth of the view.
Skipped, with the reason, only when Chromium or Playwright is missing."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from browser_util import VIEWPORT, legend_share, project
from mobmanip.cli import main
from mobmanip.motion.trajectory import read_trajectory
from mobmanip.robot.model import load_robot
from mobmanip.viz.page import visual_points
from mobmanip.viz.scene import visual_model

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
STEP = 0.2  # s: 61 samples of the 12 s path, every one a frame of the page
#: The robot stays inside this central share of the view's width and height at every time.
CENTRAL = 0.8
#: ... and spans at least this share of the view's height (readable, not a speck).
MIN_HEIGHT = 0.25
LEGEND_SHARE = 0.2


@pytest.fixture(scope="module")
def carried(tmp_path_factory):
    where = tmp_path_factory.mktemp("carry_page")
    page, out = where / "carry.html", where / "out"
    start = time.monotonic()
    code = main(["carry", "tiago_dual", "--path", str(EXAMPLES / "carry_turn.csv"), "--step", str(STEP),
                 "--prepare", "0", "--out", str(out), "--export", str(page)])  # fmt: skip
    assert code == 0
    robot = load_robot("tiago_dual")
    return robot, page, read_trajectory(robot, out / "trajectory.csv"), time.monotonic() - start


def test_the_tiago_carry_page_keeps_the_robot_in_the_middle_of_the_view(browser, carried):
    robot, page_file, motion, seconds = carried
    assert np.linalg.norm(motion.q[-1, :2] - motion.q[0, :2]) > 1.5  # m: it drives far beyond its size
    model, geometry = visual_model(robot)
    page = browser.new_page(viewport=VIEWPORT)
    try:
        page.goto(page_file.as_uri())
        # the animation loaded and the page's script has applied its camera (with the legend);
        # the projections need no mesh, so the scene is not waited for
        page.wait_for_function(
            "() => typeof viewer !== 'undefined' && viewer.animator.actions.length > 0"
            " && document.getElementById('mobmanip-legend') !== null",
            timeout=90000,
        )
        assert legend_share(page) < LEGEND_SHARE
        w, h = VIEWPORT["width"], VIEWPORT["height"]
        lo, hi = 0.5 * (1 - CENTRAL), 0.5 * (1 + CENTRAL)
        t = motion.t - motion.t[0]
        extents = []
        for k in np.linspace(0, len(t) - 2, 8).round().astype(int):
            for s in (0.0, 0.5):  # on the keyframe and halfway to the next (meshcat interpolates)
                at = t[k] + s * (t[k + 1] - t[k])
                # the page's own step of its following camera (run on every animation frame)
                page.evaluate(f"() => {{ viewer.animator.pause(); viewer.animator.seek({at}); mobmanipFollow(); }}")
                q = pin.interpolate(model, motion.q[k], motion.q[k + 1], s)  # near meshcat's blend
                xy = project(page, visual_points(model, geometry, q)) / [w, h]
                extents.append([at, *xy.min(axis=0), *xy.max(axis=0)])
                inside = (xy >= lo) & (xy <= hi)
                assert inside.all(), (at, xy.min(axis=0), xy.max(axis=0))
                assert np.ptp(xy[:, 1]) >= MIN_HEIGHT, (at, np.ptp(xy[:, 1]))
    finally:
        page.close()
    e = np.array(extents)
    print(f"carry {seconds:.1f} s; robot in x {e[:, 1].min():.3f}-{e[:, 3].max():.3f}, "
          f"y {e[:, 2].min():.3f}-{e[:, 4].max():.3f} of the view")  # fmt: skip
