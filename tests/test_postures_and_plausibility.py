"""Named postures (--posture), the hands-apart warning, placeholder limits, weight, and the
unit-consistent per-block indices of mixed (linear and angular) tasks."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from conftest import PAPER_SPEC, write_variant
from mobmanip.analysis.plausibility import block_indices, limit_warnings, weight_warnings
from mobmanip.cli import main
from mobmanip.errors import SpecError, UnknownPostureError
from mobmanip.postures.named import named_configuration, posture_names
from mobmanip.robot.spec import load_spec
from mobmanip.terms.grasp import HeldObject


def _run(argv, capsys):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


# ----- named postures -----


def _paper_variant(tmp_path, extra: str):
    urdf = PAPER_SPEC.parent / "planar_dual_arm.urdf"
    spec = PAPER_SPEC.read_text().replace('urdf = "planar_dual_arm.urdf"', f'urdf = "{urdf}"') + extra
    path = tmp_path / "variant.toml"
    path.write_text(spec)
    return path


def test_named_postures_set_their_joints(tmp_path):
    path = _paper_variant(tmp_path, "\n[postures.reach]\narm_right_2_joint = 0.25\narm_left_3_joint = -1.5\n")
    robot = mobmanip.load_robot(load_spec(path))
    assert posture_names(robot.spec) == ("home", "reach")
    q = named_configuration(robot, "reach", (1.0, -2.0, 0.5))
    joints = robot.configuration_dict(q)["joints"]
    assert joints["arm_right_2_joint"] == 0.25 and joints["arm_left_3_joint"] == -1.5
    assert joints["arm_right_1_joint"] == 0.0  # not named: at home
    np.testing.assert_allclose(robot.configuration_dict(q)["platform"], [1.0, -2.0, 0.5], atol=1e-15)
    np.testing.assert_array_equal(named_configuration(robot, "home"), robot.neutral())
    with pytest.raises(UnknownPostureError, match="'stretched'.*home, reach"):
        named_configuration(robot, "stretched")


def test_hold_is_the_spec_hold(tiago):
    assert posture_names(tiago.spec)[:2] == ("home", "hold")
    np.testing.assert_array_equal(named_configuration(tiago, "hold"), tiago.hold_configuration())


@pytest.mark.parametrize(
    "extra, message",
    [
        ("\n[postures.home]\narm_right_2_joint = 0.1\n", "reserved"),
        ("\n[postures.up]\nwheel_right_joint = 0.1\n", "not an arm or torso joint"),
        ('\n[postures.up]\narm_right_2_joint = "x"\n', "must be a finite number"),
        ("\n[postures]\nup = 3\n", "must be a table"),
    ],
)
def test_bad_postures_are_refused(tmp_path, extra, message):
    with pytest.raises(SpecError, match=message):
        load_spec(_paper_variant(tmp_path, extra))


def test_bad_grasp_offsets_are_refused(tmp_path):
    text = PAPER_SPEC.read_text()
    assert "[object]\nmass = 2.0\n" in text
    for rows in ("[[0, 0, 0]]", "[[0, 0], [0, 0]]", '[[0, 0, "a"], [0, 0, 0]]'):
        path = write_variant(
            tmp_path, (PAPER_SPEC.parent / "planar_dual_arm.urdf").read_text(),
            [("[object]\nmass = 2.0\n", f"[object]\nmass = 2.0\ngrasp_offsets = {rows}\n")],
        )  # fmt: skip
        with pytest.raises(SpecError, match="grasp_offsets"):
            load_spec(path)


# ----- the TIAGo++ example of docs/howto/posture.md (once the README's), by posture -----


def _hands(document):
    return np.array([arm["position"] for arm in document["arms"]])


def test_hold_posture_holds_the_object_and_home_warns(tmp_path, capsys, tiago):
    out = tmp_path / "hold.json"
    argv = ["analyze", "tiago_dual", "--object-mass", "2", "--task", "spatial", "--posture", "hold", "--json", out]
    code, printed, err = _run(argv, capsys)
    # the one warning (issue 24): the ellipsoid excludes rest while each holding effort is within its limit
    assert code == 0 and err.count("warning: ") == 1 and "does not contain zero acceleration" in err
    doc = json.loads(out.read_text())
    assert doc["dynamic_ellipsoid"]["empty"] is False and min(doc["dynamic_ellipsoid"]["semi_axes"]) > 0.0
    # the hands, by forward kinematics here, are the declared 0.30 m apart
    q = named_configuration(tiago, "hold")
    pin.framesForwardKinematics(tiago.model, tiago.data, q)
    hands = np.array([tiago.data.oMf[arm.frame_id].translation for arm in tiago.arms])
    np.testing.assert_allclose(_hands(doc), hands, atol=1e-12)
    assert abs(np.linalg.norm(hands[0] - hands[1]) - 0.30) < 1e-3
    assert len(doc["warnings"]) == 1 and "(the largest, arm_right_2_joint, at 57%)" in doc["warnings"][0]
    assert not doc["dynamic_ellipsoid"]["center"] == [0.0] * 6  # gravity shifts it: rest lies outside

    home = tmp_path / "home.json"
    code, _, err = _run(argv[:-4] + ["--json", home], capsys)
    assert code == 0
    doc = json.loads(home.read_text())
    assert doc["dynamic_ellipsoid"]["empty"] is True
    apart = np.linalg.norm(np.subtract(*_hands(doc)))
    assert apart > 1.9
    assert f"are {apart:.3f} m apart" in err and "0.300 m apart" in err and err.startswith("warning: ")
    assert len(doc["warnings"]) == 1 and f"{apart:.3f} m" in doc["warnings"][0]


def test_q_and_posture_together_is_a_usage_error(tmp_path, capsys):
    q = tmp_path / "q.json"
    q.write_text('{"joints": {}}')
    code, _, err = _run(["analyze", "planar_dual_arm", "--q", q, "--posture", "home"], capsys)
    assert code == 2 and "--posture" in err
    code, _, err = _run(["analyze", "planar_dual_arm", "--posture", "nowhere"], capsys)
    assert code == 2 and "'nowhere'" in err and "home" in err


def test_an_explicit_object_warns_by_its_own_offsets(robot):
    """The paper's robot at home: both hands at the same point (the object's centre). An object
    declared with grasp points 0.4 m apart is fine (hands closer than allowed); hands 1 m apart
    on a 0.4 m object warn."""
    q = robot.neutral()
    an = mobmanip.analyze(robot, q, "planar")
    assert an.warnings == ()
    centre = an.end_effector_positions.mean(axis=0)
    narrow = HeldObject(2.0, np.eye(3), centre, np.array([[0, -0.2, 0], [0, 0.2, 0]]))
    assert mobmanip.analyze(robot, q, "planar", held_object=narrow).warnings == ()
    q2 = robot.configuration((0, 0, 0), {"arm_right_1_joint": -0.5, "arm_left_1_joint": 0.5})
    spread = mobmanip.analyze(robot, q2, "planar", held_object=narrow)
    pos = spread.end_effector_positions
    apart = np.linalg.norm(pos[0] - pos[1])
    assert apart > 0.4 * 1.1 + 0.05
    # both arms stretched out (only their first joints turned): the posture is singular too
    assert len(spread.warnings) == 2 and f"{apart:.3f} m apart" in spread.warnings[0]
    assert spread.warnings[1].startswith("the posture is singular")


# ----- placeholder limits and weight -----


def test_identical_round_limits_are_flagged(tmp_path):
    text = (PAPER_SPEC.parent / "planar_dual_arm.urdf").read_text()
    efforts = "".join(f"arm_right_{i}_joint = 100.0\n" for i in (1, 2, 3))
    path = write_variant(tmp_path, text, [("# [limits.effort]\n", f"[limits.effort]\n{efforts}")])
    robot = mobmanip.load_robot(load_spec(path))
    found = limit_warnings(robot)
    assert len(found) == 1 and "'right'" in found[0] and "100 N m" in found[0] and "effort" in found[0]
    # the paper's own limits (Table 1: 3.14 rad/s on every joint, not a round value) pass
    assert limit_warnings(mobmanip.load_robot("planar_dual_arm")) == ()


def test_weight_warning_matches_the_generalized_gravity(tiago):
    """An arm whose shoulder limit is below the torque gravity needs there is named; the torque
    is checked against Pinocchio's generalized gravity (computed independently of xi)."""
    q = named_configuration(tiago, "hold")
    g = pin.computeGeneralizedGravity(tiago.model, tiago.data, q)
    names = tiago.reduced_velocity_names
    joint = "arm_right_2_joint"
    need = abs(g[tiago.model.joints[tiago.model.getJointId(joint)].idx_v])
    assert need > 1.0
    weak = tiago.with_limits(effort={joint: 0.5 * need})
    an = mobmanip.analyze(weak, q, "spatial")
    found = weight_warnings(weak, an.bias)
    assert len(found) == 1 and found[0].startswith(joint) and f"{need:.3g}" in found[0]
    assert names.index(joint) >= 2


