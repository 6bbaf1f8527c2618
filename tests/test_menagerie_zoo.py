"""MuJoCo Menagerie's wheeled mobile manipulators (issue 38, item 4): Stanford's TidyBot, the
mobile FR3 Duo, Hello Robot's Stretch 3 and PAL's TIAGo++ (``tests/data/menagerie_*``, their
meshes replaced by one placeholder box or removed, every inertial as published), each through
``init-spec`` with only the limits the file does not give, then loaded from the spec it wrote.
On random configurations with random velocities, mobmanip's mass matrix, bias (Coriolis,
centrifugal and gravity: Pinocchio's ``nonLinearEffects``) and hand Jacobians equal MuJoCo's own
(``mj_fullM``, ``qfrc_bias``, ``mj_jacSite`` / ``mj_jacBody``), computed by MuJoCo from the same
file, to 1e-9. Bodies whose mass MuJoCo takes from their meshes weigh the placeholders' volumes
in both.

How the models map. mobmanip's platform velocity is (v_x, v_y, omega) in the platform's frame;
MuJoCo's is (x', y') along the world's axes and the yaw rate, on planar joints (TidyBot, FR3 Duo)
or on the root's free joint (Stretch: linear velocity in the world, angular in the body), so
MuJoCo's velocity = T mobmanip's with T = diag(R(theta), 1, I) on the moving joints, and
M = T^T M_mj T, J = J_mj T, bias = T^T (bias_mj + M_mj dT/dt v) (MuJoCo's acceleration is
T v' + dT/dt v). The joints the spec locks sit at the spec's reference in MuJoCo and do not move.
The one stated difference (see ``test_mjcf_planar_base.py``): the FR3 Duo's ``virtual_x`` slides
along x only in MuJoCo and is counted along y too as part of the platform, so its mass is added to
MuJoCo's y-y entry.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mobmanip
from hostile_util import assert_one_line_error, run_cli
from mjcf_util import mujoco_terms, platform_map, platform_map_rate
from mobmanip.robot.spec import load_spec

mujoco = pytest.importorskip("mujoco")

DATA = Path(__file__).resolve().parent / "data"

#: name -> (file, end effectors, the limits init-spec asked for, MuJoCo bodies sliding along x only).
ROBOTS = {
    "tidybot": (
        "menagerie_stanford_tidybot/tidybot.xml",
        ["pinch_site"],
        ["--velocity-limit", "joint_*=1.4", "--velocity-limit", "base_x=1", "--velocity-limit", "base_y=1",
         "--velocity-limit", "base_yaw=2", "--effort-limit", "base_x=300", "--effort-limit", "base_y=300",
         "--effort-limit", "base_yaw=100"],
        (),
    ),
    "fr3_duo": (
        "menagerie_franka_mobile_fr3_duo/mobile_fr3_duo.xml",
        ["left_attachment_site", "right_attachment_site"],
        ["--velocity-limit", "*_fr3v2_joint*=2.6", "--velocity-limit", "base_x=1", "--velocity-limit", "base_y=1",
         "--velocity-limit", "base_yaw=1.5", "--effort-limit", "base_x=500", "--effort-limit", "base_y=500",
         "--effort-limit", "base_yaw=200"],
        ("virtual_x",),
    ),
    "tiago_dual": (
        "menagerie_tiago_dual/tiago_dual.xml",
        ["arm_right_7_link", "arm_left_7_link"],
        ["--velocity-limit", "arm_*_joint=1.9", "--effort-limit", "arm_*_joint=40", "--wheel-velocity-limit", "10",
         "--wheel-effort-limit", "20"],
        (),
    ),
    "stretch": (
        "menagerie_hello_robot_stretch_3/stretch.xml",
        ["link_grasp_center"],
        ["--velocity-limit", "joint_*=0.4", "--effort-limit", "joint_*=40"],
        (),
    ),
}  # fmt: skip


@pytest.fixture(scope="module", params=sorted(ROBOTS))
def robot(request, tmp_path_factory):
    """(name, path, spec file, the loaded robot, MuJoCo's model) of one Menagerie robot."""
    name = request.param
    relative, ends, limits, _ = ROBOTS[name]
    path = DATA / relative
    spec = tmp_path_factory.mktemp(name) / f"{name}.toml"
    argv = ["init-spec", str(path), *[a for end in ends for a in ("--ee", end)], *limits, "--out", str(spec)]
    assert mobmanip.cli.main(argv) == 0
    return name, path, spec, mobmanip.load_robot(load_spec(spec)), mujoco.MjModel.from_xml_path(str(path))


def _layout(robot, theirs):
    """MuJoCo's platform rows (x, y, yaw), its qpos addresses for x, y and the yaw (or the free
    joint's first), and each of mobmanip's joints as (MuJoCo qpos address, dof, our idx_q, nq, idx_v)."""
    description = robot.description
    if description.planar_base:
        ids = [theirs.joint(j.name).id for j in description.planar_base]
        rows = tuple(int(theirs.jnt_dofadr[j]) for j in ids)
        free = None
    else:
        free = next(j for j in range(theirs.njnt) if int(theirs.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE))
        dof = int(theirs.jnt_dofadr[free])
        rows = (dof, dof + 1, dof + 5)  # the free joint's angular velocity is in the body's frame
        ids = []
    model = robot.model
    joints = []
    for j in range(2, model.njoints):
        k = theirs.joint(model.names[j]).id
        joints.append((int(theirs.jnt_qposadr[k]), int(theirs.jnt_dofadr[k]), model.idx_qs[j], model.nqs[j],
                       model.idx_vs[j], k))  # fmt: skip
    return rows, ids, free, joints


def _sample(rng, robot, theirs, layout):
    """A random configuration and velocity: MuJoCo's (qpos, qvel) and mobmanip's (q, v), theta."""
    rows, ids, free, joints = layout
    model = robot.model
    qpos = theirs.qpos0.copy()
    ours = {j for *_, j in joints}
    one_dof = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    for k in range(theirs.njnt):  # the locked joints at the spec's reference
        if int(theirs.jnt_type[k]) in one_dof and k not in ours:
            qpos[theirs.jnt_qposadr[k]] = robot.spec.reference.get(theirs.joint(k).name, 0.0)
    x, y, theta = rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-3.1, 3.1)
    if free is None:
        for k, value in zip(ids, (x, y, theta)):
            qpos[theirs.jnt_qposadr[k]] = value
    else:
        a = theirs.jnt_qposadr[free]
        qpos[a : a + 7] = (x, y, 0.0, np.cos(theta / 2), 0.0, 0.0, np.sin(theta / 2))
    q = np.zeros(model.nq)
    q[:4] = (x, y, np.cos(theta), np.sin(theta))
    v = rng.normal(size=model.nv)
    T = platform_map(theta, rows, theirs.nv, model.nv)
    for adr, dof, idx_q, nq, idx_v, k in joints:
        low, high = theirs.jnt_range[k] if theirs.jnt_limited[k] else (-np.pi, np.pi)
        value = rng.uniform(low, high)
        qpos[adr] = value
        q[idx_q : idx_q + nq] = (value,) if nq == 1 else (np.cos(value), np.sin(value))
        T[dof, idx_v] = 1.0
    return qpos, T @ v, q, v, theta, T


