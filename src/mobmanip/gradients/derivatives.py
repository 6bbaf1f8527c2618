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

from ..errors import ModelError
from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task


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
    """Kinematic and dynamic terms at N configurations with their tangent-space derivatives.

    Derivative arrays put the configuration first, then the tangent direction k.

    Attributes:
        J: end-effector Jacobians restricted to the task rows, stacked arm by arm, (N, m k_a, nv).
        dJ: dJ/dq_k, (N, nv, m k_a, nv).
        positions: end-effector positions in the world (m), (N, k_a, 3).
        J_linear: the end effectors' linear Jacobians (all three rows), (N, k_a, 3, nv).
        M: mass matrix, (N, nv, nv).
        dM: dM/dq_k, (N, nv, nv, nv).
        g: generalized gravity, (N, nv).
        dg: dg/dq_k, (N, nv, nv) (row k).
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
        self.joints = [j for j in range(1, model.njoints) if np.any(model.inertias[j].matrix() != 0.0)]
        self.inertias = np.array([model.inertias[j].matrix() for j in self.joints])  # (nb, 6, 6)

    def evaluate(self, qs: np.ndarray) -> ConfigurationDerivatives:
        """The terms and their derivatives at the configurations qs, (N, nq) (checked by the caller).

        Pinocchio runs once per configuration; everything else is stacked over N.
        """
        model, data = self.robot.model, self.robot.data
        nv = model.nv
        n, ka, nb = qs.shape[0], len(self.frames), len(self.joints)
        J6 = np.empty((n, ka, 6, nv))
        H6 = np.empty((n, ka, 6 * nv * nv))  # raw Hessian memory, read below
        positions = np.empty((n, ka, 3))
        Jl = np.empty((n, nb, 6, nv))
        Hl = np.empty((n, nb, 6 * nv * nv))
        g = np.empty((n, nv))
        dg = np.empty((n, nv, nv))
        frame_hessian, joint_hessian = pin.getFrameKinematicHessian, pin.getJointKinematicHessian
        lwa, local = pin.LOCAL_WORLD_ALIGNED, pin.LOCAL
        for i, q in enumerate(qs):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            pin.computeJointKinematicHessians(model, data)
            for a, f in enumerate(self.frames):
                J6[i, a] = pin.getFrameJacobian(model, data, f, lwa)
                H6[i, a] = frame_hessian(model, data, f, lwa).reshape(-1)
                positions[i, a] = data.oMf[f].translation
            for b, j in enumerate(self.joints):
                Jl[i, b] = pin.getJointJacobian(model, data, j, local)
                Hl[i, b] = joint_hessian(model, data, j, local).reshape(-1)
            g[i] = pin.computeGeneralizedGravity(model, data, q)
            dg[i] = pin.computeGeneralizedGravityDerivatives(model, data, q).T
        H6 = _read_stacked(H6, nv)  # (n, ka, 6, nv, nv)
        Hl = _read_stacked(Hl, nv)
        J = J6[:, :, self.rows].reshape(n, -1, nv)
        dJ = np.moveaxis(H6[:, :, self.rows].reshape(n, -1, nv, nv), 3, 1)
        # M = sum_b J_b^T I_b J_b; T[n, i, k, j] = sum_b (dJ_b/dq_k)_i^T I_b J_b,j
        IJ = np.einsum("bxy,nbyi->nbxi", self.inertias, Jl).reshape(n, nb * 6, nv)
        M = np.matmul(_T(Jl.reshape(n, nb * 6, nv)), IJ)
        T = np.matmul(_T(Hl.reshape(n, nb * 6, nv * nv)), IJ).reshape(n, nv, nv, nv)
        T = T.transpose(0, 2, 1, 3)
        dM = T + _T(T)
        return ConfigurationDerivatives(
            J=J, dJ=dJ, positions=positions, J_linear=J6[:, :, :3], M=0.5 * (M + _T(M)), dM=dM, g=g, dg=dg
        )


def _T(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def _read_stacked(raw: np.ndarray, nv: int) -> np.ndarray:
    """Hessians stored as their arrays' C-order contents, (..., 6 nv nv) -> (..., 6, nv, nv)."""
    if hessian_layout() == "fortran":  # element [x, i, k] at x + 6 i + 6 nv k
        return np.moveaxis(raw.reshape(raw.shape[:-1] + (nv, nv, 6)), (-3, -2, -1), (-1, -2, -3))
    return raw.reshape(raw.shape[:-1] + (6, nv, nv))
