"""Capacity in motion: the dynamic measure of a moving robot and a moving held object.

At rest (:mod:`mobmanip.analysis`) the torques that give the object an acceleration a_o are
``tau = Lambda_o a_o + mu_o`` with mu_o the torques that hold robot and object still. In motion,
with reduced velocity x (joint rates v = S x), four velocity terms join mu_o:

- Coriolis and centrifugal forces of the robot, ``-S^T (h(q, v) - g(q))`` (RNEA at v), and
  ``-S^T M Sdot x`` for a platform whose S depends on q: both inside xi(q, x) of
  :func:`mobmanip.terms.dynamics.reduced_dynamics`;
- the hands' drift ``d/dt(J_u) x = Jdot S x + J Sdot x``: the hands' task accelerations are
  ``J_u xdot + d/dt(J_u) x`` (Pinocchio's classical frame acceleration, world-aligned axes);
- a moving grasp: the hands move as ``W^T v_o``, so their accelerations are
  ``W^T a_o + Wdot^T v_o`` (for a rotating object the grasp points' centripetal accelerations);
- the object's own gyroscopic wrench ``c_o = [0; w x I w]`` on its angular rows.

With the paper's policy (joint accelerations ``xdot = J_u^+ (W^T a_o + Wdot^T v_o - d/dt(J_u) x)``,
hand forces ``W^+ (M_o a_o + c_o + g_o)``), the torques are ``Lambda_o a_o + mu_o(q, x)`` with the
same Lambda_o as at rest and

    mu_o(q, x) = Q^-1 [-xi(q, x) + P J_u^+ (Wdot^T v_o - d/dt(J_u) x) + J_u^T W^+ (c_o + g_o)].

The in-motion dynamic ellipsoid ``{a_o : ||Z (Lambda_o a_o + mu_o(q, x))|| <= 1}`` is therefore
the at-rest construction of :func:`mobmanip.sets.ellipsoid.dynamic_ellipsoid` with xi replaced by
``xi_eff = xi(q, x) - P J_u^+ (Wdot^T v_o - d/dt(J_u) x)`` and g_o by ``g_o + c_o``. At x = 0 every
velocity term vanishes and the result is the at-rest ellipsoid. The kinematic ellipsoid (the
velocities the limits allow) does not depend on x.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..engine.stacked_linalg import cross3
from ..errors import ConfigurationError, TaskError
from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task
from ..sets.ellipsoid import Ellipsoid, dynamic_ellipsoid, kinematic_ellipsoid
from ..terms.constraints.floor import weight_lean
from ..terms.dynamics import decouple, frame_jacobians, placed_end_effectors, reduced_dynamics_unchecked
from ..terms.grasp import HeldObject, checked_object_mass, object_mass_of, skew


@dataclass(frozen=True)
class MotionTerms:
    """Every term of the dynamic measure at one configuration and reduced velocity.

    Attributes:
        q: configuration, (nq,).
        x: reduced velocity, (nx,).
        task: the task space.
        S: null-space matrix S(q), (nv, nx).
        J_u: unified Jacobian J S, (m k, nx).
        drift: the hands' task accelerations at xdot = 0, d/dt(J_u) x, (m k,) (m/s^2, rad/s^2).
        P: reduced inertia (decoupled if asked), (nx, nx).
        Q: input matrix, (nx, nx).
        xi: -S^T (h(q, S x) + M Sdot x): Coriolis, centrifugal and gravity terms, (nx,).
        xi_rest: -S^T g(q), the gravity part of xi, (nx,).
        held_object: the object (centre, grasp offsets, mass, inertia).
        W: grasp matrix, (m, m k).
        W_rate: its time derivative along the motion, (m, m k).
        v_o: object velocity (W^T)^+ J_u x, (m,).
        M_o: object inertia in the task, (m, m).
        c_o: object's velocity wrench [0; w x I w] on the task rows, (m,).
        g_o: wrench that holds the object against gravity, (m,).
        velocity_limits, effort_limits: (nx,) each.
    """

    q: np.ndarray
    x: np.ndarray
    task: TaskSpace
    S: np.ndarray
    J_u: np.ndarray
    drift: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    xi: np.ndarray
    xi_rest: np.ndarray
    held_object: HeldObject
    W: np.ndarray
    W_rate: np.ndarray
    v_o: np.ndarray
    M_o: np.ndarray
    c_o: np.ndarray
    g_o: np.ndarray
    velocity_limits: np.ndarray
    effort_limits: np.ndarray

    @property
    def grasp_drift(self) -> np.ndarray:
        """Wdot^T v_o: the hands' accelerations due to the grasp's motion, (m k,)."""
        return self.W_rate.T @ self.v_o

    @property
    def xi_effective(self) -> np.ndarray:
        """xi(q, x) - P J_u^+ (Wdot^T v_o - d/dt(J_u) x): the bias the at-rest formulas take, (nx,)."""
        return self.xi - self.P @ (np.linalg.pinv(self.J_u) @ (self.grasp_drift - self.drift))

    @cached_property
    def W_pinv(self) -> np.ndarray:
        """W^+, (m k, m): computed once (the effort map and the floor's rows take it and its
        transpose, ``pinv(W^T) = pinv(W)^T``)."""
        return np.linalg.pinv(self.W)

    def joint_accelerations(self, a_o: np.ndarray) -> np.ndarray:
        """The paper's policy: xdot = J_u^+ (W^T a_o + Wdot^T v_o - d/dt(J_u) x), (nx,)."""
        a_o = np.asarray(a_o, dtype=float)
        return np.linalg.pinv(self.J_u) @ (self.W.T @ a_o + self.grasp_drift - self.drift)

    def object_acceleration(self, xdot: np.ndarray) -> np.ndarray:
        """a_o from the reduced accelerations: (W^T)^+ (J_u xdot + d/dt(J_u) x - Wdot^T v_o), (m,)."""
        hands = self.J_u @ np.asarray(xdot, dtype=float) + self.drift - self.grasp_drift
        return np.linalg.lstsq(self.W.T, hands, rcond=None)[0]

    def torques(self, xdot: np.ndarray, a_o: np.ndarray | None = None) -> np.ndarray:
        """Wheel and joint efforts tau for reduced accelerations xdot, (nx,).

        ``Q tau = P xdot - xi(q, x) + J_u^T W^+ (M_o a_o + c_o + g_o)``; a_o defaults to the object
        acceleration the hands give (:meth:`object_acceleration`).
        """
        xdot = np.asarray(xdot, dtype=float)
        a_o = self.object_acceleration(xdot) if a_o is None else np.asarray(a_o, dtype=float)
        wrench = self.M_o @ a_o + self.c_o + self.g_o
        return np.linalg.solve(self.Q, self.P @ xdot - self.xi + self.J_u.T @ (self.W_pinv @ wrench))

    def effort_map(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`torques` with the object's acceleration the hands give, as ``L @ xdot + bias``:
        (L (nx, nx), bias (nx,)), the bias holding gravity and every velocity term."""
        to_object = self.W_pinv.T
        hands_to_joints = self.J_u.T @ self.W_pinv
        L = np.linalg.solve(self.Q, self.P + hands_to_joints @ (self.M_o @ (to_object @ self.J_u)))
        wrench = self.M_o @ (to_object @ (self.drift - self.grasp_drift)) + self.c_o + self.g_o
        return L, np.linalg.solve(self.Q, -self.xi + hands_to_joints @ wrench)

    def static_torques(self) -> np.ndarray:
        """The part of :meth:`torques` that does not scale with the speed: gravity, (nx,)."""
        return np.linalg.solve(self.Q, -self.xi_rest + self.J_u.T @ (self.W_pinv @ self.g_o))

    def kinematic(self) -> Ellipsoid:
        """The kinematic ellipsoid (m/s, rad/s); the same as at rest."""
        return kinematic_ellipsoid(self.J_u, self.W, self.velocity_limits)

    def dynamic(self) -> Ellipsoid:
        """The dynamic ellipsoid of object accelerations in motion (m/s^2, rad/s^2)."""
        return dynamic_ellipsoid(
            self.J_u, self.W, self.P, self.Q, self.xi_effective, self.M_o, self.c_o + self.g_o, self.effort_limits
        )


def motion_terms(
    robot: Robot,
    q: np.ndarray,
    x: np.ndarray,
    task: str | TaskSpace | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
    gravity: np.ndarray | None = None,
) -> MotionTerms:
    """The terms of the measures at configuration q moving with reduced velocity x.

    Args:
        robot: the loaded robot.
        q: configuration, (nq,).
        x: reduced velocity, (nx,) (wheel rad/s, joint rad/s or m/s).
        task, object_mass, held_object, decoupled: as :func:`mobmanip.analysis.analyze`. The
            default object sits between the hands, its grasp offsets moving with them; an
            explicit object's offsets turn with the object's angular velocity.
        gravity: gravity in the floor's axes (m/s^2), (3,); default straight down. On a ramp
            (:meth:`mobmanip.motion.carry_floor.CarryFloor.gravity`) the world's axes are the
            ramp's and the weights of robot and object lean: xi, xi_rest and g_o take the lean.

    Raises:
        ConfigurationError: q or x of the wrong size or not finite.
        TaskError: a bad mass or an object without one grasp per arm.
    """
    q = robot.check_configuration(q)
    x = check_reduced_velocity(robot, x)
    task = get_task(task or robot.spec.default_task)
    if held_object is not None and held_object.offsets.shape != (len(robot.arms), 3):
        raise TaskError(
            f"the object needs one grasp offset per arm ({len(robot.arms)}), got {held_object.offsets.shape}"
        )
    if held_object is None:
        mass = object_mass_of(robot, object_mass)
        checked_object_mass(mass)
    dyn = reduced_dynamics_unchecked(robot, q, x, False)
    P = decouple(robot, dyn.P) if decoupled else dyn.P
    model, data = robot.model, robot.data
    g = pin.computeGeneralizedGravity(model, data, q)
    S = robot.null_space(q)
    v = S @ x
    a0 = robot.null_space_rate(q, x) @ x  # joint accelerations at xdot = 0
    J_u = frame_jacobians(robot, q, task) @ S
    positions = placed_end_effectors(robot)
    pin.forwardKinematics(model, data, q, v, a0)
    rows = list(task.rows)
    drift, hand_linear = [], []
    for arm in robot.arms:
        drift.append(pin.getFrameClassicalAcceleration(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED).vector[rows])
        hand_linear.append(pin.getFrameVelocity(model, data, arm.frame_id, pin.LOCAL_WORLD_ALIGNED).linear)
    drift = np.concatenate(drift)
    hand_linear = np.array(hand_linear)
    obj = held_object if held_object is not None else HeldObject.between(positions, float(mass))
    W = obj.grasp_matrix(task)
    lean = np.zeros(model.nv) if gravity is None else weight_lean(robot, q, gravity)  # a ramp's, in g(q)
    v_o = np.linalg.lstsq(W.T, J_u @ x, rcond=None)[0]
    omega = np.zeros(3)
    for i, r in enumerate(task.rows):
        if r >= 3:
            omega[r - 3] = v_o[i]
    if held_object is None:
        offset_rates = hand_linear - hand_linear.mean(axis=0)
    else:
        offset_rates = cross3(omega, obj.offsets)
    W_rate = grasp_matrix_rate(task, offset_rates)
    inertia = obj.inertia
    c_full = np.zeros(6)
    c_full[3:] = cross3(omega, inertia @ omega)
    return MotionTerms(
        q=q,
        x=x,
        task=task,
        S=S,
        J_u=J_u,
        drift=drift,
        P=P,
        Q=robot.Q,
        xi=dyn.xi - S.T @ lean,
        xi_rest=-S.T @ (g + lean),
        held_object=obj,
        W=W,
        W_rate=W_rate,
        v_o=v_o,
        M_o=obj.inertia_matrix(task),
        c_o=c_full[task.index],
        g_o=obj.gravity_vector(task) if gravity is None else obj.gravity_vector(task, gravity),
        velocity_limits=np.asarray(robot.velocity_limits, dtype=float),
        effort_limits=np.asarray(robot.effort_limits, dtype=float),
    )


def grasp_matrix_rate(task: str | TaskSpace, offset_rates: np.ndarray) -> np.ndarray:
    """dW/dt for grasp offsets changing at ``offset_rates`` (k, 3) (m/s), (m, m k).

    Each W_i = [[I, 0], [skew(r_i), I]] restricted to the task, so dW_i/dt = [[0, 0], [skew(dr_i/dt), 0]].
    Zero for tasks without rotation (their W is constant).
    """
    task = get_task(task)
    rates = np.atleast_2d(np.asarray(offset_rates, dtype=float))
    blocks = []
    for rate in rates:
        full = np.zeros((6, 6))
        full[3:, :3] = skew(rate)
        blocks.append(task.restrict(full))
    return np.hstack(blocks)


def check_reduced_velocity(robot: Robot, x: ArrayLike) -> np.ndarray:
    """x as a float array of shape (nx,), finite.

    Raises:
        ConfigurationError: wrong shape or a NaN/infinite entry (named).
    """
    try:
        x = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ConfigurationError(f"reduced velocity must be {robot.nx} numbers, got {x!r}") from None
    if x.shape != (robot.nx,):
        raise ConfigurationError(f"reduced velocity must have shape ({robot.nx},), got {x.shape}")
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        k = int(bad[0])
        raise ConfigurationError(f"reduced velocity entry {k} ({robot.reduced_velocity_names[k]!r}) is {x[k]!r}")
    return x


@dataclass(frozen=True)
class MotionAnalysis:
    """Both measures at one configuration and reduced velocity.

    Attributes:
        terms: the terms (:class:`MotionTerms`).
        kinematic: the kinematic ellipsoid (m/s, rad/s).
        dynamic: the dynamic ellipsoid in motion (m/s^2, rad/s^2).
    """

    terms: MotionTerms
    kinematic: Ellipsoid
    dynamic: Ellipsoid


def analyze_motion(
    robot: Robot,
    q: np.ndarray,
    x: np.ndarray,
    task: str | TaskSpace | None = None,
    *,
    object_mass: float | None = None,
    held_object: HeldObject | None = None,
    decoupled: bool = False,
) -> MotionAnalysis:
    """The kinematic and the in-motion dynamic ellipsoid at configuration q and reduced velocity x.

    At x = 0 the result equals :func:`mobmanip.analysis.analyze`'s. Arguments as :func:`motion_terms`.
    """
    terms = motion_terms(robot, q, x, task, object_mass=object_mass, held_object=held_object, decoupled=decoupled)
    return MotionAnalysis(terms, terms.kinematic(), terms.dynamic())
