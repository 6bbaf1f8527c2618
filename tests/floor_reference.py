"""An independent reference for grounded capacity: the whole robot on the floor, from Pinocchio.

The robot is rebuilt from its URDF with a free-flyer root; every joint that mobmanip's own model
does not have is locked at the spec's ``[reference]`` value (zero when not listed). The base sits
at mobmanip's planar pose with its root frame at z = 0 and no roll or pitch. Its 6-dof velocity
(linear, angular; both in the base frame) is restricted to mobmanip's reduced velocities x by
S_f, mobmanip's own null space S(q) with the vertical, roll and pitch rows held at zero.

At rest, with gravity 9.81 m/s^2 along -z (or leaning, on a ramp: ``build_problem(gravity=)``),
the unknowns are the reduced accelerations xdot, the reduced efforts tau (one per entry of x: Q
= I), the contact forces, the wrenches h the hands apply ON the object (task rows) and the
object's acceleration a_o, related by::

    M_f S_f xdot + g_f = B tau + sum_c J_c^T lambda_c - J_hands^T h     (whole robot)
    J_hands S_f xdot = W^T a_o                                           (rigid grasp)
    W h = M_o a_o + g_o                                                  (object, g_o = +m g up)

The force problems (:func:`force_support`, :func:`force_straight_line`) hold robot and object
still (xdot = 0, a_o = 0) and ask for the wrench f the object exerts ON the environment, which
pushes back with -f: the object's equation becomes ``W h = g_o + f`` (f in the a_o columns).

A driven wheel's contact force is (f_x, f_y, f_z) in world axes; a caster's is a normal force
only (frictionless). The hands apply the task's wrench rows only (a translational task's hands
no moments; a planar task's object is not carried vertically), unless the object is held level
(``build_problem(level=True)``): then the hands' wrench components on the vertical, roll and
pitch rows the task leaves out are extra unknowns, the object is balanced on them (``sum f_z =
m g``, no roll or pitch moment about its centre), the robot feels their reaction, and the hands'
accelerations on those rows lie within ``level_tolerance`` of zero; two hands share that load with
no squeeze on those rows (their level wrenches orthogonal to the null space of their grasp map).
Nothing here uses mobmanip's reduced terms (P, Q, xi), grasp matrix
or polytopes: only its model's joint names, reference values, null space S(q) and limits.
"""

from __future__ import annotations

import functools
import math
import re
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.linalg import null_space
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

GRAVITY = 9.81
"""Magnitude of gravity (m/s^2), along world -z."""

TASK_ROWS = {"planar": (0, 1), "planar_rigid": (0, 1, 5), "translational": (0, 1, 2), "spatial": (0, 1, 2, 3, 4, 5)}
"""Rows of a 6-d twist or wrench (linear then angular, world axes) that each task keeps."""

LEVEL_ROWS = (2, 3, 4)
"""The object's vertical force, roll and pitch moment rows: balanced when it is held level."""

MODES = ("ideal", "no_tip", "friction")

_HIGHS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


@dataclass(frozen=True)
class SupportPoint:
    """A point where the robot touches the floor.

    Attributes:
        name: a label (the wheel's joint or the caster's link).
        joint: the joint of the body the point belongs to: the wheel's joint for a driven wheel
            (the rim's material point), the root joint for a caster (its swivel is not modelled).
        point: the contact point in the platform's root frame (m), (3,).
        driven: a wheel (3 force components) or a caster (normal force only).
        free: a roller's free-rolling direction in the platform's root frame (unit (2,)): the
            contact pushes nothing along it; ``None``: none.
    """

    name: str
    joint: str
    point: np.ndarray
    driven: bool
    free: tuple[float, float] | None = None


@dataclass(frozen=True)
class FloorProblem:
    """The equations of the robot on the floor at one configuration (SI units).

    Shapes: m task rows, k hands, nv free-flyer tangent size, nx reduced velocities, nc contacts,
    r = the rows of :data:`LEVEL_ROWS` that the task leaves out.

    Attributes:
        M: mass matrix of the free-flyer model, (nv, nv).
        g: generalized gravity, (nv,).
        S: the null space S_f, (nv, nx).
        B: actuation, (nv, nx): reduced efforts -> joint torques, S^T B = I.
        contacts: the support points: driven wheels, then casters.
        points: their world positions (m), (nc, 3).
        contact_jacobians: LOCAL_WORLD_ALIGNED translational Jacobians of the points, (nc, 3, nv).
        hand_jacobian: the hands' LOCAL_WORLD_ALIGNED Jacobians on the task rows, stacked, (k m, nv).
        W: grasp matrix from the hand positions and the object centre, (m, k m).
        M_o: object inertia on the task rows, (m, m).
        g_o: the wrench that holds the object still on the task rows (+m g along z), (m,).
        level_jacobian: the hands' Jacobians on the omitted level rows, stacked, (k r, nv).
        level_grasp: the object's level rows of the grasp map, of h and of the level wrenches,
            ((r, k m), (r, k r)); they must sum to ``level_load``.
        level_load: the object's weight on the omitted level rows, (r,).
        tau_max: effort limits of x, (nx,).
        total_mass: robot (free-flyer model) plus object (kg).
        gravity: gravity in the floor's axes (m/s^2), (3,); leaning on a ramp.
        level_tolerance: held level: |level_jacobian S xdot| <= this (m/s^2, rad/s^2).
        heading: the base's heading (rad from world +x): a friction pyramid's first face points
            along it (the pyramid turns with the robot).
        floor_efforts: the entries of tau that are the floor's traction (an omnidirectional
            base's): S^T sum_c J_c^T lambda_c equals them, and is zero on every other entry (the
            floor's forces do no work along the platform's motions: a rolling wheel's do none
            by themselves; a skid-steer's sideways forces do none along its turn in the ideal
            mode, and on the floor hold it from turning, see :func:`_floor_work`).
        wheel_joints: the joints whose contacts are wheels in the model (they roll, and on the
            floor do not slide).
        level_rows: the rows of (f, n) held level (of 2, 3, 4: vertical, roll, pitch).
        parallel_wheels: the wheels all roll along the platform's x (a differential drive's or
            skid-steer's): with springs, their sideways forces are those of equal tyres under a
            rigid platform, k (s + theta x_c) (x_c along the heading).
    """

    M: np.ndarray
    g: np.ndarray
    S: np.ndarray
    B: np.ndarray
    contacts: tuple[SupportPoint, ...]
    points: np.ndarray
    contact_jacobians: np.ndarray
    hand_jacobian: np.ndarray
    W: np.ndarray
    M_o: np.ndarray
    g_o: np.ndarray
    level_jacobian: np.ndarray
    level_grasp: tuple[np.ndarray, np.ndarray]
    level_load: np.ndarray
    tau_max: np.ndarray
    total_mass: float
    gravity: np.ndarray
    level_tolerance: float = 0.0
    heading: float = 0.0
    floor_efforts: tuple[int, ...] = ()
    wheel_joints: tuple[str, ...] = ()
    parallel_wheels: bool = False
    level_rows: tuple[int, ...] = ()