# ----- per-block indices of a mixed task -----


def test_block_indices_are_the_shadows_of_each_block(tiago):
    q = named_configuration(tiago, "hold")
    an = mobmanip.analyze(tiago, q, "spatial", object_mass=2.0)
    blocks = block_indices(mobmanip.robot.tasks.get_task("spatial"), an.measures)
    doc = an.to_dict()["block_indices"]
    for name, ellipsoid in an.measures.items():
        for block, rows in (("linear", (0, 1, 2)), ("angular", (3, 4, 5))):
            entry = blocks[name][block]
            assert doc[mobmanip.measures.get_measure(name).json_key][block] == entry
            # the shadow reaches along each unit direction u of the block exactly as far as the
            # 6-D set does along u padded with zeros (its support function), here on 40 directions
            rng = np.random.default_rng(1)
            shadow = ellipsoid.project(rows)
            for u in rng.normal(size=(40, 3)):
                u /= np.linalg.norm(u)
                full = np.zeros(6)
                full[list(rows)] = u
                assert abs(shadow.support(u) - ellipsoid.support(full)) < 1e-9 * ellipsoid.semi_axes[0]
            # its volume is that of a 3-D ellipsoid with the shadow's semi-axes
            a = np.array(entry["semi_axes"])
            assert abs(entry["volume"] - 4.0 / 3.0 * np.pi * np.prod(a)) < 1e-9 * entry["volume"]
            assert abs(entry["isotropy"] - a[-1] / a[0]) < 1e-12
    assert block_indices(mobmanip.robot.tasks.get_task("translational"), an.measures) is None


