"""A constraint's command-line option (issue 36, items 2 and 3): the toy constraint of
``tests/toy_constraint.py`` and one registration line reach every command whose sets honour
it, each checked against the closed form the toy has (its sets are the robot's with every
effort limit scaled by the share), and every command that cannot honour it refuses it in one
line naming the option, the constraint and why.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mobmanip.errors import ArgumentError
from mobmanip.sets.capacity import dynamic_polytope
from mobmanip.terms.builder import terms_at
from mobmanip.terms.constraints.options import (
    CONSTRAINT_OPTIONS,
    ConstraintOption,
    register_constraint_option,
    unregister_constraint_option,
)
from toy_constraint import EffortShare, SpeedShare

ROOT = Path(__file__).resolve().parents[1]
SHARE = 0.5
DIRECTIONS = np.array([[np.cos(t), np.sin(t)] for t in np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)])


@pytest.fixture(scope="module")
def options():
    """The two toy constraints' options, registered as a contributor would (one line each)."""
    register_constraint_option(ConstraintOption("--effort-share", EffortShare, "keep every effort within a share"))
    register_constraint_option(
        ConstraintOption("--speed-share", SpeedShare, "keep every speed within a share", problem="velocity")
    )
    yield
    unregister_constraint_option("--effort-share")
    unregister_constraint_option("--speed-share")


def _closed_form(robot, q, mass, share=SHARE):
    """The dynamic polytope at q with every effort limit scaled by ``share`` (the zonotope's
    closed form, no constraint machinery)."""
    T = terms_at(robot, q, object_mass=mass)
    return dynamic_polytope(T.J_u, T.W, T.P, T.Q, T.xi, T.M_o, T.g_o, share * T.effort_limits)


def _supports(document):
    vertices = np.asarray(document["vertices"])
    return (vertices @ DIRECTIONS.T).max(axis=0)


def test_analyze_takes_the_option_and_honours_it(options, tmp_path, capfd):
    out = tmp_path / "a.json"
    code, _, err = run_cli(capfd, "analyze", "planar_dual_arm", "--measure", "dynamic_polytope", "--effort-share",
                           str(SHARE), "--json", out)  # fmt: skip
    assert code == 0, err
    document = json.loads(out.read_text())
    assert document["constraints"] == [{"name": "effort_share", "share": SHARE, "problem": "acceleration"}]
    robot = mobmanip.load_robot("planar_dual_arm")
    closed = _closed_form(robot, robot.neutral(), robot.spec.object_mass)
    expected = closed.supports(DIRECTIONS)
    np.testing.assert_allclose(_supports(document["dynamic_polytope"]), expected, atol=1e-9 * np.abs(expected).max())
    unconstrained = _closed_form(robot, robot.neutral(), robot.spec.object_mass, share=1.0)
    assert closed.volume < 0.9 * unconstrained.volume  # the share binds
    # The set is a box here (arms stretched): the programs along +-x and +-y return the midpoints
    # of its edges, whose x differ by rounding; the vertices are its 4 corners all the same (the
    # planar hull once sorted by that rounding and dropped two corners).
    assert len(document["dynamic_polytope"]["vertices"]) == len(closed.vertices) == 4
    assert document["dynamic_polytope"]["volume"] == pytest.approx(closed.volume, rel=1e-9)