@dataclass(frozen=True)
class FloorSolution:
    """A maximiser (or an equilibrium) of a floor LP.

    Attributes:
        value: the optimum: e.a_o (support, m/s^2 or rad/s^2) or s (straight-line reach); in the
            force problems e.f or s (N, N m).
        a_o: object acceleration, (m,); in the force problems the wrench f on the environment.
        xdot: reduced accelerations, (nx,).
        tau: reduced efforts (N m or N), (nx,).
        h: the hands' wrenches on the object, task rows, (k m,).
        h_level: the hands' wrenches on the object, omitted level rows, (k r,).
        forces: contact forces in world axes (N), (nc, 3); a caster's has only z.
        zmp: the zero-moment point on the floor plane (m), (3,).
        sensitivities: HiGHS's own multipliers, as the optimum's growth per unit by which a limit
            is relaxed (from scipy's ``marginals`` of the minimised -value): ``"tau_upper"`` and
            ``"tau_lower"`` (nx,) per N m (or N) more of each effort limit, on its + and - side;
            ``"normal"`` (nc,) per N by which a contact's normal force may go below its least;
            ``"friction"`` (nc, faces) per N by which each face row of a driven wheel's pyramid
            may be exceeded (zeros for a caster).
    """

    value: float
    a_o: np.ndarray
    xdot: np.ndarray
    tau: np.ndarray
    h: np.ndarray
    h_level: np.ndarray
    forces: np.ndarray
    zmp: np.ndarray
    sensitivities: dict | None = None


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


@functools.cache  # one URDF parse per robot object (a Robot hashes by identity)
def free_flyer_model(robot) -> pin.Model:
    """The robot's URDF with a free-flyer root, locked to exactly mobmanip's joints (shared: read only).

    Joints absent from ``robot.model`` are locked at the spec's ``[reference]`` values (zero if
    unlisted), as mobmanip locks them; the result has the same joints in the same order. Leftovers
    of xacro's ``$(optenv NAME DEFAULT)`` (Clearpath's Husky has one) are read as their default.
    """
    text = re.sub(r"\$\(optenv\s+\S+\s+([^)]*)\)", r"\1", Path(robot.spec.urdf).read_text())
    return locked_to(robot, pin.buildModelFromXML(text, pin.JointModelFreeFlyer()))


def locked_to(robot, full: pin.Model) -> pin.Model:
    """``full`` (a free-flyer model of the robot's file) with the joints ``robot.model`` lacks
    locked at the spec's ``[reference]`` values (zero if unlisted)."""
    q_ref = pin.neutral(full)
    for j in range(2, full.njoints):
        joint, value = full.joints[j], robot.spec.reference.get(full.names[j], 0.0)
        if joint.nq == 2:  # continuous joint: (cos, sin)
            q_ref[joint.idx_q : joint.idx_q + 2] = (math.cos(value), math.sin(value))
        else:
            q_ref[joint.idx_q] = value
    locked = [j for j in range(2, full.njoints) if full.names[j] not in set(robot.model.names[2:])]
    return pin.buildReducedModel(full, locked, q_ref) if locked else full


