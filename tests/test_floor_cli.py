"""``mobmanip analyze --ground``: the grounded polytope from the command line, its readings per
axis and what stops each, in the summary and the JSON; bad floor options in one line, exit 2."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import floor_reference as fr
import mobmanip
from mobmanip.postures.named import named_configuration
from mobmanip.terms.constraints.floor import Floor


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "mobmanip", *args], capture_output=True, text=True, cwd=cwd)


def test_ground_from_the_command_line_equals_the_python_api(tmp_path):
    out = tmp_path / "g.json"
    run = _cli("analyze", "tiago_dual", "--posture", "hold", "--object-mass", "2", "--task", "spatial", "--mu", "0.5",
               "--load", "any", "--json", str(out))  # fmt: skip
    assert run.returncode == 0, run.stderr
    doc = json.loads(out.read_text())
    robot = mobmanip.load_robot("tiago_dual")
    api = mobmanip.analyze(
        robot, named_configuration(robot, "hold"), "spatial", object_mass=2.0,
        measures=("kinematic", "dynamic", "dynamic_polytope"), constraints=(Floor(mu=0.5, load="any"),),
    )  # fmt: skip
    reaches = {r["axis"]: r for r in doc["dynamic_polytope"]["reaches"]}
    P = api.measures["dynamic_polytope"]
    assert reaches["+x"]["straight_line"] == pytest.approx(P.straight_line_reach([1, 0, 0, 0, 0, 0]), rel=1e-9)
    assert reaches["+y"]["support"] == pytest.approx(P.support([0, 1, 0, 0, 0, 0]), rel=1e-9)
    assert round(reaches["+x"]["straight_line"], 2) == 37.08  # issue 24's table
    assert doc["dynamic_ellipsoid"]["ignored_constraints"] == ["floor"]
    assert doc["constraints"][0]["name"] == "floor" and doc["constraints"][0]["mu"] == 0.5
    assert doc["dynamic_polytope"]["model"]["floor"]["mu"] == 0.5
    assert any("lifts off the floor" in b for b in reaches["+x"]["binding"])
    assert 0.0 <= reaches["+x"]["floor"]["margin"] < 1e-3  # the ZMP inside, near the front edge
    # the summary names the readings and what stops them
    assert "straight line 37.08, support 42.94" in run.stdout
    # ranked by what 1 % more of each limit gives: the two front casters, equally
    assert re.search(
        r"support lifting off: caster_front_left_2_link \+([\d.]+), caster_front_right_2_link \+\1;", run.stdout
    )
    assert "dynamic ellipsoid (coupled) [ignores floor" in run.stdout
    assert doc["dynamic_polytope"]["model"]["floor"]["load"] == "any"


def test_the_default_load_sharing_is_compliant_with_traction_and_any_without(tmp_path):
    base = ("analyze", "tiago_dual", "--posture", "hold", "--object-mass", "2", "--task", "spatial")
    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    for extra, floor, load in (
        (("--mu", "0.5", "--reserve", "0.05"), Floor(mu=0.5, load="compliant", reserve=0.05), "compliant"),
        (("--no-traction",), Floor(mu=None, load="any"), "any"),
    ):
        out = tmp_path / "g.json"
        run = _cli(*base, *extra, "--json", str(out))
        assert run.returncode == 0, run.stderr
        doc = json.loads(out.read_text())
        model = doc["dynamic_polytope"]["model"]["floor"]
        assert model["load"] == load and model["reserve"] == (0.05 if load == "compliant" else 0.0)
        api = mobmanip.analyze(
            robot, q, "spatial", object_mass=2.0, measures=("dynamic_polytope",), constraints=(floor,)
        )
        P = api.measures["dynamic_polytope"]
        reaches = {r["axis"]: r for r in doc["dynamic_polytope"]["reaches"]}
        for axis, e in (("+x", [1, 0, 0, 0, 0, 0]), ("-y", [0, -1, 0, 0, 0, 0])):
            assert reaches[axis]["straight_line"] == pytest.approx(P.straight_line_reach(e), rel=1e-9)


@pytest.mark.parametrize(
    "args, message",
    [
        (["--mu", "-0.5"], "mu must be a finite friction coefficient >= 0, got -0.5"),
        (["--mu", "1e9"], "mu 1000000000.0 is above 10, more than any floor gives"),  # HiGHS: 'Unknown'
        (["--reserve", "1.5"], "--reserve must be a fraction in [0, 1), got 1.5"),
        (["--reserve", "nan"], "--reserve must be a fraction in [0, 1), got nan"),
        (["--mu", "0.5", "--no-traction"], "--mu and --no-traction contradict each other"),
    ],
)
def test_bad_floor_options_are_one_line(args, message):
    run = _cli("analyze", "planar_dual_arm", *args)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [f"mobmanip: error: {run.stderr.strip().split('error: ', 1)[1]}"]
    assert message in run.stderr


def test_a_fixed_base_has_no_floor(tmp_path):
    """A fixed base has no floor; an omnidirectional base stands on the wheels its spec gives (the
    built-in one on four mecanum wheels) and, given none, is told where to give them."""
    run = _cli("analyze", "ur5", "--ground")
    assert run.returncode == 2 and "'ur5' has a fixed platform" in run.stderr
    run = _cli("analyze", "planar_dual_arm_omni", "--ground")
    assert run.returncode == 0 and "contacts wheel_0, wheel_1, wheel_2, wheel_3" in run.stdout
    root = Path(__file__).resolve().parents[1] / "robots"
    text = (root / "planar_dual_arm_omni.toml").read_text()
    spec = tmp_path / "omni.toml"
    spec.write_text(
        text[: text.index("[support]")].replace('"planar_dual_arm.urdf"', f'"{root / "planar_dual_arm.urdf"}"')
    )
    run = _cli("analyze", str(spec), "--ground")
    assert run.returncode == 2 and run.stderr.count("\n") == 1
    assert (
        "no wheels on the floor (omnidirectional platform): give its driven contacts in the spec's [support] wheels"
        in run.stderr
    )


def _reference_polygon(robot) -> np.ndarray:
    """The support polygon of a robot standing at the origin, heading along x: the hull of the
    reference's contacts (its wheels below their axles, its URDF's casters: tests/floor_reference.py)."""
    return fr.support_polygon(np.array([c.point for c in fr.driven_wheels(robot) + fr.urdf_casters(robot)]))


def _centre_of_mass(robot, q, object_mass: float) -> np.ndarray:
    """The robot's and its held object's centre of mass (Pinocchio's centerOfMass, the object at
    the hands' midpoint), (3,)."""
    mass = pin.computeTotalMass(robot.model)
    center = mobmanip.analyze(robot, q, object_mass=object_mass).held_object.center
    return (mass * pin.centerOfMass(robot.model, robot.model.createData(), q) + object_mass * center) / (
        mass + object_mass
    )


def test_the_viewer_draws_the_support_and_the_zmp_at_rest(tmp_path):
    """At rest the zero-moment point is below the centre of mass of the robot and its object, and
    the support polygon is the hull of the robot's contacts (both worked out here); the page draws
    them and says the margin."""
    from mobmanip.analysis.reaches import floor_at_rest

    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    assert robot.configuration_dict(q)["platform"] == [0.0, 0.0, 0.0]
    grounded = mobmanip.analyze(
        robot, q, "spatial", object_mass=2.0, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),)
    ).measures["dynamic_polytope"]
    found = floor_at_rest(grounded)
    polygon = _reference_polygon(robot)
    assert sorted(map(tuple, np.round(found["polygon"], 12))) == sorted(map(tuple, np.round(polygon, 12)))
    np.testing.assert_allclose(found["zmp"][:2], _centre_of_mass(robot, q, 2.0)[:2], rtol=0, atol=1e-9)
    assert found["margin"] == pytest.approx(fr.polygon_margin(polygon, found["zmp"]), abs=1e-12)
    assert found["margin"] > 0
    page = tmp_path / "floor.html"
    run = _cli("view", "tiago_dual", "--posture", "hold", "--object-mass", "2", "--task", "spatial", "--mu", "0.5",
               "--no-locked", "--export", str(page))  # fmt: skip
    assert run.returncode == 0, run.stderr
    from browser_util import exported_scene, missing_browser

    if missing_browser():
        pytest.skip(f"the page's scene needs a browser: {missing_browser()}")
    drawn, text = exported_scene(page)
    assert {"meshcat/mobmanip/floor/polygon", "meshcat/mobmanip/floor/zmp"} <= drawn
    assert f"margin {found['margin']:.3f} m" in text


