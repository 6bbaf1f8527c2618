"""Teams that move: several mobile manipulators carrying one object along a path.

``carry`` (:mod:`mobmanip.motion.carry`) for a team (:mod:`mobmanip.team`). One quadratic
program per time step over the team's reduced velocities x = (x_1, ..., x_k), each robot's wheel
and joint rates, so that every platform keeps its own nonholonomic constraint exactly (robot i's
velocity is S_i x_i: a differential drive cannot slide sideways)::

    minimise    1/2 x^T D^-2 x - w g^T x + sum_i beta_i / 2 |J_p,i x_i - v_i*|^2   (D = diag(xdot_max))
    subject to  J x = b                                        (every hand follows the object)
                max(-xdot_max, (q_lo - q) / T) <= x <= min(xdot_max, (q_hi - q) / T)
                |tau(x)| <= 0.99 tau_max                       (every robot's wheels and joints)

J = blkdiag(J_i S_i) over each robot's grasping hands (their task rows) and b the hands' task
velocities that bring each hand to its target at the next step: the hands keep the grasp of the
start, each hand's target is its start pose moved with the object (translated along the path
and turned about the vertical by the path's turn), so the object follows the path and the hands
keep their places on it (the grasp constraints tie every hand to the one object). The limits
and T are ``carry``'s (:func:`mobmanip.motion.carry_step.velocity_bounds`); tau is the efforts
of the paper's policy for the whole team (:func:`mobmanip.coordination.effort.team_step_maps`),
the load shared by W^+ over all hands. g is the gradient of the team's capacity
(:class:`mobmanip.coordination.capacity.TeamCapacity`: the measure ``mobmanip team`` computes,
for the object held by all hands) over x; w is fixed at the first step so that the capacity
term alone would move at half the velocity limits, as in ``carry``. The last term is each
platform's soft task along the path (:mod:`mobmanip.coordination.platform_task`): a control
point off its axle follows where the object would carry it, so the platforms turn with the path
(without it the beam example's arms absorbed the turn until a joint reached its range, 4 s in).

As in ``carry``, the capacity-aware motion first moves to a better posture with the object held
still (a self-motion of the whole team, for at most ``prepare`` seconds); the baseline tracks
the same targets from the team's start posture with the weighted pseudo-inverse
``x = D^2 J^T (J D^2 J^T)^-1 b`` (no capacity term, no limits; J being block-diagonal, each
robot's own).

**Internal forces.** The QP is kinematic in the hands' motion and the load is shared by the
least-norm wrenches W^+ (M_o a_o + c_o + g_o): in the model the hands apply no internal
(squeezing or stretching) force, and every robot's efforts for that share stay within its
limits. What would load a real object internally is the hands' disagreement with the rigid
grasp: each run reports ``grasp_strain``, the largest change of a distance between two hands from
the start (m), bounded by twice the largest hand error; with grasps of stiffness k the internal
force is about k times it. Internal forces are not decision variables here: they are bounded
through the tracking, not chosen to widen the efforts.

The path (:class:`mobmanip.motion.carry.ObjectPath`) is relative to where the start posture
holds the object; with ``frame="object"`` (the default) its x axis is the object's heading at the
start (for a beam, along it: the path ``x`` moves the beam lengthwise), with ``"world"`` the
world's axes.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
import scipy.linalg

from ..errors import ArgumentError, CarryFailed, MeasureError
from ..gradients import Objective
from ..motion.carry import (
    DEFAULT_GAIN,
    DEFAULT_PREPARE,
    DEFAULT_STEP,
    PREPARE_TOLERANCE,
    PREPARE_WINDOW,
    TIME_DECIMALS,
    ObjectPath,
    check_step_settings,
)
from ..motion.carry_floor import CarryFloor
from ..motion.carry_step import CarryDiagnosis, solve_step_qp, velocity_bounds
from ..motion.step_constraints import StepRows, check_constraints, step_rows
from ..motion.trajectory import tangent_integrate
from ..robot.tasks import get_task
from ..support.progress import progress_bar
from ..team import Member, Team
from ..terms.builder import terms_at
from ..terms.constraints.base import Constraint
from ..terms.grasp import HeldObject
from .capacity import TeamCapacity
from .effort import diagnose_team_step, effort_rows, team_step_maps
from .floor import TeamFloor
from .platform_task import PlatformTask

__all__ = ["FRAMES", "TeamCarryResult", "TeamCarryRun", "lateral_slip", "team_carry"]

#: The frames a path may be given in.
FRAMES = ("object", "world")


@dataclass(frozen=True)
class TeamCarryRun:
    """One synthesised motion of the team.

    Attributes:
        method: ``"qp"``, ``"pinv"`` (the weighted pseudo-inverse baseline) or ``"self-motion"``.
        t: time stamps (s), (N,).
        q: each robot's configurations, one (N, nq_i) array per robot, in the team's order.
        x: each robot's reduced velocities held over each step, one (N - 1, nx_i) per robot.
        capacity: the team's objective at each time, (N,).
        tracking_error: distance of the hands' centroid from their targets' centroid (m), (N,):
            the object's position error for an object moving rigidly with its hands.
        hand_error: largest distance of a hand from its target position (m), (N,).
        turn_error: largest angle of a hand's orientation from its target (rad), (N,).
        grasp_strain: largest change of a distance between two hands from the run's start (m), (N,).
        effort: largest modelled effort of any wheel or joint over its limit during each step,
            (N - 1,) (the policy's efforts; the QP keeps it within 0.99).
        zmp_margin: on the floor, each robot's zero-moment point margin to its support polygon
            during each step (m), (N - 1, robots); ``None`` off the floor.
        traction_use: on the floor, each robot's largest wheel traction use during each step,
            (N - 1, robots) (NaN without a friction coefficient); ``None`` off the floor.
    """

    method: str
    t: np.ndarray
    q: tuple[np.ndarray, ...]
    x: tuple[np.ndarray, ...]
    capacity: np.ndarray
    tracking_error: np.ndarray
    hand_error: np.ndarray
    turn_error: np.ndarray
    grasp_strain: np.ndarray
    effort: np.ndarray
    zmp_margin: np.ndarray | None = None
    traction_use: np.ndarray | None = None

    def shifted(self, dt: float) -> TeamCarryRun:
        """The run with its time stamps moved by dt (s)."""
        return dataclasses.replace(self, t=np.round(self.t + dt, TIME_DECIMALS))


def _largest_use(uses: np.ndarray) -> float | str | None:
    """A robot's largest traction use along a run, JSON-ready: ``None`` without a friction
    coefficient, ``"unloaded"`` where a wheel lost its load (its use is unbounded)."""
    if np.isnan(uses).all():
        return None
    largest = float(np.nanmax(uses))
    return largest if math.isfinite(largest) else "unloaded"


def lateral_slip(robot: Any, t: np.ndarray, qs: np.ndarray) -> np.ndarray:
    """Each step's platform velocity across its heading (m/s), (N - 1,): the displacement between
    consecutive poses projected on the normal of the mean heading, over the step (zero for an arc
    driven without slip, whatever its curvature). Zero for a platform without a planar root."""
    root = robot.model.joints[1]
    if root.shortname() != "JointModelPlanar":
        return np.zeros(max(len(t) - 1, 0))
    block = np.asarray(qs)[:, root.idx_q : root.idx_q + 4]
    heading = np.unwrap(np.arctan2(block[:, 3], block[:, 2]))
    mid = 0.5 * (heading[1:] + heading[:-1])
    step = np.diff(block[:, :2], axis=0)
    across = -np.sin(mid) * step[:, 0] + np.cos(mid) * step[:, 1]
    return across / np.diff(t)


@dataclass(frozen=True)
class TeamCarryResult:
    """The capacity-maximising motion of a team and its baseline along the same path.

    Attributes:
        team: the team (its start configurations are the members' ``q``).
        objective: the measure maximised (and reported as capacity).
        motion, baseline: the QP motion along the path and the pseudo-inverse one.
        preparation: the self-motion before the path, or ``None`` (``prepare=0``).
        frame: the path's frame (``"object"`` or ``"world"``).
        start: the posture both runs set out from, in words.
        floor: the floor the QP motion kept (:meth:`mobmanip.motion.carry_floor.CarryFloor.describe`),
            or ``None``.
        constraints: the constraints every robot kept (each one's ``describe()``).
    """

    team: Team
    objective: Objective
    motion: TeamCarryRun
    baseline: TeamCarryRun
    preparation: TeamCarryRun | None = None
    frame: str = "object"
    start: str = "the team's posture"
    floor: dict | None = None
    constraints: tuple[dict, ...] = ()

    @property
    def task(self) -> str:
        return self.team.task

    def robots(self) -> tuple[str, ...]:
        return tuple(m.name for m in self.team.members)

    def slip(self, run: TeamCarryRun) -> float:
        """The largest lateral slip of any platform along a run (m/s)."""
        values = [np.abs(lateral_slip(m.robot, run.t, q)) for m, q in zip(self.team.members, run.q)]
        return float(max((v.max() for v in values if v.size), default=0.0))

    def hand_positions(self, run: TeamCarryRun) -> np.ndarray:
        """Every grasping hand's world position along a run (m), (N, n_hands, 3), by forward kinematics."""
        return np.array(
            [[h.translation for h in _hand_poses(self.team, [q[k] for q in run.q])] for k in range(len(run.t))]
        )

    def carried(self, qs: Sequence[np.ndarray]) -> tuple[Team, float]:
        """The team at the configurations ``qs`` (one per robot) with its object where the hands
        carry it, and the object's turn (rad) from the team's start.

        The object moves rigidly with its hands: its pose is the planar rigid motion (a turn about
        the vertical and a shift, least squares over the hands; the height shifts by the hands'
        mean) that takes the hands from their grasp at the start (``team.held_object``) to where
        the robots hold them at ``qs``; its grasp offsets are the hands' positions from the moved
        centre, its inertia turned with it.
        """
        team = self.team
        start = team.held_object
        before = start.center + start.offsets
        after = np.array([hand.translation for hand in _hand_poses(team, qs)])
        a, b = before - before.mean(axis=0), after - after.mean(axis=0)
        # the angle of sum(conj(a) b) over the hands, a and b as complex numbers x + iy
        turn = math.atan2(float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])), float(np.sum(a[:, :2] * b[:, :2])))
        R = pin.rpy.rpyToMatrix(0.0, 0.0, turn)
        centre = after.mean(axis=0) + R @ (start.center - before.mean(axis=0))
        held = HeldObject(start.mass, R @ start.inertia @ R.T, centre, after - centre)
        members = tuple(Member(m.name, m.robot, np.asarray(q, dtype=float), m.arms) for m, q in zip(team.members, qs))
        grasp_points = centre + (team.grasp_points - start.center) @ R.T
        moved = dataclasses.replace(
            team, members=members, held_object=held, grasp_points=grasp_points, object_yaw=team.object_yaw + turn
        )
        return moved, turn

    def platform_distance(self, run: TeamCarryRun) -> float | None:
        """The smallest distance between two platforms' reference points along a run (m); the QP
        does not keep robots apart (no collision rows), this says how close they came. ``None``
        for a team of one robot."""
        points = []
        for member, q in zip(self.team.members, run.q):
            root = member.robot.model.joints[1]
            points.append(q[:, root.idx_q : root.idx_q + 2])
        best = math.inf
        for i in range(len(points)):
            for j in range(i + 1, len(points)):
                best = min(best, float(np.min(np.linalg.norm(points[i] - points[j], axis=1))))
        return best if math.isfinite(best) else None

    def limits_kept(self, run: TeamCarryRun) -> tuple[float, int]:
        """(largest reduced velocity over its limit, samples with a joint beyond its position
        range) along a run, over every robot (the baseline has no limits and may break them)."""
        share, beyond = 0.0, np.zeros(len(run.t), dtype=bool)
        for member, q, x in zip(self.team.members, run.q, run.x):
            robot = member.robot
            if x.size:
                share = max(share, float(np.max(np.abs(x) / np.asarray(robot.velocity_limits, dtype=float))))
            model = robot.model
            for joint in model.joints[1:]:
                if joint.nq == 1:
                    values = q[:, joint.idx_q]
                    lower, upper = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
                    beyond |= (values < lower - 1e-9) | (values > upper + 1e-9)
        return share, int(beyond.sum())

    def summary(self) -> dict:
        """Minimum capacities, their ratio, tracking, slip, strain and effort figures (JSON-ready)."""
        out: dict[str, Any] = {
            "team": self.team.name,
            "robots": list(self.robots()),
            "objective": self.objective.name,
            "task": self.task,
            "path_frame": self.frame,
        }
        runs = [self.motion, self.baseline] + ([self.preparation] if self.preparation is not None else [])
        for run in runs:
            out[run.method] = {
                "min_capacity": float(run.capacity.min()),
                "mean_capacity": float(run.capacity.mean()),
                "max_tracking_error": float(run.tracking_error.max()),
                "max_hand_error": float(run.hand_error.max()),
                "max_turn_error": float(run.turn_error.max()),
                "max_grasp_strain": float(run.grasp_strain.max()),
                "max_lateral_slip": self.slip(run),
                "max_effort_share": float(run.effort.max()) if run.effort.size else 0.0,
                "max_velocity_share": self.limits_kept(run)[0],
                "samples_beyond_a_joint_range": self.limits_kept(run)[1],
                "min_platform_distance": self.platform_distance(run),
                "seconds": float(run.t[-1] - run.t[0]),
            }
            if run.zmp_margin is not None and run.traction_use is not None and run.zmp_margin.size:
                uses = run.traction_use
                out[run.method]["floor"] = {
                    "min_zmp_margin": dict(zip(self.robots(), run.zmp_margin.min(axis=0).tolist())),
                    "max_traction_use": dict(zip(self.robots(), [_largest_use(u) for u in uses.T])),
                }
        if self.floor is not None:
            out["floor"] = self.floor
        if self.constraints:
            out["constraints"] = list(self.constraints)
        out["pinv"]["start"] = {"posture": self.start, "capacity": float(self.baseline.capacity[0])}
        posture = self.start if self.preparation is None else f"the end of a self-motion from {self.start}"
        out["qp"]["start"] = {"posture": posture, "capacity": float(self.motion.capacity[0])}
        base = self.baseline.capacity.min()
        out["min_capacity_ratio"] = float(self.motion.capacity.min() / base) if base > 0 else None
        mean = self.baseline.capacity.mean()
        out["mean_capacity_ratio"] = float(self.motion.capacity.mean() / mean) if mean > 0 else None
        out["internal_forces"] = (
            "the load is shared by the least-norm hand wrenches (no internal force in the model); "
            "max_grasp_strain is the hands' disagreement with the rigid grasp that would load the object"
        )
        return out