def free_flyer_configuration(robot, model: pin.Model, q: np.ndarray) -> np.ndarray:
    """mobmanip's q (planar root: x, y, cos, sin) as the free-flyer model's, root frame at z = 0."""
    q_f = pin.neutral(model)
    yaw = math.atan2(q[3], q[2])
    q_f[:7] = (q[0], q[1], 0.0, 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    for j in range(2, robot.model.njoints):
        src, dst = robot.model.joints[j], model.joints[model.getJointId(robot.model.names[j])]
        q_f[dst.idx_q : dst.idx_q + dst.nq] = q[src.idx_q : src.idx_q + src.nq]
    return q_f


def free_flyer_null_space(robot, model: pin.Model, q: np.ndarray) -> np.ndarray:
    """S_f, (nv_f, nx): mobmanip's S(q) in the free-flyer tangent space.

    Planar rows (v_x, v_y, omega_z, platform frame) go to the free-flyer's v_x, v_y and omega_z
    (base frame, the same frame at zero roll and pitch); v_z, omega_x, omega_y rows are zero.
    """
    S = robot.null_space(q)
    S_f = np.zeros((model.nv, S.shape[1]))
    S_f[[0, 1, 5]] = S[:3]
    for j in range(2, robot.model.njoints):
        src, dst = robot.model.joints[j], model.joints[model.getJointId(robot.model.names[j])]
        S_f[dst.idx_v : dst.idx_v + dst.nv] = S[src.idx_v : src.idx_v + src.nv]
    return S_f


def _reference_frames(robot) -> tuple[pin.Model, pin.Data]:
    """The free-flyer model with its frames placed at the neutral configuration (base at the origin)."""
    model = free_flyer_model(robot)
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    return model, data


def urdf_casters(robot) -> tuple[SupportPoint, ...]:
    """Casters found in the URDF: links named ``*caster*`` with a sphere or cylinder collision.

    The contact lies below the link's origin (the caster wheel's centre) by the collision radius,
    with the caster joints at their locked reference (zero).
    """
    model, data = _reference_frames(robot)
    out = []
    for link in ElementTree.parse(robot.spec.urdf).getroot().iter("link"):
        name = link.get("name", "")
        shape = link.find("collision/geometry/sphere")
        shape = link.find("collision/geometry/cylinder") if shape is None else shape
        if "caster" in name and shape is not None:
            centre = data.oMf[model.getFrameId(name)].translation
            point = centre - np.array([0.0, 0.0, float(shape.get("radius"))])
            out.append(SupportPoint(name, model.names[1], point, driven=False))
    return tuple(out)


def corner_casters(half_length: float, half_width: float, floor_z: float) -> tuple[SupportPoint, ...]:
    """Four casters at (+-half_length, +-half_width, floor_z) in the platform frame (m)."""
    return tuple(
        SupportPoint(f"caster_{fb}_{lr}", "root_joint", np.array([sx * half_length, sy * half_width, floor_z]), False)
        for fb, sx in (("front", 1.0), ("back", -1.0))
        for lr, sy in (("left", 1.0), ("right", -1.0))
    )


PAPER_CASTERS = corner_casters(0.25, 0.14, -0.075)
"""The paper robot's passive supports: its base box's corners, on the floor 0.075 m below base_link."""


def driven_wheels(robot) -> tuple[SupportPoint, ...]:
    """One contact per wheel of the platform (driven or free-rolling: each has a force along the
    floor), below the wheel's centre by its radius."""
    model, data = _reference_frames(robot)
    return tuple(
        SupportPoint(name, name, data.oMi[model.getJointId(name)].translation - np.array([0.0, 0.0, r]), driven=True)
        for name, r in robot.platform.wheels()
    )


def actuated_joints(robot) -> list[list[str]]:
    """Per reduced velocity, the joints its effort turns, by the platform kind's own mechanism:
    a differential drive's wheel; a skid-steer side's wheels (sharing its effort equally); a
    steered base's drive wheel, then its steering joint (the rear wheels roll free); nothing for an
    omnidirectional base (the floor's traction moves it); an arm or torso joint itself."""
    kind, wheels = robot.platform.kind, robot.spec.wheels
    if kind == "differential_drive":
        platform = [[wheels.right], [wheels.left]]
    elif kind == "skid_steer":
        platform = [list(wheels.right), list(wheels.left)]
    elif kind == "steered":
        platform = [[wheels.drive], [wheels.steer]]
    elif kind == "omnidirectional":
        platform = [[], [], []]
    else:
        raise ValueError(f"no floor reference for a {kind} platform")
    return platform + [[name] for name in robot.reduced_velocity_names[len(platform) :]]


def build_problem(
    robot, q, task: str, held_object, casters=None, gravity=None, level=False, level_tolerance=0.01
) -> FloorProblem:
    """Assemble the floor equations at mobmanip's configuration ``q``, robot and object at rest.

    Args:
        robot: a loaded mobmanip robot with a differential-drive platform.
        q: mobmanip configuration, (nq,).
        task: a key of :data:`TASK_ROWS`.
        held_object: the object; its ``mass`` (kg), ``inertia`` ((3, 3) kg m^2, about its centre,
            world axes) and ``center`` ((3,) m) are read.
        casters: passive supports; default :func:`urdf_casters`.
        gravity: gravity in the floor's axes (m/s^2), (3,); default straight down (a level floor).
        level: hold the object level (see the module's docstring); ``level_tolerance`` its band.
    """
    model = free_flyer_model(robot)
    gravity = np.array([0.0, 0.0, -GRAVITY]) if gravity is None else np.asarray(gravity, dtype=float)
    if not np.array_equal(gravity, [0.0, 0.0, -GRAVITY]):
        model = pin.Model(model)  # a ramp: Pinocchio's own generalized gravity, with gravity leaning
        model.gravity.linear = gravity
    data = model.createData()
    q_f = free_flyer_configuration(robot, model, q)
    S = free_flyer_null_space(robot, model, q)
    # Entry k of tau turns the joints actuated_joints gives, with the sign of their rows of S (a
    # positive wheel effort drives forward, as a positive wheel rate does), shared so that
    # S^T B = I; an omnidirectional base's efforts are the floor's traction (floor_efforts).
    B = np.zeros_like(S)
    floor_efforts = []
    for k, joints in enumerate(actuated_joints(robot)):
        rows = [model.joints[model.getJointId(name)].idx_v for name in joints]
        if not rows:
            floor_efforts.append(k)
            continue
        B[rows, k] = S[rows, k] / float(np.sum(S[rows, k] ** 2))
    M = pin.crba(model, data, q_f)
    M = np.triu(M) + np.triu(M, 1).T
    g = pin.computeGeneralizedGravity(model, data, q_f).copy()
    pin.computeJointJacobians(model, data, q_f)
    pin.updateFramePlacements(model, data)

    contacts = driven_wheels(robot) + (urdf_casters(robot) if casters is None else tuple(casters))
    points, jacobians = [], []
    for c in contacts:  # the point's velocity: v_joint + omega x (point - joint origin)
        point, jid = data.oMi[1].act(np.asarray(c.point, dtype=float)), model.getJointId(c.joint)
        J = pin.getJointJacobian(model, data, jid, pin.LOCAL_WORLD_ALIGNED)
        jacobians.append(J[:3] - _skew(point - data.oMi[jid].translation) @ J[3:])
        points.append(point)

    rows = list(TASK_ROWS[task])
    level = [r for r in LEVEL_ROWS if r not in rows] if level else []
    center = np.asarray(held_object.center, dtype=float)
    hands, grasps = [], []  # per hand: 6-row Jacobian and 6x6 grasp block (force; moment = r x f + n)
    for arm in robot.arms:
        fid = model.getFrameId(arm.end_effector)
        hands.append(pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED))
        grasps.append(np.block([[np.eye(3), np.zeros((3, 3))], [_skew(data.oMf[fid].translation - center), np.eye(3)]]))
    M6 = np.zeros((6, 6))
    M6[:3, :3] = held_object.mass * np.eye(3)
    M6[3:, 3:] = held_object.inertia
    g6 = np.r_[-held_object.mass * gravity, 0.0, 0.0, 0.0]  # the wrench that holds the object still
    return FloorProblem(
        M=M,
        g=g,
        S=S,
        B=B,
        contacts=contacts,
        points=np.array(points),
        contact_jacobians=np.array(jacobians),
        hand_jacobian=np.vstack([J[rows] for J in hands]),
        W=np.hstack([G[np.ix_(rows, rows)] for G in grasps]),
        M_o=M6[np.ix_(rows, rows)],
        g_o=g6[rows],
        level_jacobian=np.vstack([J[level] for J in hands]),
        level_grasp=(
            np.hstack([G[np.ix_(level, rows)] for G in grasps]),
            np.hstack([G[np.ix_(level, level)] for G in grasps]),
        ),
        level_load=g6[level],
        tau_max=np.asarray(robot.effort_limits, dtype=float),
        total_mass=pin.computeTotalMass(model) + held_object.mass,
        gravity=gravity,
        level_tolerance=level_tolerance,
        heading=float(math.atan2(data.oMi[1].rotation[1, 0], data.oMi[1].rotation[0, 0])),
        floor_efforts=tuple(floor_efforts),
        wheel_joints=tuple(c.joint for c in contacts if c.joint != model.names[1]),
        parallel_wheels=robot.platform.kind in ("differential_drive", "skid_steer"),
        level_rows=tuple(level),
    )


