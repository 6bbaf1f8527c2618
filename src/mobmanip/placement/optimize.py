"""Base placement: where the platform should stand, and how the arms should hold the object.

Given a world point X for the object's centre, :func:`place` finds the platform pose (x, y,
heading) and the arm (and torso) joint positions that hold the object at X and maximise an
objective of :mod:`mobmanip.gradients` (e.g. the kinematic capacity along +x, the dynamic
log-volume, the minor semi-axis).

The hold. A reference posture (the spec's ``[hold]``, else the home configuration) fixes how the
hands hold the object, as in :mod:`mobmanip.postures.inverse_kinematics`: in it the end effectors sit at p_i with
orientations R_i, the object centre c_0 is their centroid and r_i = p_i - c_0. A placement holds
the object with this grasp turned by a free angle psi about the vertical: end effector i must be
at X + R_z(psi) r_i (equality constraints) and, when the task has rotations (the grasp then
transmits moments), have the orientation R_z(psi) R_i (log3 of the orientation error = 0). With
one arm, or coincident grasp points (the paper's robot), only positions constrain the hold.

The problem. Decision variables z = (x, y, heading, the torso and arm joints, psi); the wheels
stay at their reference angles (nothing depends on them). Bounds: the joints' position limits
and, when given, a rectangular region for the platform origin. The objective's gradient comes
from :class:`mobmanip.gradients.GradientEvaluator` (tangent space, turned into z by
:func:`mobmanip.gradients.platform_gradient`), the constraints' Jacobians from Pinocchio's frame
Jacobians. scipy's SLSQP runs from several starts: the reference hold placed at X with the
platform at evenly spread headings, first projected onto the constraints (the nearest pose that
holds the object; no measure evaluations), then optimised. The best run whose result satisfies
the constraints within :data:`CONSTRAINT_TOLERANCE` wins.

Self-collision: with ``collision`` (:class:`mobmanip.robot.collision.SelfCollision`), every shape
pair that may meet keeps the margin, as inequality constraints with analytic distance
gradients; without it arms and platform may intersect.
"""

from __future__ import annotations

import functools
import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike
from scipy.optimize import minimize

from ..analysis.single import Analysis
from ..errors import ArgumentError, UnreachableObjectError
from ..gradients.evaluator import GradientEvaluator, Objective, platform_gradient
from ..postures.inverse_kinematics import hold_from
from ..robot.model import Robot, platform_pose
from ..robot.tasks import get_task
from ..support.lockstep import Lockstep

if TYPE_CHECKING:
    from ..robot.collision import SelfCollision

#: How close (relative) a start's value must come to the best to count as reaching it.
AGREEMENT_RTOL = 1e-6
#: A run's result holds the object when every position error is at most this (m) and every
#: orientation error (rad) too.
CONSTRAINT_TOLERANCE = 1e-6
#: Default number of starts (platform headings around the object).
DEFAULT_STARTS = 8
#: A placement whose starts times iterations stay below this runs the gradients' NumPy forms, not
#: the compiled row loops: in a fresh process loading Numba and the loops' cached code costs about
#: 0.5 s of CPU, and on TIAGo++ the loops save about 0.5 ms per round of at most 8 evaluations
#: (1.1-1.4x; `dynamic:log_volume`, measured here), so they pay for themselves after about a
#: thousand rounds. Maps and batches keep the loops.
COMPILED_FROM_ROUNDS = 1000
#: How many of the closest shape pairs a placement passes to SLSQP as constraints.
CLOSEST_PAIRS = 100


_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Region:
    """A rectangle for the platform origin (m, world frame)."""

    x_min: float
    x_max: float
    y_min: float
    y_max: float

    def __post_init__(self):
        values = (self.x_min, self.x_max, self.y_min, self.y_max)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            raise ArgumentError(f"region bounds must be finite numbers, got {list(values)!r}")
        if self.x_min > self.x_max or self.y_min > self.y_max:
            raise ArgumentError(
                f"region {list(values)!r} is empty: need x_min <= x_max and y_min <= y_max (XMIN,XMAX,YMIN,YMAX)"
            )

    @classmethod
    def parse(cls, text: str) -> Region:
        """From ``XMIN,XMAX,YMIN,YMAX`` (m)."""
        try:
            values = [float(v) for v in str(text).split(",")]
        except ValueError:
            raise ArgumentError(f"region must be XMIN,XMAX,YMIN,YMAX in metres, got {text!r}") from None
        if len(values) != 4:
            raise ArgumentError(f"region must be XMIN,XMAX,YMIN,YMAX in metres, got {text!r}")
        return cls(*values)

    def clip(self, xy: np.ndarray) -> np.ndarray:
        return np.array([min(max(xy[0], self.x_min), self.x_max), min(max(xy[1], self.y_min), self.y_max)])


