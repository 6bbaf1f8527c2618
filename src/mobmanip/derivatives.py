"""Configuration derivatives from Pinocchio: of the frame Jacobians, the mass matrix and gravity.

Every derivative here is taken in Pinocchio's tangent space: the derivative along tangent
direction k at q is d/de f(pin.integrate(model, q, e * e_k)) at e = 0. For the planar root
joint that is a motion of the platform in its own frame (v_x, v_y, omega_z); for a revolute or
continuous joint, its angle.

- Frame Jacobians: ``pin.getFrameKinematicHessian`` in ``LOCAL_WORLD_ALIGNED``. In ``pin`` 4.1
  the kinematic Hessian getters return (6, nv, nv) arrays whose memory is column-major while
  the array is flagged row-major; :func:`hessian_layout` detects which reading is right once,
  against central differences on Pinocchio's sample manipulator, so that a Pinocchio with the
  layout fixed keeps working.
- Mass matrix: M = sum_j J_j^T I_j J_j over the bodies, with J_j the joint Jacobian in the
  joint's own frame (``LOCAL``) and I_j the body's spatial inertia in that frame (constant), so
  dM/dq_k = sum_j (dJ_j/dq_k)^T I_j J_j + J_j^T I_j dJ_j/dq_k from the joints' local kinematic
  Hessians.
- Gravity: ``pin.computeGeneralizedGravityDerivatives``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .errors import ModelError
from .model import Robot
from .tasks import TaskSpace, get_task


@functools.cache
def hessian_layout() -> str:
    """How this Pinocchio's kinematic Hessian getters lay out their (6, nv, nv) result.

    Returns:
        ``"fortran"`` when the array's memory is column-major although it is flagged row-major
        (``pin`` 4.1), ``"c"`` when the array reads as it is flagged. Decided once, by comparing
        both readings of a frame's Hessian with central differences of its Jacobian on
        Pinocchio's sample manipulator.

    Raises:
        ModelError: neither reading matches the differences (an unknown Pinocchio behaviour).
    """
    model = pin.buildSampleModelManipulator()
    data = model.createData()
    frame = model.nframes - 1
    q = pin.neutral(model) + np.linspace(0.3, 1.1, model.nq)

    def jacobian(qq):
        pin.computeJointJacobians(model, data, qq)
        pin.updateFramePlacements(model, data)
        return pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED).copy()

    step = 1e-6
    diff = np.zeros((6, model.nv, model.nv))
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = step
        diff[:, :, k] = (jacobian(pin.integrate(model, q, e)) - jacobian(pin.integrate(model, q, -e))) / (2 * step)
    jacobian(q)
    pin.computeJointKinematicHessians(model, data)
    raw = pin.getFrameKinematicHessian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
    scale = max(float(np.abs(diff).max()), 1.0)
    for name, H in (("c", np.array(raw)), ("fortran", _fortran(raw))):
        if np.abs(H - diff).max() <= 1e-6 * scale:
            return name
    raise ModelError("this Pinocchio's kinematic Hessian matches neither known memory layout")


def _fortran(H: np.ndarray) -> np.ndarray:
    """The (6, nv, nv) array whose column-major memory ``H`` holds while flagged row-major."""
    return np.asarray(H).ravel("C").reshape(H.shape, order="F")


def read_hessian(H: np.ndarray) -> np.ndarray:
    """A kinematic Hessian as returned by Pinocchio, read in the layout :func:`hessian_layout`
    found: (6, nv, nv) with ``[:, i, k]`` = d(column i of the Jacobian)/dq_k."""
    return _fortran(H) if hessian_layout() == "fortran" else np.array(H)


def frame_jacobian_derivative(model: pin.Model, data: pin.Data, frame_id: int) -> np.ndarray:
    """dJ/dq of a frame's ``LOCAL_WORLD_ALIGNED`` Jacobian, (6, nv, nv): ``[:, i, k]`` is the
    derivative of column i along tangent direction k.

    Needs ``pin.computeJointJacobians``, ``pin.updateFramePlacements`` and
    ``pin.computeJointKinematicHessians`` at the configuration first.
    """
    return read_hessian(pin.getFrameKinematicHessian(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED))


@dataclass(frozen=True)
class ConfigurationDerivatives:
    """Kinematic and dynamic terms at one configuration with their tangent-space derivatives.

    Derivative arrays put the tangent direction k first.

    Attributes:
        J: end-effector Jacobians restricted to the task rows, stacked arm by arm, (m k_a, nv).
        dJ: dJ/dq_k, (nv, m k_a, nv).
        positions: end-effector positions in the world (m), (k_a, 3).
        J_linear: the end effectors' linear Jacobians (all three rows), (k_a, 3, nv).
        M: mass matrix, (nv, nv).
        dM: dM/dq_k, (nv, nv, nv).
        g: generalized gravity, (nv,).
        dg: dg/dq_k, (nv, nv) (row k).
    """

    J: np.ndarray
    dJ: np.ndarray
    positions: np.ndarray
    J_linear: np.ndarray
    M: np.ndarray
    dM: np.ndarray
    g: np.ndarray
    dg: np.ndarray


class DerivativeWorkspace:
    """What stays constant between configurations of one robot and task: frame and joint
    indices, the bodies' spatial inertias. Reuses ``robot.data`` (not thread-safe)."""

    def __init__(self, robot: Robot, task: str | TaskSpace):
        self.robot = robot
        self.task = get_task(task)
        model = robot.model
        self.rows = list(self.task.rows)
        self.frames = [arm.frame_id for arm in robot.arms]
        self.joints = [j for j in range(1, model.njoints) if model.inertias[j].mass > 0.0 or _has_inertia(model, j)]
        self.inertias = np.array([model.inertias[j].matrix() for j in self.joints])  # (nb, 6, 6)

    def evaluate(self, q: np.ndarray) -> ConfigurationDerivatives:
        """The terms and their derivatives at configuration q, (nq,)."""
        model, data = self.robot.model, self.robot.data
        nv = model.nv
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        pin.computeJointKinematicHessians(model, data)
        J6 = np.array([pin.getFrameJacobian(model, data, f, pin.LOCAL_WORLD_ALIGNED) for f in self.frames])
        H6 = np.array([frame_jacobian_derivative(model, data, f) for f in self.frames])  # (ka, 6, nv, nv)
        positions = np.array([data.oMf[f].translation for f in self.frames])
        J = J6[:, self.rows].reshape(-1, nv)
        dJ = np.moveaxis(H6[:, self.rows].reshape(-1, nv, nv), 2, 0)
        # mass matrix and its derivative from the bodies' local Jacobians and Hessians
        nb = len(self.joints)
        Jl = np.empty((nb, 6, nv))
        Hl = np.empty((nb, 6, nv, nv))
        for b, j in enumerate(self.joints):
            Jl[b] = pin.getJointJacobian(model, data, j, pin.LOCAL)
            Hl[b] = read_hessian(pin.getJointKinematicHessian(model, data, j, pin.LOCAL))
        IJ = np.einsum("bxy,byi->bxi", self.inertias, Jl)  # (nb, 6, nv)
        M = np.einsum("bxi,bxj->ij", Jl, IJ)
        # T[k, i, j] = sum_b (dJ_b/dq_k)^T_i I_b J_b,j
        T = np.tensordot(Hl, IJ, axes=([0, 1], [0, 1]))  # (nv_i, nv_k, nv_j)
        T = T.transpose(1, 0, 2)
        dM = T + T.transpose(0, 2, 1)
        g = pin.computeGeneralizedGravity(model, data, q).copy()
        dg = pin.computeGeneralizedGravityDerivatives(model, data, q).T.copy()
        return ConfigurationDerivatives(
            J=J, dJ=dJ, positions=positions, J_linear=J6[:, :3], M=0.5 * (M + M.T), dM=dM, g=g, dg=dg
        )


def _has_inertia(model: pin.Model, j: int) -> bool:
    return bool(np.any(model.inertias[j].matrix() != 0.0))