def test_analyze_on_tiago_keeps_the_share_along_every_spatial_axis(options, tmp_path, capfd):
    """On TIAGo++ (joint frames turned, its file's numbers rounded), 6-D spatial task at the hold
    posture: each axis's support and straight-line reach with the option equal the zonotope of
    the halved effort limits, its support c.u + sum_i |g_i.u| in closed form and its reach by an
    LP over the generators' weights (scipy's HiGHS), to 1e-9."""
    from scipy.optimize import linprog

    out = tmp_path / "t.json"
    argv = ["analyze", "tiago_dual", "--posture", "hold", "--task", "spatial", "--measure", "dynamic_polytope",
            "--object-mass", "1", "--effort-share", str(SHARE), "--json", out]  # fmt: skip
    code, _, err = run_cli(capfd, *argv)
    assert code == 0, err
    document = json.loads(out.read_text())
    robot = mobmanip.load_robot("tiago_dual")
    closed = _closed_form(robot, robot.hold_configuration(), 1.0)
    G, c = np.asarray(closed.generators), np.asarray(closed.center)
    axes = document["task_axes"]
    reaches = document["dynamic_polytope"]["reaches"]
    assert len(reaches) == 12
    for entry in reaches:
        u = np.zeros(6)
        u[axes.index(entry["axis"][1:])] = 1.0 if entry["axis"][0] == "+" else -1.0
        assert entry["support"] == pytest.approx(c @ u + np.abs(G.T @ u).sum(), rel=1e-9)
        n = G.shape[1]  # max t: t u = c + G s, |s| <= 1
        lp = linprog(np.r_[-1.0, np.zeros(n)], A_eq=np.column_stack([u, -G]), b_eq=c,
                     bounds=[(0.0, None)] + [(-1.0, 1.0)] * n, method="highs")  # fmt: skip
        assert lp.status == 0
        assert entry["straight_line"] == pytest.approx(lp.x[0], rel=1e-9)
        assert entry["straight_line"] < 0.6 * entry["ideal_straight_line"]  # the share binds
        assert entry["binding"] and all("at 0.5 of its effort limit" in label for label in entry["binding"])


def test_payload_takes_the_option_and_equals_a_bisection_over_the_closed_form(options, tmp_path, capfd):
    """The heaviest object the paper robot can accelerate at 2 m/s^2 along +x with its efforts
    within half their limits: the payload program against a bisection on the mass over the closed
    form's membership of (2, 0)."""
    out = tmp_path / "p.json"
    code, _, err = run_cli(capfd, "payload", "planar_dual_arm", "--accel", "2,0", "--effort-share", str(SHARE),
                           "--json", out)  # fmt: skip
    assert code == 0, err
    got = json.loads(out.read_text())
    assert got["status"] == "bounded"
    robot = mobmanip.load_robot("planar_dual_arm")
    q = robot.neutral()
    a = np.array([2.0, 0.0])
    low, high = 0.0, 2.0 * got["mass"]
    assert _closed_form(robot, q, low).contains(a) and not _closed_form(robot, q, high).contains(a)
    for _ in range(50):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if _closed_form(robot, q, middle).contains(a, tol=1e-12) else (low, middle)
    assert got["mass"] == pytest.approx(low, rel=1e-6)


def test_team_takes_the_option_as_the_api_does(options, capfd):
    """The team's reaches from its centre along each axis, printed, are the API's under the same
    constraint (tests/test_constraint_seam.py holds the API's to the closed form)."""
    import re

    from mobmanip.team import analyze_team, load_team, ray_radius

    path = ROOT / "examples" / "two_arms_box.toml"
    code, out, err = run_cli(capfd, "team", path, "--measure", "dynamic_polytope", "--effort-share", "0.6")
    assert code == 0, err
    printed = [float(v) for v in re.findall(r"^  [a-z]+: \+([0-9.]+) limited", out, flags=re.M)]
    expected = analyze_team(load_team(path), measures=("dynamic_polytope",), constraints=(EffortShare(0.6),))
    polytope = expected.measure("dynamic_polytope")
    reaches = [ray_radius(polytope, e) for e in np.eye(6)]
    assert len(printed) == 6
    np.testing.assert_allclose(printed, reaches, rtol=5e-6)  # printed to 4 decimals
    plain = analyze_team(load_team(path), measures=("dynamic_polytope",)).measure("dynamic_polytope")
    assert reaches[0] < 0.9 * ray_radius(plain, np.eye(6)[0])  # the share binds


