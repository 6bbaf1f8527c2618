"""`mobmanip paper --out DIR`: the files it writes and that their numbers are the analysis'."""

from __future__ import annotations

import json

import numpy as np
import pytest

import mobmanip
from mobmanip.analysis import analyze
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.cli import main


@pytest.fixture(scope="module")
def paper_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    assert main(["paper", "--out", str(out)]) == 0
    return out


#: The paper's Fig. 3, Fig. 4 and its coupled twin, then each figure again with the polytopes.
PAPER_FIGURES = ("fig3_kinematic", "fig4_dynamic", "fig4_dynamic_coupled")
FIGURES = (*PAPER_FIGURES, "fig3_kinematic_polytopes", "fig4_dynamic_polytopes")


def test_writes_json_and_the_figures(paper_run):
    """Every figure as a PNG, with a PDF beside it (the file formats' own signatures)."""
    assert (paper_run / "case_study.json").stat().st_size > 0
    for name in FIGURES:
        assert (paper_run / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (paper_run / f"{name}.pdf").read_bytes()[:5] == b"%PDF-"


def test_json_lists_each_cases_polytopes_beside_its_ellipse(paper_run):
    """Velocity cases carry the kinematic polytope, acceleration cases both dynamic ones; each
    contains its ellipse (the ellipse's support never exceeds the polytope's)."""
    doc = json.loads((paper_run / "case_study.json").read_text())
    for key, names in (
        ("kinematic", ["kinematic_polytope"]),
        ("dynamic", ["dynamic_polytope", "dynamic_polytope_min_norm"]),
    ):
        for case in doc[key]:
            assert [k for k in case if k.endswith("polytope") or k.endswith("min_norm")] == names
            axes, semi = np.array(case["axes"]), np.array(case["semi_axes"])
            for name in names:
                V = np.array(case[name]["vertices"])
                for axis, s in zip(axes, semi):
                    assert np.max(V @ axis) >= s * (1.0 - 1e-9) and np.max(-V @ axis) >= s * (1.0 - 1e-9)


def test_json_layout(paper_run):
    doc = json.loads((paper_run / "case_study.json").read_text())
    assert set(doc["arm_posture"]) == {"q", "manipulability", "reach"}
    # Fig. 3: 3 angles x (3 speeds + locked); Fig. 4: 3 angles x 3 torques x (decoupled, coupled).
    assert len(doc["kinematic"]) == 12
    assert len(doc["dynamic"]) == 18
    speeds = sorted({c["platform_speed_max"] for c in doc["kinematic"]}, key=lambda v: -1 if v is None else v)
    assert speeds == [None, 0.001, 0.5, 1.0]
    assert sorted({c["wheel_torque_max"] for c in doc["dynamic"]}) == [10.0, 50.0, 200.0]
    assert {c["decoupled"] for c in doc["dynamic"]} == {True, False}
    for case in doc["kinematic"] + doc["dynamic"]:
        axes = np.array(case["axes"])
        np.testing.assert_allclose(axes @ axes.T, np.eye(2), atol=1e-12)
        assert case["semi_axes"][0] >= case["semi_axes"][1] > 0


def test_json_numbers_equal_independent_analysis(paper_run):
    """Each row equals an `analyze` call built from the documented set-up, not from the file."""
    doc = json.loads((paper_run / "case_study.json").read_text())
    robot = mobmanip.load_robot("planar_dual_arm")
    posture = optimal_posture(robot)
    np.testing.assert_allclose(doc["arm_posture"]["q"], posture.q, rtol=0, atol=0)
    for case in doc["kinematic"]:
        q = configuration_at(robot, posture, case["object_angle_deg"])
        v = case["platform_speed_max"]
        variant = robot.with_platform("fixed") if v is None else robot.with_wheel_limits(velocity=v / 0.075)
        expected = analyze(variant, q, "planar").kinematic
        np.testing.assert_allclose(case["semi_axes"], expected.semi_axes, rtol=1e-12)
    for case in doc["dynamic"]:
        q = configuration_at(robot, posture, case["object_angle_deg"])
        variant = robot.with_wheel_limits(effort=case["wheel_torque_max"])
        expected = analyze(variant, q, "planar", decoupled=case["decoupled"]).dynamic
        np.testing.assert_allclose(case["semi_axes"], expected.semi_axes, rtol=1e-12)


def test_posture_reach_is_the_distance_to_the_object(paper_run):
    """The reported reach is where both end effectors meet the object (|p_ee - P_o|)."""
    doc = json.loads((paper_run / "case_study.json").read_text())
    robot = mobmanip.load_robot("planar_dual_arm")
    posture = optimal_posture(robot)
    for angle in (0.0, 45.0, 90.0):
        result = analyze(robot, configuration_at(robot, posture, angle), "planar")
        alpha = np.radians(angle)
        for position in result.end_effector_positions:
            np.testing.assert_allclose(
                position[:2], doc["arm_posture"]["reach"] * np.array([np.cos(alpha), np.sin(alpha)]), atol=1e-12
            )


def test_unwritable_output_is_one_line_exit_2(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["paper", "--out", str(blocker / "sub")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mobmanip: error:") and "sub" in err[0]


def test_case_study_on_another_platform_is_one_line_exit_2(tmp_path, capsys):
    """The arms' posture is any platform's (``carry`` starts the omnidirectional base from it), but
    the case study varies the wheels' limits: on the holonomic base it is one line, not an
    internal error, and nothing is written."""
    assert main(["paper", "--robot", "planar_dual_arm_omni", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "mobmanip: error: the case study needs a differential drive with two arms; 'planar_dual_arm_omni' does not fit"
    ]
    assert not (tmp_path / "out").exists()
