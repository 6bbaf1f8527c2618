"""Arm postures that hold an object at a sweep's grid points, for any robot (inverse kinematics).

A sweep grid point is an object direction ``angle`` (deg, from the platform heading; 0 in front,
90 to the left) and a horizontal ``distance`` (m). For a general robot it means this:

* The *reference posture* fixes how the object is held: the spec's home configuration
  (:meth:`mobmanip.robot.model.Robot.neutral`) unless another one is given. In it, the end effectors
  sit at p_i with orientations R_i; the object centre c_0 is their centroid (as everywhere in
  the package, see :meth:`mobmanip.terms.grasp.HeldObject.between`) and r_i = p_i - c_0 are the grasp
  offsets. With one arm, the end effector itself is the task point (r_1 = 0).
* The *reference point* o is the horizontal centroid of the arms' first joints in the reference
  posture (platform frame): for the paper's robot the arms' common first joint P_o, for one arm
  its first joint, for TIAGo++ the middle of its two shoulders. The object's height h is that of
  c_0.
* At grid point (alpha, d) the object centre is c = (o_x + d cos alpha, o_y + d sin alpha, h) in
  the platform frame, and the whole hold turns with the direction: end effector i must be at
  c + R_z(alpha) r_i, ideally with orientation R_z(alpha) R_i. At alpha = 0 the hold is the
  reference posture's own, carried to distance d straight ahead of o.
* Only the arm joints move. The platform sits at the origin with heading 0 (a sweep's platform
  heading then turns the solution rigidly), and torso and locked joints stay at their values in
  the reference posture.

The positions are a requirement, the orientations a preference. Each arm's inverse kinematics
is damped least squares with three tasks in strict priority, each in the null space of those
before it: the end effector's position (world frame), its orientation (the rotation vector of
R_target R^T, as ``pin.log3``), and the posture (every joint of the arm but the first drawn
towards its value in the reference posture, which settles the redundancy of arms with more
than six joints). Steps go through ``pin.integrate``; joint positions stay within the model's
limits (a joint at a limit that a step would push further is held for that step). Arms with
fewer than six joints (the paper's planar 3R arms), or targets where the orientation cannot be
kept, still get the object. A grid point is *reachable* when every end effector ends within
:data:`POSITION_TOLERANCE` of its target; otherwise its posture is NaN. The orientation left
over is reported per point, not required. Leaving the first joint out of the posture task
makes the postures of a robot whose arm turns about a vertical first joint through the
reference point (UR5, Panda) turn with the object's direction: the other joints do not depend
on the angle, and on a fixed base neither do the ellipsoids' shapes.

Continuity: the grid is solved outwards from the grid point nearest the reference posture's own
hold; every other point starts from a solved neighbour (along distance first, then along angle,
wrapping around when the angles cover the whole turn), following its target from the
neighbour's in small steps, so the postures vary continuously along the grid. A point that
fails from one neighbour is tried from the others and, when none is left, from the reference
posture itself. Each attempt follows its target in steps of at most 0.15 m or 30 deg, then
iterates on it until the position is met and orientation and posture have settled (a few
position-only steps finish it), or until the position error stops shrinking; an attempt that
stalls with joints at their limits is resumed once with those joints moved off them. The
search is still local: with joint limits, a point marked unreachable may have a solution far
from its neighbours' postures. Collisions (between the arms, or with the body) are not
considered.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..errors import SpecError
from ..robot.model import Robot

#: An end effector is at its target when its position error is at most this (m).
POSITION_TOLERANCE = 1e-9

_MAX_STEP = 0.25  # rad (or m): largest change of any joint in one iteration
_LOWER_STEP = 0.05  # rad (or m): largest change of any joint for the orientation and posture tasks
_PATH_STEP = 0.15  # m: largest end-effector displacement between intermediate targets
_PATH_TURN = math.radians(30.0)  # largest turn of the hold between intermediate targets
_PATH_ITERATIONS = 4  # iterations on each intermediate target
_MAX_ITERATIONS = 150  # iterations on the final target
_SETTLE_ITERATIONS = 25  # further iterations for orientation and posture once near the target
_SETTLE_STEP = 1e-7  # rad: they have settled when no joint moves more than this
_STALL_WINDOW = 10  # iterations over which the position error must shrink (twice as many while
_STALL_RATIO = 0.5  # the joints still move) below this fraction of its former value, else the
_STALL_STEP = 1e-3  # point is given up; rad (or m): "still" joints move less than this
_NEAR = 1e-4  # m: a position error this small is settled after _SETTLE_ITERATIONS, then polished
_POLISH_ITERATIONS = 8  # position-only iterations to finish a settled point
_ORIENTATION_DAMPING = 1e-2  # damping (squared) of the orientation task (rad^2)
_POSTURE_DAMPING = 1e-2  # damping (squared) of the posture task (rad^2); stops rounding in its projector moving joints
_HOME_BATCH_MAX = 64  # points tried at once from the reference posture
_LOST = 2.0 * _PATH_STEP  # m: a point this far from an intermediate target stops following its path
_ESCAPES = 1  # times a point stalled with joints at their limits is moved off them and resumed
_ESCAPE_FRACTION = 0.05  # of a joint's range: how far such a joint is moved
_NUDGE = 0.05  # rad (or m): joint change that takes a stuck arm off a singular posture


@dataclass(frozen=True)
class Hold:
    """How the arms hold the object, in the platform frame, at object direction 0.

    Attributes:
        origin: reference point o, (x, y) (m): the horizontal centroid of the arms' first joints.
        height: height h of the object centre (m).
        offsets: grasp offsets r_i from the object centre, one row per arm, (k, 3) (m).
        rotations: end-effector orientations R_i, (k, 3, 3).
        center: the object centre c_0 in the reference posture, (3,) (m).
    """

    origin: np.ndarray
    height: float
    offsets: np.ndarray
    rotations: np.ndarray
    center: np.ndarray

    @property
    def home_distance(self) -> float:
        """Horizontal distance of c_0 from the reference point (m)."""
        return float(np.hypot(*(self.center[:2] - self.origin)))

    @property
    def home_angle(self) -> float:
        """Direction of c_0 from the reference point (rad; 0 when c_0 is at o)."""
        dx, dy = self.center[:2] - self.origin
        return math.atan2(dy, dx) if math.hypot(dx, dy) > 0.0 else 0.0

    def targets(self, center_angle: ArrayLike, distance: ArrayLike, turn: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """End-effector targets for object centres at polar (center_angle, distance) from o
        with the hold turned by ``turn`` (rad); at a grid point both angles are alpha.

        Returns:
            Positions (N, k, 3) (m) and orientations (N, k, 3, 3).
        """
        center_angle, distance, turn = np.broadcast_arrays(
            *(np.atleast_1d(np.asarray(v, dtype=float)) for v in (center_angle, distance, turn))
        )
        n = center_angle.shape[0]
        rz = np.zeros((n, 3, 3))
        c, s = np.cos(turn), np.sin(turn)
        rz[:, 0, 0], rz[:, 0, 1], rz[:, 1, 0], rz[:, 1, 1], rz[:, 2, 2] = c, -s, s, c, 1.0
        centre = np.empty((n, 3))
        centre[:, 0] = self.origin[0] + distance * np.cos(center_angle)
        centre[:, 1] = self.origin[1] + distance * np.sin(center_angle)
        centre[:, 2] = self.height
        positions = centre[:, None, :] + np.einsum("nij,kj->nki", rz, self.offsets)
        rotations = np.einsum("nij,kjl->nkil", rz, self.rotations)
        return positions, rotations


def reference_configuration(robot: Robot, joints: Mapping[str, float] | None = None) -> np.ndarray:
    """The reference posture: the home configuration with ``joints`` (name -> value) set, the
    platform at the origin with heading 0.

    Raises:
        JointNotFoundError, ConfigurationError: an unknown joint or a non-finite value.
    """
    return robot.configuration((0.0, 0.0, 0.0), dict(joints or {}))


def hold_from(robot: Robot, q_ref: np.ndarray) -> Hold:
    """The hold of the reference posture ``q_ref`` (platform pose ignored: taken at the origin)."""
    if not robot.arms:
        raise SpecError(f"robot {robot.name!r} has no arms to hold an object with")
    model, data = robot.model, robot.data
    q = np.array(q_ref, dtype=float)
    q[:4] = (0.0, 0.0, 1.0, 0.0)
    pin.framesForwardKinematics(model, data, q)
    points = np.array([data.oMf[arm.frame_id].translation for arm in robot.arms])
    rotations = np.array([data.oMf[arm.frame_id].rotation for arm in robot.arms])
    bases = np.array([data.oMi[model.getJointId(arm.joint_names[0])].translation[:2] for arm in robot.arms])
    center = points.mean(axis=0)
    return Hold(bases.mean(axis=0), float(center[2]), points - center, rotations, center)


@dataclass(frozen=True)
class IKPostureTable:
    """Arm postures at every (angle, distance) of a sweep grid, from inverse kinematics.

    Attributes:
        angle_deg: the grid's angles (deg), (A,).
        distance: the grid's distances (m), (D,).
        joint_names: the arm joints, arm by arm, (n,).
        joints: their positions (rad or m) per grid point, (A, D, n); NaN where unreachable.
        reachable: every end effector within :data:`POSITION_TOLERANCE` of its target, (A, D).
        position_error: largest end-effector position error (m), (A, D): of the posture where
            reachable, of the closest attempt where not.
        rotation_error: largest end-effector orientation error (rad) where reachable (the
            angle of R_target^T R), NaN where not, (A, D).
        hold: the hold (reference point, height, grasp offsets and orientations).
        reference: the reference posture, (nq,).
        seconds: time the solve took (s).
    """

    angle_deg: np.ndarray
    distance: np.ndarray
    joint_names: tuple[str, ...]
    joints: np.ndarray
    reachable: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray
    hold: Hold
    reference: np.ndarray
    seconds: float = 0.0

    method = "ik"


class _Solver:
    """Index maps and the damped least-squares iteration for all arms of a robot at once."""

    def __init__(self, robot: Robot, reference: np.ndarray):
        self.robot = robot
        model = robot.model
        self.model, self.data = model, robot.data
        self.k = len(robot.arms)
        self.v = np.array(robot.arm_v_indices, dtype=int)
        self.n = len(self.v)
        self.joint_names = tuple(name for arm in robot.arms for name in arm.joint_names)
        joints = [model.joints[model.getJointId(name)] for name in self.joint_names]
        self.idx_q = np.array([j.idx_q for j in joints], dtype=int)
        self.nq = np.array([j.nq for j in joints], dtype=int)
        bounded = []
        for c, j in enumerate(joints):
            lo, hi = model.lowerPositionLimit[j.idx_q], model.upperPositionLimit[j.idx_q]
            if j.nq == 1 and np.isfinite(lo) and np.isfinite(hi) and lo < hi:
                bounded.append((c, j.idx_q, lo, hi))
        self.bounded_cols = np.array([b[0] for b in bounded], dtype=int)
        self.bounded_q = np.array([b[1] for b in bounded], dtype=int)
        self.lower = np.array([b[2] for b in bounded], dtype=float)
        self.upper = np.array([b[3] for b in bounded], dtype=float)
        # per arm: its frame, its columns in the stacked joint vector and in Pinocchio's tangent
        self.arm_maps = []
        start = 0
        for arm in robot.arms:
            v = np.array(arm.v_indices, dtype=int)
            contiguous = bool(np.all(np.diff(v) == 1))
            self.arm_maps.append(
                (arm.frame_id, slice(start, start + len(v)), slice(v[0], v[-1] + 1) if contiguous else v)
            )
            start += len(v)
        # per arm: its bounded joints (columns within the arm, q indices, limits)
        self.arm_bounds = []
        for _, cols, _ in self.arm_maps:
            inside = (self.bounded_cols >= cols.start) & (self.bounded_cols < cols.stop)
            self.arm_bounds.append(
                (self.bounded_cols[inside] - cols.start, self.bounded_q[inside], self.lower[inside], self.upper[inside])
            )
        # the posture task: every arm joint but each arm's first, towards the reference posture
        self.reference = self.clip(np.array(reference, dtype=float)[None, :])[0]
        self.reference_values = self.joint_values(self.reference[None, :])[0]
        self.wrapped = self.nq == 2
        self.posture_weights = np.concatenate([(np.arange(len(arm.v_indices)) > 0) * 1.0 for arm in robot.arms])
        self.nudge = np.concatenate(
            [_NUDGE * (-1.0) ** (i + np.arange(len(arm.v_indices))) for i, arm in enumerate(robot.arms)]
        )

    def clip(self, qs: np.ndarray) -> np.ndarray:
        if self.bounded_q.size:
            qs[:, self.bounded_q] = np.clip(qs[:, self.bounded_q], self.lower, self.upper)
        return qs

    def joint_values(self, qs: np.ndarray) -> np.ndarray:
        """Arm joint positions (rad or m) of configurations, (N, n)."""
        out = qs[:, self.idx_q].copy()
        two = self.nq == 2
        if two.any():
            out[:, two] = np.arctan2(qs[:, self.idx_q[two] + 1], qs[:, self.idx_q[two]])
        return out

    def evaluate(self, qs: np.ndarray, targets: np.ndarray, target_rotations: np.ndarray, jacobians: bool = True):
        """Errors (and Jacobians) of the end effectors against their targets.

        Returns:
            e_p (N, 3k) target - position (m), e_o (N, 3k) log3(R_target R^T) (rad), and with
            ``jacobians`` J_p, J_o (N, 3k, n) (world-aligned, arm joint columns).
        """
        model, data, k = self.model, self.data, self.k
        N = qs.shape[0]
        positions = np.empty((N, k, 3))
        placed = np.empty((N, k, 3, 3))
        J_p = np.zeros((N, 3 * k, self.n)) if jacobians else None
        J_o = np.zeros((N, 3 * k, self.n)) if jacobians else None
        lwa = pin.LOCAL_WORLD_ALIGNED
        frame_jacobian = pin.getFrameJacobian
        for row in range(N):
            if jacobians:
                pin.computeJointJacobians(model, data, qs[row])
                pin.updateFramePlacements(model, data)
            else:
                pin.framesForwardKinematics(model, data, qs[row])
            for i, (fid, cols, v) in enumerate(self.arm_maps):
                placement = data.oMf[fid]
                positions[row, i] = placement.translation
                placed[row, i] = placement.rotation
                if jacobians:
                    J = frame_jacobian(model, data, fid, lwa)
                    J_p[row, 3 * i : 3 * i + 3, cols] = J[:3, v]  # type: ignore[index]
                    J_o[row, 3 * i : 3 * i + 3, cols] = J[3:, v]  # type: ignore[index]
        e_p = (targets - positions).reshape(N, 3 * k)
        e_o = rotation_log(target_rotations @ np.swapaxes(placed, 2, 3)).reshape(N, 3 * k)
        return e_p, e_o, J_p, J_o

    def step(self, qs, e_p, e_o, J_p, J_o, lower: bool = True) -> np.ndarray:
        """One prioritised damped least-squares step, (N, n), arm by arm (the arms do not share
        joints): position first, orientation in its null space, then the posture (every arm
        joint but the first of each arm towards its reference position) in what is left. A
        joint at a limit that the position step pushes further is held for all three tasks; one
        that only the lower tasks push there is held for those (so they cannot take a joint the
        position needs).

        At a singular posture whose position error lies entirely along the singular direction
        (an arm stretched towards a target nearer than its reach: J_p^T e_p = 0), least squares
        does not move; the step then turns every joint of that arm by :data:`_NUDGE` rad towards
        the middle of its range (a joint at the middle, or without limits: alternating signs
        along the arm, mirrored from one arm to the next) to leave the singularity.
        """
        e_r = self.reference_values - self.joint_values(qs)
        if self.wrapped.any():
            e_r[:, self.wrapped] = (e_r[:, self.wrapped] + math.pi) % (2.0 * math.pi) - math.pi
        e_r *= self.posture_weights
        dq = np.zeros((qs.shape[0], self.n))
        for i, (_, cols, _) in enumerate(self.arm_maps):
            rows = slice(3 * i, 3 * i + 3)
            dq[:, cols] = self._arm_step(qs, i, e_p[:, rows], e_o[:, rows], e_r[:, cols], J_p[:, rows, cols],
                                         J_o[:, rows, cols], lower)  # fmt: skip
        biggest = np.max(np.abs(dq), axis=1, initial=0.0)
        scale = np.where(biggest > _MAX_STEP, _MAX_STEP / np.maximum(biggest, 1e-300), 1.0)
        return dq * scale[:, None]

    def _arm_step(self, qs, i, e_p, e_o, e_r, J_p, J_o, lower_tasks: bool) -> np.ndarray:
        _, cols, _ = self.arm_maps[i]
        local, q_index, lower, upper = self.arm_bounds[i]
        J_r = np.broadcast_to(np.diag(self.posture_weights[cols]), (qs.shape[0],) + (J_p.shape[2],) * 2)
        q_b = qs[:, q_index]

        def pushed(step, free, base):
            """Free joints at a limit that ``step`` pushes further, or that ``base + step``
            takes past one."""
            d_b, moved = step[:, local], q_b + base[:, local] + step[:, local]
            out = np.zeros_like(free, dtype=bool)
            out[:, local] = ((q_b <= lower) & (d_b < 0.0)) | ((q_b >= upper) & (d_b > 0.0))
            out[:, local] |= (moved < lower) | (moved > upper)
            return out & (free > 0.0)

        # the position task first; a joint it pushes into a limit is held for every task
        free = np.ones((qs.shape[0], J_p.shape[2]))
        dq1 = _position_step(e_p, J_p)
        if local.size and (held := pushed(dq1, free, np.full_like(dq1, np.nan))).any():
            free[held] = 0.0
            dq1 = _position_step(e_p, J_p * free[:, None, :]) * free
        # then orientation and posture; a joint they push into or past a limit is held for them
        # only (clipping their step would disturb the position)
        res_o = e_o - (J_o @ dq1[..., None])[..., 0]
        free_lower = free
        dq_lower = np.zeros_like(dq1)
        for _ in range(2 if lower_tasks else 0):
            mask = free_lower[:, None, :]
            dq_lower = _lower_step(res_o, e_r, dq1, J_p * mask, J_o * mask, J_r * mask, J_r) * free_lower
            if not local.size or not (held := pushed(dq_lower, free_lower, dq1)).any():
                break
            free_lower = free_lower.copy()
            free_lower[held] = 0.0
        dq = dq1 + dq_lower
        J_p = J_p * free[:, None, :]
        err = np.linalg.norm(e_p, axis=1)
        gradient = np.linalg.norm(np.einsum("nij,ni->nj", J_p, e_p), axis=1)
        stuck = (err > POSITION_TOLERANCE) & (gradient <= 1e-9 * err * np.linalg.norm(J_p, axis=(1, 2)))
        if stuck.any():
            nudge = np.repeat(self.nudge[None, cols], int(stuck.sum()), axis=0)
            if local.size:  # towards the middle of the joint's range
                towards = np.sign(0.5 * (lower + upper) - q_b[stuck])
                n_b = nudge[:, local]
                nudge[:, local] = np.where(towards != 0.0, towards * np.abs(n_b), n_b)
            dq[stuck] += nudge
        return dq

    def at_limit(self, qs: np.ndarray) -> np.ndarray:
        """Bounded arm joints at a limit, (N, bounded)."""
        q_b = qs[:, self.bounded_q]
        return (q_b <= self.lower) | (q_b >= self.upper)

    def off_limits(self, qs: np.ndarray, which: np.ndarray) -> np.ndarray:
        """``qs`` with the bounded joints ``which`` (N, bounded) moved off their limit towards
        the middle of their range, by :data:`_ESCAPE_FRACTION` of the range."""
        out = qs.copy()
        q_b = out[:, self.bounded_q]
        move = _ESCAPE_FRACTION * (self.upper - self.lower) * np.sign(0.5 * (self.lower + self.upper) - q_b)
        out[:, self.bounded_q] = np.where(which, q_b + move, q_b)
        return out

    def apply(self, qs: np.ndarray, dq: np.ndarray) -> np.ndarray:
        v = np.zeros(self.model.nv)
        out = np.empty_like(qs)
        for row in range(qs.shape[0]):
            v[self.v] = dq[row]
            out[row] = pin.integrate(self.model, qs[row], v)
        return self.clip(out)


def _damped_solve(J: np.ndarray, e: np.ndarray, damping) -> np.ndarray:
    """J^T (J J^T + damping I)^-1 e for stacks J (N, m, n), e (N, m); damping scalar or (N,)."""
    Jt = np.swapaxes(J, 1, 2)
    A = J @ Jt + np.reshape(damping, (-1, 1, 1)) * np.eye(J.shape[1])
    return (Jt @ np.linalg.solve(A, e[..., None]))[..., 0]


def _null_projector(J: np.ndarray) -> np.ndarray:
    """I - J^+ J for a stack J (N, m, n), m <= n: the joint motions J does not see.

    J^+ J = J^T (J J^T)^+ J from the eigendecomposition of the small J J^T (m x m), its
    eigenvalues below 1e-12 of the largest taken as zero (singular values below 1e-6 of the
    largest: directions the task hardly moves count as free).
    """
    lam, V = np.linalg.eigh(J @ np.swapaxes(J, 1, 2))
    keep = lam > 1e-12 * np.max(lam, axis=1, keepdims=True)
    inv = np.where(keep, 1.0 / np.where(keep, lam, 1.0), 0.0)
    U = np.swapaxes(V, 1, 2) @ J  # rows: J's row space along the eigenvectors
    return np.eye(J.shape[2]) - np.swapaxes(U, 1, 2) @ (inv[..., None] * U)


def _position_step(e_p: np.ndarray, J_p: np.ndarray) -> np.ndarray:
    """The position task's step J_p# e_p, (N, n).

    J_p# is damped with lambda^2 = ||e_p||^2 / 4 + 1e-12 (m^2): strong far from the target and
    near singular postures, vanishing with the error (quadratic convergence where J_p has full
    rank).
    """
    return _damped_solve(J_p, e_p, 0.25 * np.einsum("ij,ij->i", e_p, e_p) + 1e-12)


def _lower_step(res_o, e_r, dq1, J_p, J_o, J_r, J_r_full) -> np.ndarray:
    """The orientation and posture tasks' step, each in the null space of the tasks before it.

    dq2 = (J_o N_1)# res_o and dq3 = (J_r N_12)# (e_r - J_r (dq1 + dq2)), with res_o the
    orientation error left after the position step dq1 and N_1, N_12 the null-space
    projectors of J_p and of [J_p; J_o] (columns of held joints zeroed in J_p, J_o, J_r:
    their rows of dq2 and dq3 are zero). The step is scaled down to at most
    :data:`_LOWER_STEP` per joint: it leaves the position alone only to first order.
    """
    dq2 = _damped_solve(J_o @ _null_projector(J_p), res_o, _ORIENTATION_DAMPING)
    J3 = J_r @ _null_projector(np.concatenate([J_p, J_o], axis=1))
    dq3 = _damped_solve(J3, e_r - (J_r_full @ (dq1 + dq2)[..., None])[..., 0], _POSTURE_DAMPING)
    lower = dq2 + dq3
    biggest = np.max(np.abs(lower), axis=1, initial=0.0)
    return lower * np.minimum(1.0, _LOWER_STEP / np.maximum(biggest, 1e-300))[:, None]


def rotation_log(R: np.ndarray) -> np.ndarray:
    """The rotation vectors of rotation matrices (..., 3, 3) -> (..., 3) (rad), as ``pin.log3``.

    Away from a half turn: theta / (2 sin theta) times the axial vector of R - R^T (theta from
    atan2 of its length and the trace). Within 1e-4
    rad of a half turn (where that loses accuracy) the axis comes from the largest column of
    the symmetric part (R + R^T) / 2 - cos(theta) I = (1 - cos(theta)) n n^T, its sign from the
    axial vector.
    """
    axial = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    cos = np.clip(0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0), -1.0, 1.0)
    sin = 0.5 * np.linalg.norm(axial, axis=-1)
    theta = np.arctan2(sin, cos)
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(theta < 1e-6, 0.5 + theta * theta / 12.0, theta / (2.0 * sin))
    out = factor[..., None] * axial
    near = theta > math.pi - 1e-4
    if np.any(near):
        Rn = R[near]
        B = 0.5 * (Rn + np.swapaxes(Rn, 1, 2)) - cos[near][:, None, None] * np.eye(3)  # (1 - cos) n n^T
        col = np.argmax(np.linalg.norm(B, axis=-2), axis=-1)
        axis = B[np.arange(B.shape[0]), :, col]
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        sign = np.where(np.einsum("ni,ni->n", axis, axial[near]) < 0.0, -1.0, 1.0)
        out[near] = (sign * theta[near])[:, None] * axis
    return out


def _rotation_angles(e_o: np.ndarray, k: int) -> np.ndarray:
    """Largest orientation error over the arms (rad), (N,)."""
    return np.max(np.linalg.norm(e_o.reshape(-1, k, 3), axis=2), axis=1)


def _position_errors(e_p: np.ndarray, k: int) -> np.ndarray:
    """Largest position error over the arms (m), (N,)."""
    return np.max(np.linalg.norm(e_p.reshape(-1, k, 3), axis=2), axis=1)


def _solve(solver: _Solver, hold: Hold, q0: np.ndarray, start: np.ndarray, end: np.ndarray):
    """Move N postures from the targets ``start`` to ``end`` ((N, 3): centre angle, distance,
    turn) in small steps, then converge on ``end``.

    Returns:
        q (N, nq), position error (N,), rotation error (N,), reached (N,).
    """
    N = q0.shape[0]
    qs = solver.clip(np.array(q0, dtype=float))
    reach = float(np.max(np.linalg.norm(hold.offsets, axis=1), initial=0.0))

    def targets(fraction):
        t = start + fraction[:, None] * (end - start)
        return hold.targets(t[:, 0], t[:, 1], t[:, 2])

    # how many intermediate targets each point needs
    p0, _ = hold.targets(start[:, 0], start[:, 1], start[:, 2])
    p1, _ = hold.targets(end[:, 0], end[:, 1], end[:, 2])
    shift = np.max(np.linalg.norm(p1 - p0, axis=2), axis=1)
    turn = np.abs(end[:, 2] - start[:, 2])
    arc = np.abs(end[:, 0] - start[:, 0]) * np.maximum(start[:, 1], end[:, 1]) + turn * reach
    steps = np.ceil(np.maximum(np.maximum(shift, arc) / _PATH_STEP, turn / _PATH_TURN)).astype(int)
    tracking = np.arange(N)  # points still following their path (the others go to the end)
    for s in range(1, int(steps.max(initial=0))):
        tracking = tracking[s < steps[tracking]]
        if tracking.size == 0:
            break
        positions, rotations = targets(np.minimum(1.0, s / np.maximum(steps, 1)))
        q_t = qs[tracking]
        for _ in range(_PATH_ITERATIONS):
            e_p, e_o, J_p, J_o = solver.evaluate(q_t, positions[tracking], rotations[tracking])
            q_t = solver.apply(q_t, solver.step(q_t, e_p, e_o, J_p, J_o))
        qs[tracking] = q_t
        lost = _position_errors(e_p, solver.k) > _LOST
        tracking = tracking[~lost]

    positions, rotations = targets(np.ones(N))
    active = np.arange(N)
    history = np.full((N, _MAX_ITERATIONS + _SETTLE_ITERATIONS + 1), np.inf)
    near_at = np.full(N, -1)  # since when the position error has stayed below _NEAR
    escapes = np.zeros(N, dtype=int)
    for it in range(_MAX_ITERATIONS + _SETTLE_ITERATIONS):
        if active.size == 0:
            break
        q_a = qs[active]
        e_p, e_o, J_p, J_o = solver.evaluate(q_a, positions[active], rotations[active])
        err = _position_errors(e_p, solver.k)
        history[active, it] = err
        near = err <= _NEAR
        near_at[active[near & (near_at[active] < 0)]] = it
        near_at[active[~near]] = -1
        dq = solver.step(q_a, e_p, e_o, J_p, J_o)
        moving = np.max(np.abs(dq), axis=1, initial=0.0)
        settled = (err <= POSITION_TOLERANCE) & (moving <= _SETTLE_STEP)
        settled |= near & (it - near_at[active] >= _SETTLE_ITERATIONS)
        slow = (it >= _STALL_WINDOW) & (err > _STALL_RATIO * history[active, it - _STALL_WINDOW])
        stalled = ~near & slow & (moving < _STALL_STEP)
        late = 2 * _STALL_WINDOW
        stalled |= ~near & (it >= late) & (err > _STALL_RATIO * history[active, it - late])
        # a point stalled with joints at their limits gets them moved off (a few times)
        limited = solver.at_limit(q_a) & (escapes[active] < _ESCAPES)[:, None]
        escape = stalled & (it < _MAX_ITERATIONS - 2 * _STALL_WINDOW) & limited.any(axis=1)
        if escape.any():
            rows = active[escape]
            qs[rows] = solver.off_limits(q_a[escape], limited[escape])
            escapes[rows] += 1
            history[rows, : it + 1] = np.inf
            stalled &= ~escape
            dq[escape] = 0.0
        stalled |= ~near & (it >= _MAX_ITERATIONS)
        move = ~(settled | stalled)
        qs[active[move]] = solver.apply(q_a[move], dq[move])
        active = active[move]
    # Polish: near the target, position steps alone (Gauss-Newton) finish what the lower tasks,
    # still turning the joints by small amounts, keep disturbing at second order.
    active = np.arange(N)
    for _ in range(_POLISH_ITERATIONS + 1):
        e_p, e_o, J_p, J_o = solver.evaluate(qs[active], positions[active], rotations[active])
        err = _position_errors(e_p, solver.k)
        todo = (err > POSITION_TOLERANCE) & (err <= _NEAR)
        if not todo.any():
            break
        active, e_p, e_o, J_p, J_o = active[todo], e_p[todo], e_o[todo], J_p[todo], J_o[todo]
        qs[active] = solver.apply(qs[active], solver.step(qs[active], e_p, e_o, J_p, J_o, lower=False))
    e_p, e_o, _, _ = solver.evaluate(qs, positions, rotations, jacobians=False)
    pos_err = _position_errors(e_p, solver.k)
    rot_err = _rotation_angles(e_o, solver.k)
    return qs, pos_err, rot_err, pos_err <= POSITION_TOLERANCE


def solve_postures(
    robot: Robot,
    angle_deg: Sequence[float] | np.ndarray,
    distance: Sequence[float] | np.ndarray,
    reference: np.ndarray | None = None,
) -> IKPostureTable:
    """Postures of all arms holding the object at every (angle, distance) of a grid.

    See the module's docstring for what a grid point means and how the grid is traversed.
    Angles that coincide modulo 360 deg share their postures.

    Args:
        robot: the robot (its platform kind does not matter: the platform stays at the origin).
        angle_deg: object directions from the platform heading (deg), (A,).
        distance: horizontal distances of the object centre from the reference point (m), (D,).
        reference: the reference posture (nq,); default the home configuration.

    Returns:
        The table; unreachable points have NaN joints and ``reachable`` False.
    """
    started = time.perf_counter()
    angle_deg = np.asarray(angle_deg, dtype=float).reshape(-1)
    distance = np.asarray(distance, dtype=float).reshape(-1)
    q_ref = robot.neutral() if reference is None else robot.check_configuration(reference).copy()
    q_ref[:4] = (0.0, 0.0, 1.0, 0.0)
    solver = _Solver(robot, q_ref)
    q_ref = solver.reference  # within the joint limits
    hold = hold_from(robot, q_ref)

    # the distinct directions (mod 360) and distances, sorted: the grid the search walks on
    keys = np.round(np.mod(angle_deg, 360.0), 9) % 360.0
    u_angle, a_index = np.unique(keys, return_inverse=True)
    u_dist, d_index = np.unique(distance, return_inverse=True)
    nu, nd = len(u_angle), len(u_dist)
    gaps = np.diff(np.append(u_angle, u_angle[0] + 360.0))
    circular = nu > 2 and gaps[-1] <= np.max(gaps[:-1]) + 1e-9
    alpha = np.radians(u_angle)
    grid_params = np.stack(np.broadcast_arrays(alpha[:, None], u_dist[None, :], alpha[:, None]), axis=-1)

    nq = robot.model.nq
    solved = np.zeros((nu, nd), dtype=bool)
    q_sol = np.full((nu, nd, nq), np.nan)
    pos_err = np.full((nu, nd), np.inf)
    rot_err = np.full((nu, nd), np.nan)
    tried = np.zeros((nu, nd, 4), dtype=bool)  # from the neighbour at d-1, d+1, a-1, a+1
    home_tried = np.zeros((nu, nd), dtype=bool)

    # the reference posture's own hold, as a start of paths: (centre angle, distance, turn 0)
    home = np.array([hold.home_angle, hold.home_distance, 0.0])
    targets, _ = hold.targets(grid_params[..., 0].ravel(), grid_params[..., 1].ravel(), grid_params[..., 2].ravel())
    p_ref = hold.targets(home[0], home[1], home[2])[0][0]
    nearness = np.sum(np.linalg.norm(targets - p_ref, axis=2), axis=1).reshape(nu, nd)
    home_batch = 1

    def shifted(a: np.ndarray, direction: int) -> np.ndarray:
        """a at the neighbour in ``direction`` (0: d-1, 1: d+1, 2: a-1, 3: a+1), False off the grid."""
        out = np.zeros_like(a)
        if direction == 0:
            out[:, 1:] = a[:, :-1]
        elif direction == 1:
            out[:, :-1] = a[:, 1:]
        elif circular:
            out = np.roll(a, 1 if direction == 2 else -1, axis=0)
        elif direction == 2:
            out[1:] = a[:-1]
        else:
            out[:-1] = a[1:]
        return out

    offsets = ((0, -1), (0, 1), (-1, 0), (1, 0))
    while True:
        choice = np.full((nu, nd), -1)
        for direction in range(4):
            free = (choice < 0) & ~solved & shifted(solved, direction) & ~tried[..., direction]
            choice[free] = direction
        points = np.argwhere(choice >= 0)
        if points.size:
            dirs = choice[points[:, 0], points[:, 1]]
            da, dd = np.array(offsets)[dirs].T
            na, nb = (points[:, 0] + da) % nu, points[:, 1] + dd
            q0 = q_sol[na, nb]
            start = grid_params[na, nb].copy()
            # along angle, walk the short way round (across 360 when wrapping)
            start[:, 0] = start[:, 2] = alpha[points[:, 0]] + np.radians(
                (u_angle[na] - u_angle[points[:, 0]] + 180.0) % 360.0 - 180.0
            )
            tried[points[:, 0], points[:, 1], dirs] = True
        else:
            left = ~solved & ~home_tried
            if not left.any():
                break
            order = np.argsort(np.where(left, nearness, np.inf), axis=None, kind="stable")[:home_batch]
            points = np.stack(np.unravel_index(order, (nu, nd)), axis=1)
            points = points[left[points[:, 0], points[:, 1]]]
            home_batch = min(2 * home_batch, _HOME_BATCH_MAX)
            q0 = np.repeat(q_ref[None, :], len(points), axis=0)
            start = np.repeat(home[None, :], len(points), axis=0)
            turn = grid_params[points[:, 0], points[:, 1], 2]
            # the short way round: the centre from its home direction, the hold from a whole turn
            start[:, 0] = turn + (home[0] - turn + math.pi) % (2 * math.pi) - math.pi
            start[:, 2] = turn - ((turn + math.pi) % (2 * math.pi) - math.pi)
            home_tried[points[:, 0], points[:, 1]] = True
        end = grid_params[points[:, 0], points[:, 1]]
        qs, p_err, r_err, ok = _solve(solver, hold, q0, start, end)
        a, d = points[:, 0], points[:, 1]
        better = p_err < pos_err[a, d]
        pos_err[a[better], d[better]] = p_err[better]
        solved[a[ok], d[ok]] = True
        q_sol[a[ok], d[ok]] = qs[ok]
        rot_err[a[ok], d[ok]] = r_err[ok]

    joints = np.full((nu, nd, solver.n), np.nan)
    if solved.any():
        joints[solved] = solver.joint_values(q_sol[solved])
    return IKPostureTable(
        angle_deg=angle_deg,
        distance=distance,
        joint_names=solver.joint_names,
        joints=joints[a_index][:, d_index],
        reachable=solved[a_index][:, d_index],
        position_error=pos_err[a_index][:, d_index],
        rotation_error=rot_err[a_index][:, d_index],
        hold=hold,
        reference=q_ref,
        seconds=time.perf_counter() - started,
    )