def contact_force_columns(problem: FloorProblem) -> tuple[np.ndarray, list[slice]]:
    """The contact forces' generalized forces, (nv, n_lambda), and each contact's columns.

    A driven wheel has 3 columns (world f_x, f_y, f_z), a caster 1 (its normal, world z).
    """
    columns, slices, start = [], [], 0
    for contact, J in zip(problem.contacts, problem.contact_jacobians):
        columns.append(J.T if contact.driven else J[2:3].T)
        slices.append(slice(start, start + columns[-1].shape[1]))
        start = slices[-1].stop
    return np.hstack(columns), slices


def _floor_work(P: FloorProblem, C: np.ndarray, slices: list[slice], equation, slide: bool = True) -> None:
    """The floor's forces along the platform's motions: S^T C lambda = tau on the floor's own
    efforts, 0 elsewhere; and a roller pushes nothing along its free direction.

    ``slide=False`` (on the floor, where no wheel slides): the contacts on wheel joints do not
    slide along the floor, C_t^T S xdot = 0 (for a rolling wheel that holds for every xdot; a
    skid-steer's turn slides its wheels sideways, so it is held at zero), and the forces that
    hold them do work along those motions: the work rows hold only on the motions left free,
    N^T (S^T C lambda - tau_floor) = 0 with N spanning {xdot : C_t^T S xdot = 0}."""
    nx = P.S.shape[1]
    select = np.zeros((nx, nx))
    select[list(P.floor_efforts), list(P.floor_efforts)] = 1.0
    free = np.eye(nx)
    if not slide:
        wheel_rows = [
            C[:, sl.start + i]
            for contact, sl in zip(P.contacts, slices)
            if contact.driven and contact.joint in P.wheel_joints
            for i in (0, 1)
        ]
        if wheel_rows:
            A = np.array(wheel_rows) @ P.S  # the wheels' contact points' velocities along the floor
            _, sigma, vt = np.linalg.svd(A)
            rank = int(np.sum(sigma > 1e-9))  # m/s per unit reduced velocity: exactly 0 when rolling
            if rank:
                equation([("xdot", vt[:rank])], np.zeros(rank))
                free = vt[rank:].T
    equation([("lambda", free.T @ P.S.T @ C), ("tau", -free.T @ select)], np.zeros(free.shape[1]))
    c, s = math.cos(P.heading), math.sin(P.heading)
    for contact, sl in zip(P.contacts, slices):
        if contact.free is not None:
            row = np.zeros((1, C.shape[1]))
            fx, fy = contact.free
            row[0, sl.start : sl.start + 2] = (c * fx - s * fy, s * fx + c * fy)
            equation([("lambda", row)], np.zeros(1))