def test_mass_matrix_bias_and_hand_jacobians_equal_mujocos(robot):
    name, _, _, ours, theirs = robot
    ends = ROBOTS[name][1]
    model, data = ours.model, ours.model.createData()
    layout = _layout(ours, theirs)
    lumped = np.zeros((theirs.nv, theirs.nv))
    for body in ROBOTS[name][3]:  # counted along y too (module docstring)
        lumped[layout[0][1], layout[0][1]] = float(theirs.body(body).mass[0])
    rng = np.random.default_rng(38)
    largest = {"M": 0.0, "bias": 0.0, "J": 0.0}
    for _ in range(5):
        qpos, qvel, q, v, theta, T = _sample(rng, ours, theirs, layout)
        M_mj, bias_mj, J_mj, at = mujoco_terms(theirs, qpos, qvel, ends)
        M_mj = M_mj + lumped
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        expected = T.T @ M_mj @ T
        np.testing.assert_allclose(M, expected, rtol=0, atol=1e-9)
        bias = pin.nonLinearEffects(model, data, q, v)
        expected_bias = T.T @ (bias_mj + M_mj @ platform_map_rate(theta, v, layout[0], theirs.nv))
        np.testing.assert_allclose(bias, expected_bias, rtol=0, atol=1e-9)
        largest["M"] = max(largest["M"], float(np.abs(M - expected).max()))
        largest["bias"] = max(largest["bias"], float(np.abs(bias - expected_bias).max()))
        pin.framesForwardKinematics(model, data, q)
        for end, J_theirs, position in zip(ends, J_mj, at):
            frame = model.getFrameId(end)
            J = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(J, J_theirs @ T, rtol=0, atol=1e-9)
            np.testing.assert_allclose(data.oMf[frame].translation, position, rtol=0, atol=1e-12)
            largest["J"] = max(largest["J"], float(np.abs(J - J_theirs @ T).max()))
        assert np.abs(bias).max() > 1.0  # gravity and the velocities are in it
    print(name, {k: f"{value:.1e}" for k, value in largest.items()})


