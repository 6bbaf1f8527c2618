"""The team's motion page (``mobmanip team-carry ... --export PAGE.html``), played in headless
Chromium (see ``browser_util``): at sampled times every robot is where its written trajectory puts
it, the object where its hands hold it and on its path, the team's kinematic ellipsoid there at the
legend's scale, and all of it in the viewport, spanning a stated share of it; the page asks the
network for nothing. Skipped, with the reason, only when Chromium or Playwright is missing.

The expectations come from the files the same command writes with ``--out`` (each robot's
trajectory, read back as a user would) through Pinocchio's forward kinematics and
``analyze_team`` of a team rebuilt there, not from the page's code.
"""

from __future__ import annotations

import re
import time
import tomllib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from browser_util import VIEWPORT, chromium, geometry_corners, missing_browser, project, wait_for_scene, world_matrix
from mobmanip.cli import main
from mobmanip.motion.carry import read_path
from mobmanip.motion.trajectory import read_trajectory
from mobmanip.team import Member, Team, analyze_team, hand_positions, load_team
from mobmanip.viz.page import visual_points
from mobmanip.viz.scene import PLANAR_THICKNESS, visual_model

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
TEAM = EXAMPLES / "beam_team.toml"
#: carry_turn.csv (a 90 deg arc, 2 m in 12 s) scaled to the beam team, as in test_team_carry.
SCALE = 2.0
STEP = 0.1  # s: 121 samples, every one a frame of the page
M = "meshcat/"
TEAM_PATH = "mobmanip/team"
#: The beam's size as its description gives it (m, along its length, across, up).
BEAM_SIZE = tomllib.loads(TEAM.read_text())["object"]["size"]
TOL = 1e-5  # m: the page's keyframes against the written motion (as the single robot's test)
#: How far the carried object may be from its path (m): the QP holds every hand within a
#: millimetre of its target (test_team_carry), so the object, rigid between them, within twice that.
ON_PATH = 2e-3
#: Share of the viewport's larger side (width or height) the robots, the object and the set must
#: span together at every sampled time. The camera frames the whole motion (4 m of path and the
#: 3.4 m team turning through 90 deg); the team alone is about as long as the framed box is wide, so
#: it must never shrink to a corner: at least a quarter of the view (the single robot, a 0.7 m
#: robot framed over a 2 m drive, must span 0.08).
MIN_SPAN = 0.25


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The command run once: the page and each robot's written trajectory, read back."""
    reason = missing_browser()
    if reason is not None:
        pytest.skip(f"browser tests need Chromium and Playwright: {reason}")
    where = tmp_path_factory.mktemp("team_page")
    page, out = where / "beam.html", where / "out"
    args = ["team-carry", str(TEAM), "--path", str(EXAMPLES / "carry_turn.csv"), "--scale", str(SCALE)]
    start = time.monotonic()
    code = main([*args, "--prepare", "0", "--step", str(STEP), "--out", str(out), "--export", str(page)])
    seconds = time.monotonic() - start
    assert code == 0
    team = load_team(TEAM)
    motions = [read_trajectory(m.robot, out / f"trajectory_{m.name}.csv") for m in team.members]
    return team, page, motions, seconds


def _legend_scale(page) -> tuple[float, float]:
    """The kinematic ellipsoid's scale (m of scene per m/s) the legend states, and half a unit of
    its last printed digit (how exact the printed number is)."""
    text = page.evaluate("() => document.getElementById('mobmanip-legend').innerText")
    match = re.search(r"kinematic ellipsoid: 1 m/s = ([0-9.]+) m", text)
    assert match is not None, text
    digits = match.group(1)
    decimals = len(digits.split(".")[1]) if "." in digits else 0
    return float(digits), 0.5 * 10.0**-decimals


