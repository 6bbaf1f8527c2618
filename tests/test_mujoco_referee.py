"""MuJoCo as physics referee (issue 24): the MuJoCo model is mobmanip's robot, and its contact
physics agrees with a Pinocchio constrained-dynamics model written here from the same URDF.

The Pinocchio side is independent of mobmanip's terms: a free-flyer model of the URDF, reduced
with the joints mobmanip locks (at the spec's ``[reference]``, else zero), the object as six
extra coordinates, every floor contact and grasp as a bilateral constraint, solved in the
constraints' null space.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest
from scipy.linalg import null_space

import mobmanip
from mobmanip.casestudy import configuration_at, optimal_posture
from mobmanip.postures.named import named_configuration

mujoco = pytest.importorskip("mujoco")
from mujoco_referee import PAPER_CASTERS, build, urdf_casters  # noqa: E402

G = 9.81


@pytest.fixture(scope="module")
def robots():
    return {"paper": mobmanip.load_robot("planar_dual_arm"), "tiago": mobmanip.load_robot("tiago_dual")}


def _paper(robots, heading=0.0):
    robot = robots["paper"]
    q = configuration_at(robot, optimal_posture(robot), 0.0, heading=heading)
    return robot, q, mobmanip.analyze(robot, q, object_mass=2.0).held_object


def _tiago(robots, platform=(0.0, 0.0, 0.0)):
    robot = robots["tiago"]
    q = named_configuration(robot, "hold", platform=platform)
    return robot, q, mobmanip.analyze(robot, q, object_mass=2.0).held_object


@pytest.fixture(scope="module")
def paper(robots):
    """The paper robot at its optimal posture, object at 0 deg, 2 kg: (robot, q, object)."""
    return _paper(robots)


@pytest.fixture(scope="module")
def tiago(robots):
    """TIAGo++ in its hold posture with a 2 kg object: (robot, q, object)."""
    return _tiago(robots)


@pytest.fixture(scope="module")
def paper_turned(robots):
    """As ``paper``, the platform heading 0.7 rad."""
    return _paper(robots, heading=0.7)


@pytest.fixture(scope="module")
def tiago_turned(robots):
    """As ``tiago``, the platform at (0.4 m, -0.3 m, 0.7 rad)."""
    return _tiago(robots, platform=(0.4, -0.3, 0.7))


def supports_of(robot):
    return PAPER_CASTERS if robot.name == "planar_dual_arm" else urdf_casters(robot)


# ----- the independent Pinocchio model -----


def free_flyer(robot, repairs):
    """Pinocchio free-flyer model of the robot's URDF, mobmanip's locked joints removed, with the
    referee's inertia repairs applied (they are about 1e-8 kg m^2; see test 1)."""
    full = pin.buildModelFromUrdf(str(robot.spec.urdf), pin.JointModelFreeFlyer())
    keep, q_ref, locked = set(robot.model.names), pin.neutral(full), []
    for j in range(2, full.njoints):
        joint, value = full.joints[j], robot.spec.reference.get(full.names[j], 0.0)
        if joint.nq == 2:
            q_ref[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
        else:
            q_ref[joint.idx_q] = value
        if full.names[j] not in keep:
            locked.append(j)
    model = pin.buildReducedModel(full, locked, q_ref)
    inertial = {link.get("name"): link.find("inertial/origin") for link in ET.parse(robot.spec.urdf).iter("link")}
    for link, (old, new) in repairs.items():
        origin = inertial[link]
        rpy = [float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()]
        frame = model.frames[model.getFrameId(link)]
        placement = frame.placement * pin.SE3(pin.rpy.rpyToMatrix(np.array(rpy)), np.zeros(3))
        delta = pin.Inertia(0.0, np.zeros(3), new - old)
        model.inertias[frame.parentJoint] = model.inertias[frame.parentJoint] + placement.act(delta)
    return model


def ff_configuration(model, robot, q, lift):
    """The free-flyer configuration of mobmanip's q, the root raised by ``lift`` (m)."""
    out = pin.neutral(model)
    yaw = math.atan2(q[3], q[2])
    out[:7] = (q[0], q[1], lift, 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    for j in range(2, robot.model.njoints):
        src, dst = robot.model.joints[j], model.joints[model.getJointId(robot.model.names[j])]
        out[dst.idx_q : dst.idx_q + dst.nq] = q[src.idx_q : src.idx_q + src.nq]
    return out


def mujoco_from_pinocchio(referee, model, q_ff):
    """T (nv_mj, nv_pin) with v_mj = T v_pin: joints matched by name; the free joint's linear
    velocity is in world axes in MuJoCo, in the root frame in Pinocchio."""
    mj = referee.model
    T = np.zeros((mj.nv, model.nv))
    T[:3, :3] = pin.Quaternion(q_ff[6], *q_ff[3:6]).toRotationMatrix()
    T[3:6, 3:6] = np.eye(3)
    for j in range(2, model.njoints):
        T[mj.joint(model.names[j]).dofadr[0], model.joints[j].idx_v] = 1.0
    return T


def point_jacobian(model, data, joint, point):
    """World-axes Jacobian (3, nv) of the point ``point`` (world, m) moving with ``joint``."""
    J = pin.getJointJacobian(model, data, joint, pin.LOCAL_WORLD_ALIGNED)
    return J[:3] - pin.skew(point - data.oMi[joint].translation) @ J[3:]


def constrained_system(referee, robot, q, obj, grasp):
    """The whole robot and the object at rest, Pinocchio's side: ``M qdd + b = B tau + J^T lambda``,
    ``J qdd = 0``, over the free-flyer coordinates then the object's (linear, angular; world).

    Returns:
        ``(M, b, B, J, model, q_ff)``: (n, n), (n,), (n, nx) for reduced efforts, (n_c, n) with
        n = nv + 6; the free-flyer model and its configuration.
    """
    model = free_flyer(robot, referee.repairs)
    data, q_ff = model.createData(), ff_configuration(model, robot, q, referee.lift)
    pin.computeJointJacobians(model, data, q_ff)
    pin.framesForwardKinematics(model, data, q_ff)
    M_r = pin.crba(model, data, q_ff)
    nv = model.nv
    M = np.zeros((nv + 6, nv + 6))
    M[:nv, :nv] = np.triu(M_r) + np.triu(M_r, 1).T
    M[nv : nv + 3, nv : nv + 3], M[nv + 3 :, nv + 3 :] = obj.mass * np.eye(3), obj.inertia
    b = np.concatenate([pin.computeGeneralizedGravity(model, data, q_ff), [0, 0, obj.mass * G, 0, 0, 0]])
    B, S = np.zeros((nv + 6, robot.nx)), robot.null_space(q)
    for k, name in enumerate(robot.reduced_velocity_names):  # mobmanip's sense: its S entry (+-1)
        sign = S[robot.model.joints[robot.model.getJointId(name)].idx_v, k]
        B[model.joints[model.getJointId(name)].idx_v, k] = sign
    rows = []
    for s in referee.supports:  # a wheel's contact point sticks; a caster's only stays on the floor
        J = point_jacobian(model, data, model.getJointId(s.name) if s.driven else 1, data.oMi[1].act(s.point))
        rows.append(np.hstack([J, np.zeros((3, 6))]) if s.driven else np.hstack([J[2:], np.zeros((1, 6))]))
    centre = np.asarray(obj.center) + [0, 0, referee.lift]
    for arm in robot.arms:
        frame = model.getFrameId(arm.end_effector)
        if grasp == "weld":  # hand frame = object frame moved by r
            J_hand = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            r = data.oMf[frame].translation - centre
            rows.append(np.hstack([J_hand[:3], -np.eye(3), pin.skew(r)]))
            rows.append(np.hstack([J_hand[3:], np.zeros((3, 3)), -np.eye(3)]))
        else:  # the hand's point at the object's centre moves with it
            J_point = point_jacobian(model, data, model.frames[frame].parentJoint, centre)
            rows.append(np.hstack([J_point, -np.eye(3), np.zeros((3, 3))]))
    return M, b, B, np.vstack(rows), model, q_ff


def constrained_acceleration(system, tau):
    """Accelerations (n,) from rest under reduced efforts ``tau``, every constraint bilateral
    (solved in the constraints' null space); the last six are the object's (linear at its
    centre, angular; world axes)."""
    M, b, B, J, *_ = system
    N = null_space(J)
    return N @ np.linalg.solve(N.T @ M @ N, N.T @ (B @ tau - b))


def floor_force(system, qdd, obj):
    """Newton's law for everything on the floor: the floor's total force (3,) N that gives the
    robot's centre of mass and the object the accelerations ``qdd`` under gravity."""
    *_, model, q_ff = system
    data = model.createData()
    pin.centerOfMass(model, data, q_ff, np.zeros(model.nv), qdd[: model.nv])
    mass = pin.computeTotalMass(model)
    return mass * data.acom[0] + obj.mass * qdd[-6:-3] + (mass + obj.mass) * G * np.array([0.0, 0.0, 1.0])


def holding_torques(system, robot):
    """Reduced efforts (nx,) that hold everything still: arm torques from the static balance
    ``B tau + J^T lambda = b`` (least squares over tau and the constraint forces), wheels zero."""
    M, b, B, J, *_ = system
    arms = [k for k, name in enumerate(robot.reduced_velocity_names) if name not in robot.platform.drive_names]
    solution, *_ = np.linalg.lstsq(np.hstack([B[:, arms], J.T]), b, rcond=None)
    tau = np.zeros(robot.nx)
    tau[arms] = solution[: len(arms)]
    assert np.abs(B @ tau + J.T @ solution[len(arms) :] - b).max() < 1e-9 * np.abs(b).max()
    return tau


def mujoco_mass_and_gravity(referee):
    """MuJoCo's mass matrix (nv, nv) and, at rest, its bias forces (gravity), (nv,)."""
    m, d = referee.model, referee.data
    referee.reset()
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    return M, d.qfrc_bias.copy()


# ----- 1. the same robot -----


@pytest.mark.parametrize("name", ["paper", "tiago"])
def test_mass_matrix_and_gravity_equal_pinocchio(name, request):
    """M and g of the MuJoCo model (stripped URDF, locked joints fixed, free base) equal those of
    Pinocchio's free-flyer model of the same URDF to 1e-9 relative (measured: 3e-16 or less; 1.2e-9
    on TIAGo++ if Pinocchio kept the antennas' invalid inertias). Centres of mass at the body frames'
    origins (the ipos/iquat trap) break it by 1.5 % (TIAGo++) and 6.7 % (paper robot)."""
    robot, q, _ = request.getfixturevalue(name)
    rng = np.random.default_rng(7)
    for trial in range(3):
        q_t = q.copy()
        if trial:  # random arm joints and platform pose as well
            for arm in robot.arms:
                for j in arm.joint_names:
                    joint = robot.model.joints[robot.model.getJointId(j)]
                    q_t[joint.idx_q] = rng.uniform(-1.5, 1.5)
            yaw = rng.uniform(-math.pi, math.pi)
            q_t[:4] = (*rng.uniform(-2, 2, 2), math.cos(yaw), math.sin(yaw))
        referee = build(robot, q_t, support_points=supports_of(robot))
        model = free_flyer(robot, referee.repairs)
        data, q_ff = model.createData(), ff_configuration(model, robot, q_t, referee.lift)
        M_pin = pin.crba(model, data, q_ff)
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        g_pin = pin.computeGeneralizedGravity(model, data, q_ff)
        T = mujoco_from_pinocchio(referee, model, q_ff)
        M_mj, g_mj = mujoco_mass_and_gravity(referee)
        err_M = np.abs(T.T @ M_mj @ T - M_pin).max() / np.abs(M_pin).max()
        err_g = np.abs(T.T @ g_mj - g_pin).max() / np.abs(g_pin).max()
        assert err_M < 1e-9 and err_g < 1e-9, (err_M, err_g)
    # the trap: centres of mass at the body frames' origins
    referee.model.body_ipos[:] = 0.0
    referee.model.body_iquat[:] = (1.0, 0.0, 0.0, 0.0)
    M_trap, _ = mujoco_mass_and_gravity(referee)
    assert np.abs(T.T @ M_trap @ T - M_pin).max() / np.abs(M_pin).max() > 1e-3


def test_inertia_repairs_are_stated_and_tiny(tiago, paper):
    """TIAGo++'s antennas have a non-positive-definite inertia that MuJoCo refuses; the referee
    keeps its diagonal and says so. The change is below 1e-7 kg m^2; the paper robot needs none."""
    referee = build(tiago[0], tiago[1], support_points=urdf_casters(tiago[0]))
    assert sorted(referee.repairs) == ["base_antenna_left_link", "base_antenna_right_link"]
    for old, new in referee.repairs.values():
        assert np.linalg.eigvalsh(old)[0] < 0 < np.linalg.eigvalsh(new)[0]
        assert np.abs(new - old).max() < 1e-7
    assert build(paper[0], paper[1], support_points=PAPER_CASTERS).repairs == {}


# ----- 2. static hold -----

CASES = [("paper", "point"), ("tiago", "weld"), ("paper_turned", "point"), ("tiago_turned", "weld")]


@pytest.mark.parametrize(("name", "grasp"), CASES)
def test_static_hold(name, grasp, request):
    """With Pinocchio's holding torques (arms hold themselves and the 2 kg object, wheels zero),
    MuJoCo's object and hands stay still and the floor carries the whole weight.

    Measured (soft contacts and grasps): object 1.3e-4 m/s^2 (paper robot, the sag of its pinned
    object) and 6e-6 m/s^2 (TIAGo++), hands below 3e-5, normal forces = weight to 2e-6."""
    robot, q, obj = request.getfixturevalue(name)
    referee = build(robot, q, support_points=supports_of(robot), object=obj, grasp=grasp)
    tau = holding_torques(constrained_system(referee, robot, q, obj, grasp), robot)
    acceleration, contacts = referee.forward(tau)
    hands = referee.hand_accelerations()
    normal = sum(c.normal for c in contacts.values())
    tangential = sum(c.tangential for c in contacts.values())
    print(
        f"{name}: |a_object| {np.abs(acceleration).max():.2e}, |a_hands| {np.abs(hands).max():.2e}, "
        f"normal/weight - 1 = {normal / referee.weight - 1:.2e}, |tangential| {np.abs(tangential).max():.2e} N"
    )
    assert np.abs(acceleration).max() < 1e-2 and np.abs(hands).max() < 1e-2  # m/s^2, rad/s^2: g / 1000
    assert normal == pytest.approx(referee.weight, rel=5e-3)
    assert all(c.normal > 0 for c in contacts.values())


# ----- 3. forward dynamics -----


@pytest.mark.parametrize(("name", "grasp"), CASES)
def test_forward_dynamics_equal_constrained_pinocchio(name, grasp, request):
    """Random moderate arm torques (holding torques + up to 10 % of each limit; wheels zero): the
    object's acceleration at t = 0 in MuJoCo equals Pinocchio's bilateral constrained dynamics
    within 1 % per component, and the floor's total force obeys Newton's law for that motion.

    Components that vanish by structure (the paper robot's object moves in the plane) are held to
    1 % of 1 % of the largest component or of g, whichever is larger: the soft grasp lets the paper
    robot's object sag at 1.3e-4 m/s^2 whatever the torques. Measured on the other components:
    6e-4 relative (paper robot), 1e-5 (TIAGo++); Newton's law to 2e-6 of the largest force."""
    robot, q, obj = request.getfixturevalue(name)
    referee = build(robot, q, support_points=supports_of(robot), object=obj, grasp=grasp)
    system = constrained_system(referee, robot, q, obj, grasp)
    hold, limits = holding_torques(system, robot), robot.effort_limits
    arms = np.array([name not in robot.platform.drive_names for name in robot.reduced_velocity_names])
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(5):
        tau = np.clip(hold + arms * rng.uniform(-0.1, 0.1, robot.nx) * limits, -limits, limits)
        acceleration, contacts = referee.forward(tau)
        qdd = constrained_acceleration(system, tau)
        expected = qdd[-6:]
        assert all(c.normal > 0 for c in contacts.values())  # bilateral = unilateral here
        assert all(
            np.linalg.norm(c.tangential) < s.mu * c.normal
            for s, c in zip(referee.supports, contacts.values())
            if s.driven
        )
        scale = np.maximum(np.abs(expected), 1e-2 * max(np.abs(expected).max(), G))
        assert np.all(np.abs(acceleration - expected) <= 1e-2 * scale), (acceleration, expected)
        worst = max(worst, np.max(np.abs(acceleration - expected) / scale))
        total = np.sum([[*c.tangential, c.normal] for c in contacts.values()], axis=0)
        newton = floor_force(system, qdd, obj)
        assert total == pytest.approx(newton, rel=1e-2, abs=1e-2 * np.abs(newton).max())
    print(f"{name}: worst |a_mujoco - a_pinocchio| / scale = {worst:.2e}")


# ----- 4. the rollout tells an excessive torque from a gentle one -----


@pytest.mark.parametrize("mu", [0.5, 1.0])
@pytest.mark.parametrize("wheel_torque", [200.0, -200.0])
def test_excessive_wheel_torque_lifts_and_slips(paper, mu, wheel_torque):
    """Both wheels at +-200 N m (the paper robot's limit; asks 2 x 2.7 kN of traction from a 142 kg
    robot): within 20 ms casters lift (the reaction torque pitches the platform about the axle; it
    even hops off its wheels) and the wheels slip, spinning at tens of m/s at the rim."""
    robot, q, obj = paper
    referee = build(robot, q, support_points=PAPER_CASTERS, object=obj, mu=mu)
    tau = np.zeros(robot.nx)
    tau[:2] = wheel_torque
    report = referee.rollout(tau, duration=0.02)
    casters = [s.name for s in referee.supports if not s.driven]
    print(f"mu {mu}, {wheel_torque:+g} N m: lifted {report.lifted}, slipping {report.slipping}")
    assert set(report.lifted) & set(casters)
    assert report.slipping == list(robot.platform.drive_names)
    assert report.slip_speed[:, :2].max() > 1.0  # m/s: spinning, not creeping
    assert np.all(report.normal >= 0.0) and report.time[-1] == pytest.approx(0.02)


@pytest.mark.parametrize("mu", [0.5, 1.0])
def test_gentle_wheel_torque_rolls(paper, mu):
    """Both wheels at +1 N m: every support keeps contact for 20 ms, the wheels roll without
    slipping, and the floor pushes the robot forward with about 2 x 1 N m / r."""
    robot, q, obj = paper
    referee = build(robot, q, support_points=PAPER_CASTERS, object=obj, mu=mu)
    tau = np.zeros(robot.nx)
    tau[:2] = 1.0
    report = referee.rollout(tau, duration=0.02)
    assert report.lifted == [] and report.slipping == []
    assert report.slip_speed[:, :2].max() < 1e-9 and report.penetration.max() < 1e-9  # wheels m/s; m
    assert report.friction_use[:, :2].max() < 0.2
    assert 0.0 < report.base_position[-1, 0] - report.base_position[0, 0] < 1e-3  # moved forward, m
    traction = report.tangential[0, :2, 0].sum()  # the wheels' own inertia takes a few per cent
    assert 0.9 * 2.0 / 0.075 < traction < 2.0 / 0.075
    _, contacts = referee.forward(tau)
    assert sum(c.tangential[0] for c in contacts.values()) == pytest.approx(traction)


def test_support_off_the_floor_is_refused(paper):
    """A passive support that is not on the floor (here at the axle's height) is an error naming it."""
    robot, q, _ = paper
    with pytest.raises(mobmanip.MobmanipError, match="caster_high.*not on the floor"):
        build(robot, q, support_points={**PAPER_CASTERS, "caster_high": (0.25, 0.0, 0.0)})
