"""A path's efforts and floor wrench at every sample, affine in (s'', s'^2), stacked.

Along a path q(s) run with a timing s(t), the reduced velocities and accelerations are
``x = x_s s'`` and ``xdot = x_s s'' + x_ss s'^2``. Every quantity the retiming keeps is then
``coefficient_a s'' + coefficient_b s'^2 + coefficient_0``:

- the efforts of the paper's policy with the held object (as
  :meth:`mobmanip.motion.in_motion.MotionTerms.torques`), from the recursive Newton-Euler
  algorithm: ``Q tau = S^T f + J_u^T W^+ w_o`` with the joint-space forces
  ``f = M qdd + C(q, v) v + g`` and the object's wrench ``w_o = M_o a_o + c_o + g_o``;
- the floor's resultant wrench on the robot and its object (as
  :func:`mobmanip.motion.ground.floor_wrench`), from the centroidal momentum's rate.

Only Pinocchio runs per sample (a few passes each); the algebra runs once on the stacks, so a
200-sample path costs a few milliseconds more than Pinocchio's passes. This is the same
mathematics as :func:`mobmanip.motion.in_motion.motion_terms` and ``floor_wrench`` by a
second route (Newton-Euler here, the reduced P and xi there); the tests hold the two together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..engine.stacked_linalg import cross3
from ..robot.model import Robot
from ..robot.tasks import TaskSpace
from ..support.progress import progress_bar
from ..terms.constraints.floor import weight_lean
from ..terms.grasp import GRAVITY, checked_object_mass
from .trajectory import Trajectory


@dataclass(frozen=True)
class PathTerms:
    """Per-sample coefficients over (a, b) = (s'', s'^2), stacked over the N samples.

    Attributes:
        effort_a, effort_b, effort_0: the wheel and joint efforts tau = effort_a a + effort_b b +
            effort_0 (N m or N), (N, nx) each; effort_0 holds gravity.
        wrench_a, wrench_b, wrench_0: the floor's resultant wrench [force; moment about the world
            origin] (world axes) likewise, (N, 6) each, wrench_0 the weight alone; ``None``
            unless asked for.
    """

    effort_a: np.ndarray
    effort_b: np.ndarray
    effort_0: np.ndarray
    wrench_a: np.ndarray | None = None
    wrench_b: np.ndarray | None = None
    wrench_0: np.ndarray | None = None


def _skews(r: np.ndarray) -> np.ndarray:
    """skew(r) for each 3-vector of r (..., 3): (..., 3, 3)."""
    out = np.zeros(r.shape + (3,))
    out[..., 0, 1], out[..., 0, 2] = -r[..., 2], r[..., 1]
    out[..., 1, 0], out[..., 1, 2] = r[..., 2], -r[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -r[..., 1], r[..., 0]
    return out


def _grasp_blocks(task: TaskSpace, lower: np.ndarray, identity: bool) -> np.ndarray:
    """[W_1 W_2 ...] with W_i = [[I, 0], [skew(lower_i), I]] (``identity``) or [[0, 0],
    [skew(lower_i), 0]], restricted to the task: (N, m, m k) for lower (N, k, 3)."""
    n, k = lower.shape[:2]
    full = np.zeros((n, k, 6, 6))
    if identity:
        full[:, :, range(6), range(6)] = 1.0
    full[:, :, 3:, :3] = _skews(lower)
    rows = list(task.rows)
    kept = full[:, :, rows][:, :, :, rows]  # (N, k, m, m)
    return np.concatenate(list(np.moveaxis(kept, 1, 0)), axis=2)


def path_terms(
    robot: Robot,
    trajectory: Trajectory,
    task: TaskSpace,
    object_mass: float,
    *,
    wrench: bool = False,
    progress: bool = False,
    gravity: np.ndarray | None = None,
) -> PathTerms:
    """The efforts (and, with ``wrench``, the floor's wrench) at every sample of ``trajectory``'s
    path, over (s'', s'^2) (see the module's docstring). The object is held between the hands as
    :meth:`mobmanip.terms.grasp.HeldObject.between` makes it (a sphere reaching the farthest hand).
    ``gravity``: gravity in the floor's axes, (3,) m/s^2, default straight down; on a ramp
    (:meth:`mobmanip.motion.carry_floor.CarryFloor.gravity`) the weights of robot and object lean
    in the efforts and in the floor's wrench alike.
    """
    g = np.asarray(GRAVITY if gravity is None else gravity, dtype=float)
    leans = gravity is not None and bool(np.any(g != np.asarray(GRAVITY, dtype=float)))
    model, data = robot.model, robot.data
    mass_o = checked_object_mass(object_mass)
    n, nv, nx, k = len(trajectory), model.nv, robot.nx, len(robot.arms)
    rows = list(task.rows)
    m = len(rows)
    frames = [arm.frame_id for arm in robot.arms]
    zero = np.zeros(nv)
    S = np.empty((n, nv, nx))
    force_a, force_b, gravity = np.empty((n, nv)), np.empty((n, nv)), np.empty((n, nv))
    J = np.empty((n, k * m, nv))
    hands, hand_velocity, drift = np.empty((n, k, 3)), np.empty((n, k, 3)), np.empty((n, k * m))
    if wrench:
        A_G, momentum_0, com = np.empty((n, 6, nv)), np.empty((n, 6)), np.empty((n, 3))
    with progress_bar(n, desc=f"path terms {robot.name}", unit="point", show=progress) as bar:
        for i in range(n):
            bar.update(1)
            q, x_s, x_ss = trajectory.q[i], trajectory.x[i], trajectory.xdot[i]
            S_i = robot.null_space(q)
            S[i] = S_i
            v = S_i @ x_s
            turning = robot.null_space_rate(q, x_s) @ x_s  # qdd at s'' = 0, s' = 1: Sdot x_s
            gravity[i] = pin.computeGeneralizedGravity(model, data, q)
            force_a[i] = pin.rnea(model, data, q, zero, v) - gravity[i]
            force_b[i] = pin.rnea(model, data, q, v, S_i @ x_ss + turning) - gravity[i]
            if leans:  # the ramp's lean of g(q) (the efforts that hold the robot still there)
                gravity[i] += weight_lean(robot, q, g)
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            for a, frame in enumerate(frames):
                J[i, a * m : (a + 1) * m] = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)[rows]
                hands[i, a] = data.oMf[frame].translation
            pin.forwardKinematics(model, data, q, v, turning)
            for a, frame in enumerate(frames):
                acceleration = pin.getFrameClassicalAcceleration(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
                drift[i, a * m : (a + 1) * m] = acceleration.vector[rows]
                hand_velocity[i, a] = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED).linear
            if wrench:
                A_G[i] = pin.computeCentroidalMap(model, data, q)
                dA_G = pin.computeCentroidalMapTimeVariation(model, data, q, v)
                com[i] = data.com[0]
                momentum_0[i] = A_G[i] @ turning + dA_G @ v  # the momentum's rate at s'' = 0, s' = 1
    x_s, x_ss = trajectory.x, trajectory.xdot
    J_u = J @ S  # (N, m k, nx)

    # the object between the hands, its grasps and their rates (HeldObject.between, grasp_matrix_rate)
    center = hands.mean(axis=1)
    offsets = hands - center[:, None]
    radius2 = np.einsum("nki,nki->nk", offsets, offsets).max(axis=1)
    inertia = 0.4 * mass_o * radius2[:, None, None] * np.eye(3)  # (N, 3, 3)
    W = _grasp_blocks(task, offsets, identity=True)  # (N, m, m k)
    W_pinv = np.linalg.pinv(W)  # (N, m k, m)
    to_object = np.swapaxes(W_pinv, 1, 2)  # (W^T)^+
    v_o = np.einsum("nij,nj->ni", to_object, np.einsum("nij,nj->ni", J_u, x_s))
    omega = np.zeros((n, 3))
    for i, r in enumerate(rows):
        if r >= 3:
            omega[:, r - 3] = v_o[:, i]
    W_rate = _grasp_blocks(task, hand_velocity - hand_velocity.mean(axis=1, keepdims=True), identity=False)
    grasp_drift = np.einsum("nji,nj->ni", W_rate, v_o)
    M_o_full = np.zeros((n, 6, 6))
    M_o_full[:, range(3), range(3)] = mass_o
    M_o_full[:, 3:, 3:] = inertia
    M_o = M_o_full[:, rows][:, :, rows]
    spin = np.zeros((n, 6))
    spin[:, 3:] = cross3(omega, np.einsum("nij,nj->ni", inertia, omega))
    g_o = np.zeros(6)
    g_o[:3] = -mass_o * g

    # the object's acceleration a_o = acc_a a + acc_b b, and its wrench
    acc_a = np.einsum("nij,nj->ni", to_object, np.einsum("nij,nj->ni", J_u, x_s))
    acc_b = np.einsum("nij,nj->ni", to_object, np.einsum("nij,nj->ni", J_u, x_ss) + drift - grasp_drift)
    hands_to_joints = np.swapaxes(J_u, 1, 2) @ W_pinv  # (N, nx, m)
    St = np.swapaxes(S, 1, 2)

    def joints(force: np.ndarray, wrench_o: np.ndarray) -> np.ndarray:
        rhs = np.einsum("nij,nj->ni", St, force) + np.einsum("nij,nj->ni", hands_to_joints, wrench_o)
        return np.linalg.solve(robot.Q, rhs.T).T

    effort_a = joints(force_a, np.einsum("nij,nj->ni", M_o, acc_a))
    effort_b = joints(force_b, np.einsum("nij,nj->ni", M_o, acc_b) + spin[:, rows])
    effort_0 = joints(gravity, np.broadcast_to(g_o[rows], (n, m)))
    if not wrench:
        return PathTerms(effort_a, effort_b, effort_0)

    # the floor's wrench: the robot's momentum rate and the object's, less the weight of both
    full_a, full_b = np.zeros((n, 6)), np.zeros((n, 6))
    full_a[:, rows], full_b[:, rows] = acc_a, acc_b
    mass = float(pin.computeTotalMass(model))
    rate_a = np.einsum("nij,nj->ni", A_G @ S, x_s)  # momentum rate per s'' (about the centre of mass)
    rate_b = np.einsum("nij,nj->ni", A_G @ S, x_ss) + momentum_0

    def about_origin(rate: np.ndarray, object_part: np.ndarray) -> np.ndarray:
        out = np.empty((n, 6))
        out[:, :3] = rate[:, :3] + mass_o * object_part[:, :3]
        out[:, 3:] = rate[:, 3:] + cross3(com, rate[:, :3]) + mass_o * cross3(center, object_part[:, :3])
        if mass_o > 0.0:
            out[:, 3:] += np.einsum("nij,nj->ni", inertia, object_part[:, 3:])
        return out

    wrench_b = about_origin(rate_b, full_b)
    wrench_b[:, 3:] += spin[:, 3:]  # the object's w x I w: zero for the sphere, kept for any inertia
    weight = np.empty((n, 6))
    weight[:, :3] = -(mass + mass_o) * g
    weight[:, 3:] = -(cross3(com, mass * g) + cross3(center, mass_o * g))
    return PathTerms(effort_a, effort_b, effort_0, about_origin(rate_a, full_a), wrench_b, weight)