def test_a_singular_posture_is_said_with_its_semi_axes():
    """The UR5 at home holds its arm stretched out: the hand's velocity set loses a direction
    (its Jacobian has rank 5). The analysis says the posture is singular with the kinematic ellipsoid's
    semi-axes, here against the singular values of Pinocchio's frame Jacobian scaled by the
    velocity limits (the ellipsoid of a single hand, W = I), also when only the dynamic measure
    was asked for; the elbow and the wrist bent get no such line."""
    import re

    ur5 = mobmanip.load_robot("ur5")
    frame = ur5.model.getFrameId(ur5.arms[0].end_effector)

    def semi_axes(q):
        J = pin.computeFrameJacobian(ur5.model, ur5.data, q, frame, pin.LOCAL_WORLD_ALIGNED)
        return np.linalg.svd(J @ ur5.null_space(q) * np.asarray(ur5.velocity_limits), compute_uv=False)

    home = ur5.neutral()
    sigma = semi_axes(home)
    assert sigma[-1] < 1e-3 * sigma[0]
    for measures in (None, ("dynamic",)):
        found = [w for w in mobmanip.analyze(ur5, home, "spatial", measures=measures).warnings if "singular" in w]
        assert len(found) == 1, found
        largest, least = map(float, re.search(r"run from (\S+) down to (\S+) \(m/s, rad/s\)", found[0]).groups())
        assert largest == pytest.approx(sigma[0], rel=1e-3) and least < 1e-3 * largest
    bent = home.copy()
    for joint, angle in (("shoulder_lift_joint", -0.8), ("elbow_joint", 1.2), ("wrist_2_joint", 1.0)):
        bent[ur5.model.joints[ur5.model.getJointId(joint)].idx_q] = angle
    sigma = semi_axes(bent)
    assert sigma[-1] > 0.01 * sigma[0]
    assert not [w for w in mobmanip.analyze(ur5, bent, "spatial").warnings if "singular" in w]