@dataclass(frozen=True)
class Placement:
    """The result of :func:`place`.

    Attributes:
        q: the chosen configuration, (nq,).
        objective: the objective maximised.
        value: its value at ``q``.
        start_value: its value at the best start (the reference hold placed at the object, projected
            onto the constraints), or ``None`` when no start could be projected.
        target: the object centre (m, world), (3,).
        hold_turn: psi, the turn of the hold about the vertical (rad).
        residual: largest constraint error at ``q`` (m or rad).
        evaluations: objective evaluations (value and gradient) spent, over all starts.
        constraint_evaluations: constraint (forward kinematics) evaluations.
        runs: per start: (start value or None, final value or None when the run failed).
        seconds: wall time (s).
        start_q: the configuration of the best start (``start_value``), or ``None``.
    """

    q: np.ndarray
    objective: Objective
    value: float
    start_value: float | None
    target: np.ndarray
    hold_turn: float
    residual: float
    evaluations: int
    constraint_evaluations: int
    runs: tuple[tuple[float | None, float | None], ...] = field(default=())
    seconds: float = 0.0
    start_q: np.ndarray | None = None

    @property
    def platform(self) -> tuple[float, float, float]:
        """(x m, y m, heading rad) of the platform."""
        return platform_pose(self.q)

    def agreement(self, rtol: float = AGREEMENT_RTOL) -> dict[str, int]:
        """How the starts ended: ``{"best": reached the best value within ``rtol`` of its size,
        "lower": stopped at a lower value, "failed": found no hold}``. Several starts at the best
        say the search found that value more than once (a local optimum each start fell into
        alone would show as one)."""
        values = [v for _, v in self.runs if v is not None]
        best = sum(1 for v in values if v >= self.value - rtol * max(abs(self.value), 1e-300))
        return {"best": best, "lower": len(values) - best, "failed": len(self.runs) - len(values)}


