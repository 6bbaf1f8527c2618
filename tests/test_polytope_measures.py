"""The capacity polytopes as registered measures: analyze's JSON, the command line's summary and
the sweeps, each checked against independent linear programs over the joint box
(``polytope_util``) or against single analyses.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from scipy.optimize import linprog

import mobmanip
from conftest import random_configurations
from mobmanip.cli import main
from mobmanip.measures import POLYTOPE_KINDS, default_measures, get_measure, measure_names
from mobmanip.sweep import SweepGrid, SweepSpec, run_sweep
from polytope_util import dynamic_lp, kinematic_lp, min_norm_lp, terms

POLYTOPES = tuple(POLYTOPE_KINDS)


def _unit(rng, n: int, m: int) -> np.ndarray:
    u = rng.normal(size=(n, m))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def _reference_lps(t: dict) -> dict:
    """Independent support programs over the joint box, by measure name."""
    dyn = (t["J_u"], t["W"], t["P"], t["Q"], t["xi"], t["M_o"], t["g_o"], t["effort_limits"])
    return {
        "kinematic_polytope": kinematic_lp(t["J_u"], t["W"], t["velocity_limits"]),
        "dynamic_polytope": dynamic_lp(*dyn),
        "dynamic_polytope_min_norm": min_norm_lp(*dyn),
    }


def _halfspace_support(A, b, d) -> float:
    """max d . a subject to A a <= b (the JSON's halfspaces), by HiGHS through scipy."""
    result = linprog(-np.asarray(d), A_ub=A, b_ub=b, bounds=[(None, None)] * len(d), method="highs")
    assert result.status == 0, result.message
    return -result.fun


def test_polytopes_are_registered_and_not_default():
    assert measure_names()[:2] == ("kinematic", "dynamic")
    assert default_measures() == ("kinematic", "dynamic")
    for name in POLYTOPES:
        measure = get_measure(name)
        assert measure.json_key == name and measure.set_kind == "polytope" and measure.sweepable
        assert measure.scene_path == f"polytopes/{name}"
    assert get_measure("kinematic_polytope").quantity.name == "velocity"
    assert {get_measure(n).quantity.name for n in POLYTOPES[1:]} == {"acceleration"}


@pytest.mark.parametrize(
    "robot_name, task, extra",
    [
        ("planar_dual_arm", "planar", []),
        ("planar_dual_arm", "planar", ["--platform", "fixed", "--decoupled"]),
        ("tiago_dual", "translational", []),
    ],
)
def test_json_polytopes_have_the_supports_of_the_joint_box(robot_name, task, extra, tmp_path, capsys, rng):
    """The JSON's halfspaces and vertices describe the set the joint box defines: their supports
    in random directions equal independent programs over (x or tau, internal forces, ...)."""
    robot = mobmanip.load_robot(robot_name)
    q = random_configurations(robot, rng, 1)[0]
    (tmp_path / "q.json").write_text(json.dumps(robot.configuration_dict(q)))
    out = tmp_path / "a.json"
    argv = ["analyze", robot_name, "--task", task, "--q", str(tmp_path / "q.json"), "--polytope", *extra]
    assert main([*argv, "--json", str(out)]) == 0
    text = out.read_text()
    document = json.loads(text)
    assert "NaN" not in text and "Infinity" not in text
    assert list(document)[-5:] == ["kinematic_ellipsoid", "dynamic_ellipsoid", *POLYTOPES]
    if "--platform" in extra:
        robot = robot.with_platform("fixed")
    an, t = terms(robot, q, task)
    if "--decoupled" in extra:
        t["P"] = an.reduced_inertia_decoupled
    references = _reference_lps(t)
    m = len(document["task_axes"])
    for name in POLYTOPES:
        entry = document[name]
        assert entry["kind"] == "polytope" and entry["empty"] is False
        A, b = np.array(entry["halfspaces"]["A"]), np.array(entry["halfspaces"]["b"])
        V = np.array(entry["vertices"])
        assert A.shape[1] == m and V.shape[1] == m
        for d in _unit(rng, 12, m):
            expected = references[name](d)
            scale = max(abs(expected), 1.0)
            assert _halfspace_support(A, b, d) == pytest.approx(expected, abs=1e-7 * scale)
            assert float(np.max(V @ d)) == pytest.approx(expected, abs=1e-7 * scale)
    capsys.readouterr()


def test_summary_gives_the_reach_along_the_ellipsoid_axes(tmp_path, capsys, rng):
    """Each axis line: the ellipsoid's semi-axis, the polytope's support along +-axis from the
    ellipsoid's centre (an independent program), their ratio."""
    robot = mobmanip.load_robot("planar_dual_arm")
    q = random_configurations(robot, rng, 1)[0]
    (tmp_path / "q.json").write_text(json.dumps(robot.configuration_dict(q)))
    assert main(["analyze", "planar_dual_arm", "--q", str(tmp_path / "q.json"), "--polytope"]) == 0
    text = capsys.readouterr().out
    assert not re.search(r"\bnan\b|\binf\b", text, re.IGNORECASE)
    an, t = terms(robot, q, "planar")
    references = _reference_lps(t)
    for name in POLYTOPES:
        ellipsoid = an.kinematic if name == "kinematic_polytope" else an.dynamic
        label = get_measure(name).label
        block = text[text.index(label + (" (coupled)" if name != "kinematic_polytope" else "")) :]
        lines = block.splitlines()[1:3]
        for line, axis, s in zip(lines, ellipsoid.axes, ellipsoid.semi_axes):
            numbers = re.search(r"ellipsoid ([\d.]+), polytope \+([\d.]+) / -([\d.]+), ratio ([\d.]+) / ([\d.]+)", line)
            assert numbers, line
            ell, plus, minus, r_plus, r_minus = (float(x) for x in numbers.groups())
            c = float(axis @ ellipsoid.center)
            expected_plus, expected_minus = references[name](axis) - c, references[name](-axis) + c
            assert ell == pytest.approx(s, abs=6e-5)
            assert plus == pytest.approx(expected_plus, abs=6e-5 + 1e-7 * expected_plus)
            assert minus == pytest.approx(expected_minus, abs=6e-5 + 1e-7 * expected_minus)
            assert r_plus == pytest.approx(expected_plus / s, abs=6e-4)
            assert r_minus == pytest.approx(expected_minus / s, abs=6e-4)
            # the ellipsoid is inside the polytope (policy and kinematic: inside sqrt(n) times it)
            assert min(r_plus, r_minus) >= 1.0 - 1e-3


def test_six_dimensional_volume_is_n_a_with_its_reason(tmp_path, capsys, tiago_q):
    """TIAGo++'s 6-D kinematic section has thousands of facets: its volume is 'n/a' with the
    reason, JSON null, and nothing printed or written is NaN or infinite."""
    q_path, _ = tiago_q
    out = tmp_path / "a.json"
    argv = ["analyze", "tiago_dual", "--task", "spatial", "--q", str(q_path), "--polytope", "--json", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert not re.search(r"\bnan\b|\binf\b", text, re.IGNORECASE)
    kinematic = text[text.index("kinematic polytope (m/s, rad/s)") :].split("dynamic polytope")[0]
    assert "volume n/a (this 6-D polytope has" in kinematic and "impractical" in kinematic
    raw = out.read_text()
    assert "NaN" not in raw and "Infinity" not in raw
    entry = json.loads(raw)["kinematic_polytope"]
    assert entry["volume"] is None and entry["isotropy"] is None
    assert len(entry["halfspaces"]["b"]) > 400 and "vertices" not in entry


@pytest.fixture(scope="module")
def tiago_q(tmp_path_factory):
    robot = mobmanip.load_robot("tiago_dual")
    q = random_configurations(robot, np.random.default_rng(3), 1)[0]
    path = tmp_path_factory.mktemp("tiago") / "q.json"
    path.write_text(json.dumps(robot.configuration_dict(q)))
    return path, q


def test_overload_is_flagged_empty_never_nan(tmp_path, capsys, tiago_q):
    """A 200 kg object: the paper's policy cannot hold it (empty), the exact set is a fall (it
    does not contain zero acceleration); printed and written without NaN."""
    out = tmp_path / "a.json"
    q_path, _ = tiago_q
    argv = [
        "analyze",
        "tiago_dual",
        "--task",
        "translational",
        "--q",
        str(q_path),
        "--object-mass",
        "200",
        "--polytope",
    ]
    assert main([*argv, "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "dynamic polytope, minimum-norm policy (coupled): EMPTY" in text
    assert not re.search(r"\bnan\b|\binf\b", text, re.IGNORECASE)
    raw = out.read_text()
    assert "NaN" not in raw and "Infinity" not in raw
    document = json.loads(raw)
    policy, exact = document["dynamic_polytope_min_norm"], document["dynamic_polytope"]
    assert policy["empty"] is True and policy["vertices"] == []
    assert exact["empty"] is False
    b = np.array(exact["halfspaces"]["b"])
    assert np.min(b) < 0.0  # zero acceleration violates a facet (A 0 <= b fails): the load falls
    assert document["dynamic_ellipsoid"]["empty"] is True  # policy polytope empty => ellipsoid empty


# --------------------------------------------------------------------------- sweeps


def test_sweep_indices_equal_single_analyses(rng):
    """Volume, isotropy, capacity along the radial direction and widths of each polytope, at
    every reachable grid point and limit scale, equal those of analyze at that configuration."""
    grid = SweepGrid(
        angle_deg=[0.0, 75.0],
        distance=[1.0, 9.0],
        heading_deg=[0.0, 30.0],
        wheel_velocity_scale=[0.5, 1.0],
        wheel_effort_scale=[1.0, 0.2],
    )
    spec = SweepSpec("planar_dual_arm", measures=POLYTOPES, decoupled=True)
    result = run_sweep(spec, grid, workers=1)
    assert [m.name for m in result.measures] == list(POLYTOPES)
    assert result.reachable[:, 0].all() and not result.reachable[:, 1].any()
    robot = mobmanip.load_robot("planar_dual_arm")
    names, joints = result.joint_positions()
    checked = 0
    for ia, alpha in enumerate(grid.angle_deg):
        for ih, heading in enumerate(grid.heading_deg):
            q = robot.configuration((0.0, 0.0, math.radians(heading)), dict(zip(names, joints[ia, 0])))
            world = math.radians(alpha + heading)
            d = np.array([math.cos(world), math.sin(world)])
            for iv, vs in enumerate(grid.wheel_velocity_scale):
                for ie, es in enumerate(grid.wheel_effort_scale):
                    variant = robot.with_wheel_limits(
                        velocity=vs * robot.velocity_limits[0], effort=es * robot.effort_limits[0]
                    )
                    an = mobmanip.analyze(variant, q, "planar", decoupled=True, measures=POLYTOPES, method="exact")
                    at = (ia, 0, ih, iv, ie)
                    for name in POLYTOPES:
                        single = an.measure(name)
                        size = single.circumradius
                        assert result.index(f"{name}.volume")[at] == pytest.approx(single.volume, rel=1e-7)
                        assert result.index(f"{name}.isotropy")[at] == pytest.approx(single.isotropy, rel=1e-7)
                        assert result.index(f"{name}.capacity")[at] == pytest.approx(single.support(d), abs=1e-9 * size)
                        for k, e in enumerate(np.eye(2), start=1):
                            width = single.support(e) + single.support(-e)
                            assert result.index(f"{name}.width_{k}")[at] == pytest.approx(width, abs=1e-9 * size)
                        assert not result.indices[f"{name}_empty"][at]
                        checked += 1
    assert checked == 2 * 2 * 2 * 2 * 3
    assert np.isnan(result.index("kinematic_polytope.volume")[:, 1]).all()  # out of reach
    # velocity limits act on the kinematic set only, effort limits on the dynamic ones
    kin, dyn = result.index("kinematic_polytope.volume"), result.index("dynamic_polytope.volume")
    assert not np.allclose(kin[:, 0, :, 0, 0], kin[:, 0, :, 1, 0])
    np.testing.assert_array_equal(kin[:, 0, :, :, 0], kin[:, 0, :, :, 1])
    assert not np.allclose(dyn[:, 0, :, 0, 0], dyn[:, 0, :, 0, 1])
    np.testing.assert_array_equal(dyn[:, 0, :, 0, :], dyn[:, 0, :, 1, :])


# --------------------------------------------------------------------------- the paper's figures


def test_paper_figures_draw_the_sets_of_the_joint_box(tmp_path, rng):
    """The extra Fig. 3 and Fig. 4 draw, for each case, polygons whose vertices (unscaled, from
    the task point) have the supports of independent programs over the joint box of that case's
    robot (wheel limits varied as the paper), and the case's ellipse beside them."""
    from mobmanip.casestudy import run_case_study
    from mobmanip.commands.paper import FIGURES, write_figures

    robot = mobmanip.load_robot("planar_dual_arm")
    study = run_case_study(robot, angles_deg=(45.0,), platform_speeds=(0.5,), wheel_torques=(50.0,), measures=POLYTOPES)
    drawn = write_figures(study, tmp_path)
    for name in FIGURES:
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    radius = robot.platform.radius

    def check(record, lp):
        assert record["kind"] == "polytope"
        local = (record["points"] - record["point"]) / record["scale"]
        for d in _unit(rng, 16, 2):
            expected = lp(d)
            assert float(np.max(local @ d)) == pytest.approx(expected, abs=1e-9 * max(abs(expected), 1.0))

    records = drawn["fig3_kinematic_polytopes.png"]
    assert len(records) == 2 * len(study.kinematic)
    for case, (poly, ell) in zip(study.kinematic, zip(records[::2], records[1::2])):
        speed = case.platform_speed_max
        variant = robot.with_platform("fixed") if speed is None else robot.with_wheel_limits(velocity=speed / radius)
        _, t = terms(variant, case.analysis.q, "planar")
        check(poly, kinematic_lp(t["J_u"], t["W"], t["velocity_limits"]))
        assert ell["kind"] == "ellipsoid" and ell["label"].startswith("_")
    decoupled = [c for c in study.dynamic if c.decoupled]
    records = drawn["fig4_dynamic_polytopes.png"]
    assert len(records) == 3 * len(decoupled)
    for k, case in enumerate(decoupled):
        exact, policy, ell = records[3 * k : 3 * k + 3]
        variant = robot.with_wheel_limits(effort=case.wheel_torque_max)
        an, t = terms(variant, case.analysis.q, "planar")
        t["P"] = an.reduced_inertia_decoupled
        lps = _reference_lps(t)
        check(exact, lps["dynamic_polytope"])
        check(policy, lps["dynamic_polytope_min_norm"])
        assert ell["kind"] == "ellipsoid"
    # the paper's own figures draw ellipses only
    assert {r["kind"] for r in drawn["fig3_kinematic.png"] + drawn["fig4_dynamic.png"]} == {"ellipsoid"}


def test_polytope_flag_adds_the_registered_polytopes_on_analyze_view_and_sweep():
    """The polytopes of the default measures' quantities (motion); a polytope of another quantity
    (the force polytope) comes when a measure of its quantity is asked for."""
    from mobmanip.cli import build_parser
    from mobmanip.commands.common import requested_measures

    motion = {get_measure(name).quantity for name in default_measures()}
    polytopes = tuple(
        m.name for m in map(get_measure, measure_names()) if m.set_kind == "polytope" and m.quantity in motion
    )
    assert set(polytopes) == set(POLYTOPES)
    parser = build_parser()
    for command in ("analyze", "view", "sweep"):
        args = parser.parse_args([command, "planar_dual_arm", "--polytope"])
        assert requested_measures(args) == default_measures() + polytopes
        args = parser.parse_args([command, "planar_dual_arm", "--measure", "kinematic", "--polytope"])
        assert requested_measures(args) == ("kinematic", *polytopes)
        assert requested_measures(parser.parse_args([command, "planar_dual_arm"])) is None
