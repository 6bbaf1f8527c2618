"""MJCF keyframes (issue 38): a ``<keyframe>`` is sized for the file's own joints (a free root
joint included), which are not the joints of mobmanip's model, so Pinocchio must never see it;
its keys are read as the robot's named postures instead.

The expected values come from MuJoCo itself: it loads the same file and lays each key's ``qpos``
out by its joints' ``jnt_qposadr``; the posture then puts the tool site where MuJoCo puts it.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from mjcf_util import mjcf_text
from mobmanip.descriptions import read_description
from mobmanip.postures.named import named_configuration, posture_names
from mobmanip.robot.detect import detect_spec

#: Degrees in the file (the keys' qpos are radians all the same), a free root joint, a body with
#: two joints, a hinge with a ``ref``, a slide; keys of the right size, a short one (MuJoCo
#: fills the rest with qpos0); a key of the wrong size can be added at the end of ``<keyframe>``.
ROBOT = mjcf_text("keyed")

JOINTS = ("lift", "pan", "tilt", "elbow")


def _write(tmp_path: Path, bad: str = "") -> Path:
    path = tmp_path / "keyed.xml"
    path.write_text(ROBOT.replace("  </keyframe>", f"    {bad}\n  </keyframe>"))
    return path


def _mujoco_keys(path: Path) -> dict[str, dict[str, float]]:
    """Each key's joint positions as MuJoCo lays them out."""
    model = mujoco.MjModel.from_xml_path(str(path))
    out = {}
    for k in range(model.nkey):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_KEY, k)
        out[name] = {joint: float(model.key_qpos[k, model.jnt_qposadr[model.joint(joint).id]]) for joint in JOINTS}
    return out


def test_keyframes_are_read_as_postures_with_mujocos_values_and_pinocchio_builds(tmp_path):
    path = _write(tmp_path)
    expected = _mujoco_keys(path)
    assert expected["reach"]["elbow"] == pytest.approx(np.radians(20.0))  # filled by MuJoCo with qpos0 = ref
    description = read_description(path)
    assert set(description.keyframes) == {"home", "reach"}
    for name, values in expected.items():
        assert description.keyframes[name] == pytest.approx(values, abs=1e-15)
    assert any("'reach' gives 10 of the file's 11 positions" in note for note in description.notes)
    model = description.build_model(pin.JointModelPlanar())  # was: "Keyframe size does not match model size"
    assert [model.names[j] for j in range(2, model.njoints)] == list(JOINTS)
    assert "<keyframe" not in description.model_text


def test_a_keyframe_of_the_wrong_size_is_left_out_with_a_note_naming_it(tmp_path):
    path = _write(tmp_path, bad='<key name="long" qpos="0 0 0 1 0 0 0 1 2 3 4 5"/>')
    with pytest.raises(ValueError, match="invalid qpos size"):  # MuJoCo refuses the whole file
        mujoco.MjModel.from_xml_path(str(path))
    description = read_description(path)
    assert set(description.keyframes) == {"home", "reach"}
    assert any("'long' gives 12 positions but the file's joints have 11" in note for note in description.notes)
    description.build_model(pin.JointModelPlanar())


def test_a_keyframe_posture_puts_the_tool_where_mujoco_puts_it(tmp_path):
    path = _write(tmp_path)
    found = detect_spec(path, ["tool"], platform="fixed", torso=False, limits=dict.fromkeys(JOINTS, (1.0, 10.0)))
    spec = found.spec
    # home is mobmanip's own: the key named home is offered under another name
    assert dict(spec.postures) == {
        "keyframe_home": pytest.approx({"lift": 0.1, "pan": 0.3, "tilt": -0.4, "elbow": 0.5}),
        "reach": pytest.approx({"lift": 0.25, "pan": -1.2, "tilt": 0.9, "elbow": np.radians(20.0)}),
    }
    assert posture_names(spec) == ("home", "keyframe_home", "reach")
    assert any("[postures.keyframe_home]" in note for note in found.notes)
    robot = mobmanip.load_robot(spec)
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    mj_data = mujoco.MjData(mj_model)
    base, tool = mj_model.body("base").id, mj_model.site("tool").id
    for k, posture in enumerate(("keyframe_home", "reach")):
        mujoco.mj_resetDataKeyframe(mj_model, mj_data, k)
        mujoco.mj_kinematics(mj_model, mj_data)
        R = mj_data.xmat[base].reshape(3, 3)
        expected = R.T @ (mj_data.site_xpos[tool] - mj_data.xpos[base])  # the tool in the base's frame
        q = named_configuration(robot, posture)
        data = robot.model.createData()
        pin.framesForwardKinematics(robot.model, data, q)
        root = data.oMi[1]  # the platform joint carries the base
        placed = root.actInv(data.oMf[robot.model.getFrameId("tool")])
        np.testing.assert_allclose(placed.translation, expected, rtol=0, atol=1e-12)