def _band(P: FloorProblem) -> np.ndarray:
    """The hands' level-band rows over xdot: vertical as they are, roll and pitch about the
    platform's forward and left axes (the band is a square in those; in the world's axes it would
    not turn with the robot)."""
    rows = P.level_jacobian @ P.S
    level = list(P.level_rows)
    if 3 in level and 4 in level:
        c, s = math.cos(P.heading), math.sin(P.heading)
        for start in range(0, len(rows), len(level)):
            roll, pitch = start + level.index(3), start + level.index(4)
            rows[[roll, pitch]] = c * rows[roll] + s * rows[pitch], -s * rows[roll] + c * rows[pitch]
    return rows


def _spring_rows(
    P: FloorProblem, slices: list[slice], stiffness, forces: int, springs: int, n: int
) -> list[np.ndarray]:
    """Contacts as springs under a rigid platform, rows over the LP's n variables (forces start at
    column ``forces``, the spring variables (a, b, c, s, theta) at ``springs``): each normal force
    is k_c (a + b x_c + c y_c) (the platform sinks and tilts); with parallel wheels, each wheel's
    sideways force (across the heading) is k_c (s + theta x_c), x_c along the heading (the
    platform shifts sideways and turns on its tyres)."""
    c, s = math.cos(P.heading), math.sin(P.heading)
    out = []
    for contact, sl, p, k in zip(P.contacts, slices, P.points, stiffness):
        row = np.zeros(n)
        row[forces + sl.stop - 1] = 1.0
        row[springs : springs + 3] = -k, -k * p[0], -k * p[1]
        out.append(row)
        if P.parallel_wheels and contact.driven and contact.joint in P.wheel_joints:
            row = np.zeros(n)
            row[forces + sl.start : forces + sl.start + 2] = -s, c
            row[springs + 3 : springs + 5] = -k, -k * (c * p[0] + s * p[1])
            out.append(row)
    return out


def zero_moment_point(points: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Where the contact forces' resultant has no horizontal moment, on the floor plane.

    Args:
        points: contact points (m), (nc, 3), all at one height z0.
        forces: contact forces (N), (nc, 3).

    Returns:
        The ZMP (m), (3,), at height z0.
    """
    z0 = float(points[0, 2])
    if np.ptp(points[:, 2]) > 1e-9:
        raise ValueError(f"contact points are not on one floor plane: heights {points[:, 2]}")
    F, Mo = forces.sum(axis=0), np.cross(points, forces).sum(axis=0)  # moment about the world origin
    if F[2] <= 0.0:  # nothing presses on the floor: the robot is lifting off, no point has it
        return np.full(3, np.nan)
    return np.array([(z0 * F[0] - Mo[1]) / F[2], (Mo[0] + z0 * F[1]) / F[2], z0])


def support_polygon(points: np.ndarray) -> np.ndarray:
    """The convex hull of the contact points on the floor, counter-clockwise vertices (m), (k, 2)."""
    xy = np.asarray(points)[:, :2]
    return xy[ConvexHull(xy).vertices]


def polygon_margin(polygon: np.ndarray, p) -> float:
    """Signed distance (m) from p (its x, y) to a CCW convex polygon's boundary: positive inside."""
    p = np.asarray(p, dtype=float)[:2]
    distance, inside = math.inf, True
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0)):
        edge = b - a
        t = np.clip(np.dot(p - a, edge) / np.dot(edge, edge), 0.0, 1.0)
        distance = min(distance, float(np.linalg.norm(p - a - t * edge)))
        inside &= bool(edge[0] * (p[1] - a[1]) - edge[1] * (p[0] - a[0]) >= 0.0)  # left of the edge
    return distance if inside else -distance


def support(
    problem: FloorProblem, e, mode="ideal", mu=None, faces=8, policy=False, springs=False, reserve=0.0
) -> FloorSolution:
    """max e.a_o over the grounded set (other components free), with a maximiser.

    Args:
        problem: from :func:`build_problem`.
        e: unit task direction, (m,).
        mode: ``"ideal"`` (contact forces free), ``"no_tip"`` (normal forces >= 0) or
            ``"friction"`` (normals >= 0 and each driven wheel's tangential force inside the
            ``faces``-sided pyramid inscribed in the cone of coefficient ``mu``).
        policy: the paper's minimum-norm policy (xdot = J_u^+ W^T a_o, h = W^+ (M_o a_o + g_o));
            tau and the contact forces stay free within their constraints.
        springs: the contacts share the weight as springs under a rigid base: each normal force
            is k (a + b x + c y) at the contact's floor position (x, y), with a, b, c three more
            unknowns and k the contact's stiffness: 1 for ``True``, else the array's entries (in
            the problem's contact order); with parallel wheels their sideways forces too (see
            :func:`_spring_rows`). ``False``: any sharing that balances the robot.
        reserve: a fraction r: every normal force at least r (robot + object weight) / (number of
            contacts), every driven wheel's pyramid shrunk to 1 - r of its size.
    """
    e = np.asarray(e, dtype=float)
    objective = np.append(-e, 0.0)
    return _solve(problem, mode, mu, faces, policy, objective=objective, springs=springs, reserve=reserve)