def test_the_team_page_plays_every_robot_the_object_and_the_set_in_view(exported):
    team, page_file, motions, seconds = exported
    t = motions[0].t
    for motion in motions:
        np.testing.assert_array_equal(motion.t, t)
    path = read_path(EXAMPLES / "carry_turn.csv")
    shift, turn = path.sample(t)
    c, s = np.cos(team.object_yaw), np.sin(team.object_yaw)
    on_path = team.held_object.center[:2] + SCALE * shift[:, :2] @ np.array([[c, s], [-s, c]])
    visuals = [visual_model(m.robot) for m in team.members]
    requests: list[str] = []
    with chromium() as browser:
        page = browser.new_page(viewport=VIEWPORT)
        page.route(re.compile(r"^https?://"), lambda route: (requests.append(route.request.url), route.abort()))
        page.on("request", lambda r: None if r.url.startswith(("file:", "data:", "blob:")) else requests.append(r.url))
        try:
            page.goto(page_file.as_uri())
            wait_for_scene(page, (f"{M}{TEAM_PATH}/object/center", f"{M}{TEAM_PATH}/sets/kinematic/shape"))
            assert page.evaluate("() => viewer.animator.duration") == pytest.approx(t[-1] - t[0], abs=0.05)
            scale, half_digit = _legend_scale(page)
            spans = []
            for k in np.linspace(0, len(t) - 1, 9).round().astype(int):
                page.evaluate(f"() => {{ viewer.animator.pause(); viewer.animator.seek({t[k] - t[0]}); }}")
                qs = [motion.q[k] for motion in motions]
                points = []
                # every robot at its own configuration: each visual geometry where Pinocchio puts it
                for member, q, (model, geometry) in zip(team.members, qs, visuals):
                    data, gdata = model.createData(), geometry.createData()
                    pin.updateGeometryPlacements(model, data, geometry, gdata, q)
                    for g, geom in enumerate(geometry.geometryObjects):
                        drawn = world_matrix(page, f"{M}{TEAM_PATH}/robots/{member.name}/visuals/{geom.name}", True)
                        assert drawn is not None, geom.name
                        np.testing.assert_allclose(drawn[:3, 3], gdata.oMg[g].translation, atol=TOL)
                        np.testing.assert_allclose(drawn[:3, :3], gdata.oMg[g].rotation, atol=TOL)
                    points.append(visual_points(model, geometry, q))
                # the object: at its hands' centroid (the beam's grasps are symmetric about its
                # centre), on its path, turned with it
                members = [Member(m.name, m.robot, q, m.arms) for m, q in zip(team.members, qs)]
                centre = np.vstack([hand_positions(m) for m in members]).mean(axis=0)  # forward kinematics
                obj = world_matrix(page, f"{M}{TEAM_PATH}/object", node=True)
                np.testing.assert_allclose(obj[:3, 3], centre, atol=TOL)
                assert np.linalg.norm(obj[:2, 3] - on_path[k]) <= ON_PATH, (t[k], obj[:3, 3], on_path[k])
                assert np.arctan2(obj[1, 0], obj[0, 0]) == pytest.approx(turn[k], abs=ON_PATH / 0.75)
                points.append(centre[None, :])
                # the beam drawn as a box of its described size, along the line from the south
                # robot's hands to the north robot's (its ends, 1.5 m apart)
                hands = np.vstack([hand_positions(m) for m in members])
                u = hands[2:].mean(axis=0) - hands[:2].mean(axis=0)
                u = np.array([u[0], u[1], 0.0]) / np.linalg.norm(u[:2])
                local = (geometry_corners(page, f"{M}{TEAM_PATH}/object/body") - centre) @ np.array(
                    [u, [-u[1], u[0], 0.0], [0.0, 0.0, 1.0]]
                ).T
                np.testing.assert_allclose(np.ptp(local, axis=0), BEAM_SIZE, atol=ON_PATH)
                np.testing.assert_allclose(local.mean(axis=0), 0.0, atol=ON_PATH)
                # the team's kinematic ellipsoid there, its (x, y) shadow drawn at the legend's scale
                rebuilt = Team.holding(members, team.held_object.mass, task=team.task, center=centre)
                G = analyze_team(rebuilt, ["kinematic"]).measures["kinematic"].generator[:2]
                drawn = world_matrix(page, f"{M}{TEAM_PATH}/sets/kinematic", node=True)
                np.testing.assert_allclose(drawn[:3, 3], centre, atol=TOL)
                shape = drawn[:3, :3] @ drawn[:3, :3].T
                thickness = PLANAR_THICKNESS[False, "kinematic"]
                np.testing.assert_allclose(shape[2], [0.0, 0.0, thickness**2], atol=TOL)
                # the legend prints the scale to its last digit: squared, twice that share at most
                share = 2.0 * half_digit / scale + 1e-9
                np.testing.assert_allclose(shape[:2, :2], scale**2 * G @ G.T, rtol=share, atol=share * scale**2)
                ring = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 32)])
                points.append(centre + np.c_[ring @ np.linalg.cholesky(shape[:2, :2]).T, np.zeros(len(ring))])
                # all of it inside the viewport, spanning MIN_SPAN of it
                xy = project(page, np.vstack(points))
                w, h = VIEWPORT["width"], VIEWPORT["height"]
                inside = (xy[:, 0] >= 0) & (xy[:, 0] <= w) & (xy[:, 1] >= 0) & (xy[:, 1] <= h)
                assert inside.all(), (t[k], xy[~inside])
                spans.append(max(np.ptp(xy[:, 0]) / w, np.ptp(xy[:, 1]) / h))
                assert spans[-1] >= MIN_SPAN, (t[k], spans[-1])
        finally:
            page.close()
    assert requests == []  # the page is self-contained: no request leaves it
    size = page_file.stat().st_size
    print(f"team page {size / 1e6:.2f} MB, command {seconds:.1f} s, spans {min(spans):.2f}-{max(spans):.2f}")
    assert size < 5e6  # each mesh once, compressed: far below meshcat's own page


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--export", "{tmp}/missing/beam.html"], "directory does not exist"),
        (["--export", "{tmp}"], "directory"),
        (["--export", "{tmp}/beam.html", "--every", "0"], "--every"),
        (["--every", "2"], "--every"),
    ],
)
def test_a_bad_export_is_one_error_line_before_any_work(extra, words, tmp_path, capsys):
    extra = [e.replace("{tmp}", str(tmp_path)) for e in extra]
    code = main(["team-carry", str(TEAM), "--path", str(EXAMPLES / "carry_turn.csv"), "--scale", "2", *extra])
    printed = capsys.readouterr()
    assert code == 2
    assert printed.err.startswith("mobmanip: error: ") and printed.err.count("\n") == 1, printed.err
    assert words in printed.err
    assert printed.out == ""  # refused before the motion: its report is the command's first line
    assert list(tmp_path.iterdir()) == []