class _Targets:
    """Every hand's target pose along the path (see the module's docstring)."""

    def __init__(self, team: Team, qs: Sequence[np.ndarray], path: ObjectPath, times: np.ndarray, frame: str):
        self.hands: list[pin.SE3] = []
        for member, q in zip(team.members, qs):
            robot = member.robot
            pin.framesForwardKinematics(robot.model, robot.data, q)
            self.hands.extend(robot.data.oMf[robot.arms[a].frame_id].copy() for a in member.arms)
        self.center0 = np.asarray(team.held_object.center, dtype=float)
        shift, self.turn = path.sample(times)
        if frame == "object":
            c, s = math.cos(team.object_yaw), math.sin(team.object_yaw)
            shift = shift @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        self.shift = shift
        self.offsets0 = np.array([h.translation for h in self.hands]) - self.center0
        self.inertia0 = team.held_object.inertia
        self.mass = team.held_object.mass

    def rotation(self, k: int) -> np.ndarray:
        return pin.rpy.rpyToMatrix(0.0, 0.0, float(self.turn[k]))

    def hand(self, k: int, i: int) -> pin.SE3:
        R = self.rotation(k)
        start = self.hands[i]
        return pin.SE3(R @ start.rotation, self.center0 + self.shift[k] + R @ self.offsets0[i])

    def held(self, k: int) -> HeldObject:
        """The object where the path has it at step k, its grasp offsets turned with it."""
        R = self.rotation(k)
        return HeldObject(self.mass, R @ self.inertia0 @ R.T, self.center0 + self.shift[k], self.offsets0 @ R.T)