def straight_line(
    problem: FloorProblem, e, mode="ideal", mu=None, faces=8, policy=False, springs=False, reserve=0.0
) -> FloorSolution:
    """max s such that a_o = s e is in the grounded set (arguments as :func:`support`)."""
    e = np.asarray(e, dtype=float)
    objective = np.append(np.zeros_like(e), -1.0)
    return _solve(problem, mode, mu, faces, policy, objective=objective, line=e, springs=springs, reserve=reserve)


def force_support(problem: FloorProblem, e, mode="ideal", mu=None, faces=8, springs=False) -> FloorSolution:
    """max e.f over the wrenches f the object exerts on the environment, robot and object at rest
    (modes as :func:`support`; the solution's ``a_o`` holds f)."""
    e = np.asarray(e, dtype=float)
    return _solve(problem, mode, mu, faces, False, objective=np.append(-e, 0.0), force=True, springs=springs)


def force_straight_line(problem: FloorProblem, e, mode="ideal", mu=None, faces=8, springs=False) -> FloorSolution:
    """max s such that the object exerts f = s e on the environment at rest (as :func:`force_support`)."""
    e = np.asarray(e, dtype=float)
    objective = np.append(np.zeros_like(e), -1.0)
    return _solve(problem, mode, mu, faces, False, objective=objective, line=e, force=True, springs=springs)


def equilibrium(problem: FloorProblem, mode="no_tip", mu=None, faces=8, springs=False) -> FloorSolution:
    """Robot and object held still (xdot = 0, a_o = 0): one feasible set of efforts and forces."""
    objective = np.zeros(problem.W.shape[0] + 1)
    return _solve(problem, mode, mu, faces, False, objective=objective, still=True, springs=springs)