def test_the_frames_play_the_self_motion_then_the_path():
    """With --prepare, the page plays the self-motion first (the object held still where the
    team holds it), then the path: frames on one clock from the team's start posture to the
    motion's end, the object carried with the hands, its turn the path's."""
    from mobmanip.coordination.carry import team_carry
    from mobmanip.motion.carry import ObjectPath
    from mobmanip.viz.team_motion_page import team_motion_frames

    team = load_team(TEAM)
    path = read_path(EXAMPLES / "carry_turn.csv")
    path = ObjectPath(path.t, SCALE * path.xy)
    result = team_carry(team, path, step=STEP, prepare=1.0)
    prep, motion = result.preparation, result.motion
    frames, times = team_motion_frames(result, every=1)
    assert len(frames) == len(prep.t) + len(motion.t) - 1  # the self-motion's end is the path's start
    np.testing.assert_allclose(times, np.r_[prep.t[:-1], motion.t] - prep.t[0], atol=1e-9)
    assert np.all(np.diff(times) > 0)
    first, last = frames[0].analysis.team, frames[-1].analysis.team
    for member, start in zip(first.members, team.members):
        np.testing.assert_array_equal(member.q, start.q)  # from the team's own posture
    for member, q in zip(last.members, motion.q):
        np.testing.assert_array_equal(member.q, q[-1])
    assert [f.label.endswith("(self-motion)") for f in frames] == [k < len(prep.t) - 1 for k in range(len(frames))]
    # at the start the object is the team's, its turn zero; at the end the path's 90 deg turn
    np.testing.assert_allclose(first.held_object.center, team.held_object.center, atol=1e-12)
    np.testing.assert_allclose(first.held_object.offsets, team.held_object.offsets, atol=1e-12)
    assert frames[0].turn == pytest.approx(0.0, abs=1e-12)
    assert frames[-1].turn == pytest.approx(np.pi / 2, abs=ON_PATH / 0.75)
    # the object moves rigidly with its hands: its centre stays their centroid (the beam's grasps
    # are symmetric about it) and each hand keeps its distance from the centre
    for frame in frames:
        held = frame.analysis.team.held_object
        hands = np.vstack([hand_positions(m) for m in frame.analysis.team.members])
        np.testing.assert_allclose(held.center, hands.mean(axis=0), atol=1e-9)
        reach = np.linalg.norm(held.offsets, axis=1)
        np.testing.assert_allclose(reach, np.linalg.norm(team.held_object.offsets, axis=1), atol=ON_PATH)