def _hand_poses(team: Team, qs: Sequence[np.ndarray]) -> list[pin.SE3]:
    """Every grasping hand's pose (frame placements of each robot's data updated)."""
    out: list[pin.SE3] = []
    for member, q in zip(team.members, qs):
        robot = member.robot
        pin.framesForwardKinematics(robot.model, robot.data, q)
        out.extend(robot.data.oMf[robot.arms[a].frame_id].copy() for a in member.arms)
    return out


def _jacobian(team: Team, qs: Sequence[np.ndarray], rows: list[int]) -> np.ndarray:
    """J = blkdiag(J_i S_i) over each robot's grasping hands' task rows."""
    blocks = []
    for member, q in zip(team.members, qs):
        robot = member.robot
        model, data = robot.model, robot.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        J = np.vstack(
            [
                pin.getFrameJacobian(model, data, robot.arms[a].frame_id, pin.LOCAL_WORLD_ALIGNED)[rows]
                for a in member.arms
            ]
        )
        blocks.append(J @ robot.null_space(q))
    return scipy.linalg.block_diag(*blocks)


def _errors(hands: list[pin.SE3], targets: _Targets, k: int, start: np.ndarray) -> tuple[float, float, float, float]:
    """(centroid error, largest hand error, largest orientation error, largest strain)."""
    goals = [targets.hand(k, i) for i in range(len(hands))]
    p = np.array([h.translation for h in hands])
    g = np.array([h.translation for h in goals])
    hand = float(np.max(np.linalg.norm(p - g, axis=1)))
    turn = max(float(np.linalg.norm(pin.log3(goal.rotation @ h.rotation.T))) for h, goal in zip(hands, goals))
    distances = np.linalg.norm(p[:, None] - p[None], axis=2)
    strain = float(np.max(np.abs(distances - start))) if len(p) > 1 else 0.0
    return float(np.linalg.norm(p.mean(axis=0) - g.mean(axis=0))), hand, turn, strain


