"""Reduced dynamics (paper Eq. 12-16) and unified Jacobians, from Pinocchio.

With v = S x (S from the platform constraint layer), the whole robot's equations of motion
M vdot + h = B tau + A^T lambda project through S^T to

    P xdot = xi + Q tau - J_u^T h_ext,   P = S^T M S,  Q = S^T B,  xi = -S^T (h + M Sdot x).

M is the mass matrix of the whole robot (platform, wheels and arms in one tree), so P's platform
block includes the arms carried as load and its platform-arm blocks are the paper's interaction
terms R. In Pinocchio's tangent coordinates S is constant (Sdot = 0) for most platforms; a
platform whose S depends on q (a steered wheel) gives Sdot x through
:meth:`mobmanip.robot.model.Robot.null_space_rate`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task


@dataclass(frozen=True)
class ReducedDynamics:
    """The reduced dynamics at one configuration and reduced velocity.

    Attributes:
        P: reduced inertia S^T M S, (nx, nx), symmetric positive definite.
        Q: input matrix S^T B, (nx, nx); the identity for wheel and joint torques.
        xi: Coriolis, centrifugal and gravity terms -S^T (h + M Sdot x), (nx,).
        M: the whole robot's mass matrix, (nv, nv).
    """

    P: np.ndarray
    Q: np.ndarray
    xi: np.ndarray
    M: np.ndarray


@functools.cache
def _crba_fills_lower_triangle() -> bool:
    """Whether this Pinocchio's ``crba`` returns the full matrix (older releases fill only the upper part)."""
    model = pin.buildSampleModelManipulator()
    M = pin.crba(model, model.createData(), pin.neutral(model))
    return bool(np.allclose(M, M.T) and np.any(np.tril(M, -1) != 0.0))


def mass_matrix(robot: Robot, q: np.ndarray) -> np.ndarray:
    """The whole robot's joint-space mass matrix M(q), (nv, nv), from CRBA (full, symmetric)."""
    M = pin.crba(robot.model, robot.data, q)
    if _crba_fills_lower_triangle():
        return M.copy()
    return np.triu(M) + np.triu(M, 1).T


def decouple(robot: Robot, P: np.ndarray) -> np.ndarray:
    """P with the platform-arm blocks set to zero (the paper's Sec. 4.3 simplification).

    All diagonal blocks (platform, each arm) are kept as they are in the coupled P.
    """
    n_eta = robot.platform.n_reduced
    out = np.array(P, copy=True)
    out[:n_eta, n_eta:] = 0.0
    out[n_eta:, :n_eta] = 0.0
    return out


def reduced_dynamics(
    robot: Robot, q: np.ndarray, x: np.ndarray | None = None, decoupled: bool = False
) -> ReducedDynamics:
    """P, Q and xi at configuration q and reduced velocity x.

    Args:
        robot: the loaded robot.
        q: configuration, (nq,).
        x: reduced velocity, (nx,); ``None`` means at rest (then xi = -S^T g).
        decoupled: zero the platform-arm blocks of P (see :func:`decouple`).
    """
    return reduced_dynamics_unchecked(robot, robot.check_configuration(q), x, decoupled)


def reduced_dynamics_unchecked(robot: Robot, q: np.ndarray, x: np.ndarray | None, decoupled: bool) -> ReducedDynamics:
    S = robot.null_space(q)
    M = mass_matrix(robot, q)
    if x is None:
        h = pin.computeGeneralizedGravity(robot.model, robot.data, q)
        sdot_x = np.zeros(robot.model.nv)
    else:
        x = np.asarray(x, dtype=float)
        h = pin.nonLinearEffects(robot.model, robot.data, q, S @ x)
        sdot_x = robot.null_space_rate(q, x) @ x
    P = S.T @ M @ S
    P = 0.5 * (P + P.T)
    if decoupled:
        P = decouple(robot, P)
    return ReducedDynamics(P=P, Q=robot.Q, xi=-S.T @ (h + M @ sdot_x), M=M)


def frame_jacobians(robot: Robot, q: np.ndarray, task: str | TaskSpace) -> np.ndarray:
    """Stacked end-effector Jacobians in the task space, (m * n_arms, nv).

    Rows: each arm's end-effector velocity in spec order, in ``LOCAL_WORLD_ALIGNED``
    (origin at the end effector, world axes), restricted to the task's rows.
    """
    task = get_task(task)
    model, data = robot.model, robot.data
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    rows = list(task.rows)
    return np.vstack(
        [pin.getFrameJacobian(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED)[rows] for arm in robot.arms]
    )


def unified_jacobian(robot: Robot, q: np.ndarray, task: str | TaskSpace) -> np.ndarray:
    """J_u = J S: end-effector task velocities from reduced velocities, (m * n_arms, nx)."""
    q = robot.check_configuration(q)
    return frame_jacobians(robot, q, task) @ robot.null_space(q)


def end_effector_positions(robot: Robot, q: np.ndarray) -> np.ndarray:
    """World positions of the end effectors, (n_arms, 3)."""
    pin.framesForwardKinematics(robot.model, robot.data, robot.check_configuration(q))
    return placed_end_effectors(robot)


def placed_end_effectors(robot: Robot) -> np.ndarray:
    """End-effector positions from ``robot.data`` as last updated (FK or Jacobians), (n_arms, 3)."""
    return np.array([robot.data.oMf[arm.frame_id].translation for arm in robot.arms])