def test_a_task_the_robot_cannot_span_anywhere_is_not_called_a_singular_posture(robot):
    """The paper's planar arms in the spatial task: no joint moves the hands along z (Pinocchio's
    frame Jacobians have zero z rows, here and at a random posture), so the kinematic ellipsoid
    is flat in every posture. That is the robot's, not the posture's: no warning says to move
    the joints."""
    rng = np.random.default_rng(3)
    q = robot.neutral()
    moved = q.copy()
    for joint in robot.model.joints[2:]:
        if joint.nq == 1:
            moved[joint.idx_q] += rng.uniform(-1.0, 1.0)
    for posture in (q, moved):
        for arm in robot.arms:
            J = pin.computeFrameJacobian(robot.model, robot.model.createData(), posture, arm.frame_id,
                                         pin.LOCAL_WORLD_ALIGNED)  # fmt: skip
            assert np.abs(J[2]).max() == 0.0
    an = mobmanip.analyze(robot, q, "spatial")
    assert an.kinematic.semi_axes[-1] < 1e-12 * an.kinematic.semi_axes[0]
    assert not [w for w in an.warnings if "singular" in w]


def test_the_analysis_block_indices_are_its_own_copies(tiago):
    """An analysis computes its block indices once (a grounded set's shadows took 10 s each time
    on TIAGo Pro) and hands out copies: changing one leaves the next call's, the JSON's and the
    independent function's alone."""
    an = mobmanip.analyze(tiago, named_configuration(tiago, "hold"), "spatial", object_mass=2.0)
    first = an.block_indices()
    key = next(iter(first))
    first[key]["linear"]["volume"] = -1.0
    first[key]["linear"]["rows"].append(99)
    again = an.block_indices()
    assert again == block_indices(mobmanip.robot.tasks.get_task("spatial"), an.measures)
    assert again[key]["linear"]["volume"] > 0 and again[key]["linear"]["rows"] == [0, 1, 2]
    assert an.to_dict()["block_indices"][mobmanip.measures.get_measure(key).json_key] == again[key]


def test_init_spec_records_postures_that_load_back(tmp_path, capsys, robot):
    """init-spec --posture NAME=Q.json writes [postures.NAME] (and [hold]) with the arm joints of
    the file; the spec reads back and the named configuration is the file's configuration."""
    urdf = PAPER_SPEC.parent / "planar_dual_arm.urdf"
    q_file = tmp_path / "reach.json"
    q_file.write_text(json.dumps({"joints": {"arm_right_2_joint": 0.7, "arm_left_2_joint": -0.7}}))
    out = tmp_path / "spec.toml"
    tools = ["arm_right_tool_link", "arm_left_tool_link"]
    argv = ["init-spec", urdf, "--ee", tools[0], "--ee", tools[1], "--out", out]
    code, _, _ = _run(argv + ["--posture", f"reach={q_file}", "--posture", f"hold={q_file}"], capsys)
    assert code == 0
    text = out.read_text()
    assert "[postures.reach]" in text and "[hold]" in text
    spec = load_spec(out)
    assert spec.postures["reach"]["arm_right_2_joint"] == 0.7 and spec.hold["arm_left_2_joint"] == -0.7
    loaded = mobmanip.load_robot(spec)
    q_named = named_configuration(loaded, "reach")
    q_file_cfg = mobmanip.robot.configurations.read_configuration(loaded, q_file)
    np.testing.assert_allclose(q_named, q_file_cfg, atol=0)
    code, _, err = _run(argv + ["--posture", "reach"], capsys)
    assert code == 2 and "NAME=Q.json" in err