def test_trajectory_ground_reports_the_margin_per_sample(tmp_path):
    """A robot standing still for a second: every sample's zero-moment point is below the robot's
    and the object's centre of mass (Pinocchio's centerOfMass), inside the support."""
    import csv

    from mobmanip.motion.trajectory import trajectory_table

    robot = mobmanip.load_robot("tiago_dual")
    q = named_configuration(robot, "hold")
    t = np.linspace(0.0, 1.0, 11)
    header, values = trajectory_table(robot, t, np.repeat(q[None], len(t), axis=0))
    path = tmp_path / "still.csv"
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(values.tolist())
    out = tmp_path / "out"
    run = _cli("trajectory", "tiago_dual", str(path), "--object-mass", "2", "--ground", "--out", str(out))
    assert run.returncode == 0, run.stderr
    doc = json.loads((out / "analysis.json").read_text())
    both = _centre_of_mass(robot, q, 2.0)
    np.testing.assert_allclose(doc["columns"]["zmp_x"], both[0], atol=1e-9)
    np.testing.assert_allclose(doc["columns"]["zmp_y"], both[1], atol=1e-9)
    margin = fr.polygon_margin(_reference_polygon(robot), both)
    assert doc["min_stability_margin"] == pytest.approx(margin, abs=1e-9) and margin > 0
    assert f"smallest stability margin {margin:.4f} m" in run.stdout