def _solve(
    P: FloorProblem,
    mode,
    mu,
    faces,
    policy,
    objective,
    line=None,
    still=False,
    force=False,
    springs=False,
    reserve=0.0,
) -> FloorSolution:
    """The LP over z = [xdot, tau, lambda, h, h_level, a_o, s, (a, b, c)]; ``objective``: the cost of (a_o, s).
    ``force``: at rest, the a_o columns hold the wrench f on the environment (W h = g_o + f)."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if mode == "friction" and (mu is None or mu < 0):
        raise ValueError(f"friction mode needs mu >= 0, got {mu!r}")
    nx = P.S.shape[1]
    C, slices = contact_force_columns(P)
    m, km = P.W.shape
    offsets = np.cumsum([0, nx, nx, C.shape[1], km, P.level_jacobian.shape[0], m, 1, 0 if springs is False else 5])
    X, T, L, H, V, A, S_, D = (slice(offsets[i], offsets[i + 1]) for i in range(8))
    n = int(offsets[-1])
    rows, rhs = [], []

    def equation(blocks, value):
        row = np.zeros((len(value), n))
        for where, block in blocks:
            row[:, where] = block
        rows.append(row)
        rhs.append(np.asarray(value, dtype=float))

    equation([(X, P.M @ P.S), (T, -P.B), (L, -C), (H, P.hand_jacobian.T), (V, P.level_jacobian.T)], -P.g)
    _floor_work(
        P,
        C,
        slices,
        lambda parts, value: equation([({"tau": T, "lambda": L, "xdot": X}[w], b) for w, b in parts], value),
        slide=mode == "ideal",
    )
    equation([(H, P.level_grasp[0]), (V, P.level_grasp[1])], P.level_load)  # the object held level
    squeeze = null_space(P.level_grasp[1]).T  # ... by the hands' minimum-norm share (no squeeze)
    equation([(V, squeeze)], np.zeros(len(squeeze)))
    if force:  # at rest; the environment pushes back with -f
        equation([(X, np.eye(nx))], np.zeros(nx))
        equation([(H, P.W), (A, -np.eye(m))], P.g_o)
    elif policy:  # with J_u and W of full row rank, the grasp and object equations follow
        J_u, W_pinv = P.hand_jacobian @ P.S, np.linalg.pinv(P.W)
        if np.linalg.matrix_rank(J_u) < km or np.linalg.matrix_rank(P.W) < m:
            raise ValueError("the minimum-norm policy needs J_u and W of full row rank (a singular posture)")
        equation([(X, np.eye(nx)), (A, -np.linalg.pinv(J_u) @ P.W.T)], np.zeros(nx))
        equation([(H, np.eye(km)), (A, -W_pinv @ P.M_o)], W_pinv @ P.g_o)
    else:
        equation([(X, P.hand_jacobian @ P.S), (A, -P.W.T)], np.zeros(km))
        equation([(H, P.W), (A, -P.M_o)], P.g_o)
    if line is not None:
        equation([(A, np.eye(m)), (S_, -line[:, None])], np.zeros(m))
    if still:
        equation([(X, np.eye(nx))], np.zeros(nx))
        equation([(A, np.eye(m))], np.zeros(m))
    if springs is not False:  # normal_c - k_c (a + b x_c + c y_c) = 0; sideways_c - k_c (s + theta x_c) = 0
        stiffness = np.ones(len(P.points)) if springs is True else np.asarray(springs, dtype=float)
        for row in _spring_rows(P, slices, stiffness, L.start, D.start, n):
            rows.append(row[None, :])
            rhs.append(np.zeros(1))

    bounds, cone = [(None, None)] * n, (mu or 0.0) * math.cos(math.pi / faces) * (1.0 - reserve)
    least = reserve * P.total_mass * -P.gravity[2] / len(P.contacts)
    bounds[T] = [(-limit, limit) for limit in P.tau_max]
    A_ub, pyramid_rows = [], []  # pyramid_rows: (contact, face) of each pyramid row of A_ub
    for c, (contact, sl) in enumerate(zip(P.contacts, slices)):
        if mode != "ideal":
            bounds[L.start + sl.stop - 1] = (least, None)  # the normal is the last (z) component
        if contact.driven and mode == "friction":  # face k: (cos, sin) . f_t <= mu cos(pi / N) f_n
            for k, angle in enumerate(P.heading + 2.0 * math.pi * np.arange(faces) / faces):
                A_ub.append(np.zeros(n))
                A_ub[-1][L.start + sl.start : L.start + sl.stop] = (math.cos(angle), math.sin(angle), -cone)
                pyramid_rows.append((c, k))
    b_ub = [0.0] * len(A_ub)
    for row in np.vstack([_band(P), -_band(P)]):  # the level band
        A_ub.append(np.zeros(n))
        A_ub[-1][X] = row
        b_ub.append(P.level_tolerance)
    cost = np.zeros(n)
    cost[A], cost[S_] = objective[:m], objective[m]
    result = _linprog(cost, A_ub, rows, rhs, bounds, f"floor LP ({mode})", b_ub)
    z = result.x
    forces = np.zeros((len(P.contacts), 3))
    for i, sl in enumerate(slices):
        forces[i, 3 - (sl.stop - sl.start) :] = z[L][sl]
    friction = np.zeros((len(P.contacts), faces))
    for (c, k), marginal in zip(pyramid_rows, result.ineqlin.marginals if A_ub else ()):
        friction[c, k] = -marginal
    sensitivities = {  # scipy's marginals are d(min -value)/d(bound): signs turned to growth of the value
        "tau_upper": -result.upper.marginals[T],
        "tau_lower": result.lower.marginals[T],
        "normal": np.array([result.lower.marginals[L.start + sl.stop - 1] for sl in slices]),
        "friction": friction,
    }
    return FloorSolution(
        value=float(-result.fun),
        a_o=z[A].copy(),
        xdot=z[X].copy(),
        tau=z[T].copy(),
        h=z[H].copy(),
        h_level=z[V].copy(),
        forces=forces,
        zmp=zero_moment_point(P.points, forces),
        sensitivities=sensitivities,
    )


def team_straight_line(
    problems: list[FloorProblem], e, mode="ideal", mu=None, faces=8, springs=False, reserve=0.0, start=None
) -> float:
    """max s such that the object's acceleration ``start + s e`` is reachable by a team: several
    robots, each on its own floor with its own efforts and contact forces (one :func:`build_problem`
    per robot, all with the one object), holding one object. Each robot's whole-body equation and
    grasp kinematics are its own; the object's equations sum the wrenches of every robot's hands
    (task rows and omitted level rows alike). ``start`` (default: rest, the origin) is where the
    line starts; ``mode``, ``mu``, ``faces``, ``springs`` (``True``: equally stiff) and ``reserve``
    as in :func:`support`, for every robot."""
    e = np.asarray(e, dtype=float)
    start = np.zeros_like(e) if start is None else np.asarray(start, dtype=float)
    program = _team_program(problems, mode, mu, faces, springs, reserve)
    A, S_, n = program["A"], program["S"], program["n"]
    row = np.zeros((len(e), n))
    row[:, A], row[:, S_] = np.eye(len(e)), -e[:, None]
    cost = np.zeros(n)
    cost[S_] = -1.0
    return float(-_team_solve(program, cost, row, start, mode).fun)


def team_support(problems: list[FloorProblem], e, mode="ideal", mu=None, faces=8, springs=False, reserve=0.0) -> float:
    """max e.a_o over the object's accelerations the team reaches (arguments as
    :func:`team_straight_line`)."""
    e = np.asarray(e, dtype=float)
    program = _team_program(problems, mode, mu, faces, springs, reserve)
    cost = np.zeros(program["n"])
    cost[program["A"]] = -e
    return float(-_team_solve(program, cost, np.zeros((0, program["n"])), np.zeros(0), mode).fun)


def team_ray_radius(
    problems: list[FloorProblem], e, mode="ideal", mu=None, faces=8, springs=False, reserve=0.0
) -> float:
    """The largest t >= 0 with ``c + t e / |e|`` reachable by the team, c the centre of the box
    that bounds its accelerations along the task axes: per axis the midpoint of the supports along
    it and against it (arguments as :func:`team_straight_line`)."""
    e = np.asarray(e, dtype=float)
    options = {"mode": mode, "mu": mu, "faces": faces, "springs": springs, "reserve": reserve}
    axes = np.eye(len(e))
    centre = np.array([0.5 * (team_support(problems, u, **options) - team_support(problems, -u, **options))
                       for u in axes])  # fmt: skip
    return team_straight_line(problems, e / np.linalg.norm(e), start=centre, **options)


def _team_program(problems: list[FloorProblem], mode, mu, faces, springs, reserve) -> dict:
    """The team's LP without its objective: its equations, inequalities and bounds over z =
    [per robot (xdot, tau, lambda, h, h_level, springs), a_o, s], and where a_o and s are."""
    m = problems[0].W.shape[0]
    blocks = []  # per robot: (xdot, tau, lambda, h, h_level, springs) slices
    start = 0
    for P in problems:
        nx = P.S.shape[1]
        C, slices = contact_force_columns(P)
        sizes = [nx, nx, C.shape[1], P.W.shape[1], P.level_jacobian.shape[0], 0 if springs is False else 5]
        at = np.cumsum([start, *sizes])
        blocks.append((C, slices, [slice(at[i], at[i + 1]) for i in range(6)]))
        start = int(at[-1])
    A, S_ = slice(start, start + m), slice(start + m, start + m + 1)
    n = start + m + 1
    rows, rhs = [], []

    def equation(parts, value):
        row = np.zeros((len(value), n))
        for where, block in parts:
            row[:, where] += block
        rows.append(row)
        rhs.append(np.asarray(value, dtype=float))

    bounds = [(None, None)] * n
    A_ub: list[np.ndarray] = []
    cone = (mu or 0.0) * math.cos(math.pi / faces) * (1.0 - reserve)
    for P, (C, slices, (X, T, L, H, V, D)) in zip(problems, blocks):
        equation([(X, P.M @ P.S), (T, -P.B), (L, -C), (H, P.hand_jacobian.T), (V, P.level_jacobian.T)], -P.g)
        _floor_work(P, C, slices, lambda parts, value, X=X, T=T, L=L: equation(
            [({"tau": T, "lambda": L, "xdot": X}[w], b) for w, b in parts], value), slide=mode == "ideal")  # fmt: skip
        equation([(X, P.hand_jacobian @ P.S), (A, -P.W.T)], np.zeros(P.W.shape[1]))  # its hands move with it
        squeeze = null_space(P.level_grasp[1]).T  # its hands share the level load without a squeeze
        equation([(V, squeeze)], np.zeros(len(squeeze)))
        if springs is not False:
            for row in _spring_rows(P, slices, np.ones(len(P.points)), L.start, D.start, n):
                rows.append(row[None, :])
                rhs.append(np.zeros(1))
        bounds[T] = [(-limit, limit) for limit in P.tau_max]
        least = reserve * P.total_mass * -P.gravity[2] / len(P.contacts)
        for contact, sl in zip(P.contacts, slices):
            if mode != "ideal":
                bounds[L.start + sl.stop - 1] = (least, None)
            if contact.driven and mode == "friction":
                for angle in P.heading + 2.0 * math.pi * np.arange(faces) / faces:
                    A_ub.append(np.zeros(n))
                    A_ub[-1][L.start + sl.start : L.start + sl.stop] = (math.cos(angle), math.sin(angle), -cone)
    b_ub = [0.0] * len(A_ub)
    for P, (_, _, (X, *_)) in zip(problems, blocks):
        for row in np.vstack([_band(P), -_band(P)]):  # the level band
            A_ub.append(np.zeros(n))
            A_ub[-1][X] = row
            b_ub.append(P.level_tolerance)
    first = problems[0]
    # the one object: every robot's hands together, on the task rows and on the level rows
    equation([(H, P.W) for P, (_, _, (_, _, _, H, _, _)) in zip(problems, blocks)] + [(A, -first.M_o)], first.g_o)
    equation(
        [(H, P.level_grasp[0]) for P, (_, _, (_, _, _, H, _, _)) in zip(problems, blocks)]
        + [(V, P.level_grasp[1]) for P, (_, _, (_, _, _, _, V, _)) in zip(problems, blocks)],
        first.level_load,
    )
    return {"rows": rows, "rhs": rhs, "A_ub": A_ub, "b_ub": b_ub, "bounds": bounds, "A": A, "S": S_, "n": n}


def _team_solve(program: dict, cost: np.ndarray, extra: np.ndarray, value: np.ndarray, mode: str):
    """HiGHS on the team's program with ``cost`` and the equations ``extra z = value`` added."""
    rows, rhs = [*program["rows"], extra], [*program["rhs"], value]
    return _linprog(cost, program["A_ub"], rows, rhs, program["bounds"], f"team floor LP ({mode})", program["b_ub"])