def test_place_by_a_reading_honours_the_option(options, tmp_path, capfd):
    """The placement's value is the closed form's straight-line reach at the placement found."""
    out = tmp_path / "place.json"
    code, _, err = run_cli(capfd, "place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective",
                           "dynamic_polytope:reach:+x", "--budget", "30", "--effort-share", str(SHARE),
                           "--json", out)  # fmt: skip
    assert code == 0, err
    document = json.loads(out.read_text())
    robot = mobmanip.load_robot("planar_dual_arm")
    q = robot.configuration(tuple(document["q"]["platform"]), document["q"]["joints"])
    closed = _closed_form(robot, q, robot.spec.object_mass)
    assert document["value"] == pytest.approx(closed.straight_line_reach(np.array([1.0, 0.0])), rel=1e-9)


def test_place_map_by_a_reading_honours_the_option(options, tmp_path, capfd):
    """--map with a measure's reading: every cell's value is the closed form's straight-line reach
    at the cell's configuration (map.npz), and the placement, seeded from the best cells, is at
    least the best cell and equals the closed form at its own configuration."""
    out = tmp_path / "place.json"
    code, printed, err = run_cli(capfd, "place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective",
                                 "dynamic_polytope:reach:+x", "--budget", "30", "--effort-share", str(SHARE),
                                 "--map", tmp_path / "map", "--map-cells", "4", "--json", out)  # fmt: skip
    assert code == 0, err
    assert "at the hold that maximises dynamic:capacity:+x there" in printed
    robot = mobmanip.load_robot("planar_dual_arm")
    mass = robot.spec.object_mass
    x = np.array([1.0, 0.0])
    grid = np.load(tmp_path / "map" / "map.npz")
    cells = list(zip(*np.nonzero(np.isfinite(grid["values"]))))
    assert len(cells) >= 2
    for cell in cells:
        closed = _closed_form(robot, grid["configurations"][cell], mass)
        assert grid["values"][cell] == pytest.approx(closed.straight_line_reach(x), rel=1e-9)
    document = json.loads(out.read_text())
    q = robot.configuration(tuple(document["q"]["platform"]), document["q"]["joints"])
    assert document["value"] == pytest.approx(_closed_form(robot, q, mass).straight_line_reach(x), rel=1e-9)
    assert document["value"] >= np.nanmax(grid["values"])


SITE = """robot = "planar_dual_arm"
objective = "{objective}"
budget = 30
starts = 2
positions = [[1.0, 0.5, 0.35], [1.4, 0.2, 0.35]]
[grounded]
mu = 0.5
"""


def test_site_by_a_reading_honours_the_option(options, tmp_path, capfd):
    """Each position's value is the closed form's straight-line reach at the configuration the
    site chose (the CSV's q), and its grounded reach is the robot's with its effort limits scaled,
    on the same floor (no constraint machinery for the share)."""
    site = tmp_path / "site.toml"
    site.write_text(SITE.format(objective="dynamic_polytope:reach:+x"))
    code, out, err = run_cli(capfd, "site", site, "-o", tmp_path / "out", "--effort-share", str(SHARE))
    assert code == 0, err
    assert "keeping effort_share" in out
    robot = mobmanip.load_robot("planar_dual_arm")
    scaled = robot.with_limits(effort={n: v * SHARE for n, v in robot.joint_effort_limits.items()})
    lines = (tmp_path / "out" / "site.csv").read_text().splitlines()
    header = lines[0].split(",")
    columns = [header.index(f"q.{name}") for name in robot.coordinate_names]
    for line in lines[1:]:
        row = line.split(",")
        q = np.array([float(row[k]) for k in columns])
        closed = _closed_form(robot, q, robot.spec.object_mass)
        assert float(row[header.index("value")]) == pytest.approx(closed.straight_line_reach(np.array([1.0, 0.0])),
                                                                   rel=1e-9)  # fmt: skip
        whole = _closed_form(robot, q, robot.spec.object_mass, share=1.0)
        assert whole.straight_line_reach(np.array([1.0, 0.0])) > 1.1 * closed.straight_line_reach(np.array([1.0, 0.0]))
        grounded = mobmanip.analyze(scaled, q, constraints=(mobmanip.Floor(mu=0.5),), measures=("dynamic_polytope",))
        reach = grounded.measure("dynamic_polytope").straight_line_reach(np.array([1.0, 0.0]))
        assert float(row[header.index("grounded_reach")]) == pytest.approx(reach, rel=1e-9)
    site.write_text(SITE.format(objective="kinematic:capacity:+x"))
    code, _, err = run_cli(capfd, "site", site, "-o", tmp_path / "out2", "--effort-share", str(SHARE))
    assert_one_line_error(code, err, "an ellipsoid's, which cannot honour the constraints (effort_share)")