def test_init_spec_asks_for_exactly_the_limits_the_file_lacks(robot, tmp_path, capfd):
    """Without the limit flags, init-spec names each joint whose limit the file lacks and the flag
    that supplies it, and nothing else; with them (the fixture), the spec is complete."""
    name, path, spec, ours, _ = robot
    relative, ends, limits, _ = ROBOTS[name]
    out = tmp_path / "bare.toml"
    code, _, err = run_cli(capfd, "init-spec", path, *[a for end in ends for a in ("--ee", end)], "--out", out)
    assert code == 0 and err.count("\n") == 1 and err.startswith("warning: "), err
    asked = set()
    for kind, names, flag in re.findall(r"(velocity|effort) limit of ([\w, ]+) \((--[\w-]+)", err):
        if flag in ("--velocity-limit", "--effort-limit"):
            asked |= {(kind, n.strip(), flag) for n in names.split(",")}
    base = {"base_x": 0, "base_y": 1, "base_yaw": 2}
    expected = set()
    description = ours.description
    for joint in ours.reduced_velocity_names:
        if joint not in base and joint not in description.joints:
            continue  # a skid-steer side: the wheels' own flags (--wheel-velocity-limit) supply it
        written = description.planar_base[base[joint]] if joint in base else description.joints[joint]
        for kind, flag in (("velocity", "--velocity-limit"), ("effort", "--effort-limit")):
            if getattr(written.limits, kind) is None:
                expected.add((kind, joint, flag))
    assert expected  # each of these files lacks some
    # every mesh is read (a geom of zero mass, as a class gives each visual geom, is no missing mesh)
    assert not [note for note in ours.description.notes if "missing or not closed" in note]
    assert asked == expected


def test_analyze_and_the_viewer_export_run_on_the_spec(robot, tmp_path, capfd):
    name, _, spec, _, _ = robot
    code, out, err = run_cli(capfd, "analyze", spec)
    assert code == 0, err
    assert "kinematic ellipsoid" in out and "dynamic ellipsoid" in out
    page = tmp_path / f"{name}.html"
    code, _, err = run_cli(capfd, "view", spec, "--export", page)
    assert code == 0, err
    assert page.stat().st_size > 10_000


def test_analyze_on_the_ground(robot, capfd):
    """Stretch stands on its two wheels and the caster geom of its base (class ``caster``). The
    FR3 Duo moves on planar joints but stands on two steered drive units and two casters:
    init-spec wrote the units as the base's driven contacts ([support] wheels) and the floor
    model finds the casters by name. TidyBot moves on planar joints and has no wheel at all:
    ``--ground`` says so in one line and names what to give."""
    name, _, spec, _, _ = robot
    if name == "tiago_dual":  # its four wheels work: about 15 s (18 velocities)
        pytest.skip("Menagerie's TIAGo++ on its floor is checked in tests/test_floor_task.py")
    code, out, err = run_cli(capfd, "analyze", spec, "--ground")
    if name == "stretch":
        assert code == 0, err
        assert "base_link/caster" in out
    elif name == "fr3_duo":
        assert code == 0, err
        assert "contacts wheel_0, wheel_1, caster_front_left_link, caster_rear_right_link" in out
    else:  # TidyBot's base inertia is also warned of (test_inertia_plausibility.py)
        errors = "\n".join(line for line in err.splitlines() if not line.startswith("warning: "))
        assert_one_line_error(code, errors, "has no wheels on the floor", "[support] wheels")
