"""``mobmanip team`` and the heading sweep: the JSON against the stacked terms and an
independent LP, the sweep's postures against forward kinematics, and the errors."""

from __future__ import annotations

import json
import math
import time
import tomllib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from mobmanip import load_robot
from mobmanip.cli import main
from mobmanip.team import load_team
from mobmanip.team.analysis import analyze_team, ray_radius
from mobmanip.team.sweep import sweep_heading
from polytope_util import kinematic_lp

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
BEAM = EXAMPLES / "beam_team.toml"


@pytest.fixture(scope="module")
def beam_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("team")
    code = main(["team", str(BEAM), "--polytope", "--json", str(out / "beam.json"), "--plot", str(out / "beam.png")])
    return code, json.loads((out / "beam.json").read_text()), out


def test_the_json_holds_the_stacked_terms_and_the_exact_set(beam_run):
    code, doc, out = beam_run
    assert code == 0
    J = np.array(doc["unified_jacobian"])
    W = np.array(doc["grasp_matrix"])
    limits = np.array(doc["velocity_limits"])
    # block structure: each robot's 8 reduced velocities move only its own two hands
    assert J.shape == (12, 16)
    assert np.all(J[:6, 8:] == 0) and np.all(J[6:, :8] == 0)
    # the kinematic polytope's support against an LP over both robots' joint boxes
    lp = kinematic_lp(J, W, limits)
    rng = np.random.default_rng(7)
    polytope = doc["kinematic_polytope"]
    vertices = np.array(polytope["vertices"])
    for d in rng.normal(size=(50, 3)):
        assert np.max(vertices @ d) == pytest.approx(lp(d), rel=1e-7)
    # velocity shares sum to one; the load sharing holds the beam (no gravity in the plane)
    for measure in ("kinematic", "kinematic_polytope"):
        for shares in doc["limiting_robot"][measure].values():
            assert sum(shares.values()) == pytest.approx(1.0, abs=1e-8)
    sharing = doc["load_sharing"]
    assert not sharing["empty"] and sharing["worst_normalised_torque"] == pytest.approx(0.0, abs=1e-9)
    assert (out / "beam.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_load_sharing_of_a_lifted_box_is_the_minimax_over_internal_forces(tmp_path):
    """The beam is held in the plane (no gravity, every choice of internal force gives zero
    torque), so its check above cannot see the load-sharing objective. The 10 kg box in the
    spatial task can: the JSON's worst normalised torque equals an independent LP over the
    JSON's own stacked terms (min t with |Z Q^-1 (-bias + J^T h)| <= t, W h = g_o), and the
    hands' wrenches it reports reach that optimum and hold the box."""
    import scipy.optimize

    out = tmp_path / "box.json"
    assert main(["team", str(EXAMPLES / "two_arms_box.toml"), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    J, W = np.array(doc["unified_jacobian"]), np.array(doc["grasp_matrix"])
    Q, bias = np.array(doc["input_matrix"]), np.array(doc["bias"])
    Z = 1.0 / np.array(doc["effort_limits"])
    g_o = np.array([0.0, 0.0, 9.81 * 10.0, 0.0, 0.0, 0.0])
    A = Z[:, None] * np.linalg.solve(Q, J.T)
    c = Z * np.linalg.solve(Q, -bias)
    n = W.shape[1]
    cost = np.r_[np.zeros(n), 1.0]
    ones = np.ones((A.shape[0], 1))
    lp = scipy.optimize.linprog(
        cost,
        A_ub=np.block([[A, -ones], [-A, -ones]]),
        b_ub=np.r_[-c, c],
        A_eq=np.hstack([W, np.zeros((W.shape[0], 1))]),
        b_eq=g_o,
        bounds=[(None, None)] * (n + 1),
        method="highs",
    )
    assert lp.status == 0
    sharing = doc["load_sharing"]
    assert lp.fun > 0.05  # the load really costs torque: the objective matters here
    assert sharing["worst_normalised_torque"] == pytest.approx(lp.fun, rel=1e-6)
    h = np.concatenate([np.ravel(sharing["hand_wrenches"][hand]) for hand in doc["object"]["hands"]])
    np.testing.assert_allclose(W @ h, g_o, atol=1e-6 * np.abs(g_o).max())
    assert np.max(np.abs(A @ h + c)) == pytest.approx(lp.fun, rel=1e-6)


def test_a_bad_description_is_one_error_line(tmp_path, capsys):
    text = BEAM.read_text().replace('name = "north"', 'name = "south"')
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    assert main(["team", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'south'" in err[0] and "already used" in err[0]


def _rot_z(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_the_heading_sweep_turns_the_grasps_and_flags_what_cannot_be_reached():
    data = tomllib.loads(BEAM.read_text())
    offsets = [-20.0, 0.0, 25.0, 90.0]
    sweep = sweep_heading(data, offsets, base_dir=EXAMPLES, measures=("kinematic",))
    assert sweep.reachable.tolist() == [True, True, True, False]
    # at its own heading the sweep is the description's analysis

    direct = analyze_team(load_team(BEAM), ("kinematic",)).measure("kinematic")
    np.testing.assert_allclose(
        sweep.points[1].reach["kinematic"], [ray_radius(direct, e) for e in np.eye(3)], rtol=1e-9
    )
    # at every reachable heading each hand is at its grasp point, turned with the beam (FK here)
    center = np.array(data["object"]["position"])
    for point in sweep.points[:3]:
        R = _rot_z(math.radians(data["object"]["yaw_deg"] + point.offset_deg))
        for entry in data["robots"]:
            robot = load_robot(entry["robot"])
            q = robot.configuration((*entry["position"], math.radians(entry["yaw_deg"])), point.joints[entry["name"]])
            pin.framesForwardKinematics(robot.model, robot.data, q)
            for grasp in entry["grasps"]:
                arm = next(a for a in robot.arms if a.name == grasp["arm"])
                hand = robot.data.oMf[arm.frame_id].translation
                target = center + R @ np.array(grasp["point"])
                assert np.linalg.norm((hand - target)[:2]) < 1e-6
    assert sweep.to_dict()["points"][3] == {
        "offset_deg": 90.0,
        "reachable": False,
        "reach": {},
        "limiting_robot": {},
        "volume": {},
        "worst_normalised_torque": None,
        "overload": None,
        "joints": {},
    }


def test_the_sweep_option_writes_its_points(tmp_path):
    out = tmp_path / "s.json"
    assert main(["team", str(BEAM), "--json", str(out), "--sweep-heading", "0,10"]) == 0
    doc = json.loads(out.read_text())
    points = doc["heading_sweep"]["points"]
    assert [p["offset_deg"] for p in points] == [0.0, 10.0] and all(p["reachable"] for p in points)


def test_dask_without_a_heading_sweep_is_a_usage_error(tmp_path, capsys):
    out = tmp_path / "t.json"
    assert main(["team", str(BEAM), "--json", str(out), "--dask", "local:2"]) == 2
    err = capsys.readouterr().err
    assert err == "mobmanip: error: --dask runs a heading sweep on a cluster: give --sweep-heading GRID too\n"
    assert not out.exists()


def test_with_dask_the_work_bound_is_checked_before_connecting(capsys):
    # a scheduler nobody listens on: the bound must refuse first, at once, without waiting for it
    started = time.monotonic()
    argv = ["team", str(BEAM), "--sweep-heading=0:10:1000000", "--dask", "tcp://127.0.0.1:9"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "robot-headings" in err and "Dask" not in err
    assert time.monotonic() - started < 2.0