@pytest.mark.parametrize(
    ("argv", "needles"),
    [
        (("brake", "planar_dual_arm"), ("brake cannot honour --effort-share (effort_share)",)),
        (("place", "planar_dual_arm", "--object", "1,0.5,0.35", "--objective", "dynamic:log_volume"),
         ("place cannot honour --effort-share (effort_share)", "an ellipsoid objective ignores")),
    ],
)  # fmt: skip
def test_a_command_that_cannot_honour_it_refuses_it_in_one_line(options, capfd, argv, needles):
    code, _, err = run_cli(capfd, *argv, "--effort-share", str(SHARE))
    assert_one_line_error(code, err, *needles)


def test_an_option_of_another_problem_is_refused_by_name(options, capfd):
    code, _, err = run_cli(capfd, "payload", "planar_dual_arm", "--accel", "2,0", "--speed-share", "0.5")
    assert_one_line_error(code, err, "payload cannot honour --speed-share", "velocity problem", "acceleration")


def test_the_option_shows_in_help_and_commands_without_constraints_do_not_take_it(options, capfd):
    code, out, _ = run_cli(capfd, "analyze", "--help")
    words = " ".join(out.split())  # argparse wraps the lines
    assert code == 0 and "--effort-share" in words and "a constraint of the acceleration problem at rest" in words
    code, _, err = run_cli(capfd, "collision-matrix", "planar_dual_arm", "--effort-share", "0.5")
    assert_one_line_error(code, err, "unrecognized arguments: --effort-share")


def test_bad_options_are_refused_at_registration():
    with pytest.raises(ArgumentError, match="a constraint option is --lower-case-words, got 'effort'"):
        ConstraintOption("effort", EffortShare, "x")
    with pytest.raises(ArgumentError, match="problem must be one of"):
        ConstraintOption("--effort", EffortShare, "x", problem="jerk")
    register_constraint_option(ConstraintOption("--twice", EffortShare, "x"))
    try:
        with pytest.raises(ArgumentError, match="constraint option --twice is registered already"):
            register_constraint_option(ConstraintOption("--twice", EffortShare, "x"))
    finally:
        unregister_constraint_option("--twice")
    with pytest.raises(ArgumentError, match="no constraint option '--never' is registered"):
        unregister_constraint_option("--never")
    assert "--twice" not in CONSTRAINT_OPTIONS


def test_an_option_that_builds_a_constraint_of_another_problem_is_refused(capfd):
    """An option declared for the acceleration problem whose constraint bounds velocities would
    reach commands that cannot honour it: refused in one line naming both problems."""
    register_constraint_option(ConstraintOption("--mislabelled", SpeedShare, "declared wrongly"))
    try:
        code, _, err = run_cli(capfd, "analyze", "planar_dual_arm", "--mislabelled", "0.5")
        assert_one_line_error(code, err, "--mislabelled declares the acceleration problem", "velocity problem")
    finally:
        unregister_constraint_option("--mislabelled")
