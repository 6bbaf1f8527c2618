"""Steered drive units in MJCF (issue 38): a steering hinge about the vertical whose axis passes
through the centre of the wheel below it, told apart from a caster, whose swivel trails its wheel.

Two files. A tricycle (``tests/data/mjcf/tricycle.xml``): a free root, a steered drive unit
ahead (the steering hinge on a fork 0.14 m above the wheel's centre, both joints driven by
motors) and a free rear axle; mobmanip makes it a ``steered`` platform, and MuJoCo, given the
velocities of that platform's S(q), finds every wheel's contact point at rest (rolling without
slipping, from ``mj_jac`` at the point below each wheel's centre). And Menagerie's mobile FR3
Duo, whose base the file moves on actuated planar joints while two steered drive units and two
casters stand under it, none of them actuated: the units are named as such (not as casters), the
casters' trail is MuJoCo's, and the units' floor contacts, which ``init-spec`` writes as
``[support] wheels``, are where MuJoCo puts the bottoms of their wheels.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

import mobmanip
from mjcf_util import mjcf_text
from mobmanip.descriptions import read_description
from mobmanip.platforms.wheels import wheel_candidates
from mobmanip.robot.detect import detect_spec

TRICYCLE = mjcf_text("tricycle")

#: The wheels' joints and bodies (their radii are MuJoCo's reading of the cylinders).
WHEELS = {"drive_wheel": "drive", "rear_right_wheel": "rear_right", "rear_left_wheel": "rear_left"}


FR3_DUO = Path(__file__).resolve().parent / "data" / "menagerie_franka_mobile_fr3_duo" / "mobile_fr3_duo.xml"


def test_an_mjcf_steered_drive_unit_makes_a_steered_platform_that_rolls_as_mujoco_says(tmp_path):
    path = tmp_path / "tricycle.xml"
    path.write_text(TRICYCLE)
    limits = {"drive_wheel": (12.0, None), "steer": (2.0, None), "arm_1": (2.0, None), "arm_2": (2.0, None)}
    found = detect_spec(path, ["tool"], limits=limits)
    spec = found.spec
    assert spec.platform == "steered"
    assert (spec.wheels.drive, spec.wheels.steer) == ("drive_wheel", "steer")
    assert set(spec.wheels.rear) == {"rear_right_wheel", "rear_left_wheel"}
    line = next(line for line in found.considered if line.startswith("wheel-like joint drive_wheel "))
    assert "on steering joint 'steer' through its centre (a steered drive unit) -> platform wheel" in line
    robot = mobmanip.load_robot(spec)
    theirs = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(theirs)
    model = robot.model
    rng = np.random.default_rng(38)
    for _ in range(5):
        x, y, theta = rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-np.pi, np.pi)
        angles = {"steer": rng.uniform(-1.3, 1.3), "arm_1": rng.uniform(-2, 2), "arm_2": rng.uniform(-1, 1),
                  "drive_wheel": rng.uniform(-3, 3), "rear_left_wheel": rng.uniform(-3, 3),
                  "rear_right_wheel": rng.uniform(-3, 3)}  # fmt: skip
        q = robot.configuration((x, y, theta), angles)
        x_reduced = rng.normal(size=robot.nx)
        x_reduced[0] = rng.choice((-1.0, 1.0)) * rng.uniform(2.0, 5.0)  # the drive wheel's rate, rad/s
        v = robot.null_space(q) @ x_reduced
        # MuJoCo's free joint: position and linear velocity in the world, angular velocity in the body
        c, s = np.cos(theta), np.sin(theta)
        data.qpos[:7] = (x, y, 0.0, np.cos(theta / 2), 0.0, 0.0, np.sin(theta / 2))
        data.qvel[:6] = (c * v[0] - s * v[1], s * v[0] + c * v[1], 0.0, 0.0, 0.0, v[2])
        for name, angle in angles.items():
            joint = theirs.joint(name)
            data.qpos[joint.qposadr[0]] = angle
            data.qvel[joint.dofadr[0]] = v[model.joints[model.getJointId(name)].idx_v]
        mujoco.mj_forward(theirs, data)
        assert np.linalg.norm(data.qvel[:6]) > 0.1  # the base does move
        for body in WHEELS.values():
            b = theirs.body(body).id
            radius = theirs.geom_size[theirs.body_geomadr[b], 0]
            contact = data.xpos[b] - np.array([0.0, 0.0, radius])  # below the wheel's centre
            jacp, jacr = np.zeros((3, theirs.nv)), np.zeros((3, theirs.nv))
            mujoco.mj_jac(theirs, data, jacp, jacr, contact, b)
            np.testing.assert_allclose(jacp @ data.qvel, 0.0, rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def fr3_duo():
    """The mobile FR3 Duo: its spec as init-spec infers it, its wheel candidates, and MuJoCo's
    model and data at its qpos0 (the base at the world's origin, as mobmanip's root)."""
    limits = {name: (1.0, 100.0) for name in ("base_x", "base_y", "base_yaw")}
    limits.update({f"{side}_fr3v2_joint{k}": (2.6, None) for side in ("left", "right") for k in range(1, 8)})
    found = detect_spec(FR3_DUO, ["left_attachment_site", "right_attachment_site"], limits=limits)
    candidates = {c.name: c for c in wheel_candidates(read_description(FR3_DUO))}
    theirs = mujoco.MjModel.from_xml_path(str(FR3_DUO))
    data = mujoco.MjData(theirs)
    mujoco.mj_forward(theirs, data)
    return found, candidates, theirs, data


def test_the_fr3_duos_drive_units_are_steered_units_and_its_casters_trail_as_in_mujoco(fr3_duo):
    found, candidates, theirs, data = fr3_duo
    units = {"tmrv0_2_joint_1": "tmrv0_2_joint_0", "tmrv0_2_joint_3": "tmrv0_2_joint_2"}
    casters = {"caster_front_left_joint": "caster_front_left_steering_joint",
               "caster_rear_right_joint": "caster_rear_right_steering_joint"}  # fmt: skip
    for wheel, steer in {**units, **casters}.items():
        c = candidates[wheel]
        assert c.steering_joint == steer
        # MuJoCo's trail: the wheel joint's anchor from the swivel's axis, in the world at qpos0
        axis = data.xaxis[theirs.joint(steer).id]
        d = data.xanchor[theirs.joint(wheel).id] - data.xanchor[theirs.joint(steer).id]
        trail = float(np.linalg.norm(d - (d @ axis) * axis))
        assert c.steering_offset == pytest.approx(trail, abs=1e-12)
        assert c.steered_unit == (wheel in units)
        line = next(line for line in found.considered if line.startswith(f"wheel-like joint {wheel} "))
        if wheel in units:
            assert "(a steered drive unit) -> a steered drive unit, not the platform's (the file actuates " in line
            assert "neither its steering nor its rolling joint" in line
        else:
            assert trail > 0.03 and f"on swivel {steer!r}, {trail:.3g} m off its axis (a caster)" in line
    # the joints the file actuates are MuJoCo's
    joint_transmission = int(mujoco.mjtTrn.mjTRN_JOINT)
    actuated = {theirs.joint(int(theirs.actuator_trnid[a, 0])).name for a in range(theirs.nu)
                if int(theirs.actuator_trntype[a]) == joint_transmission}  # fmt: skip
    assert read_description(FR3_DUO).actuated == actuated
    assert {"planar_x", "planar_y", "planar_theta"} <= actuated and not actuated & {*units, *units.values()}


def test_the_fr3_duos_drive_units_are_its_driven_floor_contacts_where_mujoco_puts_them(fr3_duo):
    found, _, theirs, data = fr3_duo
    spec = found.spec
    assert spec.platform == "omnidirectional"
    expected = []
    for wheel in ("tmrv0_2_joint_1", "tmrv0_2_joint_3"):
        joint = theirs.joint(wheel)
        geom = next(g for g in range(theirs.ngeom) if theirs.geom_bodyid[g] == joint.bodyid[0])
        expected.append(data.xanchor[joint.id] - np.array([0.0, 0.0, theirs.geom_size[geom][0]]))
    assert spec.support is not None and spec.support.casters == () and spec.support.rollers == ()
    np.testing.assert_allclose(np.array(spec.support.wheels), np.array(expected), rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(spec.support.wheels)[:, 2], 0.0, atol=1e-9)  # the wheels' floor
    note = next(note for note in found.notes if note.startswith("the base's floor contacts"))
    assert "casters caster_front_left_link, caster_rear_right_link (found by their names)" in note