class PlacementProblem:
    """Decision variables, objective and constraints of one placement."""

    @classmethod
    def of_objective(
        cls, robot, objective, task, target, region=None, reference=None, collision=None, *,
        object_mass=None, decoupled=False, compiled=None,
    ) -> PlacementProblem:  # fmt: skip
        """The problem of placing ``robot`` to hold the object at ``target``: the objective's
        :class:`~mobmanip.gradients.GradientEvaluator` on ``task`` (a name or a task; ``None``: the
        spec's default task), the hold of ``reference`` (``None``: the spec's hold configuration);
        ``compiled`` as the evaluator's."""
        task = get_task(task or robot.spec.default_task)
        evaluator = GradientEvaluator(
            robot, objective, task, object_mass=object_mass, decoupled=decoupled, compiled=compiled
        )
        q_ref = robot.hold_configuration() if reference is None else robot.check_configuration(reference).copy()
        return cls(robot, evaluator, target, region, q_ref, collision)

    def __init__(self, robot, evaluator, target, region, reference, collision=None):
        self.collision = collision
        self.robot = robot
        self.model = robot.model
        self.data = robot.data
        self.ev = evaluator
        self.target = target
        self.region = region
        self.q_ref = reference
        self.hold = hold_from(robot, reference)
        names = robot.torso_joint_names + tuple(j for arm in robot.arms for j in arm.joint_names)
        self.joint_ids = [self.model.getJointId(n) for n in names]
        self.joint_names = names
        self._joint_v = np.array([self.model.joints[j].idx_v for j in self.joint_ids], dtype=int)
        continuous = np.array([self.model.joints[j].nq == 2 for j in self.joint_ids], dtype=bool)
        slots = np.arange(3, 3 + len(names))
        idx_q = np.array([self.model.joints[j].idx_q for j in self.joint_ids], dtype=int)
        #: Where z's joint entries go in q: (z, q) indices of one-coordinate joints, then of
        #: continuous ones (q holds cos, sin).
        self._joint_slots = (slots[~continuous], idx_q[~continuous], slots[continuous], idx_q[continuous])
        self.n = 3 + len(names) + 1  # platform, joints, psi
        task = evaluator.task
        self.orientation = bool(task.angular_rows) and len(robot.arms) >= 1 and _grasp_spread(self.hold) > 0.0
        if task.angular_rows and len(robot.arms) == 1:
            self.orientation = True
        self.frames = [arm.frame_id for arm in robot.arms]
        self.constraint_evaluations = 0
        #: Serves the objective's evaluations; runs inside ``self.lockstep.run`` (starts, map
        #: cells) have theirs evaluated together, in one batched call per round.
        self.lockstep: Lockstep = Lockstep(self._evaluate_batch)
        self._frames: tuple[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        self._value: tuple[bytes, float, bool] | None = None  # the objective's last (q, value, defined)
        self.rows = None
        self.rows = self._moving_rows()
        #: Indices of the collision pairs kept as constraints: with the hands' poses held (the
        #: object's orientation held by every hand), pairs of shapes on two different hands keep
        #: their reference distance, so they are left out (the reference's touching pairs already
        #: are): as constraints they only repeat the hold's, and SLSQP found them incompatible.
        self.collision_rows = np.zeros(0, dtype=int)
        self._pair_distances = None
        self._last_clearances: tuple[np.ndarray, tuple[np.ndarray, np.ndarray]] | None = None
        if collision is not None:
            from ..robot.shape_pairs import PairDistances

            hands = {self.model.frames[f].parentJoint for f in self.frames} if self.orientation else set()
            self.collision_rows = np.array(
                [
                    k
                    for k, pair in enumerate(collision.pairs)
                    if not (set(pair.joints) <= hands and len(set(pair.joints)) == 2)
                ],
                dtype=int,
            )
            engine = collision.engine
            pairs = list(zip(engine.first[self.collision_rows], engine.second[self.collision_rows]))
            self._pair_distances = PairDistances(self.model, engine.geometry, pairs, collision.activation)

    def _moving_rows(self) -> np.ndarray:
        """Hold constraints that some variable can change: rows of the constraint Jacobian that
        are zero at a few random poses never move (e.g. the height of a planar arm's hand) and are
        left out (SLSQP needs independent constraints); they are checked at the starts instead."""
        rng = np.random.default_rng(0)
        moving: np.ndarray | None = None
        for _ in range(3):
            z = rng.uniform(-math.pi, math.pi, self.n)
            nonzero = np.abs(self.constraints(z)[1]).max(axis=1) > 1e-12
            moving = nonzero if moving is None else moving | nonzero
        self.constraint_evaluations = 0
        assert moving is not None
        return np.flatnonzero(moving)

    def fixed_errors(self, z: np.ndarray) -> np.ndarray:
        """Errors of the hold constraints no variable can change, at z."""
        saved, self.rows = self.rows, None
        try:
            value = self.constraints(z, jacobian=False)
        finally:
            self.rows = saved
        keep = np.ones(value.shape[0], dtype=bool)
        keep[saved] = False
        return value[keep]

    # ----- variables -----

    def bounds(self) -> list[tuple[float | None, float | None]]:
        out: list[tuple[float | None, float | None]] = []
        if self.region is None:
            out += [(None, None), (None, None)]
        else:
            out += [(self.region.x_min, self.region.x_max), (self.region.y_min, self.region.y_max)]
        out.append((None, None))
        for j in self.joint_ids:
            joint = self.model.joints[j]
            if joint.nq == 2:  # continuous
                out.append((None, None))
            else:
                lo, hi = self.model.lowerPositionLimit[joint.idx_q], self.model.upperPositionLimit[joint.idx_q]
                out.append((float(lo) if np.isfinite(lo) else None, float(hi) if np.isfinite(hi) else None))
        out.append((None, None))
        return out

    def configuration(self, z: np.ndarray) -> np.ndarray:
        q = self.q_ref.copy()
        q[:4] = (z[0], z[1], math.cos(z[2]), math.sin(z[2]))
        plain_z, plain_q, circle_z, circle_q = self._joint_slots
        q[plain_q] = z[plain_z]
        if circle_z.size:  # continuous joints: (cos, sin)
            angles = z[circle_z]
            q[circle_q] = np.cos(angles)
            q[circle_q + 1] = np.sin(angles)
        return q

    def variables(self, q: np.ndarray, psi: float) -> np.ndarray:
        z = np.empty(self.n)
        z[:3] = platform_pose(q)
        for k, j in enumerate(self.joint_ids):
            joint = self.model.joints[j]
            if joint.nq == 2:
                z[3 + k] = math.atan2(q[joint.idx_q + 1], q[joint.idx_q])
            else:
                z[3 + k] = q[joint.idx_q]
        z[-1] = psi
        return z

    def _to_z(self, q: np.ndarray, tangent_rows: np.ndarray) -> np.ndarray:
        """Rows over the tangent space (r, nv) -> rows over z (r, n) (psi column zero)."""
        out = np.zeros((tangent_rows.shape[0], self.n))
        c, s = float(q[2]), float(q[3])
        out[:, 0] = c * tangent_rows[:, 0] - s * tangent_rows[:, 1]
        out[:, 1] = s * tangent_rows[:, 0] + c * tangent_rows[:, 1]
        out[:, 2] = tangent_rows[:, 2]
        out[:, 3:-1] = tangent_rows[:, self._joint_v]
        return out

    # ----- objective (to minimise: minus the measure) -----

    def _evaluate_batch(self, qs: list[np.ndarray]) -> list[tuple[float, np.ndarray, bool, tuple | None]]:
        """Value, gradient, defined and the hands' frames (world positions, orientations,
        Jacobians) at each configuration, all from one pass of the gradient chain."""
        value, grad, ok, frames = self.ev.chunk_with_frames(np.array(qs))
        return [
            (float(value[i]), grad[i], bool(ok[i]), None if frames is None else tuple(f[i] for f in frames))
            for i in range(len(qs))
        ]

    def _frames_at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The hands' world positions (k, 3), orientations (k, 3, 3) and ``LOCAL_WORLD_ALIGNED``
        Jacobians (k, 6, nv) at q: those the objective's evaluation at q brought along (SLSQP
        asks for the hold constraints at the point it has just evaluated), else from Pinocchio."""
        if self._frames is not None and self._frames[0] == q.tobytes():  # the same q, bit for bit
            return self._frames[1]
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        positions = np.array([data.oMf[f].translation for f in self.frames])
        rotations = np.array([data.oMf[f].rotation for f in self.frames])
        jacobians = np.array([pin.getFrameJacobian(model, data, f, pin.LOCAL_WORLD_ALIGNED) for f in self.frames])
        return positions, rotations, jacobians

    def value_at(self, q: np.ndarray) -> tuple[float, bool]:
        """(value, defined) of the measure at q: the objective's last evaluation when it was at q
        (a run's optimum is usually the point SLSQP evaluated last), else a new one."""
        if self._value is not None and self._value[0] == q.tobytes():
            return self._value[1], self._value[2]
        value, _, ok, _ = self.lockstep.ask(q)
        return value, ok

    def objective(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        q = self.configuration(z)
        value, grad, ok, frames = self.lockstep.ask(q)
        key = q.tobytes()
        if frames is not None:
            self._frames = (key, frames)
        self._value = (key, value, ok)
        if not ok:  # singular or empty: a large cost without slope pushes the line search back
            return 1e6, np.zeros(self.n)
        gz = np.zeros(self.n)
        gz[:3] = platform_gradient(q, grad)
        gz[3:-1] = grad[self._joint_v]
        return -value, -gz

    # ----- constraints -----

    def constraints(self, z: np.ndarray, jacobian: bool = True):
        """Hold errors (positions, then orientations), (r,), and their Jacobian over z, (r, n)."""
        self.constraint_evaluations += 1
        q = self.configuration(z)
        psi = z[-1]
        positions, rotations, jacobians = self._frames_at(q)
        cz, sz = math.cos(psi), math.sin(psi)
        Rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
        turned = self.hold.offsets @ Rz.T  # (k, 3)
        position_errors = positions - self.target - turned
        if jacobian:  # every hand's position rows at once, (3 k, n)
            position_rows = self._to_z(q, jacobians[:, :3].reshape(-1, jacobians.shape[-1]))
            d_psi = np.zeros((len(turned), 3))  # d(error)/d(psi) = -(d/d psi) R_z(psi) r_i
            d_psi[:, 0], d_psi[:, 1] = turned[:, 1], -turned[:, 0]
            position_rows[:, -1] = d_psi.ravel()
        if not self.orientation:
            value = position_errors.ravel()
            if self.rows is not None:
                value = value[self.rows]
                return (value, position_rows[self.rows]) if jacobian else value
            return (value, position_rows) if jacobian else value
        ez = np.array([0.0, 0.0, 1.0])
        values, rows = [], []
        for i in range(len(self.frames)):
            values.append(position_errors[i])
            if jacobian:
                rows.append(position_rows[3 * i : 3 * i + 3])
            R_t = Rz @ self.hold.rotations[i]
            M = rotations[i].T @ R_t
            values.append(pin.log3(M))
            if jacobian:
                Jl = pin.Jlog3(M)
                block = self._to_z(q, -Jl @ R_t.T @ jacobians[i, 3:])
                block[:, -1] = Jl @ R_t.T @ ez
                rows.append(block)
        value = np.concatenate(values)
        if self.rows is not None:
            value = value[self.rows]
            rows = [np.vstack(rows)[self.rows]] if jacobian else rows
        return (value, np.vstack(rows)) if jacobian else value

    def residual(self, z: np.ndarray) -> float:
        """Largest hold error at z, or the clearance's shortfall below the margin if larger."""
        error = float(np.abs(self.constraints(z, jacobian=False)).max())
        if self.collision is not None:
            error = max(error, -float(np.min(self.clearances(z)[0], initial=np.inf)))
        return error

    def clearances(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The :data:`CLOSEST_PAIRS` smallest signed distances minus the margin over the shape
        pairs that may meet, ascending, (K,) (to keep >= 0), and their Jacobian over z, (K, n).

        All pairs keep the margin exactly when the K smallest do; the sorted smallest distances
        are continuous in z (their gradients switch where two distances are equal). SLSQP's
        subproblem grows with its constraints: 4,436 rows for TIAGo++ cost it five times the
        whole placement's time, the K closest pairs almost nothing."""
        if self._last_clearances is not None and np.array_equal(self._last_clearances[0], z):
            return self._last_clearances[1]  # SLSQP asks for the values and the Jacobian apart
        q = self.configuration(z)
        d, G = self._pair_distances.distances(q)  # q from the optimiser: finite, unit (cos, sin) by construction
        rows = np.argsort(d, kind="stable")[:CLOSEST_PAIRS]
        out = (d[rows] - self.collision.margin, self._to_z(q, G[rows]))
        self._last_clearances = (z.copy(), out)
        return out

    # ----- starts -----

    def start(self, heading: float, rng: np.random.Generator) -> np.ndarray:
        """The reference hold placed at the target with the platform at ``heading``, its joints
        moved by up to 0.2 rad at random (off a singular reference posture such as straight arms)."""
        c, s = math.cos(heading), math.sin(heading)
        center = self.hold.center[:2]
        xy = self.target[:2] - np.array([c * center[0] - s * center[1], s * center[0] + c * center[1]])
        if self.region is not None:
            xy = self.region.clip(xy)
        q = self.q_ref.copy()
        q[:4] = (xy[0], xy[1], c, s)
        z = self.variables(q, heading)
        z[3:-1] += rng.uniform(-0.2, 0.2, len(self.joint_ids))
        return z


def _grasp_spread(hold) -> float:
    return float(np.abs(hold.offsets).max()) if hold.offsets.size else 0.0


def slsqp_constraints(problem: PlacementProblem) -> list[dict]:
    """SLSQP's constraint dictionaries for one run. SLSQP asks for the hold errors and then their
    Jacobian at the same point: both come from one Pinocchio pass, kept for the last point."""
    last: list = [None, None]

    def hold(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = z.tobytes()  # SLSQP changes its x in place: compare the values, bit for bit
        if last[0] != key:
            last[:] = key, problem.constraints(z)
        return last[1]

    out = [{"type": "eq", "fun": lambda z: hold(z)[0], "jac": lambda z: hold(z)[1]}]
    if problem.collision is not None and problem.collision_rows.size:
        out.append(
            {"type": "ineq", "fun": lambda z: problem.clearances(z)[0], "jac": lambda z: problem.clearances(z)[1]}
        )
    return out


def slsqp_run(
    problem: PlacementProblem, fun, z0: np.ndarray, bounds, max_iterations: int, tolerance: float
) -> np.ndarray:
    """SLSQP's last iterate minimising ``fun`` (value and gradient at z) from ``z0``, within
    ``bounds``, under the problem's hold (and clearance) constraints; it may stop off the hold
    (check :meth:`PlacementProblem.residual`)."""
    res = minimize(
        fun,
        z0,
        jac=True,
        method="SLSQP",
        bounds=bounds,
        constraints=slsqp_constraints(problem),
        options={"maxiter": max_iterations, "ftol": tolerance},
    )
    return res.x


def clip_to_bounds(z: np.ndarray, bounds) -> np.ndarray:
    z = z.copy()
    for k, (lo, hi) in enumerate(bounds):
        if lo is not None:
            z[k] = max(z[k], lo)
        if hi is not None:
            z[k] = min(z[k], hi)
    return z


def _project(problem: PlacementProblem, z0: np.ndarray, bounds) -> np.ndarray | None:
    """The nearest z (in the variables' own units) that holds the object; None if not found."""

    def distance(z: np.ndarray) -> tuple[float, np.ndarray]:  # half the squared distance to z0, its gradient
        return 0.5 * float((z - z0) @ (z - z0)), z - z0

    z = slsqp_run(problem, distance, clip_to_bounds(z0, bounds), bounds, 200, 1e-12)
    return z if problem.residual(z) <= CONSTRAINT_TOLERANCE else None


def place(
    robot: Robot,
    target: ArrayLike,
    objective: Objective | str,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    decoupled: bool = False,
    region: Region | None = None,
    reference: np.ndarray | None = None,
    starts: int = DEFAULT_STARTS,
    max_iterations: int = 100,
    tolerance: float = 1e-9,
    hold_turn: float | None = None,
    collision: SelfCollision | None = None,
    seeds: Sequence[tuple[np.ndarray, float]] = (),
) -> Placement:
    """The platform pose and arm posture that hold the object at ``target`` and maximise ``objective``.

    Args:
        robot: the loaded robot (a moving platform; S constant in q).
        target: the object centre in the world (m), (3,).
        objective: e.g. ``"kinematic:capacity:+x"`` or ``"dynamic:log_volume"``
            (:meth:`mobmanip.gradients.Objective.parse`).
        task: task space; default the spec's.
        object_mass: mass of the held object (kg); default the spec's.
        decoupled: the decoupled P for the dynamic ellipsoid.
        region: the platform origin's allowed rectangle; default anywhere.
        reference: the posture whose hold is kept (nq,); default the spec's hold posture.
        starts: number of starts (platform headings spread evenly around the object).
        max_iterations: SLSQP iterations per start.
        tolerance: SLSQP's ``ftol``: a run stops when the objective changes less than this.
        hold_turn: a fixed turn psi of the hold about the vertical (rad), i.e. a fixed object
            orientation (the reference hold's turned by psi); default free.
        collision: a :class:`mobmanip.robot.collision.SelfCollision`: keep its shape pairs at least its
            margin apart (inequality constraints with their distance gradients); default none.
        seeds: more starts, each (configuration (nq,), hold turn psi): e.g. the best cells of a
            map of this request (:func:`mobmanip.placement.maps.placement_map`), so that the
            placement is at least as good as the best of them (a run never ends below its start).

    Returns:
        The best placement found (see :class:`Placement`).

    Raises:
        ArgumentError: a malformed target, region or number of starts.
        MeasureError: an objective unknown for the measure.
        UnreachableObjectError: no start holds the object at ``target`` (within the region).
    """
    started = time.perf_counter()
    target = check_target(target)
    if isinstance(starts, bool) or not isinstance(starts, int) or starts < 1:
        raise ArgumentError(f"starts must be a positive integer, got {starts!r}")
    seeds = tuple(seeds)
    if robot.platform_locked:
        raise ArgumentError(f"robot {robot.name!r} has a fixed platform: there is no base placement to choose")
    compiled = None if (starts + len(seeds)) * max_iterations >= COMPILED_FROM_ROUNDS else False
    problem = PlacementProblem.of_objective(
        robot, objective, task, target, region, reference, collision, object_mass=object_mass, decoupled=decoupled,
        compiled=compiled,
    )  # fmt: skip
    evaluator = problem.ev
    bounds = problem.bounds()
    if hold_turn is not None:
        hold_turn = check_turn(hold_turn)
        bounds[-1] = (hold_turn, hold_turn)
    best = None
    runs: list[tuple[float | None, float | None]] = []
    best_start = None
    best_start_q = None
    fixed = problem.fixed_errors(problem.start(0.0, np.random.default_rng(0)))
    if fixed.size and np.abs(fixed).max() > CONSTRAINT_TOLERANCE:
        raise UnreachableObjectError(
            f"no pose holds the object at {target.tolist()} m: {robot.name}'s hands cannot change "
            f"{'height' if problem.rows.size else 'position'} (the hold misses by {np.abs(fixed).max():.4g})"
        )
    rng = np.random.default_rng(0)
    firsts = []
    for s in range(starts):
        z0 = problem.start(2.0 * math.pi * s / starts, rng)
        if hold_turn is not None:  # the object's orientation fixed: the arms turn it from the start's
            z0[-1] = hold_turn
        firsts.append(z0)
    for q_seed, psi in seeds:
        z0 = problem.variables(robot.check_configuration(q_seed), float(psi))
        if hold_turn is not None:
            z0[-1] = hold_turn
        firsts.append(z0)

    def run(z0: np.ndarray) -> tuple[float | None, np.ndarray | None, tuple[float, np.ndarray, float] | None]:
        """(start value, start configuration, (value, z, residual) of the run's result or None)."""
        z0 = _project(problem, z0, bounds)
        if z0 is None:
            return None, None, None
        start_value = -problem.objective(z0)[0]
        start_value = None if start_value <= -1e6 else start_value
        z = slsqp_run(problem, problem.objective, z0, bounds, max_iterations, tolerance)
        if problem.residual(z) > CONSTRAINT_TOLERANCE:  # stopped between iterates: back onto the hold
            z = _project(problem, z, bounds)
            if z is None:
                return start_value, z0, None
        residual = problem.residual(z)
        value, ok = problem.value_at(problem.configuration(z))
        if residual > CONSTRAINT_TOLERANCE or not ok:
            return start_value, z0, None
        if start_value is not None and start_value > value:  # SLSQP ended below its (held) start
            start_residual = problem.residual(z0)
            if start_residual <= CONSTRAINT_TOLERANCE:
                return start_value, z0, (float(start_value), z0, start_residual)
        return start_value, z0, (float(value), z, residual)

    # The starts run together: their evaluations are batched, each start's run as on its own.
    for start_value, z0, result in problem.lockstep.run([functools.partial(run, z0) for z0 in firsts]):
        if start_value is not None and (best_start is None or start_value > best_start):
            best_start = start_value
            best_start_q = problem.configuration(z0)
        runs.append((start_value, None if result is None else result[0]))
        if result is not None and (best is None or result[0] > best[0]):
            best = result
    if best is None:
        where = "" if region is None else f" with the platform in region {_region_text(region)}"
        raise UnreachableObjectError(
            f"no pose holds the object at {target.tolist()} m{where} ({starts} starts; "
            f"{robot.name}'s hold keeps the object {problem.hold.height:.3f} m high in its reference posture)"
        )
    value, z, residual = best
    _log.info(
        "placement of %s for %s: %.6g after %d evaluations from %d starts (best start %s)",
        robot.name,
        evaluator.objective.text,
        value,
        evaluator.evaluations,
        starts,
        "none" if best_start is None else f"{best_start:.6g}",
    )
    return Placement(
        q=problem.configuration(z),
        objective=evaluator.objective,
        value=value,
        start_value=best_start,
        target=target,
        hold_turn=float(z[-1]),
        residual=residual,
        evaluations=evaluator.evaluations,
        constraint_evaluations=problem.constraint_evaluations,
        runs=tuple(runs),
        seconds=time.perf_counter() - started,
        start_q=best_start_q,
    )


def check_turn(value) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not math.isfinite(value)
    ):
        raise ArgumentError(f"object yaw (hold turn) must be a finite angle in radians, got {value!r}")
    return float(math.remainder(float(value), 2.0 * math.pi))


def _region_text(region: Region) -> str:
    return f"x {region.x_min:g}..{region.x_max:g} m, y {region.y_min:g}..{region.y_max:g} m"


def check_target(target) -> np.ndarray:
    try:
        t = np.asarray(target, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ArgumentError(f"object position must be three numbers X,Y,Z in metres, got {target!r}") from None
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise ArgumentError(f"object position must be three finite numbers X,Y,Z in metres, got {target!r}")
    return t


def placement_document(robot: Robot, placement: Placement, analysis: Analysis) -> dict:
    """The JSON document of ``mobmanip place --json``: the configuration under ``"q"`` in the
    q.json form (``{"platform": [x, y, yaw], "joints": {...}}``), the objective, its value, the
    start's value, the search's cost and ``"analysis"``, the configuration's analysis as
    ``mobmanip analyze --json`` writes it."""
    return {
        "robot": robot.name,
        "object": placement.target.tolist(),
        "objective": placement.objective.name,
        "value": placement.value,
        "start_value": placement.start_value,
        "hold_turn": placement.hold_turn,
        "hold_error": placement.residual,
        "evaluations": placement.evaluations,
        "starts": [{"start_value": s, "value": v} for s, v in placement.runs],
        "starts_agreeing": placement.agreement(),
        "seconds": placement.seconds,
        "q": robot.configuration_dict(placement.q),
        "analysis": analysis.to_dict(),
    }


def object_gradient(
    robot: Robot,
    placement: Placement,
    task: str | None = None,
    *,
    object_mass: float | None = None,
    decoupled: bool = False,
    region: Region | None = None,
    active_tolerance: float = 1e-7,
) -> np.ndarray:
    """d(best value)/d(object centre), (3,) (per m, world), at a placement's optimum.

    By the envelope theorem the optimal value V(X) of max f(z) s.t. h(z, X) = 0 changes with the
    object centre X as lambda^T dh/dX, with the multipliers lambda of the hold constraints from
    the optimum's stationarity, grad f = J_h^T lambda over the variables not at a bound (least
    squares). The hold's position errors are p_i - X - R_z(psi) r_i, so dh/dX = -I on each
    hand's position rows. A direction no variable can follow (the height of a planar arm's
    hands) gets NaN: the object cannot move that way while held.

    Args:
        robot, placement: the robot and :func:`place`'s result for it.
        task, object_mass, decoupled, region: as given to :func:`place`.
        active_tolerance: a variable this close to a bound (rad or m) counts as held there.

    Raises:
        MeasureError: the objective is not differentiable at the optimum.
    """
    from ..errors import MeasureError

    task = get_task(task or robot.spec.default_task)
    evaluator = GradientEvaluator(robot, placement.objective, task, object_mass=object_mass, decoupled=decoupled)
    problem = PlacementProblem(robot, evaluator, placement.target, region, robot.hold_configuration())
    z = problem.variables(placement.q, placement.hold_turn)
    cost, grad = problem.objective(z)
    if cost >= 1e6:
        raise MeasureError(f"{placement.objective.name} is not differentiable at the placement's optimum")
    _, J = problem.constraints(z)
    free = np.ones(problem.n, dtype=bool)
    for k, (lo, hi) in enumerate(problem.bounds()):
        if (lo is not None and z[k] <= lo + active_tolerance) or (hi is not None and z[k] >= hi - active_tolerance):
            free[k] = False
    lam, *_ = np.linalg.lstsq(J[:, free].T, -grad[free], rcond=None)  # grad f = J^T lambda (f = -cost)
    # the full (unreduced) rows: positions then, with orientation, three more per hand
    per_hand = 6 if problem.orientation else 3
    dh_dX = np.zeros((per_hand * len(problem.frames), 3))
    for i in range(len(problem.frames)):
        dh_dX[per_hand * i : per_hand * i + 3] = -np.eye(3)
    dh_dX = dh_dX[problem.rows]
    out = -(lam @ dh_dX)  # dV/dX = d(f - lambda^T h)/dX
    followed = np.abs(dh_dX).sum(axis=0) > 0
    return np.where(followed, out, np.nan)
