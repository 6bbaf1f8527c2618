"""``mobmanip analyze``: the JSON it writes, checked against independent computations, and its errors."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest

from conftest import PAPER_URDF, WHEEL_RADIUS, set_joints, write_variant
from mobmanip.cli import main
from mobmanip.terms.dynamics import unified_jacobian

# A configuration with some joints named and the others left out (they must come back as 0).
PLATFORM = [0.7, -1.2, 2.5]
JOINTS = {
    "arm_right_1_joint": 0.4,
    "arm_right_2_joint": -1.1,
    "arm_right_3_joint": 2.0,
    "arm_left_2_joint": 0.9,
    "wheel_left_joint": -2.2,
}
TASK_ROWS = {"planar": [0, 1], "spatial": [0, 1, 2, 3, 4, 5]}
# Every number in the document is a float64 printed with repr(): it reads back exactly; the independent
# computations differ from the code's only by round-off in the order of operations (~1e-15 relative).
TOL = 1e-12


def write_q(tmp_path, text, name="Q.json"):
    path = tmp_path / name
    path.write_text(text)
    return path


def configuration_by_hand(robot, platform, joints):
    """q from a platform pose and joint angles, without going through mobmanip."""
    model = robot.model
    q = pin.neutral(model)
    x, y, yaw = platform
    q[:4] = (x, y, math.cos(yaw), math.sin(yaw))
    return set_joints(model, q, joints)


def jacobian_by_hand(robot, q, task):
    data = robot.model.createData()
    rows = TASK_ROWS[task]
    J = np.vstack(
        [
            pin.computeFrameJacobian(robot.model, data, q, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)[rows]
            for arm in robot.arms
        ]
    )
    return J @ robot.S


def run_analyze(tmp_path, capsys, *extra):
    q_path = write_q(tmp_path, json.dumps({"platform": PLATFORM, "joints": JOINTS}))
    out = tmp_path / "OUT.json"
    code = main(["analyze", "planar_dual_arm", "--q", str(q_path), "--json", str(out), *extra])
    captured = capsys.readouterr()
    return code, captured, out


@pytest.mark.parametrize("task", ["planar", "spatial"])
def test_analyze_json_matches_independent_computation(robot, tmp_path, capsys, task):
    code, captured, out = run_analyze(tmp_path, capsys, "--task", task)
    assert code == 0
    assert captured.err == ""
    doc = json.loads(out.read_text())
    assert doc["robot"] == "planar_dual_arm" and doc["task"] == task

    q = configuration_by_hand(robot, PLATFORM, JOINTS)
    J_u = np.array(doc["unified_jacobian"])
    assert J_u.shape == (len(TASK_ROWS[task]) * 2, robot.nx)
    np.testing.assert_allclose(J_u, jacobian_by_hand(robot, q, task), rtol=0, atol=TOL)
    np.testing.assert_allclose(J_u, unified_jacobian(robot, q, task), rtol=0, atol=TOL)

    P = np.array(doc["reduced_inertia"])
    M = pin.crba(robot.model, robot.model.createData(), q)
    M = np.triu(M) + np.triu(M, 1).T
    np.testing.assert_allclose(P, robot.S.T @ M @ robot.S, rtol=0, atol=1e-10)
    np.testing.assert_allclose(P, P.T, rtol=0, atol=1e-12)
    assert np.linalg.eigvalsh(P).min() > 1e-3


def test_analyze_json_configuration_names_and_limits(robot, tmp_path, capsys):
    code, _, out = run_analyze(tmp_path, capsys)
    assert code == 0
    doc = json.loads(out.read_text())

    q = doc["q"]
    assert set(q) == {"platform", "joints"}
    np.testing.assert_allclose(q["platform"], PLATFORM, rtol=0, atol=TOL)
    assert set(q["joints"]) == {"wheel_right_joint", "wheel_left_joint"} | {
        f"arm_{s}_{k}_joint" for s in ("right", "left") for k in (1, 2, 3)
    }
    for name, value in q["joints"].items():
        assert value == pytest.approx(JOINTS.get(name, 0.0), abs=TOL), name

    names = doc["reduced_velocity_names"]
    assert names == ["wheel_right_joint", "wheel_left_joint"] + [
        f"arm_{s}_{k}_joint" for s in ("right", "left") for k in (1, 2, 3)
    ]
    # Tables 1 and 2, one entry per reduced velocity in that order.
    np.testing.assert_allclose(doc["velocity_limits"], [1 / WHEEL_RADIUS] * 2 + [3.14] * 6, rtol=1e-15)
    assert doc["effort_limits"] == [200.0, 200.0, 200.0, 100.0, 30.0, 200.0, 100.0, 30.0]


def test_analyze_json_file_is_complete_and_readable(tmp_path, capsys):
    code, captured, out = run_analyze(tmp_path, capsys)
    assert code == 0
    assert str(out) in captured.out
    # Written atomically: no temporary file left beside it, and the usual permissions (not mkstemp's 0600).
    assert sorted(p.name for p in tmp_path.iterdir()) == ["OUT.json", "Q.json"]
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask


def test_analyze_as_a_subprocess(tmp_path, capsys):
    """``python -m mobmanip`` writes the same document as the in-process call."""
    code, _, in_process = run_analyze(tmp_path, capsys)
    assert code == 0
    out = tmp_path / "sub.json"
    result = subprocess.run(
        [sys.executable, "-m", "mobmanip", "analyze", "planar_dual_arm", "--q", str(tmp_path / "Q.json")]
        + ["--json", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert json.loads(out.read_text()) == json.loads(in_process.read_text())


# ----- bad input -----


def assert_one_line_error(code, err, *needles):
    assert code == 2
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("mobmanip: error: ")
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


BAD_Q = {
    "unknown-joint": ('{"joints": {"arm_rihgt_1_joint": 0.3}}', ["arm_rihgt_1_joint"]),
    "nan-joint": ('{"joints": {"arm_right_1_joint": NaN}}', ["NaN"]),
    "nan-platform": ('{"platform": [0.0, NaN, 0.0]}', ["NaN"]),
    "infinity": ('{"platform": [0.0, 1.0, -Infinity]}', ["Infinity"]),
    "malformed": ('{"platform": [0.0, 1.0', ["Q.json"]),
    "two-entry-platform": ('{"platform": [0.5, 1.5]}', ["[0.5, 1.5]"]),
    "string-joint": ('{"joints": {"arm_left_1_joint": "fast"}}', ["arm_left_1_joint", "fast"]),
    "huge-integer": ('{"platform": [1' + "0" * 400 + ", 0, 0]}", ["inf"]),
    "not-an-object": ("[1, 2, 3]", ["list"]),
}


@pytest.mark.parametrize("case", list(BAD_Q))
def test_bad_configuration_file(tmp_path, capsys, case):
    text, needles = BAD_Q[case]
    q_path = write_q(tmp_path, text)
    out = tmp_path / "OUT.json"
    code = main(["analyze", "planar_dual_arm", "--q", str(q_path), "--json", str(out)])
    captured = capsys.readouterr()
    assert_one_line_error(code, captured.err, *needles)
    assert captured.out == ""
    assert not out.exists()


def test_configuration_file_that_is_not_utf8(tmp_path, capsys):
    q_path = tmp_path / "Q.json"
    q_path.write_bytes(b'{"joints": {"arm_right_1_joint": 0.1}}\xff\xfe')
    code = main(["analyze", "planar_dual_arm", "--q", str(q_path)])
    assert_one_line_error(code, capsys.readouterr().err, str(q_path))


def test_missing_configuration_file(tmp_path, capsys):
    code = main(["analyze", "planar_dual_arm", "--q", str(tmp_path / "absent.json")])
    assert_one_line_error(code, capsys.readouterr().err, "absent.json")


def test_unknown_robot(tmp_path, capsys):
    out = tmp_path / "OUT.json"
    code = main(["analyze", "no_such_robot", "--json", str(out)])
    captured = capsys.readouterr()
    assert_one_line_error(code, captured.err, "no_such_robot")
    assert captured.out == ""
    assert not out.exists()


@pytest.mark.parametrize("target", ["missing-directory", "is-a-directory"])
def test_unwritable_json_path(tmp_path, capsys, target):
    out = tmp_path / "nowhere" / "OUT.json" if target == "missing-directory" else tmp_path / "existing"
    if target == "is-a-directory":
        out.mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    code = main(["analyze", "planar_dual_arm", "--json", str(out)])
    assert_one_line_error(code, capsys.readouterr().err, str(out))
    # Nothing is left behind: no temporary file beside the target.
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_bad_input_in_a_subprocess_has_no_traceback(tmp_path):
    q_path = write_q(tmp_path, '{"platform": [0.0, 0.0, NaN]}')
    result = subprocess.run(
        [sys.executable, "-m", "mobmanip", "analyze", "planar_dual_arm", "--q", str(q_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert_one_line_error(result.returncode, result.stderr, "NaN")
    assert result.stdout == ""


def test_malformed_urdf_gives_one_error_line(tmp_path):
    # A real process: under pytest the log records would go to pytest's handler, not to stderr.
    text = PAPER_URDF.read_text()
    spec = write_variant(tmp_path, text[: text.index('name="arm_left_2_link"') + 12])
    result = subprocess.run(
        [sys.executable, "-m", "mobmanip", "analyze", str(spec)], capture_output=True, text=True, timeout=120
    )
    assert_one_line_error(result.returncode, result.stderr, str(tmp_path / "variant.urdf"))