def test_trajectory_ground_gives_each_wheels_traction_and_warns_where_it_slips(tmp_path):
    """The paper robot accelerating straight ahead at 3 m/s^2 (arms still, no object): the wheels
    push M a together, shared so that their moment about the vertical carries the centre of
    mass's offset (a hand computation); each wheel's use is its push over mu times its normal
    force; with mu = 0.5 they slip, and the warning names the sample and the wheel."""
    import pinocchio as pin

    from mobmanip.robot.support import robot_support

    a, mu = 3.0, 0.5
    t = np.linspace(0.0, 1.0, 51)
    path = tmp_path / "push.csv"
    path.write_text(
        "t,platform_x,platform_y,platform_yaw\n" + "".join(f"{s!r},{0.5 * a * s * s!r},0,0\n" for s in t.tolist())
    )
    out = tmp_path / "out"
    run = _cli("trajectory", "planar_dual_arm", str(path), "--object-mass", "0", "--mu", str(mu), "--out", str(out))
    assert run.returncode == 0, run.stderr
    doc = json.loads((out / "analysis.json").read_text())
    robot = mobmanip.load_robot("planar_dual_arm")
    mass = pin.computeTotalMass(robot.model)
    com = pin.centerOfMass(robot.model, robot.model.createData(), robot.neutral())
    support = robot_support(robot)
    wheels = [c for c in support.contacts if c.driven]
    y = np.array([c.point[1] for c in wheels])
    push = np.linalg.solve(np.array([[1.0, 1.0], y]), [mass * a, com[1] * mass * a])
    normals = np.array([[doc["columns"][f"normal_force_{c.name}"][i] for c in support.contacts] for i in range(51)])
    np.testing.assert_allclose(normals.sum(axis=1), mass * 9.81, rtol=1e-9)
    for k, wheel in enumerate(wheels):
        use = abs(push[k]) / (mu * normals[:, k])
        np.testing.assert_allclose(doc["columns"][f"traction_use_{wheel.name}"][1:-1], use[1:-1], rtol=1e-9)
    worst = doc["traction"]["worst"]
    assert doc["traction"]["max_traction_use"] > 1.0 and doc["traction"]["slipping_samples"] == list(range(51))
    assert f"largest traction use {doc['traction']['max_traction_use']:.4f} ({worst['wheel']} at sample" in run.stdout
    assert "warning: a driven wheel slips (traction use above 1) at 51 of 51 samples: first wheel_" in run.stderr
    assert "at sample 0 (t = 0 s" in run.stderr
    header = (out / "analysis.csv").read_text().splitlines()[0].split(",")
    assert "traction_use_wheel_right_joint" in header and "normal_force_caster_0" in header
    bad = _cli("trajectory", "planar_dual_arm", str(path), "--mu", "-1")
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0
    assert bad.stderr.startswith("mobmanip: error: --mu must be a positive friction coefficient")