class _Problem:
    """What every run of one team shares: its capacity, limits and names."""

    def __init__(self, team: Team, objective: Objective):
        self.team = team
        self.task = get_task(team.task)
        self.rows = list(self.task.rows)
        self.capacity = TeamCapacity(team, objective)
        self.slices = team.member_slices()
        robots = [m.robot for m in team.members]
        self.D2 = np.concatenate([np.asarray(r.velocity_limits, dtype=float) for r in robots]) ** 2
        self.effort_limits = np.concatenate([np.asarray(r.effort_limits, dtype=float) for r in robots])
        self.names = [f"{m.name}/{n}" for m in team.members for n in m.robot.reduced_velocity_names]

    def bounds(self, qs: Sequence[np.ndarray], h: float) -> tuple[np.ndarray, np.ndarray]:
        pairs = [velocity_bounds(m.robot, q, h) for m, q in zip(self.team.members, qs)]
        return np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])

    def joint_positions(self, qs: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
        """Each reduced velocity's joint position and limits (NaN for wheels) and units."""
        pos, low, up, units = [], [], [], []
        for member, q in zip(self.team.members, qs):
            robot = member.robot
            model = robot.model
            S = robot.null_space(q)
            for k in range(robot.nx):
                v = int(np.flatnonzero(S[:, k])[0])
                joint = next(j for j in model.joints[1:] if j.idx_v <= v < j.idx_v + j.nv)
                wheel = k < robot.platform.n_reduced or joint.nq != 1
                prismatic = not wheel and "P" in joint.shortname().replace("Planar", "")
                units.append(("m/s", "N") if prismatic else ("rad/s", "N m"))
                pos.append(np.nan if wheel else q[joint.idx_q])
                low.append(np.nan if wheel else model.lowerPositionLimit[joint.idx_q])
                up.append(np.nan if wheel else model.upperPositionLimit[joint.idx_q])
        return np.array(pos), np.array(low), np.array(up), units


def _run(
    problem: _Problem,
    qs0: Sequence[np.ndarray],
    path: ObjectPath,
    frame: str,
    dt: float,
    method: str,
    gain: float,
    weight: float | None = None,
    converge: bool = False,
    x_start: np.ndarray | None = None,
    floor: TeamFloor | None = None,
    constraints: tuple[Constraint, ...] = (),
    progress: bool = False,
) -> tuple[TeamCarryRun, float]:
    """One motion of the team along ``path`` from ``qs0``; returns it and the capacity term's weight
    (``floor``: every robot keeps it, but for the pseudo-inverse baseline, which only reads it)."""
    team = problem.team
    n = int(math.floor((path.t[-1] - path.t[0]) / dt + 1e-9)) + 1
    times = np.round(path.t[0] + dt * np.arange(n), TIME_DECIMALS)
    if times[-1] < path.t[-1] - 1e-12:
        times = np.append(times, path.t[-1])
        n += 1
    targets = _Targets(team, qs0, path, times, frame)
    nx = team.nx
    H = np.diag(1.0 / problem.D2)
    Q = [np.zeros((n, m.robot.model.nq)) for m in team.members]
    X = np.zeros((n - 1, nx))
    capacity, track, hand, turn, strain = (np.zeros(n) for _ in range(5))
    effort = np.zeros(max(n - 1, 0))
    margins = None if floor is None else np.zeros((max(n - 1, 0), len(team.members)))
    uses = None if floor is None else np.zeros((max(n - 1, 0), len(team.members)))
    qs = [np.array(q, dtype=float) for q in qs0]
    p0 = np.array([h.translation for h in _hand_poses(team, qs)])
    start_distances = np.linalg.norm(p0[:, None] - p0[None], axis=2)
    x_prev = np.zeros(nx) if x_start is None else np.asarray(x_start, dtype=float)
    window = max(1, int(round(PREPARE_WINDOW / dt)))
    platforms = PlatformTask(team, qs, targets.center0 + targets.shift, targets.turn) if method == "qp" else None

    def partial(k: int) -> TeamCarryRun:
        return TeamCarryRun(
            method, times[: k + 1], tuple(q[: k + 1] for q in Q), tuple(X[:k, s] for s in problem.slices),
            capacity[: k + 1], track[: k + 1], hand[: k + 1], turn[: k + 1], strain[: k + 1], effort[:k],
            None if margins is None else margins[:k], None if uses is None else uses[:k],
        )  # fmt: skip

    with progress_bar(n, desc=f"team-carry {method}", unit="step", show=progress) as bar:
        for k in range(n):
            bar.update(1)
            for i, q in enumerate(qs):
                Q[i][k] = q
            held = targets.held(k)
            try:
                if method == "pinv":
                    capacity[k], grad = problem.capacity.value(qs, held), None
                else:
                    capacity[k], grad = problem.capacity.gradient(qs, held)
            except MeasureError as exc:
                raise MeasureError(f"{exc} at step {k} (t = {times[k]:g} s) of the team's {method} motion") from None
            track[k], hand[k], turn[k], strain[k] = _errors(_hand_poses(team, qs), targets, k, start_distances)
            if converge and k >= window and capacity[k] - capacity[k - window] < PREPARE_TOLERANCE * abs(capacity[k]):
                n = k + 1
                break
            if k == n - 1:
                break
            h = float(times[k + 1] - times[k])
            J = _jacobian(team, qs, problem.rows)  # also updates the frame placements
            hands = _hand_poses(team, qs)
            b = (
                np.concatenate(
                    [
                        np.concatenate([g.translation - now.translation, pin.log3(g.rotation @ now.rotation.T)])[
                            problem.rows
                        ]
                        for now, g in ((now, targets.hand(k + 1, i)) for i, now in enumerate(hands))
                    ]
                )
                / h
            )
            maps = team_step_maps(team, qs, x_prev, h, problem.task, held)
            A, offset = maps.efforts
            wrenches = None
            if method == "pinv":
                D2 = problem.D2
                x = D2 * (J.T @ np.linalg.solve((J * D2) @ J.T, b))
            else:
                assert grad is not None
                if weight is None:
                    norm = float(np.linalg.norm(np.sqrt(problem.D2) * grad))
                    weight = gain / norm if norm > 0 else 0.0
                lo, hi = problem.bounds(qs, h)
                G, g_hi = effort_rows(A, offset, problem.effort_limits)
                extra = None
                if constraints:  # every robot keeps them, on its own rows
                    extra = _constraint_rows(team, qs, x_prev, h, problem.task, (A, offset), constraints)
                    G, g_hi = np.vstack([G, extra.G]), np.r_[g_hi, extra.h]
                H_k, c_k = H, -weight * grad
                if platforms is not None:
                    H_p, c_p = platforms.cost(qs, k, h)
                    H_k, c_k = H + H_p, c_k + c_p
                if floor is not None:  # the baseline only reads it
                    wrenches = floor.wrenches(team, qs, x_prev, h, problem.task, held, maps.hand_wrenches)
                    floor_G, floor_g, labels, kinds = floor.step_rows(team, qs, wrenches)
                    x = solve_step_qp(H_k, c_k, J, b, lo, hi, np.vstack([G, floor_G]), np.r_[g_hi, floor_g])
                    if x is None and solve_step_qp(H_k, c_k, J, b, lo, hi, G, g_hi) is not None:
                        binding = _floor_binding(H_k, c_k, J, b, lo, hi, G, g_hi, floor_G, floor_g, labels)
                        # a turn the base cannot make is no matter of speed
                        turning = binding in labels and kinds[labels.index(binding)] == "no turn"
                        diagnosis = CarryDiagnosis(k, float(times[k]), binding, "floor", slowing_helps=not turning)
                        raise CarryFailed(f"the team's carry QP has no solution: {diagnosis.message()}", diagnosis,
                                          partial(k))  # fmt: skip
                else:
                    x = solve_step_qp(H_k, c_k, J, b, lo, hi, G, g_hi)
                if x is None and extra is not None:
                    own = len(g_hi) - len(extra.h)
                    free = solve_step_qp(H_k, c_k, J, b, lo, hi, G[:own], g_hi[:own])
                    if free is not None:  # the constraints bind: name the row the step breaks most without them
                        label = extra.labels[int(np.argmax(extra.G @ free - extra.h))]
                        diagnosis = CarryDiagnosis(k, float(times[k]), label, "constraint")
                        raise CarryFailed(f"the team's carry QP has no solution: {diagnosis.message()}", diagnosis,
                                          partial(k))  # fmt: skip
                if x is None:
                    pos, low, up, units = problem.joint_positions(qs)
                    diagnosis = diagnose_team_step(
                        problem.names, units, H, J, b, lo, hi, np.sqrt(problem.D2), A, offset, problem.effort_limits,
                        pos, (low, up), k, float(times[k]),
                    )  # fmt: skip
                    message = f"the team's carry QP has no solution: {diagnosis.message()}"
                    raise CarryFailed(message, diagnosis, partial(k))
            X[k] = x
            effort[k] = float(np.max(np.abs(A @ x + offset) / problem.effort_limits))
            if floor is not None and margins is not None and uses is not None:
                if wrenches is None:
                    wrenches = floor.wrenches(team, qs, x_prev, h, problem.task, held, maps.hand_wrenches)
                margins[k], uses[k] = floor.readings(team, qs, wrenches, x)
            x_prev = x
            qs = [
                tangent_integrate(m.robot.model, q, m.robot.null_space(q) @ x[s] * h)
                for m, q, s in zip(team.members, qs, problem.slices)
            ]
    return partial(n - 1), (0.0 if weight is None else weight)


def _constraint_rows(
    team: Team,
    qs: Sequence[np.ndarray],
    x_prev: np.ndarray,
    h: float,
    task: Any,
    efforts: tuple[np.ndarray, np.ndarray],
    constraints: tuple[Constraint, ...],
) -> StepRows:
    """Every robot's rows of the ``constraints`` over the team's step (each robot's at its own
    terms at rest, its efforts those of the team's policy), labelled ``"ROBOT: row"``."""
    A, offset = efforts
    share = team.held_object.mass / len(team.members)
    G, g, labels = [], [], []
    for member, q, s in zip(team.members, qs, team.member_slices()):
        terms = terms_at(member.robot, q, task.name, object_mass=share, check=False)
        rows = step_rows(constraints, terms, x_prev[s], h, (A[s], offset[s]), columns=s, width=len(x_prev))
        G.append(rows.G)
        g.append(rows.h)
        labels += [f"{member.name}: {label}" for label in rows.labels]
    return StepRows(np.vstack(G), np.concatenate(g), tuple(labels))


def _floor_binding(H, c, J, b, lo, hi, G, g, floor_G, floor_g, labels: list[str]) -> str:
    """The label of the first group of floor rows whose removal alone makes the step feasible, or
    ``"the floor's rows together"``."""
    labels_ = np.asarray(labels)
    for label in dict.fromkeys(labels):
        keep = labels_ != label
        if solve_step_qp(H, c, J, b, lo, hi, np.vstack([G, floor_G[keep]]), np.r_[g, floor_g[keep]]) is not None:
            return str(label)
    return "the floor's rows together"


def team_carry(
    team: Team,
    path: ObjectPath,
    objective: Objective | str | None = None,
    *,
    frame: str = "object",
    step: float = DEFAULT_STEP,
    gain: float = DEFAULT_GAIN,
    prepare: float = DEFAULT_PREPARE,
    floor: CarryFloor | None = None,
    constraints: Sequence[Constraint] = (),
    progress: bool = False,
) -> TeamCarryResult:
    """Synthesise the team's capacity-maximising motion along ``path`` and the pseudo-inverse baseline.

    Args:
        team: the team, its robots in their start configurations (``Member.q``), every robot's
            platform S independent of q (as for ``carry``).
        path: the object's path, relative to where the team holds it at the start.
        objective: what to maximise (``ELLIPSOID:INDEX[:DIRECTION]`` or an :class:`Objective`),
            of the team's set; default ``kinematic:minor_axis``.
        frame: ``"object"`` (the path's x along the object's start heading) or ``"world"``.
        step: time step (s); gain: the capacity term's share of the velocity limits at the
            first step; prepare: longest self-motion before the path (s), 0 for none.
        floor: keep every robot on its floor (:class:`mobmanip.motion.carry_floor.CarryFloor`, a
            level one; :mod:`mobmanip.coordination.floor`) in the self-motion and the QP motion:
            each robot's zero-moment point inside its support polygon by the margin, every support
            loaded, every wheel within friction. The baseline ignores it (its readings say where
            it would break). ``None``: no floor rows.
        constraints: constraints of the sets at rest that every robot keeps at every step of the
            self-motion and the QP motion, over its own velocities and efforts
            (:func:`mobmanip.motion.step_constraints.step_rows`; a constraint that cannot join a
            step is refused by name).
        progress: show a progress bar on standard error for each of the three motions.

    Raises:
        ArgumentError: a bad step, gain, prepare, frame, path or floor (a ramp).
        MeasureError: the objective is not defined along a motion.
        CarryFailed: the QP has no solution at some step; the error names the binding limit
            (``"robot/joint"``) and holds the part of the motion that succeeded.
    """
    check_step_settings(step, gain, prepare)
    if frame not in FRAMES:
        raise ArgumentError(f"frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    if not isinstance(path, ObjectPath):
        raise ArgumentError(f"path must be an ObjectPath, got {type(path).__name__}")
    if not isinstance(team, Team):
        raise ArgumentError(f"team must be a Team, got {type(team).__name__}")
    if objective is None or isinstance(objective, str):
        objective = Objective.parse(objective or "kinematic:minor_axis", team.task)
    problem = _Problem(team, objective)
    grounded = None if floor is None else TeamFloor.build(team, floor)
    constraints = check_constraints(constraints)
    q0 = [m.robot.check_configuration(m.q) for m in team.members]
    step, gain = float(step), float(gain)
    preparation, weight, q_path, x_start = None, None, q0, None
    if prepare > 0.0 and gain > 0.0:
        still = ObjectPath(np.array([path.t[0] - float(prepare), path.t[0]]), np.zeros((2, 2)))
        run, weight = _run(problem, q0, still, frame, step, "self-motion", gain, converge=True, floor=grounded,
                           constraints=constraints, progress=progress)  # fmt: skip
        preparation = run.shifted(path.t[0] - run.t[-1])
        q_path = [q[-1] for q in preparation.q]
        x_start = np.concatenate([x[-1] for x in preparation.x]) if len(preparation.t) > 1 else None
    try:
        motion, _ = _run(problem, q_path, path, frame, step, "qp", gain, weight=weight, x_start=x_start,
                         floor=grounded, constraints=constraints, progress=progress)  # fmt: skip
    except CarryFailed as exc:
        exc.preparation = preparation
        raise
    baseline, _ = _run(problem, q0, path, frame, step, "pinv", 0.0, floor=grounded, progress=progress)
    described = None if floor is None else floor.describe()
    return TeamCarryResult(team, objective, motion, baseline, preparation, frame, floor=described,
                           constraints=tuple(c.describe() for c in constraints))  # fmt: skip