def _linprog(cost, A_ub: list, rows: list, rhs: list, bounds: list, what: str, b_ub: list):
    """HiGHS on min cost.z, A_ub z <= b_ub (the pyramids' and level band's rows), the stacked
    equations, the bounds."""
    result = linprog(
        cost,
        A_ub=np.array(A_ub) if A_ub else None,
        b_ub=np.array(b_ub) if A_ub else None,
        A_eq=np.vstack(rows),
        b_eq=np.concatenate(rhs),
        bounds=bounds,
        method="highs",
        options=_HIGHS,
    )
    if result.status != 0:
        raise RuntimeError(f"{what} failed: {result.message}")
    return result


def ramp_gravity(ramp) -> np.ndarray:
    """Gravity in the axes of a ramp ``(slope, uphill)`` (degrees), m/s^2, (3,), from first
    principles and not from the floor under test (shared by the ramp references: a gravity leaning
    the wrong way in the code must not lean the reference alike): the ramp is the level floor
    turned by its slope s about the horizontal axis u x z, u the uphill direction (cos a, sin a,
    0), so that u rises (to u cos s + z sin s); the world's gravity (0, 0, -9.81) seen in the
    turned axes is R^T g, R from Rodrigues' formula."""
    s, a = np.radians(ramp[0]), np.radians(ramp[1])
    u, z = np.array([np.cos(a), np.sin(a), 0.0]), np.array([0.0, 0.0, 1.0])
    k = np.cross(u, z)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    R = np.eye(3) + np.sin(s) * K + (1.0 - np.cos(s)) * K @ K
    np.testing.assert_allclose(R @ u, np.cos(s) * u + np.sin(s) * z, atol=1e-15)  # uphill rises
    return R.T @ np.array([0.0, 0.0, -9.81])