def test_a_collapsed_grounded_set_is_said_so_not_a_qhull_error(tmp_path):
    """TIAGo++ in a translational task, holding the object level: the minimum-norm policy moves the
    hands' roll and pitch with the object, so the level band (0.01 rad/s^2) is all the motion it
    leaves; the command names that limit (it failed in Qhull when the set was a point). With a band
    of zero width the set is the point at rest."""
    run = _cli("analyze", "tiago_dual", "--posture", "hold", "--object-mass", "2", "--task", "translational",
               "--ground", "--polytope", "--level")  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "Qhull" not in run.stderr and "internal error" not in run.stderr
    assert "object held level" in run.stdout and "stops it (gain per 1 % more): held level: " in run.stdout
    robot = mobmanip.load_robot("tiago_dual")
    P = mobmanip.analyze(
        robot, named_configuration(robot, "hold"), "translational", object_mass=2.0,
        measures=("dynamic_polytope_min_norm",), constraints=(Floor(level=True, level_tolerance=1e-12),),
    ).measures["dynamic_polytope_min_norm"]  # fmt: skip
    assert P.contains(np.zeros(3))
    assert max(P.support(e) + P.support(-e) for e in np.eye(3)) < 1e-9


def test_hold_adds_the_reach_that_holds_per_axis(tmp_path):
    """``--hold 0.02``: every axis entry of the grounded polytope gains the reach whose efforts hold
    20 ms (:func:`mobmanip.motion.hold.held_reach`, checked in tests/test_hold.py and in MuJoCo):
    never beyond the instantaneous reach, and where the instantaneous maximum gives way the
    summary says after how long and what gave way."""
    from mobmanip.motion.hold import replay

    out = tmp_path / "h.json"
    run = _cli("analyze", "planar_dual_arm", "--ground", "--mu", "0.5", "--object-mass", "2", "--hold", "0.02",
               "--json", str(out))  # fmt: skip
    assert run.returncode == 0, run.stderr
    reaches = json.loads(out.read_text())["dynamic_polytope"]["reaches"]
    robot = mobmanip.load_robot("planar_dual_arm")
    q = named_configuration(robot, "home")  # the command's configuration without --q or --posture
    analysis = mobmanip.analyze(robot, q, object_mass=2.0, measures=("dynamic_polytope",), constraints=(Floor(mu=0.5),))
    P = analysis.measures["dynamic_polytope"]
    gave_way = 0
    for k, r in enumerate(reaches):
        held = r["held"]
        assert held["duration"] == 0.02
        assert 0.0 < held["straight_line"] <= r["straight_line"] + 1e-12
        e = np.zeros(P.dim)
        e[k // 2] = 1.0 if k % 2 == 0 else -1.0
        tau = np.array(held["efforts"])  # what the JSON says achieves it: efforts within limits ...
        assert np.all(np.abs(tau) <= robot.effort_limits * (1.0 + 1e-9))
        assert P.contains(held["straight_line"] * e)
        kept = replay(robot, q, tau, object_mass=2.0, floor=Floor(mu=0.5))  # ... that reach it and hold 20 ms
        assert kept.holds and kept.object_acceleration[0] == pytest.approx(held["straight_line"] * e, abs=1e-9)
        # the floor carries the robot: in a planar task not held level the object's weight is not
        # the hands' (the floor constraint's model, which the replay now shares), so not the floor's
        weight = float(pin.computeTotalMass(robot.model)) * 9.81
        normals = held["normal_forces"]
        assert min(normals.values()) > 0.0 and sum(normals.values()) == pytest.approx(weight, rel=1e-6)
        if held["instant_gives_way"] is not None:
            gave_way += 1
            assert held["instant_holds_for"] < 0.02
            tau = np.array(held["instant_efforts"])  # the efforts that hold the maximum longest ...
            again = replay(robot, q, tau, object_mass=2.0, floor=Floor(mu=0.5))
            assert again.held == held["instant_holds_for"]  # ... hold it that long
            assert again.object_acceleration[0] == pytest.approx(held["instant_fraction"] * r["straight_line"] * e)
            assert f"give way after {1e3 * held['instant_holds_for']:.3g} ms" in run.stdout
    assert gave_way >= 1
    assert run.stdout.count("held 20 ms: straight line") == len(reaches)


@pytest.mark.parametrize(
    "extra, message",
    [
        (("--hold", "0.02"), "--hold replays efforts on the floor: it needs --ground with a traction limit"),
        (("--ground", "--no-traction", "--hold", "0.02"), "it needs --ground with a traction limit"),
        (("--ground", "--hold", "-0.01"), "--hold must be a duration in (0, 1] s, got -0.01"),
        (("--ground", "--hold", "5"), "--hold must be a duration in (0, 1] s, got 5.0"),
        (("--ground", "--hold", "nan"), "--hold must be a duration in (0, 1] s, got nan"),
    ],
)
def test_bad_hold_is_one_line(extra, message):
    run = _cli("analyze", "planar_dual_arm", *extra)
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1 and run.stderr.startswith("mobmanip: error: ")
    assert message in run.stderr


def test_an_empty_set_on_the_floor_says_the_floor_is_why():
    """The paper robot holding 10 kg level at home (a planar task carries no weight unless held
    level): its centre of mass (0.223, 0) m is inside the support
    polygon (+-0.25 m) but outside the core of four equally stiff contacts, so the compliant set is
    empty although every effort holds the load still (the ideal set is not). The summary must not
    blame the limits; the warning names the supports the weight would unload."""
    run = _cli("analyze", "planar_dual_arm", "--ground", "--mu", "0.5", "--object-mass", "10", "--polytope", "--level")
    assert run.returncode == 0, run.stderr
    assert "dynamic polytope (coupled): EMPTY (on the floor as modelled; the warning below says why)" in run.stdout
    assert "the limits cannot hold the load still" not in run.stdout
    assert (
        "would unload caster_2, caster_3 (the centre of mass, seen along gravity on the floor at (0.223, 0.000) m"
        in (run.stderr)
    )
    ideal = _cli("analyze", "planar_dual_arm", "--object-mass", "10", "--polytope")
    assert ideal.returncode == 0 and "EMPTY" not in ideal.stdout


def test_a_six_dimensional_grounded_set_beside_an_empty_ellipsoid_is_described_by_its_reaches():
    """TIAGo++ at home on the floor (the command's defaults): its dynamic ellipsoid is empty, so the
    grounded polytope is described along the task axes, and a polytope of six task dimensions has
    no vertices, hence no isotropy. The command stopped there with 'vertices are enumerated up to
    3 task dimensions'; it must print the reaches and say the isotropy is not available. Each
    axis' printed width (its two reaches from the centre) is the independent whole-robot LP's."""
    from floor_reference import build_problem, support

    run = _cli("analyze", "tiago_dual", "--ground")
    assert run.returncode == 0, run.stderr
    line = next(s for s in run.stdout.splitlines() if s.startswith("dynamic polytope (coupled) reach along the task"))
    assert "; isotropy n/a;" in line
    robot = mobmanip.load_robot("tiago_dual")
    analysis = mobmanip.analyze(robot, named_configuration(robot, "home"), "spatial", measures=("kinematic",))
    problem = build_problem(robot, analysis.q, "spatial", analysis.held_object)
    printed = line.split(": ", 1)[1].split("; isotropy")[0].split("; ")
    assert len(printed) == 6
    for e, text in zip(np.eye(6), printed):
        low, high = (float(v) for v in text.split(" .. "))  # "-a .. +b" from the centre
        width = sum(support(problem, d, mode="friction", mu=0.5, springs=True).value for d in (e, -e))
        assert high - low == pytest.approx(width, abs=2e-4)  # printed to 4 decimals


def test_without_friction_the_force_capacity_along_the_floor_is_nothing_and_says_why():
    """mu = 0: at rest the floor's horizontal force is zero, so whatever the object pushes along
    the floor nothing pushes back: the planar force polytope is the point at zero, and the
    warning names the friction, not the minimum-norm policy of a translational task."""
    run = _cli("analyze", "planar_dual_arm", "--ground", "--mu", "0", "--measure", "force_polytope")
    assert run.returncode == 0, run.stderr
    assert "straight line 0, support 0" in run.stdout
    assert (
        "force_polytope on the floor has collapsed (no extent along some direction; its widths along the task "
        "axes 0, 0): with mu = 0 the wheels can neither push nor hold along the floor"
    ) in run.stderr
    assert "minimum-norm" not in run.stderr
